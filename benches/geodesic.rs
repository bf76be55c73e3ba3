//! Heat-method geodesics: set-up (intrinsic Delaunay, operators, factorisations) and one
//! distance query, on the shared meshes the peers were measured on (the 642-vertex sphere,
//! the 11381-vertex camel head) and on generated icospheres (always available).
//!
//! Groups: `geodesic_setup/<mesh>` ([`HeatGeodesics::new`], default options),
//! `geodesic_query/<mesh>` (one source, [`HeatGeodesics::distance_into`]), and
//! `geodesic_query_plain/<mesh>` (without the intrinsic Delaunay triangulation),
//! `geodesic_setup_refined/<mesh>` and `geodesic_query_refined/<mesh>` (with intrinsic
//! Delaunay refinement to 30°),
//! `geodesic_exact/<mesh>` (exact distances, [`ExactGeodesics::distance_into`]). Without
//! `../shared/data` the shared meshes are skipped with a message. See BENCHMARKS.md.

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

use bdmorph::generate;
use bdmorph::geodesic::{ExactGeodesics, HeatGeodesics, HeatOptions};
use bdmorph::SurfaceMesh;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

fn meshes() -> Vec<(String, SurfaceMesh)> {
    let mut out = vec![
        ("icosphere4".to_string(), generate::icosphere(4)),
        ("icosphere6".to_string(), generate::icosphere(6)),
    ];
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data"));
    if !dir.is_dir() {
        eprintln!(
            "SKIPPED: {} not found; the shared meshes (sphere, camel head) are not benchmarked",
            dir.display()
        );
        return out;
    }
    for (name, rel) in [
        ("sphere642", "closed3d/odedstein/sphere.obj"),
        ("camelhead", "disk3d/libigl/camelhead.off"),
    ] {
        match bdmorph::io::read_mesh(dir.join(rel)) {
            Ok(mesh) => out.push((name.to_string(), mesh)),
            Err(e) => eprintln!("SKIPPED: {rel}: {e}"),
        }
    }
    out
}

/// Intrinsic Delaunay refinement to 30° (at most twice the vertices inserted).
fn refined() -> HeatOptions {
    HeatOptions::default().with_refinement(30.0, 2.0)
}

fn benches(c: &mut Criterion) {
    let meshes = meshes();
    for (group_name, options) in [
        ("geodesic_setup", HeatOptions::default()),
        ("geodesic_setup_refined", refined()),
    ] {
        let mut group = c.benchmark_group(group_name);
        group
            .sample_size(20)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(4));
        for (name, mesh) in &meshes {
            group.bench_function(BenchmarkId::from_parameter(name), |b| {
                b.iter(|| HeatGeodesics::new(black_box(mesh), options).expect("set up"));
            });
        }
        group.finish();
    }
    for (group_name, options) in [
        ("geodesic_query", HeatOptions::default()),
        (
            "geodesic_query_plain",
            HeatOptions::default().with_intrinsic_delaunay(false),
        ),
        ("geodesic_query_refined", refined()),
    ] {
        let mut group = c.benchmark_group(group_name);
        group
            .sample_size(50)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(3));
        for (name, mesh) in &meshes {
            let mut heat = HeatGeodesics::new(mesh, options).expect("set up");
            let mut out = vec![0.0; mesh.positions.len()];
            eprintln!("[bdmorph {name}] {:?}", heat.stats());
            group.bench_function(BenchmarkId::from_parameter(name), |b| {
                b.iter(|| {
                    heat.distance_into(black_box(&[0]), &mut out)
                        .expect("query")
                });
            });
        }
        group.finish();
    }
    // Exact distances (window propagation) from one source: a query is the whole work (the
    // set-up is a pass over the faces); against the heat query above, in the same run.
    let mut group = c.benchmark_group("geodesic_exact");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for (name, mesh) in &meshes {
        let mut exact = ExactGeodesics::new(mesh).expect("set up");
        let mut out = vec![0.0; mesh.positions.len()];
        exact.distance_into(&[0], &mut out).expect("query");
        eprintln!("[bdmorph {name}] exact: {:?}", exact.stats());
        group.bench_function(BenchmarkId::from_parameter(name), |b| {
            b.iter(|| {
                exact
                    .distance_into(black_box(&[0]), &mut out)
                    .expect("query")
            });
        });
    }
    group.finish();
}

criterion_group!(geodesic, benches);
criterion_main!(geodesic);
