//! Exact polyhedral geodesic distances and shortest paths by window propagation.
//!
//! The algorithm is Chen and Han's (1990) as improved by Xin and Wang (2009, *Improving Chen
//! and Han's algorithm on the discrete geodesic problem*, "ICH"): a shortest path on a
//! triangle mesh is straight in every face it crosses, and bends only at saddle vertices
//! (angle sum above 2π) or at the boundary. A *window* is an interval of an edge reached by
//! a family of straight paths from one *pseudo-source* (the source, or the last vertex at
//! which the paths bent), stored as the pseudo-source's position unfolded into the plane of
//! the face the window enters, and the distance at that pseudo-source. Windows cross faces
//! in order of their nearest point (a Dijkstra-like priority queue) and split where their
//! cone holds the face's far vertex; vertices reached inside a cone take the straight
//! distance; saddle and boundary vertices start new windows from themselves.
//!
//! Three rules keep the count of windows small without giving up exactness:
//! - a part of a window where the distance through it exceeds the distance through an end
//!   vertex of its edge (that vertex's current upper bound plus the straight run along the
//!   edge) carries no shortest path, and is cut off (the cut point has a closed form, the
//!   difference of the two distances being monotone along the edge);
//! - Chen and Han's "one angle, one split": a window's paths that would cross a shorter
//!   straight path to the far vertex of the same face, found earlier, are cut off;
//! - a shortest path bends at a saddle or boundary vertex only by π or more on both sides
//!   (else a path beside the vertex is shorter), so a vertex spreads new windows only into
//!   the directions at least π away from the path that reached it, measured on both sides
//!   around the vertex.
//!
//! Ties are kept. On the camel head (11,381 vertices) the third rule took a query from 3.2
//! million windows to 0.78 million (BENCHMARKS.md, "Exact geodesic distances").
//!
//! Everything is in double precision, and no distance is rounded or smoothed: on developable
//! surfaces (a plane, a cylinder, a cone), the distances agree with the closed forms to about
//! `1e-15` of the size (`tests/geodesic_exact.rs`).
//!
//! ```
//! use bdmorph::geodesic::ExactGeodesics;
//! use bdmorph::generate;
//! let sphere = generate::icosphere(2);
//! let mut exact = ExactGeodesics::new(&sphere)?;
//! let d = exact.distance(&[0])?;
//! let path = exact.path(0, 40)?;
//! // The path's polyline is exactly as long as the distance.
//! assert!((path.length() - d[40]).abs() < 1e-12);
//! # Ok::<(), bdmorph::geodesic::GeodesicError>(())
//! ```

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::intrinsic::{Intrinsic, NONE};
use super::GeodesicError;
use crate::io::SurfaceMesh;
use crate::vec3;

/// "No window": a window started at a pseudo-source.
const NO: u32 = u32::MAX;

/// Windows per face held at once, by default, before a query gives up
/// ([`GeodesicError::WindowBudget`]; 56 bytes a window). A distance query reuses the slots of
/// windows it is done with; a path keeps them all (the meshes measured made 35 to 120 a
/// face).
pub const DEFAULT_WINDOWS_PER_FACE: usize = 1_000;

/// An interval `[b0, b1]` of half-edge `h` (measured from its origin), reached by straight
/// paths from a pseudo-source at `(sx, sy)` in the frame of `h` (origin at `h`'s origin, `x`
/// along `h`, the face of `h` on the side `y > 0`, the pseudo-source at `y < 0`), whose
/// distance from the sources is `sigma`.
#[derive(Clone, Copy, Debug)]
struct Window {
    h: u32,
    /// The window this one was split from, or [`NO`].
    parent: u32,
    /// The pseudo-source vertex.
    pseudo: u32,
    b0: f64,
    b1: f64,
    sx: f64,
    sy: f64,
    sigma: f64,
}

impl Window {
    /// The distance through this window at `x` on its edge.
    fn at(&self, x: f64) -> f64 {
        self.sigma + (x - self.sx).hypot(self.sy)
    }
    /// The smallest distance through this window.
    fn nearest(&self) -> f64 {
        self.at(self.sx.clamp(self.b0, self.b1))
    }
}

/// How a vertex got its distance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Via {
    Unreached,
    Source,
    /// A straight path inside a window's cone (or at its end).
    Window(u32),
    /// Straight along an edge from a pseudo-source.
    Edge(u32),
}

/// A queue entry: a window or a pseudo-source vertex, by distance (nearest first).
#[derive(Clone, Copy, Debug)]
struct Event {
    key: f64,
    vertex: bool,
    index: u32,
}

impl PartialEq for Event {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Event {}
impl PartialOrd for Event {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Event {
    fn cmp(&self, other: &Self) -> Ordering {
        // Reversed: `BinaryHeap` pops the largest. Vertices first on ties.
        other
            .key
            .total_cmp(&self.key)
            .then(self.vertex.cmp(&other.vertex))
    }
}

/// Where a point of a [`GeodesicPath`] lies on the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OnSurface {
    /// At a vertex.
    Vertex(u32),
    /// On the edge from vertex `from` to vertex `to`, at `t` of the way (`0 < t < 1`).
    Edge {
        /// One end.
        from: u32,
        /// The other end.
        to: u32,
        /// Fraction of the way from `from` to `to`.
        t: f64,
    },
}

/// One point of a [`GeodesicPath`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathPoint {
    /// Its position in space.
    pub position: [f64; 3],
    /// Where it lies on the mesh.
    pub on: OnSurface,
}

/// A shortest path on the surface: a polyline from a source to a target, straight inside
/// each face, with a point wherever it crosses an edge or passes a vertex.
#[derive(Clone, Debug, PartialEq)]
pub struct GeodesicPath {
    /// The points, from the source to the target.
    pub points: Vec<PathPoint>,
}

impl GeodesicPath {
    /// The polyline's length.
    pub fn length(&self) -> f64 {
        self.points
            .windows(2)
            .map(|w| vec3::distance(w[0].position, w[1].position))
            .sum()
    }
    /// The positions alone.
    pub fn positions(&self) -> Vec<[f64; 3]> {
        self.points.iter().map(|p| p.position).collect()
    }
}

/// What the last query did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExactStats {
    /// Windows made (after pruning).
    pub windows: usize,
    /// The most windows held at once (the memory of the query: 56 bytes each).
    pub held: usize,
    /// Windows taken from the queue and propagated.
    pub propagated: usize,
    /// Pseudo-source vertices spread from (sources, saddles and boundary vertices reached).
    pub pseudo_sources: usize,
}

/// Exact geodesic distances on one mesh: the connectivity and the unfolded faces are built
/// once in [`ExactGeodesics::new`]; each query propagates windows from its sources.
pub struct ExactGeodesics {
    positions: Vec<[f64; 3]>,
    faces: Vec<[u32; 3]>,
    twin: Vec<u32>,
    /// Length of each half-edge.
    len: Vec<f64>,
    /// The third corner of each half-edge's face in that half-edge's frame.
    third: Vec<[f64; 2]>,
    /// Half-edges opposite each vertex (CSR by vertex).
    opposite_start: Vec<u32>,
    opposite: Vec<u32>,
    /// Vertices at which shortest paths may bend: saddles and boundary vertices.
    bends: Vec<bool>,
    /// Each corner's angle, by half-edge (`3f + j`: corner `j` of face `f`).
    corner_angle: Vec<f64>,
    /// Where each corner starts around its vertex: the angle, counter-clockwise from the
    /// vertex's first corner, of the edge from the vertex to the corner's next vertex.
    corner_start: Vec<f64>,
    /// The total angle around each vertex.
    total_angle: Vec<f64>,
    /// Whether each vertex lies on the boundary.
    on_boundary: Vec<bool>,
    /// Distances closer than this count as equal (a relative `1e-13` of the mesh's size).
    tol: f64,
    max_windows: usize,
    // The last query.
    dist: Vec<f64>,
    via: Vec<Via>,
    /// Per half-edge: the shortest straight path to its face's third vertex through a window
    /// of that half-edge, and where it crosses the half-edge.
    split_d: Vec<f64>,
    split_x: Vec<f64>,
    /// The direction from which the shortest known path reaches each bend vertex (as
    /// [`ExactGeodesics::incoming_angle`]; `NaN`: every direction).
    incoming: Vec<f64>,
    /// Slots of `windows` free for reuse, and whether to keep every window (for a path).
    free: Vec<u32>,
    keep: bool,
    /// The distance at which each vertex last spread windows.
    spread_at: Vec<f64>,
    windows: Vec<Window>,
    queue: BinaryHeap<Event>,
    stats: ExactStats,
}

/// Each corner's start angle around its vertex ([`ExactGeodesics::corner_start`]): the fan
/// of corners is walked counter-clockwise from its clockwise-most corner (the one after the
/// boundary, on a boundary vertex). A vertex with more than one fan (two cones touching at
/// a vertex) gets `NaN`: its windows are spread in every direction.
fn fan_starts(faces: &[[u32; 3]], twin: &[u32], corner_angle: &[f64]) -> Vec<f64> {
    let m = faces.len();
    let mut start = vec![f64::NAN; 3 * m];
    let mut seen = vec![false; 3 * m];
    let mut fans = vec![
        0u8;
        faces
            .iter()
            .flatten()
            .map(|&v| v as usize + 1)
            .max()
            .unwrap_or(0)
    ];
    // Clockwise: across the corner's first edge; counter-clockwise: across its second.
    let clockwise = |c: usize| -> Option<usize> {
        let t = twin[c];
        (t != NONE).then(|| 3 * (t as usize / 3) + (t as usize % 3 + 1) % 3)
    };
    let counter_clockwise = |c: usize| -> Option<usize> {
        let t = twin[3 * (c / 3) + (c % 3 + 2) % 3];
        (t != NONE).then_some(t as usize)
    };
    for c0 in 0..3 * m {
        if seen[c0] {
            continue;
        }
        let v = faces[c0 / 3][c0 % 3] as usize;
        fans[v] = fans[v].saturating_add(1);
        let mut first = c0;
        while let Some(c) = clockwise(first) {
            if c == c0 {
                break;
            }
            first = c;
        }
        let mut c = first;
        let mut angle = 0.0;
        loop {
            seen[c] = true;
            start[c] = angle;
            angle += corner_angle[c];
            match counter_clockwise(c) {
                Some(next) if next != first && !seen[next] => c = next,
                _ => break,
            }
        }
    }
    for (c, s) in start.iter_mut().enumerate() {
        if fans[faces[c / 3][c % 3] as usize] > 1 {
            *s = f64::NAN;
        }
    }
    start
}

impl ExactGeodesics {
    /// Prepares `mesh`: a manifold, consistently oriented triangle mesh (closed, with
    /// boundaries, several pieces) whose triangles have positive area.
    pub fn new(mesh: &SurfaceMesh) -> Result<ExactGeodesics, GeodesicError> {
        let n = mesh.positions.len();
        if mesh.faces.is_empty() {
            return Err(GeodesicError::Empty);
        }
        if let Some(vertex) = mesh
            .positions
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(GeodesicError::NonFinite { vertex });
        }
        let tri = Intrinsic::from_mesh(&mesh.positions, &mesh.faces)?;
        let m = mesh.faces.len();
        let mut twin = Vec::with_capacity(3 * m);
        let mut len = Vec::with_capacity(3 * m);
        let mut third = Vec::with_capacity(3 * m);
        let mut angle = vec![0.0f64; n];
        let mut corner_angle = vec![0.0f64; 3 * m];
        let mut count = vec![0u32; n + 1];
        for (f, face) in mesh.faces.iter().enumerate() {
            let p = face.map(|v| mesh.positions[v as usize]);
            for k in 0..3 {
                twin.push(tri.twin(3 * f + k));
                let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
                let ab = vec3::sub(b, a);
                let ac = vec3::sub(c, a);
                let l = vec3::dot(ab, ab).sqrt();
                len.push(l);
                let x = vec3::dot(ac, ab) / l;
                let y = vec3::dot(vec3::cross(ab, ac), vec3::cross(ab, ac)).sqrt() / l;
                third.push([x, y]);
                // The corner angle at `a`.
                let (u, v) = (ab, ac);
                let corner = vec3::dot(vec3::cross(u, v), vec3::cross(u, v))
                    .sqrt()
                    .atan2(vec3::dot(u, v));
                corner_angle[3 * f + k] = corner;
                angle[face[k] as usize] += corner;
                count[face[(k + 2) % 3] as usize + 1] += 1;
            }
        }
        for v in 0..n {
            count[v + 1] += count[v];
        }
        let opposite_start = count.clone();
        let mut fill = count;
        let mut opposite = vec![0u32; 3 * m];
        for (f, face) in mesh.faces.iter().enumerate() {
            for k in 0..3 {
                let v = face[(k + 2) % 3] as usize;
                opposite[fill[v] as usize] = (3 * f + k) as u32;
                fill[v] += 1;
            }
        }
        let on_boundary = tri.boundary_vertices();
        let corner_start = fan_starts(&mesh.faces, &twin, &corner_angle);
        let bends = (0..n)
            .map(|v| on_boundary[v] || angle[v] > 2.0 * std::f64::consts::PI * (1.0 + 1e-12))
            .collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &mesh.positions {
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
        let size = vec3::distance(lo, hi);
        Ok(ExactGeodesics {
            positions: mesh.positions.clone(),
            faces: mesh.faces.clone(),
            twin,
            len,
            third,
            opposite_start,
            opposite,
            bends,
            corner_angle,
            corner_start,
            total_angle: angle,
            on_boundary,
            tol: 1e-13 * size,
            max_windows: DEFAULT_WINDOWS_PER_FACE.saturating_mul(m).max(1 << 20),
            dist: vec![f64::INFINITY; n],
            via: vec![Via::Unreached; n],
            spread_at: vec![f64::INFINITY; n],
            incoming: vec![f64::NAN; n],
            free: Vec::new(),
            keep: false,
            split_d: vec![f64::INFINITY; 3 * m],
            split_x: vec![0.0; 3 * m],
            windows: Vec::new(),
            queue: BinaryHeap::new(),
            stats: ExactStats::default(),
        })
    }

    /// Sets how many windows a query may hold at once before it gives up with
    /// [`GeodesicError::WindowBudget`] (a bound on its memory: 56 bytes a window).
    pub fn with_max_windows(mut self, max: usize) -> Self {
        self.max_windows = max.max(1);
        self
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.positions.len()
    }

    /// What the last query did.
    pub fn stats(&self) -> ExactStats {
        self.stats
    }

    /// The exact distance from every vertex to the nearest of `sources` (`inf` on pieces of
    /// the mesh without a source).
    pub fn distance(&mut self, sources: &[u32]) -> Result<Vec<f64>, GeodesicError> {
        self.run(sources)?;
        Ok(self.dist.clone())
    }

    /// As [`ExactGeodesics::distance`], into `out` (one value per vertex).
    pub fn distance_into(&mut self, sources: &[u32], out: &mut [f64]) -> Result<(), GeodesicError> {
        if out.len() != self.n_vertices() {
            return Err(GeodesicError::OutputLength {
                expected: self.n_vertices(),
                got: out.len(),
            });
        }
        self.run(sources)?;
        out.copy_from_slice(&self.dist);
        Ok(())
    }

    /// A shortest path on the surface from vertex `from` to vertex `to`.
    pub fn path(&mut self, from: u32, to: u32) -> Result<GeodesicPath, GeodesicError> {
        let n = self.n_vertices();
        if to as usize >= n {
            return Err(GeodesicError::SourceOutOfRange {
                vertex: to,
                n_vertices: n,
            });
        }
        self.keep = true;
        let ran = self.run(&[from]);
        self.keep = false;
        ran?;
        if self.via[to as usize] == Via::Unreached {
            return Err(GeodesicError::Unreachable { from, to });
        }
        let mut points = self.trace(to)?;
        points.reverse();
        Ok(GeodesicPath { points })
    }

    fn check_sources(&self, sources: &[u32]) -> Result<(), GeodesicError> {
        if sources.is_empty() {
            return Err(GeodesicError::NoSources);
        }
        let n = self.n_vertices();
        match sources.iter().find(|&&s| s as usize >= n) {
            Some(&vertex) => Err(GeodesicError::SourceOutOfRange {
                vertex,
                n_vertices: n,
            }),
            None => Ok(()),
        }
    }

    fn run(&mut self, sources: &[u32]) -> Result<(), GeodesicError> {
        self.check_sources(sources)?;
        self.dist.fill(f64::INFINITY);
        self.via.fill(Via::Unreached);
        self.spread_at.fill(f64::INFINITY);
        self.split_d.fill(f64::INFINITY);
        self.incoming.fill(f64::NAN);
        self.windows.clear();
        self.free.clear();
        self.queue.clear();
        self.stats = ExactStats::default();
        for &s in sources {
            self.dist[s as usize] = 0.0;
            self.via[s as usize] = Via::Source;
            self.queue.push(Event {
                key: 0.0,
                vertex: true,
                index: s,
            });
        }
        while let Some(e) = self.queue.pop() {
            if e.vertex {
                // Spread at the vertex's current distance, unless it has already spread at
                // (about) that distance; an event whose key has since been lowered by less
                // than the tolerance still spreads.
                let v = e.index as usize;
                if self.dist[v] < self.spread_at[v] - self.tol {
                    self.spread_at[v] = self.dist[v];
                    self.spread_from(e.index)?;
                }
            } else {
                self.propagate(e.index)?;
                self.release(e.index);
            }
        }
        self.stats.held = self.windows.len();
        Ok(())
    }

    /// Lowers `v`'s distance to `d` if that is shorter; a bend vertex whose distance drops
    /// by more than the tolerance spreads again.
    fn reach(&mut self, v: u32, d: f64, via: Via) {
        let old = self.dist[v as usize];
        if d < old {
            self.dist[v as usize] = d;
            self.via[v as usize] = via;
            if self.bends[v as usize] {
                // Kept now: the window it came through may be reused before `v` spreads.
                self.incoming[v as usize] = self.incoming_angle(v, via).unwrap_or(f64::NAN);
            }
            if self.bends[v as usize] && d < old - self.tol {
                self.queue.push(Event {
                    key: d,
                    vertex: true,
                    index: v,
                });
            }
        }
    }

    /// Starts windows from a pseudo-source: the far edge of each face around `v`.
    fn spread_from(&mut self, v: u32) -> Result<(), GeodesicError> {
        self.stats.pseudo_sources += 1;
        let d = self.dist[v as usize];
        let (lo, hi) = (
            self.opposite_start[v as usize] as usize,
            self.opposite_start[v as usize + 1] as usize,
        );
        let incoming = Some(self.incoming[v as usize]).filter(|a| a.is_finite());
        for i in lo..hi {
            let o = self.opposite[i] as usize;
            let (f, k) = (o / 3, o % 3);
            let face = self.faces[f];
            let (u1, u2) = (face[k], face[(k + 1) % 3]);
            // Straight along the two edges at `v`.
            let to_u1 = self.len[3 * f + (k + 2) % 3];
            let to_u2 = self.len[3 * f + (k + 1) % 3];
            self.reach(u1, d + to_u1, Via::Edge(v));
            self.reach(u2, d + to_u2, Via::Edge(v));
            let g = self.twin[o];
            if g == NONE {
                continue;
            }
            // The directions of the corner a path bending at `v` may take, as angles from
            // `v → u1`, and where they meet the far edge.
            let corner = 3 * f + (k + 2) % 3;
            let (lo, hi) = match incoming {
                Some(incoming) => match self.bend_range(v, corner, incoming) {
                    Some(range) => range,
                    None => continue,
                },
                None => (0.0, self.corner_angle[corner]),
            };
            let l = self.len[o];
            let [px, py] = self.third[o];
            let meets = |phi: f64| -> f64 {
                // The ray from `v` turned `phi` counter-clockwise from `v → u1`.
                let (ex, ey) = (-px, -py);
                let (c, s) = (phi.cos(), phi.sin());
                let (dx, dy) = (c * ex - s * ey, s * ex + c * ey);
                if dy >= 0.0 {
                    return if phi <= 0.0 { 0.0 } else { l };
                }
                (px + (-py / dy) * dx).clamp(0.0, l)
            };
            let (x0, x1) = if lo <= 0.0 {
                (0.0, meets(hi))
            } else {
                (meets(lo), meets(hi))
            };
            let x1 = if hi >= self.corner_angle[corner] {
                l
            } else {
                x1
            };
            // In the frame of the twin, which runs the other way.
            self.push(Window {
                h: g,
                parent: NO,
                pseudo: v,
                b0: l - x1.max(x0),
                b1: l - x0.min(x1),
                sx: l - px,
                sy: -py,
                sigma: d,
            })?;
        }
        Ok(())
    }

    /// The direction (an angle around `v`, as [`ExactGeodesics::corner_start`]) from which
    /// the shortest known path arrives at `v`; `None` at a source or where it is not known.
    fn incoming_angle(&self, v: u32, via: Via) -> Option<f64> {
        let corner_of = |f: usize| -> Option<usize> {
            let j = self.faces[f].iter().position(|&u| u == v)?;
            let c = 3 * f + j;
            self.corner_start[c].is_finite().then_some(c)
        };
        // Not clamped to the corner: a path may arrive along the window's boundary ray
        // through faces before the corner's, which lie on in the fan, unrolled alike.
        let within = |c: usize, phi: f64| self.corner_start[c] + phi;
        match via {
            Via::Source | Via::Unreached => None,
            Via::Edge(u) => {
                let (lo, hi) = (
                    self.opposite_start[v as usize] as usize,
                    self.opposite_start[v as usize + 1] as usize,
                );
                for &o in &self.opposite[lo..hi] {
                    let f = o as usize / 3;
                    let c = corner_of(f)?;
                    let face = self.faces[f];
                    if face[(c + 1) % 3] == u {
                        return Some(self.corner_start[c]);
                    }
                    if face[(c + 2) % 3] == u {
                        return Some(self.corner_start[c] + self.corner_angle[c]);
                    }
                }
                None
            }
            Via::Window(index) => {
                let w = self.windows[index as usize];
                let h = w.h as usize;
                let (f, k) = (h / 3, h % 3);
                let face = self.faces[f];
                let l = self.len[h];
                let angle = |from: [f64; 2], to: [f64; 2]| {
                    (from[0] * to[1] - from[1] * to[0]).atan2(from[0] * to[0] + from[1] * to[1])
                };
                if face[(k + 2) % 3] == v {
                    // Inside the cone: the corner at `v` runs from `v → a` to `v → b`.
                    let [cx, cy] = self.third[h];
                    let c = corner_of(f)?;
                    Some(within(c, angle([-cx, -cy], [w.sx - cx, w.sy - cy])))
                } else {
                    // At an end of the window's edge: the path arrives through the face
                    // across that edge, whose corner at `v` holds the direction back to the
                    // pseudo-source.
                    let t = self.twin[h];
                    if t == NONE {
                        return None;
                    }
                    let g = t as usize / 3;
                    let c = corner_of(g)?;
                    if face[k] == v {
                        // `v = a` at the origin; the corner runs from `a → third` to
                        // `a → b`, the direction to the pseudo-source clockwise from `a → b`.
                        let phi = angle([w.sx, w.sy], [1.0, 0.0]);
                        Some(self.corner_start[c] + self.corner_angle[c] - phi)
                    } else {
                        // `v = b`; the corner runs from `b → a` to `b → third`.
                        Some(within(c, angle([-1.0, 0.0], [w.sx - l, w.sy])))
                    }
                }
            }
        }
    }

    /// The directions of corner `c` (as angles from its first edge) in which a shortest path
    /// arriving at `v` from direction `incoming` may leave: only where it turns by at least
    /// π on both sides (else a path beside `v` is shorter). `None`: none.
    fn bend_range(&self, v: u32, c: usize, incoming: f64) -> Option<(f64, f64)> {
        let (s, a) = (self.corner_start[c], self.corner_angle[c]);
        if !s.is_finite() {
            return Some((0.0, a));
        }
        let total = self.total_angle[v as usize];
        let slack = 1e-9;
        let pi = std::f64::consts::PI;
        // The candidate directions as intervals of the fan's angle.
        let mut pieces: [(f64, f64); 3] = [(1.0, 0.0); 3];
        if self.on_boundary[v as usize] {
            // One way round: at least π before or after the incoming direction.
            pieces[0] = (f64::NEG_INFINITY, incoming - pi + slack);
            pieces[1] = (incoming + pi - slack, f64::INFINITY);
        } else {
            // Both ways round: `[incoming + π, incoming + total - π]`, modulo `total`.
            let (lo, hi) = (incoming + pi - slack, incoming + total - pi + slack);
            if hi < lo {
                return None;
            }
            for (piece, shift) in pieces.iter_mut().zip([-total, 0.0, total]) {
                *piece = (lo + shift, hi + shift);
            }
        }
        let (mut from, mut to) = (f64::INFINITY, f64::NEG_INFINITY);
        for (lo, hi) in pieces {
            let (lo, hi) = (lo.max(s), hi.min(s + a));
            if lo <= hi {
                from = from.min(lo - s);
                to = to.max(hi - s);
            }
        }
        (from <= to).then_some((from.max(0.0), to.min(a)))
    }

    /// Cuts off the parts of `w` where an end vertex of its edge is closer; `false` when
    /// nothing is left.
    fn trim(&self, w: &mut Window) -> bool {
        let h = w.h as usize;
        let l = self.len[h];
        let face = self.faces[h / 3];
        let (a, b) = (face[h % 3], face[(h + 1) % 3]);
        let tol = self.tol;
        // Through `a`: `w.at(x) - x` does not increase along the edge.
        let da = self.dist[a as usize];
        if da.is_finite() {
            let worse = |x: f64| w.at(x) - x - da > tol;
            if worse(w.b1) {
                return false;
            }
            if worse(w.b0) {
                let c = da - w.sigma + tol;
                let x = (w.sx * w.sx + w.sy * w.sy - c * c) / (2.0 * (c + w.sx));
                if x.is_finite() {
                    w.b0 = x.clamp(w.b0, w.b1);
                }
            }
        }
        // Through `b`: `w.at(x) - (l - x)` does not decrease along the edge.
        let db = self.dist[b as usize];
        if db.is_finite() {
            let worse = |x: f64| w.at(x) - (l - x) - db > tol;
            if worse(w.b0) {
                return false;
            }
            if worse(w.b1) {
                let c = db - w.sigma + tol;
                let sx = l - w.sx;
                let y = (sx * sx + w.sy * w.sy - c * c) / (2.0 * (c + sx));
                if y.is_finite() {
                    w.b1 = (l - y).clamp(w.b0, w.b1);
                }
            }
        }
        w.b1 >= w.b0
    }

    /// Trims `w`, then keeps it, lets it reach the ends of its edge it covers, and queues it.
    fn push(&mut self, mut w: Window) -> Result<(), GeodesicError> {
        if !self.trim(&mut w) {
            return Ok(());
        }
        let h = w.h as usize;
        let l = self.len[h];
        let end = 1e-12 * l;
        self.stats.windows += 1;
        let index = match self.free.pop() {
            Some(index) => {
                self.windows[index as usize] = w;
                index
            }
            None => {
                if self.windows.len() >= self.max_windows {
                    return Err(GeodesicError::WindowBudget {
                        windows: self.max_windows,
                    });
                }
                self.windows.push(w);
                (self.windows.len() - 1) as u32
            }
        };
        let face = self.faces[h / 3];
        if w.b0 <= end {
            self.reach(face[h % 3], w.at(0.0), Via::Window(index));
        }
        if w.b1 >= l - end {
            self.reach(face[(h + 1) % 3], w.at(l), Via::Window(index));
        }
        if w.b1 - w.b0 > end {
            self.queue.push(Event {
                key: w.nearest(),
                vertex: false,
                index,
            });
        } else {
            self.release(index);
        }
        Ok(())
    }

    /// A window that is done with goes back for reuse, unless a path will be traced
    /// through it.
    fn release(&mut self, index: u32) {
        if !self.keep {
            self.free.push(index);
        }
    }

    /// Carries window `index` across its face: the far vertex if the cone holds it, and up
    /// to two windows on the face's other edges.
    fn propagate(&mut self, index: u32) -> Result<(), GeodesicError> {
        let mut w = self.windows[index as usize];
        if !self.trim(&mut w) || w.sy >= 0.0 {
            return Ok(());
        }
        self.stats.propagated += 1;
        let h = w.h as usize;
        let (f, k) = (h / 3, h % 3);
        let l = self.len[h];
        let [cx, cy] = self.third[h];
        let c = self.faces[f][(k + 2) % 3];
        let (sx, sy) = (w.sx, w.sy);
        // Where the line from the pseudo-source through `c` crosses the edge.
        let xc = sx + (cx - sx) * (-sy) / (cy - sy);
        let eps = 1e-12 * l;
        let to_c = w.sigma + (cx - sx).hypot(cy - sy);
        if xc >= w.b0 - eps && xc <= w.b1 + eps {
            self.reach(c, to_c, Via::Window(index));
            if to_c < self.split_d[h] {
                self.split_d[h] = to_c;
                self.split_x[h] = xc.clamp(0.0, l);
            }
        }
        // Chen and Han's "one angle, one split": a straight path from an earlier window of
        // this edge, entering at `x1`, reaches `c` shorter than this window's pseudo-source
        // could even in a straight line; this window's paths that would cross it (those
        // entering right of `x1` and leaving left of `c`, or the reverse) are longer than
        // the path along it, by the triangle inequality.
        let (mut left_end, mut right_start) = (w.b1.min(xc), w.b0.max(xc));
        if self.split_d[h] < to_c - self.tol {
            let x1 = self.split_x[h];
            left_end = left_end.min(x1);
            right_start = right_start.max(x1);
        }
        // The part of the cone left of `c` leaves through the edge `a → c`.
        if left_end > w.b0 {
            let h2 = 3 * f + (k + 2) % 3;
            let g = self.twin[h2];
            if g != NONE {
                let lac = self.len[h2];
                let mu = |x: f64| sy * x / (cx * sy + cy * (x - sx));
                let m0 = mu(w.b0).clamp(0.0, 1.0);
                let m1 = if left_end == xc {
                    1.0
                } else {
                    mu(left_end).clamp(0.0, 1.0)
                };
                let (ux, uy) = (cx / lac, cy / lac);
                self.push(Window {
                    h: g,
                    parent: index,
                    pseudo: w.pseudo,
                    b0: m0.min(m1) * lac,
                    b1: m0.max(m1) * lac,
                    sx: sx * ux + sy * uy,
                    sy: ux * sy - uy * sx,
                    sigma: w.sigma,
                })?;
            }
        }
        // The part right of `c` leaves through the edge `c → b`.
        if right_start < w.b1 {
            let h1 = 3 * f + (k + 1) % 3;
            let g = self.twin[h1];
            if g != NONE {
                let lcb = self.len[h1];
                let (ex, ey) = (l - cx, -cy);
                let (qx, qy) = (sx - cx, sy - cy);
                let nu = |x: f64| {
                    let (dx, dy) = (x - sx, -sy);
                    (qx * dy - qy * dx) / (ex * dy - ey * dx)
                };
                let n0 = if right_start == xc {
                    0.0
                } else {
                    nu(right_start).clamp(0.0, 1.0)
                };
                let n1 = nu(w.b1).clamp(0.0, 1.0);
                let (ux, uy) = (ex / lcb, ey / lcb);
                self.push(Window {
                    h: g,
                    parent: index,
                    pseudo: w.pseudo,
                    b0: n0.min(n1) * lcb,
                    b1: n0.max(n1) * lcb,
                    sx: qx * ux + qy * uy,
                    sy: ux * qy - uy * qx,
                    sigma: w.sigma,
                })?;
            }
        }
        Ok(())
    }

    /// The corners of half-edge `h`'s face in `h`'s frame, by the face's corner index.
    fn corners(&self, h: usize) -> [[f64; 2]; 3] {
        let k = h % 3;
        let mut out = [[0.0; 2]; 3];
        out[k] = [0.0, 0.0];
        out[(k + 1) % 3] = [self.len[h], 0.0];
        out[(k + 2) % 3] = self.third[h];
        out
    }

    fn vertex_point(&self, v: u32) -> PathPoint {
        PathPoint {
            position: self.positions[v as usize],
            on: OnSurface::Vertex(v),
        }
    }

    /// The point at `x` along half-edge `h` (a vertex at either end).
    fn edge_point(&self, h: usize, x: f64) -> PathPoint {
        let face = self.faces[h / 3];
        let (a, b) = (face[h % 3], face[(h + 1) % 3]);
        let l = self.len[h];
        let end = 1e-12 * l;
        if x <= end {
            return self.vertex_point(a);
        }
        if x >= l - end {
            return self.vertex_point(b);
        }
        let t = x / l;
        let (p, q) = (self.positions[a as usize], self.positions[b as usize]);
        PathPoint {
            position: [
                p[0] + t * (q[0] - p[0]),
                p[1] + t * (q[1] - p[1]),
                p[2] + t * (q[2] - p[2]),
            ],
            on: OnSurface::Edge { from: a, to: b, t },
        }
    }

    /// The path from `to` back to its source, by the windows and edges that reached it.
    fn trace(&self, to: u32) -> Result<Vec<PathPoint>, GeodesicError> {
        let mut out = vec![self.vertex_point(to)];
        let mut v = to;
        // Each step moves to a window's parent or to a pseudo-source with a shorter distance.
        let mut budget = self.windows.len() + 2 * self.n_vertices() + 8;
        let mut step = || {
            budget = budget.checked_sub(1)?;
            Some(())
        };
        let lost = GeodesicError::Unreachable { from: to, to };
        loop {
            match self.via[v as usize] {
                Via::Source => break,
                Via::Unreached => return Err(lost),
                Via::Edge(u) => {
                    step().ok_or(GeodesicError::PathLoop)?;
                    out.push(self.vertex_point(u));
                    v = u;
                }
                Via::Window(index) => {
                    let mut cur = index as usize;
                    let w = self.windows[cur];
                    let corner = self.faces[w.h as usize / 3]
                        .iter()
                        .position(|&c| c == v)
                        .ok_or(GeodesicError::PathLoop)?;
                    let mut p = self.corners(w.h as usize)[corner];
                    loop {
                        step().ok_or(GeodesicError::PathLoop)?;
                        let w = self.windows[cur];
                        let x = if p[1].abs() <= 1e-15 * self.len[w.h as usize] {
                            p[0]
                        } else {
                            w.sx + (p[0] - w.sx) * (-w.sy) / (p[1] - w.sy)
                        };
                        let x = x.clamp(0.0, self.len[w.h as usize]);
                        let point = self.edge_point(w.h as usize, x);
                        if point.on != out[out.len() - 1].on {
                            out.push(point);
                        }
                        if w.parent == NO {
                            v = w.pseudo;
                            if out[out.len() - 1].on != OnSurface::Vertex(v) {
                                out.push(self.vertex_point(v));
                            }
                            break;
                        }
                        // The same point in the parent's frame: on the twin of `w.h`, which
                        // runs the other way.
                        let parent = self.windows[w.parent as usize];
                        let g = self.twin[w.h as usize] as usize;
                        let lg = self.len[g];
                        let corners = self.corners(parent.h as usize);
                        let (tail, head) = (corners[g % 3], corners[(g + 1) % 3]);
                        let s = ((lg - x) / lg).clamp(0.0, 1.0);
                        p = [
                            tail[0] + s * (head[0] - tail[0]),
                            tail[1] + s * (head[1] - tail[1]),
                        ];
                        cur = w.parent as usize;
                    }
                }
            }
        }
        Ok(out)
    }
}
