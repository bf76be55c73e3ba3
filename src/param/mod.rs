//! Parameterisation: flatten a disk-topology 3D triangle mesh into the plane with little
//! distortion, in the compile-once, run-many style of the rest of the crate: per-triangle
//! constants (isometric local frames, areas, `Dm⁻¹`, cotangents) once, sparse patterns fixed
//! at set-up with their symbolic factorisation reused (through the sparse Cholesky engine, [`bdmorph_cholesky`]), then
//! cheap iterations.
//!
//! Methods ([`Method`]):
//! - `tutte`: uniform weights, boundary on a circle by arc length; never flips;
//! - `lscm`: least-squares conformal map, free boundary, two pinned vertices;
//! - `asap`, `arap`: local/global iterations (Liu et al. 2008) from the Tutte map, the global
//!   matrix factored once;
//! - `sd`, `mips`, `arap-newton`: projected Newton on the symmetric Dirichlet, MIPS and ARAP
//!   energies with the closed-form eigensystems ([`energy`]), from the Tutte map, with a line
//!   search that never inverts a triangle.
//!
//! Energies are area-weighted means over the triangles ([`Energies`]).
//!
//! ```
//! use bdmorph::generate;
//! use bdmorph::param::{Method, ParamOptions, Parameterization};
//! let cap = generate::sphere_cap(3, 0.3);
//! let mut p = Parameterization::new(&cap, Method::SymmetricDirichlet, ParamOptions::default())?;
//! let start = p.energies().symmetric_dirichlet;
//! let report = p.solve()?;
//! let end = p.energies();
//! assert!(end.symmetric_dirichlet < start && end.flipped == 0);
//! assert!(report.iterations > 0);
//! # Ok::<(), bdmorph::param::ParamError>(())
//! ```

pub mod bounded;
pub mod energy;
mod frames;
mod linear;
mod local_global;
mod newton;

use std::time::Instant;

use bdmorph_cholesky::CholeskyError;
use bdmorph_compiler::CompileError;

use crate::io::SurfaceMesh;
use energy::Energy;
use frames::Frames;
use local_global::{Fit, LocalGlobal};
use newton::{mean_energy, Newton};

pub use newton::StepReport;

/// A parameterisation method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Tutte's embedding (uniform weights, circular boundary).
    Tutte,
    /// Least-squares conformal map (free boundary).
    Lscm,
    /// As-similar-as-possible, local/global.
    Asap,
    /// As-rigid-as-possible, local/global.
    Arap,
    /// Symmetric Dirichlet by projected Newton.
    SymmetricDirichlet,
    /// MIPS by projected Newton.
    Mips,
    /// ARAP by projected Newton.
    ArapNewton,
}

impl std::str::FromStr for Method {
    type Err = String;
    /// `tutte`, `lscm`, `asap`, `arap`, `sd`, `mips` or `arap-newton`.
    fn from_str(s: &str) -> Result<Method, String> {
        Ok(match s {
            "tutte" => Method::Tutte,
            "lscm" => Method::Lscm,
            "asap" => Method::Asap,
            "arap" => Method::Arap,
            "sd" => Method::SymmetricDirichlet,
            "mips" => Method::Mips,
            "arap-newton" => Method::ArapNewton,
            other => {
                return Err(format!(
                "unknown method '{other}' (use tutte, lscm, asap, arap, sd, mips or arap-newton)"
            ))
            }
        })
    }
}

/// Options of a [`Parameterization`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct ParamOptions {
    /// The most iterations [`Parameterization::solve`] runs (default 100 for local/global
    /// methods, 200 for projected Newton).
    pub iterations: Option<u32>,
    /// Stop when an iteration decreases the energy by less than this fraction of it (default
    /// 1e-9), or when the gradient norm falls below `1e-10`.
    pub tolerance: f64,
}

impl Default for ParamOptions {
    fn default() -> Self {
        ParamOptions {
            iterations: None,
            tolerance: 1e-9,
        }
    }
}

impl ParamOptions {
    /// Sets the iteration limit.
    pub fn with_iterations(mut self, iterations: u32) -> Self {
        self.iterations = Some(iterations);
        self
    }
    /// Sets the relative energy decrease below which iterations stop.
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }
}

/// Why a mesh could not be parameterised.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ParamError {
    /// The mesh is not a disk: closed, with several boundaries, non-manifold, disconnected...
    #[error("not a disk: {0}")]
    NotADisk(#[from] CompileError),
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} (0-based) has a non-finite coordinate")]
    NonFinite {
        /// The vertex.
        vertex: usize,
    },
    /// A triangle of zero area.
    #[error("face {face} (0-based) is degenerate (zero area)")]
    Degenerate {
        /// The face.
        face: usize,
    },
    /// A distortion bound that is not a number of at least 1.
    #[error("the distortion bound {0} must be a number of at least 1")]
    BadBound(f64),
    /// A positional constraint on a vertex that does not exist, or to a non-finite point.
    #[error("constraint on vertex {vertex} (0-based): no such vertex (the mesh has {n_vertices}) or a non-finite target")]
    BadPin {
        /// The vertex.
        vertex: u32,
        /// Vertex count.
        n_vertices: usize,
    },
    /// A linear solve failed.
    #[error("{what}: {source}")]
    Solver {
        /// Which system.
        what: &'static str,
        /// Why.
        source: CholeskyError,
    },
}

/// The distortion of a map, area-weighted means over the triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Energies {
    /// Symmetric Dirichlet (4 for an isometry; infinite with an inverted triangle).
    pub symmetric_dirichlet: f64,
    /// ARAP, `Σ (σᵢ − 1)²` (0 for an isometry).
    pub arap: f64,
    /// MIPS, `σ₁/σ₂ + σ₂/σ₁` (2 for a conformal map; infinite with an inverted triangle).
    pub mips: f64,
    /// Triangles with non-positive signed area in the plane.
    pub flipped: usize,
}

/// What [`Parameterization::solve`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveReport {
    /// Iterations run.
    pub iterations: u32,
    /// The method's own energy after each iteration (empty for direct methods).
    pub energies: Vec<f64>,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// The distortion of the map `uv` (one point per vertex) of `mesh`.
pub fn energies(mesh: &SurfaceMesh, uv: &[[f64; 2]]) -> Result<Energies, ParamError> {
    let frames = Frames::new(mesh).map_err(|face| ParamError::Degenerate { face })?;
    Ok(energies_of(&frames, uv))
}

fn energies_of(frames: &Frames, uv: &[[f64; 2]]) -> Energies {
    let flipped = (0..frames.len())
        .filter(|&f| {
            let m = frames.gradient(f, uv);
            let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
            det.is_nan() || det <= 0.0
        })
        .count();
    Energies {
        symmetric_dirichlet: mean_energy(Energy::SymmetricDirichlet, frames, uv),
        arap: mean_energy(Energy::Arap, frames, uv),
        mips: mean_energy(Energy::Mips, frames, uv),
        flipped,
    }
}

enum Solver {
    Direct,
    LocalGlobal(LocalGlobal, Energy),
    Newton(Newton),
}

/// A parameterisation in progress: the current map and the prepared solver.
pub struct Parameterization {
    method: Method,
    options: ParamOptions,
    frames: Frames,
    uv: Vec<[f64; 2]>,
    solver: Solver,
}

impl std::fmt::Debug for Parameterization {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Parameterization")
            .field("method", &self.method)
            .field("vertices", &self.uv.len())
            .field("faces", &self.frames.len())
            .finish_non_exhaustive()
    }
}

impl Parameterization {
    /// Checks the mesh (a manifold disk with finite coordinates and no degenerate triangle),
    /// computes the per-triangle constants and the start (the result itself for `tutte` and
    /// `lscm`, the Tutte map for the iterative methods), and prepares the iterations.
    pub fn new(
        mesh: &SurfaceMesh,
        method: Method,
        options: ParamOptions,
    ) -> Result<Parameterization, ParamError> {
        if let Some(vertex) = mesh
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(ParamError::NonFinite { vertex });
        }
        let boundary = bdmorph_compiler::disk_boundary(mesh.positions.len(), &mesh.faces)?;
        let frames = Frames::new(mesh).map_err(|face| ParamError::Degenerate { face })?;
        let n = mesh.positions.len();
        let uv = match method {
            Method::Lscm => linear::lscm(&frames, &mesh.positions, &boundary)?,
            _ => linear::tutte(&frames, &mesh.positions, &boundary)?,
        };
        let solver = match method {
            Method::Tutte | Method::Lscm => Solver::Direct,
            Method::Arap => Solver::LocalGlobal(
                LocalGlobal::new(&frames, n, boundary[0], Fit::Rotation)?,
                Energy::Arap,
            ),
            Method::Asap => Solver::LocalGlobal(
                LocalGlobal::new(&frames, n, boundary[0], Fit::Similarity)?,
                Energy::Mips,
            ),
            Method::SymmetricDirichlet => {
                Solver::Newton(Newton::new(&frames, n, Energy::SymmetricDirichlet)?)
            }
            Method::Mips => Solver::Newton(Newton::new(&frames, n, Energy::Mips)?),
            Method::ArapNewton => Solver::Newton(Newton::new(&frames, n, Energy::Arap)?),
        };
        Ok(Parameterization {
            method,
            options,
            frames,
            uv,
            solver,
        })
    }

    /// The method.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The current map: one parameter-plane position per vertex.
    pub fn uv(&self) -> &[[f64; 2]] {
        &self.uv
    }

    /// The distortion of the current map.
    pub fn energies(&self) -> Energies {
        energies_of(&self.frames, &self.uv)
    }

    /// The method's own energy of the current map (ARAP for `arap` and `arap-newton`, MIPS
    /// for `asap`, `mips`, `lscm`, symmetric Dirichlet for `sd` and `tutte`).
    pub fn energy(&self) -> f64 {
        let e = match (&self.solver, self.method) {
            (Solver::LocalGlobal(_, e), _) => *e,
            (_, Method::Arap | Method::ArapNewton) => Energy::Arap,
            (_, Method::Mips | Method::Lscm | Method::Asap) => Energy::Mips,
            _ => Energy::SymmetricDirichlet,
        };
        mean_energy(e, &self.frames, &self.uv)
    }

    /// One iteration; `None` for the direct methods (`tutte`, `lscm`), which are done at
    /// [`Parameterization::new`].
    pub fn step(&mut self) -> Result<Option<StepReport>, ParamError> {
        match &mut self.solver {
            Solver::Direct => Ok(None),
            Solver::LocalGlobal(lg, e) => {
                let before = mean_energy(*e, &self.frames, &self.uv);
                lg.iterate(&self.frames, &mut self.uv)?;
                let after = mean_energy(*e, &self.frames, &self.uv);
                Ok(Some(StepReport {
                    energy_before: before,
                    energy_after: after,
                    gradient_norm: f64::NAN,
                    step: 1.0,
                    max_step: f64::NAN,
                }))
            }
            Solver::Newton(newton) => newton.iterate(&self.frames, &mut self.uv).map(Some),
        }
    }

    /// Iterates until the energy stops decreasing by more than the tolerance (relatively),
    /// the gradient vanishes, or the iteration limit; `progress` sees every step.
    pub fn solve_with(
        &mut self,
        mut progress: impl FnMut(u32, &StepReport),
    ) -> Result<SolveReport, ParamError> {
        let started = Instant::now();
        let limit = self.options.iterations.unwrap_or(match self.solver {
            Solver::Newton(_) => 200,
            _ => 100,
        });
        let mut energies = Vec::new();
        let mut iterations = 0;
        while iterations < limit {
            let Some(report) = self.step()? else {
                break;
            };
            iterations += 1;
            energies.push(report.energy_after);
            progress(iterations, &report);
            let decrease = report.energy_before - report.energy_after;
            let converged = decrease <= self.options.tolerance * report.energy_after.abs()
                || report.gradient_norm < 1e-10
                || report.step == 0.0;
            if converged {
                break;
            }
        }
        Ok(SolveReport {
            iterations,
            energies,
            seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// [`Parameterization::solve_with`] without progress reports.
    pub fn solve(&mut self) -> Result<SolveReport, ParamError> {
        self.solve_with(|_, _| {})
    }
}
