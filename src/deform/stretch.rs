//! Large drags followed in stretches: a drag that moves a handle further than [`STRETCH`] of
//! the mesh's size is split into stretches of at most that, each solved by the method's
//! iterations, as the same drag in small mouse moves would be. The handles' move is split
//! into the rigid motion that best fits it (about their centroid) and what is left: the
//! stretches follow the rigid part along its arc and the rest along straight lines, so
//! handles that all turn together turn the mesh rather than pull it through their chords.

use super::DragReport;

/// The farthest a handle's target moves in one stretch of a drag, relative to the mesh's
/// size: a drag that moves a handle further is followed in stretches of at most this
/// (each with the method's iterations), as a mouse moving there would. Chosen on
/// the bar of `tests/deform_large.rs` (a tip swung 1.1 sizes): in one stretch the springs'
/// first steps shear the bar into slivers the flip-free steps cannot open again; in
/// stretches of 0.05 it bends as in 20 mouse moves.
pub(super) const STRETCH: f64 = 0.05;

/// The most stretches of one drag (a drag of more than `STRETCHES × STRETCH` mesh sizes takes
/// longer strides).
pub(super) const STRETCHES: usize = 400;

/// Where a drag's stretches start and the buffer of one stretch's targets.
#[derive(Default)]
pub(super) struct Stretches {
    /// The handles' targets of the last drag, where the next drag's stretches start when
    /// `known` (otherwise at the handles' places in the pose: after new pins or a new pose).
    previous: Vec<[f64; 2]>,
    known: bool,
    /// The targets of one stretch.
    stretch: Vec<[f64; 2]>,
}

impl Stretches {
    /// New pins, `pins` of them: the next drag starts from their places in the pose.
    pub(super) fn reset(&mut self, pins: usize) {
        self.known = false;
        self.previous = vec![[0.0; 2]; pins];
        self.stretch = vec![[0.0; 2]; pins];
    }

    /// The pose was replaced: the next drag's stretches start from the handles' places.
    pub(super) fn forget(&mut self) {
        self.known = false;
    }

    /// Where the drag about to be followed starts: the last drag's targets, or the handles'
    /// places in `uv` when those are not known. Allocates nothing.
    pub(super) fn start(&mut self, pins: &[u32], uv: &[[f64; 2]]) {
        if !self.known || self.previous.len() != pins.len() {
            self.previous.clear();
            self.previous.extend(pins.iter().map(|&p| uv[p as usize]));
        }
    }

    /// Follows the drag to `targets` from where [`Stretches::start`] set it, in as many
    /// stretches as it needs, calling `each` with every stretch's targets (the last ones
    /// `targets`): the report of all of them (iterations summed; the last one's change and
    /// status). On an error the drag's start stays as it was.
    pub(super) fn follow<E>(
        &mut self,
        targets: &[[f64; 2]],
        uv: &mut [[f64; 2]],
        size: f64,
        mut each: impl FnMut(&[[f64; 2]], &mut [[f64; 2]]) -> Result<DragReport, E>,
    ) -> Result<DragReport, E> {
        let motion = Motion::fit(&self.previous, targets);
        let far = self
            .previous
            .iter()
            .zip(targets)
            .map(|(&a, &b)| motion.path_length(a, b))
            .fold(0.0, f64::max);
        let stretches = ((far / (STRETCH * size)).ceil() as usize).clamp(1, STRETCHES);
        let mut stretch = std::mem::take(&mut self.stretch);
        stretch.resize(targets.len(), [0.0; 2]);
        let mut report = DragReport::default();
        for k in 1..=stretches {
            if k == stretches {
                stretch.copy_from_slice(targets);
            } else {
                let s = k as f64 / stretches as f64;
                for ((out, &a), &b) in stretch.iter_mut().zip(&self.previous).zip(targets) {
                    *out = motion.along(a, b, s);
                }
            }
            let r = match each(&stretch, uv) {
                Ok(r) => r,
                Err(e) => {
                    self.stretch = stretch;
                    return Err(e);
                }
            };
            report.iterations += r.iterations;
            report.last_change = r.last_change;
            report.status = r.status;
        }
        self.stretch = stretch;
        self.previous.copy_from_slice(targets);
        self.known = true;
        Ok(report)
    }
}

/// The rigid motion that best takes one set of handle places to another (least squares,
/// about their centroids), to split a drag into stretches along it.
struct Motion {
    from: [f64; 2],
    to: [f64; 2],
    angle: f64,
}

impl Motion {
    fn fit(a: &[[f64; 2]], b: &[[f64; 2]]) -> Motion {
        let k = a.len().max(1) as f64;
        let centroid = |p: &[[f64; 2]]| {
            let s = p.iter().fold([0.0; 2], |s, q| [s[0] + q[0], s[1] + q[1]]);
            [s[0] / k, s[1] / k]
        };
        let (from, to) = (centroid(a), centroid(b));
        let (mut dot, mut cross) = (0.0, 0.0);
        for (p, q) in a.iter().zip(b) {
            let (x, y) = (
                [p[0] - from[0], p[1] - from[1]],
                [q[0] - to[0], q[1] - to[1]],
            );
            dot += x[0] * y[0] + x[1] * y[1];
            cross += x[0] * y[1] - x[1] * y[0];
        }
        let angle = if dot == 0.0 && cross == 0.0 {
            0.0
        } else {
            cross.atan2(dot)
        };
        Motion { from, to, angle }
    }

    /// Where the handle going from `a` to `b` is a fraction `s` of the way: `a` turned by
    /// `s` of the angle about the centroid as it moves, plus `s` of what the motion leaves.
    fn along(&self, a: [f64; 2], b: [f64; 2], s: f64) -> [f64; 2] {
        let rigid = |t: f64| {
            let (sin, cos) = (t * self.angle).sin_cos();
            let x = [a[0] - self.from[0], a[1] - self.from[1]];
            [
                self.from[0] + t * (self.to[0] - self.from[0]) + cos * x[0] - sin * x[1],
                self.from[1] + t * (self.to[1] - self.from[1]) + sin * x[0] + cos * x[1],
            ]
        };
        let end = rigid(1.0);
        let now = rigid(s);
        [now[0] + s * (b[0] - end[0]), now[1] + s * (b[1] - end[1])]
    }

    /// A bound on the length of the handle's path from `a` to `b` along the motion.
    fn path_length(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        let r = (a[0] - self.from[0]).hypot(a[1] - self.from[1]);
        let shift = (self.to[0] - self.from[0]).hypot(self.to[1] - self.from[1]);
        let rigid_end = {
            let (sin, cos) = self.angle.sin_cos();
            let x = [a[0] - self.from[0], a[1] - self.from[1]];
            [
                self.to[0] + cos * x[0] - sin * x[1],
                self.to[1] + sin * x[0] + cos * x[1],
            ]
        };
        self.angle.abs() * r + shift + (b[0] - rigid_end[0]).hypot(b[1] - rigid_end[1])
    }
}
