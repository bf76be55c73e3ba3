//! Behaviour of whole morphs: endpoints, symmetry, no flips, real keyframes, bad input.

mod common;

use bdmorph::{generate, FactorPrecision, MeshError, Morph, MorphError, MorphOptions, PlanarMesh};
use common::{align, max_distance};

fn pairs() -> Vec<(&'static str, PlanarMesh, PlanarMesh)> {
    let d = generate::disk(14, 0.25);
    let g = generate::grid(30, 20, 0.2);
    vec![
        ("twist", d.clone(), generate::twist(&d, 1.0)),
        ("bend", d.clone(), generate::bend(&d, 0.8)),
        ("stretch", d.clone(), generate::stretch(&d, 2.5)),
        (
            "grid-bend-twist",
            g.clone(),
            generate::twist(&generate::bend(&g, 0.6), 1.0),
        ),
        (
            "fan",
            generate::fan(9, 0.2),
            generate::twist(&generate::fan(9, 0.2), 0.4),
        ),
    ]
}

#[test]
fn endpoints_are_reproduced() {
    for (name, a, b) in pairs() {
        let mut m = Morph::new(&a, &b, MorphOptions::default()).expect(name);
        // Warm: walk to t = 1 and back to t = 0, so the endpoints are reached warm-started.
        for t in [0.0, 0.5, 1.0, 0.5, 0.0] {
            let f = m.frame(t).expect(name);
            let reference = if t == 0.0 { &a } else { &b };
            if t == 0.0 || t == 1.0 {
                let err = max_distance(f.positions, &reference.positions);
                assert!(
                    err < 1e-9 * reference.diameter(),
                    "{name}: t = {t} off by {err}"
                );
            }
        }
    }
}

#[test]
fn endpoints_are_reproduced_at_100k_vertices() {
    let a = generate::disk(generate::rings_for(100_000), 0.25);
    let b = generate::twist(&generate::bend(&a, 0.6), 1.2);
    assert!(a.positions.len() > 99_000);
    let mut m = Morph::new(&a, &b, MorphOptions::default()).expect("setup");
    for (t, reference) in [(0.0, &a), (1.0, &b)] {
        let f = m.frame(t).expect("frame");
        assert_eq!(f.stats.flipped_triangles, 0);
        let err = max_distance(f.positions, &reference.positions);
        assert!(
            err < 1e-9 * reference.diameter(),
            "t = {t}: layout error {err} (diameter {})",
            reference.diameter()
        );
    }
}

#[test]
fn reversing_the_pair_reverses_time_up_to_a_rigid_motion() {
    for (name, a, b) in pairs() {
        let mut ab = Morph::new(&a, &b, MorphOptions::default()).expect(name);
        let mut ba = Morph::new(&b, &a, MorphOptions::default()).expect(name);
        for t in [0.25, 0.5, 0.8] {
            let p = ab.frame(t).expect(name).positions.to_vec();
            let q = ba.frame(1.0 - t).expect(name).positions.to_vec();
            let [f0, f1, _] = a.faces[0];
            let q = align(&p, &q, f0 as usize, f1 as usize);
            let err = max_distance(&p, &q);
            assert!(err < 1e-9 * a.diameter(), "{name}: t = {t}: {err}");
        }
    }
}

#[test]
fn smooth_deformations_never_flip_and_converge_tightly() {
    for (name, a, b) in pairs() {
        let mut m = Morph::new(&a, &b, MorphOptions::default()).expect(name);
        for i in 0..=20 {
            let t = f64::from(i) / 20.0;
            let f = m.frame(t).expect(name);
            assert_eq!(f.stats.flipped_triangles, 0, "{name}: t = {t}");
            assert!(f.stats.gradient_norm < 1e-10, "{name}: t = {t}");
            assert!(
                f.stats.newton_iterations <= 8,
                "{name}: t = {t}: {:?}",
                f.stats
            );
        }
    }
}

#[test]
fn frame_levers_change_the_work_not_the_frames() {
    // Extrapolated starts and reused factors against plain warm starts with a factorisation
    // per step, over a sweep that turns around at t = 1: the same frames, fewer factors.
    for (name, a, b) in pairs() {
        let plain = MorphOptions::default()
            .with_extrapolate(false)
            .with_reuse_factor(false);
        let mut reference = Morph::new(&a, &b, plain).expect("plain");
        let mut fast = Morph::new(&a, &b, MorphOptions::default()).expect("default");
        let (mut factors_plain, mut factors_fast, mut cg) = (0, 0, 0);
        let ts = (0..=10).chain((3..10).rev()).map(|i| f64::from(i) / 10.0);
        for t in ts {
            let r = reference.frame(t).expect("plain frame");
            let (r_stats, r_pos) = (r.stats, r.positions.to_vec());
            let f = fast.frame(t).expect("fast frame");
            assert!(f.stats.gradient_norm < 1e-10 && r_stats.gradient_norm < 1e-10);
            assert_eq!(f.stats.flipped_triangles, 0, "{name} t = {t}");
            let d = max_distance(&r_pos, f.positions);
            assert!(d < 1e-9 * a.diameter(), "{name} t = {t}: {d:e}");
            assert_eq!(r_stats.factorizations, r_stats.newton_iterations);
            assert_eq!(r_stats.cg_iterations, 0);
            factors_plain += r_stats.factorizations;
            factors_fast += f.stats.factorizations;
            cg += f.stats.cg_iterations;
        }
        assert!(
            2 * factors_fast < factors_plain && cg > 0,
            "{name}: {factors_fast} factorisations (and {cg} CG iterations) against \
             {factors_plain}"
        );
    }
}

#[test]
fn tangents_cut_newton_steps_and_leave_the_frames() {
    // The same sweep with starts predicted from solutions alone and from solutions and
    // tangents (Hermite): the same frames, fewer Newton steps.
    for (name, a, b) in pairs() {
        let without = MorphOptions::default().with_tangents(false);
        let mut reference = Morph::new(&a, &b, without).expect("without tangents");
        let with = MorphOptions::default().with_tangents(true);
        let mut hermite = Morph::new(&a, &b, with).expect("with tangents");
        let (mut steps_without, mut steps_with) = (0, 0);
        for i in 0..=20 {
            let t = f64::from(i) / 20.0;
            let r = reference.frame(t).expect("frame");
            steps_without += r.stats.newton_iterations;
            let r = r.positions.to_vec();
            let h = hermite.frame(t).expect("frame");
            steps_with += h.stats.newton_iterations;
            assert!(h.stats.gradient_norm < 1e-10, "{name} t = {t}");
            let d = max_distance(&r, h.positions);
            assert!(d < 1e-9 * a.diameter(), "{name} t = {t}: {d:e}");
        }
        assert!(
            steps_with < steps_without,
            "{name}: {steps_with} Newton steps with tangents, {steps_without} without"
        );
    }
}

#[test]
fn a_single_precision_factor_leaves_the_frames() {
    // The factor stored in f32 only preconditions conjugate gradients: the frames of a sweep
    // are those of the f64 factor, at the same tolerance, and the precision is kept.
    for (name, a, b) in pairs() {
        let options = |p| MorphOptions::default().with_factor_precision(p);
        let mut double = Morph::new(&a, &b, options(FactorPrecision::Double)).expect("f64");
        let mut single = Morph::new(&a, &b, options(FactorPrecision::Single)).expect("f32");
        let mut refined = 0;
        for i in (0..=10).chain((0..10).rev()) {
            let t = f64::from(i) / 10.0;
            let r = double.frame(t).expect("frame").positions.to_vec();
            let s = single.frame(t).expect("frame");
            assert!(s.stats.gradient_norm < 1e-10, "{name} t = {t}");
            refined += s.stats.cg_iterations;
            let d = max_distance(&r, s.positions);
            assert!(d < 1e-9 * a.diameter(), "{name} t = {t}: {d:e}");
        }
        assert!(refined > 0, "{name}");
        assert_eq!(single.factor_precision(), FactorPrecision::Single, "{name}");
    }
}

#[test]
fn any_order_of_times_gives_the_frames_of_cold_starts() {
    // Repeats, jumps, reversals and tiny steps: the extrapolation must never change a frame.
    let (_, a, b) = pairs().remove(3);
    let mut warm = Morph::new(&a, &b, MorphOptions::default()).expect("warm");
    let cold_options = MorphOptions::default()
        .with_warm_start(false)
        .with_reuse_factor(false);
    let mut cold = Morph::new(&a, &b, cold_options).expect("cold");
    let ts = [
        0.5, 0.5, 0.51, 0.52, 0.52, 0.9, 0.1, 1.0, 0.0, 0.3, 0.31, 0.3, 0.29, 0.7, 0.700001, 0.2,
    ];
    for t in ts {
        let w = warm.frame(t).expect("warm frame");
        assert_eq!(w.stats.flipped_triangles, 0, "t = {t}");
        let w = w.positions.to_vec();
        let c = cold.frame(t).expect("cold frame");
        let d = max_distance(&w, c.positions);
        assert!(d < 1e-9 * a.diameter(), "t = {t}: {d:e}");
    }
}

#[test]
fn cold_and_warm_starts_agree() {
    let (_, a, b) = pairs().remove(0);
    let mut warm = Morph::new(&a, &b, MorphOptions::default()).expect("warm");
    let mut cold =
        Morph::new(&a, &b, MorphOptions::default().with_warm_start(false)).expect("cold");
    for t in [0.3, 0.6, 0.9] {
        let w = warm.frame(t).expect("warm").positions.to_vec();
        let c = cold.frame(t).expect("cold");
        assert!(max_distance(&w, c.positions) < 1e-9 * a.diameter());
    }
}

#[test]
fn distortion_of_the_path_is_bounded_by_the_target() {
    // The paper's theorem on a generated pair: the conformal distortion (ratio of singular
    // values of each triangle's affine map from the source) never exceeds the target's.
    let a = generate::disk(10, 0.2);
    let b = generate::stretch(&generate::twist(&a, 1.0), 2.0);
    let max_distortion = |p: &[[f64; 2]]| {
        a.faces
            .iter()
            .map(|f| {
                let [x0, x1, x2] = f.map(|v| a.positions[v as usize]);
                let [y0, y1, y2] = f.map(|v| p[v as usize]);
                let dm = [
                    [x1[0] - x0[0], x2[0] - x0[0]],
                    [x1[1] - x0[1], x2[1] - x0[1]],
                ];
                let ds = [
                    [y1[0] - y0[0], y2[0] - y0[0]],
                    [y1[1] - y0[1], y2[1] - y0[1]],
                ];
                let det = dm[0][0] * dm[1][1] - dm[0][1] * dm[1][0];
                let inv = [
                    [dm[1][1] / det, -dm[0][1] / det],
                    [-dm[1][0] / det, dm[0][0] / det],
                ];
                let j = |r: usize, c: usize| ds[r][0] * inv[0][c] + ds[r][1] * inv[1][c];
                let (a11, a12, a21, a22) = (j(0, 0), j(0, 1), j(1, 0), j(1, 1));
                let fro2 = a11 * a11 + a12 * a12 + a21 * a21 + a22 * a22;
                let d = (a11 * a22 - a12 * a21).abs();
                let disc = (fro2 * fro2 - 4.0 * d * d).max(0.0).sqrt();
                ((fro2 + disc) / (fro2 - disc).max(1e-300)).sqrt()
            })
            .fold(1.0, f64::max)
    };
    let bound = max_distortion(&b.positions);
    let mut m = Morph::new(&a, &b, MorphOptions::default()).expect("setup");
    for i in 0..=10 {
        let t = f64::from(i) / 10.0;
        let d = max_distortion(m.frame(t).expect("frame").positions);
        assert!(d <= bound * (1.0 + 1e-9), "t = {t}: {d} > {bound}");
    }
}

#[test]
fn man_keyframes_morph_without_flips() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let man = common::read(&dir, "morph2d/isadorable-man/man.obj");
    for pose in ["man2.obj", "man3.obj"] {
        let target = common::read(&dir, &format!("morph2d/isadorable-man/{pose}"));
        let mut m = Morph::new(&man, &target, MorphOptions::default()).expect(pose);
        for i in 0..=20 {
            let t = f64::from(i) / 20.0;
            let f = m.frame(t).unwrap_or_else(|e| panic!("{pose}: {e}"));
            assert_eq!(f.stats.flipped_triangles, 0, "{pose}: t = {t}");
            let reference = match i {
                0 => Some(&man),
                20 => Some(&target),
                _ => None,
            };
            if let Some(r) = reference {
                let err = max_distance(f.positions, &r.positions);
                assert!(err < 1e-9 * r.diameter(), "{pose}: t = {t}: {err}");
            }
        }
    }
}

#[test]
fn bad_input_is_refused_with_its_cause() {
    let a = generate::disk(3, 0.0);
    let mut b = generate::twist(&a, 0.3);
    // A triangle reversed.
    b.faces[4] = [b.faces[4][0], b.faces[4][2], b.faces[4][1]];
    assert!(matches!(
        Morph::new(&a, &b, MorphOptions::default()),
        Err(MorphError::Mesh(MeshError::FaceReversed {
            face: 4,
            source_face: 4,
            ..
        }))
    ));
    // Different sizes.
    let small = generate::disk(2, 0.0);
    assert!(matches!(
        Morph::new(&a, &small, MorphOptions::default()),
        Err(MorphError::Mesh(MeshError::CountMismatch { .. }))
    ));
    // A flipped target triangle.
    let mut c = a.clone();
    c.positions[0] = [5.0, 5.0];
    assert!(matches!(
        Morph::new(&a, &c, MorphOptions::default()),
        Err(MorphError::Mesh(
            MeshError::Clockwise { .. } | MeshError::Inverted { .. }
        ))
    ));
    // Non-finite coordinates.
    let mut d = a.clone();
    d.positions[3][1] = f64::NAN;
    assert!(matches!(
        Morph::new(&a, &d, MorphOptions::default()),
        Err(MorphError::Mesh(MeshError::NonFinite { vertex: 3 }))
    ));
    // Degenerate triangle.
    let mut e = a.clone();
    e.positions[e.faces[0][2] as usize] = e.positions[e.faces[0][1] as usize];
    assert!(matches!(
        Morph::new(&e, &e, MorphOptions::default()),
        Err(MorphError::Mesh(MeshError::Degenerate { face: 0, .. }))
    ));
    // A mesh with a hole: a ring.
    let mut pos = Vec::new();
    for i in 0..8 {
        let ang = f64::from(i) * std::f64::consts::TAU / 8.0;
        pos.push([2.0 * ang.cos(), 2.0 * ang.sin()]);
        pos.push([ang.cos(), ang.sin()]);
    }
    let mut faces = Vec::new();
    for i in 0..8u32 {
        let (o0, i0, o1, i1) = (2 * i, 2 * i + 1, 2 * ((i + 1) % 8), 2 * ((i + 1) % 8) + 1);
        faces.push([o0, o1, i1]);
        faces.push([o0, i1, i0]);
    }
    let ring = PlanarMesh {
        positions: pos,
        faces,
    };
    // A ring morphs (its hole is filled for the solve); it is no longer refused.
    let mut m = Morph::new(&ring, &ring, MorphOptions::default()).expect("a ring morphs");
    assert_eq!(m.structure().pieces[0].holes, 1);
    let frame = m.frame(0.5).expect("frame");
    assert!(max_distance(frame.positions, &ring.positions) < 1e-12);
    // A t that is not a number.
    let mut m = Morph::new(&a, &generate::twist(&a, 0.3), MorphOptions::default()).expect("ok");
    for t in [f64::NAN, f64::INFINITY] {
        assert!(matches!(m.frame(t), Err(MorphError::TimeNotFinite { .. })));
    }
}

#[test]
fn non_convergence_is_a_typed_error_and_does_not_spoil_the_next_frame() {
    let a = generate::disk(8, 0.2);
    let b = generate::twist(&a, 1.0);
    let mut m = Morph::new(&a, &b, MorphOptions::default().with_max_iterations(1)).expect("ok");
    match m.frame(0.5) {
        Err(MorphError::NotConverged {
            iterations,
            gradient_norm,
            worst,
            ..
        }) => {
            assert_eq!(iterations, 1);
            assert!(gradient_norm > 1e-10);
            assert!(!worst.is_empty() && worst.len() <= 5);
            assert!(worst.windows(2).all(|w| w[0].margin <= w[1].margin));
        }
        other => panic!("expected NotConverged, got {other:?}"),
    }
    // The failed frame restored u = 0, so t = 0 still needs no iteration.
    assert_eq!(m.frame(0.0).expect("t = 0").stats.newton_iterations, 0);
}

#[test]
fn large_distortion_leaf_pair_morphs_without_flips() {
    // A unit square mapped to a leaf: edge-length ratios from 1.6 to 87.
    let Some(dir) = common::shared_data() else {
        return;
    };
    let a = common::read(&dir, "morph2d/ustc-hw8-leaf/0.000000.obj");
    let b = common::read(&dir, "morph2d/ustc-hw8-leaf/1.000000.obj");
    let mut m = Morph::new(&a, &b, MorphOptions::default()).expect("setup");
    for i in 0..=10 {
        let t = f64::from(i) / 10.0;
        let f = m.frame(t).unwrap_or_else(|e| panic!("t = {t}: {e}"));
        assert_eq!(f.stats.flipped_triangles, 0, "t = {t}");
        if i == 10 {
            let err = max_distance(f.positions, &b.positions);
            assert!(err < 1e-9 * b.diameter(), "t = 1: {err}");
        }
    }
}

#[test]
fn revisited_places_start_from_their_solution() {
    // A slider moved up and back: the places solved on the way up are still remembered
    // (the six newest), so each revisit starts at its solution and takes no Newton step.
    let (_, a, b) = pairs().remove(0);
    let mut m = Morph::new(&a, &b, MorphOptions::default()).expect("setup");
    let mut first = Vec::new();
    for i in 0..=6 {
        let t = f64::from(i) / 10.0;
        first.push(m.frame(t).expect("up").positions.to_vec());
    }
    for i in (1..=5).rev() {
        let t = f64::from(i) / 10.0;
        let frame = m.frame(t).expect("back");
        assert_eq!(frame.stats.newton_iterations, 0, "t = {t}");
        assert_eq!(frame.stats.factorizations, 0, "t = {t}");
        assert_eq!(frame.positions, &first[i as usize][..], "t = {t}");
    }
    // Forgotten on request: the same place takes Newton steps again, to the same solution.
    m.forget_solutions();
    let again = m.frame(0.3).expect("forgotten");
    assert!(again.stats.newton_iterations > 0);
    assert!(max_distance(again.positions, &first[3]) < 1e-9 * a.diameter());
    // t = 0 (the seventh place back, dropped even before) is solved again, to the same metric.
    let again = m.frame(0.0).expect("t = 0");
    assert!(again.stats.newton_iterations > 0);
    assert!(max_distance(again.positions, &first[0]) < 1e-9 * a.diameter());
}
