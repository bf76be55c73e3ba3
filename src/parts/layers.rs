//! Layered pictures as every 2D puppet tool starts from them: one layer per part (head, torso,
//! each segment of each limb), overlapping where the parts join, stacked in a draw order.
//!
//! [`Layered`] is what the readers ([`read_layered`]: Photoshop's PSD and OpenRaster's ORA, with
//! the optional feature `layers`) give: the visible layers, bottom first, each cropped to its
//! pixels that are not fully transparent, with its place on the canvas. Groups are flattened
//! (a hidden group hides what it holds) and hidden layers are skipped, each with a note.
//!
//! Memory: a reader keeps at most [`LayerBudget`] decoded bytes, a budget proportional to the
//! file's size (plus a fixed allowance for small files of large canvases), and refuses a file
//! that needs more before decoding it.

use crate::render::Image;

/// One layer of a layered picture, cropped to its visible pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    /// Its name in the file (groups' names before it, `group/name`).
    pub name: String,
    /// Its pixels (RGBA, not premultiplied; the layer's opacity multiplied into alpha), cropped
    /// to the bounding box of the pixels that are not fully transparent.
    pub image: Image,
    /// The crop's left column on the canvas.
    pub left: i64,
    /// The crop's top row on the canvas.
    pub top: i64,
}

/// A layered picture: its canvas and its visible, non-empty layers, bottom first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Layered {
    /// Canvas width in pixels.
    pub width: u32,
    /// Canvas height in pixels.
    pub height: u32,
    /// The layers that are drawn, bottom first (the first is drawn first, under the rest).
    pub layers: Vec<Layer>,
    /// What was left out and why (hidden layers, empty layers, blend modes not honoured).
    pub notes: Vec<String>,
}

/// Why a layered picture could not be read.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum LayersError {
    /// Not a PSD or ORA file.
    #[error("not a layered picture: a PSD file starts with 8BPS, an OpenRaster file is a zip with the mimetype image/openraster")]
    UnknownFormat,
    /// The file is damaged: a section is cut short or its fields do not agree.
    #[error("the {format} file is damaged: {why}")]
    Damaged {
        /// `PSD` or `ORA`.
        format: &'static str,
        /// What is wrong.
        why: String,
    },
    /// The file is of a kind not read (CMYK, 16-bit, ...).
    #[error("the {format} file is not supported: {why}")]
    Unsupported {
        /// `PSD` or `ORA`.
        format: &'static str,
        /// What it is, and what is read.
        why: String,
    },
    /// No layer has any visible pixel.
    #[error("the layered picture has no visible layer with pixels{}", if .hidden > &0 { format!(" ({} hidden layer{} skipped)", .hidden, if *.hidden == 1 { "" } else { "s" }) } else { String::new() })]
    Empty {
        /// Hidden layers skipped.
        hidden: usize,
    },
    /// Decoding would take more memory than the file's size allows.
    #[error("the layered picture would need {needed} bytes of pixels, more than the {budget} bytes allowed for a file of its size")]
    TooLarge {
        /// Bytes the pixels would take.
        needed: u64,
        /// The budget.
        budget: u64,
    },
    /// The file could not be read.
    #[error("{0}")]
    Read(String),
    /// More layers with pixels than a character is made of.
    #[error("the layered picture has more than {max} visible layers with pixels, more than a character's {max} parts: merge or hide some")]
    TooManyLayers {
        /// The most layers read ([`MAX_PARTS`]).
        max: usize,
    },
    /// The reading was cancelled or ran out of time (see [`crate::Budget`]).
    #[error("reading the layered picture stopped: {0}")]
    Stopped(#[from] crate::Stopped),
}

/// The most layers with pixels a layered picture may give (each becomes a part of a
/// character; more are refused in one line).
pub const MAX_PARTS: usize = 256;

/// The decoded bytes a reader may hold for a file of a given size: `PER_INPUT_BYTE` per byte
/// of the file plus `FIXED` (a blank layer of a large canvas compresses to almost nothing),
/// and never more than `MAX`.
#[derive(Clone, Copy, Debug)]
pub struct LayerBudget;

impl LayerBudget {
    /// Decoded bytes allowed per byte of the file.
    pub const PER_INPUT_BYTE: u64 = 256;
    /// Decoded bytes allowed whatever the file's size (64 MiB: a 4096 x 4096 RGBA layer).
    pub const FIXED: u64 = 64 << 20;
    /// Decoded bytes never exceeded (2 GiB).
    pub const MAX: u64 = 2 << 30;

    /// The budget for a file of `input` bytes.
    pub fn of(input: usize) -> u64 {
        (input as u64)
            .saturating_mul(Self::PER_INPUT_BYTE)
            .saturating_add(Self::FIXED)
            .min(Self::MAX)
    }
}

#[cfg(feature = "layers")]
/// Counts decoded bytes against a [`LayerBudget`].
#[derive(Debug)]
pub(crate) struct Spend {
    budget: u64,
    spent: u64,
}

#[cfg(feature = "layers")]
impl Spend {
    pub(crate) fn new(input: usize) -> Spend {
        Spend {
            budget: LayerBudget::of(input),
            spent: 0,
        }
    }

    /// Bytes left.
    pub(crate) fn left(&self) -> u64 {
        self.budget - self.spent
    }

    /// Takes `bytes` more, or says the file is too large. `transient` bytes are given back at
    /// once (a buffer decoded, cropped and dropped).
    pub(crate) fn take(&mut self, bytes: u64, transient: bool) -> Result<(), LayersError> {
        let needed = self.spent.saturating_add(bytes);
        if needed > self.budget {
            return Err(LayersError::TooLarge {
                needed,
                budget: self.budget,
            });
        }
        if !transient {
            self.spent = needed;
        }
        Ok(())
    }
}

#[cfg(feature = "layers")]
/// Crops `rgba` (`width` x `height`, canvas placed at `left`, `top`) to its pixels with
/// non-zero alpha; `None` when there are none.
pub(crate) fn crop(
    rgba: &[u8],
    width: u32,
    height: u32,
    left: i64,
    top: i64,
) -> Option<(Image, i64, i64)> {
    let (w, h) = (width as usize, height as usize);
    if rgba.len() != w * h * 4 {
        return None;
    }
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    for y in 0..h {
        let row = &rgba[y * w * 4..(y + 1) * w * 4];
        for x in 0..w {
            if row[x * 4 + 3] != 0 {
                x0 = x0.min(x);
                x1 = x1.max(x + 1);
                y0 = y0.min(y);
                y1 = y1.max(y + 1);
            }
        }
    }
    if x0 == usize::MAX {
        return None;
    }
    let (cw, ch) = (x1 - x0, y1 - y0);
    let mut out = Vec::with_capacity(cw * ch * 4);
    for y in y0..y1 {
        out.extend_from_slice(&rgba[(y * w + x0) * 4..(y * w + x1) * 4]);
    }
    Some((
        Image {
            width: cw as u32,
            height: ch as u32,
            rgba: out,
        },
        left + x0 as i64,
        top + y0 as i64,
    ))
}

#[cfg(feature = "layers")]
/// Another library's message as one short line: whitespace runs (newlines included) made one
/// space, at most 160 characters.
pub(crate) fn one_line(text: &str) -> String {
    let mut out = String::new();
    for word in text.split_whitespace() {
        if !out.is_empty() {
            out.push(' ');
        }
        out.push_str(word);
    }
    if out.chars().count() > 160 {
        out = out.chars().take(157).collect::<String>() + "...";
    }
    out
}

#[cfg(feature = "layers")]
/// Multiplies alpha by `opacity` (0 to 255).
pub(crate) fn apply_opacity(rgba: &mut [u8], opacity: u8) {
    if opacity == 255 {
        return;
    }
    for p in rgba.chunks_exact_mut(4) {
        p[3] = ((u16::from(p[3]) * u16::from(opacity) + 127) / 255) as u8;
    }
}

/// Which layered format `bytes` are, if any.
pub fn layered_format(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"8BPS") {
        Some("PSD")
    } else if bytes.starts_with(b"PK\x03\x04") {
        // A zip: OpenRaster if its mimetype entry says so (checked as it is read).
        Some("ORA")
    } else {
        None
    }
}

/// Whether `path` names a layered picture by its extension (`.psd`, `.psb`, `.ora`).
pub fn is_layered_path(path: &std::path::Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| {
        ["psd", "psb", "ora"]
            .iter()
            .any(|known| e.eq_ignore_ascii_case(known))
    })
}

/// Reads a PSD or ORA file's bytes (told by their first bytes).
///
/// # Errors
/// [`LayersError::UnknownFormat`] for other bytes; those of the format's reader;
/// [`LayersError::Empty`] when nothing visible is left.
#[cfg(feature = "layers")]
pub fn read_layered(bytes: &[u8]) -> Result<Layered, LayersError> {
    read_layered_with(bytes, &crate::Budget::unlimited())
}

/// [`read_layered`], checking `budget` between layers (and between a layer's channels), so
/// that a caller can cancel the reading of a large file or give it a deadline.
///
/// # Errors
/// Those of [`read_layered`]; [`LayersError::Stopped`] when the budget is cancelled or runs
/// out.
#[cfg(feature = "layers")]
pub fn read_layered_with(bytes: &[u8], budget: &crate::Budget) -> Result<Layered, LayersError> {
    let layered = match layered_format(bytes) {
        Some("PSD") => super::psd::read_psd_with(bytes, budget)?,
        Some(_) => super::ora::read_ora_with(bytes, budget)?,
        None => return Err(LayersError::UnknownFormat),
    };
    let mut layered = layered;
    drop_backdrop(&mut layered);
    if layered.layers.is_empty() {
        let hidden = layered
            .notes
            .iter()
            .filter(|n| n.contains("hidden"))
            .count();
        return Err(LayersError::Empty { hidden });
    }
    Ok(layered)
}

/// Leaves out a bottom layer that is opaque over the whole canvas (a backdrop, not a part),
/// when other layers are left, with a note.
pub fn drop_backdrop(layered: &mut Layered) {
    let covers = |l: &Layer| {
        l.left <= 0
            && l.top <= 0
            && l.left + i64::from(l.image.width) >= i64::from(layered.width)
            && l.top + i64::from(l.image.height) >= i64::from(layered.height)
            && l.image.rgba.chunks_exact(4).all(|p| p[3] == 255)
    };
    if layered.layers.len() > 1 && covers(&layered.layers[0]) {
        let l = layered.layers.remove(0);
        layered.notes.push(format!(
            "layer '{}' covers the whole canvas (a backdrop, not a part): left out",
            l.name
        ));
    }
}

/// Reads a layered picture file, as [`read_layered`]; errors name the file.
///
/// # Errors
/// [`LayersError::Read`] when the file cannot be read; those of [`read_layered`].
#[cfg(feature = "layers")]
pub fn read_layered_file(path: &std::path::Path) -> Result<Layered, LayersError> {
    let bytes = crate::io::read_input(path, crate::io::MAX_INPUT_BYTES)
        .map_err(|e| LayersError::Read(format!("{}: {e}", path.display())))?;
    read_layered(&bytes)
}

#[cfg(all(test, feature = "layers"))]
mod tests {
    use super::*;

    #[test]
    fn crop_keeps_the_visible_box_and_its_place() {
        let (w, h) = (5u32, 4u32);
        let mut rgba = vec![0u8; 5 * 4 * 4];
        for (x, y) in [(1usize, 1usize), (3, 2)] {
            rgba[(y * 5 + x) * 4..(y * 5 + x) * 4 + 4].copy_from_slice(&[9, 8, 7, 255]);
        }
        let (img, left, top) = crop(&rgba, w, h, 10, 20).expect("pixels");
        assert_eq!((img.width, img.height, left, top), (3, 2, 11, 21));
        assert_eq!(&img.rgba[0..4], &[9, 8, 7, 255]);
        assert_eq!(&img.rgba[(3 + 2) * 4..(3 + 2) * 4 + 4], &[9, 8, 7, 255]);
        assert!(crop(&[0; 16], 2, 2, 0, 0).is_none());
    }

    #[test]
    fn the_budget_grows_with_the_file_and_stops() {
        assert_eq!(LayerBudget::of(0), LayerBudget::FIXED);
        assert_eq!(LayerBudget::of(1000), 256_000 + LayerBudget::FIXED);
        assert_eq!(LayerBudget::of(usize::MAX), LayerBudget::MAX);
        let mut s = Spend::new(0);
        assert!(s.take(LayerBudget::FIXED, true).is_ok());
        assert!(s.take(LayerBudget::FIXED + 1, true).is_err());
    }
}
