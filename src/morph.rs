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
}

impl Default for MorphOptions {
    fn default() -> Self {
        MorphOptions {
            newton: NewtonOptions::default(),
            warm_start: true,
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
}

/// Statistics of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameStats {
    /// The frame's time.
    pub t: f64,
    /// Newton iterations (numeric factorisations) the frame took.
    pub newton_iterations: u32,
    /// Gradient norm of the flattening energy at the solution.
    pub gradient_norm: f64,
    /// Triangles with non-positive signed area in the result.
    pub flipped_triangles: usize,
}

impl FrameStats {
    /// The statistics as one line of JSON.
    pub fn to_json(&self) -> String {
        format!(
            "{{\"t\":{},\"newton_iterations\":{},\"gradient_norm\":{:e},\"flipped_triangles\":{}}}",
            self.t, self.newton_iterations, self.gradient_norm, self.flipped_triangles
        )
    }
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
        if !self.options.warm_start {
            self.vm.reset_u();
        }
        let report = self.vm.newton(&self.options.newton).map_err(|e| {
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
        Ok(FrameStats {
            t,
            newton_iterations: report.iterations,
            gradient_norm: report.gradient_norm,
            flipped_triangles: self.vm.count_flipped(out),
        })
    }
}
