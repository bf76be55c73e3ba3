//! Parameterisation: flatten a disk-topology 3D triangle mesh into the plane with little
//! distortion, in the compile-once, run-many style of the rest of the crate: per-triangle
//! constants (isometric local frames, areas, `Dm⁻¹`, cotangents) once, sparse patterns fixed
//! at set-up with their symbolic factorisation reused (through the sparse Cholesky engine, [`bdmorph_cholesky`]), then
//! cheap iterations.
//!
//! Methods ([`ParamMethod`]):
//! - `tutte`: uniform weights, boundary on a circle by arc length; never flips;
//! - `lscm`: least-squares conformal map, free boundary, two pinned vertices;
//! - `asap`, `arap`: local/global iterations (Liu et al. 2008) from the Tutte map, the global
//!   matrix factored once;
//! - `sd`, `mips`, `arap-newton`: projected Newton on the symmetric Dirichlet, MIPS and ARAP
//!   energies with the closed-form eigensystems ([`energy`]), from the Tutte map, with a line
//!   search that never inverts a triangle.
//!
//! Energies are area-weighted means over the triangles ([`Energies`]).
//!
//! ```
//! use bdmorph::generate;
//! use bdmorph::param::{ParamMethod, ParamOptions, Parameterization};
//! let cap = generate::sphere_cap(3, 0.3);
//! let mut p = Parameterization::new(&cap, ParamMethod::SymmetricDirichlet, ParamOptions::default())?;
//! let start = p.energies().symmetric_dirichlet;
//! let report = p.solve()?;
//! let end = p.energies();
//! assert!(end.symmetric_dirichlet < start && end.flipped == 0);
//! assert!(report.iterations > 0);
//! # Ok::<(), bdmorph::param::ParamError>(())
//! ```

pub mod bounded;
pub mod energy;
pub(crate) mod frames;
mod linear;
pub(crate) mod local_global;
pub mod messages;
pub(crate) mod newton;

use std::time::Instant;

use bdmorph_cholesky::CholeskyError;
use bdmorph_compiler::CompileError;

use crate::io::SurfaceMesh;
use energy::{sigma2, Energy};
use frames::Frames;
use local_global::{Fit, LocalGlobal};
use newton::{mean_energy, Newton};

pub use newton::StepReport;

/// A parameterisation method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamMethod {
    /// Tutte's embedding (uniform weights, circular boundary).
    Tutte,
    /// Least-squares conformal map (free boundary).
    Lscm,
    /// As-similar-as-possible, local/global.
    Asap,
    /// As-rigid-as-possible, local/global.
    Arap,
    /// Symmetric Dirichlet by projected Newton.
    SymmetricDirichlet,
    /// MIPS by projected Newton.
    Mips,
    /// ARAP by projected Newton.
    ArapNewton,
}

/// The former name of [`ParamMethod`], which clashed with [`crate::deform::PoseMethod`]'s when both were
/// imported.
#[deprecated(since = "0.2.0", note = "renamed `ParamMethod`")]
pub type Method = ParamMethod;

impl ParamMethod {
    /// The method's name on the command line (what [`str::parse`] reads back).
    pub fn name(self) -> &'static str {
        match self {
            ParamMethod::Tutte => "tutte",
            ParamMethod::Lscm => "lscm",
            ParamMethod::Asap => "asap",
            ParamMethod::Arap => "arap",
            ParamMethod::SymmetricDirichlet => "sd",
            ParamMethod::Mips => "mips",
            ParamMethod::ArapNewton => "arap-newton",
        }
    }
}

impl std::str::FromStr for ParamMethod {
    type Err = String;
    /// `tutte`, `lscm`, `asap`, `arap`, `sd`, `mips` or `arap-newton`.
    fn from_str(s: &str) -> Result<ParamMethod, String> {
        Ok(match s {
            "tutte" => ParamMethod::Tutte,
            "lscm" => ParamMethod::Lscm,
            "asap" => ParamMethod::Asap,
            "arap" => ParamMethod::Arap,
            "sd" => ParamMethod::SymmetricDirichlet,
            "mips" => ParamMethod::Mips,
            "arap-newton" => ParamMethod::ArapNewton,
            other => {
                return Err(format!(
                "unknown method '{other}' (use tutte, lscm, asap, arap, sd, mips or arap-newton)"
            ))
            }
        })
    }
}

/// Options of a [`Parameterization`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct ParamOptions {
    /// Threads for this object's work: `None` (default) for rayon's global pool, one thread
    /// per core; `Some(n)` for a pool of its own of `n` threads, in which it is prepared and
    /// each iteration runs ([`crate::threads`]).
    pub threads: Option<usize>,
    /// The most iterations [`Parameterization::solve`] runs (default 100 for local/global
    /// methods, 200 for projected Newton).
    pub iterations: Option<u32>,
    /// Stop when an iteration decreases the energy by less than this fraction of it (default
    /// 1e-9), when the energy and its decrease are below this fraction of the starting energy
    /// (an energy whose minimum is zero), when an iteration moves no vertex by more than
    /// [`MIN_MOVE`] of the map's size, or when the gradient norm falls below `1e-10`.
    pub tolerance: f64,
    /// For `arap-newton`: the weight `w` of the collapse barrier added to ARAP
    /// ([`Energy::ArapBarrier`], default [`DEFAULT_COLLAPSE_BARRIER`]). ARAP is finite on a
    /// degenerate triangle, so its flip-free minimisation can squash triangles flat; with
    /// `w > 0` the minimised energy is infinite there and the iterations reach a real
    /// minimum. Zero minimises plain ARAP (which may then stall against a collapsing
    /// triangle: [`Stop::Stalled`]).
    pub collapse_barrier: f64,
    /// Bounds [`Parameterization::solve`] in time or by a cancellation flag, checked before
    /// every iteration (default unlimited): once spent, [`ParamError::Stopped`] (the map
    /// keeps the last iteration's result).
    pub budget: crate::Budget,
}

/// The default weight of `arap-newton`'s collapse barrier ([`ParamOptions::collapse_barrier`]).
pub const DEFAULT_COLLAPSE_BARRIER: f64 = 1e-4;

/// A triangle whose conformal distortion `σ₁ / |σ₂|` exceeds this is counted as collapsed
/// ([`Energies::collapsed`]): numerically a sliver (or a point), whatever its orientation.
/// Tutte maps of the shared disks reach 2680, local/global ARAP's flipped triangles 1e5;
/// the triangles squashed by a stalled flip-free ARAP minimisation 1e10 and more.
pub const COLLAPSE_RATIO: f64 = 1e6;

/// Newton iterations in a row whose step is below [`STALL_STEP`] of the Newton step and
/// whose energy decrease is below [`STALL_DECREASE`] of the energy, with the gradient norm
/// still above [`STALL_GRADIENT`] of its first value, after which
/// [`Parameterization::solve`] gives up and reports [`Stop::Stalled`].
pub const STALL_ITERATIONS: u32 = 3;

/// The largest vertex move of an iteration, as a fraction of the map's size, below which
/// the iterations have converged (the map no longer changes beyond rounding).
pub const MIN_MOVE: f64 = 1e-13;

/// The largest distance between corresponding points of `a` and `b`, as a fraction of
/// [`map_size`] of `b`.
pub(crate) fn relative_move(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    let moved = a
        .iter()
        .zip(b)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max);
    moved / map_size(b)
}

/// Why a mesh is not a disk, in a parameterisation's words (the compiler's speak of its
/// programs).
fn disk_problem(e: &CompileError) -> String {
    match e {
        CompileError::HasHoles { loops, euler } => format!(
            "the mesh has {loops} boundary loops (Euler characteristic {euler}): it has holes, \
             and a parameterisation flattens a disk (one boundary loop); cut the holes open to \
             the outer boundary, or fill them"
        ),
        CompileError::Disconnected { face } => format!(
            "the mesh is not connected: {face} (0-based) cannot be reached from face 0; \
             flatten each piece on its own"
        ),
        other => other.to_string(),
    }
}

/// The diagonal of the bounding box of `uv` (1 for a point or a non-finite box, so that a
/// move is then measured absolutely).
pub(crate) fn map_size(uv: &[[f64; 2]]) -> f64 {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in uv {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let size = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
    if size > 0.0 && size.is_finite() {
        size
    } else {
        1.0
    }
}

/// The fraction of the Newton step below which a step counts towards a stall.
pub const STALL_STEP: f64 = 1e-2;

/// The relative energy decrease below which a step counts towards a stall. (Short steps
/// that still lower the energy, as MIPS takes from the Tutte start, are progress.)
pub const STALL_DECREASE: f64 = 1e-4;

/// The fraction of the first gradient norm above which the gradient is "far from zero" for
/// the stall rule.
pub const STALL_GRADIENT: f64 = 1e-3;

impl Default for ParamOptions {
    fn default() -> Self {
        ParamOptions {
            iterations: None,
            tolerance: 1e-9,
            collapse_barrier: DEFAULT_COLLAPSE_BARRIER,
            threads: None,
            budget: crate::Budget::unlimited(),
        }
    }
}

impl ParamOptions {
    /// Runs on a pool of its own of `threads` threads ([`ParamOptions::threads`]).
    pub fn with_threads(mut self, threads: usize) -> Self {
        self.threads = Some(threads);
        self
    }
    /// Sets the iteration limit.
    pub fn with_iterations(mut self, iterations: u32) -> Self {
        self.iterations = Some(iterations);
        self
    }
    /// Sets the relative energy decrease below which iterations stop.
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }
    /// Sets the weight of `arap-newton`'s collapse barrier (zero: plain ARAP).
    pub fn with_collapse_barrier(mut self, weight: f64) -> Self {
        self.collapse_barrier = weight;
        self
    }
    /// Bounds the iterations by `budget` ([`ParamOptions::budget`]).
    pub fn with_budget(mut self, budget: crate::Budget) -> Self {
        self.budget = budget;
        self
    }
}

/// The first face that names a vertex out of range, as an error.
pub(crate) fn check_indices(mesh: &SurfaceMesh) -> Result<(), ParamError> {
    let n_vertices = mesh.positions.len();
    for (face, f) in mesh.faces.iter().enumerate() {
        if let Some(&vertex) = f.iter().find(|&&v| v as usize >= n_vertices) {
            return Err(ParamError::IndexOutOfRange {
                face,
                vertex,
                n_vertices,
            });
        }
    }
    Ok(())
}

/// Why a mesh could not be parameterised.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ParamError {
    /// [`ParamOptions::threads`] cannot be used.
    #[error(transparent)]
    Threads(#[from] crate::ThreadsError),
    /// The mesh file could not be read (for callers that read and parameterise with one `?`).
    #[error(transparent)]
    Read(#[from] crate::io::ReadError),
    /// The mesh is not a disk: closed, with several boundaries, non-manifold, disconnected...
    #[error("not a disk: {}", disk_problem(.0))]
    NotADisk(#[from] CompileError),
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} (0-based) has a non-finite coordinate")]
    NonFinite {
        /// The vertex.
        vertex: usize,
    },
    /// A face names a vertex that does not exist.
    #[error("face {face} (0-based) names vertex {vertex}, but the mesh has {n_vertices} vertices (numbered from 0)")]
    IndexOutOfRange {
        /// The face.
        face: usize,
        /// The vertex it names.
        vertex: u32,
        /// Vertex count.
        n_vertices: usize,
    },
    /// A triangle of zero area.
    #[error("face {face} (0-based) is degenerate (zero area)")]
    Degenerate {
        /// The face.
        face: usize,
    },
    /// A distortion bound that is not a number of at least 1.
    #[error("the distortion bound {0} must be a number of at least 1")]
    BadBound(f64),
    /// A collapse-barrier weight that is negative or not finite.
    #[error("the collapse-barrier weight {0} must be a finite number of at least 0")]
    BadBarrier(f64),
    /// Two positional constraints on one vertex.
    #[error("vertex {vertex} (0-based) is pinned twice")]
    PinnedTwice {
        /// The vertex.
        vertex: u32,
    },
    /// A positional constraint on a vertex that does not exist, or to a non-finite point.
    #[error("constraint on vertex {vertex} (0-based): no such vertex (the mesh has {n_vertices}) or a non-finite target")]
    BadPin {
        /// The vertex.
        vertex: u32,
        /// Vertex count.
        n_vertices: usize,
    },
    /// A linear solve failed.
    #[error("{what}: {source}")]
    Solver {
        /// Which system.
        what: &'static str,
        /// Why.
        source: CholeskyError,
    },
    /// The mesh has no vertex or no triangle.
    #[error("the mesh is empty ({vertices} vertices, {faces} triangles)")]
    EmptyMesh {
        /// Vertex count.
        vertices: usize,
        /// Triangle count.
        faces: usize,
    },
    /// A map given with a number of points other than the mesh's vertex count.
    #[error("the map has {got} points for {expected} vertices")]
    UvLength {
        /// The mesh's vertex count.
        expected: usize,
        /// Points given.
        got: usize,
    },
    /// An option out of its range (named as in the options struct).
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

/// Refuses `uv` unless it has one point per vertex.
pub(crate) fn check_uv_len(expected: usize, uv: &[[f64; 2]]) -> Result<(), ParamError> {
    if uv.len() == expected {
        Ok(())
    } else {
        Err(ParamError::UvLength {
            expected,
            got: uv.len(),
        })
    }
}

/// Refuses a tolerance that is not a finite number above 0 (naming the option).
pub(crate) fn check_tolerance(option: &'static str, value: f64) -> Result<(), ParamError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(ParamError::BadOption {
            option,
            value,
            expected: "a finite number above 0",
        })
    }
}

/// Refuses an iteration count of 0 (naming the option).
pub(crate) fn check_iterations(option: &'static str, value: u32) -> Result<(), ParamError> {
    if value >= 1 {
        Ok(())
    } else {
        Err(ParamError::BadOption {
            option,
            value: f64::from(value),
            expected: "at least 1",
        })
    }
}

/// The distortion of a map, area-weighted means over the triangles, and its bad triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Energies {
    /// Symmetric Dirichlet (4 for an isometry; infinite with an inverted triangle).
    pub symmetric_dirichlet: f64,
    /// ARAP, `Σ (σᵢ − 1)²` (0 for an isometry).
    pub arap: f64,
    /// MIPS, `σ₁/σ₂ + σ₂/σ₁` (2 for a conformal map; infinite with an inverted triangle).
    pub mips: f64,
    /// Triangles with non-positive signed area in the plane.
    pub flipped: usize,
    /// Triangles whose conformal distortion `σ₁ / |σ₂|` exceeds [`COLLAPSE_RATIO`] (or is
    /// not finite), flipped or not: squashed to a sliver or a point.
    pub collapsed: usize,
    /// The largest conformal distortion `σ₁ / |σ₂|` over the triangles (infinite when one is
    /// degenerate).
    pub max_distortion: f64,
}

/// Why [`Parameterization::solve`] stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// A direct method (`tutte`, `lscm`): nothing to iterate.
    Direct,
    /// The energy stopped decreasing (relative decrease below the tolerance) or the gradient
    /// vanished.
    Converged,
    /// The iteration limit was reached first.
    IterationLimit,
    /// Projected Newton could not make progress while the gradient was still far from
    /// zero: [`STALL_ITERATIONS`] steps in a row below [`STALL_STEP`] of the Newton step (the
    /// flip-free line search held back by a triangle about to collapse or invert), or a
    /// line search that found no decrease at all. The map is not a minimum.
    Stalled,
}

impl Stop {
    /// `direct`, `converged`, `iteration-limit` or `stalled`.
    pub fn name(self) -> &'static str {
        match self {
            Stop::Direct => "direct",
            Stop::Converged => "converged",
            Stop::IterationLimit => "iteration-limit",
            Stop::Stalled => "stalled",
        }
    }
}

/// What [`Parameterization::solve`] did.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct SolveReport {
    /// Iterations run.
    pub iterations: u32,
    /// The method's own energy after each iteration (empty for direct methods).
    pub energies: Vec<f64>,
    /// Wall-clock seconds of the iterations (set-up excluded: see `setup_seconds`).
    pub seconds: f64,
    /// Wall-clock seconds of [`Parameterization::new`]: checks, per-triangle constants, the
    /// start (the whole work of `tutte` and `lscm`), patterns and factorisations.
    pub setup_seconds: f64,
    /// Why the iterations stopped.
    pub stop: Stop,
    /// The gradient norm before the last iteration (NaN for the methods without one).
    pub gradient_norm: f64,
    /// Collapsed triangles of the final map ([`Energies::collapsed`]).
    pub collapsed: usize,
    /// At a stall, the triangle whose imminent inversion (or collapse) bounded the last
    /// step, if one did.
    pub limiting_face: Option<usize>,
}

impl SolveReport {
    /// Whether the iterations stalled ([`Stop::Stalled`]).
    pub fn stalled(&self) -> bool {
        self.stop == Stop::Stalled
    }
}

/// The distortion of the map `uv` (one point per vertex) of `mesh`.
///
/// # Errors
/// [`ParamError::UvLength`] unless `uv` has one point per vertex, and the mesh's own errors
/// (a face naming a vertex out of range, a degenerate triangle).
pub fn energies(mesh: &SurfaceMesh, uv: &[[f64; 2]]) -> Result<Energies, ParamError> {
    check_uv_len(mesh.positions.len(), uv)?;
    check_indices(mesh)?;
    let frames = Frames::new(mesh).map_err(|face| ParamError::Degenerate { face })?;
    Ok(energies_of(&frames, uv))
}

fn energies_of(frames: &Frames, uv: &[[f64; 2]]) -> Energies {
    let (mut flipped, mut collapsed, mut max_distortion) = (0, 0, 1.0f64);
    let (mut sd, mut arap, mut mips) = (0.0, 0.0, 0.0);
    for f in 0..frames.len() {
        let m = frames.gradient(f, uv);
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        if det.is_nan() || det <= 0.0 {
            flipped += 1;
        }
        let sigma = sigma2(m);
        let a = frames.area[f];
        sd += a * Energy::SymmetricDirichlet.psi(sigma);
        arap += a * Energy::Arap.psi(sigma);
        mips += a * Energy::Mips.psi(sigma);
        let [s1, s2] = sigma;
        let ratio = if s2 != 0.0 {
            s1 / s2.abs()
        } else {
            f64::INFINITY
        };
        if ratio.is_nan() || ratio > COLLAPSE_RATIO {
            collapsed += 1;
        }
        max_distortion = if ratio.is_nan() {
            f64::INFINITY
        } else {
            max_distortion.max(ratio)
        };
    }
    let total = frames.total_area;
    Energies {
        symmetric_dirichlet: sd / total,
        arap: arap / total,
        mips: mips / total,
        flipped,
        collapsed,
        max_distortion,
    }
}

enum Solver {
    Direct,
    LocalGlobal(Box<LocalGlobal>),
    Newton(Box<Newton>),
}

/// A parameterisation in progress: the current map and the prepared solver.
pub struct Parameterization {
    /// Where it was prepared and its iterations run.
    pool: crate::threads::Pool,
    method: ParamMethod,
    options: ParamOptions,
    frames: Frames,
    uv: Vec<[f64; 2]>,
    solver: Solver,
    /// The energy the iterations lower (and the direct methods' measure).
    objective: Energy,
    setup_seconds: f64,
}

impl std::fmt::Debug for Parameterization {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Parameterization")
            .field("method", &self.method)
            .field("vertices", &self.uv.len())
            .field("faces", &self.frames.len())
            .finish_non_exhaustive()
    }
}

impl Parameterization {
    /// Checks the mesh (a manifold disk with finite coordinates and no degenerate triangle),
    /// computes the per-triangle constants and the start (the result itself for `tutte` and
    /// `lscm`, the Tutte map for the iterative methods), and prepares the iterations.
    pub fn new(
        mesh: &SurfaceMesh,
        method: ParamMethod,
        options: ParamOptions,
    ) -> Result<Parameterization, ParamError> {
        let pool = crate::threads::Pool::new(options.threads)?;
        let mut built = pool.run(|| Parameterization::new_here(mesh, method, options.clone()))?;
        built.pool = pool;
        Ok(built)
    }

    fn new_here(
        mesh: &SurfaceMesh,
        method: ParamMethod,
        options: ParamOptions,
    ) -> Result<Parameterization, ParamError> {
        let started = Instant::now();
        if let Some(vertex) = mesh
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(ParamError::NonFinite { vertex });
        }
        let barrier = options.collapse_barrier;
        if !(barrier >= 0.0 && barrier.is_finite()) {
            return Err(ParamError::BadBarrier(barrier));
        }
        check_tolerance("tolerance", options.tolerance)?;
        if let Some(iterations) = options.iterations {
            check_iterations("iterations", iterations)?;
        }
        if mesh.positions.is_empty() || mesh.faces.is_empty() {
            return Err(ParamError::EmptyMesh {
                vertices: mesh.positions.len(),
                faces: mesh.faces.len(),
            });
        }
        let objective = match method {
            ParamMethod::Arap => Energy::Arap,
            ParamMethod::ArapNewton if barrier > 0.0 => Energy::ArapBarrier { weight: barrier },
            ParamMethod::ArapNewton => Energy::Arap,
            ParamMethod::Asap => Energy::Asap,
            ParamMethod::Mips | ParamMethod::Lscm => Energy::Mips,
            ParamMethod::Tutte | ParamMethod::SymmetricDirichlet => Energy::SymmetricDirichlet,
        };
        let boundary = bdmorph_compiler::disk_boundary(mesh.positions.len(), &mesh.faces)?;
        check_indices(mesh)?;
        let frames = Frames::new(mesh).map_err(|face| ParamError::Degenerate { face })?;
        let n = mesh.positions.len();
        let uv = match method {
            ParamMethod::Lscm => linear::lscm(&frames, &mesh.positions, &boundary)?,
            _ => linear::tutte(&frames, &mesh.positions, &boundary)?,
        };
        let solver = match method {
            ParamMethod::Tutte | ParamMethod::Lscm => Solver::Direct,
            ParamMethod::Arap => Solver::LocalGlobal(Box::new(LocalGlobal::new(
                &frames,
                n,
                boundary[0],
                Fit::Rotation,
            )?)),
            ParamMethod::Asap => Solver::LocalGlobal(Box::new(LocalGlobal::new(
                &frames,
                n,
                boundary[0],
                Fit::Similarity,
            )?)),
            ParamMethod::SymmetricDirichlet => Solver::Newton(Box::new(Newton::new(
                &frames,
                n,
                Energy::SymmetricDirichlet,
            )?)),
            ParamMethod::Mips => Solver::Newton(Box::new(Newton::new(&frames, n, Energy::Mips)?)),
            ParamMethod::ArapNewton => {
                Solver::Newton(Box::new(Newton::new(&frames, n, objective)?))
            }
        };
        Ok(Parameterization {
            pool: crate::threads::Pool::default(),
            method,
            options,
            frames,
            uv,
            solver,
            objective,
            setup_seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// Wall-clock seconds [`Parameterization::new`] took (for `tutte` and `lscm`, the whole
    /// method).
    pub fn setup_seconds(&self) -> f64 {
        self.setup_seconds
    }

    /// The method.
    pub fn method(&self) -> ParamMethod {
        self.method
    }

    /// The current map: one parameter-plane position per vertex.
    pub fn uv(&self) -> &[[f64; 2]] {
        &self.uv
    }

    /// The distortion of the current map.
    pub fn energies(&self) -> Energies {
        energies_of(&self.frames, &self.uv)
    }

    /// The method's own energy of the current map, the one its iterations lower: ARAP for
    /// `arap`, ARAP plus the collapse barrier for `arap-newton` ([`Energy::ArapBarrier`];
    /// plain ARAP with a zero barrier weight), ASAP for `asap`, MIPS for `mips` and `lscm`,
    /// symmetric Dirichlet for `sd` and `tutte`.
    pub fn energy(&self) -> f64 {
        mean_energy(self.objective, &self.frames, &self.uv)
    }

    /// One iteration; `None` for the direct methods (`tutte`, `lscm`), which are done at
    /// [`Parameterization::new`].
    pub fn step(&mut self) -> Result<Option<StepReport>, ParamError> {
        let pool = self.pool.clone();
        pool.run(|| self.step_here())
    }

    fn step_here(&mut self) -> Result<Option<StepReport>, ParamError> {
        match &mut self.solver {
            Solver::Direct => Ok(None),
            Solver::LocalGlobal(lg) => {
                let previous = self.uv.clone();
                let (before, after) = lg.iterate(&self.frames, &mut self.uv)?;
                Ok(Some(StepReport {
                    energy_before: before,
                    energy_after: after,
                    gradient_norm: f64::NAN,
                    step: 1.0,
                    max_step: f64::NAN,
                    limiting_face: None,
                    moved: relative_move(&previous, &self.uv),
                }))
            }
            Solver::Newton(newton) => newton.iterate(&self.frames, &mut self.uv).map(Some),
        }
    }

    /// Iterates until the energy stops decreasing by more than the tolerance (relatively),
    /// the gradient vanishes, the iterations stall ([`Stop::Stalled`]: projected Newton
    /// making no progress while the gradient is far from zero), or the iteration limit;
    /// `progress` sees every step.
    pub fn solve_with(
        &mut self,
        mut progress: impl FnMut(u32, &StepReport),
    ) -> Result<SolveReport, ParamError> {
        let started = Instant::now();
        let limit = self.options.iterations.unwrap_or(match self.solver {
            Solver::Newton(_) => 200,
            _ => 100,
        });
        let mut energies = Vec::new();
        let mut iterations = 0;
        let mut stop = match self.solver {
            Solver::Direct => Stop::Direct,
            _ => Stop::IterationLimit,
        };
        let (mut first_gradient, mut gradient_norm) = (f64::NAN, f64::NAN);
        let mut first_energy = 0.0f64;
        let mut blocked_run = 0;
        let mut limiting_face = None;
        while iterations < limit {
            if !matches!(self.solver, Solver::Direct) {
                self.options.budget.check()?;
            }
            let Some(report) = self.step()? else {
                break;
            };
            iterations += 1;
            energies.push(report.energy_after);
            progress(iterations, &report);
            gradient_norm = report.gradient_norm;
            limiting_face = report.limiting_face;
            if iterations == 1 {
                first_gradient = report.gradient_norm;
            }
            // Far from zero: NaN (local/global has no gradient) is never far.
            let far = report.gradient_norm > STALL_GRADIENT * first_gradient
                && report.gradient_norm >= 1e-10;
            let decrease = report.energy_before - report.energy_after;
            let blocked = far
                && report.step < STALL_STEP
                && decrease < STALL_DECREASE * report.energy_after.abs();
            blocked_run = if blocked { blocked_run + 1 } else { 0 };
            if iterations == 1 {
                first_energy = report.energy_before.abs();
            }
            // An energy whose minimum is zero (a developable surface's ARAP) falls by a
            // constant fraction per local/global iteration: relative to itself it never
            // settles. Once it is below the tolerance of where it started it is zero.
            let scale = report.energy_after.abs().max(first_energy);
            let settled = (decrease.is_finite()
                && decrease.abs() <= self.options.tolerance * report.energy_after.abs())
                || (decrease.is_finite()
                    && report.energy_after.abs() <= self.options.tolerance * scale
                    && decrease.abs() <= self.options.tolerance * scale)
                || report.moved <= MIN_MOVE;
            if report.gradient_norm < 1e-10 {
                stop = Stop::Converged;
            } else if blocked_run >= STALL_ITERATIONS || (report.step == 0.0 && far) {
                stop = Stop::Stalled;
            } else if settled || report.step == 0.0 {
                // (An energy that rose, to infinity or by more than the tolerance, is no
                // convergence.)
                // A negligible decrease from a tiny step with a large gradient is a stall
                // that has not lasted long yet, not a minimum.
                stop = if blocked {
                    Stop::Stalled
                } else {
                    Stop::Converged
                };
            } else {
                continue;
            }
            break;
        }
        let seconds = started.elapsed().as_secs_f64();
        Ok(SolveReport {
            iterations,
            energies,
            seconds,
            setup_seconds: self.setup_seconds,
            stop,
            gradient_norm,
            collapsed: self.energies().collapsed,
            limiting_face: limiting_face.filter(|_| stop == Stop::Stalled),
        })
    }

    /// [`Parameterization::solve_with`] without progress reports.
    pub fn solve(&mut self) -> Result<SolveReport, ParamError> {
        self.solve_with(|_, _| {})
    }
}
