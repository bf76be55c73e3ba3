//! Free holes: holes solved intrinsically, as free boundaries that close by their own turning.
//!
//! A hole whose outline no single triangulation suits in every keyframe (it crosses itself
//! where a limb lies over the body, or changes too much) is filled with *inert* triangles
//! for the compiler's sake only ([`bdmorph_compiler::compile_with_inert`]): they make the
//! piece a disk, but add nothing to the solve, and the layout never walks through them. The
//! hole's vertices are then unknowns whose angle sums are those of the user's triangles
//! alone, and the flattening needs a target for each:
//!
//! - **Targets.** At keyframe `k` each hole vertex has the angle sum `θ_k` of its triangles
//!   there. A frame with weights `w` targets `Σ w_k θ_k` (plus the closing term below), as
//!   the metric is `Σ w_k l_k²`. At a keyframe the keyframe itself is then the solution
//!   (`u = 0`, every target met, interior vertices flat): keyframes are reached exactly,
//!   whatever their hole's outline looks like (crossing itself, overlapping the body).
//! - **Closing.** Between keyframes the targets are a blend, and the hole's outline, drawn
//!   from its edge lengths and the turning `π - Θ_j` at each of its vertices, need not close:
//!   the layout would open a crack where its walk meets itself around the hole. The turning
//!   adds up to a full turn (the blend of the keyframes' full turns), so only the translation
//!   is left: two conditions per hole. Two degrees of freedom per hole meet them: the targets
//!   get `2 (a_x ψ_x + a_y ψ_y)` added, with `ψ` the coordinates (about their centre, summing
//!   to zero, so the full turn is kept) of the hole's vertices on the outline drawn from the
//!   frame's blended lengths and targets. Those are the least change of curvature that moves
//!   the outline's end (turning the outline at a vertex moves its end by the distance from
//!   that vertex), and they depend on the frame's metric alone: not on which keyframe comes
//!   first, nor on how the keyframes are turned. Newton's method on `a` (two unknowns per
//!   hole, the flattening solved inside each step and its sensitivity `du/da = -H⁻¹ ∂g/∂a`
//!   from two solves per hole with the Hessian's factor) makes the outline close to
//!   round-off.
//!
//! Rigid motions are unchanged, the layout places every vertex from the user's triangles,
//! and a frame is continuous in its weights.

use bdmorph_vm::{NewtonOptions, NewtonReport, Vm, VmError};

/// Closing steps per frame before giving up.
const MAX_STEPS: u32 = 30;

/// The outline closes when its end misses its start by at most this fraction of its length.
const CLOSED: f64 = 1e-11;

/// Relative residual of the solves that give the Jacobian of the misses (and the change of `u`
/// that goes with a step): an error of that size in the Jacobian leaves a miss that size
/// times the last one, beyond Newton's quadratic term (1e-6 over a miss of 1e-6 of the
/// outline's length, warm frames' usual start, is far below [`CLOSED`]).
const SENSITIVITY_RESIDUAL: f64 = 1e-7;

/// A frame whose closing stalled is still accepted when its end misses its start by at most
/// this fraction of its length (far below a pixel at any size a picture has).
const CLOSED_ENOUGH: f64 = 1e-8;

/// One free hole.
#[derive(Clone, Debug)]
struct Hole {
    /// The unknown of each of its vertices, in the order its boundary runs (the piece on the
    /// left).
    unknowns: Vec<u32>,
    /// The edge slot from each vertex to the next.
    slots: Vec<u32>,
    /// The two closing modes at each vertex (zero mean, unit root mean square distance) of
    /// the frame being solved.
    psi: Vec<[f64; 2]>,
    /// Per keyframe: the gradient offset of each vertex that makes the keyframe a solution.
    base: Vec<Vec<f64>>,
    /// A vertex of it (the piece's numbering), for messages.
    vertex: u32,
}

/// Why a frame's free holes could not be closed.
#[derive(Debug)]
pub(crate) enum ClosureError {
    /// The flattening or a solve failed.
    Vm(VmError),
    /// The outline of a hole does not close.
    Open {
        /// A vertex on it (the piece's numbering).
        vertex: u32,
        /// How far its end misses its start, over its length.
        gap: f64,
    },
}

/// What closing a frame took.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ClosureReport {
    /// Newton iterations of the flattenings, summed.
    pub iterations: u32,
    /// Their factorisations.
    pub factorizations: u32,
    /// Their conjugate-gradient iterations.
    pub cg_iterations: u32,
    /// Gradient norm of the last flattening.
    pub gradient_norm: f64,
    /// Closing steps.
    pub steps: u32,
}

/// The free holes of one piece and the buffers their closing needs.
#[derive(Clone, Debug)]
pub(crate) struct Closure {
    holes: Vec<Hole>,
    /// The closing unknowns: two per hole.
    pub a: Vec<f64>,
    /// The gradient offsets of the frame (one per unknown of the piece).
    offsets: Vec<f64>,
    /// The blended base offsets of the frame's weights (one per unknown).
    base: Vec<f64>,
    /// A right-hand side, a change of `u` and two values of `u` (one per unknown each).
    rhs: Vec<f64>,
    du: Vec<f64>,
    u_base: Vec<f64>,
    u_trial: Vec<f64>,
    /// `H⁻¹ ψ_p` at every hole vertex, per closing unknown `p` (rows of all hole vertices).
    sensitivity: Vec<f64>,
    /// The misses of the outlines (two per hole), the Jacobian, a step, a trial `a`.
    c: Vec<f64>,
    jacobian: Vec<f64>,
    step: Vec<f64>,
    trial: Vec<f64>,
    /// Per hole, the directions `d_j` of its edges and their lengths, at the last evaluation.
    directions: Vec<f64>,
    lengths: Vec<f64>,
}

impl Closure {
    /// Prepares the closing of the holes `loops` (vertices of the piece, each loop in the
    /// order its boundary runs). `vm` must have been built for the piece with the holes filled
    /// by inert triangles; `squared` are the keyframes' squared lengths per edge slot;
    /// `slot_of` finds an edge's slot.
    pub(crate) fn new(
        vm: &mut Vm,
        loops: &[Vec<u32>],
        squared: &[Vec<f64>],
        slot_of: impl Fn(u32, u32) -> Option<u32>,
    ) -> Result<Closure, VmError> {
        let n_unknowns = vm.u().len();
        let mut unknown_of = vec![u32::MAX; vm.program().n_vertices()];
        for (k, &v) in vm.program().unknown_vertex().iter().enumerate() {
            unknown_of[v as usize] = k as u32;
        }
        let mut holes = Vec::with_capacity(loops.len());
        for l in loops {
            let n = l.len();
            let unknowns: Vec<u32> = l.iter().map(|&v| unknown_of[v as usize]).collect();
            let slots: Option<Vec<u32>> = (0..n).map(|j| slot_of(l[j], l[(j + 1) % n])).collect();
            let (Some(slots), true) = (slots, unknowns.iter().all(|&u| u != u32::MAX)) else {
                // The compiler makes every vertex of a filled hole an unknown and keeps its
                // edges: this is a broken program, reported as the VM would.
                return Err(VmError::Length {
                    what: "free hole",
                    expected: n,
                    got: 0,
                });
            };
            let psi = vec![[0.0; 2]; n];
            holes.push(Hole {
                unknowns,
                slots,
                psi,
                base: Vec::with_capacity(squared.len()),
                vertex: l[0],
            });
        }
        // Each keyframe's gradient at u = 0 without offsets: minus it is the offset that makes
        // the keyframe a solution (bit for bit: the same pass computes it in the frame).
        let saved = vm.u().to_vec();
        vm.set_gradient_offsets(&[])?;
        vm.reset_u();
        for sq in squared {
            vm.set_metric(sq)?;
            vm.evaluate_gradient();
            let g = vm.gradient();
            for h in &mut holes {
                h.base
                    .push(h.unknowns.iter().map(|&k| -g[k as usize]).collect());
            }
        }
        vm.set_u(&saved)?;
        let total: usize = holes.iter().map(|h| h.unknowns.len()).sum();
        let m = 2 * holes.len();
        Ok(Closure {
            holes,
            a: vec![0.0; m],
            offsets: vec![0.0; n_unknowns],
            base: vec![0.0; n_unknowns],
            rhs: vec![0.0; n_unknowns],
            du: vec![0.0; n_unknowns],
            u_base: vec![0.0; n_unknowns],
            u_trial: vec![0.0; n_unknowns],
            sensitivity: vec![0.0; m * total],
            c: vec![0.0; m],
            jacobian: vec![0.0; m * m],
            step: vec![0.0; m],
            trial: vec![0.0; m],
            directions: vec![0.0; total],
            lengths: vec![0.0; total],
        })
    }

    /// A vertex (the piece's numbering) on each free hole.
    pub(crate) fn hole_vertices(&self) -> impl Iterator<Item = u32> + '_ {
        self.holes.iter().map(|h| h.vertex)
    }

    /// Solves the frame whose keyframe weights are `weights` and squared edge lengths
    /// `metric` (the VM's metric already set to it and its start `u` chosen), starting the
    /// closing unknowns from `start` (two per hole). Leaves the solution in the VM (evaluated
    /// at it) and its closing unknowns in [`Closure::a`]. Allocates nothing.
    pub(crate) fn solve(
        &mut self,
        vm: &mut Vm,
        weights: &[f64],
        metric: &[f64],
        start: &[f64],
        newton: &NewtonOptions,
    ) -> Result<ClosureReport, ClosureError> {
        self.base.fill(0.0);
        for h in &mut self.holes {
            for (j, &k) in h.unknowns.iter().enumerate() {
                self.base[k as usize] = weights
                    .iter()
                    .zip(&h.base)
                    .filter(|(w, _)| **w != 0.0)
                    .map(|(w, b)| w * b[j])
                    .sum();
            }
            // The closing modes: the outline drawn from the blended lengths and targets.
            let (mut d, mut p) = (0.0f64, [0.0f64; 2]);
            let mut centre = [0.0f64; 2];
            let n = h.unknowns.len();
            for j in 0..n {
                if j > 0 {
                    let theta = 2.0 * (std::f64::consts::PI + self.base[h.unknowns[j] as usize]);
                    d += std::f64::consts::PI - theta;
                }
                h.psi[j] = p;
                centre[0] += p[0] / n as f64;
                centre[1] += p[1] / n as f64;
                let l = metric[h.slots[j] as usize].sqrt();
                let (s, c) = d.sin_cos();
                p = [p[0] + l * c, p[1] + l * s];
            }
            let mut spread = 0.0;
            for q in &mut h.psi {
                *q = [q[0] - centre[0], q[1] - centre[1]];
                spread += (q[0] * q[0] + q[1] * q[1]) / n as f64;
            }
            let scale = 1.0 / spread.sqrt().max(f64::MIN_POSITIVE);
            for q in &mut h.psi {
                *q = [q[0] * scale, q[1] * scale];
            }
        }
        let mut report = ClosureReport::default();
        self.a.copy_from_slice(start);
        if weights.iter().filter(|w| **w != 0.0).count() == 1 && weights.contains(&1.0) {
            // A keyframe is its own solution: u = 0 with its outline closed as drawn, met
            // exactly (no closing step, whatever the start predicted).
            self.a.fill(0.0);
            vm.reset_u();
        }
        let mut gap = self.flatten_and_measure(vm, newton, &mut report)?;
        let m = self.a.len();
        loop {
            if gap.0 <= CLOSED {
                return Ok(report);
            }
            if report.steps >= MAX_STEPS {
                break;
            }
            report.steps += 1;
            self.jacobian_at(vm).map_err(ClosureError::Vm)?;
            // Newton's step on the closing unknowns: J step = -c.
            for (s, c) in self.step.iter_mut().zip(&self.c) {
                *s = -c;
            }
            if !solve_dense(&mut self.jacobian, &mut self.step, m) {
                break;
            }
            // The change of u that goes with it to first order: -H⁻¹ ψ step, so that the
            // flattening after the step starts next to its solution.
            self.rhs.fill(0.0);
            for (h, s) in self.holes.iter().zip(self.step.chunks_exact(2)) {
                for (&k, p) in h.unknowns.iter().zip(&h.psi) {
                    self.rhs[k as usize] = s[0] * p[0] + s[1] * p[1];
                }
            }
            let du = vm
                .solve_hessian(&self.rhs, SENSITIVITY_RESIDUAL)
                .map_err(ClosureError::Vm)?;
            self.du.copy_from_slice(du);
            self.u_base.copy_from_slice(vm.u());
            // Halve the step until the worst miss shrinks (the flattening is solved again
            // from the predicted start, which any start allows: it is convex).
            self.trial.copy_from_slice(&self.a);
            let mut fraction = 1.0;
            let mut improved = false;
            for _ in 0..8 {
                for ((a, t), s) in self.a.iter_mut().zip(&self.trial).zip(&self.step) {
                    *a = t + fraction * s;
                }
                for ((u, b), d) in self.u_trial.iter_mut().zip(&self.u_base).zip(&self.du) {
                    *u = b - fraction * d;
                }
                vm.set_u(&self.u_trial).map_err(ClosureError::Vm)?;
                match self.flatten_and_measure(vm, newton, &mut report) {
                    Ok(next) if next.0 < gap.0 => {
                        gap = next;
                        improved = true;
                        break;
                    }
                    Ok(_) | Err(ClosureError::Vm(VmError::NotConverged { .. })) => {}
                    Err(e) => return Err(e),
                }
                fraction *= 0.5;
            }
            if !improved {
                // Back to the best point: the state must be that of the returned `a`.
                self.a.copy_from_slice(&self.trial);
                vm.set_u(&self.u_base).map_err(ClosureError::Vm)?;
                gap = self.flatten_and_measure(vm, newton, &mut report)?;
                break;
            }
        }
        if gap.0 <= CLOSED_ENOUGH {
            return Ok(report);
        }
        Err(ClosureError::Open {
            vertex: self.holes[gap.1].vertex,
            gap: gap.0,
        })
    }

    /// Sets the offsets for the current `a`, flattens, and measures every outline's miss
    /// into [`Closure::c`]: the worst miss over its outline's length, and that hole.
    fn flatten_and_measure(
        &mut self,
        vm: &mut Vm,
        newton: &NewtonOptions,
        report: &mut ClosureReport,
    ) -> Result<(f64, usize), ClosureError> {
        self.offsets.copy_from_slice(&self.base);
        for (h, a) in self.holes.iter().zip(self.a.chunks_exact(2)) {
            for (&k, p) in h.unknowns.iter().zip(&h.psi) {
                self.offsets[k as usize] += a[0] * p[0] + a[1] * p[1];
            }
        }
        vm.set_gradient_offsets(&self.offsets)
            .map_err(ClosureError::Vm)?;
        let r: NewtonReport = vm.newton(newton).map_err(ClosureError::Vm)?;
        report.iterations += r.iterations;
        report.factorizations += r.factorizations;
        report.cg_iterations += r.cg_iterations;
        report.gradient_norm = r.gradient_norm;
        let (g, len) = (vm.gradient(), vm.lengths());
        let mut worst = (0.0f64, 0usize);
        let mut at = 0;
        for (q, h) in self.holes.iter().enumerate() {
            let n = h.unknowns.len();
            let (mut d, mut x, mut y, mut perimeter) = (0.0f64, 0.0, 0.0, 0.0);
            for j in 0..n {
                if j > 0 {
                    // The piece's angle at this vertex, from the flattening's gradient entry
                    // `π - Θ/2 + offset`.
                    let k = h.unknowns[j] as usize;
                    let theta = 2.0 * (std::f64::consts::PI + self.offsets[k] - g[k]);
                    d += std::f64::consts::PI - theta;
                }
                let l = len[h.slots[j] as usize];
                self.directions[at + j] = d;
                self.lengths[at + j] = l;
                let (s, c) = d.sin_cos();
                x += l * c;
                y += l * s;
                perimeter += l;
            }
            self.c[2 * q] = x;
            self.c[2 * q + 1] = y;
            let miss = x.hypot(y) / perimeter.max(f64::MIN_POSITIVE);
            // NaN counts as the worst miss.
            if miss.is_nan() || miss > worst.0 {
                worst = (miss, q);
            }
            at += n;
        }
        Ok(worst)
    }

    /// The Jacobian of the misses with respect to the closing unknowns at the current
    /// solution (the VM evaluated there).
    fn jacobian_at(&mut self, vm: &mut Vm) -> Result<(), VmError> {
        let m = self.a.len();
        let total = self.lengths.len();
        // H⁻¹ ψ_p at every hole vertex, per closing unknown p.
        for p in 0..m {
            let (hole, mode) = (p / 2, p % 2);
            self.rhs.fill(0.0);
            for (&k, psi) in self.holes[hole].unknowns.iter().zip(&self.holes[hole].psi) {
                self.rhs[k as usize] = psi[mode];
            }
            let x = vm.solve_hessian(&self.rhs, SENSITIVITY_RESIDUAL)?;
            let row = &mut self.sensitivity[p * total..(p + 1) * total];
            let mut at = 0;
            for h in &self.holes {
                for (r, &k) in row[at..].iter_mut().zip(&h.unknowns) {
                    *r = x[k as usize];
                }
                at += h.unknowns.len();
            }
        }
        // dc_q/da_p: the lengths change through u (du/da_p = -H⁻¹ ψ_p), and, for the hole's
        // own unknowns, the directions through its targets (dΘ_i/da_p = 2 ψ_p(i)).
        let mut at = 0;
        for (q, h) in self.holes.iter().enumerate() {
            let n = h.unknowns.len();
            for p in 0..m {
                let row = &self.sensitivity[p * total + at..p * total + at + n];
                let (mut dx, mut dy) = (0.0, 0.0);
                let own = p / 2 == q;
                let mut dd = 0.0;
                for j in 0..n {
                    if own && j > 0 {
                        dd -= 2.0 * h.psi[j][p % 2];
                    }
                    let (d, l) = (self.directions[at + j], self.lengths[at + j]);
                    let (s, c) = d.sin_cos();
                    let dl = -0.5 * l * (row[j] + row[(j + 1) % n]);
                    dx += dl * c - l * s * dd;
                    dy += dl * s + l * c * dd;
                }
                self.jacobian[(2 * q) * m + p] = dx;
                self.jacobian[(2 * q + 1) * m + p] = dy;
            }
            at += n;
        }
        Ok(())
    }
}

/// Solves the dense `m x m` system `a x = b` (row-major `a`, overwritten) in place of `b`, by
/// Gaussian elimination with partial pivoting; false when `a` is singular.
fn solve_dense(a: &mut [f64], b: &mut [f64], m: usize) -> bool {
    for col in 0..m {
        let pivot = (col..m)
            .max_by(|&i, &j| a[i * m + col].abs().total_cmp(&a[j * m + col].abs()))
            .unwrap_or(col);
        let p = a[pivot * m + col];
        if p == 0.0 || !p.is_finite() {
            return false;
        }
        if pivot != col {
            for k in 0..m {
                a.swap(pivot * m + k, col * m + k);
            }
            b.swap(pivot, col);
        }
        for row in col + 1..m {
            let f = a[row * m + col] / p;
            if f != 0.0 {
                for k in col..m {
                    a[row * m + k] -= f * a[col * m + k];
                }
                b[row] -= f * b[col];
            }
        }
    }
    for col in (0..m).rev() {
        let mut s = b[col];
        for k in col + 1..m {
            s -= a[col * m + k] * b[k];
        }
        b[col] = s / a[col * m + col];
    }
    b.iter().all(|x| x.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dense_solve_pivots() {
        let mut a = vec![0.0, 2.0, 1.0, 1.0];
        let mut b = vec![4.0, 3.0];
        assert!(solve_dense(&mut a, &mut b, 2));
        assert!(
            (b[0] - 1.0).abs() < 1e-15 && (b[1] - 2.0).abs() < 1e-15,
            "{b:?}"
        );
        let mut singular = vec![1.0, 2.0, 2.0, 4.0];
        assert!(!solve_dense(&mut singular, &mut [1.0, 1.0], 2));
    }
}
