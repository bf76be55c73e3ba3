//! A direct, uncompiled implementation of one Newton step's numeric work: walk the triangles,
//! compute angles with the law of cosines, accumulate the gradient and the Hessian as
//! triplets, and build the sparse matrix from them.
//!
//! It shares no code with the compiler or the VM, so tests compare the two, and benchmarks
//! use it as the baseline the compiled form is measured against.

use std::f64::consts::PI;

use faer::sparse::{SparseColMat, Triplet};

use crate::mesh::PlanarMesh;

/// Interior/boundary classification and unknown numbering of a disk mesh, by vertex.
#[derive(Clone, Debug)]
pub struct Unknowns {
    /// `Some(k)` for interior vertices (unknown `k`), `None` on the boundary.
    pub of_vertex: Vec<Option<usize>>,
    /// Number of unknowns.
    pub count: usize,
}

impl Unknowns {
    /// Numbers the interior vertices of `mesh` in vertex order. A vertex is on the boundary
    /// when one of its edges belongs to a single triangle.
    pub fn new(mesh: &PlanarMesh) -> Unknowns {
        let mut uses = std::collections::HashMap::new();
        for f in &mesh.faces {
            for i in 0..3 {
                let (a, b) = (f[i], f[(i + 1) % 3]);
                *uses.entry((a.min(b), a.max(b))).or_insert(0u32) += 1;
            }
        }
        let mut boundary = vec![false; mesh.positions.len()];
        for (&(a, b), &n) in &uses {
            if n == 1 {
                boundary[a as usize] = true;
                boundary[b as usize] = true;
            }
        }
        let mut count = 0;
        let of_vertex = boundary
            .iter()
            .map(|&b| {
                if b {
                    None
                } else {
                    count += 1;
                    Some(count - 1)
                }
            })
            .collect();
        Unknowns { of_vertex, count }
    }
}

/// Angle opposite side `c` by the law of cosines; 0 or pi where the triangle inequality fails.
pub fn angle(a: f64, b: f64, c: f64) -> f64 {
    if c >= a + b {
        PI
    } else if a >= b + c || b >= a + c {
        0.0
    } else {
        ((a * a + b * b - c * c) / (2.0 * a * b))
            .clamp(-1.0, 1.0)
            .acos()
    }
}

/// Gradient (per unknown) and Hessian (lower triangle, as a sparse matrix over unknowns) of
/// the CETM energy for the metric `l0^2 = (1 - t) |A_i - A_j|^2 + t |B_i - B_j|^2` scaled by
/// `u` (one value per vertex; boundary values are ignored and taken as 0).
pub fn gradient_and_hessian(
    a: &PlanarMesh,
    b: &PlanarMesh,
    t: f64,
    u: &[f64],
    unknowns: &Unknowns,
) -> (Vec<f64>, SparseColMat<usize, f64>) {
    let n = unknowns.count;
    let uv = |v: u32| unknowns.of_vertex[v as usize].map_or(0.0, |_| u[v as usize]);
    let mut grad = vec![PI; n];
    let mut triplets = Vec::with_capacity(a.faces.len() * 9);
    for f in &a.faces {
        let len = |i: usize, j: usize| {
            let (p, q) = (f[i], f[j]);
            let d2 = |m: &PlanarMesh| {
                let (x, y) = (m.positions[p as usize], m.positions[q as usize]);
                (x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2)
            };
            ((1.0 - t) * d2(a) + t * d2(b)).sqrt() * (0.5 * (uv(p) + uv(q))).exp()
        };
        // l[i] is the side opposite corner i.
        let l = [len(1, 2), len(2, 0), len(0, 1)];
        for i in 0..3 {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let theta = angle(l[j], l[k], l[i]);
            if let Some(ui) = unknowns.of_vertex[f[i] as usize] {
                grad[ui] -= 0.5 * theta;
            }
            // Edge (j, k) is opposite corner i.
            let cot = if theta > 0.0 && theta < PI {
                1.0 / theta.tan()
            } else {
                0.0
            };
            let w = 0.25 * cot;
            let (uj, uk) = (
                unknowns.of_vertex[f[j] as usize],
                unknowns.of_vertex[f[k] as usize],
            );
            if let Some(uj) = uj {
                triplets.push(Triplet::new(uj, uj, w));
            }
            if let Some(uk) = uk {
                triplets.push(Triplet::new(uk, uk, w));
            }
            if let (Some(uj), Some(uk)) = (uj, uk) {
                triplets.push(Triplet::new(uj.max(uk), uj.min(uk), -w));
            }
        }
    }
    // Duplicates are summed; every index is an unknown below n by construction.
    let h = SparseColMat::try_new_from_triplets(n, n, &triplets)
        .expect("triplet indices are unknowns, in range by construction");
    (grad, h)
}
