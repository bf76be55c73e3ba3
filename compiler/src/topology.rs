//! Mesh connectivity: half-edges, twins, edges, vertex fans, and the checks that make a mesh
//! compilable (a manifold, consistently oriented, connected disk).
//!
//! Half-edge `3 f + i` of face `f` runs from corner `i` to corner `(i + 1) % 3`.

use crate::error::CompileError;
use crate::ids::{FaceId, VertexId};

/// Marks a missing twin (a boundary half-edge) or an unassigned index.
pub(crate) const NONE: u32 = u32::MAX;

/// Checked connectivity of a disk-topology triangle mesh.
#[derive(Clone, Debug)]
pub(crate) struct Topology {
    pub faces: Vec<[u32; 3]>,
    /// Twin of each half-edge, or [`NONE`] on the boundary.
    pub twin: Vec<u32>,
    /// Mesh edge of each half-edge.
    pub edge_of: Vec<u32>,
    /// Endpoints of each mesh edge, `lo < hi`.
    pub edges: Vec<[u32; 2]>,
    /// Per vertex, the outgoing half-edge its counter-clockwise fan starts from (the boundary
    /// half-edge leaving it, for boundary vertices).
    pub first_out: Vec<u32>,
    /// Whether each vertex lies on the boundary.
    pub boundary: Vec<bool>,
}

#[inline]
pub(crate) fn next(he: u32) -> u32 {
    if he % 3 == 2 {
        he - 2
    } else {
        he + 1
    }
}

#[inline]
pub(crate) fn prev(he: u32) -> u32 {
    if he.is_multiple_of(3) {
        he + 2
    } else {
        he - 1
    }
}

impl Topology {
    /// Builds and checks the connectivity of `faces` over `n_vertices` vertices: a
    /// connected disk.
    pub fn new(n_vertices: usize, faces: &[[u32; 3]]) -> Result<Topology, CompileError> {
        let topo = Topology::manifold(n_vertices, faces)?;
        topo.check_disk()?;
        Ok(topo)
    }

    /// Builds and checks the connectivity of `faces` over `n_vertices` vertices: a manifold,
    /// consistently oriented, every vertex used, of any number of pieces and boundary loops.
    pub fn manifold(n_vertices: usize, faces: &[[u32; 3]]) -> Result<Topology, CompileError> {
        if faces.is_empty() {
            return Err(CompileError::NoFaces);
        }
        let too_big = CompileError::TooLarge {
            vertices: n_vertices,
            faces: faces.len(),
        };
        if n_vertices >= NONE as usize || faces.len() >= (NONE as usize) / 3 {
            return Err(too_big);
        }
        for (f, t) in faces.iter().enumerate() {
            for &v in t {
                if v as usize >= n_vertices {
                    return Err(CompileError::VertexOutOfRange {
                        face: FaceId(f as u32),
                        vertex: v,
                        n_vertices,
                    });
                }
            }
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return Err(CompileError::RepeatedVertex {
                    face: FaceId(f as u32),
                });
            }
        }
        check_duplicates(faces)?;
        let n_he = faces.len() * 3;
        let from = |he: u32| faces[he as usize / 3][he as usize % 3];
        let to = |he: u32| from(next(he));

        // Bucket half-edges by their lower endpoint (counting sort: linear and deterministic).
        let mut start = vec![0u32; n_vertices + 1];
        for he in 0..n_he as u32 {
            start[from(he).min(to(he)) as usize + 1] += 1;
        }
        for v in 0..n_vertices {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut bucket = vec![0u32; n_he];
        for he in 0..n_he as u32 {
            let lo = from(he).min(to(he)) as usize;
            bucket[fill[lo] as usize] = he;
            fill[lo] += 1;
        }

        let mut twin = vec![NONE; n_he];
        let mut edge_of = vec![NONE; n_he];
        let mut edges = Vec::with_capacity(n_he / 2 + n_vertices);
        for lo in 0..n_vertices {
            let items = &mut bucket[start[lo] as usize..start[lo + 1] as usize];
            items.sort_unstable_by_key(|&he| (from(he).max(to(he)), he));
            let mut i = 0;
            while i < items.len() {
                let hi = from(items[i]).max(to(items[i]));
                let mut j = i + 1;
                while j < items.len() && from(items[j]).max(to(items[j])) == hi {
                    j += 1;
                }
                let group = &items[i..j];
                let (a, b) = (VertexId(lo as u32), VertexId(hi));
                if group.len() > 2 {
                    return Err(CompileError::NonManifoldEdge {
                        a,
                        b,
                        faces: group.len(),
                    });
                }
                if group.len() == 2 {
                    let (h0, h1) = (group[0], group[1]);
                    if from(h0) == from(h1) {
                        return Err(CompileError::InconsistentOrientation {
                            a: VertexId(from(h0)),
                            b: VertexId(to(h0)),
                            faces: [FaceId(h0 / 3), FaceId(h1 / 3)],
                        });
                    }
                    twin[h0 as usize] = h1;
                    twin[h1 as usize] = h0;
                }
                let e = edges.len() as u32;
                edges.push([lo as u32, hi]);
                for &he in group {
                    edge_of[he as usize] = e;
                }
                i = j;
            }
        }

        // One outgoing half-edge per vertex, preferring the boundary one.
        let mut first_out = vec![NONE; n_vertices];
        let mut corners = vec![0u32; n_vertices];
        let mut boundary = vec![false; n_vertices];
        for he in 0..n_he as u32 {
            let v = from(he) as usize;
            corners[v] += 1;
            if twin[he as usize] == NONE {
                if boundary[v] {
                    // A second boundary half-edge leaving v: two fans meet at v.
                    return Err(CompileError::NonManifoldVertex {
                        vertex: VertexId(v as u32),
                    });
                }
                boundary[v] = true;
                first_out[v] = he;
            } else if first_out[v] == NONE {
                first_out[v] = he;
            }
        }
        if let Some(v) = corners.iter().position(|&c| c == 0) {
            return Err(CompileError::UnreferencedVertex {
                vertex: VertexId(v as u32),
            });
        }
        let topo = Topology {
            faces: faces.to_vec(),
            twin,
            edge_of,
            edges,
            first_out,
            boundary,
        };
        // Every corner of a vertex must lie on its single fan.
        for (v, &count) in corners.iter().enumerate() {
            let fan = topo.fan(v as u32).count() as u32;
            if fan != count {
                return Err(CompileError::NonManifoldVertex {
                    vertex: VertexId(v as u32),
                });
            }
        }
        Ok(topo)
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.first_out.len()
    }

    /// Start vertex of a half-edge.
    #[inline]
    pub fn from(&self, he: u32) -> u32 {
        self.faces[he as usize / 3][he as usize % 3]
    }

    /// End vertex of a half-edge.
    #[inline]
    pub fn to(&self, he: u32) -> u32 {
        self.from(next(he))
    }

    /// The outgoing half-edges of `v` in counter-clockwise order, starting at `first_out[v]`.
    pub fn fan(&self, v: u32) -> Fan<'_> {
        Fan {
            topo: self,
            start: self.first_out[v as usize],
            cur: self.first_out[v as usize],
        }
    }

    fn check_disk(&self) -> Result<(), CompileError> {
        // Connected: flood faces through twins.
        let nf = self.faces.len();
        let mut seen = vec![false; nf];
        let mut stack = vec![0u32];
        seen[0] = true;
        let mut reached = 1usize;
        while let Some(f) = stack.pop() {
            for i in 0..3 {
                let t = self.twin[f as usize * 3 + i];
                if t != NONE && !seen[t as usize / 3] {
                    seen[t as usize / 3] = true;
                    reached += 1;
                    stack.push(t / 3);
                }
            }
        }
        if reached != nf {
            let first_unreached = seen.iter().position(|&s| !s).unwrap_or(0);
            return Err(CompileError::Disconnected {
                face: FaceId(first_unreached as u32),
            });
        }
        // Boundary loops.
        let mut on_loop = vec![false; self.twin.len()];
        let mut loops = 0usize;
        for he in 0..self.twin.len() as u32 {
            if self.twin[he as usize] != NONE || on_loop[he as usize] {
                continue;
            }
            loops += 1;
            let mut cur = he;
            while !on_loop[cur as usize] {
                on_loop[cur as usize] = true;
                cur = self.first_out[self.to(cur) as usize];
            }
        }
        let euler = self.n_vertices() as i64 - self.edges.len() as i64 + nf as i64;
        match loops {
            0 => Err(CompileError::ClosedSurface { euler }),
            1 if euler == 1 => Ok(()),
            1 => Err(CompileError::NotADisk { euler, loops }),
            _ => Err(CompileError::HasHoles { loops, euler }),
        }
    }
}

/// Checks that `faces` over `n_vertices` vertices form a disk (manifold, consistently
/// oriented, connected, one boundary loop, Euler characteristic 1) and returns the boundary
/// loop's vertices in order, following the boundary half-edges (counter-clockwise around the
/// disk when the faces are).
///
/// ```
/// // Two triangles of a square.
/// let loop_ = bdmorph_compiler::disk_boundary(4, &[[0, 1, 2], [0, 2, 3]]).unwrap();
/// assert_eq!(loop_.len(), 4);
/// assert!(bdmorph_compiler::disk_boundary(4, &[[0, 1, 2], [0, 2, 1]]).is_err());
/// ```
pub fn disk_boundary(n_vertices: usize, faces: &[[u32; 3]]) -> Result<Vec<u32>, CompileError> {
    let topo = Topology::new(n_vertices, faces)?;
    let start = (0..topo.twin.len() as u32)
        .find(|&he| topo.twin[he as usize] == NONE)
        .ok_or(CompileError::ClosedSurface { euler: 2 })?;
    let mut out = Vec::new();
    let mut cur = start;
    loop {
        out.push(topo.from(cur));
        cur = topo.first_out[topo.to(cur) as usize];
        if cur == start || out.len() > topo.twin.len() {
            break;
        }
    }
    Ok(out)
}

/// Refuses a triangle listed twice, in either orientation, naming the first repeat in face
/// order. (Otherwise it would show up as an inconsistent orientation or a closed surface.)
fn check_duplicates(faces: &[[u32; 3]]) -> Result<(), CompileError> {
    let mut seen = std::collections::HashMap::with_capacity(faces.len());
    for (f, t) in faces.iter().enumerate() {
        let mut key = *t;
        key.sort_unstable();
        if let Some(&first) = seen.get(&key) {
            return Err(CompileError::DuplicateFace {
                faces: [FaceId(first), FaceId(f as u32)],
            });
        }
        seen.insert(key, f as u32);
    }
    Ok(())
}

/// Iterator over a vertex's outgoing half-edges, counter-clockwise.
pub(crate) struct Fan<'a> {
    topo: &'a Topology,
    start: u32,
    cur: u32,
}

impl Iterator for Fan<'_> {
    type Item = u32;
    fn next(&mut self) -> Option<u32> {
        if self.cur == NONE {
            return None;
        }
        let out = self.cur;
        let back = self.topo.twin[prev(out) as usize];
        self.cur = if back == self.start { NONE } else { back };
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Vec<[u32; 3]> {
        vec![[0, 1, 2], [0, 2, 3]]
    }

    #[test]
    fn square_is_a_disk_with_five_edges() {
        let t = Topology::new(4, &square()).expect("valid");
        assert_eq!(t.edges.len(), 5);
        assert!(t.boundary.iter().all(|&b| b));
        assert_eq!(t.fan(0).count(), 2);
        assert_eq!(t.fan(1).count(), 1);
    }

    #[test]
    fn fan_around_interior_vertex_is_closed_and_ccw() {
        // Hexagon fan around vertex 0.
        let faces: Vec<[u32; 3]> = (0..6).map(|i| [0, 1 + i, 1 + (i + 1) % 6]).collect();
        let t = Topology::new(7, &faces).expect("valid");
        assert!(!t.boundary[0]);
        let nbrs: Vec<u32> = t.fan(0).map(|he| t.to(he)).collect();
        assert_eq!(nbrs.len(), 6);
        // Counter-clockwise: each next neighbour is the previous one plus one (mod 6).
        for w in nbrs.windows(2) {
            assert_eq!((w[0] % 6) + 1, w[1]);
        }
    }

    #[test]
    fn rejects_bad_meshes_with_their_cause() {
        assert!(matches!(
            Topology::new(3, &[[0, 1, 3]]),
            Err(CompileError::VertexOutOfRange { vertex: 3, .. })
        ));
        assert!(matches!(
            Topology::new(3, &[[0, 1, 1]]),
            Err(CompileError::RepeatedVertex { .. })
        ));
        assert!(matches!(
            Topology::new(4, &[[0, 1, 2], [0, 1, 3]]),
            Err(CompileError::InconsistentOrientation { .. })
        ));
        // The same triangle twice, as listed, rotated or reversed.
        for repeat in [[0, 1, 2], [1, 2, 0], [2, 1, 0]] {
            assert_eq!(
                Topology::new(4, &[[0, 1, 2], [0, 2, 3], repeat]).err(),
                Some(CompileError::DuplicateFace {
                    faces: [FaceId(0), FaceId(2)]
                })
            );
        }
        assert!(matches!(
            Topology::new(5, &[[0, 1, 2], [1, 0, 3], [0, 1, 4]]),
            Err(CompileError::NonManifoldEdge { faces: 3, .. })
        ));
        assert!(matches!(
            Topology::new(4, &[[0, 1, 2]]),
            Err(CompileError::UnreferencedVertex {
                vertex: VertexId(3)
            })
        ));
        // Two triangles sharing only vertex 0 (a bow tie).
        assert!(matches!(
            Topology::new(5, &[[0, 1, 2], [0, 3, 4]]),
            Err(CompileError::NonManifoldVertex {
                vertex: VertexId(0)
            })
        ));
        // Tetrahedron: closed.
        let tet = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
        assert!(matches!(
            Topology::new(4, &tet),
            Err(CompileError::ClosedSurface { euler: 2 })
        ));
        assert!(matches!(Topology::new(0, &[]), Err(CompileError::NoFaces)));
    }

    #[test]
    fn rejects_annulus_as_mesh_with_hole() {
        // A square ring: outer 0..4, inner 4..8, eight triangles.
        let mut faces = Vec::new();
        for i in 0..4u32 {
            let (o0, o1, i0, i1) = (i, (i + 1) % 4, 4 + i, 4 + (i + 1) % 4);
            faces.push([o0, o1, i1]);
            faces.push([o0, i1, i0]);
        }
        assert!(matches!(
            Topology::new(8, &faces),
            Err(CompileError::HasHoles { loops: 2, euler: 0 })
        ));
    }

    #[test]
    fn rejects_two_components() {
        let faces = [[0, 1, 2], [3, 4, 5]];
        assert!(matches!(
            Topology::new(6, &faces),
            Err(CompileError::Disconnected { .. })
        ));
    }
}
