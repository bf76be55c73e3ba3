//! As-Killing-As-Possible posing (Solomon, Ben-Chen, Butscher, Guibas, SGP 2011), the original
//! BDMORPH editor's deformation, with soft handles and no drift.
//!
//! Each step solves for a velocity field `v` on the vertices and moves every vertex along it
//! by the field's log spirals. The field minimises
//!
//! ```text
//! Σ_f A_f |∇v_f − ω_f J R_f − (R_f − F_f)|²  +  w Σ_handles |v_p − (t_p − u_p)|²
//! ```
//!
//! over `v` and one angular velocity `ω_f` per triangle, where `F_f` is the triangle's
//! deformation gradient in the current pose `u`, `R_f` its closest rotation, `J` the quarter
//! turn and `t_p` the handles' targets:
//!
//! - `min_ω |∇v − ω J R|²` is the Killing energy `|sym(Rᵀ ∇v)|²` of the field on the
//!   triangle's rest shape turned by `R` (equal to the pose's own triangle whenever the pose
//!   is isometric there). Written with `ω` as a variable, the matrix of the `v` step is the
//!   rest shape's cotangent Laplacian plus the handle weights, whatever the pose: factored
//!   once per set of pins. The original builds and factors the Killing operator of the
//!   current pose (twice, with its Dirichlet pass) on every mouse move.
//! - `w` is the handles' weight (`KvfOptions::weight` times the Laplacian's mean diagonal):
//!   handles are springs, as the original's "control points weight", met more closely as
//!   the weight grows.
//! - The strain term `R − F` is this implementation's addition: it carries each triangle
//!   back toward its rest shape, so a pose depends only on where the handles are, never on
//!   the path they took. Without it (the original), any pose is at rest once the handles
//!   stop, and dragging a handle away and back leaves the shape changed. With it, a step
//!   that moves nothing is a stationary pose of ARAP energy plus the handles' springs.
//!
//! With per-triangle stiffness ([`super::Deformer::set_stiffness`]) each triangle's term of
//! the first sum, `A_f |…|²`, is multiplied by its weight: the `v` step's matrix and
//! right-hand side (each of the triangle's cotangent weights), not the `ω` step, which is per
//! triangle. The handles' `w` stays relative to the unweighted Laplacian.
//!
//! `v` and `ω` are found by alternating (each step minimises over its own variables): the
//! `ω` step is closed-form per triangle, the `v` step one solve with two right-hand sides.
//! Integrating along log spirals (per edge, the spiral the field's similarity along the
//! edge traces in unit time; each vertex the mean over its edges) turns a field's rotation
//! into a rotation rather than the growth of a straight-line step.

// Small fixed-size matrix algebra reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use bdmorph_cholesky::Cholesky;

use super::{DeformError, DragReport};
use crate::param::frames::Frames;
use crate::param::local_global::{fit_each, free_laplacian_plus, global_rhs, weighted_edges, Fit};

/// Options of [`super::PoseMethod::Kvf`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct KvfOptions {
    /// The handles' weight, relative to the mesh's own stiffness (default 100): larger holds
    /// the handles closer to their targets, smaller lets the shape pull them (the original's
    /// "control points weight"). Changing it refactors, as [`super::Deformer::set_pins`].
    pub weight: f64,
    /// Steps per drag at most (default 2), each one field and one move along it.
    pub iterations: u32,
    /// Alternations of the field's `ω` and `v` per step (default 2).
    pub alternations: u32,
    /// A drag stops early once no vertex moved by more than this times the mesh's size in a
    /// step (default `1e-12`).
    pub tolerance: f64,
}

impl Default for KvfOptions {
    fn default() -> Self {
        KvfOptions {
            weight: 100.0,
            iterations: 2,
            alternations: 2,
            tolerance: 1e-12,
        }
    }
}

impl KvfOptions {
    /// Sets the handles' weight.
    pub fn with_weight(mut self, weight: f64) -> Self {
        self.weight = weight;
        self
    }
    /// Sets the most steps per drag.
    pub fn with_iterations(mut self, iterations: u32) -> Self {
        self.iterations = iterations;
        self
    }
    /// Sets the alternations per step.
    pub fn with_alternations(mut self, alternations: u32) -> Self {
        self.alternations = alternations;
        self
    }
    /// Sets the early-stopping tolerance.
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }
}

/// The method's state.
pub(crate) struct Kvf {
    options: KvfOptions,
    /// Whether the strain term is on (always, but for the test that measures the drift of
    /// the original's flow without it).
    pub(crate) strain_feedback: bool,
    /// Every vertex is an unknown: row `v` for vertex `v`.
    index: Vec<u32>,
    pins: Vec<u32>,
    /// The handles' absolute weight.
    stiffness: f64,
    /// The Laplacian's mean diagonal: `weight` is relative to it.
    mean_diagonal: f64,
    chol: Option<Cholesky>,
    /// The solve's right-hand sides and solution (x then y, one row per vertex).
    rhs: Vec<f64>,
    /// Per triangle, the current pose's rotation `R` and the step's target `M` (rows).
    rotation: Vec<[[f64; 2]; 2]>,
    target: Vec<[[f64; 2]; 2]>,
    /// Per triangle, the gradient `F` of the pose the step starts from.
    gradient: Vec<[[f64; 2]; 2]>,
    omega: Vec<f64>,
    wdx: Vec<[[f64; 2]; 3]>,
    /// Per triangle, the factor of its term of the field's energy (`None`: all 1).
    face_stiffness: Option<Vec<f64>>,
    /// Each edge once, with how many triangles hold it (1 on the boundary, 2 inside).
    edges: Vec<(u32, u32, f64)>,
    /// Per vertex, the sum of its edges' spiral images (each counted once per triangle
    /// holding it), and how many those are.
    sum: Vec<[f64; 2]>,
    count: Vec<f64>,
}

impl Kvf {
    pub(crate) fn new(frames: &Frames, n: usize, options: KvfOptions) -> Kvf {
        let mut count = vec![0.0; n];
        let mut diagonal = 0.0;
        for (f, face) in frames.faces.iter().enumerate() {
            for &v in face {
                count[v as usize] += 2.0;
            }
            diagonal += 2.0 * frames.cot[f].iter().sum::<f64>();
        }
        let used = count.iter().filter(|&&c| c > 0.0).count().max(1);
        let mut keyed: Vec<(u32, u32)> = frames
            .faces
            .iter()
            .flat_map(|f| [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])])
            .map(|(a, b)| (a.min(b), a.max(b)))
            .collect();
        keyed.sort_unstable();
        let mut edges: Vec<(u32, u32, f64)> = Vec::with_capacity(keyed.len() / 2 + 1);
        for (a, b) in keyed {
            match edges.last_mut() {
                Some(last) if (last.0, last.1) == (a, b) => last.2 += 1.0,
                _ => edges.push((a, b, 1.0)),
            }
        }
        let m = frames.len();
        Kvf {
            options,
            strain_feedback: true,
            index: (0..n as u32).collect(),
            pins: Vec::new(),
            stiffness: 0.0,
            mean_diagonal: diagonal / used as f64,
            chol: None,
            rhs: vec![0.0; 2 * n],
            rotation: vec![[[1.0, 0.0], [0.0, 1.0]]; m],
            target: vec![[[1.0, 0.0], [0.0, 1.0]]; m],
            gradient: vec![[[1.0, 0.0], [0.0, 1.0]]; m],
            omega: vec![0.0; m],
            wdx: weighted_edges(frames, None),
            face_stiffness: None,
            edges,
            sum: vec![[0.0; 2]; n],
            count,
        }
    }

    pub(crate) fn options(&self) -> KvfOptions {
        self.options
    }

    /// Sets each triangle's factor in the field's energy (checked by the caller), its whole
    /// term `A_f |∇v − ω J R − (R − F)|²`: the Killing part and the strain part alike. The
    /// next [`Kvf::set_pins`] factors with it; the handles' weight stays relative to the
    /// unweighted Laplacian, so painting a region does not change how hard the handles pull.
    pub(crate) fn set_stiffness(&mut self, frames: &Frames, stiffness: Option<&[f64]>) {
        self.wdx = weighted_edges(frames, stiffness);
        self.face_stiffness = stiffness.map(<[f64]>::to_vec);
    }

    /// Factors the rest Laplacian plus the handles' weight on their rows.
    pub(crate) fn set_pins(&mut self, frames: &Frames, pins: &[u32]) -> Result<(), DeformError> {
        let weight = self.options.weight;
        if !(weight > 0.0 && weight.is_finite()) {
            return Err(DeformError::BadWeight(weight));
        }
        self.stiffness = weight * self.mean_diagonal;
        let extra: Vec<(u32, f64)> = pins.iter().map(|&p| (p, self.stiffness)).collect();
        let n = self.index.len() as u32;
        self.chol = Some(free_laplacian_plus(
            frames,
            self.face_stiffness.as_deref(),
            &self.index,
            n,
            &extra,
        )?);
        self.pins = pins.to_vec();
        Ok(())
    }

    /// Sets the handles' weight and refactors (pins unchanged).
    pub(crate) fn set_weight(&mut self, frames: &Frames, weight: f64) -> Result<(), DeformError> {
        let old = self.options.weight;
        self.options.weight = weight;
        let pins = std::mem::take(&mut self.pins);
        let result = self.set_pins(frames, &pins);
        if result.is_err() {
            self.options.weight = old;
        }
        self.pins = pins;
        result
    }

    pub(crate) fn drag(
        &mut self,
        frames: &Frames,
        targets: &[[f64; 2]],
        uv: &mut [[f64; 2]],
        size: f64,
    ) -> Result<DragReport, DeformError> {
        let n = uv.len();
        let mut iterations = 0;
        let mut last_change = 0.0;
        while iterations < self.options.iterations.max(1) {
            iterations += 1;
            last_change = self.step(frames, targets, uv)?;
            if last_change <= self.options.tolerance * size {
                break;
            }
        }
        debug_assert_eq!(self.rhs.len(), 2 * n);
        let energy = fit_each(frames, uv, Fit::Rotation, &mut self.rotation);
        let pin_residual = self
            .pins
            .iter()
            .zip(targets)
            .map(|(&p, t)| (uv[p as usize][0] - t[0]).hypot(uv[p as usize][1] - t[1]))
            .fold(0.0, f64::max);
        Ok(DragReport {
            iterations,
            energy,
            last_change: last_change / size,
            pin_residual,
            ..DragReport::default()
        })
    }

    /// One field and one move along it; the largest move of a vertex.
    fn step(
        &mut self,
        frames: &Frames,
        targets: &[[f64; 2]],
        uv: &mut [[f64; 2]],
    ) -> Result<f64, DeformError> {
        let n = uv.len();
        fit_each(frames, uv, Fit::Rotation, &mut self.rotation);
        if !self.strain_feedback {
            for f in 0..frames.len() {
                self.gradient[f] = frames.gradient(f, uv);
            }
        }
        self.omega.fill(0.0);
        let chol = self.chol.as_mut().ok_or(DeformError::TargetCount {
            pins: 0,
            got: targets.len(),
        })?;
        for round in 0..self.options.alternations.max(1) {
            // The v step: y = u + v minimises Σ |∇y − M|² + w Σ |y_p − t_p|², with
            // M = R + ω J R (strain term on) or F + ω J R (off).
            for f in 0..frames.len() {
                let [[p, _], [s, _]] = self.rotation[f];
                let w = self.omega[f];
                let base = if self.strain_feedback {
                    self.rotation[f]
                } else {
                    self.gradient[f]
                };
                // J R = [[-s, -p], [p, -s]].
                self.target[f] = [
                    [base[0][0] - w * s, base[0][1] - w * p],
                    [base[1][0] + w * p, base[1][1] - w * s],
                ];
            }
            global_rhs(
                frames,
                self.face_stiffness.as_deref(),
                &self.target,
                &self.wdx,
                &self.index,
                uv,
                &mut self.rhs,
            );
            for (&p, t) in self.pins.iter().zip(targets) {
                self.rhs[p as usize] += self.stiffness * t[0];
                self.rhs[n + p as usize] += self.stiffness * t[1];
            }
            chol.solve_in_place(&mut self.rhs, 2)?;
            if round + 1 < self.options.alternations.max(1) {
                // The ω step: ω = ⟨∇y − base, J R⟩ / |J R|², and ⟨base, J R⟩ = 0 for both
                // bases (R is F's polar rotation).
                for f in 0..frames.len() {
                    let g = gradient_of(frames, f, &self.rhs, n);
                    let [[p, _], [s, _]] = self.rotation[f];
                    self.omega[f] = 0.5 * (-s * g[0][0] - p * g[0][1] + p * g[1][0] - s * g[1][1]);
                }
            }
        }
        // Move along the field v = y − u by each edge's log spiral.
        self.sum.fill([0.0; 2]);
        for &(i, j, times) in &self.edges {
            let (i, j) = (i as usize, j as usize);
            let (pi, pj) = (uv[i], uv[j]);
            let vi = [self.rhs[i] - pi[0], self.rhs[n + i] - pi[1]];
            let vj = [self.rhs[j] - pj[0], self.rhs[n + j] - pj[1]];
            let phi = spiral_factor(
                [vi[0] - vj[0], vi[1] - vj[1]],
                [pi[0] - pj[0], pi[1] - pj[1]],
            );
            let (mi, mj) = (cmul(vi, phi), cmul(vj, phi));
            self.sum[i][0] += times * (pi[0] + mi[0]);
            self.sum[i][1] += times * (pi[1] + mi[1]);
            self.sum[j][0] += times * (pj[0] + mj[0]);
            self.sum[j][1] += times * (pj[1] + mj[1]);
        }
        let mut change = 0.0f64;
        for (v, out) in uv.iter_mut().enumerate() {
            let c = self.count[v];
            if c == 0.0 {
                continue;
            }
            let new = [self.sum[v][0] / c, self.sum[v][1] / c];
            change = change.max((new[0] - out[0]).hypot(new[1] - out[1]));
            *out = new;
        }
        Ok(change)
    }
}

/// The gradient of triangle `f` of the field stored as x rows then y rows in `xy`.
fn gradient_of(frames: &Frames, f: usize, xy: &[f64], n: usize) -> [[f64; 2]; 2] {
    let g = &frames.g[f];
    let mut out = [[0.0; 2]; 2];
    for (k, &v) in frames.faces[f].iter().enumerate() {
        let u = [xy[v as usize], xy[n + v as usize]];
        for r in 0..2 {
            for c in 0..2 {
                out[r][c] += u[r] * g[k][c];
            }
        }
    }
    out
}

/// `k!` for `k = 0..=10`.
const FACTORIALS: [f64; 11] = [
    1.0, 1.0, 2.0, 6.0, 24.0, 120.0, 720.0, 5040.0, 40320.0, 362880.0, 3628800.0,
];

/// Complex product.
fn cmul(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0]]
}

/// For the similarity field `v(q) = z (q − q₀)` that takes the values `dv` apart over the
/// edge `dp` (`z = dv / dp`, complex), the factor `φ = (eᶻ − 1) / z` with which the flow's
/// unit-time image of a point `q` is `q + v(q) φ`: the log spiral about `q₀`. Stable for
/// small `z` (a translation, `φ = 1`), and `1` (a straight step) on a collapsed edge.
fn spiral_factor(dv: [f64; 2], dp: [f64; 2]) -> [f64; 2] {
    let d2 = dp[0] * dp[0] + dp[1] * dp[1];
    if d2 <= 0.0 || d2.is_nan() {
        return [1.0, 0.0];
    }
    let z = [
        (dv[0] * dp[0] + dv[1] * dp[1]) / d2,
        (dv[1] * dp[0] - dv[0] * dp[1]) / d2,
    ];
    let r2 = z[0] * z[0] + z[1] * z[1];
    if r2 < 0.01 {
        // Σ zᵏ / (k + 1)! for k ≤ 9, by Horner: the remainder is below |z|¹⁰ / 11! < 1e-17
        // for |z| < 0.1, so no sines, cosines or exponentials for the small fields of a
        // drag.
        // Five terms are enough below |z| = 1e-3 (remainder below 1e-18).
        let terms = if r2 < 1e-6 { 5 } else { 10 };
        let mut acc = [1.0 / FACTORIALS[terms], 0.0];
        for k in (0..terms - 1).rev() {
            acc = cmul(acc, z);
            acc[0] += 1.0 / FACTORIALS[k + 1];
        }
        return acc;
    }
    // eᶻ − 1 = (eᵃ cos b − 1) + i eᵃ sin b, with eᵃ cos b − 1 = expm1(a) cos b − 2 sin²(b/2).
    let (a, b) = (z[0], z[1]);
    let half = (0.5 * b).sin();
    let num = [a.exp_m1() * b.cos() - 2.0 * half * half, a.exp() * b.sin()];
    // num / z
    [
        (num[0] * z[0] + num[1] * z[1]) / r2,
        (num[1] * z[0] - num[0] * z[1]) / r2,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The spiral factor is `(eᶻ − 1) / z` on both sides of the series' switch, and a
    /// rotation field's spiral is the rotation.
    #[test]
    fn spiral_factor_is_the_flow_of_a_similarity() {
        for z in [
            [1e-6, 2e-6],
            [0.05, -0.08],
            [0.099, 0.0],
            [0.0, -0.0999],
            [0.3, -0.2],
            [0.0, 1.5],
            [-2.0, 0.5],
        ] {
            let dp = [0.7, -0.4];
            let dv = cmul(z, dp);
            let phi = spiral_factor(dv, dp);
            // e^z via the reals.
            let e = [z[0].exp() * z[1].cos() - 1.0, z[0].exp() * z[1].sin()];
            let back = cmul(phi, z);
            assert!(
                (back[0] - e[0]).abs() < 1e-14 && (back[1] - e[1]).abs() < 1e-14,
                "{z:?}"
            );
        }
        // v(q) = iθ (q − c): the image of q is c + e^{iθ} (q − c).
        let (theta, c, q) = (1.2f64, [0.3, -0.1], [1.0, 2.0]);
        let field = |p: [f64; 2]| cmul([0.0, theta], [p[0] - c[0], p[1] - c[1]]);
        let other = [-0.5, 0.25];
        let (vq, vo) = (field(q), field(other));
        let phi = spiral_factor(
            [vq[0] - vo[0], vq[1] - vo[1]],
            [q[0] - other[0], q[1] - other[1]],
        );
        let moved = cmul(vq, phi);
        let image = [q[0] + moved[0], q[1] + moved[1]];
        let rot = cmul([theta.cos(), theta.sin()], [q[0] - c[0], q[1] - c[1]]);
        assert!(
            (image[0] - c[0] - rot[0]).abs() < 1e-14 && (image[1] - c[1] - rot[1]).abs() < 1e-14
        );
    }
}
