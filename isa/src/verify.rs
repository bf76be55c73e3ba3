//! The verifier: checks every index a program can make the VM touch, once, so the executor can
//! run the streams without per-operand checks.

use crate::operand::{self, unzigzag};
use crate::program::{EmbedStep, Program};
use crate::Op;

/// Why a program was rejected. Programs from the compiler always pass; these errors guard
/// programs assembled by hand or loaded from bytes.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum VerifyError {
    /// A count does not fit the program's sizes.
    #[error("inconsistent sizes: {what}")]
    Sizes {
        /// What is inconsistent.
        what: &'static str,
    },
    /// An edge slot names a vertex out of range or the same vertex twice.
    #[error("edge slot {slot} is invalid")]
    BadEdge {
        /// The slot.
        slot: usize,
    },
    /// The unknowns do not name distinct vertices in range.
    #[error("unknown {unknown} names an invalid or repeated vertex")]
    BadUnknown {
        /// The unknown.
        unknown: usize,
    },
    /// The Hessian pattern is malformed at a column.
    #[error("Hessian pattern is malformed at column {column}")]
    BadPattern {
        /// The column.
        column: usize,
    },
    /// The iteration stream cannot be decoded at a word.
    #[error("iteration stream: cannot decode at word {pc}")]
    Decode {
        /// Word offset.
        pc: usize,
    },
    /// An operand of the iteration stream is out of range.
    #[error("iteration stream: operand out of range in the instruction at word {pc}")]
    Operand {
        /// Word offset of the instruction.
        pc: usize,
    },
    /// An edge-length instruction does not match the init stream's edge for its slot.
    #[error(
        "iteration stream: edge-length instruction at word {pc} does not match edge slot {slot}"
    )]
    EdgeMismatch {
        /// Word offset of the instruction.
        pc: usize,
        /// The slot it writes.
        slot: usize,
    },
    /// A vertex-info instruction's write count does not match its Hessian column.
    #[error("iteration stream: vertex info at word {pc} does not fill Hessian column {column}")]
    ColumnMismatch {
        /// Word offset of the instruction.
        pc: usize,
        /// The column.
        column: usize,
    },
    /// The embed stream uses an edge direction or a vertex before it is known, places a vertex
    /// twice, names an edge that does not join its vertices, or leaves a vertex unplaced.
    #[error("embed stream: invalid step {step}")]
    Embed {
        /// The step (`usize::MAX` for the root, the stream length for a missing vertex).
        step: usize,
    },
    /// The fill-reducing ordering is not a permutation of the unknowns.
    #[error("the fill-reducing ordering is not a permutation of the unknowns (entry {entry})")]
    BadOrdering {
        /// The first entry out of range or repeated; the ordering's length when that is not
        /// the number of unknowns.
        entry: usize,
    },
}

/// One decoded instruction of the iteration stream (used by the verifier and the disassembler;
/// the VM decodes in place).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Instr {
    EdgeLen {
        op: Op,
        offsets: [i64; 2],
    },
    Triangle {
        back: [u32; 3],
        /// `TRIANGLE.INERT`: the same operands, inert corners.
        inert: bool,
    },
    VertexInfo {
        lower: u32,
        inner: Vec<u32>,
        pairs: Vec<[u32; 2]>,
    },
}

/// Decodes the instruction at `*pc`, advancing it.
pub(crate) fn decode(code: &[u16], pc: &mut usize) -> Option<Instr> {
    let op = Op::from_word(*code.get(*pc)?)?;
    *pc += 1;
    let mut next = || operand::read_checked(code, pc);
    Some(match op {
        Op::EdgeLenIi => {
            let a = unzigzag(next()?);
            let b = unzigzag(next()?);
            Instr::EdgeLen {
                op,
                offsets: [a, b],
            }
        }
        Op::EdgeLenIb => Instr::EdgeLen {
            op,
            offsets: [unzigzag(next()?), 0],
        },
        Op::EdgeLenBb => Instr::EdgeLen {
            op,
            offsets: [0, 0],
        },
        Op::Triangle | Op::TriangleInert => Instr::Triangle {
            back: [next()?, next()?, next()?],
            inert: op == Op::TriangleInert,
        },
        Op::VertexInfo => {
            let n = next()? as usize;
            let lower = next()?;
            // The valence is bounded by the stream length; refuse absurd counts early.
            if n > code.len() {
                return None;
            }
            let mut inner = Vec::with_capacity(n);
            for _ in 0..n {
                inner.push(next()?);
            }
            let mut pairs = Vec::with_capacity(n);
            for _ in 0..n {
                pairs.push([next()?, next()?]);
            }
            Instr::VertexInfo {
                lower,
                inner,
                pairs,
            }
        }
    })
}

/// The offset and opcode of every instruction of an iteration stream, or the offset where it
/// cannot be decoded.
pub fn instructions(code: &[u16]) -> Result<Vec<(usize, Op)>, VerifyError> {
    let mut out = Vec::new();
    let mut pc = 0;
    while pc < code.len() {
        let at = pc;
        decode(code, &mut pc).ok_or(VerifyError::Decode { pc: at })?;
        out.push((
            at,
            Op::from_word(code[at]).ok_or(VerifyError::Decode { pc: at })?,
        ));
    }
    Ok(out)
}

fn check(ok: bool, err: VerifyError) -> Result<(), VerifyError> {
    if ok {
        Ok(())
    } else {
        Err(err)
    }
}

pub(crate) fn verify(p: &Program) -> Result<(), VerifyError> {
    let nv = p.n_vertices as usize;
    let ne = p.edges.len();
    let nu = p.unknown_vertex.len();
    check(p.n_faces > 0, VerifyError::Sizes { what: "no faces" })?;
    // The root places two vertices and each embed step at most one. Checked before any table
    // is sized by the vertex count, so that a bogus count cannot allocate gigabytes.
    check(
        nv <= p.embed.len().saturating_add(2),
        VerifyError::Sizes {
            what: "more vertices than the embed stream can place",
        },
    )?;
    check(
        (p.n_iter_edges as usize) <= ne,
        VerifyError::Sizes {
            what: "more iteration edges than edges",
        },
    )?;
    check(
        u32::try_from(ne).is_ok() && u32::try_from(nu).is_ok(),
        VerifyError::Sizes {
            what: "too many edges or unknowns",
        },
    )?;

    check(
        [p.iteration.len(), p.hessian.row_idx.len(), p.embed.len()]
            .iter()
            .all(|&n| u32::try_from(n).is_ok()),
        VerifyError::Sizes {
            what: "a stream longer than 2^32 - 1 entries",
        },
    )?;
    // The root places two vertices and each embed step at most one, and every vertex must be
    // placed: this bounds the vertex count by the program's own length before anything is
    // allocated per vertex (a loaded header could claim 2^32 vertices).
    check(
        nv <= p.embed.len().saturating_add(2),
        VerifyError::Sizes {
            what: "more vertices than the embed stream can place",
        },
    )?;

    // Unknowns: distinct vertices in range.
    let mut unknown_of = vec![u32::MAX; nv];
    for (k, &v) in p.unknown_vertex.iter().enumerate() {
        let slot = unknown_of
            .get_mut(v as usize)
            .ok_or(VerifyError::BadUnknown { unknown: k })?;
        check(*slot == u32::MAX, VerifyError::BadUnknown { unknown: k })?;
        *slot = k as u32;
    }

    // Init stream.
    for (slot, &[a, b]) in p.edges.iter().enumerate() {
        check(
            (a as usize) < nv && (b as usize) < nv && a != b,
            VerifyError::BadEdge { slot },
        )?;
        if slot >= p.n_iter_edges as usize {
            // Slots the iteration stream does not write must join boundary vertices.
            check(
                unknown_of[a as usize] == u32::MAX && unknown_of[b as usize] == u32::MAX,
                VerifyError::BadEdge { slot },
            )?;
        }
    }

    // Hessian pattern.
    let h = &p.hessian;
    check(
        h.col_ptr.len() == nu + 1 && h.col_ptr.first() == Some(&0),
        VerifyError::BadPattern { column: 0 },
    )?;
    check(
        h.col_ptr.last().map(|&x| x as usize) == Some(h.row_idx.len()),
        VerifyError::BadPattern { column: nu },
    )?;
    for k in 0..nu {
        let (s, e) = (h.col_ptr[k] as usize, h.col_ptr[k + 1] as usize);
        check(
            s < e && e <= h.row_idx.len(),
            VerifyError::BadPattern { column: k },
        )?;
        let rows = &h.row_idx[s..e];
        check(rows[0] as usize == k, VerifyError::BadPattern { column: k })?;
        check(
            rows.windows(2).all(|w| w[0] < w[1]) && rows.iter().all(|&r| (r as usize) < nu),
            VerifyError::BadPattern { column: k },
        )?;
    }

    // Iteration stream.
    let code = &p.iteration;
    let (mut pc, mut li, mut ti, mut k) = (0usize, 0usize, 0usize, 0usize);
    let mut inert_faces = 0usize;
    while pc < code.len() {
        let at = pc;
        let instr = decode(code, &mut pc).ok_or(VerifyError::Decode { pc: at })?;
        match instr {
            Instr::EdgeLen { op, offsets } => {
                check(
                    li < p.n_iter_edges as usize,
                    VerifyError::Operand { pc: at },
                )?;
                let [va, vb] = p.edges[li];
                let (ua, ub) = (unknown_of[va as usize], unknown_of[vb as usize]);
                let resolve = |off: i64| -> Result<u32, VerifyError> {
                    let idx = k as i64 + off;
                    if (0..nu as i64).contains(&idx) {
                        Ok(idx as u32)
                    } else {
                        Err(VerifyError::Operand { pc: at })
                    }
                };
                let mismatch = VerifyError::EdgeMismatch { pc: at, slot: li };
                match op {
                    Op::EdgeLenIi => {
                        let (x, y) = (resolve(offsets[0])?, resolve(offsets[1])?);
                        check((x, y) == (ua, ub) || (y, x) == (ua, ub), mismatch)?;
                    }
                    Op::EdgeLenIb => {
                        let x = resolve(offsets[0])?;
                        check(
                            (x == ua && ub == u32::MAX) || (x == ub && ua == u32::MAX),
                            mismatch,
                        )?;
                    }
                    _ => check(ua == u32::MAX && ub == u32::MAX, mismatch)?,
                }
                li += 1;
            }
            Instr::Triangle { back, inert } => {
                inert_faces += usize::from(inert);
                check(
                    ti + 3 <= p.n_temps as usize,
                    VerifyError::Operand { pc: at },
                )?;
                check(
                    back.iter().all(|&b| b >= 1 && (b as usize) <= li),
                    VerifyError::Operand { pc: at },
                )?;
                ti += 3;
            }
            Instr::VertexInfo {
                lower,
                inner,
                pairs,
            } => {
                check(k < nu, VerifyError::Operand { pc: at })?;
                let column_len = (h.col_ptr[k + 1] - h.col_ptr[k]) as usize;
                check(
                    lower as usize + 1 == column_len && lower as usize <= pairs.len(),
                    VerifyError::ColumnMismatch { pc: at, column: k },
                )?;
                let ok = |b: u32| b >= 1 && (b as usize) <= ti;
                check(
                    !inner.is_empty()
                        && inner.iter().all(|&b| ok(b))
                        && pairs.iter().all(|pr| ok(pr[0]) && ok(pr[1])),
                    VerifyError::Operand { pc: at },
                )?;
                k += 1;
            }
        }
    }
    check(
        li == p.n_iter_edges as usize && ti == p.n_temps as usize && k == nu,
        VerifyError::Sizes {
            what: "iteration stream does not write every edge slot, temporary and unknown",
        },
    )?;

    verify_ordering(p)?;
    verify_embed(p, inert_faces)
}

/// The ordering, when present, names every unknown exactly once.
fn verify_ordering(p: &Program) -> Result<(), VerifyError> {
    let Some(ordering) = &p.ordering else {
        return Ok(());
    };
    let nu = p.unknown_vertex.len();
    check(
        ordering.len() == nu,
        VerifyError::BadOrdering {
            entry: ordering.len(),
        },
    )?;
    let mut seen = vec![false; nu];
    for (entry, &old) in ordering.iter().enumerate() {
        let slot = seen
            .get_mut(old as usize)
            .ok_or(VerifyError::BadOrdering { entry })?;
        check(!*slot, VerifyError::BadOrdering { entry })?;
        *slot = true;
    }
    Ok(())
}

/// The embed stream of `p`, whose iteration stream has `inert_faces` inert triangles.
fn verify_embed(p: &Program, inert_faces: usize) -> Result<(), VerifyError> {
    let nv = p.n_vertices as usize;
    // One step per triangle that is not inert: the walk reaches every such face exactly once
    // (an inert one is computed by the iteration stream, so it is counted there once).
    check(
        p.embed.len() + inert_faces == p.n_faces as usize,
        VerifyError::Embed {
            step: p.embed.len(),
        },
    )?;
    let mut known = vec![false; p.edges.len()];
    let mut placed = vec![false; nv];
    let root = p.embed_root;
    let root_err = VerifyError::Embed { step: usize::MAX };
    let (p0, p1) = (root.p0 as usize, root.p1 as usize);
    check(p0 < nv && p1 < nv && p0 != p1, root_err.clone())?;
    let e = *p.edges.get(root.edge as usize).ok_or(root_err.clone())?;
    check(e == [root.p0, root.p1] || e == [root.p1, root.p0], root_err)?;
    known[root.edge as usize] = true;
    placed[p0] = true;
    placed[p1] = true;

    let joins = |slot: u32, from: u32, to: u32, rev: bool| -> bool {
        match p.edges.get(slot as usize) {
            Some(&e) => {
                if rev {
                    e == [to, from]
                } else {
                    e == [from, to]
                }
            }
            None => false,
        }
    };
    for (i, s) in p.embed.iter().enumerate() {
        let err = VerifyError::Embed { step: i };
        check(
            (s.a as usize) < nv
                && (s.b as usize) < nv
                && (s.c as usize) < nv
                && s.a != s.b
                && s.b != s.c
                && s.a != s.c
                && s.flags < 16,
            err.clone(),
        )?;
        check(
            joins(s.e_ab, s.a, s.b, s.flags & EmbedStep::REV_AB != 0)
                && joins(s.e_bc, s.b, s.c, s.flags & EmbedStep::REV_BC != 0)
                && joins(s.e_ca, s.c, s.a, s.flags & EmbedStep::REV_CA != 0),
            err.clone(),
        )?;
        check(
            known[s.e_ab as usize] && placed[s.a as usize] && placed[s.b as usize],
            err.clone(),
        )?;
        let place = s.flags & EmbedStep::PLACE != 0;
        check(place != placed[s.c as usize], err)?;
        placed[s.c as usize] = true;
        known[s.e_bc as usize] = true;
        known[s.e_ca as usize] = true;
    }
    check(
        placed.iter().all(|&x| x),
        VerifyError::Embed {
            step: p.embed.len(),
        },
    )
}

#[cfg(test)]
mod tests {
    use crate::fixture::hexagon_parts;
    use crate::{Program, VerifyError};

    #[test]
    fn the_fixture_is_valid() {
        let parts = hexagon_parts();
        let program = Program::from_parts(parts.clone()).expect("valid");
        assert_eq!(program.to_parts(), parts);
    }

    #[test]
    fn the_ordering_must_be_a_permutation_of_the_unknowns() {
        let with = |ordering: Option<Vec<u32>>| {
            let mut parts = hexagon_parts();
            parts.ordering = ordering;
            Program::from_parts(parts)
        };
        let program = with(Some(vec![0])).expect("the identity on one unknown");
        assert_eq!(program.ordering(), Some(&[0][..]));
        assert_eq!(with(None).expect("no ordering").ordering(), None);
        for (ordering, entry) in [(vec![], 0), (vec![0, 0], 2), (vec![1], 0)] {
            assert_eq!(
                with(Some(ordering)),
                Err(VerifyError::BadOrdering { entry })
            );
        }
    }

    #[test]
    fn a_huge_vertex_count_is_refused_before_allocating_per_vertex() {
        for n_vertices in [9, u32::MAX] {
            let mut parts = hexagon_parts();
            parts.n_vertices = n_vertices;
            assert!(matches!(
                Program::from_parts(parts),
                Err(VerifyError::Sizes { what }) if what.contains("embed stream can place")
            ));
        }
        // 8 vertices pass this bound (6 steps + 2) but vertex 7 is never placed.
        let mut parts = hexagon_parts();
        parts.n_vertices = 8;
        assert_eq!(
            Program::from_parts(parts),
            Err(VerifyError::Embed { step: 6 })
        );
    }
}
