//! Newton's method on the CETM energy with a cached symbolic Cholesky factorisation.

use bdmorph_cholesky::{
    Cholesky, CholeskyOptions, FactorCost, FactorPrecision, LowerPattern, Ordering, Supernodal,
};
use bdmorph_isa::HessianPattern;

use crate::cg::AbortRule;
use crate::factor::{vm_error, FRESH_SINGLE_CG};
use crate::tangent::tangent_extra_cg;
use crate::{Vm, VmError};

/// Stopping rule and factor policy of [`Vm::newton`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct NewtonOptions {
    /// Stop when the gradient's Euclidean norm is below this (default `1e-10`).
    pub tolerance: f64,
    /// Give up after this many Newton steps (default 50).
    pub max_iterations: u32,
    /// Largest change of any `u` the first trial of a step may make (default 2, a factor
    /// e = 2.7 on lengths); longer Newton steps are scaled down to it before the line search.
    pub step_cap: f64,
    /// Reuse the last numeric Cholesky factor (of an earlier iterate or an earlier frame) as
    /// the preconditioner of conjugate gradients on the current Hessian, refactoring when the
    /// contraction they show predicts more iterations than a factorisation costs (default
    /// `true`; see [`Vm::newton`]). The tolerance is unchanged: only the work per step
    /// differs. With `false` every step factors the current Hessian.
    pub reuse_factor: bool,
    /// A [`Vm::tangent`] will follow the solve with the same factor (default `false`): the
    /// choice between an earlier factor and a new one counts the tangent's solve too.
    pub tangent_follows: bool,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions {
            tolerance: 1e-10,
            max_iterations: 50,
            step_cap: 2.0,
            reuse_factor: true,
            tangent_follows: false,
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
    /// Sets whether a tangent will follow (see [`Self::tangent_follows`]).
    pub fn with_tangent_follows(mut self, tangent_follows: bool) -> Self {
        self.tangent_follows = tangent_follows;
        self
    }
    /// Sets whether an earlier numeric factor may be reused (see [`Self::reuse_factor`]).
    pub fn with_reuse_factor(mut self, reuse_factor: bool) -> Self {
        self.reuse_factor = reuse_factor;
        self
    }
}

/// What a successful Newton solve did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonReport {
    /// Newton steps taken (linear solves); 0 when the start was already flat.
    pub iterations: u32,
    /// Numeric Cholesky factorisations among them (the rest reused an earlier factor).
    pub factorizations: u32,
    /// Conjugate-gradient iterations of the steps that reused a factor.
    pub cg_iterations: u32,
    /// Gradient norm at the start.
    pub initial_gradient_norm: f64,
    /// Passes of the iteration stream, line-search trials included.
    pub passes: u32,
    /// Gradient norm at the returned `u`.
    pub gradient_norm: f64,
    /// Step halvings the line search needed over all iterations (0 when every full Newton
    /// step was accepted).
    pub backtracks: u32,
}

/// A step is accepted on the gradient alone when it brings `||g||` below this fraction of the
/// smallest norm seen so far in the solve.
const ACCEPT_RATIO: f64 = 0.5;
/// Conjugate-gradient iterations allowed per step (any iterate is a descent direction).
const MAX_CG: u32 = 25;

/// How many further conjugate-gradient iterations a step with an inherited factor may need
/// before refactoring is cheaper: a factorisation plus one solve, counted in iterations (a
/// solve and a product with `H`, about 1.15 solves). [`Vm::pcg`] stops a step as soon as the
/// contraction it has seen predicts more than that.
///
/// The costs are estimated from the factor's structure, not timed, so that a frame's work (and
/// its result, to the last bit) does not depend on the machine's load. A simplicial
/// factorisation and the solves are both memory-bound: their multiply-add counts compare
/// directly (measured factor/solve time 14 and 19 at 1K and 10K unknowns, model 7 and 17). A
/// supernodal one runs dense kernels whose speed grows with the supernodes as fast as the
/// multiply-adds do: on the benchmark disks with a nested-dissection ordering the measured
/// factor/solve time of the engine's own loops (`bdmorph_cholesky`) is
/// 3.1, 3.9-4.8 and 4.1-4.3 at 1K, 10K and 100K unknowns (fastest runs) while the
/// multiply-add ratio grows from 8 to 36. It is taken as 3.2: counting the conjugate-gradient
/// iterations and factorisations per frame of the benchmark sweeps at 2.8, 3.2, 3.5 and 4.7
/// and pricing them at those times, 3.2 was cheapest or tied at every size (10K: 0.73
/// factorisations and 2.2 iterations against 0.52 and 3.9 at 4.7, about 10% less work).
pub(crate) fn refactor_beyond(cost: &FactorCost) -> f64 {
    let ratio = if cost.supernodal {
        3.2
    } else {
        1.2 * cost.factor / cost.solve.max(1.0)
    };
    ((ratio + 1.0) / 1.15).clamp(2.0, 20.0)
}

/// Relative residual [`Vm::factor_and_solve`] refines a single-precision factor's step to:
/// what a double-precision solve of the benchmark Hessians reaches.
const EXACT_RELATIVE: f64 = 1e-13;

/// A solve's first step trusts the contraction an inherited factor showed before (see
/// [`Vm::newton`]) only when its start gradient is at least this fraction of the one it was
/// measured at: a start much closer to its solution (smaller steps in `t`) probes again.
const STALE_MEMORY: f64 = 2.0;

/// The Hessian's sparse Cholesky factorisation, analysed once (see
/// [`bdmorph_cholesky::Cholesky`]): with `ordering` (`ordering[new] = old`, a permutation
/// checked by the verifier), supernodal: a nested dissection's separators are dense blocks,
/// and the compiler only attaches one where that pays. Without an ordering, AMD, supernodal
/// when the engine judges it pays. Precision [`FactorPrecision::Auto`].
pub(crate) fn analyse(
    n: usize,
    hessian: &HessianPattern,
    ordering: Option<&[u32]>,
) -> Result<Cholesky, VmError> {
    let pattern = LowerPattern::from_csc(n, hessian.col_ptr.clone(), hessian.row_idx.clone())
        .map_err(vm_error)?;
    let options = CholeskyOptions::default().with_precision(FactorPrecision::Auto);
    let options = match ordering {
        Some(perm) => options
            .with_ordering(Ordering::Custom(perm.to_vec()))
            .with_supernodal(Supernodal::Always),
        None => options,
    };
    Cholesky::with_options(&pattern, options).map_err(vm_error)
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

impl Vm {
    /// Sets the test [`Vm::newton`] asks before every iteration (`None`, the default: none):
    /// when it answers `true` the solve stops with [`VmError::Interrupted`], `u` restored as
    /// for any error. The test must not allocate for a solve to allocate nothing.
    pub fn set_interrupt(&mut self, interrupt: Option<crate::Interrupt>) {
        self.interrupt = interrupt;
    }

    /// Solves for the flat metric from the current `u` (the previous frame's, a warm start).
    ///
    /// Each iteration evaluates the gradient and Hessian, stops when `||g||_2` is below the
    /// tolerance, and otherwise steps along `d = -H^-1 g`, with `H` the current Hessian or,
    /// when [`NewtonOptions::reuse_factor`] allows, the last factored one (any positive
    /// definite `H` gives a descent direction).
    ///
    /// A reused factor is abandoned for a new one as soon as the conjugate gradients' mean
    /// contraction per iteration predicts that finishing the step (plus, with
    /// [`NewtonOptions::tangent_follows`], the tangent's extra iterations with that factor)
    /// would cost more than a factorisation and a solve, estimated from the factor's structure
    /// so that the choice does not depend on the machine's load. The first step of a solve
    /// judges a factor inherited from an earlier solve by the contraction seen the last time
    /// that happened, without spending an iteration on it, unless its start is much closer to
    /// the solution than that one was.
    ///
    /// A trial step is accepted outright when it
    /// brings `||g||` below half the smallest norm seen so far in this solve: that can happen
    /// only finitely often before the tolerance is met, and it spares the energy evaluation,
    /// which costs more than the rest of a pass. Otherwise a reused factor is dropped and the
    /// current Hessian factored; with a fresh factor the step is halved until the CETM energy
    /// decreases enough (Armijo). Between the outright acceptances the energy decreases, and it
    /// is convex and bounded below on a valid metric, so the solve converges from any start.
    ///
    /// On error `u` is restored to its value at the call, so a failed frame does not spoil the
    /// next warm start. Allocates nothing (but see [`Vm::factor_and_solve`] about other
    /// threads).
    pub fn newton(&mut self, options: &NewtonOptions) -> Result<NewtonReport, VmError> {
        if !self.metric_set {
            return Err(VmError::MetricNotSet);
        }
        self.u_saved.copy_from_slice(&self.u);
        self.failure.clear();
        self.factor_current = false;
        let mut report = NewtonReport {
            iterations: 0,
            factorizations: 0,
            cg_iterations: 0,
            initial_gradient_norm: f64::NAN,
            passes: 0,
            gradient_norm: f64::NAN,
            backtracks: 0,
        };
        let result = self.newton_loop(options, &mut report);
        if let Err(e) = result {
            // Where it gave up, before restoring u: the triangles that make the metric hard.
            self.failure = self.worst_triangles(5);
            self.u.copy_from_slice(&self.u_saved);
            // Leave lengths, gradient and Hessian consistent with the restored u.
            self.evaluate();
            return Err(e);
        }
        Ok(report)
    }

    fn newton_loop(
        &mut self,
        options: &NewtonOptions,
        report: &mut NewtonReport,
    ) -> Result<(), VmError> {
        let n = self.u.len();
        self.evaluate_gradient();
        report.passes += 1;
        let mut gradient_norm = norm(&self.grad);
        let mut best = gradient_norm;
        report.initial_gradient_norm = gradient_norm;
        // Terms of the energy: one per corner computed and one per unknown.
        let terms = (self.temps.len() + n).max(1) as f64;
        loop {
            report.gradient_norm = gradient_norm;
            if !gradient_norm.is_finite() {
                return Err(VmError::NonFinite {
                    iteration: report.iterations,
                });
            }
            if gradient_norm < options.tolerance {
                return Ok(());
            }
            if let Some(interrupt) = &self.interrupt {
                if interrupt() {
                    return Err(VmError::Interrupted {
                        iteration: report.iterations,
                    });
                }
            }
            if report.iterations >= options.max_iterations {
                return Err(VmError::NotConverged {
                    iterations: report.iterations,
                    gradient_norm,
                });
            }
            let first = report.iterations == 0;
            let inherited = self.factor_ready && !self.factor_current;
            let mut fresh = !(self.factor_ready && options.reuse_factor);
            // Inexact Newton: solve only as accurately as this step can use (forcing term
            // min(0.01, ||g||)), and no more accurately than the tolerance needs: a linear
            // residual of half the tolerance. That bound binds only below ||g|| = sqrt(tol / 2),
            // where the step's quadratic remainder K ||g||^2 (K measured 0.2-0.8 on the
            // benchmark disks) stays below the other half. It spared 2-7% of the CG iterations
            // and a tenth of the factorisations against a tenth of the tolerance.
            let forcing = gradient_norm
                .min(0.01)
                .max(0.5 * options.tolerance / gradient_norm)
                .min(0.5);
            let rule = AbortRule {
                limit: self.refactor_beyond,
                tangent_follows: options.tangent_follows,
            };
            let (rate, measured_at) = self.inherited_rate;
            if !fresh
                && first
                && inherited
                && rate < 1.0
                && gradient_norm * STALE_MEMORY >= measured_at
            {
                // How the last inherited factor contracted, at a start at least as far from
                // its solution, predicts this one: refactor at once rather than spend an
                // iteration finding it too stale.
                let mut needed = forcing.ln() / rate.ln();
                if rule.tangent_follows {
                    needed += tangent_extra_cg(rate);
                }
                fresh = needed > rule.limit;
            }
            if !fresh {
                let outcome = self.pcg(true, forcing, MAX_CG, Some(rule));
                report.cg_iterations += outcome.iterations;
                if first && inherited {
                    self.inherited_rate = (outcome.rate, gradient_norm);
                }
                fresh = outcome.aborted;
            }
            if fresh {
                self.factorize()?;
                self.factor_current = true;
                let (iterations, extra) = self.fresh_step(forcing)?;
                report.factorizations += 1 + extra;
                report.cg_iterations += iterations;
            }
            report.iterations += 1;
            let slope: f64 = self.grad.iter().zip(&self.step).map(|(g, d)| g * d).sum();
            let longest = self.step.iter().fold(0.0f64, |m, d| m.max(d.abs()));
            let mut alpha = if longest > options.step_cap {
                options.step_cap / longest
            } else {
                1.0
            };
            self.u_base.copy_from_slice(&self.u);
            let grad0 = gradient_norm;

            // The trial step, judged on the gradient alone.
            self.move_along(alpha);
            self.evaluate_gradient();
            report.passes += 1;
            let trial = norm(&self.grad);
            if trial.is_finite() && trial <= ACCEPT_RATIO * best {
                gradient_norm = trial;
                best = best.min(trial);
                continue;
            }
            // Not good enough: back to the base point.
            self.u.copy_from_slice(&self.u_base);
            if !fresh {
                // The reused factor has gone stale: factor the current Hessian and retry.
                // That needs the base point's Hessian, not its energy (whose pass costs
                // several times more): the energy is evaluated only if the fresh step is
                // rejected too.
                self.evaluate_gradient();
                report.passes += 1;
                self.factor_ready = false;
                report.iterations -= 1;
                continue;
            }
            // With its energy this time, for the line search.
            self.evaluate();
            report.passes += 1;
            // Armijo backtracking on the convex energy E along the fresh Newton direction,
            // whose slope g.d = -g H^-1 g is negative.
            let energy0 = self.energy;
            loop {
                self.move_along(alpha);
                self.evaluate();
                report.passes += 1;
                let trial = norm(&self.grad);
                let e1 = self.energy.value;
                let armijo = e1 <= energy0.value + 1e-4 * alpha * slope;
                // Near the solution the decrease of E drops below its round-off; there the
                // gradient norm decides. The round-off of a sum of `terms` terms grows like
                // its square root: 3.6e-14 of the magnitude at 1K unknowns, 3.4e-13 at 100K.
                let noise = 2.0
                    * f64::EPSILON
                    * terms.sqrt()
                    * energy0.magnitude.max(self.energy.magnitude);
                let flat = (e1 - energy0.value).abs() <= noise && trial < grad0;
                if e1.is_finite() && trial.is_finite() && (armijo || flat) {
                    gradient_norm = trial;
                    best = best.min(trial);
                    break;
                }
                alpha *= 0.5;
                report.backtracks += 1;
                if alpha < 1e-12 {
                    return Err(VmError::NotConverged {
                        iterations: report.iterations,
                        gradient_norm: grad0,
                    });
                }
            }
        }
    }

    /// `u = u_base + alpha * step`.
    fn move_along(&mut self, alpha: f64) {
        for ((u, b), s) in self.u.iter_mut().zip(&self.u_base).zip(&self.step) {
            *u = b + alpha * s;
        }
    }

    /// Factors the Hessian of the last [`Vm::evaluate`] numerically (reusing the symbolic
    /// factorisation computed in [`Vm::new`]) and solves `H step = -g`, returning the Newton
    /// step, one value per unknown. This is the linear-algebra half of one Newton iteration,
    /// exposed so that it can be measured and checked on its own; `u`, the gradient and the
    /// Hessian values are left unchanged. With a single-precision factor
    /// ([`Vm::factor_precision`]) the step is refined by conjugate gradients to a relative
    /// residual of 1e-13. Allocates nothing.
    ///
    /// Fails with [`VmError::NotPositiveDefinite`] when the Hessian is not numerically
    /// positive definite (for instance before any evaluation, when its values are all zero).
    pub fn factor_and_solve(&mut self) -> Result<&[f64], VmError> {
        self.factorize()?;
        self.fresh_step(EXACT_RELATIVE)?;
        Ok(&self.step)
    }

    /// Solves `H step = -g` with the last numeric factor (which may be of an earlier Hessian),
    /// returning the step: one application of the factor, the work of a conjugate-gradient
    /// iteration's preconditioner (a single-precision factor gives the step to that
    /// precision). Fails with [`VmError::NoFactor`] before any factorisation. Allocates
    /// nothing.
    pub fn solve(&mut self) -> Result<&[f64], VmError> {
        if !self.factor_ready {
            return Err(VmError::NoFactor);
        }
        self.solve_step(false);
        Ok(&self.step)
    }

    /// [`Vm::solve`] by faer's general supernodal solve (its dense triangular solve and
    /// matrix product per supernode) instead of the VM's own loops: the same result to
    /// rounding, kept as the baseline those loops are measured against (`benches/frame.rs`,
    /// group `solve_faer`). Fails with [`VmError::NoFactor`] before any factorisation.
    pub fn solve_with_faer(&mut self) -> Result<&[f64], VmError> {
        if !self.factor_ready {
            return Err(VmError::NoFactor);
        }
        self.solve_step(true);
        Ok(&self.step)
    }

    /// `step = -H^-1 g` with the current factor, which must be ready (one application; with a
    /// single-precision factor, accurate to that precision), by faer when `with_faer`.
    fn solve_step(&mut self, with_faer: bool) {
        debug_assert!(self.factor_ready);
        for (s, g) in self.step.iter_mut().zip(&self.grad) {
            *s = -g;
        }
        let solved = if with_faer {
            self.chol.solve_with_faer(&mut self.step, 1)
        } else {
            self.chol.solve_in_place(&mut self.step, 1)
        };
        // The factor is ready (checked by the callers) and the step has one value per unknown.
        debug_assert!(solved.is_ok(), "{solved:?}");
    }

    /// The Newton step with the factor just computed from the current Hessian, to relative
    /// residual `relative`: one solve in double precision; in single precision, conjugate
    /// gradients preconditioned by it. A single-precision factor whose iterations do not get
    /// there within [`FRESH_SINGLE_CG`] is too coarse for this Hessian: single precision is
    /// given up for this program and the step solved with a double-precision factor (one
    /// more factorisation, counted). Returns the conjugate-gradient iterations and the
    /// factorisations added.
    pub(crate) fn fresh_step(&mut self, relative: f64) -> Result<(u32, u32), VmError> {
        if !self.chol.factor_is_single() {
            self.solve_step(false);
            return Ok((0, 0));
        }
        let outcome = self.pcg(true, relative, FRESH_SINGLE_CG, None);
        if outcome.converged {
            return Ok((outcome.iterations, 0));
        }
        self.chol.give_up_single();
        self.factorize()?;
        self.solve_step(false);
        Ok((outcome.iterations, 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bdmorph_isa::{Program, ProgramParts};

    /// An `n` by `n` grid over the unit square, jittered, two triangles per cell.
    fn grid(n: usize) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let h = 1.0 / (n - 1) as f64;
        let mut pos = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let inside = i > 0 && j > 0 && i < n - 1 && j < n - 1;
                let k = (j * n + i) as f64;
                let jitter = if inside { 0.2 * h } else { 0.0 };
                pos.push([
                    i as f64 * h + jitter * (k * 1.3).sin(),
                    j as f64 * h + jitter * (k * 2.1).cos(),
                ]);
            }
        }
        let id = |i: usize, j: usize| (j * n + i) as u32;
        let mut faces = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (pos, faces)
    }

    #[test]
    fn nested_dissection_and_amd_give_the_same_solution() {
        let (source, faces) = grid(40);
        // The target: the grid bent into a squeezed annulus sector, so that u is far from 0.
        let target: Vec<[f64; 2]> = source
            .iter()
            .map(|p| {
                let r = 0.3 + p[0];
                let a = 2.5 * p[1];
                [r * a.cos(), 0.5 * r * a.sin()]
            })
            .collect();
        let compiled = bdmorph_compiler::compile(&source, &faces).expect("compiles");
        let nd = compiled
            .ordering()
            .expect("a 38 x 38 grid is ordered")
            .to_vec();
        assert_eq!(
            nd,
            bdmorph_compiler::nested_dissection(&compiled, &source, bdmorph_compiler::LEAF_SIZE)
                .expect("orders")
        );
        let with = |ordering: Option<Vec<u32>>| {
            Program::from_parts(ProgramParts {
                ordering,
                ..compiled.to_parts()
            })
            .expect("valid")
        };
        let mut solutions = Vec::new();
        for ordering in [None, Some(nd.clone())] {
            let mut vm = Vm::new(with(ordering.clone())).expect("vm");
            if ordering.is_some() {
                assert!(vm.factor_is_supernodal());
            }
            let a = vm.squared_lengths(&source).expect("lengths");
            let b = vm.squared_lengths(&target).expect("lengths");
            vm.set_metric_lerp(&a, &b, 0.8).expect("metric");
            let report = vm.newton(&NewtonOptions::default()).expect("converges");
            assert!(report.iterations >= 2, "{report:?}");
            solutions.push((vm.u().to_vec(), vm.factor_nnz()));
        }
        let (amd, nd) = (&solutions[0], &solutions[1]);
        assert!(amd.0.iter().any(|u| u.abs() > 0.02), "u is not trivial");
        let diff = amd
            .0
            .iter()
            .zip(&nd.0)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(diff < 1e-12, "the orderings' solutions differ by {diff:e}");
        // Both factor something of the Hessian's size, not a dense matrix.
        let n = amd.0.len();
        assert!(amd.1 < n * n / 10 && nd.1 < n * n / 10);
    }

    #[test]
    fn factor_and_solve_returns_the_newton_step() {
        // A jittered hexagonal patch: a centre, a ring of 6 and a ring of 12 vertices, so
        // there are 7 unknowns and off-diagonal Hessian entries.
        let mut positions = vec![[0.0, 0.0]];
        for (ring, n) in [(1.0, 6), (2.0, 12)] {
            for i in 0..n {
                let a = i as f64 / n as f64 * std::f64::consts::TAU;
                let r = ring * (1.0 + 0.05 * (i as f64 * 1.7).sin());
                positions.push([r * a.cos(), r * a.sin()]);
            }
        }
        let mut faces: Vec<[u32; 3]> = (0..6).map(|i| [0, 1 + i, 1 + (i + 1) % 6]).collect();
        for i in 0..6u32 {
            let (inner, next_inner) = (1 + i, 1 + (i + 1) % 6);
            let (o0, o1, o2) = (7 + 2 * i, 7 + 2 * i + 1, 7 + (2 * i + 2) % 12);
            faces.push([inner, o0, o1]);
            faces.push([inner, o1, next_inner]);
            faces.push([next_inner, o1, o2]);
        }
        let program = bdmorph_compiler::compile(&positions, &faces).expect("compiles");
        let mut vm = Vm::new(program).expect("vm");
        let n = vm.program().n_unknowns();
        assert_eq!(n, 7);
        assert!((2.0..=20.0).contains(&vm.refactor_beyond));
        let cost = vm.chol.cost();
        assert!(cost.factor > 0.0 && cost.solve > 0.0);

        // Before any evaluation the Hessian is zero: no factorisation.
        let sq = vm.squared_lengths(&positions).expect("lengths");
        vm.set_metric(&sq).expect("metric");
        assert!(matches!(
            vm.factor_and_solve(),
            Err(VmError::NotPositiveDefinite { .. })
        ));

        let u: Vec<f64> = (0..n).map(|k| 0.1 * (k as f64 - 3.0)).collect();
        vm.set_u(&u).expect("u");
        vm.evaluate();
        let grad = vm.gradient().to_vec();
        let hvals = vm.hessian_values().to_vec();
        let step = vm.factor_and_solve().expect("positive definite").to_vec();
        assert_eq!(vm.u(), &u[..], "u is left unchanged");

        // H step = -g, H symmetric and stored as its lower triangle.
        let h = vm.program().hessian();
        let mut hs = vec![0.0; n];
        for col in 0..n {
            let slots = h.col_ptr[col] as usize..h.col_ptr[col + 1] as usize;
            for (&row, &value) in h.row_idx[slots.clone()].iter().zip(&hvals[slots]) {
                let row = row as usize;
                hs[row] += value * step[col];
                if row != col {
                    hs[col] += value * step[row];
                }
            }
        }
        for k in 0..n {
            assert!(
                (hs[k] + grad[k]).abs() < 1e-12,
                "row {k}: {} vs {}",
                hs[k],
                -grad[k]
            );
        }
        assert!(
            grad.iter().any(|g| g.abs() > 1e-3),
            "a non-trivial right-hand side"
        );

        // Repeating it gives the same step.
        assert_eq!(vm.factor_and_solve().expect("again"), &step[..]);
    }
}
