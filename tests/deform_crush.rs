//! Posing that crushes nothing: the studio's default method (symmetric Dirichlet, `sd`) on
//! the drags where KVF crumples a limb: a thin arm dragged across the body in quick moves or
//! a few strokes, a bent keyframe turned a quarter turn about three handles; and a pose that
//! already has flipped triangles posed without new ones.
//!
//! The measure of crushing is the largest conformal distortion `σ₁ / σ₂` of any triangle
//! (from the rest shape), after every move. `cargo test --test deform_crush -- --ignored
//! --nocapture` prints every method's numbers on these drags (BENCHMARKS.md, posing).

use bdmorph::deform::{Deformer, DragReport, PoseMethod};
use bdmorph::distortion::RestShape;
use bdmorph::meshing::{mesh_picture, MeshOptions, PictureOptions};
use bdmorph::studio::engine::Engine;
use bdmorph::studio::project::{Keyframe, MethodData, Project};
use bdmorph::{generate, PlanarMesh};

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

/// The largest distortion of an unflipped triangle, measured here.
fn worst(mesh: &PlanarMesh, pose: &[[f64; 2]]) -> f64 {
    let mut each = vec![0.0; mesh.faces.len()];
    RestShape::new(&mesh.positions, &mesh.faces).distortion_into(pose, &mut each);
    each.iter()
        .copied()
        .filter(|d| d.is_finite())
        .fold(1.0, f64::max)
}

/// A torso, a head and an arm `arm` pixels across (230 long) on a 512-pixel picture,
/// meshed to about `vertices`; positions in pixels, y up.
fn character(arm: f64, vertices: usize) -> PlanarMesh {
    let s = 512.0;
    let picture = generate::picture(512, 512, |x, y| {
        let p = [x / s, y / s];
        let torso = generate::capsule_distance(p, [0.45, 0.45], [0.45, 0.7], 0.13);
        let head = generate::capsule_distance(p, [0.45, 0.2], [0.45, 0.2], 0.09);
        let arm = generate::capsule_distance(p, [0.5, 0.42], [0.95, 0.42], 0.5 * arm / s);
        s * torso.min(head).min(arm)
    });
    let options = MeshOptions::default().with_vertices(vertices);
    mesh_picture(&picture, &PictureOptions::default(), &options)
        .expect("meshed")
        .mesh
}

/// The studio browser test's picture (a body and a raised arm, 400 pixels square) meshed to
/// about 1,200 vertices.
fn body_and_arm() -> PlanarMesh {
    let s = 400.0;
    let picture = generate::picture(400, 400, |x, y| {
        let p = [x / s, y / s];
        let body = generate::capsule_distance(p, [0.45, 0.35], [0.45, 0.8], 0.12);
        let arm = generate::capsule_distance(p, [0.45, 0.45], [0.8, 0.3], 0.05);
        s * body.min(arm)
    });
    let options = MeshOptions::default().with_vertices(1200);
    mesh_picture(&picture, &PictureOptions::default(), &options)
        .expect("meshed")
        .mesh
}

/// The arm's moves (offsets of its tip, pixels): `quick`, 330 pixels across the body in 12
/// moves then 200 down past the hip in 6; otherwise the same way across in 3 strokes.
fn arm_moves(quick: bool) -> Vec<[f64; 2]> {
    if quick {
        (1..=12)
            .map(|k| [-330.0 * f64::from(k) / 12.0, 20.0 * f64::from(k) / 12.0])
            .chain((1..=6).map(|k| [-330.0, 20.0 - 200.0 * f64::from(k) / 6.0]))
            .collect()
    } else {
        (1..=3)
            .map(|k| [-110.0 * f64::from(k), 20.0 * f64::from(k) / 3.0])
            .collect()
    }
}

/// What a run of drags in the studio's engine did.
#[derive(Debug)]
struct Run {
    /// The largest distortion after any move.
    worst: f64,
    /// The most flipped triangles after any move.
    flips: usize,
    /// Moves refused (the pose kept).
    refused: usize,
    /// The handles' largest residual at the end.
    residual: f64,
    /// The largest distortion at the end.
    end: f64,
}

/// Drags keyframe 2 of a project of `rest` posed with `method` (starting from `key`, pins
/// `pins`) through `moves` (each the targets of every pin), in the studio's engine; every
/// kept pose's report checked against a count made here.
fn studio_run(
    rest: &PlanarMesh,
    key: &[[f64; 2]],
    method: &MethodData,
    pins: &[u32],
    moves: &[Vec<[f64; 2]>],
) -> Run {
    let mut doc = Project::new(rest, None);
    doc.method = method.clone();
    doc.keyframes.push(Keyframe {
        time: 1.0,
        easing: "linear".into(),
        positions: key.to_vec(),
        pins: pins.to_vec(),
        drawing: None,
    });
    let mut engine = Engine::new(&doc, 1).expect("engine");
    let mut run = Run {
        worst: worst(rest, key),
        flips: flipped(rest, key),
        refused: 0,
        residual: 0.0,
        end: 0.0,
    };
    for (k, t) in moves.iter().enumerate() {
        let before = doc.keyframes[1].positions.clone();
        match engine.drag(&mut doc, 1, t) {
            Ok(r) => {
                let pose = &doc.keyframes[1].positions;
                assert_eq!(r.flipped_triangles, flipped(rest, pose), "move {k}");
                let w = worst(rest, pose);
                assert!((r.max_distortion - w).abs() <= 1e-9 * w, "move {k}: {r:?}");
                run.worst = run.worst.max(w);
                run.residual = r.pin_residual;
            }
            Err(why) => {
                eprintln!("{}, move {k}: {why}", method.name);
                assert_eq!(
                    doc.keyframes[1].positions, before,
                    "a refused move keeps the pose"
                );
                run.refused += 1;
            }
        }
        run.flips = run.flips.max(flipped(rest, &doc.keyframes[1].positions));
    }
    run.end = worst(rest, &doc.keyframes[1].positions);
    run
}

/// The arm's tip dragged by `moves` in the studio with `method`, the torso held by three
/// handles.
fn arm_run(rest: &PlanarMesh, method: &MethodData, moves: &[[f64; 2]]) -> Run {
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
    let start: Vec<[f64; 2]> = pins.iter().map(|&v| p[v as usize]).collect();
    let moves: Vec<Vec<[f64; 2]>> = moves
        .iter()
        .map(|d| {
            let mut t = start.clone();
            t[3] = [start[3][0] + d[0], start[3][1] + d[1]];
            t
        })
        .collect();
    studio_run(rest, p, method, &pins, &moves)
}

/// A keyframe of the browser test's figure bent by `generate::bend` 0.45, three handles at
/// its extremes turned a quarter turn about their centroid (`sign` 1: counter-clockwise) in
/// 8 moves; the run, and the handles' largest miss at the end relative to their radius.
fn quarter_turn(rest: &PlanarMesh, method: &MethodData, sign: f64) -> (Run, f64) {
    let key = generate::bend(rest, 0.45).positions;
    let extreme = |d: [f64; 2]| {
        (0..key.len())
            .max_by(|&a, &b| {
                let s = |v: usize| d[0] * key[v][0] + d[1] * key[v][1];
                s(a).total_cmp(&s(b))
            })
            .expect("vertices") as u32
    };
    let pins = vec![
        extreme([1.0, 0.3]),
        extreme([-1.0, 0.3]),
        extreme([0.0, -1.0]),
    ];
    let start: Vec<[f64; 2]> = pins.iter().map(|&v| key[v as usize]).collect();
    let c = [
        start.iter().map(|p| p[0]).sum::<f64>() / 3.0,
        start.iter().map(|p| p[1]).sum::<f64>() / 3.0,
    ];
    let turned = |a: f64| -> Vec<[f64; 2]> {
        let (s, co) = a.sin_cos();
        start
            .iter()
            .map(|p| {
                let (x, y) = (p[0] - c[0], p[1] - c[1]);
                [c[0] + co * x - s * y, c[1] + s * x + co * y]
            })
            .collect()
    };
    let quarter = sign * std::f64::consts::FRAC_PI_2;
    let moves: Vec<Vec<[f64; 2]>> = (1..=8)
        .map(|k| turned(quarter * f64::from(k) / 8.0))
        .collect();
    let run = studio_run(rest, &key, method, &pins, &moves);
    let radius = start
        .iter()
        .map(|p| (p[0] - c[0]).hypot(p[1] - c[1]))
        .fold(0.0, f64::max);
    (run, radius)
}

fn method(name: &str) -> MethodData {
    MethodData {
        name: name.into(),
        ..MethodData::default()
    }
}

#[test]
fn the_studios_default_drags_a_thin_arm_across_the_body_without_crushing_it() {
    // An arm 8 or 36 pixels wide dragged across the body in 18 quick moves, and in 3
    // strokes: with the default method no move is refused, no triangle is flipped after any
    // move, and the largest distortion stays below 10 (KVF, the default before: 109 and 125
    // in the quick moves, 113 and 66 in the strokes). Old projects that name KVF keep it,
    // and still never keep a flipped triangle (a fold is repaired or the move refused).
    let default = MethodData::default();
    assert_eq!(default.name, "sd");
    assert!(matches!(
        bdmorph::studio::engine::method_of(&default),
        Ok(PoseMethod::Sd(_))
    ));
    for (arm, vertices) in [(8.0, 4000), (36.0, 3000)] {
        let rest = character(arm, vertices);
        for quick in [true, false] {
            let moves = arm_moves(quick);
            let sd = arm_run(&rest, &default, &moves);
            eprintln!("arm {arm} px, quick {quick}: sd {sd:?}");
            assert_eq!(sd.refused, 0, "arm {arm} px");
            assert_eq!(sd.flips, 0, "arm {arm} px");
            assert!(sd.worst < 10.0, "arm {arm} px, quick {quick}: {sd:?}");
            // The soft handles follow: the tip within a pixel of the mouse.
            assert!(sd.residual < 1.0, "arm {arm} px, quick {quick}: {sd:?}");
            if quick {
                let kvf = arm_run(&rest, &method("kvf"), &moves);
                eprintln!("arm {arm} px, quick {quick}: kvf {kvf:?}");
                assert_eq!(kvf.flips, 0, "arm {arm} px");
                assert!(kvf.refused < moves.len(), "arm {arm} px: the arm moved");
            }
        }
    }
}

#[test]
fn a_bent_keyframe_turns_a_quarter_turn_about_three_handles() {
    // The studio browser test's drag, in the engine: flip-free KVF stopped 160-220 pixels
    // short here. The default follows the handles both ways round, flips nothing and
    // crushes nothing (the bent keyframe itself has distortion 1.65).
    let rest = body_and_arm();
    let key = generate::bend(&rest, 0.45).positions;
    let own = worst(&rest, &key);
    for sign in [-1.0, 1.0] {
        let (run, radius) = quarter_turn(&rest, &MethodData::default(), sign);
        eprintln!(
            "turn {sign}: {run:?}, radius {radius:.0}, the keyframe's own distortion {own:.2}"
        );
        assert_eq!((run.flips, run.refused), (0, 0), "{run:?}");
        assert!(run.residual < 0.01 * radius, "{run:?}");
        assert!(run.worst < 10.0, "{run:?}");
    }
}

#[test]
fn a_pose_with_flipped_triangles_gets_no_more() {
    // A bar folded by one fast ARAP drag (its tip pulled back through it), then posed with
    // symmetric Dirichlet from that pose: the folded triangles are solved with ARAP's energy
    // (finite there) and may come back; no other triangle ever flips.
    let rest = generate::grid(21, 5, 0.0);
    let pins = vec![0, 21, 42, 63, 84, 20 + 2 * 21];
    let start: Vec<[f64; 2]> = pins.iter().map(|&v| rest.positions[v as usize]).collect();
    let mut arap = Deformer::new(
        &rest,
        PoseMethod::Arap(bdmorph::deform::ArapOptions::default().with_iterations(2)),
    )
    .expect("set up");
    arap.set_pins(&pins).expect("pins");
    let mut t = start.clone();
    t[5] = [8.0, 1.0];
    arap.drag(&t).expect("drag");
    let folded = arap.positions().to_vec();
    let mut flips = flipped(&rest, &folded);
    assert!(flips > 0, "the fast drag is meant to fold the bar");
    let mut sd = Deformer::new(&rest, PoseMethod::sd()).expect("set up");
    sd.set_pins(&pins).expect("pins");
    sd.set_positions(&folded).expect("pose");
    let first = flips;
    let mut report = DragReport::default();
    for k in 0..=40 {
        // Back out towards the bar's length, then held there.
        let s = f64::from(k.min(20)) / 20.0;
        t[5] = [8.0 + 12.0 * s, 1.0 + s];
        let before: Vec<bool> = rest
            .faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|v| sd.positions()[v as usize]);
                (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) > 0.0
            })
            .collect();
        report = sd.drag(&t).expect("drag");
        let pose = sd.positions();
        assert_eq!(report.flipped_triangles, flipped(&rest, pose), "move {k}");
        for (f, &was) in rest.faces.iter().zip(&before) {
            let [a, b, c] = f.map(|v| pose[v as usize]);
            let now = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) > 0.0;
            assert!(now || !was, "move {k}: triangle {f:?} flipped");
        }
        assert!(report.flipped_triangles <= flips, "move {k}: {report:?}");
        flips = report.flipped_triangles;
    }
    eprintln!("folded by ARAP: {first} flipped; after sd: {report:?}");
}

/// The numbers of BENCHMARKS.md: every method on the drags above, in the studio's engine.
#[test]
#[ignore = "a measurement: prints a table"]
fn measure_crushing() {
    let methods = [
        method("sd"),
        method("kvf"),
        method("arap"),
        MethodData {
            name: "bounded".into(),
            max_distortion: 3.0,
            ..MethodData::default()
        },
    ];
    for (arm, vertices) in [(8.0, 4000), (36.0, 3000)] {
        let rest = character(arm, vertices);
        for quick in [true, false] {
            for m in &methods {
                let clock = std::time::Instant::now();
                let moves = arm_moves(quick);
                let run = arm_run(&rest, m, &moves);
                let ms = clock.elapsed().as_secs_f64() * 1e3 / moves.len() as f64;
                eprintln!(
                    "arm {arm} px ({} vertices), {}: {:8} worst {:7.2}, end {:7.2}, flips {}, refused {}, residual {:.2} px, {ms:.1} ms/move",
                    rest.positions.len(),
                    if quick { "18 quick moves" } else { "3 strokes" },
                    m.name,
                    run.worst,
                    run.end,
                    run.flips,
                    run.refused,
                    run.residual
                );
            }
        }
    }
    let rest = body_and_arm();
    for sign in [-1.0, 1.0] {
        for m in &methods {
            let clock = std::time::Instant::now();
            let (run, radius) = quarter_turn(&rest, m, sign);
            let ms = clock.elapsed().as_secs_f64() * 1e3 / 8.0;
            eprintln!(
                "quarter turn {sign} ({} vertices, radius {radius:.0} px), {:8} worst {:7.2}, end {:7.2}, flips {}, refused {}, residual {:.2} px, {ms:.1} ms/move",
                rest.positions.len(),
                m.name,
                run.worst,
                run.end,
                run.flips,
                run.refused,
                run.residual
            );
        }
    }
}
