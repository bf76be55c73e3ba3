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

/// One corner of a triangle as the iteration stream stores it: the direction of its half angle
/// `(cos h, sin h)` scaled by a factor in (0, 1], and the cotangent of the full angle.
pub type Corner = [f64; 3];

/// The corner a `TRIANGLE.INERT` writes: a half angle of 0 (direction `(1, 0)`) and a
/// cotangent of 0, which add nothing to a vertex's angle sum or Hessian weights.
pub const INERT_CORNER: Corner = [1.0, 0.0, 0.0];

/// The three corners of a triangle with sides `l[0]`, `l[1]`, `l[2]`, corner `c` opposite
/// side `l[(c + 1) % 3]` (the `TRIANGLE` instruction's convention).
///
/// With `s` the half perimeter, `s_x = s - l_x` and `r = sqrt(s_0 s_1 s_2 / s)` the inradius,
/// the corner opposite `l_x` has half-angle tangent `r / s_x`, so direction `(s_x, r) / s`, and
/// cotangent `(l_y^2 + l_z^2 - l_x^2) / (4 r s)` (the area is `r s`): one square root and two
/// divisions for the whole triangle. Degenerate lengths and lengths whose products leave the
/// normal range take a cold path through [`half_angle_and_cot`], with the same limits (angles
/// 0 and pi, cotangents 0).
#[inline(always)]
pub fn triangle_corners(l: [f64; 3]) -> [Corner; 3] {
    let mut out = [[0.0; 3]; 3];
    triangle_corners_into(l, &mut out);
    out
}

/// [`triangle_corners`] written into `out`, each value stored once from a register (a
/// returned array is assembled on the stack and copied with wider loads than its stores,
/// which stalls store forwarding: 14-16% of the gradient pass on one instruction).
#[inline(always)]
pub fn triangle_corners_into(l: [f64; 3], out: &mut [Corner]) {
    let s = 0.5 * (l[0] + l[1] + l[2]);
    let sx = [s - l[0], s - l[1], s - l[2]];
    let p = sx[0] * sx[1] * sx[2];
    if !(sx[0] > 0.0 && sx[1] > 0.0 && sx[2] > 0.0 && p.is_normal() && s.is_finite()) {
        out[..3].copy_from_slice(&triangle_corners_cold(l));
        return;
    }
    let inv_s = 1.0 / s;
    let r = (p * inv_s).sqrt();
    let inv_4area = 0.25 / (r * s);
    let sq = [l[0] * l[0], l[1] * l[1], l[2] * l[2]];
    let sin = r * inv_s;
    // Corner c is opposite side (c + 1) % 3.
    let cot = [
        (sq[2] + sq[0] - sq[1]) * inv_4area,
        (sq[0] + sq[1] - sq[2]) * inv_4area,
        (sq[1] + sq[2] - sq[0]) * inv_4area,
    ];
    if !(sin > 0.0 && cot[0].is_finite() && cot[1].is_finite() && cot[2].is_finite()) {
        out[..3].copy_from_slice(&triangle_corners_cold(l));
        return;
    }
    let cos = [sx[1] * inv_s, sx[2] * inv_s, sx[0] * inv_s];
    for (c, o) in out[..3].iter_mut().enumerate() {
        o[0] = cos[c];
        o[1] = sin;
        o[2] = cot[c];
    }
}

/// [`triangle_corners`] for lengths the fast path cannot take, corner by corner.
#[cold]
#[inline(never)]
fn triangle_corners_cold(l: [f64; 3]) -> [Corner; 3] {
    let corner = |a: f64, b: f64, opposite: f64| {
        let [half, cot] = half_angle_and_cot(a, b, opposite, true);
        let (sin, cos) = half.sin_cos();
        [cos, sin, cot]
    };
    [
        corner(l[0], l[2], l[1]),
        corner(l[1], l[0], l[2]),
        corner(l[2], l[1], l[0]),
    ]
}

/// Sum of the half angles whose scaled directions are `corners` (each half angle in
/// [0, pi/2], each direction of magnitude at most 1): the argument of their complex product,
/// unwrapped by counting full turns, so one `atan2` (or, near pi, a short series) serves a
/// whole vertex.
///
/// `None` when the product's magnitude fell below 1e-290, where its last bits may have been
/// lost to underflow (it never grows, so checking at the end covers every step): then
/// [`half_angle_sum`] takes the same corners.
#[inline(always)]
pub fn half_angle_sum_fast(corners: impl Iterator<Item = [f64; 2]>) -> Option<f64> {
    let (re, im, turns) = product::<false>(corners);
    (re.abs() + im.abs() >= 1e-290).then(|| argument(re, im, turns))
}

/// [`half_angle_sum_fast`] for any magnitudes: rescales the product away from underflow.
#[cold]
#[inline(never)]
pub fn half_angle_sum(corners: impl Iterator<Item = [f64; 2]>) -> f64 {
    let (re, im, turns) = product::<true>(corners);
    argument(re, im, turns)
}

/// The complex product of `corners` and the full turns it made; with `RESCALE` the product is
/// renormalised whenever its magnitude drops below 1e-100.
#[inline(always)]
fn product<const RESCALE: bool>(corners: impl Iterator<Item = [f64; 2]>) -> (f64, f64, u32) {
    let (mut re, mut im) = (1.0f64, 0.0f64);
    let mut turns = 0u32;
    for [c, s] in corners {
        let next_re = re * c - im * s;
        let next_im = re * s + im * c;
        // A turn of at most pi/2 counter-clockwise brings the product from the lower half
        // plane to the upper one only across the positive real axis: a full turn.
        turns += u32::from(im < 0.0 && next_im >= 0.0);
        re = next_re;
        im = next_im;
        if RESCALE {
            let m = re.abs().max(im.abs());
            if m < 1e-100 && m > 0.0 {
                re /= m;
                im /= m;
            }
        }
    }
    (re, im, turns)
}

/// The argument of `re + i im` in [0, 2 pi), plus `turns` full turns.
#[inline(always)]
fn argument(re: f64, im: f64, turns: u32) -> f64 {
    let full_turns = std::f64::consts::TAU * f64::from(turns);
    // Near a flat vertex the sum is close to pi: the product points along the negative real
    // axis, and its argument is pi - atan(x) with x = im / -re small, where a short odd series
    // is exact to double precision (|x| < 1/32, y = x² < 2^-10: the first omitted term,
    // y⁶/13, is below 7e-20 of the sum). Estrin's scheme evaluates the polynomial in y in
    // three dependent steps instead of Horner's five: most vertices of a smooth mesh take
    // this path, and the latency chain was a fifth of the gradient pass.
    if re < 0.0 && im.abs() < (-re) * (1.0 / 32.0) {
        let x = im / -re;
        let y = x * x;
        let y2 = y * y;
        let low = 1.0 - y * (1.0 / 3.0);
        let mid = 1.0 / 5.0 - y * (1.0 / 7.0);
        let high = 1.0 / 9.0 - y * (1.0 / 11.0);
        let atan = x * (low + y2 * (mid + y2 * high));
        return std::f64::consts::PI - atan + full_turns;
    }
    let mut angle = im.atan2(re);
    if angle < 0.0 {
        angle += std::f64::consts::TAU;
    }
    angle + full_turns
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
    fn triangle_corners_match_the_corner_by_corner_formulas() {
        let cases = [
            [3.0, 4.0, 5.0],
            [1.0, 1.0, 1.0],
            [2.0, 3.0, 4.5],
            [1.0, 1.0, 1.9],
            [1e-120, 1.3e-120, 0.9e-120],
            [1e120, 1.3e120, 0.9e120],
            [1.0, 1.0, 2.5],
            [1.0, 3.0, 1.0],
            [1.0, 1.0, 2.0],
        ];
        for l in cases {
            let corners = triangle_corners(l);
            let reference = triangle_corners_cold(l);
            for (c, (x, y)) in corners.iter().zip(&reference).enumerate() {
                let (hx, hy) = (x[1].atan2(x[0]), y[1].atan2(y[0]));
                assert!((hx - hy).abs() < 1e-14, "{l:?} corner {c}: {hx} vs {hy}");
                assert!(
                    (x[2] - y[2]).abs() < 1e-12 * (1.0 + y[2].abs()),
                    "{l:?} corner {c}: cot {} vs {}",
                    x[2],
                    y[2]
                );
                assert!(x[0].hypot(x[1]) <= 1.0 + 1e-15 && x[0].hypot(x[1]) > 0.0);
            }
            // Corner c is opposite side (c + 1) % 3: the largest side faces the largest angle.
            if l == [3.0, 4.0, 5.0] {
                let right = corners[1];
                assert!(right[2].abs() < 1e-15, "the right angle is opposite side 2");
            }
        }
    }

    #[test]
    fn half_angle_sums_near_pi_take_the_series() {
        // Sums just around pi (a nearly flat vertex), either side of the series' range.
        for defect in [
            0.0, 1e-12, -1e-12, 1e-6, -3e-4, 0.01, -0.02, 0.0312, -0.0313, 0.05,
        ] {
            let halves = [0.9, 0.8, 0.7, std::f64::consts::PI - 2.4 + defect];
            let expected: f64 = halves.iter().sum();
            let got = half_angle_sum_fast(halves.iter().map(|h| [0.7 * h.cos(), 0.7 * h.sin()]))
                .expect("no underflow");
            assert!(
                (got - expected).abs() < 4e-16 * expected,
                "defect {defect}: {got} vs {expected}, {:e}",
                got - expected
            );
        }
    }

    #[test]
    fn half_angle_sums_unwrap_full_turns() {
        for n in [1usize, 3, 4, 7, 12, 40, 2000] {
            for base in [0.0, 0.3, std::f64::consts::FRAC_PI_2] {
                let halves: Vec<f64> = (0..n)
                    .map(|i| (base + 0.37 * i as f64).rem_euclid(std::f64::consts::FRAC_PI_2))
                    .collect();
                let expected: f64 = halves.iter().sum();
                // Scaled directions, magnitude in (0, 1].
                let corners = halves.iter().enumerate().map(|(i, h)| {
                    let m = 0.2 + 0.8 * ((i * 7 % 5) as f64 / 5.0);
                    [m * h.cos(), m * h.sin()]
                });
                let got = half_angle_sum(corners.clone());
                assert!(
                    (got - expected).abs() < 1e-12 * (1.0 + expected),
                    "n {n} base {base}: {got} vs {expected}"
                );
                // The fast variant gives up exactly when the product gets that small.
                match half_angle_sum_fast(corners) {
                    Some(fast) => assert_eq!(fast, got, "n {n}"),
                    None => assert!(n >= 40, "n {n}: the product of {n} factors is not tiny"),
                }
            }
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
