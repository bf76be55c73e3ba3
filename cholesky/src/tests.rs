//! Unit tests of the engine's internals: the plan, the kernels against faer's on the same
//! factor, the pivot checks. The property tests over many random matrices, through the public
//! interface, are in `tests/properties.rs`.

use crate::{fixtures, Cholesky, CholeskyError, CholeskyOptions, FactorPrecision, Supernodal};

/// The Laplacian of a `side` by `side` grid plus a small shift, factored supernodally (AMD,
/// supernodal forced), and its values.
fn grid(side: u32, precision: FactorPrecision) -> (Cholesky, Vec<f64>) {
    let (pattern, values) = fixtures::grid(side, 1, 1e-3).assemble().expect("pattern");
    let options = CholeskyOptions::default()
        .with_supernodal(Supernodal::Always)
        .with_precision(precision);
    let chol = Cholesky::with_options(&pattern, options).expect("analysed");
    assert!(chol.is_supernodal());
    (chol, values)
}

/// The largest difference between the lower triangles of two factors of `chol`'s structure,
/// relative to the largest entry of `b`.
fn difference<T: Copy + Into<f64>>(chol: &Cholesky, a: &[T], b: &[T]) -> f64 {
    let st = chol.analysis().structure.clone().expect("supernodal");
    let (mut diff, mut scale) = (0.0f64, 0.0f64);
    let mut checked = 0;
    for s in &st.list {
        let ld = s.ld();
        for c in 0..s.width as usize {
            for r in c..ld {
                let at = s.values_start + c * ld + r;
                let (x, y): (f64, f64) = (a[at].into(), b[at].into());
                diff = diff.max((x - y).abs());
                scale = scale.max(y.abs());
                checked += 1;
            }
        }
    }
    assert!(checked > 0 && scale > 0.0);
    diff / scale
}

fn rhs(n: usize) -> Vec<f64> {
    (0..n).map(|i| (i as f64 * 0.37).sin() + 0.1).collect()
}

#[test]
fn double_precision_factors_and_solves_match_faer() {
    let (mut chol, values) = grid(34, FactorPrecision::Double);
    chol.factorize(&values).expect("definite");
    let ours = chol.values().0.to_vec();
    let mut x = rhs(chol.dim());
    chol.solve_in_place(&mut x, 1).expect("solve");
    let mut y = rhs(chol.dim());
    chol.solve_with_faer(&mut y, 1).expect("solve");
    let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (a, b) in x.iter().zip(&y) {
        assert!((a - b).abs() <= 1e-12 * scale, "{a} vs {b}");
    }
    chol.factorize_with_faer(&values).expect("definite");
    let theirs = chol.values().0.to_vec();
    let d = difference(&chol, &ours, &theirs);
    assert!(d <= 1e-13, "{d}");
}

#[test]
fn single_precision_factors_match_faer_and_are_applied_in_double_precision() {
    let (mut chol, values) = grid(34, FactorPrecision::Single);
    chol.factorize(&values).expect("definite");
    assert!(chol.factor_is_single());
    let ours = chol.values().1.to_vec();
    let mut x = rhs(chol.dim());
    chol.solve_in_place(&mut x, 1).expect("solve");
    chol.factorize_with_faer(&values).expect("definite");
    assert!(chol.factor_is_single());
    let theirs = chol.values().1.to_vec();
    let d = difference(&chol, &ours, &theirs);
    assert!(d <= 1e-5, "{d}");
    // The same arithmetic in double precision on the single-precision values: faer's
    // double-precision solve with the widened factor.
    let (mut wide, _) = grid(34, FactorPrecision::Double);
    wide.set_double_factor(ours.iter().map(|&v| f64::from(v)).collect());
    let mut y = rhs(chol.dim());
    wide.solve_with_faer(&mut y, 1).expect("solve");
    let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (a, b) in x.iter().zip(&y) {
        assert!((a - b).abs() <= 1e-12 * scale, "{a} vs {b}");
    }
}

#[test]
fn the_plan_covers_every_value_once() {
    let (chol, values) = grid(34, FactorPrecision::Double);
    let plan = chol.analysis().plan.as_ref().expect("own plan");
    plan.check_coverage(values.len());
}

#[test]
fn the_portable_loops_match_the_vector_ones() {
    let (mut chol, values) = grid(34, FactorPrecision::Double);
    chol.factorize(&values).expect("definite");
    let plan = chol.analysis().plan.as_ref().expect("own plan");
    let mut fresh = vec![f64::NAN; chol.factor_nnz()];
    // NaN wherever the factorisation fails to write: every block is opened first.
    let mut portable = fresh.clone();
    let mut inv = vec![0.0; chol.dim()];
    let mut pivots = chol.analysis().pivots(&mut inv);
    plan.factorize(&values, &mut fresh, &mut pivots, &mut [])
        .expect("definite");
    plan.factorize_portable(&values, &mut portable, &mut pivots)
        .expect("definite");
    assert!(fresh.iter().chain(&portable).all(|v| v.is_finite()));
    let d = difference(&chol, &portable, &fresh);
    assert!(d <= 1e-13, "{d}");
}

#[test]
fn failures_name_their_pivot_as_faer_does() {
    for precision in [FactorPrecision::Double, FactorPrecision::Single] {
        let (mut chol, mut values) = grid(20, precision);
        // Make one unknown's diagonal negative: the factorisation stops at or before it.
        values[0] = -1.0;
        chol.give_up_single();
        let ours = chol.factorize(&values);
        let theirs = chol.factorize_with_faer(&values);
        match (ours, theirs) {
            (
                Err(CholeskyError::NotPositiveDefinite { pivot: a }),
                Err(CholeskyError::NotPositiveDefinite { pivot: b }),
            ) => assert_eq!(a, b),
            other => panic!("{other:?}"),
        }
        assert!(!chol.is_ready());
        assert!(matches!(
            chol.solve_in_place(&mut vec![0.0; chol.dim()], 1),
            Err(CholeskyError::NoFactor)
        ));
    }
    // A value that is not finite fails without a factor.
    let (mut chol, mut values) = grid(20, FactorPrecision::Double);
    let n = values.len();
    values[n / 2] = f64::NAN;
    assert!(matches!(
        chol.factorize(&values),
        Err(CholeskyError::NonFinite { .. })
    ));
    assert!(!chol.is_ready());
}

#[test]
fn values_beyond_single_range_fall_back_to_double() {
    let (mut chol, mut values) = grid(20, FactorPrecision::Single);
    let (mut exact, _) = grid(20, FactorPrecision::Double);
    exact.factorize(&values).expect("definite");
    let mut expected = rhs(chol.dim());
    exact.solve_in_place(&mut expected, 1).expect("solve");
    // H' = D H D with D = 1 but 1e40 for unknown 3: still positive definite, but its
    // diagonal there (1e80 times the original) overflows f32. H' x' = D b has the solution
    // x' = D^-1 x.
    let (k, scale) = (3u32, 1e40);
    let pattern = chol.pattern().clone();
    let ptr = pattern.col_ptr();
    for col in 0..pattern.dim() {
        let slots = ptr[col] as usize..ptr[col + 1] as usize;
        for (value, &row) in values[slots.clone()]
            .iter_mut()
            .zip(&pattern.row_idx()[slots])
        {
            for index in [row, col as u32] {
                if index == k {
                    *value *= scale;
                }
            }
        }
    }
    chol.factorize(&values)
        .expect("definite in double precision");
    assert!(!chol.factor_is_single());
    assert_eq!(chol.precision(), FactorPrecision::Double);
    let mut x = rhs(chol.dim());
    x[k as usize] *= scale;
    chol.solve_in_place(&mut x, 1).expect("solve");
    for (i, (a, b)) in x.iter().zip(&expected).enumerate() {
        let a = if i == k as usize { a * scale } else { *a };
        assert!((a - b).abs() < 1e-10 * b.abs().max(1e-3), "{i}: {a} vs {b}");
    }
    // Asking again tries single precision again.
    chol.set_precision(FactorPrecision::Single);
    assert_eq!(chol.precision(), FactorPrecision::Single);
    assert!(!chol.is_ready());
}

/// The factorisation can move to another thread (the systems that own one, and the Python
/// bindings that release the interpreter's lock around solves, rely on it).
#[test]
fn a_factorisation_is_send() {
    fn send<T: Send>() {}
    send::<Cholesky>();
    send::<crate::LowerPattern>();
}
