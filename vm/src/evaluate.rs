//! The iteration-stream executor: one pass computes every edge length, every half-angle
//! tangent, the gradient and the Hessian's CSC values (and, when asked, the energy), with no
//! mesh structure at hand.

use bdmorph_isa::{operand, Op, Program};

use crate::kernel::{half_angle_sum, half_angle_sum_fast, triangle_corners, Corner, INERT_CORNER};
use crate::lobachevsky::lobachevsky;

const EDGE_LEN_II: u16 = Op::EdgeLenIi as u16;
const EDGE_LEN_IB: u16 = Op::EdgeLenIb as u16;
const EDGE_LEN_BB: u16 = Op::EdgeLenBb as u16;
const TRIANGLE: u16 = Op::Triangle as u16;
const TRIANGLE_INERT: u16 = Op::TriangleInert as u16;
const VERTEX_INFO: u16 = Op::VertexInfo as u16;

/// Buffers the iteration stream writes; all sized once from the program.
pub(crate) struct Registers<'a> {
    pub l0: &'a [f64],
    pub u: &'a [f64],
    pub scale: &'a [f64],
    pub len: &'a mut [f64],
    pub log_len: &'a mut [f64],
    pub temps: &'a mut [Corner],
    pub grad: &'a mut [f64],
    pub hvals: &'a mut [f64],
}

/// The CETM energy from one pass (up to a constant: triangles with only boundary vertices are
/// left out), and the sum of the magnitudes of its terms, a scale for its round-off.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Energy {
    pub value: f64,
    pub magnitude: f64,
}

/// The half-angle directions of `n` corners whose temporaries `code` names from `*pc` on
/// (back-offsets from `ti`), advancing `*pc`.
#[inline(always)]
fn corner_directions<'a>(
    code: &'a [u16],
    pc: &'a mut usize,
    temps: &'a [Corner],
    ti: usize,
    n: usize,
) -> impl Iterator<Item = [f64; 2]> + 'a {
    (0..n).map(move |_| {
        let c = temps[ti - operand::read(code, pc) as usize];
        [c[0], c[1]]
    })
}

/// Runs the iteration stream of a verified program.
///
/// Besides gradient and Hessian it sums the energy
/// `E(u) = sum_T [ sum_corners (alpha / 2 - pi / 4) lambda_opp + Л(alpha) ] + pi sum_k u_k`,
/// with `lambda = 2 ln L` the scaled log length of the edge opposite each corner, so that
/// `dE/du_k = pi - (1/2) sum alpha` is the gradient. Degenerate triangles take angles 0 and pi,
/// which is the convex, C^1 extension of the CETM paper.
///
/// With `ENERGY = false` the energy (and the log lengths only it needs) is left out. The VM
/// runs that pass from the decoded plan instead ([`crate::plan`]), which computes the same
/// bits; this interpreter runs the pass with the energy, and is the plan's reference in tests.
///
/// Operand indices are bounds-checked by ordinary slice indexing: a verified program never
/// fails them. A variant with unchecked indexing was measured (10K-vertex disk, 57-62 ns per
/// triangle either way): no gain, so none is used.
pub(crate) fn run<const ENERGY: bool>(program: &Program, r: Registers<'_>) -> Energy {
    let code = program.iteration();
    let col_ptr = &program.hessian().col_ptr;
    let Registers {
        l0,
        u,
        scale,
        len,
        log_len,
        temps,
        grad,
        hvals,
    } = r;
    let mut energy = Energy::default();
    let (mut pc, mut li, mut ti, mut k) = (0usize, 0usize, 0usize, 0usize);
    let unknown = |k: usize, zz: u32| (k as i64 + operand::unzigzag(zz)) as usize;
    while pc < code.len() {
        let op = code[pc];
        pc += 1;
        match op {
            EDGE_LEN_II => {
                let a = unknown(k, operand::read(code, &mut pc));
                let b = unknown(k, operand::read(code, &mut pc));
                len[li] = l0[li] * scale[a] * scale[b];
                if ENERGY {
                    log_len[li] = len[li].ln();
                }
                li += 1;
            }
            EDGE_LEN_IB => {
                let a = unknown(k, operand::read(code, &mut pc));
                len[li] = l0[li] * scale[a];
                if ENERGY {
                    log_len[li] = len[li].ln();
                }
                li += 1;
            }
            EDGE_LEN_BB => {
                len[li] = l0[li];
                if ENERGY {
                    log_len[li] = len[li].ln();
                }
                li += 1;
            }
            TRIANGLE => {
                let e = [
                    li - operand::read(code, &mut pc) as usize,
                    li - operand::read(code, &mut pc) as usize,
                    li - operand::read(code, &mut pc) as usize,
                ];
                let corners = triangle_corners([len[e[0]], len[e[1]], len[e[2]]]);
                if ENERGY {
                    for (c, corner) in corners.iter().enumerate() {
                        let half = corner[1].atan2(corner[0]);
                        let opposite = e[(c + 1) % 3];
                        let linear = (half - std::f64::consts::FRAC_PI_4) * 2.0 * log_len[opposite];
                        let lob = lobachevsky(2.0 * half);
                        energy.value += linear + lob;
                        energy.magnitude += linear.abs() + lob.abs();
                    }
                }
                temps[ti..ti + 3].copy_from_slice(&corners);
                ti += 3;
            }
            TRIANGLE_INERT => {
                // Its operands name edges it does not read: the corners are inert.
                for _ in 0..3 {
                    operand::read(code, &mut pc);
                }
                temps[ti..ti + 3].fill(INERT_CORNER);
                ti += 3;
            }
            VERTEX_INFO => {
                let n = operand::read(code, &mut pc) as usize;
                let m = operand::read(code, &mut pc) as usize;
                let first_corner = pc;
                let angle =
                    match half_angle_sum_fast(corner_directions(code, &mut pc, temps, ti, n)) {
                        Some(angle) => angle,
                        None => {
                            let mut again = first_corner;
                            half_angle_sum(corner_directions(code, &mut again, temps, ti, n))
                        }
                    };
                grad[k] = std::f64::consts::PI - angle;
                let col = col_ptr[k] as usize;
                let mut diag = 0.0;
                for j in 0..n {
                    let a = temps[ti - operand::read(code, &mut pc) as usize][2];
                    let b = temps[ti - operand::read(code, &mut pc) as usize][2];
                    let w = 0.25 * (a + b);
                    diag += w;
                    if j < m {
                        hvals[col + 1 + j] = -w;
                    }
                }
                debug_assert!(diag.is_finite() && grad[k].is_finite(), "unknown {k}");
                hvals[col] = diag;
                if ENERGY {
                    energy.value += std::f64::consts::PI * u[k];
                    energy.magnitude += (std::f64::consts::PI * u[k]).abs();
                }
                k += 1;
            }
            _ => unreachable!(
                "verified program has an invalid opcode {op} at word {}",
                pc - 1
            ),
        }
    }
    energy
}
