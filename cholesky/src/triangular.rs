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

use std::ops::Range;
use std::sync::Arc;

use rayon::prelude::*;

use crate::subtrees::{self, Subtrees, Work};
use crate::supernodes::{Supernode, Supernodes};

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
    /// The split over threads, chosen for rayon's pool at [`SupernodalSolve::new`] (`None`:
    /// one thread).
    split: Option<Split>,
    /// Per bin of the split: its updates of the top's rows (forward), then room for its
    /// tallest supernode's values; a row's values side by side.
    bins_buf: Vec<f64>,
    /// The top's solution, for the bins to read in the backward sweep.
    top_y: Vec<f64>,
}

/// Disjoint subtrees of the supernodal elimination tree, dealt to bins (threads), and the
/// supernodes above them (see [`crate::subtrees`]).
#[derive(Clone, Debug)]
struct Split {
    /// Per bin, its subtrees as ranges of supernodes, in column order.
    bins: Vec<Vec<Range<usize>>>,
    /// The supernodes in no subtree, in column order.
    top: Vec<usize>,
    /// The (permuted) columns of the top's supernodes, in order.
    top_rows: Vec<u32>,
    /// Per permuted column, its place in `top_rows` (`u32::MAX` when in a subtree).
    top_pos: Vec<u32>,
}

impl Split {
    fn new(st: &Supernodes, threads: usize) -> Option<Split> {
        let subtrees = Subtrees::new(st, threads, Work::Solve)?;
        let mut top_pos = vec![u32::MAX; st.n()];
        let mut top_rows = Vec::new();
        for &t in &subtrees.top {
            for c in st.list[t].begin..st.list[t].end() as u32 {
                top_pos[c as usize] = top_rows.len() as u32;
                top_rows.push(c);
            }
        }
        Some(Split {
            bins: subtrees.bins,
            top: subtrees.top,
            top_rows,
            top_pos,
        })
    }

    /// Per bin, each of its subtrees with its first column and its rows of `y` (consecutive
    /// columns, disjoint from every other subtree's).
    #[allow(clippy::type_complexity)]
    fn pieces<'y, const C: usize>(
        &self,
        st: &Supernodes,
        y: &'y mut [[f64; C]],
    ) -> Vec<Vec<(Range<usize>, usize, &'y mut [[f64; C]])>> {
        let ranges = subtrees::in_column_order(&self.bins);
        let mut pieces: Vec<Vec<_>> = (0..self.bins.len()).map(|_| Vec::new()).collect();
        let (mut rest, mut at) = (y, 0);
        for (b, r) in ranges {
            let (c0, c1) = (st.list[r.start].begin as usize, st.list[r.end - 1].end());
            let (_, tail) = std::mem::take(&mut rest).split_at_mut(c0 - at);
            let (mine, tail) = tail.split_at_mut(c1 - c0);
            rest = tail;
            at = c1;
            pieces[b].push((r, c0, mine));
        }
        pieces
    }

    /// Values of one bin's buffer, for `width` right-hand sides.
    fn stride(&self, tallest: usize, width: usize) -> usize {
        (self.top_rows.len() + tallest) * width
    }
}

/// Values gathered or scattered per piece of a parallel permutation.
const GATHER: usize = 4096;

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
        let split = Split::new(&structure, rayon::current_num_threads());
        let (bins_buf, top_y) = split.as_ref().map_or((Vec::new(), Vec::new()), |sp| {
            (
                vec![0.0; sp.bins.len() * sp.stride(tallest(&structure), 1)],
                vec![0.0; sp.top_rows.len()],
            )
        });
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
            split,
            bins_buf,
            top_y,
            structure,
        }
    }

    /// Solves on the calling thread from now on (no split, its buffers freed).
    pub fn drop_split(&mut self) {
        self.split = None;
        self.bins_buf = Vec::new();
        self.top_y = Vec::new();
    }

    /// The bins of the split over threads (1 without one).
    pub fn threads(&self) -> usize {
        self.split.as_ref().map_or(1, |s| s.bins.len())
    }

    /// Makes room for solves with `columns` right-hand sides at once (blocks of up to
    /// [`BLOCK`]).
    pub fn reserve(&mut self, columns: usize) {
        let c = columns.clamp(1, BLOCK);
        if c > self.width {
            self.y = vec![0.0; self.structure.n() * c];
            self.below = vec![0.0; tallest(&self.structure) * c];
            if let Some(sp) = &self.split {
                self.bins_buf = vec![0.0; sp.bins.len() * sp.stride(tallest(&self.structure), c)];
                self.top_y = vec![0.0; sp.top_rows.len() * c];
            }
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
    pub fn solve_many<T: Copy + Into<f64> + Sync>(
        &mut self,
        values: &[T],
        x: &mut [f64],
        columns: usize,
    ) {
        self.solve_columns(values, x, columns, false);
    }

    /// [`SupernodalSolve::solve_many`] for right-hand sides that are zero outside `rows`
    /// (original numbering, each below `n`): the forward solve visits only the supernodes on
    /// the elimination-tree paths from those rows to the roots, where the others only add
    /// zeros (the same bits as the full solve). A right-hand side with a nonzero elsewhere is
    /// noticed while it is gathered, and solved in full.
    pub fn solve_many_sparse<T: Copy + Into<f64> + Sync>(
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
    fn solve_columns<T: Copy + Into<f64> + Sync>(
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
    fn solve_block<T: Copy + Into<f64> + Sync, const C: usize>(
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
        if !sparse && self.split.is_some() && rayon::current_num_threads() > 1 {
            return self.solve_block_parallel::<T, C>(values, x);
        }
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
            forward_here(st, s, values, &self.inv_diag, y, scratch);
        }
        // Backward: L^T y = z, each supernode's block read from its end to its start, so that
        // the sweep descends through memory without a jump at each supernode (a jump back
        // every few kilobytes would restart the processor's prefetching).
        for s in st.list.iter().rev() {
            backward_here(st, s, values, &self.inv_diag, y, scratch);
        }
        for (yi, &p) in y.iter().zip(&st.perm) {
            for (c, v) in yi.iter().enumerate() {
                x[c * n + p as usize] = *v;
            }
        }
    }

    /// [`SupernodalSolve::solve_block`] over the split: forward, the bins' subtrees in
    /// parallel (their updates of the top's rows summed in their own buffers, then added in
    /// bin order), then the top; backward, the top, then the bins' subtrees in parallel
    /// (reading the top's solution from a copy). Each supernode's arithmetic is that of one
    /// thread; only the order in which the top's rows receive their updates differs.
    fn solve_block_parallel<T: Copy + Into<f64> + Sync, const C: usize>(
        &mut self,
        values: &[T],
        x: &mut [f64],
    ) {
        let SupernodalSolve {
            structure,
            y,
            below,
            inv_diag,
            inverse,
            split,
            bins_buf,
            top_y,
            ..
        } = self;
        let (st, inv_diag) = (&**structure, &inv_diag[..]);
        let Some(split) = split.as_ref() else {
            unreachable!("called with a split")
        };
        let n = st.n();
        let (y, _) = y[..n * C].as_chunks_mut::<C>();
        let (scratch, _) = below.as_chunks_mut::<C>();
        {
            let x = &*x;
            y.par_chunks_mut(GATHER).enumerate().for_each(|(i, ys)| {
                for (yi, &p) in ys.iter_mut().zip(&st.perm[i * GATHER..]) {
                    for (c, v) in yi.iter_mut().enumerate() {
                        *v = x[c * n + p as usize];
                    }
                }
            });
        }
        let tops = split.top_rows.len();
        let stride = split.stride(tallest(st), C);
        let bufs = &mut bins_buf[..split.bins.len() * stride];
        let top_pos = &split.top_pos;
        // Forward over the subtrees.
        split
            .pieces(st, y)
            .into_par_iter()
            .zip(bufs.par_chunks_mut(stride))
            .for_each(|(subtrees, buf)| {
                let (buf, _) = buf.as_chunks_mut::<C>();
                let (acc, below) = buf.split_at_mut(tops);
                acc.fill([0.0; C]);
                for (r, c0, ys) in subtrees {
                    let end = c0 + ys.len();
                    for s in &st.list[r] {
                        let (b, w, h) = (s.begin as usize, s.width as usize, s.height as usize);
                        let block = &values[s.values_start..s.values_start + s.ld() * w];
                        let below = &mut below[..h];
                        forward_step(
                            block,
                            &inv_diag[b..b + w],
                            &mut ys[b - c0..b - c0 + w],
                            below,
                        );
                        for (&row, t) in st.rows_of(s).iter().zip(&*below) {
                            let row = row as usize;
                            let to = if row < end {
                                &mut ys[row - c0]
                            } else {
                                &mut acc[top_pos[row] as usize]
                            };
                            for (v, t) in to.iter_mut().zip(t) {
                                *v -= t;
                            }
                        }
                    }
                }
            });
        for buf in bufs.chunks(stride) {
            let (acc, _) = buf[..tops * C].as_chunks::<C>();
            for (&row, a) in split.top_rows.iter().zip(acc) {
                for (v, a) in y[row as usize].iter_mut().zip(a) {
                    *v += a;
                }
            }
        }
        // The top, forward then backward.
        for &t in &split.top {
            forward_here(st, &st.list[t], values, inv_diag, y, scratch);
        }
        for &t in split.top.iter().rev() {
            backward_here(st, &st.list[t], values, inv_diag, y, scratch);
        }
        let (top_y, _) = top_y[..tops * C].as_chunks_mut::<C>();
        for (t, &row) in top_y.iter_mut().zip(&split.top_rows) {
            *t = y[row as usize];
        }
        let top_y = &*top_y;
        // Backward over the subtrees.
        split
            .pieces(st, y)
            .into_par_iter()
            .zip(bufs.par_chunks_mut(stride))
            .for_each(|(subtrees, buf)| {
                let (buf, _) = buf.as_chunks_mut::<C>();
                let room = &mut buf[tops..];
                for (r, c0, ys) in subtrees {
                    let end = c0 + ys.len();
                    for s in st.list[r].iter().rev() {
                        let (b, w) = (s.begin as usize, s.width as usize);
                        let ld = s.ld();
                        let block = &values[s.values_start..s.values_start + ld * w];
                        let v = &mut room[..ld];
                        v[..w].copy_from_slice(&ys[b - c0..b - c0 + w]);
                        for (t, &row) in v[w..].iter_mut().zip(st.rows_of(s)) {
                            let row = row as usize;
                            *t = if row < end {
                                ys[row - c0]
                            } else {
                                top_y[top_pos[row] as usize]
                            };
                        }
                        backward_step(block, &inv_diag[b..b + w], v);
                        ys[b - c0..b - c0 + w].copy_from_slice(&v[..w]);
                    }
                }
            });
        let y = &*y;
        for (c, xs) in x.chunks_exact_mut(n).enumerate() {
            xs.par_chunks_mut(GATHER).enumerate().for_each(|(i, xs)| {
                for (xv, &p) in xs.iter_mut().zip(&inverse[i * GATHER..]) {
                    *xv = y[p as usize][c];
                }
            });
        }
    }
}

/// Supernode `s`'s forward step on the whole of `y` (`scratch` with room for its rows below):
/// its diagonal block solved in its rows, the product with its rows below subtracted from
/// theirs.
#[inline(always)]
fn forward_here<T: Copy + Into<f64>, const C: usize>(
    st: &Supernodes,
    s: &Supernode,
    values: &[T],
    inv_diag: &[f64],
    y: &mut [[f64; C]],
    scratch: &mut [[f64; C]],
) {
    let (b, w, h) = (s.begin as usize, s.width as usize, s.height as usize);
    let block = &values[s.values_start..s.values_start + s.ld() * w];
    let below = &mut scratch[..h];
    forward_step(block, &inv_diag[b..b + w], &mut y[b..b + w], below);
    for (&r, t) in st.rows_of(s).iter().zip(&*below) {
        for (v, t) in y[r as usize].iter_mut().zip(t) {
            *v -= t;
        }
    }
}

/// Supernode `s`'s backward step on the whole of `y` (`scratch` with room for its block's
/// rows): its rows' values gathered (its own, then those below, already solved), its own
/// solved and written back.
#[inline(always)]
fn backward_here<T: Copy + Into<f64>, const C: usize>(
    st: &Supernodes,
    s: &Supernode,
    values: &[T],
    inv_diag: &[f64],
    y: &mut [[f64; C]],
    scratch: &mut [[f64; C]],
) {
    let (b, w) = (s.begin as usize, s.width as usize);
    let ld = s.ld();
    let block = &values[s.values_start..s.values_start + ld * w];
    let v = &mut scratch[..ld];
    v[..w].copy_from_slice(&y[b..b + w]);
    for (t, &r) in v[w..].iter_mut().zip(st.rows_of(s)) {
        *t = y[r as usize];
    }
    backward_step(block, &inv_diag[b..b + w], v);
    y[b..b + w].copy_from_slice(&v[..w]);
}

/// A supernode's forward step: its diagonal block (`block`, column-major with `ld` rows and
/// `own.len()` columns, `inv` the reciprocals of its diagonal) solved in `own`, its rows'
/// values, and the product of its rows below with the result written to `below` (one row per
/// row below), for the caller to subtract.
#[inline(always)]
fn forward_step<T: Copy + Into<f64>, const C: usize>(
    block: &[T],
    inv: &[f64],
    own: &mut [[f64; C]],
    below: &mut [[f64; C]],
) {
    let (w, h) = (own.len(), below.len());
    let ld = w + h;
    for j in 0..w {
        let mut xj = own[j];
        for v in &mut xj {
            *v *= inv[j];
        }
        own[j] = xj;
        let col = &block[j * ld + j + 1..j * ld + w];
        for (t, &l) in own[j + 1..].iter_mut().zip(col) {
            let l: f64 = l.into();
            for (t, x) in t.iter_mut().zip(&xj) {
                *t -= l * x;
            }
        }
    }
    if h == 0 {
        return;
    }
    below.fill([0.0; C]);
    // below = L_below own, four columns per sweep over `below`.
    let mut j = 0;
    while j + 4 <= w {
        let x = [own[j], own[j + 1], own[j + 2], own[j + 3]];
        let c = |k: usize| &block[(j + k) * ld + w..(j + k + 1) * ld];
        let (c0, c1, c2, c3) = (c(0), c(1), c(2), c(3));
        for ((((t, &a), &b), &c), &d) in below.iter_mut().zip(c0).zip(c1).zip(c2).zip(c3) {
            let (a, b, c, d): (f64, f64, f64, f64) = (a.into(), b.into(), c.into(), d.into());
            for (k, t) in t.iter_mut().enumerate() {
                *t += (a * x[0][k] + b * x[1][k]) + (c * x[2][k] + d * x[3][k]);
            }
        }
        j += 4;
    }
    for (j, xj) in own.iter().enumerate().skip(j) {
        for (t, &a) in below.iter_mut().zip(&block[j * ld + w..(j + 1) * ld]) {
            let a: f64 = a.into();
            for (t, x) in t.iter_mut().zip(xj) {
                *t += a * x;
            }
        }
    }
}

/// A supernode's backward step: `v` holds its own rows' values from the forward sweep,
/// then its rows below, solved; its own are solved in place, one dot product per column
/// (`block` and `inv` as in [`forward_step`], `v.len()` its rows).
#[inline(always)]
fn backward_step<T: Copy + Into<f64>, const C: usize>(
    block: &[T],
    inv: &[f64],
    v: &mut [[f64; C]],
) {
    let (w, ld) = (inv.len(), v.len());
    for j in (0..w).rev() {
        let acc = dot_descending(&block[j * ld + j + 1..(j + 1) * ld], &v[j + 1..]);
        let mut out = v[j];
        for (o, a) in out.iter_mut().zip(&acc) {
            *o = (*o - a) * inv[j];
        }
        v[j] = out;
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
