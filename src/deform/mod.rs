//! Posing a planar mesh by handles: a precompute object per mesh and method, pins set when
//! the set of handles changes (the only time anything is factored), and a cheap, warm-started,
//! allocation-free drag per mouse move.
//!
//! Methods ([`PoseMethod`]):
//!
//! - [`PoseMethod::Kvf`], as-Killing-as-possible vector fields (Solomon et al. 2011), the
//!   original BDMORPH editor's: soft handles with a weight, each step a Killing field moved
//!   along by log spirals, with a strain term so that poses do not drift ([`KvfOptions`]).
//! - [`PoseMethod::Arap`], as-rigid-as-possible with hard pins (2D local/global, Sorkine and
//!   Alexa 2007, in the planar form of Liu et al. 2008): a few iterations per drag from the
//!   previous pose with one prefactored cotangent Laplacian ([`ArapOptions`]).
//! - [`PoseMethod::Bounded`], bounded distortion (Kovalsky et al. 2015) with hard pins: every
//!   triangle's conformal distortion at most `K` and none flipped, met or reported per drag
//!   ([`BoundedPoseOptions`]).
//!
//! Each drag's [`DragReport`] measures the pose the same way for every method, from the
//! positions the drag returns: ARAP energy, largest conformal distortion, flipped triangles,
//! the handles' residual, and how the drag ended ([`DragStatus`]: still moving, converged,
//! stalled, or reverted to the pose before it when the method reached a point that is not
//! finite). The positions are always finite.
//! Meshes of several pieces, with holes, pose as well: every piece needs a handle.
//!
//! Regions painted stiff ([`Deformer::set_stiffness`], one weight per triangle, After Effects'
//! "starch") keep their shape up to a rotation while the rest bends, under every method.
//!
//! KVF's steps never raise its energy, and can be made flip-free
//! ([`KvfOptions::flip_free`]); a large drag is followed in stretches, so that it ends where
//! the same drag in small moves does.
//!
//! A pose left with flipped triangles (a quick ARAP drag on a thin limb, say) is repaired by
//! [`untangle`]: the bounded-distortion projections on the region around the flips only,
//! within a distortion limit it states, or not at all.
//!
//! ```
//! use bdmorph::deform::{Deformer, PoseMethod};
//! use bdmorph::generate;
//! let rest = generate::grid(10, 4, 0.0);                // 10 x 4 vertices, 9 x 3 units
//! let mut pose = Deformer::new(&rest, PoseMethod::arap())?;
//! // Pin the bottom-left corner where it is and drag the bottom-right one up.
//! let (left, right) = (0u32, 9u32);
//! pose.set_pins(&[left, right])?;
//! let report = pose.drag(&[rest.positions[0], [8.5, 2.0]])?;
//! assert_eq!(pose.positions()[9], [8.5, 2.0]);         // hard pins are met exactly
//! assert!(report.iterations >= 1);
//! # Ok::<(), bdmorph::deform::DeformError>(())
//! ```

mod arap;
mod bounded;
mod kvf;
mod sd;
mod stretch;
mod untangle;

use crate::mesh::{MeshError, PlanarMesh};
use crate::param::frames::Frames;

pub use arap::ArapOptions;
pub use bounded::BoundedPoseOptions;
pub use kvf::KvfOptions;
pub use sd::SdOptions;
pub use untangle::{untangle, UntangleOptions, UntangleReport, Untangled};

/// How the mesh follows its handles.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum PoseMethod {
    /// As-Killing-as-possible vector fields with soft handles (the original editor's).
    Kvf(KvfOptions),
    /// As-rigid-as-possible with hard pins.
    Arap(ArapOptions),
    /// Bounded distortion with hard pins.
    Bounded(BoundedPoseOptions),
    /// Symmetric Dirichlet with soft handles, by projected Newton: no triangle ever flips
    /// or is crushed; a handle stops short where following it would crush the mesh.
    Sd(SdOptions),
}

/// The former name of [`PoseMethod`], which clashed with [`crate::param::ParamMethod`]'s when both were
/// imported.
#[deprecated(since = "0.2.0", note = "renamed `PoseMethod`")]
pub type Method = PoseMethod;

impl PoseMethod {
    /// KVF with the default options.
    pub fn kvf() -> PoseMethod {
        PoseMethod::Kvf(KvfOptions::default())
    }
    /// ARAP with the default options.
    pub fn arap() -> PoseMethod {
        PoseMethod::Arap(ArapOptions::default())
    }
    /// Bounded distortion with the bound `K` and the default options.
    pub fn bounded(max_distortion: f64) -> PoseMethod {
        PoseMethod::Bounded(BoundedPoseOptions::new(max_distortion))
    }
    /// Symmetric Dirichlet with the default options.
    pub fn sd() -> PoseMethod {
        PoseMethod::Sd(SdOptions::default())
    }
    /// The method's name: `kvf`, `arap`, `bounded` or `sd`.
    pub fn name(&self) -> &'static str {
        match self {
            PoseMethod::Kvf(_) => "kvf",
            PoseMethod::Arap(_) => "arap",
            PoseMethod::Bounded(_) => "bounded",
            PoseMethod::Sd(_) => "sd",
        }
    }
}

/// The method's state.
enum Solver {
    Kvf(Box<kvf::Kvf>),
    Arap(Box<arap::Arap>),
    Bounded(Box<bounded::Bounded>),
    Sd(Box<sd::Sd>),
}

impl From<crate::io::ReadError> for DeformError {
    /// A mesh file that could not be read, as [`MeshError::Read`] (so `?` chains a read).
    fn from(e: crate::io::ReadError) -> DeformError {
        DeformError::Mesh(MeshError::Read(e))
    }
}

/// Why posing failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DeformError {
    /// [`Deformer::set_threads`]'s count cannot be used.
    #[error(transparent)]
    Threads(#[from] crate::ThreadsError),
    /// The mesh is not valid.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A pin names a vertex that does not exist.
    #[error("pin {pin} names vertex {vertex} (0-based), but the mesh has {n_vertices} vertices")]
    PinOutOfRange {
        /// The pin's place in the list.
        pin: usize,
        /// Its vertex.
        vertex: u32,
        /// Vertices of the mesh.
        n_vertices: usize,
    },
    /// A vertex is pinned twice.
    #[error("vertex {vertex} (0-based) is pinned twice")]
    PinnedTwice {
        /// The vertex.
        vertex: u32,
    },
    /// A piece of the mesh has no pin: nothing holds it in place.
    #[error("the piece holding vertex {vertex} (0-based) has no pin; every piece needs one")]
    PieceWithoutPin {
        /// A vertex of that piece.
        vertex: u32,
    },
    /// `drag` before `set_pins`, or with another number of targets than pins.
    #[error("{got} targets given for {pins} pins")]
    TargetCount {
        /// Pins set.
        pins: usize,
        /// Targets given.
        got: usize,
    },
    /// A target that is not a finite point.
    #[error("target {index} is not a finite point")]
    NonFiniteTarget {
        /// Its place in the list.
        index: usize,
    },
    /// The linear solver failed.
    #[error("the posing system could not be factored or solved: {0}")]
    Solver(#[from] crate::CholeskyError),
    /// `set_positions` with another number of points than vertices.
    #[error("{got} positions given for {expected} vertices")]
    PositionCount {
        /// Vertices of the mesh.
        expected: usize,
        /// Points given.
        got: usize,
    },
    /// A distortion bound that is not a finite number at least 1.
    #[error("the distortion bound must be a finite number >= 1, not {0}")]
    BadBound(f64),
    /// A KVF handle weight that is not a finite positive number.
    #[error("the handles' weight must be a finite number > 0, not {0}")]
    BadWeight(f64),
    /// `set_weight` on a method without handle weights.
    #[error("only kvf and sd have a handle weight")]
    NoWeight,
    /// The bounded-distortion solver failed.
    #[error(transparent)]
    Bounded(crate::param::ParamError),
    /// [`Deformer::set_stiffness`] with another number of weights than triangles.
    #[error("{got} stiffness weights given for {expected} triangles (one per triangle)")]
    StiffnessCount {
        /// Triangles of the mesh.
        expected: usize,
        /// Weights given.
        got: usize,
    },
    /// A stiffness weight that is not a finite number at least 1.
    #[error(
        "the stiffness of triangle {index} (0-based) is {value}; each must be a finite number >= 1"
    )]
    BadStiffness {
        /// The triangle.
        index: usize,
        /// Its weight.
        value: f64,
    },
    /// An option of the method out of its range (named as in its options struct).
    #[error("{method} option `{option}` is {value}: it must be {expected}")]
    BadOption {
        /// The method (`kvf`, `arap`, `bounded`, `sd`, `untangle`).
        method: &'static str,
        /// The option's field name.
        option: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
    /// The method's [`crate::Budget`] was spent (cancelled or past its deadline) during a
    /// drag: the pose before the drag is kept.
    #[error("stopped: {0}")]
    Stopped(#[from] crate::Stopped),
}

impl DeformError {
    /// The bounded-distortion solver's error, a spent budget as [`DeformError::Stopped`].
    pub(crate) fn from_bounded(e: crate::param::ParamError) -> DeformError {
        match e {
            crate::param::ParamError::Stopped(s) => DeformError::Stopped(s),
            other => DeformError::Bounded(other),
        }
    }
}

/// Refuses a tolerance that is not a finite number >= 0 (naming the method and option). Posing
/// runs a bounded number of iterations, so 0 is allowed: never stop early.
pub(crate) fn check_tolerance(
    method: &'static str,
    option: &'static str,
    value: f64,
) -> Result<(), DeformError> {
    if value >= 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(DeformError::BadOption {
            method,
            option,
            value,
            expected: "a finite number >= 0",
        })
    }
}

/// Refuses an iteration count of 0 (naming the method and option).
pub(crate) fn check_iterations(
    method: &'static str,
    option: &'static str,
    value: u32,
) -> Result<(), DeformError> {
    if value >= 1 {
        Ok(())
    } else {
        Err(DeformError::BadOption {
            method,
            option,
            value: f64::from(value),
            expected: "at least 1",
        })
    }
}

/// How a drag's iterations ended.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum DragStatus {
    /// The iterations were spent with the pose still moving toward where the handles take
    /// it; the next drag (at the same targets or new ones) goes on from it. For
    /// [`PoseMethod::Bounded`]: the bound is not met yet.
    #[default]
    Moving,
    /// The pose moved by at most the method's tolerance in its last iteration: a stationary
    /// pose for these targets. For [`PoseMethod::Bounded`]: the bound is met.
    Converged,
    /// The method could not make progress: no step along KVF's field lowered its energy
    /// without flipping a triangle (its line search), or bounded distortion's finishing
    /// Newton step found no decrease. The pose is the last one that made progress: finite
    /// and usable, but not where the method would settle.
    Stalled,
    /// The method's iterations reached a point that is not finite (targets too far for
    /// floating point, say); the pose before the drag is kept, and the report measures it.
    Reverted,
}

/// What a drag did, and the pose it left, measured the same way for every method.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DragReport {
    /// The method's iterations run (local/global steps, KVF steps, projections).
    pub iterations: u32,
    /// The pose's ARAP energy (area-weighted mean of `|J - R|²`, `J` each triangle's
    /// deformation gradient, `R` its closest rotation).
    pub energy: f64,
    /// The largest move of any vertex in the last iteration, relative to the mesh's size:
    /// how far from converged the pose is.
    pub last_change: f64,
    /// Triangles with non-positive signed area in the pose.
    pub flipped_triangles: usize,
    /// The largest distance of a pinned vertex from its target (0 for hard pins).
    pub pin_residual: f64,
    /// The largest conformal distortion `σ₁ / σ₂` of an unflipped triangle.
    pub max_distortion: f64,
    /// For [`PoseMethod::Bounded`], whether every triangle is within the bound and none is
    /// flipped; `None` for methods without a bound.
    pub bound_met: Option<bool>,
    /// How the iterations ended: still moving, converged, stalled, or reverted to the pose
    /// before the drag.
    pub status: DragStatus,
}

/// A mesh prepared for posing.
pub struct Deformer {
    /// Where its systems are factored and its drags solved ([`Deformer::set_threads`]).
    pool: crate::threads::Pool,
    rest: PlanarMesh,
    frames: Frames,
    diameter: f64,
    positions: Vec<[f64; 2]>,
    /// The pose before the drag being made, put back if the method ends on a point that is
    /// not finite.
    before: Vec<[f64; 2]>,
    pins: Vec<u32>,
    solver: Solver,
    /// Per triangle, its stiffness ([`Deformer::set_stiffness`]; `None`: all 1).
    stiffness: Option<Vec<f64>>,
}

impl std::fmt::Debug for Deformer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Deformer")
            .field("vertices", &self.rest.positions.len())
            .field("faces", &self.rest.faces.len())
            .field("method", &self.method().name())
            .field("pins", &self.pins.len())
            .finish_non_exhaustive()
    }
}

impl Deformer {
    /// Checks the mesh (a valid planar mesh: counter-clockwise, no degenerate triangle; any
    /// number of pieces and holes) and prepares the method's constants. Nothing is factored
    /// until [`Deformer::set_pins`].
    pub fn new(mesh: &PlanarMesh, method: PoseMethod) -> Result<Deformer, DeformError> {
        if mesh.faces.is_empty() {
            return Err(MeshError::NoTriangles.into());
        }
        let frames = planar_frames(mesh)?;
        let n = mesh.positions.len();
        let solver = match method {
            PoseMethod::Kvf(options) => Solver::Kvf(Box::new(kvf::Kvf::new(&frames, n, options)?)),
            PoseMethod::Arap(options) => {
                Solver::Arap(Box::new(arap::Arap::new(&frames, n, options)?))
            }
            PoseMethod::Bounded(options) => {
                Solver::Bounded(Box::new(bounded::Bounded::new(&frames, n, options)?))
            }
            PoseMethod::Sd(options) => Solver::Sd(Box::new(sd::Sd::new(&frames, n, options)?)),
        };
        Ok(Deformer {
            pool: crate::threads::Pool::default(),
            solver,
            diameter: mesh.diameter().max(f64::MIN_POSITIVE),
            positions: mesh.positions.clone(),
            before: mesh.positions.clone(),
            rest: mesh.clone(),
            frames,
            pins: Vec::new(),
            stiffness: None,
        })
    }

    /// The method and its options.
    pub fn method(&self) -> PoseMethod {
        match &self.solver {
            Solver::Kvf(s) => PoseMethod::Kvf(s.options().clone()),
            Solver::Arap(s) => PoseMethod::Arap(s.options().clone()),
            Solver::Bounded(s) => PoseMethod::Bounded(s.options().clone()),
            Solver::Sd(s) => PoseMethod::Sd(s.options().clone()),
        }
    }

    /// Sets the pinned vertices (the handles, in the order [`Deformer::drag`] takes their
    /// targets) and factors the system. The pose so far is kept as the next drag's start.
    pub fn set_pins(&mut self, pins: &[u32]) -> Result<(), DeformError> {
        let pool = self.pool.clone();
        pool.run(|| self.set_pins_here(pins))
    }

    /// Runs the factorisations and drags from now on in a pool of its own of `threads`
    /// threads (`None`: rayon's global pool, one thread per core, the default). The split of
    /// a factorisation over threads is planned when it is analysed: set the threads before
    /// [`Deformer::set_pins`].
    ///
    /// ```
    /// use bdmorph::{deform::{Deformer, PoseMethod}, generate};
    /// let disk = generate::disk(6, 0.2);
    /// let mut pose = Deformer::new(&disk, PoseMethod::arap())?;
    /// pose.set_threads(Some(1))?;
    /// pose.set_pins(&[0, 1])?;
    /// assert!(pose.set_threads(Some(0)).is_err());
    /// # Ok::<(), bdmorph::deform::DeformError>(())
    /// ```
    pub fn set_threads(&mut self, threads: Option<usize>) -> Result<(), DeformError> {
        self.pool = crate::threads::Pool::new(threads)?;
        Ok(())
    }

    fn set_pins_here(&mut self, pins: &[u32]) -> Result<(), DeformError> {
        let n = self.rest.positions.len();
        let pinned = pinned_vertices(n, pins)?;
        if let Some(vertex) = unpinned_piece(n, &self.rest.faces, &pinned) {
            return Err(DeformError::PieceWithoutPin { vertex });
        }
        match &mut self.solver {
            Solver::Kvf(s) => s.set_pins(&self.frames, pins)?,
            Solver::Arap(s) => s.set_pins(&self.frames, pins)?,
            Solver::Bounded(s) => s.set_pins(&self.frames, n, pins)?,
            Solver::Sd(s) => s.set_pins(pins)?,
        }
        self.pins = pins.to_vec();
        Ok(())
    }

    /// Sets each triangle's stiffness, one weight per triangle in the mesh's order, each a
    /// finite number at least 1: 1 is the mesh's own stiffness, larger holds the triangle
    /// closer to its rest shape (up to a rotation) while the rest of the mesh bends (After
    /// Effects' "starch"). `None` puts every triangle back to 1. Refactors when pins are set
    /// (the pins and the pose stay); before [`Deformer::set_pins`] it only takes effect there.
    ///
    /// For every method, a triangle of weight `w`:
    ///
    /// - [`PoseMethod::Arap`]: its term of the ARAP energy, `A |J − R|²`, is multiplied by
    ///   `w` (the global step's matrix and right-hand side both).
    /// - [`PoseMethod::Kvf`]: its term of the field's energy (the Killing term and the strain
    ///   term) is multiplied by `w`; the handles' weight stays relative to the unweighted mesh.
    /// - [`PoseMethod::Bounded`]: its bound is `K_t = 1 + (K − 1) / w` (the ARAP iterations
    ///   before the projections weighted as for ARAP), and
    ///   [`DragReport::bound_met`] checks each triangle against its own bound.
    ///
    /// A weight of exactly 1 everywhere gives the same poses, bit for bit, as no weights.
    /// On an error nothing changes.
    ///
    /// ```
    /// use bdmorph::deform::{DeformError, Deformer, PoseMethod};
    /// use bdmorph::generate;
    /// let rest = generate::grid(10, 4, 0.0);                // 9 x 3 units, 54 triangles
    /// let mut pose = Deformer::new(&rest, PoseMethod::arap())?;
    /// // The left third stiff: triangles whose centroid has x < 3.
    /// let stiff: Vec<f64> = rest
    ///     .faces
    ///     .iter()
    ///     .map(|f| {
    ///         let x = f.iter().map(|&v| rest.positions[v as usize][0]).sum::<f64>() / 3.0;
    ///         if x < 3.0 { 1000.0 } else { 1.0 }
    ///     })
    ///     .collect();
    /// pose.set_stiffness(Some(&stiff))?;                    // before or after the pins
    /// pose.set_pins(&[0, 9])?;
    /// pose.drag(&[rest.positions[0], [8.0, 3.0]])?;
    /// assert_eq!(pose.stiffness(), Some(&stiff[..]));
    /// // One weight per triangle, each finite and at least 1.
    /// assert!(matches!(
    ///     pose.set_stiffness(Some(&[1.0; 3])),
    ///     Err(DeformError::StiffnessCount { expected: 54, got: 3 })
    /// ));
    /// let mut bad = stiff.clone();
    /// bad[7] = 0.5;
    /// assert!(matches!(
    ///     pose.set_stiffness(Some(&bad)),
    ///     Err(DeformError::BadStiffness { index: 7, .. })
    /// ));
    /// pose.set_stiffness(None)?;                            // all 1 again
    /// assert_eq!(pose.stiffness(), None);
    /// # Ok::<(), DeformError>(())
    /// ```
    pub fn set_stiffness(&mut self, weights: Option<&[f64]>) -> Result<(), DeformError> {
        if let Some(w) = weights {
            check_stiffness(w, self.frames.len())?;
        }
        let old = self.stiffness.take();
        self.apply_stiffness(weights);
        if self.pins.is_empty() {
            return Ok(());
        }
        let pool = self.pool.clone();
        let pins = self.pins.clone();
        let result = pool.run(|| self.set_pins_here(&pins));
        if result.is_err() {
            // Back to the weights before, and their factors.
            self.apply_stiffness(old.as_deref());
            let _ = pool.run(|| self.set_pins_here(&pins));
        }
        result
    }

    /// [`Deformer::new`] and [`Deformer::set_stiffness`] in one.
    pub fn with_stiffness(mut self, weights: Option<&[f64]>) -> Result<Deformer, DeformError> {
        self.set_stiffness(weights)?;
        Ok(self)
    }

    /// Each triangle's stiffness, as [`Deformer::set_stiffness`] set it (`None`: all 1).
    pub fn stiffness(&self) -> Option<&[f64]> {
        self.stiffness.as_deref()
    }

    /// Stores checked weights and hands them to the method (no factoring).
    fn apply_stiffness(&mut self, weights: Option<&[f64]>) {
        let frames = &self.frames;
        match &mut self.solver {
            Solver::Kvf(s) => s.set_stiffness(frames, weights),
            Solver::Arap(s) => s.set_stiffness(frames, weights),
            Solver::Bounded(s) => s.set_stiffness(frames, weights),
            Solver::Sd(s) => s.set_stiffness(weights),
        }
        self.stiffness = weights.map(<[f64]>::to_vec);
    }

    /// Sets the handles' weight of [`PoseMethod::Kvf`] (and refactors) or [`PoseMethod::Sd`];
    /// the pins stay.
    pub fn set_weight(&mut self, weight: f64) -> Result<(), DeformError> {
        let (pool, frames) = (&self.pool, &self.frames);
        match &mut self.solver {
            Solver::Kvf(s) => pool.run(|| s.set_weight(frames, weight)),
            Solver::Sd(s) => s.set_weight(weight),
            _ => Err(DeformError::NoWeight),
        }
    }

    /// Moves the pins to `targets` (one per pin, in [`Deformer::set_pins`]'s order) and
    /// updates the pose, starting from the previous one. Allocates nothing.
    pub fn drag(&mut self, targets: &[[f64; 2]]) -> Result<DragReport, DeformError> {
        let pool = self.pool.clone();
        pool.run(|| self.drag_here(targets))
    }

    fn drag_here(&mut self, targets: &[[f64; 2]]) -> Result<DragReport, DeformError> {
        if targets.len() != self.pins.len() || self.pins.is_empty() {
            return Err(DeformError::TargetCount {
                pins: self.pins.len(),
                got: targets.len(),
            });
        }
        if let Some(index) = targets
            .iter()
            .position(|t| !(t[0].is_finite() && t[1].is_finite()))
        {
            return Err(DeformError::NonFiniteTarget { index });
        }
        let size = self.diameter;
        self.before.copy_from_slice(&self.positions);
        let result = match &mut self.solver {
            Solver::Kvf(s) => s.drag(&self.frames, targets, &mut self.positions, size),
            Solver::Arap(s) => s.drag(&self.frames, targets, &mut self.positions, size),
            Solver::Bounded(s) => {
                s.drag(&self.frames, targets, &self.pins, &mut self.positions, size)
            }
            Solver::Sd(s) => s.drag(&self.frames, targets, &mut self.positions, size),
        };
        let finite = self.positions.iter().flatten().all(|c| c.is_finite());
        if result.is_err() || !finite {
            // Whatever the method did, the pose stays finite and usable: the one before.
            self.positions.copy_from_slice(&self.before);
        }
        let mut report = result?;
        if !finite {
            report.status = DragStatus::Reverted;
            report.last_change = 0.0;
        }
        self.measure(targets, &mut report);
        Ok(report)
    }

    /// Fills the report's measures of the pose: energy, distortion, flips, pin residual.
    fn measure(&self, targets: &[[f64; 2]], report: &mut DragReport) {
        let (mut energy, mut worst, mut flipped) = (0.0, 1.0f64, 0);
        // For the bounded method, whether a triangle is over its own bound.
        let bounded = match &self.solver {
            Solver::Bounded(s) => Some((s, 1.0 + s.options().tolerance)),
            _ => None,
        };
        let mut over = false;
        for f in 0..self.frames.len() {
            let (q, r) = similarity_parts(self.frames.gradient(f, &self.positions));
            energy += self.frames.area[f] * (2.0 * (q - 1.0) * (q - 1.0) + 2.0 * r * r);
            // σ₁ = q + r, σ₂ = q − r (signed): flipped when σ₂ ≤ 0 (or not a number, which
            // the drag never leaves; counted as flipped rather than hidden).
            if q - r <= 0.0 || (q - r).is_nan() {
                flipped += 1;
            } else {
                let d = (q + r) / (q - r);
                worst = worst.max(d);
                if let Some((s, slack)) = bounded {
                    over |= d > s.bound_of(f) * slack;
                }
            }
        }
        report.energy = energy / self.frames.total_area;
        report.flipped_triangles = flipped;
        report.max_distortion = worst;
        report.pin_residual = self
            .pins
            .iter()
            .zip(targets)
            .map(|(&p, t)| {
                let u = self.positions[p as usize];
                (u[0] - t[0]).hypot(u[1] - t[1])
            })
            .fold(0.0, f64::max);
        if bounded.is_some() {
            report.bound_met = Some(flipped == 0 && !over);
        }
    }

    /// The current pose, one position per vertex.
    pub fn positions(&self) -> &[[f64; 2]] {
        &self.positions
    }

    /// The pins, in [`Deformer::set_pins`]'s order.
    pub fn pins(&self) -> &[u32] {
        &self.pins
    }

    /// The rest shape.
    pub fn rest(&self) -> &PlanarMesh {
        &self.rest
    }

    /// Puts the pose back to the rest shape (pins stay).
    pub fn reset(&mut self) {
        self.positions.copy_from_slice(&self.rest.positions);
        self.forget_targets();
    }

    /// The pose was replaced: KVF's next drag starts from the handles' places.
    fn forget_targets(&mut self) {
        match &mut self.solver {
            Solver::Kvf(s) => s.forget_targets(),
            Solver::Sd(s) => s.forget_targets(),
            _ => {}
        }
    }

    /// Replaces the pose (the next drag starts from it), e.g. an undo; `positions` must
    /// have one point per vertex, all finite.
    pub fn set_positions(&mut self, positions: &[[f64; 2]]) -> Result<(), DeformError> {
        if positions.len() != self.positions.len() {
            return Err(DeformError::PositionCount {
                expected: self.positions.len(),
                got: positions.len(),
            });
        }
        if let Some(index) = positions
            .iter()
            .position(|t| !(t[0].is_finite() && t[1].is_finite()))
        {
            return Err(DeformError::NonFiniteTarget { index });
        }
        self.positions.copy_from_slice(positions);
        self.forget_targets();
        Ok(())
    }
}

/// Checks the mesh (valid and counter-clockwise) and computes its triangles' constants.
fn planar_frames(mesh: &PlanarMesh) -> Result<Frames, DeformError> {
    mesh.validate()?;
    let surface = crate::SurfaceMesh {
        positions: mesh.positions.iter().map(|p| [p[0], p[1], 0.0]).collect(),
        faces: mesh.faces.clone(),
        texcoords: None,
    };
    Ok(Frames::new(&surface).map_err(|face| MeshError::Degenerate {
        face,
        area: mesh.signed_area(&mesh.faces[face]),
    })?)
}

/// Refuses stiffness weights that are not one per triangle (`m`), each finite and >= 1.
fn check_stiffness(weights: &[f64], m: usize) -> Result<(), DeformError> {
    if weights.len() != m {
        return Err(DeformError::StiffnessCount {
            expected: m,
            got: weights.len(),
        });
    }
    match weights.iter().position(|&w| !(w.is_finite() && w >= 1.0)) {
        Some(index) => Err(DeformError::BadStiffness {
            index,
            value: weights[index],
        }),
        None => Ok(()),
    }
}

/// Whether each of `n` vertices is pinned, the pins checked: in range, none twice.
fn pinned_vertices(n: usize, pins: &[u32]) -> Result<Vec<bool>, DeformError> {
    let mut pinned = vec![false; n];
    for (pin, &v) in pins.iter().enumerate() {
        if v as usize >= n {
            return Err(DeformError::PinOutOfRange {
                pin,
                vertex: v,
                n_vertices: n,
            });
        }
        if std::mem::replace(&mut pinned[v as usize], true) {
            return Err(DeformError::PinnedTwice { vertex: v });
        }
    }
    Ok(pinned)
}

/// A Jacobian's similarity and anti-similarity parts `(q, r)`: its singular values are
/// `q + r` and, signed, `q − r` (non-positive when the triangle is flipped).
fn similarity_parts(j: [[f64; 2]; 2]) -> (f64, f64) {
    let [[a, b], [c, d]] = j;
    let (e, h) = (0.5 * (a + d), 0.5 * (c - b));
    let (fq, g) = (0.5 * (a - d), 0.5 * (c + b));
    ((e * e + h * h).sqrt(), (fq * fq + g * g).sqrt())
}

/// A vertex of a piece (faces connected through shared vertices) with no pinned vertex.
fn unpinned_piece(n: usize, faces: &[[u32; 3]], pinned: &[bool]) -> Option<u32> {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    for f in faces {
        for k in 1..3 {
            let (a, b) = (find(&mut parent, f[0]), find(&mut parent, f[k]));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut held = vec![false; n];
    for v in 0..n as u32 {
        if pinned[v as usize] {
            let r = find(&mut parent, v);
            held[r as usize] = true;
        }
    }
    let mut used = vec![false; n];
    for f in faces {
        for &v in f {
            used[v as usize] = true;
        }
    }
    (0..n as u32).find(|&v| used[v as usize] && !held[find(&mut parent, v) as usize])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate;

    /// The figure raises its arm in 20 moves and lowers it again, then settles: with the
    /// strain term the rest shape comes back; without it (the original's flow), it does
    /// not. Returns the largest distance from the rest shape, relative to the size.
    fn away_and_back(strain_feedback: bool) -> f64 {
        let rest = generate::figure(0.01);
        let p = &rest.positions;
        let nearest = |q: [f64; 2]| {
            (0..p.len())
                .min_by(|&a, &b| {
                    let d = |i: usize| (p[i][0] - q[0]).powi(2) + (p[i][1] - q[1]).powi(2);
                    d(a).total_cmp(&d(b))
                })
                .expect("vertices") as u32
        };
        let pins: Vec<u32> = [[-0.45, -1.5], [0.45, -1.5], [0.0, 2.8], [1.72, 1.4]]
            .into_iter()
            .map(nearest)
            .collect();
        let mut pose = Deformer::new(&rest, PoseMethod::kvf()).expect("set up");
        if let Solver::Kvf(kvf) = &mut pose.solver {
            kvf.strain_feedback = strain_feedback;
        }
        pose.set_pins(&pins).expect("pins");
        let start: Vec<[f64; 2]> = pins.iter().map(|&v| p[v as usize]).collect();
        let mut targets = start.clone();
        for k in (1..=20).chain((0..20).rev()) {
            let s = f64::from(k) / 20.0;
            targets[3] = [start[3][0] - 0.7 * s, start[3][1] + 1.3 * s];
            pose.drag(&targets).expect("drag");
        }
        for _ in 0..2000 {
            if pose.drag(&targets).expect("drag").last_change < 1e-13 {
                break;
            }
        }
        pose.positions()
            .iter()
            .zip(p)
            .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
            .fold(0.0, f64::max)
            / rest.diameter()
    }

    #[test]
    fn the_strain_term_is_what_stops_the_drift() {
        let with = away_and_back(true);
        let without = away_and_back(false);
        eprintln!("away and back: {with:e} with the strain term, {without:e} without");
        assert!(with < 1e-9, "{with}");
        assert!(without > 1e-3, "{without}");
    }
}
