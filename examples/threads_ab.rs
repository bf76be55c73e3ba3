//! One thread against several on the same frames, measured in turns: each round builds a
//! fresh morph of a generated disk of about N vertices in a pool of 1 thread and in a pool of
//! T threads (in alternating order), solves `t = 0` untimed, then times the warm frames
//! `t = 1/steps, ..., 1` one way (as the `frame_threads` benchmark does). Taking turns keeps a
//! noisy machine's slow spells from falling on one side only. Prints the median time per
//! frame on each side and their ratio.
//!
//! ```sh
//! cargo run --release --example threads_ab -- 6000            # N [rounds [T [steps]]]
//! cargo run --release --example threads_ab -- 100000 6 2 10
//! ```

use std::time::Instant;

use bdmorph::{generate, Morph, MorphOptions};

fn arg<T: std::str::FromStr>(i: usize, default: T) -> T {
    std::env::args()
        .nth(i)
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let n: usize = arg(1, 6_000);
    let rounds: usize = arg(2, 10);
    let threads: usize = arg(3, 2);
    let steps: u32 = arg(4, 10);
    let a = generate::disk(generate::rings_for(n), 0.25);
    let b = generate::twist(&generate::bend(&a, 0.6), 1.2);
    let pools = [1, threads].map(|t| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .expect("a thread pool")
    });
    let mut times: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
    let mut out = vec![[0.0; 2]; a.positions.len()];
    for round in 0..rounds {
        for side in [round % 2, 1 - round % 2] {
            pools[side].install(|| -> Result<(), bdmorph::MorphError> {
                let mut morph = Morph::new(&a, &b, MorphOptions::default())?;
                morph.frame_into(0.0, &mut out)?;
                for i in 1..=steps {
                    let start = Instant::now();
                    morph.frame_into(f64::from(i) / f64::from(steps), &mut out)?;
                    times[side].push(start.elapsed().as_secs_f64() * 1e3);
                }
                Ok(())
            })?;
        }
    }
    let (one, many) = (median(&mut times[0]), median(&mut times[1]));
    println!(
        "{} vertices, {rounds} rounds of {steps} frames: 1 thread {one:.3} ms, {threads} threads \
         {many:.3} ms per frame (medians): ratio {:.3}",
        a.positions.len(),
        many / one
    );
    Ok(())
}
