//! The BDMORPH virtual machine: executes a compiled [`Program`] with no mesh structure.
//!
//! A [`Vm`] owns the program, the symbolic Cholesky factorisation of its Hessian pattern
//! (computed once, in [`Vm::new`]) and every buffer a frame needs, so that in steady state a
//! Newton iteration and a whole frame allocate nothing:
//!
//! 1. [`Vm::set_metric_lerp`] (or [`Vm::set_metric`]) sets the interpolated metric `l0` of the
//!    frame from squared edge lengths computed once per keyframe by [`Vm::squared_lengths`];
//! 2. [`Vm::newton`] finds the log scale factors `u` that flatten it (CETM), warm-started from
//!    the previous frame's `u`: each iteration runs the iteration stream into the gradient and
//!    straight into the CSC values, factors numerically (the sparse Cholesky engine,
//!    [`bdmorph_cholesky`]: its own supernodal kernels into preallocated `L` values; in
//!    single precision for large factors, see [`FactorPrecision`]) and solves in place, or
//!    reuses an earlier factor as the preconditioner of conjugate gradients;
//! 3. [`Vm::embed`] lays the flat metric out, given the rigid motion (anchor position and
//!    direction of the anchor edge).
//!
//! ```
//! use bdmorph_vm::{NewtonOptions, Vm};
//! // A hexagon fan whose centre is pushed off-centre: the target metric is flat, so Newton
//! // recovers u = 0 at t = 1, and the layout reproduces the target's shape.
//! let mut a = vec![[0.0, 0.0]];
//! let mut b = vec![[0.2, 0.1]];
//! for i in 0..6 {
//!     let t = i as f64 * std::f64::consts::PI / 3.0;
//!     a.push([t.cos(), t.sin()]);
//!     b.push([t.cos(), t.sin()]);
//! }
//! let faces: Vec<[u32; 3]> = (0..6).map(|i| [0, 1 + i, 1 + (i + 1) % 6]).collect();
//! let program = bdmorph_compiler::compile(&a, &faces)?;
//! let mut vm = Vm::new(program)?;
//! let (la, lb) = (vm.squared_lengths(&a)?, vm.squared_lengths(&b)?);
//! vm.set_metric_lerp(&la, &lb, 0.5)?;
//! let report = vm.newton(&NewtonOptions::default())?;
//! assert!(report.gradient_norm < 1e-10);
//! let mut out = vec![[0.0; 2]; a.len()];
//! vm.embed([0.1, 0.05], [1.0, 0.0], &mut out)?;
//! assert_eq!(vm.count_flipped(&out), 0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]

mod cg;
mod embed;
mod error;
mod evaluate;
mod exp;
mod factor;
pub mod kernel;
pub mod lobachevsky;
mod newton;
mod plan;
mod tangent;

pub use bdmorph_cholesky::{FactorPrecision, SINGLE_FROM_VALUES};
pub use bdmorph_isa::Program;
pub use error::VmError;
pub use newton::{NewtonOptions, NewtonReport};
pub use tangent::TangentReport;

/// A triangle of the current metric, as reported when a frame fails.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleReport {
    /// Its vertices, counter-clockwise.
    pub vertices: [u32; 3],
    /// Its edge lengths (opposite each vertex).
    pub lengths: [f64; 3],
    /// `min(a + b - c) / (a + b + c)` over its sides: at most 1/3 (equilateral), 0 when
    /// degenerate, negative when the lengths break the triangle inequality.
    pub margin: f64,
}

impl std::fmt::Display for TriangleReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [a, b, c] = self.vertices;
        write!(f, "({a} {b} {c}) margin {:.2e}", self.margin)?;
        if self.margin < 0.0 {
            write!(f, " (breaks the triangle inequality)")?;
        }
        Ok(())
    }
}

use bdmorph_cholesky::Cholesky;

/// A test asked before every Newton iteration: `true` stops the solve with
/// [`VmError::Interrupted`] (a caller's deadline or cancellation flag).
pub type Interrupt = std::sync::Arc<dyn Fn() -> bool + Send + Sync>;

/// Executes one compiled program; owns every buffer it needs (see the crate documentation).
pub struct Vm {
    program: Program,
    /// The sparse Cholesky engine, analysed once for the Hessian's pattern.
    chol: Cholesky,
    l0: Vec<f64>,
    len: Vec<f64>,
    log_len: Vec<f64>,
    energy: evaluate::Energy,
    scale: Vec<f64>,
    plan: plan::Plan,
    temps: Vec<kernel::Corner>,
    u: Vec<f64>,
    u_saved: Vec<f64>,
    u_base: Vec<f64>,
    grad: Vec<f64>,
    /// Added to the gradient (and `offsets . u` to the energy) after every evaluation: the
    /// targets of vertices whose angle sum is not `2 pi` ([`Vm::set_gradient_offsets`]);
    /// empty when there are none.
    offsets: Vec<f64>,
    hvals: Vec<f64>,
    step: Vec<f64>,
    cg: cg::CgBuffers,
    /// The derivative of the gradient along a line of metrics, and the tangent it gives.
    dgrad: Vec<f64>,
    tangent: Vec<f64>,
    /// Per iteration edge: the rate of change of its log length along the line.
    dlog: Vec<f64>,
    /// Per corner: the rate of change of its angle along the line.
    dtheta: Vec<f64>,
    /// The gradient, Hessian and corners are those of the current `u` and metric.
    evaluated: bool,
    dirs: Vec<[f64; 2]>,
    metric_set: bool,
    factor_ready: bool,
    /// The factor was computed during the current (or last) Newton solve.
    factor_current: bool,
    /// Further conjugate-gradient iterations beyond which refactoring is cheaper.
    refactor_beyond: f64,
    /// Mean contraction per conjugate-gradient iteration the last time a solve started from
    /// a factor of an earlier solve, and that solve's start gradient norm (NaN before that
    /// happened).
    inherited_rate: (f64, f64),
    failure: Vec<TriangleReport>,
    /// Asked before every Newton iteration whether to stop ([`Vm::set_interrupt`]).
    interrupt: Option<Interrupt>,
}

impl std::fmt::Debug for Vm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Vm")
            .field("unknowns", &self.u.len())
            .field("edges", &self.l0.len())
            .field("factor_nnz", &self.chol.factor_nnz())
            .field("factor_precision", &self.factor_precision())
            .field("plan_bytes", &self.plan.bytes())
            .field("factorization_plan_bytes", &self.chol.plan_bytes())
            .finish_non_exhaustive()
    }
}

impl Vm {
    /// Prepares a VM for `program`: allocates every buffer and computes the symbolic Cholesky
    /// factorisation of the Hessian pattern once, with the program's fill-reducing ordering
    /// ([`Program::ordering`]) or, when it has none, AMD.
    pub fn new(program: Program) -> Result<Vm, VmError> {
        let n = program.n_unknowns();
        let h = program.hessian();
        let chol = newton::analyse(n, h, program.ordering())?;
        let refactor_beyond = newton::refactor_beyond(&chol.cost());
        Ok(Vm {
            chol,
            l0: vec![0.0; program.n_edges()],
            len: vec![0.0; program.n_edges()],
            log_len: vec![0.0; program.n_edges()],
            energy: evaluate::Energy::default(),
            scale: vec![1.0; n + 1],
            plan: plan::Plan::new(&program),
            temps: vec![[0.0; 3]; program.n_temps()],
            u: vec![0.0; n],
            u_saved: vec![0.0; n],
            u_base: vec![0.0; n],
            grad: vec![0.0; n],
            offsets: Vec::new(),
            hvals: vec![0.0; h.nnz()],
            step: vec![0.0; n],
            cg: cg::CgBuffers::new(n),
            dgrad: vec![0.0; n],
            tangent: vec![0.0; n],
            dlog: vec![0.0; program.n_iter_edges()],
            dtheta: vec![0.0; program.n_temps()],
            evaluated: false,
            dirs: vec![[0.0; 2]; program.n_edges()],
            metric_set: false,
            factor_ready: false,
            factor_current: false,
            refactor_beyond,
            inherited_rate: (f64::NAN, f64::NAN),
            failure: Vec::new(),
            interrupt: None,
            program,
        })
    }

    /// The program this VM runs.
    pub fn program(&self) -> &Program {
        &self.program
    }

    /// Squared length of every edge slot in a keyframe (one position per vertex), from the
    /// init stream. Computed once per keyframe; allocates its result.
    pub fn squared_lengths(&self, positions: &[[f64; 2]]) -> Result<Vec<f64>, VmError> {
        self.check_len("positions", self.program.n_vertices(), positions.len())?;
        Ok(self
            .program
            .edges()
            .iter()
            .map(|&[a, b]| {
                let (p, q) = (positions[a as usize], positions[b as usize]);
                (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)
            })
            .collect())
    }

    /// Sets the frame's metric from squared edge lengths (one per edge slot).
    pub fn set_metric(&mut self, squared: &[f64]) -> Result<(), VmError> {
        self.check_len("squared lengths", self.l0.len(), squared.len())?;
        self.fill_metric(|slot| squared[slot])
    }

    /// Sets the frame's metric to `l0^2 = (1 - t) a + t b`, from the squared lengths of two
    /// keyframes. Allocates nothing.
    pub fn set_metric_lerp(&mut self, a: &[f64], b: &[f64], t: f64) -> Result<(), VmError> {
        self.check_len("squared lengths", self.l0.len(), a.len())?;
        self.check_len("squared lengths", self.l0.len(), b.len())?;
        self.fill_metric(|slot| (1.0 - t) * a[slot] + t * b[slot])
    }

    fn fill_metric(&mut self, sq: impl Fn(usize) -> f64) -> Result<(), VmError> {
        self.evaluated = false;
        for slot in 0..self.l0.len() {
            let v = sq(slot);
            if !(v > 0.0 && v.is_finite()) {
                self.metric_set = false;
                let [a, b] = self.program.edges()[slot];
                return Err(VmError::BadMetric {
                    slot,
                    a,
                    b,
                    value: v,
                });
            }
            self.l0[slot] = v.sqrt();
        }
        // Slots outside the iteration stream join boundary vertices: their length is l0.
        let n_it = self.program.n_iter_edges();
        self.len[n_it..].copy_from_slice(&self.l0[n_it..]);
        self.metric_set = true;
        Ok(())
    }

    /// Runs the iteration stream once at the current `u`: fills the edge lengths, the gradient,
    /// the Hessian values and the energy. Allocates nothing.
    pub fn evaluate(&mut self) {
        self.evaluate_with::<true>();
    }

    /// As [`Vm::evaluate`] without the energy (left NaN): the cheaper pass Newton iterations
    /// run, from the stream decoded once into flat arrays at [`Vm::new`] (same results, bit for
    /// bit). Allocates nothing.
    pub fn evaluate_gradient(&mut self) {
        self.update_scale();
        let n_it = self.program.n_iter_edges();
        self.plan.run(
            &self.program.hessian().col_ptr,
            &self.l0[..n_it],
            &self.scale,
            &mut self.len[..n_it],
            &mut self.temps,
            &mut self.grad,
            &mut self.hvals,
        );
        self.energy = evaluate::Energy {
            value: f64::NAN,
            magnitude: f64::NAN,
        };
        for (g, o) in self.grad.iter_mut().zip(&self.offsets) {
            *g += o;
        }
        self.evaluated = true;
    }

    /// Sets a constant added to each unknown's gradient entry (one per unknown; an empty slice
    /// removes them), with `offsets . u` added to the energy, so that the energy stays the
    /// convex function whose gradient that is. An unknown's entry is `pi - (1/2) sum of its
    /// corner angles`, which vanishes where the angles sum to `2 pi`; with an offset `o` it
    /// vanishes where they sum to `2 pi + 2 o`: the target angle sum of a vertex on a free
    /// boundary (a hole filled with inert triangles, whose own angles add nothing; see
    /// `bdmorph_compiler::compile_with_inert`). The next solve starts from the current `u`.
    pub fn set_gradient_offsets(&mut self, offsets: &[f64]) -> Result<(), VmError> {
        if !offsets.is_empty() {
            self.check_len("gradient offsets", self.u.len(), offsets.len())?;
        }
        if let Some(unknown) = offsets.iter().position(|o| !o.is_finite()) {
            return Err(VmError::OffsetNotFinite { unknown });
        }
        self.evaluated = false;
        self.offsets.clear();
        self.offsets.extend_from_slice(offsets);
        Ok(())
    }

    /// The gradient offsets set by [`Vm::set_gradient_offsets`] (empty when none).
    pub fn gradient_offsets(&self) -> &[f64] {
        &self.offsets
    }

    /// `scale = exp(u / 2)` per unknown (its last entry, for boundary vertices, stays 1).
    fn update_scale(&mut self) {
        if self.splits_pass() {
            use rayon::prelude::*;
            let n = self.u.len();
            self.scale[..n]
                .par_chunks_mut(plan::CHUNK)
                .zip(self.u.par_chunks(plan::CHUNK))
                .for_each(|(scale, u)| exp::exp_half_into(u, scale));
        } else {
            exp::exp_half_into(&self.u, &mut self.scale);
        }
    }

    /// Whether the per-triangle and per-vertex passes are split over rayon's threads (see
    /// [`plan::PARALLEL_TRIANGLES`]).
    fn splits_pass(&self) -> bool {
        self.program.n_faces() >= plan::PARALLEL_TRIANGLES && rayon::current_num_threads() > 1
    }

    fn evaluate_with<const ENERGY: bool>(&mut self) {
        self.update_scale();
        self.energy = evaluate::run::<ENERGY>(
            &self.program,
            evaluate::Registers {
                l0: &self.l0,
                u: &self.u,
                scale: &self.scale,
                len: &mut self.len,
                log_len: &mut self.log_len,
                temps: &mut self.temps,
                grad: &mut self.grad,
                hvals: &mut self.hvals,
            },
        );
        for ((g, o), u) in self.grad.iter_mut().zip(&self.offsets).zip(&self.u) {
            *g += o;
            self.energy.value += o * u;
            self.energy.magnitude += (o * u).abs();
        }
        self.evaluated = true;
    }

    /// Log scale factors, one per unknown (interior vertex, see [`Program::unknown_vertex`]).
    pub fn u(&self) -> &[f64] {
        &self.u
    }

    /// Sets every log scale factor to 0 (a cold start for the next Newton solve).
    pub fn reset_u(&mut self) {
        self.evaluated = false;
        self.u.fill(0.0);
    }

    /// Sets the log scale factors (the next Newton solve starts from them).
    pub fn set_u(&mut self, u: &[f64]) -> Result<(), VmError> {
        self.check_len("u", self.u.len(), u.len())?;
        self.evaluated = false;
        self.u.copy_from_slice(u);
        Ok(())
    }

    /// The CETM energy at the last evaluation, up to a constant that depends only on the
    /// metric (triangles whose vertices are all on the boundary are left out). Convex in `u`;
    /// its gradient is [`Vm::gradient`]. NaN when the last pass did not compute it
    /// ([`Vm::evaluate_gradient`], or the last pass of a successful [`Vm::newton`]): call
    /// [`Vm::evaluate`] first.
    pub fn energy(&self) -> f64 {
        self.energy.value
    }

    /// The gradient from the last [`Vm::evaluate`] (or Newton iteration).
    pub fn gradient(&self) -> &[f64] {
        &self.grad
    }

    /// The Hessian's CSC values (lower triangle, in [`Program::hessian`]'s pattern) from the
    /// last evaluation.
    pub fn hessian_values(&self) -> &[f64] {
        &self.hvals
    }

    /// Edge lengths per slot from the last evaluation (`l0 * exp((u_i + u_j) / 2)`).
    pub fn lengths(&self) -> &[f64] {
        &self.len
    }

    /// Number of stored values of the Cholesky factor.
    pub fn factor_nnz(&self) -> usize {
        self.chol.factor_nnz()
    }

    /// Whether the Hessian's Cholesky factor is supernodal (blocked, the engine's own
    /// kernels), rather than simplicial (column by column, faer's).
    pub fn factor_is_supernodal(&self) -> bool {
        self.chol.is_supernodal()
    }

    /// Lays the current metric out in the plane: the anchor vertex at `anchor`, the anchor
    /// edge along `direction` (normalised here), every other vertex from the propagated edge
    /// directions. `out` receives one position per vertex. Call after [`Vm::newton`].
    /// Fails without writing when the positions could overflow ([`VmError::LayoutOverflow`]).
    pub fn embed(
        &mut self,
        anchor: [f64; 2],
        direction: [f64; 2],
        out: &mut [[f64; 2]],
    ) -> Result<(), VmError> {
        self.check_len("output positions", self.program.n_vertices(), out.len())?;
        let norm = direction[0].hypot(direction[1]);
        let dir = if norm > 0.0 && norm.is_finite() {
            [direction[0] / norm, direction[1] / norm]
        } else {
            [1.0, 0.0]
        };
        // Every position lies within the anchor's distance plus the sum of all edge lengths;
        // refuse before writing anything if that could overflow.
        let reach = anchor[0].hypot(anchor[1]) + self.len.iter().sum::<f64>();
        if reach.is_nan() || reach >= 1e300 {
            return Err(VmError::LayoutOverflow { reach });
        }
        embed::run(&self.program, &self.len, &mut self.dirs, anchor, dir, out);
        Ok(())
    }

    /// The `count` triangles closest to breaking the triangle inequality under the current
    /// lengths, worst first. Allocates; meant for error reports.
    pub fn worst_triangles(&self, count: usize) -> Vec<TriangleReport> {
        let mut all: Vec<TriangleReport> = self
            .program
            .embed()
            .iter()
            .map(|s| {
                let (ab, bc, ca) = (
                    self.len[s.e_ab as usize],
                    self.len[s.e_bc as usize],
                    self.len[s.e_ca as usize],
                );
                let sum = ab + bc + ca;
                let margin = (ab + bc - ca).min(bc + ca - ab).min(ca + ab - bc) / sum;
                TriangleReport {
                    vertices: [s.a, s.b, s.c],
                    lengths: [bc, ca, ab],
                    margin: if margin.is_finite() {
                        margin
                    } else {
                        f64::NEG_INFINITY
                    },
                }
            })
            .collect();
        all.sort_by(|x, y| x.margin.total_cmp(&y.margin));
        all.truncate(count);
        all
    }

    /// The worst triangles at the iterate where the last failed [`Vm::newton`] gave up (empty
    /// after a success).
    pub fn failure_triangles(&self) -> &[TriangleReport] {
        &self.failure
    }

    /// Threads a Newton solve splits its work over, chosen for rayon's pool when this VM was
    /// built: the most of the gradient pass's (the current pool's threads, from 12,000
    /// triangles on),
    /// the factorisation's and the solves' (see
    /// [`bdmorph_cholesky::Cholesky::factor_threads`]); 1 when nothing is split. Called from
    /// outside the pool, each split piece of work waits for the pool's threads to wake:
    /// run a whole solve on the pool instead (`rayon::scope`, as `bdmorph`'s frames do).
    pub fn threads(&self) -> usize {
        let pass = if self.program.n_faces() >= plan::PARALLEL_TRIANGLES {
            rayon::current_num_threads()
        } else {
            1
        };
        pass.max(self.chol.factor_threads())
            .max(self.chol.solve_threads())
    }

    /// Number of triangles with non-positive signed area in `positions`.
    pub fn count_flipped(&self, positions: &[[f64; 2]]) -> usize {
        if positions.len() != self.program.n_vertices() {
            return self.program.n_faces();
        }
        embed::count_flipped(&self.program, positions, self.splits_pass())
    }

    fn check_len(&self, what: &'static str, expected: usize, got: usize) -> Result<(), VmError> {
        if expected == got {
            Ok(())
        } else {
            Err(VmError::Length {
                what,
                expected,
                got,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fan() -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let mut pos = vec![[0.1, 0.05]];
        for i in 0..7 {
            let a = f64::from(i) * std::f64::consts::TAU / 7.0;
            pos.push([a.cos(), a.sin()]);
        }
        (pos, (0..7).map(|i| [0, 1 + i, 1 + (i + 1) % 7]).collect())
    }

    #[test]
    fn newton_needs_a_metric_and_checks_lengths() {
        let (pos, faces) = fan();
        let mut vm = Vm::new(bdmorph_compiler::compile(&pos, &faces).expect("ok")).expect("vm");
        assert_eq!(
            vm.newton(&NewtonOptions::default()),
            Err(VmError::MetricNotSet)
        );
        assert!(matches!(vm.solve(), Err(VmError::NoFactor)));
        vm.evaluate_gradient();
        assert!(vm.energy().is_nan(), "the cheap pass leaves no energy");
        assert!(matches!(
            vm.squared_lengths(&pos[..3]),
            Err(VmError::Length {
                expected: 8,
                got: 3,
                ..
            })
        ));
        let mut bad = vm.squared_lengths(&pos).expect("ok");
        bad[2] = -1.0;
        assert!(matches!(
            vm.set_metric(&bad),
            Err(VmError::BadMetric { slot: 2, .. })
        ));
        assert_eq!(
            vm.newton(&NewtonOptions::default()),
            Err(VmError::MetricNotSet)
        );
    }

    #[test]
    fn the_decoded_plan_computes_exactly_what_the_interpreter_computes() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("pool");
        pool.install(|| plan_matches_interpreter(9, 1));
    }

    #[test]
    fn the_plan_split_over_threads_computes_the_same_bits() {
        // 2 x 79^2 = 12,482 triangles: above the size from which the sweeps are split.
        let side = 80;
        assert!(2 * (side as usize - 1).pow(2) >= plan::PARALLEL_TRIANGLES);
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            pool.install(|| plan_matches_interpreter(side, threads));
        }
    }

    #[test]
    fn inert_triangles_compute_the_same_bits_in_the_plan_and_add_nothing() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("pool");
        pool.install(|| plan_matches_interpreter_with(9, 1, true));
    }

    type Faces = Vec<[u32; 3]>;

    /// A 9 x 9 jittered grid with the two triangles of one middle cell inert (a hole filled for
    /// the topology): a VM with those triangles inert, and one of the grid with the cell cut
    /// out (for comparison), the grid's positions, and the cell's vertices.
    fn grid_with_an_inert_cell() -> (Vm, Vec<[f64; 2]>, Faces, Vec<bool>) {
        let side = 9u32;
        let (a, faces) = jittered_grid(side);
        // The cell at (4, 4): its two triangles are the last ones of that cell's pair.
        let cell = (4 * (side - 1) + 4) as usize;
        let mut inert = vec![false; faces.len()];
        inert[2 * cell] = true;
        inert[2 * cell + 1] = true;
        let vm = Vm::new(bdmorph_compiler::compile_with_inert(&a, &faces, &inert).expect("ok"))
            .expect("vm");
        (vm, a, faces, inert)
    }

    #[test]
    fn a_hole_filled_with_inert_triangles_is_a_free_boundary() {
        let (mut vm, a, faces, inert) = grid_with_an_inert_cell();
        assert_eq!(vm.program().embed().len(), faces.len() - 2);
        // The ring alone (the cell cut out) has the same gradient at the hole's vertices as
        // a free boundary's: pi minus half the angles of its own triangles.
        let sq = vm.squared_lengths(&a).expect("a");
        vm.set_metric(&sq).expect("metric");
        vm.evaluate();
        let cut: Vec<usize> = (0..faces.len()).filter(|&f| inert[f]).collect();
        let hole: Vec<u32> = cut.iter().flat_map(|&f| faces[f]).collect();
        for (k, &v) in vm.program().unknown_vertex().iter().enumerate() {
            let angles: f64 = faces
                .iter()
                .zip(&inert)
                .filter(|(f, &i)| !i && f.contains(&v))
                .map(|(f, _)| {
                    let at = f.iter().position(|&x| x == v).expect("corner");
                    let [p, q, r] =
                        [f[at], f[(at + 1) % 3], f[(at + 2) % 3]].map(|x| a[x as usize]);
                    let (u, w) = ([q[0] - p[0], q[1] - p[1]], [r[0] - p[0], r[1] - p[1]]);
                    (u[0] * w[1] - u[1] * w[0]).atan2(u[0] * w[0] + u[1] * w[1])
                })
                .sum();
            let expected = std::f64::consts::PI - 0.5 * angles;
            let g = vm.gradient()[k];
            assert!(
                (g - expected).abs() < 1e-12,
                "vertex {v}: {g} vs {expected}"
            );
            // Flat inside, a target to meet on the hole.
            if hole.contains(&v) {
                assert!(g.abs() > 0.1, "vertex {v} is on the hole: {g}");
            } else {
                assert!(g.abs() < 1e-12, "vertex {v}: {g}");
            }
        }
        // With the offsets that make this metric a solution, Newton takes no step, and the
        // layout reproduces the grid without ever walking through the cell.
        let offsets: Vec<f64> = vm.gradient().iter().map(|g| -g).collect();
        vm.set_gradient_offsets(&offsets).expect("finite");
        let report = vm.newton(&NewtonOptions::default()).expect("solved");
        assert_eq!(report.iterations, 0);
        let root = vm.program().embed_root();
        let (p0, p1) = (a[root.p0 as usize], a[root.p1 as usize]);
        let mut out = vec![[0.0; 2]; a.len()];
        vm.embed(p0, [p1[0] - p0[0], p1[1] - p0[1]], &mut out)
            .expect("embeds");
        for (p, q) in out.iter().zip(&a) {
            assert!((p[0] - q[0]).hypot(p[1] - q[1]) < 1e-12, "{p:?} vs {q:?}");
        }
        assert_eq!(vm.count_flipped(&out), 0);
    }

    #[test]
    fn gradient_offsets_are_the_gradient_of_the_energy_and_the_hessian_solves() {
        let (mut vm, a, _, _) = grid_with_an_inert_cell();
        let b: Vec<[f64; 2]> = a
            .iter()
            .map(|p| [p[0] * (1.0 + 0.05 * p[1]), p[1] + 0.03 * p[0] * p[0]])
            .collect();
        let (sa, sb) = (
            vm.squared_lengths(&a).unwrap(),
            vm.squared_lengths(&b).unwrap(),
        );
        vm.set_metric_lerp(&sa, &sb, 0.5).unwrap();
        let n = vm.u().len();
        let offsets: Vec<f64> = (0..n).map(|k| 0.01 * (k as f64).cos()).collect();
        vm.set_gradient_offsets(&offsets).unwrap();
        assert!(matches!(
            vm.set_gradient_offsets(&[1.0]),
            Err(VmError::Length { .. })
        ));
        let mut bad = offsets.clone();
        bad[3] = f64::NAN;
        assert_eq!(
            vm.set_gradient_offsets(&bad),
            Err(VmError::OffsetNotFinite { unknown: 3 })
        );
        assert_eq!(
            vm.gradient_offsets(),
            &offsets[..],
            "a refused set changes nothing"
        );
        let u: Vec<f64> = (0..n).map(|k| 0.05 * (k as f64 * 0.3).sin()).collect();
        let energy = |vm: &mut Vm, u: &[f64]| {
            vm.set_u(u).unwrap();
            vm.evaluate();
            vm.energy()
        };
        energy(&mut vm, &u);
        let g = vm.gradient().to_vec();
        let h = 1e-6;
        for k in [0, n / 2, n - 1] {
            let (mut up, mut down) = (u.clone(), u.clone());
            up[k] += h;
            down[k] -= h;
            let central = (energy(&mut vm, &up) - energy(&mut vm, &down)) / (2.0 * h);
            assert!(
                (central - g[k]).abs() < 1e-6,
                "unknown {k}: {central} vs {}",
                g[k]
            );
        }
        // The solution has the offsets' targets; a solve with its Hessian is exact.
        vm.set_u(&u).unwrap();
        vm.newton(&NewtonOptions::default()).expect("converges");
        let rhs: Vec<f64> = (0..n).map(|k| (k as f64 * 0.9).sin()).collect();
        let x = vm.solve_hessian(&rhs, 1e-13).expect("solves").to_vec();
        let mut hx = vec![0.0; n];
        vm.chol
            .pattern()
            .symmetric_product(vm.hessian_values(), &x, &mut hx);
        let worst = hx
            .iter()
            .zip(&rhs)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-11, "{worst:e}");
        vm.set_u(&u).unwrap();
        assert_eq!(
            vm.solve_hessian(&rhs, 1e-13).err(),
            Some(VmError::NotEvaluated)
        );
    }

    /// A jittered grid of `side` x `side` vertices, alternating diagonals.
    fn jittered_grid(side: u32) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let mut a = Vec::new();
        for j in 0..side {
            for i in 0..side {
                let w = 0.2 * f64::from(i * 5 + j * 3).sin();
                a.push([f64::from(i) + w, f64::from(j) - 0.5 * w]);
            }
        }
        let mut faces = Vec::new();
        for j in 0..side - 1 {
            for i in 0..side - 1 {
                let v = j * side + i;
                if (i + j) % 2 == 0 {
                    faces.push([v, v + 1, v + side + 1]);
                    faces.push([v, v + side + 1, v + side]);
                } else {
                    faces.push([v, v + 1, v + side]);
                    faces.push([v + 1, v + side + 1, v + side]);
                }
            }
        }
        (a, faces)
    }

    fn plan_matches_interpreter(side: u32, threads: usize) {
        plan_matches_interpreter_with(side, threads, false);
    }

    /// A jittered grid of `side` x `side` vertices (interior, boundary and mixed edges, every
    /// valence), a metric that is not flat and a u that is not zero: the same bits from the
    /// plan (in the current pool, of `threads` threads) and the interpreter. With `inert`,
    /// the two triangles of a middle cell are inert.
    fn plan_matches_interpreter_with(side: u32, threads: usize, inert: bool) {
        assert_eq!(rayon::current_num_threads(), threads);
        let (a, faces) = jittered_grid(side);
        let b: Vec<[f64; 2]> = a
            .iter()
            .map(|p| [p[0] * (1.0 + 0.05 * p[1]), p[1] + 0.03 * p[0] * p[0]])
            .collect();
        let mut flags = vec![false; faces.len()];
        if inert {
            let cell = (side / 2 * (side - 1) + side / 2) as usize;
            flags[2 * cell] = true;
            flags[2 * cell + 1] = true;
        }
        let program = bdmorph_compiler::compile_with_inert(&a, &faces, &flags).expect("ok");
        let mut vm = Vm::new(program).expect("vm");
        let (sa, sb) = (
            vm.squared_lengths(&a).expect("a"),
            vm.squared_lengths(&b).expect("b"),
        );
        vm.set_metric_lerp(&sa, &sb, 0.6).expect("metric");
        let n = vm.program().n_unknowns();
        let u: Vec<f64> = (0..n).map(|k| 0.3 * (k as f64 * 0.7).sin()).collect();
        vm.set_u(&u).expect("u");
        vm.evaluate_gradient();
        let planned = (
            vm.len.clone(),
            vm.temps.clone(),
            vm.grad.clone(),
            vm.hvals.clone(),
        );
        // Slots past the iteration stream's hold l0, which neither pass writes.
        let n_it = vm.program().n_iter_edges();
        vm.len[..n_it].fill(0.0);
        vm.temps.fill([0.0; 3]);
        vm.grad.fill(0.0);
        vm.hvals.fill(0.0);
        vm.evaluate_with::<false>();
        if inert {
            assert!(vm.temps.contains(&kernel::INERT_CORNER));
        }
        assert_eq!(planned.0, vm.len);
        assert_eq!(planned.1, vm.temps);
        assert_eq!(planned.2, vm.grad);
        assert_eq!(planned.3, vm.hvals);
        assert!(
            planned.2.iter().any(|g| g.abs() > 1e-3),
            "a non-trivial gradient"
        );
    }

    #[test]
    fn flat_metric_needs_no_iteration_and_embeds_exactly() {
        let (pos, faces) = fan();
        let mut vm = Vm::new(bdmorph_compiler::compile(&pos, &faces).expect("ok")).expect("vm");
        let sq = vm.squared_lengths(&pos).expect("ok");
        vm.set_metric(&sq).expect("ok");
        let report = vm.newton(&NewtonOptions::default()).expect("flat");
        assert_eq!(report.iterations, 0);
        let root = vm.program().embed_root();
        let (p0, p1) = (pos[root.p0 as usize], pos[root.p1 as usize]);
        let mut out = vec![[0.0; 2]; pos.len()];
        vm.embed(p0, [p1[0] - p0[0], p1[1] - p0[1]], &mut out)
            .expect("ok");
        for (p, q) in out.iter().zip(&pos) {
            assert!((p[0] - q[0]).abs() < 1e-14 && (p[1] - q[1]).abs() < 1e-14);
        }
        assert_eq!(vm.count_flipped(&out), 0);
    }
}
