//! The factorisation object: a pattern analysed once, numeric factorisations into buffers it
//! owns, solves in place; in double or single precision.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{LltError, LltRegularization};
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholeskyRaw};
use faer::sparse::SparseColMatRef;
use faer::traits::ComplexField;
use faer::{Conj, MatMut, Par, Side};

use crate::analysis::{Analysis, FactorCost, Ordering, Supernodal};
use crate::numeric::{Failure, Real};
use crate::triangular::SupernodalSolve;
use crate::{CholeskyError, LowerPattern};

/// Stored values of the factor from which [`FactorPrecision::Auto`] keeps it in single
/// precision: 8 MB in double precision, four times this machine's per-core L2 cache. At 10K
/// unknowns (0.48M values) single precision saved about 10% of a factorisation and 7% of a
/// solve, which the extra solve a new factor then needs (its first step is refined by
/// conjugate gradients) cancels; at 1.6M values and above it saved 17-34%.
pub const SINGLE_FROM_VALUES: usize = 1_000_000;

/// How the numeric factor is stored.
///
/// Large factors are memory-bound: a solve streams every stored value twice, and beyond the
/// caches the factorisation's many small supernodes do too. Stored in single precision the
/// factor takes half the bytes; on the benchmark disks (nested dissection, supernodal) the
/// factorisation and a solve take 0.83 and 0.66 of their double-precision time at 30K
/// unknowns (1.6M stored values), 0.66 and 0.67 at 100K (6.2M values), and about 0.9 at 10K
/// (0.48M values, within the caches). A single-precision factor's solve is only accurate to
/// that precision (a relative error of 4.5e-6 at 10K and 8e-5 at 100K unknowns on the
/// morph's Hessians): it is meant as the preconditioner of an iterative solve (conjugate
/// gradients), as the morph uses it. The arithmetic of the engine's own solves is in double
/// precision either way.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FactorPrecision {
    /// Single precision from [`SINGLE_FROM_VALUES`] stored values of the factor, double
    /// below.
    Auto,
    /// Double precision (`f64`): a solve is exact to rounding. The default.
    #[default]
    Double,
    /// Single precision (`f32`): half the memory and memory traffic; a solve with it is a
    /// preconditioner that an iterative method refines.
    Single,
}

/// How a [`Cholesky`] is set up.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct CholeskyOptions {
    /// The fill-reducing ordering (default [`Ordering::Amd`]).
    pub ordering: Ordering,
    /// Supernodal or simplicial (default [`Supernodal::Auto`]).
    pub supernodal: Supernodal,
    /// How the factor is stored (default [`FactorPrecision::Double`]).
    pub precision: FactorPrecision,
    /// Right-hand sides the solves' workspace holds room for at once (default 1; more grows
    /// it, once).
    pub columns: usize,
}

impl Default for CholeskyOptions {
    fn default() -> Self {
        CholeskyOptions {
            ordering: Ordering::Amd,
            supernodal: Supernodal::Auto,
            precision: FactorPrecision::Double,
            columns: 1,
        }
    }
}

impl CholeskyOptions {
    /// Sets the ordering.
    pub fn with_ordering(mut self, ordering: Ordering) -> Self {
        self.ordering = ordering;
        self
    }

    /// Sets the supernodal choice.
    pub fn with_supernodal(mut self, supernodal: Supernodal) -> Self {
        self.supernodal = supernodal;
        self
    }

    /// Sets the precision.
    pub fn with_precision(mut self, precision: FactorPrecision) -> Self {
        self.precision = precision;
        self
    }

    /// Sets the number of right-hand sides to make room for.
    pub fn with_columns(mut self, columns: usize) -> Self {
        self.columns = columns;
        self
    }
}

/// Which kernels a factorisation or solve runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kernels {
    /// The engine's own where it has them (supernodal factors), faer's otherwise.
    Own,
    /// faer's: the baseline.
    Faer,
}

/// A Cholesky factorisation `P A Pᵀ = L Lᵀ` of symmetric positive definite matrices with one
/// fixed pattern: analysed once, factored and solved into buffers it owns, allocation-free
/// after set-up. See the [crate documentation](crate) for an example.
pub struct Cholesky {
    pattern: LowerPattern,
    analysis: Analysis,
    /// Double-precision values of `L` (empty while only single precision is used).
    double: Vec<f64>,
    /// Single-precision values of `L` (empty unless single precision is wanted).
    single: Vec<f32>,
    /// The matrix's values rounded to single precision (for faer's single factorisation).
    values32: Vec<f32>,
    /// Right-hand sides rounded to single precision (for faer's single solves).
    rhs32: Vec<f32>,
    /// The engine's supernodal solves (`None` for a simplicial factor: faer solves).
    solver: Option<SupernodalSolve>,
    workspace: MemBuffer,
    /// Right-hand sides the workspace holds room for.
    columns: usize,
    /// Single precision is wanted (resolved from the requested precision).
    want_single: bool,
    /// Single precision failed on this pattern: double from then on, until the precision is
    /// set again.
    single_failed: bool,
    /// The ready factor, if any: `Some(true)` for the single-precision one.
    ready: Option<bool>,
    /// Scratch copies of the factor's top for a factorisation on several threads, in the
    /// precision in use (empty when it stays on one thread).
    scratch_double: Vec<f64>,
    scratch_single: Vec<f32>,
}

impl std::fmt::Debug for Cholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Cholesky")
            .field("dim", &self.dim())
            .field("factor_nnz", &self.factor_nnz())
            .field("supernodal", &self.is_supernodal())
            .field("precision", &self.precision())
            .field("ready", &self.ready)
            .finish_non_exhaustive()
    }
}

impl Cholesky {
    /// Analyses `pattern` with the default options (AMD, supernodal when it pays, double
    /// precision, room for one right-hand side).
    pub fn new(pattern: &LowerPattern) -> Result<Cholesky, CholeskyError> {
        Cholesky::with_options(pattern, CholeskyOptions::default())
    }

    /// Analyses `pattern` as `options` say and allocates the factor and every buffer.
    pub fn with_options(
        pattern: &LowerPattern,
        options: CholeskyOptions,
    ) -> Result<Cholesky, CholeskyError> {
        let analysis = Analysis::new(pattern, &options.ordering, options.supernodal)?;
        let len_val = analysis.symbolic.len_val();
        let want_single = resolve(options.precision, len_val);
        let columns = options.columns.max(1);
        let workspace = analysis.workspace(columns, true)?;
        let solver = analysis.structure.clone().map(|st| {
            let mut solver = SupernodalSolve::new(st);
            solver.reserve(columns);
            solver
        });
        let mut this = Cholesky {
            pattern: pattern.clone(),
            analysis,
            double: Vec::new(),
            single: Vec::new(),
            values32: Vec::new(),
            rhs32: Vec::new(),
            solver,
            workspace,
            columns,
            want_single,
            single_failed: false,
            ready: None,
            scratch_double: Vec::new(),
            scratch_single: Vec::new(),
        };
        this.allocate();
        Ok(this)
    }

    /// Assembles the symmetric `n` by `n` matrix whose entry `pairs[k]` (either triangle)
    /// receives `values[k]` (entries of one slot add up: give each off-diagonal pair once),
    /// analyses it with the default options, makes room for solves with `columns`
    /// right-hand sides, and factors it.
    pub fn assemble(
        n: usize,
        pairs: &[(u32, u32)],
        values: &[f64],
        columns: usize,
    ) -> Result<Cholesky, CholeskyError> {
        if pairs.len() != values.len() {
            return Err(CholeskyError::Length {
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
        let mut chol =
            Cholesky::with_options(&pattern, CholeskyOptions::default().with_columns(columns))?;
        chol.factorize(&matrix)?;
        Ok(chol)
    }

    /// Keeps only the wanted precision's buffers: at a million unknowns the factor takes
    /// hundreds of megabytes. A fresh zeroed allocation is untouched pages until used.
    fn allocate(&mut self) {
        let (len_val, nnz, n) = (self.factor_nnz(), self.pattern.nnz(), self.dim());
        let scratch = self.analysis.plan.as_ref().map_or(0, |p| p.scratch_len());
        if self.want_single {
            zeroed(&mut self.single, len_val);
            zeroed(&mut self.values32, nnz);
            zeroed(&mut self.rhs32, n * self.columns);
            zeroed(&mut self.scratch_single, scratch);
            self.double = Vec::new();
            self.scratch_double = Vec::new();
        } else {
            zeroed(&mut self.double, len_val);
            zeroed(&mut self.scratch_double, scratch);
            self.single = Vec::new();
            self.values32 = Vec::new();
            self.rhs32 = Vec::new();
            self.scratch_single = Vec::new();
        }
    }

    /// The pattern this factorisation was analysed for.
    pub fn pattern(&self) -> &LowerPattern {
        &self.pattern
    }

    /// Matrix dimension.
    pub fn dim(&self) -> usize {
        self.pattern.dim()
    }

    /// Stored values of the factor `L`.
    pub fn factor_nnz(&self) -> usize {
        self.analysis.symbolic.len_val()
    }

    /// Threads a factorisation uses: the bins of independent subtrees it was split into for
    /// the threads of rayon's pool when it was analysed (1 when a split does not pay: small
    /// factors, one thread, simplicial factors).
    pub fn factor_threads(&self) -> usize {
        self.analysis.plan.as_ref().map_or(1, |p| p.threads())
    }

    /// Threads a solve uses: the bins of independent subtrees the triangular solves were
    /// split into for the threads of rayon's pool when this was built (1 when a split does
    /// not pay). A solve runs split only in a pool of more than one thread, and a solve with
    /// a sparse right-hand side ([`Cholesky::solve_in_place_sparse`]) never does.
    pub fn solve_threads(&self) -> usize {
        self.solver.as_ref().map_or(1, |s| s.threads())
    }

    /// Keeps this factor's solves on the calling thread from now on (they were split over
    /// rayon's pool when it was built: [`Cholesky::solve_threads`]). For callers whose solves
    /// alternate with work of their own on one thread: the pool's workers fall asleep in
    /// between, and waking them for each solve can cost more than the split saves (a heat
    /// method query on 11K vertices, two threads, measured a median of 1.96 ms split against
    /// 1.55 ms on one thread).
    pub fn keep_solves_on_one_thread(&mut self) {
        if let Some(solver) = self.solver.as_mut() {
            solver.drop_split();
        }
    }

    /// Whether the factor is supernodal (the engine's own kernels factor and solve) rather
    /// than simplicial (faer's).
    pub fn is_supernodal(&self) -> bool {
        matches!(
            self.analysis.symbolic.raw(),
            SymbolicCholeskyRaw::Supernodal(_)
        )
    }

    /// The estimated work of a factorisation and of a solve.
    pub fn cost(&self) -> FactorCost {
        self.analysis.cost()
    }

    /// Bytes of the numeric factorisation's plan beyond the factor itself (0 when faer
    /// factors).
    pub fn plan_bytes(&self) -> usize {
        self.analysis.plan.as_ref().map_or(0, |p| p.bytes())
    }

    /// Whether a factor is ready for solves.
    pub fn is_ready(&self) -> bool {
        self.ready.is_some()
    }

    /// Whether the ready factor is the single-precision one.
    pub fn factor_is_single(&self) -> bool {
        self.ready == Some(true)
    }

    /// The precision the next factorisation uses: [`FactorPrecision::Double`] or
    /// [`FactorPrecision::Single`] (never `Auto`). Single precision falls back to double for
    /// good when it fails on this pattern (see [`Cholesky::factorize`] and
    /// [`Cholesky::give_up_single`]).
    pub fn precision(&self) -> FactorPrecision {
        if self.want_single && !self.single_failed {
            FactorPrecision::Single
        } else {
            FactorPrecision::Double
        }
    }

    /// Chooses how the factor is stored. Allocates the buffers the choice needs and frees
    /// the other precision's; the current factor is dropped. A single precision that failed
    /// on this pattern is tried again.
    pub fn set_precision(&mut self, precision: FactorPrecision) {
        self.want_single = resolve(precision, self.factor_nnz());
        self.single_failed = false;
        self.ready = None;
        self.allocate();
    }

    /// Gives single precision up for this pattern (until the precision is set again): for a
    /// caller whose iterative refinement found the single-precision factor too coarse. The
    /// ready factor, if any, stays usable.
    pub fn give_up_single(&mut self) {
        self.single_failed = true;
    }

    /// Makes room in the workspace for solves with up to `columns` right-hand sides at once
    /// (allocates only when it grows).
    pub fn reserve_columns(&mut self, columns: usize) -> Result<(), CholeskyError> {
        if columns <= self.columns {
            return Ok(());
        }
        self.workspace = self.analysis.workspace(columns, true)?;
        self.columns = columns;
        if let Some(solver) = &mut self.solver {
            solver.reserve(columns);
        }
        if !self.rhs32.is_empty() {
            self.rhs32 = vec![0.0; self.dim() * columns];
        }
        Ok(())
    }

    /// Factors the matrix with these lower-triangle `values` (one per slot of the pattern),
    /// by the engine's own supernodal kernels or, for a simplicial factor, faer's. Allocates
    /// nothing.
    ///
    /// In single precision, a factorisation that fails (a value beyond `f32`'s range, a
    /// pivot lost to rounding: the matrix is too ill-conditioned for it) factors in double
    /// precision instead (allocating the double-precision factor on that first fallback), and
    /// when that succeeds, gives single precision up for this pattern. Fails with
    /// [`CholeskyError::NotPositiveDefinite`] (a pivot not positive),
    /// [`CholeskyError::Singular`] (a pivot within rounding error of zero: in double
    /// precision, within `max(4 k, n) eps` of its diagonal entry for `k` the entries of its
    /// row of `L` and `n` unknowns), [`CholeskyError::NonFinite`] or
    /// [`CholeskyError::Length`]; no factor is ready then. A matrix singular to double
    /// precision may pass in single precision (its last pivots are then single precision's
    /// own rounding): single-precision factors are for preconditioners, whose iterations
    /// check what they give.
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), CholeskyError> {
        self.factorize_by(values, Kernels::Own)
    }

    /// [`Cholesky::factorize`] by faer's general factorisation even where the engine has its
    /// own: the baseline of the benchmarks and tests. Its factor is the same up to rounding.
    /// Its first supernodal call may allocate faer's dense kernels' workspace.
    pub fn factorize_with_faer(&mut self, values: &[f64]) -> Result<(), CholeskyError> {
        self.factorize_by(values, Kernels::Faer)
    }

    fn factorize_by(&mut self, values: &[f64], kernels: Kernels) -> Result<(), CholeskyError> {
        self.ready = None;
        if values.len() != self.pattern.nnz() {
            return Err(CholeskyError::Length {
                what: "matrix values",
                expected: self.pattern.nnz(),
                got: values.len(),
            });
        }
        let tried_single = self.precision() == FactorPrecision::Single;
        if tried_single && self.factorize_single(values, kernels).is_ok() {
            self.mark_ready(true);
            return Ok(());
        }
        let double = self.factorize_double(values, kernels);
        if tried_single {
            // Single precision is given up only when double precision succeeds where it
            // failed: a matrix that is not positive definite fails in both, and the next one
            // may suit single precision again.
            self.single_failed = double.is_ok();
        }
        double?;
        self.mark_ready(false);
        Ok(())
    }

    /// The double-precision factorisation (allocating its buffer on a first fallback from
    /// single precision).
    fn factorize_double(&mut self, values: &[f64], kernels: Kernels) -> Result<(), CholeskyError> {
        let len_val = self.factor_nnz();
        zeroed(&mut self.double, len_val);
        let scratch = self.analysis.plan.as_ref().map_or(0, |p| p.scratch_len());
        zeroed(&mut self.scratch_double, scratch);
        let Cholesky {
            analysis,
            double,
            pattern,
            workspace,
            solver,
            scratch_double,
            ..
        } = self;
        factor_into(
            analysis,
            solver,
            kernels,
            pattern,
            workspace,
            values,
            (double, scratch_double),
            values,
        )
    }

    /// The single-precision factorisation.
    fn factorize_single(&mut self, values: &[f64], kernels: Kernels) -> Result<(), CholeskyError> {
        let Cholesky {
            analysis,
            single,
            values32,
            pattern,
            workspace,
            solver,
            scratch_single,
            ..
        } = self;
        if !own_kernels(analysis, solver, kernels) {
            // faer factors the matrix's values rounded to single precision.
            for (s, v) in values32.iter_mut().zip(values) {
                *s = *v as f32;
            }
            if !values32.iter().all(|s| s.is_finite()) {
                return Err(CholeskyError::NonFinite { column: 0 });
            }
        }
        factor_into(
            analysis,
            solver,
            kernels,
            pattern,
            workspace,
            values,
            (single, scratch_single),
            values32,
        )
    }

    /// Records the ready factor's precision (the supernodal solves were prepared for it by
    /// the factorisation).
    fn mark_ready(&mut self, single: bool) {
        self.ready = Some(single);
    }

    /// Solves `A X = B` in place for `columns` right-hand sides stored one after another
    /// (column-major, `dim` values each), by the engine's own supernodal solves or, for a
    /// simplicial factor, faer's. With a single-precision factor the result is only that
    /// accurate (see [`FactorPrecision::Single`]). Allocates nothing when the workspace has
    /// room for that many columns ([`Cholesky::reserve_columns`]), and grows it otherwise.
    /// Fails with [`CholeskyError::NoFactor`] before a successful factorisation.
    pub fn solve_in_place(&mut self, rhs: &mut [f64], columns: usize) -> Result<(), CholeskyError> {
        self.solve_by(rhs, columns, Kernels::Own, None)
    }

    /// [`Cholesky::solve_in_place`] for right-hand sides that are zero outside the rows
    /// `nonzero_rows` (in every column), such as the point sources of the heat method: the
    /// forward solve then visits only the supernodes on the elimination-tree paths from
    /// those rows, a small part of the factor (the backward solve is a full one). The same
    /// result, to the last bit, as [`Cholesky::solve_in_place`]; a right-hand side with a
    /// nonzero elsewhere is noticed and solved in full. Fails with
    /// [`CholeskyError::Pattern`] for a row outside the matrix.
    pub fn solve_in_place_sparse(
        &mut self,
        rhs: &mut [f64],
        columns: usize,
        nonzero_rows: &[u32],
    ) -> Result<(), CholeskyError> {
        if let Some(&r) = nonzero_rows.iter().find(|&&r| r as usize >= self.dim()) {
            return Err(CholeskyError::Pattern(format!(
                "row {r} is outside a {} by {} matrix",
                self.dim(),
                self.dim()
            )));
        }
        self.solve_by(rhs, columns, Kernels::Own, Some(nonzero_rows))
    }

    /// [`Cholesky::solve_in_place`] by faer's general solve (its dense triangular solve and
    /// matrix product per supernode) even where the engine has its own: the same result to
    /// rounding, the baseline of the benchmarks and tests.
    pub fn solve_with_faer(
        &mut self,
        rhs: &mut [f64],
        columns: usize,
    ) -> Result<(), CholeskyError> {
        self.solve_by(rhs, columns, Kernels::Faer, None)
    }

    fn solve_by(
        &mut self,
        rhs: &mut [f64],
        columns: usize,
        kernels: Kernels,
        nonzero_rows: Option<&[u32]>,
    ) -> Result<(), CholeskyError> {
        let Some(single) = self.ready else {
            return Err(CholeskyError::NoFactor);
        };
        let n = self.dim();
        if rhs.len() != n * columns {
            return Err(CholeskyError::Length {
                what: "right-hand sides",
                expected: n * columns,
                got: rhs.len(),
            });
        }
        self.reserve_columns(columns)?;
        if let (Some(solver), Kernels::Own) = (&mut self.solver, kernels) {
            match (single, nonzero_rows) {
                (true, None) => solver.solve_many(&self.single, rhs, columns),
                (false, None) => solver.solve_many(&self.double, rhs, columns),
                (true, Some(rows)) => solver.solve_many_sparse(&self.single, rhs, columns, rows),
                (false, Some(rows)) => solver.solve_many_sparse(&self.double, rhs, columns, rows),
            }
            return Ok(());
        }
        let symbolic = &self.analysis.symbolic;
        if single {
            let staged = &mut self.rhs32[..n * columns];
            for (r, v) in staged.iter_mut().zip(&*rhs) {
                *r = *v as f32;
            }
            LltRef::new(symbolic, &self.single).solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(staged, n, columns),
                Par::Seq,
                MemStack::new(&mut self.workspace),
            );
            for (v, r) in rhs.iter_mut().zip(&*staged) {
                *v = f64::from(*r);
            }
        } else {
            LltRef::new(symbolic, &self.double).solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(rhs, n, columns),
                Par::Seq,
                MemStack::new(&mut self.workspace),
            );
        }
        Ok(())
    }

    /// The ready factor's values in faer's layout (tests compare factors through this).
    #[cfg(test)]
    pub(crate) fn values(&self) -> (&[f64], &[f32]) {
        (&self.double, &self.single)
    }

    /// Makes `values` the ready double-precision factor.
    #[cfg(test)]
    pub(crate) fn set_double_factor(&mut self, values: Vec<f64>) {
        self.double = values;
        if let Some(solver) = &mut self.solver {
            solver.prepare(&self.double);
        }
        self.mark_ready(false);
    }

    #[cfg(test)]
    pub(crate) fn analysis(&self) -> &Analysis {
        &self.analysis
    }
}

/// Whether a factorisation by `kernels` runs the engine's own plan.
fn own_kernels(analysis: &Analysis, solver: &Option<SupernodalSolve>, kernels: Kernels) -> bool {
    analysis.plan.is_some() && solver.is_some() && kernels == Kernels::Own
}

/// Factors `values` into `factor` (of either precision): by the engine's plan, which checks
/// the pivots and writes the solves' reciprocal diagonal as it goes, or by faer on
/// `faer_values` (`values` in `T`), followed by the same pivot check and the solves'
/// preparation.
#[allow(clippy::too_many_arguments)]
fn factor_into<T: Real + ComplexField + Into<f64>>(
    analysis: &Analysis,
    solver: &mut Option<SupernodalSolve>,
    kernels: Kernels,
    pattern: &LowerPattern,
    workspace: &mut MemBuffer,
    values: &[f64],
    (factor, scratch): (&mut [T], &mut [T]),
    faer_values: &[T],
) -> Result<(), CholeskyError> {
    match (&analysis.plan, solver, kernels) {
        (Some(plan), Some(solver), Kernels::Own) => plan
            .factorize(
                values,
                factor,
                &mut analysis.pivots(solver.inv_diag_mut()),
                scratch,
            )
            .map_err(failure),
        (_, solver, _) => {
            let matrix = SparseColMatRef::new(pattern.pattern.as_ref(), faer_values);
            faer_llt(analysis, factor, matrix, workspace)?;
            check_pivots(analysis, values, factor)?;
            if let Some(solver) = solver {
                solver.prepare(factor);
            }
            Ok(())
        }
    }
}

/// Whether `precision` means single precision for a factor of `len_val` values.
fn resolve(precision: FactorPrecision, len_val: usize) -> bool {
    match precision {
        FactorPrecision::Auto => len_val >= SINGLE_FROM_VALUES,
        FactorPrecision::Double => false,
        FactorPrecision::Single => true,
    }
}

/// `v` with `len` values: kept if it has them, else a fresh zeroed allocation, which the
/// system provides as untouched pages (a `resize` would write hundreds of megabytes of zeros
/// for a large factor before its first use).
fn zeroed<T: Clone + Default>(v: &mut Vec<T>, len: usize) {
    if v.len() != len {
        *v = vec![T::default(); len];
    }
}

fn failure(f: Failure) -> CholeskyError {
    match f {
        Failure::Pivot(pivot) => CholeskyError::NotPositiveDefinite { pivot },
        Failure::Singular(pivot, ratio) => CholeskyError::Singular { pivot, ratio },
        Failure::NonFinite(column) => CholeskyError::NonFinite { column },
    }
}

/// faer's numeric factorisation of `matrix` (its lower triangle, in the analysed pattern)
/// into `factor`, on one thread.
fn faer_llt<T: ComplexField>(
    analysis: &Analysis,
    factor: &mut [T],
    matrix: SparseColMatRef<'_, u32, T>,
    workspace: &mut MemBuffer,
) -> Result<(), CholeskyError> {
    let simplicial = matches!(analysis.symbolic.raw(), SymbolicCholeskyRaw::Simplicial(_));
    analysis
        .symbolic
        .factorize_numeric_llt(
            factor,
            matrix,
            Side::Lower,
            LltRegularization::default(),
            Par::Seq,
            MemStack::new(workspace),
            Default::default(),
        )
        .map(|_| ())
        .map_err(|e| match e {
            // faer's simplicial factorisation counts its columns from 1.
            LltError::NonPositivePivot { index } => CholeskyError::NotPositiveDefinite {
                pivot: if simplicial {
                    index.saturating_sub(1)
                } else {
                    index
                },
            },
        })
}

/// Fails with [`CholeskyError::Singular`] at the first pivot `L_jj²` within rounding error
/// of zero, relative to the matrix's diagonal entry `a_jj`.
///
/// In single precision the bound is `4 k eps a_jj`, for `k` the entries of row `j` of `L` and
/// `eps` single precision's: the rounding error of the `k` terms subtracted from the pivot.
/// A pivot that low makes the single-precision factor worthless, and the caller falls back
/// to double precision (on the morph's Hessians the smallest ratio `L_jj² / a_jj` was 0.19
/// to 0.31 from 100K to 1M unknowns, against bounds of at most 2.6e-3).
///
/// In double precision the bound is `max(4 k, n) eps a_jj` for `n` unknowns: the errors made
/// in the earlier columns perturb the last pivots too, by up to about `n eps` of their
/// diagonal entry. The Laplacians of grids (singular: the constants are a null space) ended
/// with pivots of 0.06-0.17 `n eps` of their diagonal from 100 to 20K unknowns (or a
/// negative one), which a bound of `4 k eps` alone let through at 10K. A matrix whose
/// factorisation passes it is positive definite to within its rounding; a matrix that
/// fails it has a condition number beyond about `1 / (n eps)`, where a solve has no correct
/// digit left to give.
///
/// A matrix singular to double precision may pass in single precision, its last pivots
/// being single precision's own rounding: single-precision factors are preconditioners,
/// whose iterations (conjugate gradients) check what they give.
fn check_pivots<T: Real>(
    analysis: &Analysis,
    matrix: &[f64],
    factor: &[T],
) -> Result<(), CholeskyError> {
    let eps = T::epsilon();
    let n = if eps > f64::EPSILON {
        0.0
    } else {
        analysis.diag_at.len() as f64
    };
    for (j, ((&at, &slot), &scale)) in analysis
        .diag_at
        .iter()
        .zip(&analysis.diag_slot)
        .zip(&analysis.pivot_scale)
        .enumerate()
    {
        let l = factor[at].to_f64();
        let (pivot, a) = (l * l, matrix[slot as usize]);
        // NaN pivots fail too.
        let bound = scale.max(n) * eps * a;
        if pivot.partial_cmp(&bound) != Some(std::cmp::Ordering::Greater) {
            return Err(CholeskyError::Singular {
                pivot: j,
                ratio: pivot / a,
            });
        }
    }
    Ok(())
}
