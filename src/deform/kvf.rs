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
//!
//! # The globalised step
//!
//! The steps descend one energy, the one whose stationary poses they stop at:
//!
//! ```text
//! E(u) = Σ_f s_f A_f |F_f − R_f|²  +  ½ w Σ_handles |u_p − t_p|²
//! ```
//!
//! (`s_f` the stiffness, `R_f` the closest rotation to `F_f`: the ARAP energy plus the
//! handles' springs, in the units of the `v` step's matrix). For `α = 1, 1/2, 1/4, …` the
//! field is followed for a time `α` (a backtracking line search along the flow: `α v` has
//! the spiral factors of `α z`), and if that pose is refused, the pose is moved straight by
//! `α` towards the field's first solve (`ω = 0`, the ARAP global step with the springs: its
//! quadratic bounds `E` from above, so that direction lowers `E` for every `α` unless the
//! pose is stationary). A pose is taken when its energy is no higher than the pose's and,
//! with [`KvfOptions::flip_free`] (off by default), no unflipped triangle has shrunk below a
//! fifth of its area or past [`KvfOptions::max_distortion`]: a pose without flipped
//! triangles never gets one (a flip would need the signed area through zero, and a step
//! short enough never reaches it), and the steps do not crush triangles into slivers.
//! Without the line search, a large drag's field (a spring pulling a handle several mesh
//! sizes away) grows the pose by `e^|z|` along its spirals: energies of 1e10 to 1e137 and,
//! further, points that are not finite. A step that no `α` down to 2⁻⁴⁰ makes acceptable
//! is not taken: the drag stops there and says [`super::DragStatus::Stalled`].
//!
//! A drag that moves a handle further than 5% of the mesh's size is followed in stretches
//! of at most that, each with the drag's steps (the handles' rigid motion along its arc,
//! the rest along straight lines), as the same drag in small mouse moves would be: one
//! large drag ends where 20 small ones do.
//!
//! ARAP's energy and the springs are no barrier: where flip-free steps would have to fold
//! a triangle to go on (a limb dragged back through itself, a bent keyframe turned about its
//! handles), they stop, stalled, at distortion [`KvfOptions::max_distortion`] at most, short
//! of the handle. That is why they are not the default.

// Small fixed-size matrix algebra reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use bdmorph_cholesky::Cholesky;

use super::stretch::Stretches;
use super::{DeformError, DragReport, DragStatus};
use crate::param::frames::Frames;
use crate::param::local_global::{fit_each, free_laplacian_plus, global_rhs, weighted_edges, Fit};

/// The shortest fraction of a step the line search tries (2⁻⁴⁰): below it the step is not
/// taken and the drag stops, stalled.
const MIN_STEP: f64 = 9.094947017729282e-13;

/// The most a step may shrink a triangle: its area stays above this fraction of the area it
/// had (as projected Newton's line search stops short of a flip, at a fraction of the
/// way). Without it a step of a large drag may crush triangles to slivers (distortions of
/// 1e14 measured) that later steps cannot open again.
const SHRINK: f64 = 0.2;

/// Options of [`super::PoseMethod::Kvf`].
#[derive(Clone, Debug, PartialEq)]
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
    /// The largest conformal distortion `σ₁ / σ₂` a step may give a triangle (default 10):
    /// a step that would take a triangle over it (or over the distortion it has already,
    /// if that is more) is cut short, and a handle that cannot be followed further within
    /// it stops there, the drag [`super::DragStatus::Stalled`], rather than crushing the
    /// mesh. A finite number at least 1; checked by [`super::Deformer::set_pins`]. Only
    /// with [`KvfOptions::flip_free`].
    pub max_distortion: f64,
    /// Whether steps are flip-free (default `false`): with `true`, a triangle unflipped where
    /// a step starts keeps a positive area, above a fifth of what it had, and its distortion
    /// within [`KvfOptions::max_distortion`]. ARAP's energy is no barrier, so flip-free steps
    /// can stop against a triangle's zero area: where the way to the handles passes a fold
    /// (a limb dragged back through itself, a bent pose turned about its handles) they stop,
    /// [`super::DragStatus::Stalled`], short of the handles. With `false` (the original
    /// editor's way, and the default) the steps may fold and unfold on the way, never raising
    /// the energy; the studio repairs a drag that leaves a fold.
    pub flip_free: bool,
    /// Bounds each drag in time or by a cancellation flag, checked before every step
    /// (default unlimited): once spent, the drag ends with [`DeformError::Stopped`] and the
    /// pose before it.
    pub budget: crate::Budget,
}

impl Default for KvfOptions {
    fn default() -> Self {
        KvfOptions {
            weight: 100.0,
            iterations: 2,
            alternations: 2,
            tolerance: 1e-12,
            max_distortion: 10.0,
            flip_free: false,
            budget: crate::Budget::unlimited(),
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
    /// Sets the largest distortion a step may give a triangle.
    pub fn with_max_distortion(mut self, k: f64) -> Self {
        self.max_distortion = k;
        self
    }
    /// Sets whether steps are flip-free.
    pub fn with_flip_free(mut self, flip_free: bool) -> Self {
        self.flip_free = flip_free;
        self
    }
    /// Bounds each drag by `budget` ([`KvfOptions::budget`]).
    pub fn with_budget(mut self, budget: crate::Budget) -> Self {
        self.budget = budget;
        self
    }
    /// Refuses a tolerance that is not a finite number >= 0 and 0 steps or alternations
    /// (the weight and the distortion cap are checked by `set_pins`, as documented).
    pub(crate) fn validate(&self) -> Result<(), DeformError> {
        super::check_tolerance("kvf", "tolerance", self.tolerance)?;
        super::check_iterations("kvf", "iterations", self.iterations)?;
        super::check_iterations("kvf", "alternations", self.alternations)
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
    /// The pose a trial step reaches.
    trial: Vec<[f64; 2]>,
    /// Per triangle, the determinant of its gradient in the pose the step starts from: a
    /// positive one must stay above [`SHRINK`] times it.
    det: Vec<f64>,
    /// Per triangle, the largest distortion a step may give it: the larger of
    /// [`KvfOptions::max_distortion`] and its distortion where the step starts.
    cap: Vec<f64>,
    /// The straight step's target: the field's first solve, `ω = 0` (x then y rows).
    straight: Vec<f64>,
    /// How a drag is split into stretches.
    stretches: Stretches,
}

impl Kvf {
    pub(crate) fn new(frames: &Frames, n: usize, options: KvfOptions) -> Result<Kvf, DeformError> {
        options.validate()?;
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
        let cap = vec![options.max_distortion; m];
        Ok(Kvf {
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
            trial: vec![[0.0; 2]; n],
            det: vec![1.0; m],
            cap,
            straight: vec![0.0; 2 * n],
            stretches: Stretches::default(),
        })
    }

    pub(crate) fn options(&self) -> &KvfOptions {
        &self.options
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
        let k = self.options.max_distortion;
        if !(k >= 1.0 && k.is_finite()) {
            return Err(DeformError::BadBound(k));
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
        self.stretches.reset(pins.len());
        Ok(())
    }

    /// The pose was replaced: the next drag's stretches start from the handles' places.
    pub(crate) fn forget_targets(&mut self) {
        self.stretches.forget();
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
        let mut stretches = std::mem::take(&mut self.stretches);
        stretches.start(&self.pins, uv);
        let result = stretches.follow(targets, uv, size, |stretch, uv| {
            self.iterate(frames, stretch, uv, size)
        });
        self.stretches = stretches;
        result
    }

    /// Up to [`KvfOptions::iterations`] steps towards `targets`.
    fn iterate(
        &mut self,
        frames: &Frames,
        targets: &[[f64; 2]],
        uv: &mut [[f64; 2]],
        size: f64,
    ) -> Result<DragReport, DeformError> {
        let n = uv.len();
        let mut iterations = 0;
        let mut last_change = 0.0;
        let mut status = DragStatus::Moving;
        while iterations < self.options.iterations.max(1) {
            self.options.budget.check()?;
            iterations += 1;
            match self.step(frames, targets, uv, size)? {
                Step::Moved { change, full } => {
                    last_change = change;
                    if full && change <= self.options.tolerance * size {
                        status = DragStatus::Converged;
                        break;
                    }
                }
                Step::Stationary => {
                    last_change = 0.0;
                    status = DragStatus::Converged;
                    break;
                }
                Step::Stuck { proposed } => {
                    // No step lowered the energy without a flip: the pose stays as it is,
                    // as far from stationary as the step it could not take says.
                    last_change = proposed;
                    status = DragStatus::Stalled;
                    break;
                }
            }
        }
        debug_assert_eq!(self.rhs.len(), 2 * n);
        Ok(DragReport {
            iterations,
            last_change: last_change / size,
            status,
            ..DragReport::default()
        })
    }

    /// The energy the steps descend, `Σ s_f A_f |F_f − R_f|² + ½ w Σ |u_p − t_p|²`, of `uv`;
    /// `None` when a triangle with a positive determinant in [`Kvf::det`] has shrunk below
    /// [`SHRINK`] of it (or flipped) there, or the energy is not finite.
    fn merit(&self, frames: &Frames, targets: &[[f64; 2]], uv: &[[f64; 2]]) -> Option<f64> {
        let mut energy = 0.0;
        for f in 0..frames.len() {
            let j = frames.gradient(f, uv);
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            let (q, r) = super::similarity_parts(j);
            // A NaN fails the tests too.
            if self.options.flip_free && self.det[f] > 0.0 {
                let kept = det > SHRINK * self.det[f] && q + r <= self.cap[f] * (q - r);
                if !kept {
                    return None;
                }
            }
            let s = self.face_stiffness.as_ref().map_or(1.0, |w| w[f]);
            energy += s * frames.area[f] * (2.0 * (q - 1.0) * (q - 1.0) + 2.0 * r * r);
        }
        for (&p, t) in self.pins.iter().zip(targets) {
            let u = uv[p as usize];
            let (dx, dy) = (u[0] - t[0], u[1] - t[1]);
            energy += 0.5 * self.stiffness * (dx * dx + dy * dy);
        }
        energy.is_finite().then_some(energy)
    }

    /// One field and one move along it, as far along it as the line search allows.
    ///
    /// For `α = 1, 1/2, 1/4, …` down to [`MIN_STEP`]: the field's flow for a time `α` (the
    /// log spirals), then, if that is refused, the straight step `α (y₀ − u)` towards the
    /// field's first solve (`ω = 0`: the ARAP global step with the handles' springs, whose
    /// quadratic bounds `E` from above, so every `α` in `(0, 1]` lowers `E` unless `u` is
    /// stationary). A move is taken when it shrinks no triangle below [`SHRINK`] of its
    /// area and does not raise `E` (a full step within the tolerance is round-off of a
    /// stationary pose, taken whatever the energy's last digits say).
    fn step(
        &mut self,
        frames: &Frames,
        targets: &[[f64; 2]],
        uv: &mut [[f64; 2]],
        size: f64,
    ) -> Result<Step, DeformError> {
        let n = uv.len();
        fit_each(frames, uv, Fit::Rotation, &mut self.rotation);
        for f in 0..frames.len() {
            let j = frames.gradient(f, uv);
            self.det[f] = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            let (q, r) = super::similarity_parts(j);
            self.cap[f] = if q - r > 0.0 {
                self.options.max_distortion.max((q + r) / (q - r))
            } else {
                f64::INFINITY
            };
        }
        if !self.strain_feedback {
            for f in 0..frames.len() {
                self.gradient[f] = frames.gradient(f, uv);
            }
        }
        // Without the strain term (the original's flow, kept for the test of its drift)
        // there is no energy to descend: only shrinking and flips are refused.
        let start = if self.strain_feedback {
            self.merit(frames, targets, uv)
        } else {
            None
        };
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
            if round == 0 {
                self.straight.copy_from_slice(&self.rhs);
            }
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
        let tolerance = self.options.tolerance * size;
        let proposed = (0..n)
            .filter(|&v| self.count[v] > 0.0)
            .map(|v| (self.straight[v] - uv[v][0]).hypot(self.straight[n + v] - uv[v][1]))
            .fold(0.0, f64::max);
        let mut alpha = 1.0;
        while alpha >= MIN_STEP {
            let full = alpha == 1.0;
            for straight in [false, true] {
                if straight && !self.strain_feedback {
                    continue;
                }
                let change = if straight {
                    self.line(uv, alpha)
                } else {
                    self.advect(uv, alpha)
                };
                let Some(energy) = self.merit(frames, targets, &self.trial) else {
                    continue;
                };
                let accept = (full && change <= tolerance)
                    || match start {
                        Some(e0) => energy <= e0 + 1e-12 * e0.abs(),
                        // No energy to compare with (the original's flow, or a pose that
                        // came with none that is finite): any move that keeps the triangles
                        // is taken.
                        None => true,
                    };
                if accept {
                    uv.copy_from_slice(&self.trial);
                    return Ok(Step::Moved {
                        change,
                        full: full && !straight,
                    });
                }
            }
            alpha *= 0.5;
        }
        Ok(if proposed <= tolerance {
            Step::Stationary
        } else {
            Step::Stuck { proposed }
        })
    }

    /// The pose `uv` moved straight towards the field's first solve, by `α` of the way, into
    /// [`Kvf::trial`]; the largest move of a vertex.
    fn line(&mut self, uv: &[[f64; 2]], alpha: f64) -> f64 {
        let n = uv.len();
        let mut change = 0.0f64;
        for (v, out) in self.trial.iter_mut().enumerate() {
            if self.count[v] == 0.0 {
                *out = uv[v];
                continue;
            }
            let d = [self.straight[v] - uv[v][0], self.straight[n + v] - uv[v][1]];
            *out = [uv[v][0] + alpha * d[0], uv[v][1] + alpha * d[1]];
            change = change.max(alpha * d[0].hypot(d[1]));
        }
        change
    }

    /// The pose `uv` moved along the field `α (y − u)` (`y` in [`Kvf::rhs`]) by each edge's
    /// log spiral, into [`Kvf::trial`]; the largest move of a vertex.
    fn advect(&mut self, uv: &[[f64; 2]], alpha: f64) -> f64 {
        let n = uv.len();
        self.sum.fill([0.0; 2]);
        for &(i, j, times) in &self.edges {
            let (i, j) = (i as usize, j as usize);
            let (pi, pj) = (uv[i], uv[j]);
            let vi = [
                alpha * (self.rhs[i] - pi[0]),
                alpha * (self.rhs[n + i] - pi[1]),
            ];
            let vj = [
                alpha * (self.rhs[j] - pj[0]),
                alpha * (self.rhs[n + j] - pj[1]),
            ];
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
        for (v, out) in self.trial.iter_mut().enumerate() {
            let c = self.count[v];
            if c == 0.0 {
                *out = uv[v];
                continue;
            }
            let new = [self.sum[v][0] / c, self.sum[v][1] / c];
            change = change.max((new[0] - uv[v][0]).hypot(new[1] - uv[v][1]));
            *out = new;
        }
        change
    }
}

/// What one step did.
enum Step {
    /// It moved the pose; the largest move of a vertex, and whether it was the field's
    /// whole step.
    Moved { change: f64, full: bool },
    /// The pose is stationary: the field's first solve is the pose, within the tolerance.
    Stationary,
    /// No move was taken: none lowered the energy without shrinking a triangle too far;
    /// the largest move of a vertex the straight step proposed.
    Stuck { proposed: f64 },
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
