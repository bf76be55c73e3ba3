//! Posing by handles (`bdmorph::deform`): one drag (ARAP, 10 local/global iterations from the
//! previous pose) and a re-pin (numbering and factoring the free vertices' Laplacian), on
//! generated disks of about 1K, 5K and 20K vertices, four handles.
//!
//! `cargo bench --bench deform`

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

use bdmorph::deform::{Deformer, Method};
use bdmorph::{generate, PlanarMesh};

fn handles(mesh: &PlanarMesh) -> Vec<u32> {
    let n = mesh.positions.len() as u32;
    vec![0, n - 1, n - 1 - n / 10, n - 1 - n / 5]
}

fn bench(c: &mut Criterion) {
    let meshes: Vec<PlanarMesh> = [1000, 5000, 20000]
        .iter()
        .map(|&n| generate::disk(generate::rings_for(n), 0.2))
        .collect();
    let mut drag = c.benchmark_group("deform_drag/arap");
    for mesh in &meshes {
        let pins = handles(mesh);
        let mut pose = Deformer::new(mesh, Method::arap()).expect("set up");
        pose.set_pins(&pins).expect("pins");
        let mut targets: Vec<[f64; 2]> = pins.iter().map(|&v| mesh.positions[v as usize]).collect();
        let mut step = 0u32;
        drag.bench_function(BenchmarkId::from_parameter(mesh.positions.len()), |b| {
            b.iter(|| {
                // A mouse moving back and forth: a new target every drag.
                step += 1;
                let s = f64::from(step % 40) / 40.0;
                targets[1] = [
                    mesh.positions[pins[1] as usize][0] + 0.3 * s,
                    mesh.positions[pins[1] as usize][1] + 0.2 * s,
                ];
                pose.drag(&targets).expect("drag")
            })
        });
    }
    drag.finish();
    let mut repin = c.benchmark_group("deform_set_pins/arap");
    for mesh in &meshes {
        let pins = handles(mesh);
        let mut pose = Deformer::new(mesh, Method::arap()).expect("set up");
        repin.bench_function(BenchmarkId::from_parameter(mesh.positions.len()), |b| {
            b.iter(|| pose.set_pins(&pins).expect("pins"))
        });
    }
    repin.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
