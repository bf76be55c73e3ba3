//! `morph -o anim.mp4`: H.264 MP4 video checked by a real decoder (FFmpeg's `ffprobe` and
//! `ffmpeg`) for codec, frame count, size, duration and pictures.
//!
//! Without FFmpeg the decoder checks are skipped (`SKIPPED: ...`), except in CI (`CI` set),
//! where they fail: CI installs FFmpeg.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use bdmorph::render::{raster, Image};
use bdmorph::{generate, io, PlanarMesh};

fn bdmorph() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bdmorph"))
}

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-video-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn write(dir: &Path, name: &str, m: &PlanarMesh) -> PathBuf {
    let path = dir.join(name);
    io::write_obj_2d(&path, &m.positions, &m.faces, &[]).expect("write");
    path
}

/// Runs a command that must succeed; returns its stderr.
fn run_ok(cmd: &mut Command) -> String {
    let out = cmd.output().expect("runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{stderr}");
    stderr
}

/// FFmpeg's `ffprobe` and `ffmpeg`, or `None` after saying the test is skipped (a failure
/// in CI).
fn ffmpeg_tools() -> Option<(PathBuf, PathBuf)> {
    let find = |name: &str| {
        let path = std::env::var_os("PATH")?;
        std::env::split_paths(&path)
            .map(|dir| dir.join(name))
            .find(|p| p.is_file())
    };
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

/// What `ffprobe` says about the video stream, decoding every frame to count them.
fn probe(ffprobe: &Path, video: &Path) -> HashMap<String, String> {
    let out = Command::new(ffprobe)
        .args([
            "-v",
            "error",
            "-count_frames",
            "-select_streams",
            "v:0",
            "-show_entries",
            "stream=codec_name,width,height,pix_fmt,nb_read_frames,duration,r_frame_rate",
            "-of",
            "default=noprint_wrappers=1",
        ])
        .arg(video)
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

/// Checks codec, size, frame count and duration as a decoder sees them.
fn check_stream(ffprobe: &Path, video: &Path, width: u32, height: u32, frames: usize, fps: u32) {
    let info = probe(ffprobe, video);
    let field = |k: &str| info.get(k).unwrap_or_else(|| panic!("no {k} in {info:?}"));
    assert_eq!(field("codec_name"), "h264");
    assert_eq!(field("pix_fmt"), "yuv420p");
    assert_eq!(field("width"), &width.to_string());
    assert_eq!(field("height"), &height.to_string());
    assert_eq!(field("nb_read_frames"), &frames.to_string(), "every frame");
    assert_eq!(field("r_frame_rate"), &format!("{fps}/1"));
    let duration: f64 = field("duration").parse().expect("a duration");
    let expected = frames as f64 / f64::from(fps);
    assert!(
        (duration - expected).abs() < 0.5 / f64::from(fps),
        "duration {duration} s, expected {expected} s"
    );
}

/// Decodes every frame to RGB with `ffmpeg` (which must report no error): `width * height *
/// 3` bytes per frame.
fn decode_rgb(ffmpeg: &Path, video: &Path) -> Vec<u8> {
    let out = Command::new(ffmpeg)
        .args(["-v", "error", "-i"])
        .arg(video)
        .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
        .output()
        .expect("ffmpeg runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && stderr.trim().is_empty(),
        "ffmpeg: {stderr}"
    );
    out.stdout
}

/// PSNR (dB) of a decoded RGB frame of `video_width` columns against a rendered picture,
/// over the picture's pixels.
fn psnr(decoded: &[u8], video_width: u32, picture: &Image) -> f64 {
    let (w, h) = (picture.width as usize, picture.height as usize);
    let mut sum = 0.0;
    for y in 0..h {
        for x in 0..w {
            for c in 0..3 {
                let a = f64::from(decoded[(y * video_width as usize + x) * 3 + c]);
                let b = f64::from(picture.rgba[(y * w + x) * 4 + c]);
                sum += (a - b).powi(2);
            }
        }
    }
    let mse = sum / (w * h * 3) as f64;
    10.0 * (255.0f64.powi(2) / mse.max(1e-12)).log10()
}

#[test]
fn two_keyframes_make_an_h264_video_ffprobe_reads() {
    let Some((ffprobe, ffmpeg)) = ffmpeg_tools() else {
        return;
    };
    let dir = scratch("two");
    let a = generate::disk(8, 0.2);
    let b = generate::twist(&a, 1.0);
    let (pa, pb) = (write(&dir, "a.obj", &a), write(&dir, "b.obj", &b));
    let video = dir.join("anim.mp4");
    run_ok(
        bdmorph()
            .arg("morph")
            .args([&pa, &pb])
            .args(["--frames", "12", "--fps", "24", "--size", "320x240", "-o"])
            .arg(&video),
    );
    check_stream(&ffprobe, &video, 320, 240, 12, 24);
    let rgb = decode_rgb(&ffmpeg, &video);
    assert_eq!(rgb.len(), 12 * 320 * 240 * 3);
    // The first and last frames differ (the disk turns), and the corners are white.
    let frame = 320 * 240 * 3;
    assert_ne!(&rgb[..frame], &rgb[11 * frame..]);
    assert!(rgb[..3].iter().all(|&c| c > 240), "{:?}", &rgb[..3]);
}

/// A path through three keyframes, at an odd size, as `--format png` frames and as a video:
/// the video is the even size, has every frame, and shows the same pictures.
fn path_matches_png_frames(name: &str, look: &[&str]) {
    let Some((ffprobe, ffmpeg)) = ffmpeg_tools() else {
        return;
    };
    let dir = scratch(name);
    let k0 = generate::disk(8, 0.2);
    let k1 = generate::twist(&k0, 0.8);
    let k2 = generate::twist(&k0, -0.5);
    let keys = [
        write(&dir, "k0.obj", &k0),
        write(&dir, "k1.obj", &k1),
        write(&dir, "k2.obj", &k2),
    ];
    // A texture of coloured stripes.
    let (tw, th) = (64u32, 64u32);
    let texture = Image {
        width: tw,
        height: th,
        rgba: (0..tw * th)
            .flat_map(|i| match (i % tw) / 16 {
                0 => [230, 120, 30, 255],
                1 => [40, 160, 90, 255],
                2 => [50, 70, 200, 255],
                _ => [240, 220, 60, 255],
            })
            .collect(),
    };
    let tex = dir.join("stripes.png");
    std::fs::write(&tex, raster::encode_png(&texture).expect("png")).expect("write");
    let morph = |extra: &[&str], out: &Path| {
        let mut cmd = bdmorph();
        cmd.arg("morph")
            .args(&keys)
            .args(["--frames", "9", "--fps", "12", "--size", "161x121"])
            .args(
                look.iter()
                    .map(|a| a.replace("TEXTURE", tex.to_str().expect("utf8"))),
            )
            .args(extra)
            .arg("-o")
            .arg(out);
        run_ok(&mut cmd)
    };
    let video = dir.join("path.mp4");
    let note = morph(&[], &video);
    assert!(
        note.contains("padded with white to 162x122"),
        "the odd size is announced: {note}"
    );
    check_stream(&ffprobe, &video, 162, 122, 9, 12);
    let pngs = dir.join("pngs");
    morph(&["--format", "png"], &pngs);
    let rgb = decode_rgb(&ffmpeg, &video);
    let frame = 162 * 122 * 3;
    assert_eq!(rgb.len(), 9 * frame);
    for i in 0..9 {
        let picture =
            raster::read_image(pngs.join(format!("frame_{i:04}.png"))).expect("png frame");
        let db = psnr(&rgb[i * frame..(i + 1) * frame], 162, &picture);
        // About 30 dB: small pictures of saturated stripes and thin edges lose most in 4:2:0
        // chroma; a wrong or misplaced picture is far below.
        assert!(db > 26.0, "frame {i}: {db:.1} dB against the PNG frame");
        if i > 0 {
            let other = psnr(&rgb[(i - 1) * frame..i * frame], 162, &picture);
            assert!(
                other < db,
                "frame {i} is in its place ({other:.1} vs {db:.1} dB)"
            );
        }
    }
    // The padding column and row are white.
    let last = &rgb[8 * frame..];
    for y in 0..122 {
        assert!(last[(y * 162 + 161) * 3..][..3].iter().all(|&c| c > 235));
    }
}

#[test]
fn textured_path_at_an_odd_size() {
    path_matches_png_frames("textured", &["--texture", "TEXTURE"]);
}

#[test]
fn path_coloured_by_distortion() {
    path_matches_png_frames("distortion", &["--color-by", "distortion"]);
}

#[test]
fn sizes_the_encoder_cannot_take_are_refused_before_computing() {
    let dir = scratch("sizes");
    let a = generate::disk(4, 0.1);
    let b = generate::twist(&a, 0.5);
    let (pa, pb) = (write(&dir, "a.obj", &a), write(&dir, "b.obj", &b));
    for (size, words) in [("8x8", "too small"), ("4000x100", "too large")] {
        let video = dir.join(format!("{size}.mp4"));
        let out = bdmorph()
            .arg("morph")
            .args([&pa, &pb])
            .args(["--frames", "3", "--stats", "--size", size, "-o"])
            .arg(&video)
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success());
        assert!(stderr.contains(words), "{stderr}");
        assert!(out.stdout.is_empty(), "nothing computed: {:?}", out.stdout);
        assert!(!video.exists());
    }
}

#[test]
fn a_blend_makes_a_one_frame_video() {
    let dir = scratch("blend");
    let a = generate::disk(4, 0.1);
    let b = generate::twist(&a, 0.5);
    let (pa, pb) = (write(&dir, "a.obj", &a), write(&dir, "b.obj", &b));
    let video = dir.join("mix.mp4");
    let stderr = run_ok(
        bdmorph()
            .arg("blend")
            .args([&pa, &pb])
            .args(["--weights", "0.5,0.5", "--size", "64x64", "-o"])
            .arg(&video),
    );
    assert!(stderr.contains("one frame"), "{stderr}");
    let Some((ffprobe, _)) = ffmpeg_tools() else {
        return;
    };
    check_stream(&ffprobe, &video, 64, 64, 1, 25);
}

/// A video streamed frame by frame into a file (`Mp4Encoder`, frames rendered one at a time)
/// is the one `encode_mp4` makes of the same frames, and a decoder reads every frame.
#[test]
fn a_video_streamed_into_a_file_decodes_with_every_frame() {
    use bdmorph::render::video::{self, Mp4Encoder};
    use bdmorph::render::{Drawing, ImageSize, Viewport};
    let dir = scratch("streamed");
    let mesh = generate::disk(8, 0.2);
    let view = Viewport::fit([&mesh.positions[..]]);
    let size = ImageSize {
        width: 97,
        height: 64,
    };
    let picture = |i: usize| {
        let moved = generate::twist(&mesh, 0.1 * i as f64);
        let drawing = Drawing {
            faces: &moved.faces,
            corner_uv: None,
            texture: None,
            face_colours: None,
            depth: None,
        };
        raster::render(&moved.positions, &drawing, &view, size).expect("within the picture budget")
    };
    let path = dir.join("streamed.mp4");
    let file = std::fs::File::create(&path).expect("create");
    let mut encoder = Mp4Encoder::new(file, 97, 64, 15).expect("encoder");
    for i in 0..31 {
        encoder.push(&picture(i)).expect("push");
    }
    drop(encoder.finish().expect("finish"));
    let frames: Vec<Image> = (0..31).map(picture).collect();
    let whole = video::encode_mp4(&frames, 15).expect("encode_mp4");
    assert_eq!(std::fs::read(&path).expect("read"), whole);
    let Some((ffprobe, ffmpeg)) = ffmpeg_tools() else {
        return;
    };
    check_stream(&ffprobe, &path, 98, 64, 31, 15);
    let rgb = decode_rgb(&ffmpeg, &path);
    assert_eq!(rgb.len(), 31 * 98 * 64 * 3);
    for (i, picture) in frames.iter().enumerate() {
        let db = psnr(&rgb[i * 98 * 64 * 3..][..98 * 64 * 3], 98, picture);
        assert!(db > 30.0, "frame {i}: {db:.1} dB");
    }
}
