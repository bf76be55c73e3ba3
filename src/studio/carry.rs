//! Carrying an animation over to a new mesh of the same subject: every keyframe's pose, and its
//! pins, moved from the old rest mesh's vertices to the new one's.
//!
//! Each new vertex is located in the old rest mesh (the triangle holding it and its barycentric
//! coordinates there, through a uniform grid of the old triangles); in every keyframe it goes
//! where those coordinates put it in that triangle's posed corners. A new vertex outside the old
//! mesh (a new outline reaching beyond the old one) follows the nearest old triangle's affine
//! map, and is counted. Pins move to the new vertices nearest their rest places. The new poses
//! may have flipped triangles where a new triangle straddles a fold of an old pose; the caller
//! counts them.

use super::project::{Keyframe, KeyframeDrawing};
use crate::mesh::PlanarMesh;

/// What [`carry`] made.
#[derive(Clone, Debug)]
pub struct Carried {
    /// The keyframes on the new mesh (times, easings kept).
    pub keyframes: Vec<Keyframe>,
    /// New vertices outside the old mesh (placed by the nearest old triangle).
    pub outside: usize,
    /// Pins that landed on a vertex another pin had already taken (dropped).
    pub merged_pins: usize,
}

/// A uniform grid over a box, each cell listing items.
struct Grid {
    origin: [f64; 2],
    cell: f64,
    columns: usize,
    rows: usize,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Grid {
    /// A grid of about `count` cells over `lo..hi`, items given by their boxes.
    fn new(lo: [f64; 2], hi: [f64; 2], count: usize, boxes: &[[f64; 4]]) -> Grid {
        let (w, h) = ((hi[0] - lo[0]).max(1e-300), (hi[1] - lo[1]).max(1e-300));
        let cell = ((w * h) / count.max(1) as f64)
            .sqrt()
            .max(w.max(h) / 4096.0);
        let columns = ((w / cell).ceil() as usize).clamp(1, 4096);
        let rows = ((h / cell).ceil() as usize).clamp(1, 4096);
        let mut grid = Grid {
            origin: lo,
            cell,
            columns,
            rows,
            start: vec![0; columns * rows + 1],
            items: Vec::new(),
        };
        for pass in 0..2 {
            let mut fill = grid.start.clone();
            for (i, b) in boxes.iter().enumerate() {
                let (c0, r0) = grid.cell_of([b[0], b[1]]);
                let (c1, r1) = grid.cell_of([b[2], b[3]]);
                for r in r0..=r1 {
                    for c in c0..=c1 {
                        let at = r * columns + c;
                        if pass == 0 {
                            grid.start[at + 1] += 1;
                        } else {
                            grid.items[fill[at] as usize] = i as u32;
                            fill[at] += 1;
                        }
                    }
                }
            }
            if pass == 0 {
                for k in 0..columns * rows {
                    grid.start[k + 1] += grid.start[k];
                }
                grid.items = vec![0; grid.start[columns * rows] as usize];
            }
        }
        grid
    }

    fn cell_of(&self, p: [f64; 2]) -> (usize, usize) {
        let c = ((p[0] - self.origin[0]) / self.cell).floor();
        let r = ((p[1] - self.origin[1]) / self.cell).floor();
        let clamp = |v: f64, n: usize| {
            if v.is_nan() {
                0
            } else {
                v.clamp(0.0, (n - 1) as f64) as usize
            }
        };
        (clamp(c, self.columns), clamp(r, self.rows))
    }

    fn cell_items(&self, c: usize, r: usize) -> &[u32] {
        let at = r * self.columns + c;
        &self.items[self.start[at] as usize..self.start[at + 1] as usize]
    }

    /// Items in the ring of cells at Chebyshev distance `ring` around `(c, r)`.
    fn ring(&self, c: usize, r: usize, ring: usize, mut visit: impl FnMut(u32)) {
        let (c, r, k) = (c as isize, r as isize, ring as isize);
        for dr in -k..=k {
            for dc in -k..=k {
                if dr.abs() != k && dc.abs() != k {
                    continue;
                }
                let (cc, rr) = (c + dc, r + dr);
                if cc < 0 || rr < 0 || cc >= self.columns as isize || rr >= self.rows as isize {
                    continue;
                }
                for &i in self.cell_items(cc as usize, rr as usize) {
                    visit(i);
                }
            }
        }
    }

    fn rings(&self) -> usize {
        self.columns.max(self.rows)
    }
}

fn bounds(points: impl Iterator<Item = [f64; 2]>) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// Barycentric coordinates of `p` in the triangle `t` (affine: any point has them).
fn barycentric(t: [[f64; 2]; 3], p: [f64; 2]) -> [f64; 3] {
    let [a, b, c] = t;
    let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    let u = ((b[0] - p[0]) * (c[1] - p[1]) - (c[0] - p[0]) * (b[1] - p[1])) / det;
    let v = ((c[0] - p[0]) * (a[1] - p[1]) - (a[0] - p[0]) * (c[1] - p[1])) / det;
    [u, v, 1.0 - u - v]
}

/// Squared distance from `p` to the segment `a b`.
fn segment_distance2(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let s = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (x, y) = (a[0] + s * dx - p[0], a[1] + s * dy - p[1]);
    x * x + y * y
}

/// The old triangle holding each new vertex (or the nearest), with its coordinates there.
fn locate(old: &PlanarMesh, points: &[[f64; 2]]) -> (Vec<(u32, [f64; 3])>, usize) {
    let corners = |f: usize| old.faces[f].map(|v| old.positions[v as usize]);
    let boxes: Vec<[f64; 4]> = (0..old.faces.len())
        .map(|f| {
            let (lo, hi) = bounds(corners(f).into_iter());
            [lo[0], lo[1], hi[0], hi[1]]
        })
        .collect();
    let (lo, hi) = bounds(old.positions.iter().copied());
    let grid = Grid::new(lo, hi, old.faces.len(), &boxes);
    let tolerance = 1e-12;
    let mut outside = 0;
    let located = points
        .iter()
        .map(|&p| {
            let (c, r) = grid.cell_of(p);
            let inside = grid.cell_items(c, r).iter().find_map(|&f| {
                let w = barycentric(corners(f as usize), p);
                w.iter().all(|&x| x >= -tolerance).then_some((f, w))
            });
            if let Some(found) = inside {
                return found;
            }
            // The nearest triangle: rings of cells outwards until one is found, then one
            // ring more (a nearer triangle may start in the next ring).
            outside += 1;
            let mut best = (f64::INFINITY, 0u32);
            let mut found_at = None;
            for ring in 0..=grid.rings() {
                grid.ring(c, r, ring, |f| {
                    let t = corners(f as usize);
                    let d = (0..3)
                        .map(|k| segment_distance2(t[k], t[(k + 1) % 3], p))
                        .fold(f64::INFINITY, f64::min);
                    if d < best.0 {
                        best = (d, f);
                    }
                });
                match found_at {
                    None if best.0.is_finite() => found_at = Some(ring),
                    Some(at) if ring > at => break,
                    _ => {}
                }
            }
            let f = best.1;
            (f, barycentric(corners(f as usize), p))
        })
        .collect();
    (located, outside)
}

/// The new vertex nearest each of `points`.
fn nearest_vertices(mesh: &PlanarMesh, points: &[[f64; 2]]) -> Vec<u32> {
    let boxes: Vec<[f64; 4]> = mesh
        .positions
        .iter()
        .map(|p| [p[0], p[1], p[0], p[1]])
        .collect();
    let (lo, hi) = bounds(mesh.positions.iter().copied());
    let grid = Grid::new(lo, hi, mesh.positions.len(), &boxes);
    points
        .iter()
        .map(|&p| {
            let (c, r) = grid.cell_of(p);
            let mut best = (f64::INFINITY, 0u32);
            let mut found_at = None;
            for ring in 0..=grid.rings() {
                grid.ring(c, r, ring, |v| {
                    let q = mesh.positions[v as usize];
                    let d = (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2);
                    if d < best.0 {
                        best = (d, v);
                    }
                });
                match found_at {
                    None if best.0.is_finite() => found_at = Some(ring),
                    Some(at) if ring > at => break,
                    _ => {}
                }
            }
            best.1
        })
        .collect()
}

/// `keyframes` (poses of `old`) carried over to `new` (see the [module docs](self)).
pub fn carry(old: &PlanarMesh, keyframes: &[Keyframe], new: &PlanarMesh) -> Carried {
    let (located, outside) = locate(old, &new.positions);
    let mut merged_pins = 0;
    let keyframes = keyframes
        .iter()
        .map(|key| {
            // Per-vertex values (a pose, a drawing's texture coordinates) at the new vertices.
            let at_new = |values: &[[f64; 2]]| -> Vec<[f64; 2]> {
                located
                    .iter()
                    .map(|&(f, w)| {
                        let [a, b, c] = old.faces[f as usize].map(|v| values[v as usize]);
                        [
                            w[0] * a[0] + w[1] * b[0] + w[2] * c[0],
                            w[0] * a[1] + w[1] * b[1] + w[2] * c[1],
                        ]
                    })
                    .collect()
            };
            let positions = at_new(&key.positions);
            let places: Vec<[f64; 2]> = key
                .pins
                .iter()
                .map(|&v| old.positions[v as usize])
                .collect();
            let mut pins = Vec::with_capacity(places.len());
            for v in nearest_vertices(new, &places) {
                if pins.contains(&v) {
                    merged_pins += 1;
                } else {
                    pins.push(v);
                }
            }
            Keyframe {
                time: key.time,
                easing: key.easing.clone(),
                positions,
                pins,
                drawing: key.drawing.as_ref().map(|d| KeyframeDrawing {
                    texcoords: at_new(&d.texcoords),
                    ..d.clone()
                }),
            }
        })
        .collect();
    Carried {
        keyframes,
        outside,
        merged_pins,
    }
}

/// For each triangle of `new`, the triangle of `old` holding its centroid (or the nearest
/// one): how per-triangle paint (depth, stiffness) carries over to a new mesh.
pub fn carry_faces(old: &PlanarMesh, new: &PlanarMesh) -> Vec<u32> {
    let centroids: Vec<[f64; 2]> = new
        .faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|v| new.positions[v as usize]);
            [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0]
        })
        .collect();
    locate(old, &centroids)
        .0
        .into_iter()
        .map(|(f, _)| f)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate;

    /// An affine pose of the old mesh carries over exactly (every new vertex inside or not).
    #[test]
    fn affine_poses_carry_over_exactly_and_pins_find_their_places() {
        let old = generate::disk(12, 0.2);
        let new = generate::disk(20, 0.05);
        let affine = |p: [f64; 2]| [1.3 * p[0] - 0.4 * p[1] + 2.0, 0.2 * p[0] + 0.9 * p[1] - 1.0];
        let keyframes = vec![
            super::super::edit::keyframe_at(0.0, old.positions.clone()),
            Keyframe {
                time: 1.0,
                easing: "ease-in-out".into(),
                positions: old.positions.iter().map(|&p| affine(p)).collect(),
                pins: vec![0, (old.positions.len() - 1) as u32],
                drawing: None,
            },
        ];
        let carried = carry(&old, &keyframes, &new);
        assert_eq!(carried.keyframes.len(), 2);
        for (p, q) in new.positions.iter().zip(&carried.keyframes[0].positions) {
            assert!((p[0] - q[0]).abs() < 1e-12 && (p[1] - q[1]).abs() < 1e-12);
        }
        for (p, q) in new.positions.iter().zip(&carried.keyframes[1].positions) {
            let a = affine(*p);
            assert!(
                (a[0] - q[0]).abs() < 1e-9 && (a[1] - q[1]).abs() < 1e-9,
                "{a:?} {q:?}"
            );
        }
        assert_eq!(carried.keyframes[1].easing, "ease-in-out");
        // The centre pin lands on the new centre; the rim pin on a rim vertex near it.
        let pins = &carried.keyframes[1].pins;
        assert_eq!(pins.len(), 2);
        let centre = new.positions[pins[0] as usize];
        assert!(centre[0].hypot(centre[1]) < 1e-9);
        let rim = new.positions[pins[1] as usize];
        let was = old.positions[old.positions.len() - 1];
        assert!((rim[0] - was[0]).hypot(rim[1] - was[1]) < 0.2);
    }

    #[test]
    fn paint_carries_to_the_triangles_over_it() {
        let old = generate::grid(5, 5, 0.0); // [0, 4]^2
        let mut new = generate::grid(9, 9, 0.0);
        for p in &mut new.positions {
            *p = [0.5 * p[0], 0.5 * p[1]]; // [0, 4]^2, finer
        }
        let map = carry_faces(&old, &new);
        assert_eq!(map.len(), new.faces.len());
        for (f, &o) in new.faces.iter().zip(&map) {
            let c = f.map(|v| new.positions[v as usize]);
            let centre = [
                (c[0][0] + c[1][0] + c[2][0]) / 3.0,
                (c[0][1] + c[1][1] + c[2][1]) / 3.0,
            ];
            let oc = old.faces[o as usize].map(|v| old.positions[v as usize]);
            let (lo, hi) = bounds(oc.into_iter());
            assert!(
                centre[0] >= lo[0] - 1e-9 && centre[0] <= hi[0] + 1e-9,
                "{centre:?} is not over old triangle {o}"
            );
            assert!(centre[1] >= lo[1] - 1e-9 && centre[1] <= hi[1] + 1e-9);
        }
    }

    #[test]
    fn vertices_outside_the_old_mesh_follow_the_nearest_triangle() {
        let old = generate::grid(5, 5, 0.0); // 0..4 square
        let mut new = generate::grid(7, 7, 0.0);
        for p in &mut new.positions {
            *p = [p[0] - 1.0, p[1] - 1.0]; // -1..5: a ring of vertices outside
        }
        let shift: Vec<[f64; 2]> = old.positions.iter().map(|p| [p[0] + 3.0, p[1]]).collect();
        let keyframes = vec![super::super::edit::keyframe_at(0.0, shift)];
        let carried = carry(&old, &keyframes, &new);
        assert_eq!(carried.outside, 24);
        for (p, q) in new.positions.iter().zip(&carried.keyframes[0].positions) {
            assert!((p[0] + 3.0 - q[0]).abs() < 1e-9 && (p[1] - q[1]).abs() < 1e-9);
        }
    }
}
