//! Local changes to A's mesh that the layout over another drawing needs or allows:
//! - [`split_boundary_chords`]: an edge inside the mesh joining two outline vertices (the
//!   third side of an ear, a rung across a thin part) pins a straight segment between two
//!   points of the other drawing's outline, which may leave its drawing or cross itself
//!   there; split at its middle, it bends freely. Meshing from outlines makes many such edges
//!   at the corners of pixel outlines.
//! - [`collapse_added`]: after the guarantee's re-embedding, the vertices it added are
//!   merged into a neighbour wherever no layout then has a flipped or degenerate triangle,
//!   so that the refinement keeps only what the bijection needs.

use std::collections::HashMap;
use std::panic::{catch_unwind, AssertUnwindSafe};

use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};

use super::foldover::signed_area;
use super::layout::{squared_size, REFINED_AREA_SHARE};
use crate::mesh::PlanarMesh;

/// Fills the holes of `mesh` whose boundary runs along one of `loops` (A's transparent
/// regions, meshed first as holes) with triangles: a constrained Delaunay triangulation of
/// the hole's boundary vertices as they are (its edges kept whole), refined to about the
/// mesh's own triangle size and `min_angle` degrees. Returns, per triangle of the result,
/// whether it is one of the fill's.
pub(super) fn fill_holes(
    mesh: &mut PlanarMesh,
    loops: &[Vec<[f64; 2]>],
    min_angle: f64,
) -> Option<Vec<bool>> {
    type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;
    let mut filled = vec![false; mesh.faces.len()];
    if loops.is_empty() {
        return Some(filled);
    }
    let total: f64 = mesh.faces.iter().map(|f| mesh.signed_area(f)).sum();
    let mean = total / mesh.faces.len().max(1) as f64;
    let size = mesh.diameter().max(f64::MIN_POSITIVE);
    let on_loop = |p: [f64; 2], l: &[[f64; 2]]| {
        let n = l.len();
        (0..n).any(|i| super::outline::closest_on_segment(p, l[i], l[(i + 1) % n]).1 <= 1e-9 * size)
    };
    let boundary = boundary_loops(&mesh.faces);
    for l in loops {
        // The mesh's hole along this loop: a boundary loop whose vertices are all on it.
        let hole = boundary
            .iter()
            .find(|b| b.iter().all(|&v| on_loop(mesh.positions[v as usize], l)))?;
        // Counter-clockwise (the hole's boundary runs clockwise in the mesh).
        let ring: Vec<u32> = hole.iter().rev().copied().collect();
        let points: Vec<Point2<f64>> = ring
            .iter()
            .map(|&v| Point2::new(mesh.positions[v as usize][0], mesh.positions[v as usize][1]))
            .collect();
        let n = ring.len();
        let edges: Vec<[usize; 2]> = (0..n).map(|i| [i, (i + 1) % n]).collect();
        let mut conflicts = 0;
        let mut cdt = Cdt::try_bulk_load_cdt(points, edges, |_| conflicts += 1).ok()?;
        if conflicts > 0 || cdt.num_vertices() != n {
            return None;
        }
        let params = RefinementParameters::<f64>::new()
            .keep_constraint_edges()
            .exclude_outer_faces(true)
            .with_angle_limit(AngleLimit::from_deg(min_angle.min(25.0)))
            .with_max_allowed_area(1.5 * mean)
            .with_max_additional_vertices(20 * n + 1000);
        let result = catch_unwind(AssertUnwindSafe(|| cdt.refine(params))).ok()?;
        let mut outside = vec![false; cdt.num_all_faces()];
        for f in result.excluded_faces {
            outside[f.index()] = true;
        }
        let index: HashMap<(u64, u64), u32> = ring
            .iter()
            .map(|&v| {
                let p = mesh.positions[v as usize];
                ((p[0].to_bits(), p[1].to_bits()), v)
            })
            .collect();
        let mut number: HashMap<usize, u32> = HashMap::new();
        for f in cdt.inner_faces() {
            if outside[f.fix().index()] {
                continue;
            }
            let mut tri = [0u32; 3];
            for (k, v) in f.vertices().iter().enumerate() {
                let q = v.position();
                tri[k] = match index.get(&(q.x.to_bits(), q.y.to_bits())) {
                    Some(&w) => w,
                    None => *number.entry(v.fix().index()).or_insert_with(|| {
                        mesh.positions.push([q.x, q.y]);
                        (mesh.positions.len() - 1) as u32
                    }),
                };
            }
            if mesh.signed_area(&tri) < 0.0 {
                tri.swap(1, 2);
            }
            mesh.faces.push(tri);
            filled.push(true);
        }
    }
    Some(filled)
}

/// The boundary loops of `faces`, each a list of vertices in order (outer loops
/// counter-clockwise, holes clockwise); a vertex where loops touch ends them early.
fn boundary_loops(faces: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut directed: HashMap<(u32, u32), ()> = HashMap::with_capacity(3 * faces.len());
    for f in faces {
        for k in 0..3 {
            directed.insert((f[k], f[(k + 1) % 3]), ());
        }
    }
    let mut next: HashMap<u32, u32> = HashMap::new();
    for &(a, b) in directed.keys() {
        if !directed.contains_key(&(b, a)) {
            next.insert(a, b);
        }
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut seen: std::collections::HashSet<u32> = std::collections::HashSet::new();
    let mut loops = Vec::new();
    for s in starts {
        if seen.contains(&s) {
            continue;
        }
        let mut l = Vec::new();
        let mut v = s;
        while seen.insert(v) {
            l.push(v);
            match next.get(&v) {
                Some(&w) => v = w,
                None => break,
            }
        }
        loops.push(l);
    }
    loops
}

/// Splits every edge between two boundary vertices that is not itself on the boundary at
/// its middle (in A). The boundary is unchanged; the new vertices are inside. Returns how
/// many edges were split.
pub(super) fn split_boundary_chords(mesh: &mut PlanarMesh) -> usize {
    let n = mesh.positions.len();
    let mut edge_face: HashMap<(u32, u32), usize> = HashMap::with_capacity(3 * mesh.faces.len());
    for (f, tri) in mesh.faces.iter().enumerate() {
        for k in 0..3 {
            edge_face.insert((tri[k], tri[(k + 1) % 3]), f);
        }
    }
    let mut on = vec![false; n];
    for (&(a, b), _) in edge_face.iter() {
        if !edge_face.contains_key(&(b, a)) {
            on[a as usize] = true;
            on[b as usize] = true;
        }
    }
    let mut chords: Vec<(u32, u32)> = edge_face
        .keys()
        .filter(|&&(a, b)| a < b && on[a as usize] && on[b as usize])
        .filter(|&&(a, b)| edge_face.contains_key(&(b, a)))
        .copied()
        .collect();
    chords.sort_unstable();
    for &(a, b) in &chords {
        let (Some(&f), Some(&g)) = (edge_face.get(&(a, b)), edge_face.get(&(b, a))) else {
            continue;
        };
        let third = |tri: [u32; 3], x: u32, y: u32| {
            tri.iter().copied().find(|&v| v != x && v != y).unwrap_or(x)
        };
        let c = third(mesh.faces[f], a, b);
        let d = third(mesh.faces[g], a, b);
        let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        let m = mesh.positions.len() as u32;
        mesh.positions
            .push([0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])]);
        // f = (a, b, c) -> (a, m, c), (m, b, c); g = (b, a, d) -> (b, m, d), (m, a, d).
        edge_face.remove(&(a, b));
        edge_face.remove(&(b, a));
        let mut set = |faces: &mut Vec<[u32; 3]>, k: usize, tri: [u32; 3]| {
            if k == faces.len() {
                faces.push(tri);
            } else {
                faces[k] = tri;
            }
            for i in 0..3 {
                edge_face.insert((tri[i], tri[(i + 1) % 3]), k);
            }
        };
        set(&mut mesh.faces, f, [a, m, c]);
        let k = mesh.faces.len();
        set(&mut mesh.faces, k, [m, b, c]);
        set(&mut mesh.faces, g, [b, m, d]);
        let k = mesh.faces.len();
        set(&mut mesh.faces, k, [m, a, d]);
    }
    relax(mesh, n);
    chords.len()
}

/// Moves each vertex numbered from `first` on towards the mean of its neighbours (a few
/// rounds), when that makes the smallest angle around it larger and no triangle thinner.
fn relax(mesh: &mut PlanarMesh, first: usize) {
    let n = mesh.positions.len();
    if n <= first {
        return;
    }
    let mut star: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (f, tri) in mesh.faces.iter().enumerate() {
        for &v in tri {
            if v as usize >= first {
                star[v as usize].push(f as u32);
            }
        }
    }
    let smallest_angle = |positions: &[[f64; 2]], faces: &[u32], all: &[[u32; 3]]| {
        faces
            .iter()
            .map(|&f| {
                let [a, b, c] = all[f as usize].map(|v| positions[v as usize]);
                let angle = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
                    let (u, w) = ([q[0] - p[0], q[1] - p[1]], [r[0] - p[0], r[1] - p[1]]);
                    (u[0] * w[1] - u[1] * w[0]).atan2(u[0] * w[0] + u[1] * w[1])
                };
                angle(a, b, c).min(angle(b, c, a)).min(angle(c, a, b))
            })
            .fold(f64::INFINITY, f64::min)
    };
    for _ in 0..5 {
        for (v, around) in star.iter().enumerate().skip(first) {
            let mut sum = [0.0, 0.0];
            let mut count = 0.0;
            for &f in around {
                for &w in &mesh.faces[f as usize] {
                    if w as usize != v {
                        sum[0] += mesh.positions[w as usize][0];
                        sum[1] += mesh.positions[w as usize][1];
                        count += 1.0;
                    }
                }
            }
            if count == 0.0 {
                continue;
            }
            let before = smallest_angle(&mesh.positions, around, &mesh.faces);
            let old = mesh.positions[v];
            mesh.positions[v] = [sum[0] / count, sum[1] / count];
            let after = smallest_angle(&mesh.positions, around, &mesh.faces);
            if after.is_nan() || after <= before {
                mesh.positions[v] = old;
            }
        }
    }
}

/// Merges vertices numbered from `first_added` on into a neighbour (its places kept) while
/// every layout in `layouts` (A's first) keeps every triangle's area above its validity
/// threshold, and the mesh stays a manifold (the link condition). Removes the merged
/// vertices (the others keep their order) and returns how many were merged.
pub(super) fn collapse_added(
    faces: &mut Vec<[u32; 3]>,
    origin: &mut Vec<u32>,
    layouts: &mut [&mut Vec<[f64; 2]>],
    first_added: usize,
) -> usize {
    let n = layouts.first().map_or(0, |l| l.len());
    if n <= first_added {
        return 0;
    }
    let thresholds: Vec<f64> = layouts
        .iter()
        .map(|l| REFINED_AREA_SHARE * squared_size(l))
        .collect();
    let mut star: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (f, tri) in faces.iter().enumerate() {
        for &v in tri {
            star[v as usize].push(f as u32);
        }
    }
    let mut dead = vec![false; faces.len()];
    let mut gone = vec![false; n];
    let neighbours = |faces: &[[u32; 3]], star: &[Vec<u32>], dead: &[bool], v: u32| {
        let mut out: Vec<u32> = star[v as usize]
            .iter()
            .filter(|&&f| !dead[f as usize])
            .flat_map(|&f| faces[f as usize])
            .filter(|&w| w != v)
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    };
    let mut merged = 0;
    loop {
        let mut changed = false;
        for v in first_added as u32..n as u32 {
            if gone[v as usize] {
                continue;
            }
            let around = neighbours(faces, &star, &dead, v);
            // Old vertices first, then the nearest in A.
            let mut candidates = around.clone();
            let pv = layouts[0][v as usize];
            candidates.sort_by(|&x, &y| {
                let d = |w: u32| {
                    let p = layouts[0][w as usize];
                    (p[0] - pv[0]).hypot(p[1] - pv[1])
                };
                ((x as usize) >= first_added)
                    .cmp(&((y as usize) >= first_added))
                    .then(d(x).total_cmp(&d(y)))
            });
            for u in candidates {
                // The link condition: the common neighbours are the edge's opposite corners.
                let shared: Vec<u32> = star[v as usize]
                    .iter()
                    .filter(|&&f| !dead[f as usize] && faces[f as usize].contains(&u))
                    .copied()
                    .collect();
                let opposite = shared.len();
                let nu = neighbours(faces, &star, &dead, u);
                let common = around
                    .iter()
                    .filter(|w| nu.binary_search(w).is_ok())
                    .count();
                if common != opposite {
                    continue;
                }
                // Every triangle around v moved onto u stays valid in every layout.
                let ok = star[v as usize].iter().all(|&f| {
                    if dead[f as usize] || shared.contains(&f) {
                        return true;
                    }
                    let tri = faces[f as usize].map(|w| if w == v { u } else { w });
                    layouts
                        .iter()
                        .zip(&thresholds)
                        .all(|(l, &m)| signed_area(l, &tri) > m)
                });
                if !ok {
                    continue;
                }
                for &f in &shared {
                    dead[f as usize] = true;
                }
                let moved: Vec<u32> = star[v as usize]
                    .iter()
                    .copied()
                    .filter(|&f| !dead[f as usize])
                    .collect();
                for &f in &moved {
                    for w in faces[f as usize].iter_mut() {
                        if *w == v {
                            *w = u;
                        }
                    }
                    star[u as usize].push(f);
                }
                star[v as usize].clear();
                gone[v as usize] = true;
                merged += 1;
                changed = true;
                break;
            }
        }
        if !changed {
            break;
        }
    }
    // Renumber: the vertices kept, in order.
    let mut number = vec![u32::MAX; n];
    let mut next = 0u32;
    for v in 0..n {
        if !gone[v] {
            number[v] = next;
            next += 1;
        }
    }
    let kept: Vec<[u32; 3]> = faces
        .iter()
        .zip(&dead)
        .filter(|(_, &d)| !d)
        .map(|(tri, _)| tri.map(|w| number[w as usize]))
        .collect();
    *faces = kept;
    let mut k = 0;
    origin.retain(|_| {
        let keep = !dead[k];
        k += 1;
        keep
    });
    for l in layouts.iter_mut() {
        let mut k = 0;
        l.retain(|_| {
            let keep = !gone[k];
            k += 1;
            keep
        });
    }
    merged
}

/// The smallest angle (radians) of triangle `f` at `p`.
fn smallest_angle(p: &[[f64; 2]], f: &[u32; 3]) -> f64 {
    let [a, b, c] = f.map(|v| p[v as usize]);
    let angle = |o: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        let (u, w) = ([q[0] - o[0], q[1] - o[1]], [r[0] - o[0], r[1] - o[1]]);
        (u[0] * w[1] - u[1] * w[0]).atan2(u[0] * w[0] + u[1] * w[1])
    };
    angle(a, b, c).min(angle(b, c, a)).min(angle(c, a, b))
}

/// Flips edges inside the mesh where that makes the smaller angle of the two triangles
/// around them larger in A (`layouts[0]`) and every layout keeps both triangles' areas above
/// its validity threshold: the thin triangles a re-embedding cuts, made rounder where the
/// layouts allow (each flip only where a triangle is thinner than `below` radians). Returns
/// the flips made.
pub(super) fn flip_thin(faces: &mut [[u32; 3]], layouts: &[&Vec<[f64; 2]>], below: f64) -> usize {
    let thresholds: Vec<f64> = layouts
        .iter()
        .map(|l| REFINED_AREA_SHARE * squared_size(l))
        .collect();
    let a = layouts[0];
    let mut edge_face: HashMap<(u32, u32), usize> = HashMap::with_capacity(3 * faces.len());
    for (f, tri) in faces.iter().enumerate() {
        for k in 0..3 {
            edge_face.insert((tri[k], tri[(k + 1) % 3]), f);
        }
    }
    let mut flips = 0;
    for _ in 0..20 {
        let mut changed = false;
        for f in 0..faces.len() {
            if smallest_angle(a, &faces[f]) >= below {
                continue;
            }
            for k in 0..3 {
                let tri = faces[f];
                let (p, q, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
                let Some(&g) = edge_face.get(&(q, p)) else {
                    continue;
                };
                let other = faces[g];
                let Some(&d) = other.iter().find(|&&v| v != p && v != q) else {
                    continue;
                };
                if edge_face.contains_key(&(c, d)) || edge_face.contains_key(&(d, c)) {
                    continue;
                }
                // (p, q, c) and (q, p, d) become (p, d, c) and (q, c, d).
                let (n1, n2) = ([p, d, c], [q, c, d]);
                let before = smallest_angle(a, &tri).min(smallest_angle(a, &other));
                let after = smallest_angle(a, &n1).min(smallest_angle(a, &n2));
                if after.is_nan() || after <= before {
                    continue;
                }
                let valid = layouts
                    .iter()
                    .zip(&thresholds)
                    .all(|(l, &m)| signed_area(l, &n1) > m && signed_area(l, &n2) > m);
                if !valid {
                    continue;
                }
                for t in [tri, other] {
                    for i in 0..3 {
                        edge_face.remove(&(t[i], t[(i + 1) % 3]));
                    }
                }
                faces[f] = n1;
                faces[g] = n2;
                for (h, t) in [(f, n1), (g, n2)] {
                    for i in 0..3 {
                        edge_face.insert((t[i], t[(i + 1) % 3]), h);
                    }
                }
                flips += 1;
                changed = true;
                break;
            }
        }
        if !changed {
            break;
        }
    }
    flips
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chords_of_a_strip_are_split() {
        // A strip one triangle wide: every inner edge joins two boundary vertices.
        let positions = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [0.0, 1.0],
            [1.0, 1.0],
            [2.0, 1.0],
        ];
        let faces = vec![[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]];
        let mut mesh = PlanarMesh { positions, faces };
        let split = split_boundary_chords(&mut mesh);
        assert_eq!(split, 3);
        assert_eq!(mesh.positions.len(), 9);
        assert_eq!(mesh.faces.len(), 10);
        assert!(mesh.faces.iter().all(|f| mesh.signed_area(f) > 0.0));
        // No edge inside joins two boundary vertices now.
        assert_eq!(split_boundary_chords(&mut mesh), 0);
        // And every added vertex can be merged back when nothing forbids it.
        let mut layout = mesh.positions.clone();
        let mut a = mesh.positions.clone();
        let mut origin: Vec<u32> = (0..mesh.faces.len() as u32).collect();
        let merged = collapse_added(&mut mesh.faces, &mut origin, &mut [&mut a, &mut layout], 6);
        assert_eq!(origin.len(), mesh.faces.len());
        assert_eq!(merged, 3);
        assert_eq!(mesh.faces.len(), 4);
        assert!(mesh.faces.iter().all(|f| signed_area(&a, f) > 0.0));
    }
}
