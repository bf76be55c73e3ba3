//! `exp` for the scale factors `exp(u / 2)` that every pass recomputes, in a form the compiler
//! vectorises (no call, no branch per element): one per unknown was 7% of the gradient pass
//! through the C library's scalar `exp`.
//!
//! `exp(x) = 2^k exp(r)` with `k = round(x / ln 2)` (by adding and subtracting `1.5 · 2^52`,
//! which also leaves `k` in the low bits of the sum) and `r = x − k ln 2` in two parts (Cody and
//! Waite), `|r| ≤ ln 2 / 2`; `exp(r)` by its Taylor polynomial of degree 13 (the first omitted
//! term is below 5e-18 of the result), then `2^k` is built in the exponent bits. Within
//! 2 ulp of the correctly rounded result for `|x| ≤ 700` (tested); outside that range, and
//! for NaN, the slice version falls back to [`f64::exp`].

/// `1.5 · 2^52`: adding it rounds to an integer and leaves that integer in the low bits.
const SHIFTER: f64 = 6_755_399_441_055_744.0;
const INV_LN2: f64 = std::f64::consts::LOG2_E;
/// `ln 2` split so that `k · LN2_HI` is exact for `|k| < 2^11`.
/// (fdlibm's `ln2_hi` and `ln2_lo`, given by their bits.)
const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);

/// `exp(x)` for `|x| ≤ 700` (no range check: see [`exp_half_into`]).
#[inline(always)]
fn exp_in_range(x: f64) -> f64 {
    let t = x * INV_LN2 + SHIFTER;
    let k = t - SHIFTER;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    // Taylor coefficients 1/n!, n = 0..=13, evaluated by Estrin's scheme in r² and r⁴.
    let r2 = r * r;
    let r4 = r2 * r2;
    let r8 = r4 * r4;
    let p01 = 1.0 + r;
    let p23 = 1.0 / 2.0 + r * (1.0 / 6.0);
    let p45 = 1.0 / 24.0 + r * (1.0 / 120.0);
    let p67 = 1.0 / 720.0 + r * (1.0 / 5040.0);
    let p89 = 1.0 / 40_320.0 + r * (1.0 / 362_880.0);
    let p1011 = 1.0 / 3_628_800.0 + r * (1.0 / 39_916_800.0);
    let p1213 = 1.0 / 479_001_600.0 + r * (1.0 / 6_227_020_800.0);
    let low = (p01 + r2 * p23) + r4 * (p45 + r2 * p67);
    let high = (p89 + r2 * p1011) + r4 * p1213;
    let poly = low + r8 * high;
    // t's low bits hold k (two's complement); 2^k has the biased exponent k + 1023.
    let k_bits = t.to_bits().wrapping_sub(SHIFTER.to_bits());
    let two_k = f64::from_bits(k_bits.wrapping_add(1023) << 52);
    poly * two_k
}

/// `out[i] = exp(u[i] / 2)` for every `i` (pairs `u` with `out` as far as both go).
pub fn exp_half_into(u: &[f64], out: &mut [f64]) {
    let mut in_range = true;
    for (o, &x) in out.iter_mut().zip(u) {
        let h = 0.5 * x;
        in_range &= h.abs() <= 700.0;
        *o = exp_in_range(h);
    }
    if !in_range {
        // Rare (a scale beyond e^±700, or NaN): redo the out-of-range entries exactly.
        for (o, &x) in out.iter_mut().zip(u) {
            let h = 0.5 * x;
            if h.is_nan() || h.abs() > 700.0 {
                *o = h.exp();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ulps(a: f64, b: f64) -> u64 {
        (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs()
    }

    #[test]
    fn within_two_ulps_of_the_library_exp() {
        let mut st: u64 = 0x2545_f491_4f6c_dd1d;
        let mut worst = 0;
        for i in 0..200_000 {
            st ^= st << 13;
            st ^= st >> 7;
            st ^= st << 17;
            let unit = (st >> 11) as f64 / (1u64 << 53) as f64;
            // Mostly the range the scale factors live in, sometimes the whole range.
            let x = if i % 4 == 0 {
                1400.0 * unit - 700.0
            } else {
                40.0 * unit - 20.0
            };
            let mut out = [0.0];
            exp_half_into(&[2.0 * x], &mut out);
            let d = ulps(out[0], x.exp());
            worst = worst.max(d);
            assert!(d <= 2, "exp({x}) = {} against {}", out[0], x.exp());
        }
        eprintln!("largest difference: {worst} ulp");
    }

    #[test]
    fn edges_of_the_range_and_beyond() {
        let u = [
            0.0,
            -0.0,
            1400.0,
            -1400.0,
            1500.0,
            -1600.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            2.0 * f64::MIN_POSITIVE,
        ];
        let mut out = [0.0; 10];
        exp_half_into(&u, &mut out);
        for (x, y) in u.iter().zip(&out) {
            let want = (0.5 * x).exp();
            assert!(
                (want.is_nan() && y.is_nan()) || ulps(*y, want) <= 2,
                "exp({}) = {y} against {want}",
                0.5 * x
            );
        }
        assert_eq!(out[0], 1.0);
    }
}
