//! The studio's interactive paths on the server side, from a request's JSON text to the
//! answers' bytes (parse, the engine, the edit kept in the document, the binary frame with its
//! distortions for the page that asked): a drag at about 5K vertices (KVF, four handles) and a
//! scrub at about 10K (two keyframes, a new time per call).
//!
//! Baselines in the same run: the engine call alone (`Deformer::drag`, `KeyframePath::frame_into`),
//! so the ratio is what the session layer costs. The browser's share (transfer and drawing) is
//! measured in `tests/studio_browser.rs`.
//!
//! `cargo bench --bench studio`

use criterion::{criterion_group, criterion_main, Criterion};

use bdmorph::deform::{Deformer, PoseMethod};
use bdmorph::studio::project::Keyframe;
use bdmorph::studio::protocol::Request;
use bdmorph::studio::session::{Answer, Revs};
use bdmorph::studio::{Project, Session};
use bdmorph::{generate, KeyframePath, PlanarMesh};

fn disk(n: usize) -> PlanarMesh {
    generate::disk(generate::rings_for(n), 0.2)
}

/// A value moving back and forth in [0, 1], a new one per call.
struct Sweep(u32);

impl Sweep {
    fn next(&mut self) -> f64 {
        self.0 += 1;
        let s = f64::from(self.0 % 40) / 20.0;
        if s > 1.0 {
            2.0 - s
        } else {
            s
        }
    }
}

fn bytes_of(answers: &[Answer]) -> usize {
    answers
        .iter()
        .map(|a| match a {
            Answer::Binary(b) => b.len(),
            Answer::Text(t) => t.len(),
        })
        .sum()
}

fn drag(c: &mut Criterion) {
    let mesh = disk(5000);
    let n = mesh.positions.len() as u32;
    let pins = [0, n - 1, n - 1 - n / 10, n - 1 - n / 5];
    let reach = 0.1;
    let targets = |s: f64| -> Vec<[f64; 2]> {
        pins.iter()
            .enumerate()
            .map(|(i, &v)| {
                let p = mesh.positions[v as usize];
                if i == 1 {
                    [p[0] + reach * s, p[1] + 0.6 * reach * s]
                } else {
                    p
                }
            })
            .collect()
    };
    let mut group = c.benchmark_group(format!("studio_drag/disk-{n}"));
    let workspace = std::env::temp_dir();
    let mut session =
        Session::new(Project::new(&mesh, None), workspace, None, None).expect("session");
    for v in pins {
        session.handle(Request::PinAdd { vertex: v });
    }
    let mut seen = Revs::default();
    session.updates(&mut seen, 0);
    let mut sweep = Sweep(0);
    let mut seq = 0;
    group.bench_function("request_to_answer", |b| {
        b.iter(|| {
            seq += 1;
            let text = serde_json::json!({"op": "drag", "seq": seq, "pins": pins, "targets": targets(sweep.next())})
                .to_string();
            let request: Request = serde_json::from_str(&text).expect("request");
            let reply = session.handle(request);
            bytes_of(&reply.answers) + bytes_of(&session.updates(&mut seen, seq))
        })
    });
    let mut pose = Deformer::new(&mesh, PoseMethod::kvf()).expect("deformer");
    pose.set_pins(&pins).expect("pins");
    let mut sweep = Sweep(0);
    group.bench_function("engine_only", |b| {
        b.iter(|| pose.drag(&targets(sweep.next())).expect("drag").iterations)
    });
    group.finish();
}

fn scrub(c: &mut Criterion) {
    let mesh = disk(10000);
    let bent = generate::bend(&mesh, 0.8);
    let mut project = Project::new(&mesh, None);
    project.keyframes.push(Keyframe {
        time: 1.0,
        easing: "linear".into(),
        positions: bent.positions.clone(),
        pins: Vec::new(),
        drawing: None,
    });
    let mut group = c.benchmark_group(format!("studio_scrub/disk-{}", mesh.positions.len()));
    let mut session = Session::new(project, std::env::temp_dir(), None, None).expect("session");
    let mut seen = Revs::default();
    session.updates(&mut seen, 0);
    let mut sweep = Sweep(0);
    let mut seq = 0;
    group.bench_function("request_to_answer", |b| {
        b.iter(|| {
            seq += 1;
            // Strictly between the keyframes (a keyframe's time shows the keyframe).
            let t = 0.001 + 0.998 * sweep.next();
            let text = format!(r#"{{"op":"scrub","seq":{seq},"time":{t}}}"#);
            let request: Request = serde_json::from_str(&text).expect("request");
            let reply = session.handle(request);
            bytes_of(&reply.answers) + bytes_of(&session.updates(&mut seen, seq))
        })
    });
    let mut path = KeyframePath::new(&[mesh.clone(), bent]).expect("path");
    let mut out = mesh.positions.clone();
    let mut sweep = Sweep(0);
    group.bench_function("engine_only", |b| {
        b.iter(|| {
            path.frame_into(0.001 + 0.998 * sweep.next(), &mut out)
                .expect("frame")
                .newton_iterations
        })
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = drag, scrub
}
criterion_main!(benches);
