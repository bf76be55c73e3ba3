//! Predicting a frame's start from solutions already found on the same line of metrics: the
//! polynomial through them (and through their tangents, when known), evaluated at the new
//! place, with as many of them as the solutions' smoothness at their spacing rewards.

/// The most solutions a prediction interpolates.
pub(crate) const NODES: usize = 6;

/// Largest sum of the magnitudes of a prediction's value weights, which bounds how much it
/// amplifies the solutions' own errors (their gradients are below the tolerance): one uniform
/// step beyond three solutions gives 7 for the quadratic through them, 37 for the quintic
/// through them and their tangents; two steps beyond, 17 and 361 (then the cubic through the
/// newest two and their tangents, 55, is taken instead).
pub(crate) const MAX_AMPLIFICATION: f64 = 64.0;

/// Weights of the polynomial that interpolates the nodes' values (and the derivatives of those
/// with `with_du`) evaluated at `s`: the start is `sum(alpha_j u_j) + sum(beta_j du_j)`. Solves
/// the (confluent Vandermonde) conditions of exactness on polynomials of degree below the
/// number of data, in coordinates scaled by `spacing`. `None` when the nodes do not determine
/// the polynomial or the value weights amplify (see [`MAX_AMPLIFICATION`]).
pub(crate) fn predictor_weights(
    s: f64,
    spacing: f64,
    nodes: &[(f64, bool)],
) -> Option<([f64; NODES], [f64; NODES])> {
    const M: usize = 2 * NODES;
    // Columns: one per value, then one per derivative; the last column is the right side.
    let mut columns: [(usize, bool); M] = [(0, false); M];
    let mut m = 0;
    for (j, _) in nodes.iter().enumerate() {
        columns[m] = (j, false);
        m += 1;
    }
    for (j, &(_, with_du)) in nodes.iter().enumerate() {
        if with_du {
            columns[m] = (j, true);
            m += 1;
        }
    }
    let mut a = [[0.0f64; M + 1]; M];
    for (p, row) in a.iter_mut().enumerate().take(m) {
        for (c, &(j, derivative)) in columns[..m].iter().enumerate() {
            let x = (nodes[j].0 - s) / spacing;
            row[c] = match (derivative, p) {
                (false, _) => x.powi(p as i32),
                (true, 0) => 0.0,
                (true, _) => p as f64 * x.powi(p as i32 - 1),
            };
        }
        // The polynomial x^p at the prediction's place, x = 0.
        row[M] = if p == 0 { 1.0 } else { 0.0 };
    }
    // Gaussian elimination with partial pivoting on the m x m system.
    for col in 0..m {
        let pivot = (col..m).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))?;
        if a[pivot][col].abs() < 1e-12 {
            return None;
        }
        a.swap(col, pivot);
        // Columns m..M are zero in every row, so whole rows can be combined.
        let pivot_row = a[col];
        for (r, row) in a.iter_mut().enumerate().take(m) {
            if r != col {
                let f = row[col] / pivot_row[col];
                for (x, p) in row.iter_mut().zip(&pivot_row) {
                    *x -= f * p;
                }
            }
        }
    }
    let (mut alpha, mut beta) = ([0.0; NODES], [0.0; NODES]);
    for (c, &(j, derivative)) in columns[..m].iter().enumerate() {
        let w = a[c][M] / a[c][c];
        if derivative {
            // d/dx = spacing d/ds.
            beta[j] = w * spacing;
        } else {
            alpha[j] = w;
        }
    }
    let size: f64 = alpha.iter().map(|x| x.abs()).sum();
    let finite = alpha.iter().chain(&beta).all(|x| x.is_finite());
    (finite && size <= MAX_AMPLIFICATION).then_some((alpha, beta))
}

/// How many of the solutions `values` (at places `at` on one line, nearest to `s` first, at
/// least one) the prediction at `s` should interpolate.
///
/// The Newton form of the polynomial through the first `m` of them adds one term per
/// solution: `f[s_0..s_k] (s - s_0)...(s - s_{k-1})`. Terms are taken while each is smaller
/// than the one before (their sizes measured over a sample of the unknowns, up to 2048): a
/// term that grows means the solution is not smooth enough at this spacing for that degree,
/// and taking it would make the prediction worse. On one-way sweeps of the 10K disk this
/// keeps the quadratic at t steps of 0.1 and 0.2 and takes higher degrees at finer steps.
/// At least two (a line) when there are two.
pub(crate) fn useful_nodes(at: &[f64], values: &[&[f64]], s: f64) -> usize {
    let count = at.len().min(values.len()).min(NODES);
    if count <= 2 {
        return count;
    }
    // Divided differences f[s_{j-k}..s_j] are built in place level by level; the reciprocals
    // of their denominators and the products (s - s_0)...(s - s_{k-1}) serve every unknown.
    let mut recip = [[0.0; NODES]; NODES];
    let mut omega = [0.0; NODES];
    let mut w = 1.0;
    for k in 1..count {
        w *= s - at[k - 1];
        omega[k] = w;
        for j in k..count {
            recip[k][j] = 1.0 / (at[j] - at[j - k]);
        }
    }
    let n = values[..count].iter().map(|v| v.len()).min().unwrap_or(0);
    let stride = (n / 2048).max(1);
    let mut squares = [0.0; NODES];
    for i in (0..n).step_by(stride) {
        let mut d = [0.0; NODES];
        for (d, v) in d.iter_mut().zip(&values[..count]) {
            *d = v[i];
        }
        for k in 1..count {
            for j in (k..count).rev() {
                d[j] = (d[j] - d[j - 1]) * recip[k][j];
            }
            let term = d[k] * omega[k];
            squares[k] += term * term;
        }
    }
    let mut used = 2;
    // NaN (coincident places) compares false and stops at the line.
    while used < count && squares[used] < squares[used - 1] {
        used += 1;
    }
    used
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quintic and its derivative.
    fn quintic(x: f64) -> (f64, f64) {
        let c = [0.3, -1.1, 0.7, 2.0, -0.4, 0.9];
        let value = c.iter().rev().fold(0.0, |acc, k| acc * x + k);
        let slope = (1..6).rev().fold(0.0, |acc, p| acc * x + p as f64 * c[p]);
        (value, slope)
    }

    #[test]
    fn predictions_are_exact_on_polynomials_of_their_degree() {
        let nodes = [0.9, 0.8, 0.7];
        let predict = |s: f64, data: &[(f64, bool)], spacing: f64| {
            let (alpha, beta) = predictor_weights(s, spacing, data).expect("weights");
            data.iter()
                .enumerate()
                .map(|(j, &(x, _))| alpha[j] * quintic(x).0 + beta[j] * quintic(x).1)
                .sum::<f64>()
        };
        // Three solutions and their tangents: the quintic itself, one step beyond.
        let all: Vec<(f64, bool)> = nodes.iter().map(|&x| (x, true)).collect();
        let got = predict(1.0, &all, 0.1);
        assert!((got - quintic(1.0).0).abs() < 1e-11, "{got}");
        // Between and on the nodes too.
        for s in [0.85, 0.8, 0.75] {
            assert!((predict(s, &all, 0.1) - quintic(s).0).abs() < 1e-12, "{s}");
        }
        // Values only: exact for the quadratic part's degree, here checked on a quadratic.
        let (alpha, beta) =
            predictor_weights(1.0, 0.1, &[(0.9, false), (0.8, false), (0.7, false)])
                .expect("weights");
        assert_eq!(beta, [0.0; NODES]);
        let q = |x: f64| 1.0 - 2.0 * x + 3.0 * x * x;
        let got: f64 = nodes.iter().zip(&alpha).map(|(&x, a)| a * q(x)).sum();
        assert!((got - q(1.0)).abs() < 1e-12);
        assert!((alpha[0] - 3.0).abs() < 1e-12 && (alpha[1] + 3.0).abs() < 1e-12);
    }

    #[test]
    fn predictions_refuse_coincident_nodes_and_far_extrapolation() {
        assert!(predictor_weights(1.0, 0.1, &[(0.9, false), (0.9, false)]).is_none());
        let all = [(0.9, true), (0.8, true), (0.7, true)];
        // One step beyond: amplification 37; three steps beyond: far more.
        assert!(predictor_weights(1.0, 0.1, &all).is_some());
        assert!(predictor_weights(1.2, 0.1, &all).is_none());
        // The cubic through the newest two takes over two steps beyond (amplification 55).
        assert!(predictor_weights(1.1, 0.1, &all).is_none());
        assert!(predictor_weights(1.1, 0.1, &all[..2]).is_some());
    }

    #[test]
    fn smooth_solutions_take_every_node_and_rough_ones_stop_at_the_line() {
        let at = [0.5, 0.4, 0.3, 0.2, 0.1, 0.0];
        // A smooth curve per unknown: every further term is smaller.
        let smooth: Vec<Vec<f64>> = at
            .iter()
            .map(|&x| {
                (0..100)
                    .map(|i| (x * (1.0 + 0.01 * i as f64)).exp())
                    .collect()
            })
            .collect();
        let values: Vec<&[f64]> = smooth.iter().map(|v| v.as_slice()).collect();
        assert_eq!(useful_nodes(&at, &values, 0.6), 6);
        assert_eq!(useful_nodes(&at[..4], &values[..4], 0.6), 4);
        // Oscillating at the spacing: the quadratic term already outgrows the linear one.
        let rough: Vec<Vec<f64>> = at
            .iter()
            .enumerate()
            .map(|(j, &x)| vec![x + if j % 2 == 0 { 0.3 } else { -0.3 }; 10])
            .collect();
        let values: Vec<&[f64]> = rough.iter().map(|v| v.as_slice()).collect();
        assert_eq!(useful_nodes(&at, &values, 0.6), 2);
        // Two solutions or fewer: all of them.
        assert_eq!(useful_nodes(&at[..2], &values[..2], 0.6), 2);
        assert_eq!(useful_nodes(&at[..1], &values[..1], 0.6), 1);
    }

    #[test]
    fn a_cubic_takes_its_own_degree_and_predicts_exactly() {
        // exp's Taylor cubic: its terms shrink up to its degree; the fifth vanishes to
        // round-off, so it is smaller and taken too (harmless: it adds nothing).
        let at = [1.0, 0.9, 0.8, 0.7, 0.6, 0.5];
        let cubic = |x: f64| 1.0 + x + x * x / 2.0 + x * x * x / 6.0;
        let data: Vec<Vec<f64>> = at.iter().map(|&x| vec![cubic(x); 4]).collect();
        let values: Vec<&[f64]> = data.iter().map(|v| v.as_slice()).collect();
        let used = useful_nodes(&at, &values, 1.1);
        assert!(used >= 5, "{used}");
        let nodes: Vec<(f64, bool)> = at[..used].iter().map(|&x| (x, false)).collect();
        let (alpha, _) = predictor_weights(1.1, 0.1, &nodes).expect("weights");
        let got: f64 = at.iter().zip(&alpha).map(|(&x, a)| a * cubic(x)).sum();
        assert!((got - cubic(1.1)).abs() < 1e-10, "{got}");
    }
}
