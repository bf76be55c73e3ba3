//! The prefactored heat method.

use bdmorph_cholesky::Cholesky;
use bdmorph_cholesky::CholeskyError;

use super::intrinsic::{Intrinsic, TriangulationError, NONE};
use super::operators::FaceGeometry;
use crate::io::SurfaceMesh;

/// Boundary conditions of the heat flow, for meshes with a boundary (closed meshes have none
/// and ignore this).
///
/// The default is [`Boundary::Robin`], chosen by measurement against exact polyhedral
/// distances on the shared meshes with a boundary (BENCHMARKS.md, "Geodesic distances"):
/// from 40 sources on each of 9 meshes, absorption 0.7 for fields whose sources are off the
/// boundary and 0.2 for the others was at least as accurate as the best peer on every mesh
/// and source set, where zero flux everywhere (geometry-central's choice) was up to 2 times
/// less accurate than the best peer on the Nefertiti face, and the paper's average of zero
/// flux and zero heat up to 1.07 times on the cut-open cow. Cuts (seams) do not absorb
/// ([`HeatOptions::absorb_at_cuts`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Boundary {
    /// Partly absorbing (Robin): `∂u/∂n = −κ u` on the boundary, with `κ = r / √t`, `r` the
    /// [`HeatOptions::absorption`] (default 0.7; [`HeatOptions::boundary_source_absorption`],
    /// default 0.2, for a field with a source on the boundary) and `√t` the distance heat
    /// spreads in the time `t`. Between zero flux, which bends the directions near the
    /// boundary along it, and zero heat, which bends them across it. One heat system per
    /// absorption (two by default on a mesh with an absorbing boundary); a query
    /// back-substitutes with the one its sources need.
    #[default]
    Robin,
    /// Zero flux through the boundary: the cotan Laplacian as it is.
    Neumann,
    /// Zero heat on the boundary. A field with a source on the boundary uses the Neumann heat
    /// instead: zero heat there would contradict the source (and measured, zero heat on the
    /// rest of the boundary was 4.6 times less accurate than Neumann, geometric mean over 23
    /// boundary sources, `tools/boundary_source_experiment.py`).
    /// [`HeatGeodesics::on_boundary`] tells which sources this applies to.
    Dirichlet,
    /// The mean of the Neumann and Dirichlet heat, which the paper recommends (their
    /// boundary errors partly cancel). Costs a second heat factorisation and a third
    /// back-substitution per query. A field with a source on the boundary uses the Neumann
    /// heat alone, as for [`Boundary::Dirichlet`].
    Average,
}

/// The length `h` of the heat flow's time `t = m h²` ([`HeatOptions::time_scale`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TimeScale {
    /// The mean side of the triangles the operators are built on (a side shared by two
    /// triangles counts twice): the paper's `h`, and geometry-central's.
    MeanEdge,
    /// The area-weighted vertex spacing `h = √(2/√3 · Σ A_v² / Σ A_v)`, `A_v` the lumped
    /// vertex areas: the side of the equilateral triangles whose vertices own, on average
    /// over the surface's area, as much area as the mesh's. It equals the mean side on a
    /// uniform mesh; where the resolution varies it follows the coarse parts, which hold most
    /// of the area and most of a geodesic's length, where the mean side follows the fine
    /// parts, which hold most of the edges. The default.
    #[default]
    Spacing,
}

/// How the additive constant of the distance is fixed ([`HeatOptions::anchor`]). The heat
/// method finds the distance up to a constant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Anchor {
    /// Zero at the sources (the paper's choice). The computed field is smoothed over about
    /// `√t` around a source, so near it the distances come out short, by about a tenth of an
    /// edge on the shared meshes, and the whole field inherits the shift.
    Sources,
    /// The constant that fits, in the least-squares sense, the exact distances of the
    /// sources' neighbours: a mesh edge `sv` is a path on the surface and no path is shorter
    /// than the straight segment, so the distance from a source `s` to its neighbour `v` is
    /// exactly `|sv|` (with several sources, the nearest adjacent one's). The sources stay at
    /// zero and every distance at zero or more. A component whose sources have no
    /// neighbours but sources falls back to [`Anchor::Sources`]. The default.
    #[default]
    OneRing,
}

/// Options of [`HeatGeodesics`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct HeatOptions {
    /// The heat flows for `t = time_factor · h²`, `h` given by [`HeatOptions::time_scale`],
    /// measured on the triangles the operators are built on (the intrinsic Delaunay ones by
    /// default, whose sides are shorter than the mesh's where it flipped, as
    /// geometry-central does). Default 0.5 with [`TimeScale::Spacing`], chosen by
    /// measurement (BENCHMARKS.md, "Geodesic distances"); the paper's is 1 with
    /// [`TimeScale::MeanEdge`].
    pub time_factor: f64,
    /// Which length `h` the time `t = m h²` scales with (default [`TimeScale::Spacing`]).
    pub time_scale: TimeScale,
    /// How the additive constant of the distance is fixed (default [`Anchor::OneRing`]).
    pub anchor: Anchor,
    /// Boundary conditions (default [`Boundary::Robin`]).
    pub boundary: Boundary,
    /// The absorption `r = κ √t` of [`Boundary::Robin`] for fields whose sources are all
    /// off the boundary (default 0.7; 0 is Neumann). It is relative to the heat's spread
    /// `√t`, so it means the same on any mesh size and scale.
    pub absorption: f64,
    /// The absorption of [`Boundary::Robin`] for fields with a source on the boundary
    /// (default 0.2). Measured, such fields want less absorption than the others (heat
    /// absorbed right beside the source bends its directions); when the two differ and the
    /// mesh has an absorbing boundary, the set-up factors a second heat system, and each
    /// query back-substitutes with the one its sources need.
    pub boundary_source_absorption: f64,
    /// Whether [`Boundary::Robin`] absorbs along cuts too (default false). A cut is a
    /// boundary edge that lies on another boundary edge (both ends at the same positions):
    /// the two sides of a seam along which a closed surface was cut open, as a UV-unwrapped
    /// mesh has. By default cuts have zero flux, as if the surface were not cut there, and
    /// only the open boundary absorbs: on the cut-open cow (333 coincident boundary vertex
    /// pairs, boundary 10 times the square root of the area) absorbing along the cuts was
    /// less accurate than zero flux from 29 of 30 sources.
    pub absorb_at_cuts: bool,
    /// Build the operators on the intrinsic Delaunay triangulation (default true).
    pub intrinsic_delaunay: bool,
    /// On a mesh with a boundary, let the intrinsic Delaunay flips cross the boundary: flip on
    /// the doubled surface ([`Intrinsic::double_across_boundary`]), so that boundary edges
    /// opposite an obtuse angle lose their negative cotan weight too (default true; no effect
    /// without `intrinsic_delaunay` or on closed meshes).
    pub flip_boundary: bool,
    /// Intrinsic mollification margin, relative to the mean edge length (default `1e-5`, as
    /// geometry-central's robust Laplacian): every edge length grows by the least amount
    /// that makes each triangle satisfy the triangle inequality with this margin, so
    /// triangles of zero or nearly zero area are accepted. On meshes whose triangles all meet
    /// the margin (every shared mesh) nothing changes. `0` turns it off, and then a triangle
    /// of zero area is an error.
    pub mollify: f64,
    /// Intrinsic Delaunay refinement ([`Intrinsic::refine`]): vertices are inserted on the
    /// surface until every triangle's angles are at least this many degrees (at most 30;
    /// 0: off). The systems are solved on the refined triangulation and the distances read
    /// at the mesh's own vertices. The time `t` is measured on the triangulation before
    /// refinement, so refining changes the discretisation, not the smoothing. With
    /// [`HeatOptions::flip_boundary`] (the default) the doubled surface is refined, a closed
    /// surface; without it, boundary edges opposite an obtuse angle are split.
    pub refine_angle: f64,
    /// The most vertices refinement inserts, as a fraction of the mesh's vertices.
    pub refine_budget: f64,
    /// Threads for this object's work: `None` (default) for rayon's global pool, one thread
    /// per core; `Some(n)` for a pool of its own of `n` threads, in which the systems are
    /// factored and the queries solved ([`crate::threads`]).
    pub threads: Option<usize>,
}

impl Default for HeatOptions {
    fn default() -> Self {
        HeatOptions {
            time_factor: 0.5,
            time_scale: TimeScale::Spacing,
            anchor: Anchor::OneRing,
            boundary: Boundary::Robin,
            absorption: 0.7,
            boundary_source_absorption: 0.2,
            absorb_at_cuts: false,
            intrinsic_delaunay: true,
            flip_boundary: true,
            mollify: 1e-5,
            refine_angle: 0.0,
            refine_budget: 0.5,
            threads: None,
        }
    }
}

impl HeatOptions {
    /// Runs on a pool of its own of `threads` threads ([`HeatOptions::threads`]).
    pub fn with_threads(mut self, threads: usize) -> Self {
        self.threads = Some(threads);
        self
    }
    /// Sets the time factor `m` of `t = m h²`.
    pub fn with_time_factor(mut self, m: f64) -> Self {
        self.time_factor = m;
        self
    }
    /// Sets the length `h` of `t = m h²`.
    pub fn with_time_scale(mut self, scale: TimeScale) -> Self {
        self.time_scale = scale;
        self
    }
    /// Sets how the distance's additive constant is fixed.
    pub fn with_anchor(mut self, anchor: Anchor) -> Self {
        self.anchor = anchor;
        self
    }
    /// Sets the boundary conditions.
    pub fn with_boundary(mut self, boundary: Boundary) -> Self {
        self.boundary = boundary;
        self
    }
    /// Sets whether [`Boundary::Robin`] absorbs along cuts ([`HeatOptions::absorb_at_cuts`]).
    pub fn with_absorb_at_cuts(mut self, absorb: bool) -> Self {
        self.absorb_at_cuts = absorb;
        self
    }
    /// Sets the absorption `r` of [`Boundary::Robin`] (fields with no source on the
    /// boundary).
    pub fn with_absorption(mut self, r: f64) -> Self {
        self.absorption = r;
        self
    }
    /// Sets the absorption of [`Boundary::Robin`] for fields with a source on the boundary.
    pub fn with_boundary_source_absorption(mut self, r: f64) -> Self {
        self.boundary_source_absorption = r;
        self
    }
    /// Turns the intrinsic Delaunay triangulation on or off.
    pub fn with_intrinsic_delaunay(mut self, on: bool) -> Self {
        self.intrinsic_delaunay = on;
        self
    }
    /// Lets the intrinsic Delaunay flips cross the boundary, or not.
    pub fn with_flip_boundary(mut self, on: bool) -> Self {
        self.flip_boundary = on;
        self
    }
    /// Sets the intrinsic Delaunay refinement's angle bound in degrees (0: off) and its
    /// budget (the most vertices inserted, as a fraction of the mesh's).
    pub fn with_refinement(mut self, angle_degrees: f64, budget: f64) -> Self {
        self.refine_angle = angle_degrees;
        self.refine_budget = budget;
        self
    }
    /// Sets the intrinsic mollification margin (relative to the mean edge length; 0: off).
    pub fn with_mollify(mut self, relative_delta: f64) -> Self {
        self.mollify = relative_delta;
        self
    }
}

/// Why geodesic distances could not be set up or computed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GeodesicError {
    /// The mesh has no triangles.
    #[error("the mesh has no triangles")]
    Empty,
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} (0-based) has a non-finite coordinate")]
    NonFinite {
        /// The vertex.
        vertex: usize,
    },
    /// The triangles do not form a manifold triangulation with positive areas.
    #[error(transparent)]
    Triangulation(#[from] TriangulationError),
    /// An option out of range.
    #[error("time factor {0} must be a positive number")]
    TimeFactor(f64),
    /// The absorption is negative or not a number.
    #[error("absorption {0} must be zero or a positive number")]
    Absorption(f64),
    /// The refinement angle or budget is negative or not a number.
    #[error("refinement angle {angle} and budget {budget} must be zero or positive numbers")]
    Refine {
        /// The angle bound (degrees).
        angle: f64,
        /// The budget (fraction of the vertices).
        budget: f64,
    },
    /// The mollification margin is negative or not a number.
    #[error("mollification margin {0} must be zero or a positive number")]
    Mollify(f64),
    /// A source index that is not a vertex.
    #[error("source vertex {vertex} does not exist (the mesh has {n_vertices} vertices, numbered from 0)")]
    SourceOutOfRange {
        /// The index.
        vertex: u32,
        /// Vertex count.
        n_vertices: usize,
    },
    /// A query without sources.
    #[error("no source vertex given")]
    NoSources,
    /// The output buffer of [`HeatGeodesics::distance_into`] has the wrong length.
    #[error("output buffer holds {got} distances, the mesh has {expected} vertices")]
    OutputLength {
        /// Vertices.
        expected: usize,
        /// Buffer length.
        got: usize,
    },
    /// [`HeatOptions::threads`] cannot be used.
    #[error(transparent)]
    Threads(#[from] crate::ThreadsError),
    /// The mesh file could not be read (for callers that read and measure with one `?`).
    #[error(transparent)]
    Read(#[from] crate::io::ReadError),
    /// An exact query made more windows than allowed ([`super::ExactGeodesics::with_max_windows`]).
    #[error("the exact geodesic query gave up after {windows} windows (raise the limit with more memory, or use the heat method)")]
    WindowBudget {
        /// The limit.
        windows: usize,
    },
    /// No path joins two vertices: they lie on different pieces of the mesh.
    #[error("no path on the surface joins vertex {from} to vertex {to}: they lie on different pieces of the mesh")]
    Unreachable {
        /// The source.
        from: u32,
        /// The target.
        to: u32,
    },
    /// A path down a distance field reached a vertex with no lower neighbour that is not a
    /// source (the field has a local minimum there).
    #[error("the distance field has a local minimum at vertex {vertex}, which is not a source: no way down from there (try the exact path)")]
    NoDescent {
        /// The vertex.
        vertex: u32,
    },
    /// Tracing a shortest path back to its source went round in a loop (a bug, reported
    /// instead of hanging).
    #[error("tracing the shortest path back to its source did not end (please report this mesh)")]
    PathLoop,
    /// A factorisation failed (a matrix that is not numerically positive definite).
    #[error("{system}: {source}")]
    Factorization {
        /// Which system.
        system: &'static str,
        /// Why.
        source: CholeskyError,
    },
}

/// What the set-up did, for reports and benchmarks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeatStats {
    /// Vertices.
    pub vertices: usize,
    /// Triangles the operators are built on (after flips across the boundary, a few more
    /// than the mesh has).
    pub faces: usize,
    /// Edge flips to the intrinsic Delaunay triangulation (0 when it is off; on the doubled
    /// surface of a mesh with a boundary, the flips of both sheets).
    pub flips: usize,
    /// The heat flow's time `t`.
    pub time: f64,
    /// The mean side of the triangles the operators are built on (a side shared by two
    /// triangles counts twice; [`TimeScale::MeanEdge`]).
    pub mean_edge: f64,
    /// Their area-weighted vertex spacing ([`TimeScale::Spacing`]).
    pub spacing: f64,
    /// Whether the mesh has a boundary.
    pub has_boundary: bool,
    /// How much intrinsic mollification lengthened every edge (0 when no triangle needed it).
    pub mollified: f64,
    /// Nonzeros in the Cholesky factors (heat and Poisson, and the Dirichlet heat when used).
    pub factor_nnz: usize,
    /// What intrinsic Delaunay refinement did (all zero when it is off).
    pub refine: crate::geodesic::RefineStats,
}

/// One linear system on a subset of the vertices (its unknowns), factored once.
struct System {
    /// Unknown of each vertex, or [`NONE`].
    index: Vec<u32>,
    /// Vertex of each unknown.
    vertex: Vec<u32>,
    chol: Cholesky,
    /// Right-hand sides / solutions, `columns` of them.
    rhs: Vec<f64>,
}

impl System {
    /// Assembles `diag_mass · M + scale · Lc` on the vertices `keep` and factors it.
    fn new(
        name: &'static str,
        geometry: &FaceGeometry,
        mass: &[f64],
        keep: impl Fn(usize) -> bool,
        scale: f64,
        with_mass: bool,
    ) -> Result<System, GeodesicError> {
        let n = mass.len();
        let mut index = vec![NONE; n];
        let mut vertex = Vec::new();
        for (v, slot) in index.iter_mut().enumerate() {
            if keep(v) {
                *slot = vertex.len() as u32;
                vertex.push(v as u32);
            }
        }
        let k = vertex.len();
        let mut pairs: Vec<(u32, u32)> = (0..k as u32).map(|i| (i, i)).collect();
        let mut values: Vec<f64> = vertex
            .iter()
            .map(|&v| if with_mass { mass[v as usize] } else { 0.0 })
            .collect();
        for (i, j, w) in geometry.edge_weights() {
            if i == j {
                // An edge from a vertex to itself (on the doubled surface): w (u_i - u_i) = 0.
                continue;
            }
            let (ui, uj) = (index[i as usize], index[j as usize]);
            let w = scale * w;
            if ui != NONE {
                pairs.push((ui, ui));
                values.push(w);
            }
            if uj != NONE {
                pairs.push((uj, uj));
                values.push(w);
            }
            if ui != NONE && uj != NONE && ui != uj {
                pairs.push((ui, uj));
                values.push(-w);
            }
        }
        let factor = |source| GeodesicError::Factorization {
            system: name,
            source,
        };
        let mut chol = Cholesky::assemble(k, &pairs, &values, 1).map_err(factor)?;
        // A query's solves alternate with its own serial work (the gradient and divergence):
        // measured, splitting the Poisson solve over the threads made queries slower on 11K
        // vertices (waking the pool each time) and no faster on 41K-102K.
        chol.keep_solves_on_one_thread();
        Ok(System {
            index,
            vertex,
            chol,
            rhs: vec![0.0; k],
        })
    }

    fn dim(&self) -> usize {
        self.vertex.len()
    }

    /// Makes room for `columns` right-hand sides.
    fn reserve(&mut self, columns: usize) {
        let len = columns * self.dim();
        if self.rhs.len() != len {
            self.rhs.resize(len, 0.0);
        }
    }
}

/// Geodesic distances on one mesh by the heat method, everything that depends on the mesh
/// alone computed once. See [the module](super).
pub struct HeatGeodesics {
    /// Where it was built and its queries run.
    pool: crate::threads::Pool,
    n_vertices: usize,
    geometry: FaceGeometry,
    heat: System,
    dirichlet: Option<System>,
    /// [`Boundary::Robin`]'s heat with [`HeatOptions::boundary_source_absorption`], for the
    /// fields with a source on the boundary (when that differs from the absorption and the
    /// mesh has an absorbing boundary).
    boundary_source_heat: Option<System>,
    poisson: System,
    /// Connected component of each vertex ([`NONE`] for a vertex in no triangle).
    component: Vec<u32>,
    n_components: usize,
    stats: HeatStats,
    /// Per-vertex heat and divergence of one field, and a per-face scratch.
    u: Vec<f64>,
    grad: Vec<[f64; 2]>,
    div: Vec<f64>,
    /// Per component: the shift that anchors the potential.
    shift: Vec<f64>,
    /// Per component: the sum and count of the 1-ring misfits (for [`Anchor::OneRing`]).
    misfit: Vec<(f64, u32)>,
    anchor: Anchor,
    /// The mesh's edges by vertex (compressed rows): `ring_start[v]..ring_start[v + 1]`
    /// indexes `ring` (neighbour, 3D length). Empty unless [`Anchor::OneRing`].
    ring_start: Vec<u32>,
    ring: Vec<(u32, f64)>,
    /// Per vertex, the exact distance to the nearest adjacent source of the query, or a
    /// marker (scratch of [`Anchor::OneRing`]; infinite between queries).
    nearest: Vec<f64>,
    /// The vertices whose `nearest` a query set.
    touched: Vec<u32>,
    /// The unknowns of a query's sources in a heat system.
    source_rows: Vec<u32>,
    /// Per field: whether it uses the Dirichlet heat (all its sources are off the boundary).
    averaged: Vec<bool>,
    /// Per field: whether it uses `boundary_source_heat`, and whether `heat`.
    from_boundary_source: Vec<bool>,
    from_heat: Vec<bool>,
    boundary: Boundary,
    /// Whether each vertex lies on the mesh's boundary.
    on_boundary: Vec<bool>,
}

impl std::fmt::Debug for HeatGeodesics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HeatGeodesics")
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl HeatGeodesics {
    /// Checks the mesh, builds the (intrinsic Delaunay) triangulation and its operators, and
    /// factors the heat and Poisson systems once.
    pub fn new(mesh: &SurfaceMesh, options: HeatOptions) -> Result<HeatGeodesics, GeodesicError> {
        let pool = crate::threads::Pool::new(options.threads)?;
        let mut built = pool.run(|| HeatGeodesics::new_here(mesh, options))?;
        built.pool = pool;
        Ok(built)
    }

    fn new_here(mesh: &SurfaceMesh, options: HeatOptions) -> Result<HeatGeodesics, GeodesicError> {
        if mesh.faces.is_empty() {
            return Err(GeodesicError::Empty);
        }
        if let Some(vertex) = mesh
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(GeodesicError::NonFinite { vertex });
        }
        if !(options.time_factor > 0.0 && options.time_factor.is_finite()) {
            return Err(GeodesicError::TimeFactor(options.time_factor));
        }
        if !(options.mollify >= 0.0 && options.mollify.is_finite()) {
            return Err(GeodesicError::Mollify(options.mollify));
        }
        let (angle, budget) = (options.refine_angle, options.refine_budget);
        if !(angle >= 0.0 && angle.is_finite() && budget >= 0.0 && budget.is_finite()) {
            return Err(GeodesicError::Refine { angle, budget });
        }
        for r in [options.absorption, options.boundary_source_absorption] {
            if !(r >= 0.0 && r.is_finite()) {
                return Err(GeodesicError::Absorption(r));
            }
        }
        let n = mesh.positions.len();
        if let Some((face, &vertices)) = mesh
            .faces
            .iter()
            .enumerate()
            .find(|(_, f)| f.iter().any(|&v| v as usize >= n))
        {
            return Err(TriangulationError::BadFace { face, vertices }.into());
        }
        let mean_edge = mean_edge_length(mesh);
        let (mut tri, mollified) = Intrinsic::from_mesh_mollified(
            &mesh.positions,
            &mesh.faces,
            options.mollify * mean_edge,
        )?;
        let input_boundary = MeshBoundary::of(&tri, &mesh.positions, options.absorb_at_cuts);
        let refining = options.intrinsic_delaunay && options.refine_angle > 0.0;
        let flips = if options.intrinsic_delaunay {
            if options.flip_boundary {
                tri.double_across_boundary();
            }
            tri.flip_to_delaunay()
        } else {
            0
        };
        let faces = tri.weighted_faces();
        // The mean side of the triangles (each side of the doubled surface once; a side
        // shared by two triangles counts twice, one on the boundary once), as geometry-central
        // does on the tufted cover.
        let (sides, weights) = faces.iter().fold((0.0, 0.0), |(s, w), (_, l, weight)| {
            (s + weight * (l[0] + l[1] + l[2]), w + 3.0 * weight)
        });
        let mean_edge = sides / weights;
        let mut geometry = FaceGeometry::from_faces(&faces);
        let mass = geometry.vertex_areas(n);
        let (area, area2) = mass
            .iter()
            .fold((0.0, 0.0), |(a, a2), &m| (a + m, a2 + m * m));
        let spacing = (2.0 / 3f64.sqrt() * area2 / area).sqrt();
        let h = match options.time_scale {
            TimeScale::MeanEdge => mean_edge,
            TimeScale::Spacing => spacing,
        };
        let time = options.time_factor * h * h;
        let mut refine = crate::geodesic::RefineStats::default();
        let mut mass = mass;
        let mut faces = faces;
        if refining {
            let cap = (options.refine_budget * n as f64)
                .ceil()
                .min(u32::MAX as f64 / 4.0);
            refine = tri.refine(options.refine_angle, cap as usize);
            faces = tri.weighted_faces();
            geometry = FaceGeometry::from_faces(&faces);
            mass = geometry.vertex_areas(tri.n_vertices());
        }
        // The refined triangulation's vertices: the mesh's, then those refinement inserted.
        let n_all = tri.n_vertices();
        let MeshBoundary {
            on: boundary,
            edges: boundary_edges,
            cut,
            ..
        } = if refining {
            input_boundary.after_refinement(&tri)
        } else {
            input_boundary
        };
        let has_boundary = boundary.iter().any(|&b| b);
        let refined_faces: Vec<[u32; 3]> = faces.iter().map(|f| f.0).collect();
        let (component, n_components) = components(n_all, &refined_faces);
        let used = |v: usize| component[v] != NONE;
        let absorbing = options.boundary == Boundary::Robin && cut.iter().any(|&c| !c);
        // The heat system with absorption r: the boundary term t ∫ κ u v ds, lumped: t κ l / 2
        // from each absorbing boundary edge of length l to both its ends' diagonal entries,
        // which hold the mass.
        let robin = |name, r: f64| {
            let mut diagonal = mass.clone();
            if absorbing && r > 0.0 {
                let kappa = r / time.sqrt();
                for (&(a, b, l), _) in boundary_edges.iter().zip(&cut).filter(|(_, &c)| !c) {
                    diagonal[a as usize] += 0.5 * time * kappa * l;
                    diagonal[b as usize] += 0.5 * time * kappa * l;
                }
            }
            System::new(name, &geometry, &diagonal, used, time, true)
        };
        // `robin` absorbs nothing unless the boundary is Robin's: for the other conditions
        // this is the Neumann heat.
        let heat = robin("heat flow", options.absorption)?;
        let boundary_source_heat =
            if absorbing && options.boundary_source_absorption != options.absorption {
                Some(robin(
                    "heat flow (boundary sources)",
                    options.boundary_source_absorption,
                )?)
            } else {
                None
            };
        let dirichlet = if has_boundary
            && matches!(options.boundary, Boundary::Dirichlet | Boundary::Average)
        {
            let interior = |v: usize| used(v) && !boundary[v];
            Some(System::new(
                "heat flow (Dirichlet)",
                &geometry,
                &mass,
                interior,
                time,
                true,
            )?)
        } else {
            None
        };
        // Pin the first vertex of each component.
        let mut pinned = vec![false; n_all];
        let mut seen = vec![false; n_components];
        for v in 0..n_all {
            let c = component[v];
            if c != NONE && !seen[c as usize] {
                seen[c as usize] = true;
                pinned[v] = true;
            }
        }
        let poisson = System::new(
            "Poisson",
            &geometry,
            &mass,
            |v| used(v) && !pinned[v],
            1.0,
            false,
        )?;
        let stats = HeatStats {
            vertices: n,
            faces: geometry.len(),
            flips,
            time,
            mean_edge,
            spacing,
            has_boundary,
            mollified,
            factor_nnz: heat.chol.factor_nnz()
                + poisson.chol.factor_nnz()
                + dirichlet.as_ref().map_or(0, |d| d.chol.factor_nnz())
                + boundary_source_heat
                    .as_ref()
                    .map_or(0, |d| d.chol.factor_nnz()),
            refine,
        };
        let (ring_start, ring) = match options.anchor {
            Anchor::OneRing => one_rings(mesh),
            Anchor::Sources => (Vec::new(), Vec::new()),
        };
        Ok(HeatGeodesics {
            pool: crate::threads::Pool::default(),
            misfit: vec![(0.0, 0); n_components],
            anchor: options.anchor,
            nearest: if ring.is_empty() {
                Vec::new()
            } else {
                vec![f64::INFINITY; n]
            },
            // At most every vertex: no query grows it.
            touched: Vec::with_capacity(if ring.is_empty() { 0 } else { n }),
            ring_start,
            ring,
            u: vec![0.0; n_all],
            grad: Vec::with_capacity(geometry.len()),
            div: vec![0.0; n_all],
            shift: vec![0.0; n_components],
            source_rows: Vec::new(),
            averaged: Vec::with_capacity(16),
            from_boundary_source: Vec::with_capacity(16),
            from_heat: Vec::with_capacity(16),
            boundary_source_heat,
            boundary: options.boundary,
            on_boundary: boundary,
            n_vertices: n,
            geometry,
            heat,
            dirichlet,
            poisson,
            component,
            n_components,
            stats,
        })
    }

    /// What the set-up did.
    pub fn stats(&self) -> HeatStats {
        self.stats
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }

    /// Whether vertex `v` lies on the mesh's boundary (false for a vertex out of range). With
    /// [`Boundary::Dirichlet`] or [`Boundary::Average`], a field with such a source uses the
    /// Neumann heat.
    pub fn on_boundary(&self, v: u32) -> bool {
        self.on_boundary.get(v as usize).copied().unwrap_or(false)
    }

    /// The boundary conditions the heat flows with.
    pub fn boundary(&self) -> Boundary {
        self.boundary
    }

    /// The distance of every vertex to the nearest of `sources`: zero at the sources,
    /// non-negative, infinite on connected components without a source.
    pub fn distance(&mut self, sources: &[u32]) -> Result<Vec<f64>, GeodesicError> {
        let mut out = vec![0.0; self.n_vertices];
        self.distance_into(sources, &mut out)?;
        Ok(out)
    }

    /// As [`HeatGeodesics::distance`], into `out` (one value per vertex, else
    /// [`GeodesicError::OutputLength`]). Allocates nothing after the first query.
    pub fn distance_into(&mut self, sources: &[u32], out: &mut [f64]) -> Result<(), GeodesicError> {
        if out.len() != self.n_vertices {
            return Err(GeodesicError::OutputLength {
                expected: self.n_vertices,
                got: out.len(),
            });
        }
        self.check_sources(sources)?;
        let pool = self.pool.clone();
        pool.run(|| self.query(&[sources], out))
    }

    /// One distance field per source, reusing the factors (the back-substitutions run on all
    /// sources at once): `result[k][v]` is the distance from `sources[k]` to `v`.
    pub fn distances_each(&mut self, sources: &[u32]) -> Result<Vec<Vec<f64>>, GeodesicError> {
        let pool = self.pool.clone();
        pool.run(|| self.distances_each_here(sources))
    }

    fn distances_each_here(&mut self, sources: &[u32]) -> Result<Vec<Vec<f64>>, GeodesicError> {
        self.check_sources(sources)?;
        let groups: Vec<[u32; 1]> = sources.iter().map(|&s| [s]).collect();
        let groups: Vec<&[u32]> = groups.iter().map(|g| &g[..]).collect();
        let mut flat = vec![0.0; self.n_vertices * sources.len()];
        // In batches, so the buffers stay moderate on large meshes.
        let batch = 16;
        for (k, chunk) in groups.chunks(batch).enumerate() {
            let n = self.n_vertices;
            let start = k * batch * n;
            self.query(chunk, &mut flat[start..start + chunk.len() * n])?;
        }
        Ok(flat.chunks(self.n_vertices).map(<[f64]>::to_vec).collect())
    }

    fn check_sources(&self, sources: &[u32]) -> Result<(), GeodesicError> {
        if sources.is_empty() {
            return Err(GeodesicError::NoSources);
        }
        if let Some(&vertex) = sources.iter().find(|&&s| s as usize >= self.n_vertices) {
            return Err(GeodesicError::SourceOutOfRange {
                vertex,
                n_vertices: self.n_vertices,
            });
        }
        Ok(())
    }

    /// Solves one distance field per group of sources into `out` (`groups.len()` fields of
    /// one value per vertex, one after another).
    fn query(&mut self, groups: &[&[u32]], out: &mut [f64]) -> Result<(), GeodesicError> {
        let n = self.n_vertices;
        let k = groups.len();
        let failed = |source| GeodesicError::Factorization {
            system: "solve",
            source,
        };
        let solve = |system: &mut System| {
            system
                .chol
                .solve_in_place(&mut system.rhs, k)
                .map_err(failed)
        };
        // The heat systems' right-hand sides are zero but at the sources: their forward
        // solves visit only the part of the factor the sources reach.
        let solve_rows = |system: &mut System, rows: &[u32]| {
            system
                .chol
                .solve_in_place_sparse(&mut system.rhs, k, rows)
                .map_err(failed)
        };
        // 1. Heat: δ at the sources, Neumann or Robin (and Dirichlet). Each system solves
        // the fields that use it (`wanted`), or none.
        let load = |system: &mut System, wanted: &[bool], rows: &mut Vec<u32>| {
            system.reserve(k);
            system.rhs.fill(0.0);
            rows.clear();
            let d = system.dim();
            for (c, group) in groups.iter().enumerate().filter(|&(c, _)| wanted[c]) {
                for &s in *group {
                    let i = system.index[s as usize];
                    if i != NONE {
                        system.rhs[c * d + i as usize] = 1.0;
                        rows.push(i);
                    }
                }
            }
        };
        self.from_boundary_source.clear();
        for group in groups {
            let on_boundary = |&s: &u32| self.on_boundary[s as usize];
            self.from_boundary_source
                .push(self.boundary_source_heat.is_some() && group.iter().any(on_boundary));
        }
        self.from_heat.clear();
        self.from_heat
            .extend(self.from_boundary_source.iter().map(|&b| !b));
        if self.from_heat.iter().any(|&b| b) {
            load(&mut self.heat, &self.from_heat, &mut self.source_rows);
            solve_rows(&mut self.heat, &self.source_rows)?;
        }
        if let Some(heat) = self.boundary_source_heat.as_mut() {
            if self.from_boundary_source.iter().any(|&b| b) {
                load(heat, &self.from_boundary_source, &mut self.source_rows);
                solve_rows(heat, &self.source_rows)?;
            }
        }
        self.averaged.clear();
        self.averaged.resize(k, false);
        if let Some(d) = self.dirichlet.as_mut() {
            // A field with a source on the boundary (which has no Dirichlet unknown) keeps
            // the Neumann heat alone.
            for (c, group) in groups.iter().enumerate() {
                self.averaged[c] = group.iter().all(|&s| d.index[s as usize] != NONE);
            }
            load(d, &self.averaged, &mut self.source_rows);
            solve_rows(d, &self.source_rows)?;
        }
        // 2-3. Per field: the unit field X and its divergence, the Poisson right-hand side.
        self.poisson.reserve(k);
        for c in 0..k {
            self.u.fill(0.0);
            let heat = match (&self.boundary_source_heat, self.from_boundary_source[c]) {
                (Some(h), true) => h,
                _ => &self.heat,
            };
            let hd = heat.dim();
            for (i, &v) in heat.vertex.iter().enumerate() {
                self.u[v as usize] = heat.rhs[c * hd + i];
            }
            if let (Some(d), true) = (self.dirichlet.as_ref(), self.averaged[c]) {
                // Average: half of each; Dirichlet alone: the Dirichlet heat (zero on the
                // boundary).
                let (keep, add) = match self.boundary {
                    Boundary::Dirichlet => (0.0, 1.0),
                    _ => (0.5, 0.5),
                };
                let dd = d.dim();
                for u in self.u.iter_mut() {
                    *u *= keep;
                }
                for (i, &v) in d.vertex.iter().enumerate() {
                    self.u[v as usize] += add * d.rhs[c * dd + i];
                }
            }
            self.geometry
                .descent_divergence_into(&self.u, &mut self.grad, &mut self.div);
            let pd = self.poisson.dim();
            for (i, &v) in self.poisson.vertex.iter().enumerate() {
                self.poisson.rhs[c * pd + i] = -self.div[v as usize];
            }
        }
        solve(&mut self.poisson)?;
        // 4. Potentials by vertex, shifted to zero at the sources of each component.
        let pd = self.poisson.dim();
        for (c, group) in groups.iter().enumerate() {
            let field = &mut out[c * n..(c + 1) * n];
            for (v, phi) in field.iter_mut().enumerate() {
                let i = self.poisson.index[v];
                *phi = if i == NONE {
                    0.0
                } else {
                    self.poisson.rhs[c * pd + i as usize]
                };
            }
            self.shift.fill(f64::INFINITY);
            for &s in *group {
                let comp = self.component[s as usize];
                if comp != NONE {
                    let sh = &mut self.shift[comp as usize];
                    *sh = sh.min(field[s as usize]);
                }
            }
            if self.anchor == Anchor::OneRing {
                self.fit_one_rings(group, field);
            }
            for (v, phi) in field.iter_mut().enumerate() {
                let comp = self.component[v];
                *phi = if comp == NONE || self.shift[comp as usize].is_infinite() {
                    f64::INFINITY
                } else {
                    (*phi - self.shift[comp as usize]).max(0.0)
                };
            }
            for &s in *group {
                field[s as usize] = 0.0;
            }
        }
        debug_assert_eq!(self.shift.len(), self.n_components);
        Ok(())
    }

    /// [`Anchor::OneRing`]: per component with a source, replaces the shift by the mean of
    /// `φ(v) − |sv|` over the sources' neighbours `v` that are not sources themselves (`s`
    /// the nearest adjacent source), when there are any.
    fn fit_one_rings(&mut self, group: &[u32], field: &[f64]) {
        const SOURCE: f64 = -1.0;
        for &s in group {
            if self.nearest[s as usize] != SOURCE {
                self.nearest[s as usize] = SOURCE;
                self.touched.push(s);
            }
        }
        for &s in group {
            let (a, b) = (
                self.ring_start[s as usize] as usize,
                self.ring_start[s as usize + 1] as usize,
            );
            for &(v, len) in &self.ring[a..b] {
                let near = &mut self.nearest[v as usize];
                if *near == SOURCE {
                    continue;
                }
                if near.is_infinite() {
                    self.touched.push(v);
                }
                *near = near.min(len);
            }
        }
        self.misfit.fill((0.0, 0));
        for &v in &self.touched {
            let near = self.nearest[v as usize];
            let comp = self.component[v as usize];
            if near != SOURCE && comp != NONE {
                let m = &mut self.misfit[comp as usize];
                m.0 += field[v as usize] - near;
                m.1 += 1;
            }
        }
        for (shift, &(sum, count)) in self.shift.iter_mut().zip(&self.misfit) {
            if count > 0 && shift.is_finite() {
                *shift = sum / f64::from(count);
            }
        }
        for &v in &self.touched {
            self.nearest[v as usize] = f64::INFINITY;
        }
        self.touched.clear();
    }
}

/// The mesh's edges by vertex with their 3D lengths, in compressed rows (see
/// [`HeatGeodesics`]'s `ring_start`).
fn one_rings(mesh: &SurfaceMesh) -> (Vec<u32>, Vec<(u32, f64)>) {
    let n = mesh.positions.len();
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(6 * mesh.faces.len());
    for f in &mesh.faces {
        for (a, b) in [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])] {
            pairs.push((a, b));
            pairs.push((b, a));
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    let mut start = vec![0u32; n + 1];
    for &(a, _) in &pairs {
        start[a as usize + 1] += 1;
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let ring = pairs
        .iter()
        .map(|&(a, b)| {
            let len = crate::vec3::distance(mesh.positions[a as usize], mesh.positions[b as usize]);
            (b, len)
        })
        .collect();
    (start, ring)
}

/// The boundary of the triangulation the operators are built on.
struct MeshBoundary {
    /// Per vertex, whether it lies on the boundary.
    on: Vec<bool>,
    /// The boundary edges `(a, b, length)`.
    edges: Vec<(u32, u32, f64)>,
    /// Per boundary edge, whether it is a cut ([`HeatOptions::absorb_at_cuts`]).
    cut: Vec<bool>,
    /// Per boundary edge, the input's half-edge it lies on ([`Intrinsic::boundary_parents`]).
    parents: Vec<u32>,
}

impl MeshBoundary {
    /// The input triangulation's boundary (before any flip or doubling); no edge is a cut
    /// when cuts absorb.
    fn of(tri: &Intrinsic, positions: &[[f64; 3]], absorb_at_cuts: bool) -> MeshBoundary {
        let edges = tri.boundary_edges();
        let cut = if absorb_at_cuts {
            vec![false; edges.len()]
        } else {
            cut_edges(positions, &edges)
        };
        MeshBoundary {
            on: tri.boundary_vertices(),
            parents: tri.boundary_parents(),
            edges,
            cut,
        }
    }

    /// The boundary after `tri` (this boundary's triangulation) was refined. On the doubled
    /// surface it is the input's (its vertices keep their numbers; the new ones lie off it, on
    /// one sheet or the other). Otherwise refinement split boundary edges: each lies on one of
    /// the input's, which says whether it is a cut.
    fn after_refinement(self, tri: &Intrinsic) -> MeshBoundary {
        if tri.is_doubled() {
            let mut on = self.on;
            on.resize(tri.n_vertices(), false);
            return MeshBoundary { on, ..self };
        }
        let index: std::collections::HashMap<u32, usize> = self
            .parents
            .iter()
            .enumerate()
            .map(|(i, &h)| (h, i))
            .collect();
        let parents = tri.boundary_parents();
        let cut = parents
            .iter()
            .map(|p| index.get(p).is_some_and(|&i| self.cut[i]))
            .collect();
        MeshBoundary {
            on: tri.boundary_vertices(),
            edges: tri.boundary_edges(),
            cut,
            parents,
        }
    }
}

/// Which boundary edges are cuts ([`HeatOptions::absorb_at_cuts`]): those whose two ends'
/// positions are, bit for bit, those of another boundary edge's two ends.
fn cut_edges(positions: &[[f64; 3]], edges: &[(u32, u32, f64)]) -> Vec<bool> {
    let key = |v: u32| positions[v as usize].map(f64::to_bits);
    let mut ends: Vec<([[u64; 3]; 2], usize)> = edges
        .iter()
        .enumerate()
        .map(|(i, &(a, b, _))| {
            let (p, q) = (key(a), key(b));
            (if p <= q { [p, q] } else { [q, p] }, i)
        })
        .collect();
    ends.sort_unstable();
    let mut cut = vec![false; edges.len()];
    for run in ends.chunk_by(|x, y| x.0 == y.0) {
        if run.len() > 1 {
            for &(_, i) in run {
                cut[i] = true;
            }
        }
    }
    cut
}

/// Mean length of the mesh's own edges (each counted once).
fn mean_edge_length(mesh: &SurfaceMesh) -> f64 {
    let edges = crate::mesh::unique_edges(&mesh.faces);
    let total: f64 = edges
        .iter()
        .map(|&(a, b)| {
            crate::vec3::distance(mesh.positions[a as usize], mesh.positions[b as usize])
        })
        .sum();
    total / edges.len().max(1) as f64
}

/// Connected components of the vertices through the triangles: a label per vertex ([`NONE`]
/// for a vertex in no triangle) and their number.
fn components(n: usize, faces: &[[u32; 3]]) -> (Vec<u32>, usize) {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            let p = parent[v as usize];
            parent[v as usize] = parent[p as usize];
            v = p;
        }
        v
    }
    let mut used = vec![false; n];
    for f in faces {
        for &v in f {
            used[v as usize] = true;
        }
        for (a, b) in [(f[0], f[1]), (f[1], f[2])] {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
        }
    }
    let mut label = vec![NONE; n];
    let mut count = 0;
    let mut root_label = vec![NONE; n];
    for v in 0..n {
        if !used[v] {
            continue;
        }
        let r = find(&mut parent, v as u32) as usize;
        if root_label[r] == NONE {
            root_label[r] = count;
            count += 1;
        }
        label[v] = root_label[r];
    }
    (label, count as usize)
}
