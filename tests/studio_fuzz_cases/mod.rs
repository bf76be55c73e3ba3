//! The studio's messages fuzzed in process: seeded random sequences of requests, each a JSON
//! message built from the protocol's operations with hostile values (huge, negative and tiny
//! numbers, indices past the end, paths that leave the workspace, malformed and oversized
//! outlines and meshes as text), parsed as the server parses them and handed to one session,
//! its background work run at once. No message may panic the session; after every message
//! the document must still pass its own checks (limits, finite coordinates), be written and
//! read back, and every refusal must leave it unchanged. Uploads get random bytes too; the
//! project file reader gets mutated projects.
//!
//! Part of the `studio_session` tests. For a longer run:
//! `BDMORPH_FUZZ_SEQUENCES=2000 cargo test --test studio_session fuzz`.

use bdmorph::generate;
use bdmorph::studio::project::{Keyframe, Project};
use bdmorph::studio::protocol::Request;
use bdmorph::studio::session::{Answer, Reply, Session};
use serde_json::{json, Value};

fn scratch(name: &str) -> std::path::PathBuf {
    let dir =
        std::env::temp_dir().join(format!("bdmorph-studio-fuzz-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// xorshift, seeded: every sequence is repeatable from its seed.
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
    fn pick<T: Clone>(&mut self, items: &[T]) -> T {
        items[self.below(items.len())].clone()
    }
}

/// Numbers a careless page or an attacker might send.
const NUMBERS: [f64; 16] = [
    0.0,
    1.0,
    -1.0,
    0.5,
    2.0,
    3.0,
    10.0,
    1e9,
    -1e9,
    1e154,
    1e300,
    -1e308,
    1e-320,
    4294967295.0,
    18446744073709551615.0,
    0.25,
];

fn number(r: &mut Rng) -> Value {
    json!(r.pick(&NUMBERS))
}

/// An index: mostly small, sometimes far past the end.
fn index(r: &mut Rng) -> Value {
    match r.below(6) {
        0 => json!(u32::MAX),
        1 => json!(1_000_000),
        _ => json!(r.below(4)),
    }
}

fn text(r: &mut Rng) -> Value {
    let long = "a".repeat(5000);
    json!(r.pick(&[
        "",
        "linear",
        "ease-in-out",
        "cubic-bezier(0,2,1,-1)",
        "arap",
        "kvf",
        "bounded",
        "png",
        "gif",
        "mp4",
        "obj",
        "html",
        "x.bdmorph",
        "../outside.png",
        "/etc/passwd",
        "sub/../../x.obj",
        "a\u{0}b",
        long.as_str(),
    ]))
}

fn point(r: &mut Rng) -> Value {
    json!([r.pick(&NUMBERS), r.pick(&NUMBERS)])
}

/// File contents a page might upload or paste: meshes and outlines, good and hostile.
fn file_text(r: &mut Rng) -> (String, String) {
    let nested = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\">{}<rect width=\"1\" height=\"1\"/>{}</svg>",
        "<g>".repeat(5000),
        "</g>".repeat(5000)
    );
    r.pick(&[
        (
            "square.svg".to_owned(),
            "<svg xmlns=\"http://www.w3.org/2000/svg\"><rect width=\"10\" height=\"10\"/></svg>"
                .to_owned(),
        ),
        ("nested.svg".to_owned(), nested),
        (
            "circle.svg".to_owned(),
            "<svg xmlns=\"http://www.w3.org/2000/svg\"><circle r=\"1e154\"/></svg>".to_owned(),
        ),
        ("huge.poly".to_owned(), "100000000000000 2 0 0\n".to_owned()),
        (
            "big.poly".to_owned(),
            "1000000000 2 0 0\n1 0 0\n2 1 0\n3 0 1\n".to_owned(),
        ),
        (
            "key.obj".to_owned(),
            "v 0 0\nv 1 0\nv 0 1\nf 1 2 3\n".to_owned(),
        ),
        ("bad.obj".to_owned(), "v nan 0\nf 1 1 1\n".to_owned()),
        (
            "huge.off".to_owned(),
            "OFF\n100000000000000 1 0\n".to_owned(),
        ),
    ])
}

/// One message: an operation of the protocol with random values.
fn message(r: &mut Rng) -> Value {
    match r.below(40) {
        0 => json!({"op": "hello"}),
        1 => json!({"op": "select", "keyframe": index(r)}),
        2 => json!({"op": "mode", "mode": r.pick(&["pose", "outline", "other"])}),
        3 | 4 => json!({"op": "pin_add", "vertex": index(r)}),
        5 => json!({"op": "pin_remove", "vertex": index(r)}),
        6 => match r.below(3) {
            0 => json!({"op": "pins_clear"}),
            1 => json!({"op": "pin_move", "from": index(r), "to": index(r)}),
            _ => {
                let keys: Vec<Value> = (0..r.below(4)).map(|_| index(r)).collect();
                json!({"op": "ghosts", "keyframes": keys})
            }
        },
        7..=10 => {
            let n = r.below(3);
            let pins: Vec<Value> = (0..n).map(|_| index(r)).collect();
            let targets: Vec<Value> = (0..r.below(3)).map(|_| point(r)).collect();
            json!({"op": "drag", "seq": r.below(100), "pins": pins, "targets": targets})
        }
        11 => json!({"op": "drag_end"}),
        12 => {
            json!({"op": "method", "name": text(r), "weight": number(r), "max_distortion": number(r)})
        }
        13 | 14 => json!({"op": "undo"}),
        15 => json!({"op": "redo"}),
        16 => json!({"op": "reset"}),
        17 => json!({"op": "repair", "keyframe": index(r)}),
        18 => json!({"op": "add_keyframe", "time": number(r), "copy": index(r)}),
        19 => json!({"op": "delete_keyframe", "keyframe": index(r)}),
        20 => json!({"op": "move_keyframe", "keyframe": index(r), "to": index(r)}),
        21 => {
            json!({"op": "set_time", "keyframe": index(r), "time": number(r), "ripple": r.below(2) == 0})
        }
        22 => json!({"op": "set_easing", "keyframe": index(r), "easing": text(r)}),
        23 => json!({"op": "frame_to_keyframe", "time": number(r)}),
        24 => {
            let (name, body) = file_text(r);
            json!({"op": "load_keyframe", "name": name, "text": body, "time": number(r)})
        }
        25 => {
            json!({"op": "trace_outline", "tolerance": number(r), "threshold": number(r), "vertices": index(r)})
        }
        26 => {
            let ring: Vec<Value> = (0..r.below(6)).map(|_| point(r)).collect();
            json!({"op": "outline_set", "loops": [ring]})
        }
        27 => json!({"op": "outline_new_loop"}),
        28 => json!({"op": "outline_point", "point": point(r)}),
        29 => json!({"op": "outline_close"}),
        30 => json!({"op": "outline_move", "ring": index(r), "index": index(r), "to": point(r)}),
        31 => {
            json!({"op": "outline_insert", "ring": index(r), "index": index(r), "point": point(r)})
        }
        32 => json!({"op": "outline_remove", "ring": index(r), "index": index(r)}),
        33 => json!({"op": "mesh_outline", "vertices": r.pick(&[0usize, 3, 50, 200, 1 << 40])}),
        34 => {
            let (name, body) = file_text(r);
            json!({"op": "import_outline", "name": name, "text": body, "vertices": r.pick(&[0usize, 50, 200, 1 << 40])})
        }
        35 => match r.below(5) {
            0 => json!({"op": "fps", "fps": number(r)}),
            3 => {
                let order: Vec<Value> = (0..r.below(7)).map(|_| index(r)).collect();
                json!({"op": "part_order", "order": order})
            }
            1 => {
                let faces: Vec<Value> = (0..r.below(5)).map(|_| index(r)).collect();
                json!({"op": "paint_depth", "faces": faces, "all": r.below(4) == 0, "level": number(r)})
            }
            2 => {
                let faces: Vec<Value> = (0..r.below(5)).map(|_| index(r)).collect();
                json!({"op": "paint_stiffness", "faces": faces, "all": r.below(4) == 0, "weight": number(r)})
            }
            _ => json!({"op": "loop_range", "range": [number(r), number(r)]}),
        },
        36 => json!({"op": "scrub", "seq": r.below(100), "time": number(r)}),
        37 => json!({"op": "save", "name": text(r), "overwrite": r.below(2) == 0}),
        38 => {
            json!({"op": "export", "format": r.pick(&["gif", "apng", "webp", "sheet", "frames", "mp4"]).to_owned(), "name": text(r),
                     "frames": r.pick(&[0u64, 2, 3, 4_294_967_295]), "time": number(r),
                     "size": [index(r), index(r)], "range": [index(r), index(r)],
                     "background": r.pick(&["transparent", "#fff", "nonsense", "#12345"]).to_owned()})
        }
        _ => {
            json!({"op": r.pick(&["open", "attach_picture", "recover", "discard"]), "name": text(r)})
        }
    }
}

/// A small animated disk.
fn project() -> Project {
    let mesh = generate::disk(3, 0.1);
    let mut project = Project::new(&mesh, None);
    project.outline = vec![vec![[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]];
    project.keyframes.push(Keyframe {
        time: 1.0,
        easing: "linear".into(),
        positions: generate::bend(&mesh, 0.3).positions,
        pins: Vec::new(),
        drawing: None,
    });
    project
}

fn refused(reply: &Reply) -> bool {
    reply.answers.iter().any(|a| match a {
        Answer::Text(t) => serde_json::from_str::<Value>(t).is_ok_and(|v| v["type"] == "error"),
        Answer::Binary(_) => false,
    })
}

fn sequences() -> u64 {
    std::env::var("BDMORPH_FUZZ_SEQUENCES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(24)
}

#[test]
fn random_messages_never_panic_the_session_or_corrupt_the_document() {
    for seed in 1..=sequences() {
        let dir = scratch(&format!("seq{seed}"));
        let mut session = Session::new(project(), dir.clone(), None, None).expect("a session");
        let mut r = Rng(0x9E37_79B9_7F4A_7C15 ^ seed.wrapping_mul(0x2545_F491_4F6C_DD1D));
        for step in 0..40 {
            let sent = message(&mut r).to_string();
            if std::env::var_os("BDMORPH_FUZZ_TRACE").is_some() {
                eprintln!("seed {seed} step {step}: {sent:.200}");
            }
            let Ok(request) = serde_json::from_str::<Request>(&sent) else {
                continue;
            };
            let before = session.project().to_json();
            let reply = session.handle(request);
            if refused(&reply) {
                assert_eq!(
                    session.project().to_json(),
                    before,
                    "seed {seed} step {step}: a refused request changed the document: {sent:.300}"
                );
            }
            if let Some(work) = reply.work {
                session.run_now(work);
            }
            let doc = session.project();
            if let Err(e) = doc.check() {
                panic!("seed {seed} step {step}: the document fails its checks ({e}) after {sent:.300}");
            }
            let json = doc.to_json();
            assert!(
                Project::from_json(&json).is_ok(),
                "seed {seed} step {step}: the document does not read back after {sent:.300}"
            );
        }
        // Random uploads: a header that is not one, or one with random bytes.
        for k in 0..8 {
            let mut bytes = Vec::new();
            for _ in 0..r.below(200) {
                bytes.push(r.next() as u8);
            }
            if k % 2 == 0 {
                let header =
                    json!({"kind": r.pick(&["open", "attach", "other"]), "name": text(&mut r)});
                let mut framed = header.to_string().into_bytes();
                framed.push(b'\n');
                framed.extend_from_slice(&bytes);
                bytes = framed;
            }
            let reply = session.handle_upload(&bytes);
            if let Some(work) = reply.work {
                session.run_now(work);
            }
            assert!(session.project().check().is_ok(), "seed {seed}: upload {k}");
        }
        // Nothing was written outside the workspace.
        assert!(!dir.parent().expect("a parent").join("outside.png").exists());
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn mutated_project_files_are_read_or_refused() {
    let good = project().to_json();
    let mut r = Rng(0xDEAD_BEEF);
    for _ in 0..(sequences() * 40) {
        let mut bytes = good.clone();
        for _ in 0..1 + r.below(8) {
            if bytes.is_empty() {
                break;
            }
            let at = r.below(bytes.len());
            match r.below(4) {
                0 => bytes[at] = r.next() as u8,
                1 => {
                    bytes.remove(at);
                }
                2 => bytes.insert(at, r.pick(b"9-e[{\",0")),
                _ => bytes.truncate(at),
            }
        }
        if let Ok(project) = Project::from_json(&bytes) {
            // What reads must pass the checks a session makes.
            let _ = project.check();
        }
    }
    // Deeply nested JSON is refused, not a stack overflow.
    let deep = format!("{}{}", "[".repeat(100_000), "]".repeat(100_000));
    assert!(Project::from_json(deep.as_bytes()).is_err());
}
