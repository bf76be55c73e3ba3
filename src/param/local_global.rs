//! Local/global ARAP and ASAP (Liu, Zhang, Xu, Gotsman, Gortler 2008).
//!
//! Local step: for each triangle, the best rotation (ARAP) or similarity (ASAP) `L` taking
//! its isometric layout to the current map, in the cotangent-weighted least-squares sense.
//! In 2D both are closed forms: with `S = Σ w (u_i − u_j)(x_i − x_j)ᵀ` over the triangle's
//! edges, the best similarity is `S`'s similarity part `[[p, −q], [q, p]]` with
//! `(p, q) = ((S₀₀ + S₁₁), (S₁₀ − S₀₁)) / Σ w |x_i − x_j|²`, and the closest rotation is its
//! normalisation — the `U Vᵀ` of `S`'s signed SVD, which is always a rotation (the reflection
//! case needs no special handling: a reflection is never returned).
//!
//! Global step: the map minimising `Σ w |(u_i − u_j) − L (x_i − x_j)|²`, a Poisson problem
//! with the cotan Laplacian (one vertex pinned), factored once; each iteration is one solve
//! with two right-hand sides.

// Small fixed-size matrix algebra reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use bdmorph_cholesky::Cholesky;

use super::frames::Frames;
use super::ParamError;

const NONE: u32 = u32::MAX;

/// Rotations or similarities.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Fit {
    Rotation,
    Similarity,
}

/// The factored global step.
pub(crate) struct LocalGlobal {
    fit: Fit,
    index: Vec<u32>,
    pinned: u32,
    chol: Cholesky,
    rhs: Vec<f64>,
    /// Per triangle, the fitted `L` (rows).
    l: Vec<[[f64; 2]; 2]>,
}

impl LocalGlobal {
    /// Factors the cotan Laplacian with vertex `pinned` removed.
    pub fn new(
        frames: &Frames,
        n: usize,
        pinned: u32,
        fit: Fit,
    ) -> Result<LocalGlobal, ParamError> {
        let err = |source| ParamError::Solver {
            what: "ARAP global step",
            source,
        };
        let mut index = vec![NONE; n];
        let mut k = 0u32;
        for (v, slot) in index.iter_mut().enumerate() {
            if v as u32 != pinned {
                *slot = k;
                k += 1;
            }
        }
        let mut pairs: Vec<(u32, u32)> = (0..k).map(|i| (i, i)).collect();
        let mut vals: Vec<f64> = vec![0.0; k as usize];
        for (f, &[a, b, c]) in frames.faces.iter().enumerate() {
            for (corner, (i, j)) in [(b, c), (c, a), (a, b)].into_iter().enumerate() {
                let w = frames.cot[f][corner];
                let (ii, jj) = (index[i as usize], index[j as usize]);
                if ii != NONE {
                    pairs.push((ii, ii));
                    vals.push(w);
                }
                if jj != NONE {
                    pairs.push((jj, jj));
                    vals.push(w);
                }
                if ii != NONE && jj != NONE {
                    pairs.push((ii.max(jj), ii.min(jj)));
                    vals.push(-w);
                }
            }
        }
        let chol = Cholesky::assemble(k as usize, &pairs, &vals, 2).map_err(err)?;
        Ok(LocalGlobal {
            fit,
            index,
            pinned,
            chol,
            rhs: vec![0.0; 2 * k as usize],
            l: vec![[[1.0, 0.0], [0.0, 1.0]]; frames.len()],
        })
    }

    /// One local step and one global step, in place.
    pub fn iterate(&mut self, frames: &Frames, uv: &mut [[f64; 2]]) -> Result<(), ParamError> {
        // Local.
        for (f, &[a, b, c]) in frames.faces.iter().enumerate() {
            let x = frames.local[f];
            let (mut p, mut q, mut norm) = (0.0, 0.0, 0.0);
            for (corner, (i, j)) in [(1usize, 2usize), (2, 0), (0, 1)].into_iter().enumerate() {
                let w = frames.cot[f][corner];
                let vs = [a, b, c];
                let du = [
                    uv[vs[i] as usize][0] - uv[vs[j] as usize][0],
                    uv[vs[i] as usize][1] - uv[vs[j] as usize][1],
                ];
                let dx = [x[i][0] - x[j][0], x[i][1] - x[j][1]];
                p += w * (du[0] * dx[0] + du[1] * dx[1]);
                q += w * (du[1] * dx[0] - du[0] * dx[1]);
                norm += w * (dx[0] * dx[0] + dx[1] * dx[1]);
            }
            let (p, q) = match self.fit {
                Fit::Rotation => {
                    let r = p.hypot(q);
                    if r > 0.0 {
                        (p / r, q / r)
                    } else {
                        (1.0, 0.0)
                    }
                }
                Fit::Similarity => (p / norm, q / norm),
            };
            self.l[f] = [[p, -q], [q, p]];
        }
        // Global: Σ_j w_ij (u_i - u_j) = Σ w_ij L (x_i - x_j), the pinned vertex moved right.
        let k = self.rhs.len() / 2;
        self.rhs.fill(0.0);
        let pin = uv[self.pinned as usize];
        for (f, &[a, b, c]) in frames.faces.iter().enumerate() {
            let x = frames.local[f];
            let l = self.l[f];
            let vs = [a, b, c];
            for (corner, (i, j)) in [(1usize, 2usize), (2, 0), (0, 1)].into_iter().enumerate() {
                let w = frames.cot[f][corner];
                let dx = [x[i][0] - x[j][0], x[i][1] - x[j][1]];
                let ldx = [
                    l[0][0] * dx[0] + l[0][1] * dx[1],
                    l[1][0] * dx[0] + l[1][1] * dx[1],
                ];
                for (v, other, sign) in [(vs[i], vs[j], 1.0), (vs[j], vs[i], -1.0)] {
                    let iv = self.index[v as usize];
                    if iv == NONE {
                        continue;
                    }
                    for d in 0..2 {
                        self.rhs[d * k + iv as usize] += sign * w * ldx[d];
                    }
                    if other == self.pinned {
                        for d in 0..2 {
                            self.rhs[d * k + iv as usize] += w * pin[d];
                        }
                    }
                }
            }
        }
        self.chol
            .solve_in_place(&mut self.rhs, 2)
            .map_err(|source| ParamError::Solver {
                what: "ARAP global step",
                source,
            })?;
        for (v, out) in uv.iter_mut().enumerate() {
            let i = self.index[v];
            if i != NONE {
                *out = [self.rhs[i as usize], self.rhs[k + i as usize]];
            }
        }
        Ok(())
    }
}
