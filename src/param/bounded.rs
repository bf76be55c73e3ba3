//! Large-scale bounded-distortion mappings (Kovalsky, Aigerman, Basri, Lipman 2015): push
//! any map of a triangle mesh under a bound `K` on the conformal distortion of every triangle
//! (`σ_max ≤ K σ_min`, orientation preserved), keeping positional constraints.
//!
//! With `T` the linear map from vertex positions to the triangles' Jacobians (weighted by
//! the square roots of the areas), each iteration
//!
//! 1. projects every Jacobian `z = T x` onto the bounded-distortion set in closed form
//!    ([`project`]: the signed singular values moved onto `τ₁ = K τ₂`), giving `p`;
//! 2. solves `min ‖T x − p‖²` subject to the positional constraints and the tangent
//!    half-space of the set at `p`, `⟨n, T x − p⟩ ≤ 0` with `n = z − p`: the constraints are
//!    eliminated (pinned coordinates) and the half-space, when active, is one extra row,
//!    handled by the Schur complement: two back-substitutions with a factor computed once.
//!
//! `TᵀT` is the cotan Laplacian on each coordinate (one vertex is pinned when no constraint
//! fixes the translation), so it factors once, with two right-hand sides per solve.
//!
//! The iterations stop when every triangle's distortion is at most `K (1 + tolerance)` and no
//! triangle is inverted, or at the iteration limit, with the worst triangles reported.
//!
//! [`flatten`] runs it from one starting map after another (Tutte, LSCM, ...) until one
//! meets the bound, and [`angle_lower_bound`] is the evidence that a bound is infeasible:
//! no map of the mesh can meet a bound below it, whatever the start.

// Small fixed-size matrix algebra reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use bdmorph_cholesky::Cholesky;

use super::energy::{svd2, Energy};
use super::frames::Frames;
use super::newton::Newton;
use super::{ParamError, ParamMethod, ParamOptions, Parameterization};
use crate::io::SurfaceMesh;

const NONE: u32 = u32::MAX;

/// Alternating-projection iterations without progress before the finishing phase starts.
pub const STALL_WINDOW: u32 = 30;

/// Iterations (counted from the last progress of the alternating projections, so Newton
/// iterations included) without the largest distortion falling by a relative 1e-4 after
/// which the finishing phase gives up.
pub const NEWTON_STALL_WINDOW: u32 = 5 * STALL_WINDOW;

/// The projection of a 2×2 matrix (rows) onto the set of orientation-preserving matrices
/// whose conformal distortion `σ₁ / σ₂` is at most `k` (`k ≥ 1`), in the Frobenius norm:
/// with the signed SVD `C = U diag(σ₁, σ₂) Vᵀ`, `U diag(τ₁, τ₂) Vᵀ` where `(τ₁, τ₂)` is the
/// nearest point of `{τ₁ ≤ k τ₂}` (unchanged when already inside; otherwise on the line
/// `τ₁ = k τ₂`, `τ₂ = (k σ₁ + σ₂) / (k² + 1)`).
///
/// ```
/// use bdmorph::param::bounded::project;
/// // A stretch by 4 projected onto distortion at most 2.
/// let p = project([[4.0, 0.0], [0.0, 1.0]], 2.0);
/// assert!((p[0][0] - 3.6).abs() < 1e-12 && (p[1][1] - 1.8).abs() < 1e-12);
/// ```
pub fn project(c: [[f64; 2]; 2], k: f64) -> [[f64; 2]; 2] {
    let svd = svd2(c);
    let [s1, s2] = svd.sigma;
    if s1 <= k * s2 {
        return c;
    }
    let t2 = ((k * s1 + s2) / (k * k + 1.0)).max(0.0);
    let t1 = k * t2;
    let mut out = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            out[i][j] = svd.u[i][0] * t1 * svd.v[j][0] + svd.u[i][1] * t2 * svd.v[j][1];
        }
    }
    out
}

/// The conformal distortion of a 2×2 matrix: `σ₁ / σ₂`, infinite when not orientation
/// preserving.
pub fn distortion(c: [[f64; 2]; 2]) -> f64 {
    let [s1, s2] = svd2(c).sigma;
    if s2 > 0.0 {
        s1 / s2
    } else {
        f64::INFINITY
    }
}

/// Refuses bounds that are not finite numbers of at least 1, a tolerance that is not a
/// finite number above 0 and an iteration limit of 0.
fn check_bounds(options: &BoundedOptions) -> Result<(), ParamError> {
    for k in std::iter::once(options.max_distortion).chain(options.inverted_bound) {
        if !(k >= 1.0 && k.is_finite()) {
            return Err(ParamError::BadBound(k));
        }
    }
    super::check_tolerance("tolerance", options.tolerance)?;
    super::check_iterations("iterations", options.iterations)?;
    Ok(())
}

/// Options of [`BoundedDistortion`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct BoundedOptions {
    /// The bound `K ≥ 1` on every triangle's conformal distortion.
    pub max_distortion: f64,
    /// The most iterations (default 5000).
    pub iterations: u32,
    /// Done when every triangle's distortion is at most `K (1 + tolerance)` (default 1e-3).
    pub tolerance: f64,
    /// Whether stalled alternating projections hand over to the projected Newton finish
    /// (default true; see [`BoundedDistortion::solve_with`]).
    pub newton_finish: bool,
    /// The bound the projections use for a triangle while it is inverted, when smaller than
    /// `max_distortion` (default `None`: `max_distortion` for every triangle). An inverted
    /// Jacobian's projection has the smaller singular value `(k σ₁ + σ₂) / (k² + 1)`: near
    /// zero for a large `k` (a sliver, which its neighbours fold back), well inside for
    /// `k` about 2 or 3, so a folded start untangles in far fewer iterations. The maps the
    /// iterations stop at are the same: every triangle within `max_distortion`, none
    /// inverted.
    pub inverted_bound: Option<f64>,
    /// Bounds [`BoundedDistortion::solve_with`] in time or by a cancellation flag, checked
    /// before every iteration of either phase (default unlimited): once spent,
    /// [`ParamError::Stopped`] (the map keeps the last iteration's result).
    pub budget: crate::Budget,
}

impl BoundedOptions {
    /// Options with the bound `K`.
    pub fn new(max_distortion: f64) -> BoundedOptions {
        BoundedOptions {
            max_distortion,
            iterations: 5000,
            tolerance: 1e-3,
            newton_finish: true,
            inverted_bound: None,
            budget: crate::Budget::unlimited(),
        }
    }
    /// Bounds the iterations by `budget` ([`BoundedOptions::budget`]).
    pub fn with_budget(mut self, budget: crate::Budget) -> Self {
        self.budget = budget;
        self
    }
    /// Sets the iteration limit.
    pub fn with_iterations(mut self, iterations: u32) -> Self {
        self.iterations = iterations;
        self
    }
    /// Turns the projected Newton finish on or off (alternating projections only).
    pub fn with_newton_finish(mut self, on: bool) -> Self {
        self.newton_finish = on;
        self
    }
    /// Sets the bound the projections use for inverted triangles (see
    /// [`BoundedOptions::inverted_bound`]).
    pub fn with_inverted_bound(mut self, k: f64) -> Self {
        self.inverted_bound = Some(k);
        self
    }
}

/// What a run did.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundedReport {
    /// Whether every triangle ended within the bound (and none inverted).
    pub converged: bool,
    /// Iterations run, both phases.
    pub iterations: u32,
    /// Whether the iterations stopped before the limit because neither phase could lower the
    /// largest distortion any further: a local minimum of the excess, which does not prove
    /// the bound infeasible (another start may meet it: [`flatten`]; [`angle_lower_bound`] is
    /// evidence of infeasibility).
    pub stalled: bool,
    /// Of those, the projected Newton iterations of the finishing phase (zero when the
    /// alternating projections alone met the bound).
    pub newton_iterations: u32,
    /// The largest distortion at the end (infinite if a triangle is inverted).
    pub max_distortion: f64,
    /// Inverted (or degenerate) triangles at the end.
    pub inverted: usize,
    /// The worst triangles at the end, worst first: (face, distortion); at most 10.
    pub worst: Vec<(usize, f64)>,
    /// The largest distance of a constrained vertex from its target.
    pub constraint_error: f64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// The prepared solver: the per-triangle constants and the factored `TᵀT` on the free
/// vertices.
pub struct BoundedDistortion {
    frames: Frames,
    options: BoundedOptions,
    /// Unknown of each vertex, or [`NONE`] for a constrained one.
    index: Vec<u32>,
    /// Constrained vertices and their targets.
    pins: Vec<(u32, [f64; 2])>,
    chol: Cholesky,
    /// Two right-hand sides (u and v) for the projection target, and two for the row.
    rhs: Vec<f64>,
    row: Vec<f64>,
    /// The half-space row before its solve.
    eta: Vec<f64>,
    projected: Vec<[[f64; 2]; 2]>,
    /// Per triangle, its own bound in place of `options.max_distortion` (posing with
    /// stiffness: tighter bounds where the mesh is painted stiff).
    face_bounds: Option<Vec<f64>>,
}

impl std::fmt::Debug for BoundedDistortion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BoundedDistortion")
            .field("faces", &self.frames.len())
            .field("pins", &self.pins.len())
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

impl BoundedDistortion {
    /// Prepares the solver for `mesh` (any triangle mesh with finite coordinates and no
    /// degenerate triangle; a 2D mesh has `z = 0`) with the positional constraints `pins`
    /// (vertex, target point in the plane). Without pins, vertex 0 stays where the starting
    /// map puts it (the problem is invariant to translations).
    ///
    /// # Errors
    /// [`ParamError::EmptyMesh`] without a vertex or a triangle; [`ParamError::BadBound`] and
    /// [`ParamError::BadOption`] for options out of range; the mesh's and the pins' errors.
    pub fn new(
        mesh: &SurfaceMesh,
        pins: &[(u32, [f64; 2])],
        options: BoundedOptions,
    ) -> Result<BoundedDistortion, ParamError> {
        check_bounds(&options)?;
        if mesh.positions.is_empty() || mesh.faces.is_empty() {
            return Err(ParamError::EmptyMesh {
                vertices: mesh.positions.len(),
                faces: mesh.faces.len(),
            });
        }
        if let Some(vertex) = mesh
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(ParamError::NonFinite { vertex });
        }
        let n = mesh.positions.len();
        if let Some(&(vertex, _)) = pins
            .iter()
            .find(|(v, t)| *v as usize >= n || !(t[0].is_finite() && t[1].is_finite()))
        {
            return Err(ParamError::BadPin {
                vertex,
                n_vertices: n,
            });
        }
        let mut seen = vec![false; n];
        for &(v, _) in pins {
            if std::mem::replace(&mut seen[v as usize], true) {
                return Err(ParamError::PinnedTwice { vertex: v });
            }
        }
        super::check_indices(mesh)?;
        let frames = Frames::new(mesh).map_err(|face| ParamError::Degenerate { face })?;
        BoundedDistortion::with_frames(frames, n, pins, 0, options)
    }

    /// The solver for the handles `pins` (vertices, each checked in range, at least one),
    /// their targets to come with [`BoundedDistortion::set_targets`]: posing, where the
    /// handles move and the factor stays.
    ///
    /// With `stiffness` (one factor per triangle, each finite and at least 1, checked by the
    /// caller), each triangle's term of the least-squares step, `A_t |J_t − P_t|²`, is
    /// multiplied by its factor: a stiff triangle keeps closer to its projection, its
    /// neighbours give way.
    pub(crate) fn for_handles(
        frames: Frames,
        n: usize,
        pins: &[u32],
        options: BoundedOptions,
        stiffness: Option<&[f64]>,
    ) -> Result<BoundedDistortion, ParamError> {
        check_bounds(&options)?;
        if n == 0 || frames.faces.is_empty() {
            return Err(ParamError::EmptyMesh {
                vertices: n,
                faces: frames.len(),
            });
        }
        let pins: Vec<(u32, [f64; 2])> = pins.iter().map(|&v| (v, [0.0; 2])).collect();
        let mut frames = frames;
        if let Some(w) = stiffness {
            // The areas are the least-squares weights (of the factor and of each step), and
            // only that: the measures here are per triangle, unweighted.
            for (a, w) in frames.area.iter_mut().zip(w) {
                *a *= w;
            }
        }
        BoundedDistortion::with_frames(frames, n, &pins, 0, options)
    }

    /// Moves the handles' targets (one per pin, in order); allocates nothing.
    pub(crate) fn set_targets(&mut self, targets: &[[f64; 2]]) {
        for (pin, &t) in self.pins.iter_mut().zip(targets) {
            pin.1 = t;
        }
    }

    fn with_frames(
        frames: Frames,
        n: usize,
        pins: &[(u32, [f64; 2])],
        anchor: u32,
        options: BoundedOptions,
    ) -> Result<BoundedDistortion, ParamError> {
        let err = |source| ParamError::Solver {
            what: "bounded distortion",
            source,
        };
        let mut index = vec![0u32; n];
        for &(v, _) in pins {
            index[v as usize] = NONE;
        }
        if pins.is_empty() {
            index[anchor as usize] = NONE;
        }
        let mut k = 0u32;
        for slot in index.iter_mut() {
            if *slot != NONE {
                *slot = k;
                k += 1;
            }
        }
        // TᵀT per coordinate: Σ_t A_t Σ_c g_v[c] g_w[c] (the cotan Laplacian).
        let mut pairs: Vec<(u32, u32)> = (0..k).map(|i| (i, i)).collect();
        let mut vals: Vec<f64> = vec![0.0; k as usize];
        for (f, face) in frames.faces.iter().enumerate() {
            let g = frames.g[f];
            let a = frames.area[f];
            for p in 0..3 {
                for q in 0..3 {
                    let (ip, iq) = (index[face[p] as usize], index[face[q] as usize]);
                    if ip == NONE || iq == NONE || ip < iq {
                        continue;
                    }
                    pairs.push((ip, iq));
                    vals.push(a * (g[p][0] * g[q][0] + g[p][1] * g[q][1]));
                }
            }
        }
        let chol = Cholesky::assemble(k as usize, &pairs, &vals, 2).map_err(err)?;
        let m = frames.len();
        Ok(BoundedDistortion {
            frames,
            options,
            index,
            pins: pins.to_vec(),
            chol,
            rhs: vec![0.0; 2 * k as usize],
            row: vec![0.0; 2 * k as usize],
            eta: vec![0.0; 2 * k as usize],
            projected: vec![[[0.0; 2]; 2]; m],
            face_bounds: None,
        })
    }

    /// Gives each triangle its own bound (one per triangle, each finite and at least 1,
    /// checked by the caller), in place of `max_distortion`: the projections use it, and
    /// [`BoundedDistortion::measure_excess`] measures against it. `inverted_bound` still caps
    /// an inverted triangle's.
    pub(crate) fn set_face_bounds(&mut self, bounds: Option<Vec<f64>>) {
        self.face_bounds = bounds;
    }

    /// Triangle `f`'s bound.
    fn bound_of(&self, f: usize) -> f64 {
        self.face_bounds
            .as_ref()
            .map_or(self.options.max_distortion, |b| b[f])
    }

    /// The largest ratio of a triangle's distortion to its own bound (at most 1 when every
    /// triangle is within its bound; infinite with an inverted one) and the number of
    /// inverted triangles of `uv`.
    pub(crate) fn measure_excess(&self, uv: &[[f64; 2]]) -> (f64, usize) {
        let mut worst: f64 = 0.0;
        let mut inverted = 0;
        for f in 0..self.frames.len() {
            let d = distortion(self.frames.gradient(f, uv));
            if d.is_infinite() {
                inverted += 1;
            }
            worst = worst.max(d / self.bound_of(f));
        }
        (worst, inverted)
    }

    /// Iterates from the map `uv` (one point per vertex) until every triangle is within the
    /// bound or the iteration limit, in place. `progress` sees each iteration's largest
    /// distortion.
    ///
    /// When the alternating projections stop improving (the largest distortion not down by
    /// a relative 1e-4 in [`STALL_WINDOW`] iterations) on a map with no inverted triangle, a
    /// finishing phase minimises the excess distortion ([`Energy::Excess`], with the bound
    /// set half the tolerance inside `K`) by projected Newton with the pins held: its line
    /// search never inverts a triangle, and its energy is zero exactly on the maps within
    /// the bound.
    ///
    /// # Errors
    /// [`ParamError::UvLength`] unless `uv` has one point per vertex; [`ParamError::Stopped`]
    /// once [`BoundedOptions::budget`] is spent; a failed solve.
    pub fn solve_with(
        &mut self,
        uv: &mut [[f64; 2]],
        mut progress: impl FnMut(u32, f64),
    ) -> Result<BoundedReport, ParamError> {
        super::check_uv_len(self.index.len(), uv)?;
        let started = std::time::Instant::now();
        for &(v, t) in &self.pins {
            uv[v as usize] = t;
        }
        let k_bound = self.options.max_distortion;
        let limit = k_bound * (1.0 + self.options.tolerance);
        let mut iterations = 0;
        let mut newton_iterations = 0;
        let (mut best, mut since_best) = (f64::INFINITY, 0);
        let mut newton: Option<Newton> = None;
        let mut stalled = false;
        loop {
            let (worst, inverted) = self.measure(uv);
            progress(iterations, worst);
            if (worst <= limit && inverted == 0) || iterations >= self.options.iterations {
                break;
            }
            self.options.budget.check()?;
            if worst < best * (1.0 - 1e-4) {
                (best, since_best) = (worst, 0);
            } else {
                since_best += 1;
            }
            if self.options.newton_finish
                && newton.is_none()
                && since_best >= STALL_WINDOW
                && inverted == 0
            {
                let bound = (k_bound * (1.0 - 0.5 * self.options.tolerance)).max(1.0);
                let mut solver = Newton::new(&self.frames, uv.len(), Energy::Excess { bound })?;
                // As measured and documented for the finish (BENCHMARKS.md).
                solver.set_partial_projection(false);
                solver.fix(self.pins.iter().map(|&(v, _)| v));
                newton = Some(solver);
            }
            match newton.as_mut() {
                Some(solver) => {
                    let step = solver.iterate(&self.frames, uv)?;
                    newton_iterations += 1;
                    iterations += 1;
                    if step.step == 0.0 || since_best >= NEWTON_STALL_WINDOW {
                        // The line search found no decrease, or the largest distortion has
                        // not moved for long: a local minimum with excess.
                        stalled = true;
                        break;
                    }
                }
                None => {
                    self.iterate(uv)?;
                    iterations += 1;
                }
            }
        }
        let mut report = self.report(uv, iterations, started.elapsed().as_secs_f64());
        report.newton_iterations = newton_iterations;
        report.stalled = stalled && !report.converged;
        Ok(report)
    }

    /// The largest distortion and the number of inverted triangles of `uv`.
    pub(crate) fn measure(&self, uv: &[[f64; 2]]) -> (f64, usize) {
        let mut worst: f64 = 1.0;
        let mut inverted = 0;
        for f in 0..self.frames.len() {
            let d = distortion(self.frames.gradient(f, uv));
            if d.is_infinite() {
                inverted += 1;
            }
            worst = worst.max(d);
        }
        (worst, inverted)
    }

    fn report(&self, uv: &[[f64; 2]], iterations: u32, seconds: f64) -> BoundedReport {
        let mut all: Vec<(usize, f64)> = (0..self.frames.len())
            .map(|f| (f, distortion(self.frames.gradient(f, uv))))
            .collect();
        all.sort_by(|a, b| b.1.total_cmp(&a.1));
        let (worst, inverted) = self.measure(uv);
        let constraint_error = self
            .pins
            .iter()
            .map(|&(v, t)| (uv[v as usize][0] - t[0]).hypot(uv[v as usize][1] - t[1]))
            .fold(0.0, f64::max);
        BoundedReport {
            converged: worst <= self.options.max_distortion * (1.0 + self.options.tolerance)
                && inverted == 0,
            iterations,
            newton_iterations: 0,
            stalled: false,
            max_distortion: worst,
            inverted,
            worst: all.into_iter().take(10).collect(),
            constraint_error,
            seconds,
        }
    }

    /// One projection and one constrained least-squares step, in place.
    ///
    /// # Errors
    /// [`ParamError::UvLength`] unless `uv` has one point per vertex; a failed solve.
    pub fn iterate(&mut self, uv: &mut [[f64; 2]]) -> Result<(), ParamError> {
        super::check_uv_len(self.index.len(), uv)?;
        let k = self.rhs.len() / 2;
        let kb = self.options.max_distortion;
        let k_inverted = self.options.inverted_bound.map_or(kb, |k| k.min(kb));
        // 1. Project; the right-hand side Tᵀ W p (less the fixed vertices' part), and the
        //    half-space row η = Tᵀ W n with n = z - p, and its constant ⟨n, p⟩ (less the
        //    fixed vertices' part).
        self.rhs.fill(0.0);
        self.row.fill(0.0);
        let mut row_rhs = 0.0;
        let mut active = false;
        for f in 0..self.frames.len() {
            let z = self.frames.gradient(f, uv);
            let inverted = z[0][0] * z[1][1] - z[0][1] * z[1][0] <= 0.0;
            let p = match &self.face_bounds {
                None => project(z, if inverted { k_inverted } else { kb }),
                Some(bounds) => {
                    let k = bounds[f];
                    let ki = self.options.inverted_bound.map_or(k, |i| i.min(k));
                    project(z, if inverted { ki } else { k })
                }
            };
            self.projected[f] = p;
            let nrm = [
                [z[0][0] - p[0][0], z[0][1] - p[0][1]],
                [z[1][0] - p[1][0], z[1][1] - p[1][1]],
            ];
            let a = self.frames.area[f];
            let g = self.frames.g[f];
            let face = self.frames.faces[f];
            let touches = nrm.iter().flatten().any(|&x| x != 0.0);
            active |= touches;
            for (pv, &v) in face.iter().enumerate() {
                let i = self.index[v as usize];
                for r in 0..2 {
                    let tp = a * (p[r][0] * g[pv][0] + p[r][1] * g[pv][1]);
                    let tn = a * (nrm[r][0] * g[pv][0] + nrm[r][1] * g[pv][1]);
                    if i != NONE {
                        self.rhs[r * k + i as usize] += tp;
                        self.row[r * k + i as usize] += tn;
                    }
                }
            }
            if touches {
                for r in 0..2 {
                    for c in 0..2 {
                        row_rhs += a * nrm[r][c] * p[r][c];
                    }
                }
            }
        }
        // The fixed vertices' contributions: TᵀW T restricted, moved to the right.
        for f in 0..self.frames.len() {
            let a = self.frames.area[f];
            let g = self.frames.g[f];
            let face = self.frames.faces[f];
            // The fixed part of this triangle's Jacobian.
            let mut fixed = [[0.0; 2]; 2];
            let mut any = false;
            for (pv, &v) in face.iter().enumerate() {
                if self.index[v as usize] == NONE {
                    any = true;
                    for r in 0..2 {
                        for c in 0..2 {
                            fixed[r][c] += uv[v as usize][r] * g[pv][c];
                        }
                    }
                }
            }
            if !any {
                continue;
            }
            let z = self.frames.gradient(f, uv);
            let p = self.projected[f];
            let nrm = [
                [z[0][0] - p[0][0], z[0][1] - p[0][1]],
                [z[1][0] - p[1][0], z[1][1] - p[1][1]],
            ];
            for (pv, &v) in face.iter().enumerate() {
                let i = self.index[v as usize];
                if i == NONE {
                    continue;
                }
                for r in 0..2 {
                    self.rhs[r * k + i as usize] -=
                        a * (fixed[r][0] * g[pv][0] + fixed[r][1] * g[pv][1]);
                }
            }
            for r in 0..2 {
                for c in 0..2 {
                    row_rhs -= a * nrm[r][c] * fixed[r][c];
                }
            }
        }
        // 2. x₁ = K⁻¹ b. If ⟨η, x₁⟩ ≤ d the half-space is inactive; otherwise project onto
        //    the hyperplane: x = x₁ − μ K⁻¹ η, μ = (⟨η, x₁⟩ − d) / ⟨η, K⁻¹ η⟩.
        let err = |source| ParamError::Solver {
            what: "bounded distortion",
            source,
        };
        self.chol.solve_in_place(&mut self.rhs, 2).map_err(err)?;
        if active {
            let lhs: f64 = self.row.iter().zip(&self.rhs).map(|(a, b)| a * b).sum();
            if lhs > row_rhs {
                self.eta.copy_from_slice(&self.row);
                self.chol.solve_in_place(&mut self.row, 2).map_err(err)?;
                let denom: f64 = self.eta.iter().zip(&self.row).map(|(a, b)| a * b).sum();
                if denom > 0.0 {
                    let mu = (lhs - row_rhs) / denom;
                    for (x, y) in self.rhs.iter_mut().zip(&self.row) {
                        *x -= mu * y;
                    }
                }
            }
        }
        for (v, out) in uv.iter_mut().enumerate() {
            let i = self.index[v];
            if i != NONE {
                *out = [self.rhs[i as usize], self.rhs[k + i as usize]];
            }
        }
        Ok(())
    }
}

/// A lower bound on the distortion bound `K` that any orientation-preserving piecewise-linear
/// map of a mesh into the plane can meet ([`angle_lower_bound`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AngleBound {
    /// No map has every triangle's distortion below this (1 when the argument proves
    /// nothing).
    pub bound: f64,
    /// The interior vertex that gives it (`None` when no interior vertex constrains `K`).
    pub vertex: Option<u32>,
    /// That vertex's angle sum on the mesh, in radians (`2π` for a flat vertex).
    pub angle_sum: f64,
}

/// The per-vertex angle argument: a linear map whose distortion `σ₁/σ₂` is at most `K` maps
/// an angle `θ` to an angle between `2 atan(tan(θ/2) / K)` and `2 atan(K tan(θ/2))` (both
/// reached, with the stretch along the angle's bisector). The corner angles around an
/// interior vertex must add up to `2π` in the plane, so a vertex whose angles on the mesh add
/// up to much less (the tip of a sharp cone) or much more (a saddle) forces a lower bound on
/// `K`: the smallest `K` at which `2π` lies between the two sums, found by bisection. The
/// largest over the interior vertices is returned: any bound below it is infeasible for
/// every start and every constraint. (A necessary condition only: a bound above it may
/// still be infeasible.)
///
/// ```
/// use bdmorph::param::bounded::angle_lower_bound;
/// // A flat disk constrains nothing.
/// let disk = bdmorph::generate::disk(3, 0.0);
/// let mesh = bdmorph::SurfaceMesh {
///     positions: disk.positions.iter().map(|p| [p[0], p[1], 0.0]).collect(),
///     faces: disk.faces.clone(),
///     texcoords: None,
/// };
/// assert!(angle_lower_bound(&mesh).bound < 1.0 + 1e-9);
/// ```
pub fn angle_lower_bound(mesh: &SurfaceMesh) -> AngleBound {
    let n = mesh.positions.len();
    // Boundary vertices (on an edge of one triangle) are free: their angle sum is not fixed.
    let mut edges: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
    for f in &mesh.faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut free = vec![false; n];
    for (&(a, b), &count) in &edges {
        if count == 1 {
            for v in [a, b] {
                if let Some(free) = free.get_mut(v as usize) {
                    *free = true;
                }
            }
        }
    }
    let mut corners: Vec<Vec<f64>> = vec![Vec::new(); n];
    for f in &mesh.faces {
        for k in 0..3 {
            let p = |v: u32| mesh.positions.get(v as usize).copied().unwrap_or([0.0; 3]);
            let (o, a, b) = (p(f[k]), p(f[(k + 1) % 3]), p(f[(k + 2) % 3]));
            let u = [a[0] - o[0], a[1] - o[1], a[2] - o[2]];
            let v = [b[0] - o[0], b[1] - o[1], b[2] - o[2]];
            let cross = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let sin = (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt();
            let cos = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
            if let Some(c) = corners.get_mut(f[k] as usize) {
                c.push(sin.atan2(cos));
            }
        }
    }
    let tau = std::f64::consts::TAU;
    let feasible = |half_tans: &[f64], k: f64| {
        let low: f64 = half_tans.iter().map(|t| 2.0 * (t / k).atan()).sum();
        let high: f64 = half_tans.iter().map(|t| 2.0 * (t * k).atan()).sum();
        low <= tau && tau <= high
    };
    let mut best = AngleBound {
        bound: 1.0,
        vertex: None,
        angle_sum: tau,
    };
    for (v, angles) in corners.iter().enumerate() {
        if free[v] || angles.is_empty() || angles.iter().any(|a| !a.is_finite()) {
            continue;
        }
        let half_tans: Vec<f64> = angles.iter().map(|a| (0.5 * a).tan()).collect();
        if feasible(&half_tans, best.bound) {
            continue;
        }
        // The sums move monotonically with K: bracket, then bisect.
        let (mut lo, mut hi) = (best.bound, 2.0 * best.bound);
        while !feasible(&half_tans, hi) {
            lo = hi;
            hi *= 2.0;
            if hi > 1e12 {
                break;
            }
        }
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if feasible(&half_tans, mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        best = AngleBound {
            bound: lo,
            vertex: Some(v as u32),
            angle_sum: angles.iter().sum(),
        };
    }
    best
}

/// One starting map tried by [`flatten`], and what the iterations made of it.
#[derive(Clone, Debug, PartialEq)]
pub struct Attempt {
    /// The method of the starting map.
    pub start: ParamMethod,
    /// The bounded-distortion iterations from it.
    pub report: BoundedReport,
}

/// What [`flatten`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct Flattening {
    /// The map kept: the first that met the bound, or else the one with the lowest largest
    /// distortion.
    pub uv: Vec<[f64; 2]>,
    /// Every start tried, in order.
    pub attempts: Vec<Attempt>,
    /// The index in `attempts` of the map kept.
    pub kept: usize,
    /// The bound `K` asked for.
    pub bound: f64,
    /// The angle argument's lower bound on any feasible `K` ([`angle_lower_bound`]).
    pub lower_bound: AngleBound,
    /// Wall-clock seconds of the set-up (the checks, the factorisation and the starting maps),
    /// apart from the attempts' own `seconds`.
    pub setup_seconds: f64,
}

impl Flattening {
    /// The report of the map kept.
    pub fn report(&self) -> &BoundedReport {
        &self.attempts[self.kept].report
    }

    /// Whether the bound was met.
    pub fn converged(&self) -> bool {
        self.report().converged
    }

    /// Whether the bound is proved infeasible: below [`Flattening::lower_bound`].
    pub fn infeasible(&self) -> bool {
        self.bound < self.lower_bound.bound
    }
}

/// Flattens a disk-topology mesh under a distortion bound, trying the starting maps `starts`
/// in order ([`Parameterization`] maps, run to their own stop for the iterative methods) until
/// one meets the bound: a start whose iterations stall in a local minimum of the excess
/// distortion does not prove the bound infeasible, and another start often ends elsewhere.
/// No further start is tried once one meets the bound, or when the bound is below
/// [`angle_lower_bound`] (proved infeasible: the first start's closest map is kept). With no
/// start given, Tutte's embedding is used. `progress` sees the attempt's index, the
/// iteration and the largest distortion.
pub fn flatten(
    mesh: &SurfaceMesh,
    pins: &[(u32, [f64; 2])],
    options: BoundedOptions,
    starts: &[ParamMethod],
    mut progress: impl FnMut(usize, u32, f64),
) -> Result<Flattening, ParamError> {
    let started = std::time::Instant::now();
    let max_distortion = options.max_distortion;
    let start_options = ParamOptions::default().with_budget(options.budget.clone());
    let mut solver = BoundedDistortion::new(mesh, pins, options)?;
    let lower_bound = angle_lower_bound(mesh);
    let infeasible = max_distortion < lower_bound.bound;
    let starts = if starts.is_empty() {
        &[ParamMethod::Tutte][..]
    } else {
        starts
    };
    let mut setup_seconds = started.elapsed().as_secs_f64();
    let mut attempts: Vec<Attempt> = Vec::new();
    let mut best: Option<(usize, Vec<[f64; 2]>)> = None;
    for (i, &start) in starts.iter().enumerate() {
        let began = std::time::Instant::now();
        let mut p = Parameterization::new(mesh, start, start_options.clone())?;
        p.solve()?;
        let mut uv = p.uv().to_vec();
        setup_seconds += began.elapsed().as_secs_f64();
        let report = solver.solve_with(&mut uv, |it, worst| progress(i, it, worst))?;
        let better = match &best {
            None => true,
            Some((b, _)) => {
                let old = &attempts[*b].report;
                report.converged && !old.converged || report.max_distortion < old.max_distortion
            }
        };
        let done = report.converged || infeasible;
        attempts.push(Attempt { start, report });
        if better {
            best = Some((i, uv));
        }
        if done {
            break;
        }
    }
    let (kept, uv) = best.ok_or(ParamError::BadBound(max_distortion))?;
    Ok(Flattening {
        uv,
        attempts,
        kept,
        bound: max_distortion,
        lower_bound,
        setup_seconds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random(state: &mut u64) -> f64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        (*state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }

    fn frob(a: [[f64; 2]; 2], b: [[f64; 2]; 2]) -> f64 {
        let mut s = 0.0;
        for i in 0..2 {
            for j in 0..2 {
                s += (a[i][j] - b[i][j]).powi(2);
            }
        }
        s.sqrt()
    }

    /// The projection against a brute-force search: many matrices inside the set near the
    /// input (random similarity plus anti-similarity parts with |anti| <= k' |sim|), none
    /// closer than the analytic projection, and a fine search comes within a small margin.
    #[test]
    fn projection_matches_brute_force() {
        let mut st = 0x5151_7777_1234_abcd;
        for k in [1.0, 1.5, 3.0] {
            for _ in 0..60 {
                let c = [
                    [2.0 * random(&mut st), 2.0 * random(&mut st)],
                    [2.0 * random(&mut st), 2.0 * random(&mut st)],
                ];
                let p = project(c, k);
                assert!(
                    distortion(p) <= k * (1.0 + 1e-9) || frob(p, [[0.0; 2]; 2]) < 1e-12,
                    "{c:?}"
                );
                let best = frob(p, c);
                // Parameterise the set: M = s rot(a) + r refl(b), r <= (k - 1) / (k + 1) s.
                let kk = (k - 1.0) / (k + 1.0);
                let mut found = f64::INFINITY;
                let steps = 48;
                for i in 0..=steps {
                    let s = 3.0 * f64::from(i) / f64::from(steps);
                    for j in 0..steps {
                        let a = std::f64::consts::TAU * f64::from(j) / f64::from(steps);
                        for l in 0..=6 {
                            let r = kk * s * f64::from(l) / 6.0;
                            for m in 0..steps {
                                let b = std::f64::consts::TAU * f64::from(m) / f64::from(steps);
                                let (sa, ca) = a.sin_cos();
                                let (sb, cb) = b.sin_cos();
                                let mm = [
                                    [s * ca + r * cb, -s * sa + r * sb],
                                    [s * sa + r * sb, s * ca - r * cb],
                                ];
                                let d = frob(mm, c);
                                assert!(
                                    d >= best - 1e-9,
                                    "k {k}: {mm:?} is closer to {c:?} than {p:?}"
                                );
                                found = found.min(d);
                            }
                        }
                    }
                }
                // The grid (steps of 1/16 in scale, 7.5 degrees in angle) comes within its
                // resolution of the projection.
                assert!(
                    found <= best + 0.3,
                    "k {k}: the search found {found}, the projection {best}"
                );
            }
        }
    }

    /// One iteration's Schur-complement solve against a dense solve of the full KKT system
    /// (Lagrange multipliers for the pins and for the half-space row), on a small mesh.
    #[test]
    fn schur_step_matches_a_dense_kkt_solve() {
        let d = crate::generate::disk(3, 0.2);
        let mesh = SurfaceMesh {
            positions: d
                .positions
                .iter()
                .map(|p| [p[0], p[1], 0.3 * p[0] * p[1]])
                .collect(),
            faces: d.faces.clone(),
            texcoords: None,
        };
        let n = mesh.positions.len();
        // A map with distortion: stretch x by 3 and shear.
        let uv0: Vec<[f64; 2]> = d
            .positions
            .iter()
            .map(|p| [3.0 * p[0] + 0.5 * p[1], p[1]])
            .collect();
        let pins = vec![(0u32, [0.1, -0.2]), (5u32, uv0[5])];
        let k = 1.5;
        let mut bd = BoundedDistortion::new(&mesh, &pins, BoundedOptions::new(k)).expect("set up");
        let mut uv = uv0.clone();
        for &(v, t) in &pins {
            uv[v as usize] = t;
        }
        let start = uv.clone();
        bd.iterate(&mut uv).expect("iterate");
        // Dense: rows of W^(1/2) T (4 per triangle), the projected targets p and normals n.
        let frames = Frames::new(&mesh).expect("frames");
        let m = frames.len();
        let dim = 2 * n;
        let mut t = vec![vec![0.0; dim]; 4 * m];
        let mut p = vec![0.0; 4 * m];
        let mut nv = vec![0.0; 4 * m];
        for f in 0..m {
            let w = frames.area[f].sqrt();
            let z = frames.gradient(f, &start);
            let pr = project(z, k);
            for r in 0..2 {
                for c in 0..2 {
                    let row = 4 * f + 2 * r + c;
                    for (pv, &v) in frames.faces[f].iter().enumerate() {
                        t[row][2 * v as usize + r] = w * frames.g[f][pv][c];
                    }
                    p[row] = w * pr[r][c];
                    nv[row] = w * (z[r][c] - pr[r][c]);
                }
            }
        }
        // KKT: [TᵀT Cᵀ; C 0] with C the pins (and the half-space row when active).
        let solve_kkt = |with_row: bool| -> Vec<f64> {
            let mut rows_c: Vec<(Vec<f64>, f64)> = Vec::new();
            for &(v, target) in &pins {
                for r in 0..2 {
                    let mut c = vec![0.0; dim];
                    c[2 * v as usize + r] = 1.0;
                    rows_c.push((c, target[r]));
                }
            }
            if with_row {
                let eta: Vec<f64> = (0..dim)
                    .map(|j| (0..4 * m).map(|i| nv[i] * t[i][j]).sum())
                    .collect();
                let d0: f64 = (0..4 * m).map(|i| nv[i] * p[i]).sum();
                rows_c.push((eta, d0));
            }
            let size = dim + rows_c.len();
            let mut a = vec![vec![0.0; size + 1]; size];
            for i in 0..dim {
                for j in 0..dim {
                    a[i][j] = (0..4 * m).map(|r| t[r][i] * t[r][j]).sum();
                }
                a[i][size] = (0..4 * m).map(|r| t[r][i] * p[r]).sum();
            }
            // The translation is fixed by the pins; no regularisation needed.
            for (q, (c, rhs)) in rows_c.iter().enumerate() {
                for j in 0..dim {
                    a[dim + q][j] = c[j];
                    a[j][dim + q] = c[j];
                }
                a[dim + q][size] = *rhs;
            }
            // Gaussian elimination with partial pivoting.
            for col in 0..size {
                let piv = (col..size)
                    .max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))
                    .unwrap();
                a.swap(col, piv);
                for r in 0..size {
                    if r != col {
                        let f = a[r][col] / a[col][col];
                        if f != 0.0 {
                            for j in col..=size {
                                a[r][j] -= f * a[col][j];
                            }
                        }
                    }
                }
            }
            (0..dim).map(|i| a[i][size] / a[i][i]).collect()
        };
        let plain = solve_kkt(false);
        let violated = {
            let tx: Vec<f64> = (0..4 * m)
                .map(|i| (0..dim).map(|j| t[i][j] * plain[j]).sum())
                .collect();
            (0..4 * m).map(|i| nv[i] * (tx[i] - p[i])).sum::<f64>() > 0.0
        };
        let dense = if violated { solve_kkt(true) } else { plain };
        eprintln!("half-space active: {violated}");
        for v in 0..n {
            for r in 0..2 {
                let (a, b) = (uv[v][r], dense[2 * v + r]);
                assert!(
                    (a - b).abs() < 1e-9 * (1.0 + b.abs()),
                    "vertex {v}.{r}: {a} vs {b}"
                );
            }
        }
    }
}
