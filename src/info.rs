//! A summary of a mesh file: counts, topology, and whether it can be morphed.

use std::collections::HashMap;
use std::path::Path;

use crate::io::SurfaceMesh;
use crate::located::{Located, MeshFile};
use crate::mesh::{MeshError, PlanarMesh};

/// Counts and topology of a triangle mesh, computed leniently (any mesh, not only disks).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MeshInfo {
    /// Vertices.
    pub vertices: usize,
    /// Triangles.
    pub faces: usize,
    /// Distinct undirected edges.
    pub edges: usize,
    /// Edges with exactly one triangle.
    pub boundary_edges: usize,
    /// Connected pieces of the boundary (loops, on a manifold mesh).
    pub boundary_loops: usize,
    /// Vertices on no boundary edge that belong to some triangle.
    pub interior_vertices: usize,
    /// Vertices - edges + faces.
    pub euler: i64,
    /// Connected components of the triangles.
    pub components: usize,
    /// Every z is 0.
    pub planar: bool,
    /// The file has texture coordinates for every corner.
    pub texcoords: bool,
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb)] = ra.min(rb);
    }
}

impl MeshInfo {
    /// Summarises `mesh`. Face indices must be in range (as the readers guarantee); faces with
    /// an out-of-range index are skipped.
    pub fn of(mesh: &SurfaceMesh) -> MeshInfo {
        let n = mesh.positions.len();
        let faces: Vec<[u32; 3]> = mesh
            .faces
            .iter()
            .copied()
            .filter(|f| f.iter().all(|&v| (v as usize) < n))
            .collect();
        let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
        let mut parent: Vec<usize> = (0..n).collect();
        let mut referenced = vec![false; n];
        for f in &faces {
            for i in 0..3 {
                let (a, b) = (f[i], f[(i + 1) % 3]);
                *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1;
                union(&mut parent, a as usize, b as usize);
                referenced[a as usize] = true;
            }
        }
        let mut on_boundary = vec![false; n];
        let mut boundary_parent: Vec<usize> = (0..n).collect();
        let mut boundary_edges = 0;
        for (&(a, b), &count) in &uses {
            if count == 1 {
                boundary_edges += 1;
                on_boundary[a as usize] = true;
                on_boundary[b as usize] = true;
                union(&mut boundary_parent, a as usize, b as usize);
            }
        }
        let boundary_loops = (0..n)
            .filter(|&v| on_boundary[v] && find(&mut boundary_parent, v) == v)
            .count();
        let components = (0..n)
            .filter(|&v| referenced[v] && find(&mut parent, v) == v)
            .count();
        let interior_vertices = (0..n).filter(|&v| referenced[v] && !on_boundary[v]).count();
        MeshInfo {
            vertices: n,
            faces: mesh.faces.len(),
            edges: uses.len(),
            boundary_edges,
            boundary_loops,
            interior_vertices,
            euler: n as i64 - uses.len() as i64 + mesh.faces.len() as i64,
            components,
            planar: mesh.is_planar(),
            texcoords: mesh.texcoords.is_some(),
        }
    }
}

/// What the morph makes of a mesh that it accepts: its pieces and their holes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Morphable {
    /// Pieces (faces connected through edges); each morphs alone, with its own rigid motion.
    pub pieces: usize,
    /// Holes, in all pieces; each is filled with hidden triangles for the solve.
    pub holes: usize,
}

impl std::fmt::Display for Morphable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (self.pieces, self.holes) {
            (1, 0) => write!(f, "a counter-clockwise planar disk"),
            (pieces, holes) => {
                let plural =
                    |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
                write!(
                    f,
                    "counter-clockwise and planar, {} with {}",
                    plural(pieces, "piece"),
                    plural(holes, "hole")
                )?;
                if pieces > 1 {
                    write!(f, "; each piece morphs alone, with its own rigid motion")?;
                }
                if holes > 0 {
                    write!(
                        f,
                        "; each hole is filled with hidden triangles for the solve"
                    )?;
                }
                Ok(())
            }
        }
    }
}

/// Whether `mesh` can be a morph's source or target: planar, geometrically valid (finite,
/// counter-clockwise, no degenerate triangle) and manifold pieces, each a disk with any
/// number of holes. The error says why not.
pub fn check_morphable(mesh: &SurfaceMesh, path: &Path) -> Result<Morphable, String> {
    let planar = PlanarMesh::from_surface(mesh.clone(), path).map_err(|e| e.to_string())?;
    planar.validate().map_err(|e| e.to_string())?;
    let pieces = bdmorph_compiler::pieces(planar.positions.len(), &planar.faces)
        .map_err(|e| e.to_string())?;
    Ok(summary(&pieces))
}

/// As [`check_morphable`], for a mesh read from a file: the error is typed and names the
/// file, and the line of the face or vertex at fault (as `bdmorph morph` reports it).
pub fn morphable(file: &MeshFile) -> Result<Morphable, Located<MeshError>> {
    let planar = file.planar()?;
    let pieces = bdmorph_compiler::pieces(planar.positions.len(), &planar.faces)
        .map_err(|e| file.locate(MeshError::Topology(e)))?;
    Ok(summary(&pieces))
}

fn summary(pieces: &[bdmorph_compiler::Piece]) -> Morphable {
    Morphable {
        pieces: pieces.len(),
        holes: pieces.iter().map(|p| p.loops.len() - 1).sum(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate;

    fn surface(m: &PlanarMesh) -> SurfaceMesh {
        SurfaceMesh {
            positions: m.positions.iter().map(|p| [p[0], p[1], 0.0]).collect(),
            faces: m.faces.clone(),
            texcoords: None,
        }
    }

    #[test]
    fn disk_counts() {
        let m = generate::disk(3, 0.1);
        let info = MeshInfo::of(&surface(&m));
        assert_eq!(info.vertices, 37);
        assert_eq!(info.faces, 54);
        assert_eq!(info.boundary_loops, 1);
        assert_eq!(info.boundary_edges, 18);
        assert_eq!(info.interior_vertices, 19);
        assert_eq!(info.euler, 1);
        assert_eq!(info.components, 1);
        assert!(info.planar && !info.texcoords);
        assert!(check_morphable(&surface(&m), Path::new("d.obj")).is_ok());
    }

    #[test]
    fn morphable_names_the_file_and_the_line() {
        let text = "v 0 0\nv 1 0\nv 0 1\nv 1 1\n\nf 1 2 3\nf 2 4 3\nf 3 1 2\n";
        let (mesh, lines) = crate::io::parse_obj_with_lines(text, Path::new("t.obj")).unwrap();
        let file = MeshFile {
            path: "t.obj".into(),
            mesh,
            lines,
        };
        let err = morphable(&file).unwrap_err();
        assert_eq!(err.line, Some(8));
        assert_eq!(
            err.to_string(),
            "t.obj:8: face 0 and face 2 (0-based) are the same triangle (duplicate face); \
             face 2 is line 8, face 0 is line 6"
        );
        // The same as check_morphable says, but pointed at the file.
        let plain = check_morphable(&file.mesh, &file.path).unwrap_err();
        assert_eq!(plain, err.error.to_string());
        let mut ok = file.clone();
        ok.mesh.faces.pop();
        assert!(morphable(&ok).is_ok());
    }

    #[test]
    fn two_pieces_and_a_clockwise_triangle_are_reported() {
        let mut s = surface(&generate::fan(5, 0.0));
        let n = s.positions.len() as u32;
        s.positions
            .extend([[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.0, 0.0]]);
        s.faces.push([n, n + 1, n + 2]);
        let info = MeshInfo::of(&s);
        assert_eq!(info.components, 2);
        assert_eq!(info.boundary_loops, 2);
        // Two pieces morph, each alone.
        let found = check_morphable(&s, Path::new("x.obj")).unwrap();
        assert_eq!(
            found,
            Morphable {
                pieces: 2,
                holes: 0
            }
        );
        s.faces[0].swap(1, 2);
        assert!(check_morphable(&s, Path::new("x.obj")).is_err());
    }
}
