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
        let d_ac = rotate(d_ab, cos_sin(l_ab, l_ca, l_bc));
        let [cb, sb] = cos_sin(l_ab, l_bc, l_ca);
        let d_bc = rotate(neg(d_ab), [cb, -sb]);
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
pub(crate) fn count_flipped(program: &Program, positions: &[[f64; 2]]) -> usize {
    program
        .embed()
        .iter()
        .filter(|s| {
            let (a, b, c) = (
                positions[s.a as usize],
                positions[s.b as usize],
                positions[s.c as usize],
            );
            let area2 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            // NaN areas count as flipped.
            area2.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        })
        .count()
}
