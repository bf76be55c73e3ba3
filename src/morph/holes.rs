//! Filling a piece's holes with hidden triangles, so that the piece is a disk to the solver.
//!
//! A hole's boundary is a closed polygon in every keyframe. It is triangulated over its own
//! vertices (no new ones), by the triangulation that is counter-clockwise in *every* keyframe
//! and, among those, has the best worst triangle (the largest smallest shape quality over
//! all keyframes; then the largest total quality): a dynamic programme over the polygon's
//! sub-chains, `O(n³)` time and `O(n²)` memory for a hole of `n` boundary vertices, times the
//! keyframes.
//!
//! Why every triangle counter-clockwise is enough: in a keyframe where the hole's polygon is
//! simple, a triangulation of it whose triangles are all counter-clockwise covers it exactly
//! once (the triangles' angles at each corner sum to at least the polygon's interior angle
//! there, and all of them together to exactly `(n - 2) π`). So each keyframe, with the hidden
//! triangles added, is a valid flat disk with the same triangles, and the morph's metric
//! blends them like any others: the hole stays closed (no crack) and, while no hidden
//! triangle flips, nothing overlaps across it.
//!
//! A hole that has no such triangulation (its outline crosses itself in a keyframe) is a free
//! one ([`super::closure`]): [`fill_topology`] then fills it for the topology alone.

use std::collections::HashSet;

/// Shape quality of triangle `(a, b, c)`: `4 √3 area / (sum of squared sides)`, 1 for an
/// equilateral triangle, 0 for a degenerate one, negative when clockwise.
fn quality(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    let sq = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
    let sum = sq(a, b) + sq(b, c) + sq(c, a);
    if sum > 0.0 {
        2.0 * 3f64.sqrt() * cross / sum
    } else {
        0.0
    }
}

/// Smallest quality a hidden triangle may have in any keyframe (well away from round-off).
const MIN_QUALITY: f64 = 1e-9;

/// Triangulates the hole whose boundary, counter-clockwise around the hole, is `polygon`
/// (vertex indices into each keyframe's `positions`), counter-clockwise in every keyframe,
/// without using an edge in `taken` (edges the piece already has, as `(lo, hi)`): its
/// `polygon.len() - 2` triangles, or `None` when there is no such triangulation (the hole is
/// then a free one, see [`crate::morph`]).
pub(crate) fn fill(
    polygon: &[u32],
    keyframes: &[&[[f64; 2]]],
    taken: &HashSet<(u32, u32)>,
) -> Option<Vec<[u32; 3]>> {
    triangulate(polygon, keyframes, taken, MIN_QUALITY)
}

/// Triangulates the hole `polygon` for the topology alone (its triangles will be inert, see
/// [`crate::morph`]'s free holes): over its own vertices, without an edge in `taken`, by the
/// triangulation with the best worst shape in `reference` (the first keyframe), clockwise
/// triangles allowed. `None` only when every triangulation needs a diagonal in `taken`.
pub(crate) fn fill_topology(
    polygon: &[u32],
    reference: &[[f64; 2]],
    taken: &HashSet<(u32, u32)>,
) -> Option<Vec<[u32; 3]>> {
    triangulate(polygon, &[reference], taken, f64::NEG_INFINITY)
}

/// The dynamic programme: `best[i][j]` is the best triangulation of the sub-polygon
/// `i, i + 1, ..., j` (closed by the diagonal `(i, j)`), as (worst quality, total quality),
/// among those whose every triangle has at least `min_quality` in every keyframe.
fn triangulate(
    polygon: &[u32],
    keyframes: &[&[[f64; 2]]],
    taken: &HashSet<(u32, u32)>,
    min_quality: f64,
) -> Option<Vec<[u32; 3]>> {
    let n = polygon.len();
    if n < 3 {
        return None;
    }
    // Positions per keyframe, in polygon order.
    let points: Vec<Vec<[f64; 2]>> = keyframes
        .iter()
        .map(|p| polygon.iter().map(|&v| p[v as usize]).collect())
        .collect();
    let q = |i: usize, k: usize, j: usize| -> f64 {
        points
            .iter()
            .map(|p| quality(p[i], p[k], p[j]))
            .fold(f64::INFINITY, f64::min)
    };
    let usable = |i: usize, j: usize| -> bool {
        // Sides of the polygon are the hole's own edges; diagonals must be new edges.
        if j == i + 1 || (i == 0 && j == n - 1) {
            return true;
        }
        let (a, b) = (polygon[i], polygon[j]);
        !taken.contains(&(a.min(b), a.max(b)))
    };
    const NONE: (f64, f64) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    let mut best = vec![NONE; n * n];
    let mut split = vec![u32::MAX; n * n];
    for i in 0..n - 1 {
        best[i * n + i + 1] = (f64::INFINITY, 0.0);
    }
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            if !usable(i, j) {
                continue;
            }
            let mut cell = NONE;
            let mut at = u32::MAX;
            for k in i + 1..j {
                let (left, right) = (best[i * n + k], best[k * n + j]);
                if left.0 == f64::NEG_INFINITY || right.0 == f64::NEG_INFINITY {
                    continue;
                }
                let worst_here = left.0.min(right.0);
                if worst_here < cell.0 {
                    // Cannot beat the best so far.
                    continue;
                }
                let tq = q(i, k, j);
                if tq < min_quality {
                    continue;
                }
                let candidate = (worst_here.min(tq), left.1 + right.1 + tq);
                if candidate > cell {
                    cell = candidate;
                    at = k as u32;
                }
            }
            best[i * n + j] = cell;
            split[i * n + j] = at;
        }
    }
    if best[n - 1].0 == f64::NEG_INFINITY {
        return None;
    }
    let mut triangles = Vec::with_capacity(n - 2);
    let mut stack = vec![(0usize, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j <= i + 1 {
            continue;
        }
        let k = split[i * n + j] as usize;
        triangles.push([polygon[i], polygon[k], polygon[j]]);
        stack.push((i, k));
        stack.push((k, j));
    }
    Some(triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(p: &[[f64; 2]], t: [u32; 3]) -> f64 {
        let [a, b, c] = t.map(|v| p[v as usize]);
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    }

    #[test]
    fn a_square_is_split_into_two_counter_clockwise_triangles() {
        let p = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let t = fill(&[0, 1, 2, 3], &[&p], &HashSet::new()).unwrap();
        assert_eq!(t.len(), 2);
        assert!(t.iter().all(|&t| area(&p, t) > 0.0));
    }

    #[test]
    fn a_triangulation_valid_in_every_keyframe_is_found() {
        // A dart with its reflex corner at 2 (only the diagonal 0-2 works), and a rhombus
        // where the diagonal 1-3 gives the better triangles: together, 0-2.
        let dart = [[0.0, 0.0], [1.0, 0.0], [0.3, 0.3], [0.0, 1.0]];
        let rhombus = [[0.0, 0.0], [1.0, -0.3], [2.0, 0.0], [1.0, 0.3]];
        let polygon = [0, 1, 2, 3];
        let none = HashSet::new();
        let has =
            |t: &[[u32; 3]], a: u32, b: u32| t.iter().any(|t| t.contains(&a) && t.contains(&b));
        let alone = fill(&polygon, &[&rhombus], &none).unwrap();
        assert!(has(&alone, 1, 3), "{alone:?}");
        let both = fill(&polygon, &[&dart, &rhombus], &none).unwrap();
        assert!(has(&both, 0, 2), "{both:?}");
        for p in [&dart, &rhombus] {
            assert!(both.iter().all(|&t| area(p, t) > 0.0), "{both:?}");
        }
    }

    #[test]
    fn a_polygon_clockwise_in_one_keyframe_cannot_be_filled() {
        let a = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let b = [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]];
        assert!(fill(&[0, 1, 2, 3], &[&a, &b], &HashSet::new()).is_none());
        // For the topology alone it can: the first keyframe's shape chooses.
        let t = fill_topology(&[0, 1, 2, 3], &a, &HashSet::new()).unwrap();
        assert_eq!(t.len(), 2);
        assert!(t.iter().all(|&t| area(&a, t) > 0.0));
    }

    #[test]
    fn diagonals_the_mesh_already_has_are_not_used() {
        let p = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let taken: HashSet<_> = [(0, 2)].into_iter().collect();
        let t = fill(&[0, 1, 2, 3], &[&p], &taken).unwrap();
        assert!(
            t.iter().all(|t| !(t.contains(&0) && t.contains(&2))),
            "{t:?}"
        );
        let both: HashSet<_> = [(0, 2), (1, 3)].into_iter().collect();
        assert!(fill(&[0, 1, 2, 3], &[&p], &both).is_none());
        assert!(fill_topology(&[0, 1, 2, 3], &p, &both).is_none());
    }
}
