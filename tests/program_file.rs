//! Compiled programs as files: `Program::to_bytes` / `from_bytes` on compiled meshes, and the
//! command line's `compile` and `morph --program`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use bdmorph::{
    compile, generate, io, LoadError, MeshKey, Morph, MorphOptions, PlanarMesh, Program, Vm,
};

fn key(m: &PlanarMesh) -> MeshKey {
    MeshKey::of(m.positions.len(), &m.faces)
}

fn compiled(m: &PlanarMesh) -> (Program, Vec<u8>) {
    let program = compile(&m.positions, &m.faces).expect("compiles");
    let bytes = program.to_bytes(&key(m));
    (program, bytes)
}

#[test]
fn a_loaded_program_runs_exactly_like_a_fresh_one() {
    let a = generate::disk(8, 0.2);
    let b = generate::bend(&generate::twist(&a, 0.9), 0.5);
    let (program, bytes) = compiled(&a);
    let (loaded, loaded_key) = Program::from_bytes(&bytes).expect("loads");
    assert_eq!(loaded, program);
    assert_eq!(loaded_key, key(&a));
    // The VM accepts it directly ...
    let mut vm = Vm::new(loaded.clone()).expect("vm");
    let l = vm.squared_lengths(&a.positions).expect("lengths");
    vm.set_metric(&l).expect("metric");
    assert!(
        vm.newton(&Default::default())
            .expect("newton")
            .gradient_norm
            < 1e-10
    );
    // ... and a morph from it computes the same bits as one that compiles.
    let mut fresh = Morph::new(&a, &b, MorphOptions::default()).expect("morph");
    let mut from_file =
        Morph::with_program(loaded, &a, &b, MorphOptions::default()).expect("morph");
    for t in [0.0, 0.3, 0.7, 1.0] {
        let x = fresh.frame(t).expect("frame").positions.to_vec();
        let y = from_file.frame(t).expect("frame").positions.to_vec();
        assert_eq!(x, y, "t = {t}");
    }
}

#[test]
fn every_damaged_byte_and_truncation_of_a_compiled_program_is_refused() {
    let a = generate::disk(4, 0.2);
    let (_, bytes) = compiled(&a);
    let mut damaged = bytes.clone();
    for at in 0..bytes.len() {
        // Every byte inverted; one bit (cycling through the eight) at every 5th offset.
        let masks: &[u8] = if at % 5 == 0 {
            &[0xFF, 1 << (at / 5 % 8)]
        } else {
            &[0xFF]
        };
        for &mask in masks {
            damaged[at] ^= mask;
            assert!(
                Program::from_bytes(&damaged).is_err(),
                "byte {at} ^ {mask:#x} was accepted"
            );
            damaged[at] ^= mask;
        }
    }
    for len in 0..bytes.len() {
        assert!(
            matches!(
                Program::from_bytes(&bytes[..len]),
                Err(LoadError::Truncated { .. })
            ),
            "length {len}"
        );
    }
    assert!(Program::from_bytes(&bytes).is_ok());
}

/// The file of a generated 10K-vertex disk stays compact: the whole file and each section
/// under bounds a little above what was measured (bytes per triangle: 31.5 in all; layout
/// 3.55, unknowns 0.50, Hessian 1.95, iteration stream about 25.5 with one TRIANGLE
/// instruction per face). Tighten them when the encodings (or the stream) shrink.
#[test]
fn the_file_of_a_10k_disk_stays_small() {
    let mesh = generate::disk(generate::rings_for(10_000), 0.25);
    let (program, bytes) = compiled(&mesh);
    let faces = mesh.faces.len() as f64;
    let per = |n: usize| n as f64 / faces;
    let sizes = program.file_sizes();
    assert_eq!(sizes.total(), bytes.len());
    let report = format!("{sizes:?}, {} faces", mesh.faces.len());
    assert!(per(bytes.len()) < 33.0, "{report}");
    assert!(per(sizes.layout) < 3.7, "{report}");
    assert!(per(sizes.unknowns) < 0.55, "{report}");
    assert!(per(sizes.hessian) < 2.1, "{report}");
    assert!(per(sizes.iteration) < 27.0, "{report}");
    assert_eq!(program.stats().file_bytes, bytes.len());
}

// --- The command line ---

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bdmorph"))
}

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-prog-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn write(dir: &Path, name: &str, m: &PlanarMesh) -> PathBuf {
    let path = dir.join(name);
    io::write_obj_2d(&path, &m.positions, &m.faces, &[]).expect("write");
    path
}

fn run(cmd: &mut Command) -> Output {
    cmd.output().expect("runs")
}

fn run_ok(cmd: &mut Command) -> Output {
    let out = run(cmd);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs a command that must fail with one line on stderr containing `needle`.
fn fails(cmd: &mut Command, needle: &str) {
    let out = run(cmd);
    let err = String::from_utf8(out.stderr).expect("utf8");
    assert!(!out.status.success(), "must fail");
    assert!(err.contains(needle), "{needle:?} not in {err}");
    assert_eq!(err.lines().count(), 1, "{err}");
}

/// Names of the files in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn compile_then_morph_with_the_program_writes_the_same_bytes() {
    let dir = scratch("same");
    let a = generate::disk(6, 0.2);
    let pa = write(&dir, "a.obj", &a);
    let pb = write(&dir, "b.obj", &generate::twist(&a, 0.8));
    let prog = dir.join("a.bdm");
    let out = run_ok(bin().arg("compile").arg(&pa).arg("-o").arg(&prog));
    let bytes = std::fs::read(&prog).expect("written");
    let stderr = String::from_utf8(out.stderr).expect("utf8");
    assert!(
        stderr.contains(&format!("{} bytes", bytes.len())) && stderr.contains("bytes per triangle"),
        "{stderr}"
    );
    assert_eq!(Program::from_bytes(&bytes).expect("loads").1, key(&a));
    // Quiet: nothing printed, the same file.
    let quiet = dir.join("quiet.bdm");
    let out = run_ok(
        bin()
            .arg("compile")
            .arg(&pa)
            .arg("-q")
            .arg("-o")
            .arg(&quiet),
    );
    assert!(out.stderr.is_empty() && out.stdout.is_empty());
    assert_eq!(std::fs::read(&quiet).expect("written"), bytes);

    let morph = |program: Option<&Path>, args: &[&str]| {
        let mut c = bin();
        c.arg("morph").arg(&pa).arg(&pb).args(args);
        if let Some(p) = program {
            c.arg("--program").arg(p);
        }
        run_ok(&mut c)
    };
    let with = dir.join("with.obj");
    let without = dir.join("without.obj");
    morph(
        Some(&prog),
        &["--t", "0.5", "-o", with.to_str().expect("utf8")],
    );
    morph(None, &["--t", "0.5", "-o", without.to_str().expect("utf8")]);
    assert_eq!(
        std::fs::read(&with).expect("written"),
        std::fs::read(&without).expect("written")
    );
    // Every frame, and the statistics.
    let with = dir.join("with");
    let without = dir.join("without");
    let s1 = morph(
        Some(&prog),
        &[
            "--frames",
            "4",
            "--stats",
            "-o",
            with.to_str().expect("utf8"),
        ],
    );
    let s2 = morph(
        None,
        &[
            "--frames",
            "4",
            "--stats",
            "-o",
            without.to_str().expect("utf8"),
        ],
    );
    // The same statistics but for the wall-clock time, which is the last field.
    let timeless = |out: &[u8]| -> Vec<String> {
        String::from_utf8_lossy(out)
            .lines()
            .map(|l| l.split(",\"seconds\":").next().unwrap_or(l).to_string())
            .collect()
    };
    assert!(String::from_utf8_lossy(&s1.stdout).contains("\"seconds\":"));
    assert_eq!(timeless(&s1.stdout), timeless(&s2.stdout));
    for i in 0..4 {
        let name = format!("frame_{i:04}.obj");
        assert_eq!(
            std::fs::read(with.join(&name)).expect("written"),
            std::fs::read(without.join(&name)).expect("written"),
            "{name}"
        );
    }
}

#[test]
fn a_program_for_another_mesh_is_refused_and_nothing_is_written() {
    let dir = scratch("other");
    let a = generate::disk(6, 0.2);
    let pa = write(&dir, "a.obj", &a);
    let pb = write(&dir, "b.obj", &generate::twist(&a, 0.8));
    let small = write(&dir, "small.obj", &generate::disk(5, 0.2));
    // The same triangles with one face's corners rotated: the same counts, other faces.
    let mut rotated = a.clone();
    rotated.faces[10].rotate_left(1);
    let rotated = write(&dir, "rotated.obj", &rotated);
    for (mesh, name) in [(&small, "small.bdm"), (&rotated, "rotated.bdm")] {
        run_ok(
            bin()
                .args(["compile", "-q"])
                .arg(mesh)
                .arg("-o")
                .arg(dir.join(name)),
        );
    }
    let before = listing(&dir);
    let out = dir.join("never.obj");
    let morph = |program: &str| {
        let mut c = bin();
        c.arg("morph")
            .arg(&pa)
            .arg(&pb)
            .arg("--program")
            .arg(dir.join(program))
            .args(["--t", "0.5", "-o"])
            .arg(&out);
        c
    };
    fails(
        &mut morph("small.bdm"),
        "small.bdm was compiled for another mesh: 91 vertices vs 127 in",
    );
    fails(
        &mut morph("rotated.bdm"),
        "rotated.bdm was compiled for another mesh: faces hash",
    );
    assert_eq!(listing(&dir), before, "nothing written");
}

#[test]
fn a_damaged_program_file_is_refused_and_nothing_is_written() {
    let dir = scratch("damaged");
    let a = generate::disk(6, 0.2);
    let pa = write(&dir, "a.obj", &a);
    let pb = write(&dir, "b.obj", &generate::twist(&a, 0.8));
    let good = dir.join("a.bdm");
    run_ok(bin().args(["compile", "-q"]).arg(&pa).arg("-o").arg(&good));
    let bytes = std::fs::read(&good).expect("written");
    let damage = |name: &str, edit: &dyn Fn(&mut Vec<u8>)| {
        let mut b = bytes.clone();
        edit(&mut b);
        std::fs::write(dir.join(name), b).expect("write");
    };
    let middle = bytes.len() / 2;
    damage("flipped.bdm", &|b| b[middle] ^= 0x01);
    damage("length.bdm", &|b| {
        // The file's length in the header, one more than it is.
        let len = b.len() as u64 + 1;
        b[12..20].copy_from_slice(&len.to_le_bytes());
    });
    damage("newer.bdm", &|b| b[8] = 3); // the format version
    damage("v1.bdm", &|b| b[8] = 1); // version 1 files are not read
    damage("short.bdm", &|b| b.truncate(b.len() - 1));
    let before = listing(&dir);
    let out = dir.join("never");
    for (name, needle) in [
        ("flipped.bdm", "flipped.bdm: damaged: checksum mismatch"),
        ("length.bdm", "length.bdm: truncated or damaged"),
        (
            "newer.bdm",
            "newer.bdm: program format version 3 is not supported",
        ),
        (
            "v1.bdm",
            "v1.bdm: program format version 1 is not supported (this build reads version 2); \
             compile the mesh again",
        ),
        ("short.bdm", "short.bdm: truncated or damaged"),
        ("a.obj", "a.obj: not a bdmorph program file"),
        ("missing.bdm", "missing.bdm: cannot read"),
    ] {
        fails(
            bin()
                .arg("morph")
                .arg(&pa)
                .arg(&pb)
                .arg("--program")
                .arg(dir.join(name))
                .args(["--frames", "3", "-o"])
                .arg(&out),
            needle,
        );
    }
    assert_eq!(listing(&dir), before, "nothing written");
}

#[test]
fn compile_refuses_bad_meshes_and_mesh_extensions_writing_nothing() {
    let dir = scratch("compile-errors");
    let a = generate::disk(4, 0.2);
    let pa = write(&dir, "a.obj", &a);
    let mut cw = a.clone();
    cw.faces[3].swap(0, 1);
    let pcw = write(&dir, "cw.obj", &cw);
    let before = listing(&dir);
    fails(
        bin().arg("compile").arg(&pa).arg("-o").arg(&pa),
        "a program is not a .obj mesh",
    );
    fails(
        bin()
            .arg("compile")
            .arg(&pa)
            .arg("-o")
            .arg(dir.join("x.OFF")),
        "a program is not a .off mesh",
    );
    fails(
        bin()
            .arg("compile")
            .arg(&pcw)
            .arg("-o")
            .arg(dir.join("cw.bdm")),
        "cw.obj",
    );
    fails(
        bin().arg("compile").arg(&pa),
        "required arguments were not provided: --output <PROGRAM>",
    );
    assert_eq!(listing(&dir), before, "nothing written");
    assert_eq!(std::fs::read(&pa).expect("intact"), {
        let mut v = Vec::new();
        io::format_obj_2d(&mut v, &a.positions, &a.faces, &[]).expect("format");
        v
    });
}

#[test]
fn help_shows_the_compile_example() {
    let help = String::from_utf8(run_ok(bin().args(["compile", "--help"])).stdout).expect("utf8");
    assert!(
        help.contains("Example:") && help.contains("bdmorph compile man.obj -o man.bdm"),
        "{help}"
    );
    let help = String::from_utf8(run_ok(bin().args(["morph", "--help"])).stdout).expect("utf8");
    assert!(help.contains("--program <PROGRAM>"), "{help}");
    let help = String::from_utf8(run_ok(bin().arg("--help")).stdout).expect("utf8");
    assert!(help.contains("compile"), "{help}");
}
