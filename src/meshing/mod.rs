//! Meshing: from a picture or an outline to a planar triangle mesh ready to morph.
//!
//! A picture's subject (its opaque pixels, or what differs from a background colour, see
//! [`PictureOptions`]) is outlined by marching squares, the outlines are simplified to a
//! tolerance in pixels without crossing or jumping over each other, and the polygons, with
//! their holes and however many pieces, are triangulated by a constrained Delaunay
//! triangulation refined to a minimum angle and to about the requested number of vertices.
//! Outlines can also come from Triangle's `.poly` files ([`parse_poly`]) and SVG files
//! ([`parse_svg`]).
//!
//! A picture's specks (pieces under [`SPECK_AREA_FRACTION`], 1%, of the largest piece's
//! area: dust) are left out unless [`PictureOptions::keep_specks`]; outlines are the user's
//! own geometry and are kept whole. Without an explicit tolerance, a picture's outline is
//! simplified until it takes at most [`OUTLINE_VERTEX_SHARE`] of the requested vertices, so
//! that the mesh lands within 10% of the count; [`MeshStats::off_target`] says why when it
//! does not. [`fit_loops_to_vertices`] does the same for loops drawn by hand.
//!
//! The mesh is in a y-up frame with counter-clockwise triangles. From a picture, positions
//! are in pixels (`x` from the left edge, `y` from the bottom edge), so the aspect ratio is
//! kept, and every vertex has texture coordinates `u = x / width`, `v = y / height` (OBJ's
//! convention, `(0, 0)` the picture's bottom-left corner): the picture textures the mesh,
//! upright. From an outline, texture coordinates span the SVG's `viewBox` (when every point is
//! inside it) or the outline's bounding box as a square (keeping the aspect ratio).
//!
//! ```
//! use bdmorph::meshing::{mesh_picture, MeshOptions, PictureOptions};
//! use bdmorph::render::Image;
//!
//! // A 200 x 120 picture: an opaque ring on a transparent background.
//! let (w, h) = (200u32, 120u32);
//! let mut rgba = Vec::new();
//! for y in 0..h {
//!     for x in 0..w {
//!         let r = (x as f64 + 0.5 - 100.0).hypot(y as f64 + 0.5 - 60.0);
//!         let alpha = if (20.0..50.0).contains(&r) { 255 } else { 0 };
//!         rgba.extend([200, 120, 40, alpha]);
//!     }
//! }
//! let picture = Image { width: w, height: h, rgba };
//! let meshed = mesh_picture(&picture, &PictureOptions::default(), &MeshOptions::default().with_vertices(500))?;
//! assert_eq!((meshed.stats.pieces, meshed.stats.holes), (1, 1));
//! assert!(meshed.stats.min_angle >= 25.0);
//! assert!(meshed.stats.vertices.abs_diff(500) < 50);
//! assert!(meshed.mesh.faces.iter().all(|f| meshed.mesh.signed_area(f) > 0.0));
//! assert!(meshed.texcoords.uv.iter().flatten().all(|t| (0.0..=1.0).contains(t)));
//! # Ok::<(), bdmorph::meshing::MeshingError>(())
//! ```

mod error;
mod fit;
mod outline;
mod picture;
mod poly;
mod simplify;
mod svg;
mod trace;
mod triangulate;

use std::path::Path;
use std::time::Instant;

pub use error::{Contact, MeshingError, NoSubject, Place};
pub use fit::{fit_loops_to_vertices, FittedLoops, OUTLINE_VERTEX_SHARE};
pub use outline::{Element, Inside, Outline};
pub use picture::{Background, PictureOptions};
pub use poly::parse_poly;
pub use svg::parse_svg;

use crate::info::MeshInfo;
use crate::io::{SurfaceMesh, TexCoords};
use crate::mesh::PlanarMesh;
use crate::render::raster::read_image;
use crate::render::Image;

/// The default number of vertices.
pub const DEFAULT_VERTICES: usize = 2000;
/// The default minimum angle, in degrees.
pub const DEFAULT_MIN_ANGLE: f64 = 28.0;
/// The default tolerance for pictures, in pixels.
pub const DEFAULT_PICTURE_TOLERANCE: f64 = 1.0;
/// The default tolerance for outlines, relative to the diagonal of their bounding box.
pub const DEFAULT_OUTLINE_TOLERANCE: f64 = 1e-3;
/// The largest minimum angle accepted, in degrees: beyond about 30 degrees Delaunay
/// refinement need not stop.
pub const MAX_MIN_ANGLE: f64 = 33.0;
/// The most vertices accepted.
pub const MAX_VERTICES: usize = 20_000_000;
/// The largest magnitude of a coordinate meshing accepts (SVG numbers, radii and points after
/// their transforms, `.poly` vertices, outlines): 1e9. Checked before any curve is flattened,
/// so that a huge radius or transform is refused at once rather than flattened into
/// unbounded memory; squared, it stays far from overflow and from the triangulator's limits.
pub const MAX_COORDINATE: f64 = 1e9;
/// The smallest magnitude of a non-zero coordinate meshing accepts: 1e-30 (the triangulator
/// refuses numbers below about 1e-43).
pub const MIN_COORDINATE: f64 = 1e-30;
/// The most points an outline may have: 4,000,000 (curves flattened to the tolerance, or a
/// `.poly` file's vertices). An SVG's curves are estimated before they are flattened, and the
/// flattening stops at the limit.
pub const MAX_OUTLINE_POINTS: usize = 4_000_000;

/// The most work a traced picture may ask of simplification: its loops times the points of
/// its longest loop, 50 million (a drawing's outline of 50,000 points with 1,000 specks and
/// holes; a 300 x 300 picture of random transparency traces to about 3,900 loops, the longest
/// of 28,600 points, 110 million). Beyond it the picture is refused right after tracing
/// ([`MeshingError::TooComplex`]): simplifying tests each loop's points against the loops
/// around it.
pub const MAX_TRACE_WORK: u64 = 50_000_000;

/// The most outline vertices meshed: 100,000. The refinement to a minimum angle around many
/// short boundary segments grows faster than their count (about 3 s for 100,000 on one core,
/// 17 s for 300,000), so longer outlines are refused before triangulating, with the count.
pub const MAX_MESHED_OUTLINE_POINTS: usize = 100_000;

/// Whether `x` is within the coordinate range ([`MIN_COORDINATE`], [`MAX_COORDINATE`]).
pub(crate) fn in_range(x: f64) -> bool {
    x == 0.0 || (MIN_COORDINATE..=MAX_COORDINATE).contains(&x.abs())
}

/// How far from the requested count a mesh's vertices may be before [`MeshStats::off_target`]
/// says why: 10%.
pub const VERTEX_COUNT_SLACK: f64 = 0.1;
/// A picture's pieces whose area is below this fraction of the largest piece's are specks,
/// left out unless [`PictureOptions::keep_specks`]: 1%.
///
/// A piece is an outer loop of the subject's outline with what it holds, and its area is what
/// the outer loop encloses. Dust on a picture is a few pixels: on a 512-pixel picture whose
/// subject covers a quarter of it (65,000 square pixels), 1% is 650 square pixels, a blob 25
/// pixels across, and a speck of 3 by 3 pixels is 0.014%. A part meant to be apart (a hat
/// above a head, a floating hand, a ball) is far larger: a hand is some 2-4% of a figure, a
/// head 5-10%. Between the two there is a wide margin, and the command line says when it
/// dropped something.
pub const SPECK_AREA_FRACTION: f64 = 0.01;

/// How to mesh: density, tolerance, quality.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct MeshOptions {
    /// About how many vertices the mesh should have (default 2000; within 10% unless
    /// [`MeshStats::off_target`] says why not). The outline's own vertices count: a picture's
    /// outline without an explicit `tolerance` is simplified further until it uses at most
    /// [`OUTLINE_VERTEX_SHARE`] of them. More when the outline alone (or the minimum angle)
    /// needs more.
    pub vertices: usize,
    /// How far (at most) the mesh's boundary may be from the traced outline (pictures, in
    /// pixels, default 1, raised to fit `vertices`: see [`mesh_picture`]) or curves from
    /// their polylines (SVG, in the file's units after transforms, default 1/1000 of the
    /// outline's bounding-box diagonal). `.poly` vertices are used as they are.
    pub tolerance: Option<f64>,
    /// The smallest angle of any triangle, in degrees (default 28), except where the
    /// outline's own corners are sharper.
    pub min_angle: f64,
}

impl Default for MeshOptions {
    fn default() -> Self {
        MeshOptions {
            vertices: DEFAULT_VERTICES,
            tolerance: None,
            min_angle: DEFAULT_MIN_ANGLE,
        }
    }
}

impl MeshOptions {
    /// About `n` vertices.
    pub fn with_vertices(mut self, n: usize) -> Self {
        self.vertices = n;
        self
    }

    /// The tolerance (see [`MeshOptions::tolerance`]).
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = Some(tolerance);
        self
    }

    /// The minimum angle, in degrees.
    pub fn with_min_angle(mut self, degrees: f64) -> Self {
        self.min_angle = degrees;
        self
    }

    fn validate(&self) -> Result<(), MeshingError> {
        if !(3..=MAX_VERTICES).contains(&self.vertices) {
            return Err(MeshingError::BadOption {
                option: "--vertices",
                value: self.vertices.to_string(),
                expected: "from 3 to 20000000",
            });
        }
        if let Some(t) = self.tolerance {
            if !(t > 0.0 && t.is_finite()) {
                return Err(MeshingError::BadOption {
                    option: "--tolerance",
                    value: t.to_string(),
                    expected: "a positive number",
                });
            }
        }
        if !(0.0..=MAX_MIN_ANGLE).contains(&self.min_angle) {
            return Err(MeshingError::BadOption {
                option: "--min-angle",
                value: self.min_angle.to_string(),
                expected: "degrees from 0 to 33 (refinement need not stop beyond about 30)",
            });
        }
        Ok(())
    }
}

/// Why a mesh's vertex count is more than [`VERTEX_COUNT_SLACK`] (10%) from the count asked
/// for ([`MeshStats::off_target`]). Displayed as one sentence naming the command line's
/// options.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum OffTarget {
    /// A picture's outline, simplified to the tolerance given (pixels), has
    /// `outline_vertices` vertices alone: more than the refinement can take and land near the
    /// count (at most [`OUTLINE_VERTEX_SHARE`] of it). Without a tolerance it would be raised.
    Tolerance {
        /// The tolerance given.
        tolerance: f64,
        /// The outline's vertices.
        outline_vertices: usize,
    },
    /// A picture's outline has `loops` loops (pieces and holes) that need `outline_vertices`
    /// vertices even at `tolerance`, the coarsest tolerance that keeps every one of them
    /// (a coarser one would drop the smaller ones).
    Loops {
        /// Loops of the outline.
        loops: usize,
        /// The outline's vertices at `tolerance`.
        outline_vertices: usize,
        /// The coarsest tolerance that keeps every loop, in pixels.
        tolerance: f64,
    },
    /// A picture's outline has `outline_vertices` vertices even at `tolerance` (pixels), half
    /// the mean edge length of a mesh of the count asked for: the coarsest tolerance chosen
    /// automatically, as a coarser one would cut off detail that such a mesh could show.
    Detail {
        /// The outline's vertices at `tolerance`.
        outline_vertices: usize,
        /// The coarsest automatic tolerance, in pixels.
        tolerance: f64,
    },
    /// An outline given as it is (SVG, `.poly`, [`Outline`]) has `outline_vertices`
    /// vertices, too many for the count.
    Outline {
        /// The outline's vertices.
        outline_vertices: usize,
    },
    /// The outline fits, but the minimum angle (degrees) needs more vertices, around the
    /// outline's narrow parts and sharp corners.
    MinAngle {
        /// The minimum angle asked for.
        min_angle: f64,
    },
    /// The refinement came no closer in `passes` passes.
    Refinement {
        /// Passes run.
        passes: usize,
    },
}

/// `x` with at most two decimals, trailing zeros dropped.
fn short(x: f64) -> String {
    let s = format!("{x:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

impl std::fmt::Display for OffTarget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OffTarget::Tolerance {
                tolerance,
                outline_vertices,
            } => write!(
                f,
                "the outline simplified to --tolerance {} alone has {outline_vertices} vertices; raise --tolerance, or leave it out to have it raised to fit",
                short(*tolerance)
            ),
            OffTarget::Loops {
                loops,
                outline_vertices,
                tolerance,
            } => write!(
                f,
                "the outline's {loops} loops (pieces and holes) need {outline_vertices} vertices even at tolerance {}, the coarsest that keeps them all; ask for more vertices, or give a --tolerance that drops the smallest",
                short(*tolerance)
            ),
            OffTarget::Detail {
                outline_vertices,
                tolerance,
            } => write!(
                f,
                "the outline's detail needs {outline_vertices} vertices even simplified to {} pixels, half the mesh's edge length (coarser would cut it off); ask for more vertices, or give a larger --tolerance to smooth it",
                short(*tolerance)
            ),
            OffTarget::Outline { outline_vertices } => {
                write!(f, "the outline alone has {outline_vertices} vertices")
            }
            OffTarget::MinAngle { min_angle } => write!(
                f,
                "the minimum angle of {} degrees needs more vertices around the outline's narrow parts and sharp corners; lower --min-angle",
                short(*min_angle)
            ),
            OffTarget::Refinement { passes } => {
                write!(f, "the refinement came no closer in {passes} passes")
            }
        }
    }
}

/// What a meshing did.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshStats {
    /// Vertices of the mesh.
    pub vertices: usize,
    /// The vertices asked for ([`MeshOptions::vertices`]).
    pub requested_vertices: usize,
    /// Why `vertices` is more than [`VERTEX_COUNT_SLACK`] (10%) from `requested_vertices`;
    /// `None` when it is not.
    pub off_target: Option<OffTarget>,
    /// Triangles.
    pub faces: usize,
    /// Connected pieces.
    pub pieces: usize,
    /// Holes (boundary loops beyond one per piece).
    pub holes: usize,
    /// The smallest angle of any triangle, in degrees.
    pub min_angle: f64,
    /// Vertices of the outline before refinement.
    pub outline_vertices: usize,
    /// Outlines dropped as too small for the tolerance (pictures).
    pub dropped_outlines: usize,
    /// Pieces dropped as specks (pictures; see [`SPECK_AREA_FRACTION`]).
    pub dropped_specks: usize,
    /// The tolerance a picture's outline was simplified to, in pixels (the one given, or the
    /// default raised to fit the vertex count); `None` for outlines.
    pub tolerance: Option<f64>,
    /// Whether the refinement finished rather than ran out of vertices.
    pub refinement_complete: bool,
    /// Refinement passes run to approach the requested vertex count.
    pub passes: usize,
    /// Wall-clock time, from the picture or outline to the mesh.
    pub seconds: f64,
}

/// A mesh made from a picture or an outline.
#[derive(Clone, Debug)]
pub struct Meshed {
    /// The mesh: y up, counter-clockwise triangles.
    pub mesh: PlanarMesh,
    /// One texture coordinate per vertex (`corners` are the faces).
    pub texcoords: TexCoords,
    /// What was done.
    pub stats: MeshStats,
}

/// A picture's outline: the loops traced and the simplified outline to mesh.
#[derive(Clone, Debug)]
pub struct PictureOutline {
    /// The loops as traced, in the mesh's frame (pixels, y up): outer loops
    /// counter-clockwise, holes clockwise. All of them, including those dropped.
    pub traced: Vec<Vec<[f64; 2]>>,
    /// The simplified loops that are kept, as an outline.
    pub outline: Outline,
    /// Traced loops dropped as too small for the tolerance.
    pub dropped: usize,
    /// Pieces dropped as specks (their outer loops; the loops inside go with them).
    pub dropped_specks: usize,
    /// The tolerance the loops were simplified to, in pixels.
    pub tolerance: f64,
}

/// A picture's traced loops, and which belong to specks.
struct Traced {
    loops: Vec<Vec<[f64; 2]>>,
    /// Per loop, the outer loop of the speck it belongs to (all `None` when specks are kept).
    speck: Vec<Option<usize>>,
    /// `speck[i].is_some()`.
    leave_out: Vec<bool>,
}

fn trace_picture(image: &Image, picture: &PictureOptions) -> Result<Traced, MeshingError> {
    let coverage = picture::coverage(image, picture)?;
    let loops = trace::trace(&coverage);
    // Simplifying tests each loop against the loops around it: bounded by loops x points.
    let longest = loops.iter().map(Vec::len).max().unwrap_or(0);
    if (loops.len() as u64).saturating_mul(longest as u64) > MAX_TRACE_WORK {
        return Err(MeshingError::TooComplex {
            place: Place::default(),
            loops: loops.len(),
            longest,
        });
    }
    let speck = if picture.keep_specks {
        vec![None; loops.len()]
    } else {
        simplify::specks(&loops, SPECK_AREA_FRACTION)
    };
    let leave_out = speck.iter().map(Option::is_some).collect();
    Ok(Traced {
        loops,
        speck,
        leave_out,
    })
}

impl Traced {
    fn simplify(&self, tolerance: f64) -> simplify::Simplified {
        simplify::simplify_leaving_out(&self.loops, tolerance, &self.leave_out)
    }

    /// The picture's outline from these loops simplified to `tolerance`, and how many specks
    /// were left out.
    fn outline(
        &self,
        image: &Image,
        simplified: &simplify::Simplified,
        tolerance: f64,
    ) -> Result<(Outline, usize), MeshingError> {
        if simplified.loops.is_empty() {
            return Err(MeshingError::TooSmall {
                place: Place::default(),
                loops: self.loops.len(),
                largest_area: simplified.largest_area,
                tolerance,
            });
        }
        let mut outline = Outline::from_loops(&simplified.loops);
        outline.texture_frame = Some([0.0, 0.0, f64::from(image.width), f64::from(image.height)]);
        let dropped_specks = simplified
            .left_out
            .iter()
            .filter(|&&i| self.speck[i] == Some(i))
            .count();
        Ok((outline, dropped_specks))
    }
}

/// Traces a picture's subject and simplifies its outlines to `tolerance` pixels (default 1).
///
/// Specks are left out (unless [`PictureOptions::keep_specks`]): pieces whose area is below
/// [`SPECK_AREA_FRACTION`] of the largest piece's (the largest is always kept). Loops too
/// small for the tolerance are dropped first, and counted in `dropped`, not as specks.
///
/// # Errors
/// [`MeshingError::NoTransparency`], [`MeshingError::NoSubject`] when nothing is found,
/// [`MeshingError::TooSmall`] when every outline is too small for the tolerance,
/// [`MeshingError::BadOption`] for a threshold outside [0, 1) or a tolerance that is not
/// positive.
pub fn picture_outline(
    image: &Image,
    picture: &PictureOptions,
    tolerance: Option<f64>,
) -> Result<PictureOutline, MeshingError> {
    let tolerance = tolerance.unwrap_or(DEFAULT_PICTURE_TOLERANCE);
    MeshOptions::default()
        .with_tolerance(tolerance)
        .validate()?;
    let traced = trace_picture(image, picture)?;
    let simplified = traced.simplify(tolerance);
    let (outline, dropped_specks) = traced.outline(image, &simplified, tolerance)?;
    Ok(PictureOutline {
        traced: traced.loops,
        outline,
        dropped: simplified.dropped,
        dropped_specks,
        tolerance,
    })
}

/// Meshes a picture's subject (see the [module docs](self)), specks left out as
/// [`picture_outline`] does.
///
/// Without an explicit [`MeshOptions::tolerance`], the tolerance starts at the default (1
/// pixel) and is raised (the traced loops simplified again, doubling it, then bisecting)
/// until the outline uses at most [`OUTLINE_VERTEX_SHARE`] of the vertices asked for, so that
/// the mesh lands within 10% of the count; but never so far that a loop (a piece or a hole)
/// the default kept would be dropped. [`MeshStats::tolerance`] is the tolerance used, and
/// [`MeshStats::off_target`] says why when the count is still missed (an explicit tolerance,
/// loops that need more vertices than that, the minimum angle).
///
/// # Errors
/// Those of [`picture_outline`] and [`mesh_outline`].
pub fn mesh_picture(
    image: &Image,
    picture: &PictureOptions,
    options: &MeshOptions,
) -> Result<Meshed, MeshingError> {
    mesh_picture_sharing(image, picture, options, OUTLINE_VERTEX_SHARE, MAX_REFITS)
}

/// How many times a picture's outline is fitted again when its mesh misses the count (the
/// minimum angle needing more vertices along a detailed outline).
const MAX_REFITS: usize = 3;

/// [`mesh_picture`] with the outline at most `share` of the vertices asked for at first, and
/// at most `refits` fits again.
fn mesh_picture_sharing(
    image: &Image,
    picture: &PictureOptions,
    options: &MeshOptions,
    share: f64,
    refits: usize,
) -> Result<Meshed, MeshingError> {
    let start = Instant::now();
    options.validate()?;
    let target = options.vertices;
    let given = options.tolerance;
    let first_tolerance = given.unwrap_or(DEFAULT_PICTURE_TOLERANCE);
    let traced = trace_picture(image, picture)?;
    let first = traced.simplify(first_tolerance);
    let base = first.kept.clone();
    let kept: Vec<Vec<[f64; 2]>> = base.iter().map(|&i| traced.loops[i].clone()).collect();
    let cap = fit::max_tolerance(simplify::region_area(&kept), target);
    let mut first = Some(first);
    let mut budget = (share * target as f64).floor() as usize;
    let mut best: Option<Meshed> = None;
    // Outline vertices with which the mesh overshot, and undershot after an overshoot.
    let (mut over_at, mut under_at): (Option<usize>, Option<usize>) = (None, None);
    for _ in 0..=refits {
        let s = first
            .take()
            .unwrap_or_else(|| traced.simplify(first_tolerance));
        let (simplified, tolerance, limit) =
            if given.is_none() && !s.loops.is_empty() && fit::vertices(&s) > budget {
                let found = fit::search(
                    |t| traced.simplify(t),
                    &base,
                    budget,
                    first_tolerance,
                    first_tolerance,
                    cap,
                );
                (found.simplified, found.tolerance, found.limit)
            } else {
                (s, first_tolerance, None)
            };
        let (outline, dropped_specks) = traced.outline(image, &simplified, tolerance)?;
        let mut meshed = mesh_outline(&outline, options)?;
        let stats = &mut meshed.stats;
        stats.dropped_outlines = simplified.dropped;
        stats.dropped_specks = dropped_specks;
        stats.tolerance = Some(tolerance);
        if let Some(OffTarget::Outline { outline_vertices }) = stats.off_target {
            stats.off_target = Some(match (given, limit) {
                (Some(tolerance), _) => OffTarget::Tolerance {
                    tolerance,
                    outline_vertices,
                },
                (None, Some(fit::Limit::Detail)) => OffTarget::Detail {
                    outline_vertices,
                    tolerance,
                },
                (None, _) => OffTarget::Loops {
                    loops: simplified.loops.len(),
                    outline_vertices,
                    tolerance,
                },
            });
        }
        let vertices = stats.vertices;
        let off = stats.off_target.is_some();
        if best
            .as_ref()
            .is_none_or(|b| vertices.abs_diff(target) < b.stats.vertices.abs_diff(target))
        {
            best = Some(meshed);
        }
        if !off || given.is_some() || limit.is_some() {
            break;
        }
        // Off the count with an outline that fitted: fit it to fewer vertices (in proportion
        // to the overshoot), or between an overshoot and an undershoot.
        let used = fit::vertices(&simplified);
        if vertices > target {
            over_at = Some(used);
        } else {
            under_at = Some(used);
        }
        let next = match (over_at, under_at) {
            (Some(o), Some(u)) if u < o => (o + u) / 2,
            (Some(o), None) => o * target / vertices,
            _ => break,
        };
        if next < 3 || Some(next) == over_at || Some(next) == under_at {
            break;
        }
        budget = next;
    }
    let mut meshed = best.ok_or_else(|| MeshingError::Internal {
        place: Place::default(),
        message: "no meshing ran".into(),
    })?;
    meshed.stats.seconds = start.elapsed().as_secs_f64();
    Ok(meshed)
}

/// Meshes an outline.
///
/// # Errors
/// [`MeshingError::SelfIntersection`] and [`MeshingError::ZeroLength`] for segments that
/// cross, touch or overlap (and with [`Inside::Parity`], loops that share a vertex),
/// [`MeshingError::NothingInside`] when no area is inside, [`MeshingError::BadOption`].
pub fn mesh_outline(outline: &Outline, options: &MeshOptions) -> Result<Meshed, MeshingError> {
    let start = Instant::now();
    options.validate()?;
    let checked = outline::check(outline)?;
    let outline_vertices = checked.vertices.len();
    if outline_vertices > MAX_MESHED_OUTLINE_POINTS {
        return Err(MeshingError::TooManyPoints {
            place: Place::default(),
            what: "the outline (as meshed)".into(),
            points: outline_vertices as u64,
            limit: MAX_MESHED_OUTLINE_POINTS,
            tolerance_helps: false,
        });
    }
    let t = triangulate::triangulate(&checked, options.vertices, options.min_angle)?;
    let mesh = t.mesh;
    check_output(outline, &mesh)?;
    let frame = outline.texture_frame.unwrap_or_else(|| {
        let b = outline::bounds(&mesh.positions);
        let side = (b[2] - b[0]).max(b[3] - b[1]);
        [b[0], b[1], side, side]
    });
    let uv = mesh
        .positions
        .iter()
        .map(|p| {
            [
                ((p[0] - frame[0]) / frame[2]).clamp(0.0, 1.0),
                ((p[1] - frame[1]) / frame[3]).clamp(0.0, 1.0),
            ]
        })
        .collect();
    let texcoords = TexCoords {
        uv,
        corners: mesh.faces.clone(),
    };
    let info = MeshInfo::of(&SurfaceMesh {
        positions: mesh.positions.iter().map(|p| [p[0], p[1], 0.0]).collect(),
        faces: mesh.faces.clone(),
        texcoords: None,
    });
    let vertices = mesh.positions.len();
    let target = options.vertices;
    let off_target = if vertices.abs_diff(target) as f64 <= VERTEX_COUNT_SLACK * target as f64 {
        None
    } else if vertices > target && outline_vertices > fit::budget(target) {
        Some(OffTarget::Outline { outline_vertices })
    } else if vertices > target {
        Some(OffTarget::MinAngle {
            min_angle: options.min_angle,
        })
    } else {
        Some(OffTarget::Refinement { passes: t.passes })
    };
    let stats = MeshStats {
        vertices,
        requested_vertices: target,
        off_target,
        faces: mesh.faces.len(),
        pieces: info.components,
        holes: info.boundary_loops.saturating_sub(info.components),
        min_angle: min_angle(&mesh),
        outline_vertices,
        dropped_outlines: 0,
        dropped_specks: 0,
        tolerance: None,
        refinement_complete: t.refinement_complete,
        passes: t.passes,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok(Meshed {
        mesh,
        texcoords,
        stats,
    })
}

/// Refuses a mesh that the mesh readers (and `bdmorph info`, `bdmorph morph`) would refuse:
/// [`PlanarMesh::validate`]'s checks (a triangle of area at most 1e-14 times the squared
/// diameter is degenerate), naming where the first bad triangle is in the input's
/// coordinates.
fn check_output(outline: &Outline, mesh: &PlanarMesh) -> Result<(), MeshingError> {
    use crate::mesh::MeshError;
    let centroid = |face: usize| {
        let p = mesh.faces[face].map(|v| mesh.positions[v as usize]);
        outline.in_input([
            (p[0][0] + p[1][0] + p[2][0]) / 3.0,
            (p[0][1] + p[1][1] + p[2][1]) / 3.0,
        ])
    };
    match mesh.validate() {
        Ok(()) => Ok(()),
        Err(MeshError::Degenerate { face, area }) => Err(MeshingError::Degenerate {
            place: Place::default(),
            at: centroid(face),
            area,
        }),
        Err(e) => Err(MeshingError::Internal {
            place: Place::default(),
            message: format!("the mesh made fails its checks: {e}"),
        }),
    }
}

/// The smallest corner angle of any triangle, in degrees (180 for a mesh without triangles).
pub fn min_angle(mesh: &PlanarMesh) -> f64 {
    let mut smallest = std::f64::consts::PI;
    for f in &mesh.faces {
        let p = f.map(|v| mesh.positions[v as usize]);
        for k in 0..3 {
            let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
            let (u, w) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
            let angle = (u[0] * w[1] - u[1] * w[0])
                .abs()
                .atan2(u[0] * w[0] + u[1] * w[1]);
            smallest = smallest.min(angle);
        }
    }
    smallest.to_degrees()
}

/// What kind of input a file is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputKind {
    /// A PNG or JPEG picture.
    Picture,
    /// Triangle's `.poly`.
    Poly,
    /// SVG.
    Svg,
}

impl InputKind {
    /// The kind of `path`: by its extension (`.png`, `.jpg`, `.jpeg`, `.poly`, `.svg`,
    /// case-insensitive), or else by its first bytes.
    pub fn of(path: &Path, bytes: &[u8]) -> Option<InputKind> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png" | "jpg" | "jpeg") => return Some(InputKind::Picture),
            Some("poly") => return Some(InputKind::Poly),
            Some("svg") => return Some(InputKind::Svg),
            _ => {}
        }
        if bytes.starts_with(b"\x89PNG\r\n\x1a\n") || bytes.starts_with(&[0xff, 0xd8, 0xff]) {
            return Some(InputKind::Picture);
        }
        let text = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes);
        let first = text.iter().find(|b| !b.is_ascii_whitespace());
        (first == Some(&b'<')).then_some(InputKind::Svg)
    }
}

/// Meshes a file: a picture (PNG, JPEG), a `.poly` or an SVG outline, as [`InputKind::of`]
/// tells.
///
/// # Errors
/// [`MeshingError::Read`], [`MeshingError::UnknownInput`], and those of the reader and of
/// [`mesh_picture`] or [`mesh_outline`], naming the file.
pub fn mesh_file(
    path: &Path,
    picture: &PictureOptions,
    options: &MeshOptions,
) -> Result<Meshed, MeshingError> {
    let start = Instant::now();
    options.validate()?;
    let bytes = crate::io::read_input(path, crate::io::MAX_INPUT_BYTES).map_err(|source| {
        MeshingError::Read {
            path: path.to_path_buf(),
            source,
        }
    })?;
    let kind = InputKind::of(path, &bytes).ok_or_else(|| MeshingError::UnknownInput {
        path: path.to_path_buf(),
    })?;
    let mut meshed = match kind {
        InputKind::Picture => {
            let image = read_image(path)?;
            mesh_picture(&image, picture, options)
        }
        InputKind::Poly | InputKind::Svg => {
            let text = String::from_utf8_lossy(&bytes);
            let outline = if kind == InputKind::Poly {
                parse_poly(&text)
            } else {
                parse_svg(&text, options.tolerance)
            };
            outline.and_then(|o| mesh_outline(&o, options))
        }
    }
    .map_err(|e| e.in_file(path))?;
    meshed.stats.seconds = start.elapsed().as_secs_f64();
    Ok(meshed)
}
