//! The BDMORPH instruction set: the one format shared by the compiler (which writes programs)
//! and the VM (which executes them without ever seeing the mesh).
//!
//! A [`Program`] holds four parts, all produced once per mesh by `bdmorph-compiler`:
//!
//! * the **init stream** ([`Program::edges`]): one vertex pair per edge slot, in the order the
//!   iteration stream consumes them, used to compute the interpolated metric `l0` for a frame;
//! * the **iteration stream** ([`Program::iteration`]): a compact sequence of 16-bit words
//!   (see [`Op`] and [`operand`]) run once per Newton iteration. It writes every edge length,
//!   every half-angle tangent, every gradient entry and every value of the Hessian's CSC array
//!   exactly once, in streaming order;
//! * the **Hessian pattern** ([`HessianPattern`]): the lower triangle of the symmetric Hessian in
//!   compressed sparse column form; the VM computes its symbolic Cholesky factorisation once;
//! * the **embed stream** ([`EmbedRoot`] and [`EmbedStep`]s): lays the flat metric out in the
//!   plane by propagating edge directions across triangles.
//!
//! A `Program` can only be built through [`Program::from_parts`], which runs the verifier
//! pass: every operand index, every CSC slot and every embed dependency is checked once, so the
//! executor can trust the program. [`Program::to_bytes`] and [`Program::from_bytes`] store a
//! program in a file with a versioned header, the [`MeshKey`] of its mesh and a checksum (see
//! [`mod@file`]); loading ends with the same verifier.
//!
//! ```
//! use bdmorph_isa::{Op, operand};
//! let mut code = Vec::new();
//! code.push(Op::EdgeLenBb as u16);
//! operand::push(&mut code, 70_000); // does not fit in 16 bits: escaped
//! assert_eq!(code.len(), 4);
//! let mut pc = 1;
//! assert_eq!(operand::read_checked(&code, &mut pc), Some(70_000));
//! ```
#![warn(missing_docs)]

mod disasm;
pub mod file;
#[cfg(test)]
mod fixture;
pub mod operand;
mod program;
mod verify;

pub use disasm::disassemble;
pub use file::{FileSizes, LoadError, MeshKey};
pub use program::{EmbedRoot, EmbedStep, HessianPattern, Program, ProgramParts, ProgramStats};
pub use verify::{instructions, VerifyError};

/// Opcodes of the iteration stream. Each instruction is one opcode word followed by its
/// operands, each encoded with [`operand::push`]. Names say the operand kinds:
/// `I` = an interior vertex (it has an unknown `u`), `B` = a boundary vertex (`u = 0`).
///
/// Implicit destinations: the n-th `EdgeLen*` writes edge slot n, the n-th `Triangle` writes
/// temporaries 3n, 3n + 1 and 3n + 2, and the k-th `VertexInfo` writes gradient entry k and
/// column k of the Hessian.
#[repr(u16)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Op {
    /// `EDGE_LEN.II da db`: `L[n] = l0[n] * s[k + da] * s[k + db]`, where `s = exp(u / 2)`,
    /// `k` is the number of `VertexInfo` executed so far and `da`, `db` are zigzag-encoded
    /// signed offsets (see [`operand::zigzag`]).
    EdgeLenIi = 1,
    /// `EDGE_LEN.IB da`: edge between an interior and a boundary vertex: `L[n] = l0[n] * s[k + da]`.
    EdgeLenIb = 2,
    /// `EDGE_LEN.BB`: edge between two boundary vertices: `L[n] = l0[n]`.
    EdgeLenBb = 3,
    /// `TRIANGLE e0 e1 e2`: a triangle with sides `L[e0]`, `L[e1]`, `L[e2]` in
    /// counter-clockwise order; each operand is a back-offset `n_edges_so_far - slot` (>= 1).
    /// Writes one temporary per corner, corner `c` being the one opposite side `e(c+1 mod 3)`
    /// (between sides `e(c)` and `e(c+2 mod 3)`): the direction `(cos, sin)` of its half
    /// angle, scaled by a positive factor of at most 1, and the cotangent of its angle. All
    /// three from one square root (the inradius), with no trigonometric call.
    Triangle = 4,
    /// `TRIANGLE.INERT e0 e1 e2`: a triangle that is there for the topology only (a hole's
    /// filling whose outline closes by its own turning, not by its triangles' metric). Its
    /// operands are `Triangle`'s, but its three temporaries are inert corners: a half angle of
    /// 0 (direction `(1, 0)`) and a cotangent of 0, so it adds nothing to any gradient entry
    /// or Hessian value, and nothing to the energy. The embed stream never walks through it.
    TriangleInert = 7,
    /// `VERTEX_INFO n m  i_1..i_n  (a_1 b_1)..(a_n b_n)`: interior vertex `k` of valence `n`.
    /// `i_*` are the temporaries of its `n` corners (back-offsets into `T`), giving
    /// `g[k] = pi - sum(half angles)`; each pair `(a_j, b_j)` are the two corners opposite edge
    /// `k j`, giving `w_kj = (cot a + cot b) / 4`. The diagonal `sum w_kj` goes to the first value
    /// slot of column `k`; the first `m` pairs are the neighbours below the diagonal, in row
    /// order, and write `-w_kj` to the following `m` slots of column `k`.
    VertexInfo = 6,
}

impl Op {
    /// Decodes an opcode word.
    pub fn from_word(word: u16) -> Option<Op> {
        Some(match word {
            1 => Op::EdgeLenIi,
            2 => Op::EdgeLenIb,
            3 => Op::EdgeLenBb,
            4 => Op::Triangle,
            6 => Op::VertexInfo,
            7 => Op::TriangleInert,
            _ => return None,
        })
    }

    /// The mnemonic used by the disassembler.
    pub fn mnemonic(self) -> &'static str {
        match self {
            Op::EdgeLenIi => "edge_len.ii",
            Op::EdgeLenIb => "edge_len.ib",
            Op::EdgeLenBb => "edge_len.bb",
            Op::Triangle => "triangle",
            Op::TriangleInert => "triangle.inert",
            Op::VertexInfo => "vertex_info",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn opcode_words_round_trip() {
        for op in [
            Op::EdgeLenIi,
            Op::EdgeLenIb,
            Op::EdgeLenBb,
            Op::Triangle,
            Op::TriangleInert,
            Op::VertexInfo,
        ] {
            assert_eq!(Op::from_word(op as u16), Some(op));
        }
        assert_eq!(Op::from_word(0), None);
        assert_eq!(Op::from_word(5), None, "retired: HALF_TAN.COT");
        assert_eq!(Op::from_word(8), None);
    }

    #[test]
    fn embed_step_is_seven_words() {
        assert_eq!(std::mem::size_of::<EmbedStep>(), 28);
    }
}
