//! Distance fields and timings of the heat method on one mesh, for the comparison against the
//! peers and exact distances in `tools/geodesic_compare.py` (which runs this example).
//!
//! ```sh
//! cargo run --release --example geodesic_fields -- MESH --sources 0,17,523 --out fields.f64 \
//!     [--time-factor M] [--time-scale mean-edge|spacing] [--anchor sources|one-ring] \
//!     [--boundary robin|neumann|dirichlet|average] [--absorption R] [--boundary-source-absorption R] [--absorb-at-cuts] \
//!     [--no-intrinsic-delaunay] [--no-flip-boundary] [--mollify DELTA] [--refine DEGREES]
//!     [--refine-budget FRACTION] [--repeats R]
//! ```
//!
//! Writes one distance field per source to `--out` (little-endian `f64`, source after
//! source, vertex order) and prints one JSON object on stdout: the vertex count, the sum of
//! all coordinates (so the script can check it read the same vertices in the same order), the
//! set-up's median over 3 runs, and the median of `R` timed queries per source (default 20,
//! after one untimed query each), in seconds.

use std::io::Write as _;
use std::time::Instant;

use bdmorph::geodesic::{Anchor, Boundary, HeatGeodesics, HeatOptions, TimeScale};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn value<'a>(args: &'a [String], flag: &str) -> Option<&'a str> {
    args.iter()
        .position(|a| a == flag)
        .and_then(|i| args.get(i + 1))
        .map(String::as_str)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: geodesic_fields MESH --sources V1,V2,... --out FILE [--time-factor M] \
                 [--time-scale mean-edge|spacing] [--anchor sources|one-ring] \
                 [--boundary robin|neumann|dirichlet|average] [--absorption R] [--boundary-source-absorption R] [--absorb-at-cuts] [--no-intrinsic-delaunay] [--no-flip-boundary] \
                 [--mollify DELTA] [--refine DEGREES] [--refine-budget FRACTION] [--repeats R]";
    let path = args.first().ok_or(usage)?;
    let sources: Vec<u32> = value(&args, "--sources")
        .ok_or(usage)?
        .split(',')
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let out = value(&args, "--out").ok_or(usage)?;
    let repeats: usize = value(&args, "--repeats").unwrap_or("20").parse()?;
    let mut options = HeatOptions::default()
        .with_intrinsic_delaunay(!args.iter().any(|a| a == "--no-intrinsic-delaunay"))
        .with_flip_boundary(!args.iter().any(|a| a == "--no-flip-boundary"))
        .with_absorb_at_cuts(args.iter().any(|a| a == "--absorb-at-cuts"));
    if let Some(a) = value(&args, "--refine") {
        let budget = value(&args, "--refine-budget").unwrap_or("0.5").parse()?;
        options = options.with_refinement(a.parse()?, budget);
    }
    if let Some(r) = value(&args, "--absorption") {
        options = options.with_absorption(r.parse()?);
    }
    if let Some(delta) = value(&args, "--mollify") {
        options = options.with_mollify(delta.parse()?);
    }
    if let Some(m) = value(&args, "--time-factor") {
        options = options.with_time_factor(m.parse()?);
    }
    if let Some(scale) = value(&args, "--time-scale") {
        options = options.with_time_scale(match scale {
            "mean-edge" => TimeScale::MeanEdge,
            "spacing" => TimeScale::Spacing,
            other => return Err(format!("unknown time scale '{other}'").into()),
        });
    }
    if let Some(r) = value(&args, "--boundary-source-absorption") {
        options = options.with_boundary_source_absorption(r.parse()?);
    }
    if let Some(anchor) = value(&args, "--anchor") {
        options = options.with_anchor(match anchor {
            "sources" => Anchor::Sources,
            "one-ring" => Anchor::OneRing,
            other => return Err(format!("unknown anchor '{other}'").into()),
        });
    }
    if let Some(b) = value(&args, "--boundary") {
        options = options.with_boundary(match b {
            "robin" => Boundary::Robin,
            "neumann" => Boundary::Neumann,
            "dirichlet" => Boundary::Dirichlet,
            "average" => Boundary::Average,
            other => return Err(format!("unknown boundary '{other}'").into()),
        });
    }
    let mesh = bdmorph::io::read_mesh(std::path::Path::new(path))?;
    let n = mesh.positions.len();
    let mut setup = Vec::new();
    for _ in 0..3 {
        let started = Instant::now();
        let heat = HeatGeodesics::new(&mesh, options)?;
        setup.push(started.elapsed().as_secs_f64());
        drop(heat);
    }
    let mut heat = HeatGeodesics::new(&mesh, options)?;
    let mut field = vec![0.0; n];
    let mut bytes = Vec::with_capacity(8 * n * sources.len());
    let mut query = Vec::new();
    for &s in &sources {
        heat.distance_into(&[s], &mut field)?;
        for d in &field {
            bytes.extend_from_slice(&d.to_le_bytes());
        }
        for _ in 0..repeats {
            let started = Instant::now();
            heat.distance_into(&[s], &mut field)?;
            query.push(started.elapsed().as_secs_f64());
        }
    }
    std::fs::write(out, bytes)?;
    let coordinate_sum: f64 = mesh.positions.iter().flatten().sum();
    let stats = heat.stats();
    writeln!(
        std::io::stdout().lock(),
        "{{\"vertices\":{n},\"coordinate_sum\":{coordinate_sum:e},\"flips\":{},\"mean_edge\":{:e},\"spacing\":{:e},\"time\":{:e},\"factor_nnz\":{},\"inserted\":{},\"below_bound\":{},\"budget_reached\":{},\"min_angle\":{:.3},\"setup_seconds\":{:e},\"query_seconds\":{:e}}}",
        stats.flips,
        stats.mean_edge,
        stats.spacing,
        stats.time,
        stats.factor_nnz,
        stats.refine.inserted + stats.refine.split,
        stats.refine.below_bound,
        stats.refine.budget_reached,
        stats.refine.min_angle_degrees,
        median(setup),
        median(query)
    )?;
    Ok(())
}
