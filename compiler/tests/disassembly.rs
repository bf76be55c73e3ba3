//! Exact bytecode of a few tiny meshes, reviewed by hand (see the comments). Everything else is
//! tested by behaviour; keep this list short so the compiler stays free to change.

use bdmorph_compiler::compile;
use bdmorph_isa::disassemble;

fn hexagon_fan() -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
    let mut pos = vec![[0.0, 0.0]];
    for i in 0..6 {
        let a = f64::from(i) * std::f64::consts::PI / 3.0;
        pos.push([a.cos(), a.sin()]);
    }
    (pos, (0..6).map(|i| [0, 1 + i, 1 + (i + 1) % 6]).collect())
}

fn grid3() -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
    let mut pos = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            pos.push([f64::from(i), f64::from(j)]);
        }
    }
    let id = |i: u32, j: u32| j * 3 + i;
    let mut faces = Vec::new();
    for j in 0..2 {
        for i in 0..2 {
            faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (pos, faces)
}

/// One triangle: no unknowns, so an empty iteration stream; three edge slots outside it; one
/// embed step placing the third vertex.
#[test]
fn one_triangle() {
    let p = compile(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], &[[0, 1, 2]]).expect("compiles");
    insta::assert_snapshot!(disassemble(&p));
}

/// A fan around one interior vertex: one unknown (v0), its six spokes (edge_len.ib) and six rim
/// edges (edge_len.bb) computed as its triangles are reached, 18 half-angle tangents (the
/// corners at v0 with angles, the rim corners cotangent only), one vertex_info with six angles
/// and six spoke weights, all to the diagonal (a 1x1 Hessian).
#[test]
fn fan_around_one_interior_vertex() {
    let (pos, faces) = hexagon_fan();
    let p = compile(&pos, &faces).expect("compiles");
    insta::assert_snapshot!(disassemble(&p));
}

/// A 3x3 grid: one interior vertex (v4, the anchor), eight triangles around it.
#[test]
fn three_by_three_grid() {
    let (pos, faces) = grid3();
    let p = compile(&pos, &faces).expect("compiles");
    insta::assert_snapshot!(disassemble(&p));
}

/// A 4x4 grid: four interior vertices, so off-diagonal Hessian slots are written.
#[test]
fn four_by_four_grid_writes_off_diagonal_slots() {
    let mut pos = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            pos.push([f64::from(i), f64::from(j)]);
        }
    }
    let id = |i: u32, j: u32| j * 4 + i;
    let mut faces = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let p = compile(&pos, &faces).expect("compiles");
    insta::assert_snapshot!(disassemble(&p));
}

/// A square ring (outer 0-3, hole 4-7) whose hole is filled by two inert triangles: the hole's
/// four vertices are the unknowns (u0..u3), the two filling triangles are
/// `triangle.inert` (their temporaries add nothing), and the embed stream walks the ring's
/// eight triangles only, placing every vertex through them.
#[test]
fn ring_with_an_inert_filling() {
    let positions = [
        [0.0, 0.0],
        [3.0, 0.0],
        [3.0, 3.0],
        [0.0, 3.0],
        [1.0, 1.0],
        [2.0, 1.0],
        [2.0, 2.0],
        [1.0, 2.0],
    ];
    let mut faces = vec![
        [0, 1, 5],
        [0, 5, 4],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 0, 4],
        [3, 4, 7],
    ];
    faces.extend([[4, 5, 6], [4, 6, 7]]);
    let mut inert = vec![false; 8];
    inert.extend([true, true]);
    let p = bdmorph_compiler::compile_with_inert(&positions, &faces, &inert).expect("compiles");
    assert_eq!(p.embed().len(), 8);
    insta::assert_snapshot!(disassemble(&p));
}
