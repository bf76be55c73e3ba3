//! `bdmorph studio` against a hostile workspace and hostile clients: links leading out of the
//! workspace (an OBJ export's folder, a file to write or open), a project whose picture is
//! outside, a pipe or a device (it opens promptly without the picture, which is not served),
//! and floods of half-sent requests and idle connections (closed after the header timeout,
//! the page's socket answered meanwhile, the page served again afterwards).

#![cfg(unix)]

mod studio_common;

use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use bdmorph::generate;
use studio_common::{scratch, Studio};

/// Every file under `dir` (links not followed), as paths relative to it.
fn tree(dir: &Path) -> Vec<String> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("read_dir").flatten() {
            let t = e.file_type().expect("type");
            if t.is_dir() {
                stack.push(e.path());
            }
            found.push(
                e.path()
                    .strip_prefix(dir)
                    .expect("inside")
                    .display()
                    .to_string(),
            );
        }
    }
    found.sort();
    found
}

#[test]
fn links_out_of_the_workspace_are_refused_for_exports_saves_and_opens() {
    let dir = scratch("hostile-links");
    let outside = scratch("hostile-links-outside");
    std::fs::write(outside.join("secret.json"), "{}").expect("write");
    std::os::unix::fs::symlink(&outside, dir.join("frames")).expect("link");
    std::os::unix::fs::symlink(outside.join("secret.json"), dir.join("secret.json")).expect("link");
    std::os::unix::fs::symlink(outside.join("new.gif"), dir.join("out.gif")).expect("link");
    std::fs::create_dir(dir.join("keep")).expect("dir");
    std::fs::write(dir.join("keep").join("notes.txt"), "mine").expect("write");
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    assert_eq!(c.request(r#"{"op":"add_keyframe","time":1}"#), None);
    // A frame folder that is a link to a folder outside.
    let said = c
        .request(r#"{"op":"export","format":"obj","name":"frames","frames":3}"#)
        .expect("refused");
    assert!(said.contains("link"), "{said}");
    // A file that is a link out (to nothing yet), one to a file outside.
    assert!(c
        .request(r#"{"op":"export","format":"gif","name":"out.gif","frames":3}"#)
        .is_some());
    let said = c
        .request(r#"{"op":"save","name":"secret.json","overwrite":true}"#)
        .expect("refused");
    assert!(said.contains("outside"), "{said}");
    assert!(c.request(r#"{"op":"open","name":"secret.json"}"#).is_some());
    let listed = c.files["files"].to_string();
    assert!(!listed.contains("secret.json"), "{listed}");
    // A folder of the user's own is not replaced by frames: the page is asked first, and
    // asked to replace it, it is refused.
    assert_eq!(
        c.request(r#"{"op":"export","format":"obj","name":"keep","frames":3}"#),
        None
    );
    assert_eq!(
        c.exists.as_ref().map(|e| e["name"].clone()),
        Some("keep".into())
    );
    let said = c
        .request(r#"{"op":"export","format":"obj","name":"keep","frames":3,"overwrite":true}"#)
        .expect("refused");
    assert!(said.contains("notes.txt"), "{said}");
    // A new folder is filled, and filled again when asked to replace it.
    for overwrite in [false, true] {
        let request = format!(
            r#"{{"op":"export","format":"obj","name":"made","frames":3,"overwrite":{overwrite}}}"#
        );
        assert_eq!(c.request(&request), None);
        c.wait_for(60, "the OBJ export", |c| c.state["job"].is_null());
    }
    assert!(
        c.notes()
            .iter()
            .any(|n| n.starts_with("exported") && n.contains("made")),
        "{:?}",
        c.notes()
    );
    assert!(dir.join("made").join("frame_0002.obj").is_file());
    assert_eq!(tree(&outside), ["secret.json"], "nothing written outside");
    assert_eq!(
        std::fs::read_to_string(outside.join("secret.json")).expect("read"),
        "{}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("keep").join("notes.txt")).expect("read"),
        "mine"
    );
    assert!(studio.page_is_served());
}

/// Starts a studio on `file` in a thread of its own: `None` when no URL came in time.
fn start_within(dir: &Path, file: &str, seconds: u64) -> Option<Studio> {
    let (tx, rx) = std::sync::mpsc::channel();
    let (dir, file) = (dir.to_path_buf(), file.to_owned());
    std::thread::spawn(move || {
        let _ = tx.send(Studio::start(&dir, Some(&file)));
    });
    rx.recv_timeout(Duration::from_secs(seconds)).ok()
}

#[test]
fn a_projects_picture_outside_a_pipe_or_a_device_is_not_read() {
    let dir = scratch("hostile-pictures");
    let outside = scratch("hostile-pictures-outside");
    let picture = generate::picture(64, 48, |x, y| (x - 32.0).hypot(y - 24.0) - 20.0);
    let png = bdmorph::render::raster::encode_png(&picture).expect("png");
    std::fs::write(outside.join("private.png"), &png).expect("write");
    std::fs::write(dir.join("skin.png"), &png).expect("write");
    std::os::unix::fs::symlink(outside.join("private.png"), dir.join("link.png")).expect("link");
    let made = Command::new("mkfifo")
        .arg(dir.join("pipe.png"))
        .status()
        .expect("mkfifo runs");
    assert!(made.success());
    let rest = generate::grid(5, 5, 0.0);
    let private = outside.join("private.png").display().to_string();
    let up = format!(
        "../{}/private.png",
        outside.file_name().expect("name").to_string_lossy()
    );
    for (name, texture) in [
        ("good.json", "skin.png"),
        ("outside.json", private.as_str()),
        ("up.json", up.as_str()),
        ("link.json", "link.png"),
        ("pipe.json", "pipe.png"),
        ("zero.json", "/dev/zero"),
    ] {
        let mut project = bdmorph::studio::Project::new(&rest, Some(vec![[0.5, 0.5]; 25]));
        project.texture = Some(texture.into());
        project.write(&dir.join(name)).expect("write");
    }
    // At start-up (a file named on the command line): a pipe or a device does not hang it.
    for (name, kind) in [("pipe.json", "pipe"), ("zero.json", "device")] {
        let studio = start_within(&dir, name, 20)
            .unwrap_or_else(|| panic!("{name}: the studio starts (no hang)"));
        let c = studio.client();
        assert_eq!(c.state["textured"], false, "{name}");
        assert!(
            c.notes()
                .iter()
                .any(|n| n.contains("without its picture") && n.contains(kind)),
            "{name}: {:?}",
            c.notes()
        );
        assert!(studio.resident() < 1 << 30, "{name}: bounded memory");
    }
    // From the page: only a picture inside the workspace is read and served.
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    let texture = format!("/texture?token={}", studio.token);
    for (name, textured) in [
        ("good.json", true),
        ("outside.json", false),
        ("up.json", false),
        ("link.json", false),
        ("pipe.json", false),
        ("zero.json", false),
    ] {
        let start = Instant::now();
        assert_eq!(
            c.request(&serde_json::json!({"op": "open", "name": name}).to_string()),
            None,
            "{name}"
        );
        c.wait_for(20, name, |c| {
            c.state["job"].is_null() && c.state["source"] == name
        });
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "{name}: promptly"
        );
        assert_eq!(c.state["textured"], textured, "{name}");
        let served = studio.get(&texture, "");
        if textured {
            assert_eq!(served, 200, "{name}");
        } else {
            assert_eq!(served, 404, "{name}: the picture is not served");
            assert!(
                c.notes().iter().any(|n| n.contains("without its picture")),
                "{name}: {:?}",
                c.notes()
            );
        }
    }
    let said = c.notes().join("\n");
    assert!(said.contains("outside the workspace"), "{said}");
    assert!(said.contains("pipe"), "{said}");
    assert!(studio.resident() < 1 << 30, "bounded memory");
    assert!(studio.page_is_served());
}

/// Whether the server has closed `s` (end of file or reset); `false` while it stays open.
fn closed_by_server(s: &mut TcpStream) -> bool {
    let mut buf = [0u8; 256];
    loop {
        match s.read(&mut buf) {
            Ok(0) => return true,
            Ok(_) => continue, // an answer (408, say) before the close
            Err(e) if e.kind() == ErrorKind::WouldBlock => return false,
            Err(_) => return true,
        }
    }
}

#[test]
fn floods_of_half_sent_requests_and_idle_connections_are_closed_and_the_page_served() {
    const TIMEOUT_MS: u64 = 1500;
    let dir = scratch("hostile-flood");
    let timeout = TIMEOUT_MS.to_string();
    let studio = Studio::start_env(
        &dir,
        &[],
        &[("BDMORPH_STUDIO_HEADER_TIMEOUT_MS", timeout.as_str())],
    );
    // The page's socket, open before the flood, holds its place.
    let mut c = studio.client();
    let started = Instant::now();
    let mut flood = Vec::new();
    let partial = format!("GET / HTTP/1.1\r\nHost: 127.0.0.1:{}\r\n", studio.port);
    for i in 0..1400 {
        let Ok(mut s) = TcpStream::connect(("127.0.0.1", studio.port)) else {
            continue;
        };
        if i < 300 {
            let _ = s.write_all(partial.as_bytes());
        }
        flood.push(s);
    }
    assert!(flood.len() >= 1000, "{} connections opened", flood.len());
    // Meanwhile the page's socket is answered.
    assert_eq!(c.request(r#"{"op":"add_keyframe","time":1}"#), None);
    assert_eq!(c.state["keyframes"].as_array().map(Vec::len), Some(2));
    // Every flood connection is closed by the server after the header timeout.
    for s in &flood {
        s.set_nonblocking(true).expect("nonblocking");
    }
    let deadline = Instant::now() + Duration::from_millis(TIMEOUT_MS) + Duration::from_secs(8);
    loop {
        flood.retain_mut(|s| !closed_by_server(s));
        if flood.is_empty() {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "{} connections still open after {:?}",
            flood.len(),
            started.elapsed()
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    eprintln!("the flood was closed within {:?}", started.elapsed());
    // The page is served again, a new socket opens, the old one still answers.
    assert!(studio.page_is_served());
    let mut d = studio.client();
    assert_eq!(d.request(r#"{"op":"fps","fps":12}"#), None);
    c.sync();
    assert_eq!(c.state["fps"], 12.0);
}
