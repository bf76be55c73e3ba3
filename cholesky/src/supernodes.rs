//! The shape of a supernodal Cholesky factor, read once from faer's symbolic factorisation
//! into flat arrays and checked, for the engine's own loops over it (the numeric factorisation in
//! [`crate::numeric`], the triangular solves in [`crate::triangular`]).
//!
//! The values follow faer's layout: supernode `s` owns the columns `begin..begin + width` of
//! the permuted matrix and stores a column-major block of `width + height` rows and `width`
//! columns at `values_start`: first its diagonal block (whose upper triangle is unused), then
//! the rows below, whose indices are `rows[rows_start..rows_start + height]`.

use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};

/// One supernode's shape.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Supernode {
    /// Its first column (in the permuted numbering).
    pub begin: u32,
    /// Its number of columns.
    pub width: u32,
    /// Where its below-diagonal row indices start in [`Supernodes::rows`].
    pub rows_start: u32,
    /// How many rows it has below its diagonal block.
    pub height: u32,
    /// Where its values (a column-major `(width + height) x width` block) start.
    pub values_start: usize,
}

impl Supernode {
    /// One past its last column.
    pub fn end(&self) -> usize {
        (self.begin + self.width) as usize
    }

    /// Rows of its block, the leading dimension of its values.
    pub fn ld(&self) -> usize {
        (self.width + self.height) as usize
    }

    /// Its values' range.
    pub fn values(&self) -> std::ops::Range<usize> {
        self.values_start..self.values_start + self.ld() * self.width as usize
    }
}

/// A checked, flattened supernodal structure.
#[derive(Clone, Debug)]
pub(crate) struct Supernodes {
    /// The supernodes, in column order.
    pub list: Vec<Supernode>,
    /// Below-diagonal row indices of every supernode, in the permuted numbering.
    pub rows: Vec<u32>,
    /// The fill-reducing permutation: `perm[new] = old`.
    pub perm: Vec<u32>,
    /// Values the factor holds.
    pub len_val: usize,
}

impl Supernodes {
    /// The structure of `symbolic`, or `None` when it is not supernodal or fails a check: the
    /// supernodes tile the columns in order, each block's size matches its values, the values
    /// tile `0..len_val`, every supernode's rows below its diagonal block are strictly
    /// increasing and within the matrix, and the permutation is one. Loops that index by
    /// these fields then stay within `n` and `len_val`.
    pub fn new(symbolic: &SymbolicCholesky<u32>) -> Option<Supernodes> {
        let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() else {
            return None;
        };
        let n = symbolic.nrows();
        let perm = match symbolic.perm() {
            Some(p) => p.arrays().0.to_vec(),
            None => (0..n as u32).collect(),
        };
        let mut seen = vec![false; n];
        for &p in &perm {
            if std::mem::replace(seen.get_mut(p as usize)?, true) {
                return None;
            }
        }
        if perm.len() != n {
            return None;
        }
        let (begin, end) = (s.supernode_begin(), s.supernode_end());
        let (row_ptr, val_ptr) = (s.col_ptr_for_row_idx(), s.col_ptr_for_val());
        let mut list = Vec::with_capacity(begin.len());
        let mut next = 0u32;
        for k in 0..begin.len() {
            let (b, e) = (begin[k], end[k]);
            let (r0, r1) = (*row_ptr.get(k)?, *row_ptr.get(k + 1)?);
            let (v0, v1) = (*val_ptr.get(k)? as usize, *val_ptr.get(k + 1)? as usize);
            let (width, height) = (e.checked_sub(b)?, r1.checked_sub(r0)?);
            if b != next || width == 0 || e as usize > n {
                return None;
            }
            next = e;
            let size = (width as usize + height as usize).checked_mul(width as usize)?;
            if v1.checked_sub(v0)? != size {
                return None;
            }
            let rows = s.row_idx().get(r0 as usize..r1 as usize)?;
            let increasing = rows.windows(2).all(|w| w[0] < w[1]);
            if !increasing || rows.first().is_some_and(|&r| r < e) {
                return None;
            }
            if rows.last().is_some_and(|&r| r as usize >= n) {
                return None;
            }
            list.push(Supernode {
                begin: b,
                width,
                rows_start: r0,
                height,
                values_start: v0,
            });
        }
        let tiled =
            val_ptr.first() == Some(&0) && val_ptr.last().map(|&v| v as usize) == Some(s.len_val());
        if next as usize != n || !tiled {
            return None;
        }
        Some(Supernodes {
            list,
            rows: s.row_idx().to_vec(),
            perm,
            len_val: s.len_val(),
        })
    }

    /// Number of columns (unknowns).
    pub fn n(&self) -> usize {
        self.perm.len()
    }

    /// The rows of supernode `s` below its diagonal block.
    pub fn rows_of(&self, s: &Supernode) -> &[u32] {
        &self.rows[s.rows_start as usize..(s.rows_start + s.height) as usize]
    }
}
