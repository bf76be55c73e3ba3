//! The numeric Cholesky factor that Newton steps and conjugate gradients apply, stored in
//! double or single precision by the engine ([`bdmorph_cholesky::Cholesky`]; see
//! [`FactorPrecision`] for what each precision costs and gives).
//!
//! A single-precision factor is an excellent preconditioner: the relative error of its solve
//! was 4.5e-6 at 10K and 8e-5 at 100K unknowns, so conjugate gradients with the factor of the
//! current Hessian gain four to five digits per iteration, and with an older factor contract
//! as fast as with its double-precision twin (whose own error, the Hessian's change, is far
//! larger). The Newton tolerance is unchanged: every step is checked by a double-precision
//! gradient.

use bdmorph_cholesky::{CholeskyError, FactorPrecision};

use crate::{Vm, VmError};

/// Conjugate-gradient iterations a Newton step may take with a new single-precision factor
/// before that factor is judged too coarse for the Hessian (see [`Vm::factorize`]); one or
/// two suffice when single precision is adequate.
pub(crate) const FRESH_SINGLE_CG: u32 = 6;

/// The VM's error for a failed factorisation or solve.
pub(crate) fn vm_error(e: CholeskyError) -> VmError {
    match e {
        CholeskyError::NotPositiveDefinite { pivot } | CholeskyError::Singular { pivot, .. } => {
            VmError::NotPositiveDefinite { pivot }
        }
        CholeskyError::NonFinite { column } => VmError::NotPositiveDefinite { pivot: column },
        CholeskyError::NoFactor => VmError::NoFactor,
        CholeskyError::Length {
            what,
            expected,
            got,
        } => VmError::Length {
            what,
            expected,
            got,
        },
        other => VmError::Symbolic(other.to_string()),
    }
}

impl Vm {
    /// Chooses how the numeric Cholesky factor is stored (default
    /// [`FactorPrecision::Auto`]). Allocates the buffers the choice needs and frees the other
    /// precision's; the current factor is dropped, so the next Newton step factors anew. A
    /// single-precision factor that failed on this program is tried again.
    pub fn set_factor_precision(&mut self, precision: FactorPrecision) {
        self.chol.set_precision(precision);
        self.factor_ready = false;
    }

    /// The precision the next factorisation uses: [`FactorPrecision::Double`] or
    /// [`FactorPrecision::Single`] (never `Auto`). Single precision falls back to double for
    /// good when it fails on this program (see [`Vm::factorize`]).
    pub fn factor_precision(&self) -> FactorPrecision {
        self.chol.precision()
    }

    /// Factors the Hessian of the last evaluation numerically into the preallocated factor,
    /// in the precision [`Vm::factor_precision`] names, by the engine's own supernodal
    /// kernels (faer's for a simplicial factor). A single-precision factorisation that fails
    /// (a Hessian value beyond `f32`'s range, or a pivot lost to rounding: the Hessian is too
    /// ill-conditioned for it) gives single precision up for this program and factors in
    /// double precision instead, allocating the double-precision factor on that first
    /// fallback. Allocates nothing otherwise.
    ///
    /// Fails with [`VmError::NotPositiveDefinite`] when the Hessian is not numerically
    /// positive definite (for instance before any evaluation, when its values are all zero,
    /// or when one of them is not finite).
    pub fn factorize(&mut self) -> Result<(), VmError> {
        self.factor_ready = false;
        self.chol.factorize(&self.hvals).map_err(vm_error)?;
        self.factor_ready = true;
        Ok(())
    }

    /// [`Vm::factorize`] by faer's general supernodal factorisation even where the engine
    /// has its own: the baseline of the benchmarks and tests. Its factor is the same up to
    /// rounding.
    pub fn factorize_with_faer(&mut self) -> Result<(), VmError> {
        self.factor_ready = false;
        self.chol
            .factorize_with_faer(&self.hvals)
            .map_err(vm_error)?;
        self.factor_ready = true;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cg::tests::patch;
    use crate::NewtonOptions;
    use bdmorph_cholesky::SINGLE_FROM_VALUES;

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
        let mut hx = vec![0.0; x.len()];
        vm.chol
            .pattern()
            .symmetric_product(vm.hessian_values(), x, &mut hx);
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
        assert!(single.chol.factor_is_single());
        assert!(refined > 0);
    }

    #[test]
    fn a_single_precision_newton_step_is_refined_to_double_accuracy() {
        let (mut vm, sa, sb) = setup();
        vm.set_factor_precision(FactorPrecision::Single);
        vm.set_metric_lerp(&sa, &sb, 0.7).expect("metric");
        vm.evaluate();
        let step = vm.factor_and_solve().expect("definite").to_vec();
        assert!(vm.chol.factor_is_single());
        let refined = relative_residual(&vm, &step);
        assert!(refined < 1e-12, "{refined:e}");
        // One application of the single-precision factor is only that accurate.
        let once = vm.solve().expect("factor").to_vec();
        let coarse = relative_residual(&vm, &once);
        assert!(coarse > 1e-10 && coarse < 1e-4, "{coarse:e}");
    }
}
