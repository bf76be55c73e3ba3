//! Every public constructor that takes a mesh, given a broken one: an error, never a panic.
//!
//! A valid mesh (a triangulated disk) gets one defect at a random place: a face naming a
//! vertex out of range, a coordinate that is NaN or infinite, a face repeating a vertex, no
//! faces, no vertices, a degenerate (zero-area) face, a clockwise face. Each constructor runs
//! under `catch_unwind`: it must not panic on any of them, and it must refuse every defect
//! that no mesh of its kind may have (the first five; the last two are refused by the planar
//! systems, while a surface may be oriented either way and geodesics accept flat triangles
//! that a mollifier can repair).

use std::panic::{catch_unwind, AssertUnwindSafe};

use bdmorph::deform::{Deformer, PoseMethod};
use bdmorph::geodesic::{HeatGeodesics, HeatOptions};
use bdmorph::param::bounded::{BoundedDistortion, BoundedOptions};
use bdmorph::param::{energies, ParamMethod, ParamOptions, Parameterization};
use bdmorph::{generate, Blend, KeyframePath, Morph, MorphOptions, PlanarMesh, SurfaceMesh};
use proptest::prelude::*;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Defect {
    IndexOutOfRange,
    NotANumber,
    Infinite,
    RepeatedVertex,
    NoFaces,
    NoVertices,
    Degenerate,
    Clockwise,
}

impl Defect {
    const ALL: [Defect; 8] = [
        Defect::IndexOutOfRange,
        Defect::NotANumber,
        Defect::Infinite,
        Defect::RepeatedVertex,
        Defect::NoFaces,
        Defect::NoVertices,
        Defect::Degenerate,
        Defect::Clockwise,
    ];

    /// Whether no mesh of any kind may have it.
    fn always_refused(self) -> bool {
        !matches!(self, Defect::Degenerate | Defect::Clockwise)
    }
}

/// `mesh` with `defect` at a place chosen by `at`.
fn break_mesh(mesh: &PlanarMesh, defect: Defect, at: usize, far: u32) -> PlanarMesh {
    let mut m = mesh.clone();
    let (n, f) = (m.positions.len(), m.faces.len());
    let face = at % f;
    let vertex = at % n;
    match defect {
        Defect::IndexOutOfRange => m.faces[face][at % 3] = n as u32 + far,
        Defect::NotANumber => m.positions[vertex][at % 2] = f64::NAN,
        Defect::Infinite => m.positions[vertex][at % 2] = f64::INFINITY,
        Defect::RepeatedVertex => {
            let [a, _, c] = m.faces[face];
            m.faces[face] = [a, a, c];
        }
        Defect::NoFaces => m.faces.clear(),
        Defect::NoVertices => m.positions.clear(),
        Defect::Degenerate => {
            let [a, b, _] = m.faces[face];
            m.positions[b as usize] = m.positions[a as usize];
        }
        Defect::Clockwise => {
            let [a, b, c] = m.faces[face];
            m.faces[face] = [a, c, b];
        }
    }
    m
}

/// What `f` did: `Some(true)` for an error, `Some(false)` for success, `None` for a panic.
fn outcome<T, E>(f: impl FnOnce() -> Result<T, E>) -> Option<bool> {
    catch_unwind(AssertUnwindSafe(f)).ok().map(|r| r.is_err())
}

/// Runs every constructor on `bad` and checks the outcomes.
fn check_all(bad: &PlanarMesh, defect: Defect) -> Result<(), TestCaseError> {
    let other = PlanarMesh {
        positions: bad.positions.iter().map(|p| [p[0] * 1.1, p[1]]).collect(),
        faces: bad.faces.clone(),
    };
    let surface = SurfaceMesh::from(bad);
    let uv: Vec<[f64; 2]> = bad.positions.clone();
    let planar: Vec<(&str, Option<bool>)> = vec![
        ("PlanarMesh::validate", outcome(|| bad.validate())),
        (
            "Morph::new",
            outcome(|| Morph::new(bad, &other, MorphOptions::default())),
        ),
        (
            "Morph::new, inverted allowed",
            outcome(|| {
                Morph::new(
                    bad,
                    &other,
                    MorphOptions::default().with_allow_inverted(true),
                )
            }),
        ),
        (
            "Blend::new",
            outcome(|| Blend::new(&[bad.clone(), other.clone()])),
        ),
        (
            "KeyframePath::new",
            outcome(|| KeyframePath::new(&[bad.clone(), other.clone()])),
        ),
        (
            "Deformer::new kvf",
            outcome(|| Deformer::new(bad, PoseMethod::kvf())),
        ),
        (
            "Deformer::new arap",
            outcome(|| Deformer::new(bad, PoseMethod::arap())),
        ),
        (
            "Deformer::new bounded",
            outcome(|| Deformer::new(bad, PoseMethod::bounded(3.0))),
        ),
        (
            "compile",
            outcome(|| bdmorph::compile(&bad.positions, &bad.faces)),
        ),
    ];
    let mut surfaces: Vec<(&str, Option<bool>)> = vec![
        (
            "HeatGeodesics::new",
            outcome(|| HeatGeodesics::new(&surface, HeatOptions::default())),
        ),
        (
            "BoundedDistortion::new",
            outcome(|| BoundedDistortion::new(&surface, &[], BoundedOptions::new(3.0))),
        ),
        ("param::energies", outcome(|| energies(&surface, &uv))),
    ];
    for method in [
        ParamMethod::Tutte,
        ParamMethod::Lscm,
        ParamMethod::Arap,
        ParamMethod::SymmetricDirichlet,
    ] {
        let name = match method {
            ParamMethod::Tutte => "Parameterization::new tutte",
            ParamMethod::Lscm => "Parameterization::new lscm",
            ParamMethod::Arap => "Parameterization::new arap",
            _ => "Parameterization::new sd",
        };
        surfaces.push((
            name,
            outcome(|| Parameterization::new(&surface, method, ParamOptions::default())),
        ));
    }
    // The functions that return no error must not panic either.
    let quiet = [
        (
            "MeshInfo::of",
            catch_unwind(|| bdmorph::info::MeshInfo::of(&surface)).is_ok(),
        ),
        (
            "RestShape::new",
            catch_unwind(|| bdmorph::distortion::RestShape::new(&bad.positions, &bad.faces))
                .is_ok(),
        ),
        (
            "angle_lower_bound",
            catch_unwind(|| bdmorph::param::bounded::angle_lower_bound(&surface)).is_ok(),
        ),
        (
            "nearest_vertex",
            catch_unwind(|| bad.nearest_vertex([0.1, 0.2])).is_ok(),
        ),
    ];
    for (name, ok) in quiet {
        prop_assert!(ok, "{name} panicked on {defect:?}");
    }
    for (name, result) in planar.iter().chain(&surfaces) {
        prop_assert!(result.is_some(), "{name} panicked on {defect:?}");
    }
    for (name, result) in &planar {
        let tolerated = defect == Defect::Clockwise && name.contains("inverted allowed")
            // Vertices without triangles are a valid (empty) planar mesh; what uses it refuses.
            || defect == Defect::NoFaces && *name == "PlanarMesh::validate";
        if !tolerated && (defect.always_refused() || *name != "compile") {
            prop_assert_eq!(*result, Some(true), "{} accepted {:?}", name, defect);
        }
    }
    if defect.always_refused() {
        for (name, result) in &surfaces {
            // The energies of no triangles are those of an empty sum: a measurement, not an error.
            if defect == Defect::NoFaces && *name == "param::energies" {
                continue;
            }
            prop_assert_eq!(*result, Some(true), "{} accepted {:?}", name, defect);
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn every_constructor_refuses_a_broken_mesh_without_panicking(
        rings in 2usize..5,
        defect in 0usize..Defect::ALL.len(),
        at in 0usize..10_000,
        far in prop_oneof![Just(0u32), 1u32..1000, Just(u32::MAX / 2)],
    ) {
        let mesh = generate::disk(rings, 0.1);
        let far = far.min(u32::MAX - mesh.positions.len() as u32);
        let defect = Defect::ALL[defect];
        check_all(&break_mesh(&mesh, defect, at, far), defect)?;
    }
}

/// Each defect at least once, whatever the random cases drew.
#[test]
fn each_defect_is_refused() {
    let mesh = generate::disk(3, 0.1);
    for defect in Defect::ALL {
        for at in [0, 7, 23] {
            let bad = break_mesh(&mesh, defect, at, 5000);
            if let Err(e) = check_all(&bad, defect) {
                panic!("{defect:?} at {at}: {e}");
            }
        }
    }
}

/// The buffers of the `*_into` queries: a wrong length is an error, not a panic.
#[test]
fn output_buffers_of_the_wrong_length_are_errors() {
    let mesh = generate::disk(3, 0.1);
    let mut g =
        HeatGeodesics::new(&SurfaceMesh::from(&mesh), HeatOptions::default()).expect("geodesics");
    let n = mesh.positions.len();
    for len in [0, n - 1, n + 1] {
        let mut out = vec![0.0; len];
        let e = g.distance_into(&[0], &mut out).expect_err("wrong length");
        assert!(e.to_string().contains(&format!("{n} vertices")), "{e}");
    }
    let mut out = vec![0.0; n];
    g.distance_into(&[0], &mut out).expect("right length");
    let bent = generate::bend(&mesh, 0.5);
    let mut m = Morph::new(&mesh, &bent, MorphOptions::default()).expect("morph");
    let mut frame = vec![[0.0; 2]; n + 3];
    assert!(m.frame_into(0.5, &mut frame).is_err());
}
