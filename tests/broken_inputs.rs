//! Broken buffers, indices and options given to the library: a typed error or a valid result,
//! never a panic or a hang. The cases the outside tests found (a too-short map, an empty mesh,
//! an index out of range, a NaN layout, a zero tolerance), each option refused where the
//! object is built and by name, and a spent [`Budget`] stopping every iterative solve with a
//! typed error (a flag cancelled before the call, and a deadline already past: nothing here
//! depends on the clock). Property tests then feed random lengths, indices and NaNs to the
//! public entry points of `param`, `parts`, `inbetween`, `render` and `project`.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::{Duration, Instant};

use bdmorph::deform::{
    untangle, ArapOptions, BoundedPoseOptions, DeformError, Deformer, KvfOptions, PoseMethod,
    SdOptions, UntangleOptions,
};
use bdmorph::inbetween::{
    compatible_mesh, linear_frame, ArapInterpolation, InbetweenError, InbetweenOptions, Match,
};
use bdmorph::param::bounded::{flatten, BoundedDistortion, BoundedOptions};
use bdmorph::param::{energies, ParamError, ParamMethod, ParamOptions, Parameterization};
use bdmorph::parts::{
    character, pieces_of, CharacterOptions, JointedDeformer, Layer, Layered, Placement, Weld,
};
use bdmorph::render::{raster, Background, Drawing, Image, ImageSize, Viewport};
use bdmorph::{
    generate, Budget, KeyframePath, MeshError, Morph, MorphError, MorphOptions, PlanarMesh,
    Stopped, SurfaceMesh,
};
use proptest::prelude::*;

/// A budget whose flag was set before the call.
fn cancelled() -> Budget {
    Budget::unlimited().with_cancel(Arc::new(AtomicBool::new(true)))
}

/// A budget whose deadline has already passed.
fn expired() -> Budget {
    Budget::unlimited().with_deadline(Instant::now())
}

/// Both spent budgets, with the reason each must give.
fn spent() -> [(Budget, Stopped); 2] {
    [
        (cancelled(), Stopped::Cancelled),
        (expired(), Stopped::DeadlineReached),
    ]
}

fn disk() -> PlanarMesh {
    generate::disk(4, 0.1)
}

/// `f` must not panic; its result.
fn no_panic<T>(what: &str, f: impl FnOnce() -> T) -> T {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(_) => panic!("{what} panicked"),
    }
}

// ---------------------------------------------------------------------------------------
// The cases seen from outside.

#[test]
fn bounded_distortion_on_an_empty_mesh_is_an_error() {
    for mesh in [
        SurfaceMesh::from(&PlanarMesh {
            positions: vec![],
            faces: vec![],
        }),
        SurfaceMesh::from(&PlanarMesh {
            positions: vec![[0.0; 2]; 4],
            faces: vec![],
        }),
    ] {
        for pins in [&[][..], &[(0u32, [0.0, 0.0])][..]] {
            let r = no_panic("BoundedDistortion::new", || {
                BoundedDistortion::new(&mesh, pins, BoundedOptions::new(3.0))
            });
            assert!(
                matches!(
                    r,
                    Err(ParamError::EmptyMesh { .. } | ParamError::BadPin { .. })
                ),
                "{r:?}"
            );
        }
    }
}

#[test]
fn a_too_short_map_is_refused_by_the_bounded_solver_with_or_without_a_pin() {
    let mesh = SurfaceMesh::from(&disk());
    let n = mesh.positions.len();
    for pins in [
        vec![],
        vec![(0u32, [0.0, 0.0])],
        vec![(n as u32 - 1, [1.0, 1.0])],
    ] {
        let mut solver = BoundedDistortion::new(&mesh, &pins, BoundedOptions::new(3.0)).unwrap();
        for len in [0, 1, n - 1, n + 1] {
            let mut uv = vec![[0.5, 0.5]; len];
            let r = no_panic("solve_with", || solver.solve_with(&mut uv, |_, _| {}));
            assert!(
                matches!(r, Err(ParamError::UvLength { expected, got }) if expected == n && got == len),
                "{r:?}"
            );
            let r = no_panic("iterate", || solver.iterate(&mut uv));
            assert!(matches!(r, Err(ParamError::UvLength { .. })), "{r:?}");
        }
    }
}

#[test]
fn energies_of_a_too_short_map_are_an_error() {
    let mesh = SurfaceMesh::from(&disk());
    let n = mesh.positions.len();
    for len in [0, 2, n - 1, n + 3] {
        let uv = vec![[0.0, 0.0]; len];
        let r = no_panic("energies", || energies(&mesh, &uv));
        assert!(
            matches!(r, Err(ParamError::UvLength { expected, got }) if expected == n && got == len),
            "{r:?}"
        );
    }
    let planar = disk();
    assert!(energies(&mesh, &planar.positions).is_ok());
}

#[test]
fn pieces_of_an_index_out_of_range_is_an_error() {
    let r = no_panic("pieces_of", || pieces_of(&[[0, 1, 2], [2, 3, 7]], 4));
    assert!(
        matches!(
            r,
            Err(MeshError::IndexOutOfRange {
                face: 1,
                vertex: 7,
                n_vertices: 4
            })
        ),
        "{r:?}"
    );
    assert!(pieces_of(&[[0, 1, u32::MAX]], 3).is_err());
    let (of, count) = pieces_of(&[[0, 1, 2], [3, 4, 5], [2, 1, 6]], 8).unwrap();
    assert_eq!(count, 2);
    assert_eq!(of[6], 0);
    assert_eq!(of[7], u32::MAX);
}

#[test]
fn arap_interpolation_refuses_a_nan_layout_at_once() {
    let a = disk();
    let mut b = generate::bend(&a, 0.4).positions;
    b[3][1] = f64::NAN;
    let r = no_panic("ArapInterpolation::new", || ArapInterpolation::new(&a, &b));
    assert!(
        matches!(
            r,
            Err(InbetweenError::Mesh(MeshError::NonFinite { vertex: 3 }))
        ),
        "{r:?}"
    );
    b[3][1] = f64::INFINITY;
    assert!(ArapInterpolation::new(&a, &b).is_err());
    let mut bad_a = a.clone();
    bad_a.positions[0][0] = f64::NAN;
    assert!(ArapInterpolation::new(&bad_a, &a.positions).is_err());
    // A valid pair still works, and a non-finite t is refused.
    let b = generate::bend(&a, 0.4).positions;
    let mut arap = ArapInterpolation::new(&a, &b).unwrap();
    assert_eq!(arap.frame(0.5).unwrap().len(), a.positions.len());
    assert!(arap.frame(f64::NAN).is_err());
}

// ---------------------------------------------------------------------------------------
// Options refused when the object is built, by name.

#[test]
fn morph_options_out_of_range_are_refused_by_name() {
    let a = disk();
    let b = generate::bend(&a, 0.4);
    for (options, name) in [
        (
            MorphOptions::default().with_tolerance(0.0),
            "newton.tolerance",
        ),
        (
            MorphOptions::default().with_tolerance(f64::NAN),
            "newton.tolerance",
        ),
        (
            MorphOptions::default().with_tolerance(-1e-9),
            "newton.tolerance",
        ),
        (
            MorphOptions::default().with_tolerance(f64::INFINITY),
            "newton.tolerance",
        ),
        (
            MorphOptions::default().with_max_iterations(0),
            "newton.max_iterations",
        ),
    ] {
        let r = Morph::new(&a, &b, options.clone());
        assert!(
            matches!(&r, Err(MorphError::BadOption { option, .. }) if *option == name),
            "{r:?}"
        );
        let message = r.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(message.contains(name), "{message}");
        let path = KeyframePath::with_options(
            &[a.clone(), b.clone()],
            bdmorph::path::PathOptions::default().with_morph(options),
        );
        assert!(matches!(path, Err(MorphError::BadOption { .. })));
    }
    // A tolerance of 0 with u32::MAX iterations never starts.
    let r = Morph::new(
        &a,
        &b,
        MorphOptions::default()
            .with_tolerance(0.0)
            .with_max_iterations(u32::MAX),
    );
    assert!(matches!(r, Err(MorphError::BadOption { .. })));
}

#[test]
fn posing_options_out_of_range_are_refused_by_name() {
    let mesh = disk();
    let cases: Vec<(PoseMethod, &str, &str)> = vec![
        (
            PoseMethod::Kvf(KvfOptions::default().with_tolerance(-1e-9)),
            "kvf",
            "tolerance",
        ),
        (
            PoseMethod::Kvf(KvfOptions::default().with_tolerance(f64::NAN)),
            "kvf",
            "tolerance",
        ),
        (
            PoseMethod::Kvf(KvfOptions::default().with_iterations(0)),
            "kvf",
            "iterations",
        ),
        (
            PoseMethod::Kvf(KvfOptions::default().with_alternations(0)),
            "kvf",
            "alternations",
        ),
        (
            PoseMethod::Arap(ArapOptions::default().with_tolerance(-1.0)),
            "arap",
            "tolerance",
        ),
        (
            PoseMethod::Arap(ArapOptions::default().with_iterations(0)),
            "arap",
            "iterations",
        ),
        (
            PoseMethod::Sd(SdOptions::default().with_tolerance(f64::INFINITY)),
            "sd",
            "tolerance",
        ),
        (
            PoseMethod::Sd(SdOptions::default().with_iterations(0)),
            "sd",
            "iterations",
        ),
        (
            PoseMethod::Bounded(BoundedPoseOptions::new(3.0).with_iterations(0)),
            "bounded",
            "iterations",
        ),
    ];
    for (method, name, option) in cases {
        let r = Deformer::new(&mesh, method);
        match r {
            Err(DeformError::BadOption {
                method: m,
                option: o,
                ..
            }) => assert_eq!((m, o), (name, option)),
            other => panic!("{name} {option}: {other:?}"),
        }
    }
    let mut bounded = BoundedPoseOptions::new(3.0);
    bounded.tolerance = f64::NAN;
    assert!(matches!(
        Deformer::new(&mesh, PoseMethod::Bounded(bounded)),
        Err(DeformError::BadOption {
            option: "tolerance",
            ..
        })
    ));
    // A tolerance of 0 is allowed for every posing method (a bounded number of iterations,
    // none stopped early), as the Python package documents.
    for method in [
        PoseMethod::Kvf(KvfOptions::default().with_tolerance(0.0)),
        PoseMethod::Arap(ArapOptions::default().with_tolerance(0.0)),
        PoseMethod::Sd(SdOptions::default().with_tolerance(0.0)),
    ] {
        assert!(Deformer::new(&mesh, method).is_ok());
    }
    // ARAP iterations of 0 before the projections stay allowed (projections only).
    assert!(Deformer::new(
        &mesh,
        PoseMethod::Bounded(BoundedPoseOptions::new(3.0).with_arap_iterations(0))
    )
    .is_ok());
    let pose = mesh.positions.clone();
    let r = untangle(
        &mesh,
        &pose,
        &[0],
        &UntangleOptions::default().with_iterations(0),
    );
    assert!(matches!(r, Err(DeformError::BadOption { .. })), "{r:?}");
}

#[test]
fn param_options_out_of_range_are_refused_by_name() {
    let mesh = SurfaceMesh::from(&disk());
    for tolerance in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let r = Parameterization::new(
            &mesh,
            ParamMethod::Arap,
            ParamOptions::default().with_tolerance(tolerance),
        );
        assert!(
            matches!(
                r,
                Err(ParamError::BadOption {
                    option: "tolerance",
                    ..
                })
            ),
            "{r:?}"
        );
        let mut options = BoundedOptions::new(3.0);
        options.tolerance = tolerance;
        let r = BoundedDistortion::new(&mesh, &[], options);
        assert!(
            matches!(
                r,
                Err(ParamError::BadOption {
                    option: "tolerance",
                    ..
                })
            ),
            "{r:?}"
        );
    }
    let r = Parameterization::new(
        &mesh,
        ParamMethod::SymmetricDirichlet,
        ParamOptions::default().with_iterations(0),
    );
    assert!(matches!(
        r,
        Err(ParamError::BadOption {
            option: "iterations",
            ..
        })
    ));
    let r = BoundedDistortion::new(&mesh, &[], BoundedOptions::new(3.0).with_iterations(0));
    assert!(matches!(
        r,
        Err(ParamError::BadOption {
            option: "iterations",
            ..
        })
    ));
    let empty = SurfaceMesh::from(&PlanarMesh {
        positions: vec![],
        faces: vec![],
    });
    assert!(Parameterization::new(&empty, ParamMethod::Tutte, ParamOptions::default()).is_err());
}

// ---------------------------------------------------------------------------------------
// A spent budget stops every iterative solve with a typed error.

#[test]
fn a_spent_budget_stops_a_morph() {
    let a = generate::disk(6, 0.1);
    let b = generate::twist(&a, 1.0);
    for (budget, why) in spent() {
        // Building does no Newton iteration; every frame checks the budget first.
        let mut morph = Morph::new(&a, &b, MorphOptions::default().with_budget(budget)).unwrap();
        for t in [0.0, 0.5, 1.0] {
            let r = morph.frame(t).map(|_| ());
            assert!(
                matches!(r, Err(MorphError::Stopped(s)) if s == why),
                "t = {t}: {r:?}"
            );
        }
    }
    // Unlimited: as before.
    let mut morph = Morph::new(&a, &b, MorphOptions::default()).unwrap();
    assert_eq!(morph.frame(0.5).unwrap().stats.flipped_triangles, 0);
}

#[test]
fn a_cancel_between_frames_stops_the_next_and_the_morph_goes_on_after() {
    let a = generate::disk(6, 0.1);
    let b = generate::twist(&a, 1.0);
    let flag = Arc::new(AtomicBool::new(false));
    let options =
        MorphOptions::default().with_budget(Budget::unlimited().with_cancel(flag.clone()));
    let mut morph = Morph::new(&a, &b, options).unwrap();
    let before = morph.frame(0.3).unwrap().positions.to_vec();
    flag.store(true, std::sync::atomic::Ordering::Relaxed);
    assert!(matches!(
        morph.frame(0.6),
        Err(MorphError::Stopped(Stopped::Cancelled))
    ));
    flag.store(false, std::sync::atomic::Ordering::Relaxed);
    let again = morph.frame(0.3).unwrap().positions.to_vec();
    let miss = before
        .iter()
        .zip(&again)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max);
    assert!(miss < 1e-8, "{miss}");
}

/// Drags `method` by a step with the budget spent: a typed error, the pose unchanged.
fn drag_is_stopped(method: PoseMethod, why: Stopped) {
    let mesh = generate::grid(8, 4, 0.0);
    let mut pose = Deformer::new(&mesh, method).unwrap();
    pose.set_pins(&[0, 7]).unwrap();
    let before = pose.positions().to_vec();
    let r = pose.drag(&[mesh.positions[0], [7.5, 2.0]]);
    assert!(
        matches!(r, Err(DeformError::Stopped(s)) if s == why),
        "{r:?}"
    );
    assert_eq!(pose.positions(), &before[..]);
}

#[test]
fn a_spent_budget_stops_every_posing_method() {
    for (budget, why) in spent() {
        drag_is_stopped(
            PoseMethod::Kvf(KvfOptions::default().with_budget(budget.clone())),
            why,
        );
        drag_is_stopped(
            PoseMethod::Sd(SdOptions::default().with_budget(budget.clone())),
            why,
        );
        drag_is_stopped(
            PoseMethod::Arap(ArapOptions::default().with_budget(budget.clone())),
            why,
        );
        drag_is_stopped(
            PoseMethod::Bounded(BoundedPoseOptions::new(2.0).with_budget(budget.clone())),
            why,
        );
        drag_is_stopped(
            PoseMethod::Bounded(
                BoundedPoseOptions::new(2.0)
                    .with_arap_iterations(0)
                    .with_budget(budget.clone()),
            ),
            why,
        );
    }
}

#[test]
fn a_spent_budget_stops_untangling() {
    let mesh = generate::grid(8, 4, 0.0);
    let mut pose = mesh.positions.clone();
    // Fold a column over its neighbour.
    pose[12][0] = 2.0;
    for (budget, why) in spent() {
        let r = untangle(
            &mesh,
            &pose,
            &[0, 7],
            &UntangleOptions::default().with_budget(budget),
        );
        assert!(
            matches!(r, Err(DeformError::Stopped(s)) if s == why),
            "{r:?}"
        );
    }
}

#[test]
fn a_spent_budget_stops_the_bounded_solver_and_the_parameterisations() {
    let mesh = SurfaceMesh::from(&generate::disk(5, 0.1));
    for (budget, why) in spent() {
        let options = BoundedOptions::new(1.05).with_budget(budget.clone());
        let mut solver = BoundedDistortion::new(&mesh, &[], options.clone()).unwrap();
        let mut uv: Vec<[f64; 2]> = mesh.positions.iter().map(|p| [p[0] * 2.0, p[1]]).collect();
        let r = solver.solve_with(&mut uv, |_, _| {});
        assert!(
            matches!(r, Err(ParamError::Stopped(s)) if s == why),
            "{r:?}"
        );
        let r = flatten(&mesh, &[], options, &[], |_, _, _| {});
        assert!(
            matches!(r, Err(ParamError::Stopped(s)) if s == why),
            "{r:?}"
        );
        for method in [
            ParamMethod::Arap,
            ParamMethod::Asap,
            ParamMethod::SymmetricDirichlet,
            ParamMethod::Mips,
            ParamMethod::ArapNewton,
        ] {
            let mut p = Parameterization::new(
                &mesh,
                method,
                ParamOptions::default().with_budget(budget.clone()),
            )
            .unwrap();
            let r = p.solve();
            assert!(
                matches!(r, Err(ParamError::Stopped(s)) if s == why),
                "{method:?}: {r:?}"
            );
        }
        // The direct methods have no iterations to stop.
        let mut p = Parameterization::new(
            &mesh,
            ParamMethod::Tutte,
            ParamOptions::default().with_budget(budget.clone()),
        )
        .unwrap();
        assert!(p.solve().is_ok());
    }
}

#[test]
fn a_spent_budget_stops_the_compatible_mesh() {
    let a = generate::figure_picture(96, 0.0, 0.0);
    let b = generate::figure_picture(96, 1.5, 0.2);
    for (budget, why) in spent() {
        let options = InbetweenOptions::default()
            .with_vertices(300)
            .with_budget(budget);
        let r = compatible_mesh(&a, &b, &[], &options);
        assert!(
            matches!(r, Err(InbetweenError::Stopped(s)) if s == why),
            "{:?}",
            r.map(|_| ())
        );
        let r = bdmorph::inbetween::Inbetween::new(&a, &b, &[], &options);
        assert!(
            matches!(r, Err(InbetweenError::Stopped(s)) if s == why),
            "{:?}",
            r.map(|_| ())
        );
    }
}

// ---------------------------------------------------------------------------------------
// Property tests: random broken input into every public entry point of the modules.

/// A length near `n`: 0, short, exact, long.
fn length(n: usize, pick: usize) -> usize {
    [0, 1, n.saturating_sub(1), n, n + 1, n * 2][pick % 6]
}

/// A coordinate: mostly ordinary, sometimes NaN, infinite or huge.
fn coordinate() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -10.0f64..10.0,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(-1e300),
    ]
}

fn points(n: usize) -> impl Strategy<Value = Vec<[f64; 2]>> {
    proptest::collection::vec([coordinate(), coordinate()], 0..=n)
}

fn faces(n: u32) -> impl Strategy<Value = Vec<[u32; 3]>> {
    let index = prop_oneof![8 => 0..n.max(1), 1 => Just(n), 1 => Just(u32::MAX)];
    proptest::collection::vec([index.clone(), index.clone(), index], 0..24)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn param_entry_points_take_any_map(
        pick in 0usize..6,
        nan_at in proptest::option::of(0usize..64),
        pins in proptest::collection::vec((0u32..80, [coordinate(), coordinate()]), 0..3),
    ) {
        let mesh = SurfaceMesh::from(&generate::disk(3, 0.1));
        let n = mesh.positions.len();
        let mut uv: Vec<[f64; 2]> = mesh.positions.iter().map(|p| [p[0], p[1]]).collect();
        uv.resize(length(n, pick), [0.25, 0.5]);
        if let (Some(i), false) = (nan_at, uv.is_empty()) {
            let len = uv.len();
            uv[i % len][1] = f64::NAN;
        }
        let budget = Budget::unlimited().with_timeout(Duration::from_secs(30));
        no_panic("energies", || energies(&mesh, &uv)).ok();
        let options = BoundedOptions::new(2.0).with_iterations(50).with_budget(budget.clone());
        let built = no_panic("BoundedDistortion::new", || BoundedDistortion::new(&mesh, &pins, options));
        if let Ok(mut solver) = built {
            let r = no_panic("solve_with", || solver.solve_with(&mut uv, |_, _| {}));
            if uv.len() != n {
                let is_uv_length = matches!(r, Err(ParamError::UvLength { .. }));
                prop_assert!(is_uv_length);
            }
            no_panic("iterate", || solver.iterate(&mut uv)).ok();
        }
        let options = ParamOptions::default().with_iterations(20).with_budget(budget);
        if let Ok(mut p) = no_panic("Parameterization::new", || Parameterization::new(&mesh, ParamMethod::Arap, options)) {
            no_panic("solve", || p.solve()).ok();
        }
    }

    #[test]
    fn parts_entry_points_take_any_indices(
        n in 0usize..12,
        faces in faces(12),
        joints in proptest::collection::vec([0u32..16, 0u32..16], 0..4),
        positions in points(12),
    ) {
        let r = no_panic("pieces_of", || pieces_of(&faces, n));
        let in_range = faces.iter().flatten().all(|&v| (v as usize) < n);
        prop_assert_eq!(r.is_ok(), in_range);
        if let Ok((of, count)) = r {
            prop_assert_eq!(of.len(), n);
            prop_assert!(of.iter().all(|&p| p == u32::MAX || (p as usize) < count));
        }
        let rest = PlanarMesh { positions: positions.clone(), faces: faces.clone() };
        let mut placement = no_panic("Placement::new", || Placement::new(&rest, &joints));
        let mut out = positions.clone();
        no_panic("Placement::apply", || placement.apply(&mut out));
        no_panic("Weld::new", || Weld::new(&rest, &joints));
        if let Ok(mut jointed) = no_panic("JointedDeformer::new", || {
            JointedDeformer::new(&rest, &joints, PoseMethod::arap())
        }) {
            let pins: Vec<u32> = joints.iter().map(|j| j[0]).collect();
            if no_panic("JointedDeformer::set_pins", || jointed.set_pins(&pins)).is_ok() {
                let targets = vec![[1.0, 2.0]; pins.len()];
                no_panic("JointedDeformer::drag", || jointed.drag(&targets)).ok();
            }
            no_panic("JointedDeformer::set_positions", || jointed.set_positions(&positions)).ok();
        }
    }

    #[test]
    fn a_character_takes_any_layers(
        layers in proptest::collection::vec(
            (0u32..24, 0u32..24, -30i64..60, -30i64..60, 0usize..3000, any::<u8>()),
            0..4,
        ),
        width in 0u32..64,
        height in 0u32..64,
        vertices in prop_oneof![Just(0usize), 3usize..300],
    ) {
        let layered = Layered {
            width,
            height,
            layers: layers
                .iter()
                .enumerate()
                .map(|(i, &(w, h, left, top, len, alpha))| Layer {
                    name: format!("layer {i}"),
                    // The pixels' length is sometimes not width x height x 4.
                    image: Image {
                        width: w,
                        height: h,
                        rgba: if len % 2 == 0 {
                            vec![alpha; (w * h * 4) as usize]
                        } else {
                            vec![alpha; len]
                        },
                    },
                    left,
                    top,
                })
                .collect(),
            notes: vec![],
        };
        let options = CharacterOptions::default().with_vertices(vertices);
        no_panic("character", || character(&layered, &options)).ok();
    }

    #[test]
    fn inbetween_entry_points_take_any_layout(
        pick in 0usize..6,
        bad in proptest::option::of((0usize..64, coordinate())),
        t in coordinate(),
    ) {
        let a = generate::disk(3, 0.1);
        let n = a.positions.len();
        let mut b = generate::bend(&a, 0.3).positions;
        b.resize(length(n, pick), [0.0, 0.0]);
        if let (Some((i, x)), false) = (bad, b.is_empty()) {
            let len = b.len();
            b[i % len][0] = x;
        }
        let lerp = no_panic("linear_frame", || linear_frame(&a.positions, &b, t));
        prop_assert_eq!(lerp.len(), n.min(b.len()));
        let built = no_panic("ArapInterpolation::new", || ArapInterpolation::new(&a, &b));
        let finite = b.iter().flatten().all(|c| c.is_finite());
        if b.len() != n || !finite {
            prop_assert!(built.is_err());
        }
        if let Ok(mut arap) = built {
            let frame = no_panic("ArapInterpolation::frame", || arap.frame(t));
            if t.is_finite() {
                prop_assert_eq!(frame.map(|f| f.len()).ok(), Some(n));
            } else {
                prop_assert!(frame.is_err());
            }
        }
    }

    #[test]
    fn render_takes_any_mesh(
        positions in points(10),
        faces in faces(10),
        width in 0u32..48,
        height in 0u32..48,
        corner_uv in proptest::option::of(proptest::collection::vec(
            [
                [coordinate(), coordinate()],
                [coordinate(), coordinate()],
                [coordinate(), coordinate()],
            ],
            0..12,
        )),
        depth in proptest::option::of(proptest::collection::vec(any::<i8>(), 0..12)),
        view in [coordinate(), coordinate(), coordinate(), coordinate()],
        transparent in any::<bool>(),
    ) {
        let texture = Image { width: 3, height: 2, rgba: vec![128; 24] };
        let drawing = Drawing {
            faces: &faces,
            corner_uv: corner_uv.as_deref(),
            texture: corner_uv.as_ref().map(|_| &texture),
            face_colours: None,
            depth: depth.as_deref(),
        };
        let view = Viewport { min: [view[0], view[1]], max: [view[2], view[3]] };
        let size = ImageSize { width, height };
        let background = if transparent { Background::Transparent } else { Background::WHITE };
        // (Whatever it returns: a picture, or an error for a size over a budget.)
        let _ = no_panic("render_on", || raster::render_on(&positions, &drawing, &view, size, background));
        let fitted = no_panic("Viewport::fit", || Viewport::fit([&positions[..]]));
        let _ = no_panic("render", || raster::render(&positions, &drawing, &fitted, size));
    }

    #[test]
    fn project_reading_takes_any_damage(
        cut in 0usize..4000,
        replace in proptest::option::of((0usize..4000, prop_oneof![
            Just("NaN"), Just("-1"), Just("1e309"), Just("4294967295"), Just("[]"), Just("null"), Just("\"x\""),
        ])),
    ) {
        let mesh = generate::disk(3, 0.1);
        let mut project = bdmorph::project::Project::new(&mesh, None);
        let mut second = project.keyframes[0].clone();
        second.time = 1.0;
        second.positions = generate::bend(&mesh, 0.3).positions;
        project.keyframes.push(second);
        let json = String::from_utf8(project.to_json()).unwrap();
        // Damage: a number (or a bracket) replaced by another value, or the text cut short.
        let mut damaged = json.clone();
        if let Some((at, with)) = replace {
            let starts: Vec<usize> = json
                .char_indices()
                .filter(|&(i, c)| (c.is_ascii_digit() || c == '[') && !json[..i].ends_with(|p: char| p.is_ascii_digit() || p == '.'))
                .map(|(i, _)| i)
                .collect();
            if !starts.is_empty() {
                let s = starts[at % starts.len()];
                let e = json[s..]
                    .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '-'))
                    .map_or(json.len(), |k| s + k.max(1));
                damaged = format!("{}{}{}", &json[..s], with, &json[e..]);
            }
        } else {
            damaged.truncate(cut.min(json.len()));
        }
        let parsed = no_panic("Project::from_json", || bdmorph::project::Project::from_json(damaged.as_bytes()));
        if let Ok(doc) = parsed {
            no_panic("Project::check", || doc.check()).ok();
            if let Ok(mut animation) = no_panic("Animation::new", || bdmorph::project::Animation::new(&doc)) {
                let mut out = vec![[0.0; 2]; doc.mesh.positions.len()];
                no_panic("Animation::frame_into", || animation.frame_into(0.5, &mut out)).ok();
                let mut short = vec![[0.0; 2]; 1];
                no_panic("Animation::frame_into short", || animation.frame_into(0.5, &mut short)).ok();
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// Pictures of any size and alpha, and point pairs anywhere (NaN included): a compatible
    /// mesh or a typed error, within a budget (a hang would be `Stopped`, never a stuck test).
    #[test]
    fn the_compatible_mesh_takes_any_pictures_and_pairs(
        wa in 0u32..40, ha in 0u32..40, wb in 0u32..40, hb in 0u32..40,
        seed in any::<u64>(),
        pairs in proptest::collection::vec(([coordinate(), coordinate()], [coordinate(), coordinate()]), 0..3),
        vertices in prop_oneof![Just(0usize), Just(2), 3usize..400],
    ) {
        let mut state = seed | 1;
        let mut noise = |w: u32, h: u32| {
            let rgba = (0..w * h * 4)
                .map(|_| {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    (state >> 56) as u8
                })
                .collect();
            Image { width: w, height: h, rgba }
        };
        let (a, b) = (noise(wa, ha), noise(wb, hb));
        let matches: Vec<Match> = pairs.iter().map(|&(a, b)| Match { a, b }).collect();
        let options = InbetweenOptions::default()
            .with_vertices(vertices)
            .with_budget(Budget::unlimited().with_timeout(Duration::from_secs(20)));
        let r = no_panic("compatible_mesh", || compatible_mesh(&a, &b, &matches, &options));
        if vertices < 3 {
            prop_assert!(r.is_err());
        }
    }
}
