//! Frames of meshes with a hole, and the placement of frames, as ratios against a baseline in
//! the same run, at about 1K and 10K vertices.
//!
//! - `free_hole/filled/<n>` and `free_hole/free/<n>`: warm frames (a sweep of 40 frames from
//!   the rest pose to the keyframe and back, each warm-started from the previous ones) of
//!   [`generate::hand_on_hip`] to [`generate::arm_across`]: by 0.4 (the hole stays open, and is
//!   filled with hidden triangles) and by 1.2 (the arm lies over the body, the hole's outline
//!   crosses itself: a free hole, closed at every frame). The same mesh, a shear of the same
//!   region: the ratio is what closing a free hole costs.
//! - `placement/anchor/<n>` and `placement/fit/<n>`: the same sweep of the benchmark disk
//!   (`disk(rings_for(n), 0.25)` to `twist(bend(source, 0.6), 1.2)`, as `benches/frame.rs`)
//!   placed by the anchor and by the fit to the keyframes.
//!
//! `cargo bench --bench holes`; `-- --test` runs each once. See BENCHMARKS.md.

use std::hint::black_box;
use std::time::Duration;

use bdmorph::{generate, Morph, MorphOptions, Placement, PlanarMesh};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

/// The sweep: 0 to 1 and back in steps of 0.05.
fn sweep() -> Vec<f64> {
    (0..=20)
        .chain((1..20).rev())
        .map(|i| f64::from(i) / 20.0)
        .collect()
}

/// A warm-started sweep of `a` to `b` with `options`, one frame per iteration.
fn bench_sweep(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    id: BenchmarkId,
    a: &PlanarMesh,
    b: &PlanarMesh,
    options: MorphOptions,
) {
    let mut morph = Morph::new(a, b, options).expect("morph");
    let mut out = vec![[0.0; 2]; a.positions.len()];
    let ts = sweep();
    let mut at = 0;
    group.bench_function(id, |bench| {
        bench.iter(|| {
            let stats = morph.frame_into(ts[at], &mut out).expect("frame");
            at = (at + 1) % ts.len();
            black_box(stats)
        });
    });
}

fn benches(c: &mut Criterion) {
    // Area bounds that give about 1K and 10K vertices.
    for (n, area) in [(1_000, 0.0065), (10_000, 0.0005)] {
        let rest = generate::hand_on_hip(area);
        eprintln!("hand_on_hip: {} vertices for {n}", rest.positions.len());
        let mut group = c.benchmark_group("free_hole");
        group
            .sample_size(20)
            .measurement_time(Duration::from_secs(if n > 5_000 { 8 } else { 4 }));
        for (name, reach) in [("filled", 0.4), ("free", 1.2)] {
            let pose = generate::arm_across(&rest, reach);
            let m = Morph::new(&rest, &pose, MorphOptions::default()).expect("morph");
            let free = m.structure().pieces[0].free_holes.len();
            assert_eq!(free, usize::from(name == "free"), "{name}");
            bench_sweep(
                &mut group,
                BenchmarkId::new(name, n),
                &rest,
                &pose,
                MorphOptions::default(),
            );
        }
        group.finish();
    }
    for n in [1_000, 10_000] {
        let rest = generate::disk(generate::rings_for(n), 0.25);
        let wave = generate::twist(&generate::bend(&rest, 0.6), 1.2);
        let mut group = c.benchmark_group("placement");
        group
            .sample_size(20)
            .measurement_time(Duration::from_secs(if n > 5_000 { 8 } else { 4 }));
        for placement in [Placement::Anchor, Placement::Fit] {
            bench_sweep(
                &mut group,
                BenchmarkId::new(placement.to_string(), n),
                &rest,
                &wave,
                MorphOptions::default().with_placement(placement),
            );
        }
        group.finish();
    }
}

criterion_group!(holes, benches);
criterion_main!(holes);
