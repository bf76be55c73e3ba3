//! Property tests of the engine on its own: on many random sparse symmetric positive definite
//! matrices (grids, random graphs, dense blocks, tiny and single-column ones) the engine's
//! factorisations and solves agree with faer's and solve the system, in both precisions,
//! supernodal and simplicial, with AMD and with arbitrary orderings; singular and
//! near-singular matrices fall back (single precision) or fail with a typed error.

use bdmorph_cholesky::fixtures::{self, TestMatrix};
use bdmorph_cholesky::{
    Cholesky, CholeskyError, CholeskyOptions, FactorPrecision, LowerPattern, Ordering, Supernodal,
};
use proptest::prelude::*;

/// A small deterministic generator (xorshift64*), so that a proptest case is a few numbers.
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Rng {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: u32) -> u32 {
        (self.next() % u64::from(n.max(1))) as u32
    }
    /// Uniform in `[a, b)`.
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The kinds of matrices generated.
#[derive(Clone, Copy, Debug)]
enum Kind {
    /// A grid Laplacian with one or two unknowns per vertex (the fixture).
    Grid,
    /// A random graph's weighted Laplacian.
    Graph,
    /// Dense cliques joined by a few edges.
    Blocks,
    /// `Bᵀ B` for a sparse random `B` (not diagonally dominant).
    Gram,
}

/// A symmetric positive definite matrix of `kind` with about `size` unknowns, whose smallest
/// eigenvalue is at least `shift` times its largest diagonal entry (for `shift > 0`).
fn matrix(kind: Kind, size: u32, seed: u64, shift: f64) -> TestMatrix {
    let mut rng = Rng::new(seed);
    let n = size.max(1);
    let mut m = TestMatrix {
        n: n as usize,
        pairs: Vec::new(),
        values: Vec::new(),
    };
    let edge = |m: &mut TestMatrix, a: u32, b: u32, w: f64| {
        if a != b {
            m.pairs.extend([(a, b), (a, a), (b, b)]);
            m.values.extend([-w, w, w]);
        }
    };
    match kind {
        Kind::Grid => {
            let side = (f64::from(n).sqrt() as u32).max(1);
            m = fixtures::grid(side, 1 + rng.below(2), 0.0);
        }
        Kind::Graph => {
            let edges = n * (1 + rng.below(4));
            for _ in 0..edges {
                let (a, b) = (rng.below(n), rng.below(n));
                let w = rng.range(0.1, 3.0);
                edge(&mut m, a, b, w);
            }
        }
        Kind::Blocks => {
            let mut start = 0;
            while start < n {
                let width = (2 + rng.below(30)).min(n - start);
                for a in start..start + width {
                    for b in start..a {
                        edge(&mut m, a, b, rng.range(0.1, 1.0));
                    }
                }
                if start > 0 {
                    let (a, b) = (
                        start - 1 - rng.below(start.min(5)),
                        start + rng.below(width),
                    );
                    edge(&mut m, a, b, rng.range(0.1, 1.0));
                }
                start += width;
            }
        }
        Kind::Gram => {
            // Rows of B with 2 or 3 entries in distinct columns: B^T B gets a clique per row.
            for _ in 0..n + n / 2 {
                let mut cols: Vec<u32> = Vec::new();
                while cols.len() < (2 + rng.below(2)).min(n) as usize {
                    let c = rng.below(n);
                    if !cols.contains(&c) {
                        cols.push(c);
                    }
                }
                let vals: Vec<f64> = cols.iter().map(|_| rng.range(-1.0, 1.0)).collect();
                // Each unordered pair once: (a, b) and (b, a) share a slot.
                for (i, (&a, &x)) in cols.iter().zip(&vals).enumerate() {
                    for (&b, &y) in cols.iter().zip(&vals).take(i + 1) {
                        m.pairs.push((a, b));
                        m.values.push(x * y);
                    }
                }
            }
        }
    }
    // The shift, relative to the largest diagonal entry: diagonal dominance gives the bound.
    let (pattern, values) = m.assemble().expect("pattern");
    let largest = pattern
        .diagonal_slots()
        .iter()
        .map(|&s| values[s as usize])
        .fold(0.0f64, f64::max)
        .max(1.0);
    for i in 0..m.n as u32 {
        m.pairs.push((i, i));
        m.values.push(shift * largest);
    }
    m
}

/// `‖A x − b‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞)`: the backward error of a solve.
fn backward_error(pattern: &LowerPattern, values: &[f64], x: &[f64], b: &[f64]) -> f64 {
    let mut ax = vec![0.0; x.len()];
    pattern.symmetric_product(values, x, &mut ax);
    let mut row_sums = vec![0.0; x.len()];
    let abs: Vec<f64> = values.iter().map(|v| v.abs()).collect();
    pattern.symmetric_product(&abs, &vec![1.0; x.len()], &mut row_sums);
    let norm_a = row_sums.iter().fold(0.0f64, |m, v| m.max(*v));
    let inf = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let r: Vec<f64> = ax.iter().zip(b).map(|(a, b)| a - b).collect();
    inf(&r) / (norm_a * inf(x) + inf(b)).max(f64::MIN_POSITIVE)
}

fn kinds() -> impl Strategy<Value = Kind> {
    prop_oneof![
        Just(Kind::Grid),
        Just(Kind::Graph),
        Just(Kind::Blocks),
        Just(Kind::Gram)
    ]
}

fn supernodal() -> impl Strategy<Value = Supernodal> {
    prop_oneof![
        Just(Supernodal::Auto),
        Just(Supernodal::Always),
        Just(Supernodal::Never)
    ]
}

/// A permutation of `0..n` from a seed.
fn permutation(n: usize, seed: u64) -> Vec<u32> {
    let mut rng = Rng::new(seed ^ 0xABCD);
    let mut p: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        p.swap(i, rng.below(i as u32 + 1) as usize);
    }
    p
}

fn options(supernodal: Supernodal, custom: Option<Vec<u32>>) -> CholeskyOptions {
    let options = CholeskyOptions::default().with_supernodal(supernodal);
    match custom {
        Some(p) => options.with_ordering(Ordering::Custom(p)),
        None => options,
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    /// Double precision: the engine's factor solves the system to rounding, agrees with
    /// faer's factor's solve, and several right-hand sides at once equal one at a time.
    #[test]
    fn double_precision_solves_agree_with_faer(
        kind in kinds(),
        size in 1u32..400,
        seed in any::<u64>(),
        sn in supernodal(),
        custom in any::<bool>(),
        columns in 1usize..8,
    ) {
        let m = matrix(kind, size, seed, 1e-3);
        let (pattern, values) = m.assemble().expect("pattern");
        let perm = custom.then(|| permutation(m.n, seed));
        let mut chol = Cholesky::with_options(&pattern, options(sn, perm)).expect("analysed");
        // (faer makes a factor without off-diagonal work simplicial whatever it is asked.)
        if sn == Supernodal::Always && pattern.nnz() > m.n {
            prop_assert!(chol.is_supernodal());
        }
        if sn == Supernodal::Never {
            prop_assert!(!chol.is_supernodal());
        }
        let b: Vec<f64> = (0..m.n * columns).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
        chol.factorize(&values).expect("positive definite");
        let mut ours = b.clone();
        chol.solve_in_place(&mut ours, columns).expect("solve");
        for k in 0..columns {
            let range = k * m.n..(k + 1) * m.n;
            let e = backward_error(&pattern, &values, &ours[range.clone()], &b[range.clone()]);
            prop_assert!(e < 1e-13, "column {}: backward error {:e}", k, e);
            // One column at a time gives the same bits.
            let mut one = b[range.clone()].to_vec();
            chol.solve_in_place(&mut one, 1).expect("solve");
            prop_assert_eq!(&one[..], &ours[range]);
        }
        let mut theirs = b.clone();
        chol.solve_with_faer(&mut theirs, columns).expect("solve");
        let scale = theirs.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        for (x, y) in ours.iter().zip(&theirs) {
            prop_assert!((x - y).abs() <= 1e-9 * scale, "{} vs {}", x, y);
        }
        // faer's factorisation of the same matrix, solved by either: the same solution.
        chol.factorize_with_faer(&values).expect("positive definite");
        let mut again = b.clone();
        chol.solve_in_place(&mut again, columns).expect("solve");
        for (x, y) in again.iter().zip(&theirs) {
            prop_assert!((x - y).abs() <= 1e-9 * scale, "{} vs {}", x, y);
        }
    }

    /// Right-hand sides that are zero but at a few rows (point sources): the solve that
    /// visits only the supernodes those rows reach gives the full solve's bits, also when
    /// the rows given miss a nonzero (which it notices, and solves in full).
    #[test]
    fn sparse_right_hand_sides_give_the_full_solves_bits(
        kind in kinds(),
        size in 1u32..400,
        seed in any::<u64>(),
        sn in supernodal(),
        columns in 1usize..6,
        sources in 1usize..4,
        miss in any::<bool>(),
    ) {
        let m = matrix(kind, size, seed, 1e-3);
        let (pattern, values) = m.assemble().expect("pattern");
        let mut chol = Cholesky::with_options(&pattern, options(sn, None)).expect("analysed");
        chol.factorize(&values).expect("positive definite");
        let mut rng = Rng::new(seed ^ 77);
        let rows: Vec<u32> = (0..sources).map(|_| rng.below(m.n as u32)).collect();
        let mut b = vec![0.0; m.n * columns];
        for c in 0..columns {
            for &r in &rows {
                b[c * m.n + r as usize] = rng.range(0.5, 2.0);
            }
        }
        let given: &[u32] = if miss {
            // A nonzero at a row not given (when there is another row to put it at).
            let other = (rows[0] + 1) % m.n as u32;
            if !rows.contains(&other) {
                b[other as usize] = 1.0;
            }
            &rows[1..]
        } else {
            &rows
        };
        let mut full = b.clone();
        chol.solve_in_place(&mut full, columns).expect("solve");
        let mut sparse = b.clone();
        chol.solve_in_place_sparse(&mut sparse, columns, given).expect("solve");
        prop_assert_eq!(full, sparse);
    }

    /// Single precision: a preconditioner-quality solve (the engine's in double arithmetic on
    /// the `f32` factor, faer's in `f32`), close to the exact solution, or a fallback to
    /// double precision when the matrix is too ill-conditioned for it.
    #[test]
    fn single_precision_solves_are_close_or_fall_back(
        kind in kinds(),
        size in 1u32..300,
        seed in any::<u64>(),
        sn in supernodal(),
    ) {
        let m = matrix(kind, size, seed, 1e-2);
        let (pattern, values) = m.assemble().expect("pattern");
        let single = CholeskyOptions::default()
            .with_supernodal(sn)
            .with_precision(FactorPrecision::Single);
        let mut chol = Cholesky::with_options(&pattern, single).expect("analysed");
        let mut exact = Cholesky::with_options(&pattern, options(sn, None)).expect("analysed");
        exact.factorize(&values).expect("positive definite");
        chol.factorize(&values).expect("positive definite");
        let b: Vec<f64> = (0..m.n).map(|i| ((i * 31) % 17) as f64 - 8.0).collect();
        let mut x = b.clone();
        exact.solve_in_place(&mut x, 1).expect("solve");
        let mut y = b.clone();
        chol.solve_in_place(&mut y, 1).expect("solve");
        let scale = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let tolerance = if chol.factor_is_single() { 1e-3 } else { 1e-10 };
        for (a, c) in x.iter().zip(&y) {
            prop_assert!((a - c).abs() <= tolerance * scale, "{} vs {}", a, c);
        }
        if chol.factor_is_single() {
            let mut z = b.clone();
            chol.solve_with_faer(&mut z, 1).expect("solve");
            for (a, c) in x.iter().zip(&z) {
                prop_assert!((a - c).abs() <= 1e-3 * scale, "{} vs {}", a, c);
            }
        }
    }

    /// A singular matrix (the Laplacian of a connected graph, whose constants are a null
    /// space) never yields a double-precision factor: a typed error, with faer's kernels
    /// too. (In single precision its last pivots are single precision's own rounding, which
    /// the factorisation cannot tell from a true pivot: see `Cholesky::factorize`.)
    #[test]
    fn singular_matrices_fail_with_a_typed_error(
        kind in prop_oneof![Just(Kind::Grid), Just(Kind::Blocks)],
        size in 2u32..3000,
        seed in any::<u64>(),
        sn in supernodal(),
    ) {
        let m = matrix(kind, size, seed, 0.0);
        let (pattern, values) = m.assemble().expect("pattern");
        let options = CholeskyOptions::default().with_supernodal(sn);
        let mut chol = Cholesky::with_options(&pattern, options).expect("analysed");
        for result in [chol.factorize(&values), chol.factorize_with_faer(&values)] {
            prop_assert!(
                matches!(
                    result,
                    Err(CholeskyError::Singular { .. } | CholeskyError::NotPositiveDefinite { .. })
                ),
                "{:?}",
                result
            );
            prop_assert!(!chol.is_ready());
        }
    }
}

/// A matrix whose conditioning suits double precision but not single: the single-precision
/// factorisation falls back to double, and the solve is exact to double precision's rounding.
#[test]
fn near_singular_matrices_fall_back_to_double_precision() {
    // The grid Laplacian plus 1e-9 of its largest diagonal entry: condition about 1e10, far
    // beyond f32's 1e7, well within f64's.
    let m = matrix(Kind::Grid, 900, 7, 1e-9);
    let (pattern, values) = m.assemble().expect("pattern");
    for sn in [Supernodal::Always, Supernodal::Never] {
        let options = CholeskyOptions::default()
            .with_supernodal(sn)
            .with_precision(FactorPrecision::Single);
        let mut chol = Cholesky::with_options(&pattern, options).expect("analysed");
        assert_eq!(chol.precision(), FactorPrecision::Single);
        chol.factorize(&values)
            .expect("definite in double precision");
        assert!(!chol.factor_is_single(), "{sn:?}: single precision kept");
        assert_eq!(chol.precision(), FactorPrecision::Double);
        let b: Vec<f64> = (0..m.n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut x = b.clone();
        chol.solve_in_place(&mut x, 1).expect("solve");
        let e = backward_error(&pattern, &values, &x, &b);
        assert!(e < 1e-13, "{sn:?}: backward error {e:e}");
    }
}

/// The smallest cases: one unknown, a 2 by 2, a diagonal matrix (every column its own
/// supernode), and their errors.
#[test]
fn tiny_and_single_column_matrices() {
    for sn in [Supernodal::Auto, Supernodal::Always, Supernodal::Never] {
        let (p, _) = LowerPattern::new(1, &[(0, 0)]).expect("pattern");
        let mut chol = Cholesky::with_options(&p, options(sn, None)).expect("analysed");
        chol.factorize(&[4.0]).expect("positive");
        let mut x = [2.0];
        chol.solve_in_place(&mut x, 1).expect("solve");
        assert_eq!(x, [0.5]);
        let mut xs = [2.0, 8.0, -4.0];
        chol.solve_in_place(&mut xs, 3).expect("three columns");
        assert_eq!(xs, [0.5, 2.0, -1.0]);
        assert!(matches!(
            chol.factorize(&[-1.0]),
            Err(CholeskyError::NotPositiveDefinite { pivot: 0 })
        ));
        assert!(matches!(
            chol.factorize(&[0.0]),
            Err(CholeskyError::NotPositiveDefinite { pivot: 0 })
        ));
        assert!(matches!(
            chol.factorize(&[f64::NAN]),
            Err(CholeskyError::NotPositiveDefinite { .. } | CholeskyError::NonFinite { .. })
        ));
        assert!(matches!(
            chol.factorize(&[1.0, 2.0]),
            Err(CholeskyError::Length {
                expected: 1,
                got: 2,
                ..
            })
        ));
        assert!(matches!(
            chol.solve_in_place(&mut [1.0], 1),
            Err(CholeskyError::NoFactor)
        ));

        // [[2, 1], [1, 2]]: x = (1, 1) for b = (3, 3).
        let (p, slots) = LowerPattern::new(2, &[(0, 0), (1, 0), (1, 1)]).expect("pattern");
        let mut values = [0.0; 3];
        for (s, v) in slots.iter().zip([2.0, 1.0, 2.0]) {
            values[*s as usize] = v;
        }
        let mut chol = Cholesky::with_options(&p, options(sn, None)).expect("analysed");
        chol.factorize(&values).expect("positive definite");
        let mut x = [3.0, 3.0];
        chol.solve_in_place(&mut x, 1).expect("solve");
        assert!(
            (x[0] - 1.0).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15,
            "{x:?}"
        );
        assert!(matches!(
            chol.solve_in_place(&mut [1.0; 3], 1),
            Err(CholeskyError::Length { .. })
        ));

        // A diagonal matrix: no off-diagonal entry at all.
        let n = 50;
        let pairs: Vec<(u32, u32)> = (0..n).map(|i| (i, i)).collect();
        let (p, _) = LowerPattern::new(n as usize, &pairs).expect("pattern");
        let values: Vec<f64> = (0..n).map(|i| f64::from(i + 1)).collect();
        let mut chol = Cholesky::with_options(&p, options(sn, None)).expect("analysed");
        chol.factorize(&values).expect("positive definite");
        let mut x = values.clone();
        chol.solve_in_place(&mut x, 1).expect("solve");
        assert!(x.iter().all(|&v| (v - 1.0).abs() < 1e-15), "{x:?}");
    }
}

/// New values in the same pattern: every factorisation starts afresh (no state carried
/// over), and a failed one leaves no factor behind.
#[test]
fn refactoring_with_new_values_forgets_the_old_ones() {
    let m = matrix(Kind::Grid, 400, 3, 1e-2);
    let (pattern, values) = m.assemble().expect("pattern");
    let scaled: Vec<f64> = values.iter().map(|v| 3.0 * v).collect();
    let b: Vec<f64> = (0..m.n).map(|i| (i % 5) as f64).collect();
    for sn in [Supernodal::Always, Supernodal::Never] {
        let mut chol = Cholesky::with_options(&pattern, options(sn, None)).expect("analysed");
        chol.factorize(&values).expect("definite");
        let mut x1 = b.clone();
        chol.solve_in_place(&mut x1, 1).expect("solve");
        chol.factorize(&scaled).expect("definite");
        let mut x3 = b.clone();
        chol.solve_in_place(&mut x3, 1).expect("solve");
        for (a, c) in x1.iter().zip(&x3) {
            assert!(
                (a - 3.0 * c).abs() < 1e-12 * a.abs().max(1.0),
                "{a} vs 3 * {c}"
            );
        }
        let negative: Vec<f64> = values.iter().map(|v| -v).collect();
        assert!(chol.factorize(&negative).is_err());
        assert!(matches!(
            chol.solve_in_place(&mut x3, 1),
            Err(CholeskyError::NoFactor)
        ));
    }
}

/// Rows outside the matrix are refused by the sparse solve.
#[test]
fn sparse_solves_check_their_rows() {
    let (pattern, values) = fixtures::grid(4, 1, 1.0).assemble().expect("pattern");
    let mut chol = Cholesky::new(&pattern).expect("analysed");
    chol.factorize(&values).expect("definite");
    assert!(matches!(
        chol.solve_in_place_sparse(&mut [0.0; 16], 1, &[16]),
        Err(CholeskyError::Pattern(_))
    ));
}

/// Orderings that are not permutations are refused when analysing.
#[test]
fn bad_orderings_are_refused() {
    let (pattern, _) = fixtures::grid(4, 1, 1.0).assemble().expect("pattern");
    for bad in [
        vec![0; 16],
        (0..15).collect(),
        (1..17).collect::<Vec<u32>>(),
    ] {
        let options = CholeskyOptions::default().with_ordering(Ordering::Custom(bad));
        assert!(matches!(
            Cholesky::with_options(&pattern, options),
            Err(CholeskyError::Pattern(_))
        ));
    }
}
