//! What filling holes costs: set-up (the hole triangulations, compilation) and frames of an
//! annulus against a disk of about as many vertices, and the set-up against the hole's size.
//!
//! `cargo run --release --example holes_cost`

use std::time::Instant;

use bdmorph::{generate, Morph, MorphOptions, PlanarMesh};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Morphs `a` to its twist: set-up in ms, the median of 20 cold frames in ms, and the morph.
fn measure(a: &PlanarMesh) -> Result<(f64, f64, Morph), Box<dyn std::error::Error>> {
    let b = generate::twist(a, 1.0);
    let started = Instant::now();
    let mut m = Morph::new(a, &b, MorphOptions::default())?;
    let setup = started.elapsed().as_secs_f64() * 1e3;
    let mut times = Vec::new();
    for i in 0..20 {
        m.forget_solutions();
        let started = Instant::now();
        m.frame(0.05 + 0.045 * f64::from(i))?;
        times.push(started.elapsed().as_secs_f64() * 1e3);
    }
    Ok((setup, median(times), m))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!("mesh | vertices | hole vertices | set-up ms | frame ms (median of 20)");
    for hole_corners in [64, 256, 1024] {
        let a = generate::polygons(
            &[
                generate::circle([0.0, 0.0], 1.0, 256),
                generate::circle([0.0, 0.0], 0.4, hole_corners),
            ],
            0.0006,
        );
        let (setup, frame, m) = measure(&a)?;
        let hole = m.structure().pieces[0].hidden.len() + 2;
        println!(
            "annulus | {} | {hole} | {setup:.1} | {frame:.2}",
            a.positions.len()
        );
    }
    let d = generate::polygons(&[generate::circle([0.0, 0.0], 1.0, 256)], 0.0006);
    let (setup, frame, _) = measure(&d)?;
    println!("disk | {} | 0 | {setup:.1} | {frame:.2}", d.positions.len());
    Ok(())
}
