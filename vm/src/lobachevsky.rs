//! The Lobachevsky function `Л(x) = -∫_0^x log|2 sin t| dt = Cl2(2x) / 2`, which the CETM
//! energy (Springborn, Schroeder, Pinkall 2008) needs for every triangle angle.
//!
//! Computed through the Clausen function, reduced to `[-pi, pi]` by periodicity and oddness,
//! with the series `Cl2(t) = t - t ln|t| + sum_k zeta(2k) t (t / 2 pi)^(2k) / (k (2k + 1))`,
//! which converges geometrically (ratio at most 1/4) there; about 25 terms give full double
//! precision.

use std::f64::consts::PI;

/// zeta(2k) for k = 1..=10; beyond, 1 + 2^-2k + 3^-2k + 4^-2k is exact to double precision.
const ZETA_EVEN: [f64; 10] = [
    1.644_934_066_848_226_4,
    1.082_323_233_711_138_2,
    1.017_343_061_984_449,
    1.004_077_356_197_944_3,
    1.000_994_575_127_818_1,
    1.000_246_086_553_308,
    1.000_061_248_135_058_7,
    1.000_015_282_259_408_6,
    1.000_003_817_293_265,
    1.000_000_953_962_033_9,
];

fn zeta_even(k: usize) -> f64 {
    if k <= ZETA_EVEN.len() {
        ZETA_EVEN[k - 1]
    } else {
        let s = -2.0 * k as f64;
        1.0 + 2f64.powf(s) + 3f64.powf(s) + 4f64.powf(s)
    }
}

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
    let r2 = (x / (2.0 * PI)).powi(2);
    let mut power = 1.0;
    let mut sum = 0.0;
    for k in 1..=40 {
        power *= r2;
        let term = zeta_even(k) * power / (k as f64 * (2 * k + 1) as f64);
        sum += term;
        if term < 1e-18 * sum {
            break;
        }
    }
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
