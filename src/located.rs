//! Errors that point at the line of the file a mesh was read from.
//!
//! The library's errors name faces and vertices by their 0-based index in the mesh's arrays
//! ([`MeshError::Clockwise`]'s `face`, [`CompileError::DuplicateFace`]'s `faces`, ...): a mesh
//! need not come from a file, and the compiler knows none. A mesh read with
//! [`MeshFile::read`] keeps the line each vertex and face came from ([`LineMap`]), and
//! [`MeshFile::locate`] turns an error about it into a [`Located`] one, which names the file
//! and the line, as parse errors do: the `f` or `v` line of an OBJ file, the line a face or
//! vertex record starts on in an OFF file. The error itself is kept, typed, in
//! [`Located::error`].
//!
//! ```
//! use bdmorph::io::parse_obj_with_lines;
//! use bdmorph::located::MeshFile;
//! use bdmorph::MeshError;
//! use std::path::Path;
//!
//! // A square of four triangles whose third is listed clockwise.
//! let text = "v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.5 0.5\n\
//!             f 1 2 5\nf 2 3 5\nf 3 5 4\nf 4 1 5\n";
//! let (mesh, lines) = parse_obj_with_lines(text, Path::new("square.obj"))?;
//! let file = MeshFile { path: "square.obj".into(), mesh, lines };
//! let err = file.planar().unwrap_err();
//! assert!(matches!(err.error, MeshError::Clockwise { face: 2, .. }));
//! assert_eq!(err.line, Some(8));
//! assert_eq!(
//!     err.to_string(),
//!     "square.obj:8: face 2 (0-based) is clockwise (signed area -2.5e-1); \
//!      triangles must be counter-clockwise, consistently (a keyframe with a few inverted \
//!      triangles morphs with MorphOptions::allow_inverted)"
//! );
//!
//! // Errors found later, here by the compiler, are located the same way.
//! let twice = text.replace("f 3 5 4", "f 3 4 5") + "f 2 5 1\n";
//! let (mesh, lines) = parse_obj_with_lines(&twice, Path::new("twice.obj"))?;
//! let file = MeshFile { path: "twice.obj".into(), mesh, lines };
//! let planar = file.planar()?;
//! let err = bdmorph::compile(&planar.positions, &planar.faces).unwrap_err();
//! assert_eq!(
//!     file.locate(err).to_string(),
//!     "twice.obj:10: face 0 and face 4 (0-based) are the same triangle (duplicate face); \
//!      face 4 is line 10, face 0 is line 6"
//! );
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::fmt;
use std::path::{Path, PathBuf};

use bdmorph_compiler::{CompileError, FaceId, VertexId};

use crate::geodesic::intrinsic::TriangulationError;
use crate::geodesic::GeodesicError;
use crate::io::{self, LineMap, ReadError, Shown, SurfaceMesh};
use crate::mesh::{MeshError, NotPlanarText, PlanarMesh};
use crate::morph::{MorphError, WORST_SHOWN};
use crate::param::ParamError;

/// A face or a vertex of a mesh, by its 0-based index.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Element {
    /// A face (triangle): its index in the face array.
    Face(usize),
    /// A vertex: its index in the position array.
    Vertex(usize),
}

impl fmt::Display for Element {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Element::Face(i) => write!(f, "face {i}"),
            Element::Vertex(i) => write!(f, "vertex {i}"),
        }
    }
}

/// An error about faces or vertices of a mesh, which a [`MeshFile`] can point at in its file.
pub trait Locate: std::error::Error {
    /// The faces and vertices the error is about, the main one first: the one whose line a
    /// located message starts with (the repeat of a duplicate face, the later of two faces
    /// that disagree, the face that cannot be reached, the worst triangle of a failed frame),
    /// then the others. `faces` are the mesh's triangles, to find the faces along an edge, or
    /// the face of a triangle, that the error names by their vertices.
    fn elements(&self, faces: &[[u32; 3]]) -> Vec<Element>;

    /// The message, without the file's name when the error's own message starts with it
    /// ([`MeshError::NotPlanar`]); by default the error's own message.
    fn message(&self) -> String {
        self.to_string()
    }

    /// Whether the message already names the file and the line ([`MeshError::Read`]), so that
    /// a located message shows it as it is.
    fn names_its_place(&self) -> bool {
        false
    }
}

/// How many places a located message lists.
const PLACES_SHOWN: usize = 4;

/// An error about a mesh read from a file, with the file and the lines of the faces and
/// vertices it is about.
///
/// Shown as `FILE:LINE: MESSAGE`, the line being the main face's or vertex's (as for parse
/// errors), or `FILE: MESSAGE` when the error names none; when it is about several, each
/// one's line follows (the first four): `twice.obj:10: face 0 and face 4 (0-based) are the
/// same triangle (duplicate face); face 4 is line 10, face 0 is line 6`.
#[derive(Debug)]
pub struct Located<E> {
    /// The file.
    pub path: PathBuf,
    /// The 1-based line of the main face or vertex, when the error names one and its line is
    /// known.
    pub line: Option<usize>,
    /// Each face and vertex the error is about whose line is known, with that line, the main
    /// one first.
    pub places: Vec<(Element, usize)>,
    /// The error.
    pub error: E,
}

impl<E: Locate> Located<E> {
    /// Locates `error`, about the mesh of triangles `faces` read from `path` with the lines
    /// `lines`.
    pub fn new(path: &Path, lines: &LineMap, faces: &[[u32; 3]], error: E) -> Located<E> {
        let line_of = |e: &Element| match *e {
            Element::Face(f) => lines.face_line(f),
            Element::Vertex(v) => lines.vertex_line(v),
        };
        let elements = error.elements(faces);
        let places = elements
            .iter()
            .filter_map(|e| line_of(e).map(|line| (*e, line)))
            .collect();
        Located {
            path: path.into(),
            line: elements.first().and_then(line_of),
            places,
            error,
        }
    }
}

impl<E: Locate> fmt::Display for Located<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.error.names_its_place() {
            f.write_str(&self.error.message())?;
        } else {
            write!(f, "{}", Shown(&self.path))?;
            if let Some(line) = self.line {
                write!(f, ":{line}")?;
            }
            write!(f, ": {}", self.error.message())?;
        }
        // One place is told by the prefix; several are listed, each with its line (the first
        // few: a message stays one short line).
        if self.places.len() > usize::from(self.line.is_some()) {
            for (i, (element, line)) in self.places.iter().take(PLACES_SHOWN).enumerate() {
                let sep = if i == 0 { "; " } else { ", " };
                write!(f, "{sep}{element} is line {line}")?;
            }
            if let Some(more) = self
                .places
                .len()
                .checked_sub(PLACES_SHOWN)
                .filter(|&n| n > 0)
            {
                write!(f, " and {more} more")?;
            }
        }
        Ok(())
    }
}

impl<E: Locate + 'static> std::error::Error for Located<E> {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

/// A mesh as read from a file: the file's name, the mesh, and the line each vertex and face
/// was read from, to point errors about the mesh at their lines.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshFile {
    /// The file.
    pub path: PathBuf,
    /// The mesh.
    pub mesh: SurfaceMesh,
    /// Where each vertex and face was read.
    pub lines: LineMap,
}

impl MeshFile {
    /// Reads an `.obj` or `.off` file as [`io::read_mesh`] does, keeping the lines.
    pub fn read(path: impl AsRef<Path>) -> Result<MeshFile, ReadError> {
        let path = path.as_ref();
        let (mesh, lines) = io::read_mesh_with_lines(path)?;
        Ok(MeshFile {
            path: path.into(),
            mesh,
            lines,
        })
    }

    /// `error`, about this mesh, with the file and the lines of the faces and vertices it is
    /// about.
    pub fn locate<E: Locate>(&self, error: E) -> Located<E> {
        Located::new(&self.path, &self.lines, &self.mesh.faces, error)
    }

    /// The mesh as a planar mesh, checked as a morph's keyframe must be
    /// ([`PlanarMesh::from_surface`], then [`PlanarMesh::validate`]: z = 0, finite, every
    /// triangle counter-clockwise and not degenerate), with its errors located.
    pub fn planar(&self) -> Result<PlanarMesh, Located<MeshError>> {
        let planar = self.planar_allowing_inverted()?;
        planar.validate().map_err(|e| self.locate(e))?;
        Ok(planar)
    }

    /// As [`MeshFile::planar`], but a few inverted (clockwise) triangles are allowed (see
    /// [`PlanarMesh::validate_allowing_inverted`]).
    pub fn planar_allowing_inverted(&self) -> Result<PlanarMesh, Located<MeshError>> {
        let surface = SurfaceMesh {
            positions: self.mesh.positions.clone(),
            faces: self.mesh.faces.clone(),
            texcoords: None,
        };
        let planar = PlanarMesh::from_surface(surface, &self.path).map_err(|e| self.locate(e))?;
        planar
            .validate_allowing_inverted()
            .map_err(|e| self.locate(e))?;
        Ok(planar)
    }
}

/// The faces that have both `a` and `b` as corners, in order.
fn faces_on_edge(faces: &[[u32; 3]], a: u32, b: u32) -> Vec<Element> {
    let on = |f: &[u32; 3]| f.contains(&a) && f.contains(&b);
    let found = faces.iter().enumerate().filter(|(_, f)| on(f));
    found.map(|(i, _)| Element::Face(i)).collect()
}

/// The face with these corners: in this cyclic order if there is one, else in any order.
fn face_of(faces: &[[u32; 3]], corners: [u32; 3]) -> Option<Element> {
    let [a, b, c] = corners;
    let rotations = [[a, b, c], [b, c, a], [c, a, b]];
    let same_set = |f: &[u32; 3]| {
        let (mut x, mut y) = (*f, corners);
        x.sort_unstable();
        y.sort_unstable();
        x == y
    };
    faces
        .iter()
        .position(|f| rotations.contains(f))
        .or_else(|| faces.iter().position(same_set))
        .map(Element::Face)
}

fn face(f: FaceId) -> Element {
    Element::Face(f.0 as usize)
}

fn vertex(v: VertexId) -> Element {
    Element::Vertex(v.0 as usize)
}

impl Locate for CompileError {
    fn elements(&self, faces: &[[u32; 3]]) -> Vec<Element> {
        match *self {
            CompileError::VertexOutOfRange { face: f, .. }
            | CompileError::RepeatedVertex { face: f } => {
                vec![face(f)]
            }
            CompileError::Disconnected { face: f } => vec![face(f), Element::Face(0)],
            CompileError::NonFinitePosition { vertex: v }
            | CompileError::NonManifoldVertex { vertex: v }
            | CompileError::UnreferencedVertex { vertex: v } => vec![vertex(v)],
            CompileError::NonManifoldEdge { a, b, .. } => faces_on_edge(faces, a.0, b.0),
            CompileError::DuplicateFace {
                faces: [first, repeat],
            } => vec![face(repeat), face(first)],
            CompileError::InconsistentOrientation { faces: [f, g], .. } => vec![face(g), face(f)],
            _ => Vec::new(),
        }
    }
}

impl Locate for MeshError {
    fn elements(&self, faces: &[[u32; 3]]) -> Vec<Element> {
        match self {
            MeshError::Read(_) | MeshError::CountMismatch { .. } | MeshError::NoTriangles => {
                Vec::new()
            }
            MeshError::NotPlanar { vertex, .. } | MeshError::NonFinite { vertex } => {
                vec![Element::Vertex(*vertex)]
            }
            MeshError::IndexOutOfRange { face, .. }
            | MeshError::Degenerate { face, .. }
            | MeshError::Clockwise { face, .. }
            | MeshError::FaceMissing { face, .. }
            | MeshError::FaceReversed { face, .. } => vec![Element::Face(*face)],
            MeshError::FaceRepeated { face, first } => {
                vec![Element::Face(*face), Element::Face(*first)]
            }
            MeshError::Inverted { faces, .. } => faces.iter().map(|&f| Element::Face(f)).collect(),
            MeshError::Mirrored {
                first_counter_clockwise,
                ..
            } => first_counter_clockwise
                .map(Element::Face)
                .into_iter()
                .collect(),
            MeshError::Topology(e) => e.elements(faces),
        }
    }

    fn message(&self) -> String {
        match self {
            MeshError::NotPlanar { vertex, z, .. } => NotPlanarText(*vertex, *z).to_string(),
            other => other.to_string(),
        }
    }

    fn names_its_place(&self) -> bool {
        matches!(self, MeshError::Read(_))
    }
}

impl Locate for TriangulationError {
    fn elements(&self, _faces: &[[u32; 3]]) -> Vec<Element> {
        match *self {
            TriangulationError::NonManifoldEdge { first, second, .. } => {
                vec![Element::Face(second), Element::Face(first)]
            }
            TriangulationError::BadFace { face, .. }
            | TriangulationError::Degenerate { face, .. } => {
                vec![Element::Face(face)]
            }
        }
    }
}

impl Locate for GeodesicError {
    fn elements(&self, faces: &[[u32; 3]]) -> Vec<Element> {
        match self {
            GeodesicError::NonFinite { vertex } => vec![Element::Vertex(*vertex)],
            GeodesicError::Triangulation(e) => e.elements(faces),
            _ => Vec::new(),
        }
    }
}

impl Locate for ParamError {
    fn elements(&self, faces: &[[u32; 3]]) -> Vec<Element> {
        match self {
            ParamError::NotADisk(e) => e.elements(faces),
            ParamError::NonFinite { vertex } => vec![Element::Vertex(*vertex)],
            ParamError::Degenerate { face } => vec![Element::Face(*face)],
            _ => Vec::new(),
        }
    }
}

impl Locate for MorphError {
    /// The faces of a frame's worst triangles (as many as the message shows), and those of the
    /// mesh errors; for a keyframe's error, its elements in that keyframe.
    fn elements(&self, faces: &[[u32; 3]]) -> Vec<Element> {
        match self {
            MorphError::Mesh(e) | MorphError::Keyframe { source: e, .. } => e.elements(faces),
            MorphError::MetricBreaks { face, .. } => vec![Element::Face(*face)],
            MorphError::ProgramMismatch { face } => face_of(faces, *face).into_iter().collect(),
            MorphError::NotConverged { worst, .. } | MorphError::Solver { worst, .. } => worst
                .iter()
                .take(WORST_SHOWN)
                .filter_map(|t| face_of(faces, t.vertices))
                .collect(),
            _ => Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TriangleReport;

    /// A square of four triangles around vertex 4, as `square.obj` would list it: five `v`
    /// lines, a blank line, four `f` lines.
    fn square() -> MeshFile {
        let text = "v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.5 0.5\n\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n";
        let (mesh, lines) = io::parse_obj_with_lines(text, Path::new("square.obj")).unwrap();
        MeshFile {
            path: "square.obj".into(),
            mesh,
            lines,
        }
    }

    #[test]
    fn messages_name_the_line_of_the_main_element_and_list_the_others() {
        let file = square();
        // One face: its line, and nothing after the message.
        let one = file.locate(MeshError::Degenerate { face: 1, area: 0.0 });
        assert_eq!(
            (one.line, &one.places[..]),
            (Some(8), &[(Element::Face(1), 8)][..])
        );
        assert_eq!(
            one.to_string(),
            "square.obj:8: face 1 (0-based) is degenerate (area 0e0)"
        );
        // A vertex: its `v` line.
        let lonely = CompileError::UnreferencedVertex {
            vertex: VertexId(3),
        };
        assert_eq!(
            file.locate(lonely).to_string(),
            "square.obj:4: vertex 3 (0-based) belongs to no face"
        );
        // Several: the main one's line first, then each one's.
        let twice = CompileError::DuplicateFace {
            faces: [FaceId(0), FaceId(3)],
        };
        assert_eq!(
            file.locate(twice).to_string(),
            "square.obj:10: face 0 and face 3 (0-based) are the same triangle (duplicate face); \
             face 3 is line 10, face 0 is line 7"
        );
        // The faces along an edge named by its vertices.
        let edge = CompileError::NonManifoldEdge {
            a: VertexId(1),
            b: VertexId(4),
            faces: 2,
        };
        let located = file.locate(edge);
        assert_eq!(located.line, Some(7));
        assert!(located
            .to_string()
            .ends_with("(non-manifold); face 0 is line 7, face 1 is line 8"));
        // Many: the first four.
        let mut fan = file.clone();
        fan.mesh.faces = vec![[1, 4, 0]; 6];
        fan.lines = LineMap::new(&[], &[11, 12, 13, 14, 15, 16]);
        let edge = CompileError::NonManifoldEdge {
            a: VertexId(1),
            b: VertexId(4),
            faces: 6,
        };
        let located = fan.locate(edge);
        assert_eq!(located.places.len(), 6);
        assert!(located.to_string().ends_with(
            "; face 0 is line 11, face 1 is line 12, face 2 is line 13, face 3 is line 14 and 2 more"
        ));
        // No element: the file alone.
        let count = MeshError::CountMismatch {
            what: "vertex count",
            source_count: 5,
            target_count: 6,
        };
        assert_eq!(
            file.locate(count).to_string(),
            "square.obj: source and target differ: vertex count 5 vs 6"
        );
        // A line not known (a face beyond the map) is left out.
        let far = file.locate(CompileError::Disconnected { face: FaceId(9) });
        assert_eq!((far.line, far.places.len()), (None, 1));
        assert_eq!(
            far.to_string(),
            "square.obj: the mesh is not connected: face 9 (0-based) cannot be reached from \
             face 0, and a compiled program holds one piece; face 0 is line 7"
        );
        assert!(std::error::Error::source(&far).is_some());
    }

    #[test]
    fn errors_that_name_the_file_themselves_name_it_once() {
        let file = square();
        let bent = MeshError::NotPlanar {
            path: "square.obj".into(),
            vertex: 2,
            z: 0.5,
        };
        assert_eq!(
            file.locate(bent).to_string(),
            "square.obj:3: vertex 2 (0-based) has z = 0.5; a planar mesh (z = 0) is required"
        );
        let read = io::parse_obj("v 0 x", Path::new("square.obj")).unwrap_err();
        let located = file.locate(MeshError::Read(read));
        assert_eq!(
            located.to_string(),
            "square.obj:1: expected a number after 'v', found 'x'"
        );
        // Text parsed without a file name.
        let (mesh, lines) =
            io::parse_obj_with_lines("v 0 0\nv 0 1\nv 1 0\nf 1 2 3\n", Path::new("")).unwrap();
        let unnamed = MeshFile {
            path: PathBuf::new(),
            mesh,
            lines,
        };
        let err = unnamed.planar().unwrap_err();
        assert_eq!(err.line, None);
        assert!(err
            .to_string()
            .starts_with("<string>: the only triangle is clockwise: "));
    }

    #[test]
    fn triangles_named_by_their_vertices_are_found() {
        let faces = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
        assert_eq!(face_of(&faces, [4, 2, 3]), Some(Element::Face(2)));
        assert_eq!(face_of(&faces, [3, 2, 4]), Some(Element::Face(2)));
        assert_eq!(face_of(&faces, [0, 1, 2]), None);
        let file = square();
        let report = |vertices| TriangleReport {
            vertices,
            lengths: [1.0; 3],
            margin: 0.1,
        };
        let failed = MorphError::NotConverged {
            at: crate::FrameAt::Time(0.5),
            iterations: 1,
            gradient_norm: 1e-3,
            worst: vec![
                report([4, 3, 0]),
                report([1, 2, 4]),
                report([9, 9, 9]),
                report([0, 1, 4]),
            ],
        };
        let located = file.locate(failed);
        assert_eq!(located.line, Some(10));
        assert!(
            located
                .to_string()
                .ends_with("; face 3 is line 10, face 1 is line 8"),
            "{located}"
        );
        let mismatch = MorphError::ProgramMismatch { face: [4, 1, 2] };
        assert_eq!(file.locate(mismatch).line, Some(8));
    }
}
