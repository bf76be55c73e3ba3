//! Rigs in the studio, in a real browser (Debian's Chromium, real mouse and keyboard): a
//! character painted with its torso under its arms is joined at the shoulders; joints added,
//! moved and removed by hand, each undone and redone, and posing pivots about the moved joint;
//! a click picks the part drawn in front; pins are drawn only where they are.
//!
//! Without Chromium the tests are skipped, except in CI (`CI` set). Screenshots go to a
//! scratch folder, and are kept.

mod layered;
mod studio_common;
mod studio_page;

use std::path::Path;

use bdmorph::studio::project::Project;
use headless_chrome::browser::tab::ModifierKey;
use studio_common::{scratch, Studio};
use studio_page::*;

/// The canvas height of the layered test pictures (rows from the top there, y up in the mesh).
const H: f64 = layered::FIGURE_SIZE.1 as f64;

/// The server's document, saved to `name` through a socket of the test's own.
fn document(studio: &Studio, dir: &Path, name: &str) -> Project {
    let mut c = studio.client();
    let request = serde_json::json!({"op": "save", "name": name, "overwrite": true}).to_string();
    assert_eq!(c.request(&request), None);
    Project::from_json(&std::fs::read(dir.join(name)).expect("saved")).expect("project")
}

/// The studio opened on the torso painted under two arms, a page on it.
fn open_character(
    name: &str,
) -> Option<(
    headless_chrome::Browser,
    Studio,
    PageTab,
    std::path::PathBuf,
)> {
    let browser = browser()?;
    let dir = scratch(name);
    let (layers, _) = layered::torso_under_arms();
    std::fs::write(dir.join("figure.psd"), layered::write_psd(&layers)).expect("psd");
    let studio = Studio::start(&dir, Some("figure.psd"));
    let page = PageTab::open(&browser, &studio.url, &dir);
    page.wait(
        "!!studio.texture && !!studio.state && !!studio.state.parts",
        30,
    );
    if page.eval("document.getElementById('edges').checked") == true {
        page.click_on("#edges");
    }
    page.settle();
    Some((browser, studio, page, dir))
}

/// The vertex range `[first, end)` of the part named `name`.
fn part_range(page: &PageTab, name: &str) -> [usize; 2] {
    let r = page.eval(&format!(
        "studio.state.parts.find((p) => p.name === '{name}').vertices"
    ));
    [0, 1].map(|i| r[i].as_u64().expect("vertex") as usize)
}

/// The joints as the page holds them.
fn joints(page: &PageTab) -> Vec<[usize; 2]> {
    page.eval("studio.state.joints || []")
        .as_array()
        .expect("joints")
        .iter()
        .map(|j| [0, 1].map(|i| j[i].as_u64().expect("vertex") as usize))
        .collect()
}

/// A vertex's rest point, in the picture's pixels (rows from the top).
fn rest_pixel(page: &PageTab, v: usize) -> [f64; 2] {
    let x = page.num(&format!("studio.rest[{}]", 2 * v));
    let y = page.num(&format!("studio.rest[{}]", 2 * v + 1));
    [x, H - y]
}

/// Where a point of the picture (pixels, rows from the top) is on the page, on the rest shape.
fn on_page(page: &PageTab, p: [f64; 2]) -> [f64; 2] {
    let q = page.eval(&format!("studio.toPage({}, {})", p[0], H - p[1]));
    [q[0].as_f64().expect("x"), q[1].as_f64().expect("y")]
}

/// The joint tying a vertex of `range`, if any: its index.
fn joint_on(page: &PageTab, range: [usize; 2]) -> Option<usize> {
    joints(page)
        .iter()
        .position(|j| j.iter().any(|&v| v >= range[0] && v < range[1]))
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Waits for the history to reach `steps` and the page to settle.
fn wait_steps(page: &PageTab, steps: f64) {
    page.wait(
        &format!("studio.state.history.steps === {steps} && !studio.busy()"),
        30,
    );
    std::thread::sleep(std::time::Duration::from_millis(100));
}

fn redo(page: &PageTab) {
    let before = page.num("studio.state.history.steps");
    page.key("z", &[ModifierKey::Ctrl, ModifierKey::Shift]);
    wait_steps(page, before + 1.0);
}

/// The left arm's point on its centre line at column `x` (it runs from (135, 95) to (60, 130)).
fn on_left_arm(x: f64) -> [f64; 2] {
    let t = (135.0 - x) / 75.0;
    [x, 95.0 + 35.0 * t]
}

/// Item: automatic joints at the shoulders; a joint removed, added and moved by hand with the
/// joints tool, each undone and redone; posing pivots about the moved joint; saved, played and
/// rendered by the command line with it.
#[test]
fn joints_sit_at_the_shoulders_and_are_added_moved_and_removed_by_hand() {
    let Some((_browser, studio, page, dir)) = open_character("rigs-joints") else {
        return;
    };
    let (_, shoulders) = layered::torso_under_arms();
    page.shot("rigs-0-opened.png");
    assert_eq!(page.num("studio.state.parts.length"), 3.0);
    assert_eq!(joints(&page).len(), 2, "one joint per arm");
    let arm = part_range(&page, "arm_l");
    for (name, (shoulder, width)) in ["arm_l", "arm_r"].iter().zip(shoulders) {
        let range = part_range(&page, name);
        let j = joint_on(&page, range).unwrap_or_else(|| panic!("no joint on {name}"));
        let at = rest_pixel(&page, joints(&page)[j][0]);
        let off = distance(at, shoulder);
        eprintln!("{name}: automatic joint at {at:?}, {off:.2} px from the shoulder {shoulder:?}");
        assert!(
            off <= 0.1 * width,
            "{name}: the joint is {off:.2} px from the shoulder, over a tenth of the arm's width {width}"
        );
    }

    // The joints tool: the joints are drawn large, to be grabbed.
    page.key("j", &[]);
    page.wait("studio.tool === 'joints'", 10);
    page.settle();
    let steps = page.num("studio.state.history.steps");

    // Removed: a right-click on the left shoulder's joint.
    let j = joint_on(&page, arm).expect("left joint");
    let marker = page.vertex(joints(&page)[j][0]);
    page.right_click(marker);
    wait_steps(&page, steps + 1.0);
    assert_eq!(joints(&page).len(), 1);
    assert_eq!(joint_on(&page, arm), None, "the left arm is free");
    page.undo();
    assert_eq!(joints(&page).len(), 2, "undone: the joint is back");
    redo(&page);
    assert_eq!(joint_on(&page, arm), None, "redone: removed again");

    // Added: a click where the arm lies over the torso, well inside, at its root.
    let first = on_left_arm(133.0);
    page.click(on_page(&page, first));
    wait_steps(&page, steps + 2.0);
    let j = joint_on(&page, arm).expect("a joint added on the left arm");
    let pair = joints(&page)[j];
    let torso = part_range(&page, "torso");
    assert!(
        pair.iter().any(|&v| v >= torso[0] && v < torso[1]),
        "the joint ties the arm to the torso"
    );
    let at = rest_pixel(&page, pair[0]);
    assert!(
        distance(at, first) < 1.0,
        "the joint is where it was clicked: {at:?}"
    );
    assert_eq!(rest_pixel(&page, pair[1]), at, "its vertices coincide");
    page.shot("rigs-1-added.png");
    page.undo();
    assert_eq!(joint_on(&page, arm), None, "undone: no joint on the arm");
    redo(&page);
    assert!(joint_on(&page, arm).is_some(), "redone: the joint is back");

    // Moved: dragged to the shoulder (its marker follows the mouse).
    let j = joint_on(&page, arm).expect("joint");
    let from = page.vertex(joints(&page)[j][0]);
    let shoulder = on_left_arm(121.0);
    page.drag(from, on_page(&page, shoulder), 20);
    wait_steps(&page, steps + 3.0);
    let j = joint_on(&page, arm).expect("the moved joint");
    let moved = rest_pixel(&page, joints(&page)[j][0]);
    assert!(distance(moved, shoulder) < 1.0, "moved to {moved:?}");
    assert_eq!(joints(&page).len(), 2);
    page.shot("rigs-2-moved.png");
    page.undo();
    let j = joint_on(&page, arm).expect("joint");
    assert!(
        distance(rest_pixel(&page, joints(&page)[j][0]), first) < 1.0,
        "undone: back where it was added"
    );
    redo(&page);
    let j = joint_on(&page, arm).expect("joint");
    assert!(distance(rest_pixel(&page, joints(&page)[j][0]), shoulder) < 1.0);

    // Posing pivots about the moved joint: a second keyframe, the torso's lower corners
    // pinned, the hand raised. At the moved joint the arm and the torso hold together; where
    // the joint was before, the arm's point and the torso's (both still there, now free of
    // each other) come apart as the arm turns about the shoulder.
    page.key("d", &[]);
    page.click_on("#add-key");
    page.wait(
        "studio.state.current === 1 && studio.showing === 'pose'",
        20,
    );
    let torso = part_range(&page, "torso");
    let arm = part_range(&page, "arm_l");
    let extreme = |range: [usize; 2], key: &str| {
        page.num(&format!(
            "(() => {{ let best = -1, bk = Infinity; for (let v = {}; v < {}; v++) {{ const x = studio.rest[2 * v], y = studio.rest[2 * v + 1]; const k = {key}; if (k < bk) {{ bk = k; best = v; }} }} return best; }})()",
            range[0], range[1]
        )) as usize
    };
    let nearest = |range: [usize; 2], p: [f64; 2]| {
        extreme(
            range,
            &format!("Math.hypot(x - {}, y - {})", p[0], H - p[1]),
        )
    };
    for corner in [extreme(torso, "y - x"), extreme(torso, "y + x")] {
        page.click(page.vertex(corner));
        page.wait(&format!("studio.pins.includes({corner})"), 20);
    }
    let hand = extreme(arm, "x");
    let j = joints(&page)[joint_on(&page, arm).expect("joint")];
    let (arm_joint, torso_joint) = if j[0] >= arm[0] && j[0] < arm[1] {
        (j[0], j[1])
    } else {
        (j[1], j[0])
    };
    let (arm_old, torso_old) = (nearest(arm, at), nearest(torso, at));
    for v in [arm_old, torso_old] {
        assert_eq!(
            rest_pixel(&page, v),
            at,
            "the vertices made for the first joint"
        );
    }
    let from = page.vertex(hand);
    page.drag(from, [from[0] + 30.0, from[1] - 80.0], 40);
    page.wait(&format!("studio.pins.includes({hand})"), 20);
    page.settle();
    page.shot("rigs-3-posed.png");
    let doc = document(&studio, &dir, "figure.json");
    let (rest, posed) = (&doc.mesh.positions, &doc.keyframes[1].positions);
    let apart = |a: usize, b: usize| distance(posed[a], posed[b]);
    eprintln!(
        "posed: the hand moved {:.1} px; arm and torso apart by {:.3} px at the moved joint, {:.2} px where the joint was",
        distance(rest[hand], posed[hand]),
        apart(arm_joint, torso_joint),
        apart(arm_old, torso_old)
    );
    assert!(
        distance(rest[hand], posed[hand]) > 40.0,
        "the hand was raised"
    );
    assert!(
        apart(arm_joint, torso_joint) < 1e-9,
        "the moved joint holds"
    );
    assert!(
        apart(arm_old, torso_old) > 2.0,
        "the arm turns about the moved joint, not where the joint was"
    );
    // Saved with the document, held in the pose.
    let saved = doc.joints.as_ref().expect("joints saved");
    assert_eq!(saved.len(), 2);
    for &[a, b] in saved {
        assert!(distance(posed[a as usize], posed[b as usize]) < 1e-9);
    }
    // Played: halfway, every joint holds (to the page's f32 precision).
    page.slide_to(0.5);
    page.wait("studio.showing === 'frame'", 20);
    page.settle();
    let gap = page.num(
        "Math.max(...studio.state.joints.map(([a, b]) => Math.hypot(studio.pose[2 * a] - studio.pose[2 * b], studio.pose[2 * a + 1] - studio.pose[2 * b + 1])))",
    );
    assert!(gap < 1e-3, "joints apart by {gap} pixels halfway");
    // Rendered by the command line from the saved project.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_bdmorph"))
        .current_dir(&dir)
        .args(["render", "figure.json", "-o", "cli.png", "--sheet"])
        .args(["--background", "transparent", "--size", "150x120"])
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Item: a click where the arm is drawn over the torso picks the arm (the part in front), even
/// on a vertex of the torso hidden under it.
#[test]
fn a_click_picks_the_part_drawn_in_front() {
    let Some((_browser, _studio, page, _dir)) = open_character("rigs-pick") else {
        return;
    };
    let torso = part_range(&page, "torso");
    let arm = part_range(&page, "arm_l");
    // A torso vertex under the left arm, away from the arm's own vertices and its outline.
    let hidden = page.num(&format!(
        "(() => {{ let best = -1, bd = -1; for (let v = {}; v < {}; v++) {{ const x = studio.rest[2 * v], y = {H} - studio.rest[2 * v + 1]; const t = Math.max(0, Math.min(1, ((x - 135) * -75 + (y - 95) * 35) / (75 * 75 + 35 * 35))); const d = Math.hypot(x - (135 - 75 * t), y - (95 + 35 * t)); if (d > 7 || x < 123 || t <= 0) continue; let near = Infinity; for (let w = {}; w < {}; w++) near = Math.min(near, Math.hypot(studio.rest[2 * w] - studio.rest[2 * v], studio.rest[2 * w + 1] - studio.rest[2 * v + 1])); if (near > bd) {{ bd = near; best = v; }} }} return best; }})()",
        torso[0], torso[1], arm[0], arm[1]
    )) as usize;
    assert!(
        hidden >= torso[0] && hidden < torso[1],
        "a torso vertex under the arm"
    );
    page.click(page.vertex(hidden));
    page.wait("studio.pins.length === 1 && !studio.busy()", 20);
    page.settle();
    page.shot("rigs-pick.png");
    let pin = page.num("studio.pins[0]") as usize;
    assert!(
        pin >= arm[0] && pin < arm[1],
        "the pin lands on the arm drawn in front (vertex {pin}), not the torso under it (vertex {hidden})"
    );
}

/// Pin-red pixels in the canvas farther than `r` from every point of `marks` (page pixels).
fn red_off(shot: &Shot, canvas: [f64; 4], marks: &[[f64; 2]], r: f64) -> usize {
    let height = shot.rgb.len() / shot.width;
    let mut n = 0;
    for y in (canvas[1].max(0.0) as usize)..(canvas[3] as usize).min(height) {
        for x in (canvas[0].max(0.0) as usize)..(canvas[2] as usize).min(shot.width) {
            if pin_red(shot.rgb[y * shot.width + x])
                && marks
                    .iter()
                    .all(|m| (m[0] - x as f64).hypot(m[1] - y as f64) > r)
            {
                n += 1;
            }
        }
    }
    n
}

/// Item: pins are drawn where they are. On the keyframe, each on its vertex; on a frame
/// between keyframes (scrubbed to with the mouse, or stepped to with the arrow keys), none
/// off the mesh: a marker, if any, sits on a pinned vertex where it is drawn now; and after
/// another tab deletes the keyframe, no stale pin stays on the keyframe shown.
#[test]
fn pins_are_drawn_only_where_they_are() {
    let Some((browser, studio, page, dir)) = open_character("rigs-pins") else {
        return;
    };
    // A second keyframe: the torso's lower corners pinned, the left hand raised.
    page.click_on("#add-key");
    page.wait(
        "studio.state.current === 1 && studio.showing === 'pose'",
        20,
    );
    let torso = part_range(&page, "torso");
    let arm = part_range(&page, "arm_l");
    let extreme = |range: [usize; 2], key: &str| {
        page.num(&format!(
            "(() => {{ let best = -1, bk = Infinity; for (let v = {}; v < {}; v++) {{ const x = studio.rest[2 * v], y = studio.rest[2 * v + 1]; const k = {key}; if (k < bk) {{ bk = k; best = v; }} }} return best; }})()",
            range[0], range[1]
        )) as usize
    };
    for corner in [extreme(torso, "y - x"), extreme(torso, "y + x")] {
        page.click(page.vertex(corner));
        page.wait(&format!("studio.pins.includes({corner})"), 20);
    }
    let hand = extreme(arm, "x");
    let from = page.vertex(hand);
    page.drag(from, [from[0] + 30.0, from[1] - 110.0], 40);
    page.wait(&format!("studio.pins.includes({hand})"), 20);
    page.settle();
    let pins: Vec<usize> = page
        .eval("studio.pins")
        .as_array()
        .expect("pins")
        .iter()
        .map(|v| v.as_u64().expect("pin") as usize)
        .collect();
    assert_eq!(pins.len(), 3);
    let canvas = page.canvas();
    let marks = |page: &PageTab| pins.iter().map(|&v| page.vertex(v)).collect::<Vec<_>>();
    // On the keyframe: every pin drawn, on its vertex.
    let shot = page.shot("rigs-pins-0-key.png");
    let on_key = marks(&page);
    for m in &on_key {
        assert!(
            shot.count_near(*m, 5.0, pin_red) > 10,
            "a pin drawn at {m:?}"
        );
    }
    // (A pin's disc is over 100 pixels; a few pixels of a piece's red-orange outline may
    // pass for pin red.)
    let stray = red_off(&shot, canvas, &on_key, 9.0);
    assert!(stray < 30, "no red off the pins: {stray} pixels");

    // Between the keyframes, scrubbed to with the mouse and stepped to with the arrow key.
    for (step, how) in ["scrubbed", "stepped"].iter().enumerate() {
        if step == 0 {
            page.slide_to(0.4);
        } else {
            page.key("ArrowLeft", &[]);
        }
        page.wait("studio.showing === 'frame' && !studio.busy()", 20);
        page.settle();
        let shot = page.shot(&format!("rigs-pins-1-{how}.png"));
        let now = marks(&page);
        let off = red_off(&shot, canvas, &now, 9.0);
        eprintln!("{how}: {off} pin-red pixels off the pinned vertices");
        assert!(off < 30, "{how}: pins drawn off the mesh ({off} pixels)");
        // The keyframe's pins are not where the frame's vertices are: the hand has moved.
        assert!(distance(now[2], on_key[2]) > 10.0);
    }

    // Back on the keyframe, another tab deletes it: this page shows the first keyframe and
    // draws no pin (it has none).
    page.key("End", &[]);
    page.wait(
        "studio.showing === 'pose' && studio.state.current === 1 && studio.pins.length === 3",
        20,
    );
    page.settle();
    let other = PageTab::open(&browser, &studio.url, &dir);
    other.wait("studio.state.current === 1", 20);
    other.key("Delete", &[]);
    page.wait("studio.state.keyframes.length === 1 && !studio.busy()", 20);
    page.settle();
    let shot = page.shot("rigs-pins-2-deleted-elsewhere.png");
    assert_eq!(page.num("studio.pins.length"), 0.0);
    let stale = shot.count_in(canvas, pin_red);
    assert!(
        stale < 30,
        "no stale pin on the keyframe shown ({stale} pixels)"
    );
}
