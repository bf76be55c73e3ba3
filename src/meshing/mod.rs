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
//! own geometry and are kept whole.
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
    /// About how many vertices the mesh should have (default 2000). Fewer when the outline
    /// alone needs more: then the mesh has no more than the minimum angle needs.
    pub vertices: usize,
    /// How far (at most) the mesh's boundary may be from the traced outline (pictures, in
    /// pixels, default 1) or curves from their polylines (SVG, in the file's units after
    /// transforms, default 1/1000 of the outline's bounding-box diagonal). `.poly` vertices
    /// are used as they are.
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

/// What a meshing did.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshStats {
    /// Vertices of the mesh.
    pub vertices: usize,
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
/// # Errors
/// Those of [`picture_outline`] and [`mesh_outline`].
pub fn mesh_picture(
    image: &Image,
    picture: &PictureOptions,
    options: &MeshOptions,
) -> Result<Meshed, MeshingError> {
    let start = Instant::now();
    options.validate()?;
    let traced = picture_outline(image, picture, options.tolerance)?;
    let mut meshed = mesh_outline(&traced.outline, options)?;
    meshed.stats.dropped_outlines = traced.dropped;
    meshed.stats.dropped_specks = traced.dropped_specks;
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
    let t = triangulate::triangulate(&checked, options.vertices, options.min_angle)?;
    let mesh = t.mesh;
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
    let stats = MeshStats {
        vertices: mesh.positions.len(),
        faces: mesh.faces.len(),
        pieces: info.components,
        holes: info.boundary_loops.saturating_sub(info.components),
        min_angle: min_angle(&mesh),
        outline_vertices,
        dropped_outlines: 0,
        dropped_specks: 0,
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
    let bytes = std::fs::read(path).map_err(|source| MeshingError::Read {
        path: path.to_path_buf(),
        source,
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
