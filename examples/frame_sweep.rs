//! Sweeps `t` over 0, 0.1, ..., 1 and back on a generated disk of about N vertices (default
//! 10,000) and prints, per configuration of the frame levers, the mean and median time per
//! warm frame, the CPU time per frame over all rounds and in the fastest round (the one the
//! machine's other load disturbed least), and the Newton iterations, factorisations and CG
//! iterations per frame.
//!
//! ```sh
//! cargo run --release --example frame_sweep -- 100000
//! cargo run --release --example frame_sweep -- 10000 1 all 50   # N, rounds, configuration, frames per unit of t
//! ```

use std::time::Instant;

/// CPU time of this thread in seconds (Linux `schedstat`), which a loaded machine does not
/// inflate the way it inflates wall-clock time; falls back to wall-clock time elsewhere.
fn cpu_seconds(wall: Instant) -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or_else(|| wall.elapsed().as_secs_f64(), |ns| ns * 1e-9)
}

use bdmorph::{generate, FactorPrecision, Morph, MorphOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = match std::env::args().nth(1) {
        Some(s) => s.parse()?,
        None => 10_000,
    };
    let rounds: usize = match std::env::args().nth(2) {
        Some(s) => s.parse()?,
        None => 3,
    };
    // A fourth argument sets the number of frames from t = 0 to 1 (default 10).
    let steps: u32 = std::env::args()
        .nth(4)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10);
    let a = generate::disk(generate::rings_for(n), 0.25);
    let b = generate::twist(&generate::bend(&a, 0.6), 1.2);
    let program = bdmorph::compile(&a.positions, &a.faces)?;
    println!(
        "{} vertices, {} triangles; warm frames at a t step of 1/{steps}, swept 0 -> 1 -> 0, \
         {rounds} rounds",
        program.n_vertices(),
        program.n_faces()
    );
    let configs = [
        (
            "plain warm start",
            MorphOptions::default()
                .with_extrapolate(false)
                .with_reuse_factor(false),
        ),
        (
            "+ extrapolation",
            MorphOptions::default().with_reuse_factor(false),
        ),
        (
            "+ tangents",
            MorphOptions::default()
                .with_tangents(true)
                .with_reuse_factor(false),
        ),
        ("both (default)", MorphOptions::default()),
        (
            "default + tangents",
            MorphOptions::default().with_tangents(true),
        ),
        (
            "default, f64 factor",
            MorphOptions::default().with_factor_precision(FactorPrecision::Double),
        ),
        (
            "default, f32 factor",
            MorphOptions::default().with_factor_precision(FactorPrecision::Single),
        ),
    ];
    {
        // Phases on the state of t = 0.5.
        let mut vm = bdmorph::Vm::new(program.clone())?;
        let (sa, sb) = (
            vm.squared_lengths(&a.positions)?,
            vm.squared_lengths(&b.positions)?,
        );
        vm.set_metric_lerp(&sa, &sb, 0.5)?;
        vm.newton(&bdmorph::NewtonOptions::default())?;
        let median = |f: &mut dyn FnMut()| {
            let mut v: Vec<f64> = (0..15)
                .map(|_| {
                    let s = Instant::now();
                    f();
                    s.elapsed().as_secs_f64() * 1e3
                })
                .collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        if std::env::var_os("PASS_ONLY").is_some() {
            // For a profiler: nothing but passes of the iteration stream.
            // Also timed pass by pass: the minimum resists a noisy machine's load.
            let mut times: Vec<f64> = (0..2000)
                .map(|_| {
                    let s = Instant::now();
                    vm.evaluate_gradient();
                    s.elapsed().as_secs_f64() * 1e9 / program.n_faces() as f64
                })
                .collect();
            times.sort_by(f64::total_cmp);
            println!(
                "pass without energy, ns per triangle: min {:.1}, 10th percentile {:.1}, median {:.1}",
                times[0],
                times[times.len() / 10],
                times[times.len() / 2]
            );
            return Ok(());
        }
        let full = median(&mut || vm.evaluate());
        let grad = median(&mut || vm.evaluate_gradient());
        let mut linear_algebra = String::new();
        for precision in [FactorPrecision::Double, FactorPrecision::Single] {
            vm.set_factor_precision(precision);
            let fact = median(&mut || vm.factorize().expect("definite"));
            let solve = median(&mut || {
                vm.solve().expect("factored");
            });
            linear_algebra += &format!(
                ", {:?}: numeric factorisation {fact:.3}, solve {solve:.3}",
                vm.factor_precision()
            );
        }
        println!(
            "phases (median ms): pass with energy {full:.3}, pass without {grad:.3} ({:.1} ns \
             per triangle){linear_algebra}",
            grad * 1e6 / program.n_faces() as f64
        );
    }
    // ONE_WAY=1: each round a fresh morph solves t = 0 untimed, then t = 1/steps, ..., 1 is
    // timed: no frame repeats a t it has solved before (the sweep back down does, which a
    // longer history of solutions would turn into free frames).
    let one_way = std::env::var_os("ONE_WAY").is_some();
    let ts: Vec<f64> = if one_way {
        (0..=steps)
            .map(|i| f64::from(i) / f64::from(steps))
            .collect()
    } else {
        (0..=steps)
            .chain((0..steps).rev())
            .map(|i| f64::from(i) / f64::from(steps))
            .collect()
    };
    // A third argument picks one configuration by its position (e.g. for a profiler; "all"
    // or anything else that is not a number runs them all).
    let only: Option<usize> = std::env::args().nth(3).and_then(|s| s.parse().ok());
    for (i, (name, options)) in configs.into_iter().enumerate() {
        if only.is_some_and(|o| o != i) {
            continue;
        }
        let mut morph = Morph::with_program(program.clone(), &a, &b, options.clone())?;
        let mut out = vec![[0.0; 2]; a.positions.len()];
        morph.frame_into(0.0, &mut out)?;
        let (mut its, mut facts, mut cgs, mut frames) = (0u64, 0u64, 0u64, 0u64);
        let mut times = Vec::new();
        let origin = Instant::now();
        let cpu_start = cpu_seconds(origin);
        let mut cpu_setup = 0.0;
        // The fastest round's CPU time per frame: the least disturbed by other load.
        let mut fastest = f64::INFINITY;
        for round in 0..rounds {
            if one_way && round > 0 {
                let before = cpu_seconds(origin);
                morph = Morph::with_program(program.clone(), &a, &b, options.clone())?;
                morph.frame_into(0.0, &mut out)?;
                cpu_setup += cpu_seconds(origin) - before;
            }
            let round_start = cpu_seconds(origin);
            for &t in &ts[1..] {
                let start = Instant::now();
                let stats = morph.frame_into(t, &mut out)?;
                times.push(start.elapsed().as_secs_f64());
                its += u64::from(stats.newton_iterations);
                facts += u64::from(stats.factorizations);
                cgs += u64::from(stats.cg_iterations);
                frames += 1;
                assert_eq!(stats.flipped_triangles, 0);
            }
            let per_frame = (cpu_seconds(origin) - round_start) / (ts.len() - 1) as f64;
            fastest = fastest.min(per_frame);
        }
        let cpu = (cpu_seconds(origin) - cpu_start - cpu_setup) / frames as f64;
        times.sort_by(f64::total_cmp);
        let mean = times.iter().sum::<f64>() / times.len() as f64;
        println!(
            "{name:>18}: median {:8.3} ms, mean {:8.3} ms (CPU {:8.3} ms, fastest round \
             {:8.3} ms) per frame; {:.2} iterations, {:.2} factorisations, {:.2} CG \
             iterations per frame",
            times[times.len() / 2] * 1e3,
            mean * 1e3,
            cpu * 1e3,
            fastest * 1e3,
            its as f64 / frames as f64,
            facts as f64 / frames as f64,
            cgs as f64 / frames as f64,
        );
    }
    Ok(())
}
