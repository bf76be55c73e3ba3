//! The studio's page in a real browser, as the browser tests drive it: Debian's Chromium,
//! headless, over the DevTools protocol (headless_chrome). Mouse and keyboard events go through
//! the browser's input pipeline, as a user's would; screenshots are decoded to RGB for checks.
//!
//! Without Chromium, `browser()` says so and returns `None` (the test is skipped), except in CI
//! (`CI` set), where it fails: CI installs Chromium.

#![allow(dead_code)]

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use bdmorph::render::raster;
use headless_chrome::browser::tab::ModifierKey;
use headless_chrome::protocol::cdp::{Input, Page};
use headless_chrome::{Browser, LaunchOptions, Tab};

pub fn find_chromium() -> Option<PathBuf> {
    let fixed = Path::new("/usr/bin/chromium");
    if fixed.is_file() {
        return Some(fixed.into());
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|dir| ["chromium", "chromium-browser"].map(|name| dir.join(name)))
        .find(|p| p.is_file())
}

/// A browser, or `None` (after saying so) when Chromium is missing outside CI.
pub fn browser() -> Option<Browser> {
    let Some(chromium) = find_chromium() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "chromium is not installed, but CI must have it (.ci/run installs it with apt-get)"
        );
        eprintln!("studio_browser: chromium not found; skipping (CI installs it)");
        return None;
    };
    let args: Vec<&OsStr> = vec![
        OsStr::new("--disable-gpu"),
        OsStr::new("--hide-scrollbars"),
        OsStr::new("--force-device-scale-factor=1"),
        OsStr::new("--disable-background-networking"),
        OsStr::new("--disable-component-update"),
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
        .idle_browser_timeout(Duration::from_secs(600))
        .args(args)
        .build()
        .expect("launch options");
    Some(Browser::new(options).expect("chromium starts"))
}

/// A page of the studio in a tab, with the helpers a scripted user needs.
pub struct PageTab {
    pub tab: std::sync::Arc<Tab>,
    pub shots: PathBuf,
}

impl PageTab {
    pub fn open(browser: &Browser, url: &str, shots: &Path) -> PageTab {
        let tab = browser.new_tab().expect("tab");
        tab.set_default_timeout(Duration::from_secs(60));
        tab.navigate_to(url).expect("navigates");
        tab.wait_until_navigated().expect("loaded");
        let page = PageTab {
            tab,
            shots: shots.to_path_buf(),
        };
        page.wait(
            "!!(window.studio && studio.state && studio.pose && studio.connected)",
            30,
        );
        page
    }

    /// The value of the JavaScript expression `js`, through JSON.
    pub fn eval(&self, js: &str) -> serde_json::Value {
        let text = self
            .tab
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

    pub fn num(&self, js: &str) -> f64 {
        self.eval(js)
            .as_f64()
            .unwrap_or_else(|| panic!("{js}: not a number"))
    }

    /// The value of an expression that is a promise, once it resolves.
    pub fn eval_async(&self, js: &str) -> serde_json::Value {
        let text = self
            .tab
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
    pub fn wait(&self, js: &str, seconds: u64) {
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(seconds) {
            if self.eval(js) == serde_json::Value::Bool(true) {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let status = self.eval("document.getElementById('status').textContent");
        let notes = self.eval("document.getElementById('notes').textContent");
        let errors = self.eval("studio.pageErrors");
        panic!("timed out waiting for {js} (status: {status}; notes: {notes}; script errors: {errors})");
    }

    /// Waits until nothing is in flight and the page has drawn.
    pub fn settle(&self) {
        self.wait("!studio.busy()", 30);
        std::thread::sleep(Duration::from_millis(120));
    }

    pub fn mouse(
        &self,
        kind: Input::DispatchMouseEventTypeOption,
        at: [f64; 2],
        button: Option<Input::MouseButton>,
        buttons: u32,
        modifiers: Option<u32>,
    ) {
        self.tab
            .call_method(Input::DispatchMouseEvent {
                Type: kind,
                x: at[0],
                y: at[1],
                modifiers,
                timestamp: None,
                button,
                buttons: Some(buttons),
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

    pub fn move_to(&self, at: [f64; 2], pressed: bool) {
        let (button, buttons) = if pressed {
            (Some(Input::MouseButton::Left), 1)
        } else {
            (None, 0)
        };
        self.mouse(
            Input::DispatchMouseEventTypeOption::MouseMoved,
            at,
            button,
            buttons,
            None,
        );
    }

    pub fn press(&self, at: [f64; 2]) {
        self.move_to(at, false);
        self.mouse(
            Input::DispatchMouseEventTypeOption::MousePressed,
            at,
            Some(Input::MouseButton::Left),
            1,
            None,
        );
    }

    pub fn release(&self, at: [f64; 2]) {
        self.mouse(
            Input::DispatchMouseEventTypeOption::MouseReleased,
            at,
            Some(Input::MouseButton::Left),
            0,
            None,
        );
    }

    pub fn click(&self, at: [f64; 2]) {
        self.press(at);
        self.release(at);
    }

    pub fn right_click(&self, at: [f64; 2]) {
        self.move_to(at, false);
        for kind in [
            Input::DispatchMouseEventTypeOption::MousePressed,
            Input::DispatchMouseEventTypeOption::MouseReleased,
        ] {
            self.mouse(kind, at, Some(Input::MouseButton::Right), 2, None);
        }
    }

    pub fn drag(&self, from: [f64; 2], to: [f64; 2], moves: usize) {
        self.press(from);
        for k in 1..=moves {
            let s = k as f64 / moves as f64;
            self.move_to(
                [
                    from[0] + (to[0] - from[0]) * s,
                    from[1] + (to[1] - from[1]) * s,
                ],
                true,
            );
            std::thread::sleep(Duration::from_millis(8));
        }
        self.release(to);
    }

    pub fn wheel(&self, at: [f64; 2], delta_y: f64) {
        self.tab
            .call_method(Input::DispatchMouseEvent {
                Type: Input::DispatchMouseEventTypeOption::MouseWheel,
                x: at[0],
                y: at[1],
                modifiers: None,
                timestamp: None,
                button: None,
                buttons: None,
                click_count: None,
                force: None,
                tangential_pressure: None,
                tilt_x: None,
                tilt_y: None,
                twist: None,
                delta_x: Some(0.0),
                delta_y: Some(delta_y),
                pointer_Type: None,
            })
            .expect("wheel");
    }

    pub fn click_on(&self, selector: &str) {
        self.tab
            .find_element(selector)
            .unwrap_or_else(|e| panic!("{selector}: {e}"))
            .click()
            .unwrap_or_else(|e| panic!("{selector}: {e}"));
    }

    pub fn key(&self, key: &str, modifiers: &[ModifierKey]) {
        self.tab
            .press_key_with_modifiers(key, (!modifiers.is_empty()).then_some(modifiers))
            .expect("key");
    }

    /// Ctrl+Z, and waits for the page's state to follow.
    pub fn undo(&self) {
        let before = self.num("studio.state.history.steps");
        self.key("z", &[ModifierKey::Ctrl]);
        self.wait(
            &format!(
                "studio.state.history.steps === {} && !studio.busy()",
                before - 1.0
            ),
            30,
        );
        std::thread::sleep(Duration::from_millis(80));
    }

    /// Sets a form control's value and sends its change event, as a user's edit does.
    pub fn set_value(&self, selector: &str, value: &str) {
        self.eval(&format!(
            "(() => {{ const e = document.querySelector('{selector}'); e.focus(); e.value = {value:?}; e.dispatchEvent(new Event('input', {{bubbles: true}})); e.dispatchEvent(new Event('change', {{bubbles: true}})); e.blur(); return true; }})()"
        ));
    }

    /// The page position of vertex `v` as drawn now.
    pub fn vertex(&self, v: usize) -> [f64; 2] {
        let p = self.eval(&format!("studio.vertexOnPage({v})"));
        [p[0].as_f64().expect("x"), p[1].as_f64().expect("y")]
    }

    /// The piece with the most vertices (the subject), or the one with the fewest.
    pub fn piece(&self, largest: bool) -> i32 {
        self.num(&format!(
            "(() => {{ const c = new Map(); for (let v = 0; v < studio.n; v++) c.set(studio.pieceOf[v], (c.get(studio.pieceOf[v]) || 0) + 1); let b = null; for (const [p, k] of c) if (b === null || ({largest} ? k > c.get(b) : k < c.get(b))) b = p; return b; }})()"
        )) as i32
    }

    /// The vertex of piece `piece` furthest along `(dx, dy)`.
    pub fn extreme(&self, piece: i32, dx: f64, dy: f64) -> usize {
        self.num(&format!(
            "(() => {{ let b = -1, bv = -Infinity; for (let v = 0; v < studio.n; v++) {{ if (studio.pieceOf[v] !== {piece}) continue; const s = {dx} * studio.pose[2*v] + {dy} * studio.pose[2*v+1]; if (s > bv) {{ bv = s; b = v; }} }} return b; }})()"
        )) as usize
    }

    pub fn pose(&self) -> Vec<f64> {
        self.eval("Array.from(studio.pose)")
            .as_array()
            .expect("pose")
            .iter()
            .map(|v| v.as_f64().expect("number"))
            .collect()
    }

    pub fn shot(&self, name: &str) -> Shot {
        Shot::take(&self.tab, &self.shots.join(name))
    }

    pub fn canvas(&self) -> [f64; 4] {
        self.rect("#view")
    }

    pub fn rect(&self, selector: &str) -> [f64; 4] {
        let r = self.eval(&format!(
            "(() => {{ const r = document.querySelector('{selector}').getBoundingClientRect(); return [r.left, r.top, r.right, r.bottom]; }})()"
        ));
        [0, 1, 2, 3].map(|i| r[i].as_f64().expect("rect"))
    }

    /// Whether an element is shown (laid out, not hidden).
    pub fn shown(&self, selector: &str) -> bool {
        self.eval(&format!(
            "(() => {{ const e = document.querySelector('{selector}'); return !!e && e.getClientRects().length > 0 && getComputedStyle(e).display !== 'none'; }})()"
        )) == serde_json::Value::Bool(true)
    }

    /// The notes shown (from the server and this page's errors).
    pub fn notes(&self) -> String {
        self.eval("document.getElementById('notes').textContent")
            .as_str()
            .unwrap_or("")
            .to_owned()
    }

    /// Moves the time slider to `fraction` of its length with the mouse.
    /// A click on the timeline's axis at `fraction` of the animation's duration (away from
    /// the keys' thumbnails, on the ruler).
    pub fn slide_to(&self, fraction: f64) {
        let at = self.eval(&format!(
            "studio.timeToPage({fraction} * studio.state.duration)"
        ));
        let top = self.rect("#time")[1];
        self.click([at[0].as_f64().expect("x"), top + 8.0]);
    }

    /// Leaves the page on purpose (no unsaved-changes question) and reloads it.
    pub fn reload(&self) {
        self.eval("(studio.leaving = true)");
        self.tab.reload(true, None).expect("reload");
        std::thread::sleep(Duration::from_millis(300));
        self.wait(
            "!!(window.studio && studio.state && studio.pose && studio.connected)",
            30,
        );
    }
}

/// An RGB screenshot, also written to a file.
pub struct Shot {
    pub width: usize,
    pub rgb: Vec<[u8; 3]>,
}

impl Shot {
    pub fn take(tab: &Tab, path: &Path) -> Shot {
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
    pub fn count_in(&self, rect: [f64; 4], keep: impl Fn([u8; 3]) -> bool) -> usize {
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

    /// Pixels within `r` of `at` satisfying `keep`.
    pub fn count_near(&self, at: [f64; 2], r: f64, keep: impl Fn([u8; 3]) -> bool) -> usize {
        self.count_in([at[0] - r, at[1] - r, at[0] + r, at[1] + r], keep)
    }

    pub fn differing(&self, other: &Shot, rect: [f64; 4]) -> usize {
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

/// The dark end of the distortion ramp (distortion 1): (68, 1, 84) and its neighbours.
pub fn undistorted(p: [u8; 3]) -> bool {
    p[0] < 170 && p[1] < 120 && p[2] > 60 && p[2] > p[1] + 30
}

/// Ramp colours of real distortion: teal, green or yellow (not greys).
pub fn distorted(p: [u8; 3]) -> bool {
    let (r, g, b) = (i32::from(p[0]), i32::from(p[1]), i32::from(p[2]));
    (g > r + 40 && g > 110) || (r > 200 && g > 180 && b < 120)
}

/// The magenta of flipped triangles (and its dark stripes).
pub fn magenta(p: [u8; 3]) -> bool {
    // Bright enough that a dark purple of the picture is not taken for it.
    p[0] > 120 && p[1] < 60 && p[2] > 90 && i32::from(p[0]) > i32::from(p[2]) - 10
}

/// A pin's red (#d62728).
pub fn pin_red(p: [u8; 3]) -> bool {
    p[0] > 180 && p[1] < 80 && p[2] < 80
}

/// A picture made in code, written as PNG.
pub fn write_png(path: &Path, image: &bdmorph::render::Image) {
    std::fs::write(path, raster::encode_png(image).expect("png")).expect("write");
}
