//! Measures program files on generated disks: size per triangle, and loading (checksum and
//! verifier included) against compiling.
//!
//! ```sh
//! cargo run --release --example program_file -- 10000 100000
//! ```

use std::time::{Duration, Instant};

use bdmorph::{generate, MeshKey, Program};

/// The fastest of `runs` timings of `f`, and its last result.
fn best<T>(runs: usize, mut f: impl FnMut() -> T) -> (Duration, T) {
    let mut best = Duration::MAX;
    let mut out = None;
    for _ in 0..runs {
        let start = Instant::now();
        let x = f();
        best = best.min(start.elapsed());
        out = Some(x);
    }
    (best, out.expect("runs >= 1"))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let sizes: Vec<usize> = std::env::args()
        .skip(1)
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
    let sizes = if sizes.is_empty() {
        vec![10_000, 100_000]
    } else {
        sizes
    };
    for n in sizes {
        let mesh = generate::disk(generate::rings_for(n), 0.25);
        let key = MeshKey::of(mesh.positions.len(), &mesh.faces);
        let (compile, program) = best(5, || {
            bdmorph::compile(&mesh.positions, &mesh.faces).expect("compiles")
        });
        let (write, bytes) = best(5, || program.to_bytes(&key));
        let (load, loaded) = best(5, || Program::from_bytes(&bytes).expect("loads"));
        assert_eq!(loaded.0, program);
        let (hash, _) = best(5, || MeshKey::of(mesh.positions.len(), &mesh.faces));
        let st = program.stats();
        let file = program.file_sizes();
        assert_eq!(file.total(), bytes.len());
        let per = |b: usize| b as f64 / st.faces as f64;
        println!(
            "{} vertices, {} triangles, {} unknowns: file {} bytes = {:.1} bytes per triangle \
             (in memory {:.1})",
            st.vertices,
            st.faces,
            st.unknowns,
            bytes.len(),
            per(bytes.len()),
            per(st.total_bytes)
        );
        println!(
            "  file, per triangle: layout (edges and embed) {:.2}, unknowns {:.2}, iteration {:.2}, \
             Hessian {:.2}, header and checksum {:.4}",
            per(file.layout),
            per(file.unknowns),
            per(file.iteration),
            per(file.hessian),
            per(file.header + file.checksum)
        );
        println!(
            "  in memory, per triangle: edges {:.1}, embed {:.1}, unknowns {:.1}, iteration {:.1}, \
             Hessian {:.1}",
            per(st.edges * 8),
            per(program.embed().len() * 28),
            per(st.unknowns * 4),
            per(st.iteration_bytes),
            per((program.hessian().col_ptr.len() + program.hessian().nnz()) * 4)
        );
        println!(
            "  compile {:.2} ms, to_bytes {:.2} ms, from_bytes (CRC + parse + verify) {:.2} ms, mesh key {:.2} ms; load / compile = {:.2}",
            ms(compile),
            ms(write),
            ms(load),
            ms(hash),
            load.as_secs_f64() / compile.as_secs_f64()
        );
    }
    Ok(())
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
