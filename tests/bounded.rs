//! Bounded-distortion mappings: Tutte maps of the shared disks pushed under K = 2, 3, 5;
//! 2D deformations by handles, feasible and not; typed errors.

mod common;

use bdmorph::generate;
use bdmorph::param::bounded::{
    angle_lower_bound, distortion, flatten, BoundedDistortion, BoundedOptions,
};
use bdmorph::param::{ParamError, ParamMethod, ParamOptions, Parameterization};
use bdmorph::SurfaceMesh;

/// The largest distortion of a map.
fn largest(mesh: &SurfaceMesh, uv: &[[f64; 2]]) -> f64 {
    // Recompute independently of the solver: the affine map of each triangle.
    mesh.faces
        .iter()
        .map(|&[a, b, c]| {
            let p = |v: u32| mesh.positions[v as usize];
            let q = |v: u32| uv[v as usize];
            let (e1, e2) = (
                [p(b)[0] - p(a)[0], p(b)[1] - p(a)[1], p(b)[2] - p(a)[2]],
                [p(c)[0] - p(a)[0], p(c)[1] - p(a)[1], p(c)[2] - p(a)[2]],
            );
            let l1 = (e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]).sqrt();
            let x2 = (e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]) / l1;
            let y2 = ((e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]) - x2 * x2).sqrt();
            let (d1, d2) = (
                [q(b)[0] - q(a)[0], q(b)[1] - q(a)[1]],
                [q(c)[0] - q(a)[0], q(c)[1] - q(a)[1]],
            );
            // J = [d1 d2] [[l1, x2], [0, y2]]^-1.
            let inv = [[1.0 / l1, -x2 / (l1 * y2)], [0.0, 1.0 / y2]];
            let j = [
                [d1[0] * inv[0][0], d1[0] * inv[0][1] + d2[0] * inv[1][1]],
                [d1[1] * inv[0][0], d1[1] * inv[0][1] + d2[1] * inv[1][1]],
            ];
            distortion(j)
        })
        .fold(1.0, f64::max)
}

#[test]
fn shared_disks_are_pushed_under_the_bound() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    for rel in common::SHARED_DISKS {
        let mesh = bdmorph::io::read_mesh(dir.join(rel)).expect(rel);
        let tutte =
            Parameterization::new(&mesh, ParamMethod::Tutte, ParamOptions::default()).expect(rel);
        let start = largest(&mesh, tutte.uv());
        for k in [5.0, 3.0, 2.0] {
            // Known gap: on the hand, K = 2 is not met. Alternating projections stall at
            // 2.205 and the Newton finish ends in a local minimum of the excess at 2.1419
            // (the same from Tutte, LSCM, MIPS and symmetric Dirichlet starts; the lowest
            // bound met is 2.114): the run must stop by itself and say so.
            let stalls = rel.contains("hand") && k == 2.0;
            let mut uv = tutte.uv().to_vec();
            let mut bd = BoundedDistortion::new(&mesh, &[], BoundedOptions::new(k)).expect(rel);
            let report = bd.solve_with(&mut uv, |_, _| {}).expect(rel);
            if stalls {
                eprintln!("{rel}: K = {k} not met: {report:?}");
                assert!(!report.converged && report.stalled, "{report:?}");
                assert!(report.inverted == 0 && !report.worst.is_empty());
                assert!(report.newton_iterations > 0, "{report:?}");
                assert!(report.max_distortion < 2.15, "{report:?}");
                assert!(report.iterations < 1000, "stops by itself: {report:?}");
                continue;
            }
            eprintln!(
                "{rel}: Tutte distortion {start:.1} -> {:.4} under K = {k} in {} iterations, {:.2} s",
                report.max_distortion, report.iterations, report.seconds
            );
            assert!(report.converged, "{rel} K = {k}: {report:?}");
            assert_eq!(report.inverted, 0);
            let end = largest(&mesh, &uv);
            assert!(end <= k * (1.0 + 1e-3), "{rel} K = {k}: {end}");
        }
        if rel.contains("camelhead") {
            assert!(
                start > 100.0,
                "the camel head's Tutte map is distorted: {start}"
            );
        }
    }
}

#[test]
fn generated_disks_are_pushed_under_the_bound() {
    let cap = generate::sphere_cap(4, 0.0);
    let tutte =
        Parameterization::new(&cap, ParamMethod::Tutte, ParamOptions::default()).expect("tutte");
    for k in [1.2, 2.0] {
        let mut uv = tutte.uv().to_vec();
        let mut bd = BoundedDistortion::new(&cap, &[], BoundedOptions::new(k)).expect("set up");
        let report = bd.solve_with(&mut uv, |_, _| {}).expect("solve");
        assert!(
            report.converged && report.inverted == 0,
            "K = {k}: {report:?}"
        );
        assert!(largest(&cap, &uv) <= k * (1.0 + 1e-3));
    }
}

/// Where the bound cannot be met, the Newton finish ends by itself with a lower largest
/// distortion than alternating projections alone, and without inverted triangles (the
/// projections alone end with some on this finger).
#[test]
fn the_newton_finish_lowers_what_projections_alone_leave() {
    let mesh = generate::finger(6, 8, 0.6);
    let tutte =
        Parameterization::new(&mesh, ParamMethod::Tutte, ParamOptions::default()).expect("tutte");
    let run = |finish: bool| {
        let mut uv = tutte.uv().to_vec();
        let options = BoundedOptions::new(1.5)
            .with_iterations(1500)
            .with_newton_finish(finish);
        let mut bd = BoundedDistortion::new(&mesh, &[], options).expect("set up");
        let report = bd.solve_with(&mut uv, |_, _| {}).expect("solve");
        // The report's largest distortion is the map's (two computations of it, to
        // rounding).
        let measured = largest(&mesh, &uv);
        assert!(
            report.max_distortion == measured
                || (report.max_distortion - measured).abs() <= 1e-12 * measured,
            "{} vs {measured}",
            report.max_distortion
        );
        report
    };
    let alone = run(false);
    let finished = run(true);
    eprintln!("projections alone: {alone:?}\nwith the Newton finish: {finished:?}");
    assert!(!alone.converged && !alone.stalled && alone.newton_iterations == 0);
    assert_eq!(alone.iterations, 1500);
    assert!(!finished.converged && finished.stalled, "{finished:?}");
    assert!(finished.newton_iterations > 0 && finished.iterations < 1500);
    assert_eq!(finished.inverted, 0);
    assert!(finished.max_distortion < alone.max_distortion);
    assert!(finished.max_distortion < 1.8, "{finished:?}");
    // Met comfortably above that: alternating projections alone suffice.
    let mut uv = tutte.uv().to_vec();
    let mut bd = BoundedDistortion::new(&mesh, &[], BoundedOptions::new(1.8)).expect("set up");
    let report = bd.solve_with(&mut uv, |_, _| {}).expect("solve");
    assert!(
        report.converged && report.newton_iterations == 0,
        "{report:?}"
    );
}

fn planar(mesh: &bdmorph::PlanarMesh) -> SurfaceMesh {
    SurfaceMesh {
        positions: mesh.positions.iter().map(|p| [p[0], p[1], 0.0]).collect(),
        faces: mesh.faces.clone(),
        texcoords: None,
    }
}

#[test]
fn handles_deform_a_planar_mesh_within_the_bound() {
    let disk = generate::disk(10, 0.2);
    let mesh = planar(&disk);
    // The centre stays, a rim vertex is pulled out to 1.8 times the radius, another is
    // pushed in: a pull that forces distortion.
    let rim = disk.positions.len() - 1;
    let other = disk.positions.len() - 16;
    let q = disk.positions[other];
    let pins = vec![
        (0u32, disk.positions[0]),
        (
            rim as u32,
            [1.8 * disk.positions[rim][0], 1.8 * disk.positions[rim][1]],
        ),
        (other as u32, [0.8 * q[0], 0.8 * q[1]]),
    ];
    let mut uv = disk.positions.clone();
    let before = {
        let mut moved = uv.clone();
        for &(v, t) in &pins {
            moved[v as usize] = t;
        }
        largest(&mesh, &moved)
    };
    let mut bd = BoundedDistortion::new(&mesh, &pins, BoundedOptions::new(2.5)).expect("set up");
    let report = bd.solve_with(&mut uv, |_, _| {}).expect("solve");
    eprintln!("deform: pinned start {before:.2} -> {report:?}");
    assert!(report.converged, "{report:?}");
    assert_eq!(report.inverted, 0);
    assert!(largest(&mesh, &uv) <= 2.5 * (1.0 + 1e-3));
    for &(v, t) in &pins {
        assert!(
            (uv[v as usize][0] - t[0]).abs() < 1e-12 && (uv[v as usize][1] - t[1]).abs() < 1e-12
        );
    }
    // The handle pulled the rim: the map is far from the identity.
    assert!(before > 2.5);
}

#[test]
fn infeasible_handles_are_reported_with_the_worst_triangles() {
    // Three handles in a shape that is not similar to theirs cannot be met by a conformal
    // (K = 1) map of a connected mesh.
    let disk = generate::disk(5, 0.2);
    let mesh = planar(&disk);
    let n = disk.positions.len();
    let pins = vec![
        (0u32, [0.0, 0.0]),
        ((n - 1) as u32, [3.0, 0.0]),
        ((n - 8) as u32, [0.0, 0.3]),
    ];
    let mut uv = disk.positions.clone();
    let mut bd =
        BoundedDistortion::new(&mesh, &pins, BoundedOptions::new(1.0).with_iterations(200))
            .expect("set up");
    let report = bd.solve_with(&mut uv, |_, _| {}).expect("solve");
    assert!(!report.converged, "{report:?}");
    assert_eq!(report.iterations, 200);
    assert!(report.max_distortion > 1.001);
    assert!(!report.worst.is_empty() && report.worst[0].1 >= report.worst.last().unwrap().1);
    assert!(report.constraint_error < 1e-12, "pins are hard constraints");
}

#[test]
fn bad_bounds_and_pins_are_typed_errors() {
    let mesh = planar(&generate::disk(3, 0.0));
    assert!(matches!(
        BoundedDistortion::new(&mesh, &[], BoundedOptions::new(0.5)),
        Err(ParamError::BadBound(_))
    ));
    assert!(matches!(
        BoundedDistortion::new(&mesh, &[], BoundedOptions::new(f64::NAN)),
        Err(ParamError::BadBound(_))
    ));
    assert!(matches!(
        BoundedDistortion::new(&mesh, &[(999, [0.0, 0.0])], BoundedOptions::new(2.0)),
        Err(ParamError::BadPin { vertex: 999, .. })
    ));
}

#[test]
fn a_smaller_bound_for_inverted_triangles_untangles_a_fold_sooner() {
    // A disk with its rim held and four interior vertices pushed across their neighbours
    // (to three times their distance), pushed under a loose bound K = 50: both ways end
    // within the bound with nothing inverted; the inverted triangles' own bound of 2 gets
    // there in far fewer iterations (measured: 523 and 4).
    let disk = generate::disk(12, 0.2);
    let mesh = planar(&disk);
    let n = disk.positions.len();
    let pins: Vec<(u32, [f64; 2])> = (n - 72..n).map(|v| (v as u32, disk.positions[v])).collect();
    let mut start = disk.positions.clone();
    for v in [20usize, 100, 200, 300] {
        let w = disk
            .faces
            .iter()
            .find(|f| f.contains(&(v as u32)))
            .map(|f| if f[0] as usize == v { f[1] } else { f[0] })
            .expect("a face") as usize;
        let (a, b) = (start[v], start[w]);
        start[v] = [a[0] + 3.0 * (b[0] - a[0]), a[1] + 3.0 * (b[1] - a[1])];
    }
    let mut runs = Vec::new();
    for inverted in [None, Some(2.0)] {
        let mut options = BoundedOptions::new(50.0).with_iterations(5000);
        if let Some(k) = inverted {
            options = options.with_inverted_bound(k);
        }
        let mut uv = start.clone();
        let mut bd = BoundedDistortion::new(&mesh, &pins, options).expect("set up");
        let before = bd.solve_with(&mut start.clone(), |_, _| {}).expect("solve");
        let report = bd.solve_with(&mut uv, |_, _| {}).expect("solve");
        assert_eq!(before.iterations, report.iterations, "repeatable");
        eprintln!("inverted bound {inverted:?}: {report:?}");
        assert!(report.converged && report.inverted == 0, "{report:?}");
        assert!(largest(&mesh, &uv) <= 50.0 * (1.0 + 1e-3));
        runs.push(report.iterations);
    }
    assert!(10 * runs[1] < runs[0], "{runs:?}");
    for k in [0.5, f64::NAN] {
        assert!(matches!(
            BoundedDistortion::new(&mesh, &[], BoundedOptions::new(3.0).with_inverted_bound(k)),
            Err(ParamError::BadBound(_))
        ));
    }
}

/// A cone: `n` rim vertices on the unit circle (the boundary) and an apex at height `h`.
fn cone(n: u32, h: f64) -> SurfaceMesh {
    let mut positions: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * f64::from(i) / f64::from(n);
            [a.cos(), a.sin(), 0.0]
        })
        .collect();
    positions.push([0.0, 0.0, h]);
    let faces = (0..n).map(|i| [i, (i + 1) % n, n]).collect();
    SurfaceMesh {
        positions,
        faces,
        texcoords: None,
    }
}

/// The angle argument on a sharp cone has a closed form: the apex's `n` equal angles `θ`
/// must open to `2π / n` each, and a bound `K` opens an angle at most to
/// `2 atan(K tan(θ/2))`, so `K >= tan(π/n) / tan(θ/2)`. Below it the bound is reported
/// infeasible with that vertex as evidence and no further start is tried; above it, met.
#[test]
fn issue_23_infeasibility_needs_evidence_the_angle_bound_of_a_cone() {
    let (n, h) = (6u32, 3.0);
    let mesh = cone(n, h);
    let theta = 2.0 * ((std::f64::consts::PI / f64::from(n)).sin() / (1.0 + h * h).sqrt()).asin();
    let expected = (std::f64::consts::PI / f64::from(n)).tan() / (0.5 * theta).tan();
    let lb = angle_lower_bound(&mesh);
    assert!(
        (lb.bound - expected).abs() < 1e-9 * expected,
        "{lb:?} vs {expected}"
    );
    assert_eq!(lb.vertex, Some(n));
    assert!((lb.angle_sum - f64::from(n) * theta).abs() < 1e-12);

    let below = BoundedOptions::new(0.9 * expected).with_iterations(300);
    let flat = flatten(
        &mesh,
        &[],
        below,
        &[ParamMethod::Lscm, ParamMethod::Tutte],
        |_, _, _| {},
    )
    .expect("flatten");
    assert!(flat.infeasible() && !flat.converged(), "{flat:?}");
    assert_eq!(
        flat.attempts.len(),
        1,
        "no second start once proved infeasible"
    );
    // No map beats the bound: the solver's best is at or above it.
    assert!(flat.report().max_distortion >= expected * (1.0 - 1e-9));

    let above = BoundedOptions::new(1.05 * expected);
    let flat = flatten(&mesh, &[], above, &[ParamMethod::Tutte], |_, _, _| {}).expect("flatten");
    assert!(flat.converged() && !flat.infeasible(), "{flat:?}");
    assert!(largest(&mesh, &flat.uv) <= 1.05 * expected * (1.0 + 1e-3));
}

/// Issue 23: a start that stalls does not prove the bound infeasible. `flatten` tries the
/// next start, reports every attempt, and keeps the best map; the coarse finger at K = 1.5
/// stalls from LSCM and from Tutte (above the angle argument's bound, so "not met", not
/// "infeasible").
#[test]
fn issue_23_a_stalled_start_is_followed_by_the_other() {
    let mesh = generate::finger(6, 8, 0.6);
    let options = BoundedOptions::new(1.5).with_iterations(1500);
    let mut seen = Vec::new();
    let flat = flatten(
        &mesh,
        &[],
        options,
        &[ParamMethod::Lscm, ParamMethod::Tutte],
        |i, _, _| {
            if seen.last() != Some(&i) {
                seen.push(i);
            }
        },
    )
    .expect("flatten");
    eprintln!("{flat:#?}");
    assert_eq!(seen, [0, 1]);
    let starts: Vec<ParamMethod> = flat.attempts.iter().map(|a| a.start).collect();
    assert_eq!(starts, [ParamMethod::Lscm, ParamMethod::Tutte]);
    assert!(flat
        .attempts
        .iter()
        .all(|a| a.report.stalled && !a.report.converged));
    assert!(
        !flat.infeasible() && flat.lower_bound.bound < 1.5,
        "{flat:?}"
    );
    let best = flat
        .attempts
        .iter()
        .map(|a| a.report.max_distortion)
        .fold(f64::INFINITY, f64::min);
    assert_eq!(flat.report().max_distortion, best);
    assert!((largest(&mesh, &flat.uv) - flat.report().max_distortion).abs() < 1e-9);
    // Where the first start meets the bound, it is the only one tried.
    let flat = flatten(
        &mesh,
        &[],
        BoundedOptions::new(2.5),
        &[ParamMethod::Lscm, ParamMethod::Tutte],
        |_, _, _| {},
    )
    .expect("flatten");
    assert!(flat.converged() && flat.attempts.len() == 1, "{flat:?}");
}

/// The shared disks' angle bounds: what the stalls at the hand's K = 2 do and do not prove.
#[test]
fn issue_23_shared_disks_angle_bounds() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    for rel in common::SHARED_DISKS {
        let mesh = bdmorph::io::read_mesh(dir.join(rel)).expect(rel);
        let lb = angle_lower_bound(&mesh);
        eprintln!("{rel}: {lb:?}");
        // Every bound met in `shared_disks_are_pushed_under_the_bound` is above it.
        assert!(lb.bound < 2.0, "{rel}: {lb:?}");
    }
}
