//! A channel's image data: raw (0), RLE/PackBits (1), ZIP (2) and ZIP with prediction (3), at
//! 8, 16 or 32 bits per sample, decoded to 8 bits per sample (16 bits rounded, 32-bit floats
//! clamped to 0..1 and, for colour, encoded as sRGB: Photoshop's 32-bit documents are linear).
//! Every output is sized from the layer's rectangle, which the caller has checked against the
//! file's memory budget; the compressed data only ever fills it (an inflated stream stops at
//! the expected size, so a zip bomb stops there).

use std::io::Read as _;

use super::bytes::Bytes;
use super::{damaged, unsupported};
use crate::parts::layers::LayersError;

/// How a channel's samples are turned to 8 bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    /// A colour channel (32-bit floats are linear light, encoded as sRGB).
    Colour,
    /// Transparency (32-bit floats taken as they are).
    Alpha,
}

/// A channel of `width` x `height` samples of `depth` bits: its compression field and data.
#[derive(Clone, Copy, Debug)]
pub(super) struct Channel<'a> {
    /// The channel's bytes (compression field first).
    pub(super) data: &'a [u8],
    /// Samples per row.
    pub(super) width: usize,
    /// Rows.
    pub(super) height: usize,
    /// Bits per sample: 8, 16 or 32.
    pub(super) depth: u16,
    /// PSB: RLE row byte counts take 4 bytes.
    pub(super) large: bool,
    /// Colour or transparency.
    pub(super) kind: Kind,
}

/// Decodes `channel` into `out` (`width * height` 8-bit samples).
pub(super) fn decode(channel: &Channel<'_>, out: &mut Vec<u8>) -> Result<(), LayersError> {
    let Channel {
        width,
        height,
        depth,
        ..
    } = *channel;
    let bps = usize::from(depth / 8);
    let row_bytes = width * bps;
    out.clear();
    out.reserve_exact(width * height);
    let mut at = Bytes::new(channel.data);
    let compression = at.u16("a channel's compression")?;
    let convert = |row: &[u8], out: &mut Vec<u8>| to_8bit(row, depth, channel.kind, out);
    match compression {
        0 => {
            let raw = at.take((row_bytes * height) as u64, "a raw channel")?;
            for row in raw.chunks_exact(row_bytes.max(1)).take(height) {
                convert(row, out);
            }
        }
        1 => {
            let count = if channel.large { 4 } else { 2 };
            let counts = at.take((height * count) as u64, "an RLE channel's row counts")?;
            let mut row = vec![0u8; row_bytes];
            for c in counts.chunks_exact(count) {
                let n = if channel.large {
                    u32::from_be_bytes([c[0], c[1], c[2], c[3]])
                } else {
                    u32::from(u16::from_be_bytes([c[0], c[1]]))
                };
                let packed = at.take(u64::from(n), "an RLE row")?;
                unpack_bits(packed, &mut row)?;
                convert(&row, out);
            }
        }
        2 | 3 => {
            let size = (row_bytes * height) as u64;
            let mut raw = Vec::with_capacity(size as usize);
            let rest = at.take(at.remaining() as u64, "a ZIP channel")?;
            flate2::read::ZlibDecoder::new(rest)
                .take(size)
                .read_to_end(&mut raw)
                .map_err(|e| damaged(format!("a ZIP channel does not inflate: {e}")))?;
            if (raw.len() as u64) < size {
                return Err(damaged(format!(
                    "a ZIP channel inflates to {} bytes, not the {size} of its layer",
                    raw.len()
                )));
            }
            let mut row = vec![0u8; row_bytes];
            for packed in raw.chunks_exact(row_bytes.max(1)).take(height) {
                row.copy_from_slice(packed);
                if compression == 3 {
                    undo_prediction(&mut row, width, depth);
                }
                convert(&row, out);
            }
        }
        c => {
            return Err(unsupported(format!(
                "channels compressed by method {c}; raw, RLE and ZIP are read"
            )))
        }
    }
    out.resize(width * height, 0);
    Ok(())
}

/// PackBits: a header byte `n`, then `n + 1` literal bytes (0..=127) or one byte repeated
/// `1 - n` times (-127..=-1); -128 is nothing. Fills `row` exactly (a short row is padded
/// with zeros, a long one cut).
fn unpack_bits(mut packed: &[u8], row: &mut [u8]) -> Result<(), LayersError> {
    let mut at = 0usize;
    while let Some((&n, rest)) = packed.split_first() {
        packed = rest;
        let n = n as i8;
        if n >= 0 {
            let len = n as usize + 1;
            let Some(literal) = packed.get(..len) else {
                return Err(damaged("an RLE row ends inside a run"));
            };
            let end = (at + len).min(row.len());
            row[at..end].copy_from_slice(&literal[..end - at]);
            at = end;
            packed = &packed[len..];
        } else if n != -128 {
            let len = 1 - isize::from(n);
            let Some((&b, rest)) = packed.split_first() else {
                return Err(damaged("an RLE row ends inside a run"));
            };
            packed = rest;
            let end = (at + len as usize).min(row.len());
            row[at..end].fill(b);
            at = end;
        }
    }
    row[at..].fill(0);
    Ok(())
}

/// ZIP with prediction: each sample is stored as its difference from the one before it in
/// the row (16 bits: big-endian `u16`s; 32 bits: the row's bytes split into four planes of
/// first, second, third and fourth bytes, then differenced byte by byte).
fn undo_prediction(row: &mut [u8], width: usize, depth: u16) {
    match depth {
        8 => {
            for i in 1..row.len() {
                row[i] = row[i].wrapping_add(row[i - 1]);
            }
        }
        16 => {
            let mut prev = 0u16;
            for c in row.chunks_exact_mut(2) {
                prev = prev.wrapping_add(u16::from_be_bytes([c[0], c[1]]));
                c.copy_from_slice(&prev.to_be_bytes());
            }
        }
        _ => {
            for i in 1..row.len() {
                row[i] = row[i].wrapping_add(row[i - 1]);
            }
            let planes = row.to_vec();
            for x in 0..width {
                for b in 0..4 {
                    row[x * 4 + b] = planes[b * width + x];
                }
            }
        }
    }
}

/// Appends one row of samples as 8 bits each.
fn to_8bit(row: &[u8], depth: u16, kind: Kind, out: &mut Vec<u8>) {
    match depth {
        8 => out.extend_from_slice(row),
        16 => out.extend(row.chunks_exact(2).map(|c| {
            let v = u32::from(u16::from_be_bytes([c[0], c[1]]));
            ((v * 255 + 32_767) / 65_535) as u8
        })),
        _ => out.extend(row.chunks_exact(4).map(|c| {
            let v = f32::from_be_bytes([c[0], c[1], c[2], c[3]]);
            let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
            let v = match kind {
                Kind::Alpha => v,
                Kind::Colour if v <= 0.003_130_8 => v * 12.92,
                Kind::Colour => 1.055 * v.powf(1.0 / 2.4) - 0.055,
            };
            (v * 255.0).round() as u8
        })),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packbits_runs_literals_and_no_ops() {
        let mut row = [0u8; 8];
        unpack_bits(&[0xfe, 7, 1, 1, 2, 0x80, 0xff, 9], &mut row).expect("unpacks");
        assert_eq!(row, [7, 7, 7, 1, 2, 9, 9, 0]);
        assert!(unpack_bits(&[3, 1], &mut row).is_err());
    }

    #[test]
    fn prediction_is_undone_per_sample() {
        let mut row = [1u8, 1, 1, 255];
        undo_prediction(&mut row, 4, 8);
        assert_eq!(row, [1, 2, 3, 2]);
        let mut row = [0x01, 0x00, 0x00, 0x01, 0xff, 0xff];
        undo_prediction(&mut row, 3, 16);
        assert_eq!(row, [0x01, 0x00, 0x01, 0x01, 0x01, 0x00]);
    }
}
