//! Emits the iteration stream and the Hessian pattern.
//!
//! Interior vertices are numbered (as unknowns) in breadth-first order from the anchor. For
//! each one, in that order, the emitter first makes sure every triangle of its fan has been
//! computed (the missing edge lengths, then the triangle's corners), then
//! emits its `VERTEX_INFO`. Each command thus consumes results written shortly before it, and
//! gradient entries and Hessian columns are written in increasing order.

use bdmorph_isa::{operand, HessianPattern, Op};

use crate::topology::{prev, Topology, NONE};

/// The iteration stream with the numbering it relies on.
pub(crate) struct Emitted {
    pub code: Vec<u16>,
    /// Edge slot of each mesh edge.
    pub slot_of_edge: Vec<u32>,
    /// Mesh edges in slot order.
    pub edges: Vec<[u32; 2]>,
    pub n_iter_edges: u32,
    pub n_temps: u32,
    pub unknown_vertex: Vec<u32>,
    pub hessian: HessianPattern,
}

/// Vertices in breadth-first order from `root`, neighbours visited counter-clockwise.
pub(crate) fn bfs_vertices(topo: &Topology, root: u32) -> Vec<u32> {
    let n = topo.n_vertices();
    let mut seen = vec![false; n];
    let mut order = Vec::with_capacity(n);
    seen[root as usize] = true;
    order.push(root);
    let mut head = 0;
    while head < order.len() {
        let v = order[head];
        head += 1;
        let mut visit = |w: u32| {
            if !seen[w as usize] {
                seen[w as usize] = true;
                order.push(w);
            }
        };
        let mut last = NONE;
        for out in topo.fan(v) {
            visit(topo.to(out));
            last = out;
        }
        if topo.boundary[v as usize] && last != NONE {
            // The last neighbour of a boundary fan is only reached through prev().
            visit(topo.from(prev(last)));
        }
    }
    order
}

/// `inert` is empty or one flag per face: the inert ones are emitted as
/// `TRIANGLE.INERT`.
pub(crate) fn emit(topo: &Topology, order: &[u32], inert: &[bool]) -> Emitted {
    let nv = topo.n_vertices();
    let nf = topo.faces.len();

    let mut unknown_of = vec![NONE; nv];
    let mut unknown_vertex = Vec::new();
    for &v in order {
        if !topo.boundary[v as usize] {
            unknown_of[v as usize] = unknown_vertex.len() as u32;
            unknown_vertex.push(v);
        }
    }

    let mut code = Vec::with_capacity(nf * 24);
    let mut slot_of_edge = vec![NONE; topo.edges.len()];
    let mut edges = Vec::with_capacity(topo.edges.len());
    let mut temp_of_corner = vec![NONE; nf * 3];
    let mut face_done = vec![false; nf];
    let mut n_temps = 0u32;
    let mut col_ptr = Vec::with_capacity(unknown_vertex.len() + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0u32);
    let mut lower: Vec<(u32, [u32; 2])> = Vec::new();
    let mut other: Vec<[u32; 2]> = Vec::new();
    let mut inner: Vec<u32> = Vec::new();

    for (k, &v) in unknown_vertex.iter().enumerate() {
        let k = k as u32;
        // 1. Compute the fan's triangles that are not computed yet.
        for out in topo.fan(v) {
            let f = out / 3;
            if face_done[f as usize] {
                continue;
            }
            face_done[f as usize] = true;
            for i in 0..3 {
                let he = f * 3 + i;
                let e = topo.edge_of[he as usize] as usize;
                if slot_of_edge[e] != NONE {
                    continue;
                }
                slot_of_edge[e] = edges.len() as u32;
                let [a, b] = topo.edges[e];
                edges.push([a, b]);
                let (ua, ub) = (unknown_of[a as usize], unknown_of[b as usize]);
                let rel = |u: u32| operand::zigzag(i64::from(u) - i64::from(k));
                match (ua != NONE, ub != NONE) {
                    (true, true) => {
                        code.push(Op::EdgeLenIi as u16);
                        operand::push(&mut code, rel(ua));
                        operand::push(&mut code, rel(ub));
                    }
                    (true, false) | (false, true) => {
                        code.push(Op::EdgeLenIb as u16);
                        operand::push(&mut code, rel(ua.min(ub)));
                    }
                    (false, false) => code.push(Op::EdgeLenBb as u16),
                }
            }
            let n_slots = edges.len() as u32;
            let back = |he: u32| n_slots - slot_of_edge[topo.edge_of[he as usize] as usize];
            // Corner c lies between half-edges 3f+c (leaving it) and prev (entering it),
            // opposite next(3f+c): TRIANGLE's corner c.
            let op = if inert.get(f as usize).copied().unwrap_or(false) {
                Op::TriangleInert
            } else {
                Op::Triangle
            };
            code.push(op as u16);
            for c in 0..3 {
                let he = f * 3 + c;
                operand::push(&mut code, back(he));
                temp_of_corner[he as usize] = n_temps;
                n_temps += 1;
            }
        }

        // 2. Gradient entry and Hessian column of unknown k.
        inner.clear();
        lower.clear();
        other.clear();
        for out in topo.fan(v) {
            inner.push(temp_of_corner[out as usize]);
            let t = topo.twin[out as usize];
            // Corners opposite edge v-w: in this face, and in the face across it.
            let pair = [
                temp_of_corner[prev(out) as usize],
                temp_of_corner[prev(t) as usize],
            ];
            let uw = unknown_of[topo.to(out) as usize];
            if uw != NONE && uw > k {
                lower.push((uw, pair));
            } else {
                other.push(pair);
            }
        }
        lower.sort_unstable_by_key(|&(u, _)| u);
        code.push(Op::VertexInfo as u16);
        operand::push(&mut code, inner.len() as u32);
        operand::push(&mut code, lower.len() as u32);
        for &t in &inner {
            operand::push(&mut code, n_temps - t);
        }
        for pair in lower.iter().map(|(_, p)| p).chain(other.iter()) {
            operand::push(&mut code, n_temps - pair[0]);
            operand::push(&mut code, n_temps - pair[1]);
        }
        row_idx.push(k);
        row_idx.extend(lower.iter().map(|&(u, _)| u));
        col_ptr.push(row_idx.len() as u32);
    }

    // Edges the iteration never touches (joining boundary vertices in all-boundary triangles)
    // still have lengths the layout needs.
    let n_iter_edges = edges.len() as u32;
    for (e, &ends) in topo.edges.iter().enumerate() {
        if slot_of_edge[e] == NONE {
            slot_of_edge[e] = edges.len() as u32;
            edges.push(ends);
        }
    }

    Emitted {
        code,
        slot_of_edge,
        edges,
        n_iter_edges,
        n_temps,
        unknown_vertex,
        hessian: HessianPattern { col_ptr, row_idx },
    }
}
