//! Many keyframes: blends, paths, extrapolation limits and the distortion bound.

mod common;

use bdmorph::{
    generate, Blend, Easing, FrameAt, KeyframePath, MeshError, Morph, MorphError, MorphOptions,
    PathOptions, PlanarMesh,
};
use common::max_distance;

/// Three poses of one disk.
fn poses() -> Vec<PlanarMesh> {
    let rest = generate::disk(10, 0.25);
    vec![
        rest.clone(),
        generate::bend(&rest, 0.7),
        generate::twist(&generate::stretch(&rest, 1.6), 0.9),
    ]
}

/// `b` moved by the rigid motion (rotation and translation) that best fits it onto `a`.
fn procrustes(a: &[[f64; 2]], b: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let n = a.len() as f64;
    let mean = |p: &[[f64; 2]]| {
        let s = p.iter().fold([0.0, 0.0], |s, q| [s[0] + q[0], s[1] + q[1]]);
        [s[0] / n, s[1] / n]
    };
    let (ca, cb) = (mean(a), mean(b));
    let (mut dot, mut cross) = (0.0, 0.0);
    for (p, q) in a.iter().zip(b) {
        let (x, y) = (q[0] - cb[0], q[1] - cb[1]);
        let (u, v) = (p[0] - ca[0], p[1] - ca[1]);
        dot += x * u + y * v;
        cross += x * v - y * u;
    }
    let (s, c) = cross.atan2(dot).sin_cos();
    b.iter()
        .map(|q| {
            let (x, y) = (q[0] - cb[0], q[1] - cb[1]);
            [ca[0] + c * x - s * y, ca[1] + s * x + c * y]
        })
        .collect()
}

/// Whether squared lengths are those of a non-degenerate Euclidean triangle.
fn euclidean([a, b, c]: [f64; 3]) -> bool {
    a > 0.0 && b > 0.0 && c > 0.0 && 2.0 * (a * b + b * c + c * a) > a * a + b * b + c * c
}

/// The squared edge lengths of `face` in the affine blend of `keys` by `weights`.
fn blended_face(keys: &[PlanarMesh], weights: &[f64], face: usize) -> [f64; 3] {
    let [a, b, c] = keys[0].faces[face].map(|v| v as usize);
    [(b, c), (c, a), (a, b)].map(|(i, j)| {
        keys.iter()
            .zip(weights)
            .map(|(k, w)| {
                let (p, q) = (k.positions[i], k.positions[j]);
                w * ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2))
            })
            .sum()
    })
}

#[test]
fn unit_weights_reproduce_each_keyframe() {
    let keys = poses();
    let mut blend = Blend::new(&keys).expect("blend");
    assert_eq!(blend.keyframes(), 3);
    // In an order that makes every keyframe a warm start from another.
    for k in [2, 0, 1, 2, 1, 0] {
        let mut w = [0.0; 3];
        w[k] = 1.0;
        let f = blend.frame_weights(&w).expect("frame");
        let err = max_distance(f.positions, &keys[k].positions);
        assert!(
            err < 1e-9 * keys[k].diameter(),
            "keyframe {k}: off by {err}"
        );
        assert!(f.stats.t.is_nan());
        if k == 0 {
            assert!((f.stats.max_conformal_distortion - 1.0).abs() < 1e-6);
        }
    }
}

#[test]
fn two_keyframe_blend_is_the_morph() {
    let keys = poses();
    let pair = [keys[0].clone(), keys[2].clone()];
    let mut blend = Blend::new(&pair).expect("blend");
    let mut morph = Morph::new(&pair[0], &pair[1], MorphOptions::default()).expect("morph");
    for i in 0..=10 {
        let t = f64::from(i) / 10.0;
        let b = blend.frame_weights(&[1.0 - t, t]).expect("blend frame");
        let m = morph.frame(t).expect("morph frame");
        let err = max_distance(b.positions, m.positions);
        assert!(err < 1e-9 * pair[0].diameter(), "t = {t}: off by {err}");
        let dk = (b.stats.max_conformal_distortion - m.stats.max_conformal_distortion).abs();
        assert!(dk < 1e-6, "t = {t}: distortion differs by {dk}");
    }
}

#[test]
fn blend_does_not_depend_on_the_order_of_keyframes() {
    let keys = poses();
    let weights = [0.2, 0.3, 0.5];
    let mut reference = Blend::new(&keys).expect("blend");
    let want = reference
        .frame_weights(&weights)
        .expect("frame")
        .positions
        .to_vec();
    for order in [[1, 2, 0], [2, 1, 0], [0, 2, 1]] {
        let keys_in_order: Vec<PlanarMesh> = order.iter().map(|&k| keys[k].clone()).collect();
        let w: Vec<f64> = order.iter().map(|&k| weights[k]).collect();
        let mut blend = Blend::new(&keys_in_order).expect("blend");
        let got = blend.frame_weights(&w).expect("frame").positions.to_vec();
        let err = max_distance(&want, &procrustes(&want, &got));
        assert!(err < 1e-9 * keys[0].diameter(), "{order:?}: off by {err}");
    }
}

#[test]
fn blends_inside_the_simplex_never_flip() {
    let keys = poses();
    let mut blend = Blend::new(&keys).expect("blend");
    for i in 0..=6 {
        for j in 0..=(6 - i) {
            let w = [
                f64::from(i) / 6.0,
                f64::from(j) / 6.0,
                f64::from(6 - i - j) / 6.0,
            ];
            let f = blend.frame_weights(&w).expect("frame");
            assert_eq!(f.stats.flipped_triangles, 0, "{w:?}");
            assert!(f.stats.gradient_norm < 1e-10);
        }
    }
}

#[test]
fn paths_pass_exactly_through_their_keyframes() {
    let keys = poses();
    let mut keys4 = keys.clone();
    keys4.push(keys[0].clone());
    for options in [
        PathOptions::default(),
        PathOptions::default()
            .with_durations(vec![1.0, 2.0, 0.5])
            .with_easing(Easing::EaseInOut),
        PathOptions::default().with_easings(vec![
            Easing::Linear,
            Easing::cubic_bezier(0.2, 0.0, 0.3, 1.0).unwrap(),
            Easing::EaseInOut,
        ]),
    ] {
        let mut path = KeyframePath::with_options(&keys4, options.clone()).expect("path");
        let knots = path.keyframe_times().to_vec();
        assert_eq!(knots.len(), 4);
        assert_eq!((knots[0], knots[3]), (0.0, 1.0));
        if options.durations.is_empty() {
            assert_eq!(knots, [0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0]);
        } else {
            assert!((knots[1] - 1.0 / 3.5).abs() < 1e-15 && (knots[2] - 3.0 / 3.5).abs() < 1e-15);
        }
        // A sweep that lands on every keyframe time, warm-started across the boundaries.
        let mut times: Vec<f64> = (0..=24).map(|i| f64::from(i) / 24.0).collect();
        times.extend_from_slice(&knots);
        times.sort_by(f64::total_cmp);
        for t in times {
            let f = path.frame(t).unwrap_or_else(|e| panic!("t = {t}: {e}"));
            assert_eq!(f.stats.flipped_triangles, 0, "t = {t}");
            if let Some(k) = knots.iter().position(|&kt| kt == t) {
                let err = max_distance(f.positions, &keys4[k].positions);
                assert!(
                    err < 1e-9 * keys4[k].diameter(),
                    "keyframe {k} at t = {t}: off by {err}"
                );
            }
        }
        assert!(matches!(
            path.frame(1.2),
            Err(MorphError::TimeOutOfRange { .. })
        ));
    }
}

#[test]
fn predicted_starts_do_not_change_path_frames() {
    // Eased segments, forward and back across the keyframe times: each frame's start is
    // predicted on its segment's line (with tangents), and must end where a cold start does.
    let keys = poses();
    let mut keys4 = keys.clone();
    keys4.push(keys[0].clone());
    let options = PathOptions::default().with_easings(vec![
        Easing::EaseInOut,
        Easing::cubic_bezier(0.2, 0.0, 0.3, 1.0).unwrap(),
        Easing::Linear,
    ]);
    let hermite = options
        .clone()
        .with_morph(MorphOptions::default().with_tangents(true));
    let mut warm = KeyframePath::with_options(&keys4, hermite).expect("path");
    let cold_morph = MorphOptions::default()
        .with_warm_start(false)
        .with_reuse_factor(false);
    let mut cold =
        KeyframePath::with_options(&keys4, options.with_morph(cold_morph)).expect("path");
    let mut times: Vec<f64> = (0..=20).map(|i| f64::from(i) / 20.0).collect();
    times.extend((0..20).rev().map(|i| f64::from(i) / 20.0 + 0.013));
    let (mut warm_its, mut cold_its) = (0, 0);
    for t in times {
        let w = warm.frame(t).unwrap_or_else(|e| panic!("t = {t}: {e}"));
        assert_eq!(w.stats.flipped_triangles, 0, "t = {t}");
        warm_its += w.stats.newton_iterations;
        let w = w.positions.to_vec();
        let c = cold.frame(t).expect("cold frame");
        cold_its += c.stats.newton_iterations;
        let d = max_distance(&w, c.positions);
        assert!(d < 1e-9 * keys[0].diameter(), "t = {t}: {d:e}");
    }
    // Large steps between these poses: predictions help little, but never make it worse.
    assert!(warm_its < cold_its, "{warm_its} against {cold_its}");
}

#[test]
fn a_two_keyframe_linear_path_is_the_morph() {
    let keys = poses();
    let mut path = KeyframePath::new(&keys[..2]).expect("path");
    let mut morph = Morph::new(&keys[0], &keys[1], MorphOptions::default()).expect("morph");
    for i in 0..=8 {
        let t = f64::from(i) / 8.0;
        let p = path.frame(t).expect("path").positions.to_vec();
        let m = morph.frame(t).expect("morph");
        assert!(
            max_distance(&p, m.positions) < 1e-9 * keys[0].diameter(),
            "t = {t}"
        );
    }
}

#[test]
fn slight_extrapolation_works_and_too_much_names_the_breaking_triangle() {
    let a = generate::disk(8, 0.2);
    let b = generate::stretch(&a, 2.0);
    let keys = [a.clone(), b.clone()];
    let mut m = Morph::new(&a, &b, MorphOptions::default()).expect("morph");
    // Slightly outside [0, 1]: valid metric, no flips.
    for t in [1.1, 1.3, -0.05] {
        let f = m.frame(t).unwrap_or_else(|e| panic!("t = {t}: {e}"));
        assert_eq!(f.stats.flipped_triangles, 0, "t = {t}");
        assert!(f.stats.gradient_norm < 1e-10);
    }
    // Backwards the stretched side shrinks: where the target stretches x by s, squared
    // x-extents scale by 1 + t (s^2 - 1), which vanishes at t = -1 / (s^2 - 1) (-1/3 for the
    // largest stretch, 2), so some triangle breaks between 0 and about -1/3.
    let err = m.frame(-0.6).map(|_| ()).expect_err("t = -0.6 must break");
    let msg = err.to_string();
    let MorphError::MetricBreaks {
        at: FrameAt::Time(at),
        face,
        vertices,
        limit: FrameAt::Time(limit),
    } = err
    else {
        panic!("expected MetricBreaks in time, got {err:?}");
    };
    assert_eq!(at, -0.6);
    assert_eq!(vertices, a.faces[face]);
    assert!(limit < -0.05 && limit > -0.6, "limit {limit}");
    assert!(
        msg.contains(&format!("triangle {face}")) && msg.contains("t = -0.6"),
        "{msg}"
    );
    // The named triangle breaks just past the limit, and no triangle has broken before it.
    let w = |t: f64| [1.0 - t, t];
    assert!(!euclidean(blended_face(&keys, &w(limit - 1e-9), face)));
    for f in 0..a.faces.len() {
        assert!(
            euclidean(blended_face(&keys, &w(limit + 1e-9), f)),
            "face {f}"
        );
    }
    // Frames up to the limit are possible; the morph still works afterwards.
    let f = m.frame(limit + 0.02).expect("just inside the limit");
    assert!(f.stats.gradient_norm < 1e-10);
    assert!(m.frame(0.5).is_ok());
    assert!(matches!(
        m.frame(f64::NAN),
        Err(MorphError::TimeNotFinite { .. })
    ));
}

#[test]
fn blend_extrapolation_is_refused_with_the_weights_where_it_breaks() {
    let keys = poses();
    let mut blend = Blend::new(&keys).expect("blend");
    // A little outside the simplex works.
    let f = blend
        .frame_weights(&[-0.05, 0.5, 0.55])
        .expect("slightly outside");
    assert!(f.stats.gradient_norm < 1e-10);
    let weights = [-3.0, 0.5, 3.5];
    let err = blend
        .frame_weights(&weights)
        .map(|_| ())
        .expect_err("far outside");
    let MorphError::MetricBreaks {
        at: FrameAt::Weights(at),
        face,
        limit: FrameAt::Weights(limit),
        ..
    } = err
    else {
        panic!("expected MetricBreaks in weights, got {err:?}");
    };
    assert_eq!(at, weights);
    assert!((limit.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    // The limit lies between the nearest simplex point (0, 0.5, 3.5) / 4 and the weights.
    let base = [0.0, 0.5 / 4.0, 3.5 / 4.0];
    let lambda = limit[0] / weights[0];
    assert!(lambda > 0.0 && lambda < 1.0);
    for k in 0..3 {
        let expect = base[k] + lambda * (weights[k] - base[k]);
        assert!((limit[k] - expect).abs() < 1e-12, "{limit:?}");
    }
    let toward = |l: f64| -> Vec<f64> {
        (0..3)
            .map(|k| base[k] + l * (weights[k] - base[k]))
            .collect()
    };
    assert!(!euclidean(blended_face(
        &keys,
        &toward(lambda + 1e-9),
        face
    )));
    for f in 0..keys[0].faces.len() {
        assert!(
            euclidean(blended_face(&keys, &toward(lambda - 1e-9), f)),
            "face {f}"
        );
    }
}

#[test]
fn bad_weights_and_keyframes_are_typed_errors() {
    let keys = poses();
    let mut blend = Blend::new(&keys).expect("blend");
    assert!(matches!(
        blend.frame_weights(&[0.5, 0.5]),
        Err(MorphError::WeightCount {
            expected: 3,
            got: 2
        })
    ));
    assert!(matches!(
        blend.frame_weights(&[0.5, 0.5, 0.5]),
        Err(MorphError::WeightSum { .. })
    ));
    assert!(matches!(
        blend.frame_weights(&[f64::NAN, 0.5, 0.5]),
        Err(MorphError::WeightSum { .. })
    ));
    assert!(matches!(
        Blend::new(&keys[..1]),
        Err(MorphError::TooFewKeyframes { needed: 2, got: 1 })
    ));
    let other = generate::disk(7, 0.2);
    let mixed = [keys[0].clone(), keys[1].clone(), other];
    assert!(matches!(
        Blend::new(&mixed),
        Err(MorphError::Keyframe {
            index: 2,
            source: MeshError::CountMismatch { .. }
        })
    ));
    assert!(matches!(
        KeyframePath::with_options(&keys, PathOptions::default().with_durations(vec![1.0])),
        Err(MorphError::SegmentCount {
            what: "durations",
            expected: 2,
            got: 1
        })
    ));
    assert!(matches!(
        KeyframePath::with_options(&keys, PathOptions::default().with_durations(vec![1.0, 0.0])),
        Err(MorphError::BadDuration { segment: 1, .. })
    ));
    // A failed frame does not spoil the next.
    assert!(blend.frame_weights(&[0.2, 0.3, 0.5]).is_ok());
}

#[test]
fn overshooting_easing_extrapolates_within_the_path() {
    let keys = poses();
    let over = Easing::cubic_bezier(0.3, 1.05, 0.7, 1.05).unwrap();
    let mut path =
        KeyframePath::with_options(&keys, PathOptions::default().with_easing(over)).expect("path");
    let (k, w) = path.segment_at(0.4).unwrap();
    assert_eq!(k, 0);
    assert!(w > 1.0, "{w}");
    for i in 0..=12 {
        let t = f64::from(i) / 12.0;
        let f = path.frame(t).unwrap_or_else(|e| panic!("t = {t}: {e}"));
        assert_eq!(f.stats.flipped_triangles, 0, "t = {t}");
    }
}

/// The largest conformal distortion along t in [0, 1] must not exceed the target's (the
/// paper's bound): returns (largest along the way, the target's).
fn distortion_along(a: &PlanarMesh, b: &PlanarMesh, frames: u32) -> (f64, f64) {
    let mut m = Morph::new(a, b, MorphOptions::default()).expect("morph");
    let target = m.frame(1.0).expect("t = 1").stats.max_conformal_distortion;
    let mut worst: f64 = 0.0;
    for i in 0..=frames {
        let t = f64::from(i) / f64::from(frames);
        let f = m.frame(t).unwrap_or_else(|e| panic!("t = {t}: {e}"));
        worst = worst.max(f.stats.max_conformal_distortion);
        if i == frames / 2 {
            eprintln!(
                "t = 0.5: max distortion {}",
                f.stats.max_conformal_distortion
            );
        }
    }
    eprintln!("largest along [0, 1]: {worst}; target's: {target}");
    (worst, target)
}

#[test]
fn distortion_never_exceeds_the_targets_on_generated_pairs() {
    let d = generate::disk(12, 0.25);
    let g = generate::grid(24, 16, 0.2);
    for (name, a, b) in [
        ("bend", d.clone(), generate::bend(&d, 0.8)),
        ("twist", d.clone(), generate::twist(&d, 1.2)),
        ("stretch", d.clone(), generate::stretch(&d, 2.5)),
        ("wave", d.clone(), generate::wave(&d, 0.5)),
        (
            "grid",
            g.clone(),
            generate::twist(&generate::bend(&g, 0.6), 1.0),
        ),
    ] {
        let (worst, target) = distortion_along(&a, &b, 20);
        assert!(
            target > 1.05,
            "{name}: the pair should be distorted ({target})"
        );
        assert!(
            worst <= target * (1.0 + 1e-9),
            "{name}: {worst} > target's {target}"
        );
    }
}

#[test]
fn distortion_never_exceeds_the_targets_on_the_man_poses() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let man = common::read(&dir, "morph2d/isadorable-man/man.obj");
    let mut said = String::new();
    for other in ["man2.obj", "man3.obj"] {
        let b = common::read(&dir, &format!("morph2d/isadorable-man/{other}"));
        let (worst, target) = distortion_along(&man, &b, 20);
        assert!(
            worst <= target * (1.0 + 1e-9),
            "{other}: {worst} > target's {target}"
        );
        said.push_str(&format!("{target:.4}/"));
    }
    // The README quotes these figures: they are checked here, not typed.
    let readme = include_str!("../README.md")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    let figures = format!(
        "(man to man2: at most {}, reached at `t = 1`; man to man3: {}).",
        said.split('/').next().unwrap_or(""),
        said.split('/').nth(1).unwrap_or("")
    );
    assert!(readme.contains(&figures), "README.md should say {figures}");
}

mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

        /// Any weights summing to 1 give either a converged frame (without flips inside the
        /// simplex) or the typed extrapolation error whose limit lies between the nearest
        /// simplex point and the weights; never another error or a panic.
        #[test]
        fn any_weights_give_a_frame_or_a_named_limit(
            raw in proptest::collection::vec(-0.6f64..1.2, 3),
        ) {
            let keys = poses();
            let mut blend = Blend::new(&keys).expect("blend");
            let shift = (1.0 - raw.iter().sum::<f64>()) / 3.0;
            let w: Vec<f64> = raw.iter().map(|x| x + shift).collect();
            match blend.frame_weights(&w) {
                Ok(f) => {
                    prop_assert!(f.stats.gradient_norm < 1e-10);
                    if w.iter().all(|&x| x >= 0.0) {
                        prop_assert_eq!(f.stats.flipped_triangles, 0);
                    }
                }
                Err(MorphError::MetricBreaks { face, limit: FrameAt::Weights(limit), .. }) => {
                    prop_assert!(w.iter().any(|&x| x < 0.0));
                    prop_assert!(!euclidean(blended_face(&keys, &w, face)));
                    prop_assert!((limit.iter().sum::<f64>() - 1.0).abs() < 1e-9);
                    // Every weight of the limit lies between its simplex point's and w's.
                    for (l, x) in limit.iter().zip(&w) {
                        prop_assert!(*l >= x.min(0.0) - 1e-12 && *l <= x.max(1.0) + 1e-12);
                    }
                }
                Err(e) => prop_assert!(false, "{w:?}: {e}"),
            }
        }

        /// Any finite t gives a frame or a limit between the nearer of 0 and 1 and t.
        #[test]
        fn any_time_gives_a_frame_or_a_limit_on_the_way(t in -3.0f64..4.0) {
            let a = generate::disk(6, 0.2);
            let b = generate::bend(&generate::stretch(&a, 1.8), 0.5);
            let mut m = Morph::new(&a, &b, MorphOptions::default()).expect("morph");
            match m.frame(t) {
                Ok(f) => prop_assert!(f.stats.gradient_norm < 1e-10),
                Err(MorphError::MetricBreaks { limit: FrameAt::Time(limit), .. }) => {
                    prop_assert!(!(0.0..=1.0).contains(&t));
                    let near = t.clamp(0.0, 1.0);
                    prop_assert!((limit - near) * (t - near) > 0.0, "limit {limit}, t {t}");
                    prop_assert!((limit - near).abs() < (t - near).abs());
                }
                Err(e) => prop_assert!(false, "t = {t}: {e}"),
            }
        }
    }
}

/// However far t is, the limit and the triangle named are those of a near t, for a morph and
/// for a morph split into pieces; the message prints t and the limit in a few digits.
#[test]
fn far_extrapolations_name_the_same_limit_as_near_ones() {
    let a = generate::disk(8, 0.2);
    let b = generate::bend(&generate::stretch(&a, 2.0), 0.6);
    let mut m = Morph::new(&a, &b, MorphOptions::default()).expect("morph");
    let limit_of = |m: &mut Morph, t: f64| -> (f64, usize, String) {
        match m.frame(t).map(|_| ()).expect_err("breaks") {
            e @ MorphError::MetricBreaks { .. } => {
                let msg = e.to_string();
                let MorphError::MetricBreaks {
                    face,
                    limit: FrameAt::Time(limit),
                    ..
                } = e
                else {
                    unreachable!()
                };
                (limit, face, msg)
            }
            e => panic!("t = {t}: {e}"),
        }
    };
    for (near, fars) in [(-3.0, [-1e3, -1e20, -1e300]), (40.0, [1e3, 1e20, 1e300])] {
        let (limit, face, _) = limit_of(&mut m, near);
        for far in fars {
            let (l, f, msg) = limit_of(&mut m, far);
            assert!(
                (l - limit).abs() <= 1e-9 * limit.abs().max(1.0),
                "t = {far}: limit {l}, from t = {near}: {limit}"
            );
            assert_eq!(f, face, "t = {far}");
            assert!(msg.len() < 250, "{msg}");
            let printed = if far.abs() >= 1e7 {
                format!("t = {far:e}")
            } else {
                format!("t = {far}")
            };
            assert!(msg.starts_with(&printed), "{msg}");
        }
    }
}
