//! Factorisations split over several threads (independent subtrees of the elimination tree,
//! see the crate's `subtrees` module) agree with one thread to rounding, and give the same
//! bits every time for the same number of threads.

use bdmorph_cholesky::fixtures;
use bdmorph_cholesky::{Cholesky, CholeskyOptions, FactorPrecision};

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

/// The solution of `A x = b` for the grid's matrix, factored in a pool of `threads`, and the
/// threads the factorisation used.
fn solve(side: u32, dofs: u32, threads: usize, precision: FactorPrecision) -> (Vec<f64>, usize) {
    let (pattern, values) = fixtures::grid(side, dofs, 1e-3)
        .assemble()
        .expect("pattern");
    pool(threads).install(|| {
        let options = CholeskyOptions::default().with_precision(precision);
        let mut chol = Cholesky::with_options(&pattern, options).expect("analysis");
        chol.factorize(&values).expect("definite");
        let n = chol.dim();
        let mut x: Vec<f64> = (0..n)
            .map(|i| ((i * 37) % 101) as f64 / 101.0 - 0.5)
            .collect();
        chol.solve_in_place(&mut x, 1).expect("solve");
        (x, chol.factor_threads())
    })
}

fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

#[test]
fn split_factorisations_agree_with_one_thread() {
    for precision in [FactorPrecision::Double, FactorPrecision::Single] {
        let (one, used) = solve(160, 1, 1, precision);
        assert_eq!(used, 1, "one thread: no split");
        for threads in [2, 3, 4] {
            let (many, used) = solve(160, 1, threads, precision);
            assert!(
                (2..=threads).contains(&used),
                "{threads} threads: the 25,600-unknown grid is split ({used} bins)"
            );
            let tolerance = if precision == FactorPrecision::Double {
                1e-11
            } else {
                1e-4
            };
            let diff = max_difference(&one, &many);
            assert!(
                diff < tolerance,
                "{precision:?}, {threads} threads: {diff:e} from one thread"
            );
            let (again, _) = solve(160, 1, threads, precision);
            assert!(
                many.iter()
                    .zip(&again)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{precision:?}, {threads} threads: the same bits every time"
            );
        }
    }
}

#[test]
fn small_factorisations_stay_on_one_thread() {
    let (_, used) = solve(20, 1, 4, FactorPrecision::Double);
    assert_eq!(used, 1, "400 unknowns are not worth a second thread");
}

#[test]
fn two_unknowns_per_vertex_split_too() {
    let (one, _) = solve(100, 2, 1, FactorPrecision::Double);
    let (two, used) = solve(100, 2, 2, FactorPrecision::Double);
    assert_eq!(used, 2);
    assert!(max_difference(&one, &two) < 1e-11);
}

/// Solves of `columns` right-hand sides with the grid's matrix (factored in double
/// precision), built and run in a pool of `threads`: the solutions, one after another, the
/// relative residual `max |A x - b| / max |b|` and the threads the solves used.
fn solve_columns(side: u32, threads: usize, columns: usize) -> (Vec<f64>, f64, usize) {
    let (pattern, values) = fixtures::grid(side, 1, 1e-2).assemble().expect("pattern");
    pool(threads).install(|| {
        let mut chol =
            Cholesky::with_options(&pattern, CholeskyOptions::default()).expect("analysis");
        chol.factorize(&values).expect("definite");
        let n = chol.dim();
        let b: Vec<f64> = (0..n * columns)
            .map(|i| ((i * 53) % 97) as f64 / 97.0 - 0.5)
            .collect();
        let mut x = b.clone();
        chol.reserve_columns(columns).expect("room");
        chol.solve_in_place(&mut x, columns).expect("solve");
        let mut residual = 0.0f64;
        let mut ax = vec![0.0; n];
        for (xc, bc) in x.chunks(n).zip(b.chunks(n)) {
            pattern.symmetric_product(&values, xc, &mut ax);
            for (a, b) in ax.iter().zip(bc) {
                residual = residual.max((a - b).abs());
            }
        }
        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        (x, residual / scale, chol.solve_threads())
    })
}

#[test]
fn split_solves_are_exact_agree_with_one_thread_and_repeat() {
    // 1, 2, 3 and 7 right-hand sides: blocks of one, two and four.
    for columns in [1, 2, 3, 7] {
        let (one, residual, used) = solve_columns(160, 1, columns);
        assert_eq!(used, 1, "one thread: no split");
        assert!(residual < 1e-12, "one thread: residual {residual:e}");
        for threads in [2, 3] {
            let (many, residual, used) = solve_columns(160, threads, columns);
            assert!(
                (2..=threads).contains(&used),
                "{threads} threads: the solves are split ({used} bins)"
            );
            assert!(residual < 1e-12, "{threads} threads: residual {residual:e}");
            let diff = max_difference(&one, &many);
            assert!(diff < 1e-11, "{threads} threads: {diff:e} from one thread");
            let (again, _, _) = solve_columns(160, threads, columns);
            assert!(
                many.iter()
                    .zip(&again)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{threads} threads, {columns} columns: the same bits every time"
            );
        }
    }
}

#[test]
fn small_solves_stay_on_one_thread() {
    let (_, residual, used) = solve_columns(20, 4, 1);
    assert_eq!(used, 1, "400 unknowns are not worth a second thread");
    assert!(residual < 1e-12);
}

#[test]
fn solves_kept_on_one_thread_give_one_threads_bits() {
    let (one, _, _) = solve_columns(160, 1, 1);
    let (pattern, values) = fixtures::grid(160, 1, 1e-2).assemble().expect("pattern");
    let kept = pool(2).install(|| {
        let mut chol =
            Cholesky::with_options(&pattern, CholeskyOptions::default()).expect("analysis");
        chol.factorize(&values).expect("definite");
        assert!(chol.solve_threads() >= 2, "split for two threads");
        chol.keep_solves_on_one_thread();
        assert_eq!(chol.solve_threads(), 1);
        let n = chol.dim();
        let mut x: Vec<f64> = (0..n)
            .map(|i| ((i * 53) % 97) as f64 / 97.0 - 0.5)
            .collect();
        chol.solve_in_place(&mut x, 1).expect("solve");
        // Still one thread after a new factorisation of the same pattern.
        chol.factorize(&values).expect("definite");
        assert_eq!(chol.solve_threads(), 1);
        x
    });
    // The factorisation itself was split (its top summed in another order): rounding apart.
    let diff = max_difference(&one, &kept);
    assert!(diff < 1e-11, "{diff:e} from one thread");
}
