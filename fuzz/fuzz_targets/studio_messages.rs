//! The studio's WebSocket messages: the input split into lines, each parsed as the server
//! parses a text message and carried out on one session (its background work run at once);
//! every line that is not a request, every refused request and every accepted one must leave
//! a document that passes its own checks. Seed the corpus with one request per line, e.g.
//! `{"op":"pin_add","vertex":3}`.
#![no_main]

use bdmorph::generate;
use bdmorph::studio::project::{Keyframe, Project};
use bdmorph::studio::messages::parse_request;
use bdmorph::studio::session::Session;
use libfuzzer_sys::fuzz_target;

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

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("bdmorph-fuzz-studio-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let mut session = Session::new(project(), dir, None, None).expect("a session");
    for line in data.split(|&b| b == b'\n').take(64) {
        let request = if line.first() == Some(&b'U') {
            // An upload: the rest of the line as the binary message.
            let reply = session.handle_upload(&line[1..]);
            if let Some(work) = reply.work {
                session.run_now(work);
            }
            continue;
        } else {
            // As the server reads a text message: within its kind's bound.
            match std::str::from_utf8(line).map(parse_request) {
                Ok(Ok(request)) => request,
                _ => continue,
            }
        };
        let reply = session.handle(request);
        if let Some(work) = reply.work {
            session.run_now(work);
        }
        assert!(session.project().check().is_ok());
    }
});
