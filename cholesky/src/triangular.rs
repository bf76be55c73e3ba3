//! The two triangular solves with a supernodal Cholesky factor, `x = P^T L^-T L^-1 P x`, as
//! one flat loop over the supernodes.
//!
//! faer's own solve calls its general dense triangular solve and matrix product once per
//! supernode, whose set-up costs about as much as the arithmetic of the small supernodes that
//! a nested-dissection ordering of a mesh makes (at 10K unknowns, 804 supernodes, most of 8
//! to 31 columns). Here the supernodes' shapes are read once from the symbolic factorisation
//! into a flat array, and each supernode is a few short loops over its column-major block:
//! its diagonal triangle (multiplying by reciprocals of the diagonal read once per
//! factorisation, not dividing), then a product with the rows below, four columns at a time.
//! The backward sweep reads each supernode's block from its end to its start, so that it
//! descends through memory as the forward sweep ascends: reading each block forwards while
//! stepping back from block to block restarted the processor's prefetching at every
//! supernode, and the backward sweep took three times the forward one's profile samples.
//! Descending took about a tenth off the solve (fastest runs against faer's in the same
//! process, `examples/factorization.rs`: 0.74 → 0.65-0.68 of faer's time at 10K unknowns in
//! double precision, 0.83 → 0.76 in single; about 0.95 → 0.85 at 100K, where the solve is
//! near the memory's bandwidth). Before that, criterion medians put it at 0.54, 0.66 and
//! 0.65 of faer's time at 1K, 10K and 100K unknowns with a double-precision factor, 0.58,
//! 0.64 and 0.74 with a single-precision one. The factor may be stored in single precision;
//! the arithmetic is in double precision either way (no rounding of the right side to
//! `f32`). Compiled for the baseline x86-64; a build of the
//! loops with AVX2 and FMA (runtime dispatch) measured no faster: they wait on the chains of
//! the diagonal triangles and the gathers, not on arithmetic.
//!
//! Several right-hand sides are solved in blocks of [`BLOCK`] (then two, then one), the
//! values of a row side by side, so that each block reads the factor once: four columns at
//! 10K unknowns took 0.78 ms against 2.0 ms one by one (faer's four-column solve 1.16 ms).
//! Every right-hand side goes through the same operations in the same order whatever block
//! it is solved in, so its solution does not depend on how many are solved at once, to the
//! last bit.

use std::sync::Arc;

use crate::supernodes::Supernodes;

/// Right-hand sides solved together by [`SupernodalSolve::solve_many`]: each block of them
/// reads the factor once.
pub(crate) const BLOCK: usize = 4;

/// The supernodal structure of a factor and the solves' work buffers.
#[derive(Clone, Debug)]
pub(crate) struct SupernodalSolve {
    structure: Arc<Supernodes>,
    /// The right sides in the permuted numbering, a row's values side by side.
    y: Vec<f64>,
    /// One supernode's values of `y`: below its diagonal block, to scatter (forward), or its
    /// own then those below, gathered (backward); a row's values side by side.
    below: Vec<f64>,
    /// The reciprocals of the factor's diagonal, set by [`SupernodalSolve::prepare`].
    inv_diag: Vec<f64>,
    /// Right-hand sides the buffers hold room for at once (1 to [`BLOCK`]).
    width: usize,
    /// Per permuted column, its supernode.
    owner: Vec<u32>,
    /// Per supernode, its parent in the supernodal elimination tree (the supernode of its
    /// first row below the diagonal block), or [`NO_PARENT`] for a root.
    parent: Vec<u32>,
    /// Per original row, its permuted column.
    inverse: Vec<u32>,
    /// The supernodes a sparse right-hand side reaches (see
    /// [`SupernodalSolve::solve_many_sparse`]), and a mark per supernode.
    reached: Vec<u32>,
    marked: Vec<bool>,
}

/// The parent of a root supernode.
const NO_PARENT: u32 = u32::MAX;

impl SupernodalSolve {
    /// Solves with factors of the checked `structure` (so they index only within its bounds),
    /// with room for one right-hand side at a time.
    pub fn new(structure: Arc<Supernodes>) -> SupernodalSolve {
        let n = structure.n();
        let mut owner = vec![0u32; n];
        for (k, s) in structure.list.iter().enumerate() {
            owner[s.begin as usize..s.end()].fill(k as u32);
        }
        // Rows below a diagonal block lie in later supernodes (checked by `Supernodes`), so
        // the parents point forwards and every path ends.
        let parent = structure
            .list
            .iter()
            .map(|s| {
                structure
                    .rows_of(s)
                    .first()
                    .map_or(NO_PARENT, |&r| owner[r as usize])
            })
            .collect();
        let mut inverse = vec![0u32; n];
        for (new, &old) in structure.perm.iter().enumerate() {
            inverse[old as usize] = new as u32;
        }
        let supernodes = structure.list.len();
        SupernodalSolve {
            y: vec![0.0; n],
            below: vec![0.0; tallest(&structure)],
            inv_diag: vec![0.0; n],
            width: 1,
            owner,
            parent,
            inverse,
            reached: Vec::with_capacity(supernodes),
            marked: vec![false; supernodes],
            structure,
        }
    }

    /// Makes room for solves with `columns` right-hand sides at once (blocks of up to
    /// [`BLOCK`]).
    pub fn reserve(&mut self, columns: usize) {
        let c = columns.clamp(1, BLOCK);
        if c > self.width {
            self.y = vec![0.0; self.structure.n() * c];
            self.below = vec![0.0; tallest(&self.structure) * c];
            self.width = c;
        }
    }

    /// The reciprocals of the factor's diagonal, for the factorisation to write (see
    /// [`crate::numeric::Pivots`]) instead of [`SupernodalSolve::prepare`].
    pub fn inv_diag_mut(&mut self) -> &mut [f64] {
        &mut self.inv_diag
    }

    /// Reads the reciprocals of the diagonal of the factor `values`, which the solves with it
    /// multiply by: a division in their chain of dependent operations costs several times a
    /// multiplication. Call after every factorisation, before solving with it.
    pub fn prepare<T: Copy + Into<f64>>(&mut self, values: &[T]) {
        assert_eq!(
            values.len(),
            self.structure.len_val,
            "a factor of this structure"
        );
        for s in &self.structure.list {
            let (b, w) = (s.begin as usize, s.width as usize);
            let ld = w + s.height as usize;
            for (j, inv) in self.inv_diag[b..b + w].iter_mut().enumerate() {
                *inv = 1.0 / values[s.values_start + j * ld + j].into();
            }
        }
    }

    /// `x = P^T L^-T L^-1 P x` for `columns` right-hand sides stored one after another in `x`
    /// (`n` values each), with `values`, the factor's values in faer's supernodal layout
    /// (each supernode a column-major block of `width + height` rows and `width` columns, its
    /// diagonal block's upper triangle unused), prepared by [`SupernodalSolve::prepare`]; in
    /// blocks of up to [`BLOCK`] (as many as [`SupernodalSolve::reserve`] made room for).
    pub fn solve_many<T: Copy + Into<f64>>(&mut self, values: &[T], x: &mut [f64], columns: usize) {
        self.solve_columns(values, x, columns, false);
    }

    /// [`SupernodalSolve::solve_many`] for right-hand sides that are zero outside `rows`
    /// (original numbering, each below `n`): the forward solve visits only the supernodes on
    /// the elimination-tree paths from those rows to the roots, where the others only add
    /// zeros (the same bits as the full solve). A right-hand side with a nonzero elsewhere is
    /// noticed while it is gathered, and solved in full.
    pub fn solve_many_sparse<T: Copy + Into<f64>>(
        &mut self,
        values: &[T],
        x: &mut [f64],
        columns: usize,
        rows: &[u32],
    ) {
        self.reached.clear();
        for &r in rows {
            let mut s = self.owner[self.inverse[r as usize] as usize];
            while s != NO_PARENT && !self.marked[s as usize] {
                self.marked[s as usize] = true;
                self.reached.push(s);
                s = self.parent[s as usize];
            }
        }
        self.reached.sort_unstable();
        self.solve_columns(values, x, columns, true);
        for &s in &self.reached {
            self.marked[s as usize] = false;
        }
    }

    /// The blocks of [`SupernodalSolve::solve_many`], with the forward solve over the
    /// reached supernodes only when `sparse`.
    fn solve_columns<T: Copy + Into<f64>>(
        &mut self,
        values: &[T],
        x: &mut [f64],
        columns: usize,
        sparse: bool,
    ) {
        let n = self.structure.n();
        assert_eq!(x.len(), n * columns, "n values per right-hand side");
        let mut done = 0;
        while done < columns {
            let c = match (columns - done).min(self.width) {
                4.. => 4,
                2 | 3 => 2,
                _ => 1,
            };
            let part = &mut x[done * n..(done + c) * n];
            match c {
                4 => self.solve_block::<T, 4>(values, part, sparse),
                2 => self.solve_block::<T, 2>(values, part, sparse),
                _ => self.solve_block::<T, 1>(values, part, sparse),
            }
            done += c;
        }
    }

    /// The solves for `C` right-hand sides at once (`x` holds them one after another), a
    /// row's `C` values side by side in the work buffers. Each lane's arithmetic is that of a
    /// single right-hand side, in the same order for every `C`.
    fn solve_block<T: Copy + Into<f64>, const C: usize>(
        &mut self,
        values: &[T],
        x: &mut [f64],
        sparse: bool,
    ) {
        let st = &*self.structure;
        let n = st.n();
        assert_eq!(values.len(), st.len_val, "a factor of this structure");
        assert_eq!(x.len(), n * C, "n values per right-hand side");
        assert!(C <= self.width, "room reserved for the block");
        let (y, _) = self.y[..n * C].as_chunks_mut::<C>();
        let (scratch, _) = self.below.as_chunks_mut::<C>();
        let mut elsewhere = false;
        for ((yi, &p), &owner) in y.iter_mut().zip(&st.perm).zip(&self.owner) {
            for (c, v) in yi.iter_mut().enumerate() {
                *v = x[c * n + p as usize];
            }
            if sparse && yi.iter().any(|&v| v != 0.0) {
                elsewhere |= !self.marked[owner as usize];
            }
        }
        // Forward: L z = P x, over the reached supernodes only when the right-hand sides
        // are zero elsewhere.
        let all = !sparse || elsewhere;
        let count = if all {
            st.list.len()
        } else {
            self.reached.len()
        };
        for i in 0..count {
            let s = &st.list[if all { i } else { self.reached[i] as usize }];
            let (b, w, h) = (s.begin as usize, s.width as usize, s.height as usize);
            let ld = w + h;
            let block = &values[s.values_start..s.values_start + ld * w];
            let inv = &self.inv_diag[b..b + w];
            let top = &mut y[b..b + w];
            for j in 0..w {
                let mut xj = top[j];
                for v in &mut xj {
                    *v *= inv[j];
                }
                top[j] = xj;
                let col = &block[j * ld + j + 1..j * ld + w];
                for (t, &l) in top[j + 1..].iter_mut().zip(col) {
                    let l: f64 = l.into();
                    for (t, x) in t.iter_mut().zip(&xj) {
                        *t -= l * x;
                    }
                }
            }
            if h == 0 {
                continue;
            }
            let below = &mut scratch[..h];
            below.fill([0.0; C]);
            // below = L_below top, four columns per sweep over `below`.
            let mut j = 0;
            while j + 4 <= w {
                let x = [top[j], top[j + 1], top[j + 2], top[j + 3]];
                let c = |k: usize| &block[(j + k) * ld + w..(j + k + 1) * ld];
                let (c0, c1, c2, c3) = (c(0), c(1), c(2), c(3));
                for ((((t, &a), &b), &c), &d) in below.iter_mut().zip(c0).zip(c1).zip(c2).zip(c3) {
                    let (a, b, c, d): (f64, f64, f64, f64) =
                        (a.into(), b.into(), c.into(), d.into());
                    for (k, t) in t.iter_mut().enumerate() {
                        *t += (a * x[0][k] + b * x[1][k]) + (c * x[2][k] + d * x[3][k]);
                    }
                }
                j += 4;
            }
            for (j, xj) in top.iter().enumerate().skip(j) {
                for (t, &a) in below.iter_mut().zip(&block[j * ld + w..(j + 1) * ld]) {
                    let a: f64 = a.into();
                    for (t, x) in t.iter_mut().zip(xj) {
                        *t += a * x;
                    }
                }
            }
            for (&r, t) in st.rows_of(s).iter().zip(&*below) {
                for (v, t) in y[r as usize].iter_mut().zip(t) {
                    *v -= t;
                }
            }
        }
        // Backward: L^T y = z, each supernode's block read from its end to its start, so that
        // the sweep descends through memory without a jump at each supernode (a jump back
        // every few kilobytes would restart the processor's prefetching). `v` holds the
        // supernode's values of `y`, its own columns then its rows below, so that each
        // column is one dot product.
        for s in st.list.iter().rev() {
            let (b, w) = (s.begin as usize, s.width as usize);
            let ld = s.ld();
            let block = &values[s.values_start..s.values_start + ld * w];
            let inv = &self.inv_diag[b..b + w];
            let v = &mut scratch[..ld];
            for (t, &r) in v[w..].iter_mut().zip(st.rows_of(s)) {
                *t = y[r as usize];
            }
            for j in (0..w).rev() {
                let acc = dot_descending(&block[j * ld + j + 1..(j + 1) * ld], &v[j + 1..]);
                let mut out = y[b + j];
                for (o, a) in out.iter_mut().zip(&acc) {
                    *o = (*o - a) * inv[j];
                }
                v[j] = out;
            }
            y[b..b + w].copy_from_slice(&v[..w]);
        }
        for (yi, &p) in y.iter().zip(&st.perm) {
            for (c, v) in yi.iter().enumerate() {
                x[c * n + p as usize] = *v;
            }
        }
    }
}

/// The rows of the tallest supernode's block.
fn tallest(structure: &Supernodes) -> usize {
    structure.list.iter().map(|s| s.ld()).max().unwrap_or(0)
}

/// `sum a[i] b[i][k]` for each lane `k`, over slices of equal length, from their ends to their
/// starts, with eight independent partial sums per lane (one chain of dependent additions
/// would wait on each one's latency).
#[inline(always)]
fn dot_descending<T: Copy + Into<f64>, const C: usize>(a: &[T], b: &[[f64; C]]) -> [f64; C] {
    debug_assert_eq!(a.len(), b.len());
    let mut acc = [[0.0f64; C]; 8];
    let (ac, bc) = (a.rchunks_exact(8), b.rchunks_exact(8));
    let (ar, br) = (ac.remainder(), bc.remainder());
    for (x, y) in ac.zip(bc) {
        for k in 0..8 {
            let xk: f64 = x[k].into();
            for (acc, y) in acc[k].iter_mut().zip(&y[k]) {
                *acc += xk * y;
            }
        }
    }
    let mut tail = [0.0; C];
    for (x, y) in ar.iter().zip(br) {
        let x: f64 = (*x).into();
        for (t, y) in tail.iter_mut().zip(y) {
            *t += x * y;
        }
    }
    let mut out = [0.0; C];
    for (k, o) in out.iter_mut().enumerate() {
        *o = ((acc[0][k] + acc[4][k]) + (acc[1][k] + acc[5][k]))
            + ((acc[2][k] + acc[6][k]) + (acc[3][k] + acc[7][k]))
            + tail[k];
    }
    out
}
