//! Hard morphs: strong twists swept warm, a half turn, cold starts far from the solution.

mod common;

use bdmorph::{generate, Morph, MorphOptions, PlanarMesh};
use common::max_distance;

#[test]
fn strong_twist_of_a_10k_disk_converges_at_every_frame() {
    // Every point turned by 2 (1 - r^2) radians about the centre.
    let a = generate::disk(generate::rings_for(10_000), 0.25);
    let b = generate::twist(&a, 2.0);
    assert!(a.positions.len() > 9_000);
    let mut m = Morph::new(&a, &b, MorphOptions::default()).expect("setup");
    let mut total = 0;
    for i in 0..=10 {
        let t = f64::from(i) / 10.0;
        let f = m.frame(t).unwrap_or_else(|e| panic!("t = {t}: {e}"));
        assert!(f.stats.gradient_norm < 1e-10, "t = {t}");
        assert_eq!(f.stats.flipped_triangles, 0, "t = {t}");
        total += f.stats.newton_iterations;
        if i == 10 {
            assert!(max_distance(f.positions, &b.positions) < 1e-9 * b.diameter());
        }
    }
    eprintln!("strong twist, 10K: {total} Newton iterations over 11 frames");
}

#[test]
fn cold_starts_far_from_the_solution_converge() {
    let a = generate::disk(14, 0.25);
    let b = generate::twist(&a, 1.5);
    let mut m = Morph::new(&a, &b, MorphOptions::default().with_warm_start(false)).expect("ok");
    for t in [0.3, 0.7, 1.0] {
        let f = m.frame(t).unwrap_or_else(|e| panic!("t = {t}: {e}"));
        assert!(f.stats.gradient_norm < 1e-10);
        assert_eq!(f.stats.flipped_triangles, 0);
    }
    // Warm from t = 0.95 to t = 1: this target has a 0.47 degree sliver, which breaks the
    // triangle inequality for nearby u, so Newton needs about ten damped steps; it must
    // still converge to the exact target.
    let mut m = Morph::new(&a, &b, MorphOptions::default()).expect("ok");
    m.frame(0.95).expect("t = 0.95");
    let f = m.frame(1.0).expect("t = 1");
    assert!(f.stats.gradient_norm < 1e-10, "{:?}", f.stats);
    assert!(max_distance(f.positions, &b.positions) < 1e-9 * b.diameter());
}

#[test]
fn a_half_turn_passes_through_a_quarter_turn() {
    let a = generate::disk(10, 0.25);
    let rotate = |m: &PlanarMesh, angle: f64| PlanarMesh {
        positions: m
            .positions
            .iter()
            .map(|p| {
                let (s, c) = angle.sin_cos();
                [c * p[0] - s * p[1], s * p[0] + c * p[1]]
            })
            .collect(),
        faces: m.faces.clone(),
    };
    // Exactly negated coordinates: a turn by pi with no round-off in the target itself.
    let b = PlanarMesh {
        positions: a.positions.iter().map(|p| [-p[0], -p[1]]).collect(),
        faces: a.faces.clone(),
    };
    let quarter = rotate(&a, std::f64::consts::FRAC_PI_2);
    let mut m = Morph::new(&a, &b, MorphOptions::default()).expect("setup");
    let f = m.frame(0.5).expect("t = 0.5");
    let err = max_distance(f.positions, &quarter.positions);
    assert!(err < 1e-9 * a.diameter(), "off the quarter turn by {err}");
    assert_eq!(f.stats.newton_iterations, 0, "the metric never changes");
}

#[test]
fn the_100k_benchmark_state_converges_cold_in_a_few_iterations() {
    // The benchmarks' state: near the solution the energy's decrease drops below its
    // round-off, which grows with the mesh; Newton must then judge steps by the gradient
    // (with a fixed 1e-14 relative noise level it took 37 iterations here, or more than 50
    // depending on the ordering's rounding).
    let a = generate::disk(generate::rings_for(100_000), 0.25);
    let b = generate::twist(&generate::bend(&a, 0.6), 1.2);
    let mut m = Morph::new(&a, &b, MorphOptions::default().with_warm_start(false)).expect("ok");
    let f = m.frame(0.5).unwrap_or_else(|e| panic!("{e}"));
    assert!(f.stats.gradient_norm < 1e-10);
    assert!(
        f.stats.newton_iterations <= 4,
        "{} iterations",
        f.stats.newton_iterations
    );
}
