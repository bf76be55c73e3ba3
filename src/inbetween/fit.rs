//! A mesh that exists already (the studio's rest mesh, made from drawing A) laid over drawing
//! B: the same correspondence and layout as [`super::compatible_mesh`], without re-meshing A.

use std::time::Instant;

use super::compatible::{
    boundary_edges, boundary_vertices, nearest_free_vertex, outline_error, read_pairs, shape_of,
    CompatibleReport, PairKind, Pins, ReadPairs,
};
use super::correspondence::{arc_map, rigid_alignment};
use super::layout::{lay_out_with_pairs, max_distortion, polish, FIT_STAGES};
use super::outline::{pair_loops, Loop, Shape};
use super::{Drawing, InbetweenError, InbetweenOptions, Match};
use crate::mesh::PlanarMesh;
use crate::render::Image;

/// A mesh laid over a drawing: where each vertex goes, and its place in the drawing.
#[derive(Clone, Debug)]
pub struct DrawingFit {
    /// One position per vertex, in B's picture (pixels, y up from the bottom edge), every
    /// triangle counter-clockwise.
    pub positions: Vec<[f64; 2]>,
    /// Texture coordinates in B's picture (`x / width`, `y / height`, y up), one per vertex.
    pub texcoords: Vec<[f64; 2]>,
    /// What was done. `outline_error` is how far B's outline strays from the laid mesh's
    /// boundary: the mesh keeps its own boundary vertices, so B's corners between two of
    /// them are cut.
    pub report: CompatibleReport,
}

/// The boundary loops of `faces`, each a list of vertices in order (outer loops
/// counter-clockwise, holes clockwise).
///
/// # Errors
/// [`InbetweenError::Topology`] when the boundary is not made of simple loops (a vertex
/// where two loops touch).
fn boundary_loops(faces: &[[u32; 3]], n: usize) -> Result<Vec<Vec<u32>>, InbetweenError> {
    let edges = boundary_edges(faces);
    let mut next = vec![u32::MAX; n];
    for &(a, b) in &edges {
        if next[a as usize] != u32::MAX {
            return Err(InbetweenError::Topology(format!(
                "the mesh's boundary touches itself at vertex {a}: lay over drawings a mesh whose outline is made of separate loops"
            )));
        }
        next[a as usize] = b;
    }
    let mut seen = vec![false; n];
    let mut loops = Vec::new();
    for &(start, _) in &edges {
        if seen[start as usize] {
            continue;
        }
        let mut l = Vec::new();
        let mut v = start;
        while !seen[v as usize] {
            seen[v as usize] = true;
            l.push(v);
            v = next[v as usize];
            if v == u32::MAX {
                return Err(InbetweenError::Internal("an open boundary loop".into()));
            }
        }
        loops.push(l);
    }
    Ok(loops)
}

/// What the layout over B starts from: the mesh's boundary loops, B's outline, the user's
/// pairs read, and every boundary vertex's place on B's outline.
struct Setup {
    loops: Vec<Vec<u32>>,
    shape_b: Shape,
    tolerance_b: f64,
    kinds: Vec<PairKind>,
    reports: Vec<super::compatible::PairReport>,
    /// The boundary vertices and their places over B.
    pins: Pins,
    /// What was done about B's holes.
    notes: Vec<String>,
}

/// The correspondence of the mesh's boundary with B's outline (see [`fit_drawing`]).
fn setup(
    mesh: &PlanarMesh,
    a_height: f64,
    b: &Image,
    matches: &[Match],
    options: &InbetweenOptions,
) -> Result<Setup, InbetweenError> {
    options.validate()?;
    mesh.validate()?;
    if !(a_height.is_finite() && a_height > 0.0) {
        return Err(InbetweenError::BadOption(format!(
            "drawing A's height {a_height}: give a positive number of pixels"
        )));
    }
    let n = mesh.positions.len();
    let loops = boundary_loops(&mesh.faces, n)?;
    let shape_a = Shape::from_loops(
        loops
            .iter()
            .map(|l| Loop::new(l.iter().map(|&v| mesh.positions[v as usize]).collect()))
            .collect(),
    );
    // B's outline simplified to about as many corners as the mesh has boundary vertices.
    let boundary = boundary_vertices(mesh).len();
    let (full_b, tolerance_b, pinholes) =
        shape_of(b, Drawing(1), &options.clone().with_vertices(2 * boundary))?;
    let pairing = pair_loops(&shape_a, &full_b, Drawing(1))?;
    if let Some(&hole) = pairing.a_only.first() {
        return Err(InbetweenError::Topology(format!(
            "{} of the mesh has no hole to go onto in drawing B: the studio's mesh keeps its holes; draw the hole, or make the rest picture without it",
            shape_a.name(hole)
        )));
    }
    // B's holes the mesh lacks are covered by it (B's picture is transparent there).
    let mut notes = Vec::new();
    if pinholes > 0 {
        notes.push(format!(
            "{} in drawing B filled (holes under {} px²)",
            if pinholes == 1 {
                "1 pinhole".to_string()
            } else {
                format!("{pinholes} pinholes")
            },
            options.pinhole
        ));
    }
    for &h in &pairing.b_only {
        let l = &full_b.loops[h];
        notes.push(format!(
            "drawing B's hole at ({:.0}, {:.0}) ({:.0} px²) is covered by the mesh, transparent in its picture",
            l.centroid[0],
            f64::from(b.height) - l.centroid[1],
            -l.area
        ));
    }
    let keep: Vec<usize> = (0..shape_a.loops.len())
        .map(|la| {
            pairing
                .pairs
                .iter()
                .find(|p| p.0 == la)
                .map(|p| p.1)
                .ok_or_else(|| InbetweenError::Internal(format!("loop {la} of A is not paired")))
        })
        .collect::<Result<_, _>>()?;
    let shape_b = full_b.subset(&keep);
    let loop_pairs: Vec<(usize, usize)> = (0..keep.len()).map(|i| (i, i)).collect();
    let points: Vec<([f64; 2], [f64; 2])> = matches
        .iter()
        .map(|m| {
            (
                [m.a[0], a_height - m.a[1]],
                [m.b[0], f64::from(b.height) - m.b[1]],
            )
        })
        .collect();
    let ReadPairs {
        anchors,
        kinds,
        reports,
    } = read_pairs(&shape_a, &shape_b, &loop_pairs, &points)?;
    let main = shape_a.pieces[0];
    let partner_of = |la: usize| {
        loop_pairs
            .iter()
            .find(|p| p.0 == la)
            .map(|p| p.1)
            .ok_or_else(|| InbetweenError::Internal(format!("loop {la} of A is not paired")))
    };
    let (angle, _) = rigid_alignment(
        &shape_a,
        &shape_a.loops[main],
        &shape_b,
        &shape_b.loops[partner_of(main)?],
    );
    // The boundary onto B's outline.
    let mut pins: Pins = Vec::with_capacity(boundary + matches.len());
    for (la, l) in loops.iter().enumerate() {
        let (loop_a, loop_b) = (&shape_a.loops[la], &shape_b.loops[partner_of(la)?]);
        let map = arc_map(&shape_a, loop_a, &shape_b, loop_b, angle, &anchors[la])?;
        for (i, &v) in l.iter().enumerate() {
            pins.push((v, loop_b.at(map.forward(loop_a.cum[i]))));
        }
    }
    Ok(Setup {
        loops,
        shape_b,
        tolerance_b,
        kinds,
        reports,
        pins,
        notes,
    })
}

/// Where the mesh's boundary goes on drawing B, to check before laying the mesh over it: for
/// each boundary loop, `per_loop` of its vertices evenly spaced along it, each as its point in
/// A and its place on B's outline, both in pixels from the pictures' top-left corners. The
/// arguments are [`fit_drawing`]'s, and so are the errors.
pub fn outline_correspondence(
    mesh: &PlanarMesh,
    a_height: f64,
    b: &Image,
    matches: &[Match],
    options: &InbetweenOptions,
    per_loop: usize,
) -> Result<Vec<Vec<[[f64; 2]; 2]>>, InbetweenError> {
    let Setup { loops, pins, .. } = setup(mesh, a_height, b, matches, options)?;
    let b_height = f64::from(b.height);
    let mut at = 0;
    let mut out = Vec::with_capacity(loops.len());
    for l in &loops {
        let count = per_loop.clamp(1, l.len());
        let here = &pins[at..at + l.len()];
        out.push(
            (0..count)
                .map(|i| {
                    let (v, q) = here[i * l.len() / count];
                    let p = mesh.positions[v as usize];
                    [[p[0], a_height - p[1]], [q[0], b_height - q[1]]]
                })
                .collect(),
        );
        at += l.len();
    }
    Ok(out)
}

/// Lays `mesh` (drawing A's, in A's picture: pixels, y up; every triangle counter-clockwise)
/// over drawing `b`: its boundary vertices go onto B's outline by the correspondence of the
/// two outlines (the rigid alignment and arc-length warping [`super::compatible_mesh`] uses,
/// pinned by the user's pairs on the outlines), interior pairs pin the vertex nearest A's
/// point, and the interior follows by the same layout: ARAP, untangling, the
/// bounded-distortion mapping. `a_height` is A's picture's height in pixels (the pairs are
/// given from the top-left corner).
///
/// Unlike [`super::compatible_mesh`], A's mesh is kept as it is: B's outline is met at the
/// mesh's own boundary vertices, and the report's `outline_error` says how far B's corners
/// between them are cut. An interior pair is met at the vertex nearest its point in A; its
/// report's `error` is that vertex's distance from the point.
///
/// # Errors
/// As [`super::compatible_mesh`]: [`InbetweenError::Meshing`] when B has no subject,
/// [`InbetweenError::Topology`] when B's pieces differ from the mesh's or B lacks one of the
/// mesh's holes (holes of B's that the mesh lacks are covered by it, and said in the
/// report's notes), [`InbetweenError::Match`] for a pair that cannot be read,
/// [`InbetweenError::Flipped`] when no flip-free layout was found. The mesh is kept as it is
/// (the studio's keyframes are places of its vertices), so the guarantee of
/// [`super::compatible_mesh`], which refines the mesh, does not apply: every untangling
/// stage is tried (the projections, the foldover-free untangling of Garanzha et al. 2021
/// near the flips, the bounded-distortion mapping), and what they leave is an error.
///
/// ```
/// use bdmorph::generate;
/// use bdmorph::inbetween::{compatible_mesh, fit_drawing, InbetweenOptions};
///
/// let draw = |top: [f64; 2]| {
///     generate::picture(160, 160, move |x, y| {
///         generate::capsule_distance([x, y], [80.0, 130.0], top, 22.0)
///     })
/// };
/// let (a, b) = (draw([80.0, 40.0]), draw([115.0, 45.0]));
/// let options = InbetweenOptions::default().with_vertices(300);
/// // A's mesh from somewhere (here: the compatible mesh of A with itself).
/// let mesh = compatible_mesh(&a, &a, &[], &options)?.mesh;
/// let fit = fit_drawing(&mesh, 160.0, &b, &[], &options)?;
/// assert_eq!(fit.report.flipped, 0);
/// assert!(fit.report.outline_error < 3.0);
/// # Ok::<(), bdmorph::inbetween::InbetweenError>(())
/// ```
pub fn fit_drawing(
    mesh: &PlanarMesh,
    a_height: f64,
    b: &Image,
    matches: &[Match],
    options: &InbetweenOptions,
) -> Result<DrawingFit, InbetweenError> {
    let started = Instant::now();
    let Setup {
        shape_b,
        tolerance_b,
        kinds,
        mut reports,
        mut pins,
        notes,
        ..
    } = setup(mesh, a_height, b, matches, options)?;
    let n = mesh.positions.len();
    // Interior pairs pin the nearest interior vertex, keeping its offset from A's point.
    let mut is_boundary = vec![false; n];
    for &(v, _) in &pins {
        is_boundary[v as usize] = true;
    }
    let mut interior: Vec<(usize, u32, [f64; 2])> = Vec::new();
    for (k, kind) in kinds.iter().enumerate() {
        let PairKind::Interior(pa, pb) = *kind else {
            continue;
        };
        let taken: Vec<u32> = interior.iter().map(|p| p.1).collect();
        match nearest_free_vertex(mesh, &is_boundary, &taken, pa) {
            Some(v) => {
                let q = mesh.positions[v as usize];
                let target = [pb[0] + q[0] - pa[0], pb[1] + q[1] - pa[1]];
                interior.push((k, v, target));
                pins.push((v, target));
                reports[k].error = (q[0] - pa[0]).hypot(q[1] - pa[1]);
            }
            None => {
                reports[k].met = false;
                reports[k].error = f64::INFINITY;
                reports[k].reason = Some(
                    "every interior vertex near its point in drawing A holds another pair already"
                        .into(),
                );
            }
        }
    }
    options.budget.check()?;
    let (layout, pins) = lay_out_with_pairs(
        mesh,
        pins,
        &interior,
        &mut reports,
        None,
        None,
        FIT_STAGES,
        &options.budget,
    )?;
    if layout.flipped > 0 {
        return Err(InbetweenError::Flipped {
            which: Drawing(1),
            flipped: layout.flipped,
            faces: mesh.faces.len(),
        });
    }
    let flipped_before_untangling = layout.flipped_before;
    let mut positions = layout.positions;
    let polish_rounds = polish(mesh, &pins, &mut positions, &options.budget)?;
    let (w, h) = (f64::from(b.width), f64::from(b.height));
    let texcoords = positions.iter().map(|p| [p[0] / w, p[1] / h]).collect();
    Ok(DrawingFit {
        report: CompatibleReport {
            vertices: n,
            faces: mesh.faces.len(),
            flipped: 0,
            tolerance: [0.0, tolerance_b],
            outline_error: outline_error(&shape_b, &mesh.faces, &positions),
            pairs: reports,
            max_distortion: max_distortion(mesh, &positions),
            flipped_before_untangling,
            added_vertices: 0,
            polish_rounds,
            notes,
            seconds: started.elapsed().as_secs_f64(),
        },
        positions,
        texcoords,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loops_of_a_square_with_a_hole() {
        // A 4x4 grid of squares with the middle 2x2 cut away.
        let mut faces = Vec::new();
        let id = |i: u32, j: u32| j * 5 + i;
        for j in 0..4 {
            for i in 0..4 {
                if (1..3).contains(&i) && (1..3).contains(&j) {
                    continue;
                }
                faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let positions: Vec<[f64; 2]> = (0..25)
            .map(|v| [f64::from(v % 5), f64::from(v / 5)])
            .collect();
        let loops = boundary_loops(&faces, 25).unwrap();
        assert_eq!(loops.len(), 2);
        let areas: Vec<f64> = loops
            .iter()
            .map(|l| Loop::new(l.iter().map(|&v| positions[v as usize]).collect()).area)
            .collect();
        let mut sorted = areas.clone();
        sorted.sort_by(f64::total_cmp);
        assert_eq!(sorted, vec![-4.0, 16.0]);
    }
}
