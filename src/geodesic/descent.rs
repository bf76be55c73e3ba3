//! A path down a distance field: from a vertex, follow the steepest descent of a distance
//! (linear in each triangle) across the faces until it reaches the source. With the heat
//! method's distance this is the fast, approximate shortest path (`geodesic --path` without
//! `--exact`); [`super::ExactGeodesics::path`] is the exact one.
//!
//! Inside a face the path is straight along `-∇d`, leaving through the edge it reaches first
//! (computed on barycentric coordinates, so it never leaves the face's plane). Across an
//! edge it continues in the next face, or, where the next face's descent points back (a
//! valley along the edge), along the edge to its lower end. At a vertex it takes the
//! steepest face whose descent points into it, or else the steepest edge down. It stops at a
//! vertex of distance zero, or goes straight to one from a face that holds it.

use super::exact::{GeodesicPath, OnSurface, PathPoint};
use super::intrinsic::{Intrinsic, NONE};
use super::GeodesicError;
use crate::io::SurfaceMesh;

use crate::vec3::{cross, dot, sub};

/// Where the walk is.
#[derive(Clone, Copy, Debug)]
enum At {
    Vertex(u32),
    /// Inside face `f` (or on its boundary) at barycentric coordinates `b`.
    Face(usize, [f64; 3]),
}

struct Walker<'a> {
    mesh: &'a SurfaceMesh,
    distance: &'a [f64],
    twin: Vec<u32>,
    /// Half-edges leaving each vertex (CSR).
    out_start: Vec<u32>,
    out: Vec<u32>,
}

impl Walker<'_> {
    fn corners(&self, f: usize) -> [[f64; 3]; 3] {
        self.mesh.faces[f].map(|v| self.mesh.positions[v as usize])
    }

    /// The gradients of the barycentric coordinates of face `f`.
    fn barycentric_gradients(&self, f: usize) -> [[f64; 3]; 3] {
        let [p0, p1, p2] = self.corners(f);
        let n = cross(sub(p1, p0), sub(p2, p0));
        let nn = dot(n, n);
        let edges = [sub(p2, p1), sub(p0, p2), sub(p1, p0)];
        edges.map(|e| {
            let g = cross(n, e);
            [g[0] / nn, g[1] / nn, g[2] / nn]
        })
    }

    /// The descent direction `-∇d` in face `f`, and the barycentric gradients.
    fn descent(&self, f: usize) -> ([f64; 3], [[f64; 3]; 3]) {
        let g = self.barycentric_gradients(f);
        let d = self.mesh.faces[f].map(|v| self.distance[v as usize]);
        let mut out = [0.0; 3];
        for i in 0..3 {
            for (k, o) in out.iter_mut().enumerate() {
                *o -= d[i] * g[i][k];
            }
        }
        (out, g)
    }

    fn point(&self, f: usize, b: [f64; 3]) -> [f64; 3] {
        let p = self.corners(f);
        let mut out = [0.0; 3];
        for (i, c) in p.iter().enumerate() {
            for k in 0..3 {
                out[k] += b[i] * c[k];
            }
        }
        out
    }

    fn path_point(&self, at: At) -> PathPoint {
        match at {
            At::Vertex(v) => PathPoint {
                position: self.mesh.positions[v as usize],
                on: OnSurface::Vertex(v),
            },
            At::Face(f, b) => {
                // On an edge: the coordinate that is zero names it.
                let k = (0..3)
                    .min_by(|&i, &j| b[i].total_cmp(&b[j]))
                    .expect("three coordinates");
                let face = self.mesh.faces[f];
                let (from, to) = (face[(k + 1) % 3], face[(k + 2) % 3]);
                let s = b[(k + 1) % 3] + b[(k + 2) % 3];
                PathPoint {
                    position: self.point(f, b),
                    on: OnSurface::Edge {
                        from,
                        to,
                        t: b[(k + 2) % 3] / s,
                    },
                }
            }
        }
    }
}

/// The path from vertex `from` down the distance field `distance` (one value per vertex of
/// `mesh`, zero at the sources) to a source; its points run from the source to `from`.
pub fn descend(
    mesh: &SurfaceMesh,
    distance: &[f64],
    from: u32,
) -> Result<GeodesicPath, GeodesicError> {
    let n = mesh.positions.len();
    if distance.len() != n {
        return Err(GeodesicError::OutputLength {
            expected: n,
            got: distance.len(),
        });
    }
    if from as usize >= n {
        return Err(GeodesicError::SourceOutOfRange {
            vertex: from,
            n_vertices: n,
        });
    }
    if !distance[from as usize].is_finite() {
        return Err(GeodesicError::Unreachable { from, to: from });
    }
    let tri = Intrinsic::from_mesh(&mesh.positions, &mesh.faces)?;
    let m = mesh.faces.len();
    let mut count = vec![0u32; n + 1];
    for face in &mesh.faces {
        for &v in face {
            count[v as usize + 1] += 1;
        }
    }
    for v in 0..n {
        count[v + 1] += count[v];
    }
    let out_start = count.clone();
    let mut fill = count;
    let mut out = vec![0u32; 3 * m];
    for (f, face) in mesh.faces.iter().enumerate() {
        for (k, &v) in face.iter().enumerate() {
            out[fill[v as usize] as usize] = (3 * f + k) as u32;
            fill[v as usize] += 1;
        }
    }
    let walker = Walker {
        mesh,
        distance,
        twin: (0..3 * m).map(|h| tri.twin(h)).collect(),
        out_start,
        out,
    };
    let mut points = vec![walker.path_point(At::Vertex(from))];
    let mut at = At::Vertex(from);
    // Each step enters a face or moves to a lower vertex; a walk of more steps than this
    // is going round in circles on a field that is not a distance.
    let mut steps = 8 * m + 8 * n + 16;
    loop {
        steps = steps.checked_sub(1).ok_or(GeodesicError::PathLoop)?;
        at = match at {
            At::Vertex(v) => {
                if distance[v as usize] <= 0.0 {
                    break;
                }
                walker.leave_vertex(v)?
            }
            At::Face(f, b) => {
                // A source in this face: straight to it.
                if let Some(&s) = mesh.faces[f].iter().find(|&&s| distance[s as usize] <= 0.0) {
                    points.push(walker.path_point(At::Vertex(s)));
                    break;
                }
                walker.cross_face(f, b)
            }
        };
        let p = walker.path_point(at);
        if points.last().map(|q| q.on) != Some(p.on) {
            points.push(p);
        }
    }
    points.reverse();
    Ok(GeodesicPath { points })
}

impl Walker<'_> {
    /// From vertex `v`: into the steepest face whose descent points into it, else along the
    /// steepest edge down.
    fn leave_vertex(&self, v: u32) -> Result<At, GeodesicError> {
        let (lo, hi) = (
            self.out_start[v as usize] as usize,
            self.out_start[v as usize + 1] as usize,
        );
        let mut best_face: Option<(f64, usize, [f64; 3])> = None;
        let mut best_edge: Option<(f64, u32)> = None;
        for &h in &self.out[lo..hi] {
            let (f, k) = (h as usize / 3, h as usize % 3);
            let (d, g) = self.descent(f);
            let rate = dot(d, d).sqrt();
            // Into the face: away from `v`, towards neither other side.
            let inside = dot(g[k], d) < 0.0
                && dot(g[(k + 1) % 3], d) >= 0.0
                && dot(g[(k + 2) % 3], d) >= 0.0;
            if inside && rate > 0.0 && best_face.is_none_or(|b| rate > b.0) {
                let mut b = [0.0; 3];
                b[k] = 1.0;
                best_face = Some((rate, f, exit(b, d, &g)));
            }
            for u in [
                self.mesh.faces[f][(k + 1) % 3],
                self.mesh.faces[f][(k + 2) % 3],
            ] {
                let len = dot(
                    sub(
                        self.mesh.positions[u as usize],
                        self.mesh.positions[v as usize],
                    ),
                    sub(
                        self.mesh.positions[u as usize],
                        self.mesh.positions[v as usize],
                    ),
                )
                .sqrt();
                let slope = (self.distance[v as usize] - self.distance[u as usize]) / len;
                if slope > 0.0 && best_edge.is_none_or(|b| slope > b.0) {
                    best_edge = Some((slope, u));
                }
            }
        }
        match (best_face, best_edge) {
            (Some((rate, f, b)), edge) if edge.is_none_or(|e| rate >= e.0) => {
                Ok(self.enter_next(f, b))
            }
            (_, Some((_, u))) => Ok(At::Vertex(u)),
            _ => Err(GeodesicError::NoDescent { vertex: v }),
        }
    }

    /// From a point on the boundary of face `f` (where the walk entered it, or an edge
    /// point): across `f` along its descent, or along the edge to its lower end.
    fn cross_face(&self, f: usize, b: [f64; 3]) -> At {
        // The edge the point lies on (its zero coordinate) and the face across it.
        let k = (0..3)
            .min_by(|&i, &j| b[i].total_cmp(&b[j]))
            .expect("three coordinates");
        let face = self.mesh.faces[f];
        let (d, g) = self.descent(f);
        if dot(g[k], d) > 0.0 {
            // Into `f`, away from the edge.
            return self.enter_next(f, exit(b, d, &g));
        }
        // A valley: along the edge to its lower end.
        let (a, c) = (face[(k + 1) % 3], face[(k + 2) % 3]);
        if self.distance[a as usize] <= self.distance[c as usize] {
            At::Vertex(a)
        } else {
            At::Vertex(c)
        }
    }
}

/// Where the ray from barycentric point `b` along `d` leaves the face (through the side whose
/// coordinate reaches zero first).
fn exit(b: [f64; 3], d: [f64; 3], g: &[[f64; 3]; 3]) -> [f64; 3] {
    let mut t = f64::INFINITY;
    for i in 0..3 {
        let rate = dot(g[i], d);
        if rate < 0.0 {
            t = t.min(-b[i] / rate);
        }
    }
    if !t.is_finite() {
        return b;
    }
    let mut out = [0.0; 3];
    for i in 0..3 {
        out[i] = (b[i] + t * dot(g[i], d)).max(0.0);
    }
    let s: f64 = out.iter().sum();
    out.map(|x| x / s)
}

impl Walker<'_> {
    /// A point leaving face `f` at barycentric `b`: at a corner, that vertex; else the same
    /// point in the face across the edge it reached; on the boundary, the edge's lower end.
    fn enter_next(&self, f: usize, b: [f64; 3]) -> At {
        const CORNER: f64 = 1e-12;
        let face = self.mesh.faces[f];
        if let Some(i) = (0..3).find(|&i| b[i] >= 1.0 - CORNER) {
            return At::Vertex(face[i]);
        }
        match self.across(f, b) {
            Some((g, b)) => At::Face(g, b),
            None => {
                let k = (0..3)
                    .min_by(|&i, &j| b[i].total_cmp(&b[j]))
                    .expect("three coordinates");
                let (a, c) = (face[(k + 1) % 3], face[(k + 2) % 3]);
                if self.distance[a as usize] <= self.distance[c as usize] {
                    At::Vertex(a)
                } else {
                    At::Vertex(c)
                }
            }
        }
    }

    /// The same edge point in the face across the edge (`None` on the boundary).
    fn across(&self, f: usize, b: [f64; 3]) -> Option<(usize, [f64; 3])> {
        let k = (0..3).min_by(|&i, &j| b[i].total_cmp(&b[j]))?;
        // The half-edge from corner k+1 to corner k+2.
        let h = 3 * f + (k + 1) % 3;
        let t = self.twin[h];
        if t == NONE {
            return None;
        }
        let g = t as usize / 3;
        let j = t as usize % 3;
        // The twin runs from corner k+2 of `f` (corner j of `g`) to corner k+1 (j+1).
        let mut out = [0.0; 3];
        out[j] = b[(k + 2) % 3];
        out[(j + 1) % 3] = b[(k + 1) % 3];
        Some((g, out))
    }
}
