//! The engine against faer on mesh matrices: grid Laplacians (one unknown per vertex, as the
//! geodesic and ARAP systems have; two per vertex, as the parameterisation's Newton Hessian
//! has) of about 1K, 10K and 100K unknowns, ordered by AMD.
//!
//! Groups, each with the engine's kernels (`own`) and faer's on the same factor (`faer`):
//!
//! - `factorize/{own,faer}/<size>`: one numeric factorisation, supernodal;
//! - `factorize/simplicial/<size>`: faer's column-by-column factorisation of the same matrix
//!   (`Supernodal::Never`; `Auto` is supernodal);
//! - `solve/{own,faer,simplicial}/<size>`: one solve with one right-hand side;
//! - `solve4/{own,faer}/<size>`: one solve with four right-hand sides;
//! - `factorize_threads/<threads>/<size>`: the engine's factorisation split over 1, 2 (and,
//!   where the machine has them, 4) threads (independent subtrees of the elimination tree).
//! - `solve_threads/<threads>/<size>`: one solve (forward and backward, one right-hand side)
//!   split over the same thread counts.
//!
//! The groups against faer run on one thread (faer's kernels here are sequential).
//!
//! ```sh
//! cargo bench -p bdmorph-cholesky --bench cholesky
//! ```

use bdmorph_cholesky::fixtures;
use bdmorph_cholesky::{Cholesky, CholeskyOptions, LowerPattern, Supernodal};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::hint::black_box;

/// `(name, grid side, unknowns per vertex)`.
const CASES: [(&str, u32, u32); 4] = [
    ("1K", 32, 1),
    ("10K", 100, 1),
    ("10Kx2", 71, 2),
    ("100K", 316, 1),
];

fn setup(side: u32, dofs: u32, supernodal: Supernodal) -> (Cholesky, Vec<f64>, LowerPattern) {
    let (pattern, values) = fixtures::grid(side, dofs, 1e-3)
        .assemble()
        .expect("pattern");
    let options = CholeskyOptions::default()
        .with_supernodal(supernodal)
        .with_columns(4);
    // Analysed for the current pool: split over its threads where that pays.
    let mut chol = Cholesky::with_options(&pattern, options).expect("analysed");
    chol.factorize(&values).expect("positive definite");
    (chol, values, pattern)
}

fn rhs(n: usize) -> Vec<f64> {
    (0..n).map(|i| (i as f64 * 0.37).sin()).collect()
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

fn benches(c: &mut Criterion) {
    against_faer(c);
    let mut threads = c.benchmark_group("factorize_threads");
    threads.sample_size(20);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    for (name, side, dofs) in CASES {
        for count in [1, 2, 4] {
            if count > 1 && count > cores.max(2) {
                continue;
            }
            let pool = pool(count);
            let (mut chol, values, _) = pool.install(|| setup(side, dofs, Supernodal::Always));
            threads.bench_with_input(BenchmarkId::new(count.to_string(), name), &(), |b, _| {
                pool.install(|| b.iter(|| chol.factorize(black_box(&values)).expect("definite")))
            });
        }
    }
    threads.finish();
    let mut solves = c.benchmark_group("solve_threads");
    solves.sample_size(30);
    for (name, side, dofs) in CASES {
        for count in [1, 2, 4] {
            if count > 1 && count > cores.max(2) {
                continue;
            }
            let pool = pool(count);
            let (mut chol, _, _) = pool.install(|| setup(side, dofs, Supernodal::Always));
            let b0 = rhs(chol.dim());
            let mut x = b0.clone();
            solves.bench_with_input(BenchmarkId::new(count.to_string(), name), &(), |b, _| {
                pool.install(|| {
                    b.iter(|| {
                        x.copy_from_slice(&b0);
                        chol.solve_in_place(black_box(&mut x), 1).expect("solve");
                    })
                })
            });
        }
    }
    solves.finish();
}

/// The engine against faer, each analysed for one thread.
fn against_faer(c: &mut Criterion) {
    let one = pool(1);
    let setup = |side, dofs, supernodal| one.install(|| setup(side, dofs, supernodal));
    let mut factorize = c.benchmark_group("factorize");
    factorize.sample_size(20);
    for (name, side, dofs) in CASES {
        let (mut chol, values, _) = setup(side, dofs, Supernodal::Always);
        factorize.bench_with_input(BenchmarkId::new("own", name), &(), |b, _| {
            b.iter(|| chol.factorize(black_box(&values)).expect("definite"))
        });
        factorize.bench_with_input(BenchmarkId::new("faer", name), &(), |b, _| {
            b.iter(|| {
                chol.factorize_with_faer(black_box(&values))
                    .expect("definite")
            })
        });
        let (mut simplicial, values, _) = setup(side, dofs, Supernodal::Never);
        factorize.bench_with_input(BenchmarkId::new("simplicial", name), &(), |b, _| {
            b.iter(|| simplicial.factorize(black_box(&values)).expect("definite"))
        });
    }
    factorize.finish();

    let mut solve = c.benchmark_group("solve");
    for (name, side, dofs) in CASES {
        let (mut chol, _, pattern) = setup(side, dofs, Supernodal::Always);
        let b0 = rhs(pattern.dim());
        let mut x = b0.clone();
        solve.bench_with_input(BenchmarkId::new("own", name), &(), |b, _| {
            b.iter(|| {
                x.copy_from_slice(&b0);
                chol.solve_in_place(&mut x, 1).expect("solve")
            })
        });
        solve.bench_with_input(BenchmarkId::new("faer", name), &(), |b, _| {
            b.iter(|| {
                x.copy_from_slice(&b0);
                chol.solve_with_faer(&mut x, 1).expect("solve")
            })
        });
        let (mut simplicial, _, _) = setup(side, dofs, Supernodal::Never);
        solve.bench_with_input(BenchmarkId::new("simplicial", name), &(), |b, _| {
            b.iter(|| {
                x.copy_from_slice(&b0);
                simplicial.solve_in_place(&mut x, 1).expect("solve")
            })
        });
    }
    solve.finish();

    let mut solve4 = c.benchmark_group("solve4");
    for (name, side, dofs) in CASES {
        let (mut chol, _, pattern) = setup(side, dofs, Supernodal::Always);
        let b0 = rhs(4 * pattern.dim());
        let mut x = b0.clone();
        solve4.bench_with_input(BenchmarkId::new("own", name), &(), |b, _| {
            b.iter(|| {
                x.copy_from_slice(&b0);
                chol.solve_in_place(&mut x, 4).expect("solve")
            })
        });
        solve4.bench_with_input(BenchmarkId::new("faer", name), &(), |b, _| {
            b.iter(|| {
                x.copy_from_slice(&b0);
                chol.solve_with_faer(&mut x, 4).expect("solve")
            })
        });
    }
    solve4.finish();
}

criterion_group!(engine, benches);
criterion_main!(engine);
