//! The solver shared by [`Morph`](crate::Morph), [`Blend`](crate::Blend) and
//! [`Path`](crate::Path): the keyframes' squared edge lengths, one VM, warm starts, the rigid
//! motion, and the frame's distortion.
//!
//! A frame is an affine combination of the keyframes with weights summing to 1: its metric
//! is the combination of their squared edge lengths, its anchor vertex the combination of
//! their anchor positions, its anchor edge's angle the combination of their (unwrapped)
//! angles. Inside the simplex (non-negative weights) the metric is always Euclidean, since
//! the squared lengths of Euclidean triangles form a convex cone. Outside it the metric is
//! checked triangle by triangle first, and a broken one is named in a typed error.

use std::collections::HashMap;

use bdmorph_vm::{Program, VmError};

use crate::distortion::RestShape;
use crate::mesh::{MeshError, PlanarMesh};

use crate::morph::{FrameAt, FrameStats, MorphError, MorphOptions};

/// Solved frames kept for extrapolating the next start.
const HISTORY: usize = 3;

/// Weights must sum to 1 within this (times the sum of their magnitudes).
const WEIGHT_SUM_TOLERANCE: f64 = 1e-9;

/// How the keyframes' anchor-edge angles are made continuous.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Unwrap {
    /// Each keyframe's angle is the first's plus the shorter turn from it (for blends).
    FromFirst,
    /// Each keyframe's angle is the previous one's plus the shorter turn from it (for
    /// paths: every segment turns the shorter way).
    Cumulative,
}

/// The shorter turn from angle `from` to angle `to`, in (-pi, pi]; within 1e-9 of a half
/// turn it is counter-clockwise (round-off in atan2 must not pick the direction).
pub(crate) fn shorter_turn(from: f64, to: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let mut turn = to - from;
    while turn > PI {
        turn -= TAU;
    }
    while turn <= -PI {
        turn += TAU;
    }
    if (turn.abs() - PI).abs() < 1e-9 {
        turn = PI;
    }
    turn
}

/// A solved frame kept for extrapolating the next start.
#[derive(Clone, Debug)]
struct Solved {
    t: f64,
    u: Vec<f64>,
}

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

/// Checks that every keyframe has the first one's triangles and is valid; on failure, the
/// index of the offending keyframe and why.
pub(crate) fn validate(keyframes: &[PlanarMesh]) -> Result<(), (usize, MeshError)> {
    let first = &keyframes[0];
    first.validate().map_err(|e| (0, e))?;
    for (index, k) in keyframes.iter().enumerate().skip(1) {
        first.validate_pair(k).map_err(|e| (index, e))?;
    }
    Ok(())
}

/// The shared solver.
pub(crate) struct Engine {
    vm: bdmorph_vm::Vm,
    faces: Vec<[u32; 3]>,
    /// The edge slots opposite each face's corners.
    face_slots: Vec<[u32; 3]>,
    /// Squared edge lengths of each keyframe, one per edge slot.
    squared: Vec<Vec<f64>>,
    anchors: Vec<[f64; 2]>,
    angles: Vec<f64>,
    rest: RestShape,
    options: MorphOptions,
    /// The frame's squared lengths.
    metric: Vec<f64>,
    /// The base weights of an extrapolated frame.
    base: Vec<f64>,
    positions: Vec<[f64; 2]>,
    distortion: Vec<f64>,
    /// The last solved frames, newest last; the last `solved` of them are valid.
    history: [Solved; HISTORY],
    solved: usize,
    /// The start `u` of the frame being solved.
    start: Vec<f64>,
}

impl std::fmt::Debug for Engine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Engine")
            .field("keyframes", &self.squared.len())
            .field("vertices", &self.positions.len())
            .field("faces", &self.faces.len())
            .field("vm", &self.vm)
            .finish_non_exhaustive()
    }
}

impl Engine {
    /// Prepares the solver for already validated keyframes (at least one) from a program
    /// compiled for their connectivity.
    pub(crate) fn new(
        program: Program,
        keyframes: &[PlanarMesh],
        unwrap: Unwrap,
        options: MorphOptions,
    ) -> Result<Engine, MorphError> {
        let solver = |source| MorphError::Solver {
            at: FrameAt::Time(0.0),
            source,
            worst: Vec::new(),
        };
        let vm = bdmorph_vm::Vm::new(program).map_err(solver)?;
        let squared = keyframes
            .iter()
            .map(|k| vm.squared_lengths(&k.positions))
            .collect::<Result<Vec<_>, _>>()
            .map_err(solver)?;
        let root = vm.program().embed_root();
        let (p0, p1) = (root.p0 as usize, root.p1 as usize);
        let angle = |m: &PlanarMesh| {
            let (a, b) = (m.positions[p0], m.positions[p1]);
            (b[1] - a[1]).atan2(b[0] - a[0])
        };
        let mut angles: Vec<f64> = Vec::with_capacity(keyframes.len());
        for k in keyframes {
            let a = angle(k);
            angles.push(match (angles.first(), angles.last(), unwrap) {
                (None, ..) => a,
                (Some(&first), _, Unwrap::FromFirst) => first + shorter_turn(first, a),
                (_, Some(&last), Unwrap::Cumulative) => last + shorter_turn(last, a),
                (Some(_), None, _) => unreachable!("first implies last"),
            });
        }
        let slot_of: HashMap<(u32, u32), u32> = vm
            .program()
            .edges()
            .iter()
            .enumerate()
            .map(|(slot, &[a, b])| ((a.min(b), a.max(b)), slot as u32))
            .collect();
        let faces = keyframes[0].faces.clone();
        let face_slots = faces
            .iter()
            .map(|&[a, b, c]| {
                let slot = |x: u32, y: u32| slot_of.get(&(x.min(y), x.max(y))).copied();
                match (slot(b, c), slot(c, a), slot(a, b)) {
                    (Some(x), Some(y), Some(z)) => Ok([x, y, z]),
                    _ => Err(MorphError::ProgramMismatch { face: [a, b, c] }),
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        let n_unknowns = vm.u().len();
        let n_vertices = keyframes[0].positions.len();
        Ok(Engine {
            rest: RestShape::new(&keyframes[0].positions, &faces),
            distortion: vec![1.0; faces.len()],
            metric: vec![0.0; squared[0].len()],
            base: vec![0.0; keyframes.len()],
            anchors: keyframes.iter().map(|k| k.positions[p0]).collect(),
            angles,
            squared,
            faces,
            face_slots,
            options,
            positions: vec![[0.0; 2]; n_vertices],
            history: [(); HISTORY].map(|_| Solved {
                t: 0.0,
                u: vec![0.0; n_unknowns],
            }),
            solved: 0,
            start: vec![0.0; n_unknowns],
            vm,
        })
    }

    /// The compiled program.
    pub(crate) fn program(&self) -> &Program {
        self.vm.program()
    }

    /// The triangles.
    pub(crate) fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// Number of keyframes.
    pub(crate) fn keyframes(&self) -> usize {
        self.squared.len()
    }

    /// The last frame's log scale factors.
    pub(crate) fn scale_factors(&self) -> &[f64] {
        self.vm.u()
    }

    /// The last frame's positions.
    pub(crate) fn positions(&self) -> &[[f64; 2]] {
        &self.positions
    }

    /// The last frame's conformal distortion per triangle, relative to the first keyframe.
    pub(crate) fn distortion(&self) -> &[f64] {
        &self.distortion
    }

    /// Solves the frame with `weights` into the internal buffer.
    pub(crate) fn frame(
        &mut self,
        weights: &[f64],
        time: Option<f64>,
    ) -> Result<FrameStats, MorphError> {
        let mut out = std::mem::take(&mut self.positions);
        let result = self.frame_into(weights, time, &mut out);
        self.positions = out;
        result
    }

    /// Solves the frame with `weights` (one per keyframe, summing to 1) into `out`. `time` is
    /// the frame's place on a one-parameter family (a morph's or path's `t`), which lets warm
    /// starts extrapolate; `None` for a free blend. Allocates nothing unless it fails; on
    /// error `out` is left untouched.
    pub(crate) fn frame_into(
        &mut self,
        weights: &[f64],
        time: Option<f64>,
        out: &mut [[f64; 2]],
    ) -> Result<FrameStats, MorphError> {
        let started = std::time::Instant::now();
        let at = |w: &[f64]| match time {
            Some(t) => FrameAt::Time(t),
            None => FrameAt::Weights(w.to_vec()),
        };
        self.check_weights(weights, time)?;
        if out.len() != self.vm.program().n_vertices() {
            return Err(MorphError::OutputLength {
                expected: self.vm.program().n_vertices(),
                got: out.len(),
            });
        }
        if weights.iter().any(|&w| w < 0.0) {
            self.check_extrapolation(weights, time)?;
        }
        self.metric.fill(0.0);
        for (w, sq) in weights.iter().zip(&self.squared) {
            if *w != 0.0 {
                for (m, s) in self.metric.iter_mut().zip(sq) {
                    *m += w * s;
                }
            }
        }
        let solver = |source, weights: &[f64]| MorphError::Solver {
            at: at(weights),
            source,
            worst: Vec::new(),
        };
        self.vm
            .set_metric(&self.metric)
            .map_err(|e| solver(e, weights))?;
        let extrapolated = self.choose_start(time);
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
                    at: at(weights),
                    iterations,
                    gradient_norm,
                    worst,
                },
                other => MorphError::Solver {
                    at: at(weights),
                    source: other,
                    worst,
                },
            }
        })?;
        let mut anchor = [0.0; 2];
        let mut angle = 0.0;
        for ((w, a), phi) in weights.iter().zip(&self.anchors).zip(&self.angles) {
            if *w != 0.0 {
                anchor[0] += w * a[0];
                anchor[1] += w * a[1];
                angle += w * phi;
            }
        }
        let (s, c) = angle.sin_cos();
        self.vm
            .embed(anchor, [c, s], out)
            .map_err(|e| solver(e, weights))?;
        self.remember(time);
        let max_conformal_distortion = self.rest.distortion_into(out, &mut self.distortion);
        Ok(FrameStats {
            t: time.unwrap_or(f64::NAN),
            newton_iterations: report.iterations,
            factorizations: report.factorizations,
            cg_iterations: report.cg_iterations,
            gradient_norm: report.gradient_norm,
            flipped_triangles: self.vm.count_flipped(out),
            max_conformal_distortion,
            seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// Refuses weights that are not one finite number per keyframe summing to 1.
    fn check_weights(&self, weights: &[f64], time: Option<f64>) -> Result<(), MorphError> {
        if let Some(t) = time {
            if !t.is_finite() {
                return Err(MorphError::TimeNotFinite { t });
            }
        }
        if weights.len() != self.squared.len() {
            return Err(MorphError::WeightCount {
                expected: self.squared.len(),
                got: weights.len(),
            });
        }
        let sum: f64 = weights.iter().sum();
        let size: f64 = weights.iter().map(|w| w.abs()).sum();
        if !size.is_finite() || (sum - 1.0).abs() > WEIGHT_SUM_TOLERANCE * size.max(1.0) {
            return Err(MorphError::WeightSum {
                weights: weights.to_vec(),
                sum,
            });
        }
        Ok(())
    }

    /// For weights outside the simplex: checks that every triangle's blended squared lengths
    /// are those of a Euclidean triangle. When one is not, finds the first triangle to break
    /// on the straight way from the nearest weights inside the simplex (the negative weights
    /// set to zero, the rest rescaled) to `weights`, and where it breaks. Allocates only
    /// when it fails.
    fn check_extrapolation(
        &mut self,
        weights: &[f64],
        time: Option<f64>,
    ) -> Result<(), MorphError> {
        let positive: f64 = weights.iter().filter(|&&w| w > 0.0).sum();
        for (b, &w) in self.base.iter_mut().zip(weights) {
            *b = if w > 0.0 { w / positive } else { 0.0 };
        }
        let blend = |ws: &[f64], slot: u32| -> f64 {
            ws.iter()
                .zip(&self.squared)
                .filter(|(w, _)| **w != 0.0)
                .map(|(w, sq)| w * sq[slot as usize])
                .sum()
        };
        // The first triangle to break: (fraction of the way, face).
        let mut first: Option<(f64, usize)> = None;
        for (face, slots) in self.face_slots.iter().enumerate() {
            let end = slots.map(|s| blend(weights, s));
            if euclidean(end) {
                // The valid set is convex: valid at both ends means valid all the way.
                continue;
            }
            let start = slots.map(|s| blend(&self.base, s));
            let at = |lambda: f64| [0, 1, 2].map(|k| start[k] + lambda * (end[k] - start[k]));
            // Bisection on the validity of the blended lengths: valid at 0, invalid at 1.
            let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if euclidean(at(mid)) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            if first.is_none_or(|(f, _)| hi < f) {
                first = Some((hi, face));
            }
        }
        let Some((lambda, face)) = first else {
            return Ok(());
        };
        let limit: Vec<f64> = self
            .base
            .iter()
            .zip(weights)
            .map(|(b, w)| b + lambda * (w - b))
            .collect();
        Err(MorphError::MetricBreaks {
            at: match time {
                Some(t) => FrameAt::Time(t),
                None => FrameAt::Weights(weights.to_vec()),
            },
            face,
            vertices: self.faces[face],
            limit: FrameAt::Weights(limit),
        })
    }

    /// Sets the VM's start `u` for a frame at `time`; true when it was extrapolated.
    fn choose_start(&mut self, time: Option<f64>) -> bool {
        if !self.options.warm_start {
            self.vm.reset_u();
            return false;
        }
        if self.solved == 0 {
            return false;
        }
        let last = &self.history[HISTORY - 1];
        let weights = match time {
            Some(t) if self.options.extrapolate && self.solved >= 2 => {
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
            }
            _ => None,
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

    /// Records the VM's solution as the newest solved frame. Allocates nothing. A frame
    /// without a time (a free blend) leaves only itself to start from.
    fn remember(&mut self, time: Option<f64>) {
        let Some(t) = time else {
            self.history[HISTORY - 1].u.copy_from_slice(self.vm.u());
            self.history[HISTORY - 1].t = 0.0;
            self.solved = 1;
            return;
        };
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

/// Whether squared lengths `q` are those of a non-degenerate Euclidean triangle: all
/// positive and Heron's `16 A² = 2 (q0 q1 + q1 q2 + q2 q0) − (q0² + q1² + q2²)` positive.
fn euclidean(q: [f64; 3]) -> bool {
    let [a, b, c] = q;
    let heron = 2.0 * (a * b + b * c + c * a) - (a * a + b * b + c * c);
    a > 0.0 && b > 0.0 && c > 0.0 && heron > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heron_test_agrees_with_the_triangle_inequality() {
        let cases = [
            ([3.0, 4.0, 5.0], true),
            ([1.0, 1.0, 1.0], true),
            ([1.0, 2.0, 3.0], false),
            ([1.0, 1.0, 2.5], false),
            ([1.0, 1.0, 1.999], true),
        ];
        for (l, valid) in cases {
            assert_eq!(euclidean(l.map(|x: f64| x * x)), valid, "{l:?}");
        }
        assert!(!euclidean([-1.0, -1.0, -1.0]));
        assert!(!euclidean([f64::NAN, 1.0, 1.0]));
    }

    #[test]
    fn shorter_turn_picks_the_short_way_and_counter_clockwise_half_turns() {
        use std::f64::consts::PI;
        assert!((shorter_turn(0.0, 0.5) - 0.5).abs() < 1e-15);
        assert!((shorter_turn(3.0, -3.0) - (2.0 * PI - 6.0)).abs() < 1e-12);
        assert_eq!(shorter_turn(0.0, -PI), PI);
        assert_eq!(shorter_turn(0.0, PI), PI);
    }
}
