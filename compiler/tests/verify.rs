//! The verifier rejects every kind of corrupted program the VM could be handed.

use bdmorph_compiler::compile;
use bdmorph_isa::{instructions, operand, EmbedStep, Op, Program, ProgramParts, VerifyError};

fn parts() -> ProgramParts {
    let mut pos = Vec::new();
    for j in 0..5 {
        for i in 0..5 {
            pos.push([f64::from(i), f64::from(j)]);
        }
    }
    let id = |i: u32, j: u32| j * 5 + i;
    let mut faces = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    compile(&pos, &faces).expect("compiles").to_parts()
}

fn first(p: &ProgramParts, op: Op) -> usize {
    instructions(&p.iteration)
        .expect("decodes")
        .into_iter()
        .find(|&(_, o)| o == op)
        .expect("the program has this instruction")
        .0
}

fn rejected(p: ProgramParts) -> VerifyError {
    Program::from_parts(p).expect_err("must be rejected")
}

#[test]
fn compiled_parts_round_trip() {
    let p = parts();
    let program = Program::from_parts(p.clone()).expect("valid");
    assert_eq!(program.to_parts(), p);
}

#[test]
fn corrupted_sizes_and_tables_are_rejected() {
    let mut p = parts();
    p.n_temps += 1;
    assert!(matches!(rejected(p), VerifyError::Sizes { .. }));

    // More vertices than the embed stream can place, refused before any table is sized by
    // the count (this one would take 16 GiB).
    let mut p = parts();
    p.n_vertices = u32::MAX;
    assert!(matches!(rejected(p), VerifyError::Sizes { .. }));
    let mut p = parts();
    p.n_vertices = p.embed.len() as u32 + 3;
    assert!(matches!(rejected(p), VerifyError::Sizes { .. }));

    let mut p = parts();
    p.edges[3] = [p.n_vertices, 0];
    assert!(matches!(rejected(p), VerifyError::BadEdge { slot: 3 }));

    let mut p = parts();
    p.unknown_vertex[1] = p.unknown_vertex[0];
    assert!(matches!(
        rejected(p),
        VerifyError::BadUnknown { unknown: 1 }
    ));

    let mut p = parts();
    p.hessian.row_idx[0] = 1;
    assert!(matches!(rejected(p), VerifyError::BadPattern { column: 0 }));

    let mut p = parts();
    let last = p.hessian.col_ptr.len() - 1;
    p.hessian.col_ptr[last] += 1;
    assert!(matches!(rejected(p), VerifyError::BadPattern { .. }));
}

#[test]
fn corrupted_streams_are_rejected() {
    // Unknown opcode.
    let mut p = parts();
    p.iteration[0] = 99;
    assert_eq!(rejected(p), VerifyError::Decode { pc: 0 });

    // Truncated stream.
    let mut p = parts();
    p.iteration.pop();
    assert!(matches!(rejected(p), VerifyError::Decode { .. }));

    // A triangle reading an edge slot not yet written.
    let mut p = parts();
    let pc = first(&p, Op::Triangle);
    p.iteration[pc + 1] = 1000;
    assert_eq!(rejected(p), VerifyError::Operand { pc });

    // An edge length naming the wrong unknown.
    let mut p = parts();
    let pc = first(&p, Op::EdgeLenIi);
    let mut probe = pc + 1;
    let zz = operand::read(&p.iteration, &mut probe);
    let off = operand::unzigzag(zz);
    p.iteration[pc + 1] = operand::zigzag(if off == 0 { 1 } else { 0 }) as u16;
    assert!(matches!(
        rejected(p),
        VerifyError::EdgeMismatch { .. } | VerifyError::Operand { .. }
    ));

    // Embed: a step using an edge direction not yet known, and a vertex placed twice.
    let mut p = parts();
    let n = p.embed.len();
    p.embed.swap(1, n - 1);
    assert!(matches!(rejected(p), VerifyError::Embed { .. }));
    let mut p = parts();
    let i = p
        .embed
        .iter()
        .position(|s| s.flags & EmbedStep::PLACE == 0)
        .expect("a non-placing step");
    p.embed[i].flags |= EmbedStep::PLACE;
    assert_eq!(rejected(p), VerifyError::Embed { step: i });
}
