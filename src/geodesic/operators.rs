//! Per-triangle constants of a triangulation and the operators built from them: the cotan
//! Laplacian's weights, lumped vertex areas, the normalised gradient field of a function and
//! its divergence.
//!
//! Everything is intrinsic: each triangle is laid out in its own plane from its edge lengths
//! (vertex `a` at the origin, `b` on the positive x axis, `c` above), so the operators work
//! the same on a mesh's own triangles and on an intrinsic Delaunay triangulation of it, and
//! the gradient and the divergence stay the adjoint pair the Laplacian is made of.

#[cfg(test)]
use super::intrinsic::Intrinsic;
use super::intrinsic::{cot_opposite, triangle_area};

/// Per-triangle constants, structure of arrays.
#[derive(Clone, Debug)]
pub(crate) struct FaceGeometry {
    /// Vertices `[a, b, c]`.
    pub vertices: Vec<[u32; 3]>,
    /// `b = (xb, 0)`.
    xb: Vec<f64>,
    /// `c = (xc, yc)`.
    xc: Vec<f64>,
    yc: Vec<f64>,
    /// Half the cotangent of the angle at each corner (the weight of the opposite edge),
    /// times the face's weight.
    half_cot: Vec<[f64; 3]>,
    /// Areas, times the face's weight.
    pub area: Vec<f64>,
}

impl FaceGeometry {
    /// The constants of every triangle of `tri`, each weighted as
    /// [`Intrinsic::weighted_faces`] says.
    #[cfg(test)]
    pub fn new(tri: &Intrinsic) -> FaceGeometry {
        FaceGeometry::from_faces(&tri.weighted_faces())
    }

    /// The constants of triangles given by their vertices `[a, b, c]`, edge lengths
    /// `[|bc|, |ca|, |ab|]` and a weight that scales their contributions to the Laplacian,
    /// the masses and the divergence.
    pub fn from_faces(faces: &[([u32; 3], [f64; 3], f64)]) -> FaceGeometry {
        let m = faces.len();
        let mut g = FaceGeometry {
            vertices: Vec::with_capacity(m),
            xb: Vec::with_capacity(m),
            xc: Vec::with_capacity(m),
            yc: Vec::with_capacity(m),
            half_cot: Vec::with_capacity(m),
            area: Vec::with_capacity(m),
        };
        for &(v, [la, lb, lc], weight) in faces {
            let area = triangle_area(la, lb, lc);
            g.vertices.push(v);
            g.xb.push(lc);
            g.xc.push((lc * lc + lb * lb - la * la) / (2.0 * lc));
            g.yc.push(2.0 * area / lc);
            let w = 0.5 * weight;
            g.half_cot.push([
                w * cot_opposite(la, lb, lc),
                w * cot_opposite(lb, lc, la),
                w * cot_opposite(lc, la, lb),
            ]);
            g.area.push(weight * area);
        }
        g
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// Every edge of every triangle with the weight it adds to the cotan Laplacian: `(i, j,
    /// w)` with `w` half the cotangent of the opposite angle (an edge inside the mesh appears
    /// twice, once from each side).
    pub fn edge_weights(&self) -> impl Iterator<Item = (u32, u32, f64)> + '_ {
        self.vertices
            .iter()
            .zip(&self.half_cot)
            .flat_map(|(&[a, b, c], &[wa, wb, wc])| [(b, c, wa), (c, a, wb), (a, b, wc)])
    }

    /// Lumped (barycentric) vertex areas: a third of each incident triangle's area.
    pub fn vertex_areas(&self, n_vertices: usize) -> Vec<f64> {
        let mut m = vec![0.0; n_vertices];
        for (v, a) in self.vertices.iter().zip(&self.area) {
            for &i in v {
                m[i as usize] += a / 3.0;
            }
        }
        m
    }

    /// `x[f] = -∇u / |∇u|` in each triangle's own frame (zero where `u` is flat).
    #[cfg(test)]
    pub fn normalized_descent_into(&self, u: &[f64], x: &mut [[f64; 2]]) {
        for (f, out) in x.iter_mut().enumerate() {
            let [a, b, c] = self.vertices[f];
            let (ua, ub, uc) = (u[a as usize], u[b as usize], u[c as usize]);
            let (xb, xc, yc) = (self.xb[f], self.xc[f], self.yc[f]);
            // ∇u = Σ u_i J(e_i) / 2A with e_i the edge opposite i and J a quarter turn; the
            // common factor 1 / 2A drops out in the normalisation.
            let gx = (ub - ua) * yc;
            let gy = ua * (xc - xb) - ub * xc + uc * xb;
            let norm = (gx * gx + gy * gy).sqrt();
            *out = if norm > 0.0 {
                [-gx / norm, -gy / norm]
            } else {
                [0.0, 0.0]
            };
        }
    }

    /// The integrated divergence of the per-triangle field `x` at each vertex:
    /// `½ Σ (cot θ₁ ⟨e₁, X⟩ + cot θ₂ ⟨e₂, X⟩)` over the vertex's triangles, `e₁`, `e₂` the
    /// edges leaving it and `θ₁`, `θ₂` the angles opposite them (Crane et al. 2013).
    #[cfg(test)]
    pub fn divergence_into(&self, x: &[[f64; 2]], div: &mut [f64]) {
        div.fill(0.0);
        for (f, &[xx, xy]) in x.iter().enumerate() {
            let [a, b, c] = self.vertices[f];
            let [wa, wb, wc] = self.half_cot[f];
            let (xb, xc, yc) = (self.xb[f], self.xc[f], self.yc[f]);
            // ⟨e, X⟩ for the edges ab, ac and bc (the others are their negatives).
            let ab = xb * xx;
            let ac = xc * xx + yc * xy;
            let bc = ac - ab;
            div[a as usize] += wc * ab + wb * ac;
            div[b as usize] += wa * bc - wc * ab;
            div[c as usize] += -wb * ac - wa * bc;
        }
    }

    /// The two passes of a query in one: the integrated divergence at each vertex of the unit
    /// field `-∇u / |∇u|` (what [`FaceGeometry::divergence_into`] gives for the field of
    /// [`FaceGeometry::normalized_descent_into`]), without storing the field.
    pub fn descent_divergence_into(&self, u: &[f64], grad: &mut Vec<[f64; 2]>, div: &mut [f64]) {
        let m = self.vertices.len();
        grad.resize(m, [0.0; 2]);
        // 1. The gradients (times 2A), gathering u.
        for (((g, &[a, b, c]), (&xb, &xc)), &yc) in grad
            .iter_mut()
            .zip(&self.vertices)
            .zip(self.xb.iter().zip(&self.xc))
            .zip(&self.yc)
        {
            let (ua, ub, uc) = (u[a as usize], u[b as usize], u[c as usize]);
            *g = [(ub - ua) * yc, ua * (xc - xb) - ub * xc + uc * xb];
        }
        // 2. Normalised and negated, with no gathers or scatters, so the square roots and
        // divisions of neighbouring triangles overlap (and vectorise).
        for g in grad.iter_mut() {
            let norm2 = g[0] * g[0] + g[1] * g[1];
            let scale = if norm2 > 0.0 {
                -1.0 / norm2.sqrt()
            } else {
                0.0
            };
            *g = [g[0] * scale, g[1] * scale];
        }
        // 3. The divergence, scattered to the corners.
        div.fill(0.0);
        for ((((&[xx, xy], &[a, b, c]), (&xb, &xc)), &yc), &[wa, wb, wc]) in grad
            .iter()
            .zip(&self.vertices)
            .zip(self.xb.iter().zip(&self.xc))
            .zip(&self.yc)
            .zip(&self.half_cot)
        {
            let ab = xb * xx;
            let ac = xc * xx + yc * xy;
            let bc = ac - ab;
            div[a as usize] += wc * ab + wb * ac;
            div[b as usize] += wa * bc - wc * ab;
            div[c as usize] += -wb * ac - wa * bc;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradient_of_a_linear_function_points_along_it() {
        // One right triangle; u = 2 x + 3 y in its plane.
        let pos = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.5, 1.5, 0.0]];
        let tri = Intrinsic::from_mesh(&pos, &[[0, 1, 2]]).expect("valid");
        let g = FaceGeometry::new(&tri);
        let u: Vec<f64> = pos.iter().map(|p| 2.0 * p[0] + 3.0 * p[1]).collect();
        let mut x = [[0.0; 2]];
        g.normalized_descent_into(&u, &mut x);
        let n = 13f64.sqrt();
        assert!(
            (x[0][0] + 2.0 / n).abs() < 1e-12 && (x[0][1] + 3.0 / n).abs() < 1e-12,
            "{x:?}"
        );
    }

    #[test]
    fn divergence_is_minus_the_adjoint_of_the_gradient() {
        // Σ_v φ_v div(X)_v = -Σ_f A_f ⟨∇φ, X⟩_f for any φ and X: check on a small fan.
        let mut pos = vec![[0.1, 0.05, 0.2]];
        for i in 0..6 {
            let t = f64::from(i) * std::f64::consts::TAU / 6.0;
            pos.push([t.cos(), t.sin(), 0.1 * f64::from(i % 2)]);
        }
        let faces: Vec<[u32; 3]> = (0..6).map(|i| [0, 1 + i, 1 + (i + 1) % 6]).collect();
        let tri = Intrinsic::from_mesh(&pos, &faces).expect("valid");
        let g = FaceGeometry::new(&tri);
        let phi: Vec<f64> = (0..7).map(|i| (f64::from(i) * 0.7).sin()).collect();
        let x: Vec<[f64; 2]> = (0..6)
            .map(|f| [(f64::from(f)).cos(), 0.3 * f64::from(f)])
            .collect();
        let mut div = vec![0.0; 7];
        g.divergence_into(&x, &mut div);
        let lhs: f64 = phi.iter().zip(&div).map(|(p, d)| p * d).sum();
        let mut rhs = 0.0;
        for (f, xf) in x.iter().enumerate() {
            let [a, b, c] = g.vertices[f];
            let (ua, ub, uc) = (phi[a as usize], phi[b as usize], phi[c as usize]);
            let two_a = g.xb[f] * g.yc[f];
            let gx = (ub - ua) * g.yc[f] / two_a;
            let gy = (ua * (g.xc[f] - g.xb[f]) - ub * g.xc[f] + uc * g.xb[f]) / two_a;
            rhs -= g.area[f] * (gx * xf[0] + gy * xf[1]);
        }
        assert!((lhs - rhs).abs() < 1e-12, "{lhs} vs {rhs}");
        // The fused pass gives the divergence of the normalised descent of any function.
        let mut x = vec![[0.0; 2]; 6];
        g.normalized_descent_into(&phi, &mut x);
        g.divergence_into(&x, &mut div);
        let mut fused = vec![0.0; 7];
        g.descent_divergence_into(&phi, &mut Vec::new(), &mut fused);
        for (a, b) in div.iter().zip(&fused) {
            assert!((a - b).abs() < 1e-14, "{a} vs {b}");
        }
    }
}
