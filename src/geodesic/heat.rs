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
/// distances on the shared meshes with a boundary (BENCHMARKS.md, "Geodesic distances"): from
/// 90 sources on 9 meshes it was more accurate than zero flux on 50 of the 67 interior
/// sources and 12 of the 23 boundary sources (geometric mean of the error ratios 0.95 and
/// 0.98), where the paper's average was better on 38 of 67 and up to 1.8 times worse on the
/// cut-open cow; and it needs no second heat system.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Boundary {
    /// Partly absorbing (Robin): `∂u/∂n = −κ u` on the boundary, with `κ = r / √t`, `r` the
    /// [`HeatOptions::absorption`] (default 0.2) and `√t` the distance heat spreads in the
    /// time `t`. Between zero flux, which bends the directions near the boundary along it,
    /// and zero heat, which bends them across it. A source on the boundary is handled like
    /// any other. One heat system, as for Neumann.
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

/// Options of [`HeatGeodesics`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct HeatOptions {
    /// The heat flows for `t = time_factor · h²`, `h` the mean side of the triangles the
    /// operators are built on (a side shared by two triangles counts twice): the intrinsic
    /// Delaunay ones by default, whose sides are shorter than the mesh's where it flipped, as
    /// geometry-central does. Default 1, the paper's choice.
    pub time_factor: f64,
    /// Boundary conditions (default [`Boundary::Robin`]).
    pub boundary: Boundary,
    /// The absorption `r = κ √t` of [`Boundary::Robin`] (default 0.2; 0 is Neumann). It
    /// is relative to the heat's spread `√t`, so it means the same on any mesh size and scale.
    pub absorption: f64,
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
}

impl Default for HeatOptions {
    fn default() -> Self {
        HeatOptions {
            time_factor: 1.0,
            boundary: Boundary::Robin,
            absorption: 0.2,
            intrinsic_delaunay: true,
            flip_boundary: true,
            mollify: 1e-5,
        }
    }
}

impl HeatOptions {
    /// Sets the time factor `m` of `t = m h²`.
    pub fn with_time_factor(mut self, m: f64) -> Self {
        self.time_factor = m;
        self
    }
    /// Sets the boundary conditions.
    pub fn with_boundary(mut self, boundary: Boundary) -> Self {
        self.boundary = boundary;
        self
    }
    /// Sets the absorption `r` of [`Boundary::Robin`].
    pub fn with_absorption(mut self, r: f64) -> Self {
        self.absorption = r;
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
    /// The length `h` of `t = m h²`: the mean side of the triangles the operators are built
    /// on ([`HeatOptions::time_factor`]).
    pub mean_edge: f64,
    /// Whether the mesh has a boundary.
    pub has_boundary: bool,
    /// How much intrinsic mollification lengthened every edge (0 when no triangle needed it).
    pub mollified: f64,
    /// Nonzeros in the Cholesky factors (heat and Poisson, and the Dirichlet heat when used).
    pub factor_nnz: usize,
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
        let chol = Cholesky::assemble(k, &pairs, &values, 1).map_err(factor)?;
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
    n_vertices: usize,
    geometry: FaceGeometry,
    heat: System,
    dirichlet: Option<System>,
    poisson: System,
    /// Connected component of each vertex ([`NONE`] for a vertex in no triangle).
    component: Vec<u32>,
    n_components: usize,
    stats: HeatStats,
    /// Per-vertex heat and divergence of one field, and a per-face scratch.
    u: Vec<f64>,
    grad: Vec<[f64; 2]>,
    div: Vec<f64>,
    /// Per component: the smallest potential at a source (for the shift).
    shift: Vec<f64>,
    /// The unknowns of a query's sources in a heat system.
    source_rows: Vec<u32>,
    /// Per field: whether it uses the Dirichlet heat (all its sources are off the boundary).
    averaged: Vec<bool>,
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
        if !(options.absorption >= 0.0 && options.absorption.is_finite()) {
            return Err(GeodesicError::Absorption(options.absorption));
        }
        let n = mesh.positions.len();
        let mean_edge = mean_edge_length(mesh);
        let (mut tri, mollified) = Intrinsic::from_mesh_mollified(
            &mesh.positions,
            &mesh.faces,
            options.mollify * mean_edge,
        )?;
        let boundary = tri.boundary_vertices();
        let boundary_edges = tri.boundary_edges();
        let has_boundary = boundary.iter().any(|&b| b);
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
        let geometry = FaceGeometry::from_faces(&faces);
        let mass = geometry.vertex_areas(n);
        let (component, n_components) = components(n, &mesh.faces);
        let time = options.time_factor * mean_edge * mean_edge;
        let used = |v: usize| component[v] != NONE;
        let heat = if options.boundary == Boundary::Robin && options.absorption > 0.0 {
            // The boundary term t ∫ κ u v ds, lumped: t κ l / 2 from each boundary edge of
            // length l to both its ends' diagonal entries, which hold the mass.
            let kappa = options.absorption / time.sqrt();
            let mut diagonal = mass.clone();
            for &(a, b, l) in &boundary_edges {
                diagonal[a as usize] += 0.5 * time * kappa * l;
                diagonal[b as usize] += 0.5 * time * kappa * l;
            }
            System::new("heat flow", &geometry, &diagonal, used, time, true)?
        } else {
            System::new("heat flow", &geometry, &mass, used, time, true)?
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
        let mut pinned = vec![false; n];
        let mut seen = vec![false; n_components];
        for v in 0..n {
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
            has_boundary,
            mollified,
            factor_nnz: heat.chol.factor_nnz()
                + poisson.chol.factor_nnz()
                + dirichlet.as_ref().map_or(0, |d| d.chol.factor_nnz()),
        };
        Ok(HeatGeodesics {
            u: vec![0.0; n],
            grad: Vec::with_capacity(geometry.len()),
            div: vec![0.0; n],
            shift: vec![0.0; n_components],
            source_rows: Vec::new(),
            averaged: Vec::with_capacity(16),
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

    /// As [`HeatGeodesics::distance`], into `out` (one value per vertex). Allocates nothing
    /// after the first query.
    ///
    /// # Panics
    /// When `out` does not have one entry per vertex.
    pub fn distance_into(&mut self, sources: &[u32], out: &mut [f64]) -> Result<(), GeodesicError> {
        assert_eq!(out.len(), self.n_vertices, "one output per vertex");
        self.check_sources(sources)?;
        self.query(&[sources], out)
    }

    /// One distance field per source, reusing the factors (the back-substitutions run on all
    /// sources at once): `result[k][v]` is the distance from `sources[k]` to `v`.
    pub fn distances_each(&mut self, sources: &[u32]) -> Result<Vec<Vec<f64>>, GeodesicError> {
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
        let solve_sources = |system: &mut System, rows: &mut Vec<u32>| {
            rows.clear();
            for group in groups {
                rows.extend(
                    group
                        .iter()
                        .map(|&s| system.index[s as usize])
                        .filter(|&i| i != NONE),
                );
            }
            system
                .chol
                .solve_in_place_sparse(&mut system.rhs, k, rows)
                .map_err(failed)
        };
        // 1. Heat: δ at the sources, Neumann (and Dirichlet).
        self.heat.reserve(k);
        self.heat.rhs.fill(0.0);
        for (c, group) in groups.iter().enumerate() {
            for &s in *group {
                let i = self.heat.index[s as usize];
                if i != NONE {
                    let hd = self.heat.dim();
                    self.heat.rhs[c * hd + i as usize] = 1.0;
                }
            }
        }
        solve_sources(&mut self.heat, &mut self.source_rows)?;
        self.averaged.clear();
        self.averaged.resize(k, false);
        if let Some(d) = self.dirichlet.as_mut() {
            d.reserve(k);
            d.rhs.fill(0.0);
            for (c, group) in groups.iter().enumerate() {
                // A field with a source on the boundary (which has no Dirichlet unknown)
                // keeps the Neumann heat alone.
                if group.iter().all(|&s| d.index[s as usize] != NONE) {
                    self.averaged[c] = true;
                    let dd = d.dim();
                    for &s in *group {
                        d.rhs[c * dd + d.index[s as usize] as usize] = 1.0;
                    }
                }
            }
            solve_sources(d, &mut self.source_rows)?;
        }
        // 2-3. Per field: the unit field X and its divergence, the Poisson right-hand side.
        self.poisson.reserve(k);
        for c in 0..k {
            self.u.fill(0.0);
            let hd = self.heat.dim();
            for (i, &v) in self.heat.vertex.iter().enumerate() {
                self.u[v as usize] = self.heat.rhs[c * hd + i];
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
}

/// Mean length of the mesh's own edges (each counted once).
fn mean_edge_length(mesh: &SurfaceMesh) -> f64 {
    let edges = crate::mesh::unique_edges(&mesh.faces);
    let total: f64 = edges
        .iter()
        .map(|&(a, b)| {
            let (p, q) = (mesh.positions[a as usize], mesh.positions[b as usize]);
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
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
