//! Photoshop's PSD and PSB, read by a reader of this crate's own that reads only what a
//! character needs: the header, the layer records (rectangle, channels, blend mode, opacity,
//! visibility, name, group dividers) and the layers' channel image data. The colour mode data
//! and the image resources are skipped by their lengths, unread, and so is the merged picture.
//!
//! Read: RGB and greyscale documents, 8 and 16 bits per channel (16 rounded to 8) and 32
//! (floats clamped to 0..1, colour encoded as sRGB), channels raw, RLE (PackBits), ZIP and ZIP
//! with prediction, PSB (version 2), and groups (a hidden group hides what it holds).
//! Refused in one line: other colour modes (bitmap, indexed, CMYK, multichannel, duotone,
//! Lab) and other depths.
//!
//! Memory: every length and count the file declares is checked against the bytes that are
//! left before anything is allocated for it, so what the records take is bounded by a
//! constant times the file's size; pixels are decoded one layer at a time, each layer's
//! rectangle (clipped to the canvas) checked against the file's [`LayerBudget`] before its
//! buffers are allocated, and an inflated channel stops at the size its layer needs.
//! Per-layer work is proportional to the layer's own rectangle; empty layers cost nothing.
//!
//! [`LayerBudget`]: crate::parts::LayerBudget

mod bytes;
mod channels;
mod compose;
mod header;
mod records;

use self::bytes::Bytes;
use self::channels::{Channel, Kind};
use self::header::Mode;
use super::layers::{one_line, Layer, Layered, LayersError, Spend, MAX_PARTS};
use crate::Budget;

const FORMAT: &str = "PSD";

/// The deepest nesting of groups followed.
const MAX_DEPTH: usize = 64;
/// The longest group path kept in a layer's name, in bytes (longer ones keep their end), so
/// that names stay proportional to the file.
const MAX_PATH: usize = 256;
/// The most notes kept; the rest are counted in one.
const MAX_NOTES: usize = 200;

/// `path` cut to its last [`MAX_PATH`] bytes (at a character boundary), marked `…`.
fn bounded_path(path: String) -> String {
    if path.len() <= MAX_PATH {
        return path;
    }
    let mut start = path.len() - MAX_PATH;
    while !path.is_char_boundary(start) {
        start += 1;
    }
    format!("…{}", &path[start..])
}

fn damaged(why: impl Into<String>) -> LayersError {
    LayersError::Damaged {
        format: FORMAT,
        why: one_line(&why.into()),
    }
}

fn unsupported(why: impl Into<String>) -> LayersError {
    LayersError::Unsupported {
        format: FORMAT,
        why: why.into(),
    }
}

/// Keeps `text` among the first [`MAX_NOTES`] notes, or counts it in `left_out`.
fn note(notes: &mut Vec<String>, left_out: &mut usize, text: String) {
    if notes.len() < MAX_NOTES {
        notes.push(text);
    } else {
        *left_out += 1;
    }
}

/// A group as a layer sees it: its path of names (bounded), and the outermost hidden group
/// around it (itself included), if any.
#[derive(Clone, Debug, Default)]
struct Place {
    path: String,
    hidden: Option<String>,
}

/// Where each record sits among the groups: an index into the groups' places (`None` outside
/// every group).
fn groups(records: &[records::Record]) -> Result<(Vec<Option<usize>>, Vec<Place>), LayersError> {
    let mut out = vec![None; records.len()];
    let mut places: Vec<Place> = Vec::new();
    // The open groups: each one's place.
    let mut stack: Vec<usize> = Vec::new();
    // The file stores the bottom record first; a group's own record is above its layers and
    // its bounding divider below them.
    for (i, r) in records.iter().enumerate().rev() {
        match r.divider {
            Some(1 | 2) => {
                if stack.len() == MAX_DEPTH {
                    return Err(unsupported(format!(
                        "groups nested more than {MAX_DEPTH} deep"
                    )));
                }
                let parent = stack.last().map(|&p| &places[p]);
                let path = match parent {
                    Some(p) => bounded_path(format!("{}/{}", p.path, r.name)),
                    None => bounded_path(r.name.clone()),
                };
                let hidden = parent
                    .and_then(|p| p.hidden.clone())
                    .or_else(|| r.hidden.then(|| bounded_path(r.name.clone())));
                places.push(Place { path, hidden });
                stack.push(places.len() - 1);
            }
            Some(_) => {
                stack.pop();
            }
            None => out[i] = stack.last().copied(),
        }
    }
    Ok((out, places))
}

/// Reads a PSD or PSB file's bytes.
///
/// # Errors
/// [`LayersError::Unsupported`] for colour modes and depths not read,
/// [`LayersError::Damaged`] for files whose lengths or fields do not agree,
/// [`LayersError::TooLarge`] beyond the file's [`super::LayerBudget`],
/// [`LayersError::TooManyLayers`] beyond [`MAX_PARTS`] layers with pixels.
pub fn read_psd(bytes: &[u8]) -> Result<Layered, LayersError> {
    read_psd_with(bytes, &Budget::unlimited())
}

/// [`read_psd`], checking `budget` between layers and channels.
///
/// # Errors
/// Those of [`read_psd`]; [`LayersError::Stopped`] when the budget runs out or is cancelled.
pub fn read_psd_with(bytes: &[u8], budget: &Budget) -> Result<Layered, LayersError> {
    let mut file = Bytes::new(bytes);
    let (header, section) = header::read(&mut file)?;
    let (records, mut data) = records::read(section, header.large)?;
    let (place_of, places) = groups(&records)?;
    let no_place = Place::default();
    let (cw, ch) = (i64::from(header.width), i64::from(header.height));
    let colour_ids: &[i16] = match header.mode {
        Mode::Grey => &[0],
        Mode::Rgb => &[0, 1, 2],
    };
    let bps = u64::from(header.depth / 8);
    let mut spend = Spend::new(bytes.len());
    let mut layers = Vec::new();
    let mut notes = Vec::new();
    // Notes beyond MAX_NOTES, counted.
    let mut left_out = 0usize;
    let mut hidden_groups: std::collections::HashSet<&str> = std::collections::HashSet::new();
    let mut colour: Vec<Vec<u8>> = vec![Vec::new(); colour_ids.len()];
    let mut alpha: Vec<u8> = Vec::new();
    for (r, place) in records.iter().zip(&place_of) {
        budget.check()?;
        let Place {
            path,
            hidden: hidden_group,
        } = place.map_or(&no_place, |p| &places[p]);
        // The channels' data follow one another, layer by layer, in the records' order.
        let mut slices = Vec::with_capacity(r.channels.len());
        for &(id, len) in &r.channels {
            slices.push((id, data.take(len, "a layer's channel data")?));
        }
        if r.divider.is_some() {
            continue;
        }
        let name = if path.is_empty() {
            r.name.clone()
        } else {
            format!("{path}/{}", r.name)
        };
        if let Some(g) = hidden_group {
            if hidden_groups.insert(g.as_str()) {
                note(
                    &mut notes,
                    &mut left_out,
                    format!("group '{g}' is hidden: its layers are left out"),
                );
            }
            note(
                &mut notes,
                &mut left_out,
                format!("layer '{name}' is hidden: left out"),
            );
            continue;
        }
        if r.hidden {
            note(
                &mut notes,
                &mut left_out,
                format!("layer '{name}' is hidden: left out"),
            );
            continue;
        }
        let (w, h) = r.size();
        let [top, left, ..] = r.rect.map(i64::from);
        let clip = [
            left.max(0),
            top.max(0),
            (left + w as i64).min(cw),
            (top + h as i64).min(ch),
        ];
        let max = u64::from(header::MAX_PSB_SIDE);
        if w > max || h > max {
            return Err(damaged(format!(
                "layer '{name}' is {w} x {h} pixels, more than {max} a side"
            )));
        }
        if w == 0 || h == 0 {
            note(
                &mut notes,
                &mut left_out,
                format!("layer '{name}' has no pixels: left out"),
            );
            continue;
        }
        if clip[0] >= clip[2] || clip[1] >= clip[3] {
            note(
                &mut notes,
                &mut left_out,
                format!("layer '{name}' lies outside the canvas: left out"),
            );
            continue;
        }
        if !matches!(&r.blend, b"norm" | b"pass") {
            note(
                &mut notes,
                &mut left_out,
                format!(
                    "layer '{name}' blends by '{}': drawn over the layers below as normal",
                    String::from_utf8_lossy(&r.blend).trim()
                ),
            );
        }
        // Decoding holds the colour planes, transparency, one inflated channel and the
        // clipped RGBA at once.
        let area = w * h;
        let clipped = ((clip[2] - clip[0]) * (clip[3] - clip[1])) as u64;
        let planes = colour_ids.len() as u64 + 1;
        spend.take(
            area.saturating_mul(planes + bps)
                .saturating_add(clipped * 4),
            true,
        )?;
        let channel = |data, kind| Channel {
            data,
            width: w as usize,
            height: h as usize,
            depth: header.depth,
            large: header.large,
            kind,
        };
        for (plane, &id) in colour.iter_mut().zip(colour_ids) {
            let Some(&(_, data)) = slices.iter().find(|s| s.0 == id) else {
                return Err(damaged(format!("layer '{name}' has no channel {id}")));
            };
            channels::decode(&channel(data, Kind::Colour), plane)?;
            budget.check()?;
        }
        let has_alpha = match slices.iter().find(|s| s.0 == -1) {
            Some(&(_, data)) => {
                channels::decode(&channel(data, Kind::Alpha), &mut alpha)?;
                true
            }
            None => false,
        };
        let planes = compose::Planes {
            colour: &colour,
            alpha: has_alpha.then_some(alpha.as_slice()),
            width: w as usize,
            origin: (left, top),
        };
        match compose::compose(&planes, clip, r.opacity) {
            Some((image, left, top)) => {
                spend.take(image.rgba.len() as u64, false)?;
                layers.push(Layer {
                    name,
                    image,
                    left,
                    top,
                });
                if layers.len() > MAX_PARTS {
                    return Err(LayersError::TooManyLayers { max: MAX_PARTS });
                }
            }
            None => note(
                &mut notes,
                &mut left_out,
                format!("layer '{name}' has no visible pixel: left out"),
            ),
        }
    }
    if left_out > 0 {
        notes.push(format!("... and {left_out} more notes (layers left out)"));
    }
    Ok(Layered {
        width: header.width,
        height: header.height,
        layers,
        notes,
    })
}
