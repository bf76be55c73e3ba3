//! Benchmarks of the compile-once, run-many pipeline over generated disks of about 1K, 10K
//! and 100K vertices (source `disk(rings_for(n), 0.25)`, target `twist(bend(source, 0.6),
//! 1.2)`).
//!
//! Groups (the parameter is the nominal vertex count), by phase:
//!
//! - `compile`: [`bdmorph::compile`] alone;
//! - `symbolic`: [`Vm::new`] on a compiled program (buffers and the symbolic Cholesky
//!   factorisation; the program's clone is included);
//! - `setup`: [`Morph::new`] (checks, compile, symbolic Cholesky, keyframe lengths);
//! - `iteration_stream`: one pass of the iteration stream as Newton runs it (`vm`,
//!   [`Vm::evaluate_gradient`]), the pass with the energy the line search sometimes needs
//!   (`vm_energy`, [`Vm::evaluate`]), and the direct uncompiled implementation of the same
//!   gradient and Hessian walking an adjacency structure (`direct`,
//!   [`reference::gradient_and_hessian`]), all on the same state: `t = 0.5` and the `u` that
//!   flattens it;
//! - `factorization`: the numeric Cholesky factorisation ([`Vm::factorize`]) on that state,
//!   with the factor stored in double (`f64`) and in single precision (`f32`);
//!   `factorization_faer`, its baseline: the same factorisation by faer's general
//!   supernodal routine ([`Vm::factorize_with_faer`]);
//! - `solve`: one solve with that factor ([`Vm::solve`]), the unit of work of a conjugate-
//!   gradient iteration, in both precisions; `solve_faer`, its baseline: the same solve by
//!   faer's general supernodal routine ([`Vm::solve_with_faer`]);
//! - `tangent`: the solution's derivative along the morph ([`Vm::tangent`]: the closed-form
//!   derivative of the gradient and conjugate gradients with the factor of that state), which
//!   a warm frame computes for the next one's predicted start when tangents are on;
//! - `embed`: the layout ([`Vm::embed`]);
//! - `distortion`: every triangle's conformal distortion from the source
//!   ([`RestShape::distortion_into`]), which every frame computes for its statistics;
//! - `warm_frame`: one frame of a sweep `t = 0, 0.1, ..., 1, 0.9, ..., 0` repeated, each frame
//!   warm-started from the previous ones ([`Morph::frame_into`], default options: starts
//!   predicted from the last solutions, reused factors; the sweep back down revisits places
//!   still remembered, which start from their solutions and cost a pass each, see
//!   BENCHMARKS.md); `warm_frame_one_way`, the frames of one-way sweeps that revisit nothing:
//!   each sweep forgets the solutions ([`Morph::forget_solutions`]) and solves `t = 0`
//!   untimed, then `t = 0.1, ..., 1` are timed; `warm_frame_plain`
//!   the same with the levers off (a factorisation per Newton step, start = previous
//!   solution), the ratio being what they buy; `warm_frame_f64` and `warm_frame_f32` the
//!   default with the factor's precision forced (the default picks single precision from
//!   [`bdmorph::SINGLE_FROM_VALUES`] stored values);
//! - `cold_frame`: the frame `t = 0.5` from `u = 0` with a factorisation per step;
//! - `frame_threads/<threads>/<n>`: `warm_frame_one_way` with the morph set up and run in a
//!   pool of 1, 2 (and 4 where the machine has them) threads. Every other group runs on one
//!   thread.
//!
//! Every case is built on first use, so a filter (`cargo bench --bench frame -- warm_frame`)
//! only pays for what it runs. Program sizes and the Newton iterations of a warm frame are
//! printed to stderr once per size. `cargo bench --bench frame -- --test` runs each benchmark
//! once. See BENCHMARKS.md for results.

use std::cell::OnceCell;
use std::hint::black_box;
use std::time::{Duration, Instant};

use bdmorph::distortion::RestShape;
use bdmorph::reference::{self, Unknowns};
use bdmorph::{
    generate, FactorPrecision, FrameStats, Morph, MorphOptions, NewtonOptions, PlanarMesh, Vm,
};
use criterion::measurement::WallTime;
use criterion::{
    criterion_group, criterion_main, BenchmarkGroup, BenchmarkId, Criterion, SamplingMode,
};

/// Nominal vertex counts.
const SIZES: [usize; 3] = [1_000, 10_000, 100_000];

/// The source and target meshes of one size.
struct Meshes {
    source: PlanarMesh,
    target: PlanarMesh,
}

impl Meshes {
    fn new(n: usize) -> Meshes {
        let source = generate::disk(generate::rings_for(n), 0.25);
        let target = generate::twist(&generate::bend(&source, 0.6), 1.2);
        Meshes { source, target }
    }
}

/// A VM evaluated at `t = 0.5` and the `u` that flattens that metric, with the same state
/// prepared for the direct implementation.
struct Evaluated {
    vm: Vm,
    u_by_vertex: Vec<f64>,
    unknowns: Unknowns,
}

impl Evaluated {
    fn new(n: usize, m: &Meshes) -> Evaluated {
        let program = bdmorph::compile(&m.source.positions, &m.source.faces).expect("compiles");
        let mut vm = Vm::new(program).expect("vm");
        let a = vm.squared_lengths(&m.source.positions).expect("lengths");
        let b = vm.squared_lengths(&m.target.positions).expect("lengths");
        vm.set_metric_lerp(&a, &b, 0.5).expect("metric");
        let report = vm.newton(&NewtonOptions::default()).expect("converges");
        let max_u = vm.u().iter().fold(0.0f64, |m, u| m.max(u.abs()));
        assert!(max_u > 1e-3, "the benchmarked u is not trivial");
        vm.evaluate();
        let mut u_by_vertex = vec![0.0; m.source.positions.len()];
        for (k, &v) in vm.program().unknown_vertex().iter().enumerate() {
            u_by_vertex[v as usize] = vm.u()[k];
        }
        let unknowns = Unknowns::new(&m.source);
        // Both sides of `iteration_stream` compute the same gradient.
        let (g, _) =
            reference::gradient_and_hessian(&m.source, &m.target, 0.5, &u_by_vertex, &unknowns);
        for (k, &v) in vm.program().unknown_vertex().iter().enumerate() {
            let r = g[unknowns.of_vertex[v as usize].expect("interior")];
            assert!(
                (vm.gradient()[k] - r).abs() < 1e-9,
                "gradient mismatch at {v}"
            );
        }
        eprintln!(
            "[bdmorph n={n}] cold Newton solve at t=0.5: {} iterations, |g| = {:.1e}, \
             max |u| = {max_u:.3}; hessian nnz {}, cholesky factor nnz {}",
            report.iterations,
            report.gradient_norm,
            vm.program().hessian().nnz(),
            vm.factor_nnz(),
        );
        Evaluated {
            vm,
            u_by_vertex,
            unknowns,
        }
    }
}

/// Everything built for one size, each part on first use.
struct Case {
    n: usize,
    meshes: OnceCell<Meshes>,
    evaluated: Option<Evaluated>,
}

impl Case {
    fn meshes(&self) -> &Meshes {
        self.meshes.get_or_init(|| {
            let m = Meshes::new(self.n);
            let stats = bdmorph::compile(&m.source.positions, &m.source.faces)
                .expect("compiles")
                .stats();
            eprintln!(
                "[bdmorph n={}] {} vertices, {} faces, {} unknowns, {} edges; iteration stream \
                 {} bytes ({:.1} bytes/face), whole program {} bytes in memory ({:.1} bytes/face), \
                 {} bytes as a file ({:.1} bytes/face)",
                self.n,
                stats.vertices,
                stats.faces,
                stats.unknowns,
                stats.edges,
                stats.iteration_bytes,
                stats.iteration_bytes_per_face,
                stats.total_bytes,
                stats.total_bytes as f64 / stats.faces as f64,
                stats.file_bytes,
                stats.file_bytes as f64 / stats.faces as f64,
            );
            m
        })
    }

    fn evaluated(&mut self) -> &mut Evaluated {
        self.both().1
    }

    fn both(&mut self) -> (&Meshes, &mut Evaluated) {
        if self.evaluated.is_none() {
            let e = Evaluated::new(self.n, self.meshes());
            self.evaluated = Some(e);
        }
        (
            self.meshes.get().expect("built with the evaluation"),
            self.evaluated.as_mut().expect("just built"),
        )
    }
}

/// Applies the measurement settings of a size: the 100K cases take few, long samples.
fn configure(group: &mut BenchmarkGroup<'_, WallTime>, n: usize) {
    if n >= 100_000 {
        group
            .sample_size(10)
            .sampling_mode(SamplingMode::Flat)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(4));
    } else {
        group
            .sample_size(50)
            .sampling_mode(SamplingMode::Auto)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(3));
    }
}

fn bench_compile(c: &mut Criterion, cases: &mut [Case]) {
    let mut group = c.benchmark_group("compile");
    for case in cases.iter() {
        configure(&mut group, case.n);
        group.bench_function(BenchmarkId::from_parameter(case.n), |b| {
            let m = case.meshes();
            b.iter(|| bdmorph::compile(&m.source.positions, &m.source.faces).expect("compiles"));
        });
    }
    group.finish();

    let mut group = c.benchmark_group("setup");
    for case in cases.iter() {
        configure(&mut group, case.n);
        group.bench_function(BenchmarkId::from_parameter(case.n), |b| {
            let m = case.meshes();
            b.iter(|| Morph::new(&m.source, &m.target, MorphOptions::default()).expect("morph"));
        });
    }
    group.finish();
}

fn bench_iteration_stream(c: &mut Criterion, cases: &mut [Case]) {
    let mut group = c.benchmark_group("iteration_stream");
    for case in cases.iter_mut() {
        configure(&mut group, case.n);
        let id = BenchmarkId::new("vm", case.n);
        group.bench_function(id, |b| {
            let e = case.evaluated();
            b.iter(|| {
                e.vm.evaluate_gradient();
                black_box(e.vm.hessian_values());
            });
        });
        let id = BenchmarkId::new("vm_energy", case.n);
        group.bench_function(id, |b| {
            let e = case.evaluated();
            b.iter(|| {
                e.vm.evaluate();
                black_box(e.vm.energy());
            });
        });
        let id = BenchmarkId::new("direct", case.n);
        group.bench_function(id, |b| {
            let (m, e) = case.both();
            b.iter(|| {
                reference::gradient_and_hessian(
                    &m.source,
                    &m.target,
                    black_box(0.5),
                    &e.u_by_vertex,
                    &e.unknowns,
                )
            });
        });
    }
    group.finish();
}

/// Both storage precisions of the factor.
const PRECISIONS: [(&str, FactorPrecision); 2] = [
    ("f64", FactorPrecision::Double),
    ("f32", FactorPrecision::Single),
];

/// A group with one benchmark per size and factor precision (`f64/N`, `f32/N`), each on the
/// evaluated state with the precision set; the VM is set back to the automatic choice.
fn bench_per_precision(
    c: &mut Criterion,
    cases: &mut [Case],
    name: &str,
    mut run: impl FnMut(&mut criterion::Bencher<'_>, &mut Vm),
) {
    let mut group = c.benchmark_group(name);
    for case in cases.iter_mut() {
        configure(&mut group, case.n);
        for (label, precision) in PRECISIONS {
            group.bench_function(BenchmarkId::new(label, case.n), |b| {
                let e = case.evaluated();
                e.vm.set_factor_precision(precision);
                run(b, &mut e.vm);
            });
        }
        if let Some(e) = case.evaluated.as_mut() {
            e.vm.set_factor_precision(FactorPrecision::Auto);
        }
    }
    group.finish();
}

fn bench_factorization(c: &mut Criterion, cases: &mut [Case]) {
    bench_per_precision(c, cases, "factorization", |b, vm| {
        b.iter(|| vm.factorize().expect("positive definite"));
    });
    // The baseline of `factorization`: faer's general supernodal factorisation.
    bench_per_precision(c, cases, "factorization_faer", |b, vm| {
        b.iter(|| vm.factorize_with_faer().expect("positive definite"));
    });
    bench_per_precision(c, cases, "solve", |b, vm| {
        vm.factorize().expect("positive definite");
        b.iter(|| {
            black_box(vm.solve().expect("factored"));
        });
    });
    // The baseline of `solve`: the same solve by faer's general supernodal routine.
    bench_per_precision(c, cases, "solve_faer", |b, vm| {
        vm.factorize().expect("positive definite");
        b.iter(|| {
            black_box(vm.solve_with_faer().expect("factored"));
        });
    });

    let mut group = c.benchmark_group("tangent");
    for case in cases.iter_mut() {
        configure(&mut group, case.n);
        group.bench_function(BenchmarkId::from_parameter(case.n), |b| {
            let (m, e) = case.both();
            let a = e.vm.squared_lengths(&m.source.positions).expect("lengths");
            let target = e.vm.squared_lengths(&m.target.positions).expect("lengths");
            let rate: Vec<f64> = a.iter().zip(&target).map(|(a, b)| b - a).collect();
            e.vm.factorize().expect("positive definite");
            b.iter(|| black_box(e.vm.tangent(&rate).expect("evaluated")));
        });
    }
    group.finish();

    let mut group = c.benchmark_group("embed");
    for case in cases.iter_mut() {
        configure(&mut group, case.n);
        group.bench_function(BenchmarkId::from_parameter(case.n), |b| {
            let e = case.evaluated();
            let mut out = vec![[0.0; 2]; e.vm.program().n_vertices()];
            b.iter(|| {
                e.vm.embed([0.1, 0.2], [1.0, 0.5], &mut out).expect("fits");
                black_box(&out);
            });
        });
    }
    group.finish();
}

/// The per-frame conformal distortion of every triangle (part of every frame since the
/// distortion reports), against the warm frame it is part of.
fn bench_distortion(c: &mut Criterion, cases: &mut [Case]) {
    let mut group = c.benchmark_group("distortion");
    for case in cases.iter() {
        configure(&mut group, case.n);
        group.bench_function(BenchmarkId::from_parameter(case.n), |b| {
            let m = case.meshes();
            let rest = RestShape::new(&m.source.positions, &m.source.faces);
            let mut out = vec![0.0; m.source.faces.len()];
            b.iter(|| rest.distortion_into(black_box(&m.target.positions), &mut out));
        });
    }
    group.finish();
}

/// Times along the sweep 0, 0.1, ..., 1, 0.9, ..., 0.1 (then again from 0).
fn sweep() -> Vec<f64> {
    (0..=10)
        .chain((1..10).rev())
        .map(|i| f64::from(i) / 10.0)
        .collect()
}

/// Frames, Newton iterations, factorisations and CG iterations counted over every call of a
/// warm-frame benchmark.
#[derive(Default)]
struct Counts([u64; 4]);

impl Counts {
    fn add(&mut self, stats: &FrameStats) {
        self.0[0] += 1;
        self.0[1] += u64::from(stats.newton_iterations);
        self.0[2] += u64::from(stats.factorizations);
        self.0[3] += u64::from(stats.cg_iterations);
    }

    /// Prints them per frame to stderr.
    fn report(&self, n: usize, name: &str) {
        let [frames, newton, factorizations, cg] = self.0;
        if frames > 0 {
            let per = |x: u64| x as f64 / frames as f64;
            eprintln!(
                "[bdmorph n={n}] {name}: {frames} frames, per frame {:.2} Newton iterations, \
                 {:.2} factorisations, {:.2} CG iterations",
                per(newton),
                per(factorizations),
                per(cg),
            );
        }
    }
}

fn bench_warm_frame(c: &mut Criterion, cases: &mut [Case]) {
    let configs = [
        ("warm_frame", MorphOptions::default()),
        (
            "warm_frame_plain",
            MorphOptions::default()
                .with_extrapolate(false)
                .with_reuse_factor(false),
        ),
        (
            "warm_frame_f64",
            MorphOptions::default().with_factor_precision(FactorPrecision::Double),
        ),
        (
            "warm_frame_f32",
            MorphOptions::default().with_factor_precision(FactorPrecision::Single),
        ),
    ];
    let ts = sweep();
    for (name, options) in configs {
        let mut group = c.benchmark_group(name);
        for case in cases.iter() {
            configure(&mut group, case.n);
            // The morph, its output buffer, the position in the sweep, and (frames, Newton
            // iterations, factorisations, CG iterations) counted over every call.
            let mut state: Option<(Morph, Vec<[f64; 2]>, usize)> = None;
            let mut counts = Counts::default();
            group.bench_function(BenchmarkId::from_parameter(case.n), |b| {
                let (morph, out, at) = state.get_or_insert_with(|| {
                    let m = case.meshes();
                    let mut morph =
                        Morph::new(&m.source, &m.target, options.clone()).expect("morph");
                    let mut out = vec![[0.0; 2]; m.source.positions.len()];
                    morph.frame_into(0.0, &mut out).expect("frame");
                    (morph, out, 1)
                });
                b.iter(|| {
                    let stats = morph.frame_into(ts[*at], out).expect("frame");
                    *at = (*at + 1) % ts.len();
                    counts.add(&stats);
                    stats
                });
            });
            counts.report(case.n, name);
        }
        group.finish();
    }

    // One-way sweeps: no frame revisits a place, so none is free.
    let name = "warm_frame_one_way";
    let mut group = c.benchmark_group(name);
    for case in cases.iter() {
        configure(&mut group, case.n);
        let mut state: Option<(Morph, Vec<[f64; 2]>, u32)> = None;
        let mut counts = Counts::default();
        group.bench_function(BenchmarkId::from_parameter(case.n), |b| {
            let (morph, out, at) = state.get_or_insert_with(|| {
                let m = case.meshes();
                let morph =
                    Morph::new(&m.source, &m.target, MorphOptions::default()).expect("morph");
                (morph, vec![[0.0; 2]; m.source.positions.len()], 0)
            });
            b.iter_custom(|iters| one_way_frames(morph, out, at, &mut counts, iters));
        });
        counts.report(case.n, name);
    }
    group.finish();

    let mut group = c.benchmark_group("cold_frame");
    for case in cases.iter() {
        configure(&mut group, case.n);
        let mut state: Option<(Morph, Vec<[f64; 2]>)> = None;
        group.bench_function(BenchmarkId::from_parameter(case.n), |b| {
            let (morph, out) = state.get_or_insert_with(|| {
                let m = case.meshes();
                let options = MorphOptions::default()
                    .with_warm_start(false)
                    .with_reuse_factor(false);
                let morph = Morph::new(&m.source, &m.target, options).expect("morph");
                (morph, vec![[0.0; 2]; m.source.positions.len()])
            });
            b.iter(|| morph.frame_into(0.5, out).expect("frame"));
        });
    }
    group.finish();
}

fn bench_symbolic(c: &mut Criterion, cases: &mut [Case]) {
    let mut group = c.benchmark_group("symbolic");
    for case in cases.iter() {
        configure(&mut group, case.n);
        group.bench_function(BenchmarkId::from_parameter(case.n), |b| {
            let m = case.meshes();
            let program = bdmorph::compile(&m.source.positions, &m.source.faces).expect("ok");
            b.iter(|| Vm::new(program.clone()).expect("vm"));
        });
    }
    group.finish();
}

/// The time of `iters` frames of one-way sweeps `t = 0.1, ..., 1`: at each sweep's start the
/// solutions are forgotten and `t = 0` is solved untimed; `at` is the next frame's tenth.
fn one_way_frames(
    morph: &mut Morph,
    out: &mut [[f64; 2]],
    at: &mut u32,
    counts: &mut Counts,
    iters: u64,
) -> Duration {
    let mut timed = Duration::ZERO;
    for _ in 0..iters {
        if *at == 0 {
            morph.forget_solutions();
            morph.frame_into(0.0, out).expect("frame");
            *at = 1;
        }
        let started = Instant::now();
        let stats = morph.frame_into(f64::from(*at) / 10.0, out).expect("frame");
        timed += started.elapsed();
        *at = (*at + 1) % 11;
        counts.add(black_box(&stats));
    }
    timed
}

/// One frame of one-way sweeps (as `warm_frame_one_way`) with the morph set up and run in a
/// pool of 1, 2 (and 4, where the machine has them) threads: the factorisation split over
/// independent subtrees where that pays.
fn bench_frame_threads(c: &mut Criterion, cases: &mut [Case]) {
    let name = "frame_threads";
    let mut group = c.benchmark_group(name);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    for case in cases.iter() {
        configure(&mut group, case.n);
        for threads in [1, 2, 4] {
            if threads > cores.max(2) {
                continue;
            }
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            let mut state: Option<(Morph, Vec<[f64; 2]>, u32)> = None;
            let mut counts = Counts::default();
            let id = BenchmarkId::new(threads.to_string(), case.n);
            group.bench_function(id, |b| {
                let (morph, out, at) = state.get_or_insert_with(|| {
                    let m = case.meshes();
                    let morph = pool
                        .install(|| Morph::new(&m.source, &m.target, MorphOptions::default()))
                        .expect("morph");
                    (morph, vec![[0.0; 2]; m.source.positions.len()], 0)
                });
                b.iter_custom(|iters| {
                    pool.install(|| one_way_frames(morph, out, at, &mut counts, iters))
                });
            });
            counts.report(case.n, &format!("{name}/{threads}"));
        }
    }
    group.finish();
}

fn benches(c: &mut Criterion) {
    // Every group but `frame_threads` runs on one thread, as the C++ reference does.
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()
        .expect("the global pool is set once, first");
    let mut cases: Vec<Case> = SIZES
        .iter()
        .map(|&n| Case {
            n,
            meshes: OnceCell::new(),
            evaluated: None,
        })
        .collect();
    bench_compile(c, &mut cases);
    bench_symbolic(c, &mut cases);
    bench_iteration_stream(c, &mut cases);
    bench_factorization(c, &mut cases);
    bench_distortion(c, &mut cases);
    bench_warm_frame(c, &mut cases);
    bench_frame_threads(c, &mut cases);
}

criterion_group!(frame, benches);
criterion_main!(frame);
