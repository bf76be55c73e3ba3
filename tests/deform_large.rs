//! Large drags (`bdmorph::deform`): every method returns finite positions and a report
//! measured from them, KVF's globalised step never raises its energy nor flips a triangle,
//! symmetric Dirichlet never flips one, one large drag poses as the same drag split into 20,
//! and the deformer stays usable after a drag it cannot follow. (The studio's default
//! method on a limb dragged across the body: `tests/deform_crush.rs`.)

mod common;

use bdmorph::deform::{Deformer, DragReport, DragStatus, KvfOptions, PoseMethod};
use bdmorph::distortion::RestShape;
use bdmorph::{generate, PlanarMesh};
use common::max_distance;

/// Every method, KVF both as by default (its steps may fold on the way) and flip-free.
fn methods() -> [(&'static str, PoseMethod); 5] {
    [
        ("kvf", PoseMethod::kvf()),
        ("kvf-flip-free", flip_free()),
        ("arap", PoseMethod::arap()),
        ("bounded", PoseMethod::bounded(3.0)),
        ("sd", PoseMethod::sd()),
    ]
}

fn flip_free() -> PoseMethod {
    PoseMethod::Kvf(KvfOptions::default().with_flip_free(true))
}

/// A bar 20 x 4 units (21 x 5 vertices): its left end held by its five vertices, the middle
/// of its right end the last handle.
fn bar() -> (PlanarMesh, Vec<u32>) {
    let rest = generate::grid(21, 5, 0.0);
    let pins = vec![0, 21, 42, 63, 84, 20 + 2 * 21];
    (rest, pins)
}

fn places(rest: &PlanarMesh, pins: &[u32]) -> Vec<[f64; 2]> {
    pins.iter().map(|&v| rest.positions[v as usize]).collect()
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

/// The largest distortion of an unflipped triangle, measured here.
fn worst(mesh: &PlanarMesh, pose: &[[f64; 2]]) -> f64 {
    let mut each = vec![0.0; mesh.faces.len()];
    RestShape::new(&mesh.positions, &mesh.faces).distortion_into(pose, &mut each);
    each.iter()
        .copied()
        .filter(|d| d.is_finite())
        .fold(1.0, f64::max)
}

/// The report agrees with the pose returned, measured here.
fn check_honest(name: &str, rest: &PlanarMesh, pose: &Deformer, t: &[[f64; 2]], r: &DragReport) {
    let p = pose.positions();
    assert!(p.iter().flatten().all(|c| c.is_finite()), "{name}: {r:?}");
    assert_eq!(r.flipped_triangles, flipped(rest, p), "{name}: {r:?}");
    let w = worst(rest, p);
    assert!(
        (r.max_distortion - w).abs() <= 1e-9 * w,
        "{name}: {w} {r:?}"
    );
    let residual = pose
        .pins()
        .iter()
        .zip(t)
        .map(|(&v, q)| (p[v as usize][0] - q[0]).hypot(p[v as usize][1] - q[1]))
        .fold(0.0, f64::max);
    assert!(
        (r.pin_residual - residual).abs() <= 1e-12 * residual.max(1.0),
        "{name}: {residual} {r:?}"
    );
    assert!(
        r.energy.is_finite() && r.last_change.is_finite(),
        "{name}: {r:?}"
    );
}

/// Drags at `t` until the method says it has converged (or stalled), at most `most` drags.
fn settle(pose: &mut Deformer, t: &[[f64; 2]], most: usize) -> DragReport {
    let mut r = pose.drag(t).expect("drag");
    for _ in 1..most {
        let done = match r.status {
            DragStatus::Converged => r.last_change < 1e-12,
            DragStatus::Stalled => true,
            _ => false,
        };
        if done {
            break;
        }
        r = pose.drag(t).expect("drag");
    }
    r
}

#[test]
fn large_drags_are_finite_and_reported_as_they_are() {
    // The handle pulled 2, 20, 50 and 100 bar sizes away in one drag (KVF used to return
    // energies of 1e10 to 1e137 there, then points that are not finite, with a report of no
    // flip, distortion 1 and no residual). Every method: finite, and its report measured
    // from the pose it returns. KVF: never a flip, the handle never further from its
    // target than it started; then the same deformer, dragged back, settles at the rest
    // shape.
    let (rest, pins) = bar();
    let size = rest.diameter();
    let start = places(&rest, &pins);
    for (name, method) in methods() {
        for distance in [2.0, 20.0, 50.0, 100.0] {
            let mut pose = Deformer::new(&rest, method.clone()).expect("set up");
            pose.set_pins(&pins).expect("pins");
            let mut t = start.clone();
            t[5] = [t[5][0] + distance * size, t[5][1] + 0.3 * distance * size];
            let r = pose.drag(&t).expect("drag");
            let what = format!("{name} at {distance} sizes");
            eprintln!("{what}: {r:?}");
            check_honest(&what, &rest, &pose, &t, &r);
            if name == "kvf-flip-free" {
                assert_eq!(r.flipped_triangles, 0, "{what}");
                assert!(r.max_distortion <= 10.0 * (1.0 + 1e-9), "{what}: {r:?}");
            }
            if name == "sd" {
                assert_eq!(r.flipped_triangles, 0, "{what}");
            }
            if name.starts_with("kvf") || name == "sd" {
                let away = (distance * size).hypot(0.3 * distance * size);
                assert!(r.pin_residual <= away, "{what}: {r:?}");
            }
            // Usable after: back at the rest targets, it settles at the rest shape.
            let back = settle(&mut pose, &start, 20_000);
            let err = max_distance(pose.positions(), &rest.positions) / size;
            assert!(err < 1e-8, "{what}: {err} from rest after {back:?}");
        }
    }
}

#[test]
fn one_large_drag_is_twenty_small_ones_for_every_method() {
    // The bar's tip pulled out along the bar, swung up over it, and pulled back behind its
    // held end, each in one drag and in 20, then settled. The same pose to 1e-8 of the
    // size, or (where the energy has several minima, or a flip-free method stops short)
    // both poses without a flipped triangle and within distortion 10 (the bounded
    // method: within its bound).
    let (rest, pins) = bar();
    let size = rest.diameter();
    let start = places(&rest, &pins);
    for (name, method) in methods() {
        for (drag, goal) in [
            ("stretch", [30.0, 2.0]),
            ("swing", [4.0, 18.0]),
            ("back", [-10.0, -3.0]),
        ] {
            let what = format!("{name}, {drag}");
            let mut t = start.clone();
            t[5] = goal;
            let mut one = Deformer::new(&rest, method.clone()).expect("set up");
            one.set_pins(&pins).expect("pins");
            let r1 = settle(&mut one, &t, 3000);
            let mut many = Deformer::new(&rest, method.clone()).expect("set up");
            many.set_pins(&pins).expect("pins");
            for k in 1..=20 {
                let s = f64::from(k) / 20.0;
                let mut t = start.clone();
                t[5] = [
                    start[5][0] + s * (goal[0] - start[5][0]),
                    start[5][1] + s * (goal[1] - start[5][1]),
                ];
                many.drag(&t).expect("drag");
            }
            let r20 = settle(&mut many, &t, 3000);
            let apart = max_distance(one.positions(), many.positions()) / size;
            eprintln!("{what}: {apart:.1e} apart; one {r1:?}; twenty {r20:?}");
            check_honest(&what, &rest, &one, &t, &r1);
            check_honest(&what, &rest, &many, &t, &r20);
            if apart > 1e-8 {
                let bound = match method {
                    PoseMethod::Bounded(ref o) => o.max_distortion * (1.0 + 1e-3),
                    _ => 10.0 * (1.0 + 1e-9),
                };
                for r in [&r1, &r20] {
                    assert_eq!(r.flipped_triangles, 0, "{what}: {apart} apart, {r:?}");
                    assert!(r.max_distortion <= bound, "{what}: {apart} apart, {r:?}");
                }
            }
            // KVF and ARAP have one minimum for the stretch and the swing, and reach it
            // both ways; the bounded method's ARAP iterations and projections end where
            // the bound stopped them, which depends on the way there. Symmetric Dirichlet,
            // whose barrier keeps the bar from folding on its way back, reaches the same
            // pose both ways for all three, unflipped.
            if drag != "back" && !matches!(method, PoseMethod::Bounded(_)) || name == "sd" {
                assert!(apart < 1e-8, "{what}: {apart}");
            }
            if name == "sd" {
                assert_eq!(
                    (r1.flipped_triangles, r20.flipped_triangles),
                    (0, 0),
                    "{what}"
                );
            }
        }
    }
}

#[test]
fn a_drag_that_cannot_be_followed_leaves_a_usable_deformer() {
    let (rest, pins) = bar();
    let start = places(&rest, &pins);
    // Flip-free KVF asked, in 20 moves, to pull the tip back through the bar: it stops
    // short, stalled, unflipped and within its distortion limit; then it follows the
    // handle back.
    let mut pose = Deformer::new(&rest, flip_free()).expect("set up");
    pose.set_pins(&pins).expect("pins");
    let mut t = start.clone();
    let goal = [-10.0, -3.0];
    for k in 1..=20 {
        let s = f64::from(k) / 20.0;
        t[5] = [
            start[5][0] + s * (goal[0] - start[5][0]),
            start[5][1] + s * (goal[1] - start[5][1]),
        ];
        pose.drag(&t).expect("drag");
    }
    let mut r = pose.drag(&t).expect("drag");
    for _ in 0..200 {
        r = pose.drag(&t).expect("drag");
    }
    assert_eq!(r.flipped_triangles, 0, "{r:?}");
    assert!(r.max_distortion <= 10.0 * (1.0 + 1e-9), "{r:?}");
    check_honest("kvf stalled", &rest, &pose, &t, &r);
    assert_eq!(r.status, DragStatus::Stalled, "{r:?}");
    assert!(r.pin_residual > 1.0, "it did stop short: {r:?}");
    assert!(r.last_change > 0.0, "a stall is not convergence: {r:?}");
    let back = settle(&mut pose, &start, 20_000);
    let err = max_distance(pose.positions(), &rest.positions) / rest.diameter();
    assert!(err < 1e-8, "{err} after {back:?}");
    // Targets beyond floating point: the pose before the drag is kept, said so, and the
    // next drag works.
    for (name, method) in methods() {
        let mut pose = Deformer::new(&rest, method.clone()).expect("set up");
        pose.set_pins(&pins).expect("pins");
        let mut t = start.clone();
        t[0] = [-1e308, 0.0];
        t[5] = [1e308, 1e308];
        let r = pose.drag(&t).expect("drag");
        eprintln!("{name} at 1e308: {r:?}");
        assert!(pose.positions().iter().flatten().all(|c| c.is_finite()));
        if r.status == DragStatus::Reverted {
            assert_eq!(pose.positions(), &rest.positions[..], "{name}");
        }
        let back = settle(&mut pose, &start, 20_000);
        let err = max_distance(pose.positions(), &rest.positions) / rest.diameter();
        assert!(err < 1e-8, "{name}: {err} after {back:?}");
    }
}

#[test]
fn the_jointed_deformer_is_finite_and_honest_on_large_drags() {
    // Two bars tied end to end by a joint, the studio's deformer of characters in parts.
    let (a, _) = bar();
    let mut mesh = a.clone();
    let n = a.positions.len() as u32;
    mesh.positions
        .extend(a.positions.iter().map(|p| [p[0] + 20.0, p[1]]));
    mesh.faces.extend(a.faces.iter().map(|f| f.map(|v| v + n)));
    let joint = [20 + 2 * 21, n + 2 * 21];
    let pins = [0u32, 21, 42, 63, 84, n + 20 + 2 * 21];
    for (name, method) in methods() {
        let mut pose =
            bdmorph::parts::JointedDeformer::new(&mesh, &[joint], method).expect("set up");
        pose.set_pins(&pins).expect("pins");
        let mut t: Vec<[f64; 2]> = pins.iter().map(|&v| mesh.positions[v as usize]).collect();
        t[5] = [t[5][0] + 20.0 * 40.0, t[5][1]];
        let r = pose.drag(&t).expect("drag");
        let p = pose.positions();
        assert!(p.iter().flatten().all(|c| c.is_finite()), "{name}: {r:?}");
        assert_eq!(r.flipped_triangles, flipped(&mesh, p), "{name}");
        if name == "kvf-flip-free" || name == "sd" {
            assert_eq!(r.flipped_triangles, 0, "{name}: {r:?}");
        }
        assert_eq!(
            p[joint[0] as usize], p[joint[1] as usize],
            "{name}: the joint holds"
        );
    }
}

fn nearest(p: &[[f64; 2]], q: [f64; 2]) -> u32 {
    (0..p.len())
        .min_by(|&a, &b| {
            let d = |i: usize| (p[i][0] - q[0]).powi(2) + (p[i][1] - q[1]).powi(2);
            d(a).total_cmp(&d(b))
        })
        .expect("vertices") as u32
}

#[test]
fn the_figures_drags_with_flip_free_kvf_and_sd() {
    // The demo figure (examples/posing.rs), feet and head held: the right hand raised 65
    // degrees about the shoulder in 20 moves then 20 drags there, and pulled into the chest
    // in 20 moves. Flip-free KVF: the raised arm as before (ARAP's pose, 1.45), and no
    // triangle flipped at any move of the pull into the chest, where ARAP folds. Symmetric
    // Dirichlet: no triangle flipped either.
    let rest = generate::figure(0.01);
    let p = &rest.positions;
    let pins: Vec<u32> = [[-0.45, -1.5], [0.45, -1.5], [0.0, 2.8], [1.72, 1.4]]
        .iter()
        .map(|&q| nearest(p, q))
        .collect();
    let start = places(&rest, &pins);
    let (hand, shoulder) = (start[3], [0.6, 1.35]);
    let r = (hand[0] - shoulder[0]).hypot(hand[1] - shoulder[1]);
    let a0 = (hand[1] - shoulder[1]).atan2(hand[0] - shoulder[0]);
    let mut raised = Vec::new();
    let mut chest_flips = Vec::new();
    for method in [flip_free(), PoseMethod::arap(), PoseMethod::sd()] {
        let mut pose = Deformer::new(&rest, method.clone()).expect("set up");
        pose.set_pins(&pins).expect("pins");
        let mut t = start.clone();
        for k in 1..=20 {
            let a = a0 + 65f64.to_radians() * f64::from(k) / 20.0;
            t[3] = [shoulder[0] + r * a.cos(), shoulder[1] + r * a.sin()];
            pose.drag(&t).expect("drag");
        }
        let mut report = pose.drag(&t).expect("drag");
        for _ in 0..19 {
            report = pose.drag(&t).expect("drag");
        }
        eprintln!("raised, {}: {report:?}", method.name());
        raised.push(report.max_distortion);
        let mut pose = Deformer::new(&rest, method.clone()).expect("set up");
        pose.set_pins(&pins).expect("pins");
        let mut t = start.clone();
        let mut most = 0;
        for k in 1..=20 {
            let s = f64::from(k) / 20.0;
            t[3] = [hand[0] * (1.0 - s), hand[1] + (1.3 - hand[1]) * s];
            let report = pose.drag(&t).expect("drag");
            check_honest("chest", &rest, &pose, &t, &report);
            most = most.max(report.flipped_triangles);
        }
        let report = pose.drag(&t).expect("drag");
        eprintln!(
            "into the chest, {}: at most {most} flipped during the drag; at the end {report:?}",
            method.name()
        );
        chest_flips.push(most);
    }
    assert!((raised[0] - raised[1]).abs() < 0.01, "{raised:?}");
    assert_eq!(chest_flips[0], 0, "kvf: {chest_flips:?}");
    assert_eq!(chest_flips[2], 0, "sd: {chest_flips:?}");
    assert!(
        chest_flips[1] > 0,
        "the pull is meant to fold ARAP: {chest_flips:?}"
    );
}
