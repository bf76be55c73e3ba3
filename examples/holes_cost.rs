//! What filling holes costs: set-up (the hole triangulations, compilation) and frames of an
//! annulus against a disk of about as many vertices, and the set-up against the hole's size;
//! then free holes: the annulus morphed to a pose where its hole's outline crosses itself,
//! against a pose of the same shear that keeps it open.
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
    measure_to(a, &generate::twist(a, 1.0))
}

/// `a` (an annulus about the origin, hole radius 0.4) with the side right of its hole pushed
/// left by `reach` at mid-height (a smooth bump over the hole's height: a shear, no triangle
/// flips); from `reach > 0.8` that side lies beyond the hole's left side.
fn pushed(a: &PlanarMesh, reach: f64) -> PlanarMesh {
    let bump = |y: f64| {
        let s = y / 0.4;
        if s.abs() >= 1.0 {
            0.0
        } else {
            (std::f64::consts::FRAC_PI_2 * (1.0 + s)).sin().powi(2)
        }
    };
    PlanarMesh {
        positions: a
            .positions
            .iter()
            .map(|&[x, y]| {
                if x > 0.0 {
                    [x - reach * bump(y), y]
                } else {
                    [x, y]
                }
            })
            .collect(),
        faces: a.faces.clone(),
    }
}

/// Morphs `a` to `b`: set-up in ms, the median of 20 cold frames in ms, and the morph.
fn measure_to(
    a: &PlanarMesh,
    b: &PlanarMesh,
) -> Result<(f64, f64, Morph), Box<dyn std::error::Error>> {
    let started = Instant::now();
    let mut m = Morph::new(a, b, MorphOptions::default())?;
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
    println!();
    println!("hole | vertices | pose | free holes | set-up ms | cold frame ms | warm frame ms (60 frames forward)");
    for hole_corners in [64, 256] {
        let a = generate::polygons(
            &[
                generate::circle([0.0, 0.0], 1.0, 256),
                generate::circle([0.0, 0.0], 0.4, hole_corners),
            ],
            0.0006,
        );
        for (pose, reach) in [("pushed in (open)", 0.5), ("pushed across (crossing)", 1.1)] {
            let b = pushed(&a, reach);
            b.validate()?;
            let (setup, frame, mut m) = measure_to(&a, &b)?;
            let free = m.structure().pieces[0].free_holes.len();
            m.forget_solutions();
            let started = Instant::now();
            for i in 0..60 {
                m.frame(f64::from(i) / 59.0)?;
            }
            let warm = started.elapsed().as_secs_f64() * 1e3 / 60.0;
            println!(
                "{hole_corners} | {} | {pose} | {free} | {setup:.1} | {frame:.2} | {warm:.2}",
                a.positions.len()
            );
        }
    }
    Ok(())
}
