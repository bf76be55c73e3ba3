//! The pieces of a mesh and their boundary loops, for meshes that are not one disk: several
//! pieces are compiled one by one, and a piece's holes are filled before it is compiled.

use crate::error::CompileError;
use crate::topology::{Topology, NONE};

/// One connected piece (faces connected through shared edges) of a manifold mesh.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Piece {
    /// Its faces, in increasing order (0-based indices into the mesh's faces).
    pub faces: Vec<u32>,
    /// Its vertices, in increasing order.
    pub vertices: Vec<u32>,
    /// Its boundary loops, each as the vertices met walking its boundary edges in the
    /// direction the faces give them (the piece on the left), starting from the loop's
    /// lowest-numbered half-edge; loops in the order of their first half-edge.
    pub loops: Vec<Vec<u32>>,
    /// Its Euler characteristic, vertices minus edges plus faces: `2 - loops` for a disk
    /// with holes (a planar piece).
    pub euler: i64,
}

/// Splits a manifold, consistently oriented triangle mesh into its pieces, each with its
/// boundary loops, in the order of their first face. Refuses what [`crate::compile`] refuses
/// except several pieces and holes: a closed piece ([`CompileError::ClosedSurface`]) and a
/// piece with handles ([`CompileError::NotADisk`], loops and Euler characteristic of a
/// surface that is not a disk with holes) are refused too.
///
/// ```
/// // Two triangles apart.
/// let pieces = bdmorph_compiler::pieces(6, &[[0, 1, 2], [3, 4, 5]]).unwrap();
/// assert_eq!(pieces.len(), 2);
/// assert_eq!(pieces[1].vertices, [3, 4, 5]);
/// assert_eq!(pieces[1].loops, [vec![3, 4, 5]]);
/// ```
pub fn pieces(n_vertices: usize, faces: &[[u32; 3]]) -> Result<Vec<Piece>, CompileError> {
    let topo = Topology::manifold(n_vertices, faces)?;
    let nf = faces.len();
    let mut piece_of = vec![NONE; nf];
    let mut pieces = Vec::new();
    let mut stack = Vec::new();
    for seed in 0..nf {
        if piece_of[seed] != NONE {
            continue;
        }
        let id = pieces.len() as u32;
        piece_of[seed] = id;
        stack.push(seed as u32);
        let mut members = Vec::new();
        while let Some(f) = stack.pop() {
            members.push(f);
            for i in 0..3 {
                let t = topo.twin[f as usize * 3 + i];
                if t != NONE && piece_of[t as usize / 3] == NONE {
                    piece_of[t as usize / 3] = id;
                    stack.push(t / 3);
                }
            }
        }
        members.sort_unstable();
        let mut vertices: Vec<u32> = members.iter().flat_map(|&f| faces[f as usize]).collect();
        vertices.sort_unstable();
        vertices.dedup();
        pieces.push(Piece {
            faces: members,
            vertices,
            loops: Vec::new(),
            euler: 0,
        });
    }
    // A vertex shared by two pieces would have two fans: the manifold check refuses it, so
    // every vertex belongs to exactly one piece.
    let mut on_loop = vec![false; topo.twin.len()];
    for he in 0..topo.twin.len() as u32 {
        if topo.twin[he as usize] != NONE || on_loop[he as usize] {
            continue;
        }
        let mut cycle = Vec::new();
        let mut cur = he;
        while !on_loop[cur as usize] {
            on_loop[cur as usize] = true;
            cycle.push(topo.from(cur));
            cur = topo.first_out[topo.to(cur) as usize];
        }
        pieces[piece_of[he as usize / 3] as usize].loops.push(cycle);
    }
    let mut edges = vec![0i64; pieces.len()];
    for &[a, _] in &topo.edges {
        // Both ends of an edge lie in the same piece; find it through a face of `a`.
        let he = topo.first_out[a as usize];
        edges[piece_of[he as usize / 3] as usize] += 1;
    }
    for (piece, e) in pieces.iter_mut().zip(edges) {
        piece.euler = piece.vertices.len() as i64 - e + piece.faces.len() as i64;
        let loops = piece.loops.len();
        if loops == 0 {
            return Err(CompileError::ClosedSurface { euler: piece.euler });
        }
        if piece.euler != 2 - loops as i64 {
            return Err(CompileError::NotADisk {
                euler: piece.euler,
                loops,
            });
        }
    }
    Ok(pieces)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square annulus: an outer square 0..3 and an inner one 4..7, eight triangles.
    fn annulus() -> Vec<[u32; 3]> {
        let mut faces = Vec::new();
        for i in 0..4u32 {
            let (o0, o1, i0, i1) = (i, (i + 1) % 4, 4 + i, 4 + (i + 1) % 4);
            faces.push([o0, o1, i1]);
            faces.push([o0, i1, i0]);
        }
        faces
    }

    #[test]
    fn an_annulus_is_one_piece_with_two_loops() {
        let pieces = pieces(8, &annulus()).unwrap();
        assert_eq!(pieces.len(), 1);
        let p = &pieces[0];
        assert_eq!(p.euler, 0);
        assert_eq!(p.loops.len(), 2);
        assert_eq!(p.loops[0], [0, 1, 2, 3], "outer loop, counter-clockwise");
        let mut inner = p.loops[1].clone();
        let start = inner.iter().position(|&v| v == 4).unwrap();
        inner.rotate_left(start);
        assert_eq!(inner, [4, 7, 6, 5], "the hole's loop runs the other way");
    }

    #[test]
    fn pieces_are_split_and_closed_or_bad_ones_refused() {
        let mut faces = annulus();
        faces.extend([[8, 9, 10], [8, 10, 11]]);
        let pieces = pieces(12, &faces).unwrap();
        assert_eq!(pieces.len(), 2);
        assert_eq!(pieces[1].faces, [8, 9]);
        assert_eq!(pieces[1].vertices, [8, 9, 10, 11]);
        assert_eq!(pieces[1].loops.len(), 1);
        // A tetrahedron is closed.
        let tet = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
        assert!(matches!(
            super::pieces(4, &tet),
            Err(CompileError::ClosedSurface { euler: 2 })
        ));
        // Two triangles sharing only a vertex: a non-manifold vertex.
        assert!(matches!(
            super::pieces(5, &[[0, 1, 2], [0, 3, 4]]),
            Err(CompileError::NonManifoldVertex { .. })
        ));
    }
}
