//! In-betweens of drawing pairs made in code, compared on the same compatible meshes:
//! BDMORPH, straight-line interpolation and as-rigid-as-possible interpolation (Alexa 2000).
//! Prints Markdown tables: the largest conformal distortion from A along t (50 frames), the
//! most flipped triangles in a frame, the largest change of the total area against the
//! straight blend of the two areas; the median time per frame of each method; then the time
//! to build the compatible mesh.
//!
//! cargo run --release --example inbetween_compare [-- --sizes 1000,10000,50000]

use std::time::Instant;

use bdmorph::distortion::RestShape;
use bdmorph::generate;
use bdmorph::inbetween::{
    compatible_mesh, linear_frame, ArapInterpolation, CompatibleMesh, Inbetween, InbetweenOptions,
};
use bdmorph::render::Image;

fn ring(size: u32, c: [f64; 2], r: f64, hc: [f64; 2], hr: f64) -> Image {
    generate::picture(size, size, move |x, y| {
        let outer = generate::capsule_distance([x, y], c, c, r);
        let hole = generate::capsule_distance([x, y], hc, hc, hr);
        outer.max(-hole)
    })
}

/// A worm: capsules along a curve bent by `bend` radians in all (0: straight).
fn worm(size: u32, bend: f64) -> Image {
    let s = f64::from(size);
    let n = 24;
    let length = 0.7 * s;
    let mut points = Vec::with_capacity(n + 1);
    let (mut p, mut heading) = ([0.15 * s, 0.5 * s], 0.0f64);
    points.push(p);
    for _ in 0..n {
        heading += bend / n as f64;
        p = [
            p[0] + length / n as f64 * heading.cos(),
            p[1] - length / n as f64 * heading.sin(),
        ];
        points.push(p);
    }
    generate::picture(size, size, move |x, y| {
        points
            .windows(2)
            .map(|w| generate::capsule_distance([x, y], w[0], w[1], 0.06 * s))
            .fold(f64::INFINITY, f64::min)
    })
}

fn area(p: &[[f64; 2]], faces: &[[u32; 3]]) -> f64 {
    faces
        .iter()
        .map(|f| {
            let (a, b, c) = (p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]);
            0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
        })
        .sum()
}

struct Measure {
    distortion: f64,
    /// At t = 0.5.
    middle: f64,
    flipped: usize,
    area_change: f64,
}

fn measure(c: &CompatibleMesh, frames: &[(f64, Vec<[f64; 2]>)]) -> Measure {
    let faces = &c.mesh.faces;
    let rest = RestShape::new(&c.mesh.positions, faces);
    let (area_a, area_b) = (area(&c.mesh.positions, faces), area(&c.positions_b, faces));
    let mut out = vec![0.0; faces.len()];
    let mut m = Measure {
        distortion: 1.0,
        middle: 1.0,
        flipped: 0,
        area_change: 0.0,
    };
    for (t, p) in frames {
        let flipped = faces
            .iter()
            .filter(|f| {
                let (a, b, cc) = (p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]);
                (b[0] - a[0]) * (cc[1] - a[1]) - (b[1] - a[1]) * (cc[0] - a[0]) <= 0.0
            })
            .count();
        m.flipped = m.flipped.max(flipped);
        if flipped == 0 {
            m.distortion = m.distortion.max(rest.distortion_into(p, &mut out));
        } else {
            m.distortion = f64::INFINITY;
        }
        if *t == 0.5 {
            m.middle = if flipped == 0 {
                rest.distortion_into(p, &mut out)
            } else {
                f64::INFINITY
            };
        }
        let expected = (1.0 - t) * area_a + t * area_b;
        m.area_change = m.area_change.max((area(p, faces) / expected - 1.0).abs());
    }
    m
}

fn show(m: &Measure) -> String {
    let d = |x: f64| {
        if x.is_finite() {
            format!("{x:.2}")
        } else {
            "∞ (flips)".into()
        }
    };
    format!(
        "{} | {} | {} | {:.1}%",
        d(m.middle),
        d(m.distortion),
        m.flipped,
        100.0 * m.area_change
    )
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let sizes: Vec<usize> = args
        .iter()
        .position(|a| a == "--sizes")
        .and_then(|i| args.get(i + 1))
        .map_or(vec![1000, 10_000, 50_000], |s| {
            s.split(',').map(|v| v.parse().unwrap()).collect()
        });
    let pairs: Vec<(&str, Image, Image)> = vec![
        (
            "figure: arm raised 115°, body bent 11°",
            generate::figure_picture(512, 0.0, 0.0),
            generate::figure_picture(512, 2.0, 0.2),
        ),
        (
            "figure: arm raised 70°, body bent 6°",
            generate::figure_picture(512, 0.0, 0.0),
            generate::figure_picture(512, 1.2, 0.1),
        ),
        (
            "worm: straight to curled 180°",
            worm(512, 0.0),
            worm(512, std::f64::consts::PI),
        ),
        (
            "ring: hole moved and shrunk",
            ring(400, [200.0, 200.0], 140.0, [200.0, 200.0], 50.0),
            ring(400, [215.0, 190.0], 130.0, [170.0, 215.0], 40.0),
        ),
    ];
    println!("| pair | method | distortion at t = 0.5 | largest distortion | most flipped | largest area change |");
    println!("|---|---|---:|---:|---:|---:|");
    let mut ts: Vec<f64> = (0..50).map(|k| k as f64 / 49.0).collect();
    ts.push(0.5);
    let mut per_frame = Vec::new();
    for (name, a, b) in &pairs {
        let options = InbetweenOptions::default().with_vertices(2000);
        let mut ib = match Inbetween::new(a, b, &[], &options) {
            Ok(ib) => ib,
            Err(e) => {
                println!("| {name} | (no compatible mesh: {e}) | | | | |");
                continue;
            }
        };
        let c = ib.compatible().clone();
        // Each frame timed on its own; the median per method.
        let timed = |f: &mut dyn FnMut(f64) -> Vec<[f64; 2]>| {
            let mut seconds = Vec::with_capacity(ts.len());
            let frames: Vec<(f64, Vec<[f64; 2]>)> = ts
                .iter()
                .map(|&t| {
                    let start = Instant::now();
                    let p = f(t);
                    seconds.push(start.elapsed().as_secs_f64());
                    (t, p)
                })
                .collect();
            seconds.sort_by(f64::total_cmp);
            (frames, seconds[seconds.len() / 2])
        };
        let (bd, bd_s) = timed(&mut |t| ib.frame(t).unwrap().positions.to_vec());
        let (lin, lin_s) = timed(&mut |t| linear_frame(&c.mesh.positions, &c.positions_b, t));
        let mut arap = ArapInterpolation::new(&c.mesh, &c.positions_b).unwrap();
        let (ar, ar_s) = timed(&mut |t| arap.frame(t).unwrap());
        per_frame.push(format!(
            "| {name} | {:.3} | {:.3} | {:.4} |",
            1e3 * bd_s,
            1e3 * ar_s,
            1e3 * lin_s
        ));
        println!(
            "| {name} ({} vertices; B's layout {:.2}) | BDMORPH | {} |",
            c.report.vertices,
            c.report.max_distortion,
            show(&measure(&c, &bd))
        );
        println!("| | straight lines | {} |", show(&measure(&c, &lin)));
        println!("| | ARAP (Alexa 2000) | {} |", show(&measure(&c, &ar)));
    }
    println!();
    println!("| pair | BDMORPH (ms per frame) | ARAP | straight lines |");
    println!("|---|---:|---:|---:|");
    for line in &per_frame {
        println!("{line}");
    }
    println!();
    println!(
        "| vertices asked | vertices | triangles | build median (s) | runs | largest distortion |"
    );
    println!("|---:|---:|---:|---:|---:|---:|");
    let (a, b) = (
        generate::figure_picture(1024, 0.0, 0.0),
        generate::figure_picture(1024, 2.0, 0.2),
    );
    for &n in &sizes {
        let runs = if n >= 20_000 { 3 } else { 5 };
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..runs {
            let start = Instant::now();
            let c = compatible_mesh(&a, &b, &[], &InbetweenOptions::default().with_vertices(n));
            times.push(start.elapsed().as_secs_f64());
            last = Some(c);
        }
        times.sort_by(f64::total_cmp);
        match last.unwrap() {
            Ok(c) => println!(
                "| {n} | {} | {} | {:.3} | {runs} | {:.2} |",
                c.report.vertices,
                c.report.faces,
                times[runs / 2],
                c.report.max_distortion
            ),
            Err(e) => println!("| {n} | failed: {e} | | | | |"),
        }
    }
}
