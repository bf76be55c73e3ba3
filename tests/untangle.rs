//! Repairing a pose with flipped triangles (`bdmorph::deform::untangle`): folds of a thin arm
//! repaired within the stated bound (or left as they were), poses without flips, pieces
//! without pins, holes, hopeless pins, rigid motions.

mod common;

use bdmorph::deform::{
    untangle, ArapOptions, DeformError, Deformer, KvfOptions, PoseMethod, UntangleOptions,
    Untangled,
};
use bdmorph::meshing::{mesh_picture, MeshOptions, PictureOptions};
use bdmorph::{generate, PlanarMesh};
use common::max_distance;

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

/// A torso, a head and a thin arm (36 pixels across, 230 long) on a 512-pixel picture,
/// meshed to about `vertices`; positions in pixels, y up.
fn character(vertices: usize) -> PlanarMesh {
    let s = 512.0;
    let picture = generate::picture(512, 512, |x, y| {
        let p = [x / s, y / s];
        let torso = generate::capsule_distance(p, [0.45, 0.45], [0.45, 0.7], 0.13);
        let head = generate::capsule_distance(p, [0.45, 0.2], [0.45, 0.2], 0.09);
        let arm = generate::capsule_distance(p, [0.5, 0.42], [0.95, 0.42], 0.018);
        s * torso.min(head).min(arm)
    });
    let options = MeshOptions::default().with_vertices(vertices);
    mesh_picture(&picture, &PictureOptions::default(), &options)
        .expect("meshed")
        .mesh
}

/// The character held at three points of the torso, its arm tip pulled by `(dx, dy)` pixels
/// in one fast drag: ARAP with two iterations, as one mouse move that lands far away (the
/// globalised KVF folds it only at the far pulls). Returns the mesh, the pins and the
/// pose.
fn fast_pull(vertices: usize, dx: f64, dy: f64) -> (PlanarMesh, Vec<u32>, Vec<[f64; 2]>) {
    let rest = character(vertices);
    let p = &rest.positions;
    let arm_y = 512.0 * (1.0 - 0.42);
    let pins: Vec<u32> = [
        [230.0, 200.0],
        [230.0, 100.0],
        [230.0, 400.0],
        [486.0, arm_y],
    ]
    .iter()
    .map(|&q| nearest(p, q))
    .collect();
    let fast = PoseMethod::Arap(ArapOptions::default().with_iterations(2));
    let mut pose = Deformer::new(&rest, fast).expect("set up");
    pose.set_pins(&pins).expect("pins");
    let mut targets: Vec<[f64; 2]> = pins.iter().map(|&v| p[v as usize]).collect();
    targets[3] = [targets[3][0] + dx, targets[3][1] + dy];
    pose.drag(&targets).expect("drag");
    let positions = pose.positions().to_vec();
    (rest, pins, positions)
}

/// The largest distortion of an unflipped triangle, measured here.
fn worst(mesh: &PlanarMesh, pose: &[[f64; 2]]) -> f64 {
    let mut each = vec![0.0; mesh.faces.len()];
    bdmorph::distortion::RestShape::new(&mesh.positions, &mesh.faces)
        .distortion_into(pose, &mut each);
    each.iter()
        .copied()
        .filter(|d| d.is_finite())
        .fold(1.0, f64::max)
}

/// Every number of the result is finite, and the report agrees with a count made here.
fn check_honest(rest: &PlanarMesh, pose: &[[f64; 2]], out: &Untangled) {
    assert!(out.positions.iter().flatten().all(|c| c.is_finite()));
    let r = &out.report;
    assert!(r.max_distortion.is_finite() && r.max_move.is_finite() && r.seconds.is_finite());
    assert_eq!(r.flipped_before, flipped(rest, pose));
    assert_eq!(r.flipped_after, flipped(rest, &out.positions));
    assert_eq!(
        r.success,
        r.flipped_after == 0 && r.max_distortion <= r.limit * (1.0 + 1e-3)
    );
    let moved = out
        .positions
        .iter()
        .zip(pose)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(r.moved_vertices, moved);
    let largest = max_distance(&out.positions, pose) / rest.diameter();
    assert!((r.max_move - largest).abs() <= 1e-12 * largest.max(1.0));
}

/// A vertex of `mesh` away from the boundary, nearest to `q`, and one of its neighbours.
fn interior_edge(mesh: &PlanarMesh, q: [f64; 2]) -> (u32, u32) {
    let v = nearest(&mesh.positions, q);
    let w = mesh
        .faces
        .iter()
        .find(|f| f.contains(&v))
        .map(|f| if f[0] == v { f[1] } else { f[0] })
        .expect("a face around the vertex");
    (v, w)
}

/// `pose` with vertex `v` pushed across its neighbour `w`, to `1.6` times their distance
/// beyond where it was: the triangles around `v` on the far side fold over.
fn push_across(pose: &mut [[f64; 2]], v: u32, w: u32) {
    let (a, b) = (pose[v as usize], pose[w as usize]);
    pose[v as usize] = [a[0] + 1.6 * (b[0] - a[0]), a[1] + 1.6 * (b[1] - a[1])];
}

/// Each vertex's distance in edges from `seeds` (`usize::MAX` when not connected).
fn hops_from(mesh: &PlanarMesh, seeds: &[u32]) -> Vec<usize> {
    let mut dist = vec![usize::MAX; mesh.positions.len()];
    for &s in seeds {
        dist[s as usize] = 0;
    }
    for d in 0.. {
        let mut any = false;
        for f in &mesh.faces {
            let near = f.iter().any(|&v| dist[v as usize] == d);
            for &v in f {
                if near && dist[v as usize] == usize::MAX {
                    dist[v as usize] = d + 1;
                    any = true;
                }
            }
        }
        if !any {
            break;
        }
    }
    dist
}

#[test]
fn a_thin_arm_folded_by_one_fast_drag_is_repaired_within_the_stated_bound() {
    // The arm (36 pixels across) pulled by 80 to 330 pixels in one fast drag, some across
    // the body: folded. The repair states its bound (at least 10; the pose's distortion
    // away from the fold when that is more) and meets it over the whole pose, measured
    // here, with the pins where they were and the torso untouched.
    for (dx, dy) in [
        (-80.0, -40.0),
        (-150.0, -60.0),
        (-300.0, -100.0),
        (-200.0, 150.0),
    ] {
        let (rest, pins, pose) = fast_pull(3000, dx, dy);
        let before = flipped(&rest, &pose);
        let folded = worst(&rest, &pose);
        eprintln!("pull ({dx}, {dy}): {before} flipped, distortion {folded:.1}");
        assert!(before > 0, "pull ({dx}, {dy}): folded");
        let out = untangle(&rest, &pose, &pins, &UntangleOptions::default()).expect("untangle");
        let r = out.report;
        eprintln!("pull ({dx}, {dy}): {r:?}");
        check_honest(&rest, &pose, &out);
        assert!(r.success && r.flipped_after == 0, "{r:?}");
        assert!(r.limit >= 10.0, "{r:?}");
        let after = worst(&rest, &out.positions);
        assert!(after <= r.limit * (1.0 + 1e-3), "{after} over {r:?}");
        assert!(
            (after - r.max_distortion).abs() <= 1e-9 * after,
            "{after}: {r:?}"
        );
        for &v in &pins {
            assert_eq!(out.positions[v as usize], pose[v as usize], "pin {v}");
        }
        assert!(r.max_move < 0.05, "{r:?}");
        assert!(r.moved_vertices < rest.positions.len() / 10, "{r:?}");
        let torso_moved = (0..rest.positions.len())
            .filter(|&v| rest.positions[v][0] < 200.0 && out.positions[v] != pose[v])
            .count();
        assert_eq!(torso_moved, 0, "the torso, far from the arm's fold, stays");
    }
}

#[test]
fn a_repair_that_cannot_meet_its_bound_leaves_the_pose_unchanged() {
    // The same fold, and a limit no unfolding can meet (1.01: every triangle nearly as at
    // rest, with the arm pulled): the pose comes back as it was, and the report says what
    // the best attempt reached. Asked for its best effort, the repair returns that attempt.
    let (rest, pins, pose) = fast_pull(3000, -150.0, -60.0);
    let before = flipped(&rest, &pose);
    assert!(before > 0);
    let strict = UntangleOptions::default().with_limit(1.01);
    let out = untangle(&rest, &pose, &pins, &strict).expect("untangle");
    let r = out.report;
    eprintln!("limit 1.01: {r:?}");
    check_honest(&rest, &pose, &out);
    assert!(!r.success && r.limit == 1.01, "{r:?}");
    assert_eq!(out.positions, pose);
    assert_eq!(
        (r.flipped_after, r.moved_vertices, r.bound),
        (before, 0, None)
    );
    assert!(
        r.best_distortion.is_finite() && r.best_distortion > 1.01,
        "{r:?}"
    );
    let best = untangle(&rest, &pose, &pins, &strict.with_best_effort(true)).expect("untangle");
    check_honest(&rest, &pose, &best);
    let b = best.report;
    eprintln!("best effort: {b:?}");
    assert!(!b.success, "{b:?}");
    assert_eq!(b.flipped_after, r.best_flipped, "{b:?}");
    assert_eq!(b.max_distortion, r.best_distortion, "{b:?}");
}

#[test]
fn a_pose_without_flips_comes_back_bit_for_bit() {
    // A flip-free KVF pull, and the figure's waving pose.
    let rest = character(3000);
    let pins: Vec<u32> = [
        [230.0, 200.0],
        [230.0, 100.0],
        [230.0, 400.0],
        [486.0, 512.0 * 0.58],
    ]
    .iter()
    .map(|&q| nearest(&rest.positions, q))
    .collect();
    let flip_free = PoseMethod::Kvf(KvfOptions::default().with_flip_free(true));
    let mut kvf = Deformer::new(&rest, flip_free).expect("set up");
    kvf.set_pins(&pins).expect("pins");
    let mut targets: Vec<[f64; 2]> = pins.iter().map(|&v| rest.positions[v as usize]).collect();
    targets[3] = [targets[3][0] - 60.0, targets[3][1] + 80.0];
    kvf.drag(&targets).expect("drag");
    let pose = kvf.positions().to_vec();
    let figure = generate::figure(0.01);
    let wave = generate::wave(&figure, 1.0).positions;
    for (rest, pins, pose) in [(rest, pins, pose), (figure, vec![], wave)] {
        assert_eq!(flipped(&rest, &pose), 0);
        let out = untangle(&rest, &pose, &pins, &UntangleOptions::default()).expect("untangle");
        let bits =
            |p: &[[f64; 2]]| -> Vec<[u64; 2]> { p.iter().map(|q| q.map(f64::to_bits)).collect() };
        assert_eq!(bits(&out.positions), bits(&pose));
        let r = out.report;
        assert!(r.success && r.flipped_before == 0 && r.flipped_after == 0);
        assert_eq!((r.iterations, r.attempts, r.moved_vertices), (0, 0, 0));
        assert_eq!((r.bound, r.max_move), (None, 0.0));
        check_honest(&rest, &pose, &out);
    }
}

/// A plate with two holes and, to its right, a disk: two pieces, the plate's vertices first.
fn plate_and_disk() -> (PlanarMesh, usize) {
    let mut mesh = generate::plate_with_two_holes(0.002);
    let offset = mesh.positions.len();
    let disk = generate::disk(12, 0.2);
    mesh.positions
        .extend(disk.positions.iter().map(|p| [p[0] + 4.0, p[1]]));
    mesh.faces
        .extend(disk.faces.iter().map(|f| f.map(|v| v + offset as u32)));
    (mesh, offset)
}

#[test]
fn a_piece_without_pins_is_repaired_and_the_other_left_alone() {
    let (mesh, offset) = plate_and_disk();
    let n = mesh.positions.len();
    // Fold the plate beside each of its holes (centred at x = -0.75 and 0.75, radii 0.3
    // and 0.25): a vertex pushed across its neighbour at each.
    let mut pose = mesh.positions.clone();
    let mut pushed = Vec::new();
    for q in [[-0.75, 0.42], [0.75, -0.38]] {
        let (v, w) = interior_edge(&mesh, q);
        push_across(&mut pose, v, w);
        pushed.push(v);
    }
    // Pushing a vertex flips triangles around it only; the repair frees 4 rings around
    // those triangles' vertices, and the triangles touching them: nothing further than 6
    // edges from a pushed vertex can move.
    let hops = hops_from(&mesh, &pushed);
    let before = flipped(&mesh, &pose);
    assert!(before > 0);
    // No pin at all, and pins on the disk only: the plate has none either way.
    let disk_pins = [offset as u32, (n - 1) as u32];
    for pins in [&[][..], &disk_pins[..]] {
        let out = untangle(&mesh, &pose, pins, &UntangleOptions::default()).expect("untangle");
        let r = out.report;
        eprintln!("{} pins: {r:?}", pins.len());
        check_honest(&mesh, &pose, &out);
        assert!(r.success && r.flipped_before == before, "{r:?}");
        // The disk had no flip: not a bit of it moves.
        assert!((offset..n).all(|v| out.positions[v] == pose[v]));
        let far = (0..offset).filter(|&v| hops[v] > 6).count();
        let far_moved = (0..offset)
            .filter(|&v| hops[v] > 6 && out.positions[v] != pose[v])
            .count();
        assert!(far > offset / 2);
        assert_eq!(far_moved, 0, "{r:?}");
        assert!(r.max_move < 0.05, "{r:?}");
    }
}

#[test]
fn a_small_piece_without_pins_is_held_by_one_vertex() {
    // A 7 x 7 grid folded in the middle: the region covers it whole, so the vertex
    // furthest from the fold holds it; the repair mends the fold and the grid does not
    // slide away.
    let rest = generate::grid(7, 7, 0.1);
    let mut pose = rest.positions.clone();
    let (v, w) = interior_edge(&rest, [3.0, 3.0]);
    push_across(&mut pose, v, w);
    let out = untangle(&rest, &pose, &[], &UntangleOptions::default()).expect("untangle");
    let r = out.report;
    eprintln!("{r:?}");
    check_honest(&rest, &pose, &out);
    assert!(r.success && r.flipped_before > 0, "{r:?}");
    let hops = hops_from(&rest, &[v]);
    assert!(
        hops.iter().all(|&h| h <= 1 + r.rings as usize),
        "covered whole"
    );
    assert!(
        r.moved_vertices < rest.positions.len(),
        "one vertex held: {r:?}"
    );
    assert!(r.max_move < 0.15, "{r:?}");
}

#[test]
fn a_rigid_motion_of_a_folded_pose_changes_only_the_fold() {
    // A fold in a grid, then the whole pose turned and moved: with no pins, the repair
    // mends the fold and leaves the rest where the motion put it, and it is the same
    // repair as of the unmoved pose, moved.
    let rest = generate::grid(30, 30, 0.2);
    let mut folded = rest.positions.clone();
    let (v, w) = interior_edge(&rest, [12.0, 17.0]);
    push_across(&mut folded, v, w);
    let (s, c) = 2.1f64.sin_cos();
    let motion = |p: [f64; 2]| [c * p[0] - s * p[1] + 40.0, s * p[0] + c * p[1] - 7.0];
    let moved: Vec<[f64; 2]> = folded.iter().map(|&p| motion(p)).collect();
    let options = UntangleOptions::default();
    let still = untangle(&rest, &folded, &[], &options).expect("untangle");
    let out = untangle(&rest, &moved, &[], &options).expect("untangle");
    check_honest(&rest, &moved, &out);
    let r = out.report;
    eprintln!("{r:?}");
    assert!(r.success && r.flipped_before > 0, "{r:?}");
    assert_eq!(r.flipped_before, still.report.flipped_before);
    // Away from the fold (more than 6 edges from the pushed vertex: see the test above),
    // nothing moved at all.
    let hops = hops_from(&rest, &[v]);
    for (u, &h) in hops.iter().enumerate() {
        if h > 6 {
            assert_eq!(out.positions[u], moved[u], "vertex {u}");
        }
    }
    let expected: Vec<[f64; 2]> = still.positions.iter().map(|&p| motion(p)).collect();
    let err = max_distance(&out.positions, &expected);
    assert!(err < 1e-6 * rest.diameter(), "{err}");
    assert!(r.max_move < 0.05, "{r:?}");
}

#[test]
fn pins_that_force_a_fold_are_reported_without_nan() {
    // 1. A triangle's three vertices pinned mirrored: no move can mend it. The other fold
    //    (a vertex pushed across) is mended; the report says one flip remains.
    let rest = generate::grid(12, 12, 0.0);
    let mut pose = rest.positions.clone();
    let f = rest.faces[40];
    let pins = f.to_vec();
    pose.swap(f[1] as usize, f[2] as usize);
    let (v, w) = interior_edge(&rest, [8.0, 8.0]);
    push_across(&mut pose, v, w);
    // Asked for its best effort (otherwise the pose given comes back, as it was).
    let options = UntangleOptions::default().with_iterations(600);
    let strict = untangle(&rest, &pose, &pins, &options).expect("untangle");
    assert!(!strict.report.success && strict.report.best_flipped == 1);
    assert_eq!(strict.positions, pose);
    let options = options.with_best_effort(true);
    let out = untangle(&rest, &pose, &pins, &options).expect("untangle");
    let r = out.report;
    eprintln!("pinned mirror: {r:?}");
    check_honest(&rest, &pose, &out);
    assert!(
        !r.success && r.flipped_after == 1 && r.flipped_before > 1,
        "{r:?}"
    );
    // What could move met the bound; raising it cannot help, so no second attempt.
    assert!(r.bound_met && r.attempts == 1, "{r:?}");
    for &p in &pins {
        assert_eq!(out.positions[p as usize], pose[p as usize]);
    }
    // 2. A disk's rim pinned where it is and its centre pinned outside the rim: every
    //    orientation-preserving map keeps the centre inside, so some triangle stays flipped.
    let disk = generate::disk(6, 0.1);
    let n = disk.positions.len();
    let mut pins: Vec<u32> = ((n - 36) as u32..n as u32).collect();
    pins.push(0);
    let mut pose = disk.positions.clone();
    pose[0] = [1.5, 0.2];
    let out = untangle(&disk, &pose, &pins, &options).expect("untangle");
    let r = out.report;
    eprintln!("centre outside: {r:?}");
    check_honest(&disk, &pose, &out);
    assert!(!r.success && r.flipped_after > 0, "{r:?}");
    assert!(r.attempts > 1 && r.iterations <= 600, "{r:?}");
    // No attempt left fewer flips: the pose given comes back, and the report says so.
    if r.flipped_after == r.flipped_before {
        assert_eq!((r.bound, r.moved_vertices), (None, 0), "{r:?}");
        assert_eq!(out.positions, pose);
    }
}

#[test]
fn bad_input_is_refused() {
    let rest = generate::grid(5, 5, 0.0);
    let pose = rest.positions.clone();
    let o = UntangleOptions::default();
    assert!(matches!(
        untangle(&rest, &pose[1..], &[], &o),
        Err(DeformError::PositionCount {
            expected: 25,
            got: 24
        })
    ));
    let mut nan = pose.clone();
    nan[3][1] = f64::NAN;
    assert!(matches!(
        untangle(&rest, &nan, &[], &o),
        Err(DeformError::NonFiniteTarget { index: 3 })
    ));
    assert!(matches!(
        untangle(&rest, &pose, &[0, 25], &o),
        Err(DeformError::PinOutOfRange { pin: 1, .. })
    ));
    assert!(matches!(
        untangle(&rest, &pose, &[4, 4], &o),
        Err(DeformError::PinnedTwice { vertex: 4 })
    ));
    for k in [0.5, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            untangle(&rest, &pose, &[], &o.clone().with_max_distortion(k)),
            Err(DeformError::BadBound(_))
        ));
    }
    let mut mirrored = rest.clone();
    mirrored.faces[0].swap(1, 2);
    assert!(matches!(
        untangle(&mirrored, &pose, &[], &o),
        Err(DeformError::Mesh(_))
    ));
}

/// The studio's Repair request on keyframe 2 of a 12 x 12 grid project: the reply, if it
/// refused, and the state's notes.
fn studio_repair(
    pose: Vec<[f64; 2]>,
    pins: Vec<u32>,
) -> (Option<String>, String, serde_json::Value) {
    use bdmorph::studio::project::{Keyframe, Project};
    use bdmorph::studio::protocol::Request;
    use bdmorph::studio::session::{Answer, Session};
    let mesh = generate::grid(12, 12, 0.0);
    let mut project = Project::new(&mesh, None);
    project.keyframes.push(Keyframe {
        time: 1.0,
        easing: "linear".into(),
        positions: pose,
        pins,
        drawing: None,
    });
    let dir = std::env::temp_dir().join(format!("bdmorph-untangle-studio-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let mut s = Session::new(project, dir, None, None).expect("a session");
    let reply = s.handle(Request::Repair { keyframe: Some(1) });
    let refused = reply.answers.iter().find_map(|a| match a {
        Answer::Text(t) => {
            let v: serde_json::Value = serde_json::from_str(t).ok()?;
            (v["type"] == "error").then(|| v["message"].as_str().unwrap_or("").to_owned())
        }
        Answer::Binary(_) => None,
    });
    let state: serde_json::Value = serde_json::from_str(&s.state_json()).expect("state");
    (refused, state["notes"].to_string(), state)
}

#[test]
fn the_studios_repair_states_its_bound_and_its_result() {
    // A fold the repair mends: the note gives the largest distortion and the bound.
    let rest = generate::grid(12, 12, 0.0);
    let mut pose = rest.positions.clone();
    let (v, w) = interior_edge(&rest, [5.0, 6.0]);
    push_across(&mut pose, v, w);
    let before = flipped(&rest, &pose);
    let (refused, notes, state) = studio_repair(pose.clone(), vec![0, 11]);
    assert_eq!(refused, None, "{notes}");
    assert_eq!(state["keyframes"][1]["flipped"], 0, "{notes}");
    assert!(
        notes.contains(&format!(
            "keyframe 2: {before} flipped triangles repaired; largest distortion"
        )) && notes.contains("(bound 10.0)"),
        "{notes}"
    );
    // A fold its pins hold (a triangle's three vertices pinned mirrored): refused, the
    // bound and the best attempt said, the pose unchanged.
    let f = rest.faces[40];
    pose.swap(f[1] as usize, f[2] as usize);
    let before = flipped(&rest, &pose);
    let (refused, notes, state) = studio_repair(pose, f.to_vec());
    let why = refused.expect("refused");
    assert!(
        why.contains(&format!(
            "the {before} flipped triangles cannot be repaired within distortion"
        )) && why.contains("the best attempt left 1 of them flipped")
            && why.contains("the pose is unchanged"),
        "{why}"
    );
    assert_eq!(state["keyframes"][1]["flipped"], before as u64, "{notes}");
}
