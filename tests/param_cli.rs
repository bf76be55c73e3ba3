//! `bdmorph param` on the command line, issue 23: a stalled solver or collapsed triangles
//! are reported in `--stats` and on stderr with exit code 1 (the map still written); the
//! bounded-distortion command reports the starts it tried; every summary carries its set-up
//! time apart from the iterations'.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use bdmorph::generate;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bdmorph"))
}

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-param-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
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

/// The summary line of `--stats` (the last line of stdout).
fn summary(out: &Output) -> String {
    let stdout = String::from_utf8(out.stdout.clone()).expect("utf8");
    stdout.lines().last().expect("a summary line").to_string()
}

/// The number after `"key":` in a JSON line.
fn field(line: &str, key: &str) -> f64 {
    let at = line
        .find(&format!("\"{key}\":"))
        .unwrap_or_else(|| panic!("{key} in {line}"));
    let rest = &line[at + key.len() + 3..];
    let end = rest.find([',', '}']).expect("end of value");
    rest[..end]
        .parse()
        .unwrap_or_else(|e| panic!("{key}: {e} in {line}"))
}

/// Plain ARAP by projected Newton squashes triangles of a coarse finger flat and stalls
/// (issue 23: exit code 0 and "0 flipped" before); with the default collapse barrier it
/// converges with none collapsed.
#[test]
fn issue_23_arap_newton_stall_and_collapse_exit_1() {
    let dir = scratch("stall");
    let mesh = write_surface(&dir, "finger.obj", &generate::finger(6, 8, 0.6));
    let out = dir.join("plain.obj");
    let r = bin()
        .arg("param")
        .arg(&mesh)
        .args([
            "--method",
            "arap-newton",
            "--collapse-barrier",
            "0",
            "--stats",
            "-o",
        ])
        .arg(&out)
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(
        err.contains("arap-newton stalled after")
            && err.contains("the map is not a minimum")
            && err.contains("collapsed triangles"),
        "{err}"
    );
    let line = summary(&r);
    assert!(
        line.contains("\"stop\":\"stalled\"") && line.contains("\"stalled\":true"),
        "{line}"
    );
    assert!(field(&line, "collapsed") > 0.0, "{line}");
    assert_eq!(field(&line, "flipped"), 0.0, "{line}");
    assert!(out.is_file(), "the map is still written");

    let r = bin()
        .arg("param")
        .arg(&mesh)
        .args(["--method", "arap-newton", "--stats"])
        .output()
        .expect("runs");
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let line = summary(&r);
    assert!(
        line.contains("\"stop\":\"converged\"") && line.contains("\"stalled\":false"),
        "{line}"
    );
    assert_eq!(field(&line, "collapsed"), 0.0, "{line}");
    assert_eq!(field(&line, "flipped"), 0.0, "{line}");
    // A negative barrier weight is refused.
    let r = bin()
        .arg("param")
        .arg(&mesh)
        .args([
            "--method",
            "arap-newton",
            "--collapse-barrier",
            "-1",
            "--stats",
        ])
        .output()
        .expect("runs");
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("collapse-barrier weight"));
}

/// Every method's summary has the set-up time apart from the iterations' time.
#[test]
fn issue_23_stats_report_set_up_apart() {
    let dir = scratch("setup");
    let mesh = write_surface(&dir, "cap.obj", &generate::sphere_cap(3, 0.0));
    for method in ["tutte", "lscm", "asap", "arap", "sd", "mips", "arap-newton"] {
        let r = bin()
            .arg("param")
            .arg(&mesh)
            .args(["--method", method, "--stats", "-q"])
            .output()
            .expect("runs");
        assert!(r.status.success(), "{method}");
        let line = summary(&r);
        let (setup, seconds) = (field(&line, "setup_seconds"), field(&line, "seconds"));
        assert!(setup > 0.0 && setup.is_finite(), "{method}: {line}");
        assert!(seconds >= 0.0 && seconds.is_finite(), "{method}: {line}");
        assert!(line.contains("\"collapsed\":0"), "{method}: {line}");
    }
}
