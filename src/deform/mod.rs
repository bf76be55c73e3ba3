//! Posing a planar mesh by handles: a precompute object per mesh and method, pins set when
//! the set of handles changes (the only time anything is factored), and a cheap, warm-started,
//! allocation-free drag per mouse move.
//!
//! Methods so far: [`Method::Arap`], as-rigid-as-possible with hard pins (2D local/global,
//! Sorkine and Alexa 2007, in the planar form of Liu et al. 2008): each drag runs a few
//! local/global iterations from the previous drag's result with one prefactored cotangent
//! Laplacian. (The issue's `kvf` and per-drag `bounded` methods are still to come; bounded
//! distortion posing is `bdmorph deform --max-distortion` today.)
//!
//! ```
//! use bdmorph::deform::{Deformer, Method};
//! use bdmorph::generate;
//! let rest = generate::grid(10, 4, 0.0);                // 10 x 4 vertices, 9 x 3 units
//! let mut pose = Deformer::new(&rest, Method::arap())?;
//! // Pin the bottom-left corner where it is and drag the bottom-right one up.
//! let (left, right) = (0u32, 9u32);
//! pose.set_pins(&[left, right])?;
//! let report = pose.drag(&[rest.positions[0], [8.5, 2.0]])?;
//! assert_eq!(pose.positions()[9], [8.5, 2.0]);         // hard pins are met exactly
//! assert!(report.iterations >= 1);
//! # Ok::<(), bdmorph::deform::DeformError>(())
//! ```

mod arap;

use crate::mesh::{MeshError, PlanarMesh};
use crate::param::frames::Frames;

pub use arap::ArapOptions;

/// How the mesh follows its handles.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Method {
    /// As-rigid-as-possible with hard pins.
    Arap(ArapOptions),
}

impl Method {
    /// ARAP with the default options.
    pub fn arap() -> Method {
        Method::Arap(ArapOptions::default())
    }
}

/// Why posing failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DeformError {
    /// The mesh is not valid.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A pin names a vertex that does not exist.
    #[error("pin {pin} names vertex {vertex} (0-based), but the mesh has {n_vertices} vertices")]
    PinOutOfRange {
        /// The pin's place in the list.
        pin: usize,
        /// Its vertex.
        vertex: u32,
        /// Vertices of the mesh.
        n_vertices: usize,
    },
    /// A vertex is pinned twice.
    #[error("vertex {vertex} (0-based) is pinned twice")]
    PinnedTwice {
        /// The vertex.
        vertex: u32,
    },
    /// A piece of the mesh has no pin: nothing holds it in place.
    #[error("the piece holding vertex {vertex} (0-based) has no pin; every piece needs one")]
    PieceWithoutPin {
        /// A vertex of that piece.
        vertex: u32,
    },
    /// `drag` before `set_pins`, or with another number of targets than pins.
    #[error("{got} targets given for {pins} pins")]
    TargetCount {
        /// Pins set.
        pins: usize,
        /// Targets given.
        got: usize,
    },
    /// A target that is not a finite point.
    #[error("target {index} is not a finite point")]
    NonFiniteTarget {
        /// Its place in the list.
        index: usize,
    },
    /// The linear solver failed.
    #[error("the ARAP system could not be factored or solved: {0}")]
    Solver(#[from] crate::CholeskyError),
}

/// What a drag did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DragReport {
    /// Local/global iterations run.
    pub iterations: u32,
    /// The ARAP energy after them (area-weighted mean of `|J - R|²`).
    pub energy: f64,
    /// The largest move of any vertex in the last iteration, relative to the mesh's size:
    /// how far from converged the pose is.
    pub last_change: f64,
    /// Triangles with non-positive signed area in the pose.
    pub flipped_triangles: usize,
    /// The largest distance of a pinned vertex from its target (0 for hard pins).
    pub pin_residual: f64,
}

/// A mesh prepared for posing.
pub struct Deformer {
    rest: PlanarMesh,
    frames: Frames,
    diameter: f64,
    positions: Vec<[f64; 2]>,
    solver: arap::Arap,
}

impl std::fmt::Debug for Deformer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Deformer")
            .field("vertices", &self.rest.positions.len())
            .field("faces", &self.rest.faces.len())
            .finish_non_exhaustive()
    }
}

impl Deformer {
    /// Checks the mesh (a valid planar mesh: counter-clockwise, no degenerate triangle) and
    /// prepares the method's constants. Nothing is factored until [`Deformer::set_pins`].
    pub fn new(mesh: &PlanarMesh, method: Method) -> Result<Deformer, DeformError> {
        mesh.validate()?;
        let surface = crate::SurfaceMesh {
            positions: mesh.positions.iter().map(|p| [p[0], p[1], 0.0]).collect(),
            faces: mesh.faces.clone(),
            texcoords: None,
        };
        let frames = Frames::new(&surface).map_err(|face| MeshError::Degenerate {
            face,
            area: mesh.signed_area(&mesh.faces[face]),
        })?;
        let Method::Arap(options) = method;
        Ok(Deformer {
            solver: arap::Arap::new(&frames, mesh.positions.len(), options),
            diameter: mesh.diameter().max(f64::MIN_POSITIVE),
            positions: mesh.positions.clone(),
            rest: mesh.clone(),
            frames,
        })
    }

    /// Sets the pinned vertices (the handles, in the order [`Deformer::drag`] takes their
    /// targets) and factors the system. The pose so far is kept as the next drag's start.
    pub fn set_pins(&mut self, pins: &[u32]) -> Result<(), DeformError> {
        let n = self.rest.positions.len();
        let mut pinned = vec![false; n];
        for (pin, &v) in pins.iter().enumerate() {
            if v as usize >= n {
                return Err(DeformError::PinOutOfRange {
                    pin,
                    vertex: v,
                    n_vertices: n,
                });
            }
            if std::mem::replace(&mut pinned[v as usize], true) {
                return Err(DeformError::PinnedTwice { vertex: v });
            }
        }
        if let Some(vertex) = unpinned_piece(n, &self.rest.faces, &pinned) {
            return Err(DeformError::PieceWithoutPin { vertex });
        }
        self.solver.set_pins(&self.frames, pins)
    }

    /// Moves the pins to `targets` (one per pin, in [`Deformer::set_pins`]'s order) and
    /// updates the pose, starting from the previous one. Allocates nothing.
    pub fn drag(&mut self, targets: &[[f64; 2]]) -> Result<DragReport, DeformError> {
        let mut report =
            self.solver
                .drag(&self.frames, targets, &mut self.positions, self.diameter)?;
        report.flipped_triangles = self
            .rest
            .faces
            .iter()
            .filter(|f| {
                let [a, b, c] = f.map(|v| self.positions[v as usize]);
                (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) <= 0.0
            })
            .count();
        Ok(report)
    }

    /// The current pose, one position per vertex.
    pub fn positions(&self) -> &[[f64; 2]] {
        &self.positions
    }

    /// Puts the pose back to the rest shape (pins stay).
    pub fn reset(&mut self) {
        self.positions.copy_from_slice(&self.rest.positions);
    }
}

/// A vertex of a piece (faces connected through shared vertices) with no pinned vertex.
fn unpinned_piece(n: usize, faces: &[[u32; 3]], pinned: &[bool]) -> Option<u32> {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    for f in faces {
        for k in 1..3 {
            let (a, b) = (find(&mut parent, f[0]), find(&mut parent, f[k]));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut held = vec![false; n];
    for v in 0..n as u32 {
        if pinned[v as usize] {
            let r = find(&mut parent, v);
            held[r as usize] = true;
        }
    }
    let mut used = vec![false; n];
    for f in faces {
        for &v in f {
            used[v as usize] = true;
        }
    }
    (0..n as u32).find(|&v| used[v as usize] && !held[find(&mut parent, v) as usize])
}
