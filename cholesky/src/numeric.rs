//! The numeric supernodal Cholesky factorisation `P A P^T = L L^T`, into faer's supernodal
//! layout (see [`crate::supernodes`]), with register-blocked loops.
//!
//! faer's numeric factorisation calls its general dense kernels (Cholesky, triangular solve,
//! matrix product) a few times per supernode; a nested-dissection ordering of a mesh makes
//! many small supernodes (at 10K unknowns, 804 of them, most of 8 to 31 columns), on which
//! the set-up of each call rivals its arithmetic. Here everything that does not depend on
//! the values is worked out once, at [`SupernodalLlt::new`]:
//!
//! - where each of the Hessian's values lands in `L` (the assembly map, grouped by
//!   supernode);
//! - for each supernode, the ancestors its rows below the diagonal update, and where each of
//!   those rows lies in the ancestor's block (relative indices);
//! - for each supernode, the blocks it is the first to write (its own, or those of the
//!   ancestors it is the first to update), and the Hessian's values in each block.
//!
//! A factorisation then goes supernode by supernode in column order (right-looking):
//!
//! 0. zeroes the blocks it is the first to write and scatters the Hessian's values into them
//!    (just before they are needed, so they are still in cache when the updates come:
//!    zeroing all of `L` first cost an extra pass through memory, 0.75-0.88 → 0.65-0.75 of
//!    faer's time at 100K unknowns in double precision, fastest runs in the same process);
//! 1. factors its diagonal block and divides the rows below by it, in blocks of
//!    [`PANEL`] columns whose trailing updates are register tiles;
//! 2. subtracts `B B^T` (`B` its rows below) from the ancestors, computed in register tiles of
//!    two vectors of rows by [`NR`] columns and subtracted straight from the registers
//!    through the relative indices (no dense update matrix); a tile whose target rows are
//!    consecutive is subtracted as one slice. A column's last rows are a full tile ending at
//!    its last row, which recomputes rows already done and skips them.
//!
//! On x86-64 a copy compiled for AVX2 and FMA is chosen at run time when the processor has
//! them; its tiles are explicit vector code (the compiler's vectoriser left the
//! double-precision tile scalar, at 2.5× the time). Elsewhere the same loops run portably.
//! On the benchmark disks (fastest of 60 runs, `examples/factorization.rs`, before the blocks
//! were opened one by one) it took 0.50, 0.61 and 0.82 of faer's time at 1K, 10K and 100K
//! unknowns in double precision, 0.50, 0.60 and 0.70 in single precision; the factors agree to 1e-13 of their largest entry (tests).

use std::sync::Arc;

use rayon::prelude::*;

use crate::subtrees::{self, Subtrees, Work};
use crate::supernodes::{Supernode, Supernodes};

/// Columns factored one by one before their trailing update is applied in tiles.
const PANEL: usize = 8;
/// Columns of a register tile.
const NR: usize = 4;

/// A value type of the factor: `f64` or `f32`.
pub(crate) trait Real:
    Copy
    + Send
    + Sync
    + Default
    + PartialOrd
    + std::ops::Mul<Output = Self>
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::SubAssign
    + std::ops::MulAssign
{
    /// `v` rounded to this type.
    fn from_f64(v: f64) -> Self;
    /// The square root.
    fn sqrt(self) -> Self;
    /// `1 / self`.
    fn recip(self) -> Self;
    /// Whether finite.
    fn finite(self) -> bool;
    /// Whether greater than zero (false for NaN).
    fn positive(self) -> bool;
    /// The machine epsilon of this type, as an `f64`.
    fn epsilon() -> f64;
    /// This value as an `f64`.
    fn to_f64(self) -> f64;
    /// `self * b + c`, fused when `FMA` (only where the processor has it: elsewhere a fused
    /// multiply-add is a slow library call).
    fn madd<const FMA: bool>(self, b: Self, c: Self) -> Self;
    /// [`tile`] with [`NR`] columns, by explicit vector code where `FMA` (which callers pass
    /// only inside [`SupernodalLlt::supernodes_avx2`]) and `R` is one or two vectors: the
    /// compiler's own vectoriser left the double-precision tile scalar.
    fn tile4<const R: usize, const FMA: bool>(
        src: &[Self],
        ld: usize,
        i: usize,
        j: usize,
        k: usize,
    ) -> [[Self; R]; NR];
}

macro_rules! real {
    ($t:ty, $lanes:literal, $vector:ident) => {
        impl Real for $t {
            #[inline(always)]
            fn from_f64(v: f64) -> Self {
                v as $t
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline(always)]
            fn recip(self) -> Self {
                1.0 / self
            }
            #[inline(always)]
            fn finite(self) -> bool {
                self.is_finite()
            }
            #[inline(always)]
            fn positive(self) -> bool {
                self > 0.0
            }
            #[inline(always)]
            fn epsilon() -> f64 {
                f64::from(<$t>::EPSILON)
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                f64::from(self)
            }
            #[inline(always)]
            fn madd<const FMA: bool>(self, b: Self, c: Self) -> Self {
                if FMA {
                    self.mul_add(b, c)
                } else {
                    self * b + c
                }
            }
            #[inline(always)]
            fn tile4<const R: usize, const FMA: bool>(
                src: &[Self],
                ld: usize,
                i: usize,
                j: usize,
                k: usize,
            ) -> [[Self; R]; NR] {
                #[cfg(target_arch = "x86_64")]
                if FMA && (R == $lanes || R == 2 * $lanes) {
                    let mut out = [[0.0; R]; NR];
                    if R == $lanes {
                        // SAFETY: `FMA` is true only inside `supernodes_avx2`, which runs only
                        // when the processor has AVX2 and FMA.
                        widen(&unsafe { avx2::$vector::<1>(src, ld, i, j, k) }, &mut out);
                    } else {
                        // SAFETY: as above.
                        widen(&unsafe { avx2::$vector::<2>(src, ld, i, j, k) }, &mut out);
                    }
                    return out;
                }
                tile::<Self, R, NR, FMA>(src, ld, i, j, k)
            }
        }
    };
}
/// A vector tile's accumulators (`V` vectors of `L` lanes per column) as rows per column.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn widen<T: Copy, const L: usize, const V: usize, const R: usize>(
    acc: &[[[T; L]; V]; NR],
    out: &mut [[T; R]; NR],
) {
    for (o, a) in out.iter_mut().zip(acc) {
        o.copy_from_slice(a.as_flattened());
    }
}

real!(f64, 4, tile_f64);
real!(f32, 8, tile_f32);

/// The register tiles in AVX2 and FMA vector code.
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::{
        _mm256_fmadd_pd, _mm256_fmadd_ps, _mm256_set1_pd, _mm256_set1_ps, _mm256_setzero_pd,
        _mm256_setzero_ps,
    };

    use super::NR;

    macro_rules! tile {
        ($name:ident, $t:ty, $lanes:literal, $zero:ident, $splat:ident, $fma:ident) => {
            /// `acc[q][v][l] = sum_c src[c ld + i + v lanes + l] src[c ld + j + q]`: `V`
            /// vectors of rows by [`NR`] columns (see [`super::tile`]).
            #[target_feature(enable = "avx2,fma")]
            #[inline]
            pub fn $name<const V: usize>(
                src: &[$t],
                ld: usize,
                i: usize,
                j: usize,
                k: usize,
            ) -> [[[$t; $lanes]; V]; NR] {
                let mut acc = [[$zero(); V]; NR];
                // Checked once here, so that the loop's indexing needs no checks: every
                // column is `ld` long and holds both the rows and the columns of the tile.
                assert!(i + V * $lanes <= ld && j + NR <= ld);
                for col in src[..k * ld].chunks_exact(ld) {
                    let a = &col[i..i + V * $lanes];
                    let b = &col[j..j + NR];
                    let mut rows = [$zero(); V];
                    for (row, lanes) in rows.iter_mut().zip(a.chunks_exact($lanes)) {
                        *row = bytemuck::pod_read_unaligned(bytemuck::cast_slice(lanes));
                    }
                    for (acc, &b) in acc.iter_mut().zip(b) {
                        let b = $splat(b);
                        for (acc, &row) in acc.iter_mut().zip(&rows) {
                            *acc = $fma(row, b, *acc);
                        }
                    }
                }
                let mut out = [[[0.0; $lanes]; V]; NR];
                for (out, acc) in out.iter_mut().zip(&acc) {
                    for (out, &acc) in out.iter_mut().zip(acc) {
                        *out = bytemuck::cast(acc);
                    }
                }
                out
            }
        };
    }

    tile!(
        tile_f64,
        f64,
        4,
        _mm256_setzero_pd,
        _mm256_set1_pd,
        _mm256_fmadd_pd
    );
    tile!(
        tile_f32,
        f32,
        8,
        _mm256_setzero_ps,
        _mm256_set1_ps,
        _mm256_fmadd_ps
    );
}

/// Why a numeric factorisation stopped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Failure {
    /// The pivot of this column (in the factorisation's order) was not positive.
    Pivot(usize),
    /// The pivot of this column was positive but within rounding error of zero (see
    /// [`Pivots`]); its ratio to the matrix's diagonal entry.
    Singular(usize, f64),
    /// A value of the matrix in this column (in the factorisation's order) is not finite in
    /// the factor's precision.
    NonFinite(usize),
}

/// What the factorisation checks each pivot against, and where it leaves the reciprocals of
/// `L`'s diagonal (which the solves multiply by).
///
/// A pivot `d_j` (`L_jj²`) fails when it is no larger than `bound_j eps a_jj`, for `a_jj` the
/// matrix's diagonal entry and `eps` the factor's precision's: `bound_j` is `scale[j]` in
/// single precision and `max(scale[j], floor)` in double precision (see `check_pivots` in
/// `factor.rs`, which applies the same rule after faer's factorisations). Checked in the
/// panel, where the pivot is in cache: a separate pass over the diagonal after the
/// factorisation cost 3% of it at 10K unknowns (its entries are a cache line apart each).
pub(crate) struct Pivots<'a> {
    /// Per column, the slot of the matrix's diagonal entry.
    pub slot: &'a [u32],
    /// Per column, `4 k` for `k` the entries of its row of `L`.
    pub scale: &'a [f64],
    /// The number of unknowns: the least bound in double precision.
    pub floor: f64,
    /// Per column, receives `1 / L_jj` (computed in double precision).
    pub inv_diag: &'a mut [f64],
}

/// One supernode's update of one ancestor: the source's rows below its diagonal block from
/// `first` on, of which `first..first + count` are columns of the ancestor.
#[derive(Clone, Copy, Debug)]
struct Update {
    /// The ancestor (an index into the supernodes).
    target: u32,
    /// First of the source's below rows in the ancestor's columns.
    first: u32,
    /// How many of the source's below rows are the ancestor's columns.
    count: u32,
    /// Where the ancestor-block rows of the source's below rows `first..` start in `rel`.
    rel_start: usize,
}

/// A supernodal structure with everything its numeric factorisations need worked out once.
#[derive(Clone, Debug)]
pub(crate) struct SupernodalLlt {
    structure: Arc<Supernodes>,
    /// Per value of the Hessian's lower triangle, `[its index, its place in the factor's
    /// values]`, grouped by supernode: supernode `s`'s are
    /// `assembly[assembly_start[s]..assembly_start[s + 1]]`.
    assembly: Vec<[u32; 2]>,
    assembly_start: Vec<u32>,
    /// The supernodes whose blocks are zeroed and assembled just before supernode `k` is
    /// factored (those that `k` is the first to write): `opens[open_start[k]..open_start[k +
    /// 1]]`.
    opens: Vec<u32>,
    open_start: Vec<u32>,
    /// Supernode `s`'s updates are `updates[update_start[s]..update_start[s + 1]]`.
    update_start: Vec<u32>,
    updates: Vec<Update>,
    /// Rows in an ancestor's block (see [`Update::rel_start`]).
    rel: Vec<u32>,
    /// Whether the processor has AVX2 and FMA (checked once).
    avx2_fma: bool,
    /// The split for factoring on several threads, when it pays (see [`crate::subtrees`]).
    subtrees: Option<Subtrees>,
}

impl SupernodalLlt {
    /// The factorisation plan for matrices with the lower-triangle pattern `col_ptr`,
    /// `row_idx` (rows increasing in each column, in the original numbering) and the checked
    /// `structure` of their symbolic factorisation. `None` when the pattern has an entry the
    /// structure has no place for, when an ancestor's block lacks a row that a descendant
    /// updates, or when the factor has more values than a `u32` indexes: then faer factors.
    pub fn new(structure: Arc<Supernodes>, col_ptr: &[u32], row_idx: &[u32]) -> Option<Self> {
        let n = structure.n();
        if col_ptr.len() != n + 1 || u32::try_from(structure.len_val).is_err() {
            return None;
        }
        let mut inverse = vec![0u32; n];
        for (new, &old) in structure.perm.iter().enumerate() {
            inverse[old as usize] = new as u32;
        }
        let mut owner = vec![0u32; n];
        for (k, s) in structure.list.iter().enumerate() {
            owner[s.begin as usize..s.end()].fill(k as u32);
        }
        // The place of entry (row, col) of the permuted lower triangle in supernode `s`'s
        // block, when the structure has it.
        let local = |s: &Supernode, row: usize| -> Option<usize> {
            if row < s.begin as usize {
                return None;
            }
            if row < s.end() {
                return Some(row - s.begin as usize);
            }
            let below = structure.rows_of(s).binary_search(&(row as u32)).ok()?;
            Some(s.width as usize + below)
        };
        // [supernode, index, place] per value, then grouped by supernode.
        let mut placed = Vec::with_capacity(row_idx.len());
        for j in 0..n {
            let (e0, e1) = (col_ptr[j] as usize, col_ptr[j + 1] as usize);
            for (e, &i) in (e0..).zip(row_idx.get(e0..e1)?) {
                let (pi, pj) = (*inverse.get(i as usize)? as usize, inverse[j] as usize);
                let (row, col) = (pi.max(pj), pi.min(pj));
                let s = &structure.list[owner[col] as usize];
                let at = s.values_start + (col - s.begin as usize) * s.ld() + local(s, row)?;
                placed.push([owner[col], e as u32, at as u32]);
            }
        }
        if placed.len() != row_idx.len() || u32::try_from(placed.len()).is_err() {
            return None;
        }
        placed.sort_unstable();
        let supernodes = structure.list.len();
        let assembly_start = group_starts(placed.iter().map(|p| p[0]), supernodes);
        let assembly = placed.iter().map(|p| [p[1], p[2]]).collect();
        let (mut updates, mut update_start, mut rel) = (Vec::new(), vec![0u32], Vec::new());
        for s in &structure.list {
            let rows = structure.rows_of(s);
            let mut a = 0;
            while a < rows.len() {
                let target = owner[rows[a] as usize];
                let t = &structure.list[target as usize];
                let mut b = a + 1;
                while b < rows.len() && owner[rows[b] as usize] == target {
                    b += 1;
                }
                let rel_start = rel.len();
                for &r in &rows[a..] {
                    rel.push(local(t, r as usize)? as u32);
                }
                updates.push(Update {
                    target,
                    first: a as u32,
                    count: (b - a) as u32,
                    rel_start,
                });
                a = b;
            }
            update_start.push(u32::try_from(updates.len()).ok()?);
        }
        // Each block is zeroed and assembled when it is first written: by the first
        // supernode that updates it, or by itself. Zeroing the whole factor at once streamed
        // it through memory an extra time (at 100K unknowns, 25-50 MB) and left none of it in
        // cache for the updates that followed.
        let mut first_writer: Vec<u32> = (0..supernodes as u32).collect();
        for k in 0..supernodes {
            for u in &updates[update_start[k] as usize..update_start[k + 1] as usize] {
                let t = u.target as usize;
                first_writer[t] = first_writer[t].min(k as u32);
            }
        }
        let mut opens: Vec<u32> = (0..supernodes as u32).collect();
        opens.sort_by_key(|&t| first_writer[t as usize]);
        let open_start = group_starts(first_writer.iter().copied(), supernodes);
        Some(SupernodalLlt {
            structure: structure.clone(),
            assembly,
            assembly_start,
            opens,
            open_start,
            update_start,
            updates,
            rel,
            avx2_fma: avx2_fma(),
            subtrees: Subtrees::new(&structure, rayon::current_num_threads(), Work::Factor),
        })
    }

    /// Bytes of the plan beyond the structure (assembly map, updates, relative indices).
    pub fn bytes(&self) -> usize {
        self.assembly.len() * 8
            + (self.assembly_start.len() + self.opens.len() + self.open_start.len()) * 4
            + self.update_start.len() * 4
            + self.updates.len() * std::mem::size_of::<Update>()
            + self.rel.len() * 4
            + self.subtrees.as_ref().map_or(0, |t| t.scratch_at.len() * 8)
    }

    /// Values of the scratch space a factorisation on several threads needs (one copy of the
    /// top per bin; 0 when it stays on one thread).
    pub fn scratch_len(&self) -> usize {
        self.subtrees
            .as_ref()
            .map_or(0, |t| t.scratch_len * t.bins.len())
    }

    /// Bins (threads) a factorisation uses: 1 when it stays on one thread.
    pub fn threads(&self) -> usize {
        self.subtrees.as_ref().map_or(1, |t| t.bins.len())
    }

    /// Factors the matrix whose lower-triangle values (in the pattern given to
    /// [`SupernodalLlt::new`]) are `matrix` into `values`, rounded to `T`, checking every
    /// pivot by `pivots` (whose arrays have one entry per column) and writing the
    /// reciprocals of the diagonal there. Allocates nothing.
    ///
    /// With a `scratch` of [`SupernodalLlt::scratch_len`] values and more than one thread in
    /// rayon's current pool, independent subtrees are factored in parallel (see
    /// [`crate::subtrees`]); with an empty one, on this thread.
    pub fn factorize<T: Real>(
        &self,
        matrix: &[f64],
        values: &mut [T],
        pivots: &mut Pivots<'_>,
        scratch: &mut [T],
    ) -> Result<(), Failure> {
        let n = self.structure.n();
        assert!(
            pivots.slot.len() == n && pivots.scale.len() == n && pivots.inv_diag.len() == n,
            "one pivot rule per column"
        );
        assert_eq!(
            values.len(),
            self.structure.len_val,
            "a factor of this structure"
        );
        assert_eq!(
            matrix.len(),
            self.assembly.len(),
            "one value per pattern entry"
        );
        if !matrix.iter().all(|&v| T::from_f64(v).finite()) {
            return Err(Failure::NonFinite(self.first_non_finite(matrix, values)));
        }
        if let Some(split) = &self.subtrees {
            if scratch.len() == self.scratch_len() && rayon::current_num_threads() > 1 {
                return self.in_parallel(split, matrix, values, pivots, scratch);
            }
        }
        let all = 0..self.structure.list.len();
        let targets = |_: usize| false;
        let scratch = &mut Scratch::default();
        self.dispatch(all, &targets, matrix, values, (0, 0), pivots, scratch)
    }

    /// The factorisation on several threads: the top's blocks opened, the bins' subtrees in
    /// parallel (their updates of the top into their scratch copies), the copies added to the
    /// top, then the top.
    fn in_parallel<T: Real>(
        &self,
        split: &Subtrees,
        matrix: &[f64],
        values: &mut [T],
        pivots: &mut Pivots<'_>,
        scratch: &mut [T],
    ) -> Result<(), Failure> {
        let st = &*self.structure;
        for &t in &split.top {
            self.open(t, matrix, values);
        }
        // Each subtree's values and columns: consecutive, disjoint, in column order.
        let ranges = subtrees::in_column_order(&split.bins);
        let mut work: Vec<Vec<Share<'_, T>>> = (0..split.bins.len()).map(|_| Vec::new()).collect();
        let (mut vals, mut diag) = (&mut *values, &mut *pivots.inv_diag);
        let (mut v_at, mut c_at) = (0, 0);
        for (b, r) in ranges {
            let (v0, v1) = (
                st.list[r.start].values_start,
                st.list[r.end - 1].values().end,
            );
            let (c0, c1) = (st.list[r.start].begin as usize, st.list[r.end - 1].end());
            let (_, rest) = std::mem::take(&mut vals).split_at_mut(v0 - v_at);
            let (mine, rest) = rest.split_at_mut(v1 - v0);
            vals = rest;
            v_at = v1;
            let (_, rest) = std::mem::take(&mut diag).split_at_mut(c0 - c_at);
            let (my_diag, rest) = rest.split_at_mut(c1 - c0);
            diag = rest;
            c_at = c1;
            work[b].push((r, mine, my_diag));
        }
        let (slot, scale, floor) = (pivots.slot, pivots.scale, pivots.floor);
        let in_top = |t: usize| split.in_top(t);
        let failures: Vec<Result<(), Failure>> = work
            .into_par_iter()
            .zip(scratch.par_chunks_mut(split.scratch_len))
            .map(|(subtrees, copy)| {
                copy.fill(T::default());
                for (r, mine, my_diag) in subtrees {
                    let base = st.list[r.start].values_start;
                    let col0 = st.list[r.start].begin as usize;
                    let mut pivots = Pivots {
                        slot: &slot[col0..],
                        scale: &scale[col0..],
                        floor,
                        inv_diag: my_diag,
                    };
                    let mut copy = Scratch {
                        values: &mut *copy,
                        at: &split.scratch_at,
                    };
                    let at = (base, col0);
                    self.dispatch(r, &in_top, matrix, mine, at, &mut pivots, &mut copy)?;
                }
                Ok(())
            })
            .collect();
        // The failure of the first column, as on one thread.
        let first = failures
            .into_iter()
            .filter_map(Result::err)
            .min_by_key(|f| f.column());
        if let Some(f) = first {
            return Err(f);
        }
        for copy in scratch.chunks(split.scratch_len) {
            for &t in &split.top {
                let range = st.list[t].values();
                let at = split.scratch_at[t];
                for (v, c) in values[range.clone()]
                    .iter_mut()
                    .zip(&copy[at..at + range.len()])
                {
                    *v = *v + *c;
                }
            }
        }
        for &t in &split.top {
            let never = |_: usize| true;
            let scratch = &mut Scratch::default();
            self.dispatch(t..t + 1, &never, matrix, values, (0, 0), pivots, scratch)?;
        }
        Ok(())
    }

    /// Zeroes supernode `t`'s block of `values` and writes `matrix`'s values into it.
    #[inline(always)]
    fn open<T: Real>(&self, t: usize, matrix: &[f64], values: &mut [T]) {
        self.open_at(t, matrix, values, 0);
    }

    /// [`SupernodalLlt::open`] into `values` starting at the factor's value `base`.
    #[inline(always)]
    fn open_at<T: Real>(&self, t: usize, matrix: &[f64], values: &mut [T], base: usize) {
        let range = self.structure.list[t].values();
        values[range.start - base..range.end - base].fill(T::default());
        let (a0, a1) = (
            self.assembly_start[t] as usize,
            self.assembly_start[t + 1] as usize,
        );
        for &[i, at] in &self.assembly[a0..a1] {
            values[at as usize - base] = T::from_f64(matrix[i as usize]);
        }
    }

    /// The first column (in the factorisation's order) of `matrix` assembled into `values`
    /// holding a value that is not finite in `T`.
    #[cold]
    fn first_non_finite<T: Real>(&self, matrix: &[f64], values: &mut [T]) -> usize {
        for t in 0..self.structure.list.len() {
            self.open(t, matrix, values);
        }
        let values = &*values;
        let st = &*self.structure;
        st.list
            .iter()
            .flat_map(|s| {
                let ld = s.ld();
                values[s.values()]
                    .chunks_exact(ld)
                    .position(|c| c.iter().any(|v| !v.finite()))
                    .map(|c| s.begin as usize + c)
            })
            .next()
            .unwrap_or(0)
    }

    /// [`SupernodalLlt::range`] compiled for AVX2 and FMA where the processor has them, else
    /// the portable loops.
    #[allow(clippy::too_many_arguments)]
    fn dispatch<T: Real>(
        &self,
        range: std::ops::Range<usize>,
        opened: &impl Fn(usize) -> bool,
        matrix: &[f64],
        values: &mut [T],
        base: (usize, usize),
        pivots: &mut Pivots<'_>,
        top: &mut Scratch<'_, T>,
    ) -> Result<(), Failure> {
        #[cfg(target_arch = "x86_64")]
        if self.avx2_fma {
            // SAFETY: the processor has AVX2 and FMA (`avx2_fma` was detected at run time).
            return unsafe { self.range_avx2(range, opened, matrix, values, base, pivots, top) };
        }
        self.range::<T, false>(range, opened, matrix, values, base, pivots, top)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[allow(clippy::too_many_arguments)]
    fn range_avx2<T: Real>(
        &self,
        range: std::ops::Range<usize>,
        opened: &impl Fn(usize) -> bool,
        matrix: &[f64],
        values: &mut [T],
        base: (usize, usize),
        pivots: &mut Pivots<'_>,
        top: &mut Scratch<'_, T>,
    ) -> Result<(), Failure> {
        self.range::<T, true>(range, opened, matrix, values, base, pivots, top)
    }

    /// The supernodes `range` in column order: the blocks each is the first to write zeroed
    /// and assembled from `matrix` (but those `opened` already), then its panel, then its
    /// updates of its ancestors. `values` holds the factor's values from `base` on, as far as
    /// the range's own blocks and the ancestors it updates outside `top`; `top` receives the
    /// updates of the ancestors it holds. `pivots`' arrays start at column `col0`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn range<T: Real, const FMA: bool>(
        &self,
        range: std::ops::Range<usize>,
        opened: &impl Fn(usize) -> bool,
        matrix: &[f64],
        values: &mut [T],
        (base, col0): (usize, usize),
        pivots: &mut Pivots<'_>,
        top: &mut Scratch<'_, T>,
    ) -> Result<(), Failure> {
        let st = &*self.structure;
        // The least bound on a pivot in double precision (none in single).
        let floor = if T::epsilon() > f64::EPSILON {
            0.0
        } else {
            pivots.floor
        };
        for k in range {
            let s = &st.list[k];
            let (o0, o1) = (self.open_start[k] as usize, self.open_start[k + 1] as usize);
            for &t in &self.opens[o0..o1] {
                if !opened(t as usize) {
                    self.open_at(t as usize, matrix, values, base);
                }
            }
            let own = s.values();
            let (done, rest) = values.split_at_mut(own.end - base);
            let block = &mut done[own.start - base..];
            let (w, ld) = (s.width as usize, s.ld());
            let b = s.begin as usize;
            let columns = b - col0..b - col0 + w;
            let checks = PanelChecks {
                matrix,
                slot: &pivots.slot[columns.clone()],
                scale: &pivots.scale[columns.clone()],
                floor,
                inv_diag: &mut pivots.inv_diag[columns],
            };
            panel::<T, FMA>(block, w, ld, checks).map_err(|f| match f {
                Failure::Pivot(c) => Failure::Pivot(b + c),
                Failure::Singular(c, ratio) => Failure::Singular(b + c, ratio),
                Failure::NonFinite(c) => Failure::NonFinite(b + c),
            })?;
            let block = &*block;
            let rows = st.rows_of(s);
            let h = rows.len();
            let (u0, u1) = (
                self.update_start[k] as usize,
                self.update_start[k + 1] as usize,
            );
            for u in &self.updates[u0..u1] {
                let t = &st.list[u.target as usize];
                let target = match top.at.get(u.target as usize) {
                    Some(&at) if at != usize::MAX => &mut top.values[at..at + t.values().len()],
                    _ => &mut rest[t.values_start - own.end..t.values().end - own.end],
                };
                let (first, count) = (u.first as usize, u.count as usize);
                let rel = &self.rel[u.rel_start..u.rel_start + h - first];
                let columns = |j: usize| (rows[first + j] - t.begin) as usize * t.ld();
                // B B^T for B the rows from `first` below the diagonal block.
                trailing::<T, FMA>(
                    block,
                    ld,
                    w + first,
                    count,
                    h - first,
                    w,
                    rel,
                    &columns,
                    target,
                );
            }
        }
        Ok(())
    }
}

/// A subtree's share of a factorisation: its supernodes, their values, their columns'
/// reciprocal pivots.
type Share<'a, T> = (std::ops::Range<usize>, &'a mut [T], &'a mut [f64]);

/// A bin's scratch copy of the top's blocks: `values`, and per supernode where its block
/// starts in them (`usize::MAX` outside the top). Empty on one thread.
pub(crate) struct Scratch<'a, T> {
    values: &'a mut [T],
    at: &'a [usize],
}

impl<T> Default for Scratch<'_, T> {
    fn default() -> Self {
        Scratch {
            values: &mut [],
            at: &[],
        }
    }
}

impl Failure {
    /// The column it is about.
    fn column(&self) -> usize {
        match *self {
            Failure::Pivot(c) | Failure::Singular(c, _) | Failure::NonFinite(c) => c,
        }
    }
}

/// Where each of `groups` groups starts in a list sorted by group, given every item's group:
/// `groups + 1` offsets, the last the list's length.
fn group_starts(keys: impl Iterator<Item = u32>, groups: usize) -> Vec<u32> {
    let mut starts = vec![0u32; groups + 1];
    for key in keys {
        starts[key as usize + 1] += 1;
    }
    for k in 0..groups {
        starts[k + 1] += starts[k];
    }
    starts
}

/// Whether the processor has AVX2 and FMA.
fn avx2_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Rows of a register tile for `T`: two 256-bit vectors.
const fn mr<T>() -> usize {
    64 / std::mem::size_of::<T>()
}

/// `acc[q][r] = sum_c src[c ld + i + r] src[c ld + j + q]` over the `k` columns of `src`.
#[inline(always)]
fn tile<T: Real, const R: usize, const Q: usize, const FMA: bool>(
    src: &[T],
    ld: usize,
    i: usize,
    j: usize,
    k: usize,
) -> [[T; R]; Q] {
    let mut acc = [[T::default(); R]; Q];
    for c in 0..k {
        let col = &src[c * ld..];
        let a = &col[i..i + R];
        let b = &col[j..j + Q];
        for q in 0..Q {
            for r in 0..R {
                acc[q][r] = a[r].madd::<FMA>(b[q], acc[q][r]);
            }
        }
    }
    acc
}

/// One supernode's share of [`Pivots`]: its columns' entries, and the matrix's values.
struct PanelChecks<'a> {
    matrix: &'a [f64],
    slot: &'a [u32],
    scale: &'a [f64],
    floor: f64,
    inv_diag: &'a mut [f64],
}

/// Factors one supernode's block in place: `ld` rows (its diagonal block, then the rows
/// below) by `w` columns, column-major. The diagonal block becomes its Cholesky factor and
/// the rows below are divided by its transpose. Fails with the block column of a pivot that
/// is not positive or is within rounding error of zero (see [`Pivots`]).
#[inline(always)]
fn panel<T: Real, const FMA: bool>(
    block: &mut [T],
    w: usize,
    ld: usize,
    checks: PanelChecks<'_>,
) -> Result<(), Failure> {
    let mut k0 = 0;
    while k0 < w {
        let k1 = (k0 + PANEL).min(w);
        // Columns k0..k1 one by one, each updating the next ones within the panel.
        for k in k0..k1 {
            let (left, right) = block.split_at_mut((k + 1) * ld);
            let col = &mut left[k * ld..];
            let d = col[k];
            if !d.positive() {
                return Err(Failure::Pivot(k));
            }
            let a = checks.matrix[checks.slot[k] as usize];
            let bound = checks.scale[k].max(checks.floor) * T::epsilon() * a;
            let pivot = d.to_f64();
            if pivot <= bound {
                return Err(Failure::Singular(k, pivot / a));
            }
            let l = d.sqrt();
            col[k] = l;
            let inv = l.recip();
            // In double precision `inv` is already `1 / L_jj`; in single precision the solves'
            // reciprocal is taken in double precision.
            checks.inv_diag[k] = if T::epsilon() > f64::EPSILON {
                1.0 / l.to_f64()
            } else {
                inv.to_f64()
            };
            for v in &mut col[k + 1..ld] {
                *v *= inv;
            }
            let col = &*col;
            for c in k + 1..k1 {
                let f = col[c];
                let target = &mut right[(c - k - 1) * ld + c..(c - k) * ld];
                for (t, &v) in target.iter_mut().zip(&col[c..ld]) {
                    *t = (T::default() - f).madd::<FMA>(v, *t);
                }
            }
        }
        if k1 == w {
            break;
        }
        // The trailing columns k1..w lose the panel's contribution, in register tiles.
        let (left, right) = block.split_at_mut(k1 * ld);
        let src = &left[k0 * ld..];
        let columns = |j: usize| j * ld;
        let rel: &[u32] = &[];
        trailing::<T, FMA>(src, ld, k1, w - k1, ld - k1, k1 - k0, rel, &columns, right);
        k0 = k1;
    }
    Ok(())
}

/// The register-tiled lower-triangle product `target[row(i) + columns(j)] -= sum_c
/// src[c ld + first + i] src[c ld + first + j]` for `j < n <= i < m` or `j <= i < n`, where
/// `row(i)` is `rel[i]`, or `i + first` when `rel` is empty (a dense target).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn trailing<T: Real, const FMA: bool>(
    src: &[T],
    ld: usize,
    first: usize,
    n: usize,
    m: usize,
    k: usize,
    rel: &[u32],
    columns: &impl Fn(usize) -> usize,
    target: &mut [T],
) {
    let row = |i: usize| {
        if rel.is_empty() {
            first + i
        } else {
            rel[i] as usize
        }
    };
    let mut j0 = 0;
    while j0 < n {
        let q = (n - j0).min(NR);
        let mut cols = [0usize; NR];
        for (jj, c) in cols.iter_mut().enumerate().take(q) {
            *c = columns(j0 + jj);
        }
        // Rows from the tile column's diagonal down, a full tile at a time; the last rows
        // by a full tile ending at the last row (recomputing rows already subtracted, which
        // it skips), or, when the column is shorter than a tile, by narrower ones.
        let mut i0 = j0;
        let r = mr::<T>();
        while i0 + r <= m || (i0 < m && m >= r) {
            // A full tile from i0, or the last one, ending at the last row.
            let (start, from) = if i0 + r <= m { (i0, i0) } else { (m - r, i0) };
            if r == 8 {
                tile_out::<T, 8, FMA>(src, ld, first, start, from, j0, q, k, &cols, &row, target);
            } else {
                tile_out::<T, 16, FMA>(src, ld, first, start, from, j0, q, k, &cols, &row, target);
            }
            i0 = start + r;
        }
        if i0 + r / 2 <= m {
            if r == 8 {
                tile_out::<T, 4, FMA>(src, ld, first, i0, i0, j0, q, k, &cols, &row, target);
            } else {
                tile_out::<T, 8, FMA>(src, ld, first, i0, i0, j0, q, k, &cols, &row, target);
            }
            i0 += r / 2;
        }
        while i0 < m {
            tile_out::<T, 1, FMA>(src, ld, first, i0, i0, j0, q, k, &cols, &row, target);
            i0 += 1;
        }
        j0 += q;
    }
}

/// One tile of [`trailing`]: rows `i0..i0 + R` by the `q <= NR` columns from `j0`,
/// subtracted from `target`, skipping rows before `from` and entries above the diagonal.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn tile_out<T: Real, const R: usize, const FMA: bool>(
    src: &[T],
    ld: usize,
    first: usize,
    i0: usize,
    from: usize,
    j0: usize,
    q: usize,
    k: usize,
    cols: &[usize; NR],
    row: &impl Fn(usize) -> usize,
    target: &mut [T],
) {
    let (i, j) = (first + i0, first + j0);
    let diagonal = i0 < j0 + q || i0 < from;
    if q == NR {
        let acc = T::tile4::<R, FMA>(src, ld, i, j, k);
        // Target rows increase with the source rows: spanning R - 1 they are consecutive.
        if !diagonal && row(i0 + R - 1) - row(i0) == R - 1 {
            let base = row(i0);
            for (col, &c) in acc.iter().zip(cols) {
                for (t, &v) in target[base + c..base + c + R].iter_mut().zip(col) {
                    *t -= v;
                }
            }
            return;
        }
        for (qq, (col, &c)) in acc.iter().zip(cols).enumerate() {
            for (r, &v) in col.iter().enumerate() {
                if !diagonal || (i0 + r >= j0 + qq && i0 + r >= from) {
                    target[row(i0 + r) + c] -= v;
                }
            }
        }
    } else {
        for (qq, &c) in cols.iter().enumerate().take(q) {
            let acc = tile::<T, R, 1, FMA>(src, ld, i, j + qq, k);
            for (r, &v) in acc[0].iter().enumerate() {
                if !diagonal || (i0 + r >= j0 + qq && i0 + r >= from) {
                    target[row(i0 + r) + c] -= v;
                }
            }
        }
    }
}

#[cfg(test)]
impl SupernodalLlt {
    /// [`SupernodalLlt::factorize`] by the portable loops, whatever the processor has.
    pub fn factorize_portable(
        &self,
        matrix: &[f64],
        values: &mut [f64],
        pivots: &mut Pivots<'_>,
    ) -> Result<(), Failure> {
        let all = 0..self.structure.list.len();
        let targets = |_: usize| false;
        self.range::<f64, false>(
            all,
            &targets,
            matrix,
            values,
            (0, 0),
            pivots,
            &mut Scratch::default(),
        )
    }

    /// Checks that the plan places each of a matrix's `nnz` values exactly once, inside its
    /// supernode's block; opens every block once, before anything writes it; and that every
    /// update writes inside its ancestor's block.
    pub fn check_coverage(&self, nnz: usize) {
        let st = &*self.structure;
        let mut seen = vec![false; st.len_val];
        let mut indices = vec![false; nnz];
        for (t, s) in st.list.iter().enumerate() {
            let group = self.assembly_start[t] as usize..self.assembly_start[t + 1] as usize;
            for &[i, at] in &self.assembly[group] {
                assert!(s.values().contains(&(at as usize)), "{at} outside {t}");
                assert!(
                    !std::mem::replace(&mut seen[at as usize], true),
                    "{at} twice"
                );
                assert!(!std::mem::replace(&mut indices[i as usize], true));
            }
        }
        assert!(indices.iter().all(|&i| i), "every value placed");
        let mut opened_by = vec![usize::MAX; st.list.len()];
        for k in 0..st.list.len() {
            for &t in &self.opens[self.open_start[k] as usize..self.open_start[k + 1] as usize] {
                assert_eq!(opened_by[t as usize], usize::MAX, "{t} opened twice");
                assert!(t as usize >= k);
                opened_by[t as usize] = k;
            }
        }
        for k in 0..st.list.len() {
            let (u0, u1) = (
                self.update_start[k] as usize,
                self.update_start[k + 1] as usize,
            );
            for u in &self.updates[u0..u1] {
                assert!(opened_by[u.target as usize] <= k);
            }
        }
        for (k, s) in st.list.iter().enumerate() {
            let rows = st.rows_of(s);
            let (u0, u1) = (
                self.update_start[k] as usize,
                self.update_start[k + 1] as usize,
            );
            let mut covered = 0;
            for u in &self.updates[u0..u1] {
                assert!(u.target as usize > k);
                let t = &st.list[u.target as usize];
                let first = u.first as usize;
                assert_eq!(first, covered);
                covered += u.count as usize;
                for (i, &r) in self.rel[u.rel_start..u.rel_start + rows.len() - first]
                    .iter()
                    .enumerate()
                {
                    assert!((r as usize) < t.ld());
                    if i < u.count as usize {
                        assert_eq!(r, rows[first + i] - t.begin);
                    }
                }
            }
            assert_eq!(covered, rows.len());
        }
        assert!(self.bytes() > self.assembly.len() * 8);
    }
}
