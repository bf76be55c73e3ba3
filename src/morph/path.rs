//! Paths through keyframes: segment by segment, with durations and easing curves.

use bdmorph_vm::Program;

use crate::mesh::PlanarMesh;
use crate::morph::blend::check_count;
use crate::morph::engine::{Line, Unwrap};
use crate::morph::solver::{Solver, Structure};
use crate::morph::{Frame, FrameStats, MorphError, MorphOptions};

/// How a segment's local time maps to its blend weight: `t = easing(s)` for `s` in [0, 1],
/// with `easing(0) = 0` and `easing(1) = 1` exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Easing {
    /// `t = s`.
    Linear,
    /// Slow at both ends: CSS's `ease-in-out`, the cubic Bézier `(0.42, 0, 0.58, 1)`.
    EaseInOut,
    /// A CSS-style cubic Bézier through `(0, 0)`, `(x1, y1)`, `(x2, y2)`, `(1, 1)`, as
    /// `[x1, y1, x2, y2]`; `x1` and `x2` in [0, 1] so that time runs forward. `y` outside
    /// [0, 1] overshoots the keyframes (which extrapolates the morph).
    CubicBezier([f64; 4]),
}

/// Why an easing could not be made or parsed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EasingError {
    /// A Bézier control point's x outside [0, 1] or a non-finite coordinate.
    #[error(
        "cubic-bezier({x1}, {y1}, {x2}, {y2}): x1 and x2 must be in [0, 1] and all four finite"
    )]
    BadControlPoints {
        /// First control point.
        x1: f64,
        /// First control point.
        y1: f64,
        /// Second control point.
        x2: f64,
        /// Second control point.
        y2: f64,
    },
    /// Text that names no easing.
    #[error("unknown easing '{0}' (use linear, ease-in-out or cubic-bezier(x1,y1,x2,y2))")]
    Unknown(String),
}

impl Easing {
    /// A cubic Bézier easing, checked.
    pub fn cubic_bezier(x1: f64, y1: f64, x2: f64, y2: f64) -> Result<Easing, EasingError> {
        let ok = [x1, y1, x2, y2].iter().all(|v| v.is_finite())
            && (0.0..=1.0).contains(&x1)
            && (0.0..=1.0).contains(&x2);
        if ok {
            Ok(Easing::CubicBezier([x1, y1, x2, y2]))
        } else {
            Err(EasingError::BadControlPoints { x1, y1, x2, y2 })
        }
    }

    /// The weight at local time `s` (clamped to [0, 1]).
    ///
    /// ```
    /// use bdmorph::path::Easing;
    /// assert_eq!(Easing::EaseInOut.apply(0.0), 0.0);
    /// assert_eq!(Easing::EaseInOut.apply(1.0), 1.0);
    /// assert!((Easing::EaseInOut.apply(0.5) - 0.5).abs() < 1e-12);
    /// assert!(Easing::EaseInOut.apply(0.1) < 0.1);
    /// ```
    pub fn apply(&self, s: f64) -> f64 {
        if s.is_nan() || s <= 0.0 {
            return 0.0;
        }
        if s >= 1.0 {
            return 1.0;
        }
        let [x1, y1, x2, y2] = match *self {
            Easing::Linear => return s,
            Easing::EaseInOut => [0.42, 0.0, 0.58, 1.0],
            Easing::CubicBezier(c) => c,
        };
        let bezier = |a: f64, b: f64, u: f64| {
            let v = 1.0 - u;
            3.0 * v * v * u * a + 3.0 * v * u * u * b + u * u * u
        };
        // x(u) is non-decreasing for x1, x2 in [0, 1]: bisect for x(u) = s.
        let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if bezier(x1, x2, mid) < s {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        bezier(y1, y2, 0.5 * (lo + hi))
    }
}

impl std::str::FromStr for Easing {
    type Err = EasingError;
    /// `linear`, `ease-in-out`, or `cubic-bezier(x1,y1,x2,y2)` (also `cubic-bezier:x1,y1,x2,y2`).
    fn from_str(text: &str) -> Result<Easing, EasingError> {
        let t = text.trim().to_ascii_lowercase();
        match t.as_str() {
            "linear" => return Ok(Easing::Linear),
            "ease-in-out" => return Ok(Easing::EaseInOut),
            _ => {}
        }
        let unknown = || EasingError::Unknown(text.to_owned());
        let args = t
            .strip_prefix("cubic-bezier")
            .map(str::trim)
            .and_then(|r| {
                r.strip_prefix('(')
                    .and_then(|r| r.strip_suffix(')'))
                    .or_else(|| r.strip_prefix(':'))
            })
            .ok_or_else(unknown)?;
        let v: Vec<f64> = args
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| unknown())?;
        match v[..] {
            [x1, y1, x2, y2] => Easing::cubic_bezier(x1, y1, x2, y2),
            _ => Err(unknown()),
        }
    }
}

/// Options of a [`KeyframePath`].
#[derive(Clone, Debug, PartialEq, Default)]
#[non_exhaustive]
pub struct PathOptions {
    /// The solver's options.
    pub morph: MorphOptions,
    /// Relative durations of the segments (one per segment, positive); empty for equal ones.
    pub durations: Vec<f64>,
    /// Easing of the segments: empty for linear, one for every segment, or one per segment.
    pub easings: Vec<Easing>,
}

impl PathOptions {
    /// Sets the solver's options.
    pub fn with_morph(mut self, morph: MorphOptions) -> Self {
        self.morph = morph;
        self
    }
    /// Sets the relative durations of the segments.
    pub fn with_durations(mut self, durations: Vec<f64>) -> Self {
        self.durations = durations;
        self
    }
    /// Uses one easing for every segment.
    pub fn with_easing(mut self, easing: Easing) -> Self {
        self.easings = vec![easing];
        self
    }
    /// Sets one easing per segment (or one for all).
    pub fn with_easings(mut self, easings: Vec<Easing>) -> Self {
        self.easings = easings;
        self
    }
    /// Bounds every frame by `budget` ([`MorphOptions::budget`] of [`PathOptions::morph`]).
    pub fn with_budget(mut self, budget: crate::Budget) -> Self {
        self.morph.budget = budget;
        self
    }
}

/// A compiled path through keyframes `K0, K1, ..., Kn` (planar meshes with the same
/// triangles): global time `t` in [0, 1] walks the segments in order, keyframe `k` reached at
/// `t = k / n` (or at the sum of the first `k` durations over their total). Within a segment
/// the frame is the morph between its two keyframes at the eased local time, so the path
/// passes exactly through every keyframe. Each segment turns the anchor edge the shorter way
/// from one keyframe to the next. Warm starts (extrapolated in `t`) carry across segment
/// boundaries.
///
/// ```
/// use bdmorph::{generate, path::{Easing, KeyframePath, PathOptions}};
/// let rest = generate::disk(8, 0.2);
/// let keys = [rest.clone(), generate::bend(&rest, 0.6), generate::twist(&rest, 0.8)];
/// let options = PathOptions::default().with_easing(Easing::EaseInOut);
/// let mut path = KeyframePath::with_options(&keys, options)?;
/// for i in 0..=8 {
///     let frame = path.frame(i as f64 / 8.0)?;
///     assert_eq!(frame.stats.flipped_triangles, 0);
/// }
/// assert_eq!(path.keyframe_times(), &[0.0, 0.5, 1.0]);
/// # Ok::<(), bdmorph::MorphError>(())
/// ```
pub struct KeyframePath {
    engine: Solver,
    /// When each keyframe is reached: 0 first, 1 last.
    knots: Vec<f64>,
    easings: Vec<Easing>,
    weights: Vec<f64>,
}

impl std::fmt::Debug for KeyframePath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("KeyframePath")
            .field("knots", &self.knots)
            .field("easings", &self.easings)
            .field("engine", &self.engine)
            .finish()
    }
}

impl KeyframePath {
    /// Checks the keyframes (at least two), compiles them and prepares the solver, with equal
    /// durations and linear segments.
    pub fn new(keyframes: &[PlanarMesh]) -> Result<KeyframePath, MorphError> {
        KeyframePath::with_options(keyframes, PathOptions::default())
    }

    /// As [`KeyframePath::new`], with options.
    pub fn with_options(
        keyframes: &[PlanarMesh],
        options: PathOptions,
    ) -> Result<KeyframePath, MorphError> {
        check_path_options(keyframes.len(), &options)?;
        check_count(keyframes)?;
        let engine = Solver::new(keyframes, Unwrap::Cumulative, options.morph.clone())?;
        Ok(KeyframePath::assemble(engine, keyframes.len(), &options))
    }

    /// Prepares a path from an already compiled program (made for the first keyframe's
    /// connectivity).
    pub fn with_program(
        program: Program,
        keyframes: &[PlanarMesh],
        options: PathOptions,
    ) -> Result<KeyframePath, MorphError> {
        check_path_options(keyframes.len(), &options)?;
        check_count(keyframes)?;
        let engine = Solver::with_program(
            program,
            keyframes,
            Unwrap::Cumulative,
            options.morph.clone(),
        )?;
        Ok(KeyframePath::assemble(engine, keyframes.len(), &options))
    }

    /// The path's knots and easings around its solver.
    fn assemble(engine: Solver, keyframes: usize, options: &PathOptions) -> KeyframePath {
        let segments = keyframes - 1;
        let durations = if options.durations.is_empty() {
            vec![1.0; segments]
        } else {
            options.durations.clone()
        };
        let total: f64 = durations.iter().sum();
        let mut knots = Vec::with_capacity(keyframes);
        let mut acc = 0.0;
        knots.push(0.0);
        for d in &durations[..segments - 1] {
            acc += d;
            knots.push(acc / total);
        }
        knots.push(1.0);
        let easings = match options.easings.len() {
            0 => vec![Easing::Linear; segments],
            1 => vec![options.easings[0]; segments],
            _ => options.easings.clone(),
        };
        KeyframePath {
            weights: vec![0.0; keyframes],
            engine,
            knots,
            easings,
        }
    }

    /// What the path found in the keyframes: pieces, holes, inverted triangles.
    pub fn structure(&self) -> &Structure {
        self.engine.structure()
    }

    /// Forgets the solutions kept for warm starts: later frames are predicted only from
    /// frames solved after this call. The work a frame takes depends on the frames solved
    /// before it (a revisited place is free, a nearby one cheap); forgetting makes a
    /// sequence of frames cost the same however it was reached. The results agree either way
    /// to the Newton tolerance.
    pub fn forget_solutions(&mut self) {
        self.engine.forget_solutions();
    }

    /// When each keyframe is reached, in [0, 1]: first 0, last 1.
    pub fn keyframe_times(&self) -> &[f64] {
        &self.knots
    }

    /// The compiled program.
    pub fn program(&self) -> &Program {
        self.engine.program()
    }

    /// The triangles (the first keyframe's).
    pub fn faces(&self) -> &[[u32; 3]] {
        self.engine.faces()
    }

    /// The segment and its eased blend weight at global time `t` in [0, 1]: the frame is
    /// keyframe `k` times `1 - w` plus keyframe `k + 1` times `w`.
    pub fn segment_at(&self, t: f64) -> Result<(usize, f64), MorphError> {
        if !t.is_finite() {
            return Err(MorphError::TimeNotFinite { t });
        }
        if !(0.0..=1.0).contains(&t) {
            return Err(MorphError::TimeOutOfRange { t });
        }
        let segments = self.knots.len() - 1;
        // The last knot at or before t, as a segment index.
        let k = self.knots[1..segments].partition_point(|&knot| knot <= t);
        let (a, b) = (self.knots[k], self.knots[k + 1]);
        let local = ((t - a) / (b - a)).clamp(0.0, 1.0);
        Ok((k, self.easings[k].apply(local)))
    }

    /// Computes the frame at global time `t` in [0, 1]. The positions borrow an internal
    /// buffer reused by the next call.
    pub fn frame(&mut self, t: f64) -> Result<Frame<'_>, MorphError> {
        let line = self.set_weights(t)?;
        let stats = self.engine.frame(&self.weights, Some(t), Some(line))?;
        Ok(Frame {
            positions: self.engine.positions(),
            distortion: self.engine.distortion(),
            stats,
        })
    }

    /// Computes the frame at `t` into `out` (one position per vertex). Allocates nothing; on
    /// error `out` is left untouched.
    pub fn frame_into(&mut self, t: f64, out: &mut [[f64; 2]]) -> Result<FrameStats, MorphError> {
        let line = self.set_weights(t)?;
        self.engine
            .frame_into(&self.weights, Some(t), Some(line), out)
    }

    /// Sets the weights of global time `t`; returns the frame's place on its segment's line.
    fn set_weights(&mut self, t: f64) -> Result<Line, MorphError> {
        let (k, w) = self.segment_at(t)?;
        self.weights.fill(0.0);
        self.weights[k] = 1.0 - w;
        self.weights[k + 1] = w;
        Ok(Line {
            from: k,
            to: k + 1,
            s: w,
        })
    }
}

/// Checks durations and easings against the number of segments.
fn check_path_options(keyframes: usize, options: &PathOptions) -> Result<(), MorphError> {
    let segments = keyframes.saturating_sub(1);
    if !options.durations.is_empty() {
        if options.durations.len() != segments {
            return Err(MorphError::SegmentCount {
                what: "durations",
                expected: segments,
                got: options.durations.len(),
            });
        }
        if let Some(segment) = options
            .durations
            .iter()
            .position(|d| !(d.is_finite() && *d > 0.0))
        {
            return Err(MorphError::BadDuration {
                segment,
                duration: options.durations[segment],
            });
        }
    }
    if options.easings.len() > 1 && options.easings.len() != segments {
        return Err(MorphError::SegmentCount {
            what: "easings",
            expected: segments,
            got: options.easings.len(),
        });
    }
    Ok(())
}

/// The former name of [`KeyframePath`], which shadowed `std::path::Path` when both were
/// imported.
#[deprecated(
    since = "0.2.0",
    note = "renamed `KeyframePath` (it shadowed `std::path::Path`)"
)]
pub type Path = KeyframePath;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn easings_parse_and_hit_their_ends() {
        for text in [
            "linear",
            "ease-in-out",
            "cubic-bezier(0.1, 0.7, 1.0, 0.1)",
            "cubic-bezier:0,0,1,1",
        ] {
            let e: Easing = text.parse().expect(text);
            assert_eq!(e.apply(0.0), 0.0, "{text}");
            assert_eq!(e.apply(1.0), 1.0, "{text}");
        }
        assert!("cubic-bezier(1.5,0,0,1)".parse::<Easing>().is_err());
        assert!("cubic-bezier(0,0,1)".parse::<Easing>().is_err());
        assert!("bouncy".parse::<Easing>().is_err());
    }

    #[test]
    fn bezier_matches_its_parametric_form() {
        // cubic-bezier(0, 0, 1, 1) has x(u) = 3u^2 - 2u^3 = y(u): the identity.
        let e = Easing::cubic_bezier(0.0, 0.0, 1.0, 1.0).unwrap();
        for i in 0..=10 {
            let s = f64::from(i) / 10.0;
            assert!((e.apply(s) - s).abs() < 1e-12, "{s}");
        }
        // Ease-in-out is symmetric: e(s) + e(1 - s) = 1, and monotone.
        let mut last = 0.0;
        for i in 0..=100 {
            let s = f64::from(i) / 100.0;
            let v = Easing::EaseInOut.apply(s);
            assert!(v >= last);
            assert!((v + Easing::EaseInOut.apply(1.0 - s) - 1.0).abs() < 1e-12);
            last = v;
        }
        // An overshooting curve leaves [0, 1].
        let over = Easing::cubic_bezier(0.3, 1.6, 0.7, 1.6).unwrap();
        assert!(over.apply(0.7) > 1.0);
    }
}
