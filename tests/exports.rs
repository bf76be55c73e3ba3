//! `bdmorph export PROJECT.json`: production exports of a studio project, checked by real
//! decoders. FFmpeg (`ffprobe`, `ffmpeg`) reads the MP4, GIF and APNG files; libwebp's own
//! animation decoder reads the WebP (Debian 12's FFmpeg 5.1 cannot decode animated WebP);
//! the `png` crate reads the PNG frames and the sprite sheet.
//!
//! Without FFmpeg the FFmpeg checks are skipped (`SKIPPED: ...`), except in CI (`CI` set),
//! where they fail: CI installs FFmpeg.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use bdmorph::generate;
use bdmorph::render::{raster, Image};
use bdmorph::studio::project::{Keyframe, Project};

fn bdmorph() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bdmorph"))
}

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-exports-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// A wide strip (8 x 2 units) bending up over one second at 10 frames per second: 11
/// frames. Saved as `wave.json` in `dir`.
fn project(dir: &Path) -> PathBuf {
    let rest = generate::grid(17, 5, 0.0);
    let rest = bdmorph::PlanarMesh {
        positions: rest
            .positions
            .iter()
            .map(|p| [p[0] * 0.5, p[1] * 0.5])
            .collect(),
        faces: rest.faces,
    };
    let mut doc = Project::new(&rest, None);
    doc.fps = 10.0;
    let bent: Vec<[f64; 2]> = rest
        .positions
        .iter()
        .map(|&[x, y]| {
            let a = 0.08 * x;
            let r = 4.0 / 0.32 - y;
            [r * a.sin(), 4.0 / 0.32 - r * a.cos()]
        })
        .collect();
    doc.keyframes.push(Keyframe {
        time: 1.0,
        easing: "linear".into(),
        positions: bent,
        pins: vec![],
        drawing: None,
    });
    let path = dir.join("wave.json");
    doc.write(&path).expect("project written");
    path
}

/// Runs `bdmorph export` with `args` in `dir`; panics with its stderr unless it succeeds.
fn export_ok(dir: &Path, args: &[&str]) -> String {
    let out = bdmorph()
        .current_dir(dir)
        .arg("export")
        .arg("wave.json")
        .args(args)
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "export {args:?}: {stderr}");
    stderr
}

/// Runs `bdmorph export` expecting a refusal; its stderr.
fn export_err(dir: &Path, args: &[&str]) -> String {
    let out = bdmorph()
        .current_dir(dir)
        .arg("export")
        .arg("wave.json")
        .args(args)
        .output()
        .expect("runs");
    assert!(!out.status.success(), "export {args:?} should fail");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn find(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|dir| dir.join(name))
        .find(|p| p.is_file())
}

/// FFmpeg's `ffprobe` and `ffmpeg`, or `None` after saying the check is skipped (a failure
/// in CI).
fn ffmpeg_tools() -> Option<(PathBuf, PathBuf)> {
    match (find("ffprobe"), find("ffmpeg")) {
        (Some(probe), Some(mpeg)) => Some((probe, mpeg)),
        _ => {
            assert!(
                std::env::var_os("CI").is_none(),
                "ffprobe/ffmpeg are not installed, but CI must have them (.ci/run installs ffmpeg with apt-get)"
            );
            eprintln!("SKIPPED: ffprobe/ffmpeg not installed (apt-get install ffmpeg)");
            None
        }
    }
}

/// What `ffprobe` says about the first video stream, decoding every frame to count them.
fn probe(ffprobe: &Path, file: &Path) -> HashMap<String, String> {
    let out = Command::new(ffprobe)
        .args(["-v", "error", "-count_frames", "-select_streams", "v:0"])
        .args([
            "-show_entries",
            "stream=codec_name,width,height,pix_fmt,nb_read_frames",
        ])
        .args(["-of", "default=noprint_wrappers=1"])
        .arg(file)
        .output()
        .expect("ffprobe runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && stderr.trim().is_empty(),
        "ffprobe: {stderr}"
    );
    String::from_utf8(out.stdout)
        .expect("utf8")
        .lines()
        .filter_map(|l| l.split_once('='))
        .map(|(k, v)| (k.to_owned(), v.to_owned()))
        .collect()
}

/// Every frame decoded by `ffmpeg` to RGBA, `w * h * 4` bytes each.
fn decode_rgba(ffmpeg: &Path, file: &Path) -> Vec<u8> {
    let out = Command::new(ffmpeg)
        .args(["-v", "error", "-i"])
        .arg(file)
        .args(["-f", "rawvideo", "-pix_fmt", "rgba", "-"])
        .output()
        .expect("ffmpeg runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && stderr.trim().is_empty(),
        "ffmpeg: {stderr}"
    );
    out.stdout
}

fn read_png(path: &Path) -> Image {
    raster::read_image(path).unwrap_or_else(|e| panic!("{e}"))
}

/// The PNG frames of a folder, in order.
fn frames_in(dir: &Path) -> Vec<Image> {
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("a folder")
        .map(|e| e.expect("entry").path())
        .collect();
    names.sort();
    names.iter().map(|p| read_png(p)).collect()
}

/// Alpha of pixel `(x, y)`.
fn alpha(img: &Image, x: u32, y: u32) -> u8 {
    img.rgba[((y * img.width + x) * 4 + 3) as usize]
}

/// Pixels with alpha 0 and with alpha 255.
fn alpha_counts(rgba: &[u8]) -> (usize, usize) {
    let a = rgba.chunks_exact(4).map(|p| p[3]);
    (
        a.clone().filter(|&v| v == 0).count(),
        a.filter(|&v| v == 255).count(),
    )
}

#[test]
fn transparent_exports_agree_frame_for_frame_and_keep_their_alpha() {
    let dir = scratch("transparent");
    project(&dir);
    export_ok(&dir, &["-o", "frames", "--background", "transparent"]);
    let frames = frames_in(&dir.join("frames"));
    assert_eq!(frames.len(), 11, "1 s at 10 fps: 11 frames");
    let (w, h) = (frames[0].width, frames[0].height);
    // The subject's own aspect, not a square: the strip is wide.
    assert_eq!(w, 640);
    assert!(h < 400, "{w}x{h}");
    for f in &frames {
        // The corner is background (transparent); the middle of the first frame is subject.
        assert_eq!(alpha(f, 0, 0), 0);
        let (clear, opaque) = alpha_counts(&f.rgba);
        assert!(
            clear > 1000 && opaque > 1000,
            "{clear} clear, {opaque} opaque"
        );
    }

    // The sprite sheet, cut by its JSON, is the frames pixel for pixel.
    export_ok(
        &dir,
        &["-o", "sheet.png", "--sheet", "--background", "transparent"],
    );
    let sheet = read_png(&dir.join("sheet.png"));
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("sheet.json")).expect("json beside"))
            .expect("JSON");
    let listed = json["frames"].as_array().expect("frames");
    assert_eq!(listed.len(), 11);
    assert_eq!(json["meta"]["fps"], 10);
    assert_eq!(json["meta"]["image"], "sheet.png");
    assert_eq!(json["meta"]["size"]["w"], sheet.width);
    assert_eq!(json["meta"]["size"]["h"], sheet.height);
    for (i, entry) in listed.iter().enumerate() {
        let r = &entry["frame"];
        let [x, y, fw, fh] = ["x", "y", "w", "h"].map(|k| r[k].as_u64().expect("number") as u32);
        assert_eq!((fw, fh), (w, h));
        assert_eq!(entry["duration"], 100, "10 fps: 100 ms a frame");
        for row in 0..h {
            let start = (((y + row) * sheet.width + x) * 4) as usize;
            let cut = &sheet.rgba[start..start + (w * 4) as usize];
            let want = &frames[i].rgba[(row * w * 4) as usize..((row + 1) * w * 4) as usize];
            assert!(
                cut == want,
                "sheet frame {i}, row {row} differs from frame_{i:04}.png"
            );
        }
    }

    // The animated WebP, decoded by libwebp: the same frames, alpha and all (lossless).
    export_ok(&dir, &["-o", "wave.webp", "--background", "transparent"]);
    let bytes = std::fs::read(dir.join("wave.webp")).expect("webp");
    let decoder = webp_animation::Decoder::new(&bytes).expect("libwebp reads it");
    assert_eq!(decoder.dimensions(), (w, h));
    let decoded: Vec<_> = decoder.into_iter().collect();
    assert_eq!(decoded.len(), 11);
    for (i, f) in decoded.iter().enumerate() {
        assert!(
            f.data() == frames[i].rgba.as_slice(),
            "WebP frame {i} differs"
        );
    }

    // The animated PNG, read by FFmpeg: 11 frames, the same pixels.
    export_ok(&dir, &["-o", "wave.apng", "--background", "transparent"]);
    if let Some((ffprobe, ffmpeg)) = ffmpeg_tools() {
        let info = probe(&ffprobe, &dir.join("wave.apng"));
        assert_eq!(info["codec_name"], "apng");
        assert_eq!(info["nb_read_frames"], "11");
        assert_eq!(info["width"], w.to_string());
        assert_eq!(info["height"], h.to_string());
        assert_eq!(info["pix_fmt"], "rgba");
        let all = decode_rgba(&ffmpeg, &dir.join("wave.apng"));
        let one = (w * h * 4) as usize;
        assert_eq!(all.len(), 11 * one);
        for (i, f) in frames.iter().enumerate() {
            assert!(
                all[i * one..(i + 1) * one] == f.rgba[..],
                "APNG frame {i} differs"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn opaque_exports_take_the_size_colour_and_range_asked_for() {
    let dir = scratch("opaque");
    project(&dir);
    export_ok(
        &dir,
        &[
            "-o",
            "wave.mp4",
            "--size",
            "320x240",
            "--background",
            "#336699",
        ],
    );
    export_ok(
        &dir,
        &["-o", "wave.gif", "--size", "300x200", "--range", "2-5"],
    );
    export_ok(
        &dir,
        &["-o", "part", "--range", "3-7", "--background", "black"],
    );
    let part = frames_in(&dir.join("part"));
    assert_eq!(part.len(), 5);
    // Opaque: every pixel; the corner is the colour asked for.
    for f in &part {
        assert_eq!(alpha_counts(&f.rgba).0, 0);
        assert_eq!(&f.rgba[..4], &[0, 0, 0, 255]);
    }
    if let Some((ffprobe, ffmpeg)) = ffmpeg_tools() {
        let mp4 = probe(&ffprobe, &dir.join("wave.mp4"));
        assert_eq!(mp4["codec_name"], "h264");
        assert_eq!(
            (mp4["width"].as_str(), mp4["height"].as_str()),
            ("320", "240")
        );
        assert_eq!(mp4["nb_read_frames"], "11");
        let rgba = decode_rgba(&ffmpeg, &dir.join("wave.mp4"));
        // The corner of the first frame is the background colour (to H.264's precision).
        let [r, g, b] = [rgba[0], rgba[1], rgba[2]].map(i32::from);
        assert!(
            (r - 0x33).abs() < 8 && (g - 0x66).abs() < 8 && (b - 0x99).abs() < 8,
            "{r} {g} {b}"
        );
        let gif = probe(&ffprobe, &dir.join("wave.gif"));
        assert_eq!(gif["codec_name"], "gif");
        assert_eq!(
            (gif["width"].as_str(), gif["height"].as_str()),
            ("300", "200")
        );
        assert_eq!(gif["nb_read_frames"], "4", "frames 2 to 5");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn impossible_exports_are_refused_before_anything_is_written() {
    let dir = scratch("refused");
    project(&dir);
    let cases: &[(&[&str], &str)] = &[
        (
            &["-o", "a.mp4", "--background", "transparent"],
            "MP4 has no transparency",
        ),
        (
            &["-o", "a.gif", "--background", "transparent"],
            "GIF has no transparency",
        ),
        (&["-o", "a.png"], "--sheet"),
        (&["-o", "a.webm"], "unknown ending"),
        (&["-o", "a.gif", "--range", "5-2"], "after the last"),
        (&["-o", "a.gif", "--range", "0-11"], "frames 0-10"),
        (
            &["-o", "a.gif", "--background", "tealish"],
            "not 'transparent'",
        ),
        (&["-o", "a.gif", "--frames", "20000"], "at most 10000"),
        (&["-o", "a.gif", "--sheet"], "a .png file"),
    ];
    for (args, says) in cases {
        let err = export_err(&dir, args);
        assert!(err.contains(says), "{args:?}: {err}");
    }
    let left: Vec<_> = std::fs::read_dir(&dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, vec!["wave.json".to_owned()], "nothing half-written");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_draw_order_painted_in_the_project_decides_the_overlap() {
    // Two pieces: a red square under a blue one where they overlap (as posed), then the
    // painted depth puts red in front.
    let dir = scratch("depth");
    let mesh = bdmorph::PlanarMesh {
        positions: vec![
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 2.0],
            [0.0, 2.0],
            [3.0, 0.0],
            [5.0, 0.0],
            [5.0, 2.0],
            [3.0, 2.0],
        ],
        faces: vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]],
    };
    let mut doc = Project::new(
        &mesh,
        Some(vec![
            [0.1, 0.5],
            [0.2, 0.5],
            [0.2, 0.6],
            [0.1, 0.6],
            [0.8, 0.5],
            [0.9, 0.5],
            [0.9, 0.6],
            [0.8, 0.6],
        ]),
    );
    // The second piece slides over the first.
    let mut moved = mesh.positions.clone();
    for p in &mut moved[4..] {
        p[0] -= 2.0;
    }
    doc.keyframes.push(Keyframe {
        time: 1.0,
        easing: "linear".into(),
        positions: moved,
        pins: vec![],
        drawing: None,
    });
    doc.fps = 2.0;
    // A picture: left half red, right half blue.
    let mut picture = Image {
        width: 20,
        height: 2,
        rgba: Vec::new(),
    };
    for _ in 0..2 {
        for x in 0..20 {
            picture.rgba.extend_from_slice(if x < 10 {
                &[255, 0, 0, 255]
            } else {
                &[0, 0, 255, 255]
            });
        }
    }
    std::fs::write(
        dir.join("paint.png"),
        raster::encode_png(&picture).expect("png"),
    )
    .expect("write");
    doc.texture = Some("paint.png".into());
    let write = |doc: &Project| doc.write(&dir.join("wave.json")).expect("written");
    write(&doc);
    let last_frame = |name: &str| {
        export_ok(&dir, &["-o", name, "--size", "100x40"]);
        frames_in(&dir.join(name)).pop().expect("frames")
    };
    // The overlap at the end: x in [1, 2] world; the view fits x in [-0.25, 2.25] or so:
    // sample the middle of the overlap.
    let colour_at_overlap = |img: &Image| {
        let (scale, ox, oy) = {
            let view = bdmorph::render::Viewport::fit([
                doc.keyframes[1].positions.as_slice(),
                doc.keyframes[0].positions.as_slice(),
            ]);
            view.transform(bdmorph::render::ImageSize {
                width: 100,
                height: 40,
            })
        };
        let (x, y) = ((ox + scale * 1.5) as u32, (oy - scale * 1.0) as u32);
        let i = ((y * img.width + x) * 4) as usize;
        [img.rgba[i], img.rgba[i + 1], img.rgba[i + 2]]
    };
    // Without depth, the later triangles (blue) are drawn last.
    assert_eq!(colour_at_overlap(&last_frame("plain")), [0, 0, 255]);
    doc.depth = Some(vec![1, 1, 0, 0]);
    write(&doc);
    assert_eq!(colour_at_overlap(&last_frame("red-in-front")), [255, 0, 0]);
    doc.depth = Some(vec![-3, -3, 2, 2]);
    write(&doc);
    assert_eq!(colour_at_overlap(&last_frame("blue-in-front")), [0, 0, 255]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn morph_writes_the_same_production_formats_and_takes_a_depth_file() {
    let dir = scratch("morph");
    let a = generate::grid(9, 3, 0.0);
    let b = generate::bend(&a, 0.6);
    for (name, m) in [("a.obj", &a), ("b.obj", &b)] {
        bdmorph::io::write_obj_2d(dir.join(name), &m.positions, &m.faces, &[]).expect("obj");
    }
    let morph = |args: &[&str]| {
        let out = bdmorph()
            .current_dir(&dir)
            .args([
                "morph", "a.obj", "b.obj", "--frames", "6", "--size", "120x60",
            ])
            .args(args)
            .output()
            .expect("runs");
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    for args in [
        &["-o", "m.apng", "--background", "transparent"][..],
        &["-o", "m.webp", "--background", "transparent"],
        &["-o", "sheet.png", "--sheet", "--background", "transparent"],
        &[
            "-o",
            "frames",
            "--format",
            "png",
            "--background",
            "transparent",
        ],
    ] {
        let (ok, err) = morph(args);
        assert!(ok, "{args:?}: {err}");
    }
    let frames = frames_in(&dir.join("frames"));
    assert_eq!(frames.len(), 6);
    let sheet = read_png(&dir.join("sheet.png"));
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("sheet.json")).expect("json"))
            .expect("JSON");
    for (i, entry) in json["frames"]
        .as_array()
        .expect("frames")
        .iter()
        .enumerate()
    {
        let r = &entry["frame"];
        let [x, y, w, h] = ["x", "y", "w", "h"].map(|k| r[k].as_u64().expect("number") as u32);
        assert_eq!((w, h), (120, 60));
        for row in 0..h {
            let start = (((y + row) * sheet.width + x) * 4) as usize;
            assert!(
                sheet.rgba[start..start + (w * 4) as usize]
                    == frames[i].rgba[(row * w * 4) as usize..((row + 1) * w * 4) as usize]
            );
        }
    }
    let webp = std::fs::read(dir.join("m.webp")).expect("webp");
    let decoded: Vec<_> = webp_animation::Decoder::new(&webp)
        .expect("decodes")
        .into_iter()
        .collect();
    assert_eq!(decoded.len(), 6);
    for (f, png) in decoded.iter().zip(&frames) {
        assert!(f.data() == png.rgba.as_slice());
    }
    // A depth file: one level per face, or per vertex; wrong counts and levels are refused.
    std::fs::write(dir.join("depth.txt"), "1\n".repeat(a.positions.len())).expect("write");
    assert!(morph(&["-o", "d.gif", "--depth", "depth.txt"]).0);
    std::fs::write(dir.join("bad.txt"), "1 2 3").expect("write");
    let (ok, err) = morph(&["-o", "d.gif", "--depth", "bad.txt"]);
    assert!(!ok && err.contains("one per face"), "{err}");
    std::fs::write(dir.join("deep.txt"), "12\n".repeat(a.faces.len())).expect("write");
    let (ok, err) = morph(&["-o", "d.gif", "--depth", "deep.txt"]);
    assert!(!ok && err.contains("between -9 and 9"), "{err}");
    let (ok, err) = morph(&["-o", "m.mp4", "--background", "transparent"]);
    assert!(!ok && err.contains("no transparency"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A keyframe made from a drawing brings its own picture: the frames cross-fade from the rest
/// picture (red) to the drawing's (blue) along the segment; without the drawing's file, the
/// rest picture is drawn and a note says so.
#[test]
fn a_keyframe_drawing_is_cross_faded_in_the_frames() {
    use bdmorph::studio::project::KeyframeDrawing;
    let dir = scratch("drawing-fade");
    let solid = |rgb: [u8; 3]| Image {
        width: 8,
        height: 8,
        rgba: [rgb[0], rgb[1], rgb[2], 255].repeat(64),
    };
    std::fs::write(
        dir.join("red.png"),
        raster::encode_png(&solid([255, 0, 0])).unwrap(),
    )
    .unwrap();
    std::fs::write(
        dir.join("blue.png"),
        raster::encode_png(&solid([0, 0, 255])).unwrap(),
    )
    .unwrap();
    let rest = generate::grid(5, 5, 0.0);
    let (lo, hi) = rest.bounds();
    let uv: Vec<[f64; 2]> = rest
        .positions
        .iter()
        .map(|p| {
            [
                (p[0] - lo[0]) / (hi[0] - lo[0]),
                (p[1] - lo[1]) / (hi[1] - lo[1]),
            ]
        })
        .collect();
    let mut doc = Project::new(&rest, Some(uv.clone()));
    doc.texture = Some("red.png".into());
    doc.fps = 2.0;
    doc.keyframes.push(Keyframe {
        time: 1.0,
        easing: "linear".into(),
        positions: rest.positions.iter().map(|p| [p[0] + 0.1, p[1]]).collect(),
        pins: vec![],
        drawing: Some(KeyframeDrawing {
            picture: "blue.png".into(),
            texcoords: uv,
            pairs: vec![],
        }),
    });
    doc.write(&dir.join("fade.json")).unwrap();
    let centre = |frame: &Path| {
        let img = raster::decode_image(&std::fs::read(frame).unwrap()).unwrap();
        let i = 4 * ((img.height / 2) * img.width + img.width / 2) as usize;
        [img.rgba[i], img.rgba[i + 1], img.rgba[i + 2]]
    };
    let run = |out: &str| {
        let o = bdmorph()
            .current_dir(&dir)
            .args(["export", "fade.json", "--format", "frames", "-o", out])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    run("faded");
    let colours: Vec<[u8; 3]> = (0..3)
        .map(|k| centre(&dir.join(format!("faded/frame_{k:04}.png"))))
        .collect();
    assert!(colours[0][0] > 240 && colours[0][2] < 15, "{colours:?}");
    assert!(colours[2][2] > 240 && colours[2][0] < 15, "{colours:?}");
    // Half way (smooth fade of a linear segment: half and half).
    assert!(
        (100..156).contains(&colours[1][0]) && (100..156).contains(&colours[1][2]),
        "{colours:?}"
    );
    std::fs::remove_file(dir.join("blue.png")).unwrap();
    let said = run("plain");
    assert!(
        said.contains("keyframe 2") && said.contains("blue.png"),
        "{said}"
    );
    let last = centre(&dir.join("plain/frame_0002.png"));
    assert!(last[0] > 240 && last[2] < 15, "{last:?}");
}
