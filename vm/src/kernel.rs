//! Triangle formulas shared by the iteration and embed streams.

/// Half of the angle between sides `a` and `b` of a triangle whose third side is `c`, and the
/// cotangent of the full angle, from the half-angle tangent
/// `tan(gamma / 2) = sqrt((c + a - b)(c + b - a) / ((a + b - c)(a + b + c)))`.
///
/// Lengths that break the triangle inequality give the limits of the convex extension of the
/// energy: angle 0 (`c` too short) or pi (`c` too long), with cotangent 0.
#[inline(always)]
pub fn half_angle_and_cot(a: f64, b: f64, c: f64, with_angle: bool) -> [f64; 2] {
    let mut num = (c + a - b) * (c + b - a);
    let mut den = (a + b - c) * (a + b + c);
    if !(num.is_finite() && den.is_finite()) || den < 1e-280 {
        // Lengths beyond 1e154 overflow the products and below 1e-140 underflow them (or the
        // triangle is degenerate); the angle depends only on ratios, so normalise. Cold path.
        let m = a.max(b).max(c);
        let (a, b, c) = (a / m, b / m, c / m);
        num = (c + a - b) * (c + b - a);
        den = (a + b - c) * (a + b + c);
    }
    if num <= 0.0 {
        return [0.0, 0.0];
    }
    if den <= 0.0 {
        return [std::f64::consts::FRAC_PI_2, 0.0];
    }
    let x = (num / den).sqrt();
    // num / den can underflow to 0 or overflow for extreme lengths: the limit angles again.
    if x == 0.0 {
        return [0.0, 0.0];
    }
    if !x.is_finite() {
        return [std::f64::consts::FRAC_PI_2, 0.0];
    }
    let cot = (1.0 - x * x) / (2.0 * x);
    let half = if with_angle { x.atan() } else { 0.0 };
    [half, cot]
}

/// Cosine and sine of the angle between sides `a` and `b` opposite side `c` (rational in the
/// half-angle tangent, so no trigonometric call): `((den - num), 2 sqrt(num den)) / (den + num)`.
/// Degenerate lengths give angle 0 or pi.
#[inline(always)]
pub fn cos_sin(a: f64, b: f64, c: f64) -> [f64; 2] {
    // Scale-free: normalised lengths keep the products (and num * den) far from overflow.
    let m = a.max(b).max(c);
    let (a, b, c) = if m > 0.0 && m.is_finite() {
        (a / m, b / m, c / m)
    } else {
        (a, b, c)
    };
    let num = ((c + a - b) * (c + b - a)).max(0.0);
    let den = ((a + b - c) * (a + b + c)).max(0.0);
    let sum = num + den;
    if sum <= 0.0 {
        return [1.0, 0.0];
    }
    [(den - num) / sum, 2.0 * (num * den).sqrt() / sum]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law_of_cosines(a: f64, b: f64, c: f64) -> f64 {
        ((a * a + b * b - c * c) / (2.0 * a * b)).acos()
    }

    #[test]
    fn matches_the_law_of_cosines() {
        for &(a, b, c) in &[
            (3.0, 4.0, 5.0),
            (1.0, 1.0, 1.0),
            (2.0, 3.0, 4.5),
            (1.0, 1.0, 1.9),
        ] {
            let g = law_of_cosines(a, b, c);
            let [half, cot] = half_angle_and_cot(a, b, c, true);
            assert!((2.0 * half - g).abs() < 1e-14, "{a} {b} {c}");
            assert!((cot - 1.0 / g.tan()).abs() < 1e-12);
            let [cs, sn] = cos_sin(a, b, c);
            assert!((cs - g.cos()).abs() < 1e-14 && (sn - g.sin()).abs() < 1e-14);
        }
    }

    #[test]
    fn extreme_scales_give_the_same_angles() {
        for scale in [1e-200, 1e-150, 1e150, 1e200, 1e300] {
            let [half, cot] = half_angle_and_cot(3.0 * scale, 4.0 * scale, 5.0 * scale, true);
            let [h1, c1] = half_angle_and_cot(3.0, 4.0, 5.0, true);
            assert!(
                (half - h1).abs() < 1e-15 && (cot - c1).abs() < 1e-12,
                "{scale}"
            );
            let [cs, sn] = cos_sin(3.0 * scale, 4.0 * scale, 5.0 * scale);
            assert!(
                cs.abs() < 1e-15 && (sn - 1.0).abs() < 1e-15,
                "{scale}: {cs} {sn}"
            );
        }
    }

    #[test]
    fn degenerate_triangles_take_the_limit_angles() {
        assert_eq!(
            half_angle_and_cot(1.0, 1.0, 2.5, true),
            [std::f64::consts::FRAC_PI_2, 0.0]
        );
        assert_eq!(half_angle_and_cot(1.0, 3.0, 1.0, true), [0.0, 0.0]);
        assert_eq!(cos_sin(1.0, 1.0, 2.5), [-1.0, 0.0]);
        assert_eq!(cos_sin(1.0, 3.0, 1.0), [1.0, 0.0]);
        assert_eq!(cos_sin(0.0, 0.0, 0.0), [1.0, 0.0]);
    }
}
