//! The command line's contracts: `morph --t`, `morph --frames`, `--stats`, `demo`, errors.

use std::path::{Path, PathBuf};
use std::process::Command;

use bdmorph::{generate, io, PlanarMesh};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bdmorph"))
}

fn morph() -> Command {
    let mut c = bin();
    c.arg("morph");
    c
}

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn write(dir: &Path, name: &str, m: &PlanarMesh) -> PathBuf {
    let path = dir.join(name);
    io::write_obj_2d(&path, &m.positions, &m.faces, &[]).expect("write");
    path
}

fn pair(dir: &Path) -> (PlanarMesh, PathBuf, PlanarMesh, PathBuf) {
    let a = generate::disk(6, 0.2);
    let b = generate::twist(&a, 0.8);
    let pa = write(dir, "a.obj", &a);
    let pb = write(dir, "b.obj", &b);
    (a, pa, b, pb)
}

#[test]
fn morph_single_frame_writes_the_source_order_and_faces() {
    let dir = scratch("single");
    let (a, pa, _, pb) = pair(&dir);
    let out = dir.join("half.obj");
    let status = morph()
        .args([
            pa.as_os_str(),
            pb.as_os_str(),
            "--t".as_ref(),
            "0".as_ref(),
            "-o".as_ref(),
        ])
        .arg(&out)
        .status()
        .expect("runs");
    assert!(status.success());
    let text = std::fs::read_to_string(&out).expect("written");
    assert!(text
        .lines()
        .any(|l| l.starts_with("v ") && l.ends_with(" 0")));
    let back = PlanarMesh::read(&out).expect("readable");
    assert_eq!(back.faces, a.faces);
    let err = back
        .positions
        .iter()
        .zip(&a.positions)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max);
    assert!(err < 1e-9 * a.diameter(), "t = 0 frame is off by {err}");
}

#[test]
fn morph_frames_writes_numbered_files() {
    let dir = scratch("frames");
    let (_, pa, b, pb) = pair(&dir);
    let out = dir.join("frames");
    let status = morph()
        .arg(&pa)
        .arg(&pb)
        .args(["--frames", "4", "-o"])
        .arg(&out)
        .status()
        .expect("runs");
    assert!(status.success());
    for i in 0..4 {
        assert!(out.join(format!("frame_{i:04}.obj")).is_file(), "frame {i}");
    }
    assert!(!out.join("frame_0004.obj").exists());
    let last = PlanarMesh::read(out.join("frame_0003.obj")).expect("readable");
    let err = last
        .positions
        .iter()
        .zip(&b.positions)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max);
    assert!(err < 1e-9 * b.diameter());
}

#[test]
fn stats_without_output_prints_json_and_writes_nothing() {
    let dir = scratch("stats");
    let (_, pa, _, pb) = pair(&dir);
    let before: Vec<_> = std::fs::read_dir(&dir).expect("dir").collect();
    let out = morph()
        .arg(&pa)
        .arg(&pb)
        .args(["--frames", "3", "--stats"])
        .output()
        .expect("runs");
    assert!(out.status.success());
    let stdout = String::from_utf8(out.stdout).expect("utf8");
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 3);
    for (line, t) in lines.iter().zip(["0", "0.5", "1"]) {
        assert!(line.starts_with(&format!("{{\"t\":{t},")), "{line}");
        for key in [
            "\"newton_iterations\":",
            "\"factorizations\":",
            "\"cg_iterations\":",
            "\"gradient_norm\":",
            "\"flipped_triangles\":0",
            "\"max_conformal_distortion\":",
            "\"seconds\":",
        ] {
            assert!(line.contains(key), "{line} lacks {key}");
        }
        // The frame's time is a positive number of seconds.
        let seconds: f64 = line
            .split("\"seconds\":")
            .nth(1)
            .and_then(|rest| rest.trim_end_matches('}').parse().ok())
            .expect("a number");
        assert!(seconds > 0.0 && seconds < 60.0, "{line}");
    }
    let after: Vec<_> = std::fs::read_dir(&dir).expect("dir").collect();
    assert_eq!(before.len(), after.len());
}

#[test]
fn errors_are_one_line_name_the_file_and_write_nothing() {
    let dir = scratch("errors");
    let (_, pa, _, _) = pair(&dir);
    let other = write(&dir, "other.obj", &generate::disk(5, 0.0));
    let out = dir.join("never.obj");
    // Mismatched pair.
    let r = morph()
        .arg(&pa)
        .arg(&other)
        .args(["--t", "0.5", "-o"])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(!r.status.success());
    let err = String::from_utf8(r.stderr).expect("utf8");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("vertex count"), "{err}");
    assert!(!out.exists());
    // Missing file.
    let r = morph()
        .arg(dir.join("missing.obj"))
        .arg(&pa)
        .args(["--t", "0.5", "-o"])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(!r.status.success());
    assert!(String::from_utf8(r.stderr)
        .expect("utf8")
        .contains("missing.obj"));
    // Parse error with a line number.
    let bad = dir.join("bad.obj");
    std::fs::write(&bad, "v 0 0\nv 1 0\nv 0 x\nf 1 2 3\n").expect("write");
    let r = morph()
        .arg(&bad)
        .arg(&pa)
        .args(["--t", "0.5", "-o"])
        .arg(&out)
        .output()
        .expect("runs");
    let err = String::from_utf8(r.stderr).expect("utf8");
    assert!(!r.status.success() && err.contains("bad.obj:3"), "{err}");
    // t not a number, and no action.
    let r = morph()
        .arg(&pa)
        .arg(&pa)
        .args(["--t", "inf", "-o"])
        .arg(&out)
        .output()
        .expect("runs");
    let err = String::from_utf8(r.stderr).expect("utf8");
    assert!(
        !r.status.success() && err.contains("not a finite number"),
        "{err}"
    );
    let r = morph()
        .arg(&pa)
        .arg(&pa)
        .args(["--t", "0.5"])
        .output()
        .expect("runs");
    assert!(!r.status.success());
    assert!(!out.exists());
}

#[test]
fn demo_writes_frames() {
    let dir = scratch("demo");
    let out = dir.join("demo");
    let r = bin()
        .args(["demo", "--frames", "6", "--size", "80x80", "-o"])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    for name in [
        "viewer.html",
        "morph.gif",
        "morph.mp4",
        "frames.png",
        "figure.png",
        "source.obj",
        "target.obj",
    ] {
        assert!(out.join(name).is_file(), "{name}");
    }
    let stdout = String::from_utf8(r.stdout).expect("utf8");
    assert!(stdout.contains("0 flipped triangles"), "{stdout}");
    assert!(stdout.contains("viewer.html"), "{stdout}");
    let strip = bdmorph::render::raster::read_image(out.join("frames.png")).expect("png");
    assert!(
        strip.width > 4 * 80 && strip.height >= 80,
        "five pictures side by side"
    );
}

#[test]
fn the_readme_path_from_a_picture_to_an_animation_works() {
    // The README's four commands (fewer frames), then what each one promised.
    let dir = scratch("picture-path");
    let run = |args: &[&str]| {
        let r = bin().args(args).current_dir(&dir).output().expect("runs");
        assert!(
            r.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
        (
            String::from_utf8(r.stdout).expect("utf8"),
            String::from_utf8(r.stderr).expect("utf8"),
        )
    };
    run(&["demo", "--frames", "3", "--size", "80x80", "-q"]);
    let picture = bdmorph::render::raster::read_image(dir.join("bdmorph-demo/figure.png"))
        .expect("figure.png");
    let transparent = picture.rgba.chunks(4).filter(|p| p[3] == 0).count();
    let opaque = picture.rgba.chunks(4).filter(|p| p[3] == 255).count();
    assert!(
        transparent > 1000 && opaque > 1000,
        "a subject on a transparent ground"
    );
    run(&["mesh", "bdmorph-demo/figure.png", "-o", "figure.obj", "-q"]);
    let (_, err) = run(&[
        "deform",
        "figure.obj",
        "--fix",
        "165,30",
        "--fix",
        "265,30",
        "--fix",
        "210,480",
        "--drag",
        "405,345:345,455",
        "--max-distortion",
        "4",
        "-o",
        "wave.obj",
    ]);
    assert!(err.contains("--drag 405,345 is vertex "), "{err}");
    // The posing section's command: the same handles by KVF.
    let (kvf, _) = run(&[
        "deform",
        "figure.obj",
        "--method",
        "kvf",
        "--fix",
        "165,30",
        "--fix",
        "265,30",
        "--fix",
        "210,480",
        "--drag",
        "405,345:345,455",
        "--stats",
        "-o",
        "wave_kvf.obj",
    ]);
    assert!(
        kvf.contains("\"method\":\"kvf\"") && kvf.contains("\"flipped_triangles\":0"),
        "{kvf}"
    );
    let (stats, _) = run(&[
        "morph",
        "figure.obj",
        "wave.obj",
        "--frames",
        "6",
        "--texture",
        "bdmorph-demo/figure.png",
        "--stats",
        "-o",
        "wave.mp4",
    ]);
    assert_eq!(stats.lines().count(), 6);
    assert!(
        stats.lines().all(|l| l.contains("\"flipped_triangles\":0")),
        "{stats}"
    );
    let video = std::fs::read(dir.join("wave.mp4")).expect("wave.mp4");
    assert_eq!(&video[4..8], b"ftyp");
    // The dragged vertex is where the drag put it; the mesh kept its texture coordinates.
    let rest = bdmorph::io::read_mesh(dir.join("figure.obj")).expect("figure.obj");
    let posed = bdmorph::io::read_mesh(dir.join("wave.obj")).expect("wave.obj");
    assert!(rest.texcoords.is_some());
    let v = err
        .split("--drag 405,345 is vertex ")
        .nth(1)
        .and_then(|s| s.split([',', ' ']).next())
        .and_then(|s| s.parse::<usize>().ok())
        .expect("vertex");
    let p = posed.positions[v];
    assert!((p[0] - 345.0).hypot(p[1] - 455.0) < 1e-6, "{p:?}");
    // Two handles on one vertex, or none at all, are refused.
    let err = fails_writing_nothing(
        bin().args([
            "deform",
            "figure.obj",
            "--fix",
            "165,30",
            "--drag",
            "165.5,30:170,40",
            "--max-distortion",
            "4",
            "-o",
            "twice.obj",
        ]),
        &dir,
    );
    assert!(err.contains("are both on vertex"), "{err}");
    let r = bin()
        .args([
            "deform",
            "figure.obj",
            "--max-distortion",
            "4",
            "-o",
            "none.obj",
        ])
        .current_dir(&dir)
        .output()
        .expect("runs");
    assert!(!r.status.success() && !dir.join("none.obj").exists());
}

fn run_ok(cmd: &mut Command) -> std::process::Output {
    let out = cmd.output().expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

#[test]
fn info_reports_counts_and_morphability() {
    let dir = scratch("info");
    let (_, pa, _, _) = pair(&dir);
    let out = run_ok(bin().arg("info").arg(&pa));
    let text = String::from_utf8(out.stdout).expect("utf8");
    assert!(text.contains("vertices 127, faces 216"), "{text}");
    assert!(text.contains("boundary loops 1"), "{text}");
    assert!(text.contains("morphable: yes"), "{text}");
    // A ring has two boundary loops and cannot be morphed.
    let ring = dir.join("ring.obj");
    let mut obj = String::new();
    for i in 0..8 {
        let a = f64::from(i) * std::f64::consts::TAU / 8.0;
        obj += &format!(
            "v {} {}\nv {} {}\n",
            2.0 * a.cos(),
            2.0 * a.sin(),
            a.cos(),
            a.sin()
        );
    }
    for i in 0..8u32 {
        let (o0, i0, o1, i1) = (
            2 * i + 1,
            2 * i + 2,
            2 * ((i + 1) % 8) + 1,
            2 * ((i + 1) % 8) + 2,
        );
        obj += &format!("f {o0} {o1} {i1}\nf {o0} {i1} {i0}\n");
    }
    std::fs::write(&ring, obj).expect("write");
    let text = String::from_utf8(run_ok(bin().arg("info").arg(&ring)).stdout).expect("utf8");
    assert!(text.contains("boundary loops 2"), "{text}");
    assert!(
        text.contains("morphable: yes (counter-clockwise and planar, 1 piece with 1 hole; each hole is filled with hidden triangles for the solve)"),
        "{text}"
    );
}

#[test]
fn every_output_format_is_written() {
    let dir = scratch("formats");
    let (_, pa, _, pb) = pair(&dir);
    let single = |name: &str| {
        let out = dir.join(name);
        run_ok(
            morph()
                .arg(&pa)
                .arg(&pb)
                .args(["--t", "0.5", "--size", "64x48", "-o"])
                .arg(&out),
        );
        std::fs::read(&out).expect("written")
    };
    assert!(single("f.svg").starts_with(b"<svg"));
    assert!(single("f.png").starts_with(b"\x89PNG\r\n\x1a\n"));
    assert!(single("f.obj").starts_with(b"#"));
    let animation = |name: &str| {
        let out = dir.join(name);
        run_ok(
            morph()
                .arg(&pa)
                .arg(&pb)
                .args(["--frames", "5", "--size", "64x64", "-o"])
                .arg(&out),
        );
        std::fs::read(&out).expect("written")
    };
    assert!(animation("m.gif").starts_with(b"GIF89a"));
    assert_eq!(&animation("m.mp4")[4..8], b"ftyp");
    let page = String::from_utf8(animation("m.html")).expect("utf8");
    assert!(page.contains("<canvas") && !page.contains("<script src"));
    // Per-frame pictures in a directory.
    let pngs = dir.join("pngs");
    run_ok(
        morph()
            .arg(&pa)
            .arg(&pb)
            .args(["--frames", "3", "--format", "png", "--size", "32x32", "-o"])
            .arg(&pngs),
    );
    for i in 0..3 {
        assert!(pngs.join(format!("frame_{i:04}.png")).is_file());
    }
    let svgs = dir.join("svgs");
    run_ok(
        morph()
            .arg(&pa)
            .arg(&pb)
            .args(["--frames", "2", "--format", "svg", "-o"])
            .arg(&svgs),
    );
    assert!(svgs.join("frame_0001.svg").is_file());
}

#[test]
fn textures_change_the_picture_and_texture_coordinates_ride_along() {
    let dir = scratch("texture");
    let a = generate::disk(6, 0.2);
    let b = generate::twist(&a, 0.8);
    // The source carries vt (its normalised positions); the target does not need them.
    let tex = a.normalized_texcoords();
    let pa = dir.join("a.obj");
    io::write_obj_2d_textured(&pa, &a.positions, &a.faces, Some(&tex), &[]).expect("write");
    let pb = write(&dir, "b.obj", &b);
    // A red/blue checkerboard texture.
    let mut rgba = Vec::new();
    for y in 0..8u32 {
        for x in 0..8u32 {
            rgba.extend_from_slice(if (x / 2 + y / 2) % 2 == 0 {
                &[220, 30, 30, 255]
            } else {
                &[30, 30, 220, 255]
            });
        }
    }
    let img = bdmorph::render::Image {
        width: 8,
        height: 8,
        rgba,
    };
    let texture = dir.join("checker.png");
    std::fs::write(
        &texture,
        bdmorph::render::raster::encode_png(&img).expect("png"),
    )
    .expect("write");
    let plain = dir.join("plain.png");
    let textured = dir.join("textured.png");
    run_ok(
        morph()
            .arg(&pa)
            .arg(&pb)
            .args(["--t", "0.5", "--size", "64x64", "-o"])
            .arg(&plain),
    );
    run_ok(
        morph()
            .arg(&pa)
            .arg(&pb)
            .args(["--t", "0.5", "--size", "64x64", "--texture"])
            .arg(&texture)
            .arg("-o")
            .arg(&textured),
    );
    let decode = |p: &Path| bdmorph::render::raster::read_image(p).expect("decodes");
    let (p, t) = (decode(&plain), decode(&textured));
    let reddish = |i: &bdmorph::render::Image| {
        i.rgba
            .chunks(4)
            .filter(|c| c[0] > 150 && c[1] < 90 && c[2] < 90)
            .count()
    };
    assert!(
        reddish(&t) > 100 && reddish(&t) > 10 * reddish(&p).max(1),
        "texture visible"
    );
    // OBJ frames carry the source's vt.
    let frames = dir.join("objs");
    run_ok(
        morph()
            .arg(&pa)
            .arg(&pb)
            .args(["--frames", "2", "-o"])
            .arg(&frames),
    );
    let text = std::fs::read_to_string(frames.join("frame_0001.obj")).expect("written");
    assert!(
        text.contains("\nvt ") && text.contains('/'),
        "vt lines and f a/ta corners"
    );
    let back = io::read_mesh(frames.join("frame_0001.obj")).expect("parses");
    assert_eq!(back.texcoords, Some(tex));
}

#[test]
fn output_mistakes_are_refused_before_anything_is_written() {
    let dir = scratch("mistakes");
    let (_, pa, _, pb) = pair(&dir);
    let fails = |args: &[&str], needle: &str| {
        let r = morph().arg(&pa).arg(&pb).args(args).output().expect("runs");
        let err = String::from_utf8(r.stderr).expect("utf8");
        assert!(!r.status.success(), "{args:?} should fail");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
    };
    let o = |name: &str| dir.join(name).display().to_string();
    fails(
        &["--t", "0.5", "-o", &o("x.jpg")],
        "unknown output extension",
    );
    fails(&["--frames", "3", "-o", &o("x.png")], "names a directory");
    fails(
        &[
            "--t",
            "0.5",
            "--texture",
            &o("missing.png"),
            "-o",
            &o("y.png"),
        ],
        "missing.png",
    );
    fails(&["--t", "0.5", "--size", "big", "-o", &o("z.png")], "WxH");
    for name in ["x.jpg", "x.png", "y.png", "z.png"] {
        assert!(!dir.join(name).exists(), "{name} must not be written");
    }
    // A quad is refused with its line.
    let quad = dir.join("quad.obj");
    std::fs::write(&quad, "v 0 0\nv 1 0\nv 1 1\nv 0 1\nf 1 2 3 4\n").expect("write");
    let r = morph()
        .arg(&quad)
        .arg(&quad)
        .args(["--t", "0.5", "--stats"])
        .output()
        .expect("runs");
    let err = String::from_utf8(r.stderr).expect("utf8");
    assert!(!r.status.success() && err.contains("quad.obj:5"), "{err}");
}

#[test]
fn help_and_version() {
    let out = run_ok(bin().arg("--version"));
    assert!(String::from_utf8(out.stdout)
        .expect("utf8")
        .starts_with("bdmorph "));
    let out = run_ok(bin().args(["morph", "--help"]));
    let help = String::from_utf8(out.stdout).expect("utf8");
    assert!(
        help.contains("Examples:") && help.contains("refused, not triangulated"),
        "{help}"
    );
}

#[test]
fn frames_that_fail_are_reported_and_not_written() {
    let dir = scratch("failing-frames");
    let (_, pa, _, pb) = pair(&dir);
    let out = dir.join("frames");
    // One Newton step is not enough at t = 0.5; t = 0 and t = 1 (warm from u = 0, and the
    // target is flat) need none.
    let r = morph()
        .arg(&pa)
        .arg(&pb)
        .args(["--frames", "3", "--max-iterations", "1", "--stats", "-o"])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(!r.status.success());
    let err = String::from_utf8(r.stderr).expect("utf8");
    assert!(
        err.contains("frame t = 0.5") && err.contains("frame skipped"),
        "{err}"
    );
    assert!(err.contains("worst triangles"), "{err}");
    assert!(err.contains("1 of 3 frames could not be computed"), "{err}");
    assert!(out.join("frame_0000.obj").is_file());
    assert!(!out.join("frame_0001.obj").exists());
    assert!(out.join("frame_0002.obj").is_file());
    let stdout = String::from_utf8(r.stdout).expect("utf8");
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with("{\"t\":0.5,\"error\":\"")),
        "{stdout}"
    );
}

/// Three poses of one disk, written as a.obj, b.obj, c.obj.
fn poses(dir: &Path) -> (Vec<PlanarMesh>, Vec<PathBuf>) {
    let a = generate::disk(6, 0.2);
    let keys = vec![
        a.clone(),
        generate::bend(&a, 0.6),
        generate::twist(&generate::stretch(&a, 1.4), 0.7),
    ];
    let paths = ["a.obj", "b.obj", "c.obj"]
        .iter()
        .zip(&keys)
        .map(|(name, m)| write(dir, name, m))
        .collect();
    (keys, paths)
}

fn off_by(path: &Path, want: &PlanarMesh) -> f64 {
    let got = PlanarMesh::read(path).expect("readable");
    assert_eq!(got.faces, want.faces);
    got.positions
        .iter()
        .zip(&want.positions)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max)
        / want.diameter()
}

#[test]
fn blend_writes_one_frame_with_its_weights_in_the_stats() {
    let dir = scratch("blend");
    let (keys, paths) = poses(&dir);
    let out = dir.join("mix.obj");
    let r = run_ok(
        bin()
            .arg("blend")
            .args(&paths)
            .args(["--weights", "0,1,0", "--stats", "-o"])
            .arg(&out),
    );
    assert!(off_by(&out, &keys[1]) < 1e-9);
    let stdout = String::from_utf8(r.stdout).expect("utf8");
    assert!(stdout.starts_with("{\"weights\":[0,1,0],"), "{stdout}");
    assert!(stdout.contains("\"max_conformal_distortion\":"), "{stdout}");
    // Weights slightly outside the simplex extrapolate; far outside, the triangle is named.
    run_ok(
        bin()
            .arg("blend")
            .args(&paths)
            .args(["--weights", "-0.05,0.5,0.55", "--stats"]),
    );
    let r = bin()
        .arg("blend")
        .args(&paths)
        .args(["--weights", "-4,0.5,4.5", "-o"])
        .arg(dir.join("far.obj"))
        .output()
        .expect("runs");
    let err = String::from_utf8(r.stderr).expect("utf8");
    assert!(!r.status.success(), "{err}");
    assert!(
        err.contains("triangle") && err.contains("break the triangle inequality"),
        "{err}"
    );
    assert!(!dir.join("far.obj").exists());
    // Weights that do not fit are refused before anything is read.
    for (weights, says) in [("0.5,0.5", "3 meshes"), ("0.5,0.5,0.5", "sum to 1")] {
        let r = bin()
            .arg("blend")
            .args(&paths)
            .args(["--weights", weights, "--stats"])
            .output()
            .expect("runs");
        let err = String::from_utf8(r.stderr).expect("utf8");
        assert!(
            !r.status.success() && err.contains(says),
            "{weights}: {err}"
        );
    }
}

#[test]
fn morph_through_several_meshes_passes_through_each() {
    let dir = scratch("path");
    let (keys, paths) = poses(&dir);
    let out = dir.join("frames");
    run_ok(morph().args(&paths).args(["--frames", "5", "-o"]).arg(&out));
    for (frame, key) in [(0, 0), (2, 1), (4, 2)] {
        let err = off_by(&out.join(format!("frame_{frame:04}.obj")), &keys[key]);
        assert!(err < 1e-9, "frame {frame}: off by {err}");
    }
    // Durations 1, 3: keyframe 1 is reached at t = 0.25, frame 1 of 5; eased segments too.
    let out = dir.join("timed");
    run_ok(
        morph()
            .args(&paths)
            .args([
                "--frames",
                "5",
                "--durations",
                "1,3",
                "--easing",
                "ease-in-out",
            ])
            .args(["--easing", "cubic-bezier(0.2,0,0.4,1)", "-o"])
            .arg(&out),
    );
    assert!(off_by(&out.join("frame_0001.obj"), &keys[1]) < 1e-9);
    assert!(off_by(&out.join("frame_0004.obj"), &keys[2]) < 1e-9);
    // Per-segment values must match the segments.
    for args in [
        &["--durations", "1,2,3"][..],
        &[
            "--easing", "linear", "--easing", "linear", "--easing", "linear",
        ][..],
        &["--easing", "wobbly"][..],
    ] {
        let r = morph()
            .args(&paths)
            .args(["--frames", "3", "--stats"])
            .args(args)
            .output()
            .expect("runs");
        assert!(!r.status.success(), "{args:?}");
    }
}

#[test]
fn morph_t_outside_zero_one_extrapolates_until_a_triangle_breaks() {
    let dir = scratch("extrapolate");
    let (_, pa, _, pb) = pair(&dir);
    let out = dir.join("beyond.obj");
    run_ok(
        morph()
            .arg(&pa)
            .arg(&pb)
            .args(["--t", "1.05", "-o"])
            .arg(&out),
    );
    assert!(out.is_file());
    run_ok(morph().arg(&pa).arg(&pb).args(["--t", "-0.05", "--stats"]));
    let r = morph()
        .arg(&pa)
        .arg(&pb)
        .args(["--t", "40", "--stats"])
        .output()
        .expect("runs");
    let err = String::from_utf8(r.stderr).expect("utf8");
    assert!(!r.status.success());
    assert!(
        err.contains("t = 40: the extrapolated edge lengths of triangle")
            && err.contains("from t = "),
        "{err}"
    );
}

#[test]
fn pictures_can_be_coloured_by_distortion() {
    let dir = scratch("colour");
    let (_, paths) = poses(&dir);
    let picture = |name: &str, colour: bool| {
        let out = dir.join(name);
        let mut cmd = bin();
        cmd.arg("blend")
            .args(&paths)
            .args(["--weights", "0.2,0.3,0.5", "--size", "200x200", "-o"])
            .arg(&out);
        if colour {
            cmd.args(["--color-by", "distortion"]);
        }
        run_ok(&mut cmd);
        std::fs::read(&out).expect("written")
    };
    assert_ne!(picture("plain.png", false), picture("coloured.png", true));
    let svg = String::from_utf8(picture("coloured.svg", true)).expect("utf8");
    // Several fill groups of the colour ramp instead of one flat fill.
    assert!(svg.matches("<g fill=").count() > 3, "{svg}");
    assert!(!svg.contains("fill=\"#cfe0f5\""));
    let html = String::from_utf8(picture("coloured.html", true)).expect("utf8");
    assert!(html.contains("id=\"legend\"") && html.contains("conformal distortion"));
    let plain = String::from_utf8(picture("plain.html", false)).expect("utf8");
    assert!(!plain.contains("id=\"legend\"") && plain.contains("shades: null"));
}

fn write_surface(dir: &Path, name: &str, mesh: &bdmorph::SurfaceMesh) -> PathBuf {
    let mut text = String::new();
    for p in &mesh.positions {
        text.push_str(&format!("v {} {} {}\n", p[0], p[1], p[2]));
    }
    for f in &mesh.faces {
        text.push_str(&format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1));
    }
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write");
    path
}

#[test]
fn geodesic_exact_distances_and_shortest_paths() {
    let dir = scratch("geodesic-exact");
    let sphere = generate::icosphere(2);
    let n = sphere.positions.len();
    let mesh = write_surface(&dir, "sphere.obj", &sphere);
    let read = |path: &Path| -> Vec<Vec<f64>> {
        std::fs::read_to_string(path)
            .expect("written")
            .lines()
            .map(|l| l.split(' ').map(|x| x.parse().expect("a number")).collect())
            .collect()
    };
    // --exact agrees with the library, field by field and for the nearest source.
    let mut exact = bdmorph::geodesic::ExactGeodesics::new(&sphere).expect("set up");
    let out = dir.join("exact.txt");
    let r = run_ok(
        bin()
            .arg("geodesic")
            .arg(&mesh)
            .args(["--exact", "--each-source", "0,9", "--stats", "-o"])
            .arg(&out),
    );
    let rows = read(&out);
    assert_eq!(rows.len(), n);
    for (k, s) in [0u32, 9].into_iter().enumerate() {
        let want = exact.distance(&[s]).expect("query");
        for v in 0..n {
            assert!((rows[v][k] - want[v]).abs() <= 1e-15 * (1.0 + want[v]));
        }
    }
    let stats = String::from_utf8(r.stdout).expect("utf8");
    assert!(
        stats.contains("\"exact\":true") && stats.contains("\"windows\":"),
        "{stats}"
    );
    // --path: a polyline as long as the distance, as text and as an OBJ polyline.
    let d = exact.distance(&[3]).expect("query");
    let far = (0..n)
        .max_by(|&i, &j| d[i].total_cmp(&d[j]))
        .expect("vertices");
    let pair = format!("3,{far}");
    let txt = dir.join("path.txt");
    run_ok(
        bin()
            .arg("geodesic")
            .arg(&mesh)
            .args(["--path", &pair, "--exact", "-o"])
            .arg(&txt),
    );
    let points = read(&txt);
    assert!(points.len() > 2 && points.iter().all(|p| p.len() == 3));
    let length: f64 = points
        .windows(2)
        .map(|w| {
            ((w[0][0] - w[1][0]).powi(2)
                + (w[0][1] - w[1][1]).powi(2)
                + (w[0][2] - w[1][2]).powi(2))
            .sqrt()
        })
        .sum();
    assert!((length - d[far]).abs() < 1e-9, "{length} vs {}", d[far]);
    assert_eq!(points[0], sphere.positions[3].to_vec());
    let obj = dir.join("path.obj");
    run_ok(
        bin()
            .arg("geodesic")
            .arg(&mesh)
            .args(["--path", &pair, "--exact", "-o"])
            .arg(&obj),
    );
    let text = std::fs::read_to_string(&obj).expect("written");
    assert_eq!(
        text.lines().filter(|l| l.starts_with("v ")).count(),
        points.len()
    );
    let line = text
        .lines()
        .find(|l| l.starts_with("l "))
        .expect("a polyline");
    assert_eq!(line.split(' ').count(), points.len() + 1);
    // Without --exact: down the heat method's distance, a little longer than the shortest.
    let heat = dir.join("heat.txt");
    let r = run_ok(
        bin()
            .arg("geodesic")
            .arg(&mesh)
            .args(["--path", &pair, "--stats", "-o"])
            .arg(&heat),
    );
    assert!(String::from_utf8(r.stdout)
        .expect("utf8")
        .contains("\"exact\":false"));
    let points = read(&heat);
    let length: f64 = points
        .windows(2)
        .map(|w| {
            ((w[0][0] - w[1][0]).powi(2)
                + (w[0][1] - w[1][1]).powi(2)
                + (w[0][2] - w[1][2]).powi(2))
            .sqrt()
        })
        .sum();
    assert!(
        length >= d[far] - 1e-9 && length < 1.03 * d[far],
        "{length} vs {}",
        d[far]
    );
    assert_eq!(points[0], sphere.positions[3].to_vec());
    assert_eq!(points[points.len() - 1], sphere.positions[far].to_vec());
    // Errors, each one line.
    for (args, says) in [
        (&["--path", "0", "-o", "p.txt"][..], "A,B"),
        (&["--path", "0,x", "-o", "p.txt"][..], "not a vertex index"),
        (&["--path", "0,99999", "-o", "p.txt"][..], "does not exist"),
        (&["--path", "0,1"][..], "-o OUT.txt"),
        (&["--path", "0,1", "-o", "p.png"][..], "unknown path output"),
        (
            &["--path", "0,1", "--source", "2", "-o", "p.txt"][..],
            "cannot be used",
        ),
    ] {
        let r = bin()
            .arg("geodesic")
            .arg(&mesh)
            .args(args)
            .current_dir(&dir)
            .output()
            .expect("runs");
        let err = String::from_utf8(r.stderr).expect("utf8");
        assert!(!r.status.success() && err.contains(says), "{args:?}: {err}");
    }
}

#[test]
fn geodesic_writes_distances_columns_and_pictures() {
    let dir = scratch("geodesic");
    let sphere = generate::icosphere(2);
    let n = sphere.positions.len();
    let mesh = write_surface(&dir, "sphere.obj", &sphere);
    // One field: one value per line, zero at the sources.
    let out = dir.join("d.txt");
    run_ok(
        bin()
            .arg("geodesic")
            .arg(&mesh)
            .args(["--source", "0", "--source", "5", "-o"])
            .arg(&out),
    );
    let values: Vec<f64> = std::fs::read_to_string(&out)
        .expect("written")
        .lines()
        .map(|l| l.parse().expect("a number"))
        .collect();
    assert_eq!(values.len(), n);
    assert_eq!((values[0], values[5]), (0.0, 0.0));
    assert!(values.iter().all(|d| (0.0..3.3).contains(d)));
    // One column per source.
    let out = dir.join("each.txt");
    let r = run_ok(
        bin()
            .arg("geodesic")
            .arg(&mesh)
            .args(["--each-source", "0,5,7", "--stats", "-o"])
            .arg(&out),
    );
    let text = std::fs::read_to_string(&out).expect("written");
    let rows: Vec<Vec<f64>> = text
        .lines()
        .map(|l| l.split(' ').map(|x| x.parse().expect("a number")).collect())
        .collect();
    assert_eq!(rows.len(), n);
    assert!(rows.iter().all(|r| r.len() == 3));
    assert_eq!((rows[0][0], rows[5][1], rows[7][2]), (0.0, 0.0, 0.0));
    // The nearest-source field is close to the minimum of the columns (within about an
    // edge, 0.3 on this coarse sphere, along the ridge where the sources are equally near).
    let mut mean = 0.0;
    for (v, row) in rows.iter().enumerate() {
        let nearest = row[0].min(row[1]);
        assert!((values[v] - nearest).abs() < 0.5, "vertex {v}");
        mean += (values[v] - nearest).abs() / n as f64;
    }
    assert!(mean < 0.1, "mean difference {mean}");
    let stats = String::from_utf8(r.stdout).expect("utf8");
    assert!(
        stats.contains("\"fields\":3") && stats.contains("\"setup_seconds\":"),
        "{stats}"
    );
    // Pictures.
    for name in ["d.png", "d.html"] {
        let out = dir.join(name);
        run_ok(
            bin()
                .arg("geodesic")
                .arg(&mesh)
                .args(["--source", "0", "--size", "160x120", "-o"])
                .arg(&out),
        );
        let bytes = std::fs::read(&out).expect("written");
        if name.ends_with(".png") {
            let img = bdmorph::render::raster::decode_image(&bytes).expect("a PNG");
            assert_eq!((img.width, img.height), (160, 120));
        } else {
            let page = String::from_utf8(bytes).expect("utf8");
            assert!(page.contains("<figure><img") && page.contains("Isolines every"));
        }
    }
    // Refined: the same vertices, the refinement reported by --stats.
    let r = run_ok(
        bin()
            .arg("geodesic")
            .arg(&mesh)
            .args(["--source", "3", "--refine", "30", "--stats", "-q", "-o"])
            .arg(dir.join("refined.txt")),
    );
    let stats = String::from_utf8(r.stdout).expect("utf8");
    assert!(stats.contains("\"refined_min_angle\":"), "{stats}");
    let refined = std::fs::read_to_string(dir.join("refined.txt")).expect("written");
    assert_eq!(refined.lines().count(), n);
    // Errors: a vertex that does not exist, an unknown extension, no source, a bad option.
    for (args, says) in [
        (&["--source", "9999", "-o", "x.txt"][..], "does not exist"),
        (
            &["--source", "0", "-o", "x.obj"][..],
            "unknown output extension",
        ),
        (&["-o", "x.txt"][..], "--source"),
        (
            &["--source", "0", "--refine", "-1", "-o", "x.txt"][..],
            "refinement angle -1",
        ),
    ] {
        let r = bin()
            .arg("geodesic")
            .arg(&mesh)
            .args(args)
            .current_dir(&dir)
            .output()
            .expect("runs");
        let err = String::from_utf8(r.stderr).expect("utf8");
        assert!(!r.status.success() && err.contains(says), "{args:?}: {err}");
    }
    assert!(!dir.join("x.txt").exists());
}

#[test]
fn param_writes_vt_per_vertex_and_pictures() {
    let dir = scratch("param");
    let cap = generate::sphere_cap(3, 0.2);
    let mesh = write_surface(&dir, "cap.obj", &cap);
    let out = dir.join("flat.obj");
    let r = run_ok(
        bin()
            .arg("param")
            .arg(&mesh)
            .args(["--method", "sd", "--iterations", "5", "--stats", "-o"])
            .arg(&out),
    );
    let text = std::fs::read_to_string(&out).expect("written");
    let n = cap.positions.len();
    assert_eq!(text.lines().filter(|l| l.starts_with("v ")).count(), n);
    assert_eq!(text.lines().filter(|l| l.starts_with("vt ")).count(), n);
    let faces: Vec<&str> = text.lines().filter(|l| l.starts_with("f ")).collect();
    assert_eq!(faces.len(), cap.faces.len());
    let [a, b, c] = cap.faces[0].map(|v| v + 1);
    assert_eq!(faces[0], format!("f {a}/{a} {b}/{b} {c}/{c}"));
    // The file reads back with its texture coordinates.
    let back = bdmorph::io::read_mesh(&out).expect("readable");
    assert_eq!(back.faces, cap.faces);
    assert!(back.texcoords.is_some());
    let stdout = String::from_utf8(r.stdout).expect("utf8");
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(lines.len() >= 2 && lines.len() <= 6, "{stdout}");
    assert!(
        lines[0].starts_with("{\"iteration\":1,\"energy\":"),
        "{stdout}"
    );
    assert!(
        lines.last().expect("summary").contains("\"method\":\"sd\"")
            && stdout.contains("\"flipped\":0")
    );
    // Every method runs; PNG output decodes.
    for method in ["tutte", "lscm", "asap", "arap", "mips", "arap-newton"] {
        run_ok(bin().arg("param").arg(&mesh).args([
            "--method",
            method,
            "--iterations",
            "3",
            "--stats",
        ]));
    }
    let png = dir.join("flat.png");
    run_ok(
        bin()
            .arg("param")
            .arg(&mesh)
            .args(["--method", "tutte", "--size", "120x100", "-o"])
            .arg(&png),
    );
    let img =
        bdmorph::render::raster::decode_image(&std::fs::read(&png).expect("png")).expect("decodes");
    assert_eq!(img.height, 100);
    assert!(img.width > 240);
    // A closed mesh and an unknown method are refused with their cause.
    let sphere = write_surface(&dir, "sphere.obj", &generate::icosphere(1));
    for (args, says) in [
        (
            vec![sphere.clone().into_os_string(), "--stats".into()],
            "not a disk",
        ),
        (
            vec![
                mesh.clone().into_os_string(),
                "--method".into(),
                "slim".into(),
                "--stats".into(),
            ],
            "unknown method",
        ),
    ] {
        let r = bin().arg("param").args(&args).output().expect("runs");
        let err = String::from_utf8(r.stderr).expect("utf8");
        assert!(!r.status.success() && err.contains(says), "{err}");
    }
}

#[test]
fn bounded_param_and_deform_meet_the_bound_or_say_why() {
    let dir = scratch("bounded");
    let cap = generate::sphere_cap(3, 0.0);
    let mesh = write_surface(&dir, "cap.obj", &cap);
    let out = dir.join("k2.obj");
    let r = run_ok(
        bin()
            .arg("param")
            .arg(&mesh)
            .args([
                "--method",
                "bounded",
                "--max-distortion",
                "2",
                "--stats",
                "-o",
            ])
            .arg(&out),
    );
    let stdout = String::from_utf8(r.stdout).expect("utf8");
    assert!(stdout.starts_with("{\"converged\":true,"), "{stdout}");
    assert!(std::fs::read_to_string(&out)
        .expect("written")
        .contains("\nvt "));
    // Without the bound: refused.
    let r = bin()
        .arg("param")
        .arg(&mesh)
        .args(["--method", "bounded", "--stats"])
        .output()
        .expect("runs");
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("--max-distortion"));

    // deform: a planar disk, the centre held and a rim vertex pulled out.
    let disk = generate::disk(6, 0.2);
    let planar = write(&dir, "disk.obj", &disk);
    let rim = disk.positions.len() - 1;
    let p = disk.positions[rim];
    let out = dir.join("posed.obj");
    let pull = format!("{rim}:{},{}", 1.6 * p[0], 1.6 * p[1]);
    let r = run_ok(
        bin()
            .arg("deform")
            .arg(&planar)
            .args([
                "--pin",
                "0:0,0",
                "--pin",
                &pull,
                "--max-distortion",
                "3",
                "--stats",
                "-o",
            ])
            .arg(&out),
    );
    let stdout = String::from_utf8(r.stdout).expect("utf8");
    assert!(
        stdout.contains("\"converged\":true") && stdout.contains("\"inverted\":0"),
        "{stdout}"
    );
    let posed = PlanarMesh::read(&out).expect("readable");
    assert_eq!(posed.faces, disk.faces);
    assert!((posed.positions[rim][0] - 1.6 * p[0]).abs() < 1e-9);
    // The posed disk is a valid morphing target.
    run_ok(
        morph()
            .arg(&planar)
            .arg(&out)
            .args(["--t", "0.5", "--stats"]),
    );
    // An infeasible bound is reported, the closest map still written, exit code 1.
    let out = dir.join("tight.obj");
    let r = bin()
        .arg("deform")
        .arg(&planar)
        .args(["--pin", "0:0,0", "--pin", &pull, "--pin", "5:0,0.05"])
        .args(["--max-distortion", "1", "--iterations", "50", "-o"])
        .arg(&out)
        .output()
        .expect("runs");
    let err = String::from_utf8(r.stderr).expect("utf8");
    assert!(!r.status.success(), "{err}");
    assert!(
        err.contains("was not met") && err.contains("worst (0-based): face"),
        "{err}"
    );
    // Each worst face with its line in disk.obj (vertices first, one line each).
    let face = number_after(&err, "worst (0-based): face ");
    let n = disk.positions.len();
    assert!(
        err.contains(&format!("face {face} on line {} (", n + face + 1)),
        "{err}"
    );
    assert!(out.is_file());
}

/// `m` as an OBJ file with a two-line header and as an OFF file: in both, vertex `v` is on line
/// `3 + v` and face `f` on line `3 + n + f` (`n` vertices).
fn write_obj_and_off(dir: &Path, stem: &str, m: &PlanarMesh) -> [PathBuf; 2] {
    let obj = dir.join(format!("{stem}.obj"));
    let header = ["written by a test", "vertices, then faces"];
    io::write_obj_2d(&obj, &m.positions, &m.faces, &header).expect("write");
    let off = dir.join(format!("{stem}.off"));
    let mut text = format!("OFF\n{} {} 0\n", m.positions.len(), m.faces.len());
    for p in &m.positions {
        text += &format!("{} {} 0\n", p[0], p[1]);
    }
    for f in &m.faces {
        text += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
    }
    std::fs::write(&off, text).expect("write");
    [obj, off]
}

/// Runs a command that must fail, writing nothing into `dir`, and returns its one line of
/// stderr.
fn fails_writing_nothing(cmd: &mut Command, dir: &Path) -> String {
    let before = listing(dir);
    let r = cmd.current_dir(dir).output().expect("runs");
    let err = String::from_utf8(r.stderr).expect("utf8");
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(r.stdout.is_empty(), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert_eq!(listing(dir), before, "{err}");
    err
}

fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The commands that read a planar mesh, with `mesh` where a bad one is given and `good` /
/// `target` (valid, with `mesh`'s triangles when `mesh` is valid) elsewhere; each writes into
/// the current directory.
fn planar_commands(mesh: &Path, good: &Path, target: &Path) -> Vec<Command> {
    let mut commands = Vec::new();
    let mut c = morph();
    c.arg(mesh)
        .arg(target)
        .args(["--t", "0.5", "-o", "out.obj"]);
    commands.push(c);
    let mut c = morph();
    c.arg(good)
        .arg(mesh)
        .args(["--frames", "3", "-o", "frames"]);
    commands.push(c);
    let mut c = bin();
    c.arg("blend").arg(good).arg(target).arg(mesh).args([
        "--weights",
        "0.2,0.3,0.5",
        "-o",
        "mix.png",
    ]);
    commands.push(c);
    let mut c = bin();
    c.arg("compile").arg(mesh).args(["-o", "prog.bdm"]);
    commands.push(c);
    let mut c = bin();
    c.arg("deform")
        .arg(mesh)
        .args(["--pin", "0:0,0", "--max-distortion", "3", "-o", "posed.obj"]);
    commands.push(c);
    commands
}

/// What `info` says of `mesh`'s morphability.
fn morphable(mesh: &Path) -> String {
    let out = run_ok(bin().arg("info").arg(mesh));
    let text = String::from_utf8(out.stdout).expect("utf8");
    let line = text.lines().find(|l| l.contains("morphable: "));
    line.expect("a morphable line").trim().to_owned()
}

#[test]
fn a_clockwise_face_is_named_with_its_line_in_obj_and_off_by_every_command() {
    let dir = scratch("clockwise-line");
    let a = generate::disk(6, 0.2);
    let n = a.positions.len();
    let good = write(&dir, "a.obj", &a);
    let target = write(&dir, "b.obj", &generate::twist(&a, 0.8));
    let mut cw = a.clone();
    cw.faces[40].swap(1, 2);
    let line = 3 + n + 40;
    for path in write_obj_and_off(&dir, "cw", &cw) {
        let expected = format!(
            "{}:{line}: face 40 (0-based) is clockwise (signed area ",
            path.display()
        );
        for mut command in planar_commands(&path, &good, &target) {
            let err = fails_writing_nothing(&mut command, &dir);
            assert!(
                err.starts_with(&format!("bdmorph: error: {expected}")),
                "{command:?}: {err}"
            );
            assert!(err.ends_with(
                "; triangles must be counter-clockwise, consistently (a keyframe with a few \
                 inverted triangles morphs with --allow-inverted)\n"
            ));
        }
        let info = morphable(&path);
        assert!(
            info.starts_with(&format!("morphable: no: {expected}")),
            "{info}"
        );
    }
}

#[test]
fn topology_errors_name_the_lines_of_their_faces_and_vertices() {
    let dir = scratch("topology-lines");
    let a = generate::disk(6, 0.2);
    let (n, m) = (a.positions.len(), a.faces.len());
    let b = generate::twist(&a, 0.8);
    // Face 7 listed again at the end.
    let twice = |mut mesh: PlanarMesh| {
        mesh.faces.push(mesh.faces[7]);
        mesh
    };
    let [a_obj, a_off] = write_obj_and_off(&dir, "twice", &twice(a.clone()));
    let [b_obj, b_off] = write_obj_and_off(&dir, "twice-b", &twice(b.clone()));
    for (path, target) in [(&a_obj, &b_obj), (&a_off, &b_off)] {
        let (l7, lm) = (3 + n + 7, 3 + n + m);
        let expected = format!(
            "{}:{lm}: face 7 and face {m} (0-based) are the same triangle (duplicate face); \
             face {m} is line {lm}, face 7 is line {l7}",
            path.display()
        );
        let compile = bin()
            .arg("compile")
            .arg(path)
            .args(["-o", "prog.bdm"])
            .current_dir(&dir)
            .output()
            .expect("runs");
        let err = String::from_utf8(compile.stderr).expect("utf8");
        assert_eq!(err, format!("bdmorph: error: {expected}\n"));
        let err = fails_writing_nothing(
            morph()
                .arg(path)
                .arg(target)
                .args(["--t", "0.5", "-o", "out.obj"]),
            &dir,
        );
        assert_eq!(err, format!("bdmorph: error: {expected}\n"));
        assert_eq!(morphable(path), format!("morphable: no: {expected}"));
    }
    // A vertex no face uses: its own line.
    let mut lonely = a.clone();
    lonely.positions.push([5.0, 5.0]);
    for path in write_obj_and_off(&dir, "lonely", &lonely) {
        let expected = format!(
            "{}:{}: vertex {n} (0-based) belongs to no face",
            path.display(),
            3 + n
        );
        assert_eq!(morphable(&path), format!("morphable: no: {expected}"));
        let err = fails_writing_nothing(
            bin().arg("compile").arg(&path).args(["-o", "prog.bdm"]),
            &dir,
        );
        assert_eq!(err, format!("bdmorph: error: {expected}\n"));
    }
    // A target listing the same triangles in another order, corners rotated: the same frame.
    let mut reordered = b.clone();
    reordered.faces.swap(3, 4);
    reordered.faces.reverse();
    for f in reordered.faces.iter_mut().step_by(3) {
        f.rotate_left(1);
    }
    let plain_target = write(&dir, "plain-b.obj", &b);
    let reordered_target = write_obj_and_off(&dir, "reordered", &reordered)[1].clone();
    let source = write(&dir, "plain.obj", &a);
    let mut outputs = Vec::new();
    for (target, out) in [
        (&plain_target, "plain-out.obj"),
        (&reordered_target, "re-out.obj"),
    ] {
        let r = morph()
            .arg(&source)
            .arg(target)
            .args(["--t", "0.5", "-o", out])
            .current_dir(&dir)
            .output()
            .expect("runs");
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        let text = std::fs::read_to_string(dir.join(out)).expect("written");
        // The header names the files; the rest must be the same, byte for byte.
        let body: Vec<String> = text
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(str::to_owned)
            .collect();
        outputs.push(body);
    }
    assert!(
        outputs[0] == outputs[1],
        "frames follow the source's listing"
    );
    // A target listing one triangle twice (and so missing another): the repeat, in the target.
    let mut repeated = b.clone();
    repeated.faces[3] = repeated.faces[4];
    for (source, target) in [
        (
            write(&dir, "plain.obj", &a),
            write_obj_and_off(&dir, "repeated", &repeated)[1].clone(),
        ),
        (
            write_obj_and_off(&dir, "a", &a)[1].clone(),
            write(&dir, "repeated-plain.obj", &repeated),
        ),
    ] {
        let target_line = match source.extension() {
            Some(e) if e == "obj" => 3 + n + 4,
            _ => n + 5,
        };
        let err = fails_writing_nothing(
            morph()
                .arg(&source)
                .arg(&target)
                .args(["--t", "0.5", "-o", "out.obj"]),
            &dir,
        );
        let prefix = format!(
            "bdmorph: error: {}:{target_line}: face 3 and face 4 (0-based) are the same triangle \
             (duplicate face)",
            target.display()
        );
        assert!(err.starts_with(&prefix), "{err}");
        assert!(
            err.ends_with(&format!("(compared with {})\n", source.display())),
            "{err}"
        );
    }
}

#[test]
fn a_mirrored_mesh_is_reported_as_mirrored_with_the_fix() {
    let dir = scratch("mirrored");
    let a = generate::disk(6, 0.2);
    let good = write(&dir, "a.obj", &a);
    let target = write(&dir, "b.obj", &generate::twist(&a, 0.8));
    let nf = a.faces.len();
    // As exported with y pointing down: every triangle clockwise.
    let mirrored = PlanarMesh {
        positions: a.positions.iter().map(|p| [p[0], -p[1]]).collect(),
        faces: a.faces.clone(),
    };
    for path in write_obj_and_off(&dir, "mirrored", &mirrored) {
        let expected = format!(
            "{}: all {nf} triangles are clockwise: the mesh is mirrored, as when exported with \
             y pointing down; reverse each triangle's corner order (a b c -> a c b) or negate \
             one coordinate (y -> -y)",
            path.display()
        );
        for mut command in planar_commands(&path, &good, &target) {
            let err = fails_writing_nothing(&mut command, &dir);
            assert_eq!(err, format!("bdmorph: error: {expected}\n"), "{command:?}");
        }
        assert_eq!(morphable(&path), format!("morphable: no: {expected}"));
    }
    // Either fix gives a morphable mesh.
    let mut reversed = mirrored.clone();
    reversed.faces.iter_mut().for_each(|f| f.swap(1, 2));
    let flipped_back = PlanarMesh {
        positions: mirrored.positions.iter().map(|p| [p[0], -p[1]]).collect(),
        faces: mirrored.faces.clone(),
    };
    for (name, fixed) in [("reversed.obj", reversed), ("flipped.obj", flipped_back)] {
        let path = write(&dir, name, &fixed);
        assert_eq!(
            morphable(&path),
            "morphable: yes (a counter-clockwise planar disk)"
        );
    }
    // Mostly clockwise: mirrored too, naming the counter-clockwise faces left over.
    let mut mostly = mirrored.clone();
    mostly.faces[5].swap(1, 2);
    mostly.faces[9].swap(1, 2);
    let n = a.positions.len();
    for path in write_obj_and_off(&dir, "mostly", &mostly) {
        let expected = format!(
            "{}:{}: {} of {nf} triangles are clockwise: the mesh looks mirrored, as when \
             exported with y pointing down; reverse each triangle's corner order (a b c -> a c b) \
             or negate one coordinate (y -> -y), after which the 2 counter-clockwise ones, from \
             face 5 (0-based), would be clockwise",
            path.display(),
            3 + n + 5,
            nf - 2
        );
        let err = fails_writing_nothing(
            morph()
                .arg(&path)
                .arg(&target)
                .args(["--t", "0.5", "-o", "out.obj"]),
            &dir,
        );
        assert_eq!(err, format!("bdmorph: error: {expected}\n"));
        assert_eq!(morphable(&path), format!("morphable: no: {expected}"));
    }
}

/// The number right after `before` in `text`.
fn number_after(text: &str, before: &str) -> usize {
    let at = text
        .find(before)
        .unwrap_or_else(|| panic!("{before:?} in {text}"))
        + before.len();
    let digits: String = text[at..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits
        .parse()
        .unwrap_or_else(|_| panic!("a number after {before:?} in {text}"))
}

#[test]
fn surface_commands_name_the_lines_of_the_faces_at_fault() {
    let dir = scratch("surface-lines");
    let write_off = |name: &str, mesh: &bdmorph::SurfaceMesh| {
        let mut text = format!("OFF\n{} {}\n", mesh.positions.len(), mesh.faces.len());
        for p in &mesh.positions {
            text += &format!("{} {} {}\n", p[0], p[1], p[2]);
        }
        for f in &mesh.faces {
            text += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
        }
        let path = dir.join(name);
        std::fs::write(&path, text).expect("write");
        path
    };
    // geodesic: a sphere with face 12 listed again, so that its edges run twice one way.
    let mut sphere = generate::icosphere(1);
    let (n, m) = (sphere.positions.len(), sphere.faces.len());
    sphere.faces.push(sphere.faces[12]);
    for (path, first) in [
        (write_surface(&dir, "sphere.obj", &sphere), 1),
        (write_off("sphere.off", &sphere), 3),
    ] {
        let err = fails_writing_nothing(
            bin()
                .arg("geodesic")
                .arg(&path)
                .args(["--source", "0", "-o", "d.txt"]),
            &dir,
        );
        let expected = format!(
            "bdmorph: error: {}:{}: the edge from vertex ",
            path.display(),
            first + n + m
        );
        assert!(err.starts_with(&expected), "{err}");
        assert!(
            err.ends_with(&format!(
                "by faces 12 and {m} (0-based): the mesh is non-manifold or inconsistently \
                 oriented there; face {m} is line {}, face 12 is line {}\n",
                first + n + m,
                first + n + 12
            )),
            "{err}"
        );
    }
    // param: a cap with face 3 listed again is not a disk.
    let mut cap = generate::sphere_cap(3, 0.2);
    let (n, m) = (cap.positions.len(), cap.faces.len());
    cap.faces.push(cap.faces[3]);
    for (path, first) in [
        (write_surface(&dir, "cap.obj", &cap), 1),
        (write_off("cap.off", &cap), 3),
    ] {
        let err = fails_writing_nothing(
            bin()
                .arg("param")
                .arg(&path)
                .args(["--method", "tutte", "-o", "flat.obj"]),
            &dir,
        );
        assert_eq!(
            err,
            format!(
                "bdmorph: error: {}:{}: not a disk: face 3 and face {m} (0-based) are the same \
                 triangle (duplicate face); face {m} is line {}, face 3 is line {}\n",
                path.display(),
                first + n + m,
                first + n + m,
                first + n + 3
            )
        );
    }
}

#[test]
fn failed_frames_name_the_lines_of_their_worst_triangles() {
    let dir = scratch("frame-lines");
    let (a, pa, _, pb) = pair(&dir);
    let n = a.positions.len();
    // One Newton step is not enough at t = 0.5 (see frames_that_fail_are_reported_...).
    let r = morph()
        .arg(&pa)
        .arg(&pb)
        .args(["--t", "0.5", "--max-iterations", "1", "--stats"])
        .output()
        .expect("runs");
    let err = String::from_utf8(r.stderr).expect("utf8");
    assert_eq!(r.status.code(), Some(1), "{err}");
    // The worst triangle, by its vertices, is face f: on line n + f + 1 of a.obj.
    let needle = "worst triangles (0-based vertices): (";
    let at = err.find(needle).expect(&err) + needle.len();
    let vertices: Vec<u32> = err[at..]
        .split(')')
        .next()
        .expect("a triangle")
        .split(' ')
        .map(|v| v.parse().expect("a vertex"))
        .collect();
    let rotations: Vec<[u32; 3]> = (0..3)
        .map(|k| [0, 1, 2].map(|i| vertices[(i + k) % 3]))
        .collect();
    let face = a
        .faces
        .iter()
        .position(|f| rotations.contains(f))
        .expect("the worst triangle is a face");
    let line = n + face + 1;
    let prefix = format!(
        "bdmorph: error: {}:{line}: frame t = 0.5: Newton did not converge",
        pa.display()
    );
    assert!(err.starts_with(&prefix), "{err}");
    assert!(
        err.contains(&format!("; face {face} is line {line}, face ")),
        "{err}"
    );
    // Extrapolated too far: the triangle that breaks, and its line.
    let r = morph()
        .arg(&pa)
        .arg(&pb)
        .args(["--t", "40", "--stats"])
        .output()
        .expect("runs");
    let err = String::from_utf8(r.stderr).expect("utf8");
    let face = number_after(&err, "edge lengths of triangle ");
    assert!(
        err.starts_with(&format!(
            "bdmorph: error: {}:{}: t = 40: the extrapolated edge lengths of triangle {face} \
             (0-based; vertices ",
            pa.display(),
            n + face + 1
        )),
        "{err}"
    );
}

#[test]
fn deform_poses_by_each_method_with_the_same_stats() {
    let dir = scratch("deform-methods");
    let disk = generate::disk(8, 0.2);
    let planar = write(&dir, "disk.obj", &disk);
    let rim = disk.positions.len() - 1;
    let p = disk.positions[rim];
    let target = [1.3 * p[0] + 0.2, 1.3 * p[1]];
    let pull = format!("{rim}:{},{}", target[0], target[1]);
    for method in ["kvf", "sd", "arap", "bounded"] {
        let out = dir.join(format!("{method}.obj"));
        let mut c = bin();
        c.arg("deform")
            .arg(&planar)
            .args(["--method", method, "--pin", "0:0,0", "--pin", &pull]);
        if method == "bounded" {
            c.args(["--max-distortion", "3"]);
        }
        let r = run_ok(c.args(["--stats", "-q", "-o"]).arg(&out));
        let stats = String::from_utf8(r.stdout).expect("utf8");
        assert_eq!(stats.lines().count(), 1, "{stats}");
        assert!(
            stats.contains(&format!("\"method\":\"{method}\"")),
            "{stats}"
        );
        for key in [
            "\"max_conformal_distortion\":",
            "\"flipped_triangles\":0",
            "\"pin_residual\":",
            "\"seconds\":",
        ] {
            assert!(stats.contains(key), "{method}: {key} in {stats}");
        }
        let distortion = number_after_f64(&stats, "\"max_conformal_distortion\":");
        assert!(distortion > 1.0 && distortion < 3.01, "{method}: {stats}");
        let posed = PlanarMesh::read(&out).expect("readable");
        assert_eq!(posed.faces, disk.faces);
        let q = posed.positions[rim];
        let residual = (q[0] - target[0]).hypot(q[1] - target[1]);
        // Hard pins exactly; KVF's and sd's soft ones within their default closeness.
        let allowed = if method == "kvf" || method == "sd" {
            1e-2 * disk.diameter()
        } else {
            1e-9
        };
        assert!(residual < allowed, "{method}: {residual}");
        assert!(
            (number_after_f64(&stats, "\"pin_residual\":") - residual).abs() < 1e-9,
            "{stats}"
        );
    }
    // KVF's weight must be positive; a bounded pose still needs its bound.
    let err = fails_writing_nothing(
        bin().arg("deform").arg(&planar).args([
            "--method",
            "kvf",
            "--pin-weight",
            "0",
            "--pin",
            "0:0,0",
            "-o",
            "w.obj",
        ]),
        &dir,
    );
    assert!(err.contains("weight must be a finite number > 0"), "{err}");
}

/// The number after `key` in `text`.
fn number_after_f64(text: &str, key: &str) -> f64 {
    text.split(key)
        .nth(1)
        .and_then(|s| s.split([',', '}']).next())
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or_else(|| panic!("no number after {key} in {text}"))
}
