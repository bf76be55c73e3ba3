//! # bdmorph
//!
//! Bounded-distortion planar shape interpolation (BDMORPH, Chen, Weber, Keren and Ben-Chen
//! 2013) as a compile-once, run-many runtime.
//!
//! Two planar triangle meshes with the same triangles are interpolated by blending their
//! squared edge lengths, flattening the blended metric with a conformal scale factor per
//! interior vertex (Newton's method on the convex CETM energy), and laying the flat metric out
//! in the plane. The mesh's connectivity is compiled once ([`bdmorph_compiler`]) into command
//! streams that a VM ([`bdmorph_vm`]) executes every Newton iteration, with the Hessian's
//! symbolic Cholesky factorisation computed once per mesh.
//!
//! Beyond two poses, [`Blend`] mixes any number of keyframes by weights and [`KeyframePath`] walks
//! through them in order (with durations and [`Easing`] curves); all three extrapolate
//! slightly outside their range while the metric stays Euclidean, and report every frame's
//! conformal distortion from the first keyframe ([`distortion`]).
//!
//! ```
//! use bdmorph::{generate, Morph, MorphOptions};
//! let source = generate::disk(10, 0.2);
//! let target = generate::bend(&source, 0.7);
//! let mut morph = Morph::new(&source, &target, MorphOptions::default())?;
//! for i in 0..=4 {
//!     let frame = morph.frame(i as f64 / 4.0)?;
//!     assert_eq!(frame.stats.flipped_triangles, 0);
//! }
//! // t = 1 reproduces the target.
//! let end = morph.frame(1.0)?;
//! let err = end
//!     .positions
//!     .iter()
//!     .zip(&target.positions)
//!     .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
//!     .fold(0.0, f64::max);
//! assert!(err < 1e-9 * target.diameter());
//! # Ok::<(), bdmorph::MorphError>(())
//! ```
//!
//! ## Features
//!
//! The engine (meshes, the compiler, the VM, Cholesky, morphs, blends and keyframe paths,
//! geodesics, parameterisation, posing, meshing and pictures) is always built. The
//! application's parts are features, all on by default:
//!
//! - `cli`: the `bdmorph` command line (clap, indicatif); it needs `studio` and `video`.
//! - `studio`: the local web editor's server and document model (`bdmorph::studio`; axum, tokio).
//! - `video`: H.264 MP4 output (`render::video`; OpenH264, built from C++).
//!
//! A program that embeds the engine alone depends on
//! `bdmorph = { version = "0.1", default-features = false }`.
#![warn(missing_docs)]

pub mod budget;
pub use budget::{Budget, Stopped};
pub mod deform;
pub mod distortion;
pub mod generate;
pub mod geodesic;
pub mod inbetween;
pub mod info;
pub mod io;
pub mod located;
pub mod mesh;
pub mod meshing;
pub mod morph;
pub use morph::{blend, path};
pub mod param;
pub mod parts;
#[cfg(feature = "project")]
pub mod project;
pub mod reference;
pub mod render;
#[cfg(feature = "studio")]
pub mod studio;
pub mod threads;
mod vec3;

/// The sparse Cholesky engine every system factors and solves with.
pub use bdmorph_cholesky as cholesky;
pub use bdmorph_cholesky::CholeskyError;
pub use bdmorph_compiler::{compile, pieces, CompileError, FaceId, Piece, VertexId};
pub use bdmorph_isa::{disassemble, LoadError, MeshKey, Program};
pub use bdmorph_vm::{
    FactorPrecision, NewtonOptions, TriangleReport, Vm, VmError, SINGLE_FROM_VALUES,
};
pub use blend::Blend;
pub use io::SurfaceMesh;
pub use located::{Located, MeshFile};
pub use mesh::{MeshError, PlanarMesh};
pub use morph::{Frame, FrameAt, FrameStats, Morph, MorphError, MorphOptions, Placement};
pub use param::messages::Spelling;
#[allow(deprecated)]
pub use path::Path;
pub use path::{Easing, KeyframePath, PathOptions};
pub use threads::ThreadsError;

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
