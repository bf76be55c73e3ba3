//! Morphs a generated disk of about N vertices (default 1,000,000) and prints the time of each
//! phase, the layout error at t = 0 and t = 1, and the Newton iterations per frame.
//!
//! ```sh
//! cargo run --release --example large_disk -- 1000000
//! /usr/bin/time -v target/release/examples/large_disk 1000000   # peak memory
//! cargo run --release --example large_disk -- 1000000 f64        # the factor in double precision
//! ```

use std::time::Instant;

use bdmorph::{generate, FactorPrecision, Morph, MorphOptions, PlanarMesh};

fn max_error(p: &[[f64; 2]], q: &PlanarMesh) -> f64 {
    p.iter()
        .zip(&q.positions)
        .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
        .fold(0.0, f64::max)
        / q.diameter()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = match std::env::args().nth(1) {
        Some(s) => s.parse()?,
        None => 1_000_000,
    };
    let a = generate::disk(generate::rings_for(n), 0.25);
    let b = generate::twist(&generate::bend(&a, 0.6), 1.2);
    // Start-up as the command line pays it: read both OBJ files, then compile and analyse.
    let dir = std::env::temp_dir().join(format!("bdmorph-large-disk-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let (pa, pb) = (dir.join("source.obj"), dir.join("target.obj"));
    bdmorph::io::write_obj_2d(&pa, &a.positions, &a.faces, &[])?;
    bdmorph::io::write_obj_2d(&pb, &b.positions, &b.faces, &[])?;
    let start = Instant::now();
    let (a, b) = (PlanarMesh::read(&pa)?, PlanarMesh::read(&pb)?);
    let read = start.elapsed();
    std::fs::remove_dir_all(&dir)?;
    let start = Instant::now();
    let program = bdmorph::compile(&a.positions, &a.faces)?;
    let compiled = start.elapsed();
    let stats = program.stats();
    let start = Instant::now();
    // A second argument forces the factor's precision: `f64` or `f32` (default: automatic).
    let precision = match std::env::args().nth(2).as_deref() {
        Some("f64") => FactorPrecision::Double,
        Some("f32") => FactorPrecision::Single,
        _ => FactorPrecision::Auto,
    };
    let options = MorphOptions::default().with_factor_precision(precision);
    let mut morph = Morph::with_program(program, &a, &b, options)?;
    let setup = start.elapsed();
    println!(
        "{} vertices, {} triangles: read both OBJ files {:.3} s, compile {:.3} s, symbolic \
         analysis and setup {:.3} s; start-up {:.3} s; factor {:?}",
        stats.vertices,
        stats.faces,
        read.as_secs_f64(),
        compiled.as_secs_f64(),
        setup.as_secs_f64(),
        (read + compiled + setup).as_secs_f64(),
        morph.factor_precision()
    );
    println!(
        "iteration stream {:.1} bytes/triangle, whole program {:.1} bytes/triangle in memory, \
         {:.1} as a file",
        stats.iteration_bytes_per_face,
        stats.total_bytes as f64 / stats.faces as f64,
        stats.file_bytes as f64 / stats.faces as f64
    );
    for t in [0.0, 1.0, 0.0, 0.1, 0.2, 0.3, 0.4, 0.5] {
        let start = Instant::now();
        let frame = morph.frame(t)?;
        let took = start.elapsed().as_secs_f64();
        let err = match t {
            0.0 => format!(
                ", layout error {:.1e} of the size",
                max_error(frame.positions, &a)
            ),
            1.0 => format!(
                ", layout error {:.1e} of the size",
                max_error(frame.positions, &b)
            ),
            _ => String::new(),
        };
        println!(
            "t = {t}: {:.3} s, {} Newton iterations ({} factorisations, {} CG iterations), \
             gradient norm {:.1e}, {} flipped{err}",
            took,
            frame.stats.newton_iterations,
            frame.stats.factorizations,
            frame.stats.cg_iterations,
            frame.stats.gradient_norm,
            frame.stats.flipped_triangles
        );
    }
    Ok(())
}
