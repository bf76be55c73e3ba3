//! Conjugate gradients on the current Hessian, preconditioned by an earlier numeric Cholesky
//! factor: the Newton step without a new factorisation.

use bdmorph_cholesky::Cholesky;

use crate::tangent::tangent_extra_cg;
use crate::Vm;

/// Work vectors of the conjugate-gradient solve, one value per unknown each.
#[derive(Clone, Debug, Default)]
pub(crate) struct CgBuffers {
    pub r: Vec<f64>,
    pub z: Vec<f64>,
    pub p: Vec<f64>,
    pub hp: Vec<f64>,
}

impl CgBuffers {
    pub fn new(n: usize) -> CgBuffers {
        CgBuffers {
            r: vec![0.0; n],
            z: vec![0.0; n],
            p: vec![0.0; n],
            hp: vec![0.0; n],
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `z = M^-1 r` for `M` the factored matrix (an earlier Hessian, or the current one in single
/// precision).
fn precondition(chol: &mut Cholesky, r: &[f64], z: &mut [f64]) {
    z.copy_from_slice(r);
    // The factor is ready (the callers' invariant) and `z` has one value per unknown.
    let solved = chol.solve_in_place(z, 1);
    debug_assert!(solved.is_ok(), "{solved:?}");
}

/// How a preconditioned conjugate-gradient solve ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PcgOutcome {
    /// Iterations run (each one preconditioner application and one product with `H`).
    pub iterations: u32,
    /// The residual reached the requested fraction of the right-hand side.
    pub converged: bool,
    /// Stopped early because the contraction observed so far predicted more iterations than
    /// the caller's limit (see [`Vm::pcg`]); the iterate is still a descent direction.
    pub aborted: bool,
    /// Mean contraction of the residual per iteration (0 before the first).
    pub rate: f64,
}

/// When [`Vm::pcg`] gives up on a factor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct AbortRule {
    /// Further iterations beyond which refactoring is cheaper.
    pub limit: f64,
    /// A tangent will follow with the same factor: count its extra iterations too.
    pub tangent_follows: bool,
}

impl Vm {
    /// Solves `H x = -v` for the current Hessian by conjugate gradients preconditioned by the
    /// last numeric factor (which must be ready), until the residual is below
    /// `relative * ||v||` or after `max_iterations`. `v` is the gradient (`x` the Newton
    /// step) or the derivative of the gradient along the metric (`x` the tangent). Every
    /// iterate, the last included, lowers the quadratic model `x.Hx/2 + v.x` from 0, so for
    /// `v` the gradient it is a descent direction.
    ///
    /// With `abort`, the solve also stops as soon as the mean contraction of the residual per
    /// iteration so far predicts that more than its limit of further iterations would be
    /// needed, counting those a following tangent would need with this factor beyond a fresh
    /// one ([`tangent_extra_cg`]) when it says so: the factor has gone too stale to pay
    /// against a new factorisation. Allocates nothing.
    pub(crate) fn pcg(
        &mut self,
        of_gradient: bool,
        relative: f64,
        max_iterations: u32,
        abort: Option<AbortRule>,
    ) -> PcgOutcome {
        let CgBuffers { r, z, p, hp } = &mut self.cg;
        let (v, x) = if of_gradient {
            (&self.grad, &mut self.step)
        } else {
            (&self.dgrad, &mut self.tangent)
        };
        x.fill(0.0);
        for (r, v) in r.iter_mut().zip(v) {
            *r = -v;
        }
        let start = dot(r, r).sqrt();
        let target = relative * start;
        let mut outcome = PcgOutcome {
            iterations: 0,
            converged: start == 0.0,
            aborted: false,
            rate: 0.0,
        };
        if outcome.converged {
            return outcome;
        }
        let (chol, hvals) = (&mut self.chol, &self.hvals);
        precondition(chol, r, z);
        p.copy_from_slice(z);
        let mut rz = dot(r, z);
        for iteration in 1..=max_iterations {
            outcome.iterations = iteration;
            chol.pattern().symmetric_product(hvals, p, hp);
            let php = dot(p, hp);
            if !(php > 0.0 && rz > 0.0) {
                return outcome;
            }
            let alpha = rz / php;
            for ((x, r), (p, hp)) in x.iter_mut().zip(r.iter_mut()).zip(p.iter().zip(&*hp)) {
                *x += alpha * p;
                *r -= alpha * hp;
            }
            let residual = dot(r, r).sqrt();
            if residual <= target {
                outcome.converged = true;
                return outcome;
            }
            // Mean contraction so far.
            let rate = (residual / start).powf(1.0 / f64::from(iteration));
            outcome.rate = rate;
            if let Some(rule) = abort {
                // The iterations this contraction needs for the rest.
                let mut more = if rate < 1.0 {
                    (target / residual).ln() / rate.ln()
                } else {
                    f64::INFINITY
                };
                if rule.tangent_follows {
                    more += tangent_extra_cg(rate);
                }
                if more > rule.limit {
                    outcome.aborted = true;
                    return outcome;
                }
            }
            precondition(chol, r, z);
            let rz_next = dot(r, z);
            let beta = rz_next / rz;
            rz = rz_next;
            for (p, z) in p.iter_mut().zip(&*z) {
                *p = z + beta * *p;
            }
        }
        outcome
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::NewtonOptions;

    /// A jittered 7 x 7 grid of vertices (25 interior ones), two triangles per cell.
    pub(crate) fn patch(jitter: f64) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        patch_of(7, jitter)
    }

    /// A jittered grid of `side` x `side` vertices (interior vertices moved by up to
    /// `jitter`), two triangles per cell.
    pub(crate) fn patch_of(side: u32, jitter: f64) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let mut positions = Vec::new();
        for j in 0..side {
            for i in 0..side {
                let interior = i > 0 && j > 0 && i + 1 < side && j + 1 < side;
                let wobble = if interior {
                    jitter * f64::from(i * 7 + j * 3).sin()
                } else {
                    0.0
                };
                positions.push([f64::from(i) + wobble, f64::from(j) - wobble]);
            }
        }
        let mut faces = Vec::new();
        for j in 0..side - 1 {
            for i in 0..side - 1 {
                let v = j * side + i;
                faces.push([v, v + 1, v + side + 1]);
                faces.push([v, v + side + 1, v + side]);
            }
        }
        (positions, faces)
    }

    #[test]
    fn preconditioned_cg_solves_the_current_newton_system() {
        let (a, faces) = patch(0.05);
        let b: Vec<[f64; 2]> = a
            .iter()
            .map(|p| [p[0] * (1.0 + 0.1 * p[1]), p[1] + 0.05 * p[0] * p[0]])
            .collect();
        let program = bdmorph_compiler::compile(&a, &faces).expect("compiles");
        let mut vm = Vm::new(program).expect("vm");
        let n = vm.program().n_unknowns();
        assert_eq!(n, 25);
        let (sa, sb) = (
            vm.squared_lengths(&a).expect("a"),
            vm.squared_lengths(&b).expect("b"),
        );
        // The factor of t = 0.2's solution preconditions the system of t = 0.7 at u = 0.
        vm.set_metric_lerp(&sa, &sb, 0.2).expect("metric");
        vm.newton(&NewtonOptions::default().with_reuse_factor(false))
            .expect("solves");
        vm.factorize().expect("definite");
        vm.set_metric_lerp(&sa, &sb, 0.7).expect("metric");
        vm.reset_u();
        vm.evaluate();
        let used = vm.pcg(true, 1e-13, 200, None);
        assert!(used.converged && !used.aborted);
        assert!(used.iterations > 1 && used.iterations < 200, "{used:?}");
        let mut hs = vec![0.0; n];
        vm.chol
            .pattern()
            .symmetric_product(vm.hessian_values(), &vm.step, &mut hs);
        let g_norm = dot(vm.gradient(), vm.gradient()).sqrt();
        assert!(g_norm > 1e-4, "{g_norm}");
        for (k, (hs, g)) in hs.iter().zip(vm.gradient()).enumerate() {
            assert!((hs + g).abs() < 1e-11 * g_norm, "row {k}");
        }
        // A truncated solve is still a descent direction.
        vm.pcg(true, 1e-13, 1, None);
        assert!(dot(vm.gradient(), &vm.step) < 0.0);
    }
}
