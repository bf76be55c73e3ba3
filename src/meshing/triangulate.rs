//! Triangulating a checked outline: a constrained Delaunay triangulation refined (Ruppert and
//! Chew's algorithm, spade's `refine`) to a minimum angle and to about the requested number
//! of vertices.
//!
//! Which triangles are inside:
//! * [`Inside::Parity`]: spade's `exclude_outer_faces` keeps the faces behind an odd number of
//!   constraint loops (it peels layers from the convex hull inwards, flipping at every
//!   constraint edge it crosses), which for loops that neither touch nor cross is the nesting
//!   parity: pieces, their holes, islands in the holes, and so on.
//! * [`Inside::HolePoints`]: Triangle's rule, a flood fill bounded by constraint edges from the
//!   convex hull and from each hole point eats the outside. When every constraint edge then
//!   separates a kept triangle from an eaten one (segments bound the shape and nothing else),
//!   that is again the parity, and refinement skips the eaten faces; otherwise (a segment
//!   inside the shape, a loop without a hole point) everything is refined and the flood fill
//!   is done on the refined triangulation.
//!
//! Density: the largest triangle area is set so that the kept region holds about the
//! requested number of vertices (about area / max area, beyond the outline's own), then
//! corrected from the count a pass gives, for up to four passes, until it is within 3%.

use std::collections::VecDeque;
use std::panic::{catch_unwind, AssertUnwindSafe};

use spade::handles::{FixedFaceHandle, InnerTag};
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, PositionInTriangulation,
    RefinementParameters, Triangulation,
};

use super::error::{MeshingError, Place};
use super::outline::{Checked, Inside};
use crate::mesh::PlanarMesh;

type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;

/// A triangulated outline.
#[derive(Clone, Debug)]
pub(crate) struct Triangulated {
    /// The kept triangles (counter-clockwise) and the vertices they use.
    pub mesh: PlanarMesh,
    /// Whether the last refinement finished (met the angle everywhere it could) rather than
    /// run out of its vertex budget.
    pub refinement_complete: bool,
    /// Refinement passes run.
    pub passes: usize,
}

/// How far from the requested vertex count a pass may land and be kept.
const CLOSE_ENOUGH: f64 = 0.03;
/// The largest triangle area, as a multiple of the area per requested vertex, that gives
/// about the requested count on a first pass: refined triangles are on average about 0.4 of
/// the largest area, and there are about two per vertex (measured on pictures from 1K to 50K
/// vertices: 0.78 to 0.80).
const AREA_PER_VERTEX: f64 = 0.79;
/// The most refinement passes.
const MAX_PASSES: usize = 4;

fn internal(message: impl Into<String>) -> MeshingError {
    MeshingError::Internal {
        place: Place::default(),
        message: message.into(),
    }
}

/// Which faces (by index, spade's numbering, including the outer face 0) are inside.
fn hole_point_fill(cdt: &Cdt, holes: &[[f64; 2]]) -> Vec<bool> {
    let mut eaten = vec![false; cdt.num_all_faces()];
    let mut stack: Vec<FixedFaceHandle<InnerTag>> = Vec::new();
    for e in cdt.convex_hull() {
        let inner = e.rev();
        if !inner.is_constraint_edge() {
            if let Some(f) = inner.face().as_inner() {
                stack.push(f.fix());
            }
        }
    }
    for h in holes {
        match cdt.locate(Point2::new(h[0], h[1])) {
            PositionInTriangulation::OnFace(f) => stack.push(f),
            PositionInTriangulation::OnEdge(e) => {
                let e = cdt.directed_edge(e);
                if !e.is_constraint_edge() {
                    stack.extend(
                        [e.face(), e.rev().face()]
                            .iter()
                            .filter_map(|f| f.as_inner())
                            .map(|f| f.fix()),
                    );
                }
            }
            PositionInTriangulation::OnVertex(v) => {
                for e in cdt.vertex(v).out_edges() {
                    if let Some(f) = e.face().as_inner() {
                        stack.push(f.fix());
                    }
                }
            }
            PositionInTriangulation::OutsideOfConvexHull(_)
            | PositionInTriangulation::NoTriangulation => {}
        }
    }
    while let Some(f) = stack.pop() {
        if std::mem::replace(&mut eaten[f.index()], true) {
            continue;
        }
        for e in cdt.face(f).adjacent_edges() {
            if !e.is_constraint_edge() {
                if let Some(g) = e.rev().face().as_inner() {
                    if !eaten[g.index()] {
                        stack.push(g.fix());
                    }
                }
            }
        }
    }
    let mut inside: Vec<bool> = eaten.iter().map(|&e| !e).collect();
    inside[0] = false; // the outer face
    inside
}

/// Faces inside by nesting parity: behind an odd least number of constraint edges from the
/// outside (a 0-1 breadth-first search).
fn parity_fill(cdt: &Cdt) -> Vec<bool> {
    let mut depth = vec![u32::MAX; cdt.num_all_faces()];
    let mut queue: VecDeque<(FixedFaceHandle<InnerTag>, u32)> = VecDeque::new();
    for e in cdt.convex_hull() {
        let inner = e.rev();
        if let Some(f) = inner.face().as_inner() {
            let d = u32::from(inner.is_constraint_edge());
            if d == 0 {
                queue.push_front((f.fix(), 0));
            } else {
                queue.push_back((f.fix(), 1));
            }
        }
    }
    while let Some((f, d)) = queue.pop_front() {
        if depth[f.index()] <= d {
            continue;
        }
        depth[f.index()] = d;
        for e in cdt.face(f).adjacent_edges() {
            if let Some(g) = e.rev().face().as_inner() {
                if e.is_constraint_edge() {
                    queue.push_back((g.fix(), d + 1));
                } else {
                    queue.push_front((g.fix(), d));
                }
            }
        }
    }
    let mut inside: Vec<bool> = depth.iter().map(|&d| d != u32::MAX && d % 2 == 1).collect();
    inside[0] = false;
    inside
}

/// Whether every constraint edge has an inside face on exactly one side.
fn constraints_bound(cdt: &Cdt, inside: &[bool]) -> bool {
    let side = |f: Option<FixedFaceHandle<InnerTag>>| f.is_some_and(|f| inside[f.index()]);
    cdt.undirected_edges()
        .filter(|e| e.is_constraint_edge())
        .all(|e| {
            let d = e.as_directed();
            side(d.face().as_inner().map(|f| f.fix()))
                != side(d.rev().face().as_inner().map(|f| f.fix()))
        })
}

/// The kept region's area and vertex count.
fn measure(cdt: &Cdt, inside: &[bool]) -> (f64, usize) {
    let mut used = vec![false; cdt.num_vertices()];
    let mut area = 0.0;
    for f in cdt.inner_faces() {
        if inside[f.fix().index()] {
            area += f.area();
            for v in f.vertices() {
                used[v.fix().index()] = true;
            }
        }
    }
    (area, used.iter().filter(|&&u| u).count())
}

/// The kept faces as a mesh, vertices numbered in order of first use.
fn extract(cdt: &Cdt, inside: &[bool]) -> PlanarMesh {
    let mut index = vec![u32::MAX; cdt.num_vertices()];
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    for f in cdt.inner_faces() {
        if !inside[f.fix().index()] {
            continue;
        }
        let mut tri = f.vertices().map(|v| {
            let i = v.fix().index();
            if index[i] == u32::MAX {
                index[i] = positions.len() as u32;
                let p = v.position();
                positions.push([p.x, p.y]);
            }
            index[i]
        });
        let [a, b, c] = tri.map(|v| positions[v as usize]);
        if (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) < 0.0 {
            tri.swap(1, 2);
        }
        faces.push(tri);
    }
    PlanarMesh { positions, faces }
}

/// Triangulates `outline` with angles of at least `min_angle` degrees (where the outline's
/// own corners allow) and about `target` vertices.
pub(crate) fn triangulate(
    outline: &Checked,
    target: usize,
    min_angle: f64,
) -> Result<Triangulated, MeshingError> {
    let points: Vec<Point2<f64>> = outline
        .vertices
        .iter()
        .map(|p| Point2::new(p[0], p[1]))
        .collect();
    let edges: Vec<[usize; 2]> = outline
        .segments
        .iter()
        .map(|s| [s[0] as usize, s[1] as usize])
        .collect();
    let mut conflicts = 0usize;
    let base = Cdt::try_bulk_load_cdt(points, edges, |_| conflicts += 1).map_err(|e| {
        internal(format!(
            "the outline's vertices cannot be triangulated: {e:?}"
        ))
    })?;
    if conflicts > 0 || base.num_vertices() != outline.vertices.len() {
        return Err(internal(format!(
            "{conflicts} segments cross others, or vertices coincide, after the checks"
        )));
    }
    let holes = match &outline.inside {
        Inside::Parity => None,
        Inside::HolePoints(h) => Some(h.as_slice()),
    };
    let inside = match holes {
        None => parity_fill(&base),
        Some(h) => hole_point_fill(&base, h),
    };
    let (area, outline_vertices) = measure(&base, &inside);
    if area.is_nan() || area <= 0.0 {
        return Err(MeshingError::NothingInside {
            place: Place::default(),
            hole_points: holes.is_some_and(|h| !h.is_empty()),
        });
    }
    // Spade's parity exclusion is right unless hole points say otherwise.
    let exclude = holes.is_none() || constraints_bound(&base, &inside);
    let cap = 10 * base.num_vertices() + 4 * target;
    let pass = |max_area: Option<f64>| -> Result<(Cdt, Vec<bool>, bool), MeshingError> {
        let mut cdt = base.clone();
        let mut params = RefinementParameters::<f64>::new()
            .with_angle_limit(AngleLimit::from_deg(min_angle))
            .with_max_additional_vertices(cap)
            .exclude_outer_faces(exclude);
        if let Some(a) = max_area {
            params = params.with_max_allowed_area(a);
        }
        let result = catch_unwind(AssertUnwindSafe(|| cdt.refine(params))).map_err(|_| {
            internal("the refinement failed (a precision limit of the triangulator)")
        })?;
        let inside = if exclude {
            let mut inside = vec![true; cdt.num_all_faces()];
            inside[0] = false;
            for f in result.excluded_faces {
                inside[f.index()] = false;
            }
            inside
        } else {
            hole_point_fill(&cdt, holes.unwrap_or(&[]))
        };
        Ok((cdt, inside, result.refinement_complete))
    };
    let mut max_area = (target > outline_vertices)
        .then(|| AREA_PER_VERTEX * area / (target - outline_vertices) as f64);
    let mut best: Option<(usize, Cdt, Vec<bool>, bool)> = None;
    let mut passes = 0;
    loop {
        let (cdt, inside, complete) = pass(max_area)?;
        passes += 1;
        let (_, count) = measure(&cdt, &inside);
        let miss = count.abs_diff(target);
        if best.as_ref().is_none_or(|b| miss < b.0.abs_diff(target)) {
            best = Some((count, cdt, inside, complete));
        }
        let Some(a) = max_area else { break };
        if (miss as f64) <= CLOSE_ENOUGH * target as f64 || passes == MAX_PASSES {
            break;
        }
        // Vertices beyond the outline's grow as 1 / max area.
        let grown = count.saturating_sub(outline_vertices).max(1) as f64;
        max_area = Some(a * grown / (target - outline_vertices) as f64);
    }
    let Some((_, cdt, inside, complete)) = best else {
        return Err(internal("no refinement pass ran"));
    };
    let mesh = extract(&cdt, &inside);
    if mesh.faces.is_empty() {
        return Err(MeshingError::NothingInside {
            place: Place::default(),
            hole_points: holes.is_some_and(|h| !h.is_empty()),
        });
    }
    Ok(Triangulated {
        mesh,
        refinement_complete: complete,
        passes,
    })
}
