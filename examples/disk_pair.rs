//! Writes a generated pair of keyframes of about N vertices (default 10,000) to
//! `DIR/source.obj` and `DIR/target.obj` (default DIR `./disk-pair`): the disk of the
//! benchmarks and the same disk bent and twisted, for timing the command line on them.
//!
//! ```sh
//! cargo run --release --example disk_pair -- 10000 /tmp/pair
//! bdmorph --threads 1 morph /tmp/pair/source.obj /tmp/pair/target.obj --frames 100 --format png -o /tmp/pngs
//! ```

use bdmorph::generate;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = match std::env::args().nth(1) {
        Some(s) => s.parse()?,
        None => 10_000,
    };
    let dir = std::path::PathBuf::from(std::env::args().nth(2).unwrap_or("disk-pair".into()));
    std::fs::create_dir_all(&dir)?;
    let a = generate::disk(generate::rings_for(n), 0.25);
    let b = generate::twist(&generate::bend(&a, 0.6), 1.2);
    bdmorph::io::write_obj_2d(dir.join("source.obj"), &a.positions, &a.faces, &[])?;
    bdmorph::io::write_obj_2d(dir.join("target.obj"), &b.positions, &b.faces, &[])?;
    println!(
        "{} vertices, {} triangles: {}",
        a.positions.len(),
        a.faces.len(),
        dir.display()
    );
    Ok(())
}
