//! `bdmorph studio` as a server: the URL line, the checks on every request and socket (token,
//! Host, Origin, sizes, malformed input, paths outside the workspace), each refused with the
//! server still serving; the engine over the socket (pins, drags, keyframes, scrubs, save,
//! export in the background); every page told every edit; requests sent with a Close carried
//! out; a restart reusing its port and token; work of a killed studio recovered; uploads;
//! projects refused cleanly when damaged or from another version.

mod studio_common;

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use bdmorph::generate;
use studio_common::{positions, scratch, Client, Studio};
use tungstenite::Message;

#[test]
fn every_request_needs_the_token_our_host_and_our_origin() {
    let dir = scratch("guard");
    let studio = Studio::start(&dir, None);
    let t = &studio.token;
    assert_eq!(studio.get(&format!("/?token={t}"), ""), 200);
    assert_eq!(studio.get(&format!("/s/{t}/main.js"), ""), 200);
    assert_eq!(studio.get(&format!("/s/{t}/studio.css"), ""), 200);
    assert_eq!(studio.get(&format!("/s/{t}/nothing.js"), ""), 404);
    // No token, a wrong one, one of the wrong length.
    assert_eq!(studio.get("/", ""), 403);
    assert_eq!(studio.get("/s/main.js", ""), 403);
    assert_eq!(
        studio.get("/s/0123456789abcdef0123456789abcdef/main.js", ""),
        403
    );
    assert_eq!(studio.get("/texture", ""), 403);
    assert_eq!(
        studio.get("/?token=0123456789abcdef0123456789abcdef", ""),
        403
    );
    assert_eq!(studio.get(&format!("/?token={t}x"), ""), 403);
    // The browser's own favicon request is answered (no content) without the token.
    assert_eq!(studio.get("/favicon.ico", ""), 204);
    // A foreign Host (DNS rebinding) and a foreign Origin (another site's page).
    let foreign_host = format!(
        "GET /?token={t} HTTP/1.1\r\nHost: evil.example:{}\r\nConnection: close\r\n\r\n",
        studio.port
    );
    assert_eq!(studio.raw(foreign_host.as_bytes()), 403);
    let foreign_icon = format!(
        "GET /favicon.ico HTTP/1.1\r\nHost: evil.example:{}\r\nConnection: close\r\n\r\n",
        studio.port
    );
    assert_eq!(studio.raw(foreign_icon.as_bytes()), 403);
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
    let _ = studio.raw(b"\x00\x01garbage\r\n\r\n");
    let long = format!("/?token={t}&{}", "a".repeat(100_000));
    assert_ne!(studio.get(&long, ""), 200);
    let post = format!(
        "POST /?token={t} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nContent-Length: 0\r\nConnection: close\r\n\r\n",
        studio.port
    );
    assert_eq!(studio.raw(post.as_bytes()), 405);
    assert_eq!(studio.get(&format!("/etc/passwd?token={t}"), ""), 404);
    // The socket: without the token, or from another origin, it does not open.
    let url = format!("ws://127.0.0.1:{}/ws", studio.port);
    assert!(tungstenite::connect(&url).is_err());
    let mut request =
        tungstenite::client::IntoClientRequest::into_client_request(format!("{url}?token={t}"))
            .expect("request");
    request
        .headers_mut()
        .insert("Origin", "http://evil.example".parse().expect("header"));
    assert!(tungstenite::connect(request).is_err());
    assert!(studio.page_is_served(), "still serving");
}

#[test]
fn bad_messages_are_refused_and_the_server_keeps_serving() {
    let dir = scratch("messages");
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    let said = c.request("{ not json").expect("refused");
    assert!(said.starts_with("bad request"), "{said}");
    let said = c.request(r#"{"op":"no_such_thing"}"#).expect("refused");
    assert!(said.starts_with("bad request"), "{said}");
    let said = c
        .request(r#"{"op":"drag","seq":1,"pins":[],"targets":[[0,0]]}"#)
        .expect("refused");
    assert!(said.contains("pin a vertex first"), "{said}");
    let said = c
        .request(r#"{"op":"pin_add","vertex":999999}"#)
        .expect("refused");
    assert!(said.contains("no vertex there"), "{said}");
    c.ws.send(Message::Binary(vec![1, 2, 3].into()))
        .expect("sends");
    c.sync();
    assert!(
        c.errors
            .last()
            .is_some_and(|e| e.contains("only binary request is an upload")),
        "{:?}",
        c.errors
    );
    // An oversized message closes that socket; the server goes on.
    let big = format!(
        r#"{{"op":"outline_set","loops":[[{}[0,0]]]}}"#,
        "[0,0],".repeat(14_000_000)
    );
    let _ = c.ws.send(Message::Text(big.into()));
    let closed = (0..5).any(|_| !c.read_one());
    assert!(closed, "the oversized message's socket is closed");
    assert!(studio.page_is_served());
    // A new socket (a reload, or a second tab) works, alongside another.
    let a = studio.client();
    let b = studio.client();
    assert_eq!(a.state["type"], "state");
    assert!(a.mesh.len() > 16);
    assert_eq!(b.state["keyframes"].as_array().map(Vec::len), Some(1));
}

/// Files the studio wrote into a folder, besides its own `.bdmorph-studio`.
fn written(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .expect("dir")
        .filter_map(Result::ok)
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != ".bdmorph-studio")
        .collect()
}

#[test]
fn writes_go_only_into_the_workspace_by_plain_names() {
    let dir = scratch("paths");
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    assert_eq!(c.request(r#"{"op":"add_keyframe","time":1}"#), None);
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
        assert!(c.request(&request).is_some(), "{name:?} refused");
    }
    assert!(c
        .request(r#"{"op":"export","format":"gif","name":"../escaped.gif"}"#)
        .is_some());
    assert!(c.request(r#"{"op":"open","name":"../x.json"}"#).is_some());
    assert!(!outside.exists());
    assert!(
        written(&dir).is_empty(),
        "nothing written: {:?}",
        written(&dir)
    );
    // A plain name is written, atomically, and read back whole; an existing other file is
    // replaced only when asked.
    assert_eq!(c.request(r#"{"op":"save","name":"walk.json"}"#), None);
    assert!(
        c.notes().iter().any(|n| n.starts_with("saved")),
        "{:?}",
        c.notes()
    );
    assert_eq!(c.state["dirty"], false);
    let project = bdmorph::studio::Project::read(&dir.join("walk.json")).expect("a valid project");
    assert_eq!(project.keyframes.len(), 2);
    std::fs::write(dir.join("other.json"), "{}").expect("write");
    let said = c
        .request(r#"{"op":"save","name":"other.json"}"#)
        .expect("asks first");
    assert!(said.contains("exists"), "{said}");
    assert_eq!(std::fs::read(dir.join("other.json")).expect("read"), b"{}");
    assert_eq!(
        c.request(r#"{"op":"save","name":"other.json","overwrite":true}"#),
        None
    );
    assert!(studio.page_is_served());
}

/// Two tabs (two sockets) see each other's edits as they happen: pins, poses, keyframes,
/// the outline, the mode; a third, opened later (a reload), shows the same.
#[test]
fn every_page_sees_every_edit() {
    let dir = scratch("tabs");
    let studio = Studio::start(&dir, None);
    let mut a = studio.client();
    let mut b = studio.client();
    assert_eq!(a.request(r#"{"op":"add_keyframe","time":1}"#), None);
    b.sync();
    assert_eq!(b.state["keyframes"].as_array().map(Vec::len), Some(2));
    assert_eq!(b.state["current"], 1);
    let n = a.state["vertices"].as_u64().expect("n") as u32;
    for v in [0, n - 1] {
        assert_eq!(
            a.request(&format!(r#"{{"op":"pin_add","vertex":{v}}}"#)),
            None
        );
    }
    b.sync();
    assert_eq!(b.pins, [0, n - 1], "the other tab shows the pins");
    let p = a.positions();
    let target = [
        f64::from(p[(n - 1) as usize][0]) + 0.3,
        f64::from(p[(n - 1) as usize][1]) + 0.4,
    ];
    assert_eq!(
        a.drag(&[[f64::from(p[0][0]), f64::from(p[0][1])], target]),
        None
    );
    b.sync();
    assert_eq!(b.positions(), a.positions(), "and the pose");
    assert_eq!(b.state["undo"], "drag on keyframe 2");
    // B undoes A's drag: A sees it.
    assert_eq!(b.request(r#"{"op":"undo"}"#), None);
    a.sync();
    assert_eq!(a.positions(), p);
    // A's pins, from B's view, cannot be dragged with stale pins.
    assert_eq!(b.request(r#"{"op":"pin_remove","vertex":0}"#), None);
    let said = a.drag(&[target, target]).expect("stale pins are refused");
    assert!(said.contains("pins changed"), "{said}");
    // A reload (a new socket) shows the same state.
    let c = studio.client();
    assert_eq!(c.pins, [n - 1]);
    assert_eq!(c.state["current"], 1);
    assert_eq!(c.state["keyframes"], a.state["keyframes"]);
    // The mode and the outline are shared too.
    assert_eq!(a.request(r#"{"op":"mode","mode":"outline"}"#), None);
    assert_eq!(a.request(r#"{"op":"outline_new_loop"}"#), None);
    for p in [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]] {
        let request = serde_json::json!({"op": "outline_point", "point": p}).to_string();
        assert_eq!(a.request(&request), None);
    }
    b.sync();
    assert_eq!(b.state["mode"], "outline");
    assert_eq!(b.outline.as_array().map(Vec::len), Some(1));
    assert_eq!(b.outline[0].as_array().map(Vec::len), Some(3));
}

/// A page's answer never arrives before the edits other pages made earlier: after any edit by
/// one tab, the other tab's next answer comes after the change, whichever task runs first.
#[test]
fn answers_follow_the_edits_of_other_pages() {
    let dir = scratch("order");
    let studio = Studio::start(&dir, None);
    let mut a = studio.client();
    let mut b = studio.client();
    let n = a.state["vertices"].as_u64().expect("n") as u32;
    for round in 0..60 {
        let v = (round / 2) % n;
        let op = if round % 2 == 0 {
            "pin_add"
        } else {
            "pin_remove"
        };
        assert_eq!(a.request(&format!(r#"{{"op":"{op}","vertex":{v}}}"#)), None);
        b.sync();
        assert_eq!(b.pins, a.pins, "round {round}: the other tab is up to date");
    }
}

/// Requests that arrive together with the socket's Close are carried out (a Save sent as the
/// tab closes is not lost).
#[test]
fn requests_sent_with_the_close_are_carried_out() {
    let dir = scratch("close");
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    c.ws.send(Message::Text(r#"{"op":"add_keyframe","time":2}"#.into()))
        .expect("sends");
    c.ws.send(Message::Text(
        r#"{"op":"save","name":"closing.json"}"#.into(),
    ))
    .expect("sends");
    c.ws.close(None).expect("closes");
    let _ = c.ws.flush();
    let deadline = Instant::now() + Duration::from_secs(20);
    while !dir.join("closing.json").exists() {
        assert!(Instant::now() < deadline, "the save was lost");
        std::thread::sleep(Duration::from_millis(50));
    }
    let project =
        bdmorph::studio::Project::read(&dir.join("closing.json")).expect("a valid project");
    assert_eq!(project.keyframes.len(), 2);
}

#[test]
fn the_engine_poses_plays_saves_and_reopens_the_same_frames() {
    let dir = scratch("engine");
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    let n = u32::from_le_bytes(c.mesh[4..8].try_into().expect("n")) as usize;
    assert_eq!(c.state["vertices"].as_u64(), Some(n as u64));
    let rest = c.positions();
    // Add a keyframe, pin two vertices of it and drag one.
    assert_eq!(c.request(r#"{"op":"add_keyframe","time":2}"#), None);
    let far = (0..n)
        .max_by(|&a, &b| {
            let d = |i: usize| (rest[i][0] - rest[0][0]).hypot(rest[i][1] - rest[0][1]);
            d(a).total_cmp(&d(b))
        })
        .expect("vertices");
    for v in [0, far] {
        assert_eq!(
            c.request(&format!(r#"{{"op":"pin_add","vertex":{v}}}"#)),
            None
        );
    }
    let at = |p: [f32; 2]| [f64::from(p[0]), f64::from(p[1])];
    let mut last = Vec::new();
    for step in 1..=10 {
        let target = [
            at(rest[far])[0] + 0.05 * f64::from(step),
            at(rest[far])[1] + 0.08 * f64::from(step),
        ];
        assert_eq!(c.drag(&[at(rest[0]), target]), None);
        assert_eq!(
            u32::from_le_bytes(c.frame[4..8].try_into().expect("seq")),
            c.seq,
            "the answer carries the drag's number"
        );
        last = c.positions();
    }
    assert_eq!(c.request(r#"{"op":"drag_end"}"#), None);
    assert!(
        (last[far][0] - (rest[far][0] + 0.5)).abs() < 0.02,
        "{:?}",
        last[far]
    );
    assert_eq!(c.state["undo"], "drag on keyframe 2", "one step per stroke");
    assert_eq!(
        c.request(r#"{"op":"set_easing","keyframe":0,"easing":"ease-in-out"}"#),
        None
    );
    // Undo the easing and the drag, then redo both.
    assert_eq!(c.request(r#"{"op":"undo"}"#), None);
    assert_eq!(c.state["keyframes"][0]["easing"], "linear");
    assert_eq!(c.request(r#"{"op":"undo"}"#), None);
    assert_eq!(c.positions()[far], rest[far]);
    assert_eq!(c.request(r#"{"op":"redo"}"#), None);
    assert_eq!(c.positions()[far], last[far]);
    assert_eq!(c.request(r#"{"op":"redo"}"#), None);
    // Scrub: the frame at 1 s; at a keyframe's time, that keyframe.
    assert_eq!(c.request(r#"{"op":"scrub","seq":70,"time":1.0}"#), None);
    assert_eq!(
        u32::from_le_bytes(c.frame[..4].try_into().expect("kind")),
        3
    );
    let middle = c.positions();
    assert_eq!(c.request(r#"{"op":"scrub","seq":71,"time":2.0}"#), None);
    assert_eq!(c.state["shown"]["keyframe"], 1);
    assert!((c.positions()[far][0] - last[far][0]).abs() < 1e-6);
    // Save, export in the background, then open the saved project in a new studio: the
    // same frame at 1 s.
    assert_eq!(c.request(r#"{"op":"save","name":"anim.json"}"#), None);
    for (format, name) in [
        ("gif", "a.gif"),
        ("png", "a.png"),
        ("html", "a.html"),
        ("mp4", "a.mp4"),
        ("obj", "frames"),
    ] {
        let request =
            serde_json::json!({"op": "export", "format": format, "name": name, "frames": 6});
        assert_eq!(c.request(&request.to_string()), None, "{format}");
        c.wait_for(120, &format!("the {format} export"), |c| {
            c.state["job"].is_null() && c.notes().iter().any(|n| n.contains(name))
        });
        assert!(
            c.notes()
                .iter()
                .any(|n| n.starts_with("exported") && n.contains(name)),
            "{:?}",
            c.notes()
        );
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
    assert_eq!(
        &std::fs::read(dir.join("a.mp4")).expect("mp4")[4..8],
        b"ftyp"
    );
    assert_eq!(
        std::fs::read_dir(dir.join("frames"))
            .expect("frames")
            .count(),
        6
    );
    // Screenshots: the keyframe shown, and the frame at 1 s; drawn, and different.
    let mut stills = Vec::new();
    for (name, time) in [("posed.png", None), ("at1.png", Some(1.0))] {
        let request =
            serde_json::json!({"op": "export", "format": "still", "name": name, "time": time});
        assert_eq!(c.request(&request.to_string()), None, "{name}");
        let png = std::fs::read(dir.join(name)).expect("still");
        let image = bdmorph::render::raster::decode_image(&png).expect("a PNG");
        // The subject's own aspect, 800 pixels on the longer side.
        assert_eq!(image.width.max(image.height), 800, "{name}");
        assert!(image.width.min(image.height) >= 400, "{name}");
        let drawn = image
            .rgba
            .chunks(4)
            .filter(|p| p[3] > 0 && p[..3].iter().any(|&c| c < 200))
            .count();
        assert!(drawn > 800 * 400 / 20, "{name}: {drawn} pixels drawn");
        stills.push(image.rgba);
    }
    assert_ne!(stills[0], stills[1], "the keyframe is not the middle frame");
    drop(c);
    drop(studio);
    let again = Studio::start(&dir, Some("anim.json"));
    let mut c = again.client();
    assert_eq!(c.state["keyframes"].as_array().map(Vec::len), Some(2));
    assert_eq!(c.state["keyframes"][0]["easing"], "ease-in-out");
    assert_eq!(c.state["dirty"], false);
    assert_eq!(c.request(r#"{"op":"scrub","seq":1,"time":1.0}"#), None);
    assert_eq!(c.positions(), middle, "the same frame");
}

/// An export runs in the background: progress is reported, drags and scrubs are answered
/// meanwhile, and Cancel stops it with nothing written.
#[test]
fn exports_run_in_the_background_and_can_be_cancelled() {
    let dir = scratch("export-job");
    let mesh = generate::disk(generate::rings_for(3000), 0.1);
    let mut project = bdmorph::studio::Project::new(&mesh, None);
    project.keyframes.push(bdmorph::studio::project::Keyframe {
        time: 4.0,
        easing: "linear".into(),
        positions: generate::bend(&mesh, 0.8).positions,
        pins: Vec::new(),
        drawing: None,
    });
    project.fps = 60.0;
    project.write(&dir.join("long.json")).expect("write");
    let studio = Studio::start(&dir, Some("long.json"));
    let mut c = studio.client();
    assert_eq!(
        c.request(r#"{"op":"export","format":"gif","name":"long.gif"}"#),
        None
    );
    c.wait_for(60, "progress", |c| {
        c.state["job"]["done"].as_u64().unwrap_or(0) > 0
    });
    assert_eq!(c.state["job"]["total"], 2 * 241, "two passes of 241 frames");
    let said = c
        .request(r#"{"op":"export","format":"gif","name":"other.gif"}"#)
        .expect("one job at a time");
    assert!(said.contains("running"), "{said}");
    // Scrubs are answered while it runs.
    for (k, t) in [0.5, 1.5, 2.5].into_iter().enumerate() {
        let request = serde_json::json!({"op": "scrub", "seq": 10 + k, "time": t}).to_string();
        assert_eq!(c.request(&request), None);
        assert!(!c.state["job"].is_null(), "answered while the export runs");
    }
    assert_eq!(c.request(r#"{"op":"cancel"}"#), None);
    c.wait_for(60, "the cancelled job to end", |c| c.state["job"].is_null());
    assert!(
        c.notes().iter().any(|n| n.contains("cancelled")),
        "{:?}",
        c.notes()
    );
    assert!(!dir.join("long.gif").exists(), "nothing written");
    assert!(written(&dir).iter().all(|n| !n.contains("long.gif")));
}

#[test]
fn damaged_and_foreign_projects_are_refused_at_start() {
    let dir = scratch("damaged");
    let mesh = generate::disk(4, 0.1);
    let good = bdmorph::studio::Project::new(&mesh, None);
    let text = String::from_utf8(good.to_json()).expect("utf8");
    for (name, body, said) in [
        (
            "v5.json",
            text.replacen("\"version\": 4", "\"version\": 5", 1),
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
        (
            "nan.json",
            text.replacen("\"fps\": 25.0", "\"fps\": null", 1),
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

fn stop(studio: &mut Studio, signal: &str) -> std::process::ExitStatus {
    let pid = studio.child.id().to_string();
    let sent = Command::new("kill")
        .args([signal, &pid])
        .status()
        .expect("kill runs");
    assert!(sent.success());
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        if let Some(status) = studio.child.try_wait().expect("waits") {
            return status;
        }
        assert!(Instant::now() < deadline, "still running after {signal}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Ctrl-C: the studio stops cleanly, keeping unsaved changes for the next start; with nothing
/// unsaved it leaves nothing behind.
#[test]
fn ctrl_c_stops_the_studio_cleanly_keeping_unsaved_work() {
    let dir = scratch("ctrl-c");
    let mut studio = Studio::start(&dir, None);
    assert!(studio.page_is_served());
    assert!(stop(&mut studio, "-INT").success());
    assert!(written(&dir).is_empty(), "nothing written");
    // Unsaved changes at Ctrl-C are kept and offered by the next start.
    let mut studio = Studio::start(&dir, None);
    let mut c = studio.client();
    assert_eq!(c.request(r#"{"op":"fps","fps":12}"#), None);
    assert_eq!(c.state["fps"], 12.0);
    assert!(c.request(r#"{"op":"fps","fps":0}"#).is_some());
    assert!(stop(&mut studio, "-INT").success());
    let again = Studio::start(&dir, None);
    let c = again.client();
    let offered = c.state["recovered"].as_array().expect("recovered");
    assert_eq!(offered.len(), 1, "{offered:?}");
}

/// A studio killed (SIGKILL) mid-session: the next start in the same folder listens on the
/// same port with the same token (an open page reconnects by itself), offers the work, and
/// restoring it brings back every edit older than the autosave interval.
#[test]
fn a_killed_studio_s_work_is_recovered_by_the_next_start() {
    let dir = scratch("killed");
    let rest = generate::disk(6, 0.1);
    bdmorph::io::write_obj_2d(dir.join("rest.obj"), &rest.positions, &rest.faces, &[])
        .expect("write");
    let mut studio = Studio::start(&dir, Some("rest.obj"));
    let (port, token) = (studio.port, studio.token.clone());
    let mut c = studio.client();
    for request in [
        r#"{"op":"add_keyframe","time":1}"#,
        r#"{"op":"pin_add","vertex":0}"#,
        r#"{"op":"pin_add","vertex":30}"#,
        r#"{"op":"set_easing","keyframe":0,"easing":"ease-in-out"}"#,
        r#"{"op":"add_keyframe","time":2.5,"copy":0}"#,
    ] {
        assert_eq!(c.request(request), None, "{request}");
    }
    assert_eq!(c.request(r#"{"op":"select","keyframe":1}"#), None);
    let p = c.positions();
    let at = |q: [f32; 2]| [f64::from(q[0]), f64::from(q[1])];
    assert_eq!(
        c.drag(&[at(p[0]), [at(p[30])[0] + 0.4, at(p[30])[1]]]),
        None
    );
    let dragged = c.positions();
    assert!(dragged[30][0] - p[30][0] > 0.2, "the pose moved");
    let edited = without_revisions(&c.state["keyframes"]);
    // Older than the autosave interval.
    std::thread::sleep(Duration::from_secs(
        bdmorph::studio::workspace::AUTOSAVE_SECONDS + 2,
    ));
    let _ = stop(&mut studio, "-KILL");
    let again = Studio::start(&dir, Some("rest.obj"));
    assert_eq!(
        (again.port, &again.token),
        (port, &token),
        "same port and token"
    );
    let mut c = again.client();
    assert_eq!(
        c.state["keyframes"].as_array().map(Vec::len),
        Some(1),
        "the file as it was"
    );
    let offered = c.state["recovered"][0]["name"]
        .as_str()
        .expect("recovered work is offered")
        .to_owned();
    assert_eq!(c.state["recovered"][0]["keyframes"], 3);
    assert_eq!(
        c.request(&serde_json::json!({"op": "recover", "name": offered}).to_string()),
        None
    );
    assert_eq!(
        without_revisions(&c.state["keyframes"]),
        edited,
        "every edit is back"
    );
    assert_eq!(c.request(r#"{"op":"select","keyframe":1}"#), None);
    assert_eq!(c.positions(), dragged, "the drag is back");
    assert_eq!(c.state["recovered"].as_array().map(Vec::len), Some(0));
    assert_eq!(c.request(r#"{"op":"undo"}"#), None);
    assert_eq!(
        c.state["keyframes"].as_array().map(Vec::len),
        Some(1),
        "undo: as opened"
    );
}

/// A file uploaded by the page is stored in the workspace under a plain name and opened; a
/// picture can instead be drawn on the mesh; an OBJ opens with the picture of its name.
#[test]
fn uploads_are_stored_and_opened_and_pictures_attach() {
    let dir = scratch("upload");
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    let picture = generate::picture(120, 100, |x, y| (x - 60.0).hypot(y - 50.0) - 40.0);
    let png = bdmorph::render::raster::encode_png(&picture).expect("png");
    let upload = |name: &str, then: &str, bytes: &[u8]| {
        let header = serde_json::json!({"name": name, "then": then}).to_string();
        let mut message = Vec::new();
        message.extend_from_slice(&10u32.to_le_bytes());
        message.extend_from_slice(&(header.len() as u32).to_le_bytes());
        message.extend_from_slice(header.as_bytes());
        message.extend_from_slice(bytes);
        message
    };
    c.ws.send(Message::Binary(
        upload("../My Pic!.png", "open", &png).into(),
    ))
    .expect("sends");
    c.wait_for(60, "the picture opened", |c| {
        c.state["source"] == "My Pic_.png"
    });
    assert!(dir.join("My Pic_.png").is_file());
    assert_eq!(c.state["textured"], true);
    assert_eq!(c.state["picture"], serde_json::json!([120, 100]));
    assert_eq!(c.state["undo"], "open My Pic_.png");
    // A mesh without texture coordinates, and a picture attached to it.
    let rest = generate::grid(5, 5, 0.0);
    bdmorph::io::write_obj_2d(dir.join("grid.obj"), &rest.positions, &rest.faces, &[])
        .expect("write");
    assert_eq!(c.request(r#"{"op":"open","name":"grid.obj"}"#), None);
    c.wait_for(60, "the mesh opened", |c| c.state["source"] == "grid.obj");
    assert_eq!(c.state["textured"], false);
    c.ws.send(Message::Binary(upload("skin.png", "attach", &png).into()))
        .expect("sends");
    c.wait_for(60, "the picture attached", |c| c.state["textured"] == true);
    assert_eq!(c.state["texture_name"], "skin.png");
    assert_eq!(c.request(r#"{"op":"undo"}"#), None);
    assert_eq!(c.state["textured"], false, "attaching is undone");
    // Refused uploads: another kind of file, a header that lies about its length.
    c.ws.send(Message::Binary(upload("notes.txt", "open", b"text").into()))
        .expect("sends");
    let mut bad = upload("x.png", "open", &png);
    bad[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
    c.ws.send(Message::Binary(bad.into())).expect("sends");
    c.sync();
    assert!(
        c.errors.iter().any(|e| e.contains("notes.txt")),
        "{:?}",
        c.errors
    );
    assert!(
        c.errors.iter().any(|e| e.contains("header")),
        "{:?}",
        c.errors
    );
    assert!(!dir.join("notes.txt").exists());
    // An OBJ with a picture of its name beside it opens textured (laid over by its pixels).
    std::fs::write(dir.join("grid.png"), &png).expect("write");
    let textured = Studio::start(&dir, Some("grid.obj"));
    let c = textured.client();
    assert_eq!(c.state["textured"], true);
    // A project whose picture is missing opens untextured, saying so.
    let mut project = bdmorph::studio::Project::new(&rest, Some(vec![[0.5, 0.5]; 25]));
    project.texture = Some("gone.png".into());
    project.write(&dir.join("lost.json")).expect("write");
    let lost = Studio::start(&dir, Some("lost.json"));
    let c = lost.client();
    assert_eq!(c.state["textured"], false);
    assert!(
        c.notes()
            .iter()
            .any(|n| n.contains("lost.json") && n.contains("gone.png")),
        "{:?}",
        c.notes()
    );
}

/// A picture without transparency opens (its background told by its border's colour), and
/// `--background` / `--threshold` are taken as `mesh` takes them.
#[test]
fn pictures_without_transparency_open() {
    let dir = scratch("opaque");
    let mut picture = generate::picture(160, 120, |x, y| (x - 80.0).hypot(y - 60.0) - 45.0);
    // Opaque: a dark subject on white.
    for p in picture.rgba.chunks_mut(4) {
        let a = f64::from(p[3]) / 255.0;
        for c in p.iter_mut().take(3) {
            *c = (f64::from(*c) * a + 255.0 * (1.0 - a)).round() as u8;
        }
        p[3] = 255;
    }
    std::fs::write(
        dir.join("scan.png"),
        bdmorph::render::raster::encode_png(&picture).expect("png"),
    )
    .expect("write");
    let studio = Studio::start(&dir, Some("scan.png"));
    let c = studio.client();
    assert!(c.state["vertices"].as_u64().unwrap_or(0) > 100);
    assert_eq!(c.state["picture_settings"]["background"], "auto");
    assert!(
        c.notes().iter().any(|n| n.contains("no transparency")),
        "{:?}",
        c.notes()
    );
    let studio = Studio::start_with(
        &dir,
        &["scan.png", "--background", "white", "--threshold", "0.3"],
    );
    let c = studio.client();
    assert_eq!(c.state["picture_settings"]["background"], "#ffffff");
    assert_eq!(c.state["picture_settings"]["threshold"], 0.3);
}

#[test]
fn a_keyframe_loads_from_a_mesh_file_with_the_same_triangles() {
    let dir = scratch("load-keyframe");
    let rest = generate::disk(6, 0.1);
    bdmorph::io::write_obj_2d(dir.join("rest.obj"), &rest.positions, &rest.faces, &[])
        .expect("write");
    let studio = Studio::start(&dir, Some("rest.obj"));
    let mut c = studio.client();
    assert_eq!(c.state["anchors"].as_array().map(Vec::len), Some(1));
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
    assert_eq!(c.request(&request.to_string()), None);
    assert_eq!(c.state["keyframes"].as_array().map(Vec::len), Some(2));
    assert_eq!(c.state["undo"], "keyframe 2 from bent.obj");
    let got = c.positions();
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
    let last = bent.faces[0];
    let reversed = text.replace(
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
        let said = c.request(&request.to_string()).expect("refused");
        assert!(said.contains(name), "{name}: {said}");
        assert!(!said.contains("0-based"), "{said}");
        assert_eq!(c.state["keyframes"].as_array().map(Vec::len), Some(2));
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

fn mesh_and_wait(c: &mut Client, request: &str) -> Option<String> {
    let before = c.state["undo"].clone();
    let notes = c.notes().len();
    if let Some(e) = c.request(request) {
        return Some(e);
    }
    c.wait_for(60, "the new mesh", |c| {
        c.state["job"].is_null() && (c.state["undo"] != before || c.notes().len() != notes)
    });
    c.notes()
        .last()
        .filter(|n| !n.contains("new mesh"))
        .cloned()
}

#[test]
fn the_outline_is_traced_drawn_imported_and_meshed_over_the_picture() {
    let dir = scratch("outline");
    write_ring_picture(&dir.join("ring.png"), 200);
    let studio = Studio::start(&dir, Some("ring.png"));
    let mut c = studio.client();
    assert_eq!(c.state["picture"], serde_json::json!([200, 200]));
    // Traced: the disk's outline and the hole's, in the picture's pixels.
    assert_eq!(c.request(r#"{"op":"trace_outline"}"#), None);
    let loops = c.outline.as_array().expect("loops").clone();
    assert_eq!(loops.len(), 2, "the disk and its hole");
    let mut extents = Vec::new();
    for l in &loops {
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
    assert!(extents[0].0 > 17.0 && extents[0].1 < 31.0, "{extents:?}");
    assert!(extents[1].0 > 77.0 && extents[1].1 < 82.0, "{extents:?}");
    // Meshed as traced, at two densities: textured, the vertex count met within 10%.
    for vertices in [300, 1500] {
        let request = serde_json::json!({"op": "mesh_outline", "vertices": vertices});
        assert_eq!(mesh_and_wait(&mut c, &request.to_string()), None);
        let n = c.state["vertices"].as_u64().expect("n") as f64;
        assert!(
            (n - vertices as f64).abs() <= 0.1 * vertices as f64,
            "{n} vertices for {vertices}"
        );
        assert_eq!(
            c.state["textured"], true,
            "the picture stays on the new mesh"
        );
        for q in &positions(&c.frame) {
            let (dx, dy) = (f64::from(q[0]) - 100.0, f64::from(q[1]) - 100.0);
            assert!(dx.hypot(dy) < 81.0, "{q:?} outside");
            assert!(dx.abs().max(dy.abs()) > 19.0, "{q:?} in the hole");
        }
    }
    // The new mesh poses.
    for v in [0, 5] {
        assert_eq!(
            c.request(&format!(r#"{{"op":"pin_add","vertex":{v}}}"#)),
            None
        );
    }
    let p = c.positions();
    let at = |q: [f32; 2]| [f64::from(q[0]), f64::from(q[1])];
    assert_eq!(
        c.drag(&[at(p[0]), [at(p[5])[0] + 4.0, at(p[5])[1] + 3.0]]),
        None
    );
    let moved = c.positions();
    assert!((moved[5][0] - p[5][0] - 4.0).abs() < 0.5, "{:?}", moved[5]);
    // A hand-drawn triangle with a triangular hole, point by point, and an SVG file.
    assert_eq!(c.request(r#"{"op":"outline_set","loops":[]}"#), None);
    for ring in [
        [[10.0, 10.0], [190.0, 10.0], [100.0, 180.0]],
        [[80.0, 50.0], [120.0, 50.0], [100.0, 90.0]],
    ] {
        assert_eq!(c.request(r#"{"op":"outline_new_loop"}"#), None);
        for p in ring {
            let request = serde_json::json!({"op": "outline_point", "point": p}).to_string();
            assert_eq!(c.request(&request), None);
        }
        assert_eq!(c.request(r#"{"op":"outline_close"}"#), None);
    }
    assert_eq!(
        mesh_and_wait(&mut c, r#"{"op":"mesh_outline","vertices":400}"#),
        None
    );
    let n = c.state["vertices"].as_u64().expect("n");
    assert!(n > 250, "{n}");
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 200 200">
        <rect x="20" y="20" width="160" height="120"/></svg>"#;
    let import = serde_json::json!({"op": "import_outline", "name": "box.svg", "text": svg, "vertices": 600});
    assert_eq!(mesh_and_wait(&mut c, &import.to_string()), None);
    let n = c.state["vertices"].as_u64().expect("n");
    assert!(n > 400, "{n}");
    // Refused, each with its reason, and the project as it was.
    for (request, reason) in [
        (
            serde_json::json!({"op": "outline_set", "loops": [[[0, 0], [100, 100], [100, 0], [0, 100]]]}),
            "cross",
        ),
        (
            serde_json::json!({"op": "mesh_outline", "vertices": 10_000_000}),
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
        let said = match c.request(&request.to_string()) {
            Some(e) => e,
            // Setting a crossing outline is allowed; meshing it is what fails.
            None => mesh_and_wait(&mut c, r#"{"op":"mesh_outline","vertices":400}"#)
                .expect("meshing fails"),
        };
        assert!(said.contains(reason), "{said}");
        assert_eq!(c.state["vertices"].as_u64(), Some(n), "unchanged");
    }
    assert!(studio.page_is_served());
    // Without a picture there is nothing to trace.
    let plain = Studio::start(&dir, None);
    let mut c = plain.client();
    assert!(c.state["picture"].is_null());
    let said = c.request(r#"{"op":"trace_outline"}"#).expect("refused");
    assert!(said.contains("no picture"), "{said}");
}

#[test]
fn keyframes_reorder_and_move_in_time() {
    let dir = scratch("reorder");
    let rest = generate::disk(5, 0.1);
    bdmorph::io::write_obj_2d(dir.join("rest.obj"), &rest.positions, &rest.faces, &[])
        .expect("write");
    let studio = Studio::start(&dir, Some("rest.obj"));
    let mut c = studio.client();
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
        assert_eq!(c.request(&request.to_string()), None);
    }
    let is = |got: &[[f32; 2]], want: &bdmorph::mesh::PlanarMesh| {
        got.iter().zip(&want.positions).all(|(g, w)| {
            (f64::from(g[0]) - w[0]).abs() < 1e-6 && (f64::from(g[1]) - w[1]).abs() < 1e-6
        })
    };
    let pose_of = |c: &mut Client, k: usize| {
        assert_eq!(
            c.request(&format!(r#"{{"op":"select","keyframe":{k}}}"#)),
            None
        );
        c.positions()
    };
    // The last pose moves to the middle: poses rest, full, half; times stay 0, 1, 2.
    assert_eq!(
        c.request(r#"{"op":"move_keyframe","keyframe":2,"to":1}"#),
        None
    );
    assert_eq!(c.state["current"], 1);
    let times: Vec<f64> = c.state["keyframes"]
        .as_array()
        .expect("keyframes")
        .iter()
        .map(|k| k["time"].as_f64().expect("time"))
        .collect();
    assert_eq!(times, [0.0, 1.0, 2.0]);
    assert!(is(&pose_of(&mut c, 1), &full));
    assert!(is(&pose_of(&mut c, 2), &half));
    // The first pose to the end: full, half, rest.
    assert_eq!(
        c.request(r#"{"op":"move_keyframe","keyframe":0,"to":2}"#),
        None
    );
    assert!(is(&pose_of(&mut c, 0), &full));
    assert!(is(&pose_of(&mut c, 2), &rest));
    // The middle keyframe moves in time between its neighbours, and not past them.
    assert_eq!(
        c.request(r#"{"op":"set_time","keyframe":1,"time":1.5}"#),
        None
    );
    assert_eq!(c.state["keyframes"][1]["time"], 1.5);
    for bad in [
        r#"{"op":"set_time","keyframe":1,"time":2.5}"#,
        r#"{"op":"set_time","keyframe":0,"time":0.5}"#,
        r#"{"op":"move_keyframe","keyframe":5,"to":0}"#,
        r#"{"op":"move_keyframe","keyframe":0,"to":3}"#,
    ] {
        assert!(c.request(bad).is_some(), "{bad}");
        assert_eq!(c.state["keyframes"][1]["time"], 1.5);
    }
    // The animation plays the new order.
    assert_eq!(c.request(r#"{"op":"scrub","seq":1,"time":0.0}"#), None);
    assert!(is(&c.positions(), &full));
    assert_eq!(c.request(r#"{"op":"scrub","seq":2,"time":1.5}"#), None);
    assert!(is(&c.positions(), &half));
    // Clone the keyframe shown (half), and add a copy of the first (full).
    pose_of(&mut c, 1);
    assert_eq!(c.request(r#"{"op":"add_keyframe","time":3}"#), None);
    assert!(is(&c.positions(), &half));
    assert_eq!(
        c.request(r#"{"op":"add_keyframe","time":4,"copy":0}"#),
        None
    );
    assert!(is(&c.positions(), &full));
    assert_eq!(c.state["current"], 4);
    let said = c
        .request(r#"{"op":"add_keyframe","time":5,"copy":9}"#)
        .expect("refused");
    assert!(said.contains("no keyframe 10"), "{said}");
}

/// Keyframes as the state lists them, without their pose revisions (numbers of one session,
/// for the pages' copies of poses).
fn without_revisions(keys: &serde_json::Value) -> serde_json::Value {
    let mut keys = keys.clone();
    for key in keys.as_array_mut().into_iter().flatten() {
        if let Some(k) = key.as_object_mut() {
            k.remove("rev");
        }
    }
    keys
}
