//! Blends of any number of keyframes by convex weights on their squared edge lengths.

use bdmorph_vm::Program;

use crate::mesh::PlanarMesh;
use crate::morph::engine::Unwrap;
use crate::morph::solver::{Solver, Structure};
use crate::morph::{Frame, FrameStats, MorphError, MorphOptions};

/// A compiled blend of keyframes (planar meshes with the same triangles).
///
/// One program serves every keyframe, since they share their connectivity. A frame is given
/// by weights, one per keyframe, non-negative and summing to 1: its squared edge lengths are
/// the weighted sums of the keyframes' (convex combinations of squared lengths of Euclidean
/// triangles are again Euclidean), flattened as in a [`Morph`](crate::Morph). The rigid
/// motion blends the anchor vertex's positions linearly and the anchor edge's angle by the
/// weighted mean of the keyframes' angles, each unwrapped to within half a turn of the first
/// keyframe's. Weights slightly outside the simplex (a negative weight) extrapolate while the
/// blended metric stays Euclidean; beyond that the frame fails with
/// [`MorphError::MetricBreaks`], naming the first triangle to break and the weights where it
/// does.
///
/// Weights `(1 - t, t)` of two keyframes give the morph at `t`.
///
/// ```
/// use bdmorph::{generate, Blend};
/// let rest = generate::disk(8, 0.2);
/// let keys = [rest.clone(), generate::bend(&rest, 0.6), generate::twist(&rest, 0.8)];
/// let mut blend = Blend::new(&keys)?;
/// let frame = blend.frame_weights(&[0.2, 0.3, 0.5])?;
/// assert_eq!(frame.stats.flipped_triangles, 0);
/// // Weights (0, 1, 0) give the second keyframe.
/// let frame = blend.frame_weights(&[0.0, 1.0, 0.0])?;
/// let err = frame
///     .positions
///     .iter()
///     .zip(&keys[1].positions)
///     .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
///     .fold(0.0, f64::max);
/// assert!(err < 1e-9 * rest.diameter());
/// # Ok::<(), bdmorph::MorphError>(())
/// ```
pub struct Blend {
    engine: Solver,
}

impl std::fmt::Debug for Blend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Blend")
            .field("engine", &self.engine)
            .finish()
    }
}

impl Blend {
    /// Checks the keyframes (at least two, the same triangles, each valid), compiles their
    /// connectivity and prepares the solver, with default options.
    pub fn new(keyframes: &[PlanarMesh]) -> Result<Blend, MorphError> {
        Blend::with_options(keyframes, MorphOptions::default())
    }

    /// As [`Blend::new`], with options.
    pub fn with_options(
        keyframes: &[PlanarMesh],
        options: MorphOptions,
    ) -> Result<Blend, MorphError> {
        check_count(keyframes)?;
        let engine = Solver::new(keyframes, Unwrap::FromFirst, options)?;
        Ok(Blend { engine })
    }

    /// Prepares a blend from an already compiled program (made for the first keyframe's
    /// connectivity).
    pub fn with_program(
        program: Program,
        keyframes: &[PlanarMesh],
        options: MorphOptions,
    ) -> Result<Blend, MorphError> {
        check_count(keyframes)?;
        let engine = Solver::with_program(program, keyframes, Unwrap::FromFirst, options)?;
        Ok(Blend { engine })
    }

    /// Number of keyframes.
    pub fn keyframes(&self) -> usize {
        self.engine.keyframes()
    }

    /// What the blend found in the keyframes: pieces, holes, inverted triangles.
    pub fn structure(&self) -> &Structure {
        self.engine.structure()
    }

    /// The compiled program (the first piece's, for a mesh of several).
    pub fn program(&self) -> &Program {
        self.engine.program()
    }

    /// The triangles (the first keyframe's).
    pub fn faces(&self) -> &[[u32; 3]] {
        self.engine.faces()
    }

    /// The log scale factors of the last frame, one per interior vertex.
    pub fn scale_factors(&self) -> &[f64] {
        self.engine.scale_factors()
    }

    /// Forgets the solutions kept for warm starts: later frames are predicted only from
    /// frames solved after this call. The work a frame takes depends on the frames solved
    /// before it (a revisited place is free, a nearby one cheap); forgetting makes a
    /// sequence of frames cost the same however it was reached. The results agree either way
    /// to the Newton tolerance.
    pub fn forget_solutions(&mut self) {
        self.engine.forget_solutions();
    }

    /// Computes the frame with `weights` (one per keyframe, summing to 1). Each frame starts
    /// Newton from the previous frame's solution. The positions borrow an internal buffer
    /// reused by the next call. The statistics' `t` is NaN.
    pub fn frame_weights(&mut self, weights: &[f64]) -> Result<Frame<'_>, MorphError> {
        let stats = self.engine.frame(weights, None, None)?;
        Ok(Frame {
            positions: self.engine.positions(),
            distortion: self.engine.distortion(),
            stats,
        })
    }

    /// Computes the frame with `weights` into `out` (one position per vertex). Allocates
    /// nothing; on error `out` is left untouched.
    pub fn frame_weights_into(
        &mut self,
        weights: &[f64],
        out: &mut [[f64; 2]],
    ) -> Result<FrameStats, MorphError> {
        self.engine.frame_into(weights, None, None, out)
    }
}

/// Refuses fewer than two keyframes.
pub(crate) fn check_count(keyframes: &[PlanarMesh]) -> Result<(), MorphError> {
    if keyframes.len() < 2 {
        return Err(MorphError::TooFewKeyframes {
            needed: 2,
            got: keyframes.len(),
        });
    }
    Ok(())
}
