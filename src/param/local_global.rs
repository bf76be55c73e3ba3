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

/// Marks a pinned vertex in a row numbering.
pub(crate) const NONE: u32 = u32::MAX;

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
    chol: Cholesky,
    rhs: Vec<f64>,
    /// Per triangle, the fitted `L` (rows).
    l: Vec<[[f64; 2]; 2]>,
    /// Per triangle and edge `(b, c), (c, a), (a, b)`: its cotangent weight times its
    /// vector in the triangle's isometric layout.
    wdx: Vec<[[f64; 2]; 3]>,
    /// The energy of the map the fits in `l` were made for, when they are up to date.
    fitted: Option<f64>,
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
        let chol = free_laplacian(frames, None, &index, k).map_err(err)?;
        let wdx = weighted_edges(frames, None);
        Ok(LocalGlobal {
            fit,
            index,
            chol,
            rhs: vec![0.0; 2 * k as usize],
            l: vec![[[1.0, 0.0], [0.0, 1.0]]; frames.len()],
            wdx,
            fitted: None,
        })
    }

    /// The local step on `uv`: each triangle's best rotation or similarity, from its
    /// deformation gradient `J` (the cotangent-weighted fit of the edges is the same: for
    /// any triangle `Σ cot θₖ eₖ eₖᵀ = 2A I`, so the fit of `J`'s edges is `J`'s closest
    /// rotation or similarity); returns the method's energy of `uv` (ARAP
    /// `2 (q − 1)² + 2 r²` or ASAP `2 r²`, with `q`, `r` the norms of
    /// `J`'s similarity and anti-similarity parts), as an area-weighted mean.
    fn fit(&mut self, frames: &Frames, uv: &[[f64; 2]]) -> f64 {
        fit_each(frames, uv, self.fit, &mut self.l)
    }

    /// One local step and one global step, in place; the method's energy (ARAP or ASAP,
    /// see [`LocalGlobal::fit`]) before and after. The fits for the next iteration are made
    /// in the same pass that measures the energy after.
    pub fn iterate(
        &mut self,
        frames: &Frames,
        uv: &mut [[f64; 2]],
    ) -> Result<(f64, f64), ParamError> {
        let before = match self.fitted.take() {
            Some(e) => e,
            None => self.fit(frames, uv),
        };
        // Global: Σ_j w_ij (u_i - u_j) = Σ w_ij L (x_i - x_j), the pinned vertex moved right.
        let k = self.rhs.len() / 2;
        global_rhs(
            frames,
            None,
            &self.l,
            &self.wdx,
            &self.index,
            uv,
            &mut self.rhs,
        );
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
        let after = self.fit(frames, uv);
        self.fitted = Some(after);
        Ok((before, after))
    }
}

/// Triangle `f`'s factor in the energy: its entry of `stiffness`, 1 without one. Every
/// cotangent weight of the triangle is multiplied by it, which multiplies the triangle's
/// term `A_f |J_f − L_f|²` of the energy (a factor of exactly 1 changes no bit).
fn stiffness_of(stiffness: Option<&[f64]>, f: usize) -> f64 {
    stiffness.map_or(1.0, |s| s[f])
}

/// Per triangle and edge `(b, c), (c, a), (a, b)`: its cotangent weight (times the
/// triangle's stiffness, when given: one factor per triangle) times its vector in the
/// triangle's isometric layout.
pub(crate) fn weighted_edges(frames: &Frames, stiffness: Option<&[f64]>) -> Vec<[[f64; 2]; 3]> {
    (0..frames.len())
        .map(|f| {
            let x = frames.local[f];
            let s = stiffness_of(stiffness, f);
            let mut out = [[0.0; 2]; 3];
            for (corner, (i, j)) in [(1usize, 2usize), (2, 0), (0, 1)].into_iter().enumerate() {
                let w = frames.cot[f][corner] * s;
                out[corner] = [w * (x[i][0] - x[j][0]), w * (x[i][1] - x[j][1])];
            }
            out
        })
        .collect()
}

/// The cotangent Laplacian of the free vertices (`index[v]` their row, [`NONE`] for pinned
/// ones; `k` of them), each triangle's weights times its stiffness when given, factored for
/// solves with two right-hand sides.
pub(crate) fn free_laplacian(
    frames: &Frames,
    stiffness: Option<&[f64]>,
    index: &[u32],
    k: u32,
) -> Result<Cholesky, bdmorph_cholesky::CholeskyError> {
    free_laplacian_plus(frames, stiffness, index, k, &[])
}

/// As [`free_laplacian`], with `extra` `(row, value)` added to the diagonal (soft pins).
pub(crate) fn free_laplacian_plus(
    frames: &Frames,
    stiffness: Option<&[f64]>,
    index: &[u32],
    k: u32,
    extra: &[(u32, f64)],
) -> Result<Cholesky, bdmorph_cholesky::CholeskyError> {
    let mut pairs: Vec<(u32, u32)> = (0..k).map(|i| (i, i)).collect();
    let mut vals: Vec<f64> = vec![0.0; k as usize];
    for &(row, value) in extra {
        vals[row as usize] += value;
    }
    for (f, &[a, b, c]) in frames.faces.iter().enumerate() {
        let s = stiffness_of(stiffness, f);
        for (corner, (i, j)) in [(b, c), (c, a), (a, b)].into_iter().enumerate() {
            let w = frames.cot[f][corner] * s;
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
    Cholesky::assemble(k as usize, &pairs, &vals, 2)
}

/// The local step on `uv`: each triangle's best rotation or similarity into `l`, from its
/// deformation gradient `J` (the cotangent-weighted fit of the edges is the same: for any
/// triangle `Σ cot θₖ eₖ eₖᵀ = 2A I`, so the fit of `J`'s edges is `J`'s closest rotation or
/// similarity); returns the method's energy of `uv` (ARAP `2 (q − 1)² + 2 r²` or ASAP
/// `2 r²`, with `q`, `r` the norms of `J`'s similarity and anti-similarity parts), as an
/// area-weighted mean.
pub(crate) fn fit_each(frames: &Frames, uv: &[[f64; 2]], fit: Fit, l: &mut [[[f64; 2]; 2]]) -> f64 {
    let mut energy = 0.0;
    for (f, l) in l.iter_mut().enumerate() {
        let [[a, b], [c, d]] = frames.gradient(f, uv);
        let (e, h) = (0.5 * (a + d), 0.5 * (c - b));
        let (fq, g) = (0.5 * (a - d), 0.5 * (c + b));
        let (q2, r2) = (e * e + h * h, fq * fq + g * g);
        let q = q2.sqrt();
        let psi = match fit {
            Fit::Rotation => 2.0 * (q - 1.0) * (q - 1.0) + 2.0 * r2,
            // |J - S|² for the nearest similarity S: the anti-conformal part.
            Fit::Similarity => 2.0 * r2,
        };
        energy += frames.area[f] * psi;
        let (p, s) = match fit {
            Fit::Rotation if q > 0.0 => (e / q, h / q),
            Fit::Rotation => (1.0, 0.0),
            Fit::Similarity => (e, h),
        };
        *l = [[p, -s], [s, p]];
    }
    energy / frames.total_area
}

/// The global step's right-hand sides (x then y, one row per free vertex):
/// `Σ w_ij L (x_i − x_j)` plus, for each pinned neighbour `j`, `w_ij u_j`; `wdx` from
/// [`weighted_edges`] with the same `stiffness`.
pub(crate) fn global_rhs(
    frames: &Frames,
    stiffness: Option<&[f64]>,
    l: &[[[f64; 2]; 2]],
    wdx: &[[[f64; 2]; 3]],
    index: &[u32],
    uv: &[[f64; 2]],
    rhs: &mut [f64],
) {
    let k = rhs.len() / 2;
    rhs.fill(0.0);
    for (f, &[a, b, c]) in frames.faces.iter().enumerate() {
        let l = l[f];
        let vs = [a, b, c];
        let s = stiffness_of(stiffness, f);
        for (corner, (i, j)) in [(1usize, 2usize), (2, 0), (0, 1)].into_iter().enumerate() {
            let wdx = wdx[f][corner];
            let w = frames.cot[f][corner] * s;
            let ldx = [
                l[0][0] * wdx[0] + l[0][1] * wdx[1],
                l[1][0] * wdx[0] + l[1][1] * wdx[1],
            ];
            for (v, other, sign) in [(vs[i], vs[j], 1.0), (vs[j], vs[i], -1.0)] {
                let iv = index[v as usize];
                if iv == NONE {
                    continue;
                }
                let iv = iv as usize;
                rhs[iv] += sign * ldx[0];
                rhs[k + iv] += sign * ldx[1];
                if index[other as usize] == NONE {
                    let pin = uv[other as usize];
                    rhs[iv] += w * pin[0];
                    rhs[k + iv] += w * pin[1];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::SurfaceMesh;
    use crate::param::energy::Energy;
    use crate::param::newton::mean_energy;

    /// The fits from each triangle's `J` are the cotangent-weighted fits of its edges (the
    /// definition of the local step), and the energies they report are the methods' own.
    #[test]
    fn fits_from_the_jacobian_are_the_cotangent_weighted_edge_fits() {
        let d = crate::generate::disk(4, 0.3);
        let mesh = SurfaceMesh {
            positions: d
                .positions
                .iter()
                .map(|p| [p[0], p[1], 0.4 * p[0] * p[1] + 0.2 * p[0]])
                .collect(),
            faces: d.faces.clone(),
            texcoords: None,
        };
        let frames = Frames::new(&mesh).expect("frames");
        // A map with rotation, shear and, near one side, inverted triangles.
        let uv: Vec<[f64; 2]> = d
            .positions
            .iter()
            .map(|p| {
                [
                    0.8 * p[0] + 0.3 * p[1],
                    -0.2 * p[0] + 1.1 * p[1] - 0.9 * p[0] * p[0],
                ]
            })
            .collect();
        let n = uv.len();
        for (fit, energy) in [
            (Fit::Rotation, Energy::Arap),
            (Fit::Similarity, Energy::Asap),
        ] {
            let mut lg = LocalGlobal::new(&frames, n, 0, fit).expect("set up");
            let e = lg.fit(&frames, &uv);
            let reference = mean_energy(energy, &frames, &uv);
            assert!(
                e == reference || (e - reference).abs() < 1e-12 * reference.abs(),
                "{fit:?}: {e} vs {reference}"
            );
            for (f, &[a, b, c]) in frames.faces.iter().enumerate() {
                let x = frames.local[f];
                let vs = [a, b, c];
                let (mut p, mut q, mut norm) = (0.0, 0.0, 0.0);
                for (corner, (i, j)) in [(1usize, 2usize), (2, 0), (0, 1)].into_iter().enumerate() {
                    let w = frames.cot[f][corner];
                    let du = [
                        uv[vs[i] as usize][0] - uv[vs[j] as usize][0],
                        uv[vs[i] as usize][1] - uv[vs[j] as usize][1],
                    ];
                    let dx = [x[i][0] - x[j][0], x[i][1] - x[j][1]];
                    p += w * (du[0] * dx[0] + du[1] * dx[1]);
                    q += w * (du[1] * dx[0] - du[0] * dx[1]);
                    norm += w * (dx[0] * dx[0] + dx[1] * dx[1]);
                }
                let (p, q) = match fit {
                    Fit::Rotation => (p / p.hypot(q), q / p.hypot(q)),
                    Fit::Similarity => (p / norm, q / norm),
                };
                let l = lg.l[f];
                assert!(
                    (l[0][0] - p).abs() < 1e-12 && (l[1][0] - q).abs() < 1e-12,
                    "{fit:?} face {f}: {l:?} vs ({p}, {q})"
                );
            }
        }
    }
}
