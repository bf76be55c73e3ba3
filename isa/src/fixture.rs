//! A small valid program for unit tests: the compiler's output for a hexagon fan (one
//! interior vertex, 7 vertices, 6 faces), written out so that this crate's tests need no
//! compiler.

use crate::{EmbedRoot, EmbedStep, HessianPattern, ProgramParts};

pub(crate) fn hexagon_parts() -> ProgramParts {
    let step = |a, b, c, e_ab, e_bc, e_ca, flags| EmbedStep {
        a,
        b,
        c,
        e_ab,
        e_bc,
        e_ca,
        flags,
    };
    let iteration = vec![
        2, 0, 3, 2, 0, 4, 3, 2, 1, 3, 2, 0, 4, 3, 2, 1, 3, 2, 0, 4, 3, 2, 1, 3, 2, 0, 4, 3, 2, 1,
        3, 2, 0, 4, 3, 2, 1, 3, 4, 2, 1, 12, 6, 6, 0, 18, 15, 12, 9, 6, 3, 16, 2, 13, 17, 10, 14,
        7, 11, 4, 8, 1, 5,
    ];
    ProgramParts {
        n_vertices: 7,
        n_faces: 6,
        edges: vec![
            [0, 1],
            [1, 2],
            [0, 2],
            [2, 3],
            [0, 3],
            [3, 4],
            [0, 4],
            [4, 5],
            [0, 5],
            [5, 6],
            [0, 6],
            [1, 6],
        ],
        unknown_vertex: vec![0],
        n_iter_edges: 12,
        n_temps: 18,
        iteration,
        hessian: HessianPattern {
            col_ptr: vec![0, 1],
            row_idx: vec![0],
        },
        embed_root: EmbedRoot {
            p0: 0,
            p1: 1,
            edge: 0,
        },
        embed: vec![
            step(0, 1, 2, 0, 1, 2, 12),
            step(0, 2, 3, 2, 3, 4, 12),
            step(1, 0, 6, 0, 10, 11, 13),
            step(0, 3, 4, 4, 5, 6, 12),
            step(6, 0, 5, 10, 8, 9, 9),
            step(0, 4, 5, 6, 7, 8, 4),
        ],
        ordering: None,
    }
}
