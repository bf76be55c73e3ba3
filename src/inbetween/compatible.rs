//! A compatible mesh of two drawings: drawing A's mesh laid over drawing B without a flipped
//! triangle.

use std::time::Instant;

use super::correspondence::ArcMap;
use super::correspondence::{arc_map, common_polygon, rigid_alignment, Anchor, Corner};
use super::embed::EmbedFailure;
use super::layout::{
    guarantee, lay_out_with_pairs, lay_over, max_distortion, polish, signed_area, smooth,
    squared_size, BUILD_STAGES, REFINED_AREA_SHARE,
};
use super::outline::{closest_on_segment, pair_loops, Loop, LoopPairing, Shape};
use super::refine::{fill_holes, split_boundary_chords};
use super::{Drawing, InbetweenError, InbetweenOptions, Match};
use crate::io::TexCoords;
use crate::mesh::PlanarMesh;
use crate::meshing::{fit_loops_to_vertices, mesh_outline, picture_outline, MeshOptions, Outline};
use crate::render::Image;

/// How far from an outline (in pixels, or this share of the subject's size when larger) a
/// matched point counts as a point of the outline: 3 pixels, 2%.
const ON_OUTLINE_PIXELS: f64 = 3.0;
const ON_OUTLINE_SHARE: f64 = 0.02;

/// What became of one of the user's point pairs.
#[derive(Clone, Debug, PartialEq)]
pub struct PairReport {
    /// Whether both points are on the drawings' outlines (an anchor of the correspondence);
    /// otherwise both are inside and pin a vertex.
    pub on_outline: bool,
    /// Whether the compatible mesh meets it: A's point is a vertex whose place over B is B's
    /// point (to [`PairReport::error`]).
    pub met: bool,
    /// The distance in B (pixels) between B's point and where A's point lands, or the
    /// distance of B's point from B's outline for a point on the outline.
    pub error: f64,
    /// Why it is not met.
    pub reason: Option<String>,
}

/// What building a compatible mesh did and how good it is.
#[derive(Clone, Debug, PartialEq)]
pub struct CompatibleReport {
    /// Vertices of the mesh.
    pub vertices: usize,
    /// Triangles.
    pub faces: usize,
    /// Triangles flipped (signed area not positive) over B: 0.
    pub flipped: usize,
    /// The tolerance in pixels each drawing's outline was simplified to (A's, B's).
    pub tolerance: [f64; 2],
    /// The largest distance (pixels) of a corner of B's simplified outline from the
    /// boundary of the mesh laid over B: 0 unless corners were merged.
    pub outline_error: f64,
    /// Per user pair, in order.
    pub pairs: Vec<PairReport>,
    /// The largest conformal distortion `σ₁/σ₂` of the map from A's layout to B's.
    pub max_distortion: f64,
    /// Triangles flipped by the first layout (ARAP with the outline fixed), before untangling.
    pub flipped_before_untangling: usize,
    /// Vertices added to A's mesh where it had no flip-free layout over this drawing as it
    /// was (the guarantee's refinement, see [`super`]); 0 when none was needed.
    pub added_vertices: usize,
    /// Rounds of the bounded-distortion mapping that lowered the largest distortion (none
    /// when transparent regions are let shrink instead).
    pub polish_rounds: usize,
    /// What was done about the drawings' holes, one line each: pinholes filled (holes under
    /// [`super::InbetweenOptions::pinhole`]), holes of drawing A that this drawing lacks
    /// (meshed as transparent regions that shrink here), holes of this drawing that A lacks
    /// (covered by the mesh, transparent in its picture). Empty when the holes match.
    pub notes: Vec<String>,
    /// Wall-clock seconds from the start of the build to this layout (with several drawings,
    /// the layouts are made in order).
    pub seconds: f64,
}

/// Drawing A's mesh and the same triangles laid over drawing B.
#[derive(Clone, Debug)]
pub struct CompatibleMesh {
    /// A's mesh: positions in A's picture (pixels, y up from the bottom edge),
    /// counter-clockwise triangles.
    pub mesh: PlanarMesh,
    /// The same triangles over B: one position per vertex, in B's picture, every triangle
    /// counter-clockwise.
    pub positions_b: Vec<[f64; 2]>,
    /// Texture coordinates in A's picture, one per vertex.
    pub texcoords_a: TexCoords,
    /// Texture coordinates in B's picture, one per vertex.
    pub texcoords_b: TexCoords,
    /// What was done.
    pub report: CompatibleReport,
}

impl CompatibleMesh {
    /// B's layout as a mesh (A's triangles at B's positions).
    pub fn mesh_b(&self) -> PlanarMesh {
        PlanarMesh {
            positions: self.positions_b.clone(),
            faces: self.mesh.faces.clone(),
        }
    }
}

/// A drawing's outline without its pinholes (holes under [`InbetweenOptions::pinhole`]),
/// simplified to fit about half the vertices of the mesh; the tolerance it was simplified
/// to, and how many pinholes were filled.
pub(super) fn shape_of(
    image: &Image,
    which: Drawing,
    options: &InbetweenOptions,
) -> Result<(Shape, f64, usize), InbetweenError> {
    let traced = picture_outline(image, &options.picture, None)
        .map_err(|source| InbetweenError::Meshing { which, source })?;
    let (shape, pinholes) = Shape::of(&traced.outline).without_pinholes(options.pinhole);
    let pieces = shape.pieces.len();
    if pieces > super::MAX_PIECES || shape.loops.len() > super::MAX_LOOPS {
        return Err(InbetweenError::TooComplex {
            which,
            pieces,
            holes: shape.loops.len() - pieces,
        });
    }
    let loops: Vec<Vec<[f64; 2]>> = shape.loops.iter().map(|l| l.points.clone()).collect();
    let fitted = fit_loops_to_vertices(&loops, (options.vertices / 2).max(3));
    let tolerance = traced.tolerance + fitted.tolerance.unwrap_or(0.0);
    Ok((
        Shape::from_loops(fitted.loops.into_iter().map(Loop::new).collect()),
        tolerance,
        pinholes,
    ))
}

/// Where a point is: on a loop (its index, arc length, distance) or inside the drawing.
enum Place {
    Outline { lp: usize, s: f64, distance: f64 },
    Inside,
    Outside { distance: f64 },
}

fn place(shape: &Shape, p: [f64; 2]) -> Place {
    let (mut best, mut arg) = (f64::INFINITY, (0, 0.0));
    for (i, l) in shape.loops.iter().enumerate() {
        let (s, d) = l.project(p);
        if d < best {
            best = d;
            arg = (i, s);
        }
    }
    let near = ON_OUTLINE_PIXELS.max(ON_OUTLINE_SHARE * shape.scale);
    if best <= near {
        return Place::Outline {
            lp: arg.0,
            s: arg.1,
            distance: best,
        };
    }
    let inside = shape.loops.iter().filter(|l| l.contains(p)).count() % 2 == 1;
    if inside {
        Place::Inside
    } else {
        Place::Outside { distance: best }
    }
}

/// Builds the compatible mesh of drawings `a` and `b` (pictures of one subject, with the same
/// number of pieces; holes may differ) with the user's point pairs `matches`: see [`super`]
/// for how, and for the guarantee that no flipped triangle is left.
///
/// # Errors
/// [`InbetweenError::Meshing`] when a picture has no subject or cannot be meshed,
/// [`InbetweenError::Topology`] when the numbers of pieces differ,
/// [`InbetweenError::Match`] for a pair that cannot be read (one point on an outline and the
/// other inside, points on outlines that are not each other's, pairs in another order),
/// [`InbetweenError::NoBijection`] when even the re-embedding found no flip-free layout (B's
/// outline as laid out crosses itself, or a floating-point limit).
pub fn compatible_mesh(
    a: &Image,
    b: &Image,
    matches: &[Match],
    options: &InbetweenOptions,
) -> Result<CompatibleMesh, InbetweenError> {
    let mut path = compatible_path(&[a, b], matches, options)?;
    let (Some(positions_b), Some(report), Some(texcoords_b)) =
        (path.layouts.pop(), path.reports.pop(), path.texcoords.pop())
    else {
        return Err(InbetweenError::Internal("no layout over drawing B".into()));
    };
    let texcoords_a = path
        .texcoords
        .pop()
        .ok_or_else(|| InbetweenError::Internal("no texture coordinates in A".into()))?;
    Ok(CompatibleMesh {
        mesh: path.mesh,
        positions_b,
        texcoords_a,
        texcoords_b,
        report,
    })
}

/// One mesh laid over several drawings of one subject: the first drawing's mesh and, for
/// every other drawing, the same triangles over it.
#[derive(Clone, Debug)]
pub struct CompatiblePath {
    /// The first drawing's mesh: positions in its picture (pixels, y up), counter-clockwise.
    pub mesh: PlanarMesh,
    /// Per other drawing, in order, one position per vertex in its picture, every triangle
    /// counter-clockwise.
    pub layouts: Vec<Vec<[f64; 2]>>,
    /// Per drawing (the first included), texture coordinates in its picture.
    pub texcoords: Vec<TexCoords>,
    /// Per other drawing, what was done.
    pub reports: Vec<CompatibleReport>,
}

impl CompatiblePath {
    /// Every drawing's layout as a mesh (the first drawing's triangles), the first included.
    pub fn keyframes(&self) -> Vec<PlanarMesh> {
        std::iter::once(self.mesh.clone())
            .chain(self.layouts.iter().map(|p| PlanarMesh {
                positions: p.clone(),
                faces: self.mesh.faces.clone(),
            }))
            .collect()
    }
}

/// What a point pair of the user's is, once read.
pub(super) enum PairKind {
    Outline,
    Interior([f64; 2], [f64; 2]),
    Unmet,
}

/// The user's pairs, read: per loop of A the anchors on it, per pair what it is and its
/// report.
pub(super) struct ReadPairs {
    pub anchors: Vec<Vec<Anchor>>,
    pub kinds: Vec<PairKind>,
    pub reports: Vec<PairReport>,
}

/// Reads the user's pairs between drawings A and B: the anchors they put on A's loops, the
/// interior pairs, and a report for each.
pub(super) fn read_pairs(
    shape_a: &Shape,
    shape_b: &Shape,
    pairs: &[(usize, usize)],
    points: &[([f64; 2], [f64; 2])],
) -> Result<ReadPairs, InbetweenError> {
    let mut reports: Vec<PairReport> = Vec::with_capacity(points.len());
    let mut kinds: Vec<PairKind> = Vec::with_capacity(points.len());
    let mut anchors: Vec<Vec<Anchor>> = vec![Vec::new(); shape_a.loops.len()];
    for (k, &(pa, pb)) in points.iter().enumerate() {
        let mismatch = |reason: String| InbetweenError::Match {
            pair: k + 1,
            reason,
        };
        let unmet = |reason: String, error: f64| PairReport {
            on_outline: false,
            met: false,
            error,
            reason: Some(reason),
        };
        match (place(shape_a, pa), place(shape_b, pb)) {
            (
                Place::Outline { lp: la, s: sa, .. },
                Place::Outline {
                    lp: lb,
                    s: sb,
                    distance,
                },
            ) => {
                if !pairs.contains(&(la, lb)) {
                    let partner = pairs
                        .iter()
                        .find(|p| p.0 == la)
                        .map_or_else(String::new, |p| shape_b.name(p.1));
                    return Err(mismatch(format!(
                        "its point in drawing A is on {} (which goes to {partner} of drawing B) but its point in drawing B is on {}",
                        shape_a.name(la),
                        shape_b.name(lb)
                    )));
                }
                anchors[la].push(Anchor { sa, sb, pair: k });
                kinds.push(PairKind::Outline);
                reports.push(PairReport {
                    on_outline: true,
                    met: true,
                    error: distance,
                    reason: None,
                });
            }
            (Place::Outline { .. }, Place::Inside | Place::Outside { .. }) => {
                return Err(mismatch(
                    "its point in drawing A is on the outline but its point in drawing B is not: give both on the outline, or both inside".into(),
                ))
            }
            (Place::Inside | Place::Outside { .. }, Place::Outline { .. }) => {
                return Err(mismatch(
                    "its point in drawing B is on the outline but its point in drawing A is not: give both on the outline, or both inside".into(),
                ))
            }
            (Place::Outside { distance }, _) => {
                kinds.push(PairKind::Unmet);
                reports.push(unmet(
                    format!("its point in drawing A is outside the drawing ({distance:.1} px from its outline)"),
                    f64::INFINITY,
                ));
            }
            (Place::Inside, Place::Outside { distance }) => {
                kinds.push(PairKind::Unmet);
                reports.push(unmet(
                    format!("its point in drawing B is outside the drawing ({distance:.1} px from its outline): the mesh stays inside B's outline"),
                    distance,
                ));
            }
            (Place::Inside, Place::Inside) => {
                kinds.push(PairKind::Interior(pa, pb));
                reports.push(PairReport {
                    on_outline: false,
                    met: true,
                    error: 0.0,
                    reason: None,
                });
            }
        }
    }
    Ok(ReadPairs {
        anchors,
        kinds,
        reports,
    })
}

/// Vertices held at targets: `(vertex, target)`.
pub(super) type Pins = Vec<(u32, [f64; 2])>;

/// Meshes the common polygons (A's places) with about `vertices` vertices, and returns the
/// mesh and, per other drawing, the place of every boundary vertex over it.
fn mesh_polygons(
    polygons: &[Vec<Corner>],
    internal: &[Vec<[f64; 2]>],
    a: &Image,
    vertices: usize,
    min_angle: f64,
    others: usize,
) -> Result<(PlanarMesh, Vec<Pins>), InbetweenError> {
    let a_loops: Vec<Vec<[f64; 2]>> = polygons
        .iter()
        .map(|p| p.iter().map(|c| c.a).collect())
        .chain(internal.iter().cloned())
        .collect();
    // The transparent regions are meshed as holes first, then filled.
    let mut outline = Outline::from_loops(&a_loops);
    outline.texture_frame = Some([0.0, 0.0, f64::from(a.width), f64::from(a.height)]);
    let meshed = mesh_outline(
        &outline,
        &MeshOptions::default()
            .with_vertices(vertices)
            .with_min_angle(min_angle),
    )
    .map_err(|source| InbetweenError::Meshing {
        which: Drawing(0),
        source,
    })?;
    let mut mesh = meshed.mesh;
    fill_holes(&mut mesh, internal, min_angle).ok_or_else(|| {
        InbetweenError::Internal("a transparent region could not be meshed".into())
    })?;
    split_boundary_chords(&mut mesh);
    let segments: Vec<(&Corner, &Corner)> = polygons
        .iter()
        .flat_map(|p| (0..p.len()).map(move |i| (&p[i], &p[(i + 1) % p.len()])))
        .collect();
    let size = mesh.diameter().max(f64::MIN_POSITIVE);
    let mut targets: Vec<Pins> = vec![Vec::new(); others];
    for v in boundary_vertices(&mesh) {
        let p = mesh.positions[v as usize];
        let (segment, f, distance) = nearest_segment(&segments, p);
        if distance > 1e-6 * size {
            return Err(InbetweenError::Internal(format!(
                "boundary vertex {v} is {distance:e} px from the outline it was meshed on"
            )));
        }
        let (c, d) = segments[segment];
        for (k, out) in targets.iter_mut().enumerate() {
            let (p, q) = (c.images[k], d.images[k]);
            out.push((v, [p[0] + f * (q[0] - p[0]), p[1] + f * (q[1] - p[1])]));
        }
    }
    Ok((mesh, targets))
}

/// Builds one mesh of the first of `drawings` laid over every other one (pictures of one
/// subject, with the same pieces and holes), each as [`compatible_mesh`] lays it over B; the
/// user's pairs `matches` are between the first two drawings.
///
/// # Errors
/// As [`compatible_mesh`], naming the drawing at fault; [`InbetweenError::BadOption`] for
/// fewer than two drawings.
pub fn compatible_path(
    drawings: &[&Image],
    matches: &[Match],
    options: &InbetweenOptions,
) -> Result<CompatiblePath, InbetweenError> {
    let started = Instant::now();
    options.validate()?;
    if drawings.len() < 2 {
        return Err(InbetweenError::BadOption(format!(
            "{} drawing given: in-betweens need two or more",
            drawings.len()
        )));
    }
    let mut shapes = Vec::with_capacity(drawings.len());
    let mut tolerances = Vec::with_capacity(drawings.len());
    let mut pinholes = Vec::with_capacity(drawings.len());
    for (d, image) in drawings.iter().enumerate() {
        options.budget.check()?;
        let (shape, tolerance, filled) = shape_of(image, Drawing(d), options)?;
        shapes.push(shape);
        tolerances.push(tolerance);
        pinholes.push(filled);
    }
    let pairings: Vec<LoopPairing> = (1..drawings.len())
        .map(|d| pair_loops(&shapes[0], &shapes[d], Drawing(d)))
        .collect::<Result<_, _>>()?;
    let input = Input {
        drawings,
        matches,
        options,
        shapes: &shapes,
        tolerances: &tolerances,
        pinholes: &pinholes,
        pairings: &pairings,
        started,
    };
    match build(&input, options.transparent_holes) {
        Err(Failure::EnclosesHole(_))
            if !options.transparent_holes && shapes[0].loops.iter().any(|l| l.area < 0.0) =>
        {
            // A flipped region surrounds a hole: every hole laid out as a transparent region
            // instead (one piece without holes per piece: the guarantee holds for those).
            build(&input, true).map_err(Failure::into_error)
        }
        result => result.map_err(Failure::into_error),
    }
}

/// What [`build`] works from.
struct Input<'a> {
    drawings: &'a [&'a Image],
    matches: &'a [Match],
    options: &'a InbetweenOptions,
    shapes: &'a [Shape],
    tolerances: &'a [f64],
    pinholes: &'a [usize],
    pairings: &'a [LoopPairing],
    started: Instant,
}

/// Why [`build`] failed: an error, or the one the hole-free retry can mend.
enum Failure {
    Error(InbetweenError),
    EnclosesHole(InbetweenError),
}

impl Failure {
    fn into_error(self) -> InbetweenError {
        match self {
            Failure::Error(e) | Failure::EnclosesHole(e) => e,
        }
    }
}

impl From<InbetweenError> for Failure {
    fn from(e: InbetweenError) -> Failure {
        Failure::Error(e)
    }
}

/// How a hole is named in notes: where it is in its picture (pixels from the top-left
/// corner) and its area.
fn hole_name(l: &Loop, which: Drawing, image: &Image) -> String {
    format!(
        "{which}'s hole at ({:.0}, {:.0}) ({:.0} px²)",
        l.centroid[0],
        f64::from(image.height) - l.centroid[1],
        -l.area
    )
}

/// The compatible path with A's holes that some drawing lacks (all of them with
/// `all_transparent`) meshed as transparent regions.
fn build(input: &Input<'_>, all_transparent: bool) -> Result<CompatiblePath, Failure> {
    let Input {
        drawings,
        matches,
        options,
        shapes,
        tolerances,
        pinholes,
        pairings,
        started,
    } = *input;
    let a = drawings[0];
    let others = drawings.len() - 1;
    // Which loops are laid onto each other: A's outer loops and the holes every drawing has.
    let full_a = &shapes[0];
    let partner = |d: usize, la: usize| {
        pairings[d - 1]
            .pairs
            .iter()
            .find(|p| p.0 == la)
            .map(|p| p.1)
    };
    let keep_a: Vec<usize> = (0..full_a.loops.len())
        .filter(|&l| {
            full_a.loops[l].area > 0.0
                || (!all_transparent && (1..drawings.len()).all(|d| partner(d, l).is_some()))
        })
        .collect();
    let transparent: Vec<&Loop> = (0..full_a.loops.len())
        .filter(|l| !keep_a.contains(l))
        .map(|l| &full_a.loops[l])
        .collect();
    let mut notes: Vec<Vec<String>> = vec![Vec::new(); others];
    if pinholes[0] > 0 {
        notes[0].push(format!(
            "{} in drawing A filled (holes under {} px²)",
            plural(pinholes[0], "pinhole"),
            options.pinhole
        ));
    }
    for l in &transparent {
        notes[0].push(format!(
            "{} is meshed as a transparent region{}",
            hole_name(l, Drawing(0), a),
            if all_transparent {
                " (every hole is)"
            } else {
                ", shrinking where a drawing has no hole there"
            }
        ));
    }
    let mut reduced: Vec<Shape> = Vec::with_capacity(drawings.len());
    reduced.push(full_a.subset(&keep_a));
    // Per other drawing, its holes not laid onto A's (the mesh covers them; its picture is
    // transparent there).
    let mut uncovered: Vec<Vec<Loop>> = Vec::with_capacity(others);
    for d in 1..drawings.len() {
        let keep: Vec<usize> = keep_a
            .iter()
            .map(|&la| {
                partner(d, la).ok_or_else(|| {
                    InbetweenError::Internal(format!("loop {la} of A is not paired"))
                })
            })
            .collect::<Result<_, _>>()?;
        let full = &shapes[d];
        let dropped: Vec<Loop> = (0..full.loops.len())
            .filter(|l| !keep.contains(l))
            .map(|l| full.loops[l].clone())
            .collect();
        if pinholes[d] > 0 {
            notes[d - 1].push(format!(
                "{} in {} filled (holes under {} px²)",
                plural(pinholes[d], "pinhole"),
                Drawing(d),
                options.pinhole
            ));
        }
        for l in &dropped {
            notes[d - 1].push(format!(
                "{} is covered by the mesh, transparent in its picture",
                hole_name(l, Drawing(d), drawings[d])
            ));
        }
        reduced.push(full.subset(&keep));
        uncovered.push(dropped);
    }
    let shapes = &reduced;
    let shape_a = &shapes[0];
    let loop_pairs: Vec<Vec<(usize, usize)>> =
        vec![(0..keep_a.len()).map(|i| (i, i)).collect(); others];
    // The user's pairs, between A and B, in the mesh frame (y up).
    let height = |img: &Image| f64::from(img.height);
    let points: Vec<([f64; 2], [f64; 2])> = matches
        .iter()
        .map(|m| {
            (
                [m.a[0], height(a) - m.a[1]],
                [m.b[0], height(drawings[1]) - m.b[1]],
            )
        })
        .collect();
    let ReadPairs {
        anchors,
        kinds,
        mut reports,
    } = read_pairs(shape_a, &shapes[1], &loop_pairs[0], &points)?;
    // The correspondence with every other drawing, and the common polygons of A's loops.
    let main = shape_a.pieces[0];
    let angles: Vec<f64> = (1..drawings.len())
        .map(|d| {
            let partner = loop_pairs[d - 1]
                .iter()
                .find(|p| p.0 == main)
                .map_or(0, |p| p.1);
            rigid_alignment(
                shape_a,
                &shape_a.loops[main],
                &shapes[d],
                &shapes[d].loops[partner],
            )
            .0
        })
        .collect();
    let mut polygons: Vec<Vec<Corner>> = Vec::with_capacity(shape_a.loops.len());
    for (la, loop_a) in shape_a.loops.iter().enumerate() {
        let mut loops_x: Vec<&Loop> = Vec::with_capacity(others);
        let mut maps: Vec<ArcMap> = Vec::with_capacity(others);
        for d in 1..drawings.len() {
            let lb = loop_pairs[d - 1]
                .iter()
                .find(|p| p.0 == la)
                .map(|p| p.1)
                .ok_or_else(|| InbetweenError::Internal(format!("loop {la} of A is not paired")))?;
            let here: &[Anchor] = if d == 1 { &anchors[la] } else { &[] };
            let loop_x = &shapes[d].loops[lb];
            maps.push(arc_map(
                shape_a,
                loop_a,
                &shapes[d],
                loop_x,
                angles[d - 1],
                here,
            )?);
            loops_x.push(loop_x);
        }
        let map_refs: Vec<&ArcMap> = maps.iter().collect();
        polygons.push(common_polygon(loop_a, &loops_x, &map_refs, &anchors[la]));
    }
    let internal: Vec<Vec<[f64; 2]>> = transparent.iter().map(|l| l.points.clone()).collect();
    let (mut mesh, boundary_targets) = mesh_polygons(
        &polygons,
        &internal,
        a,
        options.vertices,
        options.min_angle,
        others,
    )?;
    // Interior pairs pin the vertex nearest A's point, moved onto it (over B only).
    let mut is_boundary = vec![false; mesh.positions.len()];
    for &(v, _) in &boundary_targets[0] {
        is_boundary[v as usize] = true;
    }
    let mut interior_pins: Vec<(usize, u32, [f64; 2])> = Vec::new();
    for (k, kind) in kinds.iter().enumerate() {
        let PairKind::Interior(pa, pb) = *kind else {
            continue;
        };
        let taken: Vec<u32> = interior_pins.iter().map(|p| p.1).collect();
        match nearest_free_vertex(&mesh, &is_boundary, &taken, pa) {
            Some(v) if moves_cleanly(&mesh, v, pa) => {
                mesh.positions[v as usize] = pa;
                interior_pins.push((k, v, pb));
            }
            _ => {
                reports[k].met = false;
                reports[k].error = f64::INFINITY;
                reports[k].reason = Some(
                    "no vertex of A's mesh could be placed on its point in drawing A (it is too close to the outline or another pair's point)".into(),
                );
            }
        }
    }
    // A coarse mesh of the same polygons gives a fine one its first layout.
    let coarse = if mesh.positions.len() > COARSE_VERTICES * 3 / 2 {
        Some(mesh_polygons(
            &polygons,
            &internal,
            a,
            COARSE_VERTICES,
            options.min_angle,
            others,
        )?)
    } else {
        None
    };
    let mut layouts = Vec::with_capacity(others);
    let mut path_reports = Vec::with_capacity(others);
    let budget = &options.budget;
    for k in 0..others {
        budget.check().map_err(InbetweenError::from)?;
        let mut pins: Vec<(u32, [f64; 2])> = boundary_targets[k].clone();
        if k == 0 {
            pins.extend(interior_pins.iter().map(|&(_, v, pb)| (v, pb)));
        }
        let start = match &coarse {
            Some((coarse_mesh, coarse_targets)) => {
                let coarse_layout = lay_over(
                    coarse_mesh,
                    &coarse_targets[k],
                    None,
                    None,
                    BUILD_STAGES,
                    budget,
                )?;
                if coarse_layout.flipped == 0 {
                    let mut positions = coarse_layout.positions;
                    polish(coarse_mesh, &coarse_targets[k], &mut positions, budget)?;
                    Some(transfer(coarse_mesh, &positions, &mesh.positions))
                } else {
                    None
                }
            }
            None => None,
        };
        let weights = transparent_weights(&mesh, &internal);
        let (mut layout, mut pins) = if k == 0 {
            lay_out_with_pairs(
                &mesh,
                pins,
                &interior_pins,
                &mut reports,
                start,
                weights.as_deref(),
                BUILD_STAGES,
                budget,
            )?
        } else {
            (
                lay_over(
                    &mesh,
                    &pins,
                    start,
                    weights.as_deref(),
                    BUILD_STAGES,
                    budget,
                )?,
                pins,
            )
        };
        let flipped_before_untangling = layout.flipped_before;
        let mut added_vertices = 0;
        if layout.flipped > 0 {
            budget.check().map_err(InbetweenError::from)?;
            // The guarantee: re-embed what is left, refining A's mesh there.
            let embedded = guarantee(
                &mesh,
                &pins,
                &layout.positions,
                weights.as_deref(),
                &mut layouts,
            )
            .map_err(|failure| {
                let error = InbetweenError::NoBijection {
                    which: Drawing(k + 1),
                    flipped: layout.flipped,
                    faces: mesh.faces.len(),
                    reason: failure.to_string(),
                };
                if failure == EmbedFailure::EnclosesHole {
                    Failure::EnclosesHole(error)
                } else {
                    Failure::Error(error)
                }
            })?;
            added_vertices = embedded.mesh.positions.len() - mesh.positions.len();
            for &v in &embedded.released {
                if let Some(&(pair, _, _)) = interior_pins.iter().find(|p| p.1 == v) {
                    reports[pair].met = false;
                    reports[pair].reason = Some(
                        "the mesh around it had to be laid out again to leave no triangle flipped over drawing B; the other pairs are met".into(),
                    );
                }
            }
            interior_pins.retain(|p| !embedded.released.contains(&p.1));
            pins.retain(|p| !embedded.released.contains(&p.0));
            mesh = embedded.mesh;
            let floor = REFINED_AREA_SHARE * squared_size(&embedded.layout);
            let floor_a = REFINED_AREA_SHARE * squared_size(&mesh.positions);
            layout.flipped = mesh
                .faces
                .iter()
                .filter(|f| {
                    !(signed_area(&embedded.layout, f) > floor
                        && signed_area(&mesh.positions, f) > floor_a)
                })
                .count();
            layout.positions = embedded.layout;
            if layout.flipped > 0 {
                return Err(InbetweenError::Internal(format!(
                    "{} triangles left flipped by the re-embedding",
                    layout.flipped
                ))
                .into());
            }
        }
        let mut positions = layout.positions;
        // Transparent regions, and the parts covering this drawing's holes that A lacks,
        // are let shrink; otherwise the largest distortion is lowered.
        let shrink = shrink_weights(&mesh, &internal, &positions, &uncovered[k]);
        let mut fixed = vec![false; mesh.positions.len()];
        for &(v, _) in &pins {
            fixed[v as usize] = true;
        }
        let polish_rounds = match &shrink {
            Some(w) => {
                smooth(&mesh, &fixed, Some(w), &mut positions, SHRINK_STEPS);
                0
            }
            None => polish(&mesh, &pins, &mut positions, budget)?,
        };
        let mut pair_reports = Vec::new();
        if k == 0 {
            for &(pair, v, pb) in &interior_pins {
                if reports[pair].met {
                    let p = positions[v as usize];
                    reports[pair].error = (p[0] - pb[0]).hypot(p[1] - pb[1]);
                }
            }
            pair_reports = reports.clone();
        }
        path_reports.push(CompatibleReport {
            vertices: mesh.positions.len(),
            faces: mesh.faces.len(),
            flipped: 0,
            tolerance: [tolerances[0], tolerances[k + 1]],
            outline_error: outline_error(&shapes[k + 1], &mesh.faces, &positions),
            pairs: pair_reports,
            max_distortion: max_distortion(&mesh, &positions),
            flipped_before_untangling,
            added_vertices,
            polish_rounds,
            notes: std::mem::take(&mut notes[k]),
            seconds: started.elapsed().as_secs_f64(),
        });
        layouts.push(positions);
    }
    let mut texcoords = Vec::with_capacity(drawings.len());
    texcoords.push(texcoords_of(&mesh, a));
    for (k, positions) in layouts.iter().enumerate() {
        let image = drawings[k + 1];
        texcoords.push(TexCoords {
            uv: positions
                .iter()
                .map(|p| [p[0] / f64::from(image.width), p[1] / height(image)])
                .collect(),
            corners: mesh.faces.clone(),
        });
    }
    Ok(CompatiblePath {
        mesh,
        layouts,
        texcoords,
        reports: path_reports,
    })
}

/// A mesh of about this many vertices lays out a finer one first.
const COARSE_VERTICES: usize = 2000;
/// The weight of a triangle of a transparent region (or covering a hole of the drawing it
/// is laid over that A lacks) in the smoothing that lets those regions shrink, against 1
/// for the others.
const TRANSPARENT_WEIGHT: f64 = 0.05;
/// L-BFGS steps of that smoothing.
const SHRINK_STEPS: usize = 600;

fn plural(n: usize, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
}

/// Per triangle of `mesh`, whether it is inside one of the transparent regions' loops
/// `internal` (in A).
fn in_transparent(mesh: &PlanarMesh, internal: &[Vec<[f64; 2]>]) -> Vec<bool> {
    let loops: Vec<Loop> = internal.iter().map(|l| Loop::new(l.clone())).collect();
    mesh.faces
        .iter()
        .map(|f| {
            let [p, q, r] = f.map(|v| mesh.positions[v as usize]);
            let c = [(p[0] + q[0] + r[0]) / 3.0, (p[1] + q[1] + r[1]) / 3.0];
            loops.iter().any(|l| l.contains(c))
        })
        .collect()
}

/// The triangle weights of the layout: [`TRANSPARENT_WEIGHT`] in the transparent regions;
/// `None` without any.
fn transparent_weights(mesh: &PlanarMesh, internal: &[Vec<[f64; 2]>]) -> Option<Vec<f64>> {
    if internal.is_empty() {
        return None;
    }
    Some(
        in_transparent(mesh, internal)
            .into_iter()
            .map(|t| if t { TRANSPARENT_WEIGHT } else { 1.0 })
            .collect(),
    )
}

/// The weights of the smoothing that lets transparent regions shrink: the transparent
/// regions' triangles, and those whose centre over the drawing is in one of its holes that A
/// lacks (`uncovered`), at [`TRANSPARENT_WEIGHT`]; `None` when there are none.
fn shrink_weights(
    mesh: &PlanarMesh,
    internal: &[Vec<[f64; 2]>],
    layout: &[[f64; 2]],
    uncovered: &[Loop],
) -> Option<Vec<f64>> {
    if internal.is_empty() && uncovered.is_empty() {
        return None;
    }
    let inside_a = in_transparent(mesh, internal);
    Some(
        mesh.faces
            .iter()
            .zip(inside_a)
            .map(|(f, t)| {
                let [p, q, r] = f.map(|v| layout[v as usize]);
                let c = [(p[0] + q[0] + r[0]) / 3.0, (p[1] + q[1] + r[1]) / 3.0];
                if t || uncovered.iter().any(|l| l.contains(c)) {
                    TRANSPARENT_WEIGHT
                } else {
                    1.0
                }
            })
            .collect(),
    )
}

/// The place of every point of `points` (inside `coarse`'s region) under the layout
/// `positions` of `coarse`: through the coarse triangle holding it (or nearest).
fn transfer(coarse: &PlanarMesh, positions: &[[f64; 2]], points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let (lo, hi) = coarse.bounds();
    let cells = ((coarse.faces.len() as f64).sqrt().ceil() as usize).max(1);
    let (w, h) = ((hi[0] - lo[0]).max(1e-12), (hi[1] - lo[1]).max(1e-12));
    let cell_of = |p: [f64; 2]| {
        let i =
            (((p[0] - lo[0]) / w * cells as f64) as isize).clamp(0, cells as isize - 1) as usize;
        let j =
            (((p[1] - lo[1]) / h * cells as f64) as isize).clamp(0, cells as isize - 1) as usize;
        (i, j)
    };
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); cells * cells];
    for (f, t) in coarse.faces.iter().enumerate() {
        let ps = t.map(|v| coarse.positions[v as usize]);
        let (i0, j0) = cell_of([
            ps.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min),
            ps.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min),
        ]);
        let (i1, j1) = cell_of([
            ps.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max),
            ps.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max),
        ]);
        for j in j0..=j1 {
            for i in i0..=i1 {
                grid[j * cells + i].push(f as u32);
            }
        }
    }
    let barycentric = |f: usize, p: [f64; 2]| {
        let t = coarse.faces[f];
        let (a, b, c) = (
            coarse.positions[t[0] as usize],
            coarse.positions[t[1] as usize],
            coarse.positions[t[2] as usize],
        );
        let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        let l1 = ((p[0] - a[0]) * (c[1] - a[1]) - (p[1] - a[1]) * (c[0] - a[0])) / det;
        let l2 = ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / det;
        [1.0 - l1 - l2, l1, l2]
    };
    points
        .iter()
        .map(|&p| {
            let (i, j) = cell_of(p);
            let inside = |f: usize| {
                let l = barycentric(f, p);
                l[0].min(l[1]).min(l[2])
            };
            let best = grid[j * cells + i]
                .iter()
                .map(|&f| (inside(f as usize), f as usize))
                .max_by(|x, y| x.0.total_cmp(&y.0));
            let f = match best {
                Some((score, f)) if score > -1e-9 => f,
                _ => (0..coarse.faces.len())
                    .map(|f| (inside(f), f))
                    .max_by(|x, y| x.0.total_cmp(&y.0))
                    .map_or(0, |(_, f)| f),
            };
            let l = barycentric(f, p);
            let t = coarse.faces[f];
            let mut q = [0.0; 2];
            for k in 0..3 {
                let r = positions[t[k] as usize];
                q[0] += l[k] * r[0];
                q[1] += l[k] * r[1];
            }
            q
        })
        .collect()
}

/// A's texture coordinates: positions over the picture's size.
fn texcoords_of(mesh: &PlanarMesh, a: &Image) -> TexCoords {
    TexCoords {
        uv: mesh
            .positions
            .iter()
            .map(|p| [p[0] / f64::from(a.width), p[1] / f64::from(a.height)])
            .collect(),
        corners: mesh.faces.clone(),
    }
}

/// The mesh's boundary edges (edges of one triangle), directed as in their triangle: the
/// outer loops run counter-clockwise, holes clockwise.
pub(super) fn boundary_edges(faces: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut edges: std::collections::HashMap<(u32, u32), (u32, (u32, u32))> =
        std::collections::HashMap::new();
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            edges.entry((a.min(b), a.max(b))).or_insert((0, (a, b))).0 += 1;
        }
    }
    let mut out: Vec<(u32, u32)> = edges
        .into_values()
        .filter(|&(count, _)| count == 1)
        .map(|(_, e)| e)
        .collect();
    out.sort_unstable();
    out
}

/// The vertices on the mesh's boundary (on an edge of one triangle), ascending.
pub(super) fn boundary_vertices(mesh: &PlanarMesh) -> Vec<u32> {
    let mut on = vec![false; mesh.positions.len()];
    for (a, b) in boundary_edges(&mesh.faces) {
        on[a as usize] = true;
        on[b as usize] = true;
    }
    (0..mesh.positions.len() as u32)
        .filter(|&v| on[v as usize])
        .collect()
}

/// The segment of the common polygons (A's places) nearest `p`: its index, the fraction
/// along it, and the distance.
fn nearest_segment(segments: &[(&Corner, &Corner)], p: [f64; 2]) -> (usize, f64, f64) {
    let mut best = (0, 0.0, f64::INFINITY);
    for (i, (c, d)) in segments.iter().enumerate() {
        let (f, dist) = closest_on_segment(p, c.a, d.a);
        if dist < best.2 {
            best = (i, f, dist);
        }
    }
    best
}

/// The interior vertex nearest `p` that is not pinned yet.
pub(super) fn nearest_free_vertex(
    mesh: &PlanarMesh,
    boundary: &[bool],
    pins: &[u32],
    p: [f64; 2],
) -> Option<u32> {
    (0..mesh.positions.len())
        .filter(|&v| !boundary[v] && !pins.contains(&(v as u32)))
        .map(|v| {
            let q = mesh.positions[v];
            ((q[0] - p[0]).hypot(q[1] - p[1]), v as u32)
        })
        .min_by(|x, y| x.0.total_cmp(&y.0))
        .map(|(_, v)| v)
}

/// Whether moving vertex `v` to `p` leaves every triangle around it counter-clockwise, none
/// thinner than a tenth of what it was.
fn moves_cleanly(mesh: &PlanarMesh, v: u32, p: [f64; 2]) -> bool {
    let mut moved = mesh.positions.clone();
    moved[v as usize] = p;
    mesh.faces.iter().filter(|f| f.contains(&v)).all(|f| {
        let before = signed_area(&mesh.positions, f);
        signed_area(&moved, f) > 0.1 * before
    })
}

/// The largest distance of a corner of B's outline from the boundary of the layout over B.
pub(super) fn outline_error(shape_b: &Shape, faces: &[[u32; 3]], positions: &[[f64; 2]]) -> f64 {
    let boundary: Vec<([f64; 2], [f64; 2])> = boundary_edges(faces)
        .into_iter()
        .map(|(a, b)| (positions[a as usize], positions[b as usize]))
        .collect();
    let mut worst = 0.0f64;
    for l in &shape_b.loops {
        for &p in &l.points {
            let d = boundary
                .iter()
                .map(|&(a, b)| closest_on_segment(p, a, b).1)
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(d);
        }
    }
    worst
}
