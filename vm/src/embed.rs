//! The embed-stream executor: lays a flat metric out in the plane.

use bdmorph_isa::{EmbedStep, Program};

use crate::kernel::cos_sin;

#[inline(always)]
fn rotate(d: [f64; 2], [c, s]: [f64; 2]) -> [f64; 2] {
    [c * d[0] - s * d[1], s * d[0] + c * d[1]]
}

#[inline(always)]
fn neg(d: [f64; 2]) -> [f64; 2] {
    [-d[0], -d[1]]
}

/// Cosines and sines of a triangle's angles at `a` and at `b`, from its side lengths `ab`,
/// `bc` and `ca`, with two divisions and one square root: the sides are scaled by `1 / ab`
/// (so the arithmetic is scale-free), and with `S = 2s`, `X = 2(s - bc)`, `Y = 2(s - ca)`,
/// `Z = 2(s - ab)` in those units, `cos A = (SX - YZ) / 4ca`, `sin A = sqrt(SXYZ) / 2ca`,
/// `cos B = (SY - ZX) / 4bc`, `sin B = sqrt(SXYZ) / 2bc` (twice the area, by Heron's formula,
/// over the two sides). `None` when the triangle is degenerate, violates the triangle
/// inequality, or its scaled sides are out of range; [`cos_sin`] then handles it.
#[inline(always)]
fn corner_turns(ab: f64, bc: f64, ca: f64) -> Option<[f64; 4]> {
    let r = 1.0 / ab;
    let (beta, gamma) = (bc * r, ca * r);
    let big_s = 1.0 + beta + gamma;
    let (x, y, z) = (1.0 - beta + gamma, 1.0 + beta - gamma, beta + gamma - 1.0);
    let q = 0.25 / (beta * gamma);
    // Written so that NaN fails every comparison.
    if !(x > 0.0 && y > 0.0 && z > 0.0 && q < f64::INFINITY) {
        return None;
    }
    // Eight times the area (Heron: 16 area^2 = SXYZ).
    let eight_area = 2.0 * (big_s * x * y * z).sqrt();
    let (over_ca, over_bc) = (beta * q, gamma * q);
    Some([
        (big_s * x - y * z) * over_ca,
        eight_area * over_ca,
        (big_s * y - z * x) * over_bc,
        eight_area * over_bc,
    ])
}

/// Places every vertex: `p0` at `anchor`, `p1` along the unit vector `direction`, then each
/// triangle's third vertex from the edge directions propagated through corner angles.
/// `dirs` holds one direction per edge slot (scratch), `out` one position per vertex.
pub(crate) fn run(
    program: &Program,
    len: &[f64],
    dirs: &mut [[f64; 2]],
    anchor: [f64; 2],
    direction: [f64; 2],
    out: &mut [[f64; 2]],
) {
    let root = program.embed_root();
    let (p0, p1, e) = (root.p0 as usize, root.p1 as usize, root.edge as usize);
    out[p0] = anchor;
    out[p1] = [
        anchor[0] + len[e] * direction[0],
        anchor[1] + len[e] * direction[1],
    ];
    dirs[e] = if program.edges()[e][0] == root.p0 {
        direction
    } else {
        neg(direction)
    };
    for s in program.embed() {
        let stored = |slot: u32, rev: u32| {
            let d = dirs[slot as usize];
            if s.flags & rev != 0 {
                neg(d)
            } else {
                d
            }
        };
        let d_ab = stored(s.e_ab, EmbedStep::REV_AB);
        let (l_ab, l_bc, l_ca) = (
            len[s.e_ab as usize],
            len[s.e_bc as usize],
            len[s.e_ca as usize],
        );
        // Counter-clockwise triangle: a -> c is a -> b turned left by the angle at a;
        // b -> c is b -> a turned right by the angle at b.
        let (d_ac, d_bc) = match corner_turns(l_ab, l_bc, l_ca) {
            Some([ca, sa, cb, sb]) => (rotate(d_ab, [ca, sa]), rotate(neg(d_ab), [cb, -sb])),
            None => {
                let d_ac = rotate(d_ab, cos_sin(l_ab, l_ca, l_bc));
                let [cb, sb] = cos_sin(l_ab, l_bc, l_ca);
                (d_ac, rotate(neg(d_ab), [cb, -sb]))
            }
        };
        dirs[s.e_ca as usize] = if s.flags & EmbedStep::REV_CA != 0 {
            d_ac
        } else {
            neg(d_ac)
        };
        dirs[s.e_bc as usize] = if s.flags & EmbedStep::REV_BC != 0 {
            neg(d_bc)
        } else {
            d_bc
        };
        if s.flags & EmbedStep::PLACE != 0 {
            let (a, b) = (out[s.a as usize], out[s.b as usize]);
            // The mean of the two ways to reach c halves the round-off of either.
            out[s.c as usize] = [
                0.5 * (a[0] + l_ca * d_ac[0] + b[0] + l_bc * d_bc[0]),
                0.5 * (a[1] + l_ca * d_ac[1] + b[1] + l_bc * d_bc[1]),
            ];
            debug_assert!(
                out[s.c as usize][0].is_finite() && out[s.c as usize][1].is_finite(),
                "vertex {} placed at a non-finite position",
                s.c
            );
        }
    }
}

/// Counts the triangles whose signed area in `positions` is not positive, over the embed
/// stream's triangles (one per face, counter-clockwise as compiled).
pub(crate) fn count_flipped(program: &Program, positions: &[[f64; 2]], parallel: bool) -> usize {
    let flipped = |s: &&EmbedStep| {
        let (a, b, c) = (
            positions[s.a as usize],
            positions[s.b as usize],
            positions[s.c as usize],
        );
        let area2 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        // NaN areas count as flipped.
        area2.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    };
    if parallel {
        use rayon::prelude::*;
        program
            .embed()
            .par_iter()
            .with_min_len(crate::plan::CHUNK)
            .filter(flipped)
            .count()
    } else {
        program.embed().iter().filter(flipped).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both corners' turns through [`cos_sin`], the reference the fast formulas must match.
    fn reference(ab: f64, bc: f64, ca: f64) -> [f64; 4] {
        let [ca_cos, ca_sin] = cos_sin(ab, ca, bc);
        let [cb_cos, cb_sin] = cos_sin(ab, bc, ca);
        [ca_cos, ca_sin, cb_cos, cb_sin]
    }

    #[test]
    fn corner_turns_match_the_corner_by_corner_formulas() {
        // A fixed pseudo-random walk over shapes from needles to near-equilateral, at scales
        // from 1e-200 to 1e200 (the arithmetic is scaled by the first side).
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut checked = 0;
        for scale in [1e-200, 1e-30, 1.0, 1e30, 1e200] {
            for _ in 0..2000 {
                let (ab, bc) = (0.05 + next(), 0.05 + next());
                let ca = (ab - bc).abs() + (ab + bc - (ab - bc).abs()) * (0.001 + 0.998 * next());
                let (ab, bc, ca) = (ab * scale, bc * scale, ca * scale);
                let fast = corner_turns(ab, bc, ca).expect("a proper triangle");
                let slow = reference(ab, bc, ca);
                for (f, s) in fast.iter().zip(&slow) {
                    assert!((f - s).abs() < 1e-12, "{ab} {bc} {ca}: {fast:?} {slow:?}");
                }
                let [c, s, ..] = fast;
                assert!((c * c + s * s - 1.0).abs() < 1e-13);
                checked += 1;
            }
        }
        assert_eq!(checked, 10_000);
        let right = corner_turns(3.0, 5.0, 4.0).expect("3-4-5");
        // Right angle at a (opposite the hypotenuse bc = 5), cos B = 3/5.
        assert!(right[0].abs() < 1e-15 && (right[1] - 1.0).abs() < 1e-15);
        assert!((right[2] - 0.6).abs() < 1e-15 && (right[3] - 0.8).abs() < 1e-15);
    }

    #[test]
    fn degenerate_triangles_fall_back_to_the_corner_by_corner_formulas() {
        for (ab, bc, ca) in [
            (1.0, 1.0, 2.0),
            (1.0, 1.0, 2.5),
            (1.0, 3.0, 1.0),
            (0.0, 1.0, 1.0),
            (0.0, 0.0, 0.0),
            (1.0, 0.0, 1.0),
            (f64::NAN, 1.0, 1.0),
            (1.0, f64::INFINITY, 1.0),
            (f64::INFINITY, 1.0, 1.0),
            (1e300, 1e-300, 1e300),
        ] {
            assert_eq!(corner_turns(ab, bc, ca), None, "{ab} {bc} {ca}");
        }
    }
}
