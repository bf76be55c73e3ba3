//! The studio in a real browser: Debian's Chromium, headless, driven over the DevTools
//! protocol (headless_chrome). Mouse events go through the browser's input pipeline, as a
//! user's would; screenshots are decoded and checked for what they must show; exported files
//! are decoded.
//!
//! Without Chromium the tests are skipped, except in CI (`CI` set), where they fail: CI
//! installs Chromium. Screenshots go to a scratch folder, printed, and kept.

use std::ffi::OsStr;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use bdmorph::generate;
use bdmorph::render::raster;
use headless_chrome::protocol::cdp::{Input, Page};
use headless_chrome::{Browser, LaunchOptions, Tab};

fn find_chromium() -> Option<PathBuf> {
    let fixed = Path::new("/usr/bin/chromium");
    if fixed.is_file() {
        return Some(fixed.into());
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|dir| ["chromium", "chromium-browser"].map(|name| dir.join(name)))
        .find(|p| p.is_file())
}

/// Chromium, or `None` (after saying so) when it is missing outside CI.
fn chromium() -> Option<PathBuf> {
    let found = find_chromium();
    if found.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "chromium is not installed, but CI must have it (.ci/run installs it with apt-get)"
        );
        eprintln!("studio_browser: chromium not found; skipping (CI installs it)");
    }
    found
}

/// A running studio, stopped when dropped.
struct Studio {
    child: Child,
    url: String,
}

impl Studio {
    fn start(dir: &Path, file: &str) -> Studio {
        let mut child = Command::new(env!("CARGO_BIN_EXE_bdmorph"))
            .args(["studio", file])
            .current_dir(dir)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("starts");
        let mut line = String::new();
        BufReader::new(child.stdout.take().expect("stdout"))
            .read_line(&mut line)
            .expect("the URL line");
        assert!(line.starts_with("http://127.0.0.1:"), "{line}");
        Studio {
            child,
            url: line.trim().to_owned(),
        }
    }
}

impl Drop for Studio {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn browser(chromium: PathBuf) -> Browser {
    let args: Vec<&OsStr> = vec![
        OsStr::new("--disable-gpu"),
        OsStr::new("--hide-scrollbars"),
        OsStr::new("--force-device-scale-factor=1"),
        // A test's tab is not the window's front tab: no background throttling of its timers,
        // rendering or tasks, as for the page a user is looking at.
        OsStr::new("--disable-background-timer-throttling"),
        OsStr::new("--disable-renderer-backgrounding"),
        OsStr::new("--disable-backgrounding-occluded-windows"),
    ];
    let options = LaunchOptions::default_builder()
        .path(Some(chromium))
        .headless(true)
        .sandbox(false)
        .window_size(Some((1280, 900)))
        .idle_browser_timeout(Duration::from_secs(300))
        .args(args)
        .build()
        .expect("launch options");
    Browser::new(options).expect("chromium starts")
}

/// The value of the JavaScript expression `js`, through JSON (arrays and objects by value).
fn eval(tab: &Tab, js: &str) -> serde_json::Value {
    let text = tab
        .evaluate(&format!("JSON.stringify(({js}))"), false)
        .unwrap_or_else(|e| panic!("{js}: {e}"))
        .value;
    match text {
        Some(serde_json::Value::String(t)) => {
            serde_json::from_str(&t).unwrap_or(serde_json::Value::Null)
        }
        _ => serde_json::Value::Null,
    }
}

fn eval_f64(tab: &Tab, js: &str) -> f64 {
    eval(tab, js)
        .as_f64()
        .unwrap_or_else(|| panic!("{js}: not a number"))
}

/// The value of an expression that is a promise, once it resolves.
fn eval_async(tab: &Tab, js: &str) -> serde_json::Value {
    let text = tab
        .evaluate(
            &format!("(async () => JSON.stringify(await ({js})))()"),
            true,
        )
        .unwrap_or_else(|e| panic!("{js}: {e}"))
        .value;
    match text {
        Some(serde_json::Value::String(t)) => {
            serde_json::from_str(&t).unwrap_or(serde_json::Value::Null)
        }
        _ => serde_json::Value::Null,
    }
}

/// Waits until `js` is true (at most `seconds`).
fn wait_for(tab: &Tab, js: &str, seconds: u64) {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(seconds) {
        if eval(tab, js) == serde_json::Value::Bool(true) {
            return;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let status = eval(tab, "document.getElementById('status').textContent");
    panic!("timed out waiting for {js} (status: {status})");
}

fn mouse(tab: &Tab, kind: Input::DispatchMouseEventTypeOption, at: [f64; 2], pressed: bool) {
    let button = if matches!(kind, Input::DispatchMouseEventTypeOption::MouseMoved) && !pressed {
        None
    } else {
        Some(Input::MouseButton::Left)
    };
    tab.call_method(Input::DispatchMouseEvent {
        Type: kind,
        x: at[0],
        y: at[1],
        modifiers: None,
        timestamp: None,
        button,
        buttons: Some(u32::from(pressed)),
        click_count: Some(1),
        force: None,
        tangential_pressure: None,
        tilt_x: None,
        tilt_y: None,
        twist: None,
        delta_x: None,
        delta_y: None,
        pointer_Type: None,
    })
    .expect("mouse event");
}

fn press(tab: &Tab, at: [f64; 2]) {
    mouse(
        tab,
        Input::DispatchMouseEventTypeOption::MouseMoved,
        at,
        false,
    );
    mouse(
        tab,
        Input::DispatchMouseEventTypeOption::MousePressed,
        at,
        true,
    );
}

fn release(tab: &Tab, at: [f64; 2]) {
    mouse(
        tab,
        Input::DispatchMouseEventTypeOption::MouseReleased,
        at,
        false,
    );
}

fn right_click(tab: &Tab, at: [f64; 2]) {
    for kind in [
        Input::DispatchMouseEventTypeOption::MousePressed,
        Input::DispatchMouseEventTypeOption::MouseReleased,
    ] {
        tab.call_method(Input::DispatchMouseEvent {
            Type: kind,
            x: at[0],
            y: at[1],
            modifiers: None,
            timestamp: None,
            button: Some(Input::MouseButton::Right),
            buttons: Some(2),
            click_count: Some(1),
            force: None,
            tangential_pressure: None,
            tilt_x: None,
            tilt_y: None,
            twist: None,
            delta_x: None,
            delta_y: None,
            pointer_Type: None,
        })
        .expect("mouse event");
    }
}

fn drag_through(tab: &Tab, from: [f64; 2], to: [f64; 2], moves: usize) {
    press(tab, from);
    for k in 1..=moves {
        let s = k as f64 / moves as f64;
        let at = [
            from[0] + (to[0] - from[0]) * s,
            from[1] + (to[1] - from[1]) * s,
        ];
        mouse(
            tab,
            Input::DispatchMouseEventTypeOption::MouseMoved,
            at,
            true,
        );
    }
    release(tab, to);
}

fn click_element(tab: &Tab, selector: &str) {
    tab.find_element(selector)
        .unwrap_or_else(|e| panic!("{selector}: {e}"))
        .click()
        .unwrap_or_else(|e| panic!("{selector}: {e}"));
}

/// The page position of vertex `v` as drawn now.
fn vertex_on_page(tab: &Tab, v: usize) -> [f64; 2] {
    let p = eval(tab, &format!("studio.vertexOnPage({v})"));
    [p[0].as_f64().expect("x"), p[1].as_f64().expect("y")]
}

/// An RGB screenshot, also written to `path`.
struct Shot {
    width: usize,
    rgb: Vec<[u8; 3]>,
}

impl Shot {
    fn take(tab: &Tab, path: &Path) -> Shot {
        let png = tab
            .capture_screenshot(Page::CaptureScreenshotFormatOption::Png, None, None, true)
            .expect("screenshot");
        std::fs::write(path, &png).expect("write screenshot");
        let image = raster::decode_image(&png).expect("a PNG");
        Shot {
            width: image.width as usize,
            rgb: image.rgba.chunks(4).map(|p| [p[0], p[1], p[2]]).collect(),
        }
    }

    /// Pixels in the rectangle (page pixels) satisfying `keep`.
    fn count_in(&self, rect: [f64; 4], keep: impl Fn([u8; 3]) -> bool) -> usize {
        let height = self.rgb.len() / self.width;
        let [x0, y0, x1, y1] = rect.map(|v| v.max(0.0) as usize);
        let mut n = 0;
        for y in y0..y1.min(height) {
            for x in x0..x1.min(self.width) {
                if keep(self.rgb[y * self.width + x]) {
                    n += 1;
                }
            }
        }
        n
    }

    fn differing(&self, other: &Shot, rect: [f64; 4]) -> usize {
        let height = self.rgb.len() / self.width;
        let [x0, y0, x1, y1] = rect.map(|v| v.max(0.0) as usize);
        let mut n = 0;
        for y in y0..y1.min(height) {
            for x in x0..x1.min(self.width) {
                let (a, b) = (self.rgb[y * self.width + x], other.rgb[y * self.width + x]);
                if a.iter().zip(&b).any(|(p, q)| p.abs_diff(*q) > 40) {
                    n += 1;
                }
            }
        }
        n
    }
}

/// The canvas's rectangle on the page.
fn canvas_rect(tab: &Tab) -> [f64; 4] {
    let r = eval(
        tab,
        "(() => { const r = document.getElementById('view').getBoundingClientRect(); return [r.left, r.top, r.right, r.bottom]; })()",
    );
    [0, 1, 2, 3].map(|i| r[i].as_f64().expect("rect"))
}

/// The dark end of the distortion ramp (distortion 1): (68, 1, 84) and its neighbours.
fn undistorted(p: [u8; 3]) -> bool {
    p[0] < 170 && p[1] < 120 && p[2] > 60 && p[2] > p[1] + 30
}

/// Ramp colours of real distortion: teal, green or yellow (not greys).
fn distorted(p: [u8; 3]) -> bool {
    let (r, g, b) = (i32::from(p[0]), i32::from(p[1]), i32::from(p[2]));
    (g > r + 40 && g > 110) || (r > 200 && g > 180 && b < 120)
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "bdmorph-studio-browser-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// A picture with one subject: a body and a raised arm (capsules), on transparency.
fn write_picture(dir: &Path) {
    let s = 400.0;
    let image = generate::picture(400, 400, |x, y| {
        let p = [x / s, y / s];
        let body = generate::capsule_distance(p, [0.45, 0.35], [0.45, 0.8], 0.12);
        let arm = generate::capsule_distance(p, [0.45, 0.45], [0.8, 0.3], 0.05);
        s * body.min(arm)
    });
    std::fs::write(
        dir.join("pic.png"),
        raster::encode_png(&image).expect("png"),
    )
    .expect("write");
}

/// The page's pose as numbers.
fn pose(tab: &Tab) -> Vec<f64> {
    eval(tab, "Array.from(studio.pose)")
        .as_array()
        .expect("pose")
        .iter()
        .map(|v| v.as_f64().expect("number"))
        .collect()
}

/// Moves the time slider to `fraction` of its length with the mouse.
fn slide_to(tab: &Tab, fraction: f64) {
    let r = eval(
        tab,
        "(() => { const r = document.getElementById('time').getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; })()",
    );
    let [left, top, width, height] = [0, 1, 2, 3].map(|i| r[i].as_f64().expect("rect"));
    // The thumb's centre runs from half a thumb in from either end; Chromium's is 16 px.
    let x = left + 8.0 + fraction * (width - 16.0);
    let at = [x, top + height / 2.0];
    press(tab, at);
    release(tab, at);
}

#[test]
fn a_picture_becomes_a_posed_keyframed_exported_and_reopened_animation() {
    let Some(chromium) = chromium() else { return };
    let dir = scratch("workflow");
    eprintln!("studio_browser: screenshots and files in {}", dir.display());
    write_picture(&dir);
    let studio = Studio::start(&dir, "pic.png");
    let browser = browser(chromium.clone());
    let tab = browser.new_tab().expect("tab");
    tab.set_default_timeout(Duration::from_secs(60));
    tab.navigate_to(&studio.url).expect("navigates");
    tab.wait_until_navigated().expect("loaded");
    wait_for(&tab, "!!(window.studio && studio.pose && studio.state)", 30);
    let n = eval_f64(&tab, "studio.n") as usize;
    assert!(n > 500, "the picture was meshed: {n} vertices");
    let rect = canvas_rect(&tab);

    // The picture opens drawn on its mesh (WebGL), then, with the texture turned off,
    // coloured by distortion: dark (undistorted) triangles over a good part of the canvas.
    assert_eq!(eval(&tab, "studio.renderer"), "webgl2");
    wait_for(&tab, "!!studio.texture", 10);
    let pictured = Shot::take(&tab, &dir.join("0-picture.png"));
    let area = (rect[2] - rect[0]) * (rect[3] - rect[1]);
    let bluish = pictured.count_in(rect, |p| p[2] > 150 && p[0] < 200 && p[1] < 200);
    assert!(
        bluish as f64 > 0.01 * area,
        "the picture is drawn: {bluish} pixels"
    );
    click_element(&tab, "#texture");
    wait_for(&tab, "!document.getElementById('texture').checked", 5);
    let first = Shot::take(&tab, &dir.join("1-opened.png"));
    let dark = first.count_in(rect, undistorted);
    assert!(dark as f64 > 0.02 * area, "{dark} dark pixels of {area}");
    assert_eq!(
        first.count_in(rect, distorted),
        0,
        "nothing distorted at rest"
    );

    // A new keyframe (a copy of the rest pose at 1 s), posed: the body's bottom held, the
    // hand dragged up, by the mouse.
    click_element(&tab, "#add-key");
    wait_for(
        &tab,
        "studio.state.keyframes.length === 2 && studio.state.current === 1",
        10,
    );
    let lowest = eval_f64(
        &tab,
        "(() => { let b = 0; for (let v = 0; v < studio.n; v++) if (studio.pose[2*v+1] < studio.pose[2*b+1]) b = v; return b; })()",
    ) as usize;
    let hand = eval_f64(
        &tab,
        "(() => { let b = 0; for (let v = 0; v < studio.n; v++) if (studio.pose[2*v] > studio.pose[2*b]) b = v; return b; })()",
    ) as usize;
    let at = vertex_on_page(&tab, lowest);
    press(&tab, at);
    release(&tab, at);
    wait_for(&tab, "studio.pins.length === 1", 10);
    let from = vertex_on_page(&tab, hand);
    let hand_before = [
        eval_f64(&tab, &format!("studio.pose[{}]", 2 * hand)),
        eval_f64(&tab, &format!("studio.pose[{}]", 2 * hand + 1)),
    ];
    let updates_before = eval_f64(&tab, "studio.stats.poseUpdates");
    drag_through(&tab, from, [from[0] - 40.0, from[1] - 120.0], 30);
    wait_for(&tab, "!studio.dragInFlight && !studio.dragWaiting", 20);
    let updates = eval_f64(&tab, "studio.stats.poseUpdates") - updates_before;
    assert!(updates >= 3.0, "{updates} pose updates during the drag");
    assert_eq!(eval_f64(&tab, "studio.pins.length"), 2.0);
    let hand_after = [
        eval_f64(&tab, &format!("studio.pose[{}]", 2 * hand)),
        eval_f64(&tab, &format!("studio.pose[{}]", 2 * hand + 1)),
    ];
    assert!(
        hand_after[1] > hand_before[1] + 50.0,
        "{hand_before:?} -> {hand_after:?}"
    );
    let posed = Shot::take(&tab, &dir.join("2-posed.png"));
    assert!(
        posed.differing(&first, rect) as f64 > 0.005 * area,
        "the picture changed"
    );
    assert!(
        posed.count_in(rect, distorted) > 50,
        "distortion colours show"
    );
    let posed_pose = pose(&tab);

    // Undo puts the rest pose back; redo the pose.
    click_element(&tab, "#undo");
    wait_for(
        &tab,
        &format!(
            "Math.abs(studio.pose[{}] - {}) < 1e-3",
            2 * hand + 1,
            hand_before[1]
        ),
        10,
    );
    click_element(&tab, "#redo");
    wait_for(
        &tab,
        &format!(
            "Math.abs(studio.pose[{}] - {}) < 1e-3",
            2 * hand + 1,
            hand_after[1]
        ),
        10,
    );

    // Scrub to the middle with the mouse: the frame is between the keyframes.
    slide_to(&tab, 0.5);
    wait_for(
        &tab,
        "studio.showing === 'frame' && !studio.scrubInFlight",
        20,
    );
    let middle = pose(&tab);
    let y_mid = middle[2 * hand + 1];
    assert!(
        y_mid > hand_before[1] + 5.0 && y_mid < hand_after[1] - 5.0,
        "{} < {y_mid} < {}",
        hand_before[1],
        hand_after[1]
    );
    Shot::take(&tab, &dir.join("3-scrubbed.png"));
    assert!(posed_pose != middle);

    // Play for a second: frames keep coming.
    let frames_before = eval_f64(&tab, "studio.stats.frameUpdates");
    click_element(&tab, "#play");
    std::thread::sleep(Duration::from_millis(1500));
    click_element(&tab, "#play");
    let played = eval_f64(&tab, "studio.stats.frameUpdates") - frames_before;
    assert!(played >= 10.0, "{played} frames in 1.5 s of playback");

    // Export a GIF and an MP4, save the project.
    for (format, name) in [("gif", "anim.gif"), ("mp4", "anim.mp4")] {
        eval(
            &tab,
            &format!(
                "(() => {{ const f = document.getElementById('export-format'); f.value = '{format}'; f.dispatchEvent(new Event('change')); document.getElementById('export-name').value = '{name}'; return true; }})()"
            ),
        );
        click_element(&tab, "#export");
        wait_for(
            &tab,
            &format!("document.getElementById('status').textContent.includes('exported') && document.getElementById('status').textContent.includes('{name}')"),
            120,
        );
    }
    let gif = std::fs::read(dir.join("anim.gif")).expect("the GIF");
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut reader = options.read_info(gif.as_slice()).expect("a GIF");
    let mut frames = 0;
    let mut textured = 0;
    while let Some(frame) = reader.read_next_frame().expect("a frame") {
        frames += 1;
        textured += frame
            .buffer
            .chunks(4)
            .filter(|p| p[3] > 0 && p[0] < 250)
            .count();
    }
    assert!(frames >= 20, "{frames} GIF frames (1 s at 25 fps)");
    assert!(textured > 1000, "the picture is drawn in the GIF");
    let mp4 = std::fs::read(dir.join("anim.mp4")).expect("the MP4");
    assert_eq!(&mp4[4..8], b"ftyp");
    if let Ok(out) = Command::new("ffprobe")
        .args(["-v", "error", "-count_frames", "-select_streams", "v:0"])
        .args(["-show_entries", "stream=nb_read_frames", "-of", "csv=p=0"])
        .arg(dir.join("anim.mp4"))
        .output()
    {
        let counted: usize = String::from_utf8_lossy(&out.stdout)
            .trim()
            .parse()
            .unwrap_or(0);
        assert_eq!(
            counted, frames,
            "the MP4 decodes to as many frames as the GIF"
        );
    }
    eval(
        &tab,
        "(document.getElementById('save-name').value = 'anim.json', true)",
    );
    click_element(&tab, "#save");
    wait_for(
        &tab,
        "document.getElementById('status').textContent.startsWith('saved')",
        20,
    );
    drop(tab);

    // Reopen the saved project in a new studio, scrub to the same place: the same frame.
    let again = Studio::start(&dir, "anim.json");
    let tab = browser.new_tab().expect("tab");
    tab.navigate_to(&again.url).expect("navigates");
    tab.wait_until_navigated().expect("loaded");
    wait_for(&tab, "!!(window.studio && studio.pose && studio.state)", 30);
    assert_eq!(eval_f64(&tab, "studio.state.keyframes.length"), 2.0);
    slide_to(&tab, 0.5);
    wait_for(
        &tab,
        "studio.showing === 'frame' && !studio.scrubInFlight",
        20,
    );
    assert_eq!(
        pose(&tab),
        middle,
        "the reopened project gives the same frame"
    );
    let reopened = Shot::take(&tab, &dir.join("4-reopened.png"));
    assert!(reopened.count_in(canvas_rect(&tab), undistorted) > 1000);
}

/// Drags at about 5K vertices and scrubs at about 10K, reporting updates per second end to
/// end (a request sent, computed, sent back, drawn), as measured by the page.
///
/// The mouse is driven from inside the page (DOM mouse and input events every 8 ms, for 3
/// seconds; the waits yield through a message channel, which background timers' throttling
/// does not slow), so the rate is the studio's and not the DevTools round trip's.
/// A picture of a disk with a square hole, on transparency (300 pixels square).
fn write_ring_picture(dir: &Path) {
    let image = generate::picture(300, 300, |x, y| {
        let (dx, dy) = (x - 150.0, y - 150.0);
        (dx.hypot(dy) - 120.0).max(30.0 - dx.abs().max(dy.abs()))
    });
    std::fs::write(
        dir.join("ring.png"),
        raster::encode_png(&image).expect("png"),
    )
    .expect("write");
}

/// The page position of outline loop `l`'s point `p`.
fn outline_point_on_page(tab: &Tab, l: usize, p: usize) -> [f64; 2] {
    let q = eval(
        tab,
        &format!("studio.toPage(...studio.outline.loops[{l}][{p}])"),
    );
    [q[0].as_f64().expect("x"), q[1].as_f64().expect("y")]
}

#[test]
fn the_outline_is_traced_edited_drawn_and_meshed_in_the_browser() {
    let Some(chromium) = chromium() else { return };
    let dir = scratch("outline");
    write_ring_picture(&dir);
    let studio = Studio::start(&dir, "ring.png");
    let browser = browser(chromium);
    let tab = browser.new_tab().expect("tab");
    tab.set_default_timeout(Duration::from_secs(60));
    tab.navigate_to(&studio.url).expect("navigates");
    tab.wait_until_navigated().expect("loaded");
    wait_for(
        &tab,
        "!!(window.studio && studio.pose && studio.state && studio.texture)",
        30,
    );
    let first_n = eval_f64(&tab, "studio.n");

    // Outline mode traces the picture: the disk and its hole, drawn over the dimmed picture.
    click_element(&tab, "#outline-mode");
    wait_for(&tab, "studio.outline.loops.length === 2", 10);
    let rect = canvas_rect(&tab);
    let shot = Shot::take(&tab, &dir.join("0-outline.png"));
    let blue = shot.count_in(rect, |p| {
        p[2] > 130 && p[0] < 80 && p[1] < 120 && p[2] > p[1] + 40
    });
    assert!(blue > 500, "the loops are drawn: {blue} pixels");
    // The outer loop (the longer one) lies on the picture's edge: just inside it the
    // picture shows, just outside it is blank.
    let outer = eval_f64(
        &tab,
        "studio.outline.loops[0].length >= studio.outline.loops[1].length ? 0 : 1",
    ) as usize;
    let count = eval_f64(&tab, &format!("studio.outline.loops[{outer}].length")) as usize;
    let centre = eval(&tab, "studio.toPage(150, 150)");
    let centre = [0, 1].map(|i| centre[i].as_f64().expect("centre"));
    let (mut inside, mut outside) = (0, 0);
    for k in (0..count).step_by((count / 12).max(1)) {
        let q = outline_point_on_page(&tab, outer, k);
        let (dx, dy) = (centre[0] - q[0], centre[1] - q[1]);
        let len = dx.hypot(dy);
        let at = |s: f64| {
            let x = (q[0] + s * dx / len) as usize;
            let y = (q[1] + s * dy / len) as usize;
            shot.rgb[y * shot.width + x]
        };
        let blank = |p: [u8; 3]| p.iter().all(|&c| c > 245);
        inside += usize::from(!blank(at(8.0)));
        outside += usize::from(blank(at(-8.0)));
    }
    let samples = count.div_ceil((count / 12).max(1));
    assert_eq!(
        (inside, outside),
        (samples, samples),
        "the outline fits the picture"
    );

    // A point of the outer loop dragged outwards by the mouse.
    let q = outline_point_on_page(&tab, outer, 0);
    let (dx, dy) = (q[0] - centre[0], q[1] - centre[1]);
    let len = dx.hypot(dy);
    let to = [q[0] + 30.0 * dx / len, q[1] + 30.0 * dy / len];
    drag_through(&tab, q, to, 6);
    let moved = outline_point_on_page(&tab, outer, 0);
    assert!(
        (moved[0] - to[0]).abs() < 1.5 && (moved[1] - to[1]).abs() < 1.5,
        "{moved:?} for {to:?}"
    );
    let moved_world = eval(&tab, &format!("studio.outline.loops[{outer}][0]"));
    let moved_world = [0, 1].map(|i| moved_world[i].as_f64().expect("point"));

    // Create mesh at 800 vertices: the new mesh reaches the moved point and leaves the hole.
    tab.evaluate("document.getElementById('density').value = 800", false)
        .expect("density");
    click_element(&tab, "#create-mesh");
    wait_for(
        &tab,
        "!studio.outline.on && studio.state.vertices !== undefined",
        20,
    );
    wait_for(&tab, &format!("studio.n !== {first_n}"), 20);
    let n = eval_f64(&tab, "studio.n");
    assert!((560.0..1120.0).contains(&n), "{n} vertices for 800");
    let p = pose(&tab);
    let reach = p
        .chunks(2)
        .map(|v| (v[0] - moved_world[0]).hypot(v[1] - moved_world[1]))
        .fold(f64::INFINITY, f64::min);
    // The page holds positions as 32-bit floats.
    assert!(reach < 1e-3, "a vertex at the moved point ({reach} away)");
    assert!(
        p.chunks(2)
            .all(|v| (v[0] - 150.0).abs().max((v[1] - 150.0).abs()) > 29.0),
        "no vertex in the hole"
    );
    assert_eq!(eval(&tab, "studio.state.textured"), true);
    let meshed = Shot::take(&tab, &dir.join("1-meshed.png"));
    assert!(
        meshed.differing(&shot, rect) as f64 > 0.01 * (rect[2] - rect[0]) * (rect[3] - rect[1]),
        "the new mesh is drawn"
    );

    // A loop drawn by clicks (a triangle), meshed: every vertex inside that triangle.
    click_element(&tab, "#outline-mode");
    click_element(&tab, "#clear-outline");
    click_element(&tab, "#new-loop");
    let corners = [[60.0, 60.0], [240.0, 60.0], [150.0, 240.0]];
    for c in corners {
        let at = eval(&tab, &format!("studio.toPage({}, {})", c[0], c[1]));
        let at = [0, 1].map(|i| at[i].as_f64().expect("corner"));
        press(&tab, at);
        release(&tab, at);
    }
    assert_eq!(eval_f64(&tab, "studio.outline.loops[0].length"), 3.0);
    // Clicking the first point again closes the loop; a click on a segment adds a point
    // there, and a right-click removes it.
    let first = outline_point_on_page(&tab, 0, 0);
    press(&tab, first);
    release(&tab, first);
    assert_eq!(
        eval(&tab, "studio.outline.drawing"),
        serde_json::Value::Null
    );
    let [a, b] = [0, 1].map(|p| outline_point_on_page(&tab, 0, p));
    let middle = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
    press(&tab, middle);
    release(&tab, middle);
    assert_eq!(eval_f64(&tab, "studio.outline.loops[0].length"), 4.0);
    let added = eval(&tab, "studio.outline.loops[0][1]");
    assert!(
        (added[0].as_f64().expect("x") - 150.0).abs() < 1.0,
        "{added}"
    );
    right_click(&tab, middle);
    assert_eq!(eval_f64(&tab, "studio.outline.loops[0].length"), 3.0);
    tab.evaluate("document.getElementById('density').value = 300", false)
        .expect("density");
    click_element(&tab, "#create-mesh");
    wait_for(&tab, "!studio.outline.on", 20);
    wait_for(&tab, &format!("studio.n !== {n}"), 20);
    let p = pose(&tab);
    let slack = 2.0;
    for v in p.chunks(2) {
        assert!(v[1] > 60.0 - slack && v[1] < 240.0 + slack, "{v:?}");
        // Inside both slanted sides.
        let left = (v[0] - 60.0) * 180.0 - (v[1] - 60.0) * 90.0;
        let right = (240.0 - v[0]) * 180.0 - (v[1] - 60.0) * 90.0;
        assert!(left > -slack * 200.0 && right > -slack * 200.0, "{v:?}");
    }
    Shot::take(&tab, &dir.join("2-drawn.png"));

    // Timeline: two more keyframes (1 s, 2 s); the middle key dragged with the mouse to a
    // quarter of the bar (0.5 s), then moved later in the order (its pose to place 2).
    click_element(&tab, "#add-key");
    wait_for(&tab, "studio.state.keyframes.length === 2", 10);
    click_element(&tab, "#add-key");
    wait_for(&tab, "studio.state.keyframes.length === 3", 10);
    let bar = eval(
        &tab,
        "(() => { const r = document.getElementById('keys').getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; })()",
    );
    let [left, top, width, height] = [0, 1, 2, 3].map(|i| bar[i].as_f64().expect("bar"));
    let y = top + height / 2.0;
    drag_through(&tab, [left + width / 2.0, y], [left + width / 4.0, y], 8);
    wait_for(
        &tab,
        "Math.abs(studio.state.keyframes[1].time - 0.5) < 0.01 && studio.state.current === 1",
        10,
    );
    click_element(&tab, "#key-later");
    wait_for(&tab, "studio.state.current === 2", 10);
    let times = eval(&tab, "studio.state.keyframes.map((k) => k.time)");
    assert_eq!(times[2], 2.0, "times stay: {times}");
}

#[test]
fn drag_and_scrub_rates_are_measured_in_the_browser() {
    let Some(chromium) = chromium() else { return };
    let dir = scratch("latency");
    let small = generate::disk(generate::rings_for(5000), 0.2);
    bdmorph::io::write_obj_2d(&dir.join("disk5k.obj"), &small.positions, &small.faces, &[])
        .expect("write");
    let large = generate::disk(generate::rings_for(10000), 0.2);
    let mut project = bdmorph::studio::Project::new(&large, None);
    project.keyframes.push(bdmorph::studio::project::Keyframe {
        time: 2.0,
        easing: "linear".into(),
        positions: generate::bend(&large, 0.6).positions,
        pins: Vec::new(),
    });
    project.write(&dir.join("disk10k.json")).expect("write");
    let browser = browser(chromium);

    // Dragging at 5K: one pin at the centre (a real click), a rim vertex dragged.
    let studio = Studio::start(&dir, "disk5k.obj");
    let tab = browser.new_tab().expect("tab");
    tab.activate().expect("front tab");
    tab.navigate_to(&studio.url).expect("navigates");
    wait_for(&tab, "!!(window.studio && studio.pose && studio.state)", 30);
    let centre = vertex_on_page(&tab, 0);
    press(&tab, centre);
    release(&tab, centre);
    wait_for(&tab, "studio.pins.length === 1", 10);
    let rim = small.positions.len() - 1;
    let drag = eval_async(
        &tab,
        &format!(
            "(async () => {{
                const canvas = document.getElementById('view');
                const [x0, y0] = studio.vertexOnPage({rim});
                const pause = (ms) => new Promise((done) => {{ const until = performance.now() + ms; const c = new MessageChannel(); c.port1.onmessage = () => (performance.now() >= until ? done() : c.port2.postMessage(0)); c.port2.postMessage(0); }});
                const ev = (type, x, y, target) => target.dispatchEvent(new MouseEvent(type, {{ clientX: x, clientY: y, button: 0, bubbles: true }}));
                ev('mousedown', x0, y0, canvas);
                studio.stats.latencies = []; studio.stats.drawMs = [];
                const before = studio.stats.poseUpdates, t0 = performance.now();
                let moves = 0;
                while (performance.now() - t0 < 3000) {{
                    moves++;
                    const s = moves / 40;
                    ev('mousemove', x0 + 80 * Math.sin(s), y0 - 60 * Math.sin(2 * s), window);
                    await pause(8);
                }}
                ev('mouseup', x0, y0, window);
                const seconds = (performance.now() - t0) / 1000;
                const median = (a) => a.slice().sort((p, q) => p - q)[a.length >> 1];
                return [studio.stats.poseUpdates - before, seconds, moves, median(studio.stats.latencies), median(studio.stats.drawMs)];
            }})()"
        ),
    );
    drop(tab);
    drop(studio);

    // Scrubbing at 10K: the slider's value set and its input event sent, as dragging it does.
    let studio = Studio::start(&dir, "disk10k.json");
    let tab = browser.new_tab().expect("tab");
    tab.activate().expect("front tab");
    tab.navigate_to(&studio.url).expect("navigates");
    wait_for(&tab, "!!(window.studio && studio.pose && studio.state)", 30);
    let scrub = eval_async(
        &tab,
        "(async () => {
            const pause = (ms) => new Promise((done) => { const until = performance.now() + ms; const c = new MessageChannel(); c.port1.onmessage = () => (performance.now() >= until ? done() : c.port2.postMessage(0)); c.port2.postMessage(0); });
            const slider = document.getElementById('time');
            studio.stats.latencies = []; studio.stats.drawMs = [];
            const before = studio.stats.frameUpdates, t0 = performance.now();
            let moves = 0;
            while (performance.now() - t0 < 3000) {
                moves++;
                slider.value = String(Math.round(500 + 480 * Math.sin(moves / 30)));
                slider.dispatchEvent(new Event('input', { bubbles: true }));
                await pause(8);
            }
            const seconds = (performance.now() - t0) / 1000;
            const median = (a) => a.slice().sort((p, q) => p - q)[a.length >> 1];
            return [studio.stats.frameUpdates - before, seconds, moves, median(studio.stats.latencies), median(studio.stats.drawMs)];
        })()",
    );
    let num = |v: &serde_json::Value, i: usize| v[i].as_f64().unwrap_or(f64::NAN);
    let report = format!(
        "studio rates (reported, not asserted; {} mouse and {} slider events in 3 s, renderer {}): \
         drag at {} vertices: {} updates in {:.2} s = {:.1} per second, median {:.1} ms from request to drawn frame, {:.2} ms to draw; \
         scrub at {} vertices: {} frames in {:.2} s = {:.1} per second, median {:.1} ms, {:.2} ms to draw",
        num(&drag, 2),
        num(&scrub, 2),
        eval(&tab, "studio.renderer"),
        small.positions.len(),
        num(&drag, 0),
        num(&drag, 1),
        num(&drag, 0) / num(&drag, 1),
        num(&drag, 3),
        num(&drag, 4),
        large.positions.len(),
        num(&scrub, 0),
        num(&scrub, 1),
        num(&scrub, 0) / num(&scrub, 1),
        num(&scrub, 3),
        num(&scrub, 4),
    );
    eprintln!("{report}");
    std::fs::write(dir.join("rates.txt"), &report).expect("write");
    assert!(num(&drag, 0) >= 10.0 && num(&scrub, 0) >= 10.0, "{report}");
}
