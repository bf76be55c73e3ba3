//! Bounded-distortion posing (Kovalsky, Aigerman, Basri, Lipman 2015), per drag, with hard
//! handles: a few ARAP local/global iterations from the previous pose (the as-rigid pose the
//! bound is then imposed on, as the paper projects a given map), then, if a triangle is
//! over the bound or flipped, alternating projections until every triangle is within it and
//! none is flipped, or the iteration budget is spent (then the report says so, and the next
//! drag goes on from there, with projections only until the bound is met again: ARAP
//! iterations would undo part of their work each time). Both factors (the rest Laplacian on the free vertices, as ARAP
//! and the projections weight it) are made once per set of pins.
//!
//! With per-triangle stiffness `w_t` ([`super::Deformer::set_stiffness`]) each triangle has its
//! own bound `K_t = 1 + (K − 1) / w_t`, in the projections and the test of whether the bound
//! is met, and its term of the ARAP iterations and of the projections' least squares is
//! weighted by `w_t`. With any triangle stiffer than 1 there is no Newton finish: its excess
//! energy is blind to scale, and shrinks a stiff region to ease its neighbours' excess (a
//! cap painted 1000 shrunk by 40% where the projections alone keep it within 1%).
//!
//! Projections alone, from the handles moved, would stop at the first map within the bound:
//! the triangles near a handle end at the bound, whatever an as-rigid pose would need, and
//! nothing brings a pose back once the handles return. The ARAP iterations give the pose
//! its shape and its way back; the projections its guarantee.

use super::arap::{Arap, ArapOptions};
use super::{DeformError, DragReport, DragStatus};
use crate::param::bounded::{BoundedDistortion, BoundedOptions};
use crate::param::energy::Energy;
use crate::param::frames::Frames;
use crate::param::newton::Newton;

/// Projections without progress (the largest distortion down by a relative 1e-4) in one drag
/// before the Newton finish takes over.
const STALL: u32 = 8;

/// Options of [`super::PoseMethod::Bounded`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct BoundedPoseOptions {
    /// The bound `K ≥ 1` on every triangle's conformal distortion.
    pub max_distortion: f64,
    /// Projection (and Newton finish) iterations per drag at most (default 100); a drag
    /// stops as soon as the bound is met.
    pub iterations: u32,
    /// ARAP local/global iterations per drag before the projections (default 5).
    pub arap_iterations: u32,
    /// The bound counts as met at `K (1 + tolerance)` (default 1e-3).
    pub tolerance: f64,
    /// Bounds each drag in time or by a cancellation flag, checked before every ARAP
    /// iteration, projection and Newton step (default unlimited): once spent, the drag ends
    /// with [`DeformError::Stopped`] and the pose before it.
    pub budget: crate::Budget,
}

impl BoundedPoseOptions {
    /// Options with the bound `K`.
    pub fn new(max_distortion: f64) -> BoundedPoseOptions {
        BoundedPoseOptions {
            max_distortion,
            iterations: 100,
            arap_iterations: 5,
            tolerance: 1e-3,
            budget: crate::Budget::unlimited(),
        }
    }
    /// Bounds each drag by `budget` ([`BoundedPoseOptions::budget`]).
    pub fn with_budget(mut self, budget: crate::Budget) -> Self {
        self.budget = budget;
        self
    }
    /// Sets the ARAP iterations per drag.
    pub fn with_arap_iterations(mut self, iterations: u32) -> Self {
        self.arap_iterations = iterations;
        self
    }
    /// Sets the most iterations per drag.
    pub fn with_iterations(mut self, iterations: u32) -> Self {
        self.iterations = iterations;
        self
    }
}

/// The method's state.
pub(crate) struct Bounded {
    options: BoundedPoseOptions,
    solver: Option<BoundedDistortion>,
    arap: Arap,
    /// The finishing phase: projected Newton on the excess distortion, pins held, for when
    /// the projections stall (as [`BoundedDistortion::solve_with`] does).
    newton: Option<Newton>,
    /// Whether the last drag ended over the bound: the next one only projects.
    behind: bool,
    /// The pose before an iteration, to measure its change.
    previous: Vec<[f64; 2]>,
    /// Per triangle, its bound `K_t = 1 + (K − 1) / w_t` for the stiffness `w_t` (`None`:
    /// `K` for all).
    face_bounds: Option<Vec<f64>>,
    /// Whether a triangle's stiffness is above 1: then no Newton finish.
    stiff: bool,
}

impl Bounded {
    pub(crate) fn new(
        frames: &Frames,
        n: usize,
        options: BoundedPoseOptions,
    ) -> Result<Bounded, DeformError> {
        let k = options.max_distortion;
        if !(k >= 1.0 && k.is_finite()) {
            return Err(DeformError::BadBound(k));
        }
        super::check_tolerance("bounded", "tolerance", options.tolerance)?;
        super::check_iterations("bounded", "iterations", options.iterations)?;
        // (No ARAP iterations is allowed: projections only.)
        let arap = Arap::new(
            frames,
            n,
            ArapOptions::default()
                .with_iterations(options.arap_iterations.max(1))
                .with_budget(options.budget.clone()),
        )?;
        Ok(Bounded {
            options,
            solver: None,
            newton: None,
            behind: false,
            arap,
            previous: Vec::new(),
            face_bounds: None,
            stiff: false,
        })
    }

    /// Sets each triangle's stiffness `w_t ≥ 1` (checked by the caller): its bound becomes
    /// `K_t = 1 + (K − 1) / w_t` (exactly `K` where `w_t = 1`), and its term of the ARAP
    /// iterations is weighted by `w_t`. The next [`Bounded::set_pins`] uses them.
    pub(crate) fn set_stiffness(&mut self, frames: &Frames, stiffness: Option<&[f64]>) {
        let k = self.options.max_distortion;
        self.face_bounds = stiffness.map(|w| {
            w.iter()
                .map(|&w| if w == 1.0 { k } else { 1.0 + (k - 1.0) / w })
                .collect()
        });
        self.stiff = stiffness.is_some_and(|w| w.iter().any(|&w| w > 1.0));
        self.arap.set_stiffness(frames, stiffness);
    }

    /// Triangle `f`'s bound.
    pub(crate) fn bound_of(&self, f: usize) -> f64 {
        self.face_bounds
            .as_ref()
            .map_or(self.options.max_distortion, |b| b[f])
    }

    pub(crate) fn options(&self) -> &BoundedPoseOptions {
        &self.options
    }

    pub(crate) fn set_pins(
        &mut self,
        frames: &Frames,
        n: usize,
        pins: &[u32],
    ) -> Result<(), DeformError> {
        let mut options = BoundedOptions::new(self.options.max_distortion)
            .with_iterations(self.options.iterations)
            .with_newton_finish(false)
            .with_budget(self.options.budget.clone());
        options.tolerance = self.options.tolerance;
        self.previous = vec![[0.0; 2]; n];
        self.behind = false;
        let bound = (self.options.max_distortion * (1.0 - 0.5 * self.options.tolerance)).max(1.0);
        // (Used only without stiff triangles, when every triangle's bound is K.)
        let mut newton =
            Newton::new(frames, n, Energy::Excess { bound }).map_err(DeformError::Bounded)?;
        newton.set_partial_projection(false);
        newton.fix(pins.iter().copied());
        self.newton = Some(newton);
        if self.options.arap_iterations > 0 {
            self.arap.set_pins(frames, pins)?;
        }
        let mut solver =
            BoundedDistortion::for_handles(frames.clone(), n, pins, options, self.arap.stiffness())
                .map_err(DeformError::Bounded)?;
        solver.set_face_bounds(self.face_bounds.clone());
        self.solver = Some(solver);
        Ok(())
    }

    pub(crate) fn drag(
        &mut self,
        frames: &Frames,
        targets: &[[f64; 2]],
        pins: &[u32],
        uv: &mut [[f64; 2]],
        size: f64,
    ) -> Result<DragReport, DeformError> {
        let solver = self.solver.as_mut().ok_or(DeformError::TargetCount {
            pins: 0,
            got: targets.len(),
        })?;
        solver.set_targets(targets);
        let (mut arap_iterations, mut arap_change) = (0, 0.0);
        if self.options.arap_iterations > 0 && !self.behind {
            let report = self.arap.drag(frames, targets, uv, size)?;
            (arap_iterations, arap_change) = (report.iterations, report.last_change);
        }
        for (&p, &t) in pins.iter().zip(targets) {
            uv[p as usize] = t;
        }
        // Each triangle's distortion over its own bound: met at 1 + tolerance.
        let limit = 1.0 + self.options.tolerance;
        let mut iterations = 0;
        let mut last_change = 0.0f64;
        let (mut best, mut since_best) = (f64::INFINITY, 0);
        let status;
        loop {
            let (worst, inverted) = solver.measure_excess(uv);
            let met = worst <= limit && inverted == 0;
            if met || iterations >= self.options.iterations {
                self.behind = !met;
                status = if met {
                    DragStatus::Converged
                } else {
                    DragStatus::Moving
                };
                break;
            }
            self.options.budget.check()?;
            if worst < best * (1.0 - 1e-4) {
                (best, since_best) = (worst, 0);
            } else {
                since_best += 1;
            }
            self.previous.copy_from_slice(uv);
            match self.newton.as_mut() {
                // Projections that stopped improving on an unflipped pose: Newton on the
                // excess, whose line search never flips a triangle.
                // Not with stiff triangles: the excess is blind to scale, and would shrink a
                // stiff region to ease its neighbours (measured: a cap painted 1000 shrunk by
                // 40%); the weighted projections keep its size.
                Some(newton) if since_best >= STALL && inverted == 0 && !self.stiff => {
                    let step = newton.iterate(frames, uv).map_err(DeformError::Bounded)?;
                    if step.step == 0.0 {
                        // No decrease: a local minimum of the excess; reported as unmet.
                        self.behind = true;
                        iterations += 1;
                        status = DragStatus::Stalled;
                        break;
                    }
                }
                _ => solver.iterate(uv).map_err(DeformError::Bounded)?,
            }
            last_change = uv
                .iter()
                .zip(&self.previous)
                .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
                .fold(0.0, f64::max);
            iterations += 1;
        }
        Ok(DragReport {
            iterations: arap_iterations + iterations,
            // The last iteration's change, of whichever phase ran last.
            last_change: if iterations > 0 {
                last_change / size
            } else {
                arap_change
            },
            status,
            ..DragReport::default()
        })
    }
}
