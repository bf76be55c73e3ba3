//! Isotropic distortion energies of a 2×2 deformation gradient `F` and their analytic
//! eigensystems (Smith, de Goes, Kim, *Analytic Eigensystems for Isotropic Distortion
//! Energies*, 2019), for projected Newton.
//!
//! An isotropic energy depends on `F = U diag(σ₁, σ₂) Vᵀ` only through its *signed* singular
//! values (`U`, `V` rotations, `σ₁ ≥ |σ₂|`, `σ₂ < 0` when `F` is inverted). The Hessian
//! `∂²Ψ/∂F²` then has four eigenvectors known in closed form: two *scaling* modes
//! `U diag(x₁, x₂) Vᵀ` from the 2×2 Hessian in `(σ₁, σ₂)`, the *twist*
//! `U [[0, −1], [1, 0]] Vᵀ / √2` with eigenvalue `(Ψ₁ + Ψ₂) / (σ₁ + σ₂)`, and the *flip*
//! `U [[0, 1], [1, 0]] Vᵀ / √2` with eigenvalue `(Ψ₁ − Ψ₂) / (σ₁ − σ₂)` (`Ψᵢ = ∂Ψ/∂σᵢ`).
//! Clamping the negative eigenvalues gives the nearest positive semi-definite Hessian at the
//! cost of a 2×2 eigenproblem. The two quotients are written out per energy so that they
//! stay finite when `σ₁ = σ₂`.

// Small fixed-size matrix algebra reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

/// A distortion energy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Energy {
    /// Symmetric Dirichlet `σ₁² + σ₂² + σ₁⁻² + σ₂⁻²` (4 for an isometry).
    SymmetricDirichlet,
    /// As-rigid-as-possible `(σ₁ − 1)² + (σ₂ − 1)²` (0 for a rotation).
    Arap,
    /// MIPS (conformal) `σ₁/σ₂ + σ₂/σ₁` (2 for a similarity).
    Mips,
    /// As-similar-as-possible `(σ₁ − σ₂)² / 2`: the squared distance `|F − S|²` from the
    /// nearest similarity `S` (0 for a similarity), which local/global ASAP lowers. Finite
    /// on degenerate and inverted triangles (`σ₂ < 0` there).
    Asap,
    /// The excess of the conformal distortion over a bound: with `m = (σ₁/σ₂ + σ₂/σ₁) / 2`
    /// (half MIPS, `(D + 1/D) / 2` for the distortion `D = σ₁/σ₂`) and `c` the value of `m`
    /// at `D = bound`, `ε (m − 1) + max(0, m − c)²` with `ε` = [`EXCESS_CONFORMAL_WEIGHT`].
    /// Zero excess exactly when the triangle is within the bound; the small conformal term
    /// keeps the Hessian definite where it is, and the barrier of `m` at `det F = 0` keeps
    /// triangles from inverting.
    Excess {
        /// The bound on `σ₁/σ₂` (at least 1).
        bound: f64,
    },
    /// ARAP plus a collapse barrier: `(σ₁ − 1)² + (σ₂ − 1)² + w (σ₁⁻² + σ₂⁻² − 2)` (0 for a
    /// rotation, infinite at `det F ≤ 0`). ARAP alone is finite on a degenerate triangle, so
    /// a flip-free minimisation of it can squash a triangle flat against the `det F = 0`
    /// wall; the barrier term (the inverse half of symmetric Dirichlet, weighted by `w`)
    /// keeps every minimiser off that wall and changes little elsewhere (`w` is small).
    ArapBarrier {
        /// The weight `w > 0` of the barrier term.
        weight: f64,
    },
}

/// The weight `ε` of the conformal term in [`Energy::Excess`].
pub const EXCESS_CONFORMAL_WEIGHT: f64 = 1e-4;

/// `φ'(m)` and `φ''(m)` for [`Energy::Excess`] at half-MIPS `m`.
fn excess_slopes(bound: f64, m: f64) -> [f64; 2] {
    let c = 0.5 * (bound + 1.0 / bound);
    if m > c {
        [EXCESS_CONFORMAL_WEIGHT + 2.0 * (m - c), 2.0]
    } else {
        [EXCESS_CONFORMAL_WEIGHT, 0.0]
    }
}

/// The signed singular value decomposition of a 2×2 matrix (rows): `F = U diag(σ) Vᵀ` with
/// `U = rot(α)`, `V = rot(β)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Svd2 {
    /// `σ₁ ≥ |σ₂|`; `σ₂` has the sign of `det F`.
    pub sigma: [f64; 2],
    /// `U` (rows).
    pub u: [[f64; 2]; 2],
    /// `V` (rows).
    pub v: [[f64; 2]; 2],
}

/// The signed SVD in closed form: `F` is a similarity part `Q rot(α − β)` plus an
/// anti-similarity part `R refl(α + β)`, and `σ = Q ± R`.
pub fn svd2(f: [[f64; 2]; 2]) -> Svd2 {
    let [[a, b], [c, d]] = f;
    let (e, h) = (0.5 * (a + d), 0.5 * (c - b));
    let (fq, g) = (0.5 * (a - d), 0.5 * (c + b));
    let q = e.hypot(h);
    let r = fq.hypot(g);
    let a1 = g.atan2(fq);
    let a2 = h.atan2(e);
    let alpha = 0.5 * (a2 + a1);
    let beta = 0.5 * (a1 - a2);
    let rot = |t: f64| {
        let (s, c) = t.sin_cos();
        [[c, -s], [s, c]]
    };
    Svd2 {
        sigma: [q + r, q - r],
        u: rot(alpha),
        v: rot(beta),
    }
}

/// The signed singular values of [`svd2`] alone (the same values, bit for bit, without the
/// angles of `U` and `V`).
pub fn sigma2(f: [[f64; 2]; 2]) -> [f64; 2] {
    let [[a, b], [c, d]] = f;
    let (e, h) = (0.5 * (a + d), 0.5 * (c - b));
    let (fq, g) = (0.5 * (a - d), 0.5 * (c + b));
    let q = e.hypot(h);
    let r = fq.hypot(g);
    [q + r, q - r]
}

/// `U diag(x) Vᵀ`, or `U M Vᵀ` for a general middle `m`.
fn sandwich(s: &Svd2, m: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
    let mut um = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            um[i][j] = s.u[i][0] * m[0][j] + s.u[i][1] * m[1][j];
        }
    }
    let mut out = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            // (U M) Vᵀ: Vᵀ[k][j] = V[j][k].
            out[i][j] = um[i][0] * s.v[j][0] + um[i][1] * s.v[j][1];
        }
    }
    out
}

/// Flattens a 2×2 matrix row by row.
pub fn flat(m: [[f64; 2]; 2]) -> [f64; 4] {
    [m[0][0], m[0][1], m[1][0], m[1][1]]
}

impl Energy {
    /// `Ψ(σ₁, σ₂)`; infinite where the energy is not defined (a degenerate or, for the
    /// barrier energies, inverted map).
    pub fn psi(self, [s1, s2]: [f64; 2]) -> f64 {
        match self {
            Energy::SymmetricDirichlet => {
                if s1 * s2 <= 0.0 {
                    return f64::INFINITY;
                }
                s1 * s1 + s2 * s2 + 1.0 / (s1 * s1) + 1.0 / (s2 * s2)
            }
            Energy::Arap => (s1 - 1.0).powi(2) + (s2 - 1.0).powi(2),
            Energy::Asap => 0.5 * (s1 - s2).powi(2),
            Energy::Mips => {
                if s1 * s2 <= 0.0 {
                    return f64::INFINITY;
                }
                s1 / s2 + s2 / s1
            }
            Energy::Excess { bound } => {
                if s1 * s2 <= 0.0 {
                    return f64::INFINITY;
                }
                let m = 0.5 * (s1 / s2 + s2 / s1);
                let c = 0.5 * (bound + 1.0 / bound);
                EXCESS_CONFORMAL_WEIGHT * (m - 1.0) + (m - c).max(0.0).powi(2)
            }
            Energy::ArapBarrier { weight } => {
                if s1 * s2 <= 0.0 {
                    return f64::INFINITY;
                }
                (s1 - 1.0).powi(2)
                    + (s2 - 1.0).powi(2)
                    + weight * (1.0 / (s1 * s1) + 1.0 / (s2 * s2) - 2.0)
            }
        }
    }

    /// `[Ψ₁, Ψ₂]`.
    pub fn gradient(self, [s1, s2]: [f64; 2]) -> [f64; 2] {
        match self {
            Energy::SymmetricDirichlet => {
                [2.0 * s1 - 2.0 / s1.powi(3), 2.0 * s2 - 2.0 / s2.powi(3)]
            }
            Energy::Arap => [2.0 * (s1 - 1.0), 2.0 * (s2 - 1.0)],
            Energy::Asap => [s1 - s2, s2 - s1],
            Energy::Mips => [1.0 / s2 - s2 / (s1 * s1), 1.0 / s1 - s1 / (s2 * s2)],
            Energy::Excess { bound } => {
                let [d1, _] = excess_slopes(bound, 0.5 * (s1 / s2 + s2 / s1));
                let [g1, g2] = Energy::Mips.gradient([s1, s2]);
                [0.5 * d1 * g1, 0.5 * d1 * g2]
            }
            Energy::ArapBarrier { weight } => [
                2.0 * (s1 - 1.0) - 2.0 * weight / s1.powi(3),
                2.0 * (s2 - 1.0) - 2.0 * weight / s2.powi(3),
            ],
        }
    }

    /// The Hessian in `(σ₁, σ₂)`: `[Ψ₁₁, Ψ₁₂, Ψ₂₂]`.
    pub fn hessian(self, [s1, s2]: [f64; 2]) -> [f64; 3] {
        match self {
            Energy::SymmetricDirichlet => [2.0 + 6.0 / s1.powi(4), 0.0, 2.0 + 6.0 / s2.powi(4)],
            Energy::Arap => [2.0, 0.0, 2.0],
            Energy::Asap => [1.0, -1.0, 1.0],
            Energy::Mips => [
                2.0 * s2 / s1.powi(3),
                -1.0 / (s1 * s1) - 1.0 / (s2 * s2),
                2.0 * s1 / s2.powi(3),
            ],
            Energy::Excess { bound } => {
                let [d1, d2] = excess_slopes(bound, 0.5 * (s1 / s2 + s2 / s1));
                let [h11, h12, h22] = Energy::Mips.hessian([s1, s2]);
                let [g1, g2] = Energy::Mips.gradient([s1, s2]);
                // φ' ∇²m + φ'' ∇m ∇mᵀ with m = MIPS / 2.
                [
                    0.5 * d1 * h11 + 0.25 * d2 * g1 * g1,
                    0.5 * d1 * h12 + 0.25 * d2 * g1 * g2,
                    0.5 * d1 * h22 + 0.25 * d2 * g2 * g2,
                ]
            }
            Energy::ArapBarrier { weight } => [
                2.0 + 6.0 * weight / s1.powi(4),
                0.0,
                2.0 + 6.0 * weight / s2.powi(4),
            ],
        }
    }

    /// The twist eigenvalue `(Ψ₁ + Ψ₂) / (σ₁ + σ₂)` and the flip eigenvalue
    /// `(Ψ₁ − Ψ₂) / (σ₁ − σ₂)`, simplified so that neither divides by zero.
    pub fn twist_flip(self, [s1, s2]: [f64; 2]) -> [f64; 2] {
        match self {
            Energy::SymmetricDirichlet => {
                let c = (s1 * s2).powi(3);
                [
                    2.0 - 2.0 * (s1 * s1 - s1 * s2 + s2 * s2) / c,
                    2.0 + 2.0 * (s1 * s1 + s1 * s2 + s2 * s2) / c,
                ]
            }
            Energy::Arap => {
                let sum = s1 + s2;
                // At σ₁ + σ₂ = 0 the twist is singular; any value keeps the clamp at zero.
                let twist = if sum.abs() > 1e-12 {
                    2.0 - 4.0 / sum
                } else {
                    0.0
                };
                [twist, 2.0]
            }
            // (Ψ₁ + Ψ₂) = 0 and (Ψ₁ − Ψ₂) = 2 (σ₁ − σ₂).
            Energy::Asap => [0.0, 2.0],
            Energy::Mips => {
                let p = s1 * s1 * s2 * s2;
                [-(s1 - s2).powi(2) / p, (s1 + s2).powi(2) / p]
            }
            Energy::Excess { bound } => {
                // (Ψ₁ ± Ψ₂) / (σ₁ ± σ₂) = φ' (m₁ ± m₂) / (σ₁ ± σ₂).
                let [d1, _] = excess_slopes(bound, 0.5 * (s1 / s2 + s2 / s1));
                let [t, f] = Energy::Mips.twist_flip([s1, s2]);
                [0.5 * d1 * t, 0.5 * d1 * f]
            }
            Energy::ArapBarrier { weight } => {
                // Both quotients are linear in Ψ: ARAP's plus w times those of σ⁻² summed.
                let [t, f] = Energy::Arap.twist_flip([s1, s2]);
                let c = (s1 * s2).powi(3);
                [
                    t - 2.0 * weight * (s1 * s1 - s1 * s2 + s2 * s2) / c,
                    f + 2.0 * weight * (s1 * s1 + s1 * s2 + s2 * s2) / c,
                ]
            }
        }
    }

    /// `∂Ψ/∂F` (rows).
    pub fn first_piola(self, svd: &Svd2) -> [[f64; 2]; 2] {
        let g = self.gradient(svd.sigma);
        sandwich(svd, [[g[0], 0.0], [0.0, g[1]]])
    }

    /// The eigenvalues and unit eigenvectors (flattened row by row) of `∂²Ψ/∂F²`, in the
    /// order scaling, scaling, twist, flip.
    pub fn eigensystem(self, svd: &Svd2) -> [(f64, [f64; 4]); 4] {
        let [h11, h12, h22] = self.hessian(svd.sigma);
        // The 2x2 symmetric eigenproblem in (σ₁, σ₂).
        let mean = 0.5 * (h11 + h22);
        let rad = (0.25 * (h11 - h22) * (h11 - h22) + h12 * h12).sqrt();
        let (l1, l2) = (mean + rad, mean - rad);
        // Eigenvector of l1: (h12, l1 - h11) or (l1 - h22, h12), the better conditioned.
        let (mut x, mut y) = if (h11 - l2).abs() >= (h22 - l2).abs() {
            (l1 - h22, h12)
        } else {
            (h12, l1 - h11)
        };
        let n = x.hypot(y);
        if n > 0.0 {
            x /= n;
            y /= n;
        } else {
            (x, y) = (1.0, 0.0);
        }
        let d1 = flat(sandwich(svd, [[x, 0.0], [0.0, y]]));
        let d2 = flat(sandwich(svd, [[-y, 0.0], [0.0, x]]));
        let r = std::f64::consts::FRAC_1_SQRT_2;
        let twist = flat(sandwich(svd, [[0.0, -r], [r, 0.0]]));
        let flip = flat(sandwich(svd, [[0.0, r], [r, 0.0]]));
        let [lt, lf] = self.twist_flip(svd.sigma);
        [(l1, d1), (l2, d2), (lt, twist), (lf, flip)]
    }

    /// The projected (positive semi-definite) `∂²Ψ/∂F²`, 4×4 over `F` flattened row by row:
    /// the eigensystem with negative eigenvalues set to zero.
    pub fn projected_hessian(self, svd: &Svd2) -> [[f64; 4]; 4] {
        let mut h = [[0.0; 4]; 4];
        for (l, q) in self.eigensystem(svd) {
            if l > 0.0 {
                for i in 0..4 {
                    for j in 0..4 {
                        h[i][j] += l * q[i] * q[j];
                    }
                }
            }
        }
        h
    }

    /// The part of `∂²Ψ/∂F²` that [`Energy::projected_hessian`] drops: its negative
    /// eigenvalues with their eigenvectors (4×4 over `F` flattened row by row), so that
    /// the projected Hessian plus this is the Hessian itself.
    pub fn negative_hessian(self, svd: &Svd2) -> [[f64; 4]; 4] {
        let mut h = [[0.0; 4]; 4];
        for (l, q) in self.eigensystem(svd) {
            if l < 0.0 {
                for i in 0..4 {
                    for j in 0..4 {
                        h[i][j] += l * q[i] * q[j];
                    }
                }
            }
        }
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random(state: &mut u64) -> f64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        (*state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }

    fn psi_of_f(e: Energy, f: [f64; 4]) -> f64 {
        e.psi(svd2([[f[0], f[1]], [f[2], f[3]]]).sigma)
    }

    #[test]
    fn signed_svd_reconstructs_and_orders() {
        let mut st = 0x1234_5678_9abc_def1;
        for _ in 0..500 {
            let f = [
                [random(&mut st), random(&mut st)],
                [random(&mut st), random(&mut st)],
            ];
            let s = svd2(f);
            assert_eq!(sigma2(f), s.sigma);
            let back = sandwich(&s, [[s.sigma[0], 0.0], [0.0, s.sigma[1]]]);
            for i in 0..2 {
                for j in 0..2 {
                    assert!((back[i][j] - f[i][j]).abs() < 1e-12, "{f:?}");
                }
            }
            assert!(s.sigma[0] >= s.sigma[1].abs() - 1e-15);
            let det = f[0][0] * f[1][1] - f[0][1] * f[1][0];
            assert!(det * s.sigma[1] >= -1e-15);
        }
    }

    /// The analytic eigensystem against a numeric Hessian (central differences of the
    /// analytic gradient) and its Jacobi eigendecomposition, on random deformation gradients,
    /// inverted ones included (for ARAP, which is defined there).
    #[test]
    fn analytic_eigensystem_matches_numeric_eigendecomposition() {
        let mut st = 0x9e37_79b9_7f4a_7c15;
        for energy in [
            Energy::SymmetricDirichlet,
            Energy::Arap,
            Energy::Mips,
            Energy::Excess { bound: 1.2 },
            Energy::ArapBarrier { weight: 0.05 },
        ] {
            let mut checked = 0;
            while checked < 200 {
                let f = [
                    1.0 + 0.6 * random(&mut st),
                    0.6 * random(&mut st),
                    0.6 * random(&mut st),
                    1.0 + 0.6 * random(&mut st),
                ];
                let f = if energy == Energy::Arap && checked % 3 == 0 {
                    [f[0], f[1], -f[2], -f[3]] // inverted
                } else {
                    f
                };
                let m = [[f[0], f[1]], [f[2], f[3]]];
                let svd = svd2(m);
                if energy != Energy::Arap && svd.sigma[1] <= 0.05 {
                    continue;
                }
                if (svd.sigma[0] - svd.sigma[1]).abs() < 1e-3
                    || (svd.sigma[0] + svd.sigma[1]).abs() < 1e-3
                {
                    continue;
                }
                // The excess energy has a kink in its second derivative at the bound.
                if let Energy::Excess { bound } = energy {
                    let ratio = svd.sigma[0] / svd.sigma[1];
                    if (ratio - bound).abs() < 1e-3 {
                        continue;
                    }
                }
                checked += 1;
                // Gradient: analytic against finite differences of Ψ.
                let p = flat(energy.first_piola(&svd));
                let hstep = 1e-6;
                for k in 0..4 {
                    let (mut fp, mut fm) = (f, f);
                    fp[k] += hstep;
                    fm[k] -= hstep;
                    let num = (psi_of_f(energy, fp) - psi_of_f(energy, fm)) / (2.0 * hstep);
                    assert!(
                        (num - p[k]).abs() < 1e-5 * (1.0 + p[k].abs()),
                        "{energy:?} grad {k}: {num} vs {}",
                        p[k]
                    );
                }
                // Hessian: finite differences of the analytic gradient.
                let mut hess = [[0.0; 4]; 4];
                for k in 0..4 {
                    let (mut fp, mut fm) = (f, f);
                    fp[k] += hstep;
                    fm[k] -= hstep;
                    let gp = flat(energy.first_piola(&svd2([[fp[0], fp[1]], [fp[2], fp[3]]])));
                    let gm = flat(energy.first_piola(&svd2([[fm[0], fm[1]], [fm[2], fm[3]]])));
                    for i in 0..4 {
                        hess[i][k] = (gp[i] - gm[i]) / (2.0 * hstep);
                    }
                }
                let mut numeric = jacobi_eigenvalues(hess);
                numeric.sort_by(f64::total_cmp);
                let system = energy.eigensystem(&svd);
                let mut analytic: Vec<f64> = system.iter().map(|(l, _)| *l).collect();
                analytic.sort_by(f64::total_cmp);
                for (a, n) in analytic.iter().zip(&numeric) {
                    assert!(
                        (a - n).abs() < 1e-4 * (1.0 + n.abs()),
                        "{energy:?} {f:?}: {analytic:?} vs {numeric:?}"
                    );
                }
                // Each analytic pair is an eigenpair of the numeric Hessian.
                for (l, q) in system {
                    for i in 0..4 {
                        let hq: f64 = (0..4).map(|j| hess[i][j] * q[j]).sum();
                        assert!(
                            (hq - l * q[i]).abs() < 1e-4 * (1.0 + l.abs()),
                            "{energy:?} {f:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn projection_is_positive_semi_definite() {
        let svd = svd2([[0.3, 0.9], [-0.2, 1.4]]);
        for energy in [
            Energy::SymmetricDirichlet,
            Energy::Arap,
            Energy::Mips,
            Energy::ArapBarrier { weight: 1e-3 },
        ] {
            let h = energy.projected_hessian(&svd);
            let mut ev = jacobi_eigenvalues(h);
            ev.sort_by(f64::total_cmp);
            assert!(ev[0] > -1e-12, "{energy:?}: {ev:?}");
        }
    }

    /// Eigenvalues of a symmetric 4x4 matrix by cyclic Jacobi rotations.
    fn jacobi_eigenvalues(mut a: [[f64; 4]; 4]) -> Vec<f64> {
        // Symmetrise the finite-difference matrix first.
        for i in 0..4 {
            for j in 0..i {
                let m = 0.5 * (a[i][j] + a[j][i]);
                a[i][j] = m;
                a[j][i] = m;
            }
        }
        for _ in 0..100 {
            for p in 0..4 {
                for q in p + 1..4 {
                    if a[p][q].abs() < 1e-300 {
                        continue;
                    }
                    let theta = 0.5 * (2.0 * a[p][q]).atan2(a[q][q] - a[p][p]);
                    let (s, c) = theta.sin_cos();
                    for k in 0..4 {
                        let (x, y) = (a[k][p], a[k][q]);
                        a[k][p] = c * x - s * y;
                        a[k][q] = s * x + c * y;
                    }
                    for k in 0..4 {
                        let (x, y) = (a[p][k], a[q][k]);
                        a[p][k] = c * x - s * y;
                        a[q][k] = s * x + c * y;
                    }
                }
            }
        }
        (0..4).map(|i| a[i][i]).collect()
    }
}
