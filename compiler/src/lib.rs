//! The BDMORPH compiler: walks a triangle mesh's connectivity once and emits a
//! [`Program`] of command streams that the VM runs every Newton
//! iteration and every frame without any mesh structure.
//!
//! The compiler is pure and deterministic: the same faces and positions (or anchor) give the
//! same bytes. It checks the mesh first (see [`CompileError`]): indices in range, manifold edges and
//! vertices, consistent orientation, one connected component, disk topology.
//!
//! ```
//! // A hexagon fan around one interior vertex.
//! let mut positions = vec![[0.0, 0.0]];
//! for i in 0..6 {
//!     let a = i as f64 * std::f64::consts::PI / 3.0;
//!     positions.push([a.cos(), a.sin()]);
//! }
//! let faces: Vec<[u32; 3]> = (0..6).map(|i| [0, 1 + i, 1 + (i + 1) % 6]).collect();
//! let program = bdmorph_compiler::compile(&positions, &faces)?;
//! assert_eq!(program.n_unknowns(), 1);
//! assert_eq!(program.n_edges(), 12);
//! println!("{}", bdmorph_isa::disassemble(&program));
//! # Ok::<(), bdmorph_compiler::CompileError>(())
//! ```
#![warn(missing_docs)]

mod embed;
mod error;
mod ids;
mod iteration;
mod ordering;
mod pieces;
mod topology;

pub use error::CompileError;
pub use ids::{FaceId, VertexId};
pub use ordering::{nested_dissection, LEAF_SIZE};
pub use pieces::{pieces, Piece};
pub use topology::disk_boundary;

use bdmorph_isa::{Program, ProgramParts};
use topology::Topology;

/// Programs with at least this many unknowns carry a [`nested_dissection`] ordering for the
/// Hessian's Cholesky factorisation when compiled with positions ([`compile`]); smaller ones
/// leave the choice to the VM (AMD). The VM factors an ordered program supernodally; on the
/// benchmark disks that is 7% slower than AMD at 547 unknowns, as fast within the noise
/// (+-10%) at 919, and 28% faster at 2.8K.
pub const ORDERING_MIN_UNKNOWNS: usize = 800;

/// Compiles a planar triangle mesh. `positions` (one per vertex) choose the anchor of the
/// layout: the vertex nearest the centre of their bounding box (lowest index on ties), with
/// the first edge of its fan; and, for programs of at least [`ORDERING_MIN_UNKNOWNS`]
/// unknowns, the fill-reducing ordering of the unknowns ([`nested_dissection`]). Any positions
/// with the same faces can be morphed by the program.
pub fn compile(positions: &[[f64; 2]], faces: &[[u32; 3]]) -> Result<Program, CompileError> {
    compile_with_inert(positions, faces, &[])
}

/// Compiles as [`compile`] does, with some faces *inert*: `inert` is empty (none) or holds one
/// flag per face. An inert face is part of the topology (the mesh with it must be a disk) but
/// not of the geometry: its corners add nothing to the gradient, the Hessian or the energy
/// ([`bdmorph_isa::Op::TriangleInert`]), and the layout never walks through it, so its
/// vertices are placed through the other faces. A hole of a mesh filled with inert faces is
/// thus solved as a free boundary: its vertices are unknowns whose angle sums are those of the
/// other faces alone (a caller sets their targets, see the VM's gradient offsets). The
/// faces that are not inert must be connected through their edges; the anchor is the vertex
/// nearest the centre of the bounding box of the vertices of those faces.
///
/// ```
/// // A square ring (8 vertices, 8 triangles) whose hole is filled by two inert triangles.
/// let positions = [
///     [0.0, 0.0], [3.0, 0.0], [3.0, 3.0], [0.0, 3.0],
///     [1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0],
/// ];
/// let mut faces = vec![
///     [0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5],
///     [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7],
/// ];
/// faces.extend([[4, 5, 6], [4, 6, 7]]);
/// let mut inert = vec![false; 8];
/// inert.extend([true, true]);
/// let program = bdmorph_compiler::compile_with_inert(&positions, &faces, &inert)?;
/// assert_eq!(program.n_unknowns(), 4);           // the hole's vertices
/// assert_eq!(program.embed().len(), 8);          // the ring's triangles only
/// # Ok::<(), bdmorph_compiler::CompileError>(())
/// ```
pub fn compile_with_inert(
    positions: &[[f64; 2]],
    faces: &[[u32; 3]],
    inert: &[bool],
) -> Result<Program, CompileError> {
    if !inert.is_empty() && inert.len() != faces.len() {
        return Err(CompileError::InertCount {
            flags: inert.len(),
            faces: faces.len(),
        });
    }
    for (v, p) in positions.iter().enumerate() {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err(CompileError::NonFinitePosition {
                vertex: VertexId(v as u32),
            });
        }
    }
    let topo = Topology::new(positions.len(), faces)?;
    if !inert.is_empty() && inert.iter().all(|&i| i) {
        return Err(CompileError::AllInert);
    }
    let anchor = if inert.iter().any(|&i| i) {
        // Vertices of the faces that are laid out.
        let mut laid = vec![false; positions.len()];
        for (f, &i) in faces.iter().zip(inert) {
            if !i {
                f.iter().for_each(|&v| laid[v as usize] = true);
            }
        }
        nearest_to_centre_of(positions, |v| laid[v])
    } else {
        nearest_to_centre(positions)
    };
    compile_topology(&topo, anchor, Some(positions), inert)
}

/// Compiles with an explicit anchor vertex instead of choosing it from positions. Without
/// positions the program carries no fill-reducing ordering (the VM uses AMD).
pub fn compile_with_anchor(
    n_vertices: usize,
    faces: &[[u32; 3]],
    anchor: VertexId,
) -> Result<Program, CompileError> {
    let topo = Topology::new(n_vertices, faces)?;
    if anchor.0 as usize >= n_vertices {
        return Err(CompileError::AnchorOutOfRange { anchor, n_vertices });
    }
    compile_topology(&topo, anchor.0, None, &[])
}

/// `inert` is empty or one flag per face, not all set; the anchor has a face that is not.
fn compile_topology(
    topo: &Topology,
    anchor: u32,
    positions: Option<&[[f64; 2]]>,
    inert: &[bool],
) -> Result<Program, CompileError> {
    let is_inert = |he: u32| inert.get(he as usize / 3).copied().unwrap_or(false);
    let order = iteration::bfs_vertices(topo, anchor);
    let it = iteration::emit(topo, &order, inert);
    let root_he = topo
        .fan(anchor)
        .find(|&he| !is_inert(he))
        .unwrap_or(topo.first_out[anchor as usize]);
    let (root, steps) = embed::emit(topo, &it.slot_of_edge, &it.edges, root_he, inert);
    let ordering = positions
        .filter(|_| it.unknown_vertex.len() >= ORDERING_MIN_UNKNOWNS.max(1))
        .map(|p| ordering::order(&it.hessian, &it.unknown_vertex, p, LEAF_SIZE));
    Ok(Program::from_parts(ProgramParts {
        n_vertices: topo.n_vertices() as u32,
        n_faces: topo.faces.len() as u32,
        edges: it.edges,
        unknown_vertex: it.unknown_vertex,
        n_iter_edges: it.n_iter_edges,
        n_temps: it.n_temps,
        iteration: it.code,
        hessian: it.hessian,
        embed_root: root,
        embed: steps,
        ordering,
    })?)
}

/// The vertex nearest the centre of the bounding box of `positions` (0 when empty).
fn nearest_to_centre(positions: &[[f64; 2]]) -> u32 {
    nearest_to_centre_of(positions, |_| true)
}

/// The vertex nearest the centre of the bounding box of the positions of the vertices `of`
/// accepts, among those (lowest index on ties; 0 when there is none).
fn nearest_to_centre_of(positions: &[[f64; 2]], of: impl Fn(usize) -> bool) -> u32 {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in positions
        .iter()
        .enumerate()
        .filter(|(v, _)| of(*v))
        .map(|(_, p)| p)
    {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let mut best = (f64::INFINITY, 0u32);
    for (v, p) in positions.iter().enumerate().filter(|(v, _)| of(*v)) {
        let d = (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2);
        if d < best.0 {
            best = (d, v as u32);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;
    use bdmorph_isa::disassemble;

    /// An `n x n` grid of vertices over the unit square, two triangles per cell.
    pub(crate) fn grid(n: usize) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let mut pos = Vec::new();
        for j in 0..n {
            for i in 0..n {
                pos.push([i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64]);
            }
        }
        let mut faces = Vec::new();
        let id = |i: usize, j: usize| (j * n + i) as u32;
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (pos, faces)
    }

    fn fan(n: u32) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let mut pos = vec![[0.0, 0.0]];
        for i in 0..n {
            let a = f64::from(i) * std::f64::consts::TAU / f64::from(n);
            pos.push([a.cos(), a.sin()]);
        }
        let faces = (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect();
        (pos, faces)
    }

    #[test]
    fn compilation_is_deterministic() {
        let (pos, faces) = grid(12);
        let a = compile(&pos, &faces).expect("grid compiles");
        let b = compile(&pos, &faces).expect("grid compiles");
        assert_eq!(a, b);
        assert_eq!(a.n_unknowns(), 10 * 10);
        assert_eq!(a.n_faces(), 2 * 11 * 11);
    }

    #[test]
    fn anchor_is_the_vertex_nearest_the_bounding_box_centre() {
        let (pos, faces) = grid(5);
        let p = compile(&pos, &faces).expect("grid compiles");
        assert_eq!(p.embed_root().p0, 12);
        // Unknowns start at the anchor, breadth-first.
        assert_eq!(p.unknown_vertex()[0], 12);
    }

    #[test]
    fn every_value_slot_and_temporary_is_written_once() {
        let (pos, faces) = grid(20);
        let p = compile(&pos, &faces).expect("grid compiles");
        // Interior grid vertex: valence 6, 3 neighbours below the diagonal on average.
        let s = p.stats();
        assert_eq!(
            s.hessian_nnz,
            p.n_unknowns() + (p.n_unknowns() * 6 - boundary_links(20)) / 2
        );
        // Only faces touching an interior vertex are computed.
        assert!(p.n_temps() <= 3 * p.n_faces());
    }

    /// Directed links from interior to boundary vertices in an n x n grid.
    fn boundary_links(n: usize) -> usize {
        // Interior vertices next to the boundary: links per side (grid diagonals included).
        let m = n - 2;
        // Each interior vertex adjacent to the boundary loses the links to boundary vertices.
        let mut links = 0;
        for j in 1..n - 1 {
            for i in 1..n - 1 {
                let nbrs = [
                    (i + 1, j),
                    (i - 1, j),
                    (i, j + 1),
                    (i, j - 1),
                    (i + 1, j + 1),
                    (i - 1, j - 1),
                ];
                links += nbrs
                    .iter()
                    .filter(|&&(x, y)| x == 0 || y == 0 || x == n - 1 || y == n - 1)
                    .count();
            }
        }
        let _ = m;
        links
    }

    #[test]
    fn single_triangle_has_no_unknowns() {
        let p = compile(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], &[[0, 1, 2]]).expect("compiles");
        assert_eq!(p.n_unknowns(), 0);
        assert!(p.iteration().is_empty());
        assert_eq!(p.embed().len(), 1);
    }

    #[test]
    fn large_valence_fan_compiles() {
        let (pos, faces) = fan(300);
        let p = compile(&pos, &faces).expect("compiles");
        assert_eq!(p.n_unknowns(), 1);
        assert!(disassemble(&p).contains("vertex_info"));
    }

    #[test]
    fn explicit_anchor_is_used_and_checked() {
        let (pos, faces) = grid(4);
        let p = compile_with_anchor(pos.len(), &faces, VertexId(5)).expect("compiles");
        assert_eq!(p.embed_root().p0, 5);
        assert_eq!(
            compile_with_anchor(pos.len(), &faces, VertexId(16)),
            Err(CompileError::AnchorOutOfRange {
                anchor: VertexId(16),
                n_vertices: 16
            })
        );
    }

    #[test]
    fn large_programs_carry_a_nested_dissection_ordering() {
        for n in [20, 40] {
            let (pos, faces) = grid(n);
            let p = compile(&pos, &faces).expect("compiles");
            let large = p.n_unknowns() >= ORDERING_MIN_UNKNOWNS;
            assert_eq!(large, n == 40);
            match p.ordering() {
                Some(o) => {
                    assert!(large);
                    assert_eq!(
                        o,
                        &nested_dissection(&p, &pos, LEAF_SIZE).expect("orders")[..]
                    );
                }
                None => assert!(!large),
            }
            // Without positions there is no ordering.
            let p = compile_with_anchor(pos.len(), &faces, VertexId(0)).expect("compiles");
            assert_eq!(p.ordering(), None);
        }
    }

    #[test]
    fn non_finite_positions_are_refused() {
        let err = compile(&[[0.0, 0.0], [f64::NAN, 0.0], [0.0, 1.0]], &[[0, 1, 2]]).unwrap_err();
        assert_eq!(
            err,
            CompileError::NonFinitePosition {
                vertex: VertexId(1)
            }
        );
    }
}
