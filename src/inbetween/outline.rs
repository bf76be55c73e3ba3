//! A drawing's outline as closed loops with arc length, grouped into pieces and holes, and the
//! check that two drawings have the same topology.

use super::{Drawing, InbetweenError};
use crate::meshing::Outline;

/// The point of segment `ab` nearest `p`: its fraction along the segment, and its distance.
pub(crate) fn closest_on_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> (f64, f64) {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let f = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (f, (p[0] - a[0] - f * dx).hypot(p[1] - a[1] - f * dy))
}

/// A closed polygon (y up) with its cumulative arc length.
#[derive(Clone, Debug)]
pub(crate) struct Loop {
    /// Corners; the last joins the first.
    pub points: Vec<[f64; 2]>,
    /// `cum[i]`: the arc length from corner 0 to corner `i`; `cum[n]` is the whole length.
    pub cum: Vec<f64>,
    /// Signed area (positive counter-clockwise).
    pub area: f64,
    /// The centroid of the area it encloses.
    pub centroid: [f64; 2],
}

impl Loop {
    pub fn new(points: Vec<[f64; 2]>) -> Loop {
        let n = points.len();
        let mut cum = Vec::with_capacity(n + 1);
        cum.push(0.0);
        let (mut area2, mut cx, mut cy) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let (p, q) = (points[i], points[(i + 1) % n]);
            cum.push(cum[i] + (q[0] - p[0]).hypot(q[1] - p[1]));
            let c = p[0] * q[1] - q[0] * p[1];
            area2 += c;
            cx += (p[0] + q[0]) * c;
            cy += (p[1] + q[1]) * c;
        }
        let centroid = if area2 != 0.0 {
            [cx / (3.0 * area2), cy / (3.0 * area2)]
        } else {
            points.first().copied().unwrap_or([0.0; 2])
        };
        Loop {
            points,
            cum,
            area: 0.5 * area2,
            centroid,
        }
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// The whole length.
    pub fn length(&self) -> f64 {
        self.cum[self.points.len()]
    }

    /// `s` brought into `[0, length)`.
    pub fn wrap(&self, s: f64) -> f64 {
        let l = self.length();
        let w = s.rem_euclid(l);
        if w >= l {
            0.0
        } else {
            w
        }
    }

    /// The segment holding arc length `s` (wrapped) and the fraction along it.
    pub fn locate(&self, s: f64) -> (usize, f64) {
        let s = self.wrap(s);
        let n = self.points.len();
        let i = match self.cum[..n].binary_search_by(|c| c.total_cmp(&s)) {
            Ok(i) => i,
            Err(i) => i.saturating_sub(1),
        }
        .min(n - 1);
        let len = self.cum[i + 1] - self.cum[i];
        let f = if len > 0.0 {
            ((s - self.cum[i]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (i, f)
    }

    /// The point at arc length `s` (wrapped).
    pub fn at(&self, s: f64) -> [f64; 2] {
        let (i, f) = self.locate(s);
        let (p, q) = (self.points[i], self.points[(i + 1) % self.points.len()]);
        [p[0] + f * (q[0] - p[0]), p[1] + f * (q[1] - p[1])]
    }

    /// The arc length of the point of the loop nearest `p`, and its distance.
    pub fn project(&self, p: [f64; 2]) -> (f64, f64) {
        let n = self.points.len();
        let mut best = (0.0, f64::INFINITY);
        for i in 0..n {
            let (f, d) = closest_on_segment(p, self.points[i], self.points[(i + 1) % n]);
            if d < best.1 {
                best = (self.cum[i] + f * (self.cum[i + 1] - self.cum[i]), d);
            }
        }
        (self.wrap(best.0), best.1)
    }

    /// Whether `p` is inside (even-odd).
    pub fn contains(&self, p: [f64; 2]) -> bool {
        let n = self.points.len();
        let mut inside = false;
        for i in 0..n {
            let (a, b) = (self.points[i], self.points[(i + 1) % n]);
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if p[0] < x {
                    inside = !inside;
                }
            }
        }
        inside
    }
}

/// A drawing's outline: its loops, which are pieces (outer loops) and which holes, and the
/// frame it is compared in (centred on its area, scaled to unit area).
#[derive(Clone, Debug)]
pub(crate) struct Shape {
    pub loops: Vec<Loop>,
    /// Per loop, the outer loop of its piece (itself for an outer loop).
    pub piece: Vec<usize>,
    /// The outer loops, largest first.
    pub pieces: Vec<usize>,
    /// The centroid of the whole area.
    pub centre: [f64; 2],
    /// The square root of the whole area.
    pub scale: f64,
}

impl Shape {
    /// The loops of an outline made of closed loops (as [`Outline::push_loop`] makes them).
    pub fn of(outline: &Outline) -> Shape {
        let mut loops = Vec::new();
        let mut current: Vec<[f64; 2]> = Vec::new();
        for s in &outline.segments {
            current.push(outline.vertices[s[0] as usize]);
            if s[1] <= s[0] {
                loops.push(Loop::new(std::mem::take(&mut current)));
            }
        }
        if current.len() >= 3 {
            loops.push(Loop::new(current));
        }
        Shape::from_loops(loops)
    }

    pub fn from_loops(loops: Vec<Loop>) -> Shape {
        let mut pieces: Vec<usize> = (0..loops.len()).filter(|&i| loops[i].area > 0.0).collect();
        pieces.sort_by(|&a, &b| loops[b].area.total_cmp(&loops[a].area));
        let piece = (0..loops.len())
            .map(|i| {
                if loops[i].area > 0.0 {
                    return i;
                }
                // The smallest outer loop around the hole.
                let p = loops[i].points[0];
                pieces
                    .iter()
                    .rev()
                    .copied()
                    .find(|&o| loops[o].contains(p))
                    .unwrap_or(i)
            })
            .collect();
        let total: f64 = loops.iter().map(|l| l.area).sum();
        let (mut cx, mut cy) = (0.0, 0.0);
        for l in &loops {
            cx += l.area * l.centroid[0];
            cy += l.area * l.centroid[1];
        }
        let (centre, scale) = if total > 0.0 {
            ([cx / total, cy / total], total.sqrt())
        } else {
            ([0.0, 0.0], 1.0)
        };
        Shape {
            loops,
            piece,
            pieces,
            centre,
            scale,
        }
    }

    /// The shape without its holes of area below `area` (pinholes), and how many there were.
    pub fn without_pinholes(self, area: f64) -> (Shape, usize) {
        let before = self.loops.len();
        let loops: Vec<Loop> = self
            .loops
            .into_iter()
            .filter(|l| l.area > 0.0 || -l.area >= area)
            .collect();
        let removed = before - loops.len();
        (Shape::from_loops(loops), removed)
    }

    /// The shape made of `keep`'s loops of this one, in that order.
    pub fn subset(&self, keep: &[usize]) -> Shape {
        Shape::from_loops(keep.iter().map(|&i| self.loops[i].clone()).collect())
    }

    /// The holes of the piece whose outer loop is `outer`, largest first.
    pub fn holes(&self, outer: usize) -> Vec<usize> {
        let mut h: Vec<usize> = (0..self.loops.len())
            .filter(|&i| i != outer && self.piece[i] == outer)
            .collect();
        h.sort_by(|&a, &b| self.loops[a].area.total_cmp(&self.loops[b].area));
        h
    }

    /// A point in the normalised frame.
    pub fn normalise(&self, p: [f64; 2]) -> [f64; 2] {
        [
            (p[0] - self.centre[0]) / self.scale,
            (p[1] - self.centre[1]) / self.scale,
        ]
    }

    /// How messages name loop `i`: "piece 2's outline", "piece 1's hole 2".
    pub fn name(&self, i: usize) -> String {
        let outer = self.piece[i];
        let k = self.pieces.iter().position(|&o| o == outer).unwrap_or(0) + 1;
        if outer == i {
            format!("the outline of piece {k}")
        } else {
            let h = self.holes(outer).iter().position(|&x| x == i).unwrap_or(0) + 1;
            format!("hole {h} of piece {k}")
        }
    }
}

/// Pairs `a`'s items with `b`'s greedily by `cost`, cheapest first, pairs costing at most
/// `limit`.
fn pair_greedily(
    a: &[usize],
    b: &[usize],
    cost: &impl Fn(usize, usize) -> f64,
    limit: f64,
) -> Vec<(usize, usize)> {
    let mut all: Vec<(f64, usize, usize)> = Vec::with_capacity(a.len() * b.len());
    for &i in a {
        for &j in b {
            all.push((cost(i, j), i, j));
        }
    }
    all.sort_by(|x, y| x.0.total_cmp(&y.0));
    let (mut used_a, mut used_b) = (Vec::new(), Vec::new());
    let mut pairs = Vec::new();
    for (c, i, j) in all {
        if c <= limit && !used_a.contains(&i) && !used_b.contains(&j) {
            used_a.push(i);
            used_b.push(j);
            pairs.push((i, j));
        }
    }
    pairs
}

/// How far apart (in the normalised frames, plus the log of the areas' ratio) two holes may
/// be and still be one hole drawn twice: holes further apart are each in one drawing only.
/// Chosen on the training walk cycles (three characters, see BENCHMARKS.md).
pub(crate) const HOLE_MATCH_COST: f64 = 1.0;

/// How the loops of two drawings pair up.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct LoopPairing {
    /// Loops in both drawings, `(A's, the other's)`: every outer loop, and the holes found
    /// in both.
    pub pairs: Vec<(usize, usize)>,
    /// A's holes the other drawing lacks.
    pub a_only: Vec<usize>,
    /// The other drawing's holes A lacks.
    pub b_only: Vec<usize>,
}

/// Pairs `a`'s loops with `b`'s: pieces by place and size in the normalised frames (the
/// counts must be equal, otherwise the error says so in one line), then each piece's holes
/// the same way, a pair of holes only when they are within [`HOLE_MATCH_COST`] of each
/// other; the others are in one drawing only.
pub(crate) fn pair_loops(
    a: &Shape,
    b: &Shape,
    which: Drawing,
) -> Result<LoopPairing, InbetweenError> {
    let plural = |n: usize, what: &str| {
        if n == 1 {
            format!("1 {what}")
        } else {
            format!("{n} {what}s")
        }
    };
    if a.pieces.is_empty() || b.pieces.is_empty() {
        return Err(InbetweenError::Topology(format!(
            "{} has no outline around its subject",
            if a.pieces.is_empty() {
                Drawing(0)
            } else {
                which
            }
        )));
    }
    if a.pieces.len() != b.pieces.len() {
        return Err(InbetweenError::Topology(format!(
            "drawing A has {} and {which} has {}: in-betweens need the same pieces in each",
            plural(a.pieces.len(), "piece"),
            plural(b.pieces.len(), "piece")
        )));
    }
    let cost = |i: usize, j: usize| {
        let (la, lb) = (&a.loops[i], &b.loops[j]);
        let (ca, cb) = (a.normalise(la.centroid), b.normalise(lb.centroid));
        let area_a = la.area.abs() / (a.scale * a.scale);
        let area_b = lb.area.abs() / (b.scale * b.scale);
        (ca[0] - cb[0]).hypot(ca[1] - cb[1]) + (area_a.max(1e-12) / area_b.max(1e-12)).ln().abs()
    };
    let pieces = pair_greedily(&a.pieces, &b.pieces, &cost, f64::INFINITY);
    let mut pairing = LoopPairing {
        pairs: pieces.clone(),
        a_only: Vec::new(),
        b_only: Vec::new(),
    };
    for &(pa, pb) in &pieces {
        let (ha, hb) = (a.holes(pa), b.holes(pb));
        let holes = pair_greedily(&ha, &hb, &cost, HOLE_MATCH_COST);
        pairing
            .a_only
            .extend(ha.iter().filter(|&&h| !holes.iter().any(|p| p.0 == h)));
        pairing
            .b_only
            .extend(hb.iter().filter(|&&h| !holes.iter().any(|p| p.1 == h)));
        pairing.pairs.extend(holes);
    }
    Ok(pairing)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(c: [f64; 2], r: f64, ccw: bool) -> Loop {
        let mut p = vec![
            [c[0] - r, c[1] - r],
            [c[0] + r, c[1] - r],
            [c[0] + r, c[1] + r],
            [c[0] - r, c[1] + r],
        ];
        if !ccw {
            p.reverse();
        }
        Loop::new(p)
    }

    #[test]
    fn loops_measure_locate_and_project() {
        let l = square([0.0, 0.0], 1.0, true);
        assert_eq!(l.length(), 8.0);
        assert_eq!(l.area, 4.0);
        assert_eq!(l.at(3.0), [1.0, 0.0]);
        assert_eq!(l.at(11.0), [1.0, 0.0]);
        let (s, d) = l.project([2.0, 0.5]);
        assert!((s - 3.5).abs() < 1e-12 && (d - 1.0).abs() < 1e-12);
        assert!(l.contains([0.2, 0.3]) && !l.contains([1.2, 0.3]));
    }

    #[test]
    fn holes_in_one_drawing_only_are_told_apart_and_pieces_must_match() {
        let a = Shape::from_loops(vec![
            square([0.0, 0.0], 2.0, true),
            square([-1.0, 0.0], 0.5, false),
            square([1.0, 0.0], 0.4, false),
        ]);
        // B: the left hole moved a little, the right one gone, a new one at the top.
        let b = Shape::from_loops(vec![
            square([0.0, 0.0], 2.0, true),
            square([-0.9, 0.1], 0.5, false),
            square([0.0, 1.5], 0.2, false),
        ]);
        let p = pair_loops(&a, &b, Drawing(1)).unwrap();
        assert_eq!(p.pairs, vec![(0, 0), (1, 1)]);
        assert_eq!(p.a_only, vec![2]);
        assert_eq!(p.b_only, vec![2]);
        let c = Shape::from_loops(vec![
            square([0.0, 0.0], 2.0, true),
            square([9.0, 0.0], 1.0, true),
        ]);
        let e = pair_loops(&b, &c, Drawing(1)).unwrap_err().to_string();
        assert!(
            e.contains("drawing A has 1 piece and drawing B has 2 pieces"),
            "{e}"
        );
        assert_eq!(e.lines().count(), 1);
        let (filled, removed) = a.clone().without_pinholes(0.7);
        assert_eq!(removed, 1);
        assert_eq!(filled.loops.len(), 2);
    }
}
