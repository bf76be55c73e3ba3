//! `bdmorph inbetween A.png B.png [--match ...] --frames N -o OUT`: outputs, options, errors.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use bdmorph::generate;
use bdmorph::render::{raster, Image};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bdmorph"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-inbetween-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn save(dir: &Path, name: &str, image: &Image) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, raster::encode_png(image).expect("png")).expect("write");
    path
}

fn drawings(dir: &Path) -> (PathBuf, PathBuf) {
    (
        save(dir, "a.png", &generate::figure_picture(200, 0.0, 0.0)),
        save(dir, "b.png", &generate::figure_picture(200, 1.6, 0.15)),
    )
}

fn run(args: &[&std::ffi::OsStr]) -> Output {
    bin().arg("inbetween").args(args).output().expect("run")
}

fn os(s: &str) -> &std::ffi::OsStr {
    std::ffi::OsStr::new(s)
}

#[test]
fn frames_are_written_as_obj_png_and_gif() {
    let dir = scratch("outputs");
    let (a, b) = drawings(&dir);
    // OBJ frames in a directory by default, with A's texture coordinates.
    let objs = dir.join("objs");
    let out = run(&[
        a.as_os_str(),
        b.as_os_str(),
        os("--frames"),
        os("5"),
        os("--vertices"),
        os("600"),
        os("-o"),
        objs.as_os_str(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let first = std::fs::read_to_string(objs.join("frame_0000.obj")).unwrap();
    let last = std::fs::read_to_string(objs.join("frame_0004.obj")).unwrap();
    assert!(first.contains("\nvt ") && first.contains("\nf "));
    assert_ne!(first, last);
    // A GIF, and PNG frames on a transparent background cross-fading the two pictures.
    let gif = dir.join("walk.gif");
    let out = run(&[
        a.as_os_str(),
        b.as_os_str(),
        os("--frames"),
        os("6"),
        os("--vertices"),
        os("600"),
        os("--size"),
        os("120x120"),
        os("-o"),
        gif.as_os_str(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::read(&gif).unwrap().starts_with(b"GIF89a"));
    let pngs = dir.join("pngs");
    let out = run(&[
        a.as_os_str(),
        b.as_os_str(),
        os("--frames"),
        os("3"),
        os("--vertices"),
        os("600"),
        os("--format"),
        os("png"),
        os("--background"),
        os("transparent"),
        os("--crossfade"),
        os("linear"),
        os("--size"),
        os("160x160"),
        os("-o"),
        pngs.as_os_str(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let middle = raster::read_image(pngs.join("frame_0001.png")).unwrap();
    let alpha = middle.rgba.chunks_exact(4).filter(|p| p[3] == 0).count();
    let covered = middle.rgba.chunks_exact(4).filter(|p| p[3] == 255).count();
    assert!(
        alpha > 1000 && covered > 1000,
        "{alpha} transparent, {covered} covered"
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("compatible mesh:") && stderr.contains("none flipped"),
        "{stderr}"
    );
}

#[test]
fn three_drawings_make_a_path() {
    let dir = scratch("path");
    let (a, b) = drawings(&dir);
    let c = save(&dir, "c.png", &generate::figure_picture(200, 2.0, -0.1));
    let gif = dir.join("path.gif");
    let out = run(&[
        a.as_os_str(),
        b.as_os_str(),
        c.as_os_str(),
        os("--frames"),
        os("9"),
        os("--vertices"),
        os("500"),
        os("--easing"),
        os("ease-in-out"),
        os("--size"),
        os("100x100"),
        os("--stats"),
        os("-o"),
        gif.as_os_str(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    // A line for the mesh over B, one over C, then nine frames.
    assert_eq!(lines.len(), 11, "{text}");
    assert!(lines[1].starts_with("{\"compatible_mesh\":{\"drawing\":2,"));
    assert!(std::fs::read(&gif).unwrap().starts_with(b"GIF89a"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("none flipped over drawing C"), "{stderr}");
}

#[test]
fn opaque_scans_on_paper_are_read_with_paper() {
    let dir = scratch("paper");
    // The drawings flattened onto white: no transparency left.
    let on_white = |image: Image| Image {
        rgba: raster::crossfade(
            &image,
            &Image {
                rgba: vec![0; image.rgba.len()],
                ..image.clone()
            },
            0.0,
            bdmorph::render::Background::WHITE,
        )
        .rgba,
        ..image
    };
    let a = save(
        &dir,
        "a.png",
        &on_white(generate::figure_picture(200, 0.0, 0.0)),
    );
    let b = save(
        &dir,
        "b.png",
        &on_white(generate::figure_picture(200, 1.6, 0.15)),
    );
    let args = [
        a.as_os_str(),
        b.as_os_str(),
        os("--frames"),
        os("3"),
        os("--vertices"),
        os("500"),
        os("--stats"),
    ];
    let out = run(&args);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("drawing A"), "{stderr}");
    let mut with_paper = args.to_vec();
    with_paper.extend([os("--paper"), os("white")]);
    let out = run(&with_paper);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.lines().next().unwrap().contains("\"flipped\":0"),
        "{text}"
    );
}

#[test]
fn stats_describe_the_compatible_mesh_then_each_frame() {
    let dir = scratch("stats");
    let (a, b) = drawings(&dir);
    let out = run(&[
        a.as_os_str(),
        b.as_os_str(),
        os("--frames"),
        os("4"),
        os("--vertices"),
        os("500"),
        os("--match"),
        os("100,55:105,40"),
        os("--stats"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 5, "{text}");
    assert!(lines[0].starts_with("{\"compatible_mesh\":{\"drawing\":1,\"vertices\":"));
    assert!(lines[0].contains("\"flipped\":0") && lines[0].contains("\"pairs\":[{"));
    for line in &lines[1..] {
        assert!(line.contains("\"flipped_triangles\":0"), "{line}");
    }
}

#[test]
fn mistakes_are_one_line_and_write_nothing() {
    let dir = scratch("mistakes");
    let (a, b) = drawings(&dir);
    let two = save(
        &dir,
        "two.png",
        &generate::picture(200, 200, |x, y| {
            generate::capsule_distance([x, y], [50.0, 100.0], [50.0, 100.0], 30.0).min(
                generate::capsule_distance([x, y], [150.0, 100.0], [150.0, 100.0], 30.0),
            )
        }),
    );
    let target = dir.join("out.gif");
    let cases: Vec<(Vec<&std::ffi::OsStr>, &str)> = vec![
        (
            vec![a.as_os_str(), two.as_os_str(), os("--frames"), os("3")],
            "drawing A has 1 piece and drawing B has 2 pieces",
        ),
        (
            vec![
                a.as_os_str(),
                b.as_os_str(),
                os("--match"),
                os("1,2"),
                os("--frames"),
                os("3"),
            ],
            "AX,AY:BX,BY",
        ),
        (
            vec![
                a.as_os_str(),
                b.as_os_str(),
                os("--frames"),
                os("3"),
                os("--format"),
                os("html"),
            ],
            "cannot cross-fade",
        ),
        (
            vec![a.as_os_str(), b.as_os_str(), os("--t"), os("1.5")],
            "[0, 1]",
        ),
        (
            vec![
                a.as_os_str(),
                b.as_os_str(),
                os("--frames"),
                os("3"),
                os("--vertices"),
                os("2"),
            ],
            "vertices",
        ),
        (
            vec![os("missing.png"), b.as_os_str(), os("--frames"), os("3")],
            "missing.png",
        ),
    ];
    for (mut args, expected) in cases {
        args.extend([os("-o"), target.as_os_str()]);
        let out = run(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(!target.exists(), "{args:?} wrote {}", target.display());
    }
}

/// The vertex positions of an OBJ file.
fn obj_positions(path: &Path) -> Vec<[f64; 2]> {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let c: Vec<f64> = l
                .split_whitespace()
                .map(|x| x.parse().expect("number"))
                .collect();
            [c[0], c[1]]
        })
        .collect()
}

#[test]
fn the_baselines_are_drawn_on_the_same_compatible_mesh() {
    let dir = scratch("methods");
    let (a, b) = drawings(&dir);
    let frames = |method: &str| {
        let out_dir = dir.join(method);
        let out = run(&[
            a.as_os_str(),
            b.as_os_str(),
            os("--frames"),
            os("3"),
            os("--vertices"),
            os("600"),
            os("--method"),
            os(method),
            os("-o"),
            out_dir.as_os_str(),
        ]);
        assert!(
            out.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        (0..3)
            .map(|i| obj_positions(&out_dir.join(format!("frame_{i:04}.obj"))))
            .collect::<Vec<_>>()
    };
    let (bd, arap, linear) = (frames("bdmorph"), frames("arap"), frames("linear"));
    let far = |p: &[[f64; 2]], q: &[[f64; 2]]| {
        p.iter()
            .zip(q)
            .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
            .fold(0.0, f64::max)
    };
    // The same mesh, and the same drawings at the ends: every method starts at A's layout and
    // ends at B's.
    for k in [0, 2] {
        assert_eq!(bd[k].len(), linear[k].len());
        assert!(far(&bd[k], &linear[k]) < 1e-6, "frame {k}");
        assert!(far(&arap[k], &linear[k]) < 1e-6, "frame {k}");
    }
    // Straight lines: the middle is the midpoint of the ends.
    let mid: Vec<[f64; 2]> = linear[0]
        .iter()
        .zip(&linear[2])
        .map(|(p, q)| [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])])
        .collect();
    assert!(far(&linear[1], &mid) < 1e-6);
    // The other two bend the arm rather than cut across: their middles differ from it.
    assert!(far(&arap[1], &mid) > 1.0);
    assert!(far(&bd[1], &mid) > 1.0);
    // A method that is not one is refused in one line, writing nothing.
    let out = run(&[
        a.as_os_str(),
        b.as_os_str(),
        os("--method"),
        os("spline"),
        os("-o"),
        dir.join("none").as_os_str(),
    ]);
    assert!(!out.status.success());
    assert!(!dir.join("none").exists());
}

#[test]
fn a_project_of_the_drawings_plays_the_command_lines_frames() {
    let dir = scratch("project");
    let (a, b) = drawings(&dir);
    let common = |out: &Path| {
        let out = run(&[
            a.as_os_str(),
            b.as_os_str(),
            os("--frames"),
            os("5"),
            os("--vertices"),
            os("600"),
            os("-o"),
            out.as_os_str(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    let (objs, project) = (dir.join("objs"), dir.join("pair.json"));
    common(&objs);
    common(&project);
    // The project names the drawings beside it, and opens.
    let text = std::fs::read_to_string(&project).expect("project");
    assert!(
        text.contains("\"a.png\"") && text.contains("\"b.png\""),
        "{text}"
    );
    // The studio's export of it (the frames at its 25 fps: 5 over 0.16 s) gives the command
    // line's frames.
    let exported = dir.join("exported");
    let out = bin()
        .arg("export")
        .arg(&project)
        .args(["--format", "obj", "-o"])
        .arg(&exported)
        .output()
        .expect("run");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let size = {
        let p = obj_positions(&objs.join("frame_0000.obj"));
        let (lo, hi) = p
            .iter()
            .fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), q| {
                (
                    [lo[0].min(q[0]), lo[1].min(q[1])],
                    [hi[0].max(q[0]), hi[1].max(q[1])],
                )
            });
        (hi[0] - lo[0]).hypot(hi[1] - lo[1])
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(&exported)
        .expect("exported")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 5, "{files:?}");
    for (i, file) in files.iter().enumerate() {
        let cli = obj_positions(&objs.join(format!("frame_{i:04}.obj")));
        let studio = obj_positions(file);
        assert_eq!(cli.len(), studio.len());
        let far = cli
            .iter()
            .zip(&studio)
            .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
            .fold(0.0, f64::max);
        assert!(far < 1e-7 * size, "frame {i}: {far} apart (size {size})");
    }
    // What a project cannot carry is refused, writing nothing.
    let refused = dir.join("refused.json");
    let out = run(&[
        a.as_os_str(),
        b.as_os_str(),
        os("--frames"),
        os("5"),
        os("--method"),
        os("linear"),
        os("-o"),
        refused.as_os_str(),
    ]);
    assert!(!out.status.success());
    assert!(!refused.exists());
}
