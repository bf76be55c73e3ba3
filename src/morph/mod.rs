//! The morph object: compile once, then frames for any `t`.

use bdmorph_vm::{FactorPrecision, NewtonOptions, Program, TriangleReport, VmError};

pub mod blend;
mod closure;
pub(crate) mod engine;
mod holes;
pub mod path;
mod placement;
mod predictor;
mod solver;

pub use placement::Placement;
pub use solver::{PieceInfo, Structure};

use crate::morph::engine::{Line, Unwrap};
use crate::morph::solver::Solver;

use crate::mesh::{MeshError, PlanarMesh};

/// Options of a [`Morph`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct MorphOptions {
    /// Newton's stopping rule (default: `||g|| < 1e-10`, at most 50 iterations).
    pub newton: NewtonOptions,
    /// Start each frame's Newton solve from the previous frame's solution (default true).
    pub warm_start: bool,
    /// With warm starts, predict the start from the nearest of the (up to six) solved frames
    /// kept on the same line of metrics (a morph's `t`, a path segment's weight) when the new
    /// place is within twice their spacing (default true): by the polynomial through as many
    /// of their solutions as keep its terms shrinking, or through the three nearest and their
    /// tangents when [`Self::tangents`] is on. A place solved before starts from its solution,
    /// with or without tangents.
    pub extrapolate: bool,
    /// With predicted starts, take each solved frame's tangent `du/dt` (a closed-form pass
    /// over the triangles and a solve with the current factor, done when the next frame on
    /// the same line is asked for) so that the prediction is a Hermite polynomial: quintic
    /// through three solutions and their tangents. Its work is counted in the next frame's
    /// statistics. Default false: on the benchmark disks it cuts Newton steps per frame by a
    /// fifth to a quarter but its own solve costs about as much (BENCHMARKS.md).
    pub tangents: bool,
    /// How the Hessian's numeric Cholesky factor is stored (default
    /// [`FactorPrecision::Auto`]: single precision from a million stored values of the
    /// factor, about 20K vertices on a disk, where halving its memory traffic makes
    /// factorisations and solves a fifth to a third faster; conjugate gradients refine its
    /// steps and the tolerance is unchanged). See [`bdmorph_vm::Vm::set_factor_precision`].
    pub factor_precision: FactorPrecision,
    /// Accept keyframes with a few inverted (clockwise) triangles (default false: they are
    /// refused, listing them, [`MeshError::Inverted`]). Their side lengths enter the metric
    /// as they are; at such a keyframe the frame is the flat shape nearest those lengths and
    /// differs from the given pose around them (it reproduces the pose only where no
    /// triangle is inverted). A mesh mostly clockwise is still refused as mirrored.
    pub allow_inverted: bool,
    /// Threads for this object's work: `None` (default) for rayon's global pool, one thread
    /// per core; `Some(n)` for a pool of its own of `n` threads (1 to
    /// [`crate::threads::MAX_THREADS`]), in which it is built and its frames are solved.
    pub threads: Option<usize>,
    /// With [`MorphOptions::allow_inverted`], reach keyframes with inverted triangles exactly
    /// too (default false: at such a keyframe the frame is the flat shape nearest its side
    /// lengths). The difference between each such keyframe and the frame solved at it is
    /// added to every frame, weighted by that keyframe's weight: frames stay continuous, every
    /// keyframe is met to round-off, and frames near a folded keyframe fold as it does (their
    /// statistics count the user's flipped triangles in the positions returned). The studio
    /// plays its projects so: what the animator posed is what every export shows.
    pub reach_inverted: bool,
    /// How each piece of a frame is placed (default [`Placement::Anchor`], the original
    /// program's: by an anchor vertex and edge). [`Placement::Fit`] places it by the
    /// similarity that best fits the keyframes, so that parts that hold still between
    /// keyframes hold still in between and the frame does not swell; keyframes are reached
    /// exactly either way.
    pub placement: Placement,
    /// Bounds each frame in time or by a cancellation flag, checked when a frame starts and
    /// before every Newton iteration (default unlimited): once spent, the frame fails with
    /// [`MorphError::Stopped`] and the next warm start is the last frame solved. Shared by
    /// the object for its whole life: a timeout counts from when it was set.
    pub budget: crate::Budget,
}

impl Default for MorphOptions {
    fn default() -> Self {
        MorphOptions {
            newton: NewtonOptions::default(),
            warm_start: true,
            extrapolate: true,
            tangents: false,
            factor_precision: FactorPrecision::Auto,
            allow_inverted: false,
            threads: None,
            reach_inverted: false,
            placement: Placement::Anchor,
            budget: crate::Budget::unlimited(),
        }
    }
}

impl MorphOptions {
    /// Sets the gradient-norm tolerance of Newton's method.
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.newton = self.newton.with_tolerance(tolerance);
        self
    }
    /// Runs on a pool of its own of `threads` threads ([`MorphOptions::threads`]).
    ///
    /// ```
    /// use bdmorph::{generate, Morph, MorphOptions};
    /// let a = generate::disk(6, 0.2);
    /// let b = generate::bend(&a, 0.5);
    /// let mut one = Morph::new(&a, &b, MorphOptions::default().with_threads(1))?;
    /// let mut every = Morph::new(&a, &b, MorphOptions::default())?;
    /// assert_eq!(one.frame(0.5)?.positions, every.frame(0.5)?.positions);
    /// # Ok::<(), bdmorph::MorphError>(())
    /// ```
    pub fn with_threads(mut self, threads: usize) -> Self {
        self.threads = Some(threads);
        self
    }
    /// Accepts keyframes with a few inverted triangles ([`MorphOptions::allow_inverted`]).
    pub fn with_allow_inverted(mut self, allow_inverted: bool) -> Self {
        self.allow_inverted = allow_inverted;
        self
    }
    /// Reaches keyframes with inverted triangles exactly ([`MorphOptions::reach_inverted`]).
    pub fn with_reach_inverted(mut self, reach_inverted: bool) -> Self {
        self.reach_inverted = reach_inverted;
        self
    }
    /// Sets how frames are placed ([`MorphOptions::placement`]).
    ///
    /// ```
    /// use bdmorph::{generate, Morph, MorphOptions, Placement};
    /// let rest = generate::figure(0.01);
    /// let wave = generate::wave(&rest, 1.0);
    /// let options = MorphOptions::default().with_placement(Placement::Fit);
    /// let mut morph = Morph::new(&rest, &wave, options)?;
    /// let end = morph.frame(1.0)?;
    /// let miss = end.positions.iter().zip(&wave.positions)
    ///     .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1])).fold(0.0, f64::max);
    /// assert!(miss < 1e-9);
    /// # Ok::<(), bdmorph::MorphError>(())
    /// ```
    pub fn with_placement(mut self, placement: Placement) -> Self {
        self.placement = placement;
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
    /// Turns the tangents of predicted starts on or off (see [`Self::tangents`]).
    pub fn with_tangents(mut self, tangents: bool) -> Self {
        self.tangents = tangents;
        self
    }
    /// Sets how the numeric Cholesky factor is stored (see [`Self::factor_precision`]).
    pub fn with_factor_precision(mut self, precision: FactorPrecision) -> Self {
        self.factor_precision = precision;
        self
    }
    /// Allows or forbids reusing an earlier numeric factor in Newton's method (see
    /// [`NewtonOptions::reuse_factor`]).
    pub fn with_reuse_factor(mut self, reuse_factor: bool) -> Self {
        self.newton = self.newton.with_reuse_factor(reuse_factor);
        self
    }
    /// Bounds every frame by `budget` ([`MorphOptions::budget`]).
    ///
    /// ```
    /// use std::sync::{atomic::{AtomicBool, Ordering}, Arc};
    /// use bdmorph::{generate, Budget, Morph, MorphError, MorphOptions, Stopped};
    /// let a = generate::disk(6, 0.2);
    /// let b = generate::bend(&a, 0.5);
    /// let cancel = Arc::new(AtomicBool::new(false));
    /// let options = MorphOptions::default().with_budget(Budget::unlimited().with_cancel(cancel.clone()));
    /// let mut morph = Morph::new(&a, &b, options)?;
    /// morph.frame(0.5)?;
    /// cancel.store(true, Ordering::Relaxed); // a Cancel button, from any thread
    /// assert!(matches!(morph.frame(0.7), Err(MorphError::Stopped(Stopped::Cancelled))));
    /// # Ok::<(), MorphError>(())
    /// ```
    pub fn with_budget(mut self, budget: crate::Budget) -> Self {
        self.budget = budget;
        self
    }

    /// Refuses a Newton tolerance or step cap that is not a finite number above 0 and an
    /// iteration limit of 0, naming the option.
    pub(crate) fn validate(&self) -> Result<(), MorphError> {
        let positive = |option: &'static str, value: f64| {
            if value > 0.0 && value.is_finite() {
                Ok(())
            } else {
                Err(MorphError::BadOption {
                    option,
                    value,
                    expected: "a finite number above 0",
                })
            }
        };
        positive("newton.tolerance", self.newton.tolerance)?;
        positive("newton.step_cap", self.newton.step_cap)?;
        if self.newton.max_iterations == 0 {
            return Err(MorphError::BadOption {
                option: "newton.max_iterations",
                value: 0.0,
                expected: "at least 1",
            });
        }
        Ok(())
    }
}

/// Statistics of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameStats {
    /// The frame's time (a morph's or path's `t`); NaN for a free blend.
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
    /// The largest conformal distortion (largest over smallest singular value of the affine
    /// map) of any triangle from the first keyframe (the source) to this frame; infinite when
    /// a triangle is flipped. See [`crate::distortion`].
    pub max_conformal_distortion: f64,
    /// Wall-clock time of the frame (metric, Newton, layout, flip count), in seconds.
    pub seconds: f64,
}

impl FrameStats {
    /// The statistics as one line of JSON. Non-finite numbers (a blend's `t`, the
    /// distortion of a frame with a flipped triangle) are written as `null`.
    pub fn to_json(&self) -> String {
        format!(
            "{{\"t\":{},\"newton_iterations\":{},\"factorizations\":{},\"cg_iterations\":{},\"gradient_norm\":{},\"flipped_triangles\":{},\"max_conformal_distortion\":{},\"seconds\":{}}}",
            Json(self.t, false),
            self.newton_iterations,
            self.factorizations,
            self.cg_iterations,
            Json(self.gradient_norm, true),
            self.flipped_triangles,
            Json(self.max_conformal_distortion, false),
            Json(self.seconds, true)
        )
    }
}

/// A JSON number: `null` when not finite, in exponent form when asked.
struct Json(f64, bool);

impl std::fmt::Display for Json {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (self.0.is_finite(), self.1) {
            (false, _) => write!(f, "null"),
            (true, true) => write!(f, "{:e}", self.0),
            (true, false) => write!(f, "{}", self.0),
        }
    }
}

/// A computed frame: positions (one per vertex, in the source's order), the conformal
/// distortion of every triangle from the first keyframe, and statistics.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// Vertex positions.
    pub positions: &'a [[f64; 2]],
    /// Conformal distortion of each triangle (in the faces' order) from the first keyframe:
    /// 1 where the triangle kept its shape up to a similarity, infinite where it is flipped.
    pub distortion: &'a [f64],
    /// Statistics.
    pub stats: FrameStats,
}

/// Which frame an error is about.
#[derive(Clone, Debug, PartialEq)]
pub enum FrameAt {
    /// A morph's or path's time.
    Time(f64),
    /// A blend's weights, one per keyframe.
    Weights(Vec<f64>),
}

/// A time or weight as people read it: to 9 decimals (short enough to read, precise enough
/// to reproduce a limit), and in exponent notation far from 1 (`1e20`, not 21 digits).
pub(crate) struct Readable(pub(crate) f64);

impl std::fmt::Display for Readable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        if x == 0.0 || !x.is_finite() || (1e-4..1e7).contains(&x.abs()) {
            write!(f, "{}", (x * 1e9).round() / 1e9)
        } else {
            // Nine significant digits, without trailing zeros.
            let s = format!("{x:.8e}");
            let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
            let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
            write!(f, "{mantissa}e{exponent}")
        }
    }
}

impl std::fmt::Display for FrameAt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FrameAt::Time(t) => write!(f, "t = {}", Readable(*t)),
            FrameAt::Weights(w) => {
                write!(f, "weights (")?;
                for (i, x) in w.iter().enumerate() {
                    let sep = if i == 0 { "" } else { ", " };
                    write!(f, "{sep}{}", Readable(*x))?;
                }
                write!(f, ")")
            }
        }
    }
}

impl From<crate::io::ReadError> for MorphError {
    /// A mesh file that could not be read, as [`MeshError::Read`] (so `?` chains a read).
    fn from(e: crate::io::ReadError) -> MorphError {
        MorphError::Mesh(MeshError::Read(e))
    }
}

/// Why a morph could not be set up or a frame computed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MorphError {
    /// The input meshes are not valid.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// `t` is not a finite number.
    #[error("t = {} is not a finite number", Readable(*.t))]
    TimeNotFinite {
        /// The time asked for.
        t: f64,
    },
    /// `t` is outside a path's [0, 1].
    #[error("t = {} is outside the path's [0, 1]", Readable(*.t))]
    TimeOutOfRange {
        /// The time asked for.
        t: f64,
    },
    /// Weights given for a different number of keyframes.
    #[error("{got} weights given for {expected} keyframes")]
    WeightCount {
        /// Keyframes.
        expected: usize,
        /// Weights given.
        got: usize,
    },
    /// Weights that are not finite or do not sum to 1.
    #[error("{}: weights must be finite and sum to 1 (they sum to {sum})", FrameAt::Weights(weights.clone()))]
    WeightSum {
        /// The weights.
        weights: Vec<f64>,
        /// Their sum.
        sum: f64,
    },
    /// Extrapolated too far: the blended squared edge lengths of a triangle are no longer
    /// those of a Euclidean triangle.
    #[error("{at}: the extrapolated edge lengths of triangle {face} (0-based; vertices {} {} {}) break the triangle inequality from {limit} on", vertices[0], vertices[1], vertices[2])]
    MetricBreaks {
        /// The frame asked for.
        at: FrameAt,
        /// The first triangle to break (index into the faces).
        face: usize,
        /// Its vertices.
        vertices: [u32; 3],
        /// Where it breaks on the straight way from the nearest valid weights (for a morph,
        /// the nearest of 0 and 1) to the frame asked for: frames are possible up to there.
        limit: FrameAt,
    },
    /// A program that does not hold one of the mesh's triangles.
    #[error("the program was not compiled for these triangles: its edges do not contain the triangle of vertices {} {} {} (0-based)", face[0], face[1], face[2])]
    ProgramMismatch {
        /// The triangle.
        face: [u32; 3],
    },
    /// A keyframe after the first is not valid, or has other triangles than the first.
    #[error("keyframe {index} (0-based): {source}")]
    Keyframe {
        /// The keyframe's index.
        index: usize,
        /// Why.
        source: MeshError,
    },
    /// Fewer keyframes than the operation needs.
    #[error("{got} keyframes given; at least {needed} are needed")]
    TooFewKeyframes {
        /// Needed.
        needed: usize,
        /// Given.
        got: usize,
    },
    /// Path options with the wrong number of per-segment values.
    #[error("{got} {what} given for {expected} segments")]
    SegmentCount {
        /// `durations` or `easings`.
        what: &'static str,
        /// Segments (keyframes minus one).
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// A segment duration that is not a positive number.
    #[error("segment {segment} (0-based): duration {duration} is not a positive number")]
    BadDuration {
        /// The segment.
        segment: usize,
        /// Its duration.
        duration: f64,
    },
    /// Newton's method did not reach the tolerance.
    #[error("frame {at}: Newton did not converge (gradient norm {gradient_norm:e} after {iterations} iterations){}", Worst(worst))]
    NotConverged {
        /// The frame.
        at: FrameAt,
        /// Iterations performed.
        iterations: u32,
        /// Gradient norm reached.
        gradient_norm: f64,
        /// The triangles closest to breaking the triangle inequality where Newton gave up,
        /// worst first.
        worst: Vec<TriangleReport>,
    },
    /// The solver failed otherwise (non-finite values, a Hessian that is not positive definite).
    #[error("frame {at}: {source}{}", Worst(worst))]
    Solver {
        /// The frame.
        at: FrameAt,
        /// The VM's error.
        source: VmError,
        /// The triangles closest to breaking the triangle inequality where the solver failed.
        worst: Vec<TriangleReport>,
    },
    /// The outline of a free hole (see [`PieceInfo::free_holes`]) could not be closed at a
    /// frame: its end misses its start by `gap` of its length after the closing steps.
    #[error("frame {at}: the outline of the hole at vertex {vertex} (0-based) does not close (its ends miss by {gap:.1e} of its length)")]
    HoleOpen {
        /// The frame.
        at: FrameAt,
        /// A vertex on the hole's outline.
        vertex: u32,
        /// How far the outline's end misses its start, over its length.
        gap: f64,
    },
    /// A hole that cannot be filled, even for the topology alone, without an edge the mesh
    /// already has (every triangulation of its outline uses a diagonal that is an edge of the
    /// mesh outside it: possible only when that outline is not simple in the first keyframe).
    #[error("the hole at vertex {vertex} (0-based; piece {piece}, {boundary_vertices} vertices around it) cannot be filled for the solve: every triangulation of its outline uses an edge the mesh already has outside it")]
    HoleUnfillable {
        /// The piece (0-based, in the order of its first face).
        piece: usize,
        /// A vertex on the hole's boundary (0-based).
        vertex: u32,
        /// Vertices on the hole's boundary.
        boundary_vertices: usize,
    },
    /// [`MorphOptions::threads`] cannot be used.
    #[error(transparent)]
    Threads(#[from] crate::ThreadsError),
    /// The output buffer has the wrong length.
    #[error("output buffer holds {got} positions, the mesh has {expected} vertices")]
    OutputLength {
        /// Vertices.
        expected: usize,
        /// Buffer length.
        got: usize,
    },
    /// An option out of its range (named as in [`MorphOptions`]), refused when the object
    /// is built.
    #[error("option `{option}` is {value}: it must be {expected}")]
    BadOption {
        /// The option's field name.
        option: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
    /// The options' [`crate::Budget`] was spent (cancelled or past its deadline).
    #[error("stopped: {0}")]
    Stopped(#[from] crate::Stopped),
}

/// How many of a failed frame's worst triangles its message shows.
pub(crate) const WORST_SHOWN: usize = 3;

/// Formats the worst triangles of a failed frame for an error message.
struct Worst<'a>(&'a [TriangleReport]);

impl std::fmt::Display for Worst<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.0.is_empty() {
            return Ok(());
        }
        write!(f, "; worst triangles (0-based vertices):")?;
        for (i, tri) in self.0.iter().take(WORST_SHOWN).enumerate() {
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
    engine: Solver,
}

impl std::fmt::Debug for Morph {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Morph")
            .field("engine", &self.engine)
            .finish()
    }
}

impl Morph {
    /// Checks the pair, compiles it and prepares the solver.
    ///
    /// The target may list the source's triangles in any order, corners rotated or not
    /// ([`PlanarMesh::match_faces`]); frames follow the source's. A mesh of several pieces
    /// morphs each piece alone (each with its own rigid motion), and holes are filled with
    /// hidden triangles for the solve ([`crate::morph`]'s notes); [`Morph::structure`] says
    /// what was found.
    pub fn new(
        source: &PlanarMesh,
        target: &PlanarMesh,
        options: MorphOptions,
    ) -> Result<Morph, MorphError> {
        let keyframes = [source.clone(), target.clone()];
        let engine = Solver::new(&keyframes, Unwrap::FromFirst, options).map_err(as_pair)?;
        Ok(Morph { engine })
    }

    /// Prepares a morph from an already compiled program (made for `source`'s connectivity,
    /// which must be one disk: program files hold one).
    pub fn with_program(
        program: Program,
        source: &PlanarMesh,
        target: &PlanarMesh,
        options: MorphOptions,
    ) -> Result<Morph, MorphError> {
        let keyframes = [source.clone(), target.clone()];
        let engine = Solver::with_program(program, &keyframes, Unwrap::FromFirst, options)
            .map_err(as_pair)?;
        Ok(Morph { engine })
    }

    /// What the morph found in the meshes: pieces, holes, inverted triangles.
    pub fn structure(&self) -> &Structure {
        self.engine.structure()
    }

    /// The compiled program (the first piece's, for a mesh of several).
    pub fn program(&self) -> &Program {
        self.engine.program()
    }

    /// The triangles (the source's).
    pub fn faces(&self) -> &[[u32; 3]] {
        self.engine.faces()
    }

    /// The log scale factors of the last frame, one per interior vertex (of the first piece,
    /// for a mesh of several; hole boundaries are interior to a filled piece).
    pub fn scale_factors(&self) -> &[f64] {
        self.engine.scale_factors()
    }

    /// The conformal distortion of each triangle in the last frame, from the source.
    pub fn distortion(&self) -> &[f64] {
        self.engine.distortion()
    }

    /// How the numeric Cholesky factor is stored: [`FactorPrecision::Double`] or
    /// [`FactorPrecision::Single`], as [`MorphOptions::factor_precision`] resolved for this
    /// mesh (single precision falls back to double for good if it fails on it).
    pub fn factor_precision(&self) -> FactorPrecision {
        self.engine.factor_precision()
    }

    /// Forgets the solutions kept for warm starts: later frames are predicted only from
    /// frames solved after this call. The work a frame takes depends on the frames solved
    /// before it (a revisited place is free, a nearby one cheap); forgetting makes a
    /// sequence of frames cost the same however it was reached. The results agree either way
    /// to the Newton tolerance.
    pub fn forget_solutions(&mut self) {
        self.engine.forget_solutions();
    }

    /// Computes the frame at `t`: `t = 0` gives the source, `t = 1` the target. The metric
    /// is `(1 - t)` times the source's squared edge lengths plus `t` times the target's.
    /// Outside [0, 1] the morph extrapolates while that metric stays Euclidean, and
    /// otherwise fails with [`MorphError::MetricBreaks`] naming the first triangle to break
    /// and the `t` where it does. The positions borrow an internal buffer reused by the next
    /// call.
    pub fn frame(&mut self, t: f64) -> Result<Frame<'_>, MorphError> {
        let stats = self
            .engine
            .frame(&[1.0 - t, t], Some(t), Some(on_line(t)))
            .map_err(|e| in_time(e, t))?;
        Ok(Frame {
            positions: self.engine.positions(),
            distortion: self.engine.distortion(),
            stats,
        })
    }

    /// Computes the frame at `t` into `out` (one position per vertex). Allocates nothing; on
    /// error `out` is left untouched.
    pub fn frame_into(&mut self, t: f64, out: &mut [[f64; 2]]) -> Result<FrameStats, MorphError> {
        self.engine
            .frame_into(&[1.0 - t, t], Some(t), Some(on_line(t)), out)
            .map_err(|e| in_time(e, t))
    }
}

/// A morph's errors about its target are the pair's, as they always were: mesh errors.
fn as_pair(e: MorphError) -> MorphError {
    match e {
        MorphError::Keyframe { source, .. } => MorphError::Mesh(source),
        other => other,
    }
}

/// A morph's frames lie on the line from the source (keyframe 0) to the target, at `t`.
fn on_line(t: f64) -> Line {
    Line {
        from: 0,
        to: 1,
        s: t,
    }
}

/// A morph's errors name times, not weights: the limit of an extrapolation is the target's
/// weight there, and non-finite times are reported as such.
fn in_time(e: MorphError, t: f64) -> MorphError {
    match e {
        MorphError::MetricBreaks {
            at,
            face,
            vertices,
            limit: FrameAt::Weights(w),
        } if w.len() == 2 => MorphError::MetricBreaks {
            at,
            face,
            vertices,
            limit: FrameAt::Time(w[1]),
        },
        MorphError::WeightSum { .. } => MorphError::TimeNotFinite { t },
        other => other,
    }
}
