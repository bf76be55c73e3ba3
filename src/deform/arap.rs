//! As-rigid-as-possible posing with hard pins: 2D local/global iterations on a prefactored
//! cotangent Laplacian of the free vertices.
//!
//! Local step: each triangle's closest rotation `R` to its deformation gradient (the
//! cotangent-weighted fit of its edges, in closed form in 2D). Global step: the free vertices
//! minimising `Σ w_ij |(u_i − u_j) − R (x_i − x_j)|²` with the pinned ones at their targets, a
//! solve with two right-hand sides. The energy never rises from one iteration to the next
//! (each step minimises it over its own variables), and a rigid motion of every pin is
//! reproduced exactly: rotating every triangle by one rotation is then the minimum.
//!
//! With per-triangle stiffness ([`super::Deformer::set_stiffness`]) each triangle's term of
//! the energy, `A_f |J_f − R_f|²`, is multiplied by its weight: each of the triangle's
//! cotangent weights, in the matrix and the right-hand side alike. The local step is
//! unchanged (each rotation is its own triangle's best fit, whatever the weight).

// Small fixed-size matrix algebra reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use bdmorph_cholesky::Cholesky;

use super::{DeformError, DragReport, DragStatus};
use crate::param::frames::Frames;
use crate::param::local_global::{fit_each, free_laplacian, global_rhs, weighted_edges, Fit, NONE};

/// Options of [`super::PoseMethod::Arap`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct ArapOptions {
    /// Local/global iterations per drag at most (default 10): each drag starts from the
    /// previous pose, so a slow drag converges over a few mouse moves.
    pub iterations: u32,
    /// A drag stops early once no vertex moved by more than this times the mesh's size in
    /// an iteration (default `1e-12`).
    pub tolerance: f64,
    /// Bounds each drag in time or by a cancellation flag, checked before every
    /// local/global iteration (default unlimited): once spent, the drag ends with
    /// [`DeformError::Stopped`] and the pose before it.
    pub budget: crate::Budget,
}

impl Default for ArapOptions {
    fn default() -> Self {
        ArapOptions {
            iterations: 10,
            tolerance: 1e-12,
            budget: crate::Budget::unlimited(),
        }
    }
}

impl ArapOptions {
    /// Sets the most iterations per drag.
    pub fn with_iterations(mut self, iterations: u32) -> Self {
        self.iterations = iterations;
        self
    }
    /// Sets the early-stopping tolerance.
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }
    /// Bounds each drag by `budget` ([`ArapOptions::budget`]).
    pub fn with_budget(mut self, budget: crate::Budget) -> Self {
        self.budget = budget;
        self
    }
    /// Refuses a tolerance that is not a finite number >= 0 and 0 iterations.
    pub(crate) fn validate(&self) -> Result<(), DeformError> {
        super::check_tolerance("arap", "tolerance", self.tolerance)?;
        super::check_iterations("arap", "iterations", self.iterations)
    }
}

/// The method's state.
pub(crate) struct Arap {
    options: ArapOptions,
    /// Per vertex, its row among the free vertices, or [`NONE`] when pinned.
    index: Vec<u32>,
    pins: Vec<u32>,
    chol: Option<Cholesky>,
    rhs: Vec<f64>,
    /// Per triangle, its fitted rotation (rows).
    l: Vec<[[f64; 2]; 2]>,
    /// Per triangle and edge `(b, c), (c, a), (a, b)`: its cotangent weight (times the
    /// triangle's stiffness) times its vector in the triangle's rest layout.
    wdx: Vec<[[f64; 2]; 3]>,
    /// Per triangle, the factor of its term in the energy (`None`: all 1).
    stiffness: Option<Vec<f64>>,
}

impl Arap {
    pub(crate) fn options(&self) -> &ArapOptions {
        &self.options
    }

    pub(crate) fn new(
        frames: &Frames,
        n: usize,
        options: ArapOptions,
    ) -> Result<Arap, DeformError> {
        options.validate()?;
        let wdx = weighted_edges(frames, None);
        Ok(Arap {
            options,
            index: vec![NONE; n],
            pins: Vec::new(),
            chol: None,
            rhs: Vec::new(),
            l: vec![[[1.0, 0.0], [0.0, 1.0]]; frames.len()],
            wdx,
            stiffness: None,
        })
    }

    /// Sets each triangle's factor in the energy (checked by the caller: one per triangle,
    /// each finite and at least 1), the matrix and right-hand side both; the next
    /// [`Arap::set_pins`] factors with it. The local step's rotations do not depend on it
    /// (each is its own triangle's best fit, whatever the triangle's factor).
    pub(crate) fn set_stiffness(&mut self, frames: &Frames, stiffness: Option<&[f64]>) {
        self.wdx = weighted_edges(frames, stiffness);
        self.stiffness = stiffness.map(<[f64]>::to_vec);
    }

    /// Each triangle's factor in the energy, as [`Arap::set_stiffness`] set it.
    pub(crate) fn stiffness(&self) -> Option<&[f64]> {
        self.stiffness.as_deref()
    }

    /// Numbers the free vertices and factors their cotangent Laplacian.
    pub(crate) fn set_pins(&mut self, frames: &Frames, pins: &[u32]) -> Result<(), DeformError> {
        self.index.fill(NONE);
        let mut pinned = vec![false; self.index.len()];
        for &p in pins {
            pinned[p as usize] = true;
        }
        let mut k = 0u32;
        for (v, slot) in self.index.iter_mut().enumerate() {
            if !pinned[v] {
                *slot = k;
                k += 1;
            }
        }
        self.chol = if k > 0 {
            Some(free_laplacian(
                frames,
                self.stiffness.as_deref(),
                &self.index,
                k,
            )?)
        } else {
            None
        };
        self.rhs = vec![0.0; 2 * k as usize];
        self.pins = pins.to_vec();
        Ok(())
    }

    pub(crate) fn drag(
        &mut self,
        frames: &Frames,
        targets: &[[f64; 2]],
        uv: &mut [[f64; 2]],
        size: f64,
    ) -> Result<DragReport, DeformError> {
        for (&p, &t) in self.pins.iter().zip(targets) {
            uv[p as usize] = t;
        }
        let k = self.rhs.len() / 2;
        let mut iterations = 0;
        let mut last_change = 0.0;
        let mut status = DragStatus::Moving;
        while iterations < self.options.iterations.max(1) {
            self.options.budget.check()?;
            iterations += 1;
            fit_each(frames, uv, Fit::Rotation, &mut self.l);
            let Some(chol) = self.chol.as_mut() else {
                // Every vertex pinned: the pose is the targets.
                status = DragStatus::Converged;
                break;
            };
            global_rhs(
                frames,
                self.stiffness.as_deref(),
                &self.l,
                &self.wdx,
                &self.index,
                uv,
                &mut self.rhs,
            );
            chol.solve_in_place(&mut self.rhs, 2)?;
            last_change = 0.0f64;
            for (v, out) in uv.iter_mut().enumerate() {
                let i = self.index[v];
                if i != NONE {
                    let new = [self.rhs[i as usize], self.rhs[k + i as usize]];
                    last_change = last_change.max((new[0] - out[0]).hypot(new[1] - out[1]));
                    *out = new;
                }
            }
            if last_change <= self.options.tolerance * size {
                status = DragStatus::Converged;
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
