//! The disassembler: a program as readable text, with every relative operand resolved to the
//! absolute slot it names.

use std::fmt::Write as _;

use crate::program::{EmbedStep, Program};
use crate::verify::{decode, Instr};
use crate::Op;

/// Renders a program as text: a header with its sizes, then the init, iteration and embed
/// streams, one instruction per line. Edge slots print as `L`, temporaries as `T`, unknowns as
/// `u` (with their mesh vertex `v`), Hessian value slots as `H`.
pub fn disassemble(p: &Program) -> String {
    let mut out = String::new();
    let st = p.stats();
    // Writing into a String cannot fail.
    let _ = writeln!(
        out,
        "; {} vertices, {} faces, {} unknowns, {} edge slots ({} written per iteration), {} temporaries",
        st.vertices,
        st.faces,
        st.unknowns,
        st.edges,
        p.n_iter_edges(),
        p.n_temps()
    );
    let _ = writeln!(
        out,
        "; iteration stream {} bytes ({:.1} per face); Hessian {}x{} lower, {} values",
        st.iteration_bytes, st.iteration_bytes_per_face, st.unknowns, st.unknowns, st.hessian_nnz
    );
    let _ = writeln!(out, "init:");
    for (slot, [a, b]) in p.edges().iter().enumerate() {
        let _ = writeln!(out, "  L{slot} = |v{a} v{b}|");
    }
    let _ = writeln!(out, "iteration:");
    let uv = |k: i64| -> String {
        match usize::try_from(k)
            .ok()
            .and_then(|k| p.unknown_vertex().get(k))
        {
            Some(v) => format!("u{k}(v{v})"),
            None => format!("u{k}(?)"),
        }
    };
    let code = p.iteration();
    let (mut pc, mut li, mut ti, mut k) = (0usize, 0i64, 0i64, 0i64);
    while pc < code.len() {
        let at = pc;
        let Some(instr) = decode(code, &mut pc) else {
            let _ = writeln!(out, "  {at:04}  <undecodable>");
            break;
        };
        match instr {
            Instr::EdgeLen { op, offsets } => {
                let args = match op {
                    Op::EdgeLenIi => format!("{} {}", uv(k + offsets[0]), uv(k + offsets[1])),
                    Op::EdgeLenIb => uv(k + offsets[0]),
                    _ => String::new(),
                };
                let _ = writeln!(out, "  {at:04}  {:<12} {args:<24} -> L{li}", op.mnemonic());
                li += 1;
            }
            Instr::Triangle { back, inert } => {
                let args = format!(
                    "L{} L{} L{}",
                    li - i64::from(back[0]),
                    li - i64::from(back[1]),
                    li - i64::from(back[2])
                );
                let _ = writeln!(
                    out,
                    "  {at:04}  {:<12} {args:<24} -> T{ti}..T{}",
                    if inert {
                        Op::TriangleInert.mnemonic()
                    } else {
                        Op::Triangle.mnemonic()
                    },
                    ti + 2
                );
                ti += 3;
            }
            Instr::VertexInfo {
                lower,
                inner,
                pairs,
            } => {
                let h = p.hessian();
                let col = usize::try_from(k)
                    .ok()
                    .and_then(|k| h.col_ptr.get(k).copied())
                    .unwrap_or(0);
                let angles: Vec<String> = inner
                    .iter()
                    .map(|&b| format!("T{}", ti - i64::from(b)))
                    .collect();
                let _ = writeln!(
                    out,
                    "  {at:04}  {:<12} {} angles[{}] diag -> H{col}",
                    Op::VertexInfo.mnemonic(),
                    uv(k),
                    angles.join(" ")
                );
                for (j, pr) in pairs.iter().enumerate() {
                    let (a, b) = (ti - i64::from(pr[0]), ti - i64::from(pr[1]));
                    if (j as u32) < lower {
                        let slot = col as usize + 1 + j;
                        let row = h.row_idx.get(slot).copied().unwrap_or(u32::MAX);
                        let _ = writeln!(
                            out,
                            "        {:<12} w(T{a} T{b}) -> H{slot} (row {})",
                            "",
                            uv(i64::from(row))
                        );
                    } else {
                        let _ = writeln!(out, "        {:<12} w(T{a} T{b}) -> diag", "");
                    }
                }
                k += 1;
            }
        }
    }
    let _ = writeln!(out, "embed:");
    let r = p.embed_root();
    let _ = writeln!(out, "  root  v{} v{} along L{}", r.p0, r.p1, r.edge);
    for s in p.embed() {
        let rev = |bit: u32| if s.flags & bit != 0 { "'" } else { "" };
        let place = if s.flags & EmbedStep::PLACE != 0 {
            "place"
        } else {
            "     "
        };
        let _ = writeln!(
            out,
            "  tri   v{} v{} v{}  {place}  L{}{} L{}{} L{}{}",
            s.a,
            s.b,
            s.c,
            s.e_ab,
            rev(EmbedStep::REV_AB),
            s.e_bc,
            rev(EmbedStep::REV_BC),
            s.e_ca,
            rev(EmbedStep::REV_CA)
        );
    }
    out
}
