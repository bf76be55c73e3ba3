//! The HTML viewer in a real browser: headless Chromium screenshots of generated pages, the
//! frame chosen by the URL fragment (`#frame=N`, `#t=X`).
//!
//! Without Chromium the test is skipped, except in CI (`CI` set), where it fails: CI installs
//! Chromium. Set `BDMORPH_KEEP_SCREENSHOTS` to keep the pages and screenshots of a passing run
//! (a failing run always keeps them); the folder is printed.

use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use bdmorph::render::html::{html, html_shaded, Shading};
use bdmorph::render::{colour, Viewport};
use bdmorph::{generate, Morph, MorphOptions, PlanarMesh};

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

/// `file://` URL of an absolute path, percent-encoding all but unreserved characters and `/`.
fn file_url(path: &Path, fragment: &str) -> String {
    let mut url = String::from("file://");
    for &b in path.to_str().expect("UTF-8 temp path").as_bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/".contains(&b) {
            url.push(char::from(b));
        } else {
            url.push_str(&format!("%{b:02X}"));
        }
    }
    url.push('#');
    url.push_str(fragment);
    url
}

/// An RGB screenshot.
struct Shot {
    width: usize,
    height: usize,
    rgb: Vec<[u8; 3]>,
}

impl Shot {
    fn decode(path: &Path) -> Shot {
        let bytes = std::fs::read(path).expect("screenshot written");
        let mut decoder = png::Decoder::new(Cursor::new(bytes));
        decoder.set_transformations(png::Transformations::normalize_to_color8());
        let mut reader = decoder.read_info().expect("PNG header");
        let mut buf = vec![0; reader.output_buffer_size().expect("PNG size")];
        let info = reader.next_frame(&mut buf).expect("PNG data");
        let channels = info.color_type.samples();
        let rgb = buf[..info.buffer_size()]
            .chunks(channels)
            .map(|p| match channels {
                1 | 2 => [p[0]; 3],
                _ => [p[0], p[1], p[2]],
            })
            .collect();
        Shot {
            width: info.width as usize,
            height: info.height as usize,
            rgb,
        }
    }

    /// `[left, right, top, bottom]` edges (in pixels from the top-left corner) of the pixels
    /// satisfying `keep`.
    fn bounds(&self, keep: impl Fn([u8; 3]) -> bool) -> [f64; 4] {
        let mut b = [usize::MAX, 0, usize::MAX, 0];
        for (i, &p) in self.rgb.iter().enumerate() {
            if keep(p) {
                let (x, y) = (i % self.width, i / self.width);
                b = [b[0].min(x), b[1].max(x + 1), b[2].min(y), b[3].max(y + 1)];
            }
        }
        b.map(|v| v as f64)
    }

    fn pixels(&self) -> usize {
        self.width * self.height
    }

    /// How many pixels satisfy `keep`, and their mean row.
    fn count(&self, keep: impl Fn([u8; 3]) -> bool) -> (usize, f64) {
        let (mut n, mut rows) = (0usize, 0.0);
        for (i, &p) in self.rgb.iter().enumerate() {
            if keep(p) {
                n += 1;
                rows += (i / self.width) as f64;
            }
        }
        (n, if n > 0 { rows / n as f64 } else { f64::NAN })
    }
}

fn near(p: [u8; 3], q: [u8; 3]) -> bool {
    p.iter().zip(q).all(|(&a, b)| a.abs_diff(b) <= 40)
}

/// The mesh's flat fill and edge colours are the only blue things on the page.
fn mesh_pixel(p: [u8; 3]) -> bool {
    i32::from(p[2]) - i32::from(p[0]) > 30 && p[1] < 230
}

fn red_pixel(p: [u8; 3]) -> bool {
    p[0] > 180 && p[1] < 90 && p[2] < 90
}

struct Browser {
    exe: PathBuf,
    dir: PathBuf,
    launches: usize,
}

impl Browser {
    /// Runs headless Chromium on `page` opened at `#fragment` with `args` besides the usual
    /// ones, in a 600 x 600 window and a fresh profile; returns its standard output.
    fn run(&mut self, page: &Path, fragment: &str, args: &[String]) -> String {
        self.launches += 1;
        let n = self.launches;
        let profile = self.dir.join(format!("profile-{n}"));
        let out = self.dir.join(format!("chromium-{n}.out"));
        let log = self.dir.join(format!("chromium-{n}.log"));
        let url = file_url(page, fragment);
        let mut child = Command::new(&self.exe)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--no-first-run",
                "--hide-scrollbars",
                "--force-device-scale-factor=1",
                "--window-size=600,600",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .args(args)
            .arg(&url)
            .stdin(Stdio::null())
            .stdout(std::fs::File::create(&out).expect("output file"))
            .stderr(std::fs::File::create(&log).expect("log file"))
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {}: {e}", self.exe.display()));
        // A hung browser must not hang the test suite; the limit is generous.
        let deadline = Instant::now() + Duration::from_secs(180);
        let status = loop {
            if let Some(status) = child.try_wait().expect("wait for chromium") {
                break status;
            }
            if Instant::now() > deadline {
                let _ = child.kill();
                let _ = child.wait();
                panic!("chromium did not finish {url}; see {}", log.display());
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        let _ = std::fs::remove_dir_all(&profile);
        assert!(
            status.success(),
            "chromium failed ({status}) on {url}:\n{}",
            std::fs::read_to_string(&log).unwrap_or_default()
        );
        std::fs::read_to_string(&out).expect("chromium's output")
    }

    /// A screenshot of `page` opened at `#fragment`.
    fn screenshot(&mut self, page: &Path, fragment: &str) -> Shot {
        let shot = self.dir.join(format!("shot-{}.png", self.launches + 1));
        self.run(
            page,
            fragment,
            &[format!("--screenshot={}", shot.display())],
        );
        let decoded = Shot::decode(&shot);
        assert_eq!((decoded.width, decoded.height), (600, 600), "{fragment}");
        decoded
    }

    /// The `<body ...>` tag and the frame label of `page` opened at `#fragment`, after
    /// `virtual_ms` milliseconds of (fast-forwarded) page time.
    fn state(&mut self, page: &Path, fragment: &str, virtual_ms: u32) -> (String, String) {
        let mut args = vec!["--dump-dom".to_string()];
        if virtual_ms > 0 {
            // (A budget of 0 never ends.)
            args.push(format!("--virtual-time-budget={virtual_ms}"));
        }
        let dom = self.run(page, fragment, &args);
        let cut = |start: &str, end: char| {
            let from = dom
                .find(start)
                .unwrap_or_else(|| panic!("no {start} in\n{dom}"));
            let to = from + start.len() + dom[from + start.len()..].find(end).expect("closed");
            dom[from..to].to_string()
        };
        (cut("<body", '>'), cut("<span id=\"label\">", '<'))
    }
}

/// `[min x, max x, min y, max y]` of the positions.
fn world_bounds(positions: &[[f64; 2]]) -> [f64; 4] {
    positions.iter().fold(
        [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ],
        |b, p| {
            [
                b[0].min(p[0]),
                b[1].max(p[0]),
                b[2].min(p[1]),
                b[3].max(p[1]),
            ]
        },
    )
}

/// A `size` x `size` checkerboard of 8 x 8 cells: `a` alternating with `top` in the upper
/// half of the image and with `bottom` in the lower half, as PNG.
fn checkerboard(size: u32, a: [u8; 3], top: [u8; 3], bottom: [u8; 3]) -> Vec<u8> {
    let mut rgb = Vec::new();
    for y in 0..size {
        for x in 0..size {
            let other = if y < size / 2 { top } else { bottom };
            rgb.extend_from_slice(&if (x / 8 + y / 8) % 2 == 0 { a } else { other });
        }
    }
    let mut png = Vec::new();
    let mut encoder = png::Encoder::new(&mut png, size, size);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().expect("PNG header");
    writer.write_image_data(&rgb).expect("PNG data");
    writer.finish().expect("PNG end");
    png
}

#[test]
fn chromium_shows_frames_textures_and_flips() {
    let Some(exe) = find_chromium() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "chromium is not installed, but CI must have it (.ci/run installs it with apt-get)"
        );
        eprintln!("SKIPPED: chromium not installed (apt-get install chromium)");
        return;
    };
    let dir = std::env::temp_dir().join(format!("bdmorph-html-browser-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    eprintln!("pages and screenshots in {}", dir.display());
    let mut browser = Browser {
        exe,
        dir: dir.clone(),
        launches: 0,
    };
    let started = Instant::now();

    // The morph, 11 frames.
    let source = generate::disk(10, 0.2);
    let target = generate::twist(&generate::bend(&source, 0.7), 1.2);
    let mut morph = Morph::new(&source, &target, MorphOptions::default()).expect("morph");
    let frames: Vec<(f64, Vec<[f64; 2]>)> = (0..=10)
        .map(|i| {
            let t = f64::from(i) / 10.0;
            let frame = morph.frame(t).expect("frame");
            assert_eq!(frame.stats.flipped_triangles, 0);
            (t, frame.positions.to_vec())
        })
        .collect();
    let frames: Vec<(f64, &[[f64; 2]])> = frames.iter().map(|(t, p)| (*t, &p[..])).collect();
    let view = Viewport::fit(frames.iter().map(|f| f.1));
    let faces = &source.faces;
    let page = dir.join("morph.html");
    std::fs::write(&page, html("morph", &frames, faces, None, None, &view)).expect("page");

    // Flat: both ends drawn, different, none red, world y up.
    let first = browser.screenshot(&page, "frame=0");
    let last = browser.screenshot(&page, "t=1");
    let (mesh0, _) = first.count(mesh_pixel);
    let (mesh1, _) = last.count(mesh_pixel);
    let total = first.pixels();
    for (mesh, name) in [(mesh0, "t = 0"), (mesh1, "t = 1")] {
        assert!(
            mesh > total / 5,
            "{name}: only {mesh} of {total} pixels show the mesh"
        );
    }
    assert_eq!(first.count(red_pixel).0, 0, "no flipped triangles at t = 0");
    assert_eq!(last.count(red_pixel).0, 0, "no flipped triangles at t = 1");
    let differing = (first.rgb.iter().zip(&last.rgb))
        .filter(|(p, q)| p.iter().zip(q.iter()).any(|(a, b)| a.abs_diff(*b) > 48))
        .count();
    assert!(
        differing > total / 10,
        "t = 0 and t = 1 differ in only {differing} of {total} pixels"
    );
    // Where the mesh lands: one uniform scale for x and y, world y up, the frames as asked.
    let (b0, b1) = (first.bounds(mesh_pixel), last.bounds(mesh_pixel));
    let (w0, w1) = (world_bounds(frames[0].1), world_bounds(frames[10].1));
    let scale = (b0[1] - b0[0]) / (w0[1] - w0[0]);
    let (ox, oy) = (b0[0] - scale * w0[0], b0[2] + scale * w0[3]);
    for (pixels, world, name) in [(b0, w0, "t = 0"), (b1, w1, "t = 1")] {
        let expected = [
            ox + scale * world[0],
            ox + scale * world[1],
            oy - scale * world[3],
            oy - scale * world[2],
        ];
        let off = (0..4)
            .map(|i| (pixels[i] - expected[i]).abs())
            .fold(0.0, f64::max);
        assert!(
            off < 3.0,
            "{name}: the mesh covers columns {:?} and rows {:?}, expected {:?} and {:?}",
            &pixels[..2],
            &pixels[2..],
            &expected[..2],
            &expected[2..]
        );
    }

    // The fragment picks the nearest t; `play` plays (1 s of page time: three steps).
    let (body, label) = browser.state(&page, "t=0.52", 0);
    assert!(body.contains("data-frame=\"5\""), "{body}");
    assert!(label.ends_with("t = 0.5 (6/11)"), "{label}");
    let (body, _) = browser.state(&page, "frame=2&play", 1000);
    assert!(
        !body.contains("data-frame=\"2\""),
        "still at frame 2 {body}"
    );

    // Textured: corners' texture coordinates from the source positions (unit disk -> unit
    // square), a checkerboard whose upper half alternates with blue, lower half with green.
    let (orange, blue, green) = ([240, 140, 20], [30, 60, 220], [30, 170, 60]);
    let texture = checkerboard(64, orange, blue, green);
    let uv: Vec<[[f64; 2]; 3]> = faces
        .iter()
        .map(|f| f.map(|v| source.positions[v as usize].map(|x| 0.5 + 0.5 * x)))
        .collect();
    let textured = dir.join("textured.html");
    let text = html("", &frames, faces, Some(&uv), Some(&texture), &view);
    std::fs::write(&textured, text).expect("page");
    let shot = browser.screenshot(&textured, "t=1");
    let (n_orange, _) = shot.count(|p| near(p, orange));
    let (n_blue, row_blue) = shot.count(|p| near(p, blue));
    let (n_green, row_green) = shot.count(|p| near(p, green));
    for (n, name) in [(n_orange, "orange"), (n_blue, "blue"), (n_green, "green")] {
        assert!(n > total / 30, "{name}: only {n} of {total} pixels");
    }
    assert!(
        row_blue < row_green - 20.0,
        "the texture's top (blue, mean row {row_blue:.1}) must be drawn above its bottom \
         (green, mean row {row_green:.1})"
    );

    // Shaded by distortion: t = 0 is undistorted (all the darkest shade), t = 1 shows the
    // ramp's brighter shades, and the legend names what the colours mean.
    let mut morph = Morph::new(&source, &target, MorphOptions::default()).expect("morph");
    let shades: Vec<Vec<u8>> = [0.0, 1.0]
        .iter()
        .map(|&t| morph.frame(t).expect("frame").distortion.to_vec())
        .collect::<Vec<_>>()
        .iter()
        .map(|d| colour::distortion_shades(d, 3.0))
        .collect();
    let ends = [frames[0], frames[10]];
    let shading = Shading {
        shades: &shades,
        label: "conformal distortion",
        max: 3.0,
    };
    let shaded = dir.join("shaded.html");
    let text = html_shaded("", &ends, faces, None, None, Some(&shading), &view);
    std::fs::write(&shaded, text).expect("page");
    let dark = colour::shade_colour(0);
    let bright = |p: [u8; 3]| p[1] > 110 && p[1] > p[2] && i32::from(p[1]) - i32::from(p[0]) > 20;
    let first = browser.screenshot(&shaded, "frame=0");
    let last = browser.screenshot(&shaded, "frame=1");
    let (dark0, _) = first.count(|p| near(p, dark));
    let (bright0, _) = first.count(bright);
    let (bright1, _) = last.count(bright);
    assert!(dark0 > total / 10, "t = 0: only {dark0} dark pixels");
    assert!(bright0 < total / 500, "t = 0: {bright0} bright pixels");
    assert!(bright1 > total / 50, "t = 1: only {bright1} bright pixels");
    let (_, legend) = browser.state(&shaded, "frame=1", 0);
    assert!(legend.contains("2/2"), "{legend}");

    // A frame with flipped triangles: the centre of a small disk dragged outside its ring.
    let mut bad: PlanarMesh = generate::disk(3, 0.0);
    bad.positions[0] = [0.6, 0.0];
    let flipped = bad
        .faces
        .iter()
        .filter(|f| bad.signed_area(f) <= 0.0)
        .count();
    assert!(flipped > 0);
    let flips = dir.join("flips.html");
    let view = Viewport::fit([&bad.positions[..]]);
    let frames = [(0.0, &bad.positions[..])];
    std::fs::write(&flips, html("", &frames, &bad.faces, None, None, &view)).expect("page");
    let shot = browser.screenshot(&flips, "");
    let (red, _) = shot.count(red_pixel);
    let (mesh, _) = shot.count(mesh_pixel);
    assert!(
        red > total / 200,
        "{flipped} flipped triangles: {red} red pixels"
    );
    assert!(mesh > red, "the unflipped rest is drawn too");

    eprintln!(
        "{} chromium runs in {:.1} s",
        browser.launches,
        started.elapsed().as_secs_f64()
    );
    if std::env::var_os("BDMORPH_KEEP_SCREENSHOTS").is_none() {
        let _ = std::fs::remove_dir_all(&dir);
    }
}
