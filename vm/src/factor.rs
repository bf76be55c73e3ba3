//! The numeric Cholesky factor that Newton steps and conjugate gradients apply, stored in
//! double or single precision.
//!
//! Large factors are memory-bound: a solve streams every stored value twice, and beyond the
//! caches the factorisation's many small supernodes do too. Stored in single precision the
//! factor takes half the bytes; on the benchmark disks (nested dissection, supernodal) the
//! factorisation and a solve take 0.83 and 0.66 of their double-precision time at 30K
//! unknowns (1.6M stored values), 0.66 and 0.67 at 100K (6.2M values), and about 0.9 at 10K
//! (0.48M values, within the caches). A single-precision factor is still an excellent
//! preconditioner: the relative error of its solve was 4.5e-6 at 10K and 8e-5 at 100K
//! unknowns, so conjugate gradients with the factor of the current Hessian gain four to five
//! digits per iteration, and with an older factor contract as fast as with its
//! double-precision twin (whose own error, the Hessian's change, is far larger). The Newton
//! tolerance is unchanged: every step is checked by a double-precision gradient.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{LltError, LltRegularization};
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky};
use faer::sparse::SparseColMatRef;
use faer::traits::ComplexField;
use faer::{Conj, MatMut, Par, Side};

use crate::numeric::{Failure, SupernodalLlt};
use crate::triangular::SupernodalSolve;
use crate::{Vm, VmError};

/// Stored values of the factor from which [`FactorPrecision::Auto`] keeps it in single
/// precision: 8 MB in double precision, four times this machine's per-core L2 cache. At 10K
/// unknowns (0.48M values) single precision saved about 10% of a factorisation and 7% of a
/// solve, which the extra solve a new factor then needs (its first step is refined by
/// conjugate gradients) cancels; at 1.6M values and above it saved 17-34%.
pub const SINGLE_FROM_VALUES: usize = 1_000_000;

/// Conjugate-gradient iterations a Newton step may take with a new single-precision factor
/// before that factor is judged too coarse for the Hessian (see [`Vm::factorize`]); one or
/// two suffice when single precision is adequate.
pub(crate) const FRESH_SINGLE_CG: u32 = 6;

/// How the numeric Cholesky factor is stored (see [`Vm::set_factor_precision`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FactorPrecision {
    /// Single precision from [`SINGLE_FROM_VALUES`] stored values of the factor, double
    /// below (the default).
    #[default]
    Auto,
    /// Double precision (`f64`): a solve with the factor of the current Hessian is exact to
    /// rounding.
    Double,
    /// Single precision (`f32`): half the memory and memory traffic; a solve with it is a
    /// preconditioner that conjugate gradients refine.
    Single,
}

/// The factor's values and the buffers of the single-precision path.
#[derive(Debug, Default)]
pub(crate) struct FactorStore {
    /// Double-precision values (empty until a double factorisation is needed).
    pub double: Vec<f64>,
    /// Single-precision values (empty unless single precision is wanted).
    pub single: Vec<f32>,
    /// The Hessian's values rounded to single precision.
    values: Vec<f32>,
    /// A right-hand side rounded to single precision.
    rhs: Vec<f32>,
    /// Single precision is wanted (resolved from the requested [`FactorPrecision`]).
    want_single: bool,
    /// Single precision failed on this program (a pivot lost to rounding, a value out of its
    /// range, or conjugate gradients that did not converge with a new factor): double from
    /// then on, until the precision is set again.
    single_failed: bool,
    /// The ready factor (if any) is the single-precision one.
    pub ready_single: bool,
    /// The flattened supernodal structure for the triangular solves (`None` for a
    /// simplicial factor, which faer's own solve takes).
    pub solver: Option<SupernodalSolve>,
    /// The numeric factorisation's plan (`None` for a simplicial factor, which faer
    /// factors).
    pub llt: Option<SupernodalLlt>,
}

impl FactorStore {
    /// Buffers for `precision`, for a factor of `len_val` values, a Hessian of `nnz` stored
    /// values and `n` unknowns.
    pub fn new(precision: FactorPrecision, len_val: usize, nnz: usize, n: usize) -> FactorStore {
        let mut store = FactorStore::default();
        store.set_precision(precision, len_val, nnz, n);
        store
    }

    /// Resolves `precision`, allocates what it needs and frees the other precision's buffers
    /// (a double-precision fallback allocates its own when it happens). No factor is ready
    /// afterwards.
    pub fn set_precision(
        &mut self,
        precision: FactorPrecision,
        len_val: usize,
        nnz: usize,
        n: usize,
    ) {
        self.want_single = match precision {
            FactorPrecision::Auto => len_val >= SINGLE_FROM_VALUES,
            FactorPrecision::Double => false,
            FactorPrecision::Single => true,
        };
        self.single_failed = false;
        self.ready_single = false;
        // Only the wanted precision's buffers are kept: at a million vertices the factor
        // takes hundreds of megabytes.
        if self.want_single {
            zeroed(&mut self.single, len_val);
            zeroed(&mut self.values, nnz);
            zeroed(&mut self.rhs, n);
            self.double = Vec::new();
        } else {
            zeroed(&mut self.double, len_val);
            self.single = Vec::new();
            self.values = Vec::new();
            self.rhs = Vec::new();
        }
    }

    /// Records that the factor just computed is the single- (`single`) or double-precision
    /// one, and prepares the supernodal solves for it.
    fn mark_ready(&mut self, single: bool) {
        self.ready_single = single;
        if let Some(solver) = &mut self.solver {
            if single {
                solver.prepare(&self.single);
            } else {
                solver.prepare(&self.double);
            }
        }
    }

    /// Whether the next factorisation tries single precision.
    pub fn single(&self) -> bool {
        self.want_single && !self.single_failed
    }

    /// Gives single precision up for this program (until the precision is set again).
    pub fn give_up_single(&mut self) {
        self.single_failed = true;
    }
}

/// `v` with `len` values: kept if it has them, else a fresh zeroed allocation, which the
/// system provides as untouched pages (a `resize` would write hundreds of megabytes of
/// zeros for a large factor before its first use).
pub(crate) fn zeroed<T: Clone + Default>(v: &mut Vec<T>, len: usize) {
    if v.len() != len {
        *v = vec![T::default(); len];
    }
}

/// The numeric Cholesky factorisation of `matrix` (its lower triangle, in the pattern
/// `symbolic` was computed for) into `factor`, on one thread, with `workspace` as scratch.
pub(crate) fn numeric_llt<T: ComplexField>(
    symbolic: &SymbolicCholesky<u32>,
    factor: &mut [T],
    matrix: SparseColMatRef<'_, u32, T>,
    workspace: &mut MemBuffer,
) -> Result<(), VmError> {
    symbolic
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
            LltError::NonPositivePivot { index } => VmError::NotPositiveDefinite { pivot: index },
        })
}

/// `x = L^-T L^-1 x` with the ready factor. A supernodal factor is applied by
/// [`SupernodalSolve`] (double-precision arithmetic on either precision's values) unless
/// `with_faer`; a simplicial one (or any with `with_faer`) by faer, in place in double
/// precision or through the single-precision buffer (rounded in, widened out).
pub(crate) fn apply(
    symbolic: &SymbolicCholesky<u32>,
    store: &mut FactorStore,
    workspace: &mut MemBuffer,
    x: &mut [f64],
    with_faer: bool,
) {
    let n = x.len();
    if let (Some(solver), false) = (&mut store.solver, with_faer) {
        if store.ready_single {
            solver.solve(&store.single, x);
        } else {
            solver.solve(&store.double, x);
        }
        return;
    }
    if store.ready_single {
        let FactorStore { single, rhs, .. } = store;
        for (r, v) in rhs.iter_mut().zip(&*x) {
            *r = *v as f32;
        }
        LltRef::new(symbolic, single).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            MemStack::new(workspace),
        );
        for (v, r) in x.iter_mut().zip(&*rhs) {
            *v = f64::from(*r);
        }
    } else {
        LltRef::new(symbolic, &store.double).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, n, 1),
            Par::Seq,
            MemStack::new(workspace),
        );
    }
}

impl Vm {
    /// Chooses how the numeric Cholesky factor is stored (default
    /// [`FactorPrecision::Auto`]). Allocates the buffers the choice needs and frees the other
    /// precision's; the current factor is dropped, so the next Newton step factors anew. A
    /// single-precision factor that failed on this program is tried again.
    pub fn set_factor_precision(&mut self, precision: FactorPrecision) {
        let (len_val, nnz, n) = (self.symbolic.len_val(), self.hvals.len(), self.u.len());
        self.store.set_precision(precision, len_val, nnz, n);
        self.factor_ready = false;
    }

    /// The precision the next factorisation uses: [`FactorPrecision::Double`] or
    /// [`FactorPrecision::Single`] (never `Auto`). Single precision falls back to double for
    /// good when it fails on this program (see [`Vm::factorize`]).
    pub fn factor_precision(&self) -> FactorPrecision {
        if self.store.single() {
            FactorPrecision::Single
        } else {
            FactorPrecision::Double
        }
    }

    /// Factors the Hessian of the last evaluation numerically into the preallocated factor,
    /// in the precision [`Vm::factor_precision`] names: a supernodal factor by the VM's own
    /// loops, a simplicial one by faer. A single-precision factorisation that fails (a
    /// Hessian value beyond `f32`'s range, or a pivot lost to rounding: the Hessian is too
    /// ill-conditioned for it) gives single precision up for this program and factors in
    /// double precision instead, allocating the double-precision factor on that first
    /// fallback. Allocates nothing otherwise.
    ///
    /// Fails with [`VmError::NotPositiveDefinite`] when the Hessian is not numerically
    /// positive definite (for instance before any evaluation, when its values are all zero,
    /// or when one of them is not finite).
    pub fn factorize(&mut self) -> Result<(), VmError> {
        self.factorize_with(false)
    }

    /// [`Vm::factorize`] by faer's general supernodal factorisation even where the VM has its
    /// own: the baseline of the benchmarks and tests. Its factor is the same up to rounding.
    pub fn factorize_with_faer(&mut self) -> Result<(), VmError> {
        self.factorize_with(true)
    }

    fn factorize_with(&mut self, with_faer: bool) -> Result<(), VmError> {
        self.factor_ready = false;
        if self.store.single() {
            if self.factorize_single(with_faer) {
                self.store.mark_ready(true);
                self.factor_ready = true;
                return Ok(());
            }
            self.store.give_up_single();
        }
        zeroed(&mut self.store.double, self.symbolic.len_val());
        match (&self.store.llt, with_faer) {
            (Some(llt), false) => {
                llt.factorize(&self.hvals, &mut self.store.double)
                    .map_err(|e| match e {
                        Failure::Pivot(pivot) | Failure::NonFinite(pivot) => {
                            VmError::NotPositiveDefinite { pivot }
                        }
                    })?
            }
            _ => numeric_llt(
                &self.symbolic,
                &mut self.store.double,
                SparseColMatRef::new(self.pattern.as_ref(), &self.hvals),
                &mut self.workspace,
            )?,
        }
        self.store.mark_ready(false);
        self.factor_ready = true;
        Ok(())
    }

    /// The single-precision factorisation; false when a value leaves `f32`'s range or a
    /// pivot is not positive.
    fn factorize_single(&mut self, with_faer: bool) -> bool {
        let FactorStore {
            single,
            values,
            llt,
            ..
        } = &mut self.store;
        // Finite values with positive pivots keep every entry of L below the square root of
        // its diagonal's: no overflow inside (a NaN pivot fails the positivity test too).
        if let (Some(llt), false) = (llt, with_faer) {
            return llt.factorize(&self.hvals, single).is_ok();
        }
        let mut finite = true;
        for (s, v) in values.iter_mut().zip(&self.hvals) {
            *s = *v as f32;
            finite &= s.is_finite();
        }
        if !finite {
            return false;
        }
        let matrix = SparseColMatRef::new(self.pattern.as_ref(), &values[..]);
        numeric_llt(&self.symbolic, single, matrix, &mut self.workspace).is_ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cg::symmetric_product;
    use crate::cg::tests::patch;
    use crate::NewtonOptions;

    /// A VM on the jittered 7 x 7 grid (25 unknowns) and the squared lengths of the grid and
    /// of a bent copy.
    fn setup() -> (Vm, Vec<f64>, Vec<f64>) {
        let (a, faces) = patch(0.05);
        let b: Vec<[f64; 2]> = a
            .iter()
            .map(|p| [p[0] * (1.0 + 0.1 * p[1]), p[1] + 0.05 * p[0] * p[0]])
            .collect();
        let vm = Vm::new(bdmorph_compiler::compile(&a, &faces).expect("compiles")).expect("vm");
        let (sa, sb) = (
            vm.squared_lengths(&a).expect("a"),
            vm.squared_lengths(&b).expect("b"),
        );
        (vm, sa, sb)
    }

    /// `max |H x + g| / |g|` for the VM's current Hessian and gradient.
    fn relative_residual(vm: &Vm, x: &[f64]) -> f64 {
        let h = vm.program().hessian();
        let mut hx = vec![0.0; x.len()];
        symmetric_product(&h.col_ptr, &h.row_idx, vm.hessian_values(), x, &mut hx);
        let g = vm.gradient();
        let g_norm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
        hx.iter()
            .zip(g)
            .map(|(a, b)| (a + b).abs())
            .fold(0.0, f64::max)
            / g_norm
    }

    #[test]
    fn small_factors_are_double_unless_asked() {
        let (mut vm, _, _) = setup();
        assert!(vm.factor_nnz() < SINGLE_FROM_VALUES);
        assert_eq!(vm.factor_precision(), FactorPrecision::Double);
        vm.set_factor_precision(FactorPrecision::Single);
        assert_eq!(vm.factor_precision(), FactorPrecision::Single);
        vm.set_factor_precision(FactorPrecision::Auto);
        assert_eq!(vm.factor_precision(), FactorPrecision::Double);
    }

    #[test]
    fn single_precision_frames_match_double_precision_ones() {
        let (mut double, sa, sb) = setup();
        let (mut single, _, _) = setup();
        single.set_factor_precision(FactorPrecision::Single);
        let options = NewtonOptions::default();
        let mut refined = 0;
        for t in [0.0, 0.3, 0.6, 1.0, 0.8] {
            let mut reports = Vec::new();
            for vm in [&mut double, &mut single] {
                vm.set_metric_lerp(&sa, &sb, t).expect("metric");
                reports.push(vm.newton(&options).expect("converges"));
            }
            let diff = double
                .u()
                .iter()
                .zip(single.u())
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(reports[1].gradient_norm < 1e-10, "t {t}: {reports:?}");
            assert!(diff < 1e-9, "t {t}: u differs by {diff:e}");
            refined += reports[1].cg_iterations;
        }
        // The single-precision factor was used (its new factors refined by CG), not dropped.
        assert_eq!(single.factor_precision(), FactorPrecision::Single);
        assert!(single.store.ready_single);
        assert!(refined > 0);
    }

    #[test]
    fn a_single_precision_newton_step_is_refined_to_double_accuracy() {
        let (mut vm, sa, sb) = setup();
        vm.set_factor_precision(FactorPrecision::Single);
        vm.set_metric_lerp(&sa, &sb, 0.7).expect("metric");
        vm.evaluate();
        let step = vm.factor_and_solve().expect("definite").to_vec();
        assert!(vm.store.ready_single);
        let refined = relative_residual(&vm, &step);
        assert!(refined < 1e-12, "{refined:e}");
        // One application of the single-precision factor is only that accurate.
        let once = vm.solve().expect("factor").to_vec();
        let coarse = relative_residual(&vm, &once);
        assert!(coarse > 1e-10 && coarse < 1e-4, "{coarse:e}");
    }

    #[test]
    fn values_beyond_single_range_fall_back_to_double() {
        let (mut vm, sa, sb) = setup();
        vm.set_metric_lerp(&sa, &sb, 0.5).expect("metric");
        vm.evaluate();
        let unscaled = vm.factor_and_solve().expect("definite").to_vec();
        vm.set_factor_precision(FactorPrecision::Single);
        // H' = D H D with D = 1 but 1e40 for unknown 3: still positive definite, but its
        // diagonal there (1e80 times the original) overflows f32. H' x' = -D g has the
        // solution x' = D^-1 x.
        let (k, scale) = (3, 1e40);
        let h = vm.program().hessian().clone();
        for col in 0..h.col_ptr.len() - 1 {
            for slot in h.col_ptr[col] as usize..h.col_ptr[col + 1] as usize {
                let row = h.row_idx[slot] as usize;
                for index in [row, col] {
                    if index == k {
                        vm.hvals[slot] *= scale;
                    }
                }
            }
        }
        vm.grad[k] *= scale;
        vm.factorize()
            .expect("positive definite in double precision");
        assert!(!vm.store.ready_single);
        assert_eq!(vm.factor_precision(), FactorPrecision::Double);
        let step = vm.solve().expect("factor").to_vec();
        for (i, (x, y)) in step.iter().zip(&unscaled).enumerate() {
            let x = if i == k { x * scale } else { *x };
            assert!((x - y).abs() < 1e-10 * y.abs().max(1e-3), "{i}: {x} vs {y}");
        }
        // Asking again tries single precision again.
        vm.set_factor_precision(FactorPrecision::Single);
        assert_eq!(vm.factor_precision(), FactorPrecision::Single);
    }
}
