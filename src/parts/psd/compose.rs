//! A layer's decoded channels made into RGBA: clipped to the canvas, the layer's opacity
//! multiplied into its alpha, and cropped to the pixels that are not fully transparent.

use crate::parts::layers::{apply_opacity, crop};
use crate::render::Image;

/// A layer's decoded channels over its rectangle.
pub(super) struct Planes<'a> {
    /// One plane (grey) or three (red, green, blue), `width` samples a row.
    pub(super) colour: &'a [Vec<u8>],
    /// Transparency, if the layer has it (opaque otherwise).
    pub(super) alpha: Option<&'a [u8]>,
    /// Samples per row of every plane.
    pub(super) width: usize,
    /// The rectangle's left column and top row on the canvas.
    pub(super) origin: (i64, i64),
}

/// The layer's pixels within `clip` (left, top, right, bottom on the canvas, inside the
/// layer's rectangle), opacity applied, cropped to its visible pixels; `None` when none is.
pub(super) fn compose(
    planes: &Planes<'_>,
    clip: [i64; 4],
    opacity: u8,
) -> Option<(Image, i64, i64)> {
    let [x0, y0, x1, y1] = clip;
    let (cw, ch) = ((x1 - x0) as usize, (y1 - y0) as usize);
    let (left, top) = planes.origin;
    let mut rgba = Vec::with_capacity(cw * ch * 4);
    for y in y0..y1 {
        let row = (y - top) as usize * planes.width;
        for x in x0..x1 {
            let at = row + (x - left) as usize;
            let alpha = planes.alpha.map_or(255, |a| a[at]);
            match planes.colour {
                [grey] => rgba.extend_from_slice(&[grey[at], grey[at], grey[at], alpha]),
                [r, g, b, ..] => rgba.extend_from_slice(&[r[at], g[at], b[at], alpha]),
                _ => rgba.extend_from_slice(&[0, 0, 0, alpha]),
            }
        }
    }
    apply_opacity(&mut rgba, opacity);
    crop(&rgba, cw as u32, ch as u32, x0, y0)
}
