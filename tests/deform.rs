//! Posing by handles (`bdmorph::deform`): KVF with soft handles, ARAP with hard pins,
//! bounded distortion, and symmetric Dirichlet with soft handles.

mod common;

use bdmorph::deform::{
    ArapOptions, BoundedPoseOptions, DeformError, Deformer, KvfOptions, PoseMethod, SdOptions,
};
use bdmorph::{generate, PlanarMesh};
use common::max_distance;

/// Boundary vertices of a disk spread around it, and the centre.
fn handles(mesh: &PlanarMesh) -> Vec<u32> {
    let n = mesh.positions.len() as u32;
    vec![0, n - 1, n - 1 - n / 10, n - 1 - n / 5]
}

fn converging() -> PoseMethod {
    PoseMethod::Arap(
        ArapOptions::default()
            .with_iterations(2000)
            .with_tolerance(1e-14),
    )
}

#[test]
fn a_rigid_motion_of_every_pin_moves_the_whole_mesh_rigidly() {
    let rest = generate::disk(8, 0.2);
    let pins = handles(&rest);
    let mut pose = Deformer::new(&rest, converging()).expect("set up");
    pose.set_pins(&pins).expect("pins");
    let (s, c) = 0.7f64.sin_cos();
    let motion = |p: [f64; 2]| [c * p[0] - s * p[1] + 0.3, s * p[0] + c * p[1] - 1.2];
    let targets: Vec<[f64; 2]> = pins
        .iter()
        .map(|&v| motion(rest.positions[v as usize]))
        .collect();
    let report = pose.drag(&targets).expect("drag");
    let expected: Vec<[f64; 2]> = rest.positions.iter().map(|&p| motion(p)).collect();
    let err = max_distance(pose.positions(), &expected);
    assert!(err < 1e-9 * rest.diameter(), "{err} after {report:?}");
    assert_eq!(report.flipped_triangles, 0);
    assert!(report.energy < 1e-16, "{report:?}");
}

#[test]
fn hard_pins_are_met_exactly_and_away_and_back_returns_the_rest_shape() {
    let rest = generate::disk(10, 0.2);
    let pins = handles(&rest);
    let mut pose = Deformer::new(&rest, PoseMethod::arap()).expect("set up");
    pose.set_pins(&pins).expect("pins");
    let at_rest: Vec<[f64; 2]> = pins.iter().map(|&v| rest.positions[v as usize]).collect();
    // Drag the second handle out and back in small steps, a few iterations each, as a mouse
    // would; every drag meets the pins exactly.
    let mut targets = at_rest.clone();
    for step in (0..=20).chain((0..20).rev()) {
        let s = f64::from(step) / 20.0;
        targets[1] = [at_rest[1][0] + 0.4 * s, at_rest[1][1] + 0.5 * s];
        let report = pose.drag(&targets).expect("drag");
        assert_eq!(report.pin_residual, 0.0);
        for (&v, t) in pins.iter().zip(&targets) {
            assert_eq!(pose.positions()[v as usize], *t);
        }
    }
    // Back at the rest targets: a few more drags there settle it (no drift, no shrinking).
    let mut report = pose.drag(&targets).expect("drag");
    for _ in 0..200 {
        if report.last_change < 1e-13 {
            break;
        }
        report = pose.drag(&targets).expect("drag");
    }
    let err = max_distance(pose.positions(), &rest.positions);
    assert!(err < 1e-9 * rest.diameter(), "{err}: {report:?}");
}

#[test]
fn flips_are_reported_as_they_are_and_bad_handles_are_refused() {
    let rest = generate::grid(12, 4, 0.0);
    let mut pose = Deformer::new(&rest, converging()).expect("set up");
    // Mirror the strip's right end (its two corners swapped): triangles there must flip.
    pose.set_pins(&[0, 12, 11, 23]).expect("pins");
    let report = pose
        .drag(&[[0.0, 0.0], [0.0, 1.0], [11.0, 1.0], [11.0, 0.0]])
        .expect("drag");
    let counted = rest
        .faces
        .iter()
        .filter(|f| {
            let [a, b, c] = f.map(|v| pose.positions()[v as usize]);
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) <= 0.0
        })
        .count();
    assert_eq!(report.flipped_triangles, counted);
    assert!(counted > 0);
    // Handles that cannot work.
    assert!(matches!(
        pose.set_pins(&[0, 999]),
        Err(DeformError::PinOutOfRange {
            pin: 1,
            vertex: 999,
            ..
        })
    ));
    assert!(matches!(
        pose.set_pins(&[3, 3]),
        Err(DeformError::PinnedTwice { vertex: 3 })
    ));
    pose.set_pins(&[0, 5]).expect("pins");
    assert!(matches!(
        pose.drag(&[[0.0, 0.0]]),
        Err(DeformError::TargetCount { pins: 2, got: 1 })
    ));
    assert!(matches!(
        pose.drag(&[[0.0, 0.0], [f64::NAN, 0.0]]),
        Err(DeformError::NonFiniteTarget { index: 1 })
    ));
    // Two pieces and one pin: the other piece would float.
    let mut two = rest.clone();
    let n = two.positions.len() as u32;
    two.positions
        .extend([[50.0, 0.0], [51.0, 0.0], [50.0, 1.0]]);
    two.faces.push([n, n + 1, n + 2]);
    let mut pose = Deformer::new(&two, PoseMethod::arap()).expect("set up");
    assert!(matches!(
        pose.set_pins(&[0]),
        Err(DeformError::PieceWithoutPin { vertex }) if vertex == n
    ));
    pose.set_pins(&[0, n]).expect("a pin per piece");
}

/// KVF run to convergence in one drag.
fn kvf_converging() -> PoseMethod {
    PoseMethod::Kvf(
        KvfOptions::default()
            .with_iterations(5000)
            .with_tolerance(1e-14),
    )
}

/// Symmetric Dirichlet run to convergence in one drag.
fn sd_converging() -> PoseMethod {
    PoseMethod::Sd(
        SdOptions::default()
            .with_iterations(5000)
            .with_tolerance(1e-14),
    )
}

/// Drags until the pose stops moving (`last_change` below `1e-13` of the size).
fn settle(pose: &mut Deformer, targets: &[[f64; 2]]) -> bdmorph::deform::DragReport {
    let mut report = pose.drag(targets).expect("drag");
    for _ in 0..5000 {
        if report.last_change < 1e-13 {
            break;
        }
        report = pose.drag(targets).expect("drag");
    }
    report
}

fn nearest(p: &[[f64; 2]], q: [f64; 2]) -> u32 {
    (0..p.len())
        .min_by(|&a, &b| {
            let d = |i: usize| (p[i][0] - q[0]).powi(2) + (p[i][1] - q[1]).powi(2);
            d(a).total_cmp(&d(b))
        })
        .expect("vertices") as u32
}

/// Triangles with non-positive signed area, counted here.
fn flipped(mesh: &PlanarMesh, pose: &[[f64; 2]]) -> usize {
    mesh.faces
        .iter()
        .filter(|f| {
            let [a, b, c] = f.map(|v| pose[v as usize]);
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) <= 0.0
        })
        .count()
}

/// The demo figure with its feet and head held and its right hand as the last handle.
fn figure_with_handles() -> (PlanarMesh, Vec<u32>) {
    let rest = generate::figure(0.01);
    let p = &rest.positions;
    let pins = [[-0.45, -1.5], [0.45, -1.5], [0.0, 2.8], [1.72, 1.4]]
        .iter()
        .map(|&q| nearest(p, q))
        .collect();
    (rest, pins)
}

#[test]
fn soft_handles_move_the_whole_mesh_rigidly_when_every_handle_moves_rigidly() {
    // KVF and symmetric Dirichlet. Stated tolerance: 1e-9 of the mesh's size once the drag
    // has converged (the rigid pose is where the steps stop: every strain and every spring
    // at zero).
    let rest = generate::disk(8, 0.2);
    let pins = handles(&rest);
    for (angle, method) in [0.3f64, 1.5, -2.5]
        .into_iter()
        .flat_map(|a| [(a, kvf_converging()), (a, sd_converging())])
    {
        let mut pose = Deformer::new(&rest, method.clone()).expect("set up");
        pose.set_pins(&pins).expect("pins");
        let (s, c) = angle.sin_cos();
        let motion = |p: [f64; 2]| [c * p[0] - s * p[1] + 0.3, s * p[0] + c * p[1] - 1.2];
        let targets: Vec<[f64; 2]> = pins
            .iter()
            .map(|&v| motion(rest.positions[v as usize]))
            .collect();
        let report = pose.drag(&targets).expect("drag");
        let expected: Vec<[f64; 2]> = rest.positions.iter().map(|&p| motion(p)).collect();
        let err = max_distance(pose.positions(), &expected);
        assert!(
            err < 1e-9 * rest.diameter(),
            "{} angle {angle}: {err} after {report:?}",
            method.name()
        );
        assert_eq!(report.flipped_triangles, 0);
        assert!(report.pin_residual < 1e-9 * rest.diameter(), "{report:?}");
    }
}

#[test]
fn soft_handles_tighten_as_their_weight_grows() {
    let rest = generate::grid(16, 5, 0.0);
    // The strip's left end held, its right end bent up: the shape pulls on the handles.
    let pins = [0u32, 16, 32, 15, 31];
    let mut targets: Vec<[f64; 2]> = pins.iter().map(|&v| rest.positions[v as usize]).collect();
    targets[3] = [13.0, 4.0];
    targets[4] = [12.0, 4.3];
    for method in [kvf_converging(), sd_converging()] {
        let mut pose = Deformer::new(&rest, method.clone()).expect("set up");
        pose.set_pins(&pins).expect("pins");
        let mut residuals = Vec::new();
        for weight in [1.0, 10.0, 100.0, 1000.0, 10000.0] {
            pose.set_weight(weight).expect("weight");
            let report = settle(&mut pose, &targets);
            assert_eq!(report.flipped_triangles, 0, "weight {weight}");
            residuals.push(report.pin_residual);
        }
        eprintln!("{}: residuals {residuals:?}", method.name());
        // Strictly tighter with each weight, and about in proportion to it once small.
        for w in residuals.windows(2) {
            assert!(w[1] < 0.5 * w[0], "{}: {residuals:?}", method.name());
        }
        assert!(residuals[0] > 1e-2, "{}: {residuals:?}", method.name());
        assert!(
            residuals[4] < 1e-3 * residuals[0],
            "{}: {residuals:?}",
            method.name()
        );
        assert!(matches!(
            pose.set_weight(0.0),
            Err(DeformError::BadWeight(_))
        ));
        assert!(matches!(
            pose.set_weight(f64::NAN),
            Err(DeformError::BadWeight(_))
        ));
        assert_eq!(pose.method().name(), method.name());
    }
    // ARAP and bounded pins are hard: met exactly.
    for method in [PoseMethod::arap(), PoseMethod::bounded(3.0)] {
        let mut pose = Deformer::new(&rest, method.clone()).expect("set up");
        pose.set_pins(&pins).expect("pins");
        let report = settle(&mut pose, &targets);
        assert_eq!(report.pin_residual, 0.0, "{}", method.name());
        assert!(matches!(pose.set_weight(5.0), Err(DeformError::NoWeight)));
    }
}

#[test]
fn every_method_returns_the_rest_shape_when_the_hand_comes_back() {
    // The demo figure raises its arm in 20 mouse moves and lowers it the same way; settled at
    // the rest targets, every method is back at the rest shape to 1e-9 of its size.
    let (rest, pins) = figure_with_handles();
    let start: Vec<[f64; 2]> = pins.iter().map(|&v| rest.positions[v as usize]).collect();
    let hand = start[3];
    let shoulder = [0.6, 1.35];
    let (r, a0) = (
        (hand[0] - shoulder[0]).hypot(hand[1] - shoulder[1]),
        (hand[1] - shoulder[1]).atan2(hand[0] - shoulder[0]),
    );
    for method in [
        PoseMethod::kvf(),
        PoseMethod::arap(),
        PoseMethod::bounded(2.0),
        PoseMethod::sd(),
    ] {
        let mut pose = Deformer::new(&rest, method.clone()).expect("set up");
        pose.set_pins(&pins).expect("pins");
        let mut targets = start.clone();
        let mut furthest: f64 = 0.0;
        for k in (1..=20).chain((0..20).rev()) {
            let a = a0 + 1.2 * f64::from(k) / 20.0;
            targets[3] = [shoulder[0] + r * a.cos(), shoulder[1] + r * a.sin()];
            if k == 0 {
                targets[3] = hand;
            }
            let report = pose.drag(&targets).expect("drag");
            furthest = furthest.max(max_distance(pose.positions(), &rest.positions));
            assert_eq!(report.flipped_triangles, 0, "{}", method.name());
        }
        assert!(
            furthest > 0.5,
            "{}: the arm did move ({furthest})",
            method.name()
        );
        settle(&mut pose, &targets);
        let err = max_distance(pose.positions(), &rest.positions);
        assert!(
            err < 1e-9 * rest.diameter(),
            "{}: {err} from the rest shape",
            method.name()
        );
    }
}

#[test]
fn bounded_and_sd_flip_nothing_on_a_drag_that_folds_the_others() {
    // The hand pulled in to the chest in 20 moves: ARAP folds a triangle on the way (and KVF
    // may), reported as counted here; bounded distortion never flips one, and reports its
    // bound met or not, truthfully, after every move; symmetric Dirichlet flips none either.
    let (rest, pins) = figure_with_handles();
    let start: Vec<[f64; 2]> = pins.iter().map(|&v| rest.positions[v as usize]).collect();
    let chest = [0.0, 1.3];
    let k = 3.0;
    let mut arap_flips = 0;
    for method in [
        PoseMethod::kvf(),
        PoseMethod::arap(),
        PoseMethod::bounded(k),
        PoseMethod::sd(),
    ] {
        let mut pose = Deformer::new(&rest, method.clone()).expect("set up");
        pose.set_pins(&pins).expect("pins");
        let mut targets = start.clone();
        for step in 1..=20 {
            let s = f64::from(step) / 20.0;
            targets[3] = [
                start[3][0] + (chest[0] - start[3][0]) * s,
                start[3][1] + (chest[1] - start[3][1]) * s,
            ];
            let report = pose.drag(&targets).expect("drag");
            let counted = flipped(&rest, pose.positions());
            assert_eq!(report.flipped_triangles, counted, "{}", method.name());
            match method {
                PoseMethod::Bounded(_) => {
                    assert_eq!(counted, 0, "bounded flipped at move {step}");
                    let mut each = vec![0.0; rest.faces.len()];
                    let worst = bdmorph::distortion::RestShape::new(&rest.positions, &rest.faces)
                        .distortion_into(pose.positions(), &mut each);
                    let met = worst <= k * (1.0 + 1e-3);
                    assert_eq!(report.bound_met, Some(met), "move {step}: {worst}");
                    assert!((report.max_distortion - worst).abs() < 1e-9 * worst);
                }
                PoseMethod::Arap(_) => arap_flips += counted,
                PoseMethod::Sd(_) => {
                    assert_eq!(counted, 0, "sd flipped at move {step}");
                    assert_eq!(report.bound_met, None);
                }
                _ => assert_eq!(report.bound_met, None),
            }
        }
    }
    assert!(arap_flips > 0, "the drag is meant to fold ARAP somewhere");
}

#[test]
fn pieces_and_holes_pose_with_every_method() {
    // A plate with two holes and, beside it, an annulus: two pieces, three holes. Each
    // piece's handles move by their own rigid motion, and each piece follows rigidly.
    let plate = generate::plate_with_two_holes(0.01);
    let ring = generate::annulus(0.02);
    let mut mesh = plate.clone();
    let offset = mesh.positions.len() as u32;
    mesh.positions
        .extend(ring.positions.iter().map(|p| [p[0] + 4.0, p[1]]));
    mesh.faces
        .extend(ring.faces.iter().map(|f| f.map(|v| v + offset)));
    let n = mesh.positions.len() as u32;
    let pins = [0u32, 5, offset, offset + 7, n - 1];
    let motion = |v: u32, p: [f64; 2]| -> [f64; 2] {
        let (angle, shift) = if v < offset {
            (0.4f64, [0.2, -0.3])
        } else {
            (-0.8, [1.0, 0.5])
        };
        let (s, c) = angle.sin_cos();
        [
            c * p[0] - s * p[1] + shift[0],
            s * p[0] + c * p[1] + shift[1],
        ]
    };
    let targets: Vec<[f64; 2]> = pins
        .iter()
        .map(|&v| motion(v, mesh.positions[v as usize]))
        .collect();
    let expected: Vec<[f64; 2]> = (0..n)
        .map(|v| motion(v, mesh.positions[v as usize]))
        .collect();
    for method in [
        kvf_converging(),
        converging(),
        PoseMethod::Bounded(BoundedPoseOptions::new(2.0).with_arap_iterations(50)),
        sd_converging(),
    ] {
        let mut pose = Deformer::new(&mesh, method.clone()).expect("set up");
        pose.set_pins(&pins).expect("pins");
        let report = settle(&mut pose, &targets);
        let err = max_distance(pose.positions(), &expected);
        assert!(
            err < 1e-9 * mesh.diameter(),
            "{}: {err}, {report:?}",
            method.name()
        );
        assert_eq!(report.flipped_triangles, 0);
    }
    // A piece without a handle is refused, for every method.
    let mut pose = Deformer::new(&mesh, PoseMethod::kvf()).expect("set up");
    assert!(matches!(
        pose.set_pins(&[0, 5]),
        Err(DeformError::PieceWithoutPin { vertex }) if vertex >= offset
    ));
}

#[test]
fn bad_options_are_refused() {
    let rest = generate::grid(5, 5, 0.0);
    for k in [0.5, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            Deformer::new(&rest, PoseMethod::bounded(k)),
            Err(DeformError::BadBound(_))
        ));
    }
    let mut pose = Deformer::new(
        &rest,
        PoseMethod::Kvf(KvfOptions::default().with_weight(-1.0)),
    )
    .expect("set up");
    assert!(matches!(
        pose.set_pins(&[0]),
        Err(DeformError::BadWeight(_))
    ));
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let mut pose = Deformer::new(&rest, PoseMethod::Sd(SdOptions::default().with_weight(bad)))
            .expect("set up");
        assert!(matches!(
            pose.set_pins(&[0]),
            Err(DeformError::BadWeight(_))
        ));
    }
    let mut pose = Deformer::new(&rest, PoseMethod::sd()).expect("set up");
    assert!(matches!(
        pose.drag(&[[0.0, 0.0]]),
        Err(DeformError::TargetCount { pins: 0, got: 1 })
    ));
    let mut pose = Deformer::new(&rest, PoseMethod::kvf()).expect("set up");
    assert!(matches!(
        pose.drag(&[[0.0, 0.0]]),
        Err(DeformError::TargetCount { pins: 0, got: 1 })
    ));
    assert!(matches!(
        pose.set_positions(&[[0.0, 0.0]]),
        Err(DeformError::PositionCount {
            expected: 25,
            got: 1
        })
    ));
}
