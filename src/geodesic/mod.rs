//! Geodesic distance on triangle meshes by the heat method (Crane, Weischedel, Wardetzky,
//! *Geodesics in Heat*, 2013), prefactored: everything that depends only on the mesh is done
//! once in [`HeatGeodesics::new`], and each query is a few back-substitutions and streaming
//! passes over the triangles.
//!
//! 1. Heat flows from the sources for a short time `t = m h²` (`h` the area-weighted vertex
//!    spacing of the triangulation below, `m = 0.5`, [`TimeScale`]): `(M + t Lc) u = δ`, one backward Euler step, with `M` the
//!    lumped vertex areas and `Lc` the (positive semi-definite) cotan Laplacian. On a mesh
//!    with a boundary, the boundary absorbs part of the heat by default ([`Boundary`]).
//! 2. In each triangle, `X = −∇u / |∇u|`: unit vectors pointing away from the sources.
//! 3. `Lc φ = −∇·X`, a Poisson problem whose solution has gradient closest to `X`; `φ`
//!    shifted by the constant that makes the sources' neighbours exact on average (their
//!    distance is the edge's length, [`Anchor`]) and clamped at zero is the distance.
//!
//! The defaults (time, anchor, boundary) were chosen by measurement against exact polyhedral
//! distances on the shared meshes, 40 sources each (BENCHMARKS.md, "Geodesic distances"):
//! the paper's (`m = 1` with the mean edge, zero at the sources) were up to 1.09 times less
//! accurate than the best peer; these are at least as accurate as the best peer on all 17
//! meshes, 0.78 times its error in geometric mean.
//!
//! By default the Laplacian is built on the *intrinsic Delaunay triangulation* of the mesh
//! (edge flips on the mesh's own metric, [`intrinsic`]), whose cotan weights are non-negative,
//! after *intrinsic mollification* (every edge lengthened just enough that each triangle
//! meets the triangle inequality with a small margin, so degenerate triangles are accepted)
//! and, on a mesh with a boundary, on the mesh glued to its mirror image so that flips may
//! cross the boundary too: geometry-central's robust Laplacian (Sharp and Crane 2020). On
//! meshes with poor triangles this is markedly more accurate; on some good meshes the plain
//! cotan Laplacian is slightly more accurate (BENCHMARKS.md, "Geodesic distances"). It costs a
//! few milliseconds once. The gradient and divergence are computed on the same triangulation,
//! in each triangle's own plane, so they stay consistent with the Laplacian.
//!
//! `Lc` is singular (constants); it is made definite by *pinning* one vertex per connected
//! component (removing its row and column). Since `−∇·X` sums to zero over each component,
//! the pinned system has exactly the singular system's solutions up to the constant, which the
//! shift to the sources removes anyway: pinning changes nothing, where a regularisation
//! `Lc + εM` would bias every distance.
//!
//! ```
//! use bdmorph::geodesic::{HeatGeodesics, HeatOptions};
//! use bdmorph::generate;
//! let sphere = generate::icosphere(3);
//! let mut heat = HeatGeodesics::new(&sphere, HeatOptions::default())?;
//! let d = heat.distance(&[0])?;
//! assert_eq!(d[0], 0.0);
//! // On the unit sphere the exact distance is the angle between the points.
//! let p = sphere.positions[0];
//! let mut error = 0.0;
//! for (q, got) in sphere.positions.iter().zip(&d).skip(1) {
//!     let exact = (p[0] * q[0] + p[1] * q[1] + p[2] * q[2]).clamp(-1.0, 1.0).acos();
//!     error += (got - exact).abs() / exact;
//! }
//! assert!(error / ((d.len() - 1) as f64) < 0.03);
//! # Ok::<(), bdmorph::geodesic::GeodesicError>(())
//! ```

mod descent;
mod exact;
mod heat;
pub mod intrinsic;
mod operators;
mod refine;

pub use descent::descend;
pub use exact::{
    ExactGeodesics, ExactStats, GeodesicPath, OnSurface, PathPoint, DEFAULT_WINDOWS_PER_FACE,
};
pub use heat::{Anchor, Boundary, GeodesicError, HeatGeodesics, HeatOptions, HeatStats, TimeScale};
pub use refine::RefineStats;
