//! The studio's time in a real browser (Debian's Chromium, real mouse and keyboard through the
//! DevTools protocol): the playhead, the readout, the status line and every command at the
//! playhead use the time of the frame shown; the scene has a length; a paste onto a keyframe
//! asks. The server's document is read back through its own socket; screenshots are checked
//! for the playhead where the time says.
//!
//! Without Chromium the browser tests are skipped, except in CI (`CI` set), where they fail.

mod studio_common;
mod studio_page;

use std::path::Path;
use std::time::Duration;

use bdmorph::generate;
use bdmorph::studio::project::{Keyframe, Project};
use headless_chrome::browser::tab::ModifierKey;
use studio_common::{scratch, Studio};
use studio_page::*;

/// A body and a raised arm (capsules), on transparency, 400 pixels square.
fn character() -> bdmorph::render::Image {
    let s = 400.0;
    generate::picture(400, 400, |x, y| {
        let p = [x / s, y / s];
        let body = generate::capsule_distance(p, [0.45, 0.35], [0.45, 0.8], 0.12);
        let arm = generate::capsule_distance(p, [0.45, 0.45], [0.8, 0.3], 0.05);
        s * body.min(arm)
    })
}

/// The picture meshed (about `vertices` vertices), textured by it, with keyframes at `times`
/// (the first at 0), bent further and further.
fn project(dir: &Path, times: &[f64], vertices: usize) -> Project {
    let image = character();
    write_png(&dir.join("pic.png"), &image);
    let meshed = bdmorph::meshing::mesh_picture(
        &image,
        &bdmorph::meshing::PictureOptions::default(),
        &bdmorph::meshing::MeshOptions::default().with_vertices(vertices),
    )
    .expect("meshed");
    let uv = bdmorph::studio::open::per_vertex_uv(
        &meshed.texcoords,
        &meshed.mesh.faces,
        meshed.mesh.positions.len(),
    );
    let mut project = Project::new(&meshed.mesh, uv);
    project.texture = Some("pic.png".into());
    for (k, &time) in times.iter().enumerate().skip(1) {
        project.keyframes.push(Keyframe {
            time,
            easing: "linear".into(),
            positions: generate::bend(&meshed.mesh, 0.15 * k as f64).positions,
            pins: Vec::new(),
            drawing: None,
        });
    }
    project
}

/// The keyframes' times, as the server has them (a socket of the test's own).
fn server_times(studio: &Studio) -> Vec<f64> {
    let c = studio.client();
    c.state["keyframes"]
        .as_array()
        .expect("keyframes")
        .iter()
        .map(|k| k["time"].as_f64().expect("time"))
        .collect()
}

/// What the server shows: a keyframe's time, or the time of the frame shown.
fn server_shown(studio: &Studio) -> f64 {
    let c = studio.client();
    let shown = &c.state["shown"];
    match shown.get("time") {
        Some(t) => t.as_f64().expect("time"),
        None => {
            let k = shown["keyframe"].as_u64().expect("keyframe") as usize;
            c.state["keyframes"][k]["time"].as_f64().expect("time")
        }
    }
}

/// The page position of `time` on the ruler (the strip of seconds above the keys).
fn on_ruler(page: &PageTab, time: f64) -> [f64; 2] {
    let at = page.eval(&format!("studio.timeToPage({time})"));
    let ruler = page.rect("#ruler");
    [at[0].as_f64().expect("x"), (ruler[1] + ruler[3]) / 2.0]
}

/// A drag on the ruler from `from` to `to` seconds in `moves` steps, `pause` apart, with the
/// real mouse.
fn drag_ruler(page: &PageTab, from: f64, to: f64, moves: usize, pause: u64) {
    let (a, b) = (on_ruler(page, from), on_ruler(page, to));
    page.press(a);
    for k in 1..=moves {
        let s = k as f64 / moves as f64;
        page.move_to([a[0] + (b[0] - a[0]) * s, a[1]], true);
        std::thread::sleep(Duration::from_millis(pause));
    }
    page.release(b);
}

/// The playhead's red pixels in a screenshot of the timeline (`[left, top, right, bottom]`),
/// near `x` and away from it.
fn playhead_pixels(shot: &Shot, time_rect: [f64; 4], x: f64) -> (usize, usize) {
    let red = |p: [u8; 3]| p[0] > 180 && p[1] < 80 && p[2] < 80;
    let all = shot.count_in(time_rect, red);
    let near = shot.count_in([x - 8.0, time_rect[1], x + 8.0, time_rect[3]], red);
    (near, all - near)
}

/// Six drag-scrubs on the ruler (different lengths and speeds), each followed by `I`: after
/// each release the readout, the status line and the server show the released time, the
/// playhead is drawn there (and nowhere else), and `I` makes the keyframe there.
///
/// Before: the readout and the playhead kept the time of the drag's first step (the page took
/// it from the state, which a scrub does not resend), so the status said one time, the
/// readout another, and `I` made its keyframe at the stale time.
#[test]
fn six_drag_scrubs_each_followed_by_i_make_keys_at_the_released_times() {
    let Some(browser) = browser() else { return };
    let dir = scratch("t1-scrubs");
    project(&dir, &[0.0, 2.0, 4.0], 3000)
        .write(&dir.join("anim.json"))
        .expect("written");
    let studio = Studio::start(&dir, Some("anim.json"));
    let page = PageTab::open(&browser, &studio.url, &dir);
    page.settle();
    let fps = page.num("studio.state.fps");
    // [from, to, moves, pause in ms]: long and short, fast and slow, both ways.
    let drags = [
        (0.4, 3.3, 30, 4),
        (3.5, 1.3, 8, 30),
        (1.1, 2.7, 60, 1),
        (2.9, 0.7, 4, 60),
        (0.2, 3.7, 15, 12),
        (3.9, 1.7, 25, 2),
    ];
    for (i, &(from, to, moves, pause)) in drags.iter().enumerate() {
        let before = server_times(&studio);
        drag_ruler(&page, from, to, moves, pause);
        page.settle();
        let readout = page.eval("document.getElementById('time-readout').textContent");
        let status = page.eval("document.getElementById('status').textContent");
        let shown = server_shown(&studio);
        let playhead = page.num("studio.frameInfo.time");
        eprintln!("drag {i}: {from} -> {to} s: readout {readout}, shown {shown}, status {status}");
        assert!(
            (shown - to).abs() <= 1.0 / fps,
            "drag {i}: the server shows {shown} s, released at {to} s"
        );
        assert_eq!(
            readout.as_str(),
            Some(format!("{shown:.2} s").as_str()),
            "drag {i}: the readout says the time shown"
        );
        assert!(
            status
                .as_str()
                .expect("status")
                .contains(&format!("frame at {shown:.2} s")),
            "drag {i}: the status says the time shown: {status}"
        );
        assert!(
            (playhead - shown).abs() < 1e-6,
            "drag {i}: the page's frame is the server's: {playhead} {shown}"
        );
        let time_rect = page.rect("#time");
        let x = on_ruler(&page, shown)[0];
        let shot = page.shot(&format!("t1-drag-{i}.png"));
        let (near, elsewhere) = playhead_pixels(&shot, time_rect, x);
        assert!(
            near > 40 && elsewhere < 10,
            "drag {i}: the playhead drawn at {shown} s: {near} red pixels there, {elsewhere} elsewhere"
        );
        page.key("i", &[]);
        page.wait(
            &format!("studio.state.keyframes.length === {}", before.len() + 1),
            20,
        );
        page.settle();
        let after = server_times(&studio);
        let new: Vec<f64> = after
            .iter()
            .copied()
            .filter(|t| !before.contains(t))
            .collect();
        assert_eq!(new.len(), 1, "drag {i}: one new keyframe: {after:?}");
        assert_eq!(new[0], shown, "drag {i}: the keyframe is at the time shown");
        assert!(
            (new[0] - to).abs() <= 1.0 / fps,
            "drag {i}: the keyframe at {} s, released at {to} s",
            new[0]
        );
    }
    assert_eq!(server_times(&studio).len(), 9);
}

/// One keyframe: → steps the playhead past it (frame by frame, a second on), `I` makes a
/// second keyframe there, posed; playback then reaches it and the pose changes on the way.
///
/// Before: the timeline ended at the last keyframe, so → did not move the playhead and `I`
/// said "keyframe 1 is at the playhead already".
#[test]
fn i_one_second_past_the_only_key_then_play() {
    let Some(browser) = browser() else { return };
    let dir = scratch("t2-length");
    write_png(&dir.join("pic.png"), &character());
    let studio = Studio::start(&dir, Some("pic.png"));
    let page = PageTab::open(&browser, &studio.url, &dir);
    page.settle();
    assert_eq!(page.num("studio.state.keyframes.length"), 1.0);
    let fps = page.num("studio.state.fps") as usize;
    // Focus on the timeline (a click on the first keyframe's time), then a second of frames.
    page.click(on_ruler(&page, 0.0));
    page.settle();
    for _ in 0..fps {
        page.key("ArrowRight", &[]);
    }
    page.settle();
    assert_eq!(
        page.eval("document.getElementById('time-readout').textContent"),
        "1.00 s"
    );
    assert_eq!(server_shown(&studio), 1.0);
    // Past the end of the timeline the playhead stops.
    page.key("ArrowRight", &[]);
    page.settle();
    assert_eq!(
        server_shown(&studio),
        1.0,
        "the timeline ends a second past the last key"
    );
    page.shot("t2-past-the-key.png");
    page.key("i", &[]);
    page.wait("studio.state.keyframes.length === 2", 20);
    page.settle();
    assert_eq!(server_times(&studio), [0.0, 1.0]);
    assert_eq!(page.num("studio.state.current"), 1.0);
    // The new keyframe posed: a pin at the body's bottom, the hand dragged up.
    let bottom = page.extreme(0, 0.0, -1.0);
    page.click(page.vertex(bottom));
    page.wait("studio.pins.length === 1", 10);
    let hand = page.extreme(0, 1.0, 0.0);
    let from = page.vertex(hand);
    page.drag(from, [from[0] - 40.0, from[1] - 100.0], 20);
    page.settle();
    let rest_y = page.num(&format!("studio.rest[{}]", 2 * hand + 1));
    let posed_y = page.num(&format!("studio.pose[{}]", 2 * hand + 1));
    assert!(
        posed_y > rest_y + 30.0,
        "the hand moved up: {rest_y} -> {posed_y}"
    );
    // Play once (no loop) from the start, watching the hand in every frame shown.
    page.click_on("#loop");
    page.key("Home", &[]);
    page.settle();
    page.eval(&format!(
        "(() => {{ window.seen = []; window.seeing = true; const look = () => {{ window.seen.push([studio.frameInfo.time, studio.pose[{}]]); if (window.seeing) requestAnimationFrame(look); }}; requestAnimationFrame(look); return true; }})()",
        2 * hand + 1
    ));
    page.key(" ", &[]);
    page.wait("studio.playing", 5);
    page.wait("!studio.playing && !studio.busy()", 20);
    page.settle();
    page.eval("(window.seeing = false)");
    std::thread::sleep(Duration::from_millis(50));
    let seen: Vec<(f64, f64)> = page
        .eval("window.seen")
        .as_array()
        .expect("seen")
        .iter()
        .map(|p| (p[0].as_f64().expect("t"), p[1].as_f64().expect("y")))
        .collect();
    let end = seen.last().copied().expect("frames");
    assert_eq!(end.0, 1.0, "playback reaches the new keyframe");
    assert!((end.1 - posed_y).abs() < 1e-3, "its pose shown at the end");
    let between = seen
        .iter()
        .filter(|(t, y)| *t > 0.05 && *t < 0.95 && *y > rest_y + 1.0 && *y < posed_y - 1.0)
        .count();
    assert!(
        between >= 3,
        "the hand rises on the way: {between} frames in between of {}",
        seen.len()
    );
    page.shot("t2-played.png");
}

/// The scene's length set in its field: saved (project version 4), playback and the timeline
/// reach it, undone and redone; `bdmorph export` makes its frames.
#[test]
fn the_scene_length_is_set_saved_undone_and_exported() {
    let Some(browser) = browser() else { return };
    let dir = scratch("t3-scene-length");
    project(&dir, &[0.0, 2.0], 800)
        .write(&dir.join("anim.json"))
        .expect("written");
    let studio = Studio::start(&dir, Some("anim.json"));
    let page = PageTab::open(&browser, &studio.url, &dir);
    page.settle();
    assert_eq!(page.num("studio.state.duration"), 2.0);
    assert_eq!(page.num("studio.state.timeline"), 3.0);
    page.set_value("#scene-length", "4");
    page.wait("studio.state.length === 4", 10);
    assert_eq!(page.num("studio.state.duration"), 4.0);
    assert_eq!(page.num("studio.state.timeline"), 4.0);
    // The playhead goes to the end: a click near it.
    page.click(on_ruler(&page, 3.99));
    page.settle();
    assert!((server_shown(&studio) - 3.99).abs() < 0.03);
    page.shot("t3-length.png");
    let mut c = studio.client();
    let save = serde_json::json!({"op": "save", "name": "long.json", "overwrite": true});
    assert_eq!(c.request(&save.to_string()), None);
    let saved: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("long.json")).expect("saved"))
            .expect("json");
    assert_eq!(saved["version"], 4);
    assert_eq!(saved["length"], 4.0);
    page.undo();
    assert_eq!(page.eval("studio.state.length"), serde_json::Value::Null);
    assert_eq!(
        page.eval("document.getElementById('scene-length').value"),
        ""
    );
    assert_eq!(page.num("studio.state.duration"), 2.0);
    // Exported from the command line: 4 s at 25 fps, 101 frames; the saved file without a
    // length, 51 (as before).
    let frames = |project: &str, out: &str| -> usize {
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_bdmorph"))
            .args(["export", project, "--format", "obj", "-q", "-o", out])
            .current_dir(&dir)
            .status()
            .expect("runs");
        assert!(status.success());
        std::fs::read_dir(dir.join(out)).expect("folder").count()
    };
    assert_eq!(frames("long.json", "long-frames"), 101);
    assert_eq!(frames("anim.json", "short-frames"), 51);
}

/// Ctrl+V at a time that has a keyframe asks: replace it (its pose becomes the copy's, its
/// time stays) or insert the copy a frame after; each choice one undo step.
///
/// Before: the copy went silently to one second after the last keyframe.
#[test]
fn a_paste_onto_a_keyframe_asks_replace_or_insert_after() {
    let Some(browser) = browser() else { return };
    let dir = scratch("t4-paste");
    project(&dir, &[0.0, 1.0, 2.0], 800)
        .write(&dir.join("anim.json"))
        .expect("written");
    let studio = Studio::start(&dir, Some("anim.json"));
    let page = PageTab::open(&browser, &studio.url, &dir);
    page.settle();
    let pose_of = |k: usize| -> Vec<f64> {
        page.eval(&format!("Array.from(studio.ghosts.get({k}).pos)"))
            .as_array()
            .expect("pose")
            .iter()
            .map(|v| v.as_f64().expect("x"))
            .collect()
    };
    page.wait("studio.ghosts.size === 3", 10);
    let first = pose_of(0);
    let third = pose_of(2);
    assert_ne!(first, third);
    // Copy keyframe 1; go to keyframe 3 (on its time); paste: asked.
    page.click(on_ruler(&page, 0.0));
    page.settle();
    page.key("c", &[ModifierKey::Ctrl]);
    page.click(on_ruler(&page, 2.0));
    page.settle();
    assert_eq!(page.num("studio.state.current"), 2.0);
    page.key("v", &[ModifierKey::Ctrl]);
    page.wait("document.getElementById('confirm-dialog').open", 5);
    let question = page.eval("document.getElementById('confirm-text').textContent");
    assert!(
        question.as_str().expect("text").contains("Replace"),
        "{question}"
    );
    page.shot("t4-asked.png");
    page.click_on("#confirm-ok");
    page.wait(
        "studio.state.undo && studio.state.undo.includes('replaced')",
        10,
    );
    page.settle();
    assert_eq!(server_times(&studio), [0.0, 1.0, 2.0], "no keyframe added");
    page.wait(
        "studio.ghosts.get(2) && studio.ghosts.get(2).rev === studio.state.keyframes[2].rev",
        10,
    );
    assert_eq!(pose_of(2), first, "keyframe 3 has keyframe 1's pose");
    page.undo();
    page.wait(
        "studio.ghosts.get(2) && studio.ghosts.get(2).rev === studio.state.keyframes[2].rev",
        10,
    );
    assert_eq!(pose_of(2), third, "undone in one step");
    // Copied again (an edit of the keyframes asks for a new copy), inserted after: a frame
    // later.
    let copy_first_paste_on_third = || {
        page.click(on_ruler(&page, 0.0));
        page.settle();
        page.key("c", &[ModifierKey::Ctrl]);
        page.click(on_ruler(&page, 2.0));
        page.settle();
        page.key("v", &[ModifierKey::Ctrl]);
    };
    copy_first_paste_on_third();
    page.wait("document.getElementById('confirm-dialog').open", 5);
    page.click_on("#confirm-other");
    page.wait("studio.state.keyframes.length === 4", 10);
    page.settle();
    assert_eq!(server_times(&studio), [0.0, 1.0, 2.0, 2.04]);
    page.undo();
    assert_eq!(server_times(&studio), [0.0, 1.0, 2.0]);
    // Cancel does nothing.
    copy_first_paste_on_third();
    page.wait("document.getElementById('confirm-dialog').open", 5);
    page.click_on("#confirm-cancel");
    page.settle();
    assert_eq!(server_times(&studio), [0.0, 1.0, 2.0]);
    assert_eq!(page.eval("studio.state.undo"), serde_json::Value::Null);
}

/// Traced loops: Shift+click selects a whole loop (drawn highlighted), Delete removes it in
/// one undo step, Undo brings it back; the other loops stay.
///
/// Before: only single points could be removed (right-click), or everything cleared.
#[test]
fn a_whole_outline_loop_is_selected_and_deleted() {
    let Some(browser) = browser() else { return };
    let dir = scratch("t5-loop");
    // The character and a ball beside it: two loops.
    let s = 400.0;
    let image = generate::picture(400, 400, |x, y| {
        let p = [x / s, y / s];
        let body = generate::capsule_distance(p, [0.45, 0.35], [0.45, 0.8], 0.12);
        let arm = generate::capsule_distance(p, [0.45, 0.45], [0.8, 0.3], 0.05);
        (s * body.min(arm)).min((x - 320.0).hypot(y - 320.0) - 35.0)
    });
    write_png(&dir.join("pic.png"), &image);
    let studio = Studio::start(&dir, Some("pic.png"));
    let page = PageTab::open(&browser, &studio.url, &dir);
    page.settle();
    page.click_on("#outline-mode");
    page.wait(
        "studio.state.mode === 'outline' && studio.outline.length === 2",
        20,
    );
    page.settle();
    let loops = page.eval("studio.outline");
    let (ball, body) = {
        let n = |i: usize| loops[i].as_array().expect("loop").len();
        if n(0) < n(1) {
            (0, 1)
        } else {
            (1, 0)
        }
    };
    let body_points = loops[body].clone();
    // Shift+click on a point of the ball's loop.
    let point = &loops[ball][0];
    let at = page.eval(&format!("studio.toPage({}, {})", point[0], point[1]));
    let at = [at[0].as_f64().expect("x"), at[1].as_f64().expect("y")];
    let magenta = |p: [u8; 3]| p[0] > 200 && p[1] < 90 && p[2] > 150;
    let before = page.shot("t5-before.png").count_in(page.canvas(), magenta);
    page.move_to(at, false);
    page.mouse(
        headless_chrome::protocol::cdp::Input::DispatchMouseEventTypeOption::MousePressed,
        at,
        Some(headless_chrome::protocol::cdp::Input::MouseButton::Left),
        1,
        Some(8),
    );
    page.mouse(
        headless_chrome::protocol::cdp::Input::DispatchMouseEventTypeOption::MouseReleased,
        at,
        Some(headless_chrome::protocol::cdp::Input::MouseButton::Left),
        0,
        Some(8),
    );
    page.wait("!document.getElementById('delete-loop').disabled", 5);
    assert_eq!(page.num("studio.selectedLoop.ring"), ball as f64);
    std::thread::sleep(Duration::from_millis(150));
    let selected = page
        .shot("t5-selected.png")
        .count_in(page.canvas(), magenta);
    assert!(
        selected > before + 500,
        "the loop selected is drawn highlighted: {before} -> {selected} magenta pixels"
    );
    // No point was added or moved by the Shift+click.
    assert_eq!(page.eval("studio.outline"), loops);
    page.key("Delete", &[]);
    page.wait("studio.outline.length === 1", 10);
    page.settle();
    assert_eq!(
        page.eval("studio.outline[0]"),
        body_points,
        "the other loop stays"
    );
    assert_eq!(
        page.num("studio.state.keyframes.length"),
        1.0,
        "no keyframe deleted"
    );
    assert!(page
        .eval("studio.state.undo")
        .as_str()
        .expect("undo")
        .contains("remove loop"));
    page.shot("t5-deleted.png");
    page.undo();
    page.wait("studio.outline.length === 2", 10);
    assert_eq!(
        page.eval("studio.outline"),
        loops,
        "undone: the loop is back in its place"
    );
    // The button does the same.
    page.mouse(
        headless_chrome::protocol::cdp::Input::DispatchMouseEventTypeOption::MousePressed,
        at,
        Some(headless_chrome::protocol::cdp::Input::MouseButton::Left),
        1,
        Some(8),
    );
    page.mouse(
        headless_chrome::protocol::cdp::Input::DispatchMouseEventTypeOption::MouseReleased,
        at,
        Some(headless_chrome::protocol::cdp::Input::MouseButton::Left),
        0,
        Some(8),
    );
    page.wait("!document.getElementById('delete-loop').disabled", 5);
    page.click_on("#delete-loop");
    page.wait("studio.outline.length === 1", 10);
}

/// The export dialog names the range it will export (the whole animation by default, as
/// `bdmorph export` makes it; the loop range a choice), and exports that many frames;
/// `bdmorph export --loop-range` makes the loop range's frames.
///
/// Before: with a loop range set, the dialog silently exported only the loop range, while
/// `bdmorph export` exported everything.
#[test]
fn the_export_dialog_names_its_range_and_exports_what_it_says() {
    let Some(browser) = browser() else { return };
    let dir = scratch("t6-export-range");
    let mut doc = project(&dir, &[0.0, 2.0, 4.0], 600);
    doc.loop_range = Some([1.0, 2.0]);
    doc.write(&dir.join("anim.json")).expect("written");
    let studio = Studio::start(&dir, Some("anim.json"));
    let page = PageTab::open(&browser, &studio.url, &dir);
    page.settle();
    page.set_value("#export-format", "obj");
    page.set_value("#export-name", "whole");
    page.click_on("#export-open");
    page.wait("document.getElementById('export-dialog').open", 5);
    let said = page.eval("document.getElementById('export-range-text').textContent");
    assert_eq!(said, "0.00-4.00 s, 101 frames");
    page.shot("t6-dialog.png");
    page.click_on("#export");
    page.wait(
        "document.getElementById('notes').textContent.includes('exported')",
        60,
    );
    assert_eq!(
        std::fs::read_dir(dir.join("whole"))
            .expect("folder")
            .count(),
        101
    );
    // The loop range, chosen.
    page.set_value("#export-name", "looped");
    page.click_on("#export-open");
    page.set_value("#export-range", "loop");
    let said = page.eval("document.getElementById('export-range-text').textContent");
    assert_eq!(said, "1.00-2.00 s, 26 frames");
    page.click_on("#export");
    page.wait(
        "studio.state.notes.filter((n) => n.text.includes('exported')).length >= 2",
        60,
    );
    assert_eq!(
        std::fs::read_dir(dir.join("looped"))
            .expect("folder")
            .count(),
        26
    );
    // The command line: the whole animation by default, the loop range on request.
    let run = |args: &[&str]| {
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_bdmorph"))
            .args(args)
            .current_dir(&dir)
            .status()
            .expect("runs");
        assert!(status.success(), "{args:?}");
    };
    run(&[
        "export",
        "anim.json",
        "--format",
        "obj",
        "-q",
        "-o",
        "cli-whole",
    ]);
    run(&[
        "export",
        "anim.json",
        "--format",
        "obj",
        "-q",
        "--loop-range",
        "-o",
        "cli-loop",
    ]);
    let count = |d: &str| std::fs::read_dir(dir.join(d)).expect("folder").count();
    assert_eq!((count("cli-whole"), count("cli-loop")), (101, 26));
    for i in [0, 13, 25] {
        let name = format!("frame_{i:04}.obj");
        let cli = std::fs::read(dir.join("cli-loop").join(&name)).expect("cli frame");
        let page_frame = std::fs::read(dir.join("looped").join(&name)).expect("page frame");
        assert_eq!(cli, page_frame, "{name}: the same frames");
    }
}

/// The drawing dialog: as pairs are clicked, both pictures stay where they are under the
/// mouse (the dialog does not grow or re-centre with the pairs listed or the status said).
///
/// Before: the list of pairs and the status grew the dialog, which the browser re-centres, so
/// the pictures moved between clicks.
#[test]
fn the_drawing_dialog_keeps_both_pictures_still_as_pairs_are_added() {
    let Some(browser) = browser() else { return };
    let dir = scratch("t7-drawing");
    write_png(&dir.join("pic.png"), &character());
    let drawn = generate::picture(300, 400, |x, y| {
        let s = 400.0;
        let p = [x / s, y / s];
        let body = generate::capsule_distance(p, [0.35, 0.35], [0.35, 0.8], 0.12);
        let arm = generate::capsule_distance(p, [0.35, 0.45], [0.6, 0.2], 0.05);
        s * body.min(arm)
    });
    write_png(&dir.join("drawn.png"), &drawn);
    let studio = Studio::start(&dir, Some("pic.png"));
    let page = PageTab::open(&browser, &studio.url, &dir);
    page.settle();
    page.eval("(document.getElementById('drawing-open').click(), true)");
    page.wait("document.getElementById('drawing-dialog').open", 5);
    page.wait(
        "document.getElementById('drawing-name').options.length > 1",
        10,
    );
    page.set_value("#drawing-name", "drawn.png");
    std::thread::sleep(Duration::from_millis(800));
    let rects = || (page.rect("#drawing-rest"), page.rect("#drawing-new"));
    let start = rects();
    let mut moved = 0.0f64;
    for i in 0..6 {
        let (a, b) = rects();
        let f = 0.3 + 0.07 * i as f64;
        page.click([a[0] + (a[2] - a[0]) * f, a[1] + (a[3] - a[1]) * 0.5]);
        std::thread::sleep(Duration::from_millis(100));
        let (a2, b2) = rects();
        page.click([b2[0] + (b2[2] - b2[0]) * f, b2[1] + (b2[3] - b2[1]) * 0.5]);
        // The preview of the matching comes and goes: wait for it.
        std::thread::sleep(Duration::from_millis(700));
        let (a3, b3) = rects();
        for (x, y) in [(a, a2), (a2, a3), (b, b2), (b2, b3)] {
            for k in 0..4 {
                moved = moved.max((x[k] - y[k]).abs());
            }
        }
    }
    page.shot("t7-pairs.png");
    assert_eq!(
        page.num("document.getElementById('drawing-pairs').children.length"),
        6.0
    );
    let end = rects();
    assert!(
        moved < 0.5 && start == end,
        "the pictures moved by up to {moved} px as pairs were added: {start:?} -> {end:?}"
    );
}
