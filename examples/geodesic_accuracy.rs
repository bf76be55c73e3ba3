//! Accuracy and speed of the heat method on one mesh: mean relative error against a
//! reference (the exact `acos` distance on a unit sphere, or a file of exact distances), set-up
//! and per-query time, for each option set. For every shared mesh against the peers, see
//! `tools/geodesic_compare.py`.
//!
//! ```sh
//! cargo run --release --example geodesic_accuracy -- ../shared/data/closed3d/odedstein/sphere.obj --sphere
//! cargo run --release --example geodesic_accuracy -- ../shared/data/disk3d/libigl/camelhead.off \
//!     --exact tests/data/camelhead_exact_0.txt
//! ```

use std::time::Instant;

use bdmorph::geodesic::{Boundary, HeatGeodesics, HeatOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args
        .first()
        .ok_or("usage: geodesic_accuracy MESH (--sphere | --exact FILE) [--source V]")?;
    let mesh = bdmorph::io::read_mesh(std::path::Path::new(path))?;
    let source: u32 = match args.iter().position(|a| a == "--source") {
        Some(i) => args[i + 1].parse()?,
        None => 0,
    };
    let reference: Vec<f64> = if args.iter().any(|a| a == "--sphere") {
        let p = mesh.positions[source as usize];
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        mesh.positions
            .iter()
            .map(|q| {
                let dot = (p[0] * q[0] + p[1] * q[1] + p[2] * q[2]) / (r * r);
                r * dot.clamp(-1.0, 1.0).acos()
            })
            .collect()
    } else if let Some(i) = args.iter().position(|a| a == "--exact") {
        std::fs::read_to_string(&args[i + 1])?
            .lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .map(|l| l.trim().parse::<f64>())
            .collect::<Result<_, _>>()?
    } else {
        return Err("give --sphere or --exact FILE".into());
    };
    println!(
        "{path}: {} vertices, {} faces, source {source}",
        mesh.positions.len(),
        mesh.faces.len()
    );
    for (name, options) in [
        ("default (robin)", HeatOptions::default()),
        (
            "iDT, neumann",
            HeatOptions::default().with_boundary(Boundary::Neumann),
        ),
        (
            "iDT, average",
            HeatOptions::default().with_boundary(Boundary::Average),
        ),
        (
            "iDT, dirichlet",
            HeatOptions::default().with_boundary(Boundary::Dirichlet),
        ),
        (
            "plain, robin",
            HeatOptions::default().with_intrinsic_delaunay(false),
        ),
    ] {
        // Set-up: the fastest of 5.
        let mut setup = f64::INFINITY;
        for _ in 0..5 {
            let started = Instant::now();
            let heat = HeatGeodesics::new(&mesh, options)?;
            setup = setup.min(started.elapsed().as_secs_f64());
            drop(heat);
        }
        let mut heat = HeatGeodesics::new(&mesh, options)?;
        let mut d = vec![0.0; mesh.positions.len()];
        heat.distance_into(&[source], &mut d)?;
        // The fastest of 20 batches of 10 queries: the machine's noise only adds time.
        let mut per_query = f64::INFINITY;
        for _ in 0..20 {
            let started = Instant::now();
            for _ in 0..10 {
                heat.distance_into(&[source], &mut d)?;
            }
            per_query = per_query.min(started.elapsed().as_secs_f64() / 10.0);
        }
        let (mut sum, mut count) = (0.0, 0);
        for (v, (&got, &want)) in d.iter().zip(&reference).enumerate() {
            if v as u32 != source && want > 0.0 {
                sum += (got - want).abs() / want;
                count += 1;
            }
        }
        let stats = heat.stats();
        println!(
            "{name:>15}: mean relative error {:.5}, set-up {:.1} ms ({} flips), per query {:.2} ms (fastest of several runs)",
            sum / f64::from(count),
            setup * 1e3,
            stats.flips,
            per_query * 1e3
        );
    }
    Ok(())
}
