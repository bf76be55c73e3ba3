//! Intrinsic Delaunay refinement (Sharp, Soliman and Crane 2019, *Navigating intrinsic
//! triangulations*, section 5): vertices inserted on the surface, at the circumcentres of
//! triangles with a small angle, until every triangle has angles of at least a bound.
//!
//! The surface and its metric do not change: a circumcentre is found by walking a straight
//! line on the surface from the triangle's centroid, unfolding each triangle it crosses into
//! the first one's plane, and the new vertex's edges are measured in that unfolding. A walk
//! that leaves the surface through a boundary edge splits that edge at its midpoint instead
//! (Ruppert's rule), and so does a boundary edge opposite an obtuse angle, whose cotan weight
//! would be negative. After each insertion the triangulation is flipped back to Delaunay
//! around the new vertex. The input's vertices keep their numbers; new vertices are numbered
//! after them.
//!
//! Delaunay refinement terminates when the input has no angle below 60° (Chew; Shewchuk).
//! Meshes do, so: a triangle whose smallest angle lies in a corner of the input whose whole
//! angle is below 60° (a cone's tip, a sharp boundary corner) cannot be improved and is left
//! alone, no edge is split and no vertex inserted closer than a small floor to the existing
//! ones, and the number of insertions has a hard cap ([`RefineStats::budget_reached`] says
//! when it stopped there).

use std::collections::VecDeque;

use super::intrinsic::{positive, triangle_area, Intrinsic, NONE};

/// What [`Intrinsic::refine`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RefineStats {
    /// Vertices inserted inside triangles (at circumcentres).
    pub inserted: usize,
    /// Edges split at a point (boundary edges at their midpoint, and interior edges where a
    /// circumcentre fell on one).
    pub split: usize,
    /// Edge flips that restored the Delaunay property.
    pub flips: usize,
    /// Whether it stopped at the insertion cap with triangles still below the bound.
    pub budget_reached: bool,
    /// Triangles left with an angle below the bound (in a sharp corner of the input, at the
    /// length floor, or at the cap).
    pub below_bound: usize,
    /// The smallest angle of any triangle at the end, in degrees.
    pub min_angle_degrees: f64,
}

/// Where a walk on the surface ended.
enum Spot {
    /// Inside a face, given by its half-edges and their origins' positions in the walk's
    /// plane, at point `p`.
    Face {
        he: [u32; 3],
        pts: [[f64; 2]; 3],
        p: [f64; 2],
    },
    /// It ended inside the diametral circle of this boundary half-edge (of a face it
    /// crossed): the point would come too close to the boundary, and Ruppert's rule splits
    /// the edge instead.
    Encroaches(u32),
    /// It left the surface through this boundary half-edge.
    Boundary(u32),
    /// It ran through a vertex or did not end: no insertion.
    Lost,
}

/// The three angles of a triangle with sides `l` (angle `i` opposite side `i`), in radians.
fn angles(l: [f64; 3]) -> [f64; 3] {
    let angle = |a: f64, b: f64, c: f64| {
        ((b * b + c * c - a * a) / (2.0 * b * c))
            .clamp(-1.0, 1.0)
            .acos()
    };
    [
        angle(l[0], l[1], l[2]),
        angle(l[1], l[2], l[0]),
        angle(l[2], l[0], l[1]),
    ]
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

impl Intrinsic {
    /// The half-edges of face `f`, from its first.
    fn face_edges(&self, f: usize) -> [u32; 3] {
        let h0 = self.face_he[f];
        let h1 = self.next[h0 as usize];
        [h0, h1, self.next[h1 as usize]]
    }

    /// The lengths of a face's half-edges and the angle at each half-edge's origin.
    fn corner_angles(&self, he: [u32; 3]) -> [f64; 3] {
        let l = he.map(|h| self.len[h as usize]);
        // The angle at origin(h_i) is opposite h_{i+1}.
        let a = angles([l[1], l[2], l[0]]);
        [a[0], a[1], a[2]]
    }

    /// Appends a half-edge (its `next`, `twin` and face are set by the caller).
    fn push_half_edge(&mut self, origin: u32, len: f64) -> u32 {
        let h = self.origin.len() as u32;
        self.origin.push(origin);
        self.len.push(len);
        self.next.push(NONE);
        self.twin.push(NONE);
        self.face_of.push(NONE);
        self.parent.push(h);
        h
    }

    fn push_face(&mut self, he: [u32; 3]) -> u32 {
        let f = self.face_he.len() as u32;
        self.face_he.push(he[0]);
        self.set_face(f, he);
        f
    }

    fn set_face(&mut self, f: u32, he: [u32; 3]) {
        for i in 0..3 {
            self.next[he[i] as usize] = he[(i + 1) % 3];
            self.face_of[he[i] as usize] = f;
        }
        self.face_he[f as usize] = he[0];
    }

    /// Walks on the surface from the centroid of face `f` to the point `target` of its plane
    /// (face `f` laid out with its first half-edge's origin at 0 and the half-edge along +x).
    fn walk(&self, f: usize, target: [f64; 2]) -> Spot {
        let he = self.face_edges(f);
        let l = he.map(|h| self.len[h as usize]);
        let x = (l[0] * l[0] + l[2] * l[2] - l[1] * l[1]) / (2.0 * l[0]);
        let y = 2.0 * triangle_area(l[0], l[1], l[2]) / l[0];
        let mut pts = [[0.0, 0.0], [l[0], 0.0], [x, y]];
        let mut he = he;
        let start = [(pts[1][0] + pts[2][0]) / 3.0, pts[2][1] / 3.0];
        let d = sub(target, start);
        let mut entry = usize::MAX;
        // The boundary edges of the faces crossed, in the walk's plane.
        let mut seen: Vec<(u32, [f64; 2], [f64; 2])> = Vec::new();
        for _ in 0..self.face_he.len() + 2 {
            for k in 0..3 {
                if self.twin[he[k] as usize] == NONE {
                    seen.push((he[k], pts[k], pts[(k + 1) % 3]));
                }
            }
            // Barycentric weights of the target: w_i is the signed area of the triangle of
            // the other two corners and the target.
            let area = cross(sub(pts[1], pts[0]), sub(pts[2], pts[0]));
            let w: [f64; 3] = std::array::from_fn(|i| {
                let (a, b) = (pts[(i + 1) % 3], pts[(i + 2) % 3]);
                cross(sub(b, a), sub(target, a)) / area
            });
            if w.iter().all(|&wi| wi >= -1e-12) {
                let inside = |&(_, a, b): &(u32, [f64; 2], [f64; 2])| {
                    let (pa, pb) = (sub(a, target), sub(b, target));
                    pa[0] * pb[0] + pa[1] * pb[1] < 0.0
                };
                if let Some(&(h, _, _)) = seen.iter().find(|e| inside(e)) {
                    return Spot::Encroaches(h);
                }
                return Spot::Face { he, pts, p: target };
            }
            // The edge k (pts[k] -> pts[k + 1]) the segment leaves through.
            let mut exit = None;
            for k in 0..3 {
                if k == entry || w[(k + 2) % 3] >= 0.0 {
                    continue;
                }
                let (a, b) = (pts[k], pts[(k + 1) % 3]);
                let e = sub(b, a);
                let denom = cross(d, e);
                if denom == 0.0 {
                    continue;
                }
                // start + s d = a + u e.
                let u = cross(d, sub(start, a)) / denom;
                if (-1e-12..=1.0 + 1e-12).contains(&u) {
                    exit = Some((k, u));
                    break;
                }
            }
            let Some((k, u)) = exit else {
                return Spot::Lost;
            };
            if !(1e-9..=1.0 - 1e-9).contains(&u) {
                return Spot::Lost;
            }
            let h = he[k];
            let t = self.twin[h as usize];
            if t == NONE {
                return Spot::Boundary(h);
            }
            // Unfold the face across the edge: t runs b -> a, then a -> c, c -> b.
            let (a, b) = (pts[k], pts[(k + 1) % 3]);
            let tn = self.next[t as usize];
            let tp = self.next[tn as usize];
            let (lt, ln, lp) = (
                self.len[t as usize],
                self.len[tn as usize],
                self.len[tp as usize],
            );
            let e = sub(b, a);
            let el = e[0].hypot(e[1]);
            let along = (ln * ln + lt * lt - lp * lp) / (2.0 * lt);
            let perp = 2.0 * triangle_area(lt, ln, lp) / lt;
            let c = [
                a[0] + along * e[0] / el + perp * e[1] / el,
                a[1] + along * e[1] / el - perp * e[0] / el,
            ];
            he = [t, tn, tp];
            pts = [b, a, c];
            entry = 0;
        }
        Spot::Lost
    }

    /// Splits the edge of half-edge `h` at the fraction `tau` of the way from its origin;
    /// returns the new vertex, or `None` (no change) when a new triangle would be degenerate.
    fn split_edge(&mut self, h: u32, tau: f64) -> Option<u32> {
        let hu = h as usize;
        let t = self.twin[hu];
        let big = self.len[hu];
        let (short_a, short_b) = (tau * big, (1.0 - tau) * big);
        // Distance from the new vertex to the apex of h's face (a -> b, b -> c, c -> a).
        let apex = |this: &Intrinsic, h: u32, from_origin: f64| {
            let hn = this.next[h as usize];
            let hp = this.next[hn as usize];
            let (ab, bc, ca) = (
                this.len[h as usize],
                this.len[hn as usize],
                this.len[hp as usize],
            );
            let cx = (ab * ab + ca * ca - bc * bc) / (2.0 * ab);
            let cy = 2.0 * triangle_area(ab, bc, ca) / ab;
            (cx - from_origin).hypot(cy)
        };
        let vc = apex(self, h, short_a);
        let hn = self.next[hu];
        let hp = self.next[hn as usize];
        let ok = |x: f64, y: f64, z: f64| positive(triangle_area(x, y, z));
        if !(ok(short_a, vc, self.len[hp as usize]) && ok(short_b, self.len[hn as usize], vc)) {
            return None;
        }
        let vd = if t != NONE {
            let vd = apex(self, t, short_b);
            let tn = self.next[t as usize];
            let tp = self.next[tn as usize];
            if !(ok(short_b, vd, self.len[tp as usize]) && ok(short_a, self.len[tn as usize], vd)) {
                return None;
            }
            vd
        } else {
            0.0
        };
        let v = self.n_vertices as u32;
        self.n_vertices += 1;
        let c = self.origin[hp as usize];
        let f1 = self.face_of[hu];
        let x = self.push_half_edge(v, vc);
        let z = self.push_half_edge(c, vc);
        let y = self.push_half_edge(v, short_b);
        self.parent[y as usize] = self.parent[hu];
        self.len[hu] = short_a;
        self.twin[x as usize] = z;
        self.twin[z as usize] = x;
        self.set_face(f1, [h, x, hp]);
        self.push_face([y, hn, z]);
        if t != NONE {
            let tu = t as usize;
            let tn = self.next[tu];
            let tp = self.next[tn as usize];
            let d = self.origin[tp as usize];
            let f2 = self.face_of[tu];
            let p = self.push_half_edge(v, vd);
            let r = self.push_half_edge(d, vd);
            let q = self.push_half_edge(v, short_a);
            self.parent[q as usize] = self.parent[tu];
            self.len[tu] = short_b;
            self.twin[p as usize] = r;
            self.twin[r as usize] = p;
            self.set_face(f2, [t, p, tp]);
            self.push_face([q, tn, r]);
            self.twin[hu] = q;
            self.twin[q as usize] = h;
            self.twin[y as usize] = t;
            self.twin[tu] = y;
        }
        Some(v)
    }

    /// Inserts a vertex inside the face of half-edges `he`, at distances `d[i]` from their
    /// origins; `None` (no change) when a new triangle would be degenerate.
    fn insert_in_face(&mut self, he: [u32; 3], d: [f64; 3]) -> Option<u32> {
        for i in 0..3 {
            if !positive(triangle_area(
                self.len[he[i] as usize],
                d[(i + 1) % 3],
                d[i],
            )) {
                return None;
            }
        }
        let v = self.n_vertices as u32;
        self.n_vertices += 1;
        let o = he.map(|h| self.origin[h as usize]);
        let f0 = self.face_of[he[0] as usize];
        // a_i runs from o_{i+1} to v, b_i from v to o_i; face i is h_i, a_i, b_i.
        let a: [u32; 3] =
            std::array::from_fn(|i| self.push_half_edge(o[(i + 1) % 3], d[(i + 1) % 3]));
        let b: [u32; 3] = std::array::from_fn(|i| self.push_half_edge(v, d[i]));
        for (i, &ai) in a.iter().enumerate() {
            let bj = b[(i + 1) % 3];
            self.twin[ai as usize] = bj;
            self.twin[bj as usize] = ai;
        }
        self.set_face(f0, [he[0], a[0], b[0]]);
        self.push_face([he[1], a[1], b[1]]);
        self.push_face([he[2], a[2], b[2]]);
        Some(v)
    }

    /// Flips the edges on `stack` (and those their flips expose) until Delaunay; pushes the
    /// faces it changes onto `touched`. Returns the number of flips.
    fn flip_from(&mut self, stack: &mut Vec<u32>, touched: &mut Vec<u32>) -> usize {
        let mut flips = 0;
        let cap = 64 * self.origin.len() + 1000;
        while let Some(h) = stack.pop() {
            let h = h as usize;
            if self.twin[h] == NONE || flips >= cap || self.cot_sum(h) >= -1e-12 {
                continue;
            }
            if !self.flip(h) {
                continue;
            }
            flips += 1;
            let t = self.twin[h] as usize;
            touched.push(self.face_of[h]);
            touched.push(self.face_of[t]);
            stack.extend([
                self.next[h],
                self.next[self.next[h] as usize],
                self.next[t],
                self.next[self.next[t] as usize],
            ]);
        }
        flips
    }

    /// Refines the (intrinsic Delaunay) triangulation until every triangle's angles are at
    /// least `min_angle_degrees` (at most 30°, where refinement provably ends; larger values
    /// are clamped), inserting at most `max_insertions` vertices (see [`RefineStats`]). The
    /// input's vertices keep their numbers. On the doubled surface
    /// ([`Intrinsic::double_across_boundary`]), a closed surface, the new vertices lie on one
    /// sheet or the other and their triangles have no mirror image
    /// ([`Intrinsic::weighted_faces`] weighs them ½).
    pub fn refine(&mut self, min_angle_degrees: f64, max_insertions: usize) -> RefineStats {
        let mut stats = RefineStats {
            flips: self.flip_to_delaunay(),
            ..RefineStats::default()
        };
        let bound = min_angle_degrees.clamp(0.0, 30.0).to_radians();
        if self.face_he.is_empty() {
            stats.min_angle_degrees = self.smallest_angle().to_degrees();
            return stats;
        }
        let n_input = self.n_vertices;
        // The whole angle at each input vertex (a cone's angle, or a boundary corner's).
        let mut whole = vec![0.0; n_input];
        for f in 0..self.face_he.len() {
            let he = self.face_edges(f);
            for (h, a) in he.iter().zip(self.corner_angles(he)) {
                whole[self.origin[*h as usize] as usize] += a;
            }
        }
        let sharp = std::f64::consts::FRAC_PI_3;
        let mean = self.len.iter().sum::<f64>() / self.len.len() as f64;
        let floor = 1e-4 * mean;
        let mut queue: VecDeque<u32> = (0..self.face_he.len() as u32).collect();
        let mut queued = vec![true; self.face_he.len()];
        let mut stack = Vec::new();
        let mut touched = Vec::new();
        while let Some(f) = queue.pop_front() {
            queued[f as usize] = false;
            let he = self.face_edges(f as usize);
            let ang = self.corner_angles(he);
            // A boundary edge opposite an obtuse angle: split it (its weight is negative).
            let encroached = (0..3).find(|&i| {
                self.twin[he[i] as usize] == NONE
                    && ang[(i + 2) % 3] > std::f64::consts::FRAC_PI_2 + 1e-9
                    && self.len[he[i] as usize] > 2.0 * floor
            });
            // What to do, if anything: split a half-edge at a fraction, or insert in a face.
            enum Step {
                Split(u32, f64),
                Insert([u32; 3], [f64; 3]),
            }
            let step = if let Some(i) = encroached {
                Step::Split(he[i], 0.5)
            } else {
                let (i, &smallest) = ang
                    .iter()
                    .enumerate()
                    .min_by(|a, b| a.1.total_cmp(b.1))
                    .unwrap_or((0, &0.0));
                let corner = self.origin[he[i] as usize] as usize;
                if smallest >= bound || (corner < n_input && whole[corner] < sharp + 1e-9) {
                    continue;
                }
                match self.circumcentre_spot(f as usize, floor) {
                    Spot::Face { he, pts, p } => {
                        let d = pts.map(|q| dist(p, q));
                        if d.iter().any(|&x| x < floor) {
                            continue;
                        }
                        let area = cross(sub(pts[1], pts[0]), sub(pts[2], pts[0]));
                        let w: [f64; 3] = std::array::from_fn(|i| {
                            let (a, b) = (pts[(i + 1) % 3], pts[(i + 2) % 3]);
                            cross(sub(b, a), sub(p, a)) / area
                        });
                        match (0..3).find(|&i| w[i] < 1e-9) {
                            // On the edge opposite corner i: he[i + 1], from corner i + 1.
                            Some(i) => {
                                let (wa, wb) = (w[(i + 1) % 3], w[(i + 2) % 3]);
                                Step::Split(he[(i + 1) % 3], wb / (wa + wb))
                            }
                            None => Step::Insert(he, d),
                        }
                    }
                    Spot::Boundary(h) | Spot::Encroaches(h)
                        if self.len[h as usize] > 2.0 * floor =>
                    {
                        Step::Split(h, 0.5)
                    }
                    _ => continue,
                }
            };
            if stats.inserted + stats.split >= max_insertions {
                stats.budget_reached = true;
                break;
            }
            let new_vertex = match step {
                Step::Split(h, tau) => {
                    let v = self.split_edge(h, tau);
                    stats.split += usize::from(v.is_some());
                    v
                }
                Step::Insert(he, d) => {
                    let v = self.insert_in_face(he, d);
                    stats.inserted += usize::from(v.is_some());
                    v
                }
            };
            let Some(v) = new_vertex else {
                continue;
            };
            // Flip back to Delaunay from the edges around the new vertex.
            stack.clear();
            touched.clear();
            // The face itself again: a split elsewhere (a boundary edge its circumcentre
            // encroached) may have left it as it was.
            touched.push(f);
            let star = self.star(v);
            for &h in &star {
                touched.push(self.face_of[h as usize]);
                stack.push(self.next[h as usize]);
            }
            stats.flips += self.flip_from(&mut stack, &mut touched);
            queued.resize(self.face_he.len(), false);
            for &g in &touched {
                if !queued[g as usize] {
                    queued[g as usize] = true;
                    queue.push_back(g);
                }
            }
        }
        let bound_ok = bound - 1e-9;
        stats.below_bound = (0..self.face_he.len())
            .filter(|&f| {
                let a = self.corner_angles(self.face_edges(f));
                a.iter().any(|&x| x < bound_ok)
            })
            .count();
        stats.min_angle_degrees = self.smallest_angle().to_degrees();
        stats
    }

    /// The half-edges out of vertex `v`, a vertex just inserted (the newest half-edge leaves
    /// it), found by turning around it through twins.
    fn star(&self, v: u32) -> Vec<u32> {
        let Some(start) = (0..self.origin.len() as u32)
            .rev()
            .find(|&h| self.origin[h as usize] == v)
        else {
            return Vec::new();
        };
        let mut out = vec![start];
        // One way round: the twin of the half-edge into v in the same face.
        let prev = |h: u32| self.next[self.next[h as usize] as usize];
        let mut h = start;
        let mut closed = false;
        while out.len() <= self.origin.len() {
            let t = self.twin[prev(h) as usize];
            if t == NONE {
                break;
            }
            if t == start {
                closed = true;
                break;
            }
            out.push(t);
            h = t;
        }
        // On the boundary, the other way round from the start too.
        if !closed {
            let mut h = start;
            while out.len() <= self.origin.len() {
                let t = self.twin[h as usize];
                if t == NONE {
                    break;
                }
                h = self.next[t as usize];
                out.push(h);
            }
        }
        out
    }

    /// Where face `f`'s circumcentre lies on the surface.
    fn circumcentre_spot(&self, f: usize, floor: f64) -> Spot {
        let he = self.face_edges(f);
        let l = he.map(|h| self.len[h as usize]);
        let bx = l[0];
        let cx = (l[0] * l[0] + l[2] * l[2] - l[1] * l[1]) / (2.0 * l[0]);
        let cy = 2.0 * triangle_area(l[0], l[1], l[2]) / l[0];
        // With the first corner at 0 and the second at (bx, 0).
        let d = 2.0 * bx * cy;
        if d.is_nan() || d <= 0.0 {
            return Spot::Lost;
        }
        let ux = bx / 2.0;
        let uy = (bx * (cx * cx + cy * cy) - cx * bx * bx) / d;
        if ux.hypot(uy) < floor {
            return Spot::Lost;
        }
        self.walk(f, [ux, uy])
    }

    /// The smallest angle of any triangle, in radians.
    pub fn smallest_angle(&self) -> f64 {
        (0..self.face_he.len())
            .map(|f| {
                let a = self.corner_angles(self.face_edges(f));
                a[0].min(a[1]).min(a[2])
            })
            .fold(std::f64::consts::PI, f64::min)
    }
}
