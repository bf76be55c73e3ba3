//! Per-triangle constants of a 3D mesh, computed once: each triangle laid out isometrically
//! in its own plane, its area, `Dm⁻¹`, the coefficients of `F = Ds Dm⁻¹` per vertex, and the
//! cotangent weights of its edges.

use crate::io::SurfaceMesh;

/// The constants of every triangle.
#[derive(Clone, Debug)]
pub(crate) struct Frames {
    pub faces: Vec<[u32; 3]>,
    /// Local 2D coordinates: `a = (0, 0)`, `b = (xb, 0)`, `c = (xc, yc)`.
    pub local: Vec<[[f64; 2]; 3]>,
    pub area: Vec<f64>,
    /// `∂F[r][c] / ∂u[v][r] = g[v][c]` for the triangle's vertices `v = a, b, c`.
    pub g: Vec<[[f64; 2]; 3]>,
    /// Cotangent of the angle at each corner (the weight of the opposite edge, doubled).
    pub cot: Vec<[f64; 3]>,
    pub total_area: f64,
}

impl Frames {
    /// The constants of `mesh`'s triangles; `None` names the first degenerate one.
    pub fn new(mesh: &SurfaceMesh) -> Result<Frames, usize> {
        let m = mesh.faces.len();
        let mut fr = Frames {
            faces: mesh.faces.clone(),
            local: Vec::with_capacity(m),
            area: Vec::with_capacity(m),
            g: Vec::with_capacity(m),
            cot: Vec::with_capacity(m),
            total_area: 0.0,
        };
        for (f, &[a, b, c]) in mesh.faces.iter().enumerate() {
            // A vertex out of range makes the triangle degenerate (NaN), never a panic.
            let p = |v: u32| {
                mesh.positions
                    .get(v as usize)
                    .copied()
                    .unwrap_or([f64::NAN; 3])
            };
            let sub = |x: [f64; 3], y: [f64; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
            let (e1, e2) = (sub(p(b), p(a)), sub(p(c), p(a)));
            let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
            let xb = dot(e1, e1).sqrt();
            let xc = dot(e1, e2) / xb;
            let yc = (dot(e2, e2) - xc * xc).max(0.0).sqrt();
            let area = 0.5 * xb * yc;
            if !(area > 0.0 && area.is_finite()) {
                return Err(f);
            }
            // Dm = [[xb, xc], [0, yc]], Dm⁻¹ = [[1/xb, -xc/(xb yc)], [0, 1/yc]].
            let w = [[1.0 / xb, -xc / (xb * yc)], [0.0, 1.0 / yc]];
            let gb = w[0];
            let gc = w[1];
            let ga = [-(gb[0] + gc[0]), -(gb[1] + gc[1])];
            fr.g.push([ga, gb, gc]);
            let pts = [[0.0, 0.0], [xb, 0.0], [xc, yc]];
            let cot = |i: usize| {
                let (o, p1, p2) = (pts[i], pts[(i + 1) % 3], pts[(i + 2) % 3]);
                let (u, v) = ([p1[0] - o[0], p1[1] - o[1]], [p2[0] - o[0], p2[1] - o[1]]);
                (u[0] * v[0] + u[1] * v[1]) / (u[0] * v[1] - u[1] * v[0]).abs()
            };
            fr.cot.push([cot(0), cot(1), cot(2)]);
            fr.local.push(pts);
            fr.area.push(area);
            fr.total_area += area;
        }
        Ok(fr)
    }

    /// The constants of the triangles `faces` (indices into these), their vertices
    /// renumbered by `local` (global vertex to local index; every vertex of those faces
    /// mapped): a part of the mesh solved on its own, with the same constants.
    pub fn select(&self, faces: &[usize], local: &[u32]) -> Frames {
        let area: Vec<f64> = faces.iter().map(|&f| self.area[f]).collect();
        Frames {
            faces: faces
                .iter()
                .map(|&f| self.faces[f].map(|v| local[v as usize]))
                .collect(),
            local: faces.iter().map(|&f| self.local[f]).collect(),
            g: faces.iter().map(|&f| self.g[f]).collect(),
            cot: faces.iter().map(|&f| self.cot[f]).collect(),
            total_area: area.iter().sum(),
            area,
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.faces.len()
    }

    /// The deformation gradient of triangle `f` under the map `uv`.
    pub fn gradient(&self, f: usize, uv: &[[f64; 2]]) -> [[f64; 2]; 2] {
        let g = &self.g[f];
        let mut out = [[0.0; 2]; 2];
        for (k, &v) in self.faces[f].iter().enumerate() {
            let u = uv[v as usize];
            for r in 0..2 {
                for c in 0..2 {
                    out[r][c] += u[r] * g[k][c];
                }
            }
        }
        out
    }
}
