//! The derivative of the flattening along a line of metrics, which lets the next frame of a
//! morph start from a Hermite prediction instead of a plain extrapolation.

use crate::{Vm, VmError};

/// Relative residual the tangent's solve aims for: an error `e` in the tangent moves a
/// predicted start by `e h |du/ds|` for a step `h`, far below what the prediction itself
/// misses by.
const TANGENT_RELATIVE: f64 = 1e-6;

/// Conjugate-gradient iterations a tangent may take: with a factor too stale to converge
/// quickly, a truncated solve is still a fair derivative for a predictor.
const MAX_TANGENT_CG: u32 = 8;

/// The smallest relative residual [`Vm::solve_hessian`] aims for.
const SOLVE_RELATIVE: f64 = 1e-14;

/// Conjugate-gradient iterations [`Vm::solve_hessian`] tries with a factor before it factors
/// the current Hessian (and then again with that factor): as many as a Newton step allows.
const SOLVE_CG: u32 = 25;

/// Iterations a tangent's solve takes with a factor of the same frame (whose Hessian differs
/// from the current one only by the last Newton step).
const FRESH_TANGENT_CG: f64 = 2.0;

/// Iterations a tangent's solve is expected to take beyond [`FRESH_TANGENT_CG`] with a
/// factor whose conjugate gradients contract the residual by `rate` per iteration: what
/// keeping an old factor through a frame costs its tangent.
pub(crate) fn tangent_extra_cg(rate: f64) -> f64 {
    let max = f64::from(MAX_TANGENT_CG);
    if rate > 0.0 && rate < 1.0 {
        (TANGENT_RELATIVE.ln() / rate.ln() - FRESH_TANGENT_CG).clamp(0.0, max)
    } else if rate <= 0.0 {
        0.0
    } else {
        max
    }
}

/// What [`Vm::tangent`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TangentReport {
    /// Conjugate-gradient iterations of the solve.
    pub cg_iterations: u32,
    /// Whether the solve reached its relative residual of 1e-6 (otherwise the tangent is the
    /// iterate after the iteration limit, still an approximation of the derivative).
    pub converged: bool,
    /// A numeric factorisation was needed first (there was no factor).
    pub factorized: bool,
}

impl Vm {
    /// The derivative `du/ds` of the flattening log scale factors at the current solution,
    /// along a line of metrics whose squared edge lengths change at `rate` per unit of `s`
    /// (one value per edge slot; for a morph `l²(t) = (1 - t) a + t b`, `rate = b - a`).
    ///
    /// The solution `u(s)` keeps the gradient `g(u(s), s)` at zero, so `H du/ds = -∂g/∂s`.
    /// `∂g/∂s` comes in closed form from the last evaluation's corners (their cotangents and
    /// each edge's `d log l / ds = rate / (2 l²)`), and the system is solved by conjugate
    /// gradients preconditioned by the last numeric factor (factored first if there is none).
    /// Must follow an evaluation at the current `u` and metric, as a successful
    /// [`Vm::newton`] leaves them; fails with [`VmError::NotEvaluated`] otherwise. Leaves `u`,
    /// the metric, the gradient and the Hessian as they were. Allocates nothing.
    ///
    /// ```
    /// use bdmorph_vm::{NewtonOptions, Vm};
    /// // A hexagon fan whose centre moves: the flattening changes smoothly with t.
    /// let mut a = vec![[0.0, 0.0]];
    /// let mut b = vec![[0.3, 0.1]];
    /// for i in 0..6 {
    ///     let t = i as f64 * std::f64::consts::PI / 3.0;
    ///     a.push([t.cos(), t.sin()]);
    ///     b.push([1.2 * t.cos(), t.sin()]);
    /// }
    /// let faces: Vec<[u32; 3]> = (0..6).map(|i| [0, 1 + i, 1 + (i + 1) % 6]).collect();
    /// let mut vm = Vm::new(bdmorph_compiler::compile(&a, &faces)?)?;
    /// let (la, lb) = (vm.squared_lengths(&a)?, vm.squared_lengths(&b)?);
    /// let rate: Vec<f64> = la.iter().zip(&lb).map(|(a, b)| b - a).collect();
    /// let opts = NewtonOptions::default();
    /// let mut solve = |vm: &mut Vm, t: f64| -> Result<Vec<f64>, bdmorph_vm::VmError> {
    ///     vm.set_metric_lerp(&la, &lb, t)?;
    ///     vm.newton(&opts)?;
    ///     Ok(vm.u().to_vec())
    /// };
    /// let (before, after) = (solve(&mut vm, 0.5 - 1e-5)?, solve(&mut vm, 0.5 + 1e-5)?);
    /// solve(&mut vm, 0.5)?;
    /// vm.tangent(&rate)?;
    /// for (k, d) in vm.tangent_values().iter().enumerate() {
    ///     let central = (after[k] - before[k]) / 2e-5;
    ///     assert!((d - central).abs() < 1e-6, "{d} {central}");
    /// }
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn tangent(&mut self, rate: &[f64]) -> Result<TangentReport, VmError> {
        self.check_len("metric rate", self.l0.len(), rate.len())?;
        if !self.evaluated {
            return Err(VmError::NotEvaluated);
        }
        for ((d, r), l) in self.dlog.iter_mut().zip(rate).zip(&self.l0) {
            *d = 0.5 * r / (l * l);
        }
        self.plan
            .metric_derivative(&self.temps, &self.dlog, &mut self.dtheta, &mut self.dgrad);
        let factorized = !self.factor_ready;
        if factorized {
            self.factorize()?;
        }
        let outcome = self.pcg(false, TANGENT_RELATIVE, MAX_TANGENT_CG, None);
        Ok(TangentReport {
            cg_iterations: outcome.iterations,
            converged: outcome.converged,
            factorized,
        })
    }

    /// Solves `H x = rhs` for the Hessian of the last evaluation (one value of `rhs` per
    /// unknown) to a residual below `relative` times that of `x = 0` (at least `1e-14`):
    /// conjugate gradients preconditioned by a factor of the last solve's Hessians, after
    /// factoring the current Hessian when there is none (the last factor is older than the
    /// last [`Vm::newton`]) or when the one there does not reach the residual within the
    /// iterations a Newton step would give it. This is what the derivative of a
    /// solution with respect to a parameter of its gradient takes (`du/dp = -H^-1 dg/dp`).
    /// Must follow an evaluation at the current `u` and metric, as a successful
    /// [`Vm::newton`] leaves them (fails with [`VmError::NotEvaluated`] otherwise). Uses the
    /// tangent's buffer (so [`Vm::tangent_values`] afterwards holds `x`) and leaves `u`, the
    /// metric, the gradient and the Hessian as they were. Allocates nothing.
    pub fn solve_hessian(&mut self, rhs: &[f64], relative: f64) -> Result<&[f64], VmError> {
        let relative = if relative.is_nan() {
            SOLVE_RELATIVE
        } else {
            relative.max(SOLVE_RELATIVE)
        };
        self.check_len("right-hand side", self.u.len(), rhs.len())?;
        if !self.evaluated {
            return Err(VmError::NotEvaluated);
        }
        for (d, r) in self.dgrad.iter_mut().zip(rhs) {
            *d = -r;
        }
        // A factor of an earlier solve would take many iterations (measured on the free-hole
        // frames of `benches/holes.rs`: 1.8 times the time at 10K vertices): one of this
        // solve's Hessians takes one or two.
        let mut fresh = false;
        if !(self.factor_ready && self.factor_current) {
            self.factorize()?;
            self.factor_current = true;
            fresh = true;
        }
        let mut outcome = self.pcg(false, relative, SOLVE_CG, None);
        if !outcome.converged && !fresh {
            // A stale factor: the current Hessian's converges in a step or two.
            self.factorize()?;
            self.factor_current = true;
            outcome = self.pcg(false, relative, SOLVE_CG, None);
        }
        if !outcome.converged {
            return Err(VmError::SolveNotConverged {
                iterations: outcome.iterations,
            });
        }
        Ok(&self.tangent)
    }

    /// The tangent of the last successful [`Vm::tangent`], one value per unknown.
    pub fn tangent_values(&self) -> &[f64] {
        &self.tangent
    }
}

#[cfg(test)]
mod tests {
    use crate::{NewtonOptions, Vm, VmError};

    /// A VM on a jittered 7 x 7 grid (25 unknowns), the squared lengths of the grid and of a
    /// sheared, bent copy, and the rate between them.
    fn setup() -> (Vm, Vec<f64>, Vec<f64>, Vec<f64>) {
        let (a, faces) = crate::cg::tests::patch(0.1);
        let b: Vec<[f64; 2]> = a
            .iter()
            .map(|p| [p[0] * (1.0 + 0.08 * p[1]), p[1] + 0.04 * p[0] * p[0]])
            .collect();
        let vm = Vm::new(bdmorph_compiler::compile(&a, &faces).expect("compiles")).unwrap();
        let (la, lb) = (
            vm.squared_lengths(&a).unwrap(),
            vm.squared_lengths(&b).unwrap(),
        );
        let rate = la.iter().zip(&lb).map(|(a, b)| b - a).collect();
        (vm, la, lb, rate)
    }

    #[test]
    fn metric_derivative_matches_central_differences_of_the_gradient() {
        let (mut vm, la, lb, rate) = setup();
        // At an arbitrary u (not a solution), t = 0.4.
        let u: Vec<f64> = (0..vm.u().len()).map(|k| 0.05 * (k as f64).sin()).collect();
        let gradient_at = |vm: &mut Vm, t: f64| {
            vm.set_metric_lerp(&la, &lb, t).unwrap();
            vm.set_u(&u).unwrap();
            vm.evaluate_gradient();
            vm.gradient().to_vec()
        };
        let h = 1e-6;
        let (plus, minus) = (gradient_at(&mut vm, 0.4 + h), gradient_at(&mut vm, 0.4 - h));
        gradient_at(&mut vm, 0.4);
        vm.tangent(&rate).unwrap();
        for (k, (p, m)) in plus.iter().zip(&minus).enumerate() {
            let central = (p - m) / (2.0 * h);
            assert!(
                (vm.dgrad[k] - central).abs() < 1e-7 + 1e-6 * central.abs(),
                "unknown {k}: {} vs {central}",
                vm.dgrad[k]
            );
        }
    }

    #[test]
    fn tangent_predicts_the_next_solution_to_second_order() {
        let (mut vm, la, lb, rate) = setup();
        let options = NewtonOptions::default();
        let solve = |vm: &mut Vm, t: f64| {
            vm.set_metric_lerp(&la, &lb, t).unwrap();
            vm.newton(&options).unwrap();
            vm.u().to_vec()
        };
        let u0 = solve(&mut vm, 0.3);
        let report = vm.tangent(&rate).unwrap();
        assert!(report.converged, "{report:?}");
        let du = vm.tangent_values().to_vec();
        // The tangent leaves the state alone: the gradient is still that of the solution.
        assert!(vm.gradient().iter().all(|g| g.abs() < 1e-10));
        let err = |h: f64, vm: &mut Vm| {
            let u1 = solve(vm, 0.3 + h);
            let euler = u0
                .iter()
                .zip(&du)
                .zip(&u1)
                .map(|((u, d), v)| (u + h * d - v).abs());
            let plain = u0.iter().zip(&u1).map(|(u, v)| (u - v).abs());
            (euler.fold(0.0, f64::max), plain.fold(0.0, f64::max))
        };
        let (e1, p1) = err(0.004, &mut vm);
        let (e2, _) = err(0.002, &mut vm);
        // First order without the tangent, second order with it.
        assert!(e1 < 0.05 * p1, "{e1} vs {p1}");
        let order = (e1 / e2).log2();
        assert!((1.7..2.3).contains(&order), "order {order}: {e1} {e2}");
    }

    #[test]
    fn tangent_needs_an_evaluation_of_the_current_state() {
        let (mut vm, la, lb, rate) = setup();
        vm.set_metric_lerp(&la, &lb, 0.5).unwrap();
        assert_eq!(vm.tangent(&rate), Err(VmError::NotEvaluated));
        vm.newton(&NewtonOptions::default()).unwrap();
        assert!(vm.tangent(&rate).is_ok());
        vm.set_u(&vec![0.0; vm.u().len()]).unwrap();
        assert_eq!(vm.tangent(&rate), Err(VmError::NotEvaluated));
        assert!(matches!(
            vm.tangent(&rate[1..]),
            Err(VmError::Length { .. })
        ));
    }
}
