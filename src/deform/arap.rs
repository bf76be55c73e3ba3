//! As-rigid-as-possible posing with hard pins: 2D local/global iterations on a prefactored
//! cotangent Laplacian of the free vertices.
//!
//! Local step: each triangle's closest rotation `R` to its deformation gradient (the
//! cotangent-weighted fit of its edges, in closed form in 2D). Global step: the free vertices
//! minimising `Σ w_ij |(u_i − u_j) − R (x_i − x_j)|²` with the pinned ones at their targets, a
//! solve with two right-hand sides. The energy never rises from one iteration to the next
//! (each step minimises it over its own variables), and a rigid motion of every pin is
//! reproduced exactly: rotating every triangle by one rotation is then the minimum.

// Small fixed-size matrix algebra reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use bdmorph_cholesky::Cholesky;

use super::{DeformError, DragReport};
use crate::param::frames::Frames;

const NONE: u32 = u32::MAX;

/// Options of [`super::Method::Arap`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct ArapOptions {
    /// Local/global iterations per drag at most (default 10): each drag starts from the
    /// previous pose, so a slow drag converges over a few mouse moves.
    pub iterations: u32,
    /// A drag stops early once no vertex moved by more than this times the mesh's size in
    /// an iteration (default `1e-12`).
    pub tolerance: f64,
}

impl Default for ArapOptions {
    fn default() -> Self {
        ArapOptions {
            iterations: 10,
            tolerance: 1e-12,
        }
    }
}

impl ArapOptions {
    /// Sets the most iterations per drag.
    pub fn with_iterations(mut self, iterations: u32) -> Self {
        self.iterations = iterations;
        self
    }
    /// Sets the early-stopping tolerance.
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }
}

/// The method's state.
pub(crate) struct Arap {
    options: ArapOptions,
    /// Per vertex, its row among the free vertices, or [`NONE`] when pinned.
    index: Vec<u32>,
    pins: Vec<u32>,
    chol: Option<Cholesky>,
    rhs: Vec<f64>,
    /// Per triangle, its fitted rotation (rows).
    l: Vec<[[f64; 2]; 2]>,
    /// Per triangle and edge `(b, c), (c, a), (a, b)`: its cotangent weight times its vector
    /// in the triangle's rest layout.
    wdx: Vec<[[f64; 2]; 3]>,
}

impl Arap {
    pub(crate) fn new(frames: &Frames, n: usize, options: ArapOptions) -> Arap {
        let wdx = (0..frames.len())
            .map(|f| {
                let x = frames.local[f];
                let mut out = [[0.0; 2]; 3];
                for (corner, (i, j)) in [(1usize, 2usize), (2, 0), (0, 1)].into_iter().enumerate() {
                    let w = frames.cot[f][corner];
                    out[corner] = [w * (x[i][0] - x[j][0]), w * (x[i][1] - x[j][1])];
                }
                out
            })
            .collect();
        Arap {
            options,
            index: vec![NONE; n],
            pins: Vec::new(),
            chol: None,
            rhs: Vec::new(),
            l: vec![[[1.0, 0.0], [0.0, 1.0]]; frames.len()],
            wdx,
        }
    }

    /// Numbers the free vertices and factors their cotangent Laplacian.
    pub(crate) fn set_pins(&mut self, frames: &Frames, pins: &[u32]) -> Result<(), DeformError> {
        self.index.fill(NONE);
        let mut pinned = vec![false; self.index.len()];
        for &p in pins {
            pinned[p as usize] = true;
        }
        let mut k = 0u32;
        for (v, slot) in self.index.iter_mut().enumerate() {
            if !pinned[v] {
                *slot = k;
                k += 1;
            }
        }
        let mut pairs: Vec<(u32, u32)> = (0..k).map(|i| (i, i)).collect();
        let mut vals: Vec<f64> = vec![0.0; k as usize];
        for (f, &[a, b, c]) in frames.faces.iter().enumerate() {
            for (corner, (i, j)) in [(b, c), (c, a), (a, b)].into_iter().enumerate() {
                let w = frames.cot[f][corner];
                let (ii, jj) = (self.index[i as usize], self.index[j as usize]);
                for x in [ii, jj] {
                    if x != NONE {
                        pairs.push((x, x));
                        vals.push(w);
                    }
                }
                if ii != NONE && jj != NONE {
                    pairs.push((ii.max(jj), ii.min(jj)));
                    vals.push(-w);
                }
            }
        }
        self.chol = if k > 0 {
            Some(Cholesky::assemble(k as usize, &pairs, &vals, 2)?)
        } else {
            None
        };
        self.rhs = vec![0.0; 2 * k as usize];
        self.pins = pins.to_vec();
        Ok(())
    }

    /// The local step: each triangle's closest rotation; returns the ARAP energy of `uv`
    /// (area-weighted mean of `|J − R|²`).
    fn fit(&mut self, frames: &Frames, uv: &[[f64; 2]]) -> f64 {
        let mut energy = 0.0;
        for (f, l) in self.l.iter_mut().enumerate() {
            let [[a, b], [c, d]] = frames.gradient(f, uv);
            let (e, h) = (0.5 * (a + d), 0.5 * (c - b));
            let (fq, g) = (0.5 * (a - d), 0.5 * (c + b));
            let q = (e * e + h * h).sqrt();
            energy += frames.area[f] * (2.0 * (q - 1.0) * (q - 1.0) + 2.0 * (fq * fq + g * g));
            let (p, s) = if q > 0.0 { (e / q, h / q) } else { (1.0, 0.0) };
            *l = [[p, -s], [s, p]];
        }
        energy / frames.total_area
    }

    pub(crate) fn drag(
        &mut self,
        frames: &Frames,
        targets: &[[f64; 2]],
        uv: &mut [[f64; 2]],
        size: f64,
    ) -> Result<DragReport, DeformError> {
        if targets.len() != self.pins.len() || self.pins.is_empty() {
            return Err(DeformError::TargetCount {
                pins: self.pins.len(),
                got: targets.len(),
            });
        }
        if let Some(index) = targets
            .iter()
            .position(|t| !(t[0].is_finite() && t[1].is_finite()))
        {
            return Err(DeformError::NonFiniteTarget { index });
        }
        for (&p, &t) in self.pins.iter().zip(targets) {
            uv[p as usize] = t;
        }
        let k = self.rhs.len() / 2;
        let mut iterations = 0;
        let mut last_change = 0.0;
        while iterations < self.options.iterations.max(1) {
            iterations += 1;
            self.fit(frames, uv);
            let Some(chol) = self.chol.as_mut() else {
                break;
            };
            self.rhs.fill(0.0);
            for (f, &[a, b, c]) in frames.faces.iter().enumerate() {
                let l = self.l[f];
                let vs = [a, b, c];
                for (corner, (i, j)) in [(1usize, 2usize), (2, 0), (0, 1)].into_iter().enumerate() {
                    let wdx = self.wdx[f][corner];
                    let w = frames.cot[f][corner];
                    let ldx = [
                        l[0][0] * wdx[0] + l[0][1] * wdx[1],
                        l[1][0] * wdx[0] + l[1][1] * wdx[1],
                    ];
                    for (v, other, sign) in [(vs[i], vs[j], 1.0), (vs[j], vs[i], -1.0)] {
                        let iv = self.index[v as usize];
                        if iv == NONE {
                            continue;
                        }
                        let iv = iv as usize;
                        self.rhs[iv] += sign * ldx[0];
                        self.rhs[k + iv] += sign * ldx[1];
                        if self.index[other as usize] == NONE {
                            let pin = uv[other as usize];
                            self.rhs[iv] += w * pin[0];
                            self.rhs[k + iv] += w * pin[1];
                        }
                    }
                }
            }
            chol.solve_in_place(&mut self.rhs, 2)?;
            last_change = 0.0f64;
            for (v, out) in uv.iter_mut().enumerate() {
                let i = self.index[v];
                if i != NONE {
                    let new = [self.rhs[i as usize], self.rhs[k + i as usize]];
                    last_change = last_change.max((new[0] - out[0]).hypot(new[1] - out[1]));
                    *out = new;
                }
            }
            if last_change <= self.options.tolerance * size {
                break;
            }
        }
        let energy = self.fit(frames, uv);
        let pin_residual = self
            .pins
            .iter()
            .zip(targets)
            .map(|(&p, t)| (uv[p as usize][0] - t[0]).hypot(uv[p as usize][1] - t[1]))
            .fold(0.0, f64::max);
        Ok(DragReport {
            iterations,
            energy,
            last_change: last_change / size,
            flipped_triangles: 0,
            pin_residual,
        })
    }
}
