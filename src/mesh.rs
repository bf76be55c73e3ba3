//! Planar triangle meshes and their checks.

use std::path::Path;

use crate::io::{self, ReadError, SurfaceMesh, TexCoords};

/// A planar triangle mesh: one 2D position per vertex, triangles as 0-based vertex indices,
/// counter-clockwise.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarMesh {
    /// Vertex positions.
    pub positions: Vec<[f64; 2]>,
    /// Triangles.
    pub faces: Vec<[u32; 3]>,
}

/// Why a mesh (or a pair of meshes) is not valid input.
///
/// Faces and vertices are named by their 0-based index in the mesh's arrays (the messages say
/// so): face 274 is the 275th `f` line of an OBJ file. For a mesh read from a file,
/// [`crate::located::MeshFile::locate`] adds the file and the line.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The file could not be read.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// A 3D mesh where a planar one is needed.
    #[error("{path}: {}", NotPlanarText(*.vertex, *.z))]
    NotPlanar {
        /// The file.
        path: String,
        /// First vertex off the plane.
        vertex: usize,
        /// Its z.
        z: f64,
    },
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} (0-based) has a non-finite coordinate")]
    NonFinite {
        /// The vertex.
        vertex: usize,
    },
    /// A face names a vertex that does not exist.
    #[error(
        "face {face} refers to vertex {vertex} (0-based), but the mesh has {n_vertices} vertices"
    )]
    IndexOutOfRange {
        /// The face.
        face: usize,
        /// The index.
        vertex: u32,
        /// Vertex count.
        n_vertices: usize,
    },
    /// A triangle has (numerically) zero area.
    #[error("face {face} (0-based) is degenerate (area {area:e})")]
    Degenerate {
        /// The face.
        face: usize,
        /// Its signed area.
        area: f64,
    },
    /// A triangle is clockwise, and no more triangles are clockwise than counter-clockwise
    /// (otherwise the mesh is [`MeshError::Mirrored`]).
    #[error("face {face} (0-based) is clockwise (signed area {area:e}); triangles must be counter-clockwise, consistently")]
    Clockwise {
        /// The face.
        face: usize,
        /// Its signed area.
        area: f64,
    },
    /// Every triangle is clockwise, or more are clockwise than counter-clockwise: the mesh is
    /// mirrored, as when it was exported with y pointing down. Reversing each triangle's
    /// corner order (`a b c` to `a c b`) or negating one coordinate (y to -y) fixes it; the
    /// counter-clockwise triangles of a mostly clockwise mesh would then be the clockwise ones.
    #[error("{}", MirroredText { clockwise: *.clockwise, faces: *.faces, counter_clockwise: *.counter_clockwise, first_counter_clockwise: *.first_counter_clockwise })]
    Mirrored {
        /// Clockwise triangles.
        clockwise: usize,
        /// Triangles in all (the others are counter-clockwise or degenerate).
        faces: usize,
        /// Counter-clockwise triangles.
        counter_clockwise: usize,
        /// The first counter-clockwise triangle (0-based), when there is one.
        first_counter_clockwise: Option<usize>,
    },
    /// Source and target differ in size.
    #[error("source and target differ: {what} {source_count} vs {target_count}")]
    CountMismatch {
        /// What differs.
        what: &'static str,
        /// Count in the source.
        source_count: usize,
        /// Count in the target.
        target_count: usize,
    },
    /// Source and target have different triangles.
    #[error("source and target differ at face {face}: vertices {source_face:?} vs {target_face:?} (0-based); both meshes need the same triangles")]
    FaceMismatch {
        /// The face.
        face: usize,
        /// Its vertices in the source.
        source_face: [u32; 3],
        /// Its vertices in the target.
        target_face: [u32; 3],
    },
    /// The connectivity cannot be compiled (not a manifold, consistently oriented, connected
    /// disk).
    #[error(transparent)]
    Topology(#[from] bdmorph_compiler::CompileError),
}

/// The message of [`MeshError::NotPlanar`] after the file's name.
pub(crate) struct NotPlanarText(pub(crate) usize, pub(crate) f64);

impl std::fmt::Display for NotPlanarText {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (vertex, z) = (self.0, Short(self.1));
        write!(
            f,
            "vertex {vertex} (0-based) has z = {z}; a planar mesh (z = 0) is required"
        )
    }
}

/// The message of [`MeshError::Mirrored`].
struct MirroredText {
    clockwise: usize,
    faces: usize,
    counter_clockwise: usize,
    first_counter_clockwise: Option<usize>,
}

impl std::fmt::Display for MirroredText {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let fix = "reverse each triangle's corner order (a b c -> a c b) or negate one \
                   coordinate (y -> -y)";
        let (cw, n) = (self.clockwise, self.faces);
        if cw == n {
            let all = match n {
                1 => "the only triangle is".to_owned(),
                n => format!("all {n} triangles are"),
            };
            return write!(
                f,
                "{all} clockwise: the mesh is mirrored, as when exported with y pointing down; \
                 {fix}"
            );
        }
        write!(
            f,
            "{cw} of {n} triangles are clockwise: the mesh looks mirrored, as when exported \
             with y pointing down; {fix}"
        )?;
        match (self.counter_clockwise, self.first_counter_clockwise) {
            (0, _) | (_, None) => Ok(()),
            (1, Some(first)) => write!(
                f,
                ", after which face {first} (0-based), counter-clockwise now, would be clockwise"
            ),
            (ccw, Some(first)) => write!(
                f,
                ", after which the {ccw} counter-clockwise ones, from face {first} (0-based), \
                 would be clockwise"
            ),
        }
    }
}

/// A number for a message: `{}` unless that would be long (`1e300` rather than 301 digits).
struct Short(f64);

impl std::fmt::Display for Short {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        if x == 0.0 || (1e-5..1e16).contains(&x.abs()) || !x.is_finite() {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

impl PlanarMesh {
    /// Reads a planar mesh from an OBJ or OFF file (z must be 0 when present).
    pub fn read(path: &Path) -> Result<PlanarMesh, MeshError> {
        PlanarMesh::from_surface(io::read_mesh(path)?, path)
    }

    /// Reads a planar mesh and its texture coordinates (when the file has them for every
    /// corner).
    pub fn read_textured(path: &Path) -> Result<(PlanarMesh, Option<TexCoords>), MeshError> {
        let mut surface = io::read_mesh(path)?;
        let texcoords = surface.texcoords.take();
        Ok((PlanarMesh::from_surface(surface, path)?, texcoords))
    }

    /// Texture coordinates from the positions: the bounding box mapped to the unit square,
    /// keeping the aspect ratio (for texturing a mesh that has no `vt`).
    pub fn normalized_texcoords(&self) -> TexCoords {
        let (lo, hi) = self.bounds();
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let scale = if extent > 0.0 { 1.0 / extent } else { 1.0 };
        TexCoords {
            uv: self
                .positions
                .iter()
                .map(|p| [(p[0] - lo[0]) * scale, (p[1] - lo[1]) * scale])
                .collect(),
            corners: self.faces.clone(),
        }
    }

    /// Drops z from a mesh that lies in the plane z = 0.
    pub fn from_surface(mesh: SurfaceMesh, path: &Path) -> Result<PlanarMesh, MeshError> {
        if let Some((vertex, p)) = mesh.positions.iter().enumerate().find(|(_, p)| p[2] != 0.0) {
            return Err(MeshError::NotPlanar {
                path: path.display().to_string(),
                vertex,
                z: p[2],
            });
        }
        Ok(PlanarMesh {
            positions: mesh.positions.iter().map(|p| [p[0], p[1]]).collect(),
            faces: mesh.faces,
        })
    }

    /// The signed area of triangle `f` (positive when counter-clockwise).
    /// Indices must be in range.
    pub fn signed_area(&self, f: &[u32; 3]) -> f64 {
        let [a, b, c] = f.map(|v| self.positions[v as usize]);
        0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    }

    /// The bounding box: lower-left and upper-right corners (infinite when empty).
    pub fn bounds(&self) -> ([f64; 2], [f64; 2]) {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in &self.positions {
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        (lo, hi)
    }

    /// Size of the mesh: the diagonal of its bounding box.
    pub fn diameter(&self) -> f64 {
        let (lo, hi) = self.bounds();
        (hi[0] - lo[0]).hypot(hi[1] - lo[1])
    }

    /// Checks the geometry: finite coordinates, indices in range, every triangle
    /// counter-clockwise with an area above `1e-14` times the squared diameter. (Topology is
    /// checked by the compiler.)
    ///
    /// A mesh with more clockwise triangles than counter-clockwise ones (all of them, say) is
    /// refused as a whole, [`MeshError::Mirrored`]: it was most likely mirrored (exported with
    /// y pointing down), and one fix mends it. Otherwise the first degenerate or clockwise
    /// triangle is named.
    pub fn validate(&self) -> Result<(), MeshError> {
        if let Some(vertex) = self
            .positions
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(MeshError::NonFinite { vertex });
        }
        let n = self.positions.len();
        for (face, f) in self.faces.iter().enumerate() {
            if let Some(&vertex) = f.iter().find(|&&v| v as usize >= n) {
                return Err(MeshError::IndexOutOfRange {
                    face,
                    vertex,
                    n_vertices: n,
                });
            }
        }
        let eps = 1e-14 * self.diameter().powi(2);
        let (mut clockwise, mut counter_clockwise) = (0, 0);
        let mut first_counter_clockwise = None;
        let mut first_error = None;
        for (face, f) in self.faces.iter().enumerate() {
            let area = self.signed_area(f);
            if area.abs() <= eps {
                first_error.get_or_insert(MeshError::Degenerate { face, area });
            } else if area < 0.0 {
                clockwise += 1;
                first_error.get_or_insert(MeshError::Clockwise { face, area });
            } else {
                counter_clockwise += 1;
                first_counter_clockwise.get_or_insert(face);
            }
        }
        if clockwise > counter_clockwise {
            return Err(MeshError::Mirrored {
                clockwise,
                faces: self.faces.len(),
                counter_clockwise,
                first_counter_clockwise,
            });
        }
        first_error.map_or(Ok(()), Err)
    }

    /// Checks that `target` can be morphed with `self`: same counts, same triangles, both
    /// geometrically valid.
    pub fn validate_pair(&self, target: &PlanarMesh) -> Result<(), MeshError> {
        for (what, s, t) in [
            ("vertex count", self.positions.len(), target.positions.len()),
            ("face count", self.faces.len(), target.faces.len()),
        ] {
            if s != t {
                return Err(MeshError::CountMismatch {
                    what,
                    source_count: s,
                    target_count: t,
                });
            }
        }
        if let Some(face) = (0..self.faces.len()).find(|&i| self.faces[i] != target.faces[i]) {
            return Err(MeshError::FaceMismatch {
                face,
                source_face: self.faces[face],
                target_face: target.faces[face],
            });
        }
        self.validate()?;
        target.validate()
    }
}

/// The edges of `faces`, each once, as `(lo, hi)` vertex pairs in sorted order.
pub fn unique_edges(faces: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut edges: Vec<(u32, u32)> = faces
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Four triangles around a centre, counter-clockwise.
    fn square() -> PlanarMesh {
        PlanarMesh {
            positions: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]],
            faces: vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
        }
    }

    #[test]
    fn a_mesh_mostly_or_all_clockwise_is_mirrored() {
        let mut mesh = square();
        assert!(mesh.validate().is_ok());
        // One clockwise triangle of four: that triangle is named.
        mesh.faces[2].swap(0, 1);
        let err = mesh.validate().unwrap_err();
        assert!(matches!(err, MeshError::Clockwise { face: 2, .. }), "{err}");
        // Two of four: no majority, still the first one.
        mesh.faces[0].swap(0, 1);
        assert!(matches!(
            mesh.validate(),
            Err(MeshError::Clockwise { face: 0, .. })
        ));
        // Three of four: mirrored, and the counter-clockwise one would be wrong after the fix.
        mesh.faces[1].swap(0, 1);
        let err = mesh.validate().unwrap_err();
        assert!(matches!(
            err,
            MeshError::Mirrored {
                clockwise: 3,
                faces: 4,
                counter_clockwise: 1,
                first_counter_clockwise: Some(3)
            }
        ));
        assert_eq!(
            err.to_string(),
            "3 of 4 triangles are clockwise: the mesh looks mirrored, as when exported with y \
             pointing down; reverse each triangle's corner order (a b c -> a c b) or negate one \
             coordinate (y -> -y), after which face 3 (0-based), counter-clockwise now, would be \
             clockwise"
        );
        // All of them, as with y pointing down.
        let mut flipped = square();
        flipped.positions.iter_mut().for_each(|p| p[1] = -p[1]);
        let err = flipped.validate().unwrap_err();
        assert_eq!(
            err.to_string(),
            "all 4 triangles are clockwise: the mesh is mirrored, as when exported with y \
             pointing down; reverse each triangle's corner order (a b c -> a c b) or negate one \
             coordinate (y -> -y)"
        );
        // Either fix gives a valid mesh.
        let mut reversed = flipped.clone();
        reversed.faces.iter_mut().for_each(|f| f.swap(1, 2));
        assert!(reversed.validate().is_ok());
        // A degenerate triangle does not count either way; one triangle alone.
        flipped.positions[4] = [0.5, 0.0];
        assert!(matches!(
            flipped.validate(),
            Err(MeshError::Mirrored {
                clockwise: 3,
                faces: 4,
                counter_clockwise: 0,
                first_counter_clockwise: None
            })
        ));
        assert!(flipped.validate().unwrap_err().to_string().starts_with(
            "3 of 4 triangles are clockwise: the mesh looks mirrored, as when exported"
        ));
        let one = PlanarMesh {
            positions: vec![[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]],
            faces: vec![[0, 1, 2]],
        };
        let err = one.validate().unwrap_err().to_string();
        assert!(err.starts_with("the only triangle is clockwise: "), "{err}");
    }

    #[test]
    fn numbers_in_messages_stay_short() {
        let shown = |x: f64| Short(x).to_string();
        assert_eq!(shown(0.5), "0.5");
        assert_eq!(shown(-2.0), "-2");
        assert_eq!(shown(1e308), "1e308");
        assert_eq!(shown(-1e-300), "-1e-300");
        assert_eq!(shown(f64::NAN), "NaN");
    }
}
