//! The file header and the sections after it: the kind of document is checked first (colour
//! mode, depth, canvas), the colour mode data and the image resources are skipped by their
//! lengths without reading them, and the layer and mask information section is handed on.

use super::bytes::Bytes;
use super::{damaged, unsupported};
use crate::parts::layers::LayersError;

/// The colour modes read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mode {
    /// One grey channel (id 0).
    Grey,
    /// Red, green, blue (ids 0, 1, 2).
    Rgb,
}

/// What the header says.
#[derive(Clone, Copy, Debug)]
pub(super) struct Header {
    /// PSB (version 2): 8-byte section and channel lengths, 4-byte RLE row counts.
    pub(super) large: bool,
    /// Canvas width and height.
    pub(super) width: u32,
    /// Canvas height.
    pub(super) height: u32,
    /// Bits per channel: 8, 16 or 32.
    pub(super) depth: u16,
    /// The colour mode.
    pub(super) mode: Mode,
}

/// The widest canvas side of a PSD (Photoshop's own limit).
pub(super) const MAX_PSD_SIDE: u32 = 30_000;
/// The widest canvas side of a PSB.
pub(super) const MAX_PSB_SIDE: u32 = 300_000;

fn mode_name(mode: u16) -> &'static str {
    match mode {
        0 => "bitmap",
        1 => "greyscale",
        2 => "indexed colour",
        3 => "RGB",
        4 => "CMYK",
        7 => "multichannel",
        8 => "duotone",
        9 => "Lab colour",
        _ => "an unknown colour mode",
    }
}

/// Reads the header and skips the colour mode data and image resources; gives the header and
/// the layer and mask information section.
pub(super) fn read<'a>(file: &mut Bytes<'a>) -> Result<(Header, Bytes<'a>), LayersError> {
    if file.remaining() < 26 {
        return Err(damaged("the header is cut short"));
    }
    let signature = file.take(4, "the signature")?;
    if signature != b"8BPS" {
        return Err(LayersError::UnknownFormat);
    }
    let large = match file.u16("the version")? {
        1 => false,
        2 => true,
        v => return Err(damaged(format!("version {v} (PSD is 1, PSB is 2)"))),
    };
    file.take(6, "the header")?;
    let _channels = file.u16("the channel count")?;
    let height = file.u32("the height")?;
    let width = file.u32("the width")?;
    let depth = file.u16("the depth")?;
    let mode = file.u16("the colour mode")?;
    let max = if large { MAX_PSB_SIDE } else { MAX_PSD_SIDE };
    if !(1..=max).contains(&width) || !(1..=max).contains(&height) {
        return Err(damaged(format!(
            "a canvas of {width} x {height} pixels ({} canvases are 1 to {max} a side)",
            if large { "PSB" } else { "PSD" }
        )));
    }
    let mode = match mode {
        1 => Mode::Grey,
        3 => Mode::Rgb,
        m => {
            return Err(unsupported(format!(
                "{}; RGB and greyscale are read (convert the document to RGB)",
                mode_name(m)
            )))
        }
    };
    if !matches!(depth, 8 | 16 | 32) {
        return Err(unsupported(format!(
            "{depth} bits per channel; 8, 16 and 32 are read"
        )));
    }
    file.section(false, "the colour mode data")?;
    file.section(false, "the image resources")?;
    let layers = file.section(large, "the layer and mask information")?;
    Ok((
        Header {
            large,
            width,
            height,
            depth,
            mode,
        },
        layers,
    ))
}
