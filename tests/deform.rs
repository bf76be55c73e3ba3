//! Posing by handles (`bdmorph::deform`): ARAP with hard pins.

mod common;

use bdmorph::deform::{ArapOptions, DeformError, Deformer, Method};
use bdmorph::{generate, PlanarMesh};
use common::max_distance;

/// Boundary vertices of a disk spread around it, and the centre.
fn handles(mesh: &PlanarMesh) -> Vec<u32> {
    let n = mesh.positions.len() as u32;
    vec![0, n - 1, n - 1 - n / 10, n - 1 - n / 5]
}

fn converging() -> Method {
    Method::Arap(
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
    let mut pose = Deformer::new(&rest, Method::arap()).expect("set up");
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
    let mut pose = Deformer::new(&two, Method::arap()).expect("set up");
    assert!(matches!(
        pose.set_pins(&[0]),
        Err(DeformError::PieceWithoutPin { vertex }) if vertex == n
    ));
    pose.set_pins(&[0, n]).expect("a pin per piece");
}
