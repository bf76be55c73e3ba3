//! Posing by handles (`bdmorph::deform`), every method: one drag (a mouse moving back and
//! forth, a new target each time, warm-started from the previous pose) and a re-pin (the
//! only factorisation), on generated disks of about 1K, 5K, 10K and 20K vertices with four
//! handles, and on the shared planar meshes (woody, 694 vertices; the USTC leaf, 3,000) when
//! `../shared/data` is present.
//!
//! Baseline in the same run: a KVF drag that factors its system on every move, as the
//! original editor does (here `set_pins` then `drag`), against the drag on the factor made
//! once.
//!
//! `cargo bench --bench deform`

use std::path::Path;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

use bdmorph::deform::{Deformer, KvfOptions, PoseMethod};
use bdmorph::{generate, PlanarMesh};

/// Four handles: the first vertex, and three on the far side, spread out.
fn handles(mesh: &PlanarMesh) -> Vec<u32> {
    let n = mesh.positions.len() as u32;
    vec![0, n - 1, n - 1 - n / 10, n - 1 - n / 5]
}

/// The methods, as named in the benchmark ids: symmetric Dirichlet (`sd`, the studio's
/// default: no triangle flips or is crushed), KVF (steps that may fold, its default) and KVF
/// with flip-free steps (`kvf-flip-free`), ARAP, and bounded distortion.
fn methods() -> [(&'static str, PoseMethod); 5] {
    [
        ("sd", PoseMethod::sd()),
        ("kvf", PoseMethod::kvf()),
        (
            "kvf-flip-free",
            PoseMethod::Kvf(KvfOptions::default().with_flip_free(true)),
        ),
        ("arap", PoseMethod::arap()),
        ("bounded", PoseMethod::bounded(2.5)),
    ]
}

/// A mouse moving handle 1 back and forth by a tenth of the mesh's size, a new target per
/// call.
struct Mouse {
    from: [f64; 2],
    reach: f64,
    step: u32,
}

impl Mouse {
    fn next(&mut self) -> [f64; 2] {
        self.step += 1;
        let s = f64::from(self.step % 40) / 40.0;
        let s = if s > 0.5 { 1.0 - s } else { s };
        [
            self.from[0] + self.reach * s,
            self.from[1] + 0.6 * self.reach * s,
        ]
    }
}

fn meshes() -> Vec<(String, PlanarMesh)> {
    let mut out: Vec<(String, PlanarMesh)> = [1000, 5000, 10000, 20000]
        .iter()
        .map(|&n| {
            let mesh = generate::disk(generate::rings_for(n), 0.2);
            (format!("disk-{}", mesh.positions.len()), mesh)
        })
        .collect();
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/morph2d");
    for (name, file) in [
        ("woody", "woody/woody.obj"),
        ("leaf", "ustc-hw8-leaf/0.000000.obj"),
    ] {
        match PlanarMesh::read(shared.join(file)) {
            Ok(mesh) => out.push((format!("{name}-{}", mesh.positions.len()), mesh)),
            Err(e) => eprintln!("deform bench: skipping {name}: {e} (is ../shared/data there?)"),
        }
    }
    out
}

fn bench(c: &mut Criterion) {
    let meshes = meshes();
    for (label, method) in methods() {
        let mut drag = c.benchmark_group(format!("deform_drag/{label}"));
        for (name, mesh) in &meshes {
            let pins = handles(mesh);
            let mut pose = Deformer::new(mesh, method.clone()).expect("set up");
            pose.set_pins(&pins).expect("pins");
            let mut targets: Vec<[f64; 2]> =
                pins.iter().map(|&v| mesh.positions[v as usize]).collect();
            let mut mouse = Mouse {
                from: targets[1],
                reach: 0.1 * mesh.diameter(),
                step: 0,
            };
            drag.bench_function(BenchmarkId::from_parameter(name), |b| {
                b.iter(|| {
                    targets[1] = mouse.next();
                    pose.drag(&targets).expect("drag")
                })
            });
        }
        drag.finish();
        let mut repin = c.benchmark_group(format!("deform_set_pins/{label}"));
        for (name, mesh) in &meshes {
            let pins = handles(mesh);
            let mut pose = Deformer::new(mesh, method.clone()).expect("set up");
            repin.bench_function(BenchmarkId::from_parameter(name), |b| {
                b.iter(|| pose.set_pins(&pins).expect("pins"))
            });
        }
        repin.finish();
    }
    // The baseline: factoring on every move.
    let mut baseline = c.benchmark_group("deform_drag_refactoring/kvf");
    for (name, mesh) in &meshes {
        let pins = handles(mesh);
        let mut pose = Deformer::new(mesh, PoseMethod::kvf()).expect("set up");
        let mut targets: Vec<[f64; 2]> = pins.iter().map(|&v| mesh.positions[v as usize]).collect();
        let mut mouse = Mouse {
            from: targets[1],
            reach: 0.1 * mesh.diameter(),
            step: 0,
        };
        baseline.bench_function(BenchmarkId::from_parameter(name), |b| {
            b.iter(|| {
                targets[1] = mouse.next();
                pose.set_pins(&pins).expect("pins");
                pose.drag(&targets).expect("drag")
            })
        });
    }
    baseline.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
