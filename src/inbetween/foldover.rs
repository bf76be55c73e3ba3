//! Foldover-free maps (Garanzha, Kaporin, Kudryavtseva, Protais, Ray, Sokolov, *Foldover-free
//! maps in 50 lines of code*, SIGGRAPH 2021): a layout with flipped triangles untangled, with
//! chosen vertices held, by minimising a regularised distortion energy for a decreasing
//! regularisation.
//!
//! Each triangle's Jacobian `J` is taken from its rest shape (drawing A's triangle, scaled so
//! that the rest's area is the layout's) to the layout. With `D = det J` and
//! `χ(D, ε) = (D + √(ε² + D²)) / 2` (positive for every `D` while `ε > 0`, tending to
//! `max(D, 0)` as `ε → 0`), the energy of a triangle is
//!
//! ```text
//! f_ε(J) = (1 − θ) tr(JᵀJ) / χ(D, ε) + θ (D² + 1) / χ(D, ε)
//! ```
//!
//! (shape and area terms, `θ` = [`THETA`]) times its rest area and its weight. For `ε > 0` it
//! is finite and smooth everywhere, so a plain quasi-Newton method (L-BFGS here) lowers it
//! from any start, flipped triangles included; as `ε` falls (the paper's rule, from the
//! smallest determinant and the energy's decrease) it becomes a barrier against `D ≤ 0`. The
//! minimiser of the limit has no flipped triangle whenever a flip-free layout of the mesh
//! with the held vertices exists and the iterations reach it; this is the fast first try,
//! not the guarantee (see `super::embed` for that).
//!
//! Once a layout is flip-free, [`smooth`] lowers the same energy with `ε` tiny and a line
//! search that never lets a triangle fold, so the layout stays valid while its distortion
//! falls; triangles can be given small weights (regions meant to shrink, such as a hole of
//! one drawing that the other lacks).

/// The weight of the area term against the shape term (the paper's value).
pub(crate) const THETA: f64 = 1.0 / 128.0;
/// L-BFGS memory.
const MEMORY: usize = 8;

/// What the untangling did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FoldoverReport {
    /// Triangles whose signed area is at most the validity threshold afterwards.
    pub bad_after: usize,
    /// L-BFGS iterations, all rounds together.
    pub iterations: usize,
}

/// The per-triangle constants: the rest shape's inverse edge matrix and area.
pub(crate) struct Rest {
    faces: Vec<[u32; 3]>,
    /// `M = E_A⁻¹` (rows), scaled so that `J = E_B M`.
    inverse: Vec<[[f64; 2]; 2]>,
    /// Rest area times the triangle's weight.
    weight: Vec<f64>,
    /// Faces with a free vertex.
    active: Vec<u32>,
    /// Per vertex, whether it moves.
    free: Vec<bool>,
}

impl Rest {
    /// The constants of `faces` over the rest positions `rest`, scaled so that the rest's
    /// total area equals the layout's (`layout_area`), each triangle weighted by `weights`
    /// (or 1), with the vertices `fixed` held.
    pub fn new(
        rest: &[[f64; 2]],
        faces: &[[u32; 3]],
        weights: Option<&[f64]>,
        fixed: &[bool],
        layout_area: f64,
    ) -> Rest {
        let rest_area: f64 = faces.iter().map(|f| signed_area(rest, f)).sum();
        let scale = if rest_area > 0.0 && layout_area > 0.0 {
            (layout_area / rest_area).sqrt()
        } else {
            1.0
        };
        let mut inverse = Vec::with_capacity(faces.len());
        let mut weight = Vec::with_capacity(faces.len());
        for (k, f) in faces.iter().enumerate() {
            let [a, b, c] = f.map(|v| rest[v as usize]);
            let e = [
                [scale * (b[0] - a[0]), scale * (c[0] - a[0])],
                [scale * (b[1] - a[1]), scale * (c[1] - a[1])],
            ];
            let det = e[0][0] * e[1][1] - e[0][1] * e[1][0];
            let inv = if det.abs() > 0.0 {
                [
                    [e[1][1] / det, -e[0][1] / det],
                    [-e[1][0] / det, e[0][0] / det],
                ]
            } else {
                [[0.0; 2]; 2]
            };
            inverse.push(inv);
            let w = weights.map_or(1.0, |w| w[k]);
            weight.push(0.5 * det.abs() * w);
        }
        let free: Vec<bool> = fixed.iter().map(|&x| !x).collect();
        let active = faces
            .iter()
            .enumerate()
            .filter(|(_, f)| f.iter().any(|&v| free[v as usize]))
            .map(|(k, _)| k as u32)
            .collect();
        Rest {
            faces: faces.to_vec(),
            inverse,
            weight,
            active,
            free,
        }
    }

    /// `J = E_B M` of face `k` at `x`.
    fn jacobian(&self, k: usize, x: &[[f64; 2]]) -> [[f64; 2]; 2] {
        let [a, b, c] = self.faces[k].map(|v| x[v as usize]);
        let e = [[b[0] - a[0], c[0] - a[0]], [b[1] - a[1], c[1] - a[1]]];
        let m = &self.inverse[k];
        [
            [
                e[0][0] * m[0][0] + e[0][1] * m[1][0],
                e[0][0] * m[0][1] + e[0][1] * m[1][1],
            ],
            [
                e[1][0] * m[0][0] + e[1][1] * m[1][0],
                e[1][0] * m[0][1] + e[1][1] * m[1][1],
            ],
        ]
    }

    /// The smallest determinant over the faces that move, and the energy at `eps`.
    fn min_det(&self, x: &[[f64; 2]]) -> f64 {
        self.active
            .iter()
            .map(|&k| {
                let j = self.jacobian(k as usize, x);
                j[0][0] * j[1][1] - j[0][1] * j[1][0]
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The energy at `x` for `eps`, and its gradient into `grad` when given.
    fn energy(&self, x: &[[f64; 2]], eps: f64, mut grad: Option<&mut [[f64; 2]]>) -> f64 {
        if let Some(g) = grad.as_deref_mut() {
            g.fill([0.0; 2]);
        }
        let mut total = 0.0;
        for &k in &self.active {
            let k = k as usize;
            let j = self.jacobian(k, x);
            let d = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            let tr = j[0][0] * j[0][0] + j[0][1] * j[0][1] + j[1][0] * j[1][0] + j[1][1] * j[1][1];
            let c = chi(d, eps);
            let dc = chi_slope(d, eps);
            let w = self.weight[k];
            total += w * ((1.0 - THETA) * tr / c + THETA * (d * d + 1.0) / c);
            let Some(g) = grad.as_deref_mut() else {
                continue;
            };
            // ∂f/∂J = (1 − θ)(2J/χ − tr χ'/χ² cof J) + θ (2D/χ − (D² + 1) χ'/χ²) cof J.
            let cof = [[j[1][1], -j[1][0]], [-j[0][1], j[0][0]]];
            let s = (1.0 - THETA) * (-tr * dc / (c * c))
                + THETA * (2.0 * d / c - (d * d + 1.0) * dc / (c * c));
            let a = (1.0 - THETA) * 2.0 / c;
            let gj = [
                [
                    w * (a * j[0][0] + s * cof[0][0]),
                    w * (a * j[0][1] + s * cof[0][1]),
                ],
                [
                    w * (a * j[1][0] + s * cof[1][0]),
                    w * (a * j[1][1] + s * cof[1][1]),
                ],
            ];
            // J = E_B M: ∂f/∂E_B = (∂f/∂J) Mᵀ; columns are the edges b − a and c − a.
            let m = &self.inverse[k];
            let ge = [
                [
                    gj[0][0] * m[0][0] + gj[0][1] * m[0][1],
                    gj[0][0] * m[1][0] + gj[0][1] * m[1][1],
                ],
                [
                    gj[1][0] * m[0][0] + gj[1][1] * m[0][1],
                    gj[1][0] * m[1][0] + gj[1][1] * m[1][1],
                ],
            ];
            let [va, vb, vc] = self.faces[k].map(|v| v as usize);
            let gb = [ge[0][0], ge[1][0]];
            let gc = [ge[0][1], ge[1][1]];
            for (v, gv) in [(vb, gb), (vc, gc), (va, [-gb[0] - gc[0], -gb[1] - gc[1]])] {
                if self.free[v] {
                    g[v][0] += gv[0];
                    g[v][1] += gv[1];
                }
            }
        }
        total
    }

    /// Faces whose layout area is at most `min_area` (flipped or degenerate).
    fn bad(&self, x: &[[f64; 2]], min_area: f64) -> usize {
        self.faces
            .iter()
            .filter(|f| signed_area(x, f) <= min_area)
            .count()
    }

    /// Whether no face with a free vertex has a layout area at most `min_area`.
    fn valid(&self, x: &[[f64; 2]], min_area: f64) -> bool {
        self.active
            .iter()
            .all(|&k| signed_area(x, &self.faces[k as usize]) > min_area)
    }
}

/// `χ(D, ε) = (D + √(ε² + D²)) / 2`, written for negative `D` so that it does not cancel.
fn chi(d: f64, eps: f64) -> f64 {
    let r = (eps * eps + d * d).sqrt();
    if d >= 0.0 {
        0.5 * (d + r)
    } else {
        0.5 * eps * eps / (r - d)
    }
}

/// `χ'(D, ε)`.
fn chi_slope(d: f64, eps: f64) -> f64 {
    0.5 + 0.5 * d / (eps * eps + d * d).sqrt()
}

pub(crate) fn signed_area(p: &[[f64; 2]], f: &[u32; 3]) -> f64 {
    let (a, b, c) = (p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]);
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
}

/// L-BFGS on `rest`'s energy at `eps` from `x`, at most `iterations` steps, until the
/// gradient is `tolerance` of its first size. With `keep_valid`, a step that makes a moving
/// face's area at most `min_area` is refused (halved). Returns the steps taken.
fn lbfgs(
    rest: &Rest,
    x: &mut [[f64; 2]],
    eps: f64,
    iterations: usize,
    tolerance: f64,
    keep_valid: Option<f64>,
) -> usize {
    let n = x.len();
    let mut g = vec![[0.0; 2]; n];
    let mut e = rest.energy(x, eps, Some(&mut g));
    let norm = |v: &[[f64; 2]]| {
        v.iter()
            .map(|p| p[0] * p[0] + p[1] * p[1])
            .sum::<f64>()
            .sqrt()
    };
    let g0 = norm(&g).max(f64::MIN_POSITIVE);
    let mut s_hist: Vec<Vec<[f64; 2]>> = Vec::with_capacity(MEMORY);
    let mut y_hist: Vec<Vec<[f64; 2]>> = Vec::with_capacity(MEMORY);
    let mut trial = x.to_vec();
    let mut g_new = vec![[0.0; 2]; n];
    let mut d = vec![[0.0; 2]; n];
    let dot = |a: &[[f64; 2]], b: &[[f64; 2]]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| p[0] * q[0] + p[1] * q[1])
            .sum::<f64>()
    };
    let mut taken = 0;
    for _ in 0..iterations {
        if norm(&g) <= tolerance * g0 || !e.is_finite() {
            break;
        }
        // Two-loop recursion: d = −H g.
        d.copy_from_slice(&g);
        let m = s_hist.len();
        let mut alpha = vec![0.0; m];
        for i in (0..m).rev() {
            let rho = 1.0 / dot(&y_hist[i], &s_hist[i]);
            alpha[i] = rho * dot(&s_hist[i], &d);
            for (p, q) in d.iter_mut().zip(&y_hist[i]) {
                p[0] -= alpha[i] * q[0];
                p[1] -= alpha[i] * q[1];
            }
        }
        if let (Some(s), Some(y)) = (s_hist.last(), y_hist.last()) {
            let gamma = dot(s, y) / dot(y, y);
            for p in d.iter_mut() {
                p[0] *= gamma;
                p[1] *= gamma;
            }
        } else {
            // The first step: a small move along the gradient.
            let scale = 1e-3 * x_size(x) / norm(&g).max(f64::MIN_POSITIVE);
            for p in d.iter_mut() {
                p[0] *= scale;
                p[1] *= scale;
            }
        }
        for i in 0..m {
            let rho = 1.0 / dot(&y_hist[i], &s_hist[i]);
            let beta = rho * dot(&y_hist[i], &d);
            for (p, q) in d.iter_mut().zip(&s_hist[i]) {
                p[0] += (alpha[i] - beta) * q[0];
                p[1] += (alpha[i] - beta) * q[1];
            }
        }
        for p in d.iter_mut() {
            p[0] = -p[0];
            p[1] = -p[1];
        }
        let mut slope = dot(&g, &d);
        if slope >= 0.0 || slope.is_nan() {
            // Not a descent direction: restart from the gradient.
            s_hist.clear();
            y_hist.clear();
            let scale = 1e-3 * x_size(x) / norm(&g).max(f64::MIN_POSITIVE);
            for (p, q) in d.iter_mut().zip(&g) {
                *p = [-scale * q[0], -scale * q[1]];
            }
            slope = dot(&g, &d);
        }
        // Backtracking (Armijo).
        let mut step = 1.0;
        let mut accepted = false;
        for _ in 0..40 {
            for ((t, p), q) in trial.iter_mut().zip(x.iter()).zip(&d) {
                *t = [p[0] + step * q[0], p[1] + step * q[1]];
            }
            let ok = keep_valid.is_none_or(|min_area| rest.valid(&trial, min_area));
            if ok {
                let e_new = rest.energy(&trial, eps, Some(&mut g_new));
                if e_new.is_finite() && e_new <= e + 1e-4 * step * slope {
                    let s: Vec<[f64; 2]> = trial
                        .iter()
                        .zip(x.iter())
                        .map(|(t, p)| [t[0] - p[0], t[1] - p[1]])
                        .collect();
                    let y: Vec<[f64; 2]> = g_new
                        .iter()
                        .zip(&g)
                        .map(|(a, b)| [a[0] - b[0], a[1] - b[1]])
                        .collect();
                    if dot(&s, &y) > 1e-16 * dot(&s, &s).sqrt() * dot(&y, &y).sqrt() {
                        if s_hist.len() == MEMORY {
                            s_hist.remove(0);
                            y_hist.remove(0);
                        }
                        s_hist.push(s);
                        y_hist.push(y);
                    }
                    x.copy_from_slice(&trial);
                    g.copy_from_slice(&g_new);
                    e = e_new;
                    accepted = true;
                    break;
                }
            }
            step *= 0.5;
        }
        taken += 1;
        if !accepted {
            if s_hist.is_empty() {
                break;
            }
            s_hist.clear();
            y_hist.clear();
        }
    }
    taken
}

fn x_size(x: &[[f64; 2]]) -> f64 {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in x {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (hi[0] - lo[0]).hypot(hi[1] - lo[1]).max(f64::MIN_POSITIVE)
}

/// Untangles `x` (a layout of `faces` whose rest shape is `rest`, the vertices `fixed`
/// held): rounds of L-BFGS on `f_ε` with `ε` lowered by the paper's rule, until no face is
/// at most `min_area` and the energy has settled, or `rounds` rounds of at most
/// `iterations` steps. `x` is changed only when the result has fewer bad faces.
#[allow(clippy::too_many_arguments)]
pub(crate) fn untangle(
    rest_positions: &[[f64; 2]],
    faces: &[[u32; 3]],
    weights: Option<&[f64]>,
    fixed: &[bool],
    x: &mut [[f64; 2]],
    min_area: f64,
    rounds: usize,
    iterations: usize,
) -> FoldoverReport {
    let layout_area: f64 = faces.iter().map(|f| signed_area(x, f)).sum();
    let rest = Rest::new(rest_positions, faces, weights, fixed, layout_area);
    let before = rest.bad(x, min_area);
    let mut y = x.to_vec();
    let mut det = rest.min_det(&y);
    let mut eps = if det > 0.0 { 1e-10 } else { 1.0f64.max(-det) };
    let mut total = 0;
    let mut best = (before, x.to_vec());
    for _ in 0..rounds {
        let e_prev = rest.energy(&y, eps, None);
        total += lbfgs(&rest, &mut y, eps, iterations, 1e-6, None);
        let e = rest.energy(&y, eps, None);
        det = rest.min_det(&y);
        let bad = rest.bad(&y, min_area);
        if bad < best.0 {
            best = (bad, y.clone());
        }
        if bad == 0 && det > 0.0 && ((e_prev - e) / e).abs() < 1e-4 {
            break;
        }
        let sigma = (1.0 - e / e_prev).max(0.1);
        let mu = (1.0 - sigma) * chi(det, eps);
        eps = if det < mu {
            2.0 * (mu * (mu - det)).max(0.0).sqrt()
        } else {
            1e-10
        };
        if !eps.is_finite() || !y.iter().all(|p| p[0].is_finite() && p[1].is_finite()) {
            break;
        }
    }
    if best.0 < before {
        x.copy_from_slice(&best.1);
    }
    FoldoverReport {
        bad_after: best.0.min(before),
        iterations: total,
    }
}

/// Lowers the energy of a valid layout `x` (every face's area above `min_area`) with `ε`
/// tiny, never letting a face's area fall to `min_area`: at most `iterations` steps.
/// Returns the steps taken; `x` stays valid.
pub(crate) fn smooth(
    rest_positions: &[[f64; 2]],
    faces: &[[u32; 3]],
    weights: Option<&[f64]>,
    fixed: &[bool],
    x: &mut [[f64; 2]],
    min_area: f64,
    iterations: usize,
) -> usize {
    let layout_area: f64 = faces.iter().map(|f| signed_area(x, f)).sum();
    let rest = Rest::new(rest_positions, faces, weights, fixed, layout_area);
    if !rest.valid(x, min_area) {
        return 0;
    }
    lbfgs(&rest, x, 1e-12, iterations, 1e-7, Some(min_area))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 5x5 grid of squares, each cut in two.
    fn grid() -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let id = |i: u32, j: u32| j * 6 + i;
        let mut faces = Vec::new();
        for j in 0..5 {
            for i in 0..5 {
                faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let p = (0..36)
            .map(|v| [f64::from(v % 6), f64::from(v / 6)])
            .collect();
        (p, faces)
    }

    #[test]
    fn a_folded_grid_is_untangled_with_its_boundary_held() {
        let (rest, faces) = grid();
        let fixed: Vec<bool> = rest
            .iter()
            .map(|p| p[0] == 0.0 || p[1] == 0.0 || p[0] == 5.0 || p[1] == 5.0)
            .collect();
        // Interior vertices thrown across the square.
        let mut x = rest.clone();
        for (v, p) in x.iter_mut().enumerate() {
            if !fixed[v] {
                *p = [5.0 - p[1] * 0.9, p[0] * 0.7 + 0.3];
            }
        }
        let bad = faces.iter().filter(|f| signed_area(&x, f) <= 0.0).count();
        assert!(bad > 0);
        let report = untangle(&rest, &faces, None, &fixed, &mut x, 1e-9, 30, 300);
        assert_eq!(report.bad_after, 0, "{report:?}");
        assert!(faces.iter().all(|f| signed_area(&x, f) > 0.0));
        for (v, p) in x.iter().enumerate() {
            if fixed[v] {
                assert_eq!(*p, rest[v]);
            }
        }
        // Smoothing keeps it valid and brings it back near the grid.
        let steps = smooth(&rest, &faces, None, &fixed, &mut x, 1e-9, 500);
        assert!(steps > 0);
        assert!(faces.iter().all(|f| signed_area(&x, f) > 0.0));
        let far = x
            .iter()
            .zip(&rest)
            .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
            .fold(0.0, f64::max);
        assert!(far < 1e-3, "{far}");
    }
}
