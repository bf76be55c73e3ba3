//! Intrinsic triangulations: a triangle mesh known only by its connectivity and edge lengths,
//! and edge flips that make it Delaunay.
//!
//! Flipping an edge of an intrinsic triangulation replaces it by the other diagonal of its two
//! triangles, laid out flat side by side, with the length measured in that layout: the surface
//! (and its metric) is unchanged, only the triangulation on it is. Flipping every edge whose
//! opposite angles sum to more than π ends in the intrinsic Delaunay triangulation, on which
//! the cotan Laplacian has non-negative weights (Bobenko and Springborn 2007; Fisher et al.
//! 2006; Sharp, Soliman and Crane 2019).
//!
//! The connectivity is a half-edge structure: half-edge `h` runs from `origin[h]` around its
//! face (`next`), `twin[h]` is the opposite half-edge or [`NONE`] on the boundary. After flips
//! the triangulation may join a vertex pair by several edges; everything here works per
//! half-edge and never looks edges up by their vertices. On the doubled surface
//! ([`Intrinsic::double_across_boundary`]) an edge may even join a vertex to itself.

/// No twin: a boundary half-edge.
pub const NONE: u32 = u32::MAX;

/// Why a mesh cannot be made into a half-edge triangulation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TriangulationError {
    /// Two faces use the same edge in the same direction: the mesh is not manifold there, or
    /// its faces are not consistently oriented.
    #[error("the edge from vertex {a} to vertex {b} is used twice in the same direction, by faces {first} and {second} (0-based): the mesh is non-manifold or inconsistently oriented there")]
    NonManifoldEdge {
        /// Origin vertex.
        a: u32,
        /// Destination vertex.
        b: u32,
        /// First face using it.
        first: usize,
        /// Second face using it.
        second: usize,
    },
    /// A face names one vertex twice or an index out of range.
    #[error("face {face} (0-based; vertices {} {} {}) repeats a vertex or names one out of range", vertices[0], vertices[1], vertices[2])]
    BadFace {
        /// The face.
        face: usize,
        /// Its vertices.
        vertices: [u32; 3],
    },
    /// A face whose edge lengths do not make a triangle of positive area.
    #[error("face {face} (0-based) is degenerate (edge lengths {} {} {})", lengths[0], lengths[1], lengths[2])]
    Degenerate {
        /// The face.
        face: usize,
        /// Its edge lengths.
        lengths: [f64; 3],
    },
}

/// A triangle mesh by connectivity and edge lengths.
#[derive(Clone, Debug)]
pub struct Intrinsic {
    pub(super) origin: Vec<u32>,
    pub(super) next: Vec<u32>,
    pub(super) twin: Vec<u32>,
    /// Length of each half-edge's edge (twins agree).
    pub(super) len: Vec<f64>,
    /// Face of each half-edge, and a half-edge of each face.
    pub(super) face_of: Vec<u32>,
    pub(super) face_he: Vec<u32>,
    pub(super) n_vertices: usize,
    /// Whether this is the doubled surface of [`Intrinsic::double_across_boundary`].
    pub(super) doubled: bool,
    /// For each half-edge, the half-edge of the input mesh it lies on (itself unless
    /// [`Intrinsic::refine`] split it; meaningful on the boundary, whose edges never flip).
    pub(super) parent: Vec<u32>,
}

impl Intrinsic {
    /// The triangulation of `faces` over `n_vertices` vertices with the Euclidean lengths of
    /// `positions`. Fails on a face of zero area (see [`Intrinsic::from_mesh_mollified`]).
    pub fn from_mesh(
        positions: &[[f64; 3]],
        faces: &[[u32; 3]],
    ) -> Result<Intrinsic, TriangulationError> {
        Intrinsic::from_mesh_mollified(positions, faces, 0.0).map(|(tri, _)| tri)
    }

    /// As [`Intrinsic::from_mesh`], after *intrinsic mollification* (Sharp and Crane 2020, *A
    /// Laplacian for Nonmanifold Triangle Meshes*): every edge length grows by the smallest
    /// `ε ≥ 0` such that each triangle satisfies the triangle inequality with margin `delta`
    /// (`l_i + l_j ≥ l_k + delta` at every corner). With `delta > 0` faces of zero or
    /// nearly zero area become valid intrinsic triangles; a mesh whose triangles all meet the
    /// margin is left exactly as it is (`ε = 0`). Returns the triangulation and `ε`.
    pub fn from_mesh_mollified(
        positions: &[[f64; 3]],
        faces: &[[u32; 3]],
        delta: f64,
    ) -> Result<(Intrinsic, f64), TriangulationError> {
        let n = positions.len();
        let m = faces.len();
        let mut origin = Vec::with_capacity(3 * m);
        let mut next = Vec::with_capacity(3 * m);
        let mut len = Vec::with_capacity(3 * m);
        for (f, &[a, b, c]) in faces.iter().enumerate() {
            if a == b || b == c || c == a || [a, b, c].iter().any(|&v| v as usize >= n) {
                return Err(TriangulationError::BadFace {
                    face: f,
                    vertices: [a, b, c],
                });
            }
            let base = 3 * f as u32;
            for (k, (p, q)) in [(a, b), (b, c), (c, a)].into_iter().enumerate() {
                origin.push(p);
                next.push(base + (k as u32 + 1) % 3);
                len.push(crate::vec3::distance(
                    positions[p as usize],
                    positions[q as usize],
                ));
            }
        }
        // Mollify: the largest shortfall of any corner's triangle inequality against `delta`
        // (adding ε to all three sides adds ε to each `l_i + l_j - l_k`).
        let mut epsilon: f64 = 0.0;
        if delta > 0.0 {
            for l in len.chunks_exact(3) {
                for k in 0..3 {
                    let slack = l[k] + l[(k + 1) % 3] - l[(k + 2) % 3];
                    epsilon = epsilon.max(delta - slack);
                }
            }
            if epsilon > 0.0 {
                for l in &mut len {
                    *l += epsilon;
                }
            }
        }
        for f in 0..m {
            let l = [len[3 * f], len[3 * f + 1], len[3 * f + 2]];
            if !positive(triangle_area(l[0], l[1], l[2])) {
                return Err(TriangulationError::Degenerate {
                    face: f,
                    lengths: l,
                });
            }
        }
        // Twins: sort half-edges by (origin, destination) and match each with its reverse.
        let dest = |h: usize| origin[next[h] as usize];
        let mut keyed: Vec<(u32, u32, u32)> =
            (0..3 * m).map(|h| (origin[h], dest(h), h as u32)).collect();
        keyed.sort_unstable();
        for w in keyed.windows(2) {
            if w[0].0 == w[1].0 && w[0].1 == w[1].1 {
                return Err(TriangulationError::NonManifoldEdge {
                    a: w[0].0,
                    b: w[0].1,
                    first: w[0].2 as usize / 3,
                    second: w[1].2 as usize / 3,
                });
            }
        }
        let mut twin = vec![NONE; 3 * m];
        for h in 0..3 * m {
            let key = (dest(h), origin[h]);
            if let Ok(k) = keyed.binary_search_by(|e| (e.0, e.1).cmp(&key)) {
                twin[h] = keyed[k].2;
            }
        }
        let tri = Intrinsic {
            parent: (0..3 * m as u32).collect(),
            face_of: (0..3 * m as u32).map(|h| h / 3).collect(),
            face_he: (0..m as u32).map(|f| 3 * f).collect(),
            origin,
            next,
            twin,
            len,
            n_vertices: n,
            doubled: false,
        };
        Ok((tri, epsilon))
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }

    /// Whether this is the doubled surface ([`Intrinsic::double_across_boundary`]).
    pub fn is_doubled(&self) -> bool {
        self.doubled
    }

    /// The twin of half-edge `h` ([`NONE`] on the boundary). Before any flip, half-edge
    /// `3f + k` runs from corner `k` of face `f` to corner `k + 1`.
    pub fn twin(&self, h: usize) -> u32 {
        self.twin[h]
    }

    /// Number of faces.
    pub fn n_faces(&self) -> usize {
        self.face_he.len()
    }

    /// Face `f`'s vertices `[a, b, c]` (counter-clockwise) and edge lengths
    /// `[|bc|, |ca|, |ab|]` (opposite each vertex).
    pub fn face(&self, f: usize) -> ([u32; 3], [f64; 3]) {
        let h0 = self.face_he[f] as usize;
        let h1 = self.next[h0] as usize;
        let h2 = self.next[h1] as usize;
        (
            [self.origin[h0], self.origin[h1], self.origin[h2]],
            [self.len[h1], self.len[h2], self.len[h0]],
        )
    }

    /// Whether a vertex lies on the boundary (is the origin of a half-edge without twin).
    pub fn boundary_vertices(&self) -> Vec<bool> {
        let mut on = vec![false; self.n_vertices];
        for (h, &t) in self.twin.iter().enumerate() {
            if t == NONE {
                on[self.origin[h] as usize] = true;
                on[self.origin[self.next[h] as usize] as usize] = true;
            }
        }
        on
    }

    /// Glues a mirror image of the triangulation to it along the boundary, making the
    /// *doubled surface*: a closed surface (the tufted cover of Sharp and Crane 2020 for a
    /// manifold mesh) whose two sheets share the vertices. Returns the number of boundary
    /// edges glued (0, and no change, for a closed triangulation).
    ///
    /// Functions on the vertices are the same on both sheets, so the doubled surface's cotan
    /// Laplacian and masses are twice the mesh's own with zero-flux (Neumann) boundary
    /// conditions, until flips: [`Intrinsic::flip_to_delaunay`] may then flip a boundary edge
    /// (whose single opposite angle is obtuse) across to the other sheet, which removes the
    /// negative cotan weights that interior flips alone leave on the boundary. Such a flip
    /// joins the vertex opposite the edge to itself (an edge from a vertex to itself across
    /// the two sheets). [`Intrinsic::weighted_faces`] halves the doubled surface back.
    pub fn double_across_boundary(&mut self) -> usize {
        if self.doubled {
            return 0;
        }
        let nh = self.origin.len();
        let m = self.n_faces();
        if self.twin.iter().all(|&t| t != NONE) {
            return 0;
        }
        // The mirror of face (a, b, c), with half-edges a->b, b->c, c->a, is (a, c, b); the
        // mirror of half-edge k of the face (k = 0, 1, 2) runs the other way and is half-edge
        // MIRROR[k] of the mirror face, whose half-edges are b->a, a->c, c->b.
        const MIRROR: [usize; 3] = [0, 2, 1];
        let mirror = |h: usize| nh + 3 * (h / 3) + MIRROR[h % 3];
        // Only the original layout (face f's half-edges at 3f..3f+3) is mirrored: this runs
        // before any flip.
        debug_assert!((0..m).all(|f| self.face_he[f] as usize == 3 * f));
        self.origin.resize(2 * nh, 0);
        self.next.resize(2 * nh, 0);
        self.twin.resize(2 * nh, NONE);
        self.len.resize(2 * nh, 0.0);
        self.parent = (0..2 * nh as u32).collect();
        let mut glued = 0;
        for h in 0..nh {
            let g = mirror(h);
            // The mirror runs from h's destination to h's origin.
            self.origin[g] = self.origin[self.next[h] as usize];
            self.len[g] = self.len[h];
            // In the mirror face the order is reversed: mirror(h) is followed by the mirror
            // of h's predecessor in its face.
            let prev = 3 * (h / 3) + (h % 3 + 2) % 3;
            self.next[g] = mirror(prev) as u32;
            let t = self.twin[h];
            if t == NONE {
                self.twin[h] = g as u32;
                self.twin[g] = h as u32;
                glued += 1;
            } else {
                self.twin[g] = mirror(t as usize) as u32;
            }
        }
        self.face_of = (0..2 * nh as u32).map(|h| h / 3).collect();
        self.face_he = (0..2 * m as u32).map(|f| 3 * f).collect();
        self.doubled = true;
        glued
    }

    /// Every face with its vertices, edge lengths (as [`Intrinsic::face`]) and the weight of
    /// its contribution to the operators: 1, except on the doubled surface, where the two
    /// mirror copies of a face are given once with weight 1 and a face without an identical
    /// copy (one made by flipping across the boundary) has weight ½. Either way the operators
    /// assembled from these faces are those of the mesh itself.
    pub fn weighted_faces(&self) -> Vec<([u32; 3], [f64; 3], f64)> {
        let faces: Vec<([u32; 3], [f64; 3])> = (0..self.n_faces()).map(|f| self.face(f)).collect();
        if !self.doubled {
            return faces.into_iter().map(|(v, l)| (v, l, 1.0)).collect();
        }
        // A face's contribution depends only on which vertex is opposite which length: sort
        // the (vertex, length) corners so that mirror copies get the same key.
        let key = |f: usize| {
            let (v, l) = faces[f];
            let mut corners = [
                (v[0], l[0].to_bits()),
                (v[1], l[1].to_bits()),
                (v[2], l[2].to_bits()),
            ];
            corners.sort_unstable();
            corners
        };
        let mut order: Vec<usize> = (0..faces.len()).collect();
        order.sort_unstable_by_key(|&f| (key(f), f));
        let mut out = Vec::with_capacity(faces.len() / 2 + 16);
        let mut i = 0;
        while i < order.len() {
            let f = order[i];
            if i + 1 < order.len() && key(order[i + 1]) == key(f) {
                out.push((f, 1.0));
                i += 2;
            } else {
                out.push((f, 0.5));
                i += 1;
            }
        }
        // Back in face order, for the locality of the passes over the faces.
        out.sort_unstable_by_key(|&(f, _)| f);
        out.into_iter()
            .map(|(f, w)| (faces[f].0, faces[f].1, w))
            .collect()
    }

    /// The boundary edges `(a, b, length)` (none once doubled).
    pub fn boundary_edges(&self) -> Vec<(u32, u32, f64)> {
        (0..self.origin.len())
            .filter(|&h| self.twin[h] == NONE)
            .map(|h| {
                (
                    self.origin[h],
                    self.origin[self.next[h] as usize],
                    self.len[h],
                )
            })
            .collect()
    }

    /// For each of [`Intrinsic::boundary_edges`], in the same order, the half-edge of the
    /// input mesh it lies on (itself unless [`Intrinsic::refine`] split it).
    pub fn boundary_parents(&self) -> Vec<u32> {
        (0..self.origin.len())
            .filter(|&h| self.twin[h] == NONE)
            .map(|h| self.parent[h])
            .collect()
    }

    /// The sum of the cotangents of the two angles opposite `h`'s edge (one when it is a
    /// boundary edge); negative when the edge is not Delaunay.
    pub(super) fn cot_sum(&self, h: usize) -> f64 {
        let opposite = |h: usize| {
            let n = self.next[h] as usize;
            let p = self.next[n] as usize;
            cot_opposite(self.len[h], self.len[n], self.len[p])
        };
        let t = self.twin[h];
        if t == NONE {
            opposite(h)
        } else {
            opposite(h) + opposite(t as usize)
        }
    }

    /// Flips edges until every interior edge is Delaunay (its opposite angles sum to at most
    /// π, to a relative 1e-12), and returns the number of flips.
    pub fn flip_to_delaunay(&mut self) -> usize {
        let nh = self.origin.len();
        // A stack of half-edges to check, one per edge, and whether each edge is on it.
        let mut queued = vec![false; nh];
        let mut stack: Vec<u32> = Vec::with_capacity(nh / 2);
        for (h, (q, &t)) in queued.iter_mut().zip(&self.twin).enumerate() {
            if t != NONE && (h as u32) < t {
                *q = true;
                stack.push(h as u32);
            }
        }
        let key = |this: &Intrinsic, h: u32| h.min(this.twin[h as usize]) as usize;
        let mut flips = 0;
        // Delaunay flipping terminates; the cap only guards against round-off cycles.
        let cap = 64 * nh + 1000;
        while let Some(h) = stack.pop() {
            queued[h as usize] = false;
            if flips >= cap {
                break;
            }
            let h = h as usize;
            if self.cot_sum(h) >= -1e-12 {
                continue;
            }
            if !self.flip(h) {
                continue;
            }
            flips += 1;
            let t = self.twin[h] as usize;
            for e in [
                self.next[h],
                self.next[self.next[h] as usize],
                self.next[t],
                self.next[self.next[t] as usize],
            ] {
                if self.twin[e as usize] != NONE {
                    let k = key(self, e);
                    if !queued[k] {
                        queued[k] = true;
                        stack.push(k as u32);
                    }
                }
            }
        }
        flips
    }

    /// Flips the interior edge of half-edge `h`; false (and no change) when it cannot be
    /// flipped (a boundary edge, both sides one face, or a degenerate layout).
    pub(super) fn flip(&mut self, h: usize) -> bool {
        let t = self.twin[h];
        if t == NONE {
            return false;
        }
        let t = t as usize;
        let (f1, f2) = (self.face_of[h], self.face_of[t]);
        if f1 == f2 {
            return false;
        }
        // Face 1: h (a -> b), hn (b -> c), hp (c -> a); face 2: t (b -> a), tn (a -> d),
        // tp (d -> b).
        let (hn, tn) = (self.next[h] as usize, self.next[t] as usize);
        let (hp, tp) = (self.next[hn] as usize, self.next[tn] as usize);
        let (c, d) = (self.origin[hp], self.origin[tp]);
        let (ab, bc, ca) = (self.len[h], self.len[hn], self.len[hp]);
        let (ad, db) = (self.len[tn], self.len[tp]);
        // Lay the two triangles out with the midpoint of ab at the origin, a on the negative
        // and b on the positive x axis, c above and d below. The formulas are symmetric in
        // a and b to the last bit (swapping them negates cx and dx exactly), so that the
        // mirror image of a flip on the doubled surface gives the same length, and the
        // mirror pairs of faces are found again.
        let cx = (ca * ca - bc * bc) / (2.0 * ab);
        let cy = 2.0 * triangle_area(ab, bc, ca) / ab;
        let dx = (ad * ad - db * db) / (2.0 * ab);
        let dy = 2.0 * triangle_area(ab, ad, db) / ab;
        let cd = (cx - dx).hypot(cy + dy);
        // The new triangles (d, c, a) and (c, d, b) must have positive area.
        if !(positive(triangle_area(cd, ca, ad)) && positive(triangle_area(cd, db, bc))) {
            return false;
        }
        self.origin[h] = d;
        self.origin[t] = c;
        self.len[h] = cd;
        self.len[t] = cd;
        // Face 1 becomes h (d -> c), hp (c -> a), tn (a -> d); face 2 t (c -> d), tp (d -> b),
        // hn (b -> c).
        self.next[h] = hp as u32;
        self.next[hp] = tn as u32;
        self.next[tn] = h as u32;
        self.next[t] = tp as u32;
        self.next[tp] = hn as u32;
        self.next[hn] = t as u32;
        self.face_of[tn] = f1;
        self.face_of[hn] = f2;
        self.face_he[f1 as usize] = h as u32;
        self.face_he[f2 as usize] = t as u32;
        true
    }

    /// The largest violation of the Delaunay condition: the most negative sum of opposite
    /// cotangents over interior edges (0 when Delaunay).
    pub fn worst_cot_sum(&self) -> f64 {
        (0..self.origin.len())
            .filter(|&h| self.twin[h] != NONE)
            .map(|h| self.cot_sum(h))
            .fold(0.0, f64::min)
    }
}

/// Area of a triangle with side lengths `a`, `b`, `c` (Heron, in Kahan's stable form); NaN
/// or zero when they break the triangle inequality.
pub fn triangle_area(a: f64, b: f64, c: f64) -> f64 {
    // Sort so that a >= b >= c.
    let (mut a, mut b, mut c) = (a, b, c);
    if a < b {
        std::mem::swap(&mut a, &mut b);
    }
    if b < c {
        std::mem::swap(&mut b, &mut c);
    }
    if a < b {
        std::mem::swap(&mut a, &mut b);
    }
    let p = (a + (b + c)) * (c - (a - b)) * (c + (a - b)) * (a + (b - c));
    0.25 * p.sqrt()
}

/// Whether `x` is a positive number (false for NaN).
pub(super) fn positive(x: f64) -> bool {
    x > 0.0
}

/// Cotangent of the angle opposite side `a` in the triangle with sides `a`, `b`, `c`.
pub fn cot_opposite(a: f64, b: f64, c: f64) -> f64 {
    (b * b + c * c - a * a) / (4.0 * triangle_area(a, b, c))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square split along the diagonal 0-2 into two right triangles: Delaunay (the
    /// opposite angles sum to exactly pi).
    fn square(stretch: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        (
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, stretch, 0.0],
                [0.0, stretch, 0.0],
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn heron_and_cotangents_of_a_right_triangle() {
        assert!((triangle_area(3.0, 4.0, 5.0) - 6.0).abs() < 1e-14);
        assert!(cot_opposite(5.0, 3.0, 4.0).abs() < 1e-15);
        assert!((cot_opposite(3.0, 4.0, 5.0) - 4.0 / 3.0).abs() < 1e-14);
        assert!(!positive(triangle_area(1.0, 1.0, 3.0)));
    }

    #[test]
    fn a_thin_quad_flips_to_its_short_diagonal_and_keeps_its_area() {
        // A rhombus made of two thin triangles sharing the long diagonal: flipping makes the
        // short diagonal the edge.
        let pos = vec![
            [0.0, 0.0, 0.0],
            [4.0, 0.0, 0.0],
            [2.0, 0.5, 0.0],
            [2.0, -0.5, 0.0],
        ];
        let faces = vec![[0, 1, 2], [1, 0, 3]];
        let mut tri = Intrinsic::from_mesh(&pos, &faces).expect("valid");
        let area = |t: &Intrinsic| {
            (0..t.n_faces())
                .map(|f| {
                    let (_, l) = t.face(f);
                    triangle_area(l[0], l[1], l[2])
                })
                .sum::<f64>()
        };
        let before = area(&tri);
        assert!(tri.worst_cot_sum() < 0.0);
        assert_eq!(tri.flip_to_delaunay(), 1);
        assert!(tri.worst_cot_sum() >= -1e-12);
        assert!((area(&tri) - before).abs() < 1e-12);
        // The new edge joins 2 and 3, of length 1.
        let has_short = (0..2).any(|f| {
            let (v, l) = tri.face(f);
            (0..3).any(|k| {
                let (p, q) = (v[(k + 1) % 3], v[(k + 2) % 3]);
                ((p == 2 && q == 3) || (p == 3 && q == 2)) && (l[k] - 1.0).abs() < 1e-12
            })
        });
        assert!(has_short, "{:?} {:?}", tri.face(0), tri.face(1));
    }

    #[test]
    fn a_delaunay_square_is_left_alone_and_boundaries_are_found() {
        let (pos, faces) = square(1.0);
        let mut tri = Intrinsic::from_mesh(&pos, &faces).expect("valid");
        assert_eq!(tri.flip_to_delaunay(), 0);
        assert_eq!(tri.boundary_vertices(), vec![true; 4]);
    }

    /// Total area of weighted faces.
    fn weighted_area(tri: &Intrinsic) -> f64 {
        tri.weighted_faces()
            .iter()
            .map(|(_, l, w)| w * triangle_area(l[0], l[1], l[2]))
            .sum()
    }

    #[test]
    fn the_doubled_surface_is_closed_and_halves_back_to_the_mesh() {
        let (pos, faces) = square(1.0);
        let mut tri = Intrinsic::from_mesh(&pos, &faces).expect("valid");
        let before = tri.weighted_faces();
        assert_eq!(tri.double_across_boundary(), 4);
        assert_eq!(tri.double_across_boundary(), 0, "only once");
        assert!(tri.twin.iter().all(|&t| t != NONE));
        for h in 0..tri.origin.len() {
            let t = tri.twin[h] as usize;
            assert_eq!(tri.twin[t] as usize, h);
            // Twins run in opposite directions and have one length.
            assert_eq!(tri.origin[t], tri.origin[tri.next[h] as usize]);
            assert_eq!(tri.len[t], tri.len[h]);
        }
        assert_eq!(tri.n_faces(), 4);
        assert_eq!(tri.flip_to_delaunay(), 0);
        assert_eq!(tri.weighted_faces(), before);
        // A closed triangulation is left alone.
        let mut closed = Intrinsic::from_mesh(
            &[
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            &[[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        )
        .expect("valid");
        assert_eq!(closed.double_across_boundary(), 0);
        assert_eq!(closed.n_faces(), 4);
    }

    #[test]
    fn flips_across_the_boundary_remove_its_negative_weights() {
        // A thin triangle whose angle opposite its boundary side is nearly flat, on top of a
        // well-shaped one: only a flip across the boundary can make the side's weight
        // non-negative.
        let pos = vec![
            [0.0, 0.0, 0.0],
            [4.0, 0.0, 0.0],
            [2.0, 0.2, 0.0],
            [2.0, 3.0, 0.0],
        ];
        let faces = vec![[0, 1, 2], [0, 2, 3], [2, 1, 3]];
        let mut inside = Intrinsic::from_mesh(&pos, &faces).expect("valid");
        inside.flip_to_delaunay();
        let boundary_cot = (0..inside.origin.len())
            .filter(|&h| inside.twin[h] == NONE)
            .map(|h| inside.cot_sum(h))
            .fold(f64::INFINITY, f64::min);
        assert!(boundary_cot < -1.0, "{boundary_cot}");
        let mut tri = Intrinsic::from_mesh(&pos, &faces).expect("valid");
        let area = weighted_area(&tri);
        tri.double_across_boundary();
        assert!(tri.flip_to_delaunay() > 0);
        assert!(tri.worst_cot_sum() >= -1e-12, "{}", tri.worst_cot_sum());
        // The flip joined vertex 2 to itself; faces made by it have weight one half, and
        // the halved surface keeps the mesh's area.
        let weighted = tri.weighted_faces();
        assert!(weighted
            .iter()
            .any(|(v, _, w)| *w == 0.5 && v.iter().filter(|&&x| x == 2).count() == 2));
        assert!((weighted_area(&tri) - area).abs() < 1e-12 * area);
    }

    #[test]
    fn a_flip_and_its_mirror_image_give_the_same_length_to_the_bit() {
        // Quads (a, b, c, d) split along ab into (a, b, c) and (b, a, d), and their mirror
        // images (a, c, b) and (b, d, a): flipping ab must give one length, so that the two
        // sheets of the doubled surface stay mirror images after flips.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut checked = 0;
        for _ in 0..200 {
            let pos = vec![
                [0.0, 0.0, 0.0],
                [1.0 + 3.0 * next(), 0.1 * next(), 0.0],
                [0.2 + next(), 0.05 + 0.3 * next(), 0.1 * next()],
                [0.2 + next(), -0.05 - 0.3 * next(), 0.1 * next()],
            ];
            let mut front = Intrinsic::from_mesh(&pos, &[[0, 1, 2], [1, 0, 3]]).expect("valid");
            let mut back = Intrinsic::from_mesh(&pos, &[[0, 2, 1], [1, 3, 0]]).expect("valid");
            // Half-edge 0 runs a -> b in front; half-edge 2 runs b -> a in back.
            assert_eq!((back.origin[2], back.origin[back.next[2] as usize]), (1, 0));
            if front.flip(0) {
                assert!(back.flip(2));
                assert_eq!(front.len[0].to_bits(), back.len[2].to_bits());
                checked += 1;
            }
        }
        assert!(checked > 100, "{checked}");
    }

    #[test]
    fn mollification_lengthens_every_edge_just_enough() {
        let line = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
        let (tri, eps) = Intrinsic::from_mesh_mollified(&line, &[[0, 1, 2]], 0.01).expect("valid");
        // 1 + 2 = 3: the shortfall against the margin is 0.01.
        assert!((eps - 0.01).abs() < 1e-15);
        let (_, l) = tri.face(0);
        let mut l = l.to_vec();
        l.sort_by(f64::total_cmp);
        assert!((l[0] + l[1] - l[2] - 0.01).abs() < 1e-12, "{l:?}");
        assert!(positive(triangle_area(l[0], l[1], l[2])));
        // A triangle with the margin already is left exactly as it is.
        let (pos, faces) = square(1.0);
        let (tri, eps) = Intrinsic::from_mesh_mollified(&pos, &faces, 0.01).expect("valid");
        assert_eq!(eps, 0.0);
        assert_eq!(
            tri.len,
            Intrinsic::from_mesh(&pos, &faces).expect("valid").len
        );
    }

    #[test]
    fn bad_meshes_are_refused() {
        let (pos, _) = square(1.0);
        assert!(matches!(
            Intrinsic::from_mesh(&pos, &[[0, 1, 2], [0, 1, 3]]),
            Err(TriangulationError::NonManifoldEdge { a: 0, b: 1, .. })
        ));
        assert!(matches!(
            Intrinsic::from_mesh(&pos, &[[0, 1, 1]]),
            Err(TriangulationError::BadFace { face: 0, .. })
        ));
        assert!(matches!(
            Intrinsic::from_mesh(&pos, &[[0, 1, 9]]),
            Err(TriangulationError::BadFace { .. })
        ));
        let line = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert!(matches!(
            Intrinsic::from_mesh(&line, &[[0, 1, 2]]),
            Err(TriangulationError::Degenerate { face: 0, .. })
        ));
    }
}
