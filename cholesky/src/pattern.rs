//! The lower triangle's sparsity pattern of a symmetric matrix, in CSC form, with a fixed
//! slot per stored entry: filling the matrix is a scatter into known positions.

use faer::sparse::SymbolicSparseColMat;

use crate::CholeskyError;

/// The lower triangle's sparsity pattern of a symmetric `n` by `n` matrix, in CSC form: in
/// each column, its diagonal first, then the rows below it, increasing. The values of a matrix
/// with this pattern are one `f64` per stored entry (a *slot*), column after column.
#[derive(Clone, Debug)]
pub struct LowerPattern {
    pub(crate) pattern: SymbolicSparseColMat<u32>,
}

impl LowerPattern {
    /// The pattern holding every pair `(row, column)` (either triangle: `(i, j)` and `(j, i)`
    /// share a slot) of an `n` by `n` symmetric matrix, and the slot of each pair in the
    /// values array. Diagonal entries are always present. Fails with
    /// [`CholeskyError::Pattern`] when an index is out of range.
    pub fn new(n: usize, pairs: &[(u32, u32)]) -> Result<(LowerPattern, Vec<u32>), CholeskyError> {
        check_size(n)?;
        if let Some(&(r, c)) = pairs
            .iter()
            .find(|&&(r, c)| r as usize >= n || c as usize >= n)
        {
            return Err(CholeskyError::Pattern(format!(
                "entry ({r}, {c}) is outside a {n} by {n} matrix"
            )));
        }
        // Column j holds rows i >= j: its diagonal and each pair's larger index.
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
            let next = col_ptr[col_ptr.len() - 1]
                .checked_add(*c)
                .ok_or_else(too_many)?;
            col_ptr.push(next);
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
        let mut slots = Vec::with_capacity(pairs.len());
        for p in pairs {
            let (r, c) = lower(p);
            // Every pair was inserted above.
            slots.push(this.slot(r, c).ok_or_else(|| {
                CholeskyError::Pattern(format!("entry ({r}, {c}) was not stored"))
            })?);
        }
        Ok((this, slots))
    }

    /// The pattern given in CSC form: `col_ptr` (`n + 1` offsets) and `row_idx`, each column
    /// starting with its diagonal entry and then rows strictly increasing below it. Checks all
    /// of that, and fails with [`CholeskyError::Pattern`] naming the first column that breaks
    /// it.
    pub fn from_csc(
        n: usize,
        col_ptr: Vec<u32>,
        row_idx: Vec<u32>,
    ) -> Result<LowerPattern, CholeskyError> {
        check_size(n)?;
        let bad = |j: usize, why: &str| CholeskyError::Pattern(format!("column {j}: {why}"));
        if col_ptr.len() != n + 1 || col_ptr[0] != 0 || col_ptr[n] as usize != row_idx.len() {
            return Err(CholeskyError::Pattern(format!(
                "{} column offsets ending at {} for {n} columns and {} row indices",
                col_ptr.len(),
                col_ptr.last().copied().unwrap_or(0),
                row_idx.len()
            )));
        }
        for j in 0..n {
            let (a, b) = (col_ptr[j] as usize, col_ptr[j + 1] as usize);
            if a >= b || b > row_idx.len() {
                return Err(bad(j, "no diagonal entry (or decreasing offsets)"));
            }
            let rows = &row_idx[a..b];
            if rows[0] as usize != j {
                return Err(bad(j, "does not start with its diagonal entry"));
            }
            if !rows.windows(2).all(|w| w[0] < w[1]) {
                return Err(bad(j, "rows are not strictly increasing"));
            }
            if rows[rows.len() - 1] as usize >= n {
                return Err(bad(j, "a row index is outside the matrix"));
            }
        }
        let pattern = SymbolicSparseColMat::<u32>::new_checked(n, n, col_ptr, None, row_idx);
        Ok(LowerPattern { pattern })
    }

    /// Matrix dimension.
    pub fn dim(&self) -> usize {
        self.pattern.ncols()
    }

    /// Stored entries (the lower triangle with the diagonal): the length of a values array.
    pub fn nnz(&self) -> usize {
        self.pattern.row_idx().len()
    }

    /// Column offsets into [`LowerPattern::row_idx`] (`dim + 1` of them).
    pub fn col_ptr(&self) -> &[u32] {
        self.pattern.col_ptr()
    }

    /// The row of every slot, column after column (each column's diagonal first).
    pub fn row_idx(&self) -> &[u32] {
        self.pattern.row_idx()
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

    /// The slot of each diagonal entry (the first of its column).
    pub fn diagonal_slots(&self) -> &[u32] {
        &self.pattern.col_ptr()[..self.dim()]
    }

    /// `y = A x` for the symmetric matrix with these lower-triangle `values` (one per slot).
    ///
    /// # Panics
    /// When `values`, `x` or `y` do not have the pattern's sizes.
    pub fn symmetric_product(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        let (ptr, rows) = (self.pattern.col_ptr(), self.pattern.row_idx());
        assert!(values.len() == rows.len() && x.len() == self.dim() && y.len() == self.dim());
        y.fill(0.0);
        for j in 0..x.len() {
            let (start, end) = (ptr[j] as usize, ptr[j + 1] as usize);
            let xj = x[j];
            // The diagonal first, then the rows below.
            let mut acc = values[start] * xj;
            for slot in start + 1..end {
                let i = rows[slot] as usize;
                let v = values[slot];
                y[i] += v * xj;
                acc += v * x[i];
            }
            y[j] += acc;
        }
    }
}

/// `(row, column)` with the row at or below the column.
fn lower(&(r, c): &(u32, u32)) -> (u32, u32) {
    if r >= c {
        (r, c)
    } else {
        (c, r)
    }
}

fn too_many() -> CholeskyError {
    CholeskyError::Pattern("more than 2^32 stored entries".into())
}

fn check_size(n: usize) -> Result<(), CholeskyError> {
    if u32::try_from(n).is_err() {
        return Err(CholeskyError::Pattern(format!(
            "{n} columns: at most 2^32 - 1 are supported"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slots_are_shared_by_symmetric_pairs_and_sorted() {
        let pairs = [(0, 1), (1, 0), (2, 0), (1, 1), (2, 2)];
        let (p, slots) = LowerPattern::new(3, &pairs).expect("pattern");
        assert_eq!(p.nnz(), 5); // 3 diagonal + (1, 0) + (2, 0)
        assert_eq!(slots[0], slots[1]);
        assert_eq!(p.slot(1, 0), Some(slots[0]));
        assert_eq!(p.slot(2, 1), None);
        assert_eq!(p.diagonal_slots(), &[0, 3, 4]);
        assert!(matches!(
            LowerPattern::new(3, &[(3, 0)]),
            Err(CholeskyError::Pattern(_))
        ));
    }

    #[test]
    fn csc_input_is_checked() {
        let ok = LowerPattern::from_csc(2, vec![0, 2, 3], vec![0, 1, 1]).expect("valid");
        assert_eq!(ok.nnz(), 3);
        for (ptr, rows) in [
            (vec![0, 2, 3], vec![1, 0, 1]),    // diagonal not first
            (vec![0, 1, 1], vec![0]),          // column 1 empty
            (vec![0, 2, 3], vec![0, 2, 1]),    // row out of range
            (vec![0, 3, 4], vec![0, 1, 1, 1]), // repeated row
            (vec![0, 2], vec![0, 1]),          // too few offsets
        ] {
            assert!(
                matches!(
                    LowerPattern::from_csc(2, ptr.clone(), rows.clone()),
                    Err(CholeskyError::Pattern(_))
                ),
                "{ptr:?} {rows:?}"
            );
        }
    }

    #[test]
    fn the_product_uses_both_triangles() {
        // [[4, 1, 0], [1, 3, 2], [0, 2, 5]] stored as its lower triangle.
        let (p, slots) =
            LowerPattern::new(3, &[(0, 0), (1, 0), (1, 1), (2, 1), (2, 2)]).expect("pattern");
        let mut values = vec![0.0; p.nnz()];
        for (s, v) in slots.iter().zip([4.0, 1.0, 3.0, 2.0, 5.0]) {
            values[*s as usize] = v;
        }
        let mut y = [0.0; 3];
        p.symmetric_product(&values, &[1.0, 2.0, 3.0], &mut y);
        assert_eq!(y, [6.0, 13.0, 19.0]);
    }
}
