//! Why a mesh cannot be compiled.

use crate::ids::{FaceId, VertexId};

/// A mesh the compiler refuses, with the elements that show why. All indices are 0-based, and
/// the messages say so; the compiler knows no file, so a caller that read the mesh from one
/// names the lines (`bdmorph::located`).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum CompileError {
    /// The mesh has no triangles.
    #[error("the mesh has no triangles")]
    NoFaces,
    /// The mesh is too large for 32-bit indices.
    #[error("the mesh is too large ({vertices} vertices, {faces} faces) for 32-bit indices")]
    TooLarge {
        /// Vertex count.
        vertices: usize,
        /// Face count.
        faces: usize,
    },
    /// A face names a vertex that does not exist.
    #[error("{face} refers to vertex {vertex} (0-based), but the mesh has {n_vertices} vertices")]
    VertexOutOfRange {
        /// The face.
        face: FaceId,
        /// The index it uses.
        vertex: u32,
        /// Number of vertices.
        n_vertices: usize,
    },
    /// The anchor asked for does not exist.
    #[error("anchor {anchor} (0-based) does not exist: the mesh has {n_vertices} vertices")]
    AnchorOutOfRange {
        /// The anchor.
        anchor: VertexId,
        /// Number of vertices.
        n_vertices: usize,
    },
    /// A face uses one vertex twice.
    #[error("{face} (0-based) uses the same vertex twice")]
    RepeatedVertex {
        /// The face.
        face: FaceId,
    },
    /// A vertex position is NaN or infinite.
    #[error("{vertex} (0-based) has a non-finite coordinate")]
    NonFinitePosition {
        /// The vertex.
        vertex: VertexId,
    },
    /// Inert-face flags given for another number of faces.
    #[error("{flags} inert-face flags given for a mesh of {faces} faces")]
    InertCount {
        /// Flags given.
        flags: usize,
        /// Faces.
        faces: usize,
    },
    /// Every face is inert: nothing would lay the mesh out.
    #[error("every face is inert: a program needs at least one face that is laid out")]
    AllInert,
    /// The position array and the faces disagree on the number of vertices.
    #[error("{positions} positions given for a mesh of {n_vertices} vertices")]
    PositionCount {
        /// Positions given.
        positions: usize,
        /// Vertices expected.
        n_vertices: usize,
    },
    /// More than two faces share an edge.
    #[error("the edge between {a} and {b} (0-based) is shared by {faces} faces (non-manifold)")]
    NonManifoldEdge {
        /// One end.
        a: VertexId,
        /// The other end.
        b: VertexId,
        /// How many faces share it.
        faces: usize,
    },
    /// The same triangle is listed twice (in either orientation).
    #[error("{} and {} (0-based) are the same triangle (duplicate face)", faces[0], faces[1])]
    DuplicateFace {
        /// The first listing and the repeat, in face order.
        faces: [FaceId; 2],
    },
    /// Two faces traverse an edge in the same direction.
    #[error("{} and {} both run from {a} to {b} (0-based): inconsistent orientation", faces[0], faces[1])]
    InconsistentOrientation {
        /// Start of the directed edge.
        a: VertexId,
        /// End of the directed edge.
        b: VertexId,
        /// The two faces.
        faces: [FaceId; 2],
    },
    /// The faces around a vertex do not form a single fan (for example a bow tie).
    #[error("{vertex} (0-based) is non-manifold: its faces do not form a single fan")]
    NonManifoldVertex {
        /// The vertex.
        vertex: VertexId,
    },
    /// A vertex belongs to no face.
    #[error("{vertex} (0-based) belongs to no face")]
    UnreferencedVertex {
        /// The vertex.
        vertex: VertexId,
    },
    /// The mesh has several connected components: one program holds one piece (a morph
    /// compiles each piece alone; program files hold one).
    #[error("the mesh is not connected: {face} (0-based) cannot be reached from face 0, and a compiled program holds one piece")]
    Disconnected {
        /// A face of another component.
        face: FaceId,
    },
    /// The mesh has no boundary.
    #[error("the mesh is a closed surface (Euler characteristic {euler}); a disk is required")]
    ClosedSurface {
        /// Its Euler characteristic.
        euler: i64,
    },
    /// The mesh has holes: one program holds one disk (a morph fills holes before compiling,
    /// see `bdmorph::morph`; program files hold disks only).
    #[error("the mesh has {loops} boundary loops (Euler characteristic {euler}): it has holes, and a compiled program holds one disk")]
    HasHoles {
        /// Boundary loops.
        loops: usize,
        /// Euler characteristic.
        euler: i64,
    },
    /// One boundary loop, but handles: not a disk.
    #[error("the mesh is not a disk (Euler characteristic {euler}, {loops} boundary loop)")]
    NotADisk {
        /// Euler characteristic.
        euler: i64,
        /// Boundary loops.
        loops: usize,
    },
    /// An internal invariant failed: the emitted program did not verify. This is a compiler bug.
    #[error("internal error: the compiled program failed verification: {0}")]
    Internal(#[from] bdmorph_isa::VerifyError),
}
