//! The studio's session in process, request by request: every refused request changes nothing
//! (the document, its history and the shared view), undoing every edit gives the document back
//! bit for bit and redoing gives the edited one, meshes of several pieces pose, keyframes with
//! flipped triangles play, a new mesh carries the animation over as one undoable step, poses
//! that are not finite are never kept, and the history stays within its budget.

mod studio_fuzz_cases;

use bdmorph::generate;
use bdmorph::studio::project::{Keyframe, Project};
use bdmorph::studio::protocol::Request;
use bdmorph::studio::session::{Answer, Reply, Session};

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "bdmorph-studio-session-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// A small random number generator (xorshift), seeded: sequences are repeatable.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn pick<T: Clone>(&mut self, items: &[T]) -> T {
        items[self.below(items.len())].clone()
    }
}

/// A disk with `keys` keyframes (bent more and more), one second apart.
fn animated(rings: usize, keys: usize) -> Project {
    let mesh = generate::disk(rings, 0.1);
    let mut project = Project::new(&mesh, None);
    project.outline = vec![vec![[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]];
    for k in 1..keys {
        project.keyframes.push(Keyframe {
            time: k as f64,
            easing: "linear".into(),
            positions: generate::bend(&mesh, 0.2 * k as f64).positions,
            pins: Vec::new(),
            drawing: None,
        });
    }
    project
}

fn session(project: Project, name: &str) -> Session {
    Session::new(project, scratch(name), None, None).expect("a session")
}

/// Whether the reply refused the request (and its message).
fn refusal(reply: &Reply) -> Option<String> {
    reply.answers.iter().find_map(|a| match a {
        Answer::Text(t) => {
            let v: serde_json::Value = serde_json::from_str(t).ok()?;
            (v["type"] == "error").then(|| v["message"].as_str().unwrap_or("").to_owned())
        }
        Answer::Binary(_) => None,
    })
}

/// Carries out a request, and its background work at once.
fn ask(s: &mut Session, request: Request) -> Option<String> {
    let reply = s.handle(request);
    let refused = refusal(&reply);
    if let Some(work) = reply.work {
        s.run_now(work);
    }
    refused
}

/// What a refused request must leave as it was.
#[derive(Debug, PartialEq)]
struct Snapshot {
    document: Vec<u8>,
    undo: usize,
    redo: usize,
    state: u64,
    labels: Vec<String>,
    current: usize,
    mode: &'static str,
    shown: String,
    drawing: Option<usize>,
}

fn snapshot(s: &Session) -> Snapshot {
    let h = s.history();
    Snapshot {
        document: s.project().to_json(),
        undo: h.undo_len(),
        redo: h.redo_len(),
        state: h.state(),
        labels: h.labels().map(str::to_owned).collect(),
        current: s.view().current,
        mode: s.view().mode,
        shown: format!("{:?}", s.view().shown),
        drawing: s.view().drawing,
    }
}

fn finite(p: &Project) -> bool {
    p.keyframes
        .iter()
        .flat_map(|k| k.positions.iter())
        .flatten()
        .all(|c| c.is_finite())
}

/// A random request: valid ones and hostile ones (out of range, non-finite, absurd).
fn random_request(rng: &mut Rng, s: &Session) -> Request {
    let doc = s.project();
    let n = doc.mesh.positions.len();
    let keys = doc.keyframes.len();
    let k = |rng: &mut Rng| {
        if rng.below(8) == 0 {
            keys + rng.below(3)
        } else {
            rng.below(keys)
        }
    };
    let time = |rng: &mut Rng| match rng.below(10) {
        0 => f64::NAN,
        1 => -1.0,
        2 => 1e300,
        3 => f64::INFINITY,
        _ => (rng.unit() * (keys as f64 + 1.0) * 1000.0).round() / 1000.0,
    };
    let point = |rng: &mut Rng| match rng.below(12) {
        0 => [f64::NAN, 0.0],
        1 => [1e300, -1e300],
        _ => [4.0 * rng.unit() - 2.0, 4.0 * rng.unit() - 2.0],
    };
    let vertex = |rng: &mut Rng| {
        if rng.below(10) == 0 {
            (n + rng.below(5)) as u32
        } else {
            rng.below(n) as u32
        }
    };
    let pins = doc.keyframes[s.view().current].pins.clone();
    match rng.below(31) {
        0 => Request::Select { keyframe: k(rng) },
        1..=3 => Request::PinAdd {
            vertex: vertex(rng),
        },
        4 => Request::PinRemove {
            vertex: if pins.is_empty() || rng.below(5) == 0 {
                vertex(rng)
            } else {
                rng.pick(&pins)
            },
        },
        5 => match rng.below(3) {
            0 => Request::PinsClear,
            1 => Request::PinMove {
                from: if pins.is_empty() || rng.below(5) == 0 {
                    vertex(rng)
                } else {
                    rng.pick(&pins)
                },
                to: vertex(rng),
            },
            _ => Request::Ghosts {
                keyframes: (0..rng.below(4)).map(|_| k(rng)).collect(),
            },
        },
        6..=9 => {
            let mut targets: Vec<[f64; 2]> = pins
                .iter()
                .map(|&v| {
                    let p = doc.keyframes[s.view().current].positions[v as usize];
                    [
                        p[0] + 0.3 * (rng.unit() - 0.5),
                        p[1] + 0.3 * (rng.unit() - 0.5),
                    ]
                })
                .collect();
            if rng.below(6) == 0 && !targets.is_empty() {
                targets[0] = point(rng);
            }
            if rng.below(8) == 0 {
                targets.push([0.0, 0.0]);
            }
            let pins = if rng.below(10) == 0 {
                vec![vertex(rng)]
            } else {
                pins
            };
            Request::Drag {
                seq: 1,
                pins,
                targets,
                moving: None,
            }
        }
        10 => Request::DragEnd,
        11 => Request::Method {
            name: rng
                .pick(&["sd", "kvf", "arap", "bounded", "magic"])
                .to_owned(),
            weight: [None, Some(50.0), Some(1e-300), Some(f64::NAN), Some(1e9)][rng.below(5)],
            max_distortion: [None, Some(2.0), Some(0.5), Some(f64::INFINITY)][rng.below(4)],
        },
        12 | 13 => Request::Undo,
        14 => Request::Redo,
        15 => Request::Reset,
        16 => Request::AddKeyframe {
            time: time(rng),
            copy: [None, Some(0), Some(keys + 3)][rng.below(3)],
        },
        17 => Request::DeleteKeyframe { keyframe: k(rng) },
        18 => Request::MoveKeyframe {
            keyframe: k(rng),
            to: k(rng),
        },
        19 => Request::SetTime {
            keyframe: k(rng),
            time: time(rng),
            ripple: rng.below(2) == 0,
        },
        20 => Request::SetEasing {
            keyframe: k(rng),
            easing: rng
                .pick(&[
                    "linear",
                    "ease-in-out",
                    "cubic-bezier(0.4,0,0.2,1)",
                    "bouncy",
                    "cubic-bezier(2,0,0,1)",
                ])
                .to_owned(),
        },
        21 => Request::FrameToKeyframe { time: time(rng) },
        22 => Request::Scrub {
            seq: 2,
            time: time(rng),
        },
        23 => match rng.below(3) {
            0 => Request::LoopRange {
                range: [
                    None,
                    Some([0.5, 1.5]),
                    Some([2.0, 1.0]),
                    Some([f64::NAN, 1.0]),
                ][rng.below(4)],
            },
            _ => Request::Fps {
                fps: [25.0, 12.5, 0.0, -3.0, 1e9, f64::NAN][rng.below(6)],
            },
        },
        24 => Request::OutlineMove {
            ring: rng.below(doc.outline.len() + 1),
            index: rng.below(6),
            to: point(rng),
        },
        25 => Request::OutlineInsert {
            ring: rng.below(doc.outline.len() + 1),
            index: rng.below(6),
            point: point(rng),
        },
        26 => Request::OutlineRemove {
            ring: rng.below(doc.outline.len() + 1),
            index: rng.below(6),
        },
        27 => match rng.below(3) {
            0 => Request::OutlineNewLoop,
            1 => Request::OutlinePoint { point: point(rng) },
            _ => Request::OutlineClose,
        },
        28 => match rng.below(4) {
            // A drawing keyframe on a project without a picture, or of a missing file:
            // refused, whatever the pairs and time.
            0 => Request::DrawingKeyframe {
                name: ["b.png", "../x.png", "", "a.obj"][rng.below(4)].into(),
                pairs: (0..rng.below(4))
                    .map(|_| [point(rng), point(rng)])
                    .collect(),
                time: Some(time(rng)),
            },
            _ => Request::Repair {
                keyframe: Some(k(rng)),
            },
        },
        29 => {
            let m = doc.mesh.faces.len() as u32;
            let faces: Vec<u32> = (0..rng.below(6))
                .map(|_| rng.below(m as usize + 2) as u32)
                .collect();
            if rng.below(2) == 0 {
                Request::PaintDepth {
                    faces,
                    all: rng.below(5) == 0,
                    level: [1, -2, 0, 9, 10, -128][rng.below(6)],
                }
            } else {
                Request::PaintStiffness {
                    faces,
                    all: rng.below(5) == 0,
                    weight: [1000.0, 1.0, 0.5, f64::NAN, 1e7, 30.0][rng.below(6)],
                }
            }
        }
        _ => Request::Mode {
            mode: rng.pick(&["pose", "outline", "sideways"]).to_owned(),
        },
    }
}

/// 6,000 random requests, a third of them hostile: after every refused one the document,
/// the history and the view are exactly as before; after every one the document passes its
/// own checks and holds only finite points.
#[test]
fn refused_requests_change_nothing_and_the_document_stays_valid() {
    let mut refused = 0;
    let mut kept = 0;
    for seed in 1..=6u64 {
        let mut s = session(animated(5, 4), &format!("atomic-{seed}"));
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ seed);
        for step in 0..1000 {
            let request = random_request(&mut rng, &s);
            let shown = format!("{request:?}");
            let before = snapshot(&s);
            let reply = s.handle(request);
            assert!(reply.work.is_none());
            match refusal(&reply) {
                Some(why) => {
                    refused += 1;
                    let after = snapshot(&s);
                    assert_eq!(
                        after, before,
                        "seed {seed} step {step}: {shown} was refused ({why}) but changed the session"
                    );
                }
                None => kept += 1,
            }
            let doc = s.project();
            doc.check()
                .unwrap_or_else(|e| panic!("seed {seed} step {step}: {shown} left {e}"));
            assert!(finite(doc), "seed {seed} step {step}: {shown}");
            assert!(s.view().current < doc.keyframes.len());
        }
    }
    eprintln!("{kept} requests carried out, {refused} refused, none changed anything");
    assert!(
        refused > 1000 && kept > 1000,
        "{kept} kept, {refused} refused"
    );
}

/// Random valid edits of every kind, then undo to the start: the document is the original,
/// byte for byte; redo to the end: the edited one.
#[test]
fn undoing_every_edit_gives_the_original_back_and_redoing_the_edited() {
    for seed in 1..=5u64 {
        let mut s = session(animated(5, 3), &format!("undo-{seed}"));
        let original = s.project().to_json();
        let mut rng = Rng(0x2545_f491_4f6c_dd1d ^ seed);
        let mut steps = 0;
        while s.history().undo_len() < 40 && steps < 3000 {
            steps += 1;
            let request = random_request(&mut rng, &s);
            if matches!(request, Request::Undo | Request::Redo) {
                continue;
            }
            ask(&mut s, request);
            // Strokes end, so that each drag is its own step.
            s.handle(Request::DragEnd);
        }
        assert!(
            s.history().undo_len() >= 40,
            "seed {seed}: only {} steps",
            s.history().undo_len()
        );
        let edited = s.project().to_json();
        assert_ne!(edited, original);
        while ask(&mut s, Request::Undo).is_none() {}
        assert_eq!(
            s.project().to_json(),
            original,
            "seed {seed}: undone to the start"
        );
        assert!(
            !s.dirty(),
            "back at the opened state, the document is clean"
        );
        while ask(&mut s, Request::Redo).is_none() {}
        assert_eq!(
            s.project().to_json(),
            edited,
            "seed {seed}: redone to the end"
        );
    }
}

/// Two disks side by side and a speck: a pin on one disk poses it; the other pieces keep
/// their places exactly; a pin on the second disk moves it too.
#[test]
fn a_mesh_of_several_pieces_poses_with_pins_on_any_piece() {
    let a = generate::disk(6, 0.1);
    let n = a.positions.len() as u32;
    let mut mesh = a.clone();
    for (shift, scale) in [(5.0, 1.0), (9.0, 0.05)] {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(
            a.positions
                .iter()
                .map(|p| [scale * p[0] + shift, scale * p[1]]),
        );
        mesh.faces
            .extend(a.faces.iter().map(|f| f.map(|v| v + base)));
    }
    let mut s = session(Project::new(&mesh, None), "pieces");
    assert!(ask(
        &mut s,
        Request::AddKeyframe {
            time: 1.0,
            copy: Some(0)
        }
    )
    .is_none());
    let rim = (0..n)
        .max_by(|&x, &y| a.positions[x as usize][0].total_cmp(&a.positions[y as usize][0]))
        .expect("rim");
    for v in [0, rim] {
        assert_eq!(ask(&mut s, Request::PinAdd { vertex: v }), None);
    }
    let start = s.project().keyframes[1].positions.clone();
    let target = [start[rim as usize][0] + 0.5, start[rim as usize][1] + 0.8];
    let why = ask(
        &mut s,
        Request::Drag {
            seq: 1,
            pins: vec![0, rim],
            targets: vec![start[0], target],
            moving: None,
        },
    );
    assert_eq!(why, None);
    let posed = &s.project().keyframes[1].positions;
    assert!(
        (posed[rim as usize][1] - start[rim as usize][1]) > 0.3,
        "the first disk moved"
    );
    assert_eq!(
        &posed[n as usize..],
        &start[n as usize..],
        "the others stayed exactly"
    );
    // A pin on the second disk: it moves as well.
    s.handle(Request::DragEnd);
    assert_eq!(ask(&mut s, Request::PinAdd { vertex: n + 3 }), None);
    let pins = s.project().keyframes[1].pins.clone();
    let mut targets: Vec<[f64; 2]> = pins
        .iter()
        .map(|&v| s.project().keyframes[1].positions[v as usize])
        .collect();
    targets[2][1] += 0.5;
    assert_eq!(
        ask(
            &mut s,
            Request::Drag {
                seq: 2,
                pins,
                targets,
                moving: None,
            }
        ),
        None
    );
    let moved = &s.project().keyframes[1].positions;
    assert!((moved[(n + 3) as usize][1] - start[(n + 3) as usize][1]) > 0.2);
    let speck = 2 * n as usize;
    assert_eq!(&moved[speck..], &start[speck..], "the speck stayed exactly");
}

/// A keyframe with two flipped triangles: scrubbing and frames to keyframes work; the
/// keyframe is marked; a pin on a frame between keyframes makes it a keyframe.
#[test]
fn keyframes_with_flipped_triangles_do_not_block_the_timeline() {
    let mut project = animated(6, 3);
    let faces = project.mesh.faces.clone();
    // Fold one interior vertex across its neighbour in keyframe 2: pushed past it.
    let positions = &mut project.keyframes[1].positions;
    let [v, u, _] = faces[faces.len() / 2].map(|x| x as usize);
    let (p, q) = (positions[v], positions[u]);
    positions[v] = [p[0] + 1.6 * (q[0] - p[0]), p[1] + 1.6 * (q[1] - p[1])];
    let flipped = bdmorph::studio::engine::flipped(&faces, positions);
    assert!(flipped > 0, "the fold flips triangles");
    let mut s = session(project, "flips");
    let state: serde_json::Value = serde_json::from_str(&s.state_json()).expect("json");
    assert_eq!(state["keyframes"][1]["flipped"], flipped);
    for t in [0.25, 0.5, 0.75, 1.0, 1.5, 2.0] {
        assert_eq!(
            ask(&mut s, Request::Scrub { seq: 1, time: t }),
            None,
            "scrub to {t}"
        );
    }
    assert_eq!(ask(&mut s, Request::Scrub { seq: 1, time: 0.5 }), None);
    assert_eq!(ask(&mut s, Request::PinAdd { vertex: 3 }), None);
    assert_eq!(s.project().keyframes.len(), 4, "a keyframe at 0.5 s");
    assert_eq!(s.project().keyframes[1].time, 0.5);
    assert_eq!(s.project().keyframes[1].pins, [3]);
    assert_eq!(
        s.history().labels().last(),
        Some("pin on a new keyframe 2 at 0.50 s")
    );
    ask(&mut s, Request::Undo);
    assert_eq!(
        s.project().keyframes.len(),
        3,
        "one step: the keyframe and its pin"
    );
}

/// Pins pulled a hundred mesh sizes apart, or to a point that is not finite: the drag is
/// refused or the pose kept finite; the document never holds a non-finite point, and saves.
#[test]
fn poses_that_are_not_finite_are_never_kept() {
    for method in ["sd", "kvf", "arap", "bounded"] {
        let mut s = session(animated(5, 2), &format!("nan-{method}"));
        ask(
            &mut s,
            Request::Method {
                name: method.into(),
                weight: None,
                max_distortion: None,
            },
        );
        ask(&mut s, Request::Select { keyframe: 1 });
        let n = s.project().mesh.positions.len() as u32;
        for v in [0, n - 1] {
            assert_eq!(ask(&mut s, Request::PinAdd { vertex: v }), None);
        }
        for (a, b) in [
            ([-100.0, 0.0], [100.0, 0.0]),
            ([0.0, 0.0], [f64::NAN, 1.0]),
            ([1e200, 0.0], [0.0, 0.0]),
        ] {
            let _ = ask(
                &mut s,
                Request::Drag {
                    seq: 1,
                    pins: vec![0, n - 1],
                    targets: vec![a, b],
                    moving: None,
                },
            );
            assert!(finite(s.project()), "{method}: {a:?} {b:?}");
        }
        let refused = ask(
            &mut s,
            Request::Drag {
                seq: 1,
                pins: vec![0, n - 1],
                targets: vec![[-1e6, 0.0], [1e6, 0.0]],
                moving: None,
            },
        )
        .expect("too far is refused");
        assert!(refused.contains("too far"), "{refused}");
        assert_eq!(
            ask(
                &mut s,
                Request::Save {
                    name: Some("p.json".into()),
                    overwrite: None
                }
            ),
            None
        );
        let back = Project::read(&s.workspace().root().join("p.json")).expect("reads back");
        assert!(finite(&back));
    }
}

/// A new mesh on an animated project: every keyframe carried over (times, easings, pins near
/// their places), in one undoable step; undo gives the old document back exactly.
#[test]
fn a_new_mesh_keeps_the_animation_in_one_undoable_step() {
    let mut project = animated(6, 4);
    project.keyframes[2].easing = "ease-in-out".into();
    project.keyframes[1].pins = vec![0, 5];
    project.outline = vec![generate::disk(6, 0.1)
        .positions
        .iter()
        .copied()
        .filter(|p| (p[0].hypot(p[1]) - 1.0).abs() < 1e-9)
        .collect()];
    // The rim, in angle order.
    project.outline[0].sort_by(|a, b| a[1].atan2(a[0]).total_cmp(&b[1].atan2(b[0])));
    let mut s = session(project.clone(), "remesh");
    let before = s.project().to_json();
    assert_eq!(ask(&mut s, Request::MeshOutline { vertices: 400 }), None);
    let doc = s.project();
    assert_ne!(doc.mesh.positions.len(), project.mesh.positions.len());
    assert_eq!(doc.keyframes.len(), 4);
    for (a, b) in doc.keyframes.iter().zip(&project.keyframes) {
        assert_eq!((a.time, &a.easing), (b.time, &b.easing));
    }
    assert_eq!(doc.keyframes[1].pins.len(), 2);
    assert_eq!(
        s.history()
            .labels()
            .last()
            .map(|l| l.starts_with("new mesh")),
        Some(true)
    );
    let n = doc.mesh.positions.len();
    assert!(
        (n as f64 - 400.0).abs() / 400.0 <= 0.1,
        "{n} vertices for 400"
    );
    // The bent keyframes stay bent: their points moved from the rest like the old ones.
    let spread = |p: &[[f64; 2]]| p.iter().map(|q| q[1]).fold(f64::NEG_INFINITY, f64::max);
    assert!(
        (spread(&doc.keyframes[3].positions) - spread(&project.keyframes[3].positions)).abs()
            < 0.05
    );
    ask(&mut s, Request::Undo);
    assert_eq!(s.project().to_json(), before);
    ask(&mut s, Request::Redo);
    assert_eq!(s.project().keyframes.len(), 4);
    // An outline of more points than the studio meshes is refused before any work.
    let big: Vec<[f64; 2]> = (0..300_000)
        .map(|i| {
            let a = i as f64 * std::f64::consts::TAU / 300_000.0;
            [a.cos(), a.sin()]
        })
        .collect();
    assert!(
        ask(&mut s, Request::OutlineSet { loops: vec![big] }).is_some(),
        "over the outline limit"
    );
    ask(
        &mut s,
        Request::OutlineSet {
            loops: vec![project.outline[0].clone()],
        },
    );
    assert!(ask(&mut s, Request::MeshOutline { vertices: 500_000 }).is_some());
}

/// Drags fill the history only up to its byte budget (here 4 MB), dropping the oldest steps
/// and saying so; undo then reaches back as far as is kept.
#[test]
fn the_history_stays_within_its_budget() {
    let mesh = generate::disk(generate::rings_for(5_000), 0.1);
    let n = mesh.positions.len() as u32;
    let mut s = session(Project::new(&mesh, None), "budget");
    let budget = 4 << 20;
    s.limit_history(budget, 1000);
    ask(
        &mut s,
        Request::Method {
            name: "arap".into(),
            weight: None,
            max_distortion: None,
        },
    );
    for v in [0, n - 1] {
        assert_eq!(ask(&mut s, Request::PinAdd { vertex: v }), None);
    }
    let far = s.project().keyframes[0].positions[(n - 1) as usize];
    // 100 strokes of one move each: each keeps a 5K-vertex pose (80 KB).
    for k in 0..100 {
        let t = 0.02 * (k % 10) as f64;
        let why = ask(
            &mut s,
            Request::Drag {
                seq: 1,
                pins: vec![0, n - 1],
                targets: vec![[0.0, 0.0], [far[0] + t, far[1]]],
                moving: None,
            },
        );
        assert_eq!(why, None);
        s.handle(Request::DragEnd);
    }
    let h = s.history();
    assert!(h.bytes() <= budget, "{} bytes", h.bytes());
    assert!(h.dropped() > 0);
    let kept = h.undo_len();
    assert!(kept > 20 && kept < 60, "{kept} steps kept");
    let state: serde_json::Value = serde_json::from_str(&s.state_json()).expect("json");
    assert_eq!(state["history"]["dropped"], h.dropped());
    let mut undone = 0;
    while ask(&mut s, Request::Undo).is_none() {
        undone += 1;
    }
    assert_eq!(undone, kept);
    assert!(
        s.dirty(),
        "the opened state was dropped: the document stays unsaved"
    );
}

/// Messages count keyframes from 1 and name no vertex by its number.
#[test]
fn messages_count_from_one() {
    let mut s = session(animated(4, 3), "numbers");
    let why = ask(&mut s, Request::DeleteKeyframe { keyframe: 5 }).expect("refused");
    assert!(why.contains("keyframe 6"), "{why}");
    let why = ask(
        &mut s,
        Request::SetTime {
            keyframe: 1,
            time: 7.0,
            ripple: false,
        },
    )
    .expect("refused");
    assert!(why.contains("keyframe 2"), "{why}");
    ask(&mut s, Request::PinAdd { vertex: 2 });
    let why = ask(&mut s, Request::PinAdd { vertex: 2 }).expect("refused");
    assert!(!why.contains('2') || why.contains("already"), "{why}");
    assert!(s
        .history()
        .labels()
        .last()
        .is_some_and(|l| l.contains("keyframe 1")));
}

/// A ripple retime moves the keyframe and every later one by the same time, as one undo step;
/// without ripple the later ones stay.
#[test]
fn a_ripple_retime_moves_the_later_keyframes_in_one_step() {
    let mut s = session(animated(4, 4), "ripple");
    let times =
        |s: &Session| -> Vec<f64> { s.project().keyframes.iter().map(|k| k.time).collect() };
    assert_eq!(times(&s), [0.0, 1.0, 2.0, 3.0]);
    let set = |keyframe, time, ripple| Request::SetTime {
        keyframe,
        time,
        ripple,
    };
    assert_eq!(ask(&mut s, set(1, 1.5, true)), None);
    assert_eq!(times(&s), [0.0, 1.5, 2.5, 3.5]);
    assert_eq!(s.view().current, 1);
    // Earlier again, past where keyframe 3 was: each step keeps the order.
    assert_eq!(ask(&mut s, set(1, 0.25, true)), None);
    assert_eq!(times(&s), [0.0, 0.25, 1.25, 2.25]);
    // Not before the keyframe before it.
    assert!(ask(&mut s, set(2, 0.2, true)).is_some());
    assert_eq!(times(&s), [0.0, 0.25, 1.25, 2.25]);
    assert_eq!(ask(&mut s, Request::Undo), None);
    assert_eq!(times(&s), [0.0, 1.5, 2.5, 3.5]);
    assert_eq!(ask(&mut s, Request::Undo), None);
    assert_eq!(times(&s), [0.0, 1.0, 2.0, 3.0]);
    assert_eq!(ask(&mut s, set(1, 1.5, false)), None);
    assert_eq!(times(&s), [0.0, 1.5, 2.0, 3.0]);
    // The last keyframe ripples alone; the first never moves.
    assert_eq!(ask(&mut s, set(3, 4.0, true)), None);
    assert_eq!(times(&s), [0.0, 1.5, 2.0, 4.0]);
    assert!(ask(&mut s, set(0, 0.5, true)).is_some());
}

/// A pin moved to another vertex keeps the pose (the handle is placed again), is one undo step,
/// and is refused onto a pinned vertex or off the mesh.
#[test]
fn a_pin_moves_to_another_vertex_without_moving_the_pose() {
    let mut s = session(animated(4, 3), "pin-move");
    assert_eq!(ask(&mut s, Request::Select { keyframe: 1 }), None);
    assert_eq!(ask(&mut s, Request::PinAdd { vertex: 3 }), None);
    assert_eq!(ask(&mut s, Request::PinAdd { vertex: 5 }), None);
    let pose = s.project().keyframes[1].positions.clone();
    assert_eq!(ask(&mut s, Request::PinMove { from: 3, to: 7 }), None);
    assert_eq!(s.project().keyframes[1].pins, [7, 5]);
    assert_eq!(s.project().keyframes[1].positions, pose);
    assert!(ask(&mut s, Request::PinMove { from: 7, to: 5 }).is_some());
    assert!(ask(
        &mut s,
        Request::PinMove {
            from: 7,
            to: 1_000_000
        }
    )
    .is_some());
    assert!(ask(&mut s, Request::PinMove { from: 8, to: 9 }).is_some());
    assert_eq!(ask(&mut s, Request::Undo), None);
    assert_eq!(s.project().keyframes[1].pins, [3, 5]);
}

/// Keyframe poses are sent to the page that asks, each with its revision, which is new when
/// that keyframe's pose changes and the same when another's does.
#[test]
fn keyframe_poses_are_sent_with_revisions_that_follow_their_edits() {
    let mut s = session(animated(4, 3), "ghosts");
    let revs = |s: &Session| -> Vec<u64> {
        let state: serde_json::Value = serde_json::from_str(&s.state_json()).expect("json");
        state["keyframes"]
            .as_array()
            .expect("keys")
            .iter()
            .map(|k| k["rev"].as_u64().expect("rev"))
            .collect()
    };
    let before = revs(&s);
    let reply = s.handle(Request::Ghosts {
        keyframes: vec![2, 0],
    });
    let ghosts: Vec<&Vec<u8>> = reply
        .answers
        .iter()
        .filter_map(|a| match a {
            Answer::Binary(b) => Some(b),
            _ => None,
        })
        .collect();
    assert_eq!(ghosts.len(), 2);
    let word = |b: &[u8], i: usize| u32::from_le_bytes(b[4 * i..4 * i + 4].try_into().expect("4"));
    let n = s.project().mesh.positions.len();
    assert_eq!(
        [word(ghosts[0], 0), word(ghosts[0], 1), word(ghosts[0], 2)],
        [4, 2, n as u32]
    );
    assert_eq!(u64::from(word(ghosts[0], 3)), before[2]);
    assert_eq!(ghosts[0].len(), 16 + 8 * n);
    let x = f32::from_le_bytes(ghosts[0][16..20].try_into().expect("4"));
    assert_eq!(x, s.project().keyframes[2].positions[0][0] as f32);
    // A drag on keyframe 2 renews its revision only.
    assert_eq!(ask(&mut s, Request::Select { keyframe: 1 }), None);
    assert_eq!(ask(&mut s, Request::PinAdd { vertex: 0 }), None);
    let p = s.project().keyframes[1].positions[0];
    assert_eq!(
        ask(
            &mut s,
            Request::Drag {
                seq: 1,
                pins: vec![0],
                targets: vec![[p[0] + 0.05, p[1]]],
                moving: None,
            }
        ),
        None
    );
    assert_eq!(ask(&mut s, Request::DragEnd), None);
    let after = revs(&s);
    assert_eq!((after[0], after[2]), (before[0], before[2]));
    assert_ne!(after[1], before[1]);
    assert!(ask(&mut s, Request::Ghosts { keyframes: vec![3] }).is_some());
    assert!(ask(
        &mut s,
        Request::Ghosts {
            keyframes: vec![0; 65]
        }
    )
    .is_some());
}

/// A keyframe from another drawing: the rest mesh laid over it in the background, added as
/// one undoable step with the drawing's picture and texture coordinates, kept by a save and
/// read back; a drawing that cannot be laid over leaves the document as it was and says why.
#[test]
fn a_drawing_becomes_a_keyframe_in_one_undoable_step() {
    use bdmorph::render::raster;
    let dir = scratch("drawing");
    let write = |name: &str, arm: f64, bend: f64| {
        let png = raster::encode_png(&generate::figure_picture(256, arm, bend)).expect("png");
        std::fs::write(dir.join(name), png).expect("write");
    };
    write("a.png", 0.0, 0.0);
    // The drawing in blue, to tell its picture from the rest picture's in a still.
    let mut blue = generate::figure_picture(256, 2.0, 0.2);
    for p in blue.rgba.chunks_mut(4) {
        p[..3].copy_from_slice(&[20, 40, 240]);
    }
    std::fs::write(dir.join("b.png"), raster::encode_png(&blue).expect("png")).expect("write");
    // Two pieces: holes that differ are handled, a different number of pieces is not.
    let two = generate::picture(256, 256, |x, y| {
        let left = generate::capsule_distance([x, y], [70.0, 128.0], [70.0, 128.0], 40.0);
        let right = generate::capsule_distance([x, y], [190.0, 128.0], [190.0, 128.0], 40.0);
        left.min(right)
    });
    std::fs::write(dir.join("two.png"), raster::encode_png(&two).unwrap()).unwrap();
    let mut s = Session::new(
        Project::new(&generate::disk(4, 0.1), None),
        dir.clone(),
        None,
        None,
    )
    .expect("a session");
    // Without a picture there is nothing to lay over.
    let refused = ask(
        &mut s,
        Request::DrawingKeyframe {
            name: "b.png".into(),
            pairs: vec![],
            time: None,
        },
    );
    assert!(refused.unwrap().contains("no picture"));
    assert_eq!(
        ask(
            &mut s,
            Request::Open {
                name: "a.png".into()
            }
        ),
        None
    );
    let before = s.project().to_json();
    assert_eq!(s.project().keyframes.len(), 1);
    // A pair inside: the body's middle moved 4 px right.
    let pairs = vec![[[128.0, 150.0], [132.0, 150.0]]];
    assert_eq!(
        ask(
            &mut s,
            Request::DrawingKeyframe {
                name: "b.png".into(),
                pairs: pairs.clone(),
                time: Some(2.0),
            },
        ),
        None
    );
    let doc = s.project().clone();
    assert_eq!(doc.keyframes.len(), 2);
    let key = &doc.keyframes[1];
    assert_eq!(key.time, 2.0);
    let drawing = key.drawing.as_ref().expect("a drawing");
    assert_eq!(drawing.picture, "b.png");
    assert_eq!(drawing.pairs, pairs);
    let n = doc.mesh.positions.len();
    assert_eq!(drawing.texcoords.len(), n);
    // Flip-free, and placed as the drawing is: the rest mesh's map from its picture's pixels
    // applied to the layout over B.
    let area = |p: &[[f64; 2]], f: &[u32; 3]| {
        let (a, b, c) = (p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]);
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    assert!(doc.mesh.faces.iter().all(|f| area(&key.positions, f) > 0.0));
    let rest_uv = doc.mesh.texcoords.as_ref().expect("texcoords");
    let (i, j) = (0, n - 1);
    let scale =
        (doc.mesh.positions[j][0] - doc.mesh.positions[i][0]) / (rest_uv[j][0] - rest_uv[i][0]);
    for v in 0..n {
        let want = [
            doc.mesh.positions[i][0] + scale * (drawing.texcoords[v][0] - rest_uv[i][0]),
            doc.mesh.positions[i][1] + scale * (drawing.texcoords[v][1] - rest_uv[i][1]),
        ];
        let got = key.positions[v];
        assert!(
            (got[0] - want[0]).hypot(got[1] - want[1]) < 1e-6 * scale,
            "vertex {v}: {got:?} against {want:?}"
        );
    }
    let state: serde_json::Value = serde_json::from_str(&s.state_json()).unwrap();
    assert_eq!(state["keyframes"][1]["drawing"], "b.png");
    assert!(s.drawing_picture(1).is_some());
    assert_eq!(s.drawing_texcoords(1).map(|b| b.len()), Some(8 * n));
    assert!(s.drawing_texcoords(0).is_none());
    // A still of the keyframe, and of the animation half way: its drawing's picture, then
    // the two pictures cross-faded.
    let still = |s: &mut Session, time: Option<f64>, name: &str| {
        let request = Request::Export {
            format: "still".into(),
            name: name.into(),
            frames: None,
            time,
            size: Some([200, 200]),
            range: None,
            background: Some("transparent".into()),
            overwrite: false,
        };
        assert_eq!(ask(s, request), None);
        let image = raster::decode_image(&std::fs::read(dir.join(name)).unwrap()).unwrap();
        let opaque: Vec<&[u8]> = image.rgba.chunks(4).filter(|p| p[3] == 255).collect();
        let blue = opaque.iter().filter(|p| p[2] > 200 && p[0] < 60).count();
        (blue as f64 / opaque.len() as f64, opaque.len())
    };
    let (keyed, covered) = still(&mut s, Some(2.0), "key.png");
    assert!(covered > 1000 && keyed > 0.95, "{keyed} of {covered}");
    let (start, _) = still(&mut s, Some(0.0), "start.png");
    assert!(start < 0.01, "{start}");
    let (half, _) = still(&mut s, Some(1.0), "half.png");
    assert!(half < 0.01, "half way neither picture alone: {half}");
    // One undo step.
    ask(&mut s, Request::Undo);
    assert_eq!(s.project().to_json(), before);
    ask(&mut s, Request::Redo);
    assert_eq!(s.project(), &doc);
    // Saved and read back.
    assert_eq!(
        ask(
            &mut s,
            Request::Save {
                name: Some("walk.json".into()),
                overwrite: None
            }
        ),
        None
    );
    let back = Project::read(&dir.join("walk.json")).expect("reads");
    assert_eq!(back.keyframes[1].drawing, doc.keyframes[1].drawing);
    // Opened again in a new studio: the drawing's picture is found.
    let mut again = Session::new(
        Project::new(&generate::disk(4, 0.1), None),
        dir.clone(),
        None,
        None,
    )
    .expect("a session");
    assert_eq!(
        ask(
            &mut again,
            Request::Open {
                name: "walk.json".into()
            }
        ),
        None
    );
    assert_eq!(
        again.project().keyframes[1].drawing,
        doc.keyframes[1].drawing
    );
    assert!(again.drawing_picture(1).is_some());
    // Without the drawing's file: opened, and said so; an export says so too.
    std::fs::copy(dir.join("b.png"), dir.join("b.kept")).unwrap();
    std::fs::remove_file(dir.join("b.png")).unwrap();
    let mut third = Session::new(
        Project::new(&generate::disk(4, 0.1), None),
        dir.clone(),
        None,
        None,
    )
    .expect("a session");
    assert_eq!(
        ask(
            &mut third,
            Request::Open {
                name: "walk.json".into()
            }
        ),
        None
    );
    let said = serde_json::from_str::<serde_json::Value>(&third.state_json()).unwrap()["notes"]
        .to_string();
    assert!(
        said.contains("keyframe 2's (b.png)") && said.contains("not there"),
        "{said}"
    );
    assert!(third.drawing_picture(1).is_none());
    let export = Request::Export {
        format: "gif".into(),
        name: "anim.gif".into(),
        frames: Some(3),
        time: None,
        size: Some([64, 64]),
        range: None,
        background: None,
        overwrite: false,
    };
    assert_eq!(ask(&mut third, export), None);
    let said = serde_json::from_str::<serde_json::Value>(&third.state_json()).unwrap()["notes"]
        .to_string();
    assert!(
        said.contains("could not be read") && said.contains("exported"),
        "{said}"
    );
    std::fs::rename(dir.join("b.kept"), dir.join("b.png")).unwrap();
    // A drawing of two pieces: the job fails, says why, and changes nothing.
    let kept = s.project().to_json();
    assert_eq!(
        ask(
            &mut s,
            Request::DrawingKeyframe {
                name: "two.png".into(),
                pairs: vec![],
                time: None,
            },
        ),
        None
    );
    assert_eq!(s.project().to_json(), kept);
    let state: serde_json::Value = serde_json::from_str(&s.state_json()).unwrap();
    let notes = state["notes"].to_string();
    assert!(
        notes.contains("two.png") && notes.contains("piece"),
        "{notes}"
    );
    // Refused before any work: a missing file, a time taken, too many pairs.
    for (name, time, pairs) in [
        ("nothing.png", None, 0),
        ("b.png", Some(2.0), 0),
        ("b.png", None, 201),
    ] {
        let refused = ask(
            &mut s,
            Request::DrawingKeyframe {
                name: name.into(),
                pairs: vec![[[1.0, 1.0], [1.0, 1.0]]; pairs],
                time,
            },
        );
        assert!(refused.is_some(), "{name} {time:?} {pairs}");
        assert_eq!(s.project().to_json(), kept);
    }
}
