//! The symbolic analysis of a pattern, done once: a fill-reducing ordering, faer's symbolic
//! Cholesky factorisation (supernodal or simplicial), and everything the numeric
//! factorisations and solves that follow need that does not depend on the values.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, StackReq};
use faer::linalg::matmul::matmul;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::{Accum, Mat, Par, Side};

use crate::numeric::{Pivots, SupernodalLlt};
use crate::supernodes::Supernodes;
use crate::{CholeskyError, LowerPattern};

/// The fill-reducing ordering of the unknowns.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Ordering {
    /// Approximate minimum degree, computed from the pattern (faer's).
    #[default]
    Amd,
    /// A caller's permutation `perm[new] = old` (the unknown eliminated `new`-th), for
    /// instance a nested dissection computed from the mesh's geometry. Checked to be one.
    Custom(Vec<u32>),
}

/// Whether the factor is supernodal (dense blocks of columns, the engine's own register-tiled
/// kernels) or simplicial (column by column, faer's).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Supernodal {
    /// The engine's choice, today always supernodal. With faer's kernels on both sides,
    /// simplicial was faster below about 3K unknowns on mesh matrices (faer's own default
    /// keeps it up to about 15K); the engine's supernodal factorisation is faster from 36
    /// unknowns up (Laplacians of grids with AMD, fastest of 40 runs: 0.005 against 0.007 ms
    /// at 100 unknowns, 0.094 against 0.189 ms at 1K, 1.7 against 6.6-7.0 ms at 10K, 46
    /// against 288-290 ms at 100K), and its solves are within a few microseconds of faer's
    /// simplicial ones below 1K unknowns and faster at 10K (0.30 against 0.37 ms). Only
    /// solve-bound uses of factors beyond about 50K unknowns would gain from a simplicial
    /// factor, whose solves stream fewer stored values (at 100K, 7.1-7.5 against 9.1-9.5 ms;
    /// the factorisation takes six times longer): ask for [`Supernodal::Never`] there.
    #[default]
    Auto,
    /// Always supernodal (but for a factor with nothing below its diagonal, such as a
    /// diagonal matrix's, which faer keeps simplicial).
    Always,
    /// Always simplicial.
    Never,
}

/// Estimated work of one numeric factorisation and of one solve with it (multiply-adds),
/// from the factor's structure; the VM's cost model compares them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FactorCost {
    /// Multiply-adds of a numeric factorisation.
    pub factor: f64,
    /// Multiply-adds of one solve (both triangles) with one right-hand side.
    pub solve: f64,
    /// Whether the factor is supernodal.
    pub supernodal: bool,
}

/// Everything worked out once per pattern.
pub(crate) struct Analysis {
    pub symbolic: SymbolicCholesky<u32>,
    /// The checked supernodal structure (`None` when simplicial).
    pub structure: Option<Arc<Supernodes>>,
    /// The engine's own numeric factorisation plan (`None` when simplicial, or when the
    /// factor is too large for its 32-bit indices: faer factors then).
    pub plan: Option<SupernodalLlt>,
    /// Per column of the factor (permuted order), where its diagonal entry `L_jj` is stored.
    pub diag_at: Vec<usize>,
    /// Per column of the factor, the slot of the matrix's diagonal entry in that column.
    pub diag_slot: Vec<u32>,
    /// Per column of the factor, `4 k` for `k` the entries of its row of `L`: a pivot no
    /// larger than `4 k eps` times its diagonal entry is within the rounding error of the
    /// `k` terms subtracted from it (see `check_pivots` in `factor.rs`).
    pub pivot_scale: Vec<f64>,
}

impl Analysis {
    pub fn new(
        pattern: &LowerPattern,
        ordering: &Ordering,
        supernodal: Supernodal,
    ) -> Result<Analysis, CholeskyError> {
        let n = pattern.dim();
        let inverse = match ordering {
            Ordering::Amd => None,
            Ordering::Custom(fwd) => Some(inverse_permutation(fwd, n)?),
        };
        let order = match (ordering, &inverse) {
            (Ordering::Custom(fwd), Some(inv)) => {
                SymmetricOrdering::Custom(PermRef::new_checked(fwd, inv, n))
            }
            _ => SymmetricOrdering::Amd,
        };
        let threshold = match supernodal {
            Supernodal::Auto | Supernodal::Always => SupernodalThreshold::FORCE_SUPERNODAL,
            Supernodal::Never => SupernodalThreshold::FORCE_SIMPLICIAL,
        };
        let symbolic = factorize_symbolic_cholesky(
            pattern.pattern.as_ref(),
            Side::Lower,
            order,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: threshold,
                ..Default::default()
            },
        )
        .map_err(|e| CholeskyError::Symbolic(format!("{e:?}")))?;
        let perm: Vec<u32> = match symbolic.perm() {
            Some(p) => p.arrays().0.to_vec(),
            None => (0..n as u32).collect(),
        };
        let inconsistent =
            |what: &str| CholeskyError::Symbolic(format!("faer's symbolic factor: {what}"));
        let diag_slot = perm
            .iter()
            .map(|&old| pattern.diagonal_slots().get(old as usize).copied())
            .collect::<Option<Vec<u32>>>()
            .ok_or_else(|| inconsistent("a permutation index out of range"))?;
        let mut count = vec![0u32; n];
        let (structure, diag_at) = match symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(_) => {
                let st = Supernodes::new(&symbolic)
                    .ok_or_else(|| inconsistent("the supernodes failed their checks"))?;
                let mut diag_at = vec![0usize; n];
                for s in &st.list {
                    let (b, w) = (s.begin as usize, s.width as usize);
                    for c in 0..w {
                        diag_at[b + c] = s.values_start + c * s.ld() + c;
                        count[b + c] += c as u32 + 1;
                    }
                    for &r in st.rows_of(s) {
                        count[r as usize] += w as u32;
                    }
                }
                (Some(Arc::new(st)), diag_at)
            }
            SymbolicCholeskyRaw::Simplicial(s) => {
                let (ptr, rows) = (s.col_ptr(), s.row_idx());
                if ptr.len() != n + 1 || ptr[n] as usize != rows.len() {
                    return Err(inconsistent("column offsets"));
                }
                let mut diag_at = vec![0usize; n];
                for j in 0..n {
                    let col = rows
                        .get(ptr[j] as usize..ptr[j + 1] as usize)
                        .ok_or_else(|| inconsistent("column offsets"))?;
                    // faer stores each column's diagonal entry first.
                    if col.first() != Some(&(j as u32)) || col.iter().any(|&r| r as usize >= n) {
                        return Err(inconsistent("a column without its diagonal first"));
                    }
                    diag_at[j] = ptr[j] as usize;
                    for &r in col {
                        count[r as usize] += 1;
                    }
                }
                (None, diag_at)
            }
        };
        let plan = structure
            .clone()
            .and_then(|st| SupernodalLlt::new(st, pattern.col_ptr(), pattern.row_idx()));
        if structure.is_some() && plan.is_none() {
            warm_up_dense_kernels();
        }
        Ok(Analysis {
            symbolic,
            structure,
            plan,
            diag_at,
            diag_slot,
            pivot_scale: count.iter().map(|&k| 4.0 * f64::from(k.max(1))).collect(),
        })
    }

    /// Workspace for faer's numeric factorisation and solve with `columns` right-hand sides,
    /// in double and (when `single`) single precision.
    pub fn workspace(&self, columns: usize, single: bool) -> Result<MemBuffer, CholeskyError> {
        let s = &self.symbolic;
        let mut req = vec![
            s.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            s.solve_in_place_scratch::<f64>(columns, Par::Seq),
        ];
        if single {
            req.push(s.factorize_numeric_llt_scratch::<f32>(Par::Seq, Default::default()));
            req.push(s.solve_in_place_scratch::<f32>(columns, Par::Seq));
        }
        MemBuffer::try_new(StackReq::any_of(&req))
            .map_err(|e| CholeskyError::Symbolic(format!("workspace: {e:?}")))
    }

    /// The pivot rule of the engine's factorisation, writing the diagonal's reciprocals into
    /// `inv_diag`.
    pub fn pivots<'a>(&'a self, inv_diag: &'a mut [f64]) -> Pivots<'a> {
        Pivots {
            slot: &self.diag_slot,
            scale: &self.pivot_scale,
            floor: self.diag_at.len() as f64,
            inv_diag,
        }
    }

    /// The work of a factorisation and of a solve, estimated from the structure.
    pub fn cost(&self) -> FactorCost {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let (mut factor, mut solve) = (0.0, 0.0);
                for w in s.col_ptr().windows(2) {
                    let c = f64::from(w[1] - w[0]);
                    factor += 0.5 * c * (c + 1.0);
                    solve += 2.0 * c;
                }
                FactorCost {
                    factor,
                    solve,
                    supernodal: false,
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let (mut factor, mut solve) = (0.0, 0.0);
                let rows = s.col_ptr_for_row_idx();
                for (k, (&b, &e)) in s
                    .supernode_begin()
                    .iter()
                    .zip(s.supernode_end())
                    .enumerate()
                {
                    let w = f64::from(e - b);
                    let h = f64::from(rows[k + 1] - rows[k]);
                    factor += w * w * w / 6.0 + 0.5 * h * w * w + 0.5 * h * h * w;
                    solve += w * w + 2.0 * h * w;
                }
                FactorCost {
                    factor,
                    solve,
                    supernodal: true,
                }
            }
        }
    }
}

/// `perm`'s inverse, when it is a permutation of `0..n`.
fn inverse_permutation(perm: &[u32], n: usize) -> Result<Vec<u32>, CholeskyError> {
    let bad = || CholeskyError::Pattern(format!("the ordering is not a permutation of 0..{n}"));
    if perm.len() != n {
        return Err(bad());
    }
    let mut inverse = vec![u32::MAX; n];
    for (new, &old) in perm.iter().enumerate() {
        let slot = inverse.get_mut(old as usize).ok_or_else(bad)?;
        if *slot != u32::MAX {
            return Err(bad());
        }
        *slot = new as u32;
    }
    Ok(inverse)
}

/// faer's dense matrix products, which its supernodal factorisation uses, allocate a
/// workspace per thread on first use (twice the L3 cache's size; its packing differs for
/// products of at most 48 rows and of more). Two small products here make that allocation
/// on the thread that analyses the pattern rather than in its first factorisation. Only
/// where faer factors supernodally: the engine's own factorisation calls none of them (and
/// these products leave the vector registers' upper halves dirty, which slows the C
/// library's `log` 7-8× until the next AVX code clears them).
pub(crate) fn warm_up_dense_kernels() {
    let b = Mat::<f64>::zeros(64, 64);
    for rows in [32, 64] {
        let a = Mat::<f64>::zeros(rows, 64);
        let mut c = Mat::<f64>::zeros(rows, 64);
        matmul(&mut c, Accum::Replace, &a, &b, 1.0, Par::Seq);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orderings_must_be_permutations() {
        assert_eq!(inverse_permutation(&[2, 0, 1], 3), Ok(vec![1, 2, 0]));
        for bad in [&[0, 0, 1][..], &[0, 1][..], &[0, 1, 3][..]] {
            assert!(matches!(
                inverse_permutation(bad, 3),
                Err(CholeskyError::Pattern(_))
            ));
        }
    }
}
