//! The solver shared by [`Morph`](crate::Morph), [`Blend`](crate::Blend) and
//! [`KeyframePath`](crate::KeyframePath): the keyframes' squared edge lengths, one VM, warm starts, the rigid
//! motion, and the frame's distortion.
//!
//! A frame is an affine combination of the keyframes with weights summing to 1: its metric
//! is the combination of their squared edge lengths, its anchor vertex the combination of
//! their anchor positions, its anchor edge's angle the combination of their (unwrapped)
//! angles. Inside the simplex (non-negative weights) the metric is always Euclidean, since
//! the squared lengths of Euclidean triangles form a convex cone. Outside it the metric is
//! checked triangle by triangle first, and a broken one is named in a typed error.

use bdmorph_vm::{NewtonOptions, Program, VmError};

use crate::distortion::RestShape;
use crate::mesh::PlanarMesh;
use crate::morph::closure::{Closure, ClosureError, ClosureReport};
use crate::morph::placement::{Fit, Placement};
use crate::morph::predictor::{predictor_weights, useful_nodes, NODES};

use crate::morph::{FrameAt, FrameStats, MorphError, MorphOptions};
use bdmorph_vm::FactorPrecision;

/// Solved frames kept for extrapolating the next start.
const HISTORY: usize = NODES;

/// Solutions a prediction with tangents interpolates (a quintic through three and theirs).
const TANGENT_NODES: usize = 3;

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

/// Where a frame lies on the line of metrics through two keyframes: weight `1 - s` on `from`
/// and `s` on `to` (a morph's `t`, or a path segment's eased weight). Frames on one line
/// share a smooth solution `u(s)`, which the warm starts predict.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Line {
    /// The keyframe at `s = 0`.
    pub from: usize,
    /// The keyframe at `s = 1`.
    pub to: usize,
    /// The place on the line.
    pub s: f64,
}

/// A solved frame kept for predicting the next start.
#[derive(Clone, Debug)]
struct Solved {
    /// The line's keyframes (`(usize::MAX, usize::MAX)` for a free blend).
    line: (usize, usize),
    s: f64,
    u: Vec<f64>,
    /// `du/ds` at the solution, when `has_du` (empty unless the options predict with tangents).
    du: Vec<f64>,
    has_du: bool,
    /// The free holes' closing unknowns at the solution (empty without free holes).
    a: Vec<f64>,
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
    /// The last solved frames, newest last; the last `solved` of them are valid, and no two
    /// of them on one line share `s`.
    history: [Solved; HISTORY],
    solved: usize,
    /// The line of the newest solution while the VM still holds its evaluation, so that the
    /// next frame on that line can take its tangent first.
    pending_tangent: Option<(usize, usize)>,
    /// The line's rate of change of squared lengths (one per edge slot).
    rate: Vec<f64>,
    /// The start `u` of the frame being solved.
    start: Vec<f64>,
    /// The free holes and their closing ([`crate::morph::closure`]); `None` without any.
    closure: Option<Closure>,
    /// The start of the closing unknowns of the frame being solved.
    a_start: Vec<f64>,
    /// Faces that carry a metric (the user's, then hidden ones filling holes); the rest are
    /// inert, filling free holes.
    real_faces: usize,
    /// [`Placement::Fit`]'s data; `None` with [`Placement::Anchor`].
    fit: Option<Fit>,
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

/// The program's edge slots by their ends: per vertex, its neighbours of higher index and the
/// slot of the edge to each (compressed rows, a handful per vertex, searched linearly). At a
/// million vertices this takes a tenth of the time a hash map of the three million edges took.
struct SlotLookup {
    start: Vec<u32>,
    entries: Vec<(u32, u32)>,
}

impl SlotLookup {
    fn new(n_vertices: usize, edges: &[[u32; 2]]) -> SlotLookup {
        let mut start = vec![0u32; n_vertices + 1];
        for &[a, b] in edges {
            start[a.min(b) as usize + 1] += 1;
        }
        for v in 0..n_vertices {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut entries = vec![(0u32, 0u32); edges.len()];
        for (slot, &[a, b]) in edges.iter().enumerate() {
            let at = &mut fill[a.min(b) as usize];
            entries[*at as usize] = (a.max(b), slot as u32);
            *at += 1;
        }
        SlotLookup { start, entries }
    }

    /// The slot of the edge between `x` and `y`, if the program has one.
    fn get(&self, x: u32, y: u32) -> Option<u32> {
        let (lo, hi) = (x.min(y) as usize, x.max(y));
        let range = *self.start.get(lo)? as usize..*self.start.get(lo + 1)? as usize;
        self.entries[range].iter().find(|e| e.0 == hi).map(|e| e.1)
    }
}

impl Engine {
    /// Prepares the solver for already validated keyframes (at least one) from a program
    /// compiled for their connectivity. The first `visible` faces are the user's (their
    /// distortion is measured); any after them are hidden ones filling holes.
    ///
    /// Faces from `real_faces` on are inert (the program was compiled with them so), filling
    /// the free holes `free` (each a loop of the piece's vertices in the order its boundary
    /// runs), which are closed by [`Closure`].
    pub(crate) fn new(
        program: Program,
        keyframes: &[PlanarMesh],
        visible: usize,
        real_faces: usize,
        free: &[Vec<u32>],
        unwrap: Unwrap,
        mut options: MorphOptions,
    ) -> Result<Engine, MorphError> {
        if !free.is_empty() {
            // A tangent would miss the targets' change along the line: predictions use values.
            options.tangents = false;
        }
        let solver = |source| MorphError::Solver {
            at: FrameAt::Time(0.0),
            source,
            worst: Vec::new(),
        };
        let mut vm = bdmorph_vm::Vm::new(program).map_err(solver)?;
        vm.set_factor_precision(options.factor_precision);
        if !options.budget.is_unlimited() {
            let budget = options.budget.clone();
            vm.set_interrupt(Some(std::sync::Arc::new(move || budget.check().is_err())));
        }
        let mut squared = keyframes
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
        let slots = SlotLookup::new(vm.program().n_vertices(), vm.program().edges());
        let faces = keyframes[0].faces.clone();
        let face_slots = faces
            .iter()
            .map(
                |&[a, b, c]| match (slots.get(b, c), slots.get(c, a), slots.get(a, b)) {
                    (Some(x), Some(y), Some(z)) => Ok([x, y, z]),
                    _ => Err(MorphError::ProgramMismatch { face: [a, b, c] }),
                },
            )
            .collect::<Result<Vec<_>, _>>()?;
        let real_faces = real_faces.min(faces.len());
        let closure = if free.is_empty() {
            None
        } else {
            // Edges of inert triangles alone are never read: one length in every keyframe
            // keeps the metric valid where two hole vertices meet in a keyframe.
            let mut read = vec![false; squared[0].len()];
            for f in &face_slots[..real_faces] {
                f.iter().for_each(|&e| read[e as usize] = true);
            }
            for sq in &mut squared {
                for (v, _) in sq.iter_mut().zip(&read).filter(|(_, r)| !**r) {
                    *v = 1.0;
                }
            }
            Some(Closure::new(&mut vm, free, &squared, |a, b| slots.get(a, b)).map_err(solver)?)
        };
        let n_closing = closure.as_ref().map_or(0, |c| c.a.len());
        let fit = (options.placement == Placement::Fit).then(|| {
            Fit::new(
                keyframes.iter().map(|k| k.positions.clone()).collect(),
                &faces[..visible.min(faces.len())],
            )
        });
        let n_unknowns = vm.u().len();
        let n_vertices = keyframes[0].positions.len();
        let n_slots = squared[0].len();
        let tangents = options.tangents;
        Ok(Engine {
            rest: RestShape::new(&keyframes[0].positions, &faces[..visible.min(faces.len())]),
            distortion: vec![1.0; visible.min(faces.len())],
            metric: vec![0.0; n_slots],
            base: vec![0.0; keyframes.len()],
            anchors: keyframes.iter().map(|k| k.positions[p0]).collect(),
            angles,
            squared,
            faces,
            face_slots,
            options,
            positions: vec![[0.0; 2]; n_vertices],
            history: [(); HISTORY].map(|_| Solved {
                line: (usize::MAX, usize::MAX),
                s: 0.0,
                u: vec![0.0; n_unknowns],
                // Tangents only where they are predicted with.
                du: if tangents {
                    vec![0.0; n_unknowns]
                } else {
                    Vec::new()
                },
                has_du: false,
                a: vec![0.0; n_closing],
            }),
            solved: 0,
            pending_tangent: None,
            rate: vec![0.0; n_slots],
            start: vec![0.0; n_unknowns],
            closure,
            a_start: vec![0.0; n_closing],
            real_faces,
            fit,
            vm,
        })
    }

    /// A vertex (the piece's numbering) on each free hole.
    pub(crate) fn free_holes(&self) -> Vec<u32> {
        self.closure
            .as_ref()
            .map_or_else(Vec::new, |c| c.hole_vertices().collect())
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

    /// How the solver's numeric factor is stored now (see [`bdmorph_vm::Vm::factor_precision`]).
    pub(crate) fn factor_precision(&self) -> FactorPrecision {
        self.vm.factor_precision()
    }

    /// The last frame's positions.
    pub(crate) fn positions(&self) -> &[[f64; 2]] {
        &self.positions
    }

    /// The last frame's conformal distortion per visible triangle, relative to the first
    /// keyframe.
    pub(crate) fn distortion(&self) -> &[f64] {
        &self.distortion
    }

    /// Forgets every solved frame: the next frame starts from the current `u` as it is (the
    /// last solution), and the ones after it predict only from frames solved after this.
    pub(crate) fn forget_solutions(&mut self) {
        self.solved = 0;
        self.pending_tangent = None;
    }

    /// Solves the frame with `weights` into the internal buffer.
    pub(crate) fn frame(
        &mut self,
        weights: &[f64],
        time: Option<f64>,
        line: Option<Line>,
    ) -> Result<FrameStats, MorphError> {
        let mut out = std::mem::take(&mut self.positions);
        let result = self.frame_into(weights, time, line, &mut out);
        self.positions = out;
        result
    }

    /// Solves the frame with `weights` (one per keyframe, summing to 1) into `out`. `time` is
    /// the frame's time as reported (a morph's or path's `t`; `None` for a free blend), `line`
    /// its place on the line through two keyframes that its weights lie on (which lets warm
    /// starts predict). Allocates nothing unless it fails; on error `out` is left untouched.
    pub(crate) fn frame_into(
        &mut self,
        weights: &[f64],
        time: Option<f64>,
        line: Option<Line>,
        out: &mut [[f64; 2]],
    ) -> Result<FrameStats, MorphError> {
        if self.vm.threads() > 1 && rayon::current_thread_index().is_none() {
            // From outside rayon's pool each split piece of work would wait for its threads
            // to wake (a 5K-vertex frame took 1.3-1.6x as long): the whole frame goes to the
            // pool once.
            return rayon::scope(|_| self.frame_here(weights, time, line, out));
        }
        self.frame_here(weights, time, line, out)
    }

    /// [`Engine::frame_into`] on this thread.
    fn frame_here(
        &mut self,
        weights: &[f64],
        time: Option<f64>,
        line: Option<Line>,
        out: &mut [[f64; 2]],
    ) -> Result<FrameStats, MorphError> {
        let started = std::time::Instant::now();
        let at = |w: &[f64]| match time {
            Some(t) => FrameAt::Time(t),
            None => FrameAt::Weights(w.to_vec()),
        };
        self.options.budget.check()?;
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
        // The previous frame's tangent, while the VM still holds its solution's evaluation.
        let (tangent_cg, tangent_factorizations) = self.take_tangent(line);
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
        let extrapolated = self.choose_start(line);
        // This frame's tangent will be taken with the factor Newton leaves.
        let newton = self
            .options
            .newton
            .with_tangent_follows(line.is_some() && self.predicts_with_tangents());
        let mut result = self.flatten(weights, &newton);
        if result.is_err() && extrapolated {
            // An extrapolated start is a guess: fall back to the last solution before failing.
            self.vm
                .set_u(&self.history[HISTORY - 1].u)
                .expect("history has one value per unknown");
            self.a_start.copy_from_slice(&self.history[HISTORY - 1].a);
            result = self.flatten(weights, &newton);
        }
        let report = result.map_err(|e| {
            let worst = self.vm.failure_triangles().to_vec();
            match e {
                ClosureError::Vm(VmError::NotConverged {
                    iterations,
                    gradient_norm,
                }) => MorphError::NotConverged {
                    at: at(weights),
                    iterations,
                    gradient_norm,
                    worst,
                },
                ClosureError::Vm(VmError::Interrupted { .. }) => MorphError::Stopped(
                    self.options
                        .budget
                        .check()
                        .err()
                        .unwrap_or(crate::Stopped::Cancelled),
                ),
                ClosureError::Vm(other) => MorphError::Solver {
                    at: at(weights),
                    source: other,
                    worst,
                },
                ClosureError::Open { vertex, gap } => MorphError::HoleOpen {
                    at: at(weights),
                    vertex,
                    gap,
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
        if let Some(fit) = &mut self.fit {
            fit.place(weights, line.map(|l| (l.from, l.to)), out);
        }
        self.remember(line);
        let max_conformal_distortion = self.rest.distortion_into(out, &mut self.distortion);
        Ok(FrameStats {
            t: time.unwrap_or(f64::NAN),
            newton_iterations: report.iterations,
            factorizations: report.factorizations + tangent_factorizations,
            cg_iterations: report.cg_iterations + tangent_cg,
            gradient_norm: report.gradient_norm,
            flipped_triangles: self.vm.count_flipped(out),
            max_conformal_distortion,
            seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// Flattens the frame's metric from the start chosen: Newton's method, and with free
    /// holes, their closing around it.
    fn flatten(
        &mut self,
        weights: &[f64],
        newton: &NewtonOptions,
    ) -> Result<ClosureReport, ClosureError> {
        match &mut self.closure {
            Some(closure) => {
                closure.solve(&mut self.vm, weights, &self.metric, &self.a_start, newton)
            }
            None => {
                let r = self.vm.newton(newton).map_err(ClosureError::Vm)?;
                Ok(ClosureReport {
                    iterations: r.iterations,
                    factorizations: r.factorizations,
                    cg_iterations: r.cg_iterations,
                    gradient_norm: r.gradient_norm,
                    steps: 0,
                })
            }
        }
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
    pub(crate) fn check_extrapolation(
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
        // Inert faces (filling free holes) have no metric to break.
        for (face, slots) in self.face_slots[..self.real_faces].iter().enumerate() {
            let end = slots.map(|s| blend(weights, s));
            if euclidean(end) {
                // The valid set is convex: valid at both ends means valid all the way.
                continue;
            }
            let start = slots.map(|s| blend(&self.base, s));
            let at = |lambda: f64| [0, 1, 2].map(|k| start[k] + lambda * (end[k] - start[k]));
            // Valid at 0, invalid at 1. Far extrapolations (t = 1e20) break at a tiny fraction
            // of the way: the break is first bracketed by halving, so that the bisection
            // below finds it to 60 bits relative to where it is, not to the whole way.
            let mut hi = 1.0_f64;
            while hi > f64::MIN_POSITIVE && !euclidean(at(0.5 * hi)) {
                hi *= 0.5;
            }
            let mut lo = 0.5 * hi;
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

    /// Whether starts are predicted with tangents.
    fn predicts_with_tangents(&self) -> bool {
        self.options.warm_start && self.options.extrapolate && self.options.tangents
    }

    /// When the newest solution's evaluation is still in the VM and `line` is its line (and
    /// tangents are on), computes its tangent `du/ds` into the history: the frame after it
    /// then starts from a Hermite prediction. Returns the conjugate-gradient iterations and
    /// factorisations that took. A failed tangent only leaves the prediction without it.
    fn take_tangent(&mut self, line: Option<Line>) -> (u32, u32) {
        let pending = self.pending_tangent.take();
        let Some(line) = line else { return (0, 0) };
        if !self.predicts_with_tangents()
            || pending != Some((line.from, line.to))
            || self.solved == 0
        {
            return (0, 0);
        }
        let (from, to) = (&self.squared[line.from], &self.squared[line.to]);
        for ((r, a), b) in self.rate.iter_mut().zip(from).zip(to) {
            *r = b - a;
        }
        let newest = &mut self.history[HISTORY - 1];
        match self.vm.tangent(&self.rate) {
            Ok(report) => {
                newest.du.copy_from_slice(self.vm.tangent_values());
                newest.has_du = newest.du.iter().all(|d| d.is_finite());
                (report.cg_iterations, u32::from(report.factorized))
            }
            Err(_) => (0, 0),
        }
    }

    /// Sets the VM's start `u` for a frame at `line`; true when it was predicted from more
    /// than the last solution.
    ///
    /// A place on the line solved before starts from its solution (a slider moved back and
    /// forth revisits places). Otherwise the prediction interpolates solutions on the same
    /// line, nearest first: as many of them as keep the polynomial's terms shrinking
    /// ([`useful_nodes`]), or, with tangents, the three nearest and their tangents (a Hermite
    /// polynomial, quintic with three solutions and three tangents). It is evaluated at the
    /// new place when that is within twice the spacing of the two nearest; it drops solutions
    /// while the weights would amplify their differences, and falls back to the last solution.
    fn choose_start(&mut self, line: Option<Line>) -> bool {
        if !self.options.warm_start {
            self.vm.reset_u();
            self.a_start.fill(0.0);
            return false;
        }
        if let Some(c) = &self.closure {
            // The last solution's, unless a solved frame says better below.
            self.a_start.copy_from_slice(&c.a);
        }
        if self.solved == 0 {
            return false;
        }
        let last = HISTORY - 1;
        let mut prediction = None;
        if let (Some(line), true) = (line, self.options.extrapolate) {
            // The solutions on this line, nearest to the new place first (newest first among
            // equals).
            let mut nodes = [0usize; HISTORY];
            let mut count = 0;
            for i in (HISTORY - self.solved..HISTORY).rev() {
                if self.history[i].line == (line.from, line.to) {
                    nodes[count] = i;
                    count += 1;
                }
            }
            let distance = |i: usize| (self.history[i].s - line.s).abs();
            nodes[..count].sort_by(|&a, &b| distance(a).total_cmp(&distance(b)));
            if count >= 1 && distance(nodes[0]) == 0.0 {
                // A place solved before: its solution is the start.
                self.vm
                    .set_u(&self.history[nodes[0]].u)
                    .expect("history has one value per unknown");
                self.a_start.copy_from_slice(&self.history[nodes[0]].a);
                return true;
            }
            if count >= 2 {
                let (a, b) = (&self.history[nodes[0]], &self.history[nodes[1]]);
                let spacing = (a.s - b.s).abs();
                if (line.s - a.s).abs() <= 2.0 * spacing {
                    let tangents = self.options.tangents;
                    let most = if tangents {
                        count.min(TANGENT_NODES)
                    } else {
                        let mut at = [0.0; HISTORY];
                        let mut values: [&[f64]; HISTORY] = [&[]; HISTORY];
                        for ((a, v), &i) in at.iter_mut().zip(&mut values).zip(&nodes[..count]) {
                            *a = self.history[i].s;
                            *v = &self.history[i].u;
                        }
                        useful_nodes(&at[..count], &values[..count], line.s)
                    };
                    // With tangents first (if any), then values only, fewer solutions until
                    // the weights do not amplify.
                    let tangent_tries = [(most, true), (2, true)].into_iter().filter(|_| tangents);
                    let value_tries = (2..=most).rev().map(|used| (used, false));
                    for (used, with_du) in tangent_tries.chain(value_tries) {
                        let mut data = [(0.0, false); HISTORY];
                        for (d, &i) in data.iter_mut().zip(&nodes[..used]) {
                            let h = &self.history[i];
                            *d = (h.s, with_du && h.has_du);
                        }
                        if let Some(w) = predictor_weights(line.s, spacing, &data[..used]) {
                            prediction = Some((nodes, used, w));
                            break;
                        }
                    }
                }
            }
        }
        let Some((nodes, used, (alpha, beta))) = prediction else {
            self.vm
                .set_u(&self.history[last].u)
                .expect("history has one value per unknown");
            self.a_start.copy_from_slice(&self.history[last].a);
            return false;
        };
        self.start.fill(0.0);
        self.a_start.fill(0.0);
        for (j, &i) in nodes[..used].iter().enumerate() {
            let node = &self.history[i];
            for (s, u) in self.start.iter_mut().zip(&node.u) {
                *s += alpha[j] * u;
            }
            for (s, a) in self.a_start.iter_mut().zip(&node.a) {
                *s += alpha[j] * a;
            }
            if beta[j] != 0.0 {
                for (s, d) in self.start.iter_mut().zip(&node.du) {
                    *s += beta[j] * d;
                }
            }
        }
        self.vm
            .set_u(&self.start)
            .expect("start has one value per unknown");
        true
    }

    /// Records the VM's solution as the newest solved frame, replacing a solution at the same
    /// place of the same line, and marks its tangent as pending. Allocates nothing. A frame
    /// off any line (a free blend) leaves only itself to start from.
    fn remember(&mut self, line: Option<Line>) {
        let last = HISTORY - 1;
        let Some(line) = line else {
            let newest = &mut self.history[last];
            newest.u.copy_from_slice(self.vm.u());
            if let Some(c) = &self.closure {
                newest.a.copy_from_slice(&c.a);
            }
            newest.line = (usize::MAX, usize::MAX);
            newest.has_du = false;
            self.solved = 1;
            return;
        };
        let key = (line.from, line.to);
        let same = (HISTORY - self.solved..HISTORY)
            .find(|&i| self.history[i].line == key && self.history[i].s == line.s);
        match same {
            // Move the old solution there to the newest place, keeping the others' order.
            Some(i) => self.history[i..].rotate_left(1),
            None => {
                self.history.rotate_left(1);
                self.solved = (self.solved + 1).min(HISTORY);
                self.history[last].has_du = false;
            }
        }
        let newest = &mut self.history[last];
        newest.line = key;
        newest.s = line.s;
        newest.u.copy_from_slice(self.vm.u());
        if let Some(c) = &self.closure {
            newest.a.copy_from_slice(&c.a);
        }
        // A solution of the same metric again keeps its tangent: both solve it to the
        // tolerance.
        if !newest.has_du {
            self.pending_tangent = Some(key);
        }
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
    fn slot_lookup_finds_edges_in_either_direction() {
        let edges = [[0, 1], [2, 1], [0, 2], [3, 0], [1, 3]];
        let slots = SlotLookup::new(4, &edges);
        for (slot, &[a, b]) in edges.iter().enumerate() {
            assert_eq!(slots.get(a, b), Some(slot as u32));
            assert_eq!(slots.get(b, a), Some(slot as u32));
        }
        assert_eq!(slots.get(2, 3), None, "no such edge");
        assert_eq!(slots.get(3, 3), None);
        assert_eq!(slots.get(1, 7), None, "7 is not a vertex");
        assert_eq!(slots.get(9, 7), None);
    }

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
