//! Sparse assembly into fixed CSC slots and a Cholesky factorisation analysed once, for the
//! systems besides the morph (heat geodesics, parameterisation) that share the VM's
//! compile-once, run-many shape.
//!
//! A [`LowerPattern`] is built once from the `(row, column)` pairs a matrix will ever hold;
//! each pair gets a slot in the values array, so filling the matrix is a scatter into known
//! positions. A [`Cholesky`] analyses the pattern once (AMD ordering, faer's supernodal or
//! simplicial choice), then factors new values and solves (one or several right-hand sides)
//! into preallocated buffers.
//!
//! ```
//! use bdmorph_vm::sparse::{Cholesky, LowerPattern};
//! // The 1D Laplacian plus identity on 4 unknowns.
//! let mut pairs = Vec::new();
//! for i in 0..4u32 {
//!     pairs.push((i, i));
//!     if i > 0 {
//!         pairs.push((i, i - 1));
//!     }
//! }
//! let (pattern, slots) = LowerPattern::new(4, &pairs)?;
//! let mut values = vec![0.0; pattern.nnz()];
//! for (&(r, c), &s) in pairs.iter().zip(&slots) {
//!     values[s as usize] += if r == c { 3.0 } else { -1.0 };
//! }
//! let mut chol = Cholesky::new(&pattern)?;
//! chol.factorize(&values)?;
//! let mut x = vec![1.0, 1.0, 1.0, 1.0];
//! chol.solve_in_place(&mut x, 1)?;
//! // Check A x = 1.
//! let ax0 = 3.0 * x[0] - x[1];
//! assert!((ax0 - 1.0).abs() < 1e-12);
//! # Ok::<(), bdmorph_vm::VmError>(())
//! ```

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use crate::VmError;

/// The lower triangle's sparsity pattern of a symmetric matrix, in CSC form.
#[derive(Clone, Debug)]
pub struct LowerPattern {
    pattern: SymbolicSparseColMat<u32>,
}

impl LowerPattern {
    /// The pattern holding every pair `(row, column)` (either triangle: `(i, j)` and `(j, i)`
    /// share a slot) of an `n` by `n` symmetric matrix, and the slot of each pair in the
    /// values array. Diagonal entries are always present. Fails when an index is out of range.
    pub fn new(n: usize, pairs: &[(u32, u32)]) -> Result<(LowerPattern, Vec<u32>), VmError> {
        if let Some(&(r, c)) = pairs
            .iter()
            .find(|&&(r, c)| r as usize >= n || c as usize >= n)
        {
            return Err(VmError::Symbolic(format!(
                "entry ({r}, {c}) is outside a {n} by {n} matrix"
            )));
        }
        // Column j holds rows i >= j: its diagonal and each pair's larger index.
        let lower = |&(r, c): &(u32, u32)| if r >= c { (r, c) } else { (c, r) };
        let mut count = vec![1u32; n];
        let mut entries: Vec<(u32, u32)> =
            pairs.iter().map(lower).filter(|(r, c)| r != c).collect();
        entries.sort_unstable_by_key(|&(r, c)| (c, r));
        entries.dedup();
        for &(_, c) in &entries {
            count[c as usize] += 1;
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0u32);
        for c in &count {
            col_ptr.push(col_ptr.last().copied().unwrap_or(0) + c);
        }
        let mut row_idx = vec![0u32; col_ptr[n] as usize];
        let mut next: Vec<u32> = col_ptr[..n].to_vec();
        for j in 0..n {
            row_idx[next[j] as usize] = j as u32;
            next[j] += 1;
        }
        for &(r, c) in &entries {
            row_idx[next[c as usize] as usize] = r;
            next[c as usize] += 1;
        }
        let pattern = SymbolicSparseColMat::<u32>::new_checked(n, n, col_ptr, None, row_idx);
        let this = LowerPattern { pattern };
        let slots = pairs
            .iter()
            .map(|p| {
                let (r, c) = lower(p);
                this.slot(r, c).expect("every pair was inserted")
            })
            .collect();
        Ok((this, slots))
    }

    /// Matrix dimension.
    pub fn dim(&self) -> usize {
        self.pattern.ncols()
    }

    /// Stored entries (the lower triangle with the diagonal).
    pub fn nnz(&self) -> usize {
        self.pattern.row_idx().len()
    }

    /// The slot of entry `(row, column)` with `row >= column`, if stored.
    pub fn slot(&self, row: u32, column: u32) -> Option<u32> {
        let c = column as usize;
        if c >= self.dim() {
            return None;
        }
        let ptr = self.pattern.col_ptr();
        let (start, end) = (ptr[c] as usize, ptr[c + 1] as usize);
        let rows = &self.pattern.row_idx()[start..end];
        rows.binary_search(&row).ok().map(|k| (start + k) as u32)
    }

    /// `y = A x` for the symmetric matrix with these lower-triangle `values`.
    pub fn symmetric_product(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        let ptr = self.pattern.col_ptr();
        let rows = self.pattern.row_idx();
        for j in 0..self.dim() {
            for k in ptr[j] as usize..ptr[j + 1] as usize {
                let i = rows[k] as usize;
                y[i] += values[k] * x[j];
                if i != j {
                    y[j] += values[k] * x[i];
                }
            }
        }
    }
}

/// A Cholesky factorisation `A = L Lᵀ` of matrices with one fixed pattern: analysed once,
/// factored and solved into preallocated buffers.
pub struct Cholesky {
    pattern: SymbolicSparseColMat<u32>,
    symbolic: SymbolicCholesky<u32>,
    factor: Vec<f64>,
    workspace: MemBuffer,
    /// Right-hand sides the workspace holds room for.
    columns: usize,
    ready: bool,
}

impl std::fmt::Debug for Cholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Cholesky")
            .field("dim", &self.pattern.ncols())
            .field("factor_nnz", &self.factor.len())
            .field("ready", &self.ready)
            .finish_non_exhaustive()
    }
}

impl Cholesky {
    /// Analyses `pattern` (AMD ordering) and allocates the factor and a workspace for solves
    /// with one right-hand side at a time.
    pub fn new(pattern: &LowerPattern) -> Result<Cholesky, VmError> {
        let pattern = pattern.pattern.clone();
        let symbolic = factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| VmError::Symbolic(format!("{e:?}")))?;
        let factor = vec![0.0; symbolic.len_val()];
        let mut this = Cholesky {
            pattern,
            symbolic,
            factor,
            workspace: MemBuffer::new(StackReq::EMPTY),
            columns: 0,
            ready: false,
        };
        this.reserve_columns(1)?;
        crate::newton::warm_up_dense_kernels();
        Ok(this)
    }

    /// Assembles the symmetric `n` by `n` matrix whose entry `pairs[k]` (either triangle)
    /// receives `values[k]` (entries of one slot add up: give each off-diagonal pair once),
    /// analyses it, makes room for solves with `columns` right-hand sides, and factors it.
    pub fn assemble(
        n: usize,
        pairs: &[(u32, u32)],
        values: &[f64],
        columns: usize,
    ) -> Result<Cholesky, VmError> {
        if pairs.len() != values.len() {
            return Err(VmError::Length {
                what: "entry values",
                expected: pairs.len(),
                got: values.len(),
            });
        }
        let (pattern, slots) = LowerPattern::new(n, pairs)?;
        let mut matrix = vec![0.0; pattern.nnz()];
        for (s, v) in slots.iter().zip(values) {
            matrix[*s as usize] += v;
        }
        let mut chol = Cholesky::new(&pattern)?;
        chol.reserve_columns(columns)?;
        chol.factorize(&matrix)?;
        Ok(chol)
    }

    /// Makes room in the workspace for solves with up to `columns` right-hand sides at once
    /// (allocates only when it grows).
    pub fn reserve_columns(&mut self, columns: usize) -> Result<(), VmError> {
        if columns <= self.columns {
            return Ok(());
        }
        let req = StackReq::any_of(&[
            self.symbolic
                .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            self.symbolic
                .solve_in_place_scratch::<f64>(columns, Par::Seq),
        ]);
        self.workspace =
            MemBuffer::try_new(req).map_err(|e| VmError::Symbolic(format!("{e:?}")))?;
        self.columns = columns;
        Ok(())
    }

    /// Matrix dimension.
    pub fn dim(&self) -> usize {
        self.pattern.ncols()
    }

    /// Entries of the factor `L`.
    pub fn factor_nnz(&self) -> usize {
        self.factor.len()
    }

    /// Factors the matrix with these lower-triangle `values` (one per slot of the pattern).
    /// Allocates nothing. Fails with [`VmError::NotPositiveDefinite`] when it is not
    /// numerically positive definite, or [`VmError::Length`] for a wrong number of values.
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), VmError> {
        self.ready = false;
        if values.len() != self.pattern.row_idx().len() {
            return Err(VmError::Length {
                what: "matrix values",
                expected: self.pattern.row_idx().len(),
                got: values.len(),
            });
        }
        crate::factor::numeric_llt(
            &self.symbolic,
            &mut self.factor,
            SparseColMatRef::new(self.pattern.as_ref(), values),
            &mut self.workspace,
        )?;
        self.ready = true;
        Ok(())
    }

    /// Solves `A X = B` in place for `columns` right-hand sides stored one after another
    /// (column-major, `dim` values each). Allocates nothing when the workspace has room for
    /// that many columns ([`Cholesky::reserve_columns`]), and grows it otherwise.
    pub fn solve_in_place(&mut self, rhs: &mut [f64], columns: usize) -> Result<(), VmError> {
        if !self.ready {
            return Err(VmError::NoFactor);
        }
        let n = self.dim();
        if rhs.len() != n * columns {
            return Err(VmError::Length {
                what: "right-hand sides",
                expected: n * columns,
                got: rhs.len(),
            });
        }
        self.reserve_columns(columns)?;
        let llt = LltRef::new(&self.symbolic, &self.factor);
        let stack = MemStack::new(&mut self.workspace);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, columns),
            Par::Seq,
            stack,
        );
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn assemble_sums_entries_and_factors() {
        // [[2, -1], [-1, 2]] given as diagonal halves and one off-diagonal entry.
        let pairs = [(0, 0), (0, 0), (1, 1), (0, 1)];
        let values = [1.0, 1.0, 2.0, -1.0];
        let mut chol = Cholesky::assemble(2, &pairs, &values, 1).expect("SPD");
        let mut x = vec![1.0, 1.0];
        chol.solve_in_place(&mut x, 1).expect("solve");
        assert!(
            (x[0] - 1.0).abs() < 1e-14 && (x[1] - 1.0).abs() < 1e-14,
            "{x:?}"
        );
        assert!(matches!(
            Cholesky::assemble(2, &pairs, &values[..3], 1),
            Err(VmError::Length { .. })
        ));
    }

    #[test]
    fn pattern_slots_are_shared_by_symmetric_pairs_and_sorted() {
        let pairs = [(0, 1), (1, 0), (2, 0), (1, 1), (2, 2)];
        let (p, slots) = LowerPattern::new(3, &pairs).expect("pattern");
        assert_eq!(p.nnz(), 5); // 3 diagonal + (1, 0) + (2, 0)
        assert_eq!(slots[0], slots[1]);
        assert_eq!(p.slot(1, 0), Some(slots[0]));
        assert_eq!(p.slot(2, 1), None);
        assert!(LowerPattern::new(3, &[(3, 0)]).is_err());
    }

    #[test]
    fn solves_match_a_dense_check_for_several_columns() {
        // A random sparse SPD matrix: a grid Laplacian plus a diagonal.
        let n = 30u32;
        let mut pairs = Vec::new();
        for i in 0..n {
            pairs.push((i, i));
            if i % 5 != 0 {
                pairs.push((i, i - 1));
            }
            if i >= 5 {
                pairs.push((i, i - 5));
            }
        }
        let (p, slots) = LowerPattern::new(n as usize, &pairs).expect("pattern");
        let mut values = vec![0.0; p.nnz()];
        for (&(r, c), &s) in pairs.iter().zip(&slots) {
            values[s as usize] += if r == c { 4.5 + f64::from(r % 3) } else { -1.0 };
        }
        let mut chol = Cholesky::new(&p).expect("analysed");
        assert!(matches!(
            chol.solve_in_place(&mut [0.0; 30], 1),
            Err(VmError::NoFactor)
        ));
        chol.factorize(&values).expect("SPD");
        let b: Vec<f64> = (0..2 * n).map(|i| f64::from(i % 7) - 3.0).collect();
        let mut x = b.clone();
        chol.solve_in_place(&mut x, 2).expect("solve");
        let mut ax = vec![0.0; n as usize];
        for k in 0..2 {
            let range = k * n as usize..(k + 1) * n as usize;
            p.symmetric_product(&values, &x[range.clone()], &mut ax);
            for (a, bb) in ax.iter().zip(&b[range]) {
                assert!((a - bb).abs() < 1e-12, "{a} vs {bb}");
            }
        }
        // Not positive definite: a typed error.
        let negative: Vec<f64> = values.iter().map(|v| -v).collect();
        assert!(matches!(
            chol.factorize(&negative),
            Err(VmError::NotPositiveDefinite { .. })
        ));
    }
}
