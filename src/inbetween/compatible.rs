//! A compatible mesh of two drawings: drawing A's mesh laid over drawing B without a flipped
//! triangle.

use std::time::Instant;

use super::correspondence::ArcMap;
use super::correspondence::{arc_map, common_polygon, rigid_alignment, Anchor, Corner};
use super::outline::{closest_on_segment, pair_loops, Loop, Shape};
use super::{Drawing, InbetweenError, InbetweenOptions, Match};
use crate::deform::{untangle, Deformer, PoseMethod, UntangleOptions};
use crate::io::{SurfaceMesh, TexCoords};
use crate::mesh::PlanarMesh;
use crate::meshing::{fit_loops_to_vertices, mesh_outline, picture_outline, MeshOptions, Outline};
use crate::param::bounded::{BoundedDistortion, BoundedOptions};
use crate::render::Image;

/// How far from an outline (in pixels, or this share of the subject's size when larger) a
/// matched point counts as a point of the outline: 3 pixels, 2%.
const ON_OUTLINE_PIXELS: f64 = 3.0;
const ON_OUTLINE_SHARE: f64 = 0.02;
/// Rounds of ARAP iterations (10 each) for the first layout over B.
const ARAP_ROUNDS: usize = 40;

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
    /// Rounds of the bounded-distortion mapping that lowered the largest distortion.
    pub polish_rounds: usize,
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

/// A drawing's outline, simplified to fit about half the vertices of the mesh.
pub(super) fn shape_of(
    image: &Image,
    which: Drawing,
    options: &InbetweenOptions,
) -> Result<(Shape, f64), InbetweenError> {
    let traced = picture_outline(image, &options.picture, None)
        .map_err(|source| InbetweenError::Meshing { which, source })?;
    let shape = Shape::of(&traced.outline);
    let loops: Vec<Vec<[f64; 2]>> = shape.loops.iter().map(|l| l.points.clone()).collect();
    let fitted = fit_loops_to_vertices(&loops, (options.vertices / 2).max(3));
    let tolerance = traced.tolerance + fitted.tolerance.unwrap_or(0.0);
    Ok((
        Shape::from_loops(fitted.loops.into_iter().map(Loop::new).collect()),
        tolerance,
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
/// pieces and holes) with the user's point pairs `matches`: see [`super`] for how.
///
/// # Errors
/// [`InbetweenError::Meshing`] when a picture has no subject or cannot be meshed,
/// [`InbetweenError::Topology`] naming what differs, [`InbetweenError::Match`] for a pair
/// that cannot be read (one point on an outline and the other inside, points on outlines
/// that are not each other's, pairs in another order), [`InbetweenError::Flipped`] when no
/// flip-free layout over B was found.
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
    a: &Image,
    vertices: usize,
    min_angle: f64,
    others: usize,
) -> Result<(PlanarMesh, Vec<Pins>), InbetweenError> {
    let a_loops: Vec<Vec<[f64; 2]>> = polygons
        .iter()
        .map(|p| p.iter().map(|c| c.a).collect())
        .collect();
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
    let mesh = meshed.mesh;
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
    let a = drawings[0];
    let others = drawings.len() - 1;
    let mut shapes = Vec::with_capacity(drawings.len());
    let mut tolerances = Vec::with_capacity(drawings.len());
    for (d, image) in drawings.iter().enumerate() {
        let (shape, tolerance) = shape_of(image, Drawing(d), options)?;
        shapes.push(shape);
        tolerances.push(tolerance);
    }
    let shape_a = &shapes[0];
    let loop_pairs: Vec<Vec<(usize, usize)>> = (1..drawings.len())
        .map(|d| pair_loops(shape_a, &shapes[d], Drawing(d)))
        .collect::<Result<_, _>>()?;
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
    let (mut mesh, boundary_targets) =
        mesh_polygons(&polygons, a, options.vertices, options.min_angle, others)?;
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
    for k in 0..others {
        let mut pins: Vec<(u32, [f64; 2])> = boundary_targets[k].clone();
        if k == 0 {
            pins.extend(interior_pins.iter().map(|&(_, v, pb)| (v, pb)));
        }
        let start = match &coarse {
            Some((coarse_mesh, coarse_targets)) => {
                let coarse_layout = lay_over(coarse_mesh, &coarse_targets[k], None)?;
                if coarse_layout.flipped == 0 {
                    let mut positions = coarse_layout.positions;
                    polish(coarse_mesh, &coarse_targets[k], &mut positions)?;
                    Some(transfer(coarse_mesh, &positions, &mesh.positions))
                } else {
                    None
                }
            }
            None => None,
        };
        let (layout, pins) = if k == 0 {
            lay_out_with_pairs(&mesh, pins, &interior_pins, &mut reports, start)?
        } else {
            (lay_over(&mesh, &pins, start)?, pins)
        };
        let flipped_before_untangling = layout.flipped_before;
        if layout.flipped > 0 {
            return Err(InbetweenError::Flipped {
                which: Drawing(k + 1),
                flipped: layout.flipped,
                faces: mesh.faces.len(),
            });
        }
        let mut positions = layout.positions;
        let polish_rounds = polish(&mesh, &pins, &mut positions)?;
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
            polish_rounds,
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
) -> Result<usize, InbetweenError> {
    let surface = SurfaceMesh::from(mesh);
    let mut kept = 0;
    for _ in 0..POLISH_ROUNDS {
        let current = max_distortion(mesh, positions);
        let k = (POLISH_SHARE * current).max(1.5);
        if k >= current {
            break;
        }
        let options = BoundedOptions::new(k).with_iterations(POLISH_ITERATIONS);
        let mut solver = BoundedDistortion::new(&surface, pins, options).map_err(|e| {
            InbetweenError::Internal(format!("the bounded-distortion mapping: {e}"))
        })?;
        let mut trial = positions.to_vec();
        let report = solver.solve_with(&mut trial, |_, _| {}).map_err(|e| {
            InbetweenError::Internal(format!("the bounded-distortion mapping: {e}"))
        })?;
        let better = report.inverted == 0
            && flipped(&mesh.faces, &trial) == 0
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

/// Interior pins of the user's pairs: `(pair, vertex, target)`.
pub(super) type InteriorPins = [(usize, u32, [f64; 2])];

/// [`lay_over`] with `pins` (the boundary's and the interior pairs' `interior`); when
/// triangles stay flipped, the interior pairs next to them are let go (and their reports say
/// so) if that leaves fewer flips. Returns the layout and the pins it holds.
pub(super) fn lay_out_with_pairs(
    mesh: &PlanarMesh,
    pins: Pins,
    interior: &InteriorPins,
    reports: &mut [PairReport],
    start: Option<Vec<[f64; 2]>>,
) -> Result<(Layout, Pins), InbetweenError> {
    let mut pins = pins;
    let mut layout = lay_over(mesh, &pins, start)?;
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
            let retry = lay_over(mesh, &kept, Some(layout.positions.clone()))?;
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
    pub flipped: usize,
    /// Triangles flipped before the untangling.
    pub flipped_before: usize,
}

/// A layout with every pin at its target: from `start` when given, otherwise by ARAP from
/// A's layout; then [`untangle`] with the same pins, and when flips remain the
/// bounded-distortion mapping over the whole mesh.
pub(super) fn lay_over(
    mesh: &PlanarMesh,
    pins: &[(u32, [f64; 2])],
    start: Option<Vec<[f64; 2]>>,
) -> Result<Layout, InbetweenError> {
    let (vertices, targets): (Vec<u32>, Vec<[f64; 2]>) = pins.iter().copied().unzip();
    let pose = match start {
        Some(mut pose) => {
            for &(v, t) in pins {
                pose[v as usize] = t;
            }
            pose
        }
        None => {
            let mut deformer = Deformer::new(mesh, PoseMethod::arap())?;
            deformer.set_pins(&vertices)?;
            let size = mesh.diameter().max(f64::MIN_POSITIVE);
            let mut previous = deformer.positions().to_vec();
            for _ in 0..ARAP_ROUNDS {
                deformer.drag(&targets)?;
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
    let flipped_before = flipped(&mesh.faces, &pose);
    let repaired = untangle(mesh, &pose, &vertices, &UntangleOptions::default())?;
    let mut layout = Layout {
        flipped: flipped(&mesh.faces, &repaired.positions),
        positions: repaired.positions,
        flipped_before,
    };
    if layout.flipped > 0 {
        // The untangling works near the flips; the bounded-distortion mapping over the whole
        // mesh, flipped triangles projected well inside the bound, may mend what it left.
        let bound = (2.0 * max_distortion_unflipped(mesh, &layout.positions)).max(10.0);
        let options = BoundedOptions::new(bound)
            .with_inverted_bound(2.0)
            .with_iterations(RESCUE_ITERATIONS);
        let mut solver =
            BoundedDistortion::new(&SurfaceMesh::from(mesh), pins, options).map_err(|e| {
                InbetweenError::Internal(format!("the bounded-distortion mapping: {e}"))
            })?;
        let mut trial = layout.positions.clone();
        solver.solve_with(&mut trial, |_, _| {}).map_err(|e| {
            InbetweenError::Internal(format!("the bounded-distortion mapping: {e}"))
        })?;
        let left = flipped(&mesh.faces, &trial);
        if left < layout.flipped && trial.iter().all(|p| p[0].is_finite() && p[1].is_finite()) {
            layout.positions = trial;
            layout.flipped = left;
        }
    }
    Ok(layout)
}

fn signed_area(p: &[[f64; 2]], f: &[u32; 3]) -> f64 {
    let (a, b, c) = (p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]);
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
}

/// Triangles whose signed area is not positive.
pub(crate) fn flipped(faces: &[[u32; 3]], positions: &[[f64; 2]]) -> usize {
    faces
        .iter()
        .filter(|f| signed_area(positions, f) <= 0.0)
        .count()
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
