//! The interpolations BDMORPH is compared with on the same compatible meshes: straight lines
//! between the two layouts, and as-rigid-as-possible interpolation (Alexa, Cohen-Or and
//! Levin 2000).

use std::collections::VecDeque;

use bdmorph_cholesky::Cholesky;

use super::InbetweenError;
use crate::io::SurfaceMesh;
use crate::mesh::PlanarMesh;
use crate::param::frames::Frames;
use crate::param::local_global::{free_laplacian, global_rhs, weighted_edges, NONE};

/// Every vertex on the straight line from A's layout to B's: `(1 − t) a + t b`.
///
/// ```
/// let a = [[0.0, 0.0], [2.0, 0.0]];
/// let b = [[1.0, 1.0], [1.0, 3.0]];
/// assert_eq!(bdmorph::inbetween::linear_frame(&a, &b, 0.5), vec![[0.5, 0.5], [1.5, 1.5]]);
/// ```
pub fn linear_frame(a: &[[f64; 2]], b: &[[f64; 2]], t: f64) -> Vec<[f64; 2]> {
    a.iter()
        .zip(b)
        .map(|(p, q)| [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])])
        .collect()
}

/// As-rigid-as-possible interpolation of two layouts of one mesh (Alexa, Cohen-Or and Levin
/// 2000): each triangle's affine map from A to B is split into a rotation and a stretch
/// (polar decomposition), the rotation's angle interpolated (made continuous across
/// neighbouring triangles) and the stretch linearly; the frame is the layout whose triangles
/// come closest to those maps in the least-squares sense (the cotangent Laplacian, factored
/// once), one vertex per piece on its straight line.
pub struct ArapInterpolation {
    frames: Frames,
    /// Per triangle, the rotation angle from A to B (continuous across neighbours), the
    /// stretch (symmetric, rows) and A's gradient in the triangle's frame.
    angle: Vec<f64>,
    stretch: Vec<[[f64; 2]; 2]>,
    gradient_a: Vec<[[f64; 2]; 2]>,
    wdx: Vec<[[f64; 2]; 3]>,
    index: Vec<u32>,
    chol: Option<Cholesky>,
    a: Vec<[f64; 2]>,
    b: Vec<[f64; 2]>,
}

impl std::fmt::Debug for ArapInterpolation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ArapInterpolation")
            .field("faces", &self.frames.len())
            .finish_non_exhaustive()
    }
}

fn mul(p: [[f64; 2]; 2], q: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
    [
        [
            p[0][0] * q[0][0] + p[0][1] * q[1][0],
            p[0][0] * q[0][1] + p[0][1] * q[1][1],
        ],
        [
            p[1][0] * q[0][0] + p[1][1] * q[1][0],
            p[1][0] * q[0][1] + p[1][1] * q[1][1],
        ],
    ]
}

fn inverse(m: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    [
        [m[1][1] / det, -m[0][1] / det],
        [-m[1][0] / det, m[0][0] / det],
    ]
}

fn rotation(theta: f64) -> [[f64; 2]; 2] {
    let (s, c) = theta.sin_cos();
    [[c, -s], [s, c]]
}

impl ArapInterpolation {
    /// Prepares the interpolation from `a` (a valid planar mesh) to the layout `b` of its
    /// triangles.
    ///
    /// # Errors
    /// [`InbetweenError::Mesh`] for a mesh without triangles, a face naming a vertex out of
    /// range, or a non-finite coordinate of `a` or `b` ([`crate::MeshError::NonFinite`]);
    /// [`InbetweenError::Internal`] for a degenerate triangle, a layout of the wrong length,
    /// a failed factorisation.
    pub fn new(a: &PlanarMesh, b: &[[f64; 2]]) -> Result<ArapInterpolation, InbetweenError> {
        let n = a.positions.len();
        if b.len() != n {
            return Err(InbetweenError::Internal(format!(
                "{} positions for {n} vertices",
                b.len()
            )));
        }
        if a.faces.is_empty() {
            return Err(crate::MeshError::NoTriangles.into());
        }
        for (face, f) in a.faces.iter().enumerate() {
            if let Some(&vertex) = f.iter().find(|&&v| v as usize >= n) {
                return Err(crate::MeshError::IndexOutOfRange {
                    face,
                    vertex,
                    n_vertices: n,
                }
                .into());
            }
        }
        if let Some(vertex) = a
            .positions
            .iter()
            .chain(b)
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(crate::MeshError::NonFinite { vertex: vertex % n }.into());
        }
        let frames = Frames::new(&SurfaceMesh::from(a)).map_err(|f| {
            InbetweenError::Internal(format!("triangle {f} of drawing A is degenerate"))
        })?;
        let faces = &a.faces;
        let m = faces.len();
        let mut raw = vec![0.0; m];
        let mut stretch = vec![[[1.0, 0.0], [0.0, 1.0]]; m];
        let mut gradient_a = vec![[[1.0, 0.0], [0.0, 1.0]]; m];
        for f in 0..m {
            let ga = frames.gradient(f, &a.positions);
            let gb = frames.gradient(f, b);
            let map = mul(gb, inverse(ga));
            let theta = (map[1][0] - map[0][1]).atan2(map[0][0] + map[1][1]);
            if !theta.is_finite() {
                return Err(InbetweenError::Internal(format!(
                    "triangle {f}: its map from A to B is not finite"
                )));
            }
            raw[f] = theta;
            stretch[f] = mul(rotation(-theta), map);
            gradient_a[f] = ga;
        }
        // Angles made continuous across neighbours, from each piece's first triangle.
        let mut by_edge: std::collections::HashMap<(u32, u32), Vec<usize>> =
            std::collections::HashMap::new();
        for (f, t) in faces.iter().enumerate() {
            for k in 0..3 {
                let (i, j) = (t[k], t[(k + 1) % 3]);
                by_edge.entry((i.min(j), i.max(j))).or_default().push(f);
            }
        }
        let mut angle = vec![f64::NAN; m];
        for start in 0..m {
            if !angle[start].is_nan() {
                continue;
            }
            angle[start] = raw[start];
            let mut queue = VecDeque::from([start]);
            while let Some(f) = queue.pop_front() {
                let t = faces[f];
                for k in 0..3 {
                    let (i, j) = (t[k], t[(k + 1) % 3]);
                    for &g in &by_edge[&(i.min(j), i.max(j))] {
                        if angle[g].is_nan() {
                            let turns = ((angle[f] - raw[g]) / std::f64::consts::TAU).round();
                            angle[g] = raw[g] + turns * std::f64::consts::TAU;
                            queue.push_back(g);
                        }
                    }
                }
            }
        }
        // One vertex per piece held: the lowest of each piece.
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(parent: &mut [u32], v: u32) -> u32 {
            let mut r = v;
            while parent[r as usize] != r {
                r = parent[r as usize];
            }
            let mut v = v;
            while parent[v as usize] != r {
                let next = parent[v as usize];
                parent[v as usize] = r;
                v = next;
            }
            r
        }
        for t in faces {
            for k in 1..3 {
                let (x, y) = (find(&mut parent, t[0]), find(&mut parent, t[k]));
                if x != y {
                    parent[x.max(y) as usize] = x.min(y);
                }
            }
        }
        let mut used = vec![false; n];
        for t in faces {
            for &v in t {
                used[v as usize] = true;
            }
        }
        let mut held: Vec<u32> = (0..n as u32)
            .filter(|&v| used[v as usize] && find(&mut parent, v) == v)
            .collect();
        held.extend((0..n as u32).filter(|&v| !used[v as usize]));
        let mut index = vec![NONE; n];
        let mut k = 0u32;
        for (v, slot) in index.iter_mut().enumerate() {
            if !held.contains(&(v as u32)) {
                *slot = k;
                k += 1;
            }
        }
        let chol = if k > 0 {
            Some(
                free_laplacian(&frames, None, &index, k)
                    .map_err(|e| InbetweenError::Internal(e.to_string()))?,
            )
        } else {
            None
        };
        Ok(ArapInterpolation {
            wdx: weighted_edges(&frames, None),
            frames,
            angle,
            stretch,
            gradient_a,
            index,
            chol,
            a: a.positions.clone(),
            b: b.to_vec(),
        })
    }

    /// The layout at `t` (0: A's, 1: B's up to the least-squares fit).
    ///
    /// # Errors
    /// [`InbetweenError::BadOption`] for a `t` that is not finite; [`InbetweenError::Internal`]
    /// when the solve fails.
    pub fn frame(&mut self, t: f64) -> Result<Vec<[f64; 2]>, InbetweenError> {
        if !t.is_finite() {
            return Err(InbetweenError::BadOption(format!(
                "t = {t}: give a finite number"
            )));
        }
        let mut uv = linear_frame(&self.a, &self.b, t);
        let Some(chol) = self.chol.as_mut() else {
            return Ok(uv);
        };
        let l: Vec<[[f64; 2]; 2]> = (0..self.frames.len())
            .map(|f| {
                let s = self.stretch[f];
                let blend = [
                    [1.0 - t + t * s[0][0], t * s[0][1]],
                    [t * s[1][0], 1.0 - t + t * s[1][1]],
                ];
                mul(mul(rotation(t * self.angle[f]), blend), self.gradient_a[f])
            })
            .collect();
        let k = self.index.iter().filter(|&&i| i != NONE).count();
        let mut rhs = vec![0.0; 2 * k];
        global_rhs(
            &self.frames,
            None,
            &l,
            &self.wdx,
            &self.index,
            &uv,
            &mut rhs,
        );
        chol.solve_in_place(&mut rhs, 2)
            .map_err(|e| InbetweenError::Internal(e.to_string()))?;
        for (v, out) in uv.iter_mut().enumerate() {
            let i = self.index[v];
            if i != NONE {
                *out = [rhs[i as usize], rhs[k + i as usize]];
            }
        }
        Ok(uv)
    }
}
