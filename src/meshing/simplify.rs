//! Simplifying traced loops to a tolerance, keeping them simple, apart and nested as they
//! were.
//!
//! Each closed loop is simplified by Douglas-Peucker: every dropped point lies within the
//! tolerance of the segment that replaces it, and the kept points are points of the loop, so
//! the simplified loop stays within the tolerance of the traced one. Simplified loops could
//! cross (themselves or each other) or jump over a small loop nearby; where they do, the
//! offending segments get back their farthest dropped point, until nothing crosses and every
//! loop lies inside the same loops as before. Loops enclosing less than `(2 tolerance)^2`, and
//! loops that narrow to a line (every point within the tolerance of one chord), are dropped,
//! with the loops inside them.

use super::outline::{bounds, contains, crossings, twice_area};

/// Loops after simplification.
#[derive(Clone, Debug, Default)]
pub(crate) struct Simplified {
    /// The kept loops, simplified, in the order of the input.
    pub loops: Vec<Vec<[f64; 2]>>,
    /// The input index of each kept loop.
    pub kept: Vec<usize>,
    /// Loops large enough for the tolerance but left out as asked (see [`simplify_leaving_out`]),
    /// by input index.
    pub left_out: Vec<usize>,
    /// How many input loops were dropped as too small.
    pub dropped: usize,
    /// The largest area an input loop encloses.
    pub largest_area: f64,
}

/// The distance from `p` to the segment `ab`.
fn distance_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// The point of `points` strictly between cyclic indices `i` and `j` farthest from the chord
/// `points[i] points[j]`, with its distance.
fn farthest(points: &[[f64; 2]], i: usize, j: usize) -> Option<(usize, f64)> {
    let n = points.len();
    let (a, b) = (points[i], points[j]);
    let len = (j + n - i) % n;
    let len = if len == 0 { n } else { len };
    (1..len)
        .map(|s| {
            let k = (i + s) % n;
            (k, distance_to_segment(points[k], a, b))
        })
        .fold(None, |best: Option<(usize, f64)>, (k, d)| match best {
            Some((_, bd)) if bd >= d => best,
            _ => Some((k, d)),
        })
}

/// Douglas-Peucker on a closed loop: the indices kept, in increasing order.
fn douglas_peucker(points: &[[f64; 2]], tolerance: f64) -> Vec<usize> {
    let n = points.len();
    let a = (0..n)
        .min_by(|&i, &j| {
            points[i]
                .partial_cmp(&points[j])
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .unwrap_or(0);
    let b = (0..n)
        .max_by(|&i, &j| {
            let d = |k: usize| (points[k][0] - points[a][0]).hypot(points[k][1] - points[a][1]);
            d(i).total_cmp(&d(j))
        })
        .unwrap_or(0);
    let mut keep = vec![false; n];
    keep[a] = true;
    keep[b] = true;
    let mut spans = vec![(a, b), (b, a)];
    while let Some((i, j)) = spans.pop() {
        if let Some((k, d)) = farthest(points, i, j) {
            if d > tolerance {
                keep[k] = true;
                spans.push((i, k));
                spans.push((k, j));
            }
        }
    }
    (0..n).filter(|&k| keep[k]).collect()
}

/// Each loop's parent: the smallest larger loop (by enclosed area) of `candidates` holding
/// its first point, for the loops of `candidates` (given largest first); `None` elsewhere.
fn parents(
    loops: &[Vec<[f64; 2]>],
    boxes: &[[f64; 4]],
    candidates: &[usize],
) -> Vec<Option<usize>> {
    let inside_box =
        |b: &[f64; 4], p: [f64; 2]| p[0] >= b[0] && p[0] <= b[2] && p[1] >= b[1] && p[1] <= b[3];
    let mut parent: Vec<Option<usize>> = vec![None; loops.len()];
    for (x, &i) in candidates.iter().enumerate() {
        let p = loops[i][0];
        parent[i] = candidates[..x]
            .iter()
            .rev()
            .copied()
            .find(|&j| inside_box(&boxes[j], p) && contains(&loops[j], p));
    }
    parent
}

/// The loops with at least three points and `area(i) >= min_area`, largest first (so that a
/// parent comes before what it holds).
fn largest_first(loops: &[Vec<[f64; 2]>], areas: &[f64], min_area: f64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..loops.len())
        .filter(|&i| areas[i] >= min_area && loops[i].len() >= 3)
        .collect();
    order.sort_by(|&i, &j| areas[j].total_cmp(&areas[i]).then(i.cmp(&j)));
    order
}

/// How closed loops nest: their enclosed areas, the loops (of three points or more) largest
/// first, each loop's parent (the smallest loop around it) and depth (how many loops are
/// around it).
struct Nesting {
    areas: Vec<f64>,
    order: Vec<usize>,
    parent: Vec<Option<usize>>,
    depth: Vec<usize>,
}

fn nesting(loops: &[Vec<[f64; 2]>]) -> Nesting {
    let areas: Vec<f64> = loops.iter().map(|l| twice_area(l).abs() / 2.0).collect();
    let order = largest_first(loops, &areas, 0.0);
    let boxes: Vec<[f64; 4]> = loops.iter().map(|l| bounds(l)).collect();
    let parent = parents(loops, &boxes, &order);
    let mut depth = vec![0usize; loops.len()];
    for &i in &order {
        depth[i] = parent[i].map_or(0, |j| depth[j] + 1);
    }
    Nesting {
        areas,
        order,
        parent,
        depth,
    }
}

/// The area of the region of odd winding of closed loops that do not cross: each loop's
/// enclosed area, added at even depths (a piece), taken away at odd ones (a hole).
pub(crate) fn region_area(loops: &[Vec<[f64; 2]>]) -> f64 {
    let n = nesting(loops);
    n.order
        .iter()
        .map(|&i| {
            if n.depth[i] % 2 == 0 {
                n.areas[i]
            } else {
                -n.areas[i]
            }
        })
        .sum()
}

/// The pieces of closed loops that are specks: per loop, the index of the loop that is the
/// outer loop of the speck it belongs to, or `None`.
///
/// Loops nest by parity (as [`super::Outline::from_loops`] takes them): a loop inside an even
/// number of others is a piece's outer loop, the loops directly inside it its holes, a loop
/// inside a hole another piece. A piece's area is the area its outer loop encloses (holes
/// included: a ring counts by its extent); a piece whose area is below `fraction` of the
/// largest piece's is a speck, with everything inside it.
pub(crate) fn specks(loops: &[Vec<[f64; 2]>], fraction: f64) -> Vec<Option<usize>> {
    let Nesting {
        areas,
        order,
        parent,
        depth,
    } = nesting(loops);
    let largest = order
        .iter()
        .filter(|&&i| depth[i] % 2 == 0)
        .map(|&i| areas[i])
        .fold(0.0, f64::max);
    let mut speck: Vec<Option<usize>> = vec![None; loops.len()];
    for &i in &order {
        speck[i] = match parent[i].and_then(|j| speck[j]) {
            Some(root) => Some(root),
            None if depth[i] % 2 == 0 && areas[i] < fraction * largest => Some(i),
            None => None,
        };
    }
    speck
}

/// Simplifies closed loops (as traced: simple, apart from each other) to `tolerance`.
pub(crate) fn simplify(loops: &[Vec<[f64; 2]>], tolerance: f64) -> Simplified {
    simplify_leaving_out(loops, tolerance, &[])
}

/// Simplifies closed loops (as traced: simple, apart from each other) to `tolerance`, leaving
/// out the loops marked in `leave_out` (indexed as `loops`; missing entries are `false`):
/// they are dropped as too small when they are, otherwise listed in
/// [`Simplified::left_out`], and they constrain nothing (the other loops may be simplified
/// across them).
pub(crate) fn simplify_leaving_out(
    loops: &[Vec<[f64; 2]>],
    tolerance: f64,
    leave_out: &[bool],
) -> Simplified {
    let areas: Vec<f64> = loops.iter().map(|l| twice_area(l).abs() / 2.0).collect();
    let largest_area = areas.iter().copied().fold(0.0, f64::max);
    let min_area = (2.0 * tolerance).powi(2);
    // Large enough loops, largest first (so a parent comes before what it holds).
    let order = largest_first(loops, &areas, min_area);
    let boxes: Vec<[f64; 4]> = loops.iter().map(|l| bounds(l)).collect();
    let parent = parents(loops, &boxes, &order);
    let mut keep: Vec<Option<Vec<usize>>> = vec![None; loops.len()];
    for &i in &order {
        if parent[i].is_some_and(|j| keep[j].is_none()) {
            continue; // inside a dropped loop
        }
        let k = douglas_peucker(&loops[i], tolerance);
        if k.len() >= 3 {
            keep[i] = Some(k);
        }
    }
    let mut out = Simplified {
        largest_area,
        ..Simplified::default()
    };
    let mut left_out = vec![false; loops.len()];
    for (i, k) in keep.iter_mut().enumerate() {
        if k.is_some() && leave_out.get(i).copied().unwrap_or(false) {
            *k = None;
            left_out[i] = true;
            out.left_out.push(i);
        }
    }
    repair(loops, &boxes, &mut keep);
    for (i, k) in keep.iter().enumerate() {
        match k {
            Some(k) => {
                out.loops.push(k.iter().map(|&v| loops[i][v]).collect());
                out.kept.push(i);
            }
            None if left_out[i] => {}
            None => out.dropped += 1,
        }
    }
    out
}

/// Gives segments back their farthest dropped point until no simplified segments cross and
/// every loop is inside the same loops as before.
fn repair(loops: &[Vec<[f64; 2]>], boxes: &[[f64; 4]], keep: &mut [Option<Vec<usize>>]) {
    loop {
        // (loop, segment) pairs to refine.
        let mut marked: Vec<(usize, usize)> = Vec::new();
        let mut points = Vec::new();
        let mut segments = Vec::new();
        let mut owner = Vec::new();
        for (i, k) in keep.iter().enumerate() {
            let Some(k) = k else { continue };
            let first = points.len() as u32;
            let m = k.len() as u32;
            points.extend(k.iter().map(|&v| loops[i][v]));
            for s in 0..m {
                segments.push([first + s, first + (s + 1) % m]);
                owner.push((i, s as usize));
            }
        }
        for c in crossings(&points, &segments) {
            marked.push(owner[c.first]);
            marked.push(owner[c.second]);
        }
        // A loop must not have jumped over another: test each loop's first kept point
        // against every other loop, traced and simplified.
        for (l, kl) in keep.iter().enumerate() {
            let Some(kl) = kl else { continue };
            let p = loops[l][kl[0]];
            for (m, km) in keep.iter().enumerate() {
                let Some(km) = km else { continue };
                let b = &boxes[m];
                if m == l || !(p[0] >= b[0] && p[0] <= b[2] && p[1] >= b[1] && p[1] <= b[3]) {
                    continue;
                }
                let simplified: Vec<[f64; 2]> = km.iter().map(|&v| loops[m][v]).collect();
                if contains(&loops[m], p) == contains(&simplified, p) {
                    continue;
                }
                // Refine the segments of m whose dropped stretch surrounds p.
                let n = loops[m].len();
                for s in 0..km.len() {
                    let (i, j) = (km[s], km[(s + 1) % km.len()]);
                    let len = (j + n - i) % n;
                    let stretch: Vec<[f64; 2]> = (0..=len).map(|t| loops[m][(i + t) % n]).collect();
                    let sb = bounds(&stretch);
                    if p[0] >= sb[0] && p[0] <= sb[2] && p[1] >= sb[1] && p[1] <= sb[3] {
                        marked.push((m, s));
                    }
                }
            }
        }
        if marked.is_empty() {
            return;
        }
        marked.sort_unstable();
        marked.dedup();
        let mut refined = false;
        for (l, s) in marked {
            let Some(k) = &keep[l] else { continue };
            let (i, j) = (k[s], k[(s + 1) % k.len()]);
            if let Some((v, _)) = farthest(&loops[l], i, j) {
                if let Some(k) = &mut keep[l] {
                    k.push(v);
                }
                refined = true;
            }
        }
        if !refined {
            return; // only original segments left: they do not cross
        }
        for k in keep.iter_mut().flatten() {
            k.sort_unstable();
            k.dedup();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(c: [f64; 2], r: f64, n: usize) -> Vec<[f64; 2]> {
        (0..n)
            .map(|i| {
                let a = i as f64 / n as f64 * std::f64::consts::TAU;
                [c[0] + r * a.cos(), c[1] + r * a.sin()]
            })
            .collect()
    }

    fn max_distance_to_polygon(points: &[[f64; 2]], polygon: &[[f64; 2]]) -> f64 {
        points
            .iter()
            .map(|&p| {
                (0..polygon.len())
                    .map(|i| distance_to_segment(p, polygon[i], polygon[(i + 1) % polygon.len()]))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn a_circle_keeps_few_points_within_the_tolerance() {
        let c = circle([0.0, 0.0], 100.0, 2000);
        let s = simplify(std::slice::from_ref(&c), 1.0);
        assert_eq!(s.loops.len(), 1);
        let n = s.loops[0].len();
        // A chord of sagitta 1 on radius 100 spans about 2 sqrt(2 r) = 28 units: ~22 of them.
        assert!((16..=40).contains(&n), "{n} points");
        assert!(max_distance_to_polygon(&c, &s.loops[0]) <= 1.0);
    }

    #[test]
    fn specks_and_slivers_are_dropped_with_what_they_hold() {
        let big = circle([0.0, 0.0], 50.0, 400);
        let speck = circle([80.0, 0.0], 0.8, 12);
        // A sliver 0.5 units tall: every point within 1 of its chord.
        let sliver = vec![[0.0, 70.0], [40.0, 70.0], [40.0, 70.5], [0.0, 70.5]];
        let s = simplify(&[big, speck, sliver], 1.0);
        assert_eq!(s.loops.len(), 1);
        assert_eq!(s.dropped, 2);
    }

    #[test]
    fn specks_are_small_pieces_with_what_they_hold() {
        let reversed = |mut l: Vec<[f64; 2]>| {
            l.reverse();
            l
        };
        let loops = vec![
            circle([0.0, 0.0], 100.0, 400),          // 0: the largest piece
            reversed(circle([0.0, 0.0], 40.0, 200)), // 1: its hole
            circle([0.0, 0.0], 15.0, 100),           // 2: an island in it, 2.3%
            circle([300.0, 0.0], 50.0, 200),         // 3: another piece, 25%
            circle([0.0, 200.0], 9.0, 60),           // 4: a speck, 0.8%
            reversed(circle([0.0, 200.0], 4.0, 30)), // 5: its hole
            circle([200.0, 200.0], 2.0, 20),         // 6: a speck
        ];
        let specks = specks(&loops, 0.01);
        assert_eq!(
            specks,
            vec![None, None, None, None, Some(4), Some(4), Some(6)]
        );
        // By nesting, not orientation: the same with every loop counter-clockwise.
        let ccw: Vec<Vec<[f64; 2]>> = loops
            .iter()
            .map(|l| {
                if twice_area(l) < 0.0 {
                    reversed(l.clone())
                } else {
                    l.clone()
                }
            })
            .collect();
        assert_eq!(super::specks(&ccw, 0.01), specks);
        // Everything is a speck of nothing but the largest piece when it is alone.
        assert_eq!(super::specks(&loops[..1], 0.01), vec![None]);
    }

    #[test]
    fn the_region_is_pieces_less_holes() {
        let square = |x: f64, y: f64, s: f64| vec![[x, y], [x + s, y], [x + s, y + s], [x, y + s]];
        let loops = [
            square(0.0, 0.0, 10.0),
            square(3.0, 3.0, 4.0),
            square(4.0, 4.0, 1.0),
            square(20.0, 0.0, 2.0),
        ];
        assert_eq!(region_area(&loops), 100.0 - 16.0 + 1.0 + 4.0);
    }

    #[test]
    fn loops_left_out_constrain_nothing() {
        // As below: without the island in the dent, the dent goes.
        let outer = vec![
            [0.0, 0.0],
            [100.0, 0.0],
            [100.0, 100.0],
            [70.0, 100.0],
            [65.0, 96.0],
            [35.0, 96.0],
            [30.0, 100.0],
            [0.0, 100.0],
        ];
        let island = vec![[45.0, 97.0], [55.0, 97.0], [55.0, 107.0], [45.0, 107.0]];
        let speck = vec![[200.0, 0.0], [200.5, 0.0], [200.5, 0.5]];
        let s = simplify_leaving_out(&[outer, island, speck], 5.0, &[false, true, true]);
        assert_eq!((s.loops.len(), s.loops[0].len()), (1, 4));
        assert_eq!((s.kept, s.left_out, s.dropped), (vec![0], vec![1], 1));
    }

    #[test]
    fn a_loop_close_to_another_is_not_crossed() {
        // A square with a dent 4 deep in its top side, and an island in the dent sticking
        // out above: dropping the dent (it is within the tolerance 5) would cut the island.
        let outer = vec![
            [0.0, 0.0],
            [100.0, 0.0],
            [100.0, 100.0],
            [70.0, 100.0],
            [65.0, 96.0],
            [35.0, 96.0],
            [30.0, 100.0],
            [0.0, 100.0],
        ];
        let island = vec![[45.0, 97.0], [55.0, 97.0], [55.0, 107.0], [45.0, 107.0]];
        let s = simplify(&[outer.clone(), island], 5.0);
        assert_eq!(s.loops.len(), 2);
        assert!(s.loops[0].len() > 4, "some of the dent is back");
        assert!(
            !contains(&s.loops[0], [50.0, 100.0]),
            "the island stays outside"
        );
        let points: Vec<[f64; 2]> = s.loops.concat();
        let m = s.loops[0].len() as u32;
        let segments: Vec<[u32; 2]> = (0..m)
            .map(|k| [k, (k + 1) % m])
            .chain((0..4).map(|k| [m + k, m + (k + 1) % 4]))
            .collect();
        assert!(crossings(&points, &segments).is_empty());
        // Without the island, the dent goes.
        assert_eq!(simplify(&[outer], 5.0).loops[0].len(), 4);
    }
}
