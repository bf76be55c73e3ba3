//! Thread counts (`--threads`, rayon pools): results agree across thread counts within the
//! solver's tolerance (positions within 1e-9 of the mesh's size), and repeat byte for byte
//! with the same count.

use std::path::{Path, PathBuf};
use std::process::Command;

use bdmorph::{generate, io, Morph, MorphOptions, PlanarMesh};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bdmorph"))
}

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-threads-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// The benchmarks' pair at about `n` vertices: large enough at 10K for the factorisation to
/// be split over two threads.
fn pair(n: usize) -> (PlanarMesh, PlanarMesh) {
    let a = generate::disk(generate::rings_for(n), 0.25);
    let b = generate::twist(&generate::bend(&a, 0.6), 1.2);
    (a, b)
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a pool")
}

fn max_distance(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max)
}

/// Frames of a one-way sweep, the morph set up and run in a pool of `threads`.
fn frames(a: &PlanarMesh, b: &PlanarMesh, threads: usize) -> Vec<Vec<[f64; 2]>> {
    pool(threads).install(|| {
        let mut morph = Morph::new(a, b, MorphOptions::default()).expect("morph");
        (0..=10)
            .map(|i| {
                let frame = morph.frame(f64::from(i) / 10.0).expect("frame");
                assert_eq!(frame.stats.flipped_triangles, 0);
                frame.positions.to_vec()
            })
            .collect()
    })
}

#[test]
fn library_frames_agree_across_pools_and_repeat_bit_for_bit() {
    let (a, b) = pair(10_000);
    let size = a.diameter();
    let one = frames(&a, &b, 1);
    for threads in [2, 3] {
        let many = frames(&a, &b, threads);
        for (i, (p, q)) in one.iter().zip(&many).enumerate() {
            let d = max_distance(p, q) / size;
            assert!(d < 1e-9, "{threads} threads, frame {i}: {d:e} of the size");
        }
        let again = frames(&a, &b, threads);
        let same = many
            .iter()
            .flatten()
            .zip(again.iter().flatten())
            .all(|(p, q)| p[0].to_bits() == q[0].to_bits() && p[1].to_bits() == q[1].to_bits());
        assert!(same, "{threads} threads: the same bits every run");
    }
}

fn read_positions(path: &Path) -> Vec<[f64; 2]> {
    let file = bdmorph::MeshFile::read(path).expect("read");
    file.planar().expect("planar").positions
}

/// `morph --frames` into `out` with `--threads`.
fn morph_frames(a: &Path, b: &Path, threads: &str, frames: &str, out: &Path) {
    let status = bin()
        .args(["--threads", threads, "morph"])
        .arg(a)
        .arg(b)
        .args(["--frames", frames, "-q", "-o"])
        .arg(out)
        .status()
        .expect("runs");
    assert!(status.success(), "--threads {threads} -o {}", out.display());
}

#[test]
fn command_line_frames_agree_across_thread_counts() {
    let dir = scratch("cli");
    let (a, b) = pair(10_000);
    let (pa, pb) = (dir.join("a.obj"), dir.join("b.obj"));
    io::write_obj_2d(&pa, &a.positions, &a.faces, &[]).expect("write");
    io::write_obj_2d(&pb, &b.positions, &b.faces, &[]).expect("write");
    // 24 frames: two stretches of 12 on two threads, each warm-started from its own start.
    let runs = [
        ("1", "one"),
        ("2", "two"),
        ("2", "two-again"),
        ("3", "three"),
    ];
    for (threads, name) in runs {
        morph_frames(&pa, &pb, threads, "24", &dir.join(name));
    }
    let size = a.diameter();
    for i in 0..24 {
        let file = format!("frame_{i:04}.obj");
        let one = read_positions(&dir.join("one").join(&file));
        for other in ["two", "three"] {
            let p = read_positions(&dir.join(other).join(&file));
            let d = max_distance(&one, &p) / size;
            assert!(
                d < 1e-9,
                "{file}, {other} threads: {d:e} of the size from one thread"
            );
        }
        let two = std::fs::read(dir.join("two").join(&file)).expect("read");
        let again = std::fs::read(dir.join("two-again").join(&file)).expect("read");
        assert!(
            two == again,
            "{file}: the same bytes with the same --threads"
        );
    }
    // Animations: pictures drawn and encoded in parallel, written in order.
    for name in ["x.gif", "y.gif", "x.mp4", "y.mp4", "x.html", "y.html"] {
        morph_frames(&pa, &pb, "2", "16", &dir.join(name));
    }
    for ext in ["gif", "mp4", "html"] {
        let x = std::fs::read(dir.join(format!("x.{ext}"))).expect("read");
        let y = std::fs::read(dir.join(format!("y.{ext}"))).expect("read");
        assert!(
            !x.is_empty() && x == y,
            "{ext}: the same bytes with the same --threads"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn pictures_do_not_depend_on_the_thread_count() {
    // A small morph: one stretch whatever the count, so the frames are the same bits and the
    // pictures drawn in parallel must be the same bytes as those drawn on one thread.
    let dir = scratch("pictures");
    let a = generate::disk(8, 0.2);
    let b = generate::twist(&a, 0.8);
    let (pa, pb) = (dir.join("a.obj"), dir.join("b.obj"));
    io::write_obj_2d(&pa, &a.positions, &a.faces, &[]).expect("write");
    io::write_obj_2d(&pb, &b.positions, &b.faces, &[]).expect("write");
    for threads in ["1", "2"] {
        let status = bin()
            .args(["--threads", threads, "morph"])
            .arg(&pa)
            .arg(&pb)
            .args([
                "--frames", "6", "--format", "png", "--size", "96x96", "-q", "-o",
            ])
            .arg(dir.join(format!("png{threads}")))
            .status()
            .expect("runs");
        assert!(status.success());
        morph_frames(
            &pa,
            &pb,
            threads,
            "6",
            &dir.join(format!("gif{threads}.gif")),
        );
    }
    for i in 0..6 {
        let file = format!("frame_{i:04}.png");
        let one = std::fs::read(dir.join("png1").join(&file)).expect("read");
        let two = std::fs::read(dir.join("png2").join(&file)).expect("read");
        assert!(one == two, "{file}: the same bytes on one and two threads");
    }
    let one = std::fs::read(dir.join("gif1.gif")).expect("read");
    let two = std::fs::read(dir.join("gif2.gif")).expect("read");
    assert!(one == two, "GIF: the same bytes on one and two threads");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_thread_count_of_zero_is_refused() {
    let out = bin()
        .args(["--threads", "0", "info", "x.obj"])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--threads") && err.contains("1..=1024"),
        "{err}"
    );
}

#[test]
fn frames_called_from_outside_the_pool_are_those_of_the_pool() {
    // The library runs a split frame on rayon's global pool when called from another thread:
    // the same split, so the same bits as the frames run inside a pool of that many threads.
    let (a, b) = pair(10_000);
    let threads = rayon::current_num_threads();
    let mut morph = Morph::new(&a, &b, MorphOptions::default()).expect("morph");
    let outside: Vec<Vec<[f64; 2]>> = (0..=10)
        .map(|i| {
            let frame = morph.frame(f64::from(i) / 10.0).expect("frame");
            frame.positions.to_vec()
        })
        .collect();
    let inside = frames(&a, &b, threads);
    let same = outside
        .iter()
        .flatten()
        .zip(inside.iter().flatten())
        .all(|(p, q)| p[0].to_bits() == q[0].to_bits() && p[1].to_bits() == q[1].to_bits());
    assert!(same, "{threads} threads: outside the pool, the pool's bits");
}

/// The library's own thread option on each precompute object: the same frames, distances,
/// maps and poses on one thread, two threads and the global pool (to the solver's
/// tolerance), the same bits for the same count, and a count out of range refused by name.
#[test]
fn each_precompute_object_runs_on_the_threads_it_is_given() {
    use bdmorph::deform::{Deformer, PoseMethod};
    use bdmorph::geodesic::{HeatGeodesics, HeatOptions};
    use bdmorph::param::{ParamMethod, ParamOptions, Parameterization};
    use bdmorph::{Blend, KeyframePath, SurfaceMesh};

    let a = generate::disk(60, 0.2);
    let b = generate::bend(&a, 0.6);
    let size = a.diameter();
    let close = |p: &[[f64; 2]], q: &[[f64; 2]]| {
        p.iter()
            .zip(q)
            .map(|(x, y)| (x[0] - y[0]).hypot(x[1] - y[1]))
            .fold(0.0, f64::max)
            <= 1e-9 * size
    };
    let options = [None, Some(1), Some(2)];
    // Morph, Blend, KeyframePath.
    let morphs: Vec<Vec<[f64; 2]>> = options
        .iter()
        .map(|&t| {
            let o = match t {
                Some(n) => MorphOptions::default().with_threads(n),
                None => MorphOptions::default(),
            };
            let mut m = Morph::new(&a, &b, o).expect("morph");
            m.frame(0.4).expect("frame").positions.to_vec()
        })
        .collect();
    assert!(close(&morphs[0], &morphs[1]) && close(&morphs[0], &morphs[2]));
    let again = Morph::new(&a, &b, MorphOptions::default().with_threads(2))
        .expect("morph")
        .frame(0.4)
        .expect("frame")
        .positions
        .to_vec();
    assert_eq!(again, morphs[2], "the same count repeats bit for bit");
    let keys = [a.clone(), b.clone()];
    assert!(
        Blend::with_options(&keys, MorphOptions::default().with_threads(2))
            .expect("blend")
            .frame_weights(&[0.6, 0.4])
            .map(|f| close(f.positions, &morphs[0]))
            .expect("frame")
    );
    let path_options =
        bdmorph::PathOptions::default().with_morph(MorphOptions::default().with_threads(1));
    let mut path = KeyframePath::with_options(&keys, path_options).expect("path");
    assert!(close(path.frame(0.4).expect("frame").positions, &morphs[0]));
    // Geodesics.
    let surface = SurfaceMesh::from(&a);
    let distances: Vec<Vec<f64>> = options
        .iter()
        .map(|&t| {
            let o = match t {
                Some(n) => HeatOptions::default().with_threads(n),
                None => HeatOptions::default(),
            };
            HeatGeodesics::new(&surface, o)
                .expect("geodesics")
                .distance(&[0])
                .expect("distance")
        })
        .collect();
    for d in &distances[1..] {
        let worst = d
            .iter()
            .zip(&distances[0])
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(worst <= 1e-9 * size, "geodesics differ by {worst}");
    }
    // Parameterisation.
    let maps: Vec<Vec<[f64; 2]>> = options
        .iter()
        .map(|&t| {
            let o = match t {
                Some(n) => ParamOptions::default().with_threads(n),
                None => ParamOptions::default(),
            };
            let mut p =
                Parameterization::new(&surface, ParamMethod::Lscm, o).expect("parameterisation");
            p.solve().expect("solve");
            p.uv().to_vec()
        })
        .collect();
    assert!(close(&maps[0], &maps[1]) && close(&maps[0], &maps[2]));
    // Posing.
    let poses: Vec<Vec<[f64; 2]>> = options
        .iter()
        .map(|&t| {
            let mut d = Deformer::new(&a, PoseMethod::arap()).expect("deformer");
            d.set_threads(t).expect("threads");
            d.set_pins(&[0, 1]).expect("pins");
            let p = a.positions[1];
            d.drag(&[a.positions[0], [p[0] + 0.1, p[1] + 0.05]])
                .expect("drag");
            d.positions().to_vec()
        })
        .collect();
    assert!(close(&poses[0], &poses[1]) && close(&poses[0], &poses[2]));
    // Counts out of range.
    for n in [0, 1025] {
        let said = Morph::new(&a, &b, MorphOptions::default().with_threads(n))
            .expect_err("refused")
            .to_string();
        assert!(
            said.contains(&format!("threads must be from 1 to 1024, not {n}")),
            "{said}"
        );
        assert!(HeatGeodesics::new(&surface, HeatOptions::default().with_threads(n)).is_err());
        assert!(Parameterization::new(
            &surface,
            ParamMethod::Tutte,
            ParamOptions::default().with_threads(n)
        )
        .is_err());
        let mut d = Deformer::new(&a, PoseMethod::kvf()).expect("deformer");
        assert!(d.set_threads(Some(n)).is_err());
    }
}
