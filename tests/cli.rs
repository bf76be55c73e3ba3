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
    let last = PlanarMesh::read(&out.join("frame_0003.obj")).expect("readable");
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
            "\"gradient_norm\":",
            "\"flipped_triangles\":0",
        ] {
            assert!(line.contains(key), "{line} lacks {key}");
        }
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
    // t out of range, and no action.
    let r = morph()
        .arg(&pa)
        .arg(&pa)
        .args(["--t", "2", "-o"])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(!r.status.success());
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
    let r = bin().args(["demo", "-o"]).arg(&out).output().expect("runs");
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    for name in [
        "source.obj",
        "target.obj",
        "frame_0000.obj",
        "frame_0010.obj",
    ] {
        assert!(out.join(name).is_file(), "{name}");
    }
    let stdout = String::from_utf8(r.stdout).expect("utf8");
    assert!(stdout.contains("0 flipped triangles"));
}
