//! Meshes that are not one disk: holes, several pieces, keyframes listing the same triangles
//! differently, and keyframes with a few inverted triangles (issue 24).

mod common;

use bdmorph::distortion::RestShape;
use bdmorph::{generate, KeyframePath, MeshError, Morph, MorphError, MorphOptions, PlanarMesh};
use common::max_distance;

/// Whether segments `a-b` and `c-d` intersect or touch.
fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let orient = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    };
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    if d1 == 0.0 && d2 == 0.0 {
        // Collinear: they meet when their extents along the line overlap.
        let along = |p: [f64; 2]| (p[0] - a[0]) * (b[0] - a[0]) + (p[1] - a[1]) * (b[1] - a[1]);
        let (lo, hi) = (0.0, along(b));
        let (u, v) = (along(c).min(along(d)), along(c).max(along(d)));
        return u <= hi && v >= lo;
    }
    (d1 * d2 <= 0.0) && (d3 * d4 <= 0.0)
}

/// Every boundary loop of `mesh` at `positions` is a simple polygon, and no two loops meet.
fn loops_are_simple_and_apart(mesh: &PlanarMesh, positions: &[[f64; 2]]) -> Result<(), String> {
    let pieces = bdmorph::pieces(mesh.positions.len(), &mesh.faces).expect("pieces");
    let loops: Vec<Vec<u32>> = pieces.into_iter().flat_map(|p| p.loops).collect();
    let segments = |l: &[u32]| -> Vec<[usize; 2]> {
        (0..l.len())
            .map(|i| [l[i] as usize, l[(i + 1) % l.len()] as usize])
            .collect()
    };
    for (i, a) in loops.iter().enumerate() {
        for (j, b) in loops.iter().enumerate().skip(i) {
            let (sa, sb) = (segments(a), segments(b));
            for (x, s) in sa.iter().enumerate() {
                for (y, t) in sb.iter().enumerate() {
                    // Neighbouring segments of one loop share a corner.
                    if i == j && (x == y || s.contains(&t[0]) || s.contains(&t[1])) {
                        continue;
                    }
                    let p = |v: usize| positions[v];
                    if segments_meet(p(s[0]), p(s[1]), p(t[0]), p(t[1])) {
                        return Err(format!(
                            "loops {i} and {j} meet at segments {s:?} and {t:?}"
                        ));
                    }
                }
            }
        }
    }
    Ok(())
}

/// Morphs `a` to `b` at 21 times and checks: no flipped triangle (hidden ones included), every
/// loop simple and apart from the others, endpoints reproduced, and the conformal distortion
/// of the user's triangles within the paper's bound (the target's, over the filled mesh).
fn morphs_cleanly(name: &str, a: &PlanarMesh, b: &PlanarMesh) {
    let mut morph = Morph::new(a, b, MorphOptions::default()).expect(name);
    let structure = morph.structure().clone();
    let hidden: Vec<[u32; 3]> = structure
        .pieces
        .iter()
        .flat_map(|p| p.hidden.clone())
        .collect();
    let mut filled = a.faces.clone();
    filled.extend(&hidden);
    let rest = RestShape::new(&a.positions, &filled);
    let mut d = vec![0.0; filled.len()];
    let bound = rest.distortion_into(&b.positions, &mut d);
    for i in 0..=20 {
        let t = f64::from(i) / 20.0;
        let frame = morph
            .frame(t)
            .unwrap_or_else(|e| panic!("{name}: t = {t}: {e}"));
        assert_eq!(frame.stats.flipped_triangles, 0, "{name}: t = {t}");
        loops_are_simple_and_apart(a, frame.positions)
            .unwrap_or_else(|e| panic!("{name}: t = {t}: {e}"));
        let user = frame.stats.max_conformal_distortion;
        assert!(
            user <= bound * (1.0 + 1e-9),
            "{name}: t = {t}: {user} > {bound}"
        );
        let positions = frame.positions.to_vec();
        let mut all = vec![0.0; filled.len()];
        let filled_max = rest.distortion_into(&positions, &mut all);
        assert!(
            filled_max <= bound * (1.0 + 1e-9),
            "{name}: t = {t}: {filled_max} > {bound}"
        );
        for (end, pose) in [(0.0, a), (1.0, b)] {
            if t == end {
                let err = max_distance(&positions, &pose.positions);
                assert!(err < 1e-9 * a.diameter(), "{name}: t = {t}: {err}");
            }
        }
    }
}

#[test]
fn an_annulus_morphs_to_twisted_and_bent_poses_without_crack_or_overlap() {
    let a = generate::annulus(0.003);
    let s = Morph::new(&a, &a, MorphOptions::default()).expect("annulus");
    assert_eq!(s.structure().pieces.len(), 1);
    assert_eq!(s.structure().pieces[0].holes, 1);
    // Each hole is filled over its own boundary: n - 2 triangles.
    let hole = bdmorph::pieces(a.positions.len(), &a.faces).expect("pieces")[0]
        .loops
        .iter()
        .map(Vec::len)
        .min()
        .unwrap();
    assert_eq!(s.structure().pieces[0].hidden.len(), hole - 2);
    morphs_cleanly("annulus twisted", &a, &generate::twist(&a, 1.2));
    morphs_cleanly("annulus bent", &a, &generate::bend(&a, 0.8));
    morphs_cleanly(
        "annulus stretched and twisted",
        &a,
        &generate::stretch(&generate::twist(&a, 1.2), 1.8),
    );
}

#[test]
fn a_plate_with_two_holes_morphs_to_bent_and_twisted_poses() {
    let a = generate::plate_with_two_holes(0.004);
    let s = Morph::new(&a, &a, MorphOptions::default()).expect("plate");
    assert_eq!(s.structure().pieces[0].holes, 2);
    morphs_cleanly("plate bent", &a, &generate::bend(&a, 0.9));
    morphs_cleanly("plate twisted", &a, &generate::twist(&a, 1.5));
    morphs_cleanly(
        "plate bent and twisted",
        &a,
        &generate::twist(&generate::bend(&a, -0.7), 0.8),
    );
}

/// `b`'s vertices after `a`'s, its faces renumbered.
fn side_by_side(a: &PlanarMesh, b: &PlanarMesh) -> PlanarMesh {
    let n = a.positions.len() as u32;
    let mut m = a.clone();
    m.positions.extend(&b.positions);
    m.faces.extend(b.faces.iter().map(|f| f.map(|v| v + n)));
    m
}

fn shifted(m: &PlanarMesh, dx: f64) -> PlanarMesh {
    let mut m = m.clone();
    m.positions.iter_mut().for_each(|p| p[0] += dx);
    m
}

#[test]
fn pieces_morph_as_if_alone() {
    let disk = generate::disk(8, 0.2);
    let ring = shifted(&generate::annulus(0.01), 3.0);
    let (disk_to, ring_to) = (generate::twist(&disk, 1.0), generate::bend(&ring, 0.6));
    let both = side_by_side(&disk, &ring);
    let both_to = side_by_side(&disk_to, &ring_to);
    let mut together = Morph::new(&both, &both_to, MorphOptions::default()).expect("two pieces");
    let pieces = &together.structure().pieces;
    assert_eq!(pieces.len(), 2);
    assert_eq!((pieces[0].holes, pieces[1].holes), (0, 1));
    assert!(
        (pieces[1].anchor as usize) >= disk.positions.len(),
        "each piece its anchor"
    );
    let mut alone = [
        Morph::new(&disk, &disk_to, MorphOptions::default()).expect("disk"),
        Morph::new(&ring, &ring_to, MorphOptions::default()).expect("ring"),
    ];
    let n = disk.positions.len();
    for i in 0..=10 {
        let t = f64::from(i) / 10.0;
        let frame = together.frame(t).expect("frame");
        assert_eq!(frame.stats.flipped_triangles, 0);
        let p = frame.positions.to_vec();
        let d = frame.distortion.to_vec();
        let f0 = alone[0].frame(t).expect("disk frame");
        assert_eq!(&p[..n], f0.positions, "t = {t}: the disk as if alone");
        assert_eq!(&d[..disk.faces.len()], f0.distortion);
        let f1 = alone[1].frame(t).expect("ring frame");
        assert_eq!(&p[n..], f1.positions, "t = {t}: the ring as if alone");
        assert_eq!(&d[disk.faces.len()..], f1.distortion);
    }
}

#[test]
fn shuffled_and_rotated_face_lists_give_the_same_frames() {
    let a = generate::disk(10, 0.2);
    let keys = [a.clone(), generate::twist(&a, 1.0), generate::bend(&a, 0.6)];
    // The later keyframes list the triangles in another order, corners rotated.
    let mut shuffled = keys.clone();
    for (k, key) in shuffled.iter_mut().enumerate().skip(1) {
        let m = key.faces.len();
        let mut faces: Vec<[u32; 3]> = (0..m).map(|i| key.faces[(i * 7 + k) % m]).collect();
        for (i, f) in faces.iter_mut().enumerate() {
            f.rotate_left((i + k) % 3);
        }
        key.faces = faces;
    }
    assert_ne!(shuffled[1].faces, keys[1].faces);
    let mut plain = KeyframePath::new(&keys).expect("plain");
    let mut other = KeyframePath::new(&shuffled).expect("shuffled");
    assert_eq!(
        other.faces(),
        &keys[0].faces[..],
        "frames keep the first keyframe's faces"
    );
    for i in 0..=12 {
        let t = f64::from(i) / 12.0;
        let p = plain.frame(t).expect("plain").positions.to_vec();
        let q = other.frame(t).expect("shuffled").positions.to_vec();
        assert_eq!(p, q, "t = {t}");
    }
    // A morph too, and a triangle really reversed is refused, naming it.
    let mut m = Morph::new(&keys[0], &shuffled[1], MorphOptions::default()).expect("morph");
    let q = m.frame(0.5).expect("frame").positions.to_vec();
    let mut r = Morph::new(&keys[0], &keys[1], MorphOptions::default()).expect("morph");
    assert_eq!(q, r.frame(0.5).expect("frame").positions);
    let mut reversed = shuffled[1].clone();
    reversed.faces[5].swap(0, 1);
    let err = Morph::new(&keys[0], &reversed, MorphOptions::default()).unwrap_err();
    assert!(
        matches!(
            err,
            MorphError::Mesh(MeshError::FaceReversed { face: 5, .. })
        ),
        "{err}"
    );
    let mut missing = shuffled[1].clone();
    missing.faces[5] = [0, 5, 40];
    let err = Morph::new(&keys[0], &missing, MorphOptions::default()).unwrap_err();
    assert!(
        matches!(
            err,
            MorphError::Mesh(MeshError::FaceMissing { face: 5, .. })
        ),
        "{err}"
    );
}

/// A bent grid with every corner vertex that lies in one triangle folded over: reflected
/// across the line through that triangle's other two corners. Returns the pose, the folded
/// vertices and their triangles.
fn folded(grid: &PlanarMesh) -> (PlanarMesh, Vec<usize>, Vec<usize>) {
    let mut count = vec![0; grid.positions.len()];
    for f in &grid.faces {
        for &v in f {
            count[v as usize] += 1;
        }
    }
    let mut pose = generate::bend(grid, 0.3);
    let (mut vertices, mut faces) = (Vec::new(), Vec::new());
    for v in (0..count.len()).filter(|&v| count[v] == 1) {
        let f = grid
            .faces
            .iter()
            .position(|f| f.contains(&(v as u32)))
            .unwrap();
        let others: Vec<[f64; 2]> = grid.faces[f]
            .iter()
            .filter(|&&w| w as usize != v)
            .map(|&w| pose.positions[w as usize])
            .collect();
        let (p, q, x) = (others[0], others[1], pose.positions[v]);
        let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
        let s = ((x[0] - p[0]) * dx + (x[1] - p[1]) * dy) / (dx * dx + dy * dy);
        let foot = [p[0] + s * dx, p[1] + s * dy];
        pose.positions[v] = [2.0 * foot[0] - x[0], 2.0 * foot[1] - x[1]];
        vertices.push(v);
        faces.push(f);
    }
    faces.sort_unstable();
    (pose, vertices, faces)
}

#[test]
fn a_keyframe_with_inverted_triangles_is_refused_by_default_and_morphs_when_allowed() {
    let a = generate::grid(8, 8, 0.0);
    let (b, folded_vertices, folded_faces) = folded(&a);
    assert!(folded_faces.len() >= 2, "{folded_faces:?}");
    for &f in &folded_faces {
        assert!(
            b.signed_area(&b.faces[f]) < 0.0,
            "the fold inverts face {f}"
        );
    }
    // Refused by default, listing them all.
    let err = Morph::new(&a, &b, MorphOptions::default()).unwrap_err();
    match &err {
        MorphError::Mesh(MeshError::Inverted {
            faces,
            count,
            total,
        }) => {
            assert_eq!(
                (faces, *count, *total),
                (&folded_faces, folded_faces.len(), a.faces.len())
            );
        }
        other => panic!("{other}"),
    }
    assert!(
        err.to_string().contains("MorphOptions::allow_inverted"),
        "{err}"
    );
    let allowed = MorphOptions::default().with_allow_inverted(true);
    let mut m = Morph::new(&a, &b, allowed).expect("allowed");
    assert_eq!(m.structure().inverted, [vec![], folded_faces.clone()]);
    for i in 0..=10 {
        let t = f64::from(i) / 10.0;
        let frame = m.frame(t).expect("frame");
        // The metric is Euclidean all the way: nothing flips, even at the folded keyframe.
        assert_eq!(frame.stats.flipped_triangles, 0, "t = {t}");
        assert!(frame.stats.max_conformal_distortion.is_finite(), "t = {t}");
    }
    // At the folded keyframe the frame is not the pose: the folded corners are unfolded,
    // and the rest of the pose is nearly kept.
    let end = m.frame(1.0).expect("end").positions.to_vec();
    for &v in &folded_vertices {
        let off = (end[v][0] - b.positions[v][0]).hypot(end[v][1] - b.positions[v][1]);
        assert!(
            off > 1e-3 * a.diameter(),
            "vertex {v} is not reproduced: {off}"
        );
    }
    let far = end
        .iter()
        .zip(&b.positions)
        .enumerate()
        .filter(|(i, _)| !folded_vertices.contains(i))
        .map(|(_, (p, q))| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max);
    assert!(far < 0.1 * a.diameter(), "{far}");
    // Its start is reproduced exactly.
    let start = m.frame(0.0).expect("start").positions.to_vec();
    assert!(max_distance(&start, &a.positions) < 1e-9 * a.diameter());
}

#[test]
fn a_folded_keyframe_is_reached_exactly_when_asked_and_frames_stay_continuous() {
    let a = generate::grid(8, 8, 0.0);
    let (b, _, folded_faces) = folded(&a);
    let c = generate::bend(&a, -0.3);
    let options = MorphOptions::default()
        .with_allow_inverted(true)
        .with_reach_inverted(true);
    let path_options = bdmorph::PathOptions::default().with_morph(options.clone());
    let mut path =
        bdmorph::KeyframePath::with_options(&[a.clone(), b.clone(), c.clone()], path_options)
            .expect("path");
    let size = a.diameter();
    for (t, key) in [(0.0, &a), (0.5, &b), (1.0, &c)] {
        let f = path.frame(t).expect("frame");
        let miss = max_distance(f.positions, &key.positions);
        assert!(miss < 1e-9 * size, "t = {t}: {miss:e}");
        // The statistics are those of what is returned: the fold, at the folded keyframe.
        let expected = if t == 0.5 { folded_faces.len() } else { 0 };
        assert_eq!(f.stats.flipped_triangles, expected, "t = {t}");
    }
    // Continuous through the folded keyframe: no step is much larger than its neighbours.
    let frames: Vec<Vec<[f64; 2]>> = (0..=100)
        .map(|i| {
            path.frame(f64::from(i) / 100.0)
                .expect("frame")
                .positions
                .to_vec()
        })
        .collect();
    let steps: Vec<f64> = frames
        .windows(2)
        .map(|w| max_distance(&w[0], &w[1]))
        .collect();
    let median = {
        let mut s = steps.clone();
        s.sort_by(f64::total_cmp);
        s[s.len() / 2]
    };
    assert!(steps.iter().all(|&s| s < 5.0 * median), "{steps:?}");
    // Without it, the folded keyframe is the flat shape nearest it, as before.
    let mut plain = Morph::new(&a, &b, options.with_reach_inverted(false)).expect("morph");
    let end = plain.frame(1.0).expect("end");
    assert!(max_distance(end.positions, &b.positions) > 1e-3 * size);
    assert_eq!(end.stats.flipped_triangles, 0);
}

// The command line.

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-holes-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn run(dir: &std::path::Path, args: &[&str]) -> (bool, String, String) {
    let r = std::process::Command::new(env!("CARGO_BIN_EXE_bdmorph"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("runs");
    let text = |b: Vec<u8>| String::from_utf8(b).expect("utf8");
    (r.status.success(), text(r.stdout), text(r.stderr))
}

#[test]
fn the_command_line_morphs_holes_and_pieces_and_says_what_it_found() {
    let dir = scratch("cli");
    let plate = generate::plate_with_two_holes(0.01);
    let ring = shifted(&generate::annulus(0.01), 4.0);
    let a = side_by_side(&plate, &ring);
    let b = side_by_side(&generate::bend(&plate, 0.8), &generate::twist(&ring, 1.0));
    bdmorph::io::write_obj_2d(dir.join("a.obj"), &a.positions, &a.faces, &[]).unwrap();
    bdmorph::io::write_obj_2d(dir.join("b.obj"), &b.positions, &b.faces, &[]).unwrap();
    let (ok, out, err) = run(&dir, &["info", "a.obj"]);
    assert!(ok, "{err}");
    assert!(
        out.contains("morphable: yes (counter-clockwise and planar, 2 pieces with 3 holes; each piece morphs alone, with its own rigid motion; each hole is filled with hidden triangles for the solve)"),
        "{out}"
    );
    let (ok, out, err) = run(
        &dir,
        &[
            "morph", "a.obj", "b.obj", "--frames", "5", "--stats", "-o", "frames",
        ],
    );
    assert!(ok, "{err}");
    assert_eq!(out.lines().count(), 5);
    assert!(
        out.lines().all(|l| l.contains("\"flipped_triangles\":0")),
        "{out}"
    );
    // Output keeps exactly the user's vertices and faces.
    let last = std::fs::read_to_string(dir.join("frames/frame_0004.obj")).unwrap();
    assert_eq!(
        last.lines().filter(|l| l.starts_with("v ")).count(),
        a.positions.len()
    );
    assert_eq!(
        last.lines().filter(|l| l.starts_with("f ")).count(),
        a.faces.len()
    );
    // A program file holds one disk: refused with the reason.
    let (ok, _, err) = run(&dir, &["compile", "a.obj", "-o", "a.bdm"]);
    assert!(
        !ok && err.contains("a compiled program holds one piece"),
        "{err}"
    );
}

#[test]
fn the_command_line_lists_inverted_triangles_and_reports_the_folded_keyframe() {
    let dir = scratch("inverted");
    let a = generate::grid(8, 8, 0.0);
    let (b, _, faces) = folded(&a);
    bdmorph::io::write_obj_2d(dir.join("a.obj"), &a.positions, &a.faces, &[]).unwrap();
    bdmorph::io::write_obj_2d(dir.join("b.obj"), &b.positions, &b.faces, &[]).unwrap();
    let (ok, _, err) = run(
        &dir,
        &["morph", "a.obj", "b.obj", "--frames", "3", "-o", "out"],
    );
    assert!(!ok);
    let expected = format!(
        "b.obj:{}: {} of {} triangles are clockwise (inverted): face {}, {} (0-based)",
        a.positions.len() + faces[0] + 1,
        faces.len(),
        a.faces.len(),
        faces[0],
        faces[1]
    );
    assert!(err.contains(&expected), "{err}\n{expected}");
    assert!(!dir.join("out").exists(), "nothing written");
    let (ok, out, err) = run(
        &dir,
        &[
            "morph",
            "a.obj",
            "b.obj",
            "--frames",
            "3",
            "--allow-inverted",
            "--stats",
            "-o",
            "out",
        ],
    );
    assert!(ok, "{err}");
    let last = out.lines().last().unwrap();
    assert!(
        last.contains(&format!(
            "\"keyframe\":1,\"inverted_triangles\":{}",
            faces.len()
        )),
        "{last}"
    );
    assert!(last.contains("\"keyframe_deviation\":"), "{last}");
    assert!(
        err.contains("t = 1 is keyframe 1 (b.obj), which has 2 inverted triangles"),
        "{err}"
    );
    assert!(
        err.contains("not that pose; it differs from it by up to"),
        "{err}"
    );
    assert!(dir.join("out/frame_0002.obj").is_file());
}
