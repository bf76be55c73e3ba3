//! Posing that can neither flip nor crush a triangle: the symmetric Dirichlet energy with soft
//! handles, minimised by projected Newton from the previous pose on every drag.
//!
//! The pose `u` minimises
//!
//! ```text
//! E(u) = Σ_f s_f (A_f / A) (σ₁² + σ₂² + σ₁⁻² + σ₂⁻²)  +  ½ k Σ_handles |u_p − t_p|²
//! ```
//!
//! (`σ₁, σ₂` the singular values of triangle `f`'s deformation gradient from the rest shape,
//! `A_f` its area and `A` the mesh's, `s_f` its stiffness, `t_p` the handles' targets). The
//! first sum is infinite as a triangle degenerates, from either side: a triangle squashed flat
//! has `σ₂ → 0`, one stretched thin `σ₁ → ∞`. So the energy is a barrier against crushing as
//! well as against flipping, and its minimiser spreads a bend along a limb instead of folding
//! it at a joint. Near the rest shape it is four times ARAP's energy (`σ + σ⁻¹ ≈ 2 + (σ − 1)²`),
//! so small poses look as ARAP's and KVF's do.
//!
//! The handles are springs of weight `k` ([`SdOptions::weight`] times the mean diagonal of
//! the first sum's Hessian at rest, as KVF's weight is relative to its Laplacian's): where
//! following a handle would crush the mesh, the handle stops short, and the drag's
//! [`super::DragReport::pin_residual`] says by how much.
//!
//! Each iteration is a projected Newton step ([`crate::param::newton`]: per triangle the
//! analytic eigensystem of Smith, de Goes and Kim 2019, negative eigenvalues clamped, one
//! sparse factorisation on the pattern analysed once per mesh) with a line search whose first
//! trial is capped at 0.9 of the step at which a triangle's determinant would reach zero,
//! then halved until the energy decreases (Armijo): every accepted step keeps every triangle
//! unflipped and lowers `E`. A step the line search cannot take is not taken: the drag says
//! [`super::DragStatus::Stalled`], never success. A drag moving a handle further than 5% of
//! the mesh is followed in stretches ([`super::stretch`]), as the same drag in mouse moves.
//!
//! A pose that already has inverted triangles (a keyframe made elsewhere, or by a method that
//! folds) is posed with them: a triangle inverted where an iteration starts is given ARAP's
//! energy (finite there) for that iteration and does not limit its step, so it may come back;
//! the others still never invert. Flipped triangles never increase.

use super::stretch::Stretches;
use super::{DeformError, DragReport, DragStatus};
use crate::param::energy::{svd2, Energy};
use crate::param::frames::Frames;
use crate::param::newton::Newton;
use crate::param::ParamError;

/// A step made with an earlier pose's factor that moved the pose more than this fraction of
/// the step before it (converging linearly, slowly) has the next iteration factor anew.
const REFACTOR: f64 = 0.8;

/// Options of [`super::PoseMethod::Sd`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct SdOptions {
    /// The handles' weight, relative to the mesh's own stiffness (default 100, as KVF's):
    /// larger holds the handles closer to their targets and lets the mesh be distorted more
    /// to follow them, smaller lets the mesh hold them back sooner. A finite number > 0,
    /// checked by [`super::Deformer::set_pins`].
    pub weight: f64,
    /// Newton iterations per drag at most (default 4): a drag stops early once converged;
    /// the next drag goes on from the pose.
    pub iterations: u32,
    /// A drag stops early once no vertex moved by more than this times the mesh's size in an
    /// iteration (default `1e-12`).
    pub tolerance: f64,
    /// Bounds each drag in time or by a cancellation flag, checked before every Newton
    /// iteration (default unlimited): once spent, the drag ends with
    /// [`DeformError::Stopped`] and the pose before it.
    pub budget: crate::Budget,
}

impl Default for SdOptions {
    fn default() -> Self {
        SdOptions {
            weight: 100.0,
            iterations: 4,
            tolerance: 1e-12,
            budget: crate::Budget::unlimited(),
        }
    }
}

impl SdOptions {
    /// Sets the handles' weight.
    pub fn with_weight(mut self, weight: f64) -> Self {
        self.weight = weight;
        self
    }
    /// Sets the most Newton iterations per drag.
    pub fn with_iterations(mut self, iterations: u32) -> Self {
        self.iterations = iterations;
        self
    }
    /// Sets the early-stopping tolerance.
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }
    /// Bounds each drag by `budget` ([`SdOptions::budget`]).
    pub fn with_budget(mut self, budget: crate::Budget) -> Self {
        self.budget = budget;
        self
    }
}

/// The method's state.
pub(crate) struct Sd {
    options: SdOptions,
    newton: Newton,
    /// The mean diagonal of the energy's Hessian at rest (per unknown): `weight` is relative
    /// to it.
    mean_diagonal: f64,
    pins: Vec<u32>,
    /// Whether pins are set.
    pinned: bool,
    /// Whether the next iteration factors the Hessian at its pose (otherwise it solves with
    /// the last factor, made at an earlier pose).
    stale: bool,
    stretches: Stretches,
}

/// A failure of the Newton solver as the deformer's error.
fn solver_error(e: ParamError) -> DeformError {
    match e {
        ParamError::Solver { source, .. } => DeformError::Solver(source),
        other => DeformError::Bounded(other),
    }
}

impl Sd {
    /// Analyses the Hessian's pattern (once per mesh: it does not depend on the pins).
    pub(crate) fn new(frames: &Frames, n: usize, options: SdOptions) -> Result<Sd, DeformError> {
        super::check_tolerance("sd", "tolerance", options.tolerance)?;
        super::check_iterations("sd", "iterations", options.iterations)?;
        let energy = Energy::SymmetricDirichlet;
        let mut newton = Newton::new(frames, n, energy).map_err(solver_error)?;
        newton.set_partial_projection(false);
        newton.set_inverted_energy(Some(Energy::Arap));
        newton.set_roundoff_steps(true);
        Ok(Sd {
            options,
            newton,
            mean_diagonal: mean_rest_diagonal(frames, n, energy),
            pins: Vec::new(),
            pinned: false,
            stale: true,
            stretches: Stretches::default(),
        })
    }

    pub(crate) fn options(&self) -> &SdOptions {
        &self.options
    }

    /// Sets each triangle's factor in the energy (checked by the caller); the handles' weight
    /// stays relative to the unweighted mesh.
    pub(crate) fn set_stiffness(&mut self, stiffness: Option<&[f64]>) {
        self.newton.set_face_weights(stiffness);
        self.stale = true;
    }

    /// Sets the springs on the pins (nothing is factored here: each iteration factors).
    pub(crate) fn set_pins(&mut self, pins: &[u32]) -> Result<(), DeformError> {
        let weight = self.options.weight;
        if !(weight > 0.0 && weight.is_finite()) {
            return Err(DeformError::BadWeight(weight));
        }
        self.newton.set_springs(pins, weight * self.mean_diagonal);
        self.pins = pins.to_vec();
        self.pinned = true;
        self.stale = true;
        self.stretches.reset(pins.len());
        Ok(())
    }

    /// Sets the handles' weight (pins unchanged).
    pub(crate) fn set_weight(&mut self, weight: f64) -> Result<(), DeformError> {
        if !(weight > 0.0 && weight.is_finite()) {
            return Err(DeformError::BadWeight(weight));
        }
        self.options.weight = weight;
        if self.pinned {
            self.newton
                .set_springs(&self.pins, weight * self.mean_diagonal);
        }
        self.stale = true;
        Ok(())
    }

    /// The pose was replaced: the next drag's stretches start from the handles' places.
    pub(crate) fn forget_targets(&mut self) {
        self.stretches.forget();
        self.stale = true;
    }

    pub(crate) fn drag(
        &mut self,
        frames: &Frames,
        targets: &[[f64; 2]],
        uv: &mut [[f64; 2]],
        size: f64,
    ) -> Result<DragReport, DeformError> {
        if !self.pinned {
            return Err(DeformError::TargetCount {
                pins: 0,
                got: targets.len(),
            });
        }
        let mut stretches = std::mem::take(&mut self.stretches);
        stretches.start(&self.pins, uv);
        let result = stretches.follow(targets, uv, size, |stretch, uv| {
            self.iterate(frames, stretch, uv, size)
        });
        self.stretches = stretches;
        result
    }

    /// Up to [`SdOptions::iterations`] Newton iterations towards `targets`.
    fn iterate(
        &mut self,
        frames: &Frames,
        targets: &[[f64; 2]],
        uv: &mut [[f64; 2]],
        size: f64,
    ) -> Result<DragReport, DeformError> {
        self.newton.set_spring_targets(targets);
        let tolerance = self.options.tolerance * size;
        let limit = self.options.iterations.max(1);
        let (mut iterations, mut retried) = (0, false);
        let mut last_change = 0.0;
        let mut previous = f64::INFINITY;
        let mut status = DragStatus::Moving;
        while iterations < limit {
            self.options.budget.check()?;
            iterations += 1;
            let fresh = self.stale;
            let step = self
                .newton
                .iterate_reusing(frames, uv, !fresh)
                .map_err(solver_error)?;
            self.stale = false;
            let proposed = self.newton.proposed_move();
            if !(step.energy_before.is_finite() && step.gradient_norm.is_finite()) {
                // Targets beyond floating point: the energy (or its gradient) is not finite
                // where the pose is, and no step is taken.
                last_change = 0.0;
                self.stale = true;
                status = DragStatus::Stalled;
                break;
            }
            if step.step > 0.0 {
                last_change = step.step * proposed;
                if last_change <= tolerance {
                    status = DragStatus::Converged;
                    break;
                }
                // The factor is made again when its steps are no longer (nearly) Newton's:
                // cut short by the line search, or converging slowly.
                self.stale = step.step < 1.0 || last_change > REFACTOR * previous;
                previous = last_change;
            } else if proposed <= tolerance {
                // A stationary pose: the step asked for is within the tolerance.
                last_change = 0.0;
                status = DragStatus::Converged;
                break;
            } else if !fresh && !retried {
                // An earlier pose's factor gave a step the line search could not take: once
                // per drag, the iteration is made again with the Hessian where the pose is.
                self.stale = true;
                retried = true;
                iterations -= 1;
            } else {
                // Not even the Newton step at the pose lowers the energy (or it is not
                // finite, for targets beyond floating point): nothing moved.
                last_change = if proposed.is_finite() { proposed } else { 0.0 };
                self.stale = true;
                status = DragStatus::Stalled;
                break;
            }
        }
        Ok(DragReport {
            iterations,
            last_change: last_change / size,
            status,
            ..DragReport::default()
        })
    }
}

/// The mean diagonal entry of the Hessian of `energy` (area-weighted mean over the
/// triangles) at the rest shape, over the unknowns of vertices some triangle uses.
fn mean_rest_diagonal(frames: &Frames, n: usize, energy: Energy) -> f64 {
    let h = energy.projected_hessian(&svd2([[1.0, 0.0], [0.0, 1.0]]));
    let mut diagonal = vec![0.0; 2 * n];
    for (f, face) in frames.faces.iter().enumerate() {
        let w = frames.area[f] / frames.total_area;
        let g = &frames.g[f];
        for (k, &v) in face.iter().enumerate() {
            for r in 0..2 {
                let mut sum = 0.0;
                for c in 0..2 {
                    for d in 0..2 {
                        sum += h[2 * r + c][2 * r + d] * g[k][c] * g[k][d];
                    }
                }
                diagonal[2 * v as usize + r] += w * sum;
            }
        }
    }
    let used: Vec<f64> = diagonal.into_iter().filter(|&d| d > 0.0).collect();
    used.iter().sum::<f64>() / used.len().max(1) as f64
}
