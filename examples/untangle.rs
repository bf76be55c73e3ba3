//! Repairing poses with flipped triangles (`bdmorph::deform::untangle`) on a character with a
//! thin arm: the arm's tip pulled sharply in one fast drag (ARAP with two iterations; the
//! globalised KVF folds it only at the far pulls), the flips counted, the repair timed
//! (median of RUNS).
//!
//! `cargo run --release --example untangle [VERTICES] [RUNS] [DX,DY ...]`
//!
//! Without pulls given, 12 pulls of 40 to 140 pixels (the arm is 36 pixels thick and 230
//! long on a 512-pixel picture).

use bdmorph::deform::{untangle, ArapOptions, Deformer, PoseMethod, UntangleOptions};
use bdmorph::meshing::{mesh_picture, MeshOptions, PictureOptions};
use bdmorph::{generate, PlanarMesh};

fn nearest(p: &[[f64; 2]], q: [f64; 2]) -> u32 {
    (0..p.len())
        .min_by(|&a, &b| {
            let d = |i: usize| (p[i][0] - q[0]).powi(2) + (p[i][1] - q[1]).powi(2);
            d(a).total_cmp(&d(b))
        })
        .expect("vertices") as u32
}

/// A torso, a head and a thin arm, 512 pixels square, meshed to about `vertices`.
fn character(vertices: usize) -> PlanarMesh {
    let s = 512.0;
    let picture = generate::picture(512, 512, |x, y| {
        let p = [x / s, y / s];
        let torso = generate::capsule_distance(p, [0.45, 0.45], [0.45, 0.7], 0.13);
        let head = generate::capsule_distance(p, [0.45, 0.2], [0.45, 0.2], 0.09);
        let arm = generate::capsule_distance(p, [0.5, 0.42], [0.95, 0.42], 0.018);
        s * torso.min(head).min(arm)
    });
    let options = MeshOptions::default().with_vertices(vertices);
    mesh_picture(&picture, &PictureOptions::default(), &options)
        .expect("meshed")
        .mesh
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let vertices: usize = args.get(1).map_or(5000, |s| s.parse().expect("VERTICES"));
    let runs: usize = args.get(2).map_or(5, |s| s.parse().expect("RUNS"));
    let mut pulls: Vec<[f64; 2]> = args
        .iter()
        .skip(3)
        .map(|s| {
            let (x, y) = s.split_once(',').expect("DX,DY");
            [x.parse().expect("DX"), y.parse().expect("DY")]
        })
        .collect();
    if pulls.is_empty() {
        pulls = vec![
            [-40.0, 80.0],
            [-60.0, -40.0],
            [-80.0, 0.0],
            [-40.0, -80.0],
            [-60.0, 80.0],
            [-80.0, 40.0],
            [-120.0, 0.0],
            [-80.0, 80.0],
            [-120.0, -40.0],
            [-80.0, -80.0],
            [-120.0, 40.0],
            [-120.0, 80.0],
        ];
    }
    let rest = character(vertices);
    let p = &rest.positions;
    println!(
        "{} vertices, {} triangles; {runs} runs per pose",
        p.len(),
        rest.faces.len()
    );
    // Pixels, y up: three points of the torso held, the arm's tip pulled.
    let arm_y = 512.0 * (1.0 - 0.42);
    let pins: Vec<u32> = [
        [230.0, 200.0],
        [230.0, 100.0],
        [230.0, 400.0],
        [486.0, arm_y],
    ]
    .iter()
    .map(|&q| nearest(p, q))
    .collect();
    let start: Vec<[f64; 2]> = pins.iter().map(|&v| p[v as usize]).collect();
    println!(
        "{:>10} {:>10} {:>6} {:>6} {:>7} {:>5} {:>8} {:>6} {:>9} {:>9}",
        "pull",
        "reach",
        "flips",
        "after",
        "bound",
        "its",
        "attempts",
        "moved",
        "max move",
        "median"
    );
    for pull in pulls {
        let fast = PoseMethod::Arap(ArapOptions::default().with_iterations(2));
        let mut pose = Deformer::new(&rest, fast).expect("set up");
        pose.set_pins(&pins).expect("pins");
        let mut targets = start.clone();
        targets[3] = [start[3][0] + pull[0], start[3][1] + pull[1]];
        pose.drag(&targets).expect("drag");
        // How far the drag threw its furthest vertex from the rest shape (relative to the size):
        // far beyond 1, the pose is broken, not folded.
        let reach = pose
            .positions()
            .iter()
            .zip(p)
            .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
            .fold(0.0, f64::max)
            / rest.diameter();
        let mut times = Vec::new();
        let mut out = None;
        for _ in 0..runs.max(1) {
            let t = std::time::Instant::now();
            let r = untangle(&rest, pose.positions(), &pins, &UntangleOptions::default())
                .expect("untangle");
            times.push(t.elapsed().as_secs_f64());
            out = Some(r);
        }
        times.sort_by(f64::total_cmp);
        let r = out.expect("a run").report;
        println!(
            "{:>10} {:>10.2e} {:>6} {:>6} {:>7.2} {:>5} {:>8} {:>6} {:>9.2e} {:>7.1}ms",
            format!("{},{}", pull[0], pull[1]),
            reach,
            r.flipped_before,
            r.flipped_after,
            r.bound.unwrap_or(f64::NAN),
            r.iterations,
            r.attempts,
            r.moved_vertices,
            r.max_move,
            1e3 * times[times.len() / 2]
        );
    }
}
