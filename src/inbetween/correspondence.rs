//! Which point of drawing B's outline each point of drawing A's outline becomes.
//!
//! Each pair of loops (A's and B's outline of a piece, or of a hole) gets a monotone map of
//! arc length. Without pairs from the user, the loops are aligned rigidly first: both
//! resampled to [`SAMPLES`] points by arc length in their drawing's normalised frame
//! (centred on the subject's area, scaled to unit area), the rotation and the cyclic shift
//! that bring A's samples closest to B's found in closed form for every shift (Procrustes).
//! The map then follows a dynamic time warping of the two loops from that start: each step
//! pays for the distance of the aligned points and for the difference of the outline's
//! turning there (corners meet corners, the tip of a raised arm meets the tip of the arm),
//! and a little for leaving the diagonal (so that plain stretches are matched by arc
//! length). The user's pairs on a loop pin its map: between consecutive pairs the arcs are
//! warped the same way, ends fixed.
//!
//! The result per loop of A is a common polygon: every corner of A's loop and of the loops
//! paired with it in the other drawings, each with its place on every loop (corners closer
//! than a third of a segment merged), so that A's mesh laid over any of them reproduces its
//! outline exactly.

use super::outline::{Loop, Shape};
use super::InbetweenError;

/// Samples per loop for the rigid alignment and the warping.
pub(crate) const SAMPLES: usize = 256;
/// The weight of the difference in turning angle against the squared distance.
const TURN_WEIGHT: f64 = 0.5;
/// The cost of a step off the diagonal.
const STEP_COST: f64 = 0.004;
/// Half the width of the moving average over the warping path, in samples.
const SMOOTHING: usize = 3;
/// The share of arc-length proportion mixed into the warped map (keeps it strictly monotone).
const LINEAR_SHARE: f64 = 0.1;
/// A corner and a user's pair closer than this share of the merging distance (a third of a
/// mean segment) on every loop are one corner, at the pair's place.
const TOUCHING: f64 = 0.15;

/// A point of the user's pair lying on a loop pair: its arc lengths on A's and B's loops.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Anchor {
    pub sa: f64,
    pub sb: f64,
    /// The pair's index (0-based) in the user's list.
    pub pair: usize,
}

/// One corner of a common polygon: where it is on A's outline and on each other drawing's.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Corner {
    pub a: [f64; 2],
    /// On each other drawing's outline, in order.
    pub images: Vec<[f64; 2]>,
    /// The user's pair it is, if any.
    pub pair: Option<usize>,
}

/// The rotation (angle) that best brings A's main loop onto B's in the normalised frames,
/// with the best cyclic shift of B's samples.
pub(crate) fn rigid_alignment(a: &Shape, la: &Loop, b: &Shape, lb: &Loop) -> (f64, usize) {
    let pa = samples(la, 0.0, la.length(), SAMPLES, false);
    let pb = samples(lb, 0.0, lb.length(), SAMPLES, false);
    let na: Vec<[f64; 2]> = pa.iter().map(|&p| a.normalise(p)).collect();
    let nb: Vec<[f64; 2]> = pb.iter().map(|&p| b.normalise(p)).collect();
    let mut best = (f64::INFINITY, 0.0, 0);
    for k in 0..SAMPLES {
        let (mut dot, mut cross, mut norms) = (0.0, 0.0, 0.0);
        for i in 0..SAMPLES {
            let (p, q) = (na[i], nb[(i + k) % SAMPLES]);
            dot += p[0] * q[0] + p[1] * q[1];
            cross += p[0] * q[1] - p[1] * q[0];
            norms += p[0] * p[0] + p[1] * p[1] + q[0] * q[0] + q[1] * q[1];
        }
        // min over θ of Σ|R p − q|² = Σ|p|² + |q|² − 2 |(dot, cross)|.
        let cost = norms - 2.0 * dot.hypot(cross);
        if cost < best.0 {
            best = (cost, cross.atan2(dot), k);
        }
    }
    (best.1, best.2)
}

/// The best cyclic shift of B's samples against A's rotated by `angle`.
fn best_shift(a: &Shape, la: &Loop, b: &Shape, lb: &Loop, angle: f64) -> usize {
    let na = rotated(a, &samples(la, 0.0, la.length(), SAMPLES, false), angle);
    let nb: Vec<[f64; 2]> = samples(lb, 0.0, lb.length(), SAMPLES, false)
        .iter()
        .map(|&p| b.normalise(p))
        .collect();
    (0..SAMPLES)
        .map(|k| {
            let cost: f64 = (0..SAMPLES)
                .map(|i| {
                    let (p, q) = (na[i], nb[(i + k) % SAMPLES]);
                    (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)
                })
                .sum();
            (cost, k)
        })
        .min_by(|x, y| x.0.total_cmp(&y.0))
        .map_or(0, |(_, k)| k)
}

fn rotated(shape: &Shape, points: &[[f64; 2]], angle: f64) -> Vec<[f64; 2]> {
    let (s, c) = angle.sin_cos();
    points
        .iter()
        .map(|&p| {
            let q = shape.normalise(p);
            [c * q[0] - s * q[1], s * q[0] + c * q[1]]
        })
        .collect()
}

/// `count` points from arc length `start` over `span` (the ends included when `closed_ends`,
/// otherwise `span / count` apart from `start`).
fn samples(l: &Loop, start: f64, span: f64, count: usize, closed_ends: bool) -> Vec<[f64; 2]> {
    arc_lengths(start, span, count, closed_ends)
        .into_iter()
        .map(|s| l.at(s))
        .collect()
}

fn arc_lengths(start: f64, span: f64, count: usize, closed_ends: bool) -> Vec<f64> {
    let step = if closed_ends {
        span / (count.max(2) - 1) as f64
    } else {
        span / count.max(1) as f64
    };
    (0..count).map(|i| start + step * i as f64).collect()
}

/// The outline's turning at arc length `s`: the angle between the chords a fraction of the
/// loop before and after it (positive turning left).
fn turning(l: &Loop, s: f64) -> f64 {
    let d = l.length() / 64.0;
    let (p, q, r) = (l.at(s - d), l.at(s), l.at(s + d));
    let (u, v) = ([q[0] - p[0], q[1] - p[1]], [r[0] - q[0], r[1] - q[1]]);
    (u[0] * v[1] - u[1] * v[0]).atan2(u[0] * v[0] + u[1] * v[1])
}

/// A monotone map of arc length from an arc of A's loop to an arc of B's, as knots
/// `(sa, sb)` (not wrapped) from `(a0, b0)` to `(a0 + span_a, b0 + span_b)`.
#[allow(clippy::too_many_arguments)]
fn warp(
    a: &Shape,
    la: &Loop,
    (a0, span_a): (f64, f64),
    b: &Shape,
    lb: &Loop,
    (b0, span_b): (f64, f64),
    angle: f64,
    out: &mut Vec<[f64; 2]>,
) {
    let n = ((SAMPLES as f64 * span_a / la.length()).round() as usize).clamp(8, SAMPLES + 1);
    let m = ((SAMPLES as f64 * span_b / lb.length()).round() as usize).clamp(8, SAMPLES + 1);
    let sa = arc_lengths(a0, span_a, n, true);
    let sb = arc_lengths(b0, span_b, m, true);
    let pa = rotated(a, &sa.iter().map(|&s| la.at(s)).collect::<Vec<_>>(), angle);
    let pb: Vec<[f64; 2]> = sb.iter().map(|&s| b.normalise(lb.at(s))).collect();
    let ta: Vec<f64> = sa.iter().map(|&s| turning(la, s)).collect();
    let tb: Vec<f64> = sb.iter().map(|&s| turning(lb, s)).collect();
    let cost = |i: usize, j: usize| {
        let d = (pa[i][0] - pb[j][0]).powi(2) + (pa[i][1] - pb[j][1]).powi(2);
        d + TURN_WEIGHT * (ta[i] - tb[j]).powi(2)
    };
    // Accumulated cost, row-major n x m; the path runs from (0, 0) to (n-1, m-1) by steps
    // (1, 1), (1, 2) and (2, 1) (Sakoe and Chiba's symmetric pattern), so that the map's
    // slope stays between 1/2 and 2 of the arcs' ratio: no stretch of one outline is
    // squeezed onto a point of the other.
    let step = STEP_COST;
    let mut acc = vec![f64::INFINITY; n * m];
    acc[0] = cost(0, 0);
    let at = |acc: &[f64], i: usize, j: usize| acc[i * m + j];
    for i in 1..n {
        for j in 1..m {
            let mut best = at(&acc, i - 1, j - 1) + cost(i, j);
            if j >= 2 {
                best = best.min(at(&acc, i - 1, j - 2) + cost(i, j - 1) + cost(i, j) + step);
            }
            if i >= 2 {
                best = best.min(at(&acc, i - 2, j - 1) + cost(i - 1, j) + cost(i, j) + step);
            }
            acc[i * m + j] = best;
        }
    }
    // Per sample of A, the mean sample of B the path visits.
    let mut sum = vec![0.0; n];
    let mut count = vec![0usize; n];
    if acc[n * m - 1].is_finite() {
        let (mut i, mut j) = (n - 1, m - 1);
        loop {
            sum[i] += j as f64;
            count[i] += 1;
            if i == 0 && j == 0 {
                break;
            }
            let here = acc[i * m + j];
            let diag = at(&acc, i - 1, j - 1) + cost(i, j);
            let close = |x: f64| (x - here).abs() <= 1e-12 * here.abs().max(1.0);
            if close(diag) {
                i -= 1;
                j -= 1;
            } else if j >= 2 && close(at(&acc, i - 1, j - 2) + cost(i, j - 1) + cost(i, j) + step) {
                sum[i] += (j - 1) as f64;
                count[i] += 1;
                i -= 1;
                j -= 2;
            } else {
                sum[i - 1] += j as f64;
                count[i - 1] += 1;
                i -= 2;
                j -= 1;
            }
        }
    } else {
        // The arcs' ratio is beyond the pattern's slopes (pairs far apart on one drawing
        // and close on the other): arc-length proportion.
        for k in 0..n {
            sum[k] = k as f64 * (m - 1) as f64 / (n - 1) as f64;
            count[k] = 1;
        }
    }
    let mut raw: Vec<f64> = (0..n).map(|k| sum[k] / count[k].max(1) as f64).collect();
    // The arcs' ends meet exactly (a last step of two samples of B would average them).
    raw[0] = 0.0;
    raw[n - 1] = (m - 1) as f64;
    // A moving average over a few samples smooths the path's steps (and keeps it monotone).
    let smooth: Vec<f64> = (0..n)
        .map(|k| {
            if k == 0 || k == n - 1 {
                return raw[k];
            }
            let r = SMOOTHING.min(k).min(n - 1 - k);
            raw[k - r..=k + r].iter().sum::<f64>() / (2 * r + 1) as f64
        })
        .collect();
    for (k, &smoothed) in smooth.iter().enumerate() {
        let f = k as f64 / (n - 1) as f64;
        let g = smoothed / (m - 1) as f64;
        let g = (1.0 - LINEAR_SHARE) * g + LINEAR_SHARE * f;
        // The arc's first knot is the previous arc's last.
        if k > 0 || out.is_empty() {
            out.push([a0 + f * span_a, b0 + g * span_b]);
        }
    }
}

/// A monotone map of arc length around a loop pair: knots from `(a0, b0)` once around both.
#[derive(Clone, Debug)]
pub(crate) struct ArcMap {
    knots: Vec<[f64; 2]>,
    length_a: f64,
    length_b: f64,
}

impl ArcMap {
    /// B's arc length for A's `sa`.
    pub fn forward(&self, sa: f64) -> f64 {
        self.interpolate(sa, 0, self.length_a, self.length_b)
    }

    /// A's arc length for B's `sb`.
    pub fn backward(&self, sb: f64) -> f64 {
        self.interpolate(sb, 1, self.length_b, self.length_a)
    }

    fn interpolate(&self, s: f64, from: usize, len_from: f64, len_to: f64) -> f64 {
        let to = 1 - from;
        let k0 = self.knots[0][from];
        let s = k0 + (s - k0).rem_euclid(len_from);
        let i = self
            .knots
            .partition_point(|k| k[from] <= s)
            .clamp(1, self.knots.len() - 1);
        let (p, q) = (self.knots[i - 1], self.knots[i]);
        let f = if q[from] > p[from] {
            ((s - p[from]) / (q[from] - p[from])).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p[to] + f * (q[to] - p[to])).rem_euclid(len_to)
    }
}

/// The map of arc length around loops `la` (A) and `lb` (B), through the user's `anchors` on
/// them when there are any; `angle` is the drawings' rotation from the rigid alignment.
///
/// # Errors
/// [`InbetweenError::Match`] when the anchors come in a different order around A's loop
/// than around B's.
pub(crate) fn arc_map(
    a: &Shape,
    la: &Loop,
    b: &Shape,
    lb: &Loop,
    angle: f64,
    anchors: &[Anchor],
) -> Result<ArcMap, InbetweenError> {
    let (len_a, len_b) = (la.length(), lb.length());
    let mut knots = Vec::new();
    if anchors.is_empty() {
        let k = best_shift(a, la, b, lb, angle);
        let b0 = len_b * k as f64 / SAMPLES as f64;
        warp(a, la, (0.0, len_a), b, lb, (b0, len_b), angle, &mut knots);
    } else {
        let mut sorted = anchors.to_vec();
        sorted.sort_by(|x, y| x.sa.total_cmp(&y.sa));
        let first = sorted[0];
        let rel = |s: f64| (s - first.sb).rem_euclid(len_b);
        for w in sorted.windows(2) {
            if rel(w[1].sb) <= rel(w[0].sb) {
                return Err(InbetweenError::Match {
                    pair: w[1].pair + 1,
                    reason: format!(
                        "pairs {} and {} come in one order along the outline in drawing A and in the other in drawing B",
                        w[0].pair + 1,
                        w[1].pair + 1
                    ),
                });
            }
        }
        for (k, anchor) in sorted.iter().enumerate() {
            let next = sorted.get(k + 1).copied();
            let span_a = next.map_or(first.sa + len_a, |x| x.sa) - anchor.sa;
            let b0 = first.sb + rel(anchor.sb);
            let span_b = next.map_or(len_b, |x| rel(x.sb)) - rel(anchor.sb);
            warp(
                a,
                la,
                (anchor.sa, span_a),
                b,
                lb,
                (b0, span_b),
                angle,
                &mut knots,
            );
        }
    }
    Ok(ArcMap {
        knots,
        length_a: len_a,
        length_b: len_b,
    })
}

/// A corner of the common polygon being built: its arc length on A's loop and on each other
/// drawing's, which drawings' own corners it is, and the user's pair it is.
#[derive(Clone, Debug)]
struct Entry {
    sa: f64,
    sx: Vec<f64>,
    /// Per drawing (A first), whether this is one of that drawing's own corners.
    from: Vec<bool>,
    pair: Option<usize>,
}

impl Entry {
    /// `self` and `other` as one corner, when they can be: neither is a pair and no drawing
    /// gave both; or one is a pair and the other is at (almost) the same place, `touching`
    /// (the pair's place kept).
    fn merge(&self, other: &Entry, touching: bool) -> Option<Entry> {
        match (self.pair, other.pair) {
            (Some(_), Some(_)) => None,
            // A point of the user's on (or next to) a corner: one corner, at the user's
            // place. Two corners there would make a segment of no length.
            (Some(_), None) if touching => Some(self.clone()),
            (None, Some(_)) if touching => Some(other.clone()),
            // A pair's place is the user's, and a corner next to it is kept: dropping it
            // would cut a corner off the outline.
            (Some(_), _) | (_, Some(_)) => None,
            (None, None) => {
                if self.from.iter().zip(&other.from).any(|(x, y)| *x && *y) {
                    return None;
                }
                let mut merged = self.clone();
                if other.from[0] {
                    merged.sa = other.sa;
                }
                for (k, slot) in merged.sx.iter_mut().enumerate() {
                    if other.from[k + 1] {
                        *slot = other.sx[k];
                    }
                }
                for (f, o) in merged.from.iter_mut().zip(&other.from) {
                    *f |= *o;
                }
                Some(merged)
            }
        }
    }
}

/// The common polygon of A's loop `la` and the loops `lx` of the other drawings paired with
/// it (`maps[k]` A's arc length to `lx[k]`'s): every drawing's corners, each with its image
/// on every other loop, and the user's `anchors` (pairs of A and the first other drawing);
/// corners closer than a third of their loop's mean segment (on any loop) merged into one
/// that takes each drawing's own corner where it has one.
pub(crate) fn common_polygon(
    la: &Loop,
    lx: &[&Loop],
    maps: &[&ArcMap],
    anchors: &[Anchor],
) -> Vec<Corner> {
    let len_a = la.length();
    let m = lx.len();
    let plain = |sa: f64, own: usize| Entry {
        sa,
        sx: maps.iter().map(|map| map.forward(sa)).collect(),
        from: (0..=m).map(|d| d == own).collect(),
        pair: None,
    };
    let mut entries: Vec<Entry> = (0..la.len()).map(|i| plain(la.cum[i], 0)).collect();
    for (k, (l, map)) in lx.iter().zip(maps).enumerate() {
        for j in 0..l.len() {
            let sa = map.backward(l.cum[j]);
            let mut e = plain(sa, k + 1);
            e.sx[k] = l.cum[j];
            entries.push(e);
        }
    }
    for anchor in anchors {
        let mut e = plain(anchor.sa, usize::MAX);
        if let Some(first) = e.sx.first_mut() {
            *first = anchor.sb;
        }
        e.pair = Some(anchor.pair);
        entries.push(e);
    }
    // Around A's loop from where the maps start.
    let start = maps.first().map_or(0.0, |map| map.knots[0][0]);
    let key = |s: f64| (s - start).rem_euclid(len_a);
    entries.sort_by(|x, y| key(x.sa).total_cmp(&key(y.sa)));
    let near_a = 0.34 * len_a / la.len() as f64;
    let near_x: Vec<f64> = lx
        .iter()
        .map(|l| 0.34 * l.length() / l.len() as f64)
        .collect();
    let gap = |x: f64, y: f64, len: f64| {
        let d = (x - y).rem_euclid(len);
        d.min(len - d)
    };
    let close = |p: &Entry, q: &Entry| {
        gap(p.sa, q.sa, len_a) < near_a
            || (0..m).any(|k| gap(p.sx[k], q.sx[k], lx[k].length()) < near_x[k])
    };
    // Within this share of a mean segment on every loop, a pair and a corner are one.
    let touching = |p: &Entry, q: &Entry| {
        gap(p.sa, q.sa, len_a) < TOUCHING * near_a
            && (0..m).all(|k| gap(p.sx[k], q.sx[k], lx[k].length()) < TOUCHING * near_x[k])
    };
    let mut merged: Vec<Entry> = Vec::with_capacity(entries.len());
    for e in entries {
        if let Some(last) = merged.last_mut() {
            if close(last, &e) {
                if let Some(both) = last.merge(&e, touching(last, &e)) {
                    *last = both;
                    continue;
                }
            }
        }
        merged.push(e);
    }
    // The last and the first may be neighbours too.
    while merged.len() > 3 {
        let (first, last) = (&merged[0], &merged[merged.len() - 1]);
        if !close(last, first) {
            break;
        }
        let Some(both) = first.merge(last, touching(first, last)) else {
            break;
        };
        merged[0] = both;
        merged.pop();
    }
    // Every other loop's arc lengths must increase around it as A's do: drop what breaks
    // the order (never a pair).
    for (k, loop_x) in lx.iter().enumerate() {
        let len = loop_x.length();
        let origin = merged.first().map_or(0.0, |e| e.sx[k]);
        let rel = |s: f64| (s - origin).rem_euclid(len);
        let mut kept: Vec<Entry> = Vec::with_capacity(merged.len());
        for e in merged {
            let Some(last) = kept.last() else {
                kept.push(e);
                continue;
            };
            if rel(e.sx[k]) > rel(last.sx[k]) {
                kept.push(e);
            } else if e.pair.is_some() && last.pair.is_none() {
                kept.pop();
                kept.push(e);
            }
        }
        merged = kept;
    }
    merged
        .into_iter()
        .map(|e| Corner {
            a: la.at(e.sa),
            images: e.sx.iter().zip(lx).map(|(&s, l)| l.at(s)).collect(),
            pair: e.pair,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ellipse(c: [f64; 2], rx: f64, ry: f64, n: usize, phase: f64) -> Loop {
        Loop::new(
            (0..n)
                .map(|i| {
                    let t = phase + std::f64::consts::TAU * i as f64 / n as f64;
                    [c[0] + rx * t.cos(), c[1] + ry * t.sin()]
                })
                .collect(),
        )
    }

    #[test]
    fn a_moved_and_rotated_loop_maps_onto_itself() {
        // A square with one sharp notch, and the same rotated by 30 degrees and moved,
        // sampled from another corner.
        let base = vec![
            [0.0, 0.0],
            [4.0, 0.0],
            [4.0, 4.0],
            [2.2, 4.0],
            [2.0, 2.5],
            [1.8, 4.0],
            [0.0, 4.0],
        ];
        let (s, c) = 30f64.to_radians().sin_cos();
        let mut moved: Vec<[f64; 2]> = base
            .iter()
            .map(|p| [10.0 + c * p[0] - s * p[1], 5.0 + s * p[0] + c * p[1]])
            .collect();
        moved.rotate_left(3);
        let (la, lb) = (Loop::new(base.clone()), Loop::new(moved.clone()));
        let (a, b) = (
            Shape::from_loops(vec![la.clone()]),
            Shape::from_loops(vec![lb.clone()]),
        );
        let (angle, _) = rigid_alignment(&a, &la, &b, &lb);
        assert!((angle - 30f64.to_radians()).abs() < 0.05, "{angle}");
        let map = arc_map(&a, &la, &b, &lb, angle, &[]).unwrap();
        let corners = common_polygon(&la, &[&lb], &[&map], &[]);
        // Every corner of A lands on the matching corner of B (the notch's tip included).
        for (k, p) in base.iter().enumerate() {
            let c = corners.iter().find(|c| c.a == *p).unwrap();
            let q = moved[(k + base.len() - 3) % base.len()];
            assert!(
                (c.images[0][0] - q[0]).hypot(c.images[0][1] - q[1]) < 0.15,
                "{k}: {c:?} {q:?}"
            );
        }
    }

    #[test]
    fn anchors_are_met_and_order_is_checked() {
        let la = ellipse([0.0, 0.0], 2.0, 1.0, 60, 0.0);
        let lb = ellipse([0.0, 0.0], 1.0, 2.0, 50, 0.3);
        let (a, b) = (
            Shape::from_loops(vec![la.clone()]),
            Shape::from_loops(vec![lb.clone()]),
        );
        let anchors = [
            Anchor {
                sa: 1.0,
                sb: 2.0,
                pair: 0,
            },
            Anchor {
                sa: 5.0,
                sb: 6.5,
                pair: 1,
            },
        ];
        let map = arc_map(&a, &la, &b, &lb, 0.0, &anchors).unwrap();
        assert!((map.forward(1.0) - 2.0).abs() < 1e-9);
        assert!((map.forward(5.0) - 6.5).abs() < 1e-9);
        assert!((map.backward(6.5) - 5.0).abs() < 1e-9);
        let corners = common_polygon(&la, &[&lb], &[&map], &anchors);
        for an in &anchors {
            let c = corners.iter().find(|c| c.pair == Some(an.pair)).unwrap();
            assert_eq!(c.a, la.at(an.sa));
            assert_eq!(c.images[0], lb.at(an.sb));
        }
        let swapped = [
            Anchor {
                sa: 1.0,
                sb: 2.0,
                pair: 0,
            },
            Anchor {
                sa: 5.0,
                sb: 6.5,
                pair: 1,
            },
            Anchor {
                sa: 6.0,
                sb: 4.0,
                pair: 2,
            },
        ];
        let e = arc_map(&a, &la, &b, &lb, 0.0, &swapped)
            .unwrap_err()
            .to_string();
        assert!(e.contains("pairs"), "{e}");
    }

    #[test]
    fn a_pair_on_a_corner_makes_one_corner() {
        // The pair's point in A is exactly corner 5 of A's loop.
        let la = ellipse([0.0, 0.0], 2.0, 1.0, 40, 0.0);
        let lb = ellipse([0.0, 0.0], 2.0, 1.2, 48, 0.1);
        let (a, b) = (
            Shape::from_loops(vec![la.clone()]),
            Shape::from_loops(vec![lb.clone()]),
        );
        let anchors = [Anchor {
            sa: la.cum[5],
            sb: lb.cum[6],
            pair: 0,
        }];
        let map = arc_map(&a, &la, &b, &lb, 0.0, &anchors).unwrap();
        let corners = common_polygon(&la, &[&lb], &[&map], &anchors);
        let n = corners.len();
        for i in 0..n {
            let (p, q) = (&corners[i], &corners[(i + 1) % n]);
            assert!(
                p.a != q.a && p.images[0] != q.images[0],
                "corners {i} and {} coincide",
                (i + 1) % n
            );
        }
        let c = corners.iter().find(|c| c.pair == Some(0)).unwrap();
        assert_eq!(c.a, la.points[5]);
        assert_eq!(c.images[0], lb.at(lb.cum[6]));
    }
}
