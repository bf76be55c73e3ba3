//! Holes whose outline crosses itself in a keyframe (a limb over the body): solved as free
//! boundaries, keyframes reached exactly, frames continuous, nothing refused.

use bdmorph::{
    generate, Blend, Easing, KeyframePath, Morph, MorphOptions, PathOptions, PlanarMesh,
};

/// A closed polygon with `per_side` points on each side.
fn dense(corners: &[[f64; 2]], per_side: usize) -> Vec<[f64; 2]> {
    let n = corners.len();
    (0..n)
        .flat_map(|i| {
            let (a, b) = (corners[i], corners[(i + 1) % n]);
            (0..per_side).map(move |k| {
                let s = k as f64 / per_side as f64;
                [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])]
            })
        })
        .collect()
}

/// `mesh` with every vertex right of `x = 2` sheared left by `reach` at mid-height (a smooth
/// bump over `y` from 1 to 3): the bar right of a square hole spanning those heights, pushed
/// across it from `reach > 2`.
fn pushed(mesh: &PlanarMesh, reach: f64) -> PlanarMesh {
    let bump = |y: f64| {
        if y <= 1.0 || y >= 3.0 {
            0.0
        } else {
            let s = (y - 1.0) / 2.0;
            (std::f64::consts::PI * s).sin().powi(2)
        }
    };
    PlanarMesh {
        positions: mesh
            .positions
            .iter()
            .map(|&[x, y]| {
                if x > 2.0 {
                    [x - reach * bump(y), y]
                } else {
                    [x, y]
                }
            })
            .collect(),
        faces: mesh.faces.clone(),
    }
}

fn size(m: &PlanarMesh) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &m.positions {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (hi[0] - lo[0]).hypot(hi[1] - lo[1])
}

fn max_distance(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max)
}

#[test]
fn an_arm_swung_across_the_body_is_reached_exactly_and_without_a_pop() {
    // A figure with its hand on its hip (the arm and the body enclose a hole), and a keyframe
    // where the arm lies across the body: the hole's outline crosses itself there.
    let a = generate::hand_on_hip(0.005);
    let b = generate::arm_across(&a, 1.2);
    b.validate().expect("the arm's shear flips no triangle");
    if let Ok(dir) = std::env::var("DUMP") {
        bdmorph::io::write_obj_2d(format!("{dir}/a.obj"), &a.positions, &a.faces, &[]).unwrap();
        bdmorph::io::write_obj_2d(format!("{dir}/b.obj"), &b.positions, &b.faces, &[]).unwrap();
    }
    let mut morph = Morph::new(&a, &b, MorphOptions::default()).expect("morphs");
    let structure = morph.structure().clone();
    assert_eq!(structure.pieces[0].holes, 1);
    assert_eq!(structure.pieces[0].free_holes.len(), 1, "{structure:?}");
    let n = 101;
    let mut frames = Vec::with_capacity(n);
    for i in 0..n {
        let t = i as f64 / (n - 1) as f64;
        let f = morph.frame(t).unwrap_or_else(|e| panic!("t = {t}: {e}"));
        assert_eq!(f.stats.flipped_triangles, 0, "t = {t}");
        frames.push(f.positions.to_vec());
    }
    let s = size(&a);
    let end = max_distance(&frames[n - 1], &b.positions) / s;
    let start = max_distance(&frames[0], &a.positions) / s;
    assert!(
        end < 1e-9,
        "frame 100 misses the key by {end:e} of its size"
    );
    assert!(start < 1e-9, "frame 0 misses the rest by {start:e}");
    no_pop(&frames, s);
}

/// No vertex steps between two neighbouring frames by more than 5 times its median step.
fn no_pop(frames: &[Vec<[f64; 2]>], s: f64) {
    for v in 0..frames[0].len() {
        let mut steps: Vec<f64> = frames
            .windows(2)
            .map(|w| (w[1][v][0] - w[0][v][0]).hypot(w[1][v][1] - w[0][v][1]))
            .collect();
        let worst = steps.iter().cloned().fold(0.0, f64::max);
        steps.sort_by(f64::total_cmp);
        let median = steps[steps.len() / 2];
        assert!(
            worst <= 5.0 * median.max(1e-12 * s),
            "vertex {v}: a step of {worst:e} against a median of {median:e}"
        );
    }
}

#[test]
fn a_path_through_keyframes_with_and_without_crossings_reaches_each_and_does_not_pop() {
    let rest = generate::hand_on_hip(0.005);
    let over = generate::arm_across(&rest, 1.2);
    // A third pose: the figure bent and turned.
    let out = generate::twist(&generate::bend(&rest, 0.3), 0.3);
    let keys = [rest.clone(), over.clone(), out.clone(), over.clone()];
    if let Ok(dir) = std::env::var("DUMP") {
        for (k, m) in keys.iter().enumerate() {
            bdmorph::io::write_obj_2d(format!("{dir}/k{k}.obj"), &m.positions, &m.faces, &[])
                .unwrap();
        }
    }
    let options = PathOptions::default()
        .with_durations(vec![1.0, 2.0, 1.5])
        .with_easing(Easing::Linear);
    let mut path = KeyframePath::with_options(&keys, options).expect("path");
    assert_eq!(path.structure().pieces[0].free_holes.len(), 1);
    let times = path.keyframe_times().to_vec();
    let s = size(&rest);
    for (k, &t) in times.iter().enumerate() {
        let f = path.frame(t).expect("frame");
        let miss = max_distance(f.positions, &keys[k].positions) / s;
        assert!(miss < 1e-9, "keyframe {k} at t = {t}: missed by {miss:e}");
    }
    let n = 181;
    let frames: Vec<Vec<[f64; 2]>> = (0..n)
        .map(|i| {
            let t = i as f64 / (n - 1) as f64;
            let f = path.frame(t).unwrap_or_else(|e| panic!("t = {t}: {e}"));
            assert_eq!(f.stats.flipped_triangles, 0, "t = {t}");
            f.positions.to_vec()
        })
        .collect();
    // Each segment on its own (the speed changes at a keyframe).
    let mut start = 0;
    for &t in &times[1..] {
        let end = ((t * (n - 1) as f64).round() as usize).min(n - 1);
        no_pop(&frames[start..=end], s);
        start = end;
    }
    // Scrubbing backwards gives the same frames (to the solver's tolerance).
    for i in (0..n).rev().step_by(7) {
        let t = i as f64 / (n - 1) as f64;
        let f = path.frame(t).expect("frame");
        let d = max_distance(f.positions, &frames[i]) / s;
        assert!(d < 1e-8, "t = {t}: {d:e} from the forward scrub");
    }
}

#[test]
fn blends_and_a_source_whose_hole_crosses_itself_work_too() {
    let rest = generate::hand_on_hip(0.005);
    let over = generate::arm_across(&rest, 1.2);
    let s = size(&rest);
    // The crossing pose first: its hole's topology filling is taken from a crossing outline.
    let mut back = Morph::new(&over, &rest, MorphOptions::default()).expect("morphs");
    assert_eq!(back.structure().pieces[0].free_holes.len(), 1);
    for (t, key) in [(0.0, &over), (1.0, &rest)] {
        let f = back.frame(t).expect("frame");
        assert!(
            max_distance(f.positions, &key.positions) / s < 1e-9,
            "t = {t}"
        );
    }
    let mid = back.frame(0.5).expect("frame").positions.to_vec();
    let mut forth = Morph::new(&rest, &over, MorphOptions::default()).expect("morphs");
    let other = forth.frame(0.5).expect("frame");
    // The same metric and targets: the same shape, up to the rigid motion (each morph places
    // it by its own anchor), so compare side lengths.
    let worst = rest
        .faces
        .iter()
        .flat_map(|f| [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])])
        .map(|(i, j)| {
            let l = |p: &[[f64; 2]]| {
                let (a, b) = (p[i as usize], p[j as usize]);
                (a[0] - b[0]).hypot(a[1] - b[1])
            };
            (l(&mid) - l(other.positions)).abs()
        })
        .fold(0.0, f64::max);
    assert!(worst < 1e-8 * s, "{worst:e}");
    let mut blend =
        Blend::new(&[rest.clone(), over.clone(), generate::arm_across(&rest, 0.4)]).expect("blend");
    for w in [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.2, 0.5, 0.3],
    ] {
        let f = blend.frame_weights(&w).expect("blend frame");
        assert_eq!(f.stats.flipped_triangles, 0, "{w:?}");
    }
    let f = blend.frame_weights(&[0.0, 1.0, 0.0]).expect("key");
    assert!(max_distance(f.positions, &over.positions) / s < 1e-9);
}

#[test]
fn filled_and_free_holes_live_in_one_piece() {
    // A plate with two square holes; the right one's outer bar is pushed across it.
    let outer = dense(&[[0.0, 0.0], [8.0, 0.0], [8.0, 4.0], [0.0, 4.0]], 24);
    let left = dense(&[[1.0, 1.0], [1.0, 3.0], [3.0, 3.0], [3.0, 1.0]], 12);
    let right = dense(&[[5.0, 1.0], [5.0, 3.0], [7.0, 3.0], [7.0, 1.0]], 12);
    let plate = generate::polygons(&[outer, left, right], 0.02);
    let shifted = PlanarMesh {
        positions: plate.positions.iter().map(|p| [p[0] - 4.0, p[1]]).collect(),
        faces: plate.faces.clone(),
    };
    let over = pushed(&shifted, 2.6);
    let over = PlanarMesh {
        positions: over.positions.iter().map(|p| [p[0] + 4.0, p[1]]).collect(),
        faces: plate.faces.clone(),
    };
    over.validate().expect("no flip");
    let mut morph = Morph::new(&plate, &over, MorphOptions::default()).expect("morphs");
    let piece = morph.structure().pieces[0].clone();
    assert_eq!((piece.holes, piece.free_holes.len()), (2, 1), "{piece:?}");
    assert!(!piece.hidden.is_empty(), "the left hole is filled");
    let s = size(&plate);
    let frames: Vec<Vec<[f64; 2]>> = (0..=40)
        .map(|i| {
            let f = morph.frame(f64::from(i) / 40.0).expect("frame");
            assert_eq!(f.stats.flipped_triangles, 0, "frame {i}");
            f.positions.to_vec()
        })
        .collect();
    assert!(max_distance(&frames[40], &over.positions) / s < 1e-9);
    no_pop(&frames, s);
}

#[test]
fn the_figure_with_a_hand_on_its_hip_scales_and_its_arm_crosses_the_body() {
    for (area, at_least) in [(0.005, 1_000), (0.0006, 9_000)] {
        let figure = generate::hand_on_hip(area);
        figure.validate().expect("valid");
        let n = figure.positions.len();
        assert!(n >= at_least, "{area}: {n} vertices");
        eprintln!("hand_on_hip({area}): {n} vertices");
        let pieces = bdmorph::pieces(n, &figure.faces).expect("pieces");
        assert_eq!((pieces.len(), pieces[0].loops.len()), (1, 2));
        generate::arm_across(&figure, 1.2)
            .validate()
            .expect("no flip");
    }
}
