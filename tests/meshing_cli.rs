//! `bdmorph mesh` on the command line: a picture meshed, deformed and morphed end to end with
//! the picture as texture; outline inputs; statistics; one-line errors that write nothing.

use std::path::{Path, PathBuf};
use std::process::Command;

use bdmorph::generate::{self, capsule_distance};
use bdmorph::render::raster::{decode_image, encode_png};
use bdmorph::render::Image;
use bdmorph::PlanarMesh;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bdmorph"))
}

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-mesh-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn save(dir: &Path, name: &str, image: &Image) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, encode_png(image).expect("encodes")).expect("writes");
    path
}

/// Runs a command that must succeed, in `dir`; returns its stdout.
fn succeeds(cmd: &mut Command, dir: &Path) -> String {
    let r = cmd.current_dir(dir).output().expect("runs");
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{err}");
    String::from_utf8(r.stdout).expect("utf8")
}

/// Runs a command that must fail, writing nothing into `dir`; returns its one line of stderr.
fn fails_writing_nothing(cmd: &mut Command, dir: &Path) -> String {
    let listing = || {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .expect("dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    };
    let before = listing();
    let r = cmd.current_dir(dir).output().expect("runs");
    let err = String::from_utf8(r.stderr).expect("utf8");
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(r.stdout.is_empty(), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert_eq!(listing(), before, "{err}");
    err
}

/// Mean of a channel over the opaque pixels of `img` in the given part (`x`, `y` in [0, 1]).
fn mean_channel(img: &Image, channel: usize, part: impl Fn(f64, f64) -> bool) -> f64 {
    let (mut sum, mut n) = (0.0, 0.0);
    for y in 0..img.height {
        for x in 0..img.width {
            let i = 4 * (y * img.width + x) as usize;
            let p = &img.rgba[i..i + 4];
            let (u, v) = (
                f64::from(x) / f64::from(img.width),
                f64::from(y) / f64::from(img.height),
            );
            if p[3] == 255 && part(u, v) {
                sum += f64::from(p[channel]);
                n += 1.0;
            }
        }
    }
    assert!(n > 100.0, "{n} opaque pixels");
    sum / n
}

#[test]
fn a_picture_meshed_deformed_and_morphed_with_its_texture() {
    let dir = scratch("end-to-end");
    // A wide oval: a disk-topology subject, lighter at the top and bluer on the left.
    let (w, h) = (320, 200);
    let picture = generate::picture(w, h, |x, y| {
        capsule_distance([x, y], [110.0, 100.0], [210.0, 100.0], 70.0)
    });
    save(&dir, "pic.png", &picture);
    succeeds(
        bin().args(["mesh", "pic.png", "--vertices", "700", "-o", "m.obj"]),
        &dir,
    );
    let (mesh, texcoords) = PlanarMesh::read_textured(dir.join("m.obj")).expect("reads");
    let texcoords = texcoords.expect("vt lines");
    assert!(mesh.positions.len().abs_diff(700) < 70);
    assert_eq!(texcoords.uv.len(), mesh.positions.len());
    for (p, t) in mesh.positions.iter().zip(&texcoords.uv) {
        assert!((t[0] - p[0] / f64::from(w)).abs() < 1e-9);
        assert!((t[1] - p[1] / f64::from(h)).abs() < 1e-9);
    }
    // Handles: the four leftmost vertices stay, the four rightmost rise a little.
    let mut by_x: Vec<usize> = (0..mesh.positions.len()).collect();
    by_x.sort_by(|&a, &b| mesh.positions[a][0].total_cmp(&mesh.positions[b][0]));
    let n = by_x.len();
    let mut deform = bin();
    deform.arg("deform").arg("m.obj");
    for (k, &v) in by_x[..4].iter().chain(&by_x[n - 4..]).enumerate() {
        let p = mesh.positions[v];
        let lift = if k < 4 { 0.0 } else { 20.0 };
        deform
            .arg("--pin")
            .arg(format!("{v}:{},{}", p[0], p[1] + lift));
    }
    succeeds(
        deform.args(["--max-distortion", "4", "-o", "posed.obj"]),
        &dir,
    );
    let posed = PlanarMesh::read(dir.join("posed.obj")).expect("reads");
    assert_eq!(posed.faces, mesh.faces);
    succeeds(
        bin().args([
            "morph",
            "m.obj",
            "posed.obj",
            "--frames",
            "5",
            "--texture",
            "pic.png",
            "-o",
            "out.gif",
        ]),
        &dir,
    );
    let gif = std::fs::File::open(dir.join("out.gif")).expect("written");
    let mut decoder = gif::DecodeOptions::new()
        .read_info(std::io::BufReader::new(gif))
        .expect("a GIF");
    let mut frames = 0;
    while decoder.read_next_frame().expect("decodes").is_some() {
        frames += 1;
    }
    assert_eq!(frames, 5);
    succeeds(
        bin().args([
            "morph",
            "m.obj",
            "posed.obj",
            "--frames",
            "5",
            "--format",
            "png",
            "--size",
            "320x200",
            "--texture",
            "pic.png",
            "-o",
            "frames",
        ]),
        &dir,
    );
    // The first frame is the picture, upright: lighter at the top, bluer on the left; as the
    // picture itself is.
    let first = decode_image(&std::fs::read(dir.join("frames/frame_0000.png")).expect("a frame"))
        .expect("a PNG");
    for img in [&picture, &first] {
        let (top, bottom) = (
            mean_channel(img, 1, |_, v| v < 0.4),
            mean_channel(img, 1, |_, v| v > 0.6),
        );
        assert!(
            top > bottom + 10.0,
            "green {top} at the top, {bottom} at the bottom"
        );
        let (left, right) = (
            mean_channel(img, 2, |u, _| u < 0.4),
            mean_channel(img, 2, |u, _| u > 0.6),
        );
        assert!(
            left > right + 20.0,
            "blue {left} on the left, {right} on the right"
        );
    }
    assert!(dir.join("frames/frame_0004.png").is_file());
}

#[test]
fn stats_and_outline_inputs() {
    let dir = scratch("stats");
    let picture = generate::picture_subject(256);
    save(&dir, "subject.png", &picture);
    let out = succeeds(
        bin().args(["mesh", "subject.png", "--vertices", "900", "--stats"]),
        &dir,
    );
    let line = out.trim();
    assert_eq!(out.lines().count(), 1);
    for key in [
        "\"vertices\":",
        "\"faces\":",
        "\"pieces\":2,",
        "\"holes\":1,",
        "\"min_angle\":",
        "\"seconds\":",
    ] {
        assert!(line.contains(key), "{key} in {line}");
    }
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
  <path d="M 10 90 C 10 10, 90 10, 90 90 Z"/>
</svg>"#;
    std::fs::write(dir.join("arch.svg"), svg).expect("writes");
    succeeds(
        bin().args([
            "mesh",
            "arch.svg",
            "--vertices",
            "400",
            "-q",
            "-o",
            "arch.obj",
        ]),
        &dir,
    );
    let (arch, uv) = PlanarMesh::read_textured(dir.join("arch.obj")).expect("reads");
    assert!(uv.is_some());
    bdmorph::compile(&arch.positions, &arch.faces).expect("a disk");
    let poly = "4 2 0 0\n1 0 0\n2 3 0\n3 3 2\n4 0 2\n4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n0\n";
    std::fs::write(dir.join("box.poly"), poly).expect("writes");
    succeeds(
        bin().args(["mesh", "box.poly", "--vertices", "300", "-o", "box.png"]),
        &dir,
    );
    decode_image(&std::fs::read(dir.join("box.png")).expect("written")).expect("a PNG");
}

#[test]
fn bad_inputs_are_one_line_and_write_nothing() {
    let dir = scratch("errors");
    save(&dir, "clear.png", &generate::picture(40, 30, |_, _| 5.0));
    let specks = generate::picture(60, 60, |x, y| {
        capsule_distance([x, y], [10.5, 10.5], [10.5, 10.5], 0.8)
    });
    save(&dir, "specks.png", &specks);
    let mut opaque = generate::picture(40, 30, |_, _| -5.0);
    opaque.rgba.chunks_exact_mut(4).for_each(|p| p[3] = 255);
    save(&dir, "opaque.png", &opaque);
    std::fs::write(
        dir.join("cross.svg"),
        "<svg>\n<polygon points=\"0,0 10,10 10,0 0,4\"/>\n</svg>\n",
    )
    .expect("writes");
    std::fs::write(
        dir.join("bad.poly"),
        "3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n3 0\n1 1 2\n2 2 4\n3 3 1\n0\n",
    )
    .expect("writes");
    std::fs::write(dir.join("notes.txt"), "hello").expect("writes");
    let cases: [(&[&str], &str); 8] = [
        (
            &["clear.png"],
            "bdmorph: error: clear.png: the picture is fully transparent",
        ),
        (
            &["specks.png"],
            "bdmorph: error: specks.png: every outline is too small for the tolerance 1",
        ),
        (
            &["opaque.png"],
            "bdmorph: error: opaque.png: the picture has no transparent pixels: give --background COLOR",
        ),
        (
            &["cross.svg"],
            "bdmorph: error: cross.svg:2: <polygon> segment 0 crosses <polygon> segment 2 near (2.85714, 2.85714)",
        ),
        (
            &["bad.poly"],
            "bdmorph: error: bad.poly:7: segment 2 refers to vertex 4, but the vertices are numbered 1 to 3",
        ),
        (
            &["notes.txt"],
            "bdmorph: error: notes.txt: not a picture (.png, .jpg) or an outline (.poly, .svg)",
        ),
        (
            &["clear.png", "--min-angle", "40"],
            "bdmorph: error: --min-angle 40: degrees from 0 to 33",
        ),
        (
            &["missing.png"],
            "bdmorph: error: missing.png: cannot read:",
        ),
    ];
    for (args, start) in cases {
        let err = fails_writing_nothing(bin().arg("mesh").args(args).args(["-o", "out.obj"]), &dir);
        assert!(err.starts_with(start), "{args:?}: {err}");
    }
    // --background makes the opaque picture a subject.
    succeeds(
        bin().args([
            "mesh",
            "opaque.png",
            "--background",
            "black",
            "--vertices",
            "100",
            "-o",
            "out.obj",
        ]),
        &dir,
    );
}

/// Runs a command that must succeed, in `dir`; returns its stdout and stderr.
fn succeeds_saying(cmd: &mut Command, dir: &Path) -> (String, String) {
    let r = cmd.current_dir(dir).output().expect("runs");
    let err = String::from_utf8(r.stderr).expect("utf8");
    assert!(r.status.success(), "{err}");
    (String::from_utf8(r.stdout).expect("utf8"), err)
}

/// The value of `key` in a one-line JSON object of numbers, booleans, strings and nulls.
fn json_field<'a>(line: &'a str, key: &str) -> &'a str {
    let start = line.find(&format!("\"{key}\":")).expect(key) + key.len() + 3;
    let rest = &line[start..];
    let end = if let Some(text) = rest.strip_prefix('"') {
        text.find('"').expect("a closing quote") + 2
    } else {
        rest.find([',', '}']).expect("an end")
    };
    &rest[..end]
}

#[test]
fn specks_are_noted_and_kept_on_request() {
    let dir = scratch("specks");
    // A body and two specks of dust of a few pixels.
    let picture = generate::picture(300, 200, |x, y| {
        capsule_distance([x, y], [100.0, 100.0], [180.0, 110.0], 60.0)
            .min(capsule_distance([x, y], [280.0, 20.0], [280.0, 20.0], 2.0))
            .min(capsule_distance([x, y], [15.0, 180.0], [18.0, 183.0], 1.5))
    });
    save(&dir, "dusty.png", &picture);
    let (out, err) = succeeds_saying(
        bin().args([
            "mesh",
            "dusty.png",
            "--vertices",
            "400",
            "--stats",
            "-o",
            "m.obj",
        ]),
        &dir,
    );
    assert!(
        err.lines().any(|l| l
            == "bdmorph: note: dropped 2 specks (pieces under 1% of the largest piece's area); --keep-specks keeps them"),
        "{err}"
    );
    assert_eq!(json_field(&out, "pieces"), "1");
    assert_eq!(json_field(&out, "dropped_specks"), "2");
    let mesh = PlanarMesh::read(dir.join("m.obj")).expect("reads");
    bdmorph::compile(&mesh.positions, &mesh.faces).expect("one piece, a disk");
    let (out, err) = succeeds_saying(
        bin().args([
            "mesh",
            "dusty.png",
            "--vertices",
            "400",
            "--keep-specks",
            "--stats",
        ]),
        &dir,
    );
    assert!(!err.contains("speck"), "{err}");
    assert_eq!(json_field(&out, "pieces"), "3");
    assert_eq!(json_field(&out, "dropped_specks"), "0");
    // -q keeps the note to itself; outlines are kept whole, and say so.
    let (_, err) = succeeds_saying(bin().args(["mesh", "dusty.png", "-q", "-o", "q.obj"]), &dir);
    assert!(err.is_empty(), "{err}");
    std::fs::write(
        dir.join("two.svg"),
        r#"<svg viewBox="0 0 100 100"><rect width="90" height="90"/><rect x="95" y="95" width="1" height="1"/></svg>"#,
    )
    .expect("writes");
    let (out, err) = succeeds_saying(
        bin().args([
            "mesh",
            "two.svg",
            "--keep-specks",
            "--vertices",
            "300",
            "--stats",
        ]),
        &dir,
    );
    assert_eq!(
        err.trim(),
        "bdmorph: warning: --keep-specks only applies to pictures"
    );
    assert_eq!(json_field(&out, "pieces"), "2");
    assert_eq!(json_field(&out, "tolerance"), "null");
}

#[test]
fn the_vertex_count_is_met_or_explained() {
    let dir = scratch("vertex-count");
    // A gear of 200 teeth: 1000 outline vertices at the default tolerance.
    let gear = generate::picture(800, 800, |x, y| {
        let (dx, dy) = (x - 400.0, y - 400.0);
        dx.hypot(dy) - 320.0 - 4.0 * (4.0 * (200.0 * dy.atan2(dx)).sin()).tanh()
    });
    save(&dir, "gear.png", &gear);
    let (out, err) = succeeds_saying(
        bin().args([
            "mesh",
            "gear.png",
            "--vertices",
            "500",
            "--stats",
            "-o",
            "m.obj",
        ]),
        &dir,
    );
    assert!(!err.contains("note"), "{err}");
    let vertices: usize = json_field(&out, "vertices").parse().expect("a count");
    assert!(vertices.abs_diff(500) <= 50, "{vertices}");
    assert_eq!(json_field(&out, "requested_vertices"), "500");
    assert_eq!(json_field(&out, "off_target"), "null");
    let tolerance: f64 = json_field(&out, "tolerance").parse().expect("a tolerance");
    assert!(tolerance > 1.0, "{tolerance}");
    // A tolerance given explicitly is kept, and the miss explained on one line.
    let (out, err) = succeeds_saying(
        bin().args([
            "mesh",
            "gear.png",
            "--vertices",
            "100",
            "--tolerance",
            "0.5",
            "--stats",
            "-o",
            "fine.obj",
        ]),
        &dir,
    );
    let vertices: usize = json_field(&out, "vertices").parse().expect("a count");
    let outline: usize = json_field(&out, "outline_vertices")
        .parse()
        .expect("a count");
    assert!(vertices > 110, "{vertices}");
    let note = format!(
        "bdmorph: note: {vertices} vertices, not about 100 as asked: the outline simplified to --tolerance 0.5 alone has {outline} vertices; raise --tolerance, or leave it out to have it raised to fit"
    );
    assert_eq!(
        err.lines()
            .filter(|l| l.contains("note"))
            .collect::<Vec<_>>(),
        [note.as_str()]
    );
    assert!(
        json_field(&out, "off_target").starts_with("\"the outline simplified to --tolerance 0.5"),
        "{out}"
    );
}

/// Runs `bdmorph mesh FILE -o out.obj` in `dir` with its address space limited to 1 GiB:
/// it must fail cleanly (exit code 1, one line on stderr, nothing written); returns the line.
fn refused_within_1_gib(dir: &Path, file: &str) -> String {
    let mut cmd = Command::new("prlimit");
    cmd.arg("--as=1073741824")
        .arg(env!("CARGO_BIN_EXE_bdmorph"))
        .args(["mesh", file, "-o", "out.obj"]);
    fails_writing_nothing(&mut cmd, dir)
}

#[test]
fn deeply_nested_groups_are_read() {
    let dir = scratch("nested");
    let depth = 20_000;
    let mut text = String::from("<svg xmlns=\"http://www.w3.org/2000/svg\">\n");
    text.push_str(&"<g>".repeat(depth));
    text.push_str("\n<rect x=\"0\" y=\"0\" width=\"10\" height=\"5\"/>\n");
    text.push_str(&"</g>".repeat(depth));
    text.push_str("\n</svg>\n");
    std::fs::write(dir.join("nested.svg"), text).expect("writes");
    let out = succeeds(
        bin().args(["mesh", "nested.svg", "--vertices", "100", "-o", "out.obj"]),
        &dir,
    );
    assert!(out.is_empty(), "{out}");
    assert!(dir.join("out.obj").exists());
}

#[test]
fn poly_counts_beyond_the_file_are_refused_without_allocating() {
    let dir = scratch("poly-counts");
    for (name, header, what) in [
        (
            "vertices.poly",
            "1000000000 2 0 0",
            "1000000000 vertices declared, but only 4 lines follow",
        ),
        (
            "huge.poly",
            "100000000000000 2 0 0",
            "100000000000000 vertices declared, but only 4 lines follow",
        ),
    ] {
        let text = format!("{header}\n1 0 0\n2 1 0\n3 0 1\n3 0\n");
        std::fs::write(dir.join(name), text).expect("writes");
        let err = refused_within_1_gib(&dir, name);
        assert!(err.contains(&format!("{name}:1: {what}")), "{err}");
    }
    std::fs::write(
        dir.join("segments.poly"),
        "3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n4000000000000 0\n1 1 2\n",
    )
    .expect("writes");
    let err = refused_within_1_gib(&dir, "segments.poly");
    assert!(
        err.contains("segments.poly:5: 4000000000000 segments declared, but only 1 lines follow"),
        "{err}"
    );
}

#[test]
fn huge_radii_are_refused_before_flattening() {
    let dir = scratch("huge-circle");
    for (name, svg, what) in [
        (
            "circle.svg",
            "<svg><circle cx=\"0\" cy=\"0\" r=\"1e154\"/></svg>",
            "circle.svg:1: <circle> r is 1.00000e154, outside the supported range",
        ),
        (
            "arc.svg",
            "<svg>\n<path d=\"M0 0 A1e300 1e300 0 1 1 1 1 Z\"/></svg>",
            "arc.svg:2: <path> d: a number is 1.00000e300",
        ),
        (
            "scaled.svg",
            "<svg><g transform=\"scale(1e300)\"><circle r=\"1e10\"/></g></svg>",
            "scaled.svg:1: <circle> r is 1.00000e10",
        ),
        (
            "transformed.svg",
            "<svg><g transform=\"scale(1e200)\">\n<circle r=\"1e200\"/></g></svg>",
            "transformed.svg:2: <circle> r is 1.00000e200",
        ),
        (
            "overflow.svg",
            "<svg><g transform=\"scale(1e300)\">\n<rect width=\"1e5\" height=\"1e5\"/></g></svg>",
            "overflow.svg:2: <rect> a point's coordinate after the transforms is",
        ),
    ] {
        std::fs::write(dir.join(name), svg).expect("writes");
        let err = refused_within_1_gib(&dir, name);
        assert!(err.contains(what), "{err}");
    }
}

/// A star-shaped polygon of `n` points as one SVG `<path>` (no two segments cross).
fn star_path(n: usize) -> String {
    let mut d = String::with_capacity(n * 24);
    for k in 0..n {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        // A wave, and a zigzag about as deep as the points are apart.
        let r = 1000.0 + 30.0 * (a * 7.0).sin() + 3000.0 / n as f64 * ((k % 2) as f64);
        let (x, y) = (1200.0 + r * a.cos(), 1200.0 + r * a.sin());
        d.push_str(&format!("{}{x:.4} {y:.4} ", if k == 0 { 'M' } else { 'L' }));
    }
    format!("<svg xmlns=\"http://www.w3.org/2000/svg\">\n<path d=\"{d}Z\"/>\n</svg>\n")
}

/// A path of 200,000 segments is read, checked for crossings (in about linear time) and refused
/// before the refinement, whose time grows faster than the outline's length, with the count
/// and the limit.
#[test]
fn a_path_of_200k_segments_is_refused_before_meshing() {
    let dir = scratch("large-path");
    std::fs::write(dir.join("star.svg"), star_path(200_000)).expect("writes");
    let out = bin()
        .args(["mesh", "star.svg", "-o", "out.obj"])
        .current_dir(&dir)
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("more than the limit of 100000"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(!dir.join("out.obj").exists());
}
