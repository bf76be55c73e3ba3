//! Pictures of a scalar field (a distance, say) on a 3D triangle mesh: an orthographic view,
//! triangles coloured by the field (viridis, from 0 to the largest finite value), lit softly
//! so the shape reads, with isolines at round intervals.
//!
//! The view looks along the mesh's direction of least extent (the principal axis of smallest
//! variance), so a disk-like surface is seen face on. Triangles are drawn back to front
//! (painter's algorithm) with their isolines, so hidden parts stay hidden.
//!
//! ```
//! use bdmorph::generate;
//! use bdmorph::render::{surface, ImageSize};
//! let sphere = generate::icosphere(2);
//! let height: Vec<f64> = sphere.positions.iter().map(|p| p[2] + 1.0).collect();
//! let size = ImageSize { width: 120, height: 100 };
//! let image = surface::render_field(&sphere.positions, &sphere.faces, &height, size)?;
//! assert_eq!((image.width, image.height), (120, 100));
//! # Ok::<(), bdmorph::render::raster::RenderError>(())
//! ```

use tiny_skia::{Color, FillRule, LineCap, Paint, PathBuilder, Pixmap, Stroke, Transform};

use super::colour::shade_colour;
use super::raster::{check_budget, RenderError};
use super::{Image, ImageSize};
use crate::vec3::{cross, dot};

/// Colour of isolines.
const ISOLINE: [u8; 3] = [0x20, 0x20, 0x20];
/// Colour of triangles whose field is not finite (unreachable vertices).
const UNREACHED: [u8; 3] = [0xc8, 0xc8, 0xc8];

/// The spacing of isolines for values up to `max`: about 20 lines, at 1, 2 or 5 times a
/// power of ten.
pub fn isoline_spacing(max: f64) -> f64 {
    if !(max > 0.0 && max.is_finite()) {
        return 1.0;
    }
    let raw = max / 20.0;
    let power = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .find(|m| m * power >= raw)
        .unwrap_or(10.0);
    step * power
}

/// An orthonormal frame `[right, up, towards the viewer]` looking along the mesh's axis of
/// least extent, and the centroid.
fn view_frame(positions: &[[f64; 3]]) -> ([[f64; 3]; 3], [f64; 3]) {
    let n = positions.len().max(1) as f64;
    let mut c = [0.0; 3];
    for p in positions {
        for k in 0..3 {
            c[k] += p[k] / n;
        }
    }
    let mut cov = [[0.0; 3]; 3];
    for p in positions {
        let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += d[i] * d[j];
            }
        }
    }
    // Principal axes by Jacobi rotations on the symmetric 3x3 covariance.
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if cov[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = 0.5 * (2.0 * cov[p][q]).atan2(cov[q][q] - cov[p][p]);
            let (s, co) = theta.sin_cos();
            for row in cov.iter_mut() {
                let (a, b) = (row[p], row[q]);
                row[p] = co * a - s * b;
                row[q] = s * a + co * b;
            }
            let (rp, rq) = (cov[p], cov[q]);
            cov[p] = std::array::from_fn(|k| co * rp[k] - s * rq[k]);
            cov[q] = std::array::from_fn(|k| s * rp[k] + co * rq[k]);
            for row in v.iter_mut() {
                let (a, b) = (row[p], row[q]);
                row[p] = co * a - s * b;
                row[q] = s * a + co * b;
            }
        }
    }
    let axis = |k: usize| [v[0][k], v[1][k], v[2][k]];
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| cov[b][b].total_cmp(&cov[a][a]));
    let (right, up) = (axis(order[0]), axis(order[1]));
    let towards = cross(right, up);
    ([right, up, towards], c)
}

/// Draws the field `values` (one per vertex) on the mesh as an image of `size` on white: see
/// [the module](self). Faces naming missing vertices are skipped; triangles with a
/// non-finite value are grey.
///
/// # Errors
/// [`RenderError::OverBudget`] for a size over [`super::MAX_PIXELS`] pixels, before anything
/// is allocated.
pub fn render_field(
    positions: &[[f64; 3]],
    faces: &[[u32; 3]],
    values: &[f64],
    size: ImageSize,
) -> Result<Image, RenderError> {
    check_budget(size.width, size.height)?;
    let n = positions.len().min(values.len());
    let max = values[..n]
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let colour = |f: &[u32; 3]| {
        let mean = f.iter().map(|&v| values[v as usize]).sum::<f64>() / 3.0;
        if mean.is_finite() {
            let s = if max > 0.0 {
                (255.0 * mean / max).round().clamp(0.0, 255.0)
            } else {
                0.0
            };
            shade_colour(s as u8)
        } else {
            UNREACHED
        }
    };
    Ok(draw(
        positions,
        faces,
        n,
        &colour,
        Some((values, isoline_spacing(max))),
        size,
    ))
}

/// The mesh textured with a checkerboard through the map `uv` (one 2D point per vertex):
/// 16 squares across the map's longer side, each triangle coloured by the square its
/// centroid maps into. Squares that stay square on the surface mean a map without
/// distortion; triangles the map inverts are red.
///
/// # Errors
/// [`RenderError::OverBudget`] for a size over [`super::MAX_PIXELS`] pixels, before anything
/// is allocated.
pub fn render_checker(
    positions: &[[f64; 3]],
    faces: &[[u32; 3]],
    uv: &[[f64; 2]],
    size: ImageSize,
) -> Result<Image, RenderError> {
    check_budget(size.width, size.height)?;
    let n = positions.len().min(uv.len());
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &uv[..n] {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let cell = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-300) / 16.0;
    let colour = |f: &[u32; 3]| {
        let [a, b, c] = f.map(|v| uv[v as usize]);
        let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        if det.is_nan() || det <= 0.0 {
            return [0xe0, 0x50, 0x50];
        }
        let cx = ((a[0] + b[0] + c[0]) / 3.0 - lo[0]) / cell;
        let cy = ((a[1] + b[1] + c[1]) / 3.0 - lo[1]) / cell;
        if (cx.floor() as i64 + cy.floor() as i64).rem_euclid(2) == 0 {
            [60, 90, 150]
        } else {
            [235, 238, 245]
        }
    };
    Ok(draw(positions, faces, n, &colour, None, size))
}

/// Draws the faces (those whose vertices are all below `n`) in `colour`, lit, back to front,
/// with isolines of `field` at multiples of its spacing when given.
fn draw(
    positions: &[[f64; 3]],
    faces: &[[u32; 3]],
    n: usize,
    colour: &dyn Fn(&[u32; 3]) -> [u8; 3],
    field: Option<(&[f64], f64)>,
    size: ImageSize,
) -> Image {
    let blank = || Image {
        width: size.width,
        height: size.height,
        rgba: vec![255; size.width as usize * size.height as usize * 4],
    };
    let Some(mut pixmap) = Pixmap::new(size.width, size.height) else {
        return blank();
    };
    pixmap.fill(Color::WHITE);
    let faces: Vec<[u32; 3]> = faces
        .iter()
        .copied()
        .filter(|f| f.iter().all(|&v| (v as usize) < n))
        .collect();
    if faces.is_empty() {
        return blank();
    }
    let ([right, up, towards], c) = view_frame(positions);
    let projected: Vec<[f64; 3]> = positions
        .iter()
        .map(|p| {
            let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
            [dot(d, right), dot(d, up), dot(d, towards)]
        })
        .collect();
    // Fit the projection into the image with a 4% margin, y up.
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &projected {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let (w, h) = (f64::from(size.width), f64::from(size.height));
    let scale = 0.92 * (w / (hi[0] - lo[0]).max(1e-300)).min(h / (hi[1] - lo[1]).max(1e-300));
    let mid = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
    let pixel = |p: [f64; 3]| {
        [
            (0.5 * w + scale * (p[0] - mid[0])) as f32,
            (0.5 * h - scale * (p[1] - mid[1])) as f32,
        ]
    };
    // Back to front.
    let mut order: Vec<usize> = (0..faces.len()).collect();
    let depth = |f: &[u32; 3]| f.iter().map(|&v| projected[v as usize][2]).sum::<f64>();
    order.sort_by(|&a, &b| depth(&faces[a]).total_cmp(&depth(&faces[b])));
    let stroke = Stroke {
        width: (0.0022 * w.min(h)).max(1.0) as f32,
        line_cap: LineCap::Round,
        ..Stroke::default()
    };
    let mut line_paint = Paint::default();
    line_paint.set_color(Color::from_rgba8(ISOLINE[0], ISOLINE[1], ISOLINE[2], 200));
    line_paint.anti_alias = true;
    for &f in &order {
        let [a, b, cc] = faces[f];
        let (pa, pb, pc) = (
            projected[a as usize],
            projected[b as usize],
            projected[cc as usize],
        );
        // Soft light from the viewer: brighter where the triangle faces it.
        let normal = cross(
            [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]],
            [pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]],
        );
        let len = dot(normal, normal).sqrt();
        let facing = if len > 0.0 {
            (normal[2] / len).abs()
        } else {
            1.0
        };
        let light = 0.6 + 0.4 * facing;
        let rgb = colour(&faces[f]);
        let lit = rgb.map(|x| (f64::from(x) * light).round().clamp(0.0, 255.0) as u8);
        let mut paint = Paint::default();
        paint.set_color(Color::from_rgba8(lit[0], lit[1], lit[2], 255));
        // Not anti-aliased: neighbours then leave no seams; isolines give the detail.
        paint.anti_alias = false;
        let (qa, qb, qc) = (pixel(pa), pixel(pb), pixel(pc));
        let mut pb_ = PathBuilder::new();
        pb_.move_to(qa[0], qa[1]);
        pb_.line_to(qb[0], qb[1]);
        pb_.line_to(qc[0], qc[1]);
        pb_.close();
        if let Some(path) = pb_.finish() {
            pixmap.fill_path(
                &path,
                &paint,
                FillRule::Winding,
                Transform::identity(),
                None,
            );
        }
        let Some((values, spacing)) = field else {
            continue;
        };
        let (va, vb, vc) = (values[a as usize], values[b as usize], values[cc as usize]);
        if !(va.is_finite() && vb.is_finite() && vc.is_finite()) {
            continue;
        }
        // Isolines: where the linear interpolant crosses each multiple of the spacing.
        let (lo_v, hi_v) = (va.min(vb).min(vc), va.max(vb).max(vc));
        let mut lines = PathBuilder::new();
        let corners = [(qa, va), (qb, vb), (qc, vc)];
        let first = (lo_v / spacing).ceil().max(1.0) as u64;
        let last = (hi_v / spacing).floor() as u64;
        for k in first..=last {
            let level = k as f64 * spacing;
            let mut ends = [[0.0f32; 2]; 2];
            let mut found = 0;
            for i in 0..3 {
                let (p, vp) = corners[i];
                let (q, vq) = corners[(i + 1) % 3];
                if (vp < level) != (vq < level) && found < 2 {
                    let s = ((level - vp) / (vq - vp)) as f32;
                    ends[found] = [p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])];
                    found += 1;
                }
            }
            if found == 2 {
                lines.move_to(ends[0][0], ends[0][1]);
                lines.line_to(ends[1][0], ends[1][1]);
            }
        }
        if let Some(path) = lines.finish() {
            pixmap.stroke_path(&path, &line_paint, &stroke, Transform::identity(), None);
        }
    }
    Image {
        width: size.width,
        height: size.height,
        rgba: pixmap.take_demultiplied(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isoline_spacing_is_round() {
        assert_eq!(isoline_spacing(20.0), 1.0);
        assert_eq!(isoline_spacing(3.3), 0.2);
        assert_eq!(isoline_spacing(90.0), 5.0);
        assert_eq!(isoline_spacing(0.0), 1.0);
    }

    #[test]
    fn a_field_is_drawn_in_colours_with_dark_isolines() {
        let sphere = crate::generate::icosphere(3);
        let d: Vec<f64> = sphere
            .positions
            .iter()
            .map(|p| (p[2] + 1.0) * 10.0)
            .collect();
        let size = ImageSize {
            width: 200,
            height: 200,
        };
        let img = render_field(&sphere.positions, &sphere.faces, &d, size).unwrap();
        let pixels: Vec<[u8; 3]> = img.rgba.chunks(4).map(|p| [p[0], p[1], p[2]]).collect();
        let pixels: Vec<[u16; 3]> = pixels.iter().map(|p| p.map(u16::from)).collect();
        let white = pixels.iter().filter(|p| **p == [255, 255, 255]).count();
        let dark = pixels.iter().filter(|p| p.iter().all(|&c| c < 70)).count();
        let green = pixels
            .iter()
            .filter(|p| p[1] > 120 && p[1] > p[0] + 20)
            .count();
        assert!(white > 4000 && white < 30000, "{white} white pixels");
        assert!(dark > 200, "{dark} isoline pixels");
        assert!(green > 1000, "{green} mid-range pixels");
    }
}
