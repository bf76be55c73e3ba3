//! Projected Newton (Teran et al. 2005; Smith, de Goes, Kim 2019) on an isotropic distortion
//! energy, flip-free.
//!
//! Each iteration assembles the gradient and the projected (positive semi-definite) Hessian
//! per triangle from the analytic eigensystem ([`super::energy`]) into a sparse pattern fixed
//! at set-up (its symbolic factorisation computed once), solves for the step, and searches
//! along it: the first trial step is capped at 0.9 of the largest step before any triangle
//! would invert (the smallest positive root of each triangle's `det F(α) = 0` quadratic), then
//! halved until the Armijo condition holds. So a map that starts without inverted triangles
//! never gets one, and the energy never increases.

// Small fixed-size matrix algebra reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use bdmorph_cholesky::{Cholesky, LowerPattern};

use super::energy::{sigma2, svd2, Energy};
use super::frames::Frames;
use super::ParamError;

/// The Newton solver's fixed structures and buffers.
pub(crate) struct Newton {
    energy: Energy,
    /// Per face, the 21 lower-triangle entries of its 6×6 block: (local row, local column,
    /// slot) with the global row at or below the global column.
    blocks: Vec<[(u8, u8, u32); 21]>,
    pattern: LowerPattern,
    chol: Cholesky,
    values: Vec<f64>,
    /// The negative curvature the projection drops (assembled only when it is used).
    negative: Vec<f64>,
    /// The partly projected matrix being tried.
    mixed: Vec<f64>,
    /// The fraction of the negative curvature last left out (1: fully projected).
    mu: f64,
    /// Whether the next iteration tries a partly projected Hessian.
    try_partial: bool,
    /// Whether partly projected Hessians are tried at all.
    partial: bool,
    grad: Vec<f64>,
    step: Vec<f64>,
    trial: Vec<[f64; 2]>,
    /// Vertices held where they are (positional constraints).
    fixed: Vec<bool>,
    /// What posing adds to the energy ([`Newton::set_face_weights`], [`Newton::set_springs`],
    /// [`Newton::set_inverted_energy`]); nothing for parameterisation.
    extra: Extra,
    /// The longest vertex move of the last full step solved for (before the line search).
    longest: f64,
    /// Whether `chol` holds a factor of a Hessian of the current energy (its terms unchanged
    /// since): [`Newton::iterate_reusing`] may solve with it.
    factored: bool,
}

/// Terms posing adds to the energy: per-triangle weights, springs pulling vertices towards
/// targets, and another energy for triangles inverted where an iteration starts.
#[derive(Default)]
struct Extra {
    /// Per triangle, the factor of its term (`None`: all 1).
    weights: Option<Vec<f64>>,
    /// The sprung vertices, their targets, and each one's two diagonal slots.
    springs: Vec<u32>,
    targets: Vec<[f64; 2]>,
    slots: Vec<[Option<u32>; 2]>,
    /// The springs' weight `k`: each adds `½ k |u − t|²` to the (area-weighted mean) energy.
    spring_weight: f64,
    /// The energy of triangles inverted (or degenerate) where an iteration starts, if they are
    /// to be solved at all: such a triangle does not limit the step either.
    inverted_energy: Option<Energy>,
    /// Per triangle, whether the current iteration gives it `inverted_energy`.
    inverted: Vec<bool>,
    /// Whether a full step whose energy change is below round-off is taken (see
    /// [`Newton::set_roundoff_steps`]).
    roundoff_steps: bool,
}

impl Extra {
    /// Whether nothing is added: the energy is the plain area-weighted mean.
    fn is_plain(&self) -> bool {
        self.weights.is_none() && self.springs.is_empty() && self.inverted_energy.is_none()
    }
}

/// What one iteration did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepReport {
    /// Energy (area-weighted mean) before and after.
    pub energy_before: f64,
    /// Energy after the step.
    pub energy_after: f64,
    /// Gradient norm before the step.
    pub gradient_norm: f64,
    /// The step length taken (a fraction of the Newton step).
    pub step: f64,
    /// The largest step that keeps every triangle uninverted.
    pub max_step: f64,
    /// The triangle whose inversion bounds `max_step` (`None` when nothing does).
    pub limiting_face: Option<usize>,
    /// The largest vertex move of the step, as a fraction of the map's size.
    pub moved: f64,
}

impl Newton {
    pub fn new(frames: &Frames, n: usize, energy: Energy) -> Result<Newton, ParamError> {
        let err = |source| ParamError::Solver {
            what: "Newton",
            source,
        };
        let dof = |f: &[u32; 3], local: usize| 2 * f[local / 2] + (local % 2) as u32;
        let mut pairs: Vec<(u32, u32)> = (0..2 * n as u32).map(|i| (i, i)).collect();
        for f in &frames.faces {
            for p in 0..6 {
                for q in 0..=p {
                    pairs.push((dof(f, p), dof(f, q)));
                }
            }
        }
        let (pattern, _) = LowerPattern::new(2 * n, &pairs).map_err(err)?;
        let blocks = frames
            .faces
            .iter()
            .map(|f| {
                let mut block = [(0u8, 0u8, 0u32); 21];
                let mut k = 0;
                for p in 0..6 {
                    for q in 0..6 {
                        let (gp, gq) = (dof(f, p), dof(f, q));
                        if gp > gq || (gp == gq && p == q) {
                            let slot = pattern.slot(gp, gq).expect("pattern holds the block");
                            block[k] = (p as u8, q as u8, slot);
                            k += 1;
                        }
                    }
                }
                debug_assert_eq!(k, 21);
                block
            })
            .collect();
        let mut chol = Cholesky::new(&pattern).map_err(err)?;
        chol.reserve_columns(1).map_err(err)?;
        Ok(Newton {
            energy,
            blocks,
            values: vec![0.0; pattern.nnz()],
            negative: vec![0.0; pattern.nnz()],
            mixed: vec![0.0; pattern.nnz()],
            mu: 1.0,
            try_partial: false,
            partial: true,
            pattern,
            chol,
            grad: vec![0.0; 2 * n],
            step: vec![0.0; 2 * n],
            trial: vec![[0.0; 2]; n],
            fixed: vec![false; n],
            extra: Extra {
                inverted: vec![false; frames.len()],
                ..Extra::default()
            },
            longest: 0.0,
            factored: false,
        })
    }

    /// Multiplies each triangle's term of the energy by its weight (`None`: all 1; one
    /// finite positive weight per triangle, checked by the caller).
    pub fn set_face_weights(&mut self, weights: Option<&[f64]>) {
        self.extra.weights = weights.map(<[f64]>::to_vec);
        self.factored = false;
    }

    /// Springs: each of `vertices` pulled towards its target ([`Newton::set_spring_targets`],
    /// at first where it is) by `½ weight |u − t|²` added to the area-weighted mean energy
    /// (soft handles, a finite `weight > 0` checked by the caller).
    pub fn set_springs(&mut self, vertices: &[u32], weight: f64) {
        let x = &mut self.extra;
        x.springs = vertices.to_vec();
        x.targets = vec![[0.0; 2]; vertices.len()];
        x.slots = vertices
            .iter()
            .map(|&v| [0, 1].map(|r| self.pattern.slot(2 * v + r, 2 * v + r)))
            .collect();
        x.spring_weight = weight;
        self.factored = false;
    }

    /// The springs' targets, one per sprung vertex in [`Newton::set_springs`]' order.
    /// Allocates nothing.
    pub fn set_spring_targets(&mut self, targets: &[[f64; 2]]) {
        self.extra.targets.copy_from_slice(targets);
    }

    /// With `Some(e)`, a triangle inverted or degenerate where an iteration starts is given
    /// the energy `e` (which must be finite there, ARAP say) for that iteration and does not
    /// limit its step, instead of making the energy infinite: a map that starts with
    /// inverted triangles is then solved with them (they may come back), and the others
    /// still never invert.
    pub fn set_inverted_energy(&mut self, energy: Option<Energy>) {
        self.extra.inverted_energy = energy;
        self.extra.inverted.fill(false);
    }

    /// With `true`, a full step (`α = 1`, within the flip-free limit) whose predicted decrease
    /// is below the energy's round-off is taken when the energy it reaches is the same
    /// within round-off: near a minimum the Armijo test cannot see such steps, and refusing
    /// them stops the iterations at about the square root of the machine precision.
    pub fn set_roundoff_steps(&mut self, on: bool) {
        self.extra.roundoff_steps = on;
    }

    /// The longest vertex move of the last step solved for, in full (before its line
    /// search), in the map's units; NaN when the step is not finite.
    pub fn proposed_move(&self) -> f64 {
        self.longest
    }

    /// The energy [`Newton::iterate`] lowers, at `uv`: the area-weighted mean of the
    /// triangles' energies (each by its weight; inverted ones as the last iteration gave
    /// them), plus the springs.
    pub fn energy_at(&self, frames: &Frames, uv: &[[f64; 2]]) -> f64 {
        let x = &self.extra;
        if x.is_plain() {
            return mean_energy(self.energy, frames, uv);
        }
        let mut e = 0.0;
        for f in 0..frames.len() {
            let energy = match x.inverted_energy {
                Some(inverted) if x.inverted[f] => inverted,
                _ => self.energy,
            };
            let mut a = frames.area[f];
            if let Some(w) = &x.weights {
                a *= w[f];
            }
            e += a * energy.psi(sigma2(frames.gradient(f, uv)));
        }
        e / frames.total_area + self.spring_energy(uv)
    }

    /// `Σ ½ k |u − t|²` over the springs.
    fn spring_energy(&self, uv: &[[f64; 2]]) -> f64 {
        let x = &self.extra;
        let mut e = 0.0;
        for (&v, t) in x.springs.iter().zip(&x.targets) {
            let u = uv[v as usize];
            e += (u[0] - t[0]) * (u[0] - t[0]) + (u[1] - t[1]) * (u[1] - t[1]);
        }
        0.5 * x.spring_weight * e
    }

    /// Whether, once full steps are taken, the iterations try Hessians that keep part of
    /// the negative curvature (default on; see [`Newton::iterate`]).
    pub fn set_partial_projection(&mut self, on: bool) {
        self.partial = on;
        self.try_partial &= on;
    }

    /// Holds `vertices` where they are: their rows of the step are zero.
    pub fn fix(&mut self, vertices: impl IntoIterator<Item = u32>) {
        for v in vertices {
            self.fixed[v as usize] = true;
        }
    }

    /// One projected Newton step with the flip-free line search, in place.
    ///
    /// Far from a minimum the Hessian is the projected one (each triangle's negative
    /// eigenvalues set to zero). Once full steps are taken, the next iteration first tries
    /// `H₊ + (1 − μ) H₋` (`H₋` the dropped negative curvature) with `μ` a quarter of the
    /// last one that worked, multiplying it by 8 while the matrix is not positive definite
    /// or the step is not a descent direction, and falling back to `μ = 1`: projecting every
    /// triangle discards curvature that the whole mesh does not need discarded (compressed
    /// triangles' twist modes under ARAP), and converges only linearly where that matters.
    pub fn iterate(
        &mut self,
        frames: &Frames,
        uv: &mut [[f64; 2]],
    ) -> Result<StepReport, ParamError> {
        let energy_before = self.assemble(frames, uv);
        self.step_from_assembly(frames, uv, energy_before)
    }

    /// [`Newton::iterate`], or, with `reuse` and a factor of an earlier iteration's Hessian
    /// at hand (the energy's terms unchanged since), the same line search along the step
    /// that factor gives: only the gradient is assembled and nothing is factored. Any
    /// positive definite matrix gives a descent direction, so every step still lowers the
    /// energy and keeps the triangles unflipped; a factor of a nearby pose's Hessian (the
    /// previous mouse move's) makes it nearly a Newton step, at the cost of one solve. Such
    /// a step never tries a partly projected Hessian.
    pub fn iterate_reusing(
        &mut self,
        frames: &Frames,
        uv: &mut [[f64; 2]],
        reuse: bool,
    ) -> Result<StepReport, ParamError> {
        if !(reuse && self.factored) {
            return self.iterate(frames, uv);
        }
        let energy_before = self.assemble_with(frames, uv, false);
        let gradient_norm = self.grad.iter().map(|x| x * x).sum::<f64>().sqrt();
        self.solve_step()?;
        Ok(self.search(frames, uv, energy_before, gradient_norm))
    }

    /// Fills the gradient and the projected Hessian's values at `uv`; returns the energy.
    fn assemble(&mut self, frames: &Frames, uv: &[[f64; 2]]) -> f64 {
        self.assemble_with(frames, uv, true)
    }

    /// Fills the gradient, and with `hessian` the projected Hessian's values, at `uv`;
    /// returns the energy.
    fn assemble_with(&mut self, frames: &Frames, uv: &[[f64; 2]], hessian: bool) -> f64 {
        let total = frames.total_area;
        let partial = self.try_partial && hessian;
        if hessian {
            self.values.fill(0.0);
        }
        if partial {
            self.negative.fill(0.0);
        }
        self.grad.fill(0.0);
        let mut energy_before = 0.0;
        for (f, face) in frames.faces.iter().enumerate() {
            let fmat = frames.gradient(f, uv);
            let svd = svd2(fmat);
            let mut w = frames.area[f] / total;
            let mut energy = self.energy;
            if let Some(inverted) = self.extra.inverted_energy {
                let now = svd.sigma[1] <= 0.0;
                self.extra.inverted[f] = now;
                if now {
                    energy = inverted;
                }
            }
            if let Some(weights) = &self.extra.weights {
                w *= weights[f];
            }
            energy_before += w * energy.psi(svd.sigma);
            let p = energy.first_piola(&svd);
            let g = &frames.g[f];
            if !hessian {
                for (k, &v) in face.iter().enumerate() {
                    if self.fixed[v as usize] {
                        continue;
                    }
                    for r in 0..2 {
                        self.grad[2 * v as usize + r] +=
                            w * (p[r][0] * g[k][0] + p[r][1] * g[k][1]);
                    }
                }
                continue;
            }
            let h = energy.projected_hessian(&svd);
            let hx = if partial {
                energy.negative_hessian(&svd)
            } else {
                [[0.0; 4]; 4]
            };
            // Gradient: ∂E/∂u[v][r] = Σ_c P[r][c] g[v][c].
            for (k, &v) in face.iter().enumerate() {
                if self.fixed[v as usize] {
                    continue;
                }
                for r in 0..2 {
                    self.grad[2 * v as usize + r] += w * (p[r][0] * g[k][0] + p[r][1] * g[k][1]);
                }
            }
            // Hessian: H[(v,r),(w,s)] = Σ_{c,d} H_F[(r,c),(s,d)] g[v][c] g[w][d].
            for &(lp, lq, slot) in &self.blocks[f] {
                let (vp, r) = ((lp / 2) as usize, (lp % 2) as usize);
                let (vq, s) = ((lq / 2) as usize, (lq % 2) as usize);
                if self.fixed[face[vp] as usize] || self.fixed[face[vq] as usize] {
                    continue;
                }
                let (mut sum, mut sum_x) = (0.0, 0.0);
                for c in 0..2 {
                    for d in 0..2 {
                        sum += h[2 * r + c][2 * s + d] * g[vp][c] * g[vq][d];
                        if partial {
                            sum_x += hx[2 * r + c][2 * s + d] * g[vp][c] * g[vq][d];
                        }
                    }
                }
                self.values[slot as usize] += w * sum;
                if partial {
                    self.negative[slot as usize] += w * sum_x;
                }
            }
        }
        // The springs: ½ k |u − t|² each.
        let x = &self.extra;
        let k = x.spring_weight;
        for ((&v, t), slots) in x.springs.iter().zip(&x.targets).zip(&x.slots) {
            if self.fixed[v as usize] {
                continue;
            }
            let u = uv[v as usize];
            for r in 0..2 {
                self.grad[2 * v as usize + r] += k * (u[r] - t[r]);
                if let (true, Some(slot)) = (hessian, slots[r]) {
                    self.values[slot as usize] += k;
                }
            }
        }
        if !x.springs.is_empty() {
            energy_before += self.spring_energy(uv);
        }
        if !hessian {
            return energy_before;
        }
        // A fixed vertex's rows are the identity (and its gradient zero): its step is zero.
        for (v, _) in self.fixed.iter().enumerate().filter(|(_, &f)| f) {
            for r in 0..2 {
                let j = (2 * v + r) as u32;
                if let Some(slot) = self.pattern.slot(j, j) {
                    self.values[slot as usize] = 1.0;
                }
            }
        }
        energy_before
    }

    /// Solves for the step from the assembled system and searches along it.
    fn step_from_assembly(
        &mut self,
        frames: &Frames,
        uv: &mut [[f64; 2]],
        energy_before: f64,
    ) -> Result<StepReport, ParamError> {
        let gradient_norm = self.grad.iter().map(|x| x * x).sum::<f64>().sqrt();
        // The energies are invariant to translations (and more): a tiny relative increase of
        // the diagonal keeps the projected Hessian definite without changing the step. It is
        // relative per entry, not to the mean, because the entries of a map whose scale
        // varies by orders of magnitude (a conformal flattening of long fingers) do too.
        let tried_partial = self.try_partial;
        let mut partial_step = false;
        regularise(&self.pattern, &mut self.values);
        if tried_partial {
            let mut mu = (self.mu * 0.25).max(1e-6);
            while mu < 1.0 {
                for ((m, p), q) in self.mixed.iter_mut().zip(&self.values).zip(&self.negative) {
                    *m = p + (1.0 - mu) * q;
                }
                if self.chol.factorize(&self.mixed).is_ok() && self.solve_step()? {
                    partial_step = true;
                    break;
                }
                mu *= 8.0;
            }
            self.mu = if partial_step { mu } else { 1.0 };
        }
        if !partial_step {
            self.factored = false;
            self.chol
                .factorize(&self.values)
                .map_err(|source| ParamError::Solver {
                    what: "Newton",
                    source,
                })?;
            self.solve_step()?;
        }
        self.factored = true;
        let report = self.search(frames, uv, energy_before, gradient_norm);
        self.try_partial = self.partial && report.step == 1.0;
        if !(tried_partial && partial_step) {
            self.mu = 1.0;
        }
        Ok(report)
    }

    /// The flip-free backtracking line search along `step` from `uv` (moved in place when
    /// a step is taken).
    fn search(
        &mut self,
        frames: &Frames,
        uv: &mut [[f64; 2]],
        energy_before: f64,
        gradient_norm: f64,
    ) -> StepReport {
        let skip = self
            .extra
            .inverted_energy
            .is_some()
            .then_some(&self.extra.inverted[..]);
        let (max_step, limiting_face) = max_flip_free_step(frames, uv, &self.step, skip);
        let slope: f64 = self.grad.iter().zip(&self.step).map(|(g, s)| g * s).sum();
        let mut alpha = (0.9 * max_step).min(1.0);
        let mut energy_after = energy_before;
        let mut taken = 0.0;
        for _ in 0..60 {
            for (v, t) in self.trial.iter_mut().enumerate() {
                *t = [
                    uv[v][0] + alpha * self.step[2 * v],
                    uv[v][1] + alpha * self.step[2 * v + 1],
                ];
            }
            let e = self.energy_at(frames, &self.trial);
            // Near a minimum the predicted decrease may be below the energy's round-off.
            let roundoff = self.extra.roundoff_steps
                && alpha == 1.0
                && -slope <= 1e-11 * energy_before.abs()
                && e <= energy_before + 1e-12 * energy_before.abs();
            if e.is_finite() && (e <= energy_before + 1e-4 * alpha * slope || roundoff) {
                energy_after = e;
                taken = alpha;
                uv.copy_from_slice(&self.trial);
                break;
            }
            alpha *= 0.5;
        }
        let longest = self
            .step
            .chunks_exact(2)
            .map(|d| d[0].hypot(d[1]))
            .fold(0.0, f64::max);
        self.longest = if self.step.iter().all(|x| x.is_finite()) {
            longest
        } else {
            f64::NAN
        };
        StepReport {
            energy_before,
            energy_after,
            gradient_norm,
            step: taken,
            max_step,
            limiting_face,
            moved: taken * longest / super::map_size(uv),
        }
    }

    /// `step = −H⁻¹ grad` with the current factor; whether it is a descent direction.
    fn solve_step(&mut self) -> Result<bool, ParamError> {
        for (s, g) in self.step.iter_mut().zip(&self.grad) {
            *s = -g;
        }
        self.chol
            .solve_in_place(&mut self.step, 1)
            .map_err(|source| ParamError::Solver {
                what: "Newton",
                source,
            })?;
        let slope: f64 = self.grad.iter().zip(&self.step).map(|(g, s)| g * s).sum();
        Ok(slope < 0.0 && self.step.iter().all(|x| x.is_finite()))
    }
}

/// Adds a tiny relative amount to every diagonal entry (see `step_from_assembly`).
fn regularise(pattern: &LowerPattern, values: &mut [f64]) {
    for j in 0..pattern.dim() as u32 {
        if let Some(slot) = pattern.slot(j, j) {
            let d = &mut values[slot as usize];
            *d += 1e-9 * *d + 1e-300;
        }
    }
}

/// The area-weighted mean of `energy` over the triangles of the map `uv`.
pub(crate) fn mean_energy(energy: Energy, frames: &Frames, uv: &[[f64; 2]]) -> f64 {
    let mut e = 0.0;
    for f in 0..frames.len() {
        e += frames.area[f] * energy.psi(sigma2(frames.gradient(f, uv)));
    }
    e / frames.total_area
}

/// The largest `α` (at most infinity) such that no triangle's `det F` reaches zero along
/// `uv + α d`: per triangle the smallest positive root of `det(Ds + α dDs) = 0`; and the
/// triangle that sets it. Triangles marked in `skip` (if any) are left out.
pub(crate) fn max_flip_free_step(
    frames: &Frames,
    uv: &[[f64; 2]],
    d: &[f64],
    skip: Option<&[bool]>,
) -> (f64, Option<usize>) {
    let mut best = f64::INFINITY;
    let mut face = None;
    for (f, &[a, b, c]) in frames.faces.iter().enumerate() {
        if skip.is_some_and(|s| s[f]) {
            continue;
        }
        let p = |v: u32| uv[v as usize];
        let q = |v: u32| [d[2 * v as usize], d[2 * v as usize + 1]];
        let (e1, e2) = (
            [p(b)[0] - p(a)[0], p(b)[1] - p(a)[1]],
            [p(c)[0] - p(a)[0], p(c)[1] - p(a)[1]],
        );
        let (f1, f2) = (
            [q(b)[0] - q(a)[0], q(b)[1] - q(a)[1]],
            [q(c)[0] - q(a)[0], q(c)[1] - q(a)[1]],
        );
        // det(e + α f) = c0 + c1 α + c2 α².
        let c0 = e1[0] * e2[1] - e1[1] * e2[0];
        let c1 = e1[0] * f2[1] + f1[0] * e2[1] - e1[1] * f2[0] - f1[1] * e2[0];
        let c2 = f1[0] * f2[1] - f1[1] * f2[0];
        if let Some(root) = smallest_positive_root(c2, c1, c0) {
            if root < best {
                best = root;
                face = Some(f);
            }
        }
    }
    (best, face)
}

/// The smallest positive root of `a α² + b α + c`, if any (stable formulas).
fn smallest_positive_root(a: f64, b: f64, c: f64) -> Option<f64> {
    let scale = a.abs().max(b.abs()).max(c.abs());
    if scale == 0.0 {
        return None;
    }
    let roots: [f64; 2] = if a.abs() <= 1e-14 * scale {
        if b == 0.0 {
            return None;
        }
        [-c / b, f64::NAN]
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc < 0.0 {
            return None;
        }
        let sq = disc.sqrt();
        let qq = -0.5 * (b + b.signum() * sq);
        let r1 = qq / a;
        let r2 = if qq != 0.0 { c / qq } else { f64::NAN };
        [r1, r2]
    };
    roots
        .into_iter()
        .filter(|r| r.is_finite() && *r > 0.0)
        .min_by(f64::total_cmp)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::SurfaceMesh;

    /// A flat jittered disk in 3D and a map of it: the disk scaled by 1.3 and turned, then
    /// bent a little (so no eigenvalue is clamped for SD and ARAP: the projected Hessian is
    /// the true one).
    fn setup() -> (Frames, Vec<[f64; 2]>) {
        let d = crate::generate::disk(4, 0.2);
        let mesh = SurfaceMesh {
            positions: d.positions.iter().map(|p| [p[0], p[1], 0.0]).collect(),
            faces: d.faces.clone(),
            texcoords: None,
        };
        let frames = Frames::new(&mesh).expect("valid");
        let (s, c) = 0.4f64.sin_cos();
        let uv = d
            .positions
            .iter()
            .map(|p| {
                let (x, y) = (1.3 * p[0], 1.3 * p[1] + 0.05 * p[0] * p[0]);
                [c * x - s * y, s * x + c * y]
            })
            .collect();
        (frames, uv)
    }

    #[test]
    fn assembled_gradient_and_hessian_match_finite_differences() {
        let (frames, uv) = setup();
        let n = uv.len();
        for energy in [
            Energy::SymmetricDirichlet,
            Energy::Arap,
            Energy::Mips,
            Energy::Excess { bound: 1.02 },
            Energy::ArapBarrier { weight: 1e-3 },
        ] {
            let mut newton = Newton::new(&frames, n, energy).expect("set up");
            newton.assemble(&frames, &uv);
            let grad = newton.grad.clone();
            let values = newton.values.clone();
            let h = 1e-6;
            let shifted = |k: usize, by: f64| {
                let mut q = uv.clone();
                q[k / 2][k % 2] += by;
                q
            };
            for k in 0..2 * n {
                let num = (mean_energy(energy, &frames, &shifted(k, h))
                    - mean_energy(energy, &frames, &shifted(k, -h)))
                    / (2.0 * h);
                assert!(
                    (num - grad[k]).abs() < 1e-6 * (1.0 + grad[k].abs()),
                    "{energy:?} {k}"
                );
            }
            // H d against the change of the gradient along d (MIPS clamps its twist, so its
            // projected Hessian is not the true one).
            if matches!(energy, Energy::Mips | Energy::Excess { .. }) {
                continue;
            }
            let d: Vec<f64> = (0..2 * n)
                .map(|i| ((i * 7 % 11) as f64 - 5.0) / 5.0)
                .collect();
            let mut hd = vec![0.0; 2 * n];
            newton.pattern.symmetric_product(&values, &d, &mut hd);
            let along = |t: f64| {
                let q: Vec<[f64; 2]> = uv
                    .iter()
                    .enumerate()
                    .map(|(v, p)| [p[0] + t * d[2 * v], p[1] + t * d[2 * v + 1]])
                    .collect();
                let mut m = Newton::new(&frames, n, energy).expect("set up");
                m.assemble(&frames, &q);
                m.grad
            };
            let (gp, gm) = (along(h), along(-h));
            for i in 0..2 * n {
                let num = (gp[i] - gm[i]) / (2.0 * h);
                assert!(
                    (num - hd[i]).abs() < 1e-5 * (1.0 + hd[i].abs()),
                    "{energy:?} {i}: {num} vs {}",
                    hd[i]
                );
            }
        }
    }

    /// Fixed vertices stay exactly where they are; the rest lower the excess distortion.
    #[test]
    fn fixed_vertices_do_not_move() {
        let (frames, mut uv) = setup();
        // Shear the map so that some triangles exceed the bound.
        for p in uv.iter_mut() {
            p[0] += 0.6 * p[1];
        }
        let n = uv.len();
        let energy = Energy::Excess { bound: 1.3 };
        let mut newton = Newton::new(&frames, n, energy).expect("set up");
        newton.fix([0, 7]);
        let (p0, p7) = (uv[0], uv[7]);
        let before = mean_energy(energy, &frames, &uv);
        for _ in 0..5 {
            let r = newton.iterate(&frames, &mut uv).expect("step");
            assert!(r.energy_after <= r.energy_before);
        }
        assert_eq!((uv[0], uv[7]), (p0, p7));
        let after = mean_energy(energy, &frames, &uv);
        assert!(after < 0.5 * before, "{before} -> {after}");
    }

    #[test]
    fn quadratic_roots() {
        assert_eq!(smallest_positive_root(1.0, -3.0, 2.0), Some(1.0));
        assert_eq!(smallest_positive_root(0.0, -2.0, 1.0), Some(0.5));
        assert_eq!(smallest_positive_root(1.0, 0.0, 1.0), None);
        assert_eq!(smallest_positive_root(1.0, 3.0, 2.0), None);
    }
}
