//! Emits the embed stream: a breadth-first walk over triangles from the anchor edge.
//!
//! Each step enters a triangle through an edge whose direction is known and derives the
//! directions of its two other edges by rotating through the corner angles. Directions thus
//! accumulate additive round-off along the walk (no step reads back a placed position), and
//! breadth-first order keeps the walk shallow.

use std::collections::VecDeque;

use bdmorph_isa::{EmbedRoot, EmbedStep};

use crate::topology::{next, prev, Topology, NONE};

pub(crate) fn emit(
    topo: &Topology,
    slot_of_edge: &[u32],
    edges: &[[u32; 2]],
    root_he: u32,
    inert: &[bool],
) -> (EmbedRoot, Vec<EmbedStep>) {
    // The walk never enters an inert face (marked visited from the start).
    let nf = topo.faces.len();
    let slot = |he: u32| slot_of_edge[topo.edge_of[he as usize] as usize];
    let root = EmbedRoot {
        p0: topo.from(root_he),
        p1: topo.to(root_he),
        edge: slot(root_he),
    };
    let mut placed = vec![false; topo.n_vertices()];
    placed[root.p0 as usize] = true;
    placed[root.p1 as usize] = true;
    let mut visited: Vec<bool> = (0..nf)
        .map(|f| inert.get(f).copied().unwrap_or(false))
        .collect();
    visited[root_he as usize / 3] = true;
    let mut queue = VecDeque::from([root_he]);
    let mut steps = Vec::with_capacity(nf);
    while let Some(h) = queue.pop_front() {
        let (a, b) = (topo.from(h), topo.to(h));
        let c = topo.from(prev(h));
        let (s_ab, s_bc, s_ca) = (slot(h), slot(next(h)), slot(prev(h)));
        let mut flags = 0;
        if edges[s_ab as usize] != [a, b] {
            flags |= EmbedStep::REV_AB;
        }
        if edges[s_bc as usize] != [b, c] {
            flags |= EmbedStep::REV_BC;
        }
        if edges[s_ca as usize] != [c, a] {
            flags |= EmbedStep::REV_CA;
        }
        if !placed[c as usize] {
            placed[c as usize] = true;
            flags |= EmbedStep::PLACE;
        }
        steps.push(EmbedStep {
            a,
            b,
            c,
            e_ab: s_ab,
            e_bc: s_bc,
            e_ca: s_ca,
            flags,
        });
        for he in [next(h), prev(h), h] {
            let t = topo.twin[he as usize];
            if t != NONE && !visited[t as usize / 3] {
                visited[t as usize / 3] = true;
                queue.push_back(t);
            }
        }
    }
    (root, steps)
}
