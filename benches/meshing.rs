//! Meshing a 1024 x 1024 picture made in code ([`generate::picture_subject`]: a round body with
//! a hole and an arm, and a separate disk) at about 1K, 10K and 50K vertices.
//!
//! Groups: `meshing_picture/<N>` (the whole [`meshing::mesh_picture`]: coverage, tracing,
//! simplification, checks, refinement passes, texture coordinates), `meshing_outline` (the
//! picture to its simplified outline, [`meshing::picture_outline`], the same for every N) and
//! `meshing_triangulate/<N>` ([`meshing::mesh_outline`] on that outline). See BENCHMARKS.md.

use std::hint::black_box;
use std::time::Duration;

use bdmorph::generate;
use bdmorph::meshing::{self, MeshOptions, PictureOptions};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

const SIZES: [usize; 3] = [1_000, 10_000, 50_000];

fn benches(c: &mut Criterion) {
    let picture = generate::picture_subject(1024);
    let subject = PictureOptions::default();
    let mut group = c.benchmark_group("meshing_picture");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for n in SIZES {
        let options = MeshOptions::default().with_vertices(n);
        let m = meshing::mesh_picture(&picture, &subject, &options).expect("meshes");
        eprintln!("[bdmorph meshing {n}] {:?}", m.stats);
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                meshing::mesh_picture(black_box(&picture), &subject, &options).expect("meshes")
            });
        });
    }
    group.finish();

    let mut group = c.benchmark_group("meshing_outline");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    group.bench_function("1024x1024", |b| {
        b.iter(|| meshing::picture_outline(black_box(&picture), &subject, None).expect("traces"));
    });
    group.finish();

    let outline = meshing::picture_outline(&picture, &subject, None)
        .expect("traces")
        .outline;
    let mut group = c.benchmark_group("meshing_triangulate");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for n in SIZES {
        let options = MeshOptions::default().with_vertices(n);
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| meshing::mesh_outline(black_box(&outline), &options).expect("meshes"));
        });
    }
    group.finish();
}

criterion_group!(meshing, benches);
criterion_main!(meshing);
