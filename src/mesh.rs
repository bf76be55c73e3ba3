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
    /// The mesh has no triangles (for what needs some: posing, morphing).
    #[error("the mesh has no triangles")]
    NoTriangles,
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
    #[error("face {face} (0-based) is clockwise (signed area {area:e}); triangles must be counter-clockwise, consistently (a keyframe with a few inverted triangles morphs with MorphOptions::allow_inverted)")]
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
    /// A later keyframe (the target) has a triangle the first (the source) does not have.
    /// Triangles may be listed in any order and with their corners rotated (`a b c` as
    /// `c a b`); see [`PlanarMesh::match_faces`].
    #[error("face {face} (0-based; vertices {} {} {}) is not a triangle of the first mesh; both meshes need the same triangles (in any order)", target_face[0], target_face[1], target_face[2])]
    FaceMissing {
        /// The face, in the target's order.
        face: usize,
        /// Its vertices.
        target_face: [u32; 3],
    },
    /// A later keyframe (the target) lists a triangle of the first one with the opposite
    /// orientation (`a c b` for `a b c`).
    #[error("face {face} (0-based; vertices {} {} {}) is face {source_face} of the first mesh reversed ({} {} {}); a triangle must keep its corners' cyclic order", target_face[0], target_face[1], target_face[2], source_corners[0], source_corners[1], source_corners[2])]
    FaceReversed {
        /// The face, in the target's order.
        face: usize,
        /// Its vertices.
        target_face: [u32; 3],
        /// The same triangle's index in the first mesh.
        source_face: usize,
        /// Its vertices there.
        source_corners: [u32; 3],
    },
    /// A later keyframe (the target) lists a triangle twice.
    #[error("face {first} and face {face} (0-based) are the same triangle (duplicate face)")]
    FaceRepeated {
        /// The repeat, in the target's order.
        face: usize,
        /// Its first listing.
        first: usize,
    },
    /// Several triangles are clockwise (inverted), but fewer than the counter-clockwise ones
    /// (otherwise the mesh is [`MeshError::Mirrored`]). A keyframe with a few inverted
    /// triangles can still be morphed when asked for
    /// ([`crate::MorphOptions::allow_inverted`]).
    #[error("{}", InvertedText { faces, count: *.count, total: *.total })]
    Inverted {
        /// The first [`INVERTED_LISTED`] of them, in face order (0-based).
        faces: Vec<usize>,
        /// How many there are.
        count: usize,
        /// Triangles in all.
        total: usize,
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

/// How many inverted triangles [`MeshError::Inverted`] names.
pub const INVERTED_LISTED: usize = 10;

/// The message of [`MeshError::Inverted`].
struct InvertedText<'a> {
    faces: &'a [usize],
    count: usize,
    total: usize,
}

impl std::fmt::Display for InvertedText<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} of {} triangles are clockwise (inverted): face",
            self.count, self.total
        )?;
        for (i, face) in self.faces.iter().enumerate() {
            let sep = if i == 0 { " " } else { ", " };
            write!(f, "{sep}{face}")?;
        }
        if self.count > self.faces.len() {
            write!(f, " and {} more", self.count - self.faces.len())?;
        }
        write!(
            f,
            " (0-based); triangles must be counter-clockwise (a keyframe with a few inverted \
             triangles morphs with MorphOptions::allow_inverted)"
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

impl From<&PlanarMesh> for SurfaceMesh {
    /// The planar mesh in 3D, at z = 0, for the systems that take surfaces (geodesics,
    /// parameterisation).
    ///
    /// ```
    /// use bdmorph::{generate, geodesic::{HeatGeodesics, HeatOptions}, SurfaceMesh};
    /// let disk = generate::disk(6, 0.2);
    /// let mut g = HeatGeodesics::new(&SurfaceMesh::from(&disk), HeatOptions::default())?;
    /// assert_eq!(g.distance(&[0])?.len(), disk.positions.len());
    /// # Ok::<(), bdmorph::geodesic::GeodesicError>(())
    /// ```
    fn from(mesh: &PlanarMesh) -> SurfaceMesh {
        SurfaceMesh {
            positions: mesh.positions.iter().map(|&[x, y]| [x, y, 0.0]).collect(),
            faces: mesh.faces.clone(),
            texcoords: None,
        }
    }
}

impl From<PlanarMesh> for SurfaceMesh {
    /// As `SurfaceMesh::from(&mesh)`.
    fn from(mesh: PlanarMesh) -> SurfaceMesh {
        SurfaceMesh::from(&mesh)
    }
}

impl PlanarMesh {
    /// The vertex nearest `point` (the first of equally near ones), as the command line's
    /// `--drag X,Y:TX,TY` and `--fix X,Y` pick their handles; `None` for a mesh without
    /// vertices or a point that is not finite.
    ///
    /// ```
    /// let disk = bdmorph::generate::disk(6, 0.2);
    /// let v = disk.nearest_vertex([0.01, 0.0]).expect("a vertex");
    /// assert_eq!(disk.positions[v as usize], [0.0, 0.0]);
    /// ```
    pub fn nearest_vertex(&self, point: [f64; 2]) -> Option<u32> {
        if !(point[0].is_finite() && point[1].is_finite()) {
            return None;
        }
        let d = |q: &[f64; 2]| (q[0] - point[0]).powi(2) + (q[1] - point[1]).powi(2);
        self.positions
            .iter()
            .enumerate()
            .filter(|(_, q)| d(q).is_finite())
            .min_by(|(_, a), (_, b)| d(a).total_cmp(&d(b)))
            .map(|(v, _)| v as u32)
    }

    /// Reads a planar mesh from an OBJ or OFF file (z must be 0 when present).
    pub fn read(path: impl AsRef<Path>) -> Result<PlanarMesh, MeshError> {
        let path = path.as_ref();
        PlanarMesh::from_surface(io::read_mesh(path)?, path)
    }

    /// Reads a planar mesh and its texture coordinates (when the file has them for every
    /// corner).
    pub fn read_textured(
        path: impl AsRef<Path>,
    ) -> Result<(PlanarMesh, Option<TexCoords>), MeshError> {
        let path = path.as_ref();
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
    pub fn from_surface(
        mesh: SurfaceMesh,
        path: impl AsRef<Path>,
    ) -> Result<PlanarMesh, MeshError> {
        let path = path.as_ref();
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
        let inverted = self.validate_allowing_inverted()?;
        match inverted.len() {
            0 => Ok(()),
            1 => Err(MeshError::Clockwise {
                face: inverted[0],
                area: self.signed_area(&self.faces[inverted[0]]),
            }),
            count => Err(MeshError::Inverted {
                faces: inverted[..count.min(INVERTED_LISTED)].to_vec(),
                count,
                total: self.faces.len(),
            }),
        }
    }

    /// As [`PlanarMesh::validate`], but a few clockwise (inverted) triangles are allowed:
    /// returns them, in face order. A mesh with more clockwise triangles than
    /// counter-clockwise ones is still refused as [`MeshError::Mirrored`], and degenerate
    /// triangles as [`MeshError::Degenerate`].
    pub fn validate_allowing_inverted(&self) -> Result<Vec<usize>, MeshError> {
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
        let mut counter_clockwise = 0;
        let mut first_counter_clockwise = None;
        let mut degenerate = None;
        let mut inverted = Vec::new();
        for (face, f) in self.faces.iter().enumerate() {
            let area = self.signed_area(f);
            if area.abs() <= eps {
                degenerate.get_or_insert(MeshError::Degenerate { face, area });
            } else if area < 0.0 {
                inverted.push(face);
            } else {
                counter_clockwise += 1;
                first_counter_clockwise.get_or_insert(face);
            }
        }
        if inverted.len() > counter_clockwise {
            return Err(MeshError::Mirrored {
                clockwise: inverted.len(),
                faces: self.faces.len(),
                counter_clockwise,
                first_counter_clockwise,
            });
        }
        // Inverted triangles have a metric; degenerate ones do not.
        match degenerate {
            Some(e) => Err(e),
            None => Ok(inverted),
        }
    }

    /// For each face of `other` (a keyframe listing the same triangles as `self`, in any
    /// order, each triangle's corners possibly rotated: `a b c` as `b c a` or `c a b`), the
    /// index of the same triangle in `self`. Refuses a triangle that `self` does not have
    /// ([`MeshError::FaceMissing`]), one with its corners reversed
    /// ([`MeshError::FaceReversed`]) and one listed twice ([`MeshError::FaceRepeated`]),
    /// naming it by its index in `other`; counts must agree ([`MeshError::CountMismatch`]).
    ///
    /// ```
    /// use bdmorph::PlanarMesh;
    /// let a = PlanarMesh {
    ///     positions: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
    ///     faces: vec![[0, 1, 2], [0, 2, 3]],
    /// };
    /// let mut b = a.clone();
    /// b.faces = vec![[3, 0, 2], [1, 2, 0]];
    /// assert_eq!(a.match_faces(&b.faces)?, [1, 0]);
    /// b.faces[0] = [0, 3, 2];
    /// assert!(a.match_faces(&b.faces).is_err());
    /// # Ok::<(), bdmorph::MeshError>(())
    /// ```
    pub fn match_faces(&self, other: &[[u32; 3]]) -> Result<Vec<usize>, MeshError> {
        if self.faces.len() != other.len() {
            return Err(MeshError::CountMismatch {
                what: "face count",
                source_count: self.faces.len(),
                target_count: other.len(),
            });
        }
        // The same listing: nothing to look up.
        if self.faces == other {
            return Ok((0..other.len()).collect());
        }
        let canonical = |f: [u32; 3]| {
            // Rotate the smallest corner first: equal for rotations, different for reversals.
            let k = (0..3).min_by_key(|&i| f[i]).unwrap_or(0);
            [f[k], f[(k + 1) % 3], f[(k + 2) % 3]]
        };
        let mut index = std::collections::HashMap::with_capacity(self.faces.len());
        for (i, &f) in self.faces.iter().enumerate() {
            index.insert(canonical(f), i);
        }
        let mut seen = vec![usize::MAX; self.faces.len()];
        let mut map = Vec::with_capacity(other.len());
        for (face, &f) in other.iter().enumerate() {
            let Some(&i) = index.get(&canonical(f)) else {
                let reversed = canonical([f[0], f[2], f[1]]);
                return Err(match index.get(&reversed) {
                    Some(&i) => MeshError::FaceReversed {
                        face,
                        target_face: f,
                        source_face: i,
                        source_corners: self.faces[i],
                    },
                    None => MeshError::FaceMissing {
                        face,
                        target_face: f,
                    },
                });
            };
            if seen[i] != usize::MAX {
                return Err(MeshError::FaceRepeated {
                    face,
                    first: seen[i],
                });
            }
            seen[i] = face;
            map.push(i);
        }
        Ok(map)
    }

    /// Checks that `target` can be morphed with `self`: same counts, the same triangles (in
    /// any order, corners rotated or not: [`PlanarMesh::match_faces`]), both geometrically
    /// valid.
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
        self.match_faces(&target.faces)?;
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
        // Two of four: no majority, both named.
        mesh.faces[0].swap(0, 1);
        let err = mesh.validate().unwrap_err();
        assert!(
            matches!(&err, MeshError::Inverted { faces, count: 2, total: 4 } if faces == &[0, 2]),
            "{err}"
        );
        assert_eq!(
            err.to_string(),
            "2 of 4 triangles are clockwise (inverted): face 0, 2 (0-based); triangles must be \
             counter-clockwise (a keyframe with a few inverted triangles morphs with \
             MorphOptions::allow_inverted)"
        );
        assert_eq!(mesh.validate_allowing_inverted().unwrap(), [0, 2]);
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
