//! Parameterisation: set-up (checks, per-triangle constants, Tutte or LSCM start, symbolic
//! factorisation) and one iteration per method, on a generated hemisphere (always) and the
//! shared camel head (skipped with a message without `../shared/data`).
//!
//! Groups: `param_setup/<method>/<mesh>` ([`Parameterization::new`]) and
//! `param_iteration/<method>/<mesh>` (the first [`Parameterization::step`] from the Tutte
//! start, set-up excluded). See BENCHMARKS.md; the whole-run figures
//! against SLIM come from `examples/param_compare.rs`.

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

use bdmorph::generate;
use bdmorph::param::{ParamMethod, ParamOptions, Parameterization};
use bdmorph::SurfaceMesh;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

fn meshes() -> Vec<(&'static str, SurfaceMesh)> {
    let mut out = vec![("hemisphere", generate::sphere_cap(5, 0.0))];
    let path = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/data/disk3d/libigl/camelhead.off"
    ));
    match bdmorph::io::read_mesh(&path) {
        Ok(mesh) => out.push(("camelhead", mesh)),
        Err(e) => eprintln!("SKIPPED: the camel head is not benchmarked: {e}"),
    }
    out
}

const METHODS: [(&str, ParamMethod); 7] = [
    ("tutte", ParamMethod::Tutte),
    ("lscm", ParamMethod::Lscm),
    ("asap", ParamMethod::Asap),
    ("arap", ParamMethod::Arap),
    ("sd", ParamMethod::SymmetricDirichlet),
    ("mips", ParamMethod::Mips),
    ("arap-newton", ParamMethod::ArapNewton),
];

fn benches(c: &mut Criterion) {
    let meshes = meshes();
    let mut group = c.benchmark_group("param_setup");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    for (mesh_name, mesh) in &meshes {
        for (name, method) in METHODS {
            group.bench_function(BenchmarkId::new(name, mesh_name), |b| {
                b.iter(|| {
                    Parameterization::new(black_box(mesh), method, ParamOptions::default())
                        .expect("set up")
                });
            });
        }
    }
    group.finish();
    let mut group = c.benchmark_group("param_iteration");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    for (mesh_name, mesh) in &meshes {
        for (name, method) in METHODS.into_iter().skip(2) {
            // The first iteration from a fresh Tutte start each time (the set-up outside the
            // timing): a converged state would time line searches that find nothing.
            group.bench_function(BenchmarkId::new(name, mesh_name), |b| {
                b.iter_batched(
                    || {
                        Parameterization::new(mesh, method, ParamOptions::default())
                            .expect("set up")
                    },
                    |mut p| p.step().expect("step"),
                    criterion::BatchSize::LargeInput,
                );
            });
        }
    }
    group.finish();
}

criterion_group!(param, benches);
criterion_main!(param);
