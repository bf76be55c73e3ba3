//! Rasterised pictures: [`render`] a frame to an [`Image`], encode it as PNG ([`encode_png`])
//! or a looping animated GIF ([`encode_gif`], or frame by frame with a [`GifEncoder`]), tile
//! frames into a contact sheet ([`strip`]), and read PNG or JPEG textures ([`read_image`],
//! [`decode_image`]).
//!
//! Triangles are drawn anti-aliased with [`tiny_skia`]: light blue with dark blue edges, or
//! filled with a texture through their corner texture coordinates; triangles that are flipped
//! (signed area zero or negative) are red so problems stand out.
//!
//! ```
//! use bdmorph::generate;
//! use bdmorph::render::{raster, Drawing, ImageSize, Viewport};
//!
//! let mesh = generate::disk(4, 0.0);
//! let drawing = Drawing { faces: &mesh.faces, corner_uv: None, texture: None, face_colours: None, depth: None };
//! let view = Viewport::fit([&mesh.positions[..]]);
//! let size = ImageSize { width: 64, height: 48 };
//! let image = raster::render(&mesh.positions, &drawing, &view, size)?;
//! assert_eq!((image.width, image.height), (64, 48));
//! let png = raster::encode_png(&image)?;
//! assert_eq!(raster::decode_image(&png)?, image);
//! # Ok::<(), raster::RenderError>(())
//! ```

use super::{depth_order, Background, Drawing, Image, ImageSize, Viewport};
use rayon::prelude::*;
use std::error::Error as StdError;
use std::fmt;
use std::io::{Cursor, Write};
use std::path::{Path, PathBuf};
use tiny_skia::{
    Color, FillRule, FilterQuality, Paint, PathBuilder, Pattern, Pixmap, PixmapRef, Shader,
    SpreadMode, Stroke, Transform,
};

/// Fill of a triangle without texture (`#cfe0f5`).
pub(super) const FILL: [u8; 3] = [0xcf, 0xe0, 0xf5];
/// Triangle edges (`#3a5a80`).
pub(super) const EDGE: [u8; 3] = [0x3a, 0x5a, 0x80];
/// Fill of a flipped triangle (`#e05050`).
pub(super) const FLIPPED: [u8; 3] = [0xe0, 0x50, 0x50];

/// Largest width or height of a decoded image.
const MAX_DECODED_SIDE: u32 = super::MAX_SIDE;
/// White space between the frames of a [`strip`], in pixels.
const STRIP_GAP: u32 = 4;

/// Why a picture could not be read, decoded or encoded. Every message is one line; errors of
/// [`read_image`] start with the file name.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", .path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The bytes are neither a PNG nor a JPEG image.
    #[error("{}not a PNG or JPEG image", FilePrefix(.path))]
    UnknownFormat {
        /// The file, when the bytes came from one.
        path: Option<PathBuf>,
    },
    /// The image is damaged or uses a feature the decoder does not support.
    #[error("{}cannot decode {format} image: {source}", FilePrefix(.path))]
    Decode {
        /// The file, when the bytes came from one.
        path: Option<PathBuf>,
        /// `"PNG"` or `"JPEG"`.
        format: &'static str,
        /// The decoder's error.
        source: Box<dyn StdError + Send + Sync>,
    },
    /// A decoded image is wider or taller than 16384 pixels.
    #[error("{}image is {width}x{height} pixels; at most {max} per side are supported", FilePrefix(.path))]
    TooLarge {
        /// The file, when the bytes came from one.
        path: Option<PathBuf>,
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// The largest supported side.
        max: u32,
    },
    /// A picture whose header claims more pixels than its data could hold (compressed, a
    /// byte of PNG or JPEG data holds at most about a thousand pixels' bytes): damaged or
    /// hostile, refused before its pixels are allocated.
    #[error("{}image claims {width}x{height} pixels but its file holds only {bytes} bytes", FilePrefix(.path))]
    Unbacked {
        /// The file, when the bytes came from one.
        path: Option<PathBuf>,
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// The file's size.
        bytes: usize,
    },
    /// A picture of more pixels than [`super::MAX_PIXELS`] (or wider or taller than
    /// [`super::MAX_SIDE`]), read or asked for: refused before its pixels are allocated.
    #[error("{}a {width}x{height} picture is {} pixels, over the budget of {} pixels ({} Mpx) and {} a side", FilePrefix(.path), u64::from(*.width) * u64::from(*.height), super::MAX_PIXELS, super::MAX_PIXELS >> 20, super::MAX_SIDE)]
    OverBudget {
        /// The file, when the picture came from one.
        path: Option<PathBuf>,
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// The encoder failed.
    #[error("cannot encode {format}: {source}")]
    Encode {
        /// `"PNG"` or `"GIF"`.
        format: &'static str,
        /// The encoder's error.
        source: Box<dyn StdError + Send + Sync>,
    },
    /// An [`Image`]'s pixel buffer does not have `width * height * 4` bytes.
    #[error("a {width}x{height} image needs {expected} RGBA bytes, but has {actual}")]
    BadBuffer {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// `width * height * 4`.
        expected: u64,
        /// The buffer's length.
        actual: usize,
    },
    /// An image has no pixels, or an animation no frames.
    #[error("nothing to encode: {what}")]
    Empty {
        /// What is empty.
        what: &'static str,
    },
    /// The frames of an animation differ in size.
    #[error("frame {index} is {width}x{height} pixels but the animation is {first_width}x{first_height}; all frames must have one size")]
    FrameSize {
        /// The frame (0-based).
        index: usize,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
        /// The animation's width: frame 0's for [`encode_gif`], the one a [`GifEncoder`]
        /// was created with.
        first_width: u32,
        /// The animation's height.
        first_height: u32,
    },
    /// An earlier write of a [`GifEncoder`] failed: the file is incomplete and the encoder
    /// takes no more frames.
    #[error("an earlier write failed: the {format} file is incomplete")]
    Incomplete {
        /// The format.
        format: &'static str,
    },
    /// The image is too large for the format (GIF allows at most 65535 pixels per side).
    #[error("{format} allows at most {max} pixels per side, the image is {width}x{height}")]
    TooLargeForFormat {
        /// The format.
        format: &'static str,
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// The largest side the format allows.
        max: u32,
    },
}

/// Shows `path: ` before a message when there is a path.
struct FilePrefix<'a>(&'a Option<PathBuf>);

impl fmt::Display for FilePrefix<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(path) => write!(f, "{}: ", path.display()),
            None => Ok(()),
        }
    }
}

impl RenderError {
    /// The same error, naming `file` (for errors that can name one).
    fn in_file(mut self, file: &Path) -> RenderError {
        match &mut self {
            RenderError::UnknownFormat { path }
            | RenderError::Decode { path, .. }
            | RenderError::TooLarge { path, .. }
            | RenderError::Unbacked { path, .. }
            | RenderError::OverBudget { path, .. } => *path = Some(file.to_path_buf()),
            _ => {}
        }
        self
    }
}

/// A triangle in pixel coordinates, with its face index and whether it is flipped.
pub(super) struct PixelTriangle {
    /// Index into `Drawing::faces`.
    pub face: usize,
    /// Corners in pixels (`y` down).
    pub corners: [[f64; 2]; 3],
    /// Signed area in world coordinates is zero or negative (or NaN).
    pub flipped: bool,
}

/// The drawable triangles of `faces` in pixel coordinates: faces with a vertex index out of
/// range or a non-finite (or beyond 10^7 px) pixel coordinate are left out.
pub(super) fn pixel_triangles<'a>(
    positions: &'a [[f64; 2]],
    faces: &'a [[u32; 3]],
    view: &Viewport,
    size: ImageSize,
) -> impl Iterator<Item = PixelTriangle> + 'a {
    let (scale, ox, oy) = view.transform(size);
    faces.iter().enumerate().filter_map(move |(face, f)| {
        let p = [
            *positions.get(f[0] as usize)?,
            *positions.get(f[1] as usize)?,
            *positions.get(f[2] as usize)?,
        ];
        let area2 =
            (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
        let corners = p.map(|q| [ox + scale * q[0], oy - scale * q[1]]);
        // Beyond this tiny-skia's f32 geometry loses precision; a triangle with a corner
        // thousands of pictures away is left out like a non-finite one.
        let limit = 1e7;
        if !corners.iter().flatten().all(|c| c.abs() < limit) {
            return None;
        }
        Some(PixelTriangle {
            face,
            corners,
            flipped: area2.is_nan() || area2 <= 0.0,
        })
    })
}

fn colour([r, g, b]: [u8; 3]) -> Color {
    Color::from_rgba8(r, g, b, 255)
}

fn solid(rgb: [u8; 3], anti_alias: bool) -> Paint<'static> {
    let mut paint = Paint::default();
    paint.set_color(colour(rgb));
    paint.anti_alias = anti_alias;
    paint
}

fn add_triangle(pb: &mut PathBuilder, c: &[[f64; 2]; 3]) {
    pb.move_to(c[0][0] as f32, c[0][1] as f32);
    pb.line_to(c[1][0] as f32, c[1][1] as f32);
    pb.line_to(c[2][0] as f32, c[2][1] as f32);
    pb.close();
}

/// Fills all `triangles` as one path, so shared edges leave no seams.
fn fill_union<'a>(
    pixmap: &mut Pixmap,
    triangles: impl Iterator<Item = &'a PixelTriangle>,
    rgb: [u8; 3],
) {
    let mut pb = PathBuilder::new();
    for t in triangles {
        add_triangle(&mut pb, &t.corners);
    }
    if let Some(path) = pb.finish() {
        pixmap.fill_path(
            &path,
            &solid(rgb, true),
            FillRule::Winding,
            Transform::identity(),
            None,
        );
    }
}

/// Fills the unflipped triangles with their face's colour, one path per colour (so
/// neighbours of one colour leave no seams).
fn fill_by_colour<'t>(
    pixmap: &mut Pixmap,
    triangles: impl Iterator<Item = &'t PixelTriangle>,
    colours: &[[u8; 3]],
) {
    let mut order: Vec<&PixelTriangle> = triangles.filter(|t| !t.flipped).collect();
    order.sort_by_key(|t| colours[t.face]);
    for group in order.chunk_by(|a, b| colours[a.face] == colours[b.face]) {
        fill_union(pixmap, group.iter().copied(), colours[group[0].face]);
    }
}

/// Strokes every edge once (shared edges are not drawn twice), 1 px wide and anti-aliased.
/// When the mesh is so dense that edges would hide the fills, they fade.
fn stroke_edges(pixmap: &mut Pixmap, triangles: &[&PixelTriangle], faces: &[[u32; 3]]) {
    let mut edges: Vec<(u32, u32, usize, usize)> = Vec::with_capacity(3 * triangles.len());
    for (ti, t) in triangles.iter().enumerate() {
        let f = faces[t.face];
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            // Remember which triangle and corner the edge starts at, for its pixel position.
            let (lo, hi) = if a < b { (a, b) } else { (b, a) };
            edges.push((lo, hi, ti, k));
        }
    }
    edges.sort_unstable_by_key(|e| (e.0, e.1));
    edges.dedup_by_key(|e| (e.0, e.1));
    if edges.is_empty() {
        return;
    }
    let mut lengths: Vec<f64> = Vec::with_capacity(edges.len());
    let mut pb = PathBuilder::with_capacity(2 * edges.len(), 2 * edges.len());
    for &(_, _, ti, k) in &edges {
        let c = &triangles[ti].corners;
        let (p, q) = (c[k], c[(k + 1) % 3]);
        lengths.push((q[0] - p[0]).hypot(q[1] - p[1]));
        pb.move_to(p[0] as f32, p[1] as f32);
        pb.line_to(q[0] as f32, q[1] as f32);
    }
    let mid = lengths.len() / 2;
    let median = *lengths.select_nth_unstable_by(mid, f64::total_cmp).1;
    // Full strength from a median edge of 12 px, fading linearly to a fifth at 4 px.
    let opacity = ((median - 2.0) / 10.0).clamp(0.2, 1.0);
    let mut paint = solid(EDGE, true);
    paint.shader.apply_opacity(opacity as f32);
    if let Some(path) = pb.finish() {
        let stroke = Stroke {
            width: 1.0,
            ..Stroke::default()
        };
        pixmap.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
    }
}

/// The texture as a tiny-skia pixmap, or `None` when it has no pixels or a malformed
/// buffer: composited over `under` (opaque) when given, else premultiplied with its
/// transparency kept.
fn texture_pixmap(texture: &Image, under: Option<[u8; 3]>) -> Option<Pixmap> {
    if texture.width == 0 || texture.height == 0 || check_buffer(texture).is_err() {
        return None;
    }
    let size = tiny_skia::IntSize::from_wh(texture.width, texture.height)?;
    let mut data = texture.rgba.clone();
    for px in data.chunks_exact_mut(4) {
        let a = u32::from(px[3]);
        match under {
            Some(rgb) => {
                for (c, b) in px[..3].iter_mut().zip(rgb) {
                    *c = ((u32::from(*c) * a + u32::from(b) * (255 - a) + 127) / 255) as u8;
                }
                px[3] = 255;
            }
            None => {
                for c in &mut px[..3] {
                    *c = ((u32::from(*c) * a + 127) / 255) as u8;
                }
            }
        }
    }
    Pixmap::from_vec(data, size)
}

/// The affine map taking texture pixel coordinates of the corners to their pixel positions,
/// or `None` when the texture coordinates are (nearly) collinear.
fn texture_transform(
    uv: &[[f64; 2]; 3],
    corners: &[[f64; 2]; 3],
    w: f64,
    h: f64,
) -> Option<Transform> {
    let t = uv.map(|c| [c[0] * w, (1.0 - c[1]) * h]);
    let (a, b) = (
        [t[1][0] - t[0][0], t[1][1] - t[0][1]],
        [t[2][0] - t[0][0], t[2][1] - t[0][1]],
    );
    let (p, q) = (
        [corners[1][0] - corners[0][0], corners[1][1] - corners[0][1]],
        [corners[2][0] - corners[0][0], corners[2][1] - corners[0][1]],
    );
    let det = a[0] * b[1] - a[1] * b[0];
    let norm = (a[0] * a[0] + a[1] * a[1]) * (b[0] * b[0] + b[1] * b[1]);
    if det.is_nan() || det.abs() <= 1e-9 * norm.sqrt() {
        return None;
    }
    // M = [p q] [a b]^-1.
    let inv = [[b[1] / det, -b[0] / det], [-a[1] / det, a[0] / det]];
    let m00 = p[0] * inv[0][0] + q[0] * inv[1][0];
    let m01 = p[0] * inv[0][1] + q[0] * inv[1][1];
    let m10 = p[1] * inv[0][0] + q[1] * inv[1][0];
    let m11 = p[1] * inv[0][1] + q[1] * inv[1][1];
    let tx = corners[0][0] - (m00 * t[0][0] + m01 * t[0][1]);
    let ty = corners[0][1] - (m10 * t[0][0] + m11 * t[0][1]);
    let ts = Transform::from_row(
        m00 as f32, m10 as f32, m01 as f32, m11 as f32, tx as f32, ty as f32,
    );
    ts.is_finite().then_some(ts)
}

/// The texture's colour at the (nearest pixel to) the centroid of `uv`.
fn texture_colour_at_centroid(texture: PixmapRef<'_>, uv: &[[f64; 2]; 3]) -> Color {
    let (w, h) = (texture.width(), texture.height());
    let u = (uv[0][0] + uv[1][0] + uv[2][0]) / 3.0;
    let v = (uv[0][1] + uv[1][1] + uv[2][1]) / 3.0;
    let x = (u * f64::from(w)).floor().clamp(0.0, f64::from(w - 1)) as u32;
    let y = ((1.0 - v) * f64::from(h))
        .floor()
        .clamp(0.0, f64::from(h - 1)) as u32;
    texture
        .pixel(x, y)
        .map(|c| c.demultiply())
        .map(|c| Color::from_rgba8(c.red(), c.green(), c.blue(), 255))
        .unwrap_or(Color::WHITE)
}

/// Fills the unflipped triangles with the texture. Anti-aliased fills of adjacent triangles
/// leave faint seams where both cover a pixel partially, so a second pass without
/// anti-aliasing paints every pixel whose centre lies in a triangle opaquely: the seams
/// vanish and only the outline keeps the first pass's smooth edge.
///
/// On a transparent background the texture keeps its transparency, and the second pass
/// replaces pixels rather than blending over them (a half-transparent texel is not doubled).
fn fill_textured<'t>(
    pixmap: &mut Pixmap,
    triangles: impl Iterator<Item = &'t PixelTriangle> + Clone,
    corner_uv: &[[[f64; 2]; 3]],
    texture: &Pixmap,
    transparent: bool,
) {
    let (w, h) = (f64::from(texture.width()), f64::from(texture.height()));
    let mut pb = PathBuilder::new();
    for anti_alias in [true, false] {
        for t in triangles.clone().filter(|t| !t.flipped) {
            let uv = &corner_uv[t.face];
            let shader = match texture_transform(uv, &t.corners, w, h) {
                Some(ts) => Pattern::new(
                    texture.as_ref(),
                    SpreadMode::Pad,
                    FilterQuality::Bilinear,
                    1.0,
                    ts,
                ),
                None => Shader::SolidColor(texture_colour_at_centroid(texture.as_ref(), uv)),
            };
            let blend_mode = if transparent && !anti_alias {
                tiny_skia::BlendMode::Source
            } else {
                tiny_skia::BlendMode::SourceOver
            };
            let paint = Paint {
                shader,
                anti_alias,
                blend_mode,
                ..Paint::default()
            };
            add_triangle(&mut pb, &t.corners);
            let Some(path) = pb.finish() else {
                pb = PathBuilder::new();
                continue;
            };
            pixmap.fill_path(
                &path,
                &paint,
                FillRule::Winding,
                Transform::identity(),
                None,
            );
            pb = path.clear();
        }
    }
}

/// Draws the triangles of `drawing` at `positions` (world coordinates, `y` up) as an image
/// of `size` on a white background, `view` mapped to the image as by
/// [`Viewport::transform`]: [`render_on`] with [`Background::WHITE`].
///
/// With a texture and per-corner texture coordinates (one entry per face), each triangle is
/// filled with the texture (bilinear sampling, transparency composited over white) through
/// the affine map its corners define; otherwise triangles are light blue with dark blue,
/// 1 px, anti-aliased edges (fading when the median edge is shorter than 12 px, so a dense
/// mesh does not turn solid blue). Flipped triangles (world signed area zero or negative) are
/// filled red on top in both cases. With per-face colours (one per face), triangles are
/// filled with those instead of the flat fill or the texture, with edges. Faces with out-of-range vertex indices or non-finite (or
/// beyond 10^7 px) positions are skipped. A texture whose `corner_uv` length differs from the
/// number of faces is ignored.
///
/// The result is opaque. An image with zero width or height has no pixels.
///
/// # Errors
/// [`RenderError::OverBudget`] for a size over [`super::MAX_PIXELS`] or [`super::MAX_SIDE`]
/// a side, before anything is allocated.
pub fn render(
    positions: &[[f64; 2]],
    drawing: &Drawing,
    view: &Viewport,
    size: ImageSize,
) -> Result<Image, RenderError> {
    render_on(positions, drawing, view, size, Background::WHITE)
}

/// As [`render`], on `background`: a colour, or transparency (pixels the subject does not
/// cover have alpha 0, its anti-aliased outline partial alpha, and a texture keeps its own
/// transparency). With a per-face depth ([`Drawing::depth`]), the faces are drawn a level
/// at a time from the lowest, each level's fills, flips and edges over the levels below, so
/// where the mesh overlaps itself the higher level is in front.
///
/// The image is not premultiplied.
///
/// # Errors
/// As [`render`].
pub fn render_on(
    positions: &[[f64; 2]],
    drawing: &Drawing,
    view: &Viewport,
    size: ImageSize,
    background: Background,
) -> Result<Image, RenderError> {
    check_budget(size.width, size.height)?;
    let (fill, under) = match background {
        Background::Transparent => (Color::TRANSPARENT, None),
        Background::Colour(rgb) => (colour(rgb), Some(rgb)),
    };
    let blank = || {
        let px = match under {
            Some([r, g, b]) => [r, g, b, 255],
            None => [0; 4],
        };
        Image {
            width: size.width,
            height: size.height,
            rgba: px.repeat(size.width as usize * size.height as usize),
        }
    };
    let Some(mut pixmap) = Pixmap::new(size.width, size.height) else {
        return Ok(blank());
    };
    pixmap.fill(fill);
    let triangles: Vec<PixelTriangle> =
        pixel_triangles(positions, drawing.faces, view, size).collect();

    let textured = match (drawing.texture, drawing.corner_uv) {
        (Some(texture), Some(uv)) if uv.len() == drawing.faces.len() => {
            texture_pixmap(texture, under).map(|t| (t, uv))
        }
        _ => None,
    };
    let coloured = drawing
        .face_colours
        .filter(|c| c.len() == drawing.faces.len());
    let levels = drawing
        .depth
        .filter(|d| d.len() == drawing.faces.len())
        .and_then(|d| depth_order(d).map(|_| d));
    let layer = |pixmap: &mut Pixmap, layer: &[&PixelTriangle]| {
        let all = || layer.iter().copied();
        match (coloured, &textured) {
            (Some(colours), _) => fill_by_colour(pixmap, all(), colours),
            (None, Some((texture, uv))) => {
                fill_textured(pixmap, all(), uv, texture, under.is_none())
            }
            (None, None) => fill_union(pixmap, all().filter(|t| !t.flipped), FILL),
        }
        fill_union(pixmap, all().filter(|t| t.flipped), FLIPPED);
        if textured.is_none() || coloured.is_some() {
            stroke_edges(pixmap, layer, drawing.faces);
        }
    };
    match levels {
        None => layer(&mut pixmap, &triangles.iter().collect::<Vec<_>>()),
        Some(depth) => {
            let mut order: Vec<&PixelTriangle> = triangles.iter().collect();
            order.sort_by_key(|t| depth[t.face]);
            for group in order.chunk_by(|a, b| depth[a.face] == depth[b.face]) {
                layer(&mut pixmap, group);
            }
        }
    }
    Ok(Image {
        width: size.width,
        height: size.height,
        rgba: pixmap.take_demultiplied(),
    })
}

fn check_buffer(img: &Image) -> Result<(), RenderError> {
    let expected = u64::from(img.width) * u64::from(img.height) * 4;
    if img.rgba.len() as u64 != expected {
        return Err(RenderError::BadBuffer {
            width: img.width,
            height: img.height,
            expected,
            actual: img.rgba.len(),
        });
    }
    Ok(())
}

fn encode_error(
    format: &'static str,
) -> impl FnOnce(Box<dyn StdError + Send + Sync>) -> RenderError {
    move |source| RenderError::Encode { format, source }
}

/// Encodes an image as an 8-bit RGBA PNG.
///
/// # Errors
/// [`RenderError::Empty`] for an image without pixels, [`RenderError::BadBuffer`] when the
/// buffer does not match the size.
pub fn encode_png(img: &Image) -> Result<Vec<u8>, RenderError> {
    check_buffer(img)?;
    if img.rgba.is_empty() {
        return Err(RenderError::Empty {
            what: "the image has no pixels",
        });
    }
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, img.width, img.height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    let fail = |e: png::EncodingError| encode_error("PNG")(Box::new(e));
    let mut writer = encoder.write_header().map_err(fail)?;
    writer.write_image_data(&img.rgba).map_err(fail)?;
    writer.finish().map_err(fail)?;
    Ok(out)
}

/// Decoded bytes (RGBA) one byte of a compressed picture may claim: deflate expands a byte
/// at most 1032-fold, and a flat JPEG block of 8 x 8 pixels takes a few bits.
const MAX_EXPANSION: usize = 2048;

/// Refuses a picture over [`MAX_DECODED_SIDE`] a side, or claiming more pixels than `data`
/// bytes of file could hold (beyond 16 MiB decoded), before its pixels are allocated.
fn too_large(width: u32, height: u32, data: usize) -> Result<(), RenderError> {
    if width > MAX_DECODED_SIDE || height > MAX_DECODED_SIDE {
        return Err(RenderError::TooLarge {
            path: None,
            width,
            height,
            max: MAX_DECODED_SIDE,
        });
    }
    let decoded = 4 * width as usize * height as usize;
    if decoded > (16 << 20) + MAX_EXPANSION.saturating_mul(data) {
        return Err(RenderError::Unbacked {
            path: None,
            width,
            height,
            bytes: data,
        });
    }
    check_budget(width, height)
}

/// Refuses a picture of `width` x `height` over [`super::MAX_PIXELS`] or wider or taller
/// than [`super::MAX_SIDE`] ([`RenderError::OverBudget`]): checked before any picture is
/// decoded or drawn.
///
/// # Errors
/// [`RenderError::OverBudget`].
pub fn check_budget(width: u32, height: u32) -> Result<(), RenderError> {
    if u64::from(width) * u64::from(height) > super::MAX_PIXELS
        || width > super::MAX_SIDE
        || height > super::MAX_SIDE
    {
        return Err(RenderError::OverBudget {
            path: None,
            width,
            height,
        });
    }
    Ok(())
}

/// Widens 8-bit pixels of 1 (grey), 2 (grey, alpha), 3 (RGB) or 4 (RGBA) channels to RGBA.
fn to_rgba(pixels: &[u8], channels: usize) -> Vec<u8> {
    match channels {
        4 => pixels.to_vec(),
        3 => pixels
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect(),
        2 => pixels
            .chunks_exact(2)
            .flat_map(|p| [p[0], p[0], p[0], p[1]])
            .collect(),
        _ => pixels.iter().flat_map(|&g| [g, g, g, 255]).collect(),
    }
}

fn decode_png(bytes: &[u8]) -> Result<Image, RenderError> {
    let fail = |e: png::DecodingError| {
        // The decoder's own words, unless they would print a damaged chunk's bytes.
        let text = e.to_string();
        let source: Box<dyn StdError + Send + Sync> = if text.contains("ChunkType")
            || !text.chars().all(|c| c.is_ascii() && !c.is_control())
        {
            "damaged data (a chunk of an unknown kind where a known one was needed)".into()
        } else {
            Box::new(e)
        };
        RenderError::Decode {
            path: None,
            format: "PNG",
            source,
        }
    };
    let mut decoder = png::Decoder::new(Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(fail)?;
    let (width, height) = (reader.info().width, reader.info().height);
    too_large(width, height, bytes.len())?;
    let len = reader
        .output_buffer_size()
        .ok_or_else(|| RenderError::TooLarge {
            path: None,
            width,
            height,
            max: MAX_DECODED_SIDE,
        })?;
    let mut buf = vec![0; len];
    let info = reader.next_frame(&mut buf).map_err(fail)?;
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => {
            // Expanded by `normalize_to_color8`; kept as an error rather than a panic.
            return Err(RenderError::Decode {
                path: None,
                format: "PNG",
                source: "indexed colour was not expanded".into(),
            });
        }
    };
    let row = width as usize * channels;
    let mut rgba = Vec::with_capacity(width as usize * height as usize * 4);
    for line in buf.chunks(info.line_size).take(height as usize) {
        rgba.extend(to_rgba(&line[..row], channels));
    }
    Ok(Image {
        width,
        height,
        rgba,
    })
}

fn decode_jpeg(bytes: &[u8]) -> Result<Image, RenderError> {
    use zune_jpeg::zune_core::bytestream::ZCursor;
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    let fail = |e: Box<dyn StdError + Send + Sync>| RenderError::Decode {
        path: None,
        format: "JPEG",
        source: e,
    };
    let options = DecoderOptions::default()
        .jpeg_set_out_colorspace(ColorSpace::RGBA)
        .set_max_width(usize::MAX)
        .set_max_height(usize::MAX);
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), options);
    decoder.decode_headers().map_err(|e| fail(Box::new(e)))?;
    let (w, h) = decoder
        .dimensions()
        .ok_or_else(|| fail("no image size in the headers".into()))?;
    let (width, height) = (
        u32::try_from(w).unwrap_or(u32::MAX),
        u32::try_from(h).unwrap_or(u32::MAX),
    );
    too_large(width, height, bytes.len())?;
    let pixels = decoder.decode().map_err(|e| fail(Box::new(e)))?;
    let channels = match decoder.output_colorspace() {
        Some(ColorSpace::RGBA) => 4,
        Some(ColorSpace::RGB) => 3,
        Some(ColorSpace::LumaA) => 2,
        Some(ColorSpace::Luma) => 1,
        other => {
            return Err(fail(
                format!("unsupported output colour space {other:?}").into(),
            ))
        }
    };
    if pixels.len() != w * h * channels {
        return Err(fail(
            format!(
                "decoder returned {} bytes for {w}x{h} pixels of {channels} channels",
                pixels.len()
            )
            .into(),
        ));
    }
    Ok(Image {
        width,
        height,
        rgba: to_rgba(&pixels, channels),
    })
}

/// Decodes a PNG or JPEG image (recognised by its first bytes) to RGBA: grey, palette and
/// 16-bit PNGs are converted; a PNG's transparency is kept.
///
/// # Errors
/// [`RenderError::UnknownFormat`] for other bytes, [`RenderError::Decode`] for damaged or
/// unsupported images, [`RenderError::TooLarge`] beyond 16384 pixels per side.
pub fn decode_image(bytes: &[u8]) -> Result<Image, RenderError> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        decode_png(bytes)
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        decode_jpeg(bytes)
    } else {
        Err(RenderError::UnknownFormat { path: None })
    }
}

/// Reads a PNG or JPEG file, as [`decode_image`].
///
/// # Errors
/// [`RenderError::Read`] when the file cannot be read; otherwise those of [`decode_image`],
/// naming the file.
pub fn read_image(path: impl AsRef<Path>) -> Result<Image, RenderError> {
    let path = path.as_ref();
    let bytes = crate::io::read_input(path, crate::io::MAX_INPUT_BYTES).map_err(|source| {
        RenderError::Read {
            path: path.to_path_buf(),
            source,
        }
    })?;
    decode_image(&bytes).map_err(|e| e.in_file(path))
}

/// Checks that every frame has the first one's size and a whole pixel buffer, in order, and
/// returns that size.
fn check_gif_frames(frames: &[Image]) -> Result<(u32, u32), RenderError> {
    let first = frames.first().ok_or(RenderError::Empty {
        what: "an animation needs at least one frame",
    })?;
    let (width, height) = (first.width, first.height);
    for (index, f) in frames.iter().enumerate() {
        check_gif_frame(f, index, width, height)?;
    }
    Ok((width, height))
}

/// Checks that frame `index` is `width` x `height` pixels with a whole pixel buffer (every
/// animation encoder's check of a frame pushed).
pub(super) fn check_gif_frame(
    f: &Image,
    index: usize,
    width: u32,
    height: u32,
) -> Result<(), RenderError> {
    if (f.width, f.height) != (width, height) {
        return Err(RenderError::FrameSize {
            index,
            width: f.width,
            height: f.height,
            first_width: width,
            first_height: height,
        });
    }
    check_buffer(f)
}

/// A frame quantised to its own palette and LZW-compressed, ready to be written: what one
/// frame of an animation costs after it is encoded.
fn gif_frame(f: &Image, w: u16, h: u16, delay_centiseconds: u16) -> gif::Frame<'static> {
    let mut pixels = f.rgba.clone();
    let mut frame = gif::Frame::from_rgba_speed(w, h, &mut pixels, 10);
    frame.delay = delay_centiseconds;
    frame.make_lzw_pre_encoded();
    frame
}

/// Where a [`GifEncoder`] is: waiting for its first frame (nothing written yet), writing, or
/// stopped by a failed write.
enum GifState<W: Write> {
    Waiting(W),
    Writing(gif::Encoder<W>),
    Failed,
}

/// An animated GIF written frame by frame to a [`Write`] sink, so that an animation of any
/// length holds only the frames in hand, never all of them: the same file as [`encode_gif`]
/// (byte for byte) for the same frames and delay, whichever way they are pushed.
///
/// Each frame gets its own palette (exact when it has at most 256 colours, otherwise
/// quantised with NeuQuant) and is LZW-compressed on its own, then written at once; fully
/// transparent pixels stay transparent; the animation loops forever, each frame shown for
/// the delay given at creation. [`push_batch`](GifEncoder::push_batch) quantises and
/// compresses a batch of frames in parallel on rayon's pool and writes them in order (the
/// bytes do not depend on the batch sizes or the number of threads).
///
/// Nothing is written before the first frame. Frames of another size than the encoder's,
/// or with a malformed pixel buffer, are refused before anything of them is encoded, and the
/// encoder goes on. A failed write leaves the file incomplete: the encoder then refuses more
/// frames ([`RenderError::Incomplete`]). Dropping the encoder without
/// [`finish`](GifEncoder::finish) ends the file as `finish` does, ignoring write errors.
///
/// ```
/// use bdmorph::render::raster::{self, GifEncoder};
/// use bdmorph::render::Image;
///
/// let frame = |grey: u8| Image { width: 8, height: 4, rgba: [grey, grey, grey, 255].repeat(32) };
/// let mut encoder = GifEncoder::new(Vec::new(), 8, 4, 10)?;
/// for i in 0..3 {
///     encoder.push(&frame(80 * i))?;
/// }
/// let bytes = encoder.finish()?;
/// assert!(bytes.starts_with(b"GIF89a"));
/// let frames: Vec<Image> = (0..3).map(|i| frame(80 * i)).collect();
/// assert_eq!(bytes, raster::encode_gif(&frames, 10)?);
/// # Ok::<(), raster::RenderError>(())
/// ```
pub struct GifEncoder<W: Write> {
    state: GifState<W>,
    width: u32,
    height: u32,
    w: u16,
    h: u16,
    delay_centiseconds: u16,
    frames: usize,
}

impl<W: Write> GifEncoder<W> {
    /// An encoder of `width` x `height` frames, each shown for `delay_centiseconds`
    /// (viewers tend to treat 0 and 1 as 10), writing to `sink`. Nothing is written yet.
    ///
    /// # Errors
    /// [`RenderError::Empty`] for frames without pixels (a zero side),
    /// [`RenderError::TooLargeForFormat`] beyond 65535 pixels per side.
    ///
    /// ```
    /// use bdmorph::render::raster::{GifEncoder, RenderError};
    ///
    /// assert!(GifEncoder::new(Vec::new(), 640, 480, 4).is_ok());
    /// assert!(matches!(
    ///     GifEncoder::new(Vec::new(), 70_000, 10, 4),
    ///     Err(RenderError::TooLargeForFormat { .. })
    /// ));
    /// assert!(matches!(GifEncoder::new(Vec::new(), 0, 10, 4), Err(RenderError::Empty { .. })));
    /// ```
    pub fn new(
        sink: W,
        width: u32,
        height: u32,
        delay_centiseconds: u16,
    ) -> Result<GifEncoder<W>, RenderError> {
        if width == 0 || height == 0 {
            return Err(RenderError::Empty {
                what: "the frames have no pixels",
            });
        }
        let (Ok(w), Ok(h)) = (u16::try_from(width), u16::try_from(height)) else {
            return Err(RenderError::TooLargeForFormat {
                format: "GIF",
                width,
                height,
                max: u32::from(u16::MAX),
            });
        };
        Ok(GifEncoder {
            state: GifState::Waiting(sink),
            width,
            height,
            w,
            h,
            delay_centiseconds,
            frames: 0,
        })
    }

    /// Quantises, compresses and writes one frame (on the calling thread).
    ///
    /// # Errors
    /// [`RenderError::FrameSize`] for a frame of another size than the encoder's and
    /// [`RenderError::BadBuffer`] for a malformed one (nothing written; the encoder goes on),
    /// [`RenderError::Encode`] when writing fails, [`RenderError::Incomplete`] after an
    /// earlier failed write.
    ///
    /// ```
    /// use bdmorph::render::raster::{GifEncoder, RenderError};
    /// use bdmorph::render::Image;
    ///
    /// let white = |width, height| Image { width, height, rgba: vec![255; (width * height * 4) as usize] };
    /// let mut encoder = GifEncoder::new(Vec::new(), 4, 4, 10)?;
    /// encoder.push(&white(4, 4))?;
    /// let err = encoder.push(&white(4, 5)).unwrap_err();
    /// assert!(matches!(err, RenderError::FrameSize { index: 1, height: 5, first_height: 4, .. }));
    /// encoder.push(&white(4, 4))?;
    /// assert_eq!(encoder.frames(), 2);
    /// # Ok::<(), RenderError>(())
    /// ```
    pub fn push(&mut self, frame: &Image) -> Result<(), RenderError> {
        self.usable()?;
        check_gif_frame(frame, self.frames, self.width, self.height)?;
        let encoded = gif_frame(frame, self.w, self.h, self.delay_centiseconds);
        self.write(std::slice::from_ref(&encoded))
    }

    /// Quantises and compresses a batch of frames in parallel on rayon's pool, then writes
    /// them in order: the same bytes as pushing them one by one. The batch is checked
    /// whole first, so a bad frame refuses the batch before any of it is written.
    ///
    /// # Errors
    /// Those of [`push`](GifEncoder::push), for the first bad frame of the batch (its
    /// `index` counts every frame pushed before the batch).
    ///
    /// ```
    /// use bdmorph::render::raster::{self, GifEncoder};
    /// use bdmorph::render::Image;
    ///
    /// let frames: Vec<Image> = (0..5u8)
    ///     .map(|i| Image { width: 6, height: 6, rgba: [50 * i, 0, 0, 255].repeat(36) })
    ///     .collect();
    /// let mut encoder = GifEncoder::new(Vec::new(), 6, 6, 5)?;
    /// encoder.push_batch(&frames[..2])?;
    /// encoder.push_batch(&frames[2..])?;
    /// assert_eq!(encoder.finish()?, raster::encode_gif(&frames, 5)?);
    /// # Ok::<(), raster::RenderError>(())
    /// ```
    pub fn push_batch(&mut self, frames: &[Image]) -> Result<(), RenderError> {
        self.usable()?;
        for (i, f) in frames.iter().enumerate() {
            check_gif_frame(f, self.frames + i, self.width, self.height)?;
        }
        let (w, h, delay) = (self.w, self.h, self.delay_centiseconds);
        let encoded: Vec<gif::Frame<'static>> = frames
            .par_iter()
            .map(|f| gif_frame(f, w, h, delay))
            .collect();
        self.write(&encoded)
    }

    /// How many frames have been written.
    ///
    /// ```
    /// use bdmorph::render::raster::GifEncoder;
    ///
    /// let encoder = GifEncoder::new(std::io::sink(), 4, 4, 10)?;
    /// assert_eq!(encoder.frames(), 0);
    /// # Ok::<(), bdmorph::render::raster::RenderError>(())
    /// ```
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Ends the file (its trailer) and returns the sink.
    ///
    /// # Errors
    /// [`RenderError::Empty`] when no frame was pushed (nothing was written),
    /// [`RenderError::Encode`] when writing fails, [`RenderError::Incomplete`] after an
    /// earlier failed write.
    ///
    /// ```
    /// use bdmorph::render::raster::{GifEncoder, RenderError};
    /// use bdmorph::render::Image;
    ///
    /// let empty = GifEncoder::new(Vec::new(), 4, 4, 10)?;
    /// assert!(matches!(empty.finish(), Err(RenderError::Empty { .. })));
    ///
    /// let mut encoder = GifEncoder::new(Vec::new(), 4, 4, 10)?;
    /// encoder.push(&Image { width: 4, height: 4, rgba: vec![0; 64] })?;
    /// let bytes = encoder.finish()?;
    /// assert_eq!(bytes.last(), Some(&b';'));
    /// # Ok::<(), RenderError>(())
    /// ```
    pub fn finish(self) -> Result<W, RenderError> {
        match self.state {
            GifState::Waiting(_) => Err(RenderError::Empty {
                what: "an animation needs at least one frame",
            }),
            GifState::Writing(encoder) => encoder.into_inner().map_err(gif_error),
            GifState::Failed => Err(RenderError::Incomplete { format: "GIF" }),
        }
    }

    fn usable(&self) -> Result<(), RenderError> {
        match self.state {
            GifState::Failed => Err(RenderError::Incomplete { format: "GIF" }),
            _ => Ok(()),
        }
    }

    /// Writes encoded frames in order (the header first, before the first frame); a failure
    /// stops the encoder.
    fn write(&mut self, encoded: &[gif::Frame<'static>]) -> Result<(), RenderError> {
        if encoded.is_empty() {
            return Ok(());
        }
        let mut encoder = match std::mem::replace(&mut self.state, GifState::Failed) {
            GifState::Waiting(sink) => {
                let mut encoder =
                    gif::Encoder::new(sink, self.w, self.h, &[]).map_err(gif_error)?;
                encoder
                    .set_repeat(gif::Repeat::Infinite)
                    .map_err(gif_error)?;
                encoder
            }
            GifState::Writing(encoder) => encoder,
            GifState::Failed => return Err(RenderError::Incomplete { format: "GIF" }),
        };
        for frame in encoded {
            encoder
                .write_lzw_pre_encoded_frame(frame)
                .map_err(gif_error)?;
            self.frames += 1;
        }
        self.state = GifState::Writing(encoder);
        Ok(())
    }
}

fn gif_error(e: gif::EncodingError) -> RenderError {
    encode_error("GIF")(Box::new(e))
}

/// Encodes frames as an animated GIF that loops forever, each shown for
/// `delay_centiseconds` (viewers tend to treat 0 and 1 as 10). Each frame gets its own
/// palette: exact when it has at most 256 colours, otherwise quantised (NeuQuant).
/// Fully transparent pixels stay transparent.
///
/// Every frame is checked before any is encoded; then all are encoded in parallel as one
/// batch of a [`GifEncoder`], which makes animations frame by frame without holding them
/// all.
///
/// # Errors
/// [`RenderError::Empty`] without frames or for frames without pixels,
/// [`RenderError::FrameSize`] when frames differ in size, [`RenderError::TooLargeForFormat`]
/// beyond 65535 pixels per side, [`RenderError::BadBuffer`] for a malformed frame.
///
/// ```
/// use bdmorph::render::{raster, Image};
///
/// let frames: Vec<Image> = (0..4u8)
///     .map(|i| Image { width: 10, height: 10, rgba: [60 * i, 90, 200, 255].repeat(100) })
///     .collect();
/// let gif = raster::encode_gif(&frames, 8)?;
/// assert!(gif.starts_with(b"GIF89a"));
/// assert!(matches!(raster::encode_gif(&[], 8), Err(raster::RenderError::Empty { .. })));
/// # Ok::<(), raster::RenderError>(())
/// ```
pub fn encode_gif(frames: &[Image], delay_centiseconds: u16) -> Result<Vec<u8>, RenderError> {
    let (width, height) = check_gif_frames(frames)?;
    let mut encoder = GifEncoder::new(Vec::new(), width, height, delay_centiseconds)?;
    encoder.push_batch(frames)?;
    encoder.finish()
}

/// A contact sheet: the frames tiled left to right, `columns` per row (at least 1, at most
/// the number of frames), top to bottom, separated by 4 px of white. Each cell is as large as
/// the largest frame; smaller frames sit at its top left. No frames give an empty image.
/// Frames whose buffer does not match their size are drawn as far as their rows go.
///
/// # Panics
/// When the sheet would be more than `u32::MAX` pixels wide or tall.
pub fn strip(frames: &[Image], columns: usize) -> Image {
    if frames.is_empty() {
        return Image {
            width: 0,
            height: 0,
            rgba: Vec::new(),
        };
    }
    let columns = columns.clamp(1, frames.len());
    let rows = frames.len().div_ceil(columns);
    let cell_w = frames.iter().map(|f| f.width).max().unwrap_or(0) as usize;
    let cell_h = frames.iter().map(|f| f.height).max().unwrap_or(0) as usize;
    let gap = STRIP_GAP as usize;
    let width = columns * cell_w + (columns - 1) * gap;
    let height = rows * cell_h + (rows - 1) * gap;
    let too_big = "contact sheet larger than u32::MAX pixels per side";
    let (sheet_w, sheet_h) = (
        u32::try_from(width).expect(too_big),
        u32::try_from(height).expect(too_big),
    );
    let mut rgba = vec![255u8; width * height * 4];
    for (i, f) in frames.iter().enumerate() {
        let (x0, y0) = (
            (i % columns) * (cell_w + gap),
            (i / columns) * (cell_h + gap),
        );
        let row_bytes = f.width as usize * 4;
        if row_bytes == 0 {
            continue;
        }
        for (y, line) in f
            .rgba
            .chunks_exact(row_bytes)
            .take(f.height as usize)
            .enumerate()
        {
            let start = ((y0 + y) * width + x0) * 4;
            rgba[start..start + row_bytes].copy_from_slice(line);
        }
    }
    Image {
        width: sheet_w,
        height: sheet_h,
        rgba,
    }
}

/// Cross-fades two pictures of the same geometry drawn on a transparent background (`a` and
/// `b`, the same size, not premultiplied): `weight` of `b` (clamped to [0, 1]) over
/// `1 - weight` of `a`, mixed in premultiplied space (so a pixel only one of them covers
/// fades rather than darkens), then laid on `background`. Two textures of one mesh cross-fade
/// this way: in-betweens of two drawings. Pictures of different sizes give `a` unchanged.
///
/// ```
/// use bdmorph::render::{raster::crossfade, Background, Image};
/// let a = Image { width: 1, height: 1, rgba: vec![255, 0, 0, 255] };
/// let b = Image { width: 1, height: 1, rgba: vec![0, 0, 255, 255] };
/// let mid = crossfade(&a, &b, 0.5, Background::Transparent);
/// assert_eq!(mid.rgba, vec![128, 0, 128, 255]);
/// let on_white = crossfade(&a, &Image { width: 1, height: 1, rgba: vec![0; 4] }, 0.5, Background::WHITE);
/// assert_eq!(on_white.rgba, vec![255, 128, 128, 255]);
/// ```
pub fn crossfade(a: &Image, b: &Image, weight: f64, background: Background) -> Image {
    if a.width != b.width || a.height != b.height || a.rgba.len() != b.rgba.len() {
        return a.clone();
    }
    let w = if weight.is_nan() {
        0.0
    } else {
        weight.clamp(0.0, 1.0)
    };
    let mut rgba = Vec::with_capacity(a.rgba.len());
    for (p, q) in a.rgba.chunks_exact(4).zip(b.rgba.chunks_exact(4)) {
        let (ap, aq) = (f64::from(p[3]) / 255.0, f64::from(q[3]) / 255.0);
        let alpha = (1.0 - w) * ap + w * aq;
        let mut px = [0u8; 4];
        for c in 0..3 {
            let premul = (1.0 - w) * ap * f64::from(p[c]) + w * aq * f64::from(q[c]);
            px[c] = match background {
                Background::Colour(bg) => premul + (1.0 - alpha) * f64::from(bg[c]),
                Background::Transparent if alpha > 0.0 => premul / alpha,
                Background::Transparent => 0.0,
            }
            .round()
            .clamp(0.0, 255.0) as u8;
        }
        px[3] = match background {
            Background::Colour(_) => 255,
            Background::Transparent => (255.0 * alpha).round().clamp(0.0, 255.0) as u8,
        };
        rgba.extend(px);
    }
    Image {
        width: a.width,
        height: a.height,
        rgba,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit square as two counter-clockwise triangles.
    fn square() -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        (
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    /// Shows `[-0.25, 1.25]^2`: the unit square covers pixels 10.67 to 53.33 of a 64x64 image.
    const VIEW: Viewport = Viewport {
        min: [-0.25, -0.25],
        max: [1.25, 1.25],
    };
    const SIZE: ImageSize = ImageSize {
        width: 64,
        height: 64,
    };

    fn px(img: &Image, x: u32, y: u32) -> [u8; 4] {
        let i = ((y * img.width + x) * 4) as usize;
        img.rgba[i..i + 4].try_into().unwrap()
    }

    fn near(got: [u8; 4], rgb: [u8; 3], tol: u8) -> bool {
        (0..3).all(|c| got[c].abs_diff(rgb[c]) <= tol) && got[3] == 255
    }

    fn lum(p: [u8; 4]) -> u32 {
        u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2])
    }

    /// The pixel containing world point `p`.
    fn pixel_of(view: &Viewport, size: ImageSize, p: [f64; 2]) -> (u32, u32) {
        let (s, ox, oy) = view.transform(size);
        ((ox + s * p[0]) as u32, (oy - s * p[1]) as u32)
    }

    fn plain(faces: &[[u32; 3]]) -> Drawing<'_> {
        Drawing {
            faces,
            corner_uv: None,
            texture: None,
            face_colours: None,
            depth: None,
        }
    }

    #[test]
    fn square_is_filled_inside_white_outside_with_darker_edges() {
        let (pos, faces) = square();
        let img = render(&pos, &plain(&faces), &VIEW, SIZE).unwrap();
        assert_eq!(
            (img.width, img.height, img.rgba.len()),
            (64, 64, 64 * 64 * 4)
        );
        // Inside, away from the edges and the diagonal (x + y = 64 in pixels).
        for (x, y) in [(20, 20), (44, 44), (16, 30), (30, 16)] {
            assert!(
                near(px(&img, x, y), FILL, 2),
                "({x},{y}) {:?}",
                px(&img, x, y)
            );
        }
        // Outside.
        for (x, y) in [(2, 2), (60, 32), (32, 61), (5, 58)] {
            assert_eq!(px(&img, x, y), [255; 4], "({x},{y})");
        }
        // On the left boundary (x = 10.67), and on the shared diagonal.
        let fill = lum([FILL[0], FILL[1], FILL[2], 255]);
        for (x, y) in [(10, 32), (31, 32), (32, 31)] {
            let p = px(&img, x, y);
            assert!(
                lum(p) + 120 < fill,
                "({x},{y}) {p:?} is not darker than the fill"
            );
        }
    }

    #[test]
    fn flipped_triangles_are_red() {
        let (pos, _) = square();
        // Clockwise in world coordinates, and a degenerate one.
        let faces = [[0, 2, 1], [0, 0, 3]];
        let img = render(&pos, &plain(&faces), &VIEW, SIZE).unwrap();
        let (x, y) = pixel_of(&VIEW, SIZE, [0.7, 0.3]);
        assert!(near(px(&img, x, y), FLIPPED, 2), "{:?}", px(&img, x, y));
        // The other half of the square is empty.
        let (x, y) = pixel_of(&VIEW, SIZE, [0.3, 0.7]);
        assert_eq!(px(&img, x, y), [255; 4]);
    }

    #[test]
    fn world_y_up_is_image_up() {
        let pos = [[-1.0, 0.1], [1.0, 0.1], [0.0, 1.0]];
        let faces = [[0, 1, 2]];
        let view = Viewport {
            min: [-1.0, -1.0],
            max: [1.0, 1.0],
        };
        let img = render(&pos, &plain(&faces), &view, SIZE).unwrap();
        let inked = |rows: std::ops::Range<u32>| {
            rows.flat_map(|y| (0..64).map(move |x| (x, y)))
                .filter(|&(x, y)| px(&img, x, y) != [255; 4])
                .count()
        };
        assert!(inked(0..30) > 300);
        assert_eq!(inked(32..64), 0);
    }

    /// Bounding box `(width, height)` of the non-white pixels.
    fn ink_extent(img: &Image) -> (u32, u32) {
        let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
        for y in 0..img.height {
            for x in 0..img.width {
                if px(img, x, y) != [255; 4] {
                    (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
                }
            }
        }
        (x1 + 1 - x0, y1 + 1 - y0)
    }

    #[test]
    fn odd_aspect_ratios_keep_a_square_square() {
        let (pos, faces) = square();
        let view = Viewport::fit([&pos[..]]);
        for (w, h) in [(120, 50), (50, 120), (97, 33)] {
            let size = ImageSize {
                width: w,
                height: h,
            };
            let img = render(&pos, &plain(&faces), &view, size).unwrap();
            let (ew, eh) = ink_extent(&img);
            assert!(ew.abs_diff(eh) <= 1, "{w}x{h}: square drawn {ew}x{eh}");
            assert!(ew >= w.min(h) * 8 / 10, "{w}x{h}: square drawn {ew}x{eh}");
        }
    }

    /// A 2x2 texture: red top left, green top right, blue bottom left, white bottom right.
    fn quadrants() -> Image {
        Image {
            width: 2,
            height: 2,
            rgba: vec![
                255, 0, 0, 255, 0, 255, 0, 255, //
                0, 0, 255, 255, 255, 255, 255, 255,
            ],
        }
    }

    #[test]
    fn texture_quadrants_land_in_the_right_place() {
        let (pos, faces) = square();
        // uv = position: (0, 0) is the texture's bottom left.
        let uv: Vec<[[f64; 2]; 3]> = faces.iter().map(|f| f.map(|i| pos[i as usize])).collect();
        let texture = quadrants();
        let drawing = Drawing {
            faces: &faces,
            corner_uv: Some(&uv),
            texture: Some(&texture),
            face_colours: None,
            depth: None,
        };
        let img = render(&pos, &drawing, &VIEW, SIZE).unwrap();
        for (p, rgb) in [
            ([0.25, 0.75], [255, 0, 0]),
            ([0.75, 0.75], [0, 255, 0]),
            ([0.25, 0.25], [0, 0, 255]),
            ([0.75, 0.25], [255, 255, 255]),
        ] {
            let (x, y) = pixel_of(&VIEW, SIZE, p);
            assert!(near(px(&img, x, y), rgb, 16), "{p:?}: {:?}", px(&img, x, y));
        }
        // Texture only: no edge lines, outside stays white.
        assert_eq!(px(&img, 2, 2), [255; 4]);
    }

    #[test]
    fn textured_triangles_leave_no_seam() {
        let (pos, faces) = square();
        let uv: Vec<[[f64; 2]; 3]> = faces.iter().map(|f| f.map(|i| pos[i as usize])).collect();
        let grey = Image {
            width: 1,
            height: 1,
            rgba: vec![90, 120, 150, 255],
        };
        let drawing = Drawing {
            faces: &faces,
            corner_uv: Some(&uv),
            texture: Some(&grey),
            face_colours: None,
            depth: None,
        };
        let img = render(&pos, &drawing, &VIEW, SIZE).unwrap();
        // Every pixel with its centre inside the square, the diagonal included, is the
        // texture's colour exactly.
        let (s, ox, oy) = VIEW.transform(SIZE);
        for y in 0..64 {
            for x in 0..64 {
                let wx = (f64::from(x) + 0.5 - ox) / s;
                let wy = (oy - f64::from(y) - 0.5) / s;
                if (0.02..0.98).contains(&wx) && (0.02..0.98).contains(&wy) {
                    assert_eq!(px(&img, x, y), [90, 120, 150, 255], "({x},{y})");
                }
            }
        }
    }

    #[test]
    fn bad_faces_and_empty_sizes_do_not_panic() {
        let pos = [[0.0, 0.0], [1.0, 0.0], [f64::NAN, 1.0]];
        let faces = [[0, 1, 2], [0, 1, 7]];
        let img = render(&pos, &plain(&faces), &VIEW, SIZE).unwrap();
        assert!(img.rgba.iter().all(|&b| b == 255));
        let empty = render(
            &pos,
            &plain(&faces),
            &VIEW,
            ImageSize {
                width: 0,
                height: 5,
            },
        )
        .unwrap();
        assert!(empty.rgba.is_empty());
        assert!(matches!(encode_png(&empty), Err(RenderError::Empty { .. })));
    }

    fn noise(width: u32, height: u32, seed: u32) -> Image {
        let mut state = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
        let rgba = (0..width * height * 4)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 17;
                state ^= state << 5;
                (state >> 24) as u8
            })
            .collect();
        Image {
            width,
            height,
            rgba,
        }
    }

    #[test]
    fn png_round_trips_exactly() {
        let (pos, faces) = square();
        let img = render(&pos, &plain(&faces), &VIEW, SIZE).unwrap();
        let bytes = encode_png(&img).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"));
        assert_eq!(decode_image(&bytes).unwrap(), img);
        // Transparency and arbitrary values survive too.
        let img = noise(7, 3, 1);
        assert_eq!(decode_image(&encode_png(&img).unwrap()).unwrap(), img);
    }

    #[test]
    fn grey_pngs_widen_to_rgba() {
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, 2, 1);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(&[10, 200]).unwrap();
        writer.finish().unwrap();
        let img = decode_image(&bytes).unwrap();
        assert_eq!(img.rgba, vec![10, 10, 10, 255, 200, 200, 200, 255]);
    }

    /// A baseline greyscale JPEG of 16x8 pixels: two flat 8x8 blocks, grey 64 then 192,
    /// written bit by bit (DC coefficients only, quantisation 1).
    fn two_block_jpeg() -> Vec<u8> {
        let mut out = vec![0xff, 0xd8];
        // Quantisation table 0: all ones.
        out.extend([0xff, 0xdb, 0, 67, 0]);
        out.extend([1u8; 64]);
        // Frame: 8 bits, height 8, width 16, one component (id 1, 1x1, table 0).
        out.extend([0xff, 0xc0, 0, 11, 8, 0, 8, 0, 16, 1, 1, 0x11, 0]);
        // DC table 0: two codes of length 2, categories 10 ("00") and 11 ("01").
        out.extend([0xff, 0xc4, 0, 21, 0x00, 0, 2]);
        out.extend([0u8; 14]);
        out.extend([10, 11]);
        // AC table 0: one code of length 1, end of block ("0").
        out.extend([0xff, 0xc4, 0, 20, 0x10, 1]);
        out.extend([0u8; 15]);
        out.extend([0x00]);
        // Scan header.
        out.extend([0xff, 0xda, 0, 8, 1, 1, 0x00, 0, 63, 0]);
        // DC of a flat block of grey g is 8 (g - 128): -512, then a difference of +1024.
        // -512 in category 10 is written as 511; +1024 in category 11 as itself.
        let bits = format!("00{:010b}0", 511) + &format!("01{:011b}0", 1024);
        let padded = format!("{bits:1<32}");
        for chunk in padded.as_bytes().chunks(8) {
            let byte = u8::from_str_radix(std::str::from_utf8(chunk).unwrap(), 2).unwrap();
            out.push(byte);
            if byte == 0xff {
                out.push(0);
            }
        }
        out.extend([0xff, 0xd9]);
        out
    }

    #[test]
    fn jpegs_decode_to_rgba() {
        let img = decode_image(&two_block_jpeg()).unwrap();
        assert_eq!((img.width, img.height), (16, 8));
        assert!(
            near(px(&img, 3, 4), [64, 64, 64], 2),
            "{:?}",
            px(&img, 3, 4)
        );
        assert!(
            near(px(&img, 12, 4), [192, 192, 192], 2),
            "{:?}",
            px(&img, 12, 4)
        );
    }

    #[test]
    fn decode_errors_are_one_line_and_name_the_file() {
        let err = decode_image(b"GIF89a...").unwrap_err();
        assert!(matches!(err, RenderError::UnknownFormat { path: None }));
        assert_eq!(err.to_string(), "not a PNG or JPEG image");

        let mut png = encode_png(&noise(4, 4, 2)).unwrap();
        png.truncate(png.len() - 20);
        let err = decode_image(&png).unwrap_err();
        assert!(
            matches!(err, RenderError::Decode { format: "PNG", .. }),
            "{err}"
        );

        let dir = std::env::temp_dir().join(format!("bdmorph-raster-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let missing = dir.join("missing.png");
        let err = read_image(&missing).unwrap_err();
        assert!(matches!(err, RenderError::Read { .. }));
        assert!(err
            .to_string()
            .starts_with(&format!("{}: cannot read", missing.display())));

        let bogus = dir.join("bogus.jpg");
        std::fs::write(&bogus, b"hello").unwrap();
        let err = read_image(&bogus).unwrap_err();
        assert_eq!(
            err.to_string(),
            format!("{}: not a PNG or JPEG image", bogus.display())
        );
        let damaged = dir.join("damaged.png");
        std::fs::write(&damaged, &png).unwrap();
        let message = read_image(&damaged).unwrap_err().to_string();
        assert!(message.starts_with(&format!("{}: cannot decode PNG image: ", damaged.display())));
        assert!(!message.contains('\n'));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn gif_loops_forever_with_every_frame() {
        let frames: Vec<Image> = (0..3).map(|i| noise(20, 10, i)).collect();
        let bytes = encode_gif(&frames, 7).unwrap();
        assert!(bytes.starts_with(b"GIF89a"));
        assert!(bytes.windows(11).any(|w| w == b"NETSCAPE2.0"));

        let mut options = gif::DecodeOptions::new();
        options.set_color_output(gif::ColorOutput::RGBA);
        let mut decoder = options.read_info(Cursor::new(&bytes)).unwrap();
        assert_eq!((decoder.width(), decoder.height()), (20, 10));
        let mut count = 0;
        while let Some(frame) = decoder.read_next_frame().unwrap() {
            assert_eq!((frame.width, frame.height, frame.delay), (20, 10, 7));
            count += 1;
        }
        assert_eq!(count, 3);
        assert_eq!(decoder.repeat(), gif::Repeat::Infinite);
    }

    #[test]
    fn gif_keeps_few_colours_exact() {
        let (pos, faces) = square();
        let img = render(&pos, &plain(&faces), &VIEW, SIZE).unwrap();
        let bytes = encode_gif(std::slice::from_ref(&img), 10).unwrap();
        let mut options = gif::DecodeOptions::new();
        options.set_color_output(gif::ColorOutput::RGBA);
        let mut decoder = options.read_info(Cursor::new(&bytes)).unwrap();
        let frame = decoder.read_next_frame().unwrap().unwrap();
        assert_eq!(&frame.buffer[..], &img.rgba[..]);
    }

    #[test]
    fn gif_refuses_mixed_sizes_and_no_frames() {
        let err = encode_gif(&[noise(4, 4, 0), noise(4, 5, 1)], 5).unwrap_err();
        assert!(matches!(
            err,
            RenderError::FrameSize {
                index: 1,
                height: 5,
                first_height: 4,
                ..
            }
        ));
        assert!(err.to_string().contains("4x5"));
        assert!(matches!(encode_gif(&[], 5), Err(RenderError::Empty { .. })));
        let mut broken = noise(4, 4, 0);
        broken.rgba.pop();
        assert!(matches!(
            encode_gif(&[broken], 5),
            Err(RenderError::BadBuffer {
                expected: 64,
                actual: 63,
                ..
            })
        ));
    }

    /// `encode_gif` as it was before `GifEncoder` (every frame checked, then all quantised
    /// and compressed in parallel, then written), to compare bytes with.
    fn encode_gif_whole(frames: &[Image], delay: u16) -> Vec<u8> {
        let (w, h) = (frames[0].width as u16, frames[0].height as u16);
        let mut out = Vec::new();
        let mut encoder = gif::Encoder::new(&mut out, w, h, &[]).unwrap();
        encoder.set_repeat(gif::Repeat::Infinite).unwrap();
        let encoded: Vec<gif::Frame<'static>> = frames
            .par_iter()
            .map(|f| {
                let mut pixels = f.rgba.clone();
                let mut frame = gif::Frame::from_rgba_speed(w, h, &mut pixels, 10);
                frame.delay = delay;
                frame.make_lzw_pre_encoded();
                frame
            })
            .collect();
        for frame in &encoded {
            encoder.write_lzw_pre_encoded_frame(frame).unwrap();
        }
        encoder.into_inner().unwrap();
        out
    }

    /// Frames of a few colours (exact palettes), of noise (quantised), and with transparent
    /// pixels.
    fn mixed_frames(count: u32, width: u32, height: u32) -> Vec<Image> {
        (0..count)
            .map(|i| match i % 3 {
                0 => noise(width, height, i),
                1 => {
                    let (pos, faces) = square();
                    let size = ImageSize { width, height };
                    let view = Viewport {
                        min: [-0.25 - 0.05 * f64::from(i), -0.25],
                        max: [1.25, 1.25 + 0.05 * f64::from(i)],
                    };
                    render(&pos, &plain(&faces), &view, size).unwrap()
                }
                _ => {
                    let mut img = noise(width, height, 100 + i);
                    for p in img.rgba.chunks_exact_mut(4).step_by(3) {
                        p[3] = 0;
                    }
                    img
                }
            })
            .collect()
    }

    #[test]
    fn streamed_gifs_are_the_whole_slice_bytes() {
        for (count, delay) in [(1, 10), (2, 0), (17, 7)] {
            let frames = mixed_frames(count, 37, 23);
            let old = encode_gif_whole(&frames, delay);
            assert_eq!(encode_gif(&frames, delay).unwrap(), old, "{count} frames");
            // One at a time.
            let mut one = GifEncoder::new(Vec::new(), 37, 23, delay).unwrap();
            for f in &frames {
                one.push(f).unwrap();
            }
            assert_eq!(one.frames(), frames.len());
            assert_eq!(
                one.finish().unwrap(),
                old,
                "{count} frames pushed one by one"
            );
            // Batches of uneven sizes, empty ones and single pushes among them.
            let mut batched = GifEncoder::new(Vec::new(), 37, 23, delay).unwrap();
            let mut rest = &frames[..];
            for size in [0, 1, 4, 0, 2, 7, 1].into_iter().cycle() {
                if rest.is_empty() {
                    break;
                }
                let (batch, tail) = rest.split_at(size.min(rest.len()));
                if batch.len() == 1 && size == 1 {
                    batched.push(&batch[0]).unwrap();
                } else {
                    batched.push_batch(batch).unwrap();
                }
                rest = tail;
            }
            assert_eq!(batched.finish().unwrap(), old, "{count} frames in batches");
        }
        // Into a writer that is not a Vec.
        let frames = mixed_frames(4, 16, 16);
        let mut encoder = GifEncoder::new(Cursor::new(Vec::new()), 16, 16, 3).unwrap();
        encoder.push_batch(&frames).unwrap();
        let bytes = encoder.finish().unwrap().into_inner();
        assert_eq!(bytes, encode_gif_whole(&frames, 3));
    }

    #[test]
    fn gif_encoder_refuses_bad_frames_and_goes_on() {
        let good = mixed_frames(3, 8, 6);
        // A frame of another size, even the first, is refused against the encoder's size.
        let mut encoder = GifEncoder::new(Vec::new(), 8, 6, 5).unwrap();
        let err = encoder.push(&noise(8, 7, 0)).unwrap_err();
        assert!(
            matches!(
                err,
                RenderError::FrameSize {
                    index: 0,
                    width: 8,
                    height: 7,
                    first_width: 8,
                    first_height: 6
                }
            ),
            "{err:?}"
        );
        assert_eq!(
            err.to_string(),
            "frame 0 is 8x7 pixels but the animation is 8x6; all frames must have one size"
        );
        encoder.push(&good[0]).unwrap();
        // A batch with a bad frame is refused whole, naming the frame by its place in the
        // animation; nothing of it is written.
        let mut broken = good[2].clone();
        broken.rgba.pop();
        let batch = [good[1].clone(), broken];
        assert!(matches!(
            encoder.push_batch(&batch),
            Err(RenderError::BadBuffer {
                expected: 192,
                actual: 191,
                ..
            })
        ));
        let batch = [good[1].clone(), noise(9, 6, 1)];
        assert!(matches!(
            encoder.push_batch(&batch),
            Err(RenderError::FrameSize {
                index: 2,
                width: 9,
                ..
            })
        ));
        assert_eq!(encoder.frames(), 1);
        encoder.push_batch(&good[1..]).unwrap();
        assert_eq!(encoder.finish().unwrap(), encode_gif_whole(&good, 5));

        // Nothing pushed: refused at the end, and nothing written.
        let mut sink = Vec::new();
        let encoder = GifEncoder::new(&mut sink, 8, 6, 5).unwrap();
        assert!(matches!(encoder.finish(), Err(RenderError::Empty { .. })));
        assert!(sink.is_empty());
        // Sizes GIF cannot hold.
        for (w, h) in [(0, 5), (5, 0), (0, 0)] {
            assert!(matches!(
                GifEncoder::new(Vec::new(), w, h, 5),
                Err(RenderError::Empty { .. })
            ));
        }
        assert!(matches!(
            GifEncoder::new(Vec::new(), 65536, 1, 5),
            Err(RenderError::TooLargeForFormat { width: 65536, .. })
        ));
        assert!(GifEncoder::new(Vec::new(), 65535, 1, 5).is_ok());
    }

    /// A sink that takes `room` bytes and then fails.
    struct Full {
        room: usize,
    }

    impl Write for Full {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            if self.room == 0 {
                return Err(std::io::Error::other("disk full"));
            }
            let n = buf.len().min(self.room);
            self.room -= n;
            Ok(n)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn gif_encoder_stops_after_a_failed_write() {
        let frames = mixed_frames(3, 12, 12);
        let whole = encode_gif_whole(&frames, 5).len();
        for room in [0, 5, 30, whole / 2, whole - 1] {
            let mut encoder = GifEncoder::new(Full { room }, 12, 12, 5).unwrap();
            let mut failed = false;
            for f in &frames {
                match encoder.push(f) {
                    Ok(()) => assert!(!failed, "a push after a failure must fail"),
                    Err(RenderError::Encode { format: "GIF", .. }) if !failed => failed = true,
                    Err(RenderError::Incomplete { format: "GIF" }) if failed => {}
                    Err(e) => panic!("room {room}: {e:?}"),
                }
            }
            let end = encoder.finish();
            assert!(end.is_err(), "room {room}: the file cannot be complete");
            if failed {
                assert!(matches!(end, Err(RenderError::Incomplete { .. })));
            }
        }
    }

    #[test]
    fn strip_tiles_frames_in_rows_with_white_gaps() {
        let frames: Vec<Image> = (0..5)
            .map(|i| Image {
                width: 10,
                height: 8,
                rgba: [i as u8 * 40, 0, 0, 255].repeat(80),
            })
            .collect();
        let sheet = strip(&frames, 3);
        assert_eq!((sheet.width, sheet.height), (3 * 10 + 2 * 4, 2 * 8 + 4));
        assert_eq!(sheet.rgba.len(), (sheet.width * sheet.height * 4) as usize);
        // Frame 4 is the second of the second row; the gap and the missing sixth are white.
        assert_eq!(px(&sheet, 14 + 5, 12 + 3), [160, 0, 0, 255]);
        assert_eq!(px(&sheet, 11, 3), [255; 4]);
        assert_eq!(px(&sheet, 5, 9), [255; 4]);
        assert_eq!(px(&sheet, 28 + 5, 12 + 3), [255; 4]);
        // One column, and more columns than frames.
        assert_eq!(
            (strip(&frames, 0).width, strip(&frames, 0).height),
            (10, 5 * 8 + 4 * 4)
        );
        assert_eq!(strip(&frames, 9).width, 5 * 10 + 4 * 4);
        assert_eq!(strip(&[], 3).rgba.len(), 0);
    }

    /// A PNG whose header claims `width` x `height` pixels, with `padding` bytes of a private
    /// ancillary chunk (which decoders skip) and a little image data: as large on disk as a
    /// real picture of that size may be.
    fn png_claiming(width: u32, height: u32, padding: usize) -> Vec<u8> {
        let mut out = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut out, width, height);
            encoder.set_color(png::ColorType::Rgba);
            encoder.set_depth(png::BitDepth::Eight);
            let mut writer = encoder.write_header().unwrap();
            writer
                .write_chunk(png::chunk::ChunkType(*b"prIv"), &vec![0; padding])
                .unwrap();
            // A stored zlib block of 16 zero bytes.
            let mut idat = vec![0x78, 0x01, 1, 16, 0, !16, 0xff];
            idat.extend_from_slice(&[0; 16]);
            idat.extend_from_slice(&[0, 16, 0, 1]);
            writer.write_chunk(png::chunk::IDAT, &idat).unwrap();
        }
        out
    }

    #[test]
    fn a_picture_over_the_pixel_budget_is_refused_before_it_is_decoded() {
        // 16000 x 16000 in a megabyte: a real file of that size could hold it (no "claims").
        let bytes = png_claiming(16_000, 16_000, 1 << 20);
        let err = decode_image(&bytes).unwrap_err();
        assert!(
            matches!(err, RenderError::OverBudget { width: 16_000, .. }),
            "{err:?}"
        );
        let message = err.to_string();
        assert!(message.contains("16000x16000"), "{message}");
        assert!(
            message.contains(&super::super::MAX_PIXELS.to_string()),
            "{message}"
        );
        // Just over the budget, in a square of 8193: refused; the budget's own square is not
        // refused for its size (it fails later, on its missing pixels).
        let over = decode_image(&png_claiming(8193, 8193, 1 << 19)).unwrap_err();
        assert!(matches!(over, RenderError::OverBudget { .. }), "{over:?}");
        let at = decode_image(&png_claiming(8192, 8192, 1 << 19)).unwrap_err();
        assert!(matches!(at, RenderError::Decode { .. }), "{at:?}");
    }

    #[test]
    fn render_refuses_a_size_over_the_budget_without_allocating_it() {
        let pos = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let faces = [[0, 1, 2]];
        for (width, height) in [(100_000, 100_000), (16384, 16384), (16385, 1), (8193, 8192)] {
            let size = ImageSize { width, height };
            let err = render(&pos, &plain(&faces), &VIEW, size).unwrap_err();
            assert!(
                matches!(err, RenderError::OverBudget { width: w, height: h, path: None } if (w, h) == (width, height)),
                "{err:?}"
            );
            let err = render_on(&pos, &plain(&faces), &VIEW, size, Background::Transparent);
            assert!(err.is_err());
            assert!(size.check().is_err());
        }
        let size = ImageSize {
            width: 8192,
            height: 16,
        };
        assert_eq!(
            render(&pos, &plain(&faces), &VIEW, size).unwrap().width,
            8192
        );
        assert!("16384x16384".parse::<ImageSize>().is_err());
        assert!("16384x4096".parse::<ImageSize>().is_ok());
    }
}
