//! The solver behind [`Morph`](crate::Morph), [`Blend`](crate::Blend) and
//! [`KeyframePath`](crate::KeyframePath) for any planar mesh: keyframes that list the same triangles
//! differently, several pieces, holes, and keyframes with a few inverted triangles.
//!
//! - **Listings.** Every keyframe after the first may list the first one's triangles in any
//!   order and with their corners rotated ([`PlanarMesh::match_faces`]); only its positions
//!   are used after that, with the first keyframe's faces, so output follows the first
//!   keyframe's face order.
//! - **Pieces.** Each piece (faces connected through edges) gets its own compiled program
//!   and solver ([`Engine`]), its own anchor vertex and rigid motion: pieces morph as if
//!   alone, and a frame is all of them.
//! - **Holes.** Each hole of a piece (every boundary loop but the outer one, the loop of
//!   largest signed area in the first keyframe) is filled with hidden triangles over its own
//!   boundary vertices ([`holes`](super::holes)), counter-clockwise in every keyframe, when
//!   one triangulation is so. The filled piece is a disk: its metric is blended like any
//!   other (the hidden triangles' squared lengths too), flattened and laid out, so the layout
//!   closes around the hole (no crack) and the paper's bound holds for every triangle, hidden
//!   or not. The hidden triangles are never drawn or written; a hidden triangle that flips
//!   is counted in [`FrameStats::flipped_triangles`]. Cost: `n - 2` more triangles and `n`
//!   more unknowns per hole of `n` boundary vertices (its vertices become interior to the
//!   filled disk), and an `O(n³)` set-up per hole.
//! - **Free holes.** A hole whose outline no triangulation suits in every keyframe (it
//!   crosses itself in one, where a limb lies over the body, or changes too much) is a
//!   *free hole* ([`PieceInfo::free_holes`]): filled with inert triangles for the topology
//!   only, its vertices are unknowns whose angle sums blend the keyframes' as the metric
//!   blends their lengths, and the outline is closed by two more unknowns per hole
//!   ([`closure`](super::closure)). Every keyframe is reached exactly whatever its hole
//!   looks like, and frames are continuous; the paper's bound covers the user's triangles of
//!   the flattened metric as before, but nothing keeps the hole open between keyframes (it
//!   may overlap itself, as it does in the keyframes). Cost: two (or more) flattenings and
//!   two solves per free hole per frame.
//! - **Inverted triangles.** With [`MorphOptions::allow_inverted`] a keyframe may have a few
//!   clockwise triangles: their side lengths enter the metric as they are (it stays
//!   Euclidean), so the frame at that keyframe is the nearest flat shape with those lengths
//!   and differs from the given pose near them; [`Structure::inverted`] lists them.

use std::collections::HashSet;

use bdmorph_compiler::CompileError;
use bdmorph_vm::{FactorPrecision, Program, TriangleReport};

use crate::distortion::RestShape;
use crate::mesh::{MeshError, PlanarMesh};
use crate::morph::engine::{Engine, Line, Unwrap};
use crate::morph::holes;
use crate::morph::{FrameAt, FrameStats, MorphError, MorphOptions};

/// What the solver found in the keyframes: pieces, holes, inverted triangles.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Structure {
    /// The pieces, in the order of their first face.
    pub pieces: Vec<PieceInfo>,
    /// Per keyframe, its inverted (clockwise) triangles as indices into that keyframe's own
    /// faces; empty unless [`MorphOptions::allow_inverted`].
    pub inverted: Vec<Vec<usize>>,
}

/// One piece of a mesh, as the solver treats it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PieceInfo {
    /// Its vertices.
    pub vertices: usize,
    /// Its triangles (the user's).
    pub faces: usize,
    /// Its holes (boundary loops besides the outer one).
    pub holes: usize,
    /// The hidden triangles that fill its holes for the solve (vertices of the mesh,
    /// counter-clockwise in every keyframe), free holes' excepted.
    pub hidden: Vec<[u32; 3]>,
    /// Its free holes, a vertex (of the mesh) on each: holes whose outline no one filling
    /// suits in every keyframe (it crosses itself where a limb lies over the body, or changes
    /// too much between keyframes). They are solved as free boundaries that close by their
    /// own turning ([`crate::morph`]'s notes on holes); keyframes are still reached exactly.
    pub free_holes: Vec<u32>,
    /// Its anchor vertex (0-based, in the mesh): the frame places it, and the direction of
    /// its first edge, by blending the keyframes' rigid motions.
    pub anchor: u32,
    /// That first edge: the anchor and its neighbour (mesh vertices).
    pub anchor_edge: [u32; 2],
}

/// One piece's solver and where its vertices and faces go in the mesh.
struct PieceSolver {
    engine: Engine,
    /// Mesh vertex of each of the piece's vertices.
    vertices: Vec<u32>,
    /// Mesh face of each of the piece's visible faces.
    faces: Vec<u32>,
    /// The piece's positions in the frame being solved.
    out: Vec<[f64; 2]>,
}

/// The solver of one set of keyframes.
pub(crate) struct Solver {
    pieces: Vec<PieceSolver>,
    faces: Vec<[u32; 3]>,
    n_vertices: usize,
    /// One piece whose numbering is the mesh's: its engine writes frames directly.
    direct: bool,
    positions: Vec<[f64; 2]>,
    distortion: Vec<f64>,
    structure: Structure,
    /// Where it was built and its frames are solved.
    pool: crate::threads::Pool,
    /// Keyframes reached by a correction ([`MorphOptions::reach_inverted`]): each one's index
    /// and its difference from the frame solved at it, per vertex.
    reach: Vec<(usize, Vec<[f64; 2]>)>,
    /// The first keyframe's shape, to measure corrected frames.
    reach_shape: Option<RestShape>,
}

impl std::fmt::Debug for Solver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let engines: Vec<&Engine> = self.pieces.iter().map(|p| &p.engine).collect();
        f.debug_struct("Solver")
            .field("structure", &self.structure)
            .field("engines", &engines)
            .finish_non_exhaustive()
    }
}

/// A keyframe's error: the first keyframe's as a mesh error, a later one's with its index.
fn keyframe_error(index: usize, source: MeshError) -> MorphError {
    match index {
        0 => MorphError::Mesh(source),
        index => MorphError::Keyframe { index, source },
    }
}

/// Checks every keyframe (geometry, and the first one's triangles in any listing) and
/// returns each one's inverted triangles (empty unless allowed). Only the first keyframe's
/// faces are used after this; the others' positions.
fn check(keyframes: &[PlanarMesh], allow_inverted: bool) -> Result<Vec<Vec<usize>>, MorphError> {
    let first = &keyframes[0];
    let geometry = |k: &PlanarMesh| {
        if allow_inverted {
            k.validate_allowing_inverted()
        } else {
            k.validate().map(|()| Vec::new())
        }
    };
    let mut inverted = vec![geometry(first).map_err(|e| keyframe_error(0, e))?];
    for (index, k) in keyframes.iter().enumerate().skip(1) {
        if k.positions.len() != first.positions.len() {
            return Err(keyframe_error(
                index,
                MeshError::CountMismatch {
                    what: "vertex count",
                    source_count: first.positions.len(),
                    target_count: k.positions.len(),
                },
            ));
        }
        if k.faces.len() != first.faces.len() {
            return Err(keyframe_error(
                index,
                MeshError::CountMismatch {
                    what: "face count",
                    source_count: first.faces.len(),
                    target_count: k.faces.len(),
                },
            ));
        }
        // A triangle listed reversed is named as such before it shows up as clockwise.
        first
            .match_faces(&k.faces)
            .map_err(|e| keyframe_error(index, e))?;
        inverted.push(geometry(k).map_err(|e| keyframe_error(index, e))?);
    }
    Ok(inverted)
}

/// Twice the signed area of the polygon through `loop_`'s vertices.
fn loop_area(loop_: &[u32], positions: &[[f64; 2]]) -> f64 {
    let n = loop_.len();
    (0..n)
        .map(|i| {
            let (a, b) = (
                positions[loop_[i] as usize],
                positions[loop_[(i + 1) % n] as usize],
            );
            a[0] * b[1] - a[1] * b[0]
        })
        .sum()
}

impl Solver {
    /// Checks the keyframes (at least one), splits the mesh into pieces, fills their holes,
    /// compiles each piece and prepares its solver.
    pub(crate) fn new(
        keyframes: &[PlanarMesh],
        unwrap: Unwrap,
        options: MorphOptions,
    ) -> Result<Solver, MorphError> {
        options.validate()?;
        let pool = crate::threads::Pool::new(options.threads)?;
        let mut solver = pool.run(|| {
            let mut solver = Solver::new_here(keyframes, unwrap, options.clone())?;
            solver.prepare_reach(keyframes, &options)?;
            Ok::<_, MorphError>(solver)
        })?;
        solver.pool = pool;
        Ok(solver)
    }

    /// With [`MorphOptions::reach_inverted`]: solves each keyframe with inverted triangles
    /// once and keeps its difference from the keyframe, which every frame then adds by that
    /// keyframe's weight.
    fn prepare_reach(
        &mut self,
        keyframes: &[PlanarMesh],
        options: &MorphOptions,
    ) -> Result<(), MorphError> {
        if !(options.allow_inverted && options.reach_inverted) {
            return Ok(());
        }
        let folded: Vec<usize> = (0..keyframes.len())
            .filter(|&k| !self.structure.inverted[k].is_empty())
            .collect();
        if folded.is_empty() {
            return Ok(());
        }
        // Corrected frames are written through the general path (its buffers).
        self.direct = false;
        for p in &mut self.pieces {
            p.out.resize(p.vertices.len(), [0.0; 2]);
        }
        self.positions = vec![[0.0; 2]; self.n_vertices];
        self.distortion = vec![1.0; self.faces.len()];
        self.reach_shape = Some(RestShape::new(&keyframes[0].positions, &self.faces));
        let mut weights = vec![0.0; keyframes.len()];
        let mut out = vec![[0.0; 2]; self.n_vertices];
        for k in folded {
            weights.fill(0.0);
            weights[k] = 1.0;
            self.frame_into_here(&weights, None, None, &mut out)?;
            let miss = keyframes[k]
                .positions
                .iter()
                .zip(&out)
                .map(|(p, q)| [p[0] - q[0], p[1] - q[1]])
                .collect();
            self.reach.push((k, miss));
        }
        self.forget_solutions();
        Ok(())
    }

    fn new_here(
        keyframes: &[PlanarMesh],
        unwrap: Unwrap,
        options: MorphOptions,
    ) -> Result<Solver, MorphError> {
        let inverted = check(keyframes, options.allow_inverted)?;
        let first = &keyframes[0];
        let n = first.positions.len();
        // One disk, the common case: compiled as it is, with no second look at its topology.
        match bdmorph_compiler::compile(&first.positions, &first.faces) {
            Ok(program) => {
                return Solver::disk(program, keyframes, inverted, unwrap, options);
            }
            Err(CompileError::Disconnected { .. } | CompileError::HasHoles { .. }) => {}
            Err(e) => return Err(MeshError::Topology(e).into()),
        }
        let topology = bdmorph_compiler::pieces(n, &first.faces).map_err(MeshError::from)?;
        let mut pieces = Vec::with_capacity(topology.len());
        let mut infos = Vec::with_capacity(topology.len());
        let mut local = vec![u32::MAX; n];
        for (p, piece) in topology.iter().enumerate() {
            for (i, &v) in piece.vertices.iter().enumerate() {
                local[v as usize] = i as u32;
            }
            let to_local = |f: [u32; 3]| f.map(|v| local[v as usize]);
            let mut faces: Vec<[u32; 3]> = piece
                .faces
                .iter()
                .map(|&f| to_local(first.faces[f as usize]))
                .collect();
            let visible = faces.len();
            let local_keyframes: Vec<Vec<[f64; 2]>> = keyframes
                .iter()
                .map(|k| {
                    piece
                        .vertices
                        .iter()
                        .map(|&v| k.positions[v as usize])
                        .collect()
                })
                .collect();
            let holes = piece.loops.len() - 1;
            // Free holes: their inert filling (after every other face) and their loops.
            let mut inert: Vec<[u32; 3]> = Vec::new();
            let mut free: Vec<Vec<u32>> = Vec::new();
            if holes > 0 {
                let outer = (0..piece.loops.len())
                    .max_by(|&a, &b| {
                        let area = |l: usize| loop_area(&piece.loops[l], &first.positions);
                        area(a).total_cmp(&area(b))
                    })
                    .unwrap_or(0);
                let taken: HashSet<(u32, u32)> = faces
                    .iter()
                    .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
                    .map(|(a, b)| (a.min(b), a.max(b)))
                    .collect();
                let views: Vec<&[[f64; 2]]> = local_keyframes.iter().map(|k| &k[..]).collect();
                for (h, l) in piece.loops.iter().enumerate() {
                    if h == outer {
                        continue;
                    }
                    // The loop runs with the piece on its left: reversed, it runs
                    // counter-clockwise around the hole.
                    let polygon: Vec<u32> = l.iter().rev().map(|&v| local[v as usize]).collect();
                    if let Some(hidden) = holes::fill(&polygon, &views, &taken) {
                        faces.extend(hidden);
                        continue;
                    }
                    // No filling suits every keyframe: a free hole.
                    let topology = holes::fill_topology(&polygon, views[0], &taken).ok_or(
                        MorphError::HoleUnfillable {
                            piece: p,
                            vertex: l[0],
                            boundary_vertices: l.len(),
                        },
                    )?;
                    inert.extend(topology);
                    free.push(l.iter().map(|&v| local[v as usize]).collect());
                }
            }
            let real_faces = faces.len();
            let mut flags = Vec::new();
            if !inert.is_empty() {
                flags = vec![false; real_faces];
                flags.resize(real_faces + inert.len(), true);
                faces.extend(inert);
            }
            let local_meshes: Vec<PlanarMesh> = local_keyframes
                .into_iter()
                .map(|positions| PlanarMesh {
                    positions,
                    faces: faces.clone(),
                })
                .collect();
            let program =
                bdmorph_compiler::compile_with_inert(&local_meshes[0].positions, &faces, &flags)
                    // Pieces are disks with holes (checked above) and the hidden triangles
                    // add no edge the piece has: this compiles. A piece alone is numbered as
                    // the mesh.
                    .map_err(MeshError::from)?;
            let root = program.embed_root();
            let anchor = piece.vertices[root.p0 as usize];
            let anchor_edge = [anchor, piece.vertices[root.p1 as usize]];
            let engine = Engine::new(
                program,
                &local_meshes,
                visible,
                real_faces,
                &free,
                unwrap,
                options.clone(),
            )?;
            infos.push(PieceInfo {
                vertices: piece.vertices.len(),
                faces: visible,
                holes,
                hidden: faces[visible..real_faces]
                    .iter()
                    .map(|f| f.map(|v| piece.vertices[v as usize]))
                    .collect(),
                free_holes: engine
                    .free_holes()
                    .into_iter()
                    .map(|v| piece.vertices[v as usize])
                    .collect(),
                anchor,
                anchor_edge,
            });
            pieces.push(PieceSolver {
                engine,
                out: vec![[0.0; 2]; piece.vertices.len()],
                vertices: piece.vertices.clone(),
                faces: piece.faces.clone(),
            });
        }
        let direct = pieces.len() == 1;
        Ok(Solver {
            direct,
            positions: vec![[0.0; 2]; if direct { 0 } else { n }],
            distortion: vec![1.0; if direct { 0 } else { first.faces.len() }],
            faces: first.faces.clone(),
            n_vertices: n,
            pieces,
            structure: Structure {
                pieces: infos,
                inverted,
            },
            pool: crate::threads::Pool::default(),
            reach: Vec::new(),
            reach_shape: None,
        })
    }

    /// Prepares the solver from a program already compiled for the first keyframe's
    /// triangles, which must form one disk (program files hold one disk).
    pub(crate) fn with_program(
        program: Program,
        keyframes: &[PlanarMesh],
        unwrap: Unwrap,
        options: MorphOptions,
    ) -> Result<Solver, MorphError> {
        // The program holds one disk; a face it does not have is refused when the solver
        // looks up the face's edges ([`MorphError::ProgramMismatch`]).
        options.validate()?;
        let pool = crate::threads::Pool::new(options.threads)?;
        let inverted = check(keyframes, options.allow_inverted)?;
        let mut solver = pool.run(|| {
            let mut solver = Solver::disk(program, keyframes, inverted, unwrap, options.clone())?;
            solver.prepare_reach(keyframes, &options)?;
            Ok::<_, MorphError>(solver)
        })?;
        solver.pool = pool;
        Ok(solver)
    }

    /// The solver of one disk, from its program.
    fn disk(
        program: Program,
        keyframes: &[PlanarMesh],
        inverted: Vec<Vec<usize>>,
        unwrap: Unwrap,
        options: MorphOptions,
    ) -> Result<Solver, MorphError> {
        let first = &keyframes[0];
        let n = first.positions.len();
        let root = program.embed_root();
        let anchor = root.p0;
        let m = first.faces.len();
        let engine = Engine::new(program, keyframes, m, m, &[], unwrap, options)?;
        Ok(Solver {
            direct: true,
            positions: Vec::new(),
            distortion: Vec::new(),
            faces: first.faces.clone(),
            n_vertices: n,
            pieces: vec![PieceSolver {
                engine,
                vertices: (0..n as u32).collect(),
                faces: (0..first.faces.len() as u32).collect(),
                out: Vec::new(),
            }],
            pool: crate::threads::Pool::default(),
            reach: Vec::new(),
            reach_shape: None,
            structure: Structure {
                pieces: vec![PieceInfo {
                    vertices: n,
                    faces: first.faces.len(),
                    holes: 0,
                    hidden: Vec::new(),
                    free_holes: Vec::new(),
                    anchor,
                    anchor_edge: [root.p0, root.p1],
                }],
                inverted,
            },
        })
    }

    /// What the solver found.
    pub(crate) fn structure(&self) -> &Structure {
        &self.structure
    }

    /// The compiled program of the first piece.
    pub(crate) fn program(&self) -> &Program {
        self.pieces[0].engine.program()
    }

    /// The triangles (the first keyframe's).
    pub(crate) fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// Number of keyframes.
    pub(crate) fn keyframes(&self) -> usize {
        self.pieces[0].engine.keyframes()
    }

    /// The last frame's log scale factors of the first piece, one per interior vertex of it.
    pub(crate) fn scale_factors(&self) -> &[f64] {
        self.pieces[0].engine.scale_factors()
    }

    /// How the first piece's numeric factor is stored now.
    pub(crate) fn factor_precision(&self) -> FactorPrecision {
        self.pieces[0].engine.factor_precision()
    }

    /// The last frame's positions.
    pub(crate) fn positions(&self) -> &[[f64; 2]] {
        if self.direct {
            self.pieces[0].engine.positions()
        } else {
            &self.positions
        }
    }

    /// The last frame's conformal distortion per triangle, relative to the first keyframe.
    pub(crate) fn distortion(&self) -> &[f64] {
        if self.direct {
            self.pieces[0].engine.distortion()
        } else {
            &self.distortion
        }
    }

    /// Forgets every piece's solved frames.
    pub(crate) fn forget_solutions(&mut self) {
        for p in &mut self.pieces {
            p.engine.forget_solutions();
        }
    }

    /// Solves the frame with `weights` into the internal buffer.
    pub(crate) fn frame(
        &mut self,
        weights: &[f64],
        time: Option<f64>,
        line: Option<Line>,
    ) -> Result<FrameStats, MorphError> {
        let pool = self.pool.clone();
        pool.run(|| self.frame_here(weights, time, line))
    }

    fn frame_here(
        &mut self,
        weights: &[f64],
        time: Option<f64>,
        line: Option<Line>,
    ) -> Result<FrameStats, MorphError> {
        if self.direct {
            return self.pieces[0].engine.frame(weights, time, line);
        }
        let mut out = std::mem::take(&mut self.positions);
        let result = self.frame_into_here(weights, time, line, &mut out);
        self.positions = out;
        result
    }

    /// Solves the frame with `weights` into `out`; see [`Engine::frame_into`]. Allocates
    /// nothing unless it fails; on error `out` is left untouched.
    pub(crate) fn frame_into(
        &mut self,
        weights: &[f64],
        time: Option<f64>,
        line: Option<Line>,
        out: &mut [[f64; 2]],
    ) -> Result<FrameStats, MorphError> {
        let pool = self.pool.clone();
        pool.run(|| self.frame_into_here(weights, time, line, out))
    }

    fn frame_into_here(
        &mut self,
        weights: &[f64],
        time: Option<f64>,
        line: Option<Line>,
        out: &mut [[f64; 2]],
    ) -> Result<FrameStats, MorphError> {
        if self.direct {
            return self.pieces[0].engine.frame_into(weights, time, line, out);
        }
        let started = std::time::Instant::now();
        if out.len() != self.n_vertices {
            return Err(MorphError::OutputLength {
                expected: self.n_vertices,
                got: out.len(),
            });
        }
        if weights.iter().any(|&w| w < 0.0) {
            self.check_extrapolation(weights, time)?;
        }
        let mut total: Option<FrameStats> = None;
        let n_faces = self.faces.len();
        let mut hidden_before = 0;
        for p in &mut self.pieces {
            let stats = p
                .engine
                .frame_into(weights, time, line, &mut p.out)
                .map_err(|e| to_mesh(e, p, n_faces + hidden_before))?;
            hidden_before += p.engine.faces().len() - p.faces.len();
            total = Some(match total {
                None => stats,
                Some(t) => FrameStats {
                    t: t.t,
                    newton_iterations: t.newton_iterations + stats.newton_iterations,
                    factorizations: t.factorizations + stats.factorizations,
                    cg_iterations: t.cg_iterations + stats.cg_iterations,
                    gradient_norm: t.gradient_norm.max(stats.gradient_norm),
                    flipped_triangles: t.flipped_triangles + stats.flipped_triangles,
                    max_conformal_distortion: t
                        .max_conformal_distortion
                        .max(stats.max_conformal_distortion),
                    seconds: 0.0,
                },
            });
        }
        for p in &self.pieces {
            for (&v, &x) in p.vertices.iter().zip(&p.out) {
                out[v as usize] = x;
            }
            for (&f, &d) in p.faces.iter().zip(p.engine.distortion()) {
                self.distortion[f as usize] = d;
            }
        }
        let mut stats = total.ok_or(MorphError::OutputLength {
            expected: self.n_vertices,
            got: out.len(),
        })?;
        let mut corrected = false;
        for (k, miss) in &self.reach {
            let w = weights[*k];
            if w != 0.0 {
                corrected = true;
                for (p, d) in out.iter_mut().zip(miss) {
                    p[0] += w * d[0];
                    p[1] += w * d[1];
                }
            }
        }
        if let (true, Some(shape)) = (corrected, &self.reach_shape) {
            // Measured on what is returned: the user's triangles as corrected.
            stats.max_conformal_distortion = shape.distortion_into(out, &mut self.distortion);
            stats.flipped_triangles = self.distortion.iter().filter(|d| d.is_infinite()).count();
        }
        stats.seconds = started.elapsed().as_secs_f64();
        Ok(stats)
    }

    /// For weights outside the simplex: the earliest break of any piece's metric.
    fn check_extrapolation(
        &mut self,
        weights: &[f64],
        time: Option<f64>,
    ) -> Result<(), MorphError> {
        let n_faces = self.faces.len();
        let mut hidden_before = 0;
        let mut earliest: Option<(f64, MorphError)> = None;
        // The pieces share their base weights (the nearest inside the simplex): the nearer a
        // limit is to them, the earlier the break. Measured from the base, not from the asked
        // weights, which may be 1e20 away.
        let positive: f64 = weights.iter().filter(|&&w| w > 0.0).sum();
        let base = |w: f64| if w > 0.0 { w / positive } else { 0.0 };
        for p in &mut self.pieces {
            if let Err(e) = p.engine.check_extrapolation(weights, time) {
                let reach = match &e {
                    MorphError::MetricBreaks {
                        limit: FrameAt::Weights(l),
                        ..
                    } => l
                        .iter()
                        .zip(weights)
                        .map(|(a, &w)| (a - base(w)).abs())
                        .sum::<f64>(),
                    _ => f64::INFINITY,
                };
                let e = to_mesh(e, p, n_faces + hidden_before);
                if earliest.as_ref().is_none_or(|(r, _)| reach < *r) {
                    earliest = Some((reach, e));
                }
            }
            hidden_before += p.engine.faces().len() - p.faces.len();
        }
        match earliest {
            Some((_, e)) => Err(e),
            None => Ok(()),
        }
    }
}

/// A piece's error in the mesh's numbering: vertices and faces of the piece become the
/// mesh's; a hidden triangle's face index is `hidden_base` plus its place among the hidden
/// ones (at or beyond the mesh's face count).
fn to_mesh(e: MorphError, piece: &PieceSolver, hidden_base: usize) -> MorphError {
    let vertex = |v: u32| piece.vertices.get(v as usize).copied().unwrap_or(v);
    let reports = |worst: Vec<TriangleReport>| -> Vec<TriangleReport> {
        worst
            .into_iter()
            .map(|mut t| {
                t.vertices = t.vertices.map(vertex);
                t
            })
            .collect()
    };
    match e {
        MorphError::MetricBreaks {
            at,
            face,
            vertices,
            limit,
        } => MorphError::MetricBreaks {
            at,
            face: match piece.faces.get(face) {
                Some(&f) => f as usize,
                None => hidden_base + face - piece.faces.len(),
            },
            vertices: vertices.map(vertex),
            limit,
        },
        MorphError::NotConverged {
            at,
            iterations,
            gradient_norm,
            worst,
        } => MorphError::NotConverged {
            at,
            iterations,
            gradient_norm,
            worst: reports(worst),
        },
        MorphError::Solver { at, source, worst } => MorphError::Solver {
            at,
            source,
            worst: reports(worst),
        },
        MorphError::HoleOpen { at, vertex: v, gap } => MorphError::HoleOpen {
            at,
            vertex: vertex(v),
            gap,
        },
        other => other,
    }
}
