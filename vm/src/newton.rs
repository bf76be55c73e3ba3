//! Newton's method on the CETM energy with a cached symbolic Cholesky factorisation.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltError;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use crate::{Vm, VmError};

/// Stopping rule of [`Vm::newton`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct NewtonOptions {
    /// Stop when the gradient's Euclidean norm is below this (default `1e-10`).
    pub tolerance: f64,
    /// Give up after this many Newton steps (default 50).
    pub max_iterations: u32,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions {
            tolerance: 1e-10,
            max_iterations: 50,
        }
    }
}

impl NewtonOptions {
    /// Sets the gradient-norm tolerance.
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }
    /// Sets the iteration limit.
    pub fn with_max_iterations(mut self, max_iterations: u32) -> Self {
        self.max_iterations = max_iterations;
        self
    }
}

/// What a successful Newton solve did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonReport {
    /// Newton steps taken (factorisations); 0 when the start was already flat.
    pub iterations: u32,
    /// Gradient norm at the returned `u`.
    pub gradient_norm: f64,
}

/// Symbolic factorisation and a workspace large enough for every numeric factorisation and
/// solve that follows.
pub(crate) fn analyse(
    pattern: &SymbolicSparseColMat<u32>,
) -> Result<(SymbolicCholesky<u32>, MemBuffer), VmError> {
    let symbolic = factorize_symbolic_cholesky(
        pattern.as_ref(),
        Side::Lower,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams::default(),
    )
    .map_err(|e| VmError::Symbolic(format!("{e:?}")))?;
    let req = StackReq::any_of(&[
        symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
        symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
    ]);
    let workspace = MemBuffer::try_new(req).map_err(|e| VmError::Symbolic(format!("{e:?}")))?;
    Ok((symbolic, workspace))
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

impl Vm {
    /// Solves for the flat metric from the current `u` (the previous frame's, a warm start).
    ///
    /// Each iteration evaluates the gradient and Hessian, stops when `||g||_2` is below the
    /// tolerance, and otherwise takes the Newton step `u -= H^-1 g`, halved until `||g||`
    /// decreases (a safeguard; the full step is taken whenever it reduces `||g||`). On error `u` is restored
    /// to its value at the call, so a failed frame does not spoil the next warm start.
    /// Allocates nothing.
    pub fn newton(&mut self, options: &NewtonOptions) -> Result<NewtonReport, VmError> {
        if !self.metric_set {
            return Err(VmError::MetricNotSet);
        }
        self.u_saved.copy_from_slice(&self.u);
        let result = self.newton_loop(options);
        if result.is_err() {
            self.u.copy_from_slice(&self.u_saved);
            // Leave lengths, gradient and Hessian consistent with the restored u.
            self.evaluate();
        }
        result
    }

    fn newton_loop(&mut self, options: &NewtonOptions) -> Result<NewtonReport, VmError> {
        let n = self.u.len();
        let mut iteration = 0u32;
        self.evaluate();
        let mut gradient_norm = norm(&self.grad);
        loop {
            if !gradient_norm.is_finite() {
                return Err(VmError::NonFinite { iteration });
            }
            if gradient_norm < options.tolerance {
                return Ok(NewtonReport {
                    iterations: iteration,
                    gradient_norm,
                });
            }
            if iteration >= options.max_iterations {
                return Err(VmError::NotConverged {
                    iterations: iteration,
                    gradient_norm,
                });
            }
            self.newton_step(n)?;
            iteration += 1;
            // Damping: the Newton direction d = -H^-1 g descends ||g||^2 / 2 (its derivative
            // along d is -||g||^2), so halve the step until ||g|| decreases. The full step is
            // tried first and nearly always accepted; the evaluation at the accepted point is
            // the next iteration's.
            self.u_base.copy_from_slice(&self.u);
            let mut alpha = 1.0;
            loop {
                for ((u, b), s) in self.u.iter_mut().zip(&self.u_base).zip(&self.step) {
                    *u = b + alpha * s;
                }
                self.evaluate();
                let trial = norm(&self.grad);
                if trial.is_finite() && trial <= (1.0 - 1e-4 * alpha) * gradient_norm {
                    gradient_norm = trial;
                    break;
                }
                alpha *= 0.5;
                if alpha < 1e-12 {
                    // No decrease along the Newton direction: round-off floor or a failure.
                    return Err(VmError::NotConverged {
                        iterations: iteration,
                        gradient_norm,
                    });
                }
            }
        }
    }

    /// Factors the Hessian of the last evaluation and solves `H step = -g` in place.
    fn newton_step(&mut self, n: usize) -> Result<(), VmError> {
        let stack = MemStack::new(&mut self.workspace);
        let matrix = SparseColMatRef::new(self.pattern.as_ref(), &self.hvals);
        let llt = self
            .symbolic
            .factorize_numeric_llt(
                &mut self.factor,
                matrix,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )
            .map_err(|e| match e {
                LltError::NonPositivePivot { index } => {
                    VmError::NotPositiveDefinite { pivot: index }
                }
            })?;
        for (s, g) in self.step.iter_mut().zip(&self.grad) {
            *s = -g;
        }
        let stack = MemStack::new(&mut self.workspace);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut self.step, n, 1),
            Par::Seq,
            stack,
        );
        Ok(())
    }
}
