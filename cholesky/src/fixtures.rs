//! Matrices to test and measure the engine with: the Laplacians of triangulated grids, as the
//! mesh systems produce them. Used by this crate's tests and benchmarks; public so that
//! callers' tests can use them too.

use crate::{CholeskyError, LowerPattern};

/// A symmetric matrix given by entries: `values[k]` goes to `pairs[k]` (entries of one slot
/// add up).
#[derive(Clone, Debug)]
pub struct TestMatrix {
    /// Dimension.
    pub n: usize,
    /// Entry positions (either triangle).
    pub pairs: Vec<(u32, u32)>,
    /// Entry values.
    pub values: Vec<f64>,
}

impl TestMatrix {
    /// The pattern and the values assembled into its slots.
    pub fn assemble(&self) -> Result<(LowerPattern, Vec<f64>), CholeskyError> {
        let (pattern, slots) = LowerPattern::new(self.n, &self.pairs)?;
        let mut values = vec![0.0; pattern.nnz()];
        for (&s, &v) in slots.iter().zip(&self.values) {
            values[s as usize] += v;
        }
        Ok((pattern, values))
    }
}

/// The weighted Laplacian of a `side` by `side` grid triangulated along one diagonal, with
/// `dofs` unknowns per vertex (coupled within a vertex and along each edge, as a 2D map's
/// `x` and `y` are in a parameterisation's Newton Hessian), plus `shift` times the identity.
/// Weights vary deterministically between 1 and 1.4 (0.3-0.42 on the diagonals). Positive
/// definite for `shift > 0`; singular (the constants are a null space) for `shift = 0`.
pub fn grid(side: u32, dofs: u32, shift: f64) -> TestMatrix {
    let id = |i: u32, j: u32| j * side + i;
    let weight = |k: u32| 1.0 + 0.4 * f64::from(k.wrapping_mul(7) % 11) / 11.0;
    let vertices = side * side;
    let n = vertices * dofs;
    let mut m = TestMatrix {
        n: n as usize,
        pairs: Vec::new(),
        values: Vec::new(),
    };
    for v in 0..vertices {
        for a in 0..dofs {
            m.pairs.push((v * dofs + a, v * dofs + a));
            m.values.push(shift);
            // A weak coupling of a vertex's unknowns keeps the blocks dense.
            for b in 0..a {
                m.pairs.push((v * dofs + a, v * dofs + b));
                m.values.push(0.0);
            }
        }
    }
    let mut edge = |p: u32, q: u32, w: f64| {
        for a in 0..dofs {
            let (x, y) = (p * dofs + a, q * dofs + a);
            m.pairs.extend([(x, y), (x, x), (y, y)]);
            m.values.extend([-w, w, w]);
            for b in 0..dofs {
                if b != a {
                    m.pairs.push((x, q * dofs + b));
                    m.values.push(0.0);
                }
            }
        }
    };
    for j in 0..side {
        for i in 0..side {
            let v = id(i, j);
            if i + 1 < side {
                edge(v, id(i + 1, j), weight(v));
            }
            if j + 1 < side {
                edge(v, id(i, j + 1), weight(v + 3));
            }
            if i + 1 < side && j + 1 < side {
                edge(v, id(i + 1, j + 1), 0.3 * weight(v + 5));
            }
        }
    }
    m
}
