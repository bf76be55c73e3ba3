//! The three posing methods on the demo figure raising its right arm: the same handles and
//! the same mouse path for each, and what each pose ends as.
//!
//! `cargo run --release --example pose_compare [MOVES]`

use bdmorph::deform::{Deformer, PoseMethod};
use bdmorph::generate;

fn nearest(p: &[[f64; 2]], q: [f64; 2]) -> u32 {
    (0..p.len())
        .min_by(|&a, &b| {
            let d = |i: usize| (p[i][0] - q[0]).powi(2) + (p[i][1] - q[1]).powi(2);
            d(a).total_cmp(&d(b))
        })
        .unwrap() as u32
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let moves: usize = std::env::args().nth(1).map_or(Ok(20), |s| s.parse())?;
    let rest = generate::figure(0.01);
    let p = &rest.positions;
    let fixed = [[-0.45, -1.5], [0.45, -1.5], [0.0, 2.8], [-1.7, 1.4]];
    let hand = p[nearest(p, [1.72, 1.4]) as usize];
    let raised = [1.05, 2.75];
    let mut pins: Vec<u32> = fixed.iter().map(|&q| nearest(p, q)).collect();
    pins.push(nearest(p, hand));
    let start: Vec<[f64; 2]> = pins.iter().map(|&v| p[v as usize]).collect();
    println!(
        "{} vertices, {} triangles, {moves} mouse moves",
        p.len(),
        rest.faces.len()
    );
    let env = |k: &str, d: f64| {
        std::env::var(k)
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let kvf = bdmorph::deform::KvfOptions::default()
        .with_iterations(env("KVF_IT", 4.0) as u32)
        .with_alternations(env("KVF_ALT", 3.0) as u32)
        .with_weight(env("KVF_W", 100.0));
    for method in [
        PoseMethod::Kvf(kvf),
        PoseMethod::arap(),
        PoseMethod::bounded(4.0),
    ] {
        let mut pose = Deformer::new(&rest, method.clone())?;
        pose.set_pins(&pins)?;
        let mut targets = start.clone();
        let shoulder = [0.6, 1.35];
        let a0 = (hand[1] - shoulder[1]).atan2(hand[0] - shoulder[0]);
        let a1 = (raised[1] - shoulder[1]).atan2(raised[0] - shoulder[0]);
        let r0 = (hand[0] - shoulder[0]).hypot(hand[1] - shoulder[1]);
        let t0 = std::time::Instant::now();
        let mut report = None;
        for k in 1..=moves {
            let s = k as f64 / moves as f64;
            let a = a0 + (a1 - a0) * s;
            let last = targets.len() - 1;
            targets[last] = [shoulder[0] + r0 * a.cos(), shoulder[1] + r0 * a.sin()];
            report = Some(pose.drag(&targets)?);
        }
        let per = t0.elapsed().as_secs_f64() / moves as f64;
        let r = report.unwrap();
        // Settle at the end: what the pose converges to.
        let mut settled = r;
        for _ in 0..200 {
            settled = pose.drag(&targets)?;
        }
        // Back to rest along the same path, then settle.
        for k in (0..moves).rev() {
            let s = k as f64 / moves as f64;
            let a = a0 + (a1 - a0) * s;
            let last = targets.len() - 1;
            targets[last] = [shoulder[0] + r0 * a.cos(), shoulder[1] + r0 * a.sin()];
            pose.drag(&targets)?;
        }
        let mut back = pose.drag(&targets)?;
        let drift_now = drift(pose.positions(), p);
        for _ in 0..500 {
            back = pose.drag(&targets)?;
        }
        println!(
            "{:8} per move {:.3} ms | after the drag: max K {:.3}, flips {}, energy {:.3e}, pin res {:.2e} | settled: K {:.3} flips {} energy {:.3e} pin {:.2e} | back: drift {:.2e} then {:.2e} (last change {:.1e})",
            method.name(),
            per * 1e3,
            r.max_distortion,
            r.flipped_triangles,
            r.energy,
            r.pin_residual,
            settled.max_distortion,
            settled.flipped_triangles,
            settled.energy,
            settled.pin_residual,
            drift_now,
            drift(pose.positions(), p),
            back.last_change,
        );
    }
    Ok(())
}

fn drift(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x[0] - y[0]).hypot(x[1] - y[1]))
        .fold(0.0, f64::max)
}
