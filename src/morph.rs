//! The morph object: compile once, then frames for any `t`.

use bdmorph_vm::{NewtonOptions, Program, TriangleReport, Vm, VmError};

use crate::mesh::{MeshError, PlanarMesh};

/// Options of a [`Morph`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct MorphOptions {
    /// Newton's stopping rule (default: `||g|| < 1e-10`, at most 50 iterations).
    pub newton: NewtonOptions,
    /// Start each frame's Newton solve from the previous frame's solution (default true).
    pub warm_start: bool,
    /// With warm starts, extrapolate the start in `t` through the last three solved frames
    /// (quadratically; linearly through two when three would amplify them) when the new `t`
    /// is within twice the last spacing (default true).
    pub extrapolate: bool,
}

impl Default for MorphOptions {
    fn default() -> Self {
        MorphOptions {
            newton: NewtonOptions::default(),
            warm_start: true,
            extrapolate: true,
        }
    }
}

impl MorphOptions {
    /// Sets the gradient-norm tolerance of Newton's method.
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.newton = self.newton.with_tolerance(tolerance);
        self
    }
    /// Sets the iteration limit of Newton's method.
    pub fn with_max_iterations(mut self, max_iterations: u32) -> Self {
        self.newton = self.newton.with_max_iterations(max_iterations);
        self
    }
    /// Turns warm starts on or off.
    pub fn with_warm_start(mut self, warm_start: bool) -> Self {
        self.warm_start = warm_start;
        self
    }
    /// Turns the extrapolation of warm starts on or off.
    pub fn with_extrapolate(mut self, extrapolate: bool) -> Self {
        self.extrapolate = extrapolate;
        self
    }
    /// Allows or forbids reusing an earlier numeric factor in Newton's method (see
    /// [`NewtonOptions::reuse_factor`]).
    pub fn with_reuse_factor(mut self, reuse_factor: bool) -> Self {
        self.newton = self.newton.with_reuse_factor(reuse_factor);
        self
    }
}

/// Statistics of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameStats {
    /// The frame's time.
    pub t: f64,
    /// Newton iterations (linear solves) the frame took.
    pub newton_iterations: u32,
    /// Numeric Cholesky factorisations among them (the others reused an earlier factor).
    pub factorizations: u32,
    /// Conjugate-gradient iterations of the steps that reused a factor.
    pub cg_iterations: u32,
    /// Gradient norm of the flattening energy at the solution.
    pub gradient_norm: f64,
    /// Triangles with non-positive signed area in the result.
    pub flipped_triangles: usize,
    /// Wall-clock time of the frame (metric, Newton, layout, flip count), in seconds.
    pub seconds: f64,
}

impl FrameStats {
    /// The statistics as one line of JSON.
    pub fn to_json(&self) -> String {
        format!(
            "{{\"t\":{},\"newton_iterations\":{},\"factorizations\":{},\"cg_iterations\":{},\"gradient_norm\":{:e},\"flipped_triangles\":{},\"seconds\":{:e}}}",
            self.t,
            self.newton_iterations,
            self.factorizations,
            self.cg_iterations,
            self.gradient_norm,
            self.flipped_triangles,
            self.seconds
        )
    }
}

/// Solved frames kept for extrapolating the next start.
const HISTORY: usize = 3;

/// Weights of the Lagrange polynomial through the nodes' times evaluated at `t`, and their
/// count; `None` when two nodes share a time or the weights would amplify the nodes' values
/// (sum of magnitudes above 8: one step of uniform quadratic extrapolation gives 7).
fn lagrange_weights(t: f64, nodes: &[Solved]) -> Option<([f64; HISTORY], usize)> {
    let mut w = [0.0; HISTORY];
    for (i, a) in nodes.iter().enumerate() {
        let mut wi = 1.0;
        for (j, b) in nodes.iter().enumerate() {
            if i != j {
                let d = a.t - b.t;
                if d == 0.0 {
                    return None;
                }
                wi *= (t - b.t) / d;
            }
        }
        w[i] = wi;
    }
    let size: f64 = w.iter().map(|x| x.abs()).sum();
    (size.is_finite() && size <= 8.0).then_some((w, nodes.len()))
}

/// A solved frame kept for extrapolating the next start.
#[derive(Clone, Debug)]
struct Solved {
    t: f64,
    u: Vec<f64>,
}

/// A computed frame: positions (one per vertex, in the source's order) and statistics.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// Vertex positions.
    pub positions: &'a [[f64; 2]],
    /// Statistics.
    pub stats: FrameStats,
}

/// Why a morph could not be set up or a frame computed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MorphError {
    /// The input meshes are not valid.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// `t` is not a finite number in [0, 1].
    #[error("t = {t} is outside [0, 1]")]
    TimeOutOfRange {
        /// The time asked for.
        t: f64,
    },
    /// Newton's method did not reach the tolerance.
    #[error("frame t = {t}: Newton did not converge (gradient norm {gradient_norm:e} after {iterations} iterations){}", Worst(worst))]
    NotConverged {
        /// The frame.
        t: f64,
        /// Iterations performed.
        iterations: u32,
        /// Gradient norm reached.
        gradient_norm: f64,
        /// The triangles closest to breaking the triangle inequality where Newton gave up,
        /// worst first.
        worst: Vec<TriangleReport>,
    },
    /// The solver failed otherwise (non-finite values, a Hessian that is not positive definite).
    #[error("frame t = {t}: {source}{}", Worst(worst))]
    Solver {
        /// The frame.
        t: f64,
        /// The VM's error.
        source: VmError,
        /// The triangles closest to breaking the triangle inequality where the solver failed.
        worst: Vec<TriangleReport>,
    },
    /// The output buffer has the wrong length.
    #[error("output buffer holds {got} positions, the mesh has {expected} vertices")]
    OutputLength {
        /// Vertices.
        expected: usize,
        /// Buffer length.
        got: usize,
    },
}

/// Formats the worst triangles of a failed frame for an error message.
struct Worst<'a>(&'a [TriangleReport]);

impl std::fmt::Display for Worst<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.0.is_empty() {
            return Ok(());
        }
        write!(f, "; worst triangles:")?;
        for (i, tri) in self.0.iter().take(3).enumerate() {
            let sep = if i == 0 { " " } else { ", " };
            write!(f, "{sep}{tri}")?;
        }
        Ok(())
    }
}

/// A compiled morph between two planar meshes with the same triangles.
///
/// Construction checks both meshes, compiles the connectivity once and factors the Hessian
/// pattern symbolically once; each [`Morph::frame`] then runs Newton (warm-started from the
/// previous frame) and the layout, reusing every buffer.
///
/// ```
/// use bdmorph::{generate, Morph, MorphOptions};
/// let source = generate::disk(8, 0.2);
/// let target = generate::twist(&source, 1.0);
/// let mut morph = Morph::new(&source, &target, MorphOptions::default())?;
/// let frame = morph.frame(0.5)?;
/// assert_eq!(frame.positions.len(), source.positions.len());
/// assert_eq!(frame.stats.flipped_triangles, 0);
/// assert!(frame.stats.gradient_norm < 1e-10);
/// # Ok::<(), bdmorph::MorphError>(())
/// ```
pub struct Morph {
    vm: Vm,
    faces: Vec<[u32; 3]>,
    sq_source: Vec<f64>,
    sq_target: Vec<f64>,
    anchor_source: [f64; 2],
    anchor_target: [f64; 2],
    angle_source: f64,
    angle_turn: f64,
    options: MorphOptions,
    positions: Vec<[f64; 2]>,
    /// The last solved frames, newest last; the last `solved` of them are valid.
    history: [Solved; HISTORY],
    solved: usize,
    /// The start `u` of the frame being solved.
    start: Vec<f64>,
}

impl std::fmt::Debug for Morph {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Morph")
            .field("vertices", &self.positions.len())
            .field("faces", &self.faces.len())
            .field("vm", &self.vm)
            .finish_non_exhaustive()
    }
}

impl Morph {
    /// Checks the pair, compiles it and prepares the solver.
    pub fn new(
        source: &PlanarMesh,
        target: &PlanarMesh,
        options: MorphOptions,
    ) -> Result<Morph, MorphError> {
        source.validate_pair(target)?;
        let program =
            bdmorph_compiler::compile(&source.positions, &source.faces).map_err(MeshError::from)?;
        Morph::with_program(program, source, target, options)
    }

    /// Prepares a morph from an already compiled program (made for `source`'s connectivity).
    pub fn with_program(
        program: Program,
        source: &PlanarMesh,
        target: &PlanarMesh,
        options: MorphOptions,
    ) -> Result<Morph, MorphError> {
        source.validate_pair(target)?;
        let solver = |source| MorphError::Solver {
            t: 0.0,
            source,
            worst: Vec::new(),
        };
        let vm = Vm::new(program).map_err(solver)?;
        let sq_source = vm.squared_lengths(&source.positions).map_err(solver)?;
        let sq_target = vm.squared_lengths(&target.positions).map_err(solver)?;
        let root = vm.program().embed_root();
        let (p0, p1) = (root.p0 as usize, root.p1 as usize);
        let angle = |m: &PlanarMesh| {
            let (a, b) = (m.positions[p0], m.positions[p1]);
            (b[1] - a[1]).atan2(b[0] - a[0])
        };
        let angle_source = angle(source);
        // The shorter turn from the source's direction to the target's, in (-pi, pi].
        let mut angle_turn = angle(target) - angle_source;
        while angle_turn > std::f64::consts::PI {
            angle_turn -= std::f64::consts::TAU;
        }
        while angle_turn <= -std::f64::consts::PI {
            angle_turn += std::f64::consts::TAU;
        }
        // A half turn is ambiguous: round-off in atan2 must not pick the direction, so within
        // 1e-9 of pi the turn is counter-clockwise.
        if (angle_turn.abs() - std::f64::consts::PI).abs() < 1e-9 {
            angle_turn = std::f64::consts::PI;
        }
        Ok(Morph {
            faces: source.faces.clone(),
            sq_source,
            sq_target,
            anchor_source: source.positions[p0],
            anchor_target: target.positions[p0],
            angle_source,
            angle_turn,
            options,
            positions: vec![[0.0; 2]; source.positions.len()],
            history: [(); HISTORY].map(|_| Solved {
                t: 0.0,
                u: vec![0.0; vm.u().len()],
            }),
            solved: 0,
            start: vec![0.0; vm.u().len()],
            vm,
        })
    }

    /// The compiled program.
    pub fn program(&self) -> &Program {
        self.vm.program()
    }

    /// The triangles (the source's).
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// The log scale factors of the last frame, one per interior vertex.
    pub fn scale_factors(&self) -> &[f64] {
        self.vm.u()
    }

    /// Computes the frame at `t` in [0, 1]: `t = 0` gives the source, `t = 1` the target.
    /// The positions borrow an internal buffer reused by the next call.
    pub fn frame(&mut self, t: f64) -> Result<Frame<'_>, MorphError> {
        let mut out = std::mem::take(&mut self.positions);
        let result = self.frame_into(t, &mut out);
        self.positions = out;
        Ok(Frame {
            stats: result?,
            positions: &self.positions,
        })
    }

    /// Computes the frame at `t` into `out` (one position per vertex). Allocates nothing; on
    /// error `out` is left untouched.
    pub fn frame_into(&mut self, t: f64, out: &mut [[f64; 2]]) -> Result<FrameStats, MorphError> {
        let started = std::time::Instant::now();
        if !(0.0..=1.0).contains(&t) {
            return Err(MorphError::TimeOutOfRange { t });
        }
        if out.len() != self.vm.program().n_vertices() {
            return Err(MorphError::OutputLength {
                expected: self.vm.program().n_vertices(),
                got: out.len(),
            });
        }
        let solver = |source| MorphError::Solver {
            t,
            source,
            worst: Vec::new(),
        };
        self.vm
            .set_metric_lerp(&self.sq_source, &self.sq_target, t)
            .map_err(solver)?;
        let extrapolated = self.choose_start(t);
        let mut result = self.vm.newton(&self.options.newton);
        if result.is_err() && extrapolated {
            // An extrapolated start is a guess: fall back to the last solution before failing.
            self.vm
                .set_u(&self.history[HISTORY - 1].u)
                .expect("history has one value per unknown");
            result = self.vm.newton(&self.options.newton);
        }
        let report = result.map_err(|e| {
            let worst = self.vm.failure_triangles().to_vec();
            match e {
                VmError::NotConverged {
                    iterations,
                    gradient_norm,
                } => MorphError::NotConverged {
                    t,
                    iterations,
                    gradient_norm,
                    worst,
                },
                other => MorphError::Solver {
                    t,
                    source: other,
                    worst,
                },
            }
        })?;
        let anchor = [
            (1.0 - t) * self.anchor_source[0] + t * self.anchor_target[0],
            (1.0 - t) * self.anchor_source[1] + t * self.anchor_target[1],
        ];
        let (s, c) = (self.angle_source + t * self.angle_turn).sin_cos();
        self.vm.embed(anchor, [c, s], out).map_err(solver)?;
        self.remember(t);
        Ok(FrameStats {
            t,
            newton_iterations: report.iterations,
            factorizations: report.factorizations,
            cg_iterations: report.cg_iterations,
            gradient_norm: report.gradient_norm,
            flipped_triangles: self.vm.count_flipped(out),
            seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// Sets the VM's start `u` for a frame at `t`; true when it was extrapolated.
    fn choose_start(&mut self, t: f64) -> bool {
        if !self.options.warm_start {
            self.vm.reset_u();
            return false;
        }
        if self.solved == 0 {
            return false;
        }
        let last = &self.history[HISTORY - 1];
        let weights = if self.options.extrapolate && self.solved >= 2 {
            let prev = &self.history[HISTORY - 2];
            let near = (t - last.t).abs() <= 2.0 * (last.t - prev.t).abs();
            let nodes = &self.history[HISTORY - self.solved..];
            let cubic = lagrange_weights(t, nodes);
            let linear = lagrange_weights(t, &nodes[nodes.len() - 2..]);
            match (near, cubic, linear) {
                (false, ..) => None,
                (true, Some(w), _) => Some(w),
                (true, None, Some(w)) => Some(w),
                (true, None, None) => None,
            }
        } else {
            None
        };
        let Some((weights, count)) = weights else {
            self.vm
                .set_u(&last.u)
                .expect("history has one value per unknown");
            return false;
        };
        let nodes = &self.history[HISTORY - count..];
        self.start.fill(0.0);
        for (node, w) in nodes.iter().zip(&weights[..count]) {
            for (s, u) in self.start.iter_mut().zip(&node.u) {
                *s += w * u;
            }
        }
        self.vm
            .set_u(&self.start)
            .expect("start has one value per unknown");
        true
    }

    /// Records the VM's solution for `t` as the newest solved frame. Allocates nothing.
    fn remember(&mut self, t: f64) {
        if self.solved > 0 && self.history[HISTORY - 1].t == t {
            // The same frame again: do not let a repeat collapse the spacing.
            self.history[HISTORY - 1].u.copy_from_slice(self.vm.u());
            return;
        }
        self.history.rotate_left(1);
        self.history[HISTORY - 1].t = t;
        self.history[HISTORY - 1].u.copy_from_slice(self.vm.u());
        self.solved = (self.solved + 1).min(HISTORY);
    }
}
