//! `bdmorph studio` within its bounds, through its socket and routes: the server's resident
//! memory before and after many large pictures and a refused huge message (printed, and
//! bounded generously), Cancel of each long job answered within a second (printed; checked
//! with a generous margin), a second job answered while one runs, temporary files of a killed
//! studio removed at start (and nothing else), exports that never replace or delete without
//! the overwrite flag, two tabs dragging different pins at once, and a PSD crafted to make a
//! reader allocate terabytes, by each route that reads one.

#![cfg(target_os = "linux")]

mod layered;
mod studio_common;

use std::path::Path;
use std::time::{Duration, Instant};

use studio_common::{scratch, Client, Studio};

const MB: f64 = 1024.0 * 1024.0;

/// A distinct 8192 x 8192 PNG (1-bit grey, about 300 KB: noise over its top 300 rows, as a
/// decoder refuses a file claiming far more pixels than its bytes can hold; 256 MiB decoded).
fn big_png(seed: u32) -> Vec<u8> {
    let side = 8192u32;
    let mut out = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut out, side, side);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::One);
        let mut writer = encoder.write_header().expect("header");
        let row = (side / 8) as usize;
        let mut data = vec![0xffu8; row * side as usize];
        let mut x = u64::from(seed).wrapping_mul(0x9e37_79b9_7f4a_7c15) + 1;
        for b in &mut data[..300 * row] {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            *b = (x >> 56) as u8;
        }
        writer.write_image_data(&data).expect("data");
    }
    out
}

/// The CRC-32 of a PNG chunk's type and data (to keep a patched header valid).
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xffff_ffffu32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

fn print_rss(what: &str, before: u64, after: u64) {
    println!(
        "RSS {what}: before {:.0} MB, after {:.0} MB",
        before as f64 / MB,
        after as f64 / MB
    );
}

/// Waits until the studio's resident memory stops growing (freed memory is given back
/// promptly, but a page's task may still be finishing).
fn settled_resident(studio: &Studio) -> u64 {
    std::thread::sleep(Duration::from_millis(300));
    studio.resident()
}

#[test]
fn eight_large_pictures_stay_within_the_picture_budget() {
    let dir = scratch("bounds-pictures");
    for k in 0..8 {
        std::fs::write(dir.join(format!("big{k}.png")), big_png(k)).expect("write");
    }
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    c.sync();
    let before = settled_resident(&studio);
    for k in 0..8 {
        assert_eq!(
            studio.get_with_token(&format!("/picture?name=big{k}.png")),
            200
        );
    }
    let after = settled_resident(&studio);
    print_rss("after 8 GETs of distinct 8192x8192 PNGs", before, after);
    // The cache keeps at most 320 MiB; without a bound this was 2 GB.
    assert!(
        after < before + (450 << 20),
        "resident memory grew from {before} to {after} bytes"
    );
    // A picture over the studio's pixel limit is refused before it is decoded.
    let mut huge = big_png(0);
    huge[16..20].copy_from_slice(&16384u32.to_be_bytes());
    let crc = crc32(&huge[12..29]);
    huge[29..33].copy_from_slice(&crc.to_be_bytes());
    std::fs::write(dir.join("huge.png"), &huge).expect("write");
    let said = c
        .request(r#"{"op":"attach_picture","name":"huge.png"}"#)
        .expect("refused");
    assert!(
        said.contains("16384x8192") && said.contains("budget"),
        "{said}"
    );
    assert!(studio.page_is_served());
}

#[test]
fn a_refused_forty_megabyte_message_costs_no_lasting_memory() {
    let dir = scratch("bounds-message");
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    c.sync();
    let before = settled_resident(&studio);
    let points = "[1.5,2.5],".repeat(4 << 20);
    let message = format!(r#"{{"op":"outline_set","loops":[[{points}[0,0]]]}}"#);
    assert!(message.len() > 40_000_000);
    let said = c.request(&message).expect("refused");
    drop(message);
    assert!(
        said.contains("'outline_set'") && said.contains("at most"),
        "{said}"
    );
    let after = settled_resident(&studio);
    print_rss("after a refused 40 MB outline_set", before, after);
    // It was 1.18 GB, kept.
    assert!(
        after < before + (120 << 20),
        "resident memory grew from {before} to {after} bytes"
    );
    // A small message of a small kind, made long, is refused by its kind's limit.
    let long = format!(
        r#"{{"op":"select","keyframe":0,"x":"{}"}}"#,
        "y".repeat(100_000)
    );
    let said = c.request(&long).expect("refused");
    assert!(said.contains("'select'"), "{said}");
    assert_eq!(c.request(r#"{"op":"add_keyframe","time":1}"#), None);
}

/// Sends Cancel once `running` shows the job started; the seconds until the job was gone.
fn cancel_latency(c: &mut Client, what: &str) -> f64 {
    c.wait_for(120, &format!("{what} to start"), |c| {
        !c.state["job"].is_null()
    });
    std::thread::sleep(Duration::from_millis(300));
    assert!(!c.state["job"].is_null() || c.notes().iter().any(|n| n.contains("cancelled")));
    let start = Instant::now();
    assert_eq!(c.request(r#"{"op":"cancel"}"#), None, "{what}");
    c.wait_for(300, &format!("{what} to stop"), |c| {
        c.state["job"].is_null()
    });
    let seconds = start.elapsed().as_secs_f64();
    assert!(
        c.notes().iter().any(|n| n.ends_with("cancelled")),
        "{what}: {:?}",
        c.notes()
    );
    println!("Cancel of {what}: answered in {seconds:.2} s");
    seconds
}

#[test]
fn cancel_stops_a_long_export_within_a_second_and_a_second_job_is_answered() {
    let dir = scratch("bounds-cancel-export");
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    assert_eq!(c.request(r#"{"op":"add_keyframe","time":1}"#), None);
    assert_eq!(
        c.request(
            r#"{"op":"export","format":"gif","name":"long.gif","frames":10000,"size":[1920,1080]}"#
        ),
        None
    );
    // A second job while one runs: answered, naming what runs.
    c.wait_for(60, "the export to start", |c| !c.state["job"].is_null());
    let said = c
        .request(r#"{"op":"export","format":"gif","name":"other.gif","frames":3}"#)
        .expect("answered");
    assert!(said.contains("exporting long.gif is running"), "{said}");
    let seconds = cancel_latency(&mut c, "a 10,000-frame 1920x1080 GIF export");
    assert!(seconds < 3.0, "{seconds} s");
    assert!(!dir.join("long.gif").exists());
    let left: Vec<_> = std::fs::read_dir(&dir)
        .expect("dir")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".part-"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    // Frames larger than the studio exports are refused at once.
    let said = c
        .request(
            r#"{"op":"export","format":"gif","name":"huge.gif","frames":3,"size":[16384,16384]}"#,
        )
        .expect("refused");
    assert!(
        said.contains("at most") || said.contains("over the budget"),
        "{said}"
    );
    assert!(studio.page_is_served());
}

/// The studio's largest mesh (200,000 vertices) is made in about a second, and Cancel is
/// heard between the stages of meshing.
#[test]
fn cancel_stops_meshing_within_a_second() {
    let dir = scratch("bounds-cancel-mesh");
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    let ring: Vec<[f64; 2]> = (0..400)
        .map(|i| {
            let a = f64::from(i) / 400.0 * std::f64::consts::TAU;
            [a.cos() * (1.0 + 0.2 * (7.0 * a).sin()), a.sin()]
        })
        .collect();
    let set = serde_json::json!({"op": "outline_set", "loops": [ring]}).to_string();
    assert_eq!(c.request(&set), None);
    assert_eq!(
        c.request(r#"{"op":"mesh_outline","vertices":200000}"#),
        None
    );
    let seconds = cancel_latency(&mut c, "meshing 200,000 vertices");
    assert!(seconds < 3.0, "{seconds} s");
}

#[test]
fn cancel_stops_opening_a_many_layer_psd_within_a_second() {
    let dir = scratch("bounds-cancel-open");
    let base = layered::figure();
    let mut layers = Vec::new();
    // As many layers as a character may have (more are refused at once), all overlapping:
    // seconds of meshing and joints.
    for k in 0..bdmorph::parts::MAX_PARTS {
        let l = &base[k % base.len()];
        layers.push(layered::TestLayer {
            name: format!("layer {k}"),
            rgba: l.rgba.clone(),
            hidden: l.hidden,
        });
    }
    std::fs::write(dir.join("many.psd"), layered::write_psd(&layers)).expect("write");
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    assert_eq!(c.request(r#"{"op":"open","name":"many.psd"}"#), None);
    let seconds = cancel_latency(&mut c, "opening a 256-layer PSD");
    assert!(seconds < 3.0, "{seconds} s");
}

#[test]
fn cancel_stops_a_drawing_fit_within_a_second() {
    use bdmorph::generate;
    use bdmorph::render::raster;
    let dir = scratch("bounds-cancel-fit");
    for (name, arm, bend) in [("a.png", 0.0, 0.0), ("b.png", 2.0, 0.2)] {
        let png = raster::encode_png(&generate::figure_picture(1024, arm, bend)).expect("png");
        std::fs::write(dir.join(name), png).expect("write");
    }
    let studio = Studio::start(&dir, Some("a.png"));
    let mut c = studio.client();
    // A fine mesh, so that the fit takes long.
    assert_eq!(
        c.request(r#"{"op":"mesh_outline","vertices":100000}"#),
        None
    );
    c.wait_for(600, "the mesh", |c| c.state["job"].is_null());
    assert_eq!(
        c.request(r#"{"op":"drawing_keyframe","name":"b.png","time":2}"#),
        None
    );
    let seconds = cancel_latency(&mut c, "laying a 100,000-vertex mesh over a drawing");
    assert!(seconds < 3.0, "{seconds} s");
}

/// Names of the entries of `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut n: Vec<String> = std::fs::read_dir(dir)
        .expect("dir")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    n.sort();
    n
}

#[test]
fn temporary_files_of_a_killed_studio_are_removed_at_start_and_nothing_else() {
    let dir = scratch("bounds-temporaries");
    let state = dir.join(".bdmorph-studio");
    std::fs::create_dir_all(&state).expect("state");
    // A process id that is not running (above Linux's largest).
    let gone = 4_194_305u32;
    let ours = std::process::id();
    let stale = [
        format!(".anim.json.tmp-{gone}-0"),
        format!(".walk.gif.part-{gone}"),
    ];
    for name in &stale {
        std::fs::write(dir.join(name), vec![7u8; 1 << 20]).expect("write");
    }
    std::fs::write(state.join(format!(".autosave.json.tmp-{gone}-3")), "{}").expect("write");
    let frames = dir.join(format!(".walk-png.part-{gone}"));
    std::fs::create_dir(&frames).expect("dir");
    std::fs::write(frames.join("frame_0000.png"), "x").expect("write");
    // Kept: another running process's, other names, a folder with a file of the user's.
    let kept = [
        format!(".live.json.tmp-{ours}-1"),
        "notes.tmp-1".to_owned(),
        ".bashrc".to_owned(),
        "anim.json.tmp-1-2".to_owned(),
    ];
    for name in &kept {
        std::fs::write(dir.join(name), "mine").expect("write");
    }
    let mixed = dir.join(format!(".mine.part-{gone}"));
    std::fs::create_dir(&mixed).expect("dir");
    std::fs::write(mixed.join("notes.txt"), "mine").expect("write");
    std::thread::sleep(Duration::from_millis(20));
    let studio = Studio::start(&dir, None);
    assert!(studio.page_is_served());
    let left = names(&dir);
    for name in &stale {
        assert!(!left.contains(name), "{name} left: {left:?}");
    }
    assert!(!frames.exists(), "{left:?}");
    for name in &kept {
        assert!(left.contains(name), "{name} removed: {left:?}");
    }
    assert!(mixed.join("notes.txt").is_file());
    assert!(!names(&state).iter().any(|n| n.contains(".tmp-")));
}

/// Runs an export and waits for it; the error, if any (the `exists` answer is kept in `c`).
fn export(c: &mut Client, request: &str) -> Option<String> {
    c.exists = None;
    let said = c.request(request);
    c.wait_for(120, "the export", |c| c.state["job"].is_null());
    said
}

#[test]
fn exports_never_delete_or_replace_without_the_overwrite_flag() {
    let dir = scratch("bounds-exports");
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    assert_eq!(c.request(r#"{"op":"add_keyframe","time":1}"#), None);
    // PNG frames, then OBJ frames of the same name: answered "exists", the PNGs kept.
    assert_eq!(
        export(
            &mut c,
            r#"{"op":"export","format":"frames","name":"walk","frames":4}"#
        ),
        None
    );
    let pngs = names(&dir.join("walk"));
    assert_eq!(pngs.len(), 4, "{pngs:?}");
    let note = c
        .notes()
        .into_iter()
        .rfind(|n| n.starts_with("exported"))
        .expect("note");
    assert!(
        !note.contains(" 0.0 MB") && note.contains("written"),
        "{note}"
    );
    let written: u64 = std::fs::read_dir(dir.join("walk"))
        .expect("dir")
        .flatten()
        .map(|e| e.metadata().expect("meta").len())
        .sum();
    println!("{note} ({written} bytes on disk)");
    assert_eq!(
        export(
            &mut c,
            r#"{"op":"export","format":"obj","name":"walk","frames":4}"#
        ),
        None
    );
    let exists = c.exists.clone().expect("answered exists");
    assert_eq!(exists["name"], "walk");
    assert!(exists["path"].as_str().is_some_and(|p| p.ends_with("walk")));
    assert_eq!(names(&dir.join("walk")), pngs, "nothing deleted");
    // With overwrite, OBJ frames do not replace a folder of PNG frames (other files).
    let said = export(
        &mut c,
        r#"{"op":"export","format":"obj","name":"walk","frames":4,"overwrite":true}"#,
    )
    .expect("refused");
    assert!(said.contains(".png") && said.contains("walk"), "{said}");
    assert_eq!(names(&dir.join("walk")), pngs, "nothing deleted");
    // PNG frames over PNG frames, asked for: replaced.
    assert_eq!(
        export(
            &mut c,
            r#"{"op":"export","format":"frames","name":"walk","frames":3,"overwrite":true}"#
        ),
        None
    );
    assert_eq!(names(&dir.join("walk")).len(), 3);
    // A GIF twice: the second answered "exists", the first kept byte for byte.
    assert_eq!(
        export(
            &mut c,
            r#"{"op":"export","format":"gif","name":"a.gif","frames":3}"#
        ),
        None
    );
    let first = std::fs::read(dir.join("a.gif")).expect("gif");
    assert_eq!(
        export(
            &mut c,
            r#"{"op":"export","format":"gif","name":"a.gif","frames":5}"#
        ),
        None
    );
    assert!(c.exists.is_some());
    assert_eq!(std::fs::read(dir.join("a.gif")).expect("gif"), first);
    assert_eq!(
        export(
            &mut c,
            r#"{"op":"export","format":"gif","name":"a.gif","frames":5,"overwrite":true}"#
        ),
        None
    );
    assert!(c.exists.is_none());
    assert_ne!(std::fs::read(dir.join("a.gif")).expect("gif"), first);
    // A sprite sheet's JSON counts: a file of the user's named like it is not replaced.
    std::fs::write(dir.join("sheet.json"), "mine").expect("write");
    assert_eq!(
        export(
            &mut c,
            r#"{"op":"export","format":"sheet","name":"sheet.png","frames":3}"#
        ),
        None
    );
    assert!(c.exists.is_some());
    assert!(!dir.join("sheet.png").exists());
    assert_eq!(
        std::fs::read_to_string(dir.join("sheet.json")).expect("json"),
        "mine"
    );
    // A still onto a file that is there: asked too.
    std::fs::write(dir.join("frame.png"), "mine").expect("write");
    assert_eq!(
        export(
            &mut c,
            r#"{"op":"export","format":"still","name":"frame.png"}"#
        ),
        None
    );
    assert!(c.exists.is_some());
    assert_eq!(
        std::fs::read_to_string(dir.join("frame.png")).expect("png"),
        "mine"
    );
}

#[test]
fn two_tabs_dragging_different_pins_at_once_both_move() {
    let dir = scratch("bounds-two-drags");
    let studio = Studio::start(&dir, None);
    let mut a = studio.client();
    let mut b = studio.client();
    assert_eq!(a.request(r#"{"op":"add_keyframe","time":1}"#), None);
    let n = a.state["vertices"].as_u64().expect("n") as u32;
    for v in [0, n - 1] {
        assert_eq!(
            a.request(&format!(r#"{{"op":"pin_add","vertex":{v}}}"#)),
            None
        );
    }
    b.sync();
    assert_eq!(b.pins, [0, n - 1]);
    let p = a.positions();
    let at = |v: u32| [f64::from(p[v as usize][0]), f64::from(p[v as usize][1])];
    let (start0, start1) = (at(0), at(n - 1));
    // Each tab moves its own pin in small steps, interleaved; each sends the other pin where
    // it saw it when its drag began (as a page does).
    let mut last = ([0.0; 2], [0.0; 2]);
    for step in 1..=5 {
        let s = f64::from(step) * 0.05;
        let t0 = [start0[0] - s, start0[1]];
        let t1 = [start1[0] + s, start1[1] + s];
        assert_eq!(a.drag_moving(&[t0, start1], &[0]), None);
        assert_eq!(b.drag_moving(&[start0, t1], &[n - 1]), None);
        last = (t0, t1);
    }
    assert_eq!(a.request(r#"{"op":"drag_end"}"#), None);
    assert_eq!(b.request(r#"{"op":"drag_end"}"#), None);
    a.sync();
    b.sync();
    let close =
        |q: [f32; 2], t: [f64; 2]| (f64::from(q[0]) - t[0]).hypot(f64::from(q[1]) - t[1]) < 1e-3;
    for c in [&a, &b] {
        let q = c.positions();
        assert!(
            close(q[0], last.0),
            "tab A's pin: {:?} vs {:?}",
            q[0],
            last.0
        );
        assert!(
            close(q[(n - 1) as usize], last.1),
            "tab B's pin: {:?} vs {:?}",
            q[(n - 1) as usize],
            last.1
        );
    }
    // A drag naming a pin that is not there is refused, and said.
    let said = a.drag_moving(&[start0, start1], &[12345]).expect("refused");
    assert!(said.contains("not pinned"), "{said}");
}

/// A small valid PSD whose slices resource (image resource 1050) declares 0xFFFFFFFF
/// descriptor fields: a reader that trusts the count allocates about a terabyte.
fn crafted_psd() -> Vec<u8> {
    let good = layered::write_psd(&layered::figure());
    let mut data = Vec::new();
    data.extend_from_slice(&7i32.to_be_bytes()); // slices version 7: a descriptor
    data.extend_from_slice(&16i32.to_be_bytes()); // descriptor version
    data.extend_from_slice(&0u32.to_be_bytes()); // its name: an empty Unicode string
    data.extend_from_slice(&0u32.to_be_bytes()); // class id: 4 bytes follow
    data.extend_from_slice(b"null");
    data.extend_from_slice(&u32::MAX.to_be_bytes()); // the field count
    let mut resource = Vec::new();
    resource.extend_from_slice(b"8BIM");
    resource.extend_from_slice(&1050u16.to_be_bytes());
    resource.extend_from_slice(&[0, 0]); // no name
    resource.extend_from_slice(&(data.len() as u32).to_be_bytes());
    resource.extend_from_slice(&data);
    // The header (26 bytes) and the empty colour mode data (4); then the resources' length.
    let mut out = good[..30].to_vec();
    out.extend_from_slice(&(resource.len() as u32).to_be_bytes());
    out.extend_from_slice(&resource);
    out.extend_from_slice(&good[34..]);
    out
}

#[test]
fn a_crafted_psd_by_each_route_leaves_the_server_answering() {
    let dir = scratch("bounds-crafted-psd");
    let bytes = crafted_psd();
    std::fs::write(dir.join("crafted.psd"), &bytes).expect("write");
    std::fs::write(dir.join("crafted.png"), &bytes).expect("write");
    let studio = Studio::start(&dir, None);
    let mut c = studio.client();
    let before = studio.resident();
    // 1. An upload opened.
    let said = c.upload("upload.psd", "open", &bytes);
    println!("upload then open: {said:?}");
    assert!(studio.page_is_served());
    c.wait_for(60, "the open", |c| c.state["job"].is_null());
    // 2. Opening the file.
    let said = c.request(r#"{"op":"open","name":"crafted.psd"}"#);
    println!("open: {said:?}");
    c.wait_for(60, "the open", |c| c.state["job"].is_null());
    assert!(studio.page_is_served());
    // 3. The same bytes under a picture's name, asked for by the page.
    let status = studio.get_with_token("/picture?name=crafted.png");
    println!("GET /picture: {status}");
    assert!(studio.page_is_served());
    // 4. Attached as the mesh's picture.
    let said = c.request(r#"{"op":"attach_picture","name":"crafted.png"}"#);
    println!("attach_picture: {said:?}");
    assert!(studio.page_is_served());
    c.sync();
    let after = studio.resident();
    print_rss("after the crafted PSD by 4 routes", before, after);
    assert!(after < before + (512 << 20));
}
