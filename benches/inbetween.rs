//! In-betweens of two drawings made in code ([`generate::figure_picture`]: a figure, and the
//! same figure with an arm raised 115° and the body bent 11°), 1024 x 1024 pixels.
//!
//! Groups: `inbetween_compatible_mesh/<N>` (the whole [`compatible_mesh`] at about N
//! vertices: outlines, correspondence, meshing, the layout over B, untangling, polishing)
//! `inbetween_fit_drawing/<N>` (the studio's "Drawing…": an existing mesh of A, made by
//! [`bdmorph::meshing::mesh_picture`], laid over B by [`fit_drawing`], to compare with the
//! compatible mesh's build at the same size; and `correspondence`, the preview of where its
//! outline goes), and `inbetween_frame/<method>` (one in-between at about 2K vertices, t alternating
//! between 0.3 and 0.7 so that no frame is a repeat: BDMORPH against the as-rigid-as-possible
//! interpolation and straight lines on the same compatible mesh), and
//! `inbetween_robust/<N>` (the whole [`compatible_mesh`] of two walk-cycle drawings whose
//! layout needs the guarantee, robot walk2 to walk4 from the shared data scaled up 4 times:
//! A's mesh refined where it has no flip-free layout, a hole of one drawing only as a
//! transparent region; skipped without the shared data). See BENCHMARKS.md.

use std::hint::black_box;
use std::time::Duration;

use bdmorph::generate;
use bdmorph::inbetween::{
    compatible_mesh, fit_drawing, linear_frame, outline_correspondence, ArapInterpolation,
    Inbetween, InbetweenOptions,
};
use bdmorph::meshing::{mesh_picture, MeshOptions, PictureOptions};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

fn benches(c: &mut Criterion) {
    let a = generate::figure_picture(1024, 0.0, 0.0);
    let b = generate::figure_picture(1024, 2.0, 0.2);
    let mut group = c.benchmark_group("inbetween_compatible_mesh");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for n in [1_000usize, 10_000] {
        let options = InbetweenOptions::default().with_vertices(n);
        let made = compatible_mesh(&a, &b, &[], &options).expect("compatible");
        eprintln!("[bdmorph inbetween {n}] {:?}", made.report);
        group.bench_function(BenchmarkId::from_parameter(n), |bench| {
            bench.iter(|| compatible_mesh(black_box(&a), &b, &[], &options).expect("compatible"));
        });
    }
    group.finish();

    let walk = std::path::PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/data/animation2d/kenney-characters/robot"
    ));
    let read = |i: usize| {
        bdmorph::render::raster::read_image(walk.join(format!("robot_walk{i}.png")))
            .ok()
            .map(|image| scale(&image, 4))
    };
    if let (Some(wa), Some(wb)) = (read(2), read(4)) {
        let mut group = c.benchmark_group("inbetween_robust");
        group
            .sample_size(10)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(5));
        for n in [1_000usize, 10_000] {
            let options = InbetweenOptions::default().with_vertices(n);
            let made = compatible_mesh(&wa, &wb, &[], &options).expect("compatible");
            eprintln!("[bdmorph inbetween robust {n}] {:?}", made.report);
            group.bench_function(BenchmarkId::from_parameter(n), |bench| {
                bench.iter(|| {
                    compatible_mesh(black_box(&wa), &wb, &[], &options).expect("compatible")
                });
            });
        }
        group.finish();
    } else {
        eprintln!("SKIPPED inbetween_robust: {} not found", walk.display());
    }

    let mut group = c.benchmark_group("inbetween_fit_drawing");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for n in [1_000usize, 10_000] {
        let meshed = mesh_picture(
            &a,
            &PictureOptions::default(),
            &MeshOptions::default().with_vertices(n),
        )
        .expect("meshed");
        let mut mesh = meshed.mesh;
        for (p, t) in mesh.positions.iter_mut().zip(&meshed.texcoords.uv) {
            *p = [t[0] * 1024.0, t[1] * 1024.0];
        }
        let options = InbetweenOptions::default();
        let fit = fit_drawing(&mesh, 1024.0, &b, &[], &options).expect("fit");
        eprintln!(
            "[bdmorph fit_drawing {}] {:?}",
            mesh.positions.len(),
            fit.report
        );
        group.bench_function(BenchmarkId::from_parameter(n), |bench| {
            bench.iter(|| fit_drawing(&mesh, 1024.0, black_box(&b), &[], &options).expect("fit"));
        });
        if n == 1_000 {
            group.bench_function("correspondence", |bench| {
                bench.iter(|| {
                    outline_correspondence(&mesh, 1024.0, black_box(&b), &[], &options, 24)
                        .expect("correspondence")
                });
            });
        }
    }
    group.finish();

    let options = InbetweenOptions::default().with_vertices(2_000);
    let mut inbetween = Inbetween::new(&a, &b, &[], &options).expect("compatible");
    let made = inbetween.compatible().clone();
    let mut arap = ArapInterpolation::new(&made.mesh, &made.positions_b).expect("arap");
    let mut group = c.benchmark_group("inbetween_frame");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    let mut flip = false;
    let mut next_t = move || {
        flip = !flip;
        if flip {
            0.3
        } else {
            0.7
        }
    };
    group.bench_function("bdmorph", |bench| {
        bench.iter(|| {
            let t = next_t();
            inbetween
                .frame(black_box(t))
                .expect("frame")
                .stats
                .flipped_triangles
        });
    });
    group.bench_function("arap", |bench| {
        bench.iter(|| arap.frame(black_box(next_t())).expect("frame"));
    });
    group.bench_function("linear", |bench| {
        bench.iter(|| linear_frame(&made.mesh.positions, &made.positions_b, black_box(next_t())));
    });
    group.finish();
}

/// `image` scaled up `k` times by nearest neighbour.
fn scale(image: &bdmorph::render::Image, k: u32) -> bdmorph::render::Image {
    let (w, h) = (image.width * k, image.height * k);
    let mut rgba = vec![0u8; 4 * w as usize * h as usize];
    for y in 0..h {
        for x in 0..w {
            let s = 4 * ((y / k) * image.width + x / k) as usize;
            let d = 4 * (y * w + x) as usize;
            rgba[d..d + 4].copy_from_slice(&image.rgba[s..s + 4]);
        }
    }
    bdmorph::render::Image {
        width: w,
        height: h,
        rgba,
    }
}

criterion_group!(inbetween, benches);
criterion_main!(inbetween);
