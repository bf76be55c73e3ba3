//! The Lobachevsky function `Л(x) = -∫_0^x log|2 sin t| dt = Cl2(2x) / 2`, which the CETM
//! energy (Springborn, Schroeder, Pinkall 2008) needs for every triangle angle.
//!
//! Computed through the Clausen function, reduced to `[-pi, pi]` by periodicity and oddness,
//! with the series `Cl2(t) = t - t ln|t| + sum_k zeta(2k) t (t / 2 pi)^(2k) / (k (2k + 1))`,
//! which converges geometrically (ratio at most 1/4) there: a fixed polynomial of 22 terms in
//! `t^2` (Horner) gives full double precision, with one logarithm.

use std::f64::consts::PI;

/// Coefficients `a_k = |B_2k| / (2 (2k)! k (2k + 1))` of `Cl2(x) = x - x ln x + sum a_k x^(2k+1)`
/// (`B` the Bernoulli numbers), k = 1..=22: for `|x| <= pi` the last term is below 1e-18.
/// (Computed exactly from rational Bernoulli numbers, then rounded.)
#[allow(clippy::excessive_precision)]
const CLAUSEN: [f64; 22] = [
    0.013888888888888888,
    6.944444444444444e-05,
    7.873519778281683e-07,
    1.1482216343327455e-08,
    1.8978869988971e-10,
    3.387301370953521e-12,
    6.372636443183181e-14,
    1.2462059912950672e-15,
    2.5105444608999545e-17,
    5.178258806090623e-19,
    1.0887357368300849e-20,
    2.325744114302087e-22,
    5.03519521314739e-24,
    1.1026499294381215e-25,
    2.4386585509007344e-27,
    5.440142678856253e-29,
    1.2228340131217352e-30,
    2.767263468967951e-32,
    6.3000905918320136e-34,
    1.4420868388418476e-35,
    3.3170939991595428e-37,
    7.663913557920658e-39,
];

/// The Clausen function `Cl2(t) = -∫_0^t log|2 sin(s / 2)| ds`.
pub fn clausen2(t: f64) -> f64 {
    if !t.is_finite() {
        return f64::NAN;
    }
    // Reduce to [-pi, pi]: Cl2 is 2 pi periodic and odd.
    let mut x = t % (2.0 * PI);
    if x > PI {
        x -= 2.0 * PI;
    } else if x < -PI {
        x += 2.0 * PI;
    }
    if x == 0.0 {
        return 0.0;
    }
    let (sign, x) = if x < 0.0 { (-1.0, -x) } else { (1.0, x) };
    let y = x * x;
    let mut poly = 0.0;
    for &a in CLAUSEN.iter().rev() {
        poly = poly * y + a;
    }
    let sum = poly * y;
    sign * x * (1.0 - x.ln() + sum)
}

/// The Lobachevsky function `Л(x) = Cl2(2x) / 2`; `Л(0) = Л(pi/2) = Л(pi) = 0`.
#[inline]
pub fn lobachevsky(x: f64) -> f64 {
    0.5 * clausen2(2.0 * x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        // Catalan's constant, and the maximum of Cl2 at pi/3.
        let catalan = 0.915_965_594_177_219;
        assert!((clausen2(PI / 2.0) - catalan).abs() < 1e-15);
        assert!((clausen2(PI / 3.0) - 1.014_941_606_409_653_6).abs() < 1e-15);
        assert!((lobachevsky(PI / 4.0) - catalan / 2.0).abs() < 1e-15);
        for x in [0.0, PI / 2.0, PI] {
            assert!(lobachevsky(x).abs() < 1e-15, "Л({x})");
        }
        // Odd and pi-periodic.
        assert!((lobachevsky(-0.3) + lobachevsky(0.3)).abs() < 1e-16);
        assert!((lobachevsky(0.3 + PI) - lobachevsky(0.3)).abs() < 1e-14);
    }

    #[test]
    fn derivative_is_minus_log_2_sin() {
        for &x in &[0.05, 0.3, 0.7, 1.2, PI / 2.0, 2.0, 2.9, 3.1] {
            let h = 1e-5;
            let fd = (lobachevsky(x + h) - lobachevsky(x - h)) / (2.0 * h);
            let exact = -(2.0 * f64::sin(x)).abs().ln();
            // Central differences: the error is h^2/6 times the third derivative (~2/x^3).
            assert!((fd - exact).abs() < 1e-7, "x = {x}: {fd} vs {exact}");
        }
    }

    #[test]
    fn satisfies_the_duplication_formula() {
        // Л(2x) = 2 Л(x) + 2 Л(x + pi/2), an identity independent of the series.
        for &x in &[0.01, 0.2, 0.5, 0.9, 1.3, 1.5, 2.2, 3.0] {
            let lhs = lobachevsky(2.0 * x);
            let rhs = 2.0 * lobachevsky(x) + 2.0 * lobachevsky(x + PI / 2.0);
            assert!((lhs - rhs).abs() < 1e-14, "x = {x}: {lhs} vs {rhs}");
        }
    }
}
