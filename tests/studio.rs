//! `bdmorph studio` as a server: the URL line, the checks on every request and socket (token,
//! Host, Origin, sizes, malformed input, paths outside the workspace), each refused with the
//! server still serving; the engine over the socket (pins, drags, keyframes, scrubs, save,
//! export); projects refused cleanly when damaged or from another version.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use bdmorph::generate;
use tungstenite::client::IntoClientRequest;
use tungstenite::{Message, WebSocket};

/// A running studio, stopped when dropped.
struct Studio {
    child: Child,
    port: u16,
    token: String,
}

impl Studio {
    fn start(dir: &Path, file: Option<&str>) -> Studio {
        let mut c = Command::new(env!("CARGO_BIN_EXE_bdmorph"));
        c.arg("studio").current_dir(dir);
        if let Some(f) = file {
            c.arg(f);
        }
        let mut child = c
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("starts");
        let mut line = String::new();
        BufReader::new(child.stdout.take().expect("stdout"))
            .read_line(&mut line)
            .expect("the URL line");
        let url = line.trim();
        let rest = url
            .strip_prefix("http://127.0.0.1:")
            .unwrap_or_else(|| panic!("a loopback URL, not {url:?}"));
        let (port, query) = rest.split_once("/?token=").expect("a token");
        Studio {
            child,
            port: port.parse().expect("port"),
            token: query.to_owned(),
        }
    }

    /// Sends raw bytes as one HTTP request; the status code of the answer.
    fn raw(&self, request: &[u8]) -> u16 {
        let mut s = TcpStream::connect(("127.0.0.1", self.port)).expect("connects");
        s.set_read_timeout(Some(Duration::from_secs(10)))
            .expect("timeout");
        s.write_all(request).expect("writes");
        let mut answer = Vec::new();
        let _ = s.read_to_end(&mut answer);
        let text = String::from_utf8_lossy(&answer);
        text.split_whitespace()
            .nth(1)
            .and_then(|c| c.parse().ok())
            .unwrap_or(0)
    }

    fn get(&self, path: &str, extra_headers: &str) -> u16 {
        let request = format!(
            "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\n{extra_headers}Connection: close\r\n\r\n",
            self.port
        );
        self.raw(request.as_bytes())
    }

    fn page_is_served(&self) -> bool {
        self.get(&format!("/?token={}", self.token), "") == 200
    }

    fn socket(&self) -> WebSocket<tungstenite::stream::MaybeTlsStream<TcpStream>> {
        let url = format!("ws://127.0.0.1:{}/ws?token={}", self.port, self.token);
        let (ws, _) = tungstenite::connect(url).expect("socket opens");
        ws
    }
}

impl Drop for Studio {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-studio-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// Sends a request and reads answers until one of `kind` (a binary kind number, or 0 for a
/// JSON state); returns the JSON states seen and that answer's bytes.
fn ask(
    ws: &mut WebSocket<tungstenite::stream::MaybeTlsStream<TcpStream>>,
    request: &str,
    kind: u32,
) -> (Vec<serde_json::Value>, Vec<u8>) {
    ws.send(Message::Text(request.into())).expect("sends");
    let mut states = Vec::new();
    loop {
        match ws.read().expect("an answer") {
            Message::Text(t) => {
                let v: serde_json::Value = serde_json::from_str(t.as_str()).expect("JSON");
                states.push(v);
                if kind == 0 {
                    return (states, Vec::new());
                }
            }
            Message::Binary(b) => {
                let k = u32::from_le_bytes(b[..4].try_into().expect("header"));
                if k == kind {
                    return (states, b.to_vec());
                }
            }
            _ => {}
        }
    }
}

/// `hello`: the state, the mesh message and the first pose (its answers, in that order).
fn hello(
    ws: &mut WebSocket<tungstenite::stream::MaybeTlsStream<TcpStream>>,
) -> (serde_json::Value, Vec<u8>, Vec<u8>) {
    let (states, mesh) = ask(ws, r#"{"op":"hello"}"#, 2);
    let (_, pose) = ask_more(ws, 1);
    (states[0].clone(), mesh, pose)
}

/// Reads on without sending, until a binary answer of `kind`.
fn ask_more(
    ws: &mut WebSocket<tungstenite::stream::MaybeTlsStream<TcpStream>>,
    kind: u32,
) -> (Vec<serde_json::Value>, Vec<u8>) {
    loop {
        if let Message::Binary(b) = ws.read().expect("an answer") {
            if u32::from_le_bytes(b[..4].try_into().expect("header")) == kind {
                return (Vec::new(), b.to_vec());
            }
        }
    }
}

/// Positions of a binary frame (kind 1 or 3).
fn positions(frame: &[u8]) -> Vec<[f32; 2]> {
    let n = u32::from_le_bytes(frame[8..12].try_into().expect("n")) as usize;
    (0..n)
        .map(|i| {
            let at = 32 + 8 * i;
            [
                f32::from_le_bytes(frame[at..at + 4].try_into().expect("x")),
                f32::from_le_bytes(frame[at + 4..at + 8].try_into().expect("y")),
            ]
        })
        .collect()
}

#[test]
fn every_request_needs_the_token_our_host_and_our_origin() {
    let dir = scratch("guard");
    let studio = Studio::start(&dir, None);
    let t = &studio.token;
    assert_eq!(studio.get(&format!("/?token={t}"), ""), 200);
    assert_eq!(studio.get(&format!("/studio.js?token={t}"), ""), 200);
    // No token, a wrong one, one of the wrong length.
    assert_eq!(studio.get("/", ""), 403);
    assert_eq!(studio.get("/studio.js", ""), 403);
    assert_eq!(
        studio.get("/?token=0123456789abcdef0123456789abcdef", ""),
        403
    );
    assert_eq!(studio.get(&format!("/?token={t}x"), ""), 403);
    // A foreign Host (DNS rebinding) and a foreign Origin (another site's page).
    let foreign_host = format!(
        "GET /?token={t} HTTP/1.1\r\nHost: evil.example:{}\r\nConnection: close\r\n\r\n",
        studio.port
    );
    assert_eq!(studio.raw(foreign_host.as_bytes()), 403);
    assert_eq!(
        studio.get(&format!("/?token={t}"), "Origin: http://evil.example\r\n"),
        403
    );
    assert_eq!(
        studio.get(
            &format!("/?token={t}"),
            &format!("Origin: http://127.0.0.1:{}\r\n", studio.port)
        ),
        200
    );
    // No Host at all, malformed HTTP, an oversized request line, other methods, other paths.
    assert_eq!(
        studio.raw(format!("GET /?token={t} HTTP/1.0\r\n\r\n").as_bytes()),
        400
    );
    let garbage = studio.raw(b"\x16\x03\x01 not http at all\r\n\r\n");
    assert!((400..500).contains(&garbage) || garbage == 0, "{garbage}");
    let long = format!("/?token={t}&pad={}", "a".repeat(200_000));
    let code = studio.get(&long, "");
    assert!((400..500).contains(&code) || code == 0, "{code}");
    let post = format!(
        "POST /?token={t} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nContent-Length: 3\r\nConnection: close\r\n\r\nabc",
        studio.port
    );
    assert_eq!(studio.raw(post.as_bytes()), 405);
    assert_eq!(studio.get(&format!("/../../etc/passwd?token={t}"), ""), 404);
    assert_eq!(studio.get(&format!("/texture.png?token={t}"), ""), 404);
    // Sockets: without the token, or from another origin, the handshake is refused.
    let bare = format!("ws://127.0.0.1:{}/ws", studio.port);
    assert!(tungstenite::connect(bare).is_err());
    let mut request = format!("ws://127.0.0.1:{}/ws?token={t}", studio.port)
        .into_client_request()
        .expect("request");
    request
        .headers_mut()
        .insert("Origin", "http://evil.example".parse().expect("header"));
    assert!(tungstenite::connect(request).is_err());
    assert!(studio.page_is_served(), "still serving after all that");
}

#[test]
fn bad_messages_are_refused_and_the_server_keeps_serving() {
    let dir = scratch("messages");
    let studio = Studio::start(&dir, None);
    let mut ws = studio.socket();
    let (states, _) = ask(&mut ws, "{ not json", 0);
    assert_eq!(states[0]["type"], "error", "{states:?}");
    let (states, _) = ask(&mut ws, r#"{"op":"no_such_thing"}"#, 0);
    assert_eq!(states[0]["type"], "error");
    let (states, _) = ask(&mut ws, r#"{"op":"drag","seq":1,"targets":[[0,0]]}"#, 0);
    assert!(
        states[0]["message"]
            .as_str()
            .is_some_and(|m| m.contains("pin some vertices")),
        "{states:?}"
    );
    let (states, _) = ask(&mut ws, r#"{"op":"pins","pins":[999999]}"#, 0);
    assert!(states[0]["message"]
        .as_str()
        .is_some_and(|m| m.starts_with("error")));
    ws.send(Message::Binary(vec![1, 2, 3].into()))
        .expect("sends");
    match ws.read().expect("answer") {
        Message::Text(t) => assert!(t.as_str().contains("binary requests are not accepted")),
        other => panic!("{other:?}"),
    }
    // An oversized message closes that socket; the server goes on.
    let big = format!(r#"{{"op":"pins","pins":[{}0]}}"#, "0,".repeat(4_500_000));
    let _ = ws.send(Message::Text(big.into()));
    let closed = (0..5).any(|_| ws.read().is_err());
    assert!(closed, "the oversized message's socket is closed");
    assert!(studio.page_is_served());
    // A new socket (a reload, or a second tab) works, alongside another.
    let mut a = studio.socket();
    let mut b = studio.socket();
    let (state, mesh, _) = hello(&mut a);
    assert_eq!(state["type"], "state");
    assert!(mesh.len() > 16);
    let (state, _, _) = hello(&mut b);
    assert_eq!(state["keyframes"].as_array().map(Vec::len), Some(1));
}

#[test]
fn writes_go_only_into_the_workspace_by_plain_names() {
    let dir = scratch("paths");
    let studio = Studio::start(&dir, None);
    let mut ws = studio.socket();
    hello(&mut ws);
    ask(&mut ws, r#"{"op":"add_keyframe","time":1}"#, 1);
    let outside = dir.parent().expect("parent").join("bdmorph-escaped.json");
    for name in [
        "../bdmorph-escaped.json",
        "/tmp/bdmorph-escaped.json",
        "sub/dir.json",
        ".hidden.json",
        "notes.txt",
        "",
    ] {
        let request = serde_json::json!({"op": "save", "name": name}).to_string();
        let (states, _) = ask(&mut ws, &request, 0);
        let said = states[0]["message"].as_str().unwrap_or_default();
        assert!(said.starts_with("error"), "{name:?}: {said}");
    }
    let (states, _) = ask(
        &mut ws,
        r#"{"op":"export","format":"gif","name":"../escaped.gif"}"#,
        0,
    );
    assert!(states[0]["message"]
        .as_str()
        .unwrap_or_default()
        .starts_with("error"));
    assert!(!outside.exists());
    assert_eq!(
        std::fs::read_dir(&dir).expect("dir").count(),
        0,
        "nothing written"
    );
    // A plain name is written, atomically, and read back whole.
    let (states, _) = ask(&mut ws, r#"{"op":"save","name":"walk.json"}"#, 0);
    assert!(
        states[0]["message"]
            .as_str()
            .unwrap_or_default()
            .starts_with("saved"),
        "{states:?}"
    );
    let project = bdmorph::studio::Project::read(&dir.join("walk.json")).expect("a valid project");
    assert_eq!(project.keyframes.len(), 2);
    assert!(studio.page_is_served());
}

#[test]
fn the_engine_poses_plays_saves_and_reopens_the_same_frames() {
    let dir = scratch("engine");
    let studio = Studio::start(&dir, None);
    let mut ws = studio.socket();
    let (state, mesh, _) = hello(&mut ws);
    let n = u32::from_le_bytes(mesh[4..8].try_into().expect("n")) as usize;
    assert_eq!(state["vertices"].as_u64(), Some(n as u64));
    let (_, rest) = ask(&mut ws, r#"{"op":"select","keyframe":0}"#, 1);
    let rest = positions(&rest);
    // Add a keyframe, pin two vertices of it and drag one.
    ask(&mut ws, r#"{"op":"add_keyframe","time":2}"#, 1);
    let far = (0..n)
        .max_by(|&a, &b| {
            let d = |i: usize| (rest[i][0] - rest[0][0]).hypot(rest[i][1] - rest[0][1]);
            d(a).total_cmp(&d(b))
        })
        .expect("vertices");
    ask(&mut ws, &format!(r#"{{"op":"pins","pins":[0,{far}]}}"#), 0);
    let mut last = Vec::new();
    for step in 1..=10 {
        let target = [
            rest[far][0] + 0.05 * step as f32,
            rest[far][1] + 0.08 * step as f32,
        ];
        let request = serde_json::json!({
            "op": "drag", "seq": step, "targets": [rest[0], target]
        });
        let (_, frame) = ask(&mut ws, &request.to_string(), 1);
        assert_eq!(
            u32::from_le_bytes(frame[4..8].try_into().expect("seq")),
            step
        );
        last = positions(&frame);
    }
    ask(&mut ws, r#"{"op":"drag_end"}"#, 0);
    assert!(
        (last[far][0] - (rest[far][0] + 0.5)).abs() < 0.02,
        "{:?}",
        last[far]
    );
    ask(
        &mut ws,
        r#"{"op":"set_easing","keyframe":0,"easing":"ease-in-out"}"#,
        0,
    );
    // Undo and redo the drag.
    let (_, undone) = ask(&mut ws, r#"{"op":"undo"}"#, 1);
    assert_eq!(positions(&undone)[far], rest[far]);
    let (_, redone) = ask(&mut ws, r#"{"op":"redo"}"#, 1);
    assert_eq!(positions(&redone)[far], last[far]);
    // Scrub: the frame at 1 s, and the ends are the keyframes.
    let (_, middle) = ask(&mut ws, r#"{"op":"scrub","seq":7,"time":1.0}"#, 3);
    let (_, end) = ask(&mut ws, r#"{"op":"scrub","seq":8,"time":2.0}"#, 3);
    let end = positions(&end);
    assert!((end[far][0] - last[far][0]).abs() < 1e-4);
    // Save, export, then open the saved project in a new studio: the same frame at 1 s.
    let (states, _) = ask(&mut ws, r#"{"op":"save","name":"anim.json"}"#, 0);
    assert!(states[0]["message"]
        .as_str()
        .unwrap_or_default()
        .starts_with("saved"));
    for (format, name) in [("gif", "a.gif"), ("png", "a.png"), ("html", "a.html")] {
        let request =
            serde_json::json!({"op": "export", "format": format, "name": name, "frames": 6});
        let (states, _) = ask(&mut ws, &request.to_string(), 0);
        let said = states[0]["message"].as_str().unwrap_or_default();
        assert!(said.starts_with("exported"), "{format}: {said}");
    }
    let gif = std::fs::read(dir.join("a.gif")).expect("gif");
    let mut decoder = gif::DecodeOptions::new();
    decoder.set_color_output(gif::ColorOutput::RGBA);
    let mut reader = decoder.read_info(gif.as_slice()).expect("a GIF");
    let mut frames = 0;
    while reader.read_next_frame().expect("frame").is_some() {
        frames += 1;
    }
    assert_eq!(frames, 6);
    let html = std::fs::read_to_string(dir.join("a.html")).expect("html");
    assert!(html.contains("<canvas") || html.contains("<svg"));
    // Screenshots: the keyframe being posed, and the frame at 1 s; drawn, and different.
    let mut stills = Vec::new();
    for (name, time) in [("posed.png", None), ("at1.png", Some(1.0))] {
        let request =
            serde_json::json!({"op": "export", "format": "still", "name": name, "time": time});
        let (states, _) = ask(&mut ws, &request.to_string(), 0);
        let said = states[0]["message"].as_str().unwrap_or_default();
        assert!(said.starts_with("exported"), "{name}: {said}");
        let png = std::fs::read(dir.join(name)).expect("still");
        let image = bdmorph::render::raster::decode_image(&png).expect("a PNG");
        assert_eq!((image.width, image.height), (800, 800));
        let drawn = image
            .rgba
            .chunks(4)
            .filter(|p| p[3] > 0 && p[..3].iter().any(|&c| c < 200))
            .count();
        assert!(drawn > 800 * 800 / 20, "{name}: {drawn} pixels drawn");
        stills.push(image.rgba);
    }
    assert_ne!(
        stills[0], stills[1],
        "the posed keyframe is not the middle frame"
    );
    drop(ws);
    drop(studio);
    let again = Studio::start(&dir, Some("anim.json"));
    let mut ws = again.socket();
    let (state, _, _) = hello(&mut ws);
    assert_eq!(state["keyframes"].as_array().map(Vec::len), Some(2));
    assert_eq!(state["keyframes"][0]["easing"], "ease-in-out");
    let (_, reopened) = ask(&mut ws, r#"{"op":"scrub","seq":1,"time":1.0}"#, 3);
    assert_eq!(positions(&reopened), positions(&middle), "the same frame");
}

#[test]
fn damaged_and_foreign_projects_are_refused_at_start() {
    let dir = scratch("damaged");
    let mesh = generate::disk(4, 0.1);
    let good = bdmorph::studio::Project::new(&mesh, None);
    let text = String::from_utf8(good.to_json()).expect("utf8");
    for (name, body, said) in [
        (
            "v2.json",
            text.replacen("\"version\": 1", "\"version\": 2", 1),
            "another version",
        ),
        (
            "other.json",
            "{\"format\": \"something\"}".to_owned(),
            "not a bdmorph studio project",
        ),
        (
            "cut.json",
            text[..text.len() / 2].to_owned(),
            "not a bdmorph studio project",
        ),
    ] {
        std::fs::write(dir.join(name), body).expect("write");
        let out = Command::new(env!("CARGO_BIN_EXE_bdmorph"))
            .args(["studio", name])
            .current_dir(&dir)
            .output()
            .expect("runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{name}");
        assert!(out.stdout.is_empty(), "{name}: no URL");
        assert!(err.contains(said), "{name}: {err}");
    }
}

#[test]
fn ctrl_c_stops_the_studio_cleanly() {
    let dir = scratch("ctrl-c");
    let mut studio = Studio::start(&dir, None);
    assert!(studio.page_is_served());
    let pid = studio.child.id().to_string();
    let sent = Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .expect("kill runs");
    assert!(sent.success());
    let deadline = std::time::Instant::now() + Duration::from_secs(20);
    let status = loop {
        if let Some(status) = studio.child.try_wait().expect("waits") {
            break status;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "still running after Ctrl-C"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(status.success(), "{status:?}");
    let mut ws_dir = std::fs::read_dir(&dir).expect("dir");
    assert!(ws_dir.next().is_none(), "nothing written");
    // The frame rate is the project's, within bounds.
    let studio = Studio::start(&dir, None);
    let mut ws = studio.socket();
    hello(&mut ws);
    let (states, _) = ask(&mut ws, r#"{"op":"fps","fps":12}"#, 0);
    assert_eq!(states[0]["fps"], 12.0);
    let (states, _) = ask(&mut ws, r#"{"op":"fps","fps":0}"#, 0);
    assert!(states[0]["message"]
        .as_str()
        .unwrap_or_default()
        .starts_with("error"));
}

#[test]
fn a_keyframe_loads_from_a_mesh_file_with_the_same_triangles() {
    let dir = scratch("load-keyframe");
    let rest = generate::disk(6, 0.1);
    bdmorph::io::write_obj_2d(&dir.join("rest.obj"), &rest.positions, &rest.faces, &[])
        .expect("write");
    let studio = Studio::start(&dir, Some("rest.obj"));
    let mut ws = studio.socket();
    let (state, _, _) = hello(&mut ws);
    let anchors = state["anchors"].as_array().expect("anchors");
    assert_eq!(anchors.len(), 1, "one piece, one anchor edge");
    // The bent pose with its triangles listed in another order, corners rotated.
    let bent = generate::bend(&rest, 0.5);
    let mut text = String::new();
    for p in &bent.positions {
        text += &format!("v {} {} 0\n", p[0], p[1]);
    }
    for f in bent.faces.iter().rev() {
        text += &format!("f {} {} {}\n", f[1] + 1, f[2] + 1, f[0] + 1);
    }
    let request =
        serde_json::json!({"op": "load_keyframe", "name": "bent.obj", "text": text, "time": 1.0});
    let (states, pose) = ask(&mut ws, &request.to_string(), 1);
    assert!(
        states[0]["message"]
            .as_str()
            .unwrap_or_default()
            .starts_with("loaded"),
        "{states:?}"
    );
    assert_eq!(states[0]["keyframes"].as_array().map(Vec::len), Some(2));
    let got = positions(&pose);
    assert!((got[10][0] - bent.positions[10][0] as f32).abs() < 1e-6);
    // Another mesh's file, a reversed triangle, or an unknown format is refused.
    let small = generate::disk(3, 0.1);
    let mut other = String::new();
    for p in &small.positions {
        other += &format!("v {} {} 0\n", p[0], p[1]);
    }
    for f in &small.faces {
        other += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    let mut reversed = text.clone();
    let last = bent.faces[0];
    reversed = reversed.replace(
        &format!("f {} {} {}\n", last[1] + 1, last[2] + 1, last[0] + 1),
        &format!("f {} {} {}\n", last[0] + 1, last[2] + 1, last[1] + 1),
    );
    for (name, body) in [
        ("small.obj", other),
        ("flip.obj", reversed),
        ("x.stl", text),
    ] {
        let request =
            serde_json::json!({"op": "load_keyframe", "name": name, "text": body, "time": 2.0});
        let (states, _) = ask(&mut ws, &request.to_string(), 0);
        let said = states[0]["message"].as_str().unwrap_or_default();
        assert!(
            said.starts_with("error") && said.contains(name),
            "{name}: {said}"
        );
        assert_eq!(states[0]["keyframes"].as_array().map(Vec::len), Some(2));
    }
}

/// A picture of a disk with a square hole, on transparency (`size` pixels square).
fn write_ring_picture(path: &Path, size: u32) {
    let s = f64::from(size);
    let image = generate::picture(size, size, |x, y| {
        let (dx, dy) = (x - 0.5 * s, y - 0.5 * s);
        let disk = dx.hypot(dy) - 0.4 * s;
        let hole = 0.1 * s - dx.abs().max(dy.abs());
        disk.max(hole)
    });
    std::fs::write(
        path,
        bdmorph::render::raster::encode_png(&image).expect("png"),
    )
    .expect("write");
}

#[test]
fn the_outline_is_traced_drawn_imported_and_meshed_over_the_picture() {
    let dir = scratch("outline");
    write_ring_picture(&dir.join("ring.png"), 200);
    let studio = Studio::start(&dir, Some("ring.png"));
    let mut ws = studio.socket();
    let (state, _, _) = hello(&mut ws);
    assert_eq!(state["picture"], serde_json::json!([200, 200]));
    // Traced: the disk's outline and the hole's, in the picture's pixels.
    let (answers, _) = ask(&mut ws, r#"{"op":"trace_outline"}"#, 0);
    let answer = &answers[0];
    assert_eq!(answer["type"], "outline", "{answer}");
    let loops = answer["loops"].as_array().expect("loops");
    assert_eq!(loops.len(), 2, "the disk and its hole");
    let mut extents = Vec::new();
    for l in loops {
        let points: Vec<[f64; 2]> = serde_json::from_value(l.clone()).expect("points");
        assert!(points.len() >= 4, "{} points", points.len());
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in &points {
            let r = (p[0] - 100.0).hypot(p[1] - 100.0);
            lo = lo.min(r);
            hi = hi.max(r);
        }
        extents.push((lo, hi));
    }
    extents.sort_by(|a, b| a.1.total_cmp(&b.1));
    // The hole: a 40-pixel square (corners at 28 pixels from the centre).
    assert!(extents[0].0 > 17.0 && extents[0].1 < 31.0, "{extents:?}");
    // The disk: radius 80.
    assert!(extents[1].0 > 77.0 && extents[1].1 < 82.0, "{extents:?}");

    // Meshed as traced, at two densities: a new project (one keyframe), textured.
    for vertices in [300, 1500] {
        let request =
            serde_json::json!({"op": "mesh_outline", "loops": loops, "vertices": vertices});
        let (states, mesh) = ask(&mut ws, &request.to_string(), 2);
        let n = u32::from_le_bytes(mesh[4..8].try_into().expect("n")) as usize;
        assert!(
            n as f64 > 0.7 * vertices as f64 && (n as f64) < 1.4 * vertices as f64,
            "{n} vertices for {vertices}"
        );
        let s = &states[0];
        assert_eq!(s["vertices"].as_u64(), Some(n as u64));
        assert_eq!(s["keyframes"].as_array().map(Vec::len), Some(1));
        assert_eq!(s["textured"], true, "the picture stays on the new mesh");
        let (_, pose) = ask_more(&mut ws, 1);
        let p = positions(&pose);
        // No vertex in the hole, none outside the disk.
        for q in &p {
            let (dx, dy) = (f64::from(q[0]) - 100.0, f64::from(q[1]) - 100.0);
            assert!(dx.hypot(dy) < 81.0, "{q:?} outside");
            assert!(dx.abs().max(dy.abs()) > 19.0, "{q:?} in the hole");
        }
    }
    // The new mesh poses.
    ask(&mut ws, r#"{"op":"pins","pins":[0,5]}"#, 0);
    let (_, pose) = ask(&mut ws, r#"{"op":"select","keyframe":0}"#, 1);
    let p = positions(&pose);
    let request = serde_json::json!({
        "op": "drag", "seq": 1, "targets": [p[0], [p[5][0] + 4.0, p[5][1] + 3.0]]
    });
    let (_, moved) = ask(&mut ws, &request.to_string(), 1);
    let moved = positions(&moved);
    assert!((moved[5][0] - p[5][0] - 4.0).abs() < 0.5, "{:?}", moved[5]);

    // A hand-drawn triangle with a triangular hole, and an SVG file.
    let drawn = serde_json::json!({"op": "mesh_outline", "vertices": 400, "loops": [
        [[10, 10], [190, 10], [100, 180]], [[80, 50], [120, 50], [100, 90]]]});
    let (_, mesh) = ask(&mut ws, &drawn.to_string(), 2);
    let n = u32::from_le_bytes(mesh[4..8].try_into().expect("n")) as usize;
    assert!(n > 250, "{n}");
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 200 200">
        <rect x="20" y="20" width="160" height="120"/></svg>"#;
    let import = serde_json::json!({"op": "import_outline", "name": "box.svg", "text": svg, "vertices": 600});
    let (states, mesh) = ask(&mut ws, &import.to_string(), 2);
    let n = u32::from_le_bytes(mesh[4..8].try_into().expect("n")) as usize;
    assert!(n > 400, "{n}");
    assert!(
        states[0]["message"]
            .as_str()
            .unwrap_or_default()
            .contains("box.svg"),
        "{states:?}"
    );

    // Refused, each with its reason, and the project as it was.
    for (request, reason) in [
        (
            serde_json::json!({"op": "mesh_outline", "vertices": 400, "loops": [[[0, 0], [1, 1]]]}),
            "three points",
        ),
        (
            serde_json::json!({"op": "mesh_outline", "vertices": 400, "loops": [
                [[0, 0], [100, 100], [100, 0], [0, 100]]]}),
            "cross",
        ),
        (
            serde_json::json!({"op": "mesh_outline", "vertices": 10_000_000, "loops": loops}),
            "between",
        ),
        (
            serde_json::json!({"op": "import_outline", "name": "x.dxf", "text": "0", "vertices": 400}),
            "x.dxf",
        ),
        (
            serde_json::json!({"op": "import_outline", "name": "bad.svg", "text": "<svg", "vertices": 400}),
            "bad.svg",
        ),
    ] {
        let (states, _) = ask(&mut ws, &request.to_string(), 0);
        let said = states[0]["message"].as_str().unwrap_or_default();
        assert!(said.starts_with("error") && said.contains(reason), "{said}");
        assert_eq!(states[0]["vertices"].as_u64(), Some(n as u64), "unchanged");
    }
    assert!(studio.page_is_served());

    // Without a picture there is nothing to trace.
    let plain = Studio::start(&dir, None);
    let mut ws = plain.socket();
    let (state, _, _) = hello(&mut ws);
    assert!(state["picture"].is_null());
    let (states, _) = ask(&mut ws, r#"{"op":"trace_outline"}"#, 0);
    let said = states[0]["message"].as_str().unwrap_or_default();
    assert!(said.contains("no picture"), "{said}");
}

#[test]
fn keyframes_reorder_and_move_in_time() {
    let dir = scratch("reorder");
    let rest = generate::disk(5, 0.1);
    bdmorph::io::write_obj_2d(&dir.join("rest.obj"), &rest.positions, &rest.faces, &[])
        .expect("write");
    let studio = Studio::start(&dir, Some("rest.obj"));
    let mut ws = studio.socket();
    hello(&mut ws);
    let obj = |m: &bdmorph::mesh::PlanarMesh| {
        let mut text = String::new();
        for p in &m.positions {
            text += &format!("v {} {} 0\n", p[0], p[1]);
        }
        for f in &m.faces {
            text += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
        }
        text
    };
    let (half, full) = (generate::bend(&rest, 0.5), generate::bend(&rest, 1.0));
    for (mesh, time) in [(&half, 1.0), (&full, 2.0)] {
        let request = serde_json::json!({"op": "load_keyframe", "name": "k.obj", "text": obj(mesh), "time": time});
        ask(&mut ws, &request.to_string(), 1);
    }
    let pose_of = |ws: &mut WebSocket<_>, k: usize| {
        let (states, pose) = ask(ws, &format!(r#"{{"op":"select","keyframe":{k}}}"#), 1);
        (states, positions(&pose))
    };
    let is = |got: &[[f32; 2]], want: &bdmorph::mesh::PlanarMesh| {
        got.iter().zip(&want.positions).all(|(g, w)| {
            (f64::from(g[0]) - w[0]).abs() < 1e-6 && (f64::from(g[1]) - w[1]).abs() < 1e-6
        })
    };
    // The last pose moves to the middle: poses rest, full, half; times stay 0, 1, 2.
    let (states, _) = ask(&mut ws, r#"{"op":"move_keyframe","keyframe":2,"to":1}"#, 1);
    assert_eq!(states[0]["current"], 1);
    let times: Vec<f64> = states[0]["keyframes"]
        .as_array()
        .expect("keyframes")
        .iter()
        .map(|k| k["time"].as_f64().expect("time"))
        .collect();
    assert_eq!(times, [0.0, 1.0, 2.0]);
    assert!(is(&pose_of(&mut ws, 1).1, &full));
    assert!(is(&pose_of(&mut ws, 2).1, &half));
    // The first pose to the end: full, half, rest.
    ask(&mut ws, r#"{"op":"move_keyframe","keyframe":0,"to":2}"#, 1);
    assert!(is(&pose_of(&mut ws, 0).1, &full));
    assert!(is(&pose_of(&mut ws, 2).1, &rest));
    // The middle keyframe moves in time between its neighbours, and not past them.
    let (states, _) = ask(&mut ws, r#"{"op":"set_time","keyframe":1,"time":1.5}"#, 0);
    assert_eq!(states[0]["keyframes"][1]["time"], 1.5);
    for bad in [
        r#"{"op":"set_time","keyframe":1,"time":2.5}"#,
        r#"{"op":"set_time","keyframe":0,"time":0.5}"#,
        r#"{"op":"move_keyframe","keyframe":5,"to":0}"#,
        r#"{"op":"move_keyframe","keyframe":0,"to":3}"#,
    ] {
        let (states, _) = ask(&mut ws, bad, 0);
        let said = states[0]["message"].as_str().unwrap_or_default();
        assert!(said.starts_with("error"), "{bad}: {said}");
        assert_eq!(states[0]["keyframes"][1]["time"], 1.5);
    }
    // The animation plays the new order: halfway between keyframes 0 (full) and 1 (half).
    let (_, frame) = ask(&mut ws, r#"{"op":"scrub","seq":1,"time":0.0}"#, 3);
    assert!(is(&positions(&frame), &full));
    let (_, frame) = ask(&mut ws, r#"{"op":"scrub","seq":2,"time":1.5}"#, 3);
    assert!(is(&positions(&frame), &half));
    // Clone the keyframe being posed (half), and add a copy of the first (full).
    pose_of(&mut ws, 1);
    let (_, pose) = ask(&mut ws, r#"{"op":"add_keyframe","time":3}"#, 1);
    assert!(is(&positions(&pose), &half));
    let (states, pose) = ask(&mut ws, r#"{"op":"add_keyframe","time":4,"copy":0}"#, 1);
    assert!(is(&positions(&pose), &full));
    assert_eq!(states[0]["current"], 4);
    let (states, _) = ask(&mut ws, r#"{"op":"add_keyframe","time":5,"copy":9}"#, 0);
    let said = states[0]["message"].as_str().unwrap_or_default();
    assert!(said.contains("no keyframe 9"), "{said}");
}
