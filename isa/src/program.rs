//! The compiled program and its parts.

use crate::verify::{verify, VerifyError};

/// The lower triangle (diagonal included) of the symmetric Hessian in compressed sparse column
/// form over the unknowns. In column `k` the diagonal comes first and rows are strictly
/// increasing, which is the order in which `VertexInfo` writes its value slots.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HessianPattern {
    /// `col_ptr[k]..col_ptr[k + 1]` are the value slots of column `k`; length `n + 1`.
    pub col_ptr: Vec<u32>,
    /// Row index of each value slot.
    pub row_idx: Vec<u32>,
}

impl HessianPattern {
    /// Number of rows and columns.
    pub fn dim(&self) -> usize {
        self.col_ptr.len().saturating_sub(1)
    }

    /// Number of stored values (the length of the CSC value array).
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }
}

/// Start of the layout: the anchor vertex and its neighbour, whose edge direction is given at
/// run time (the rigid motion of the frame).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmbedRoot {
    /// The anchor vertex, placed at the position given at run time.
    pub p0: u32,
    /// The anchor's neighbour, placed at `p0 + L[edge] * direction`.
    pub p1: u32,
    /// Edge slot of `p0 p1`.
    pub edge: u32,
}

/// One step of the embed stream: triangle `(a, b, c)`, counter-clockwise, entered through the
/// edge `a b` whose direction is already known. The step computes the directions of edges
/// `b c` and `c a` from the corner angles at `a` and `b`, and places `c` when [`Self::PLACE`]
/// is set.
///
/// Directions are stored per edge slot, oriented from `edges[slot][0]` to `edges[slot][1]`;
/// the `REV_*` flags say that the step's orientation of that edge is the opposite one.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmbedStep {
    /// First vertex of the entry edge.
    pub a: u32,
    /// Second vertex of the entry edge.
    pub b: u32,
    /// The third vertex.
    pub c: u32,
    /// Edge slot of `a b`.
    pub e_ab: u32,
    /// Edge slot of `b c`.
    pub e_bc: u32,
    /// Edge slot of `c a`.
    pub e_ca: u32,
    /// Bit set of `REV_AB`, `REV_BC`, `REV_CA`, `PLACE`.
    pub flags: u32,
}

impl EmbedStep {
    /// Edge slot `e_ab` is stored oriented `b -> a`.
    pub const REV_AB: u32 = 1;
    /// Edge slot `e_bc` is stored oriented `c -> b`.
    pub const REV_BC: u32 = 2;
    /// Edge slot `e_ca` is stored oriented `a -> c`.
    pub const REV_CA: u32 = 4;
    /// Vertex `c` is placed by this step (it is the first step to reach it).
    pub const PLACE: u32 = 8;
}

/// The unverified parts of a program, as the compiler emits them or a loader reads them.
/// [`Program::from_parts`] verifies them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ProgramParts {
    /// Number of mesh vertices.
    pub n_vertices: u32,
    /// Number of mesh triangles.
    pub n_faces: u32,
    /// The init stream: the two vertices of each edge slot.
    pub edges: Vec<[u32; 2]>,
    /// The mesh vertex of each unknown.
    pub unknown_vertex: Vec<u32>,
    /// Edge slots written by the iteration stream (the rest join boundary vertices).
    pub n_iter_edges: u32,
    /// Temporaries written by the iteration stream.
    pub n_temps: u32,
    /// The iteration stream.
    pub iteration: Vec<u16>,
    /// The Hessian's pattern.
    pub hessian: HessianPattern,
    /// Start of the layout.
    pub embed_root: EmbedRoot,
    /// The embed stream.
    pub embed: Vec<EmbedStep>,
    /// A fill-reducing ordering of the unknowns for the Cholesky factorisation of the Hessian,
    /// or `None` to let the VM choose one (AMD). `ordering[new] = old`: the unknown that
    /// comes `new`-th in elimination order (faer's forward permutation). Must be a
    /// permutation of `0..n_unknowns`; with no unknowns, `Some(vec![])` becomes `None`.
    pub ordering: Option<Vec<u32>>,
}

/// A compiled, verified BDMORPH program. See the crate documentation for its parts.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Program {
    pub(crate) n_vertices: u32,
    pub(crate) n_faces: u32,
    pub(crate) n_iter_edges: u32,
    pub(crate) n_temps: u32,
    pub(crate) edges: Vec<[u32; 2]>,
    pub(crate) unknown_vertex: Vec<u32>,
    pub(crate) iteration: Vec<u16>,
    pub(crate) hessian: HessianPattern,
    pub(crate) embed_root: EmbedRoot,
    pub(crate) embed: Vec<EmbedStep>,
    pub(crate) ordering: Option<Vec<u32>>,
}

/// Sizes of a program, for reports and benchmarks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgramStats {
    /// Vertices of the mesh.
    pub vertices: usize,
    /// Triangles of the mesh.
    pub faces: usize,
    /// Unknowns (interior vertices).
    pub unknowns: usize,
    /// Edge slots (all edges of the mesh).
    pub edges: usize,
    /// Bytes of the iteration stream.
    pub iteration_bytes: usize,
    /// Bytes of the iteration stream per triangle.
    pub iteration_bytes_per_face: f64,
    /// Bytes of all streams in memory: init, iteration, embed, Hessian pattern, the unknowns'
    /// vertices and the ordering.
    pub total_bytes: usize,
    /// Bytes of the program's file ([`Program::to_bytes`]), header and checksum included.
    pub file_bytes: usize,
    /// Stored values of the Hessian's lower triangle.
    pub hessian_nnz: usize,
}

impl Program {
    /// Assembles a program from its parts and verifies it (see [`VerifyError`]).
    pub fn from_parts(parts: ProgramParts) -> Result<Program, VerifyError> {
        let ProgramParts {
            n_vertices,
            n_faces,
            edges,
            unknown_vertex,
            n_iter_edges,
            n_temps,
            iteration,
            hessian,
            embed_root,
            embed,
            ordering,
        } = parts;
        // Without unknowns, an empty ordering is the same as none (and stored as none).
        let ordering = ordering.filter(|o| !(o.is_empty() && unknown_vertex.is_empty()));
        let program = Program {
            n_vertices,
            n_faces,
            n_iter_edges,
            n_temps,
            edges,
            unknown_vertex,
            iteration,
            hessian,
            embed_root,
            embed,
            ordering,
        };
        verify(&program)?;
        Ok(program)
    }

    /// A copy of the program's parts (for serialisation or inspection).
    pub fn to_parts(&self) -> ProgramParts {
        ProgramParts {
            n_vertices: self.n_vertices,
            n_faces: self.n_faces,
            edges: self.edges.clone(),
            unknown_vertex: self.unknown_vertex.clone(),
            n_iter_edges: self.n_iter_edges,
            n_temps: self.n_temps,
            iteration: self.iteration.clone(),
            hessian: self.hessian.clone(),
            embed_root: self.embed_root,
            embed: self.embed.clone(),
            ordering: self.ordering.clone(),
        }
    }

    /// Number of mesh vertices (the length of a position array).
    pub fn n_vertices(&self) -> usize {
        self.n_vertices as usize
    }
    /// Number of triangles of the mesh.
    pub fn n_faces(&self) -> usize {
        self.n_faces as usize
    }
    /// Number of unknowns (interior vertices).
    pub fn n_unknowns(&self) -> usize {
        self.unknown_vertex.len()
    }
    /// Number of edge slots (every edge of the mesh).
    pub fn n_edges(&self) -> usize {
        self.edges.len()
    }
    /// Edge slots written by the iteration stream; slots from here on join boundary vertices.
    pub fn n_iter_edges(&self) -> usize {
        self.n_iter_edges as usize
    }
    /// Number of temporaries written by the iteration stream.
    pub fn n_temps(&self) -> usize {
        self.n_temps as usize
    }
    /// The init stream: the two vertices of each edge slot.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }
    /// The mesh vertex of each unknown.
    pub fn unknown_vertex(&self) -> &[u32] {
        &self.unknown_vertex
    }
    /// The iteration stream.
    pub fn iteration(&self) -> &[u16] {
        &self.iteration
    }
    /// The Hessian's CSC pattern (lower triangle).
    pub fn hessian(&self) -> &HessianPattern {
        &self.hessian
    }
    /// The layout's starting edge.
    pub fn embed_root(&self) -> EmbedRoot {
        self.embed_root
    }
    /// The embed stream.
    pub fn embed(&self) -> &[EmbedStep] {
        &self.embed
    }
    /// The fill-reducing ordering of the unknowns, if the program carries one:
    /// `ordering[new] = old`, a permutation of `0..n_unknowns` (see [`ProgramParts::ordering`]).
    pub fn ordering(&self) -> Option<&[u32]> {
        self.ordering.as_deref()
    }

    /// Sizes of the program. This encodes the program to measure its file.
    pub fn stats(&self) -> ProgramStats {
        let iteration_bytes = self.iteration.len() * 2;
        let total_bytes = iteration_bytes
            + self.edges.len() * 8
            + self.embed.len() * std::mem::size_of::<EmbedStep>()
            + (self.hessian.col_ptr.len() + self.hessian.row_idx.len()) * 4
            + self.unknown_vertex.len() * 4
            + self.ordering.as_ref().map_or(0, |o| o.len() * 4);
        ProgramStats {
            vertices: self.n_vertices(),
            faces: self.n_faces(),
            unknowns: self.n_unknowns(),
            edges: self.n_edges(),
            iteration_bytes,
            iteration_bytes_per_face: iteration_bytes as f64 / self.n_faces.max(1) as f64,
            total_bytes,
            file_bytes: self.file_sizes().total(),
            hessian_nnz: self.hessian.nnz(),
        }
    }
}
