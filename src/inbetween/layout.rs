//! Laying A's mesh over another drawing: every boundary vertex (and interior pair) pinned at
//! its place over the drawing, the inside by as-rigid-as-possible posing, then, while
//! triangles are flipped (or degenerate), three stages in turn:
//!
//! 1. the foldover-free untangling of Garanzha et al. 2021 ([`super::foldover`]), the fast
//!    first try;
//! 2. the untangling of [`crate::deform::untangle`] (bounded-distortion projections near the
//!    flips) and the bounded-distortion mapping over the whole mesh;
//! 3. the guarantee ([`guarantee`]): the region around what is left is re-embedded
//!    bijectively by composing Tutte embeddings onto a common convex polygon
//!    ([`super::embed`]), which refines A's mesh there, and the result is smoothed without
//!    letting a triangle fold.
//!
//! A flip-free layout's largest distortion is then lowered by [`polish`].

use super::compatible::{PairReport, Pins};
use super::embed::{embed, EmbedFailure, Embedded};
use super::foldover;
use super::refine::{collapse_added, flip_thin};
use super::InbetweenError;
use crate::deform::{untangle, ArapOptions, DeformError, Deformer, PoseMethod, UntangleOptions};
use crate::io::SurfaceMesh;
use crate::mesh::PlanarMesh;
use crate::param::bounded::{BoundedDistortion, BoundedOptions};
use crate::param::energy::Energy;
use crate::param::frames::Frames;
use crate::param::newton::Newton;
use crate::param::ParamError;
use crate::Budget;

/// Rounds of ARAP iterations (10 each) for the first layout over B.
const ARAP_ROUNDS: usize = 40;
/// A triangle counts as valid when its area is above this share of the squared diameter
/// (of A's mesh, or of the layout): 100 times the threshold below which the morph refuses a
/// triangle as degenerate ([`PlanarMesh::validate`]).
pub(super) const MIN_AREA_SHARE: f64 = 1e-12;
/// The smallest area (the same way) of a triangle of the guarantee's result, in A or over
/// the drawing: twice the morph's threshold.
pub(super) const REFINED_AREA_SHARE: f64 = 2e-14;
/// The smallest area of a triangle the re-embedding may make before the merging and
/// smoothing that follow it (which grow the thin ones, moving the added vertices in A too):
/// well above rounding.
const EMBED_AREA_SHARE: f64 = 1e-22;
/// The untangling stages tried in turn while triangles stay flipped: `u` the projections of
/// [`untangle`], `f` the foldover-free untangling near the flips, `r` the bounded-distortion
/// mapping over the whole mesh. When the guarantee follows (a mesh of A's own), the
/// projections alone: on the 48 training triples of the walk cycles, adding the others
/// doubled the time (120 to 226 s) without a layout the guarantee would not have made, and
/// its median distortion was lower (39 against 49).
pub(super) const BUILD_STAGES: &str = "u";
/// When it does not (a mesh laid over a drawing as it is): all of them.
pub(super) const FIT_STAGES: &str = "ufr";
/// Rounds and L-BFGS steps per round of the foldover-free untangling.
const FOLDOVER_ROUNDS: usize = 20;
const FOLDOVER_STEPS: usize = 200;
/// The foldover-free untangling moves the vertices within this many rings of a flip.
const FOLDOVER_RINGS: usize = 8;
/// L-BFGS steps of the smoothing after an untangling or a re-embedding.
const SMOOTHING_STEPS: usize = 400;
/// Triangles thinner than this (radians, 10°) in A have their edges flipped after the
/// guarantee where every layout allows.
const THIN_ANGLE: f64 = 0.1745;
/// Projected Newton steps on the symmetric Dirichlet energy after the guarantee.
const NEWTON_STEPS: usize = 40;
/// Rounds of smoothing the added vertices' places in A and the layout in turn.
const RELAX_ROUNDS: usize = 3;

/// The smallest valid triangle area of a layout of `positions`.
pub(super) fn min_area(positions: &[[f64; 2]]) -> f64 {
    MIN_AREA_SHARE * squared_size(positions)
}

/// The squared diagonal of the bounding box of `positions` (0 when not finite).
pub(super) fn squared_size(positions: &[[f64; 2]]) -> f64 {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in positions {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let d2 = (hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2);
    if d2.is_finite() {
        d2
    } else {
        0.0
    }
}

/// Triangles whose area in the layout is at most the validity threshold.
pub(super) fn bad(faces: &[[u32; 3]], positions: &[[f64; 2]]) -> usize {
    let m = min_area(positions);
    faces
        .iter()
        .filter(|f| {
            let area = signed_area(positions, f);
            area.is_nan() || area <= m
        })
        .count()
}

/// Rounds of [`polish`] at most, and the share of the largest distortion each aims for.
const POLISH_ROUNDS: usize = 4;
const POLISH_SHARE: f64 = 0.6;
/// Iterations of the bounded-distortion mapping when the untangling left flips.
const RESCUE_ITERATIONS: u32 = 1500;
/// Iterations of one round of [`polish`].
const POLISH_ITERATIONS: u32 = 400;

/// Lowers the largest distortion of a flip-free layout by the bounded-distortion mapping
/// with the pins held: each round asks for [`POLISH_SHARE`] of the largest distortion and is
/// kept when it gets there without a flip. Returns the rounds kept.
pub(super) fn polish(
    mesh: &PlanarMesh,
    pins: &[(u32, [f64; 2])],
    positions: &mut [[f64; 2]],
    budget: &Budget,
) -> Result<usize, InbetweenError> {
    let surface = SurfaceMesh::from(mesh);
    let mut kept = 0;
    for _ in 0..POLISH_ROUNDS {
        budget.check()?;
        let current = max_distortion(mesh, positions);
        let k = (POLISH_SHARE * current).max(1.5);
        if k >= current {
            break;
        }
        let options = BoundedOptions::new(k)
            .with_iterations(POLISH_ITERATIONS)
            .with_budget(budget.clone());
        let mut solver = BoundedDistortion::new(&surface, pins, options).map_err(bounded_error)?;
        let mut trial = positions.to_vec();
        let report = solver
            .solve_with(&mut trial, |_, _| {})
            .map_err(bounded_error)?;
        let better = report.inverted == 0
            && bad(&mesh.faces, &trial) == 0
            && max_distortion(mesh, &trial) < current;
        if !better {
            break;
        }
        positions.copy_from_slice(&trial);
        kept += 1;
        if !report.converged {
            break;
        }
    }
    Ok(kept)
}

/// A failure of the bounded-distortion mapping: a spent budget as
/// [`InbetweenError::Stopped`], anything else a bug of the construction.
pub(super) fn bounded_error(e: ParamError) -> InbetweenError {
    match e {
        ParamError::Stopped(s) => InbetweenError::Stopped(s),
        e => InbetweenError::Internal(format!("the bounded-distortion mapping: {e}")),
    }
}

/// A posing failure: a spent budget as [`InbetweenError::Stopped`].
pub(super) fn deform_error(e: DeformError) -> InbetweenError {
    match e {
        DeformError::Stopped(s) => InbetweenError::Stopped(s),
        e => InbetweenError::Deform(e),
    }
}

/// Interior pins of the user's pairs: `(pair, vertex, target)`.
pub(super) type InteriorPins = [(usize, u32, [f64; 2])];

/// [`lay_over`] with `pins` (the boundary's and the interior pairs' `interior`); when
/// triangles stay flipped, the interior pairs next to them are let go (and their reports say
/// so) if that leaves fewer flips. Returns the layout and the pins it holds.
// (The stages' inputs, and the budget bounding them.)
#[allow(clippy::too_many_arguments)]
pub(super) fn lay_out_with_pairs(
    mesh: &PlanarMesh,
    pins: Pins,
    interior: &InteriorPins,
    reports: &mut [PairReport],
    start: Option<Vec<[f64; 2]>>,
    weights: Option<&[f64]>,
    stages: &str,
    budget: &Budget,
) -> Result<(Layout, Pins), InbetweenError> {
    let mut pins = pins;
    let mut layout = lay_over(mesh, &pins, start, weights, stages, budget)?;
    if layout.flipped > 0 && !interior.is_empty() {
        // Let go of the interior pairs next to what stays flipped, and try again.
        let near = near_flips(mesh, &layout.positions, 3);
        let dropped: Vec<usize> = interior
            .iter()
            .filter(|&&(_, v, _)| near[v as usize])
            .map(|&(k, _, _)| k)
            .collect();
        if !dropped.is_empty() {
            let kept: Pins = pins
                .iter()
                .copied()
                .filter(|(v, _)| {
                    !interior
                        .iter()
                        .any(|&(k, w, _)| w == *v && dropped.contains(&k))
                })
                .collect();
            let retry = lay_over(
                mesh,
                &kept,
                Some(layout.positions.clone()),
                weights,
                stages,
                budget,
            )?;
            if retry.flipped < layout.flipped {
                for &k in &dropped {
                    reports[k].met = false;
                    reports[k].reason = Some(
                        "no flip-free layout over drawing B meets it with the outline where it is; the other pairs are met".into(),
                    );
                }
                layout = retry;
                pins = kept;
            }
        }
    }
    Ok((layout, pins))
}

/// A layout of the mesh over another drawing and how many of its triangles are flipped.
pub(super) struct Layout {
    pub positions: Vec<[f64; 2]>,
    /// Triangles flipped or degenerate (area at most the validity threshold).
    pub flipped: usize,
    /// Triangles flipped before the untangling.
    pub flipped_before: usize,
}

/// A layout with every pin at its target: from `start` when given, otherwise by ARAP from
/// A's layout; then, while triangles are flipped, the foldover-free untangling, then
/// [`untangle`] and the bounded-distortion mapping over the whole mesh (stages 1 and 2 of
/// the module docs). Triangles are weighted by `weights` in the untangling and smoothing
/// (or all alike).
pub(super) fn lay_over(
    mesh: &PlanarMesh,
    pins: &[(u32, [f64; 2])],
    start: Option<Vec<[f64; 2]>>,
    weights: Option<&[f64]>,
    stages: &str,
    budget: &Budget,
) -> Result<Layout, InbetweenError> {
    budget.check()?;
    let (vertices, targets): (Vec<u32>, Vec<[f64; 2]>) = pins.iter().copied().unzip();
    let pose = match start {
        Some(mut pose) => {
            for &(v, t) in pins {
                pose[v as usize] = t;
            }
            pose
        }
        None => {
            let method = PoseMethod::Arap(ArapOptions::default().with_budget(budget.clone()));
            let mut deformer = Deformer::new(mesh, method)?;
            deformer.set_pins(&vertices)?;
            let size = mesh.diameter().max(f64::MIN_POSITIVE);
            let mut previous = deformer.positions().to_vec();
            for _ in 0..ARAP_ROUNDS {
                deformer.drag(&targets).map_err(deform_error)?;
                let moved = deformer
                    .positions()
                    .iter()
                    .zip(&previous)
                    .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
                    .fold(0.0, f64::max);
                previous.copy_from_slice(deformer.positions());
                if moved < 1e-5 * size {
                    break;
                }
            }
            deformer.positions().to_vec()
        }
    };
    let flipped_before = bad(&mesh.faces, &pose);
    let mut layout = Layout {
        flipped: flipped_before,
        positions: pose.clone(),
        flipped_before,
    };
    if layout.flipped == 0 {
        return Ok(layout);
    }
    let mut fixed = vec![false; mesh.positions.len()];
    for &v in &vertices {
        fixed[v as usize] = true;
    }
    for stage in stages.chars() {
        if layout.flipped == 0 {
            break;
        }
        budget.check()?;
        match stage {
            'f' => {
                // Foldover-free untangling, near the flips.
                let mut window = near_flips(mesh, &layout.positions, FOLDOVER_RINGS);
                for (w, f) in window.iter_mut().zip(&fixed) {
                    *w = !*w || *f;
                }
                let mut trial = layout.positions.clone();
                let m = min_area(&trial);
                foldover::untangle(
                    &mesh.positions,
                    &mesh.faces,
                    weights,
                    &window,
                    &mut trial,
                    m,
                    FOLDOVER_ROUNDS,
                    FOLDOVER_STEPS,
                );
                let left = bad(&mesh.faces, &trial);
                if left < layout.flipped {
                    layout.flipped = left;
                    layout.positions = trial;
                }
            }
            'u' => {
                // Bounded-distortion projections near the flips.
                let repaired = untangle(
                    mesh,
                    &layout.positions,
                    &vertices,
                    // Any fewer flips are kept below: the layout is untangled further after.
                    &UntangleOptions::default()
                        .with_best_effort(true)
                        .with_budget(budget.clone()),
                )
                .map_err(deform_error)?;
                let left = bad(&mesh.faces, &repaired.positions);
                if left < layout.flipped {
                    layout.flipped = left;
                    layout.positions = repaired.positions;
                }
            }
            'r' => {
                // The bounded-distortion mapping over the whole mesh.
                let bound = (2.0 * max_distortion_unflipped(mesh, &layout.positions)).max(10.0);
                let options = BoundedOptions::new(bound)
                    .with_inverted_bound(2.0)
                    .with_iterations(RESCUE_ITERATIONS)
                    .with_budget(budget.clone());
                let mut solver = BoundedDistortion::new(&SurfaceMesh::from(mesh), pins, options)
                    .map_err(bounded_error)?;
                let mut trial = layout.positions.clone();
                solver
                    .solve_with(&mut trial, |_, _| {})
                    .map_err(bounded_error)?;
                let left = bad(&mesh.faces, &trial);
                if left < layout.flipped
                    && trial.iter().all(|p| p[0].is_finite() && p[1].is_finite())
                {
                    layout.positions = trial;
                    layout.flipped = left;
                }
            }
            _ => {}
        }
    }
    if layout.flipped == 0 && weights.is_some() {
        // Transparent regions: their triangles weigh less, and may shrink.
        smooth(
            mesh,
            &fixed,
            weights,
            &mut layout.positions,
            SMOOTHING_STEPS,
        );
    }
    Ok(layout)
}

/// Lowers the untangling energy of a valid layout without letting a triangle fold, at most
/// `steps` L-BFGS steps.
pub(super) fn smooth(
    mesh: &PlanarMesh,
    fixed: &[bool],
    weights: Option<&[f64]>,
    positions: &mut [[f64; 2]],
    steps: usize,
) {
    // Valid stays valid: above the threshold, or above half the smallest area now.
    let smallest = mesh
        .faces
        .iter()
        .map(|f| signed_area(positions, f))
        .fold(f64::INFINITY, f64::min);
    let m = min_area(positions).min(0.5 * smallest);
    foldover::smooth(
        &mesh.positions,
        &mesh.faces,
        weights,
        fixed,
        positions,
        m,
        steps,
    );
}

/// What the guarantee did: A's mesh refined where it had to be, the layout over the drawing,
/// and the held vertices it let go.
pub(super) struct Guaranteed {
    /// The refined mesh (A's): the input's vertices first, at the same places.
    pub mesh: PlanarMesh,
    /// Its layout over the drawing.
    pub layout: Vec<[f64; 2]>,
    /// Held interior vertices inside a re-embedded region.
    pub released: Vec<u32>,
}

/// Stage 3: the layout `positions` of `mesh` (with the pins `pins` held) re-embedded
/// bijectively where it is still flipped, refining the mesh there ([`super::embed`]); the
/// layouts over other drawings made already (`earlier`, affine per triangle of `mesh`) are
/// extended to the refined mesh. The result is smoothed, the added vertices that no layout
/// needs are merged away again ([`collapse_added`]), and it is smoothed once more. Held
/// interior vertices inside a re-embedded region are let go (`released`).
///
/// # Errors
/// [`EmbedFailure`] when the region around the flips surrounds a hole of the mesh, when the
/// outline over the drawing is not simple (no bijection exists), or at a precision limit.
pub(super) fn guarantee(
    mesh: &PlanarMesh,
    pins: &[(u32, [f64; 2])],
    positions: &[[f64; 2]],
    weights: Option<&[f64]>,
    earlier: &mut [Vec<[f64; 2]>],
) -> Result<Guaranteed, EmbedFailure> {
    let n0 = mesh.positions.len();
    let mut fixed = vec![false; n0];
    for &(v, _) in pins {
        fixed[v as usize] = true;
    }
    let Embedded {
        mesh: mut refined,
        mut layout,
        new_vertices,
        mut origin,
        released,
        ..
    } = embed(
        mesh,
        positions,
        &fixed,
        min_area(positions),
        EMBED_AREA_SHARE * squared_size(&mesh.positions),
        EMBED_AREA_SHARE * squared_size(positions),
    )?;
    for l in earlier.iter_mut() {
        extend_layout(mesh, l, &new_vertices);
    }
    let mut fixed_after = fixed;
    fixed_after.resize(refined.positions.len(), false);
    for &v in &released {
        fixed_after[v as usize] = false;
    }
    // Refined triangles take the weight of the input triangle holding them.
    let weights_of = |origin: &[u32]| -> Option<Vec<f64>> {
        weights.map(|w| origin.iter().map(|&o| w[o as usize]).collect())
    };
    smooth(
        &refined,
        &fixed_after,
        weights_of(&origin).as_deref(),
        &mut layout,
        SMOOTHING_STEPS,
    );
    {
        let mut all: Vec<&mut Vec<[f64; 2]>> = Vec::with_capacity(2 + earlier.len());
        all.push(&mut refined.positions);
        all.push(&mut layout);
        all.extend(earlier.iter_mut());
        collapse_added(&mut refined.faces, &mut origin, &mut all, n0);
    }
    fixed_after.truncate(refined.positions.len());
    // The added vertices are A's own Steiner points: their places in A may move too (their
    // texture coordinates follow), so the thin triangles the chords cut are evened out,
    // A's shapes smoothed towards B's and B's towards A's in turn.
    let mut only_added: Vec<bool> = (0..refined.positions.len()).map(|v| v < n0).collect();
    if refined.positions.len() > n0 {
        for _ in 0..RELAX_ROUNDS {
            {
                let mut all: Vec<&Vec<[f64; 2]>> = vec![&refined.positions, &layout];
                all.extend(earlier.iter());
                flip_thin(&mut refined.faces, &all, THIN_ANGLE);
            }
            let in_a = PlanarMesh {
                positions: layout.clone(),
                faces: refined.faces.clone(),
            };
            smooth(
                &in_a,
                &only_added,
                None,
                &mut refined.positions,
                SMOOTHING_STEPS,
            );
            smooth(
                &refined,
                &fixed_after,
                weights_of(&origin).as_deref(),
                &mut layout,
                SMOOTHING_STEPS,
            );
        }
    } else {
        smooth(
            &refined,
            &fixed_after,
            weights_of(&origin).as_deref(),
            &mut layout,
            SMOOTHING_STEPS,
        );
    }
    only_added.clear();
    newton_smooth(
        &refined,
        &fixed_after,
        weights_of(&origin).as_deref(),
        &mut layout,
        NEWTON_STEPS,
    );
    Ok(Guaranteed {
        mesh: refined,
        layout,
        released,
    })
}

/// Lowers the symmetric Dirichlet energy `σ₁² + σ₂² + σ₁⁻² + σ₂⁻²` of a flip-free layout
/// (each triangle's area times its weight) by projected Newton with the flip-free line
/// search of [`crate::param`], the vertices `fixed` held: at most `steps` steps, stopping
/// when a step gains less than a millionth.
fn newton_smooth(
    mesh: &PlanarMesh,
    fixed: &[bool],
    weights: Option<&[f64]>,
    positions: &mut [[f64; 2]],
    steps: usize,
) {
    let Ok(mut frames) = Frames::new(&SurfaceMesh::from(mesh)) else {
        return;
    };
    if let Some(w) = weights {
        for (a, w) in frames.area.iter_mut().zip(w) {
            *a *= w;
        }
        frames.total_area = frames.area.iter().sum();
    }
    let Ok(mut newton) = Newton::new(&frames, positions.len(), Energy::SymmetricDirichlet) else {
        return;
    };
    newton.fix((0..fixed.len() as u32).filter(|&v| fixed[v as usize]));
    for _ in 0..steps {
        let r = newton.iterate(&frames, positions);
        match r {
            Ok(r)
                if r.step > 0.0
                    && r.energy_before - r.energy_after > 1e-6 * r.energy_before.abs() => {}
            _ => break,
        }
    }
}

/// Appends to `layout` (of `mesh`, affine per triangle) the places of the vertices a
/// refinement added: `(triangle of mesh, barycentric coordinates)` each.
fn extend_layout(mesh: &PlanarMesh, layout: &mut Vec<[f64; 2]>, added: &[(u32, [f64; 3])]) {
    for &(f, l) in added {
        let [p, q, r] = mesh.faces[f as usize].map(|v| layout[v as usize]);
        layout.push([
            l[0] * p[0] + l[1] * q[0] + l[2] * r[0],
            l[0] * p[1] + l[1] * q[1] + l[2] * r[1],
        ]);
    }
}

pub(super) fn signed_area(p: &[[f64; 2]], f: &[u32; 3]) -> f64 {
    let (a, b, c) = (p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]);
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
}

/// Vertices within `rings` rings of a flipped triangle.
fn near_flips(mesh: &PlanarMesh, positions: &[[f64; 2]], rings: usize) -> Vec<bool> {
    let mut near = vec![false; mesh.positions.len()];
    for f in &mesh.faces {
        if signed_area(positions, f) <= 0.0 {
            for &v in f {
                near[v as usize] = true;
            }
        }
    }
    for _ in 0..rings {
        let mut next = near.clone();
        for f in &mesh.faces {
            if f.iter().any(|&v| near[v as usize]) {
                for &v in f {
                    next[v as usize] = true;
                }
            }
        }
        near = next;
    }
    near
}

/// The largest conformal distortion of the unflipped triangles of the map.
pub(super) fn max_distortion_unflipped(mesh: &PlanarMesh, positions: &[[f64; 2]]) -> f64 {
    let rest = crate::distortion::RestShape::new(&mesh.positions, &mesh.faces);
    let mut out = vec![0.0; mesh.faces.len()];
    rest.distortion_into(positions, &mut out);
    out.into_iter()
        .filter(|d| d.is_finite())
        .fold(1.0, f64::max)
}

/// The largest conformal distortion of the map from `mesh` to `positions` (infinite with a
/// flipped triangle).
pub(crate) fn max_distortion(mesh: &PlanarMesh, positions: &[[f64; 2]]) -> f64 {
    let rest = crate::distortion::RestShape::new(&mesh.positions, &mesh.faces);
    let mut out = vec![0.0; mesh.faces.len()];
    rest.distortion_into(positions, &mut out).max(1.0)
}
