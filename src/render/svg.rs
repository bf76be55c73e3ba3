//! SVG pictures: the triangles of a frame as a standalone SVG document.
//!
//! Same colours as the raster pictures ([`super::raster`]): light blue triangles with dark
//! blue edges, flipped triangles red. Textures are not drawn in SVG (the document would have
//! to embed the image and clip it per triangle); a [`Drawing`]'s `texture` and `corner_uv` are
//! ignored.
//!
//! ```
//! use bdmorph::generate;
//! use bdmorph::render::{svg::svg, Drawing, ImageSize, Viewport};
//!
//! let mesh = generate::disk(2, 0.0);
//! let drawing = Drawing { faces: &mesh.faces, corner_uv: None, texture: None, face_colours: None, depth: None };
//! let view = Viewport::fit([&mesh.positions[..]]);
//! let doc = svg(&mesh.positions, &drawing, &view, ImageSize { width: 120, height: 90 });
//! assert!(doc.starts_with("<svg"));
//! assert_eq!(doc.matches("<polygon").count(), mesh.faces.len());
//! ```

use super::raster::{pixel_triangles, PixelTriangle, EDGE, FILL, FLIPPED};
use super::{Drawing, ImageSize, Viewport};
use std::fmt::Write;

/// Appends `x` with at most two decimals, without trailing zeros (`12.5`, `3`, `-0.25`).
fn push_number(out: &mut String, x: f64) {
    let start = out.len();
    let _ = write!(out, "{x:.2}");
    if out[start..].contains('.') {
        let trimmed = out[start..]
            .trim_end_matches('0')
            .trim_end_matches('.')
            .len();
        out.truncate(start + trimmed);
    }
    if &out[start..] == "-0" {
        out.truncate(start);
        out.push('0');
    }
}

fn hex([r, g, b]: [u8; 3]) -> String {
    format!("#{r:02x}{g:02x}{b:02x}")
}

/// A standalone SVG document of `size` pixels (`width`, `height` and a `viewBox` in pixels)
/// showing the triangles of `drawing` at `positions` (world coordinates, `y` up) through
/// `view`, as [`super::raster::render`] would place them: a white background, then one
/// `<polygon>` per triangle, grouped by colour (unflipped light blue, then flipped red), each
/// with a 1 px dark blue outline. Coordinates have at most two decimals. Faces with
/// out-of-range vertex indices or non-finite positions are left out.
///
/// Textures are ignored: SVG output is always untextured. With per-face colours (one per
/// face), unflipped triangles are grouped by their colour instead of the flat fill.
pub fn svg(positions: &[[f64; 2]], drawing: &Drawing, view: &Viewport, size: ImageSize) -> String {
    let (w, h) = (size.width, size.height);
    let mut out = String::with_capacity(200 + 40 * drawing.faces.len());
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}">"#
    );
    let _ = writeln!(out, r##"<rect width="{w}" height="{h}" fill="#ffffff"/>"##);
    let triangles: Vec<_> = pixel_triangles(positions, drawing.faces, view, size).collect();
    let coloured = drawing
        .face_colours
        .filter(|c| c.len() == drawing.faces.len());
    // Layers by depth (one when there is none), each in groups of one fill: unflipped
    // triangles by colour, then the flipped ones.
    let mut layers: Vec<Vec<&PixelTriangle>> = vec![triangles.iter().collect()];
    if let Some(depth) = drawing.depth.filter(|d| d.len() == drawing.faces.len()) {
        let mut order = layers.remove(0);
        order.sort_by_key(|t| depth[t.face]);
        layers = order
            .chunk_by(|a, b| depth[a.face] == depth[b.face])
            .map(<[_]>::to_vec)
            .collect();
    }
    let mut groups: Vec<([u8; 3], Vec<&PixelTriangle>)> = Vec::new();
    for layer in &layers {
        match coloured {
            Some(colours) => {
                let mut order: Vec<&PixelTriangle> =
                    layer.iter().copied().filter(|t| !t.flipped).collect();
                order.sort_by_key(|t| colours[t.face]);
                for group in order.chunk_by(|a, b| colours[a.face] == colours[b.face]) {
                    groups.push((colours[group[0].face], group.to_vec()));
                }
            }
            None => groups.push((FILL, layer.iter().copied().filter(|t| !t.flipped).collect())),
        }
        groups.push((
            FLIPPED,
            layer.iter().copied().filter(|t| t.flipped).collect(),
        ));
    }
    for (fill, group) in groups {
        if group.is_empty() {
            continue;
        }
        let _ = writeln!(
            out,
            r#"<g fill="{}" stroke="{}" stroke-width="1" stroke-linejoin="round">"#,
            hex(fill),
            hex(EDGE)
        );
        for t in group {
            out.push_str(r#"<polygon points=""#);
            for (k, c) in t.corners.iter().enumerate() {
                if k > 0 {
                    out.push(' ');
                }
                push_number(&mut out, c[0]);
                out.push(',');
                push_number(&mut out, c[1]);
            }
            out.push_str("\"/>\n");
        }
        out.push_str("</g>\n");
    }
    out.push_str("</svg>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn number(x: f64) -> String {
        let mut s = String::new();
        push_number(&mut s, x);
        s
    }

    #[test]
    fn numbers_are_compact() {
        assert_eq!(number(12.5), "12.5");
        assert_eq!(number(3.0), "3");
        assert_eq!(number(10.666_666), "10.67");
        assert_eq!(number(-0.25), "-0.25");
        assert_eq!(number(-0.001), "0");
        assert_eq!(number(100.0), "100");
        assert_eq!(number(0.999), "1");
    }

    fn attribute<'a>(doc: &'a str, name: &str) -> &'a str {
        let start = doc.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
        &doc[start..start + doc[start..].find('"').unwrap()]
    }

    #[test]
    fn one_polygon_per_triangle_flipped_ones_red() {
        let pos = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        // Two counter-clockwise triangles, one clockwise, one naming a missing vertex.
        let faces = [[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 1, 9]];
        let drawing = Drawing {
            faces: &faces,
            corner_uv: None,
            texture: None,
            face_colours: None,
            depth: None,
        };
        let view = Viewport {
            min: [-0.25, -0.25],
            max: [1.25, 1.25],
        };
        let size = ImageSize {
            width: 90,
            height: 60,
        };
        let doc = svg(&pos, &drawing, &view, size);
        assert!(doc.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""));
        assert!(doc.trim_end().ends_with("</svg>"));
        assert_eq!(attribute(&doc, "width"), "90");
        assert_eq!(attribute(&doc, "height"), "60");
        assert_eq!(attribute(&doc, "viewBox"), "0 0 90 60");
        assert_eq!(doc.matches("<polygon ").count(), 3);
        assert_eq!(doc.matches("<g ").count(), doc.matches("</g>").count());

        let red = doc.find(r##"<g fill="#e05050""##).expect("a red group");
        assert_eq!(doc[red..].matches("<polygon ").count(), 1);
        let blue = doc
            .find(r##"<g fill="#cfe0f5""##)
            .expect("a light blue group");
        assert_eq!(doc[blue..red].matches("<polygon ").count(), 2);
        assert!(doc.contains(r##"stroke="#3a5a80""##));

        // Placed as the raster picture would be: scale 40, square from (25, 50) to (65, 10),
        // world y up being image y down.
        assert!(
            doc.contains(r#"<polygon points="25,50 65,50 65,10"/>"#),
            "{doc}"
        );
    }

    #[test]
    fn textures_are_ignored() {
        let pos = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let faces = [[0, 1, 2]];
        let uv = [[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]];
        let texture = crate::render::Image {
            width: 1,
            height: 1,
            rgba: vec![1, 2, 3, 255],
        };
        let view = Viewport::fit([&pos[..]]);
        let size = ImageSize::default();
        let plain = Drawing {
            faces: &faces,
            corner_uv: None,
            texture: None,
            face_colours: None,
            depth: None,
        };
        let textured = Drawing {
            corner_uv: Some(&uv),
            texture: Some(&texture),
            ..plain
        };
        assert_eq!(
            svg(&pos, &plain, &view, size),
            svg(&pos, &textured, &view, size)
        );
    }
}
