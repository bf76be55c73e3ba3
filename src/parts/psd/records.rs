//! The layer and mask information section: the layer records (rectangle, channels, blend
//! mode, opacity, flags, name, group divider), and where the channel image data starts. 16-
//! and 32-bit documents keep their layers in a tagged block (`Lr16`, `Lr32`) after the global
//! layer mask instead; that is followed too.

use super::bytes::Bytes;
use super::damaged;
use crate::parts::layers::LayersError;

/// A layer record.
#[derive(Clone, Debug)]
pub(super) struct Record {
    /// Top, left, bottom, right on the canvas (bottom and right exclusive).
    pub(super) rect: [i32; 4],
    /// Each channel's id (0.. colour, -1 transparency, -2 and -3 user masks) and the length
    /// of its image data (compression field included).
    pub(super) channels: Vec<(i16, u64)>,
    /// The blend mode's key (`norm`, `pass`, `mul `, ...).
    pub(super) blend: [u8; 4],
    /// Opacity, 0 to 255.
    pub(super) opacity: u8,
    /// Hidden (flag bit 1).
    pub(super) hidden: bool,
    /// Its name (the Unicode name when there is one).
    pub(super) name: String,
    /// A group's divider (`lsct`): 1 an open folder, 2 a closed one (the group's own record,
    /// above its layers), 3 the bounding divider (below them); `None` for a layer.
    pub(super) divider: Option<u32>,
}

impl Record {
    /// Width and height of the layer's rectangle (0 for an empty or inverted one).
    pub(super) fn size(&self) -> (u64, u64) {
        let [top, left, bottom, right] = self.rect.map(i64::from);
        ((right - left).max(0) as u64, (bottom - top).max(0) as u64)
    }
}

/// Keys whose length is 8 bytes in a PSB.
const LONG_KEYS: [&[u8; 4]; 13] = [
    b"LMsk", b"Lr16", b"Lr32", b"Layr", b"Mt16", b"Mt32", b"Mtrn", b"Alph", b"FMsk", b"lnk2",
    b"FEid", b"FXid", b"PxSD",
];

/// One tagged block (additional layer information): its key and contents, or `None` at the
/// end of the blocks (fewer than 12 bytes left, or no signature: what follows is not read).
fn tagged<'a>(
    at: &mut Bytes<'a>,
    large: bool,
) -> Result<Option<([u8; 4], Bytes<'a>)>, LayersError> {
    let mut peek = *at;
    // Some writers pad a block to 4 bytes without counting the padding in its length.
    for _ in 0..3 {
        if peek.remaining() >= 12 && !peek.starts_with(b"8B") {
            peek.take(1, "a tagged block")?;
        }
    }
    if peek.remaining() < 12 {
        return Ok(None);
    }
    let sig = peek.take(4, "a tagged block")?;
    if sig != b"8BIM" && sig != b"8B64" {
        return Ok(None);
    }
    let mut key = [0u8; 4];
    key.copy_from_slice(peek.take(4, "a tagged block's key")?);
    let long = large && LONG_KEYS.contains(&&key);
    let body = peek.section(long, "a tagged block")?;
    *at = peek;
    Ok(Some((key, body)))
}

/// Reads a record's extra data: mask and blending ranges (skipped), the Pascal name, and the
/// tagged blocks `luni` (the Unicode name) and `lsct`/`lsdk` (a group's divider).
fn extra(mut at: Bytes<'_>, large: bool) -> Result<(String, Option<u32>), LayersError> {
    at.section(false, "a layer's mask data")?;
    at.section(false, "a layer's blending ranges")?;
    let n = at.u8("a layer's name")?;
    let mut name = String::from_utf8_lossy(at.take(u64::from(n), "a layer's name")?).into_owned();
    // The name is padded to a multiple of 4 bytes, its length byte included.
    let pad = (4 - (1 + usize::from(n)) % 4) % 4;
    at.take(pad.min(at.remaining()) as u64, "a layer's name")?;
    let mut divider = None;
    while let Some((key, mut body)) = tagged(&mut at, large)? {
        match &key {
            b"luni" => {
                let count = body.u32("a Unicode name")?;
                if let Ok(units) = body.take(u64::from(count) * 2, "a Unicode name") {
                    let units: Vec<u16> = units
                        .chunks_exact(2)
                        .map(|c| u16::from_be_bytes([c[0], c[1]]))
                        .collect();
                    let text = String::from_utf16_lossy(&units);
                    let text = text.trim_end_matches('\0');
                    if !text.is_empty() {
                        name = text.to_owned();
                    }
                }
            }
            b"lsct" | b"lsdk" => divider = Some(body.u32("a group divider")?),
            _ => {}
        }
    }
    Ok((name, divider))
}

/// Reads one layer record.
fn record(at: &mut Bytes<'_>, large: bool) -> Result<Record, LayersError> {
    let mut rect = [0i32; 4];
    for r in &mut rect {
        *r = at.i32("a layer's rectangle")?;
    }
    let count = at.u16("a layer's channel count")?;
    // Each channel entry takes 6 (PSB: 10) bytes: the count is checked against what is left.
    let entry = if large { 10 } else { 6 };
    if u64::from(count) * entry > at.remaining() as u64 {
        return Err(damaged(format!(
            "a layer declares {count} channels, more than the file holds"
        )));
    }
    let mut channels = Vec::with_capacity(usize::from(count));
    for _ in 0..count {
        let id = at.u16("a channel's id")? as i16;
        let len = at.len(large, "a channel's length")?;
        channels.push((id, len));
    }
    if at.take(4, "a blend mode")? != b"8BIM" {
        return Err(damaged("a layer record's blend mode signature is not 8BIM"));
    }
    let mut blend = [0u8; 4];
    blend.copy_from_slice(at.take(4, "a blend mode")?);
    let opacity = at.u8("an opacity")?;
    let _clipping = at.u8("a clipping flag")?;
    let flags = at.u8("a layer's flags")?;
    let _filler = at.u8("a layer record")?;
    let extra_data = at.section(false, "a layer's extra data")?;
    let (name, divider) = extra(extra_data, large)?;
    Ok(Record {
        rect,
        channels,
        blend,
        opacity,
        hidden: flags & 2 != 0,
        name,
        divider: divider.filter(|d| (1..=3).contains(d)),
    })
}

/// The layer info (count, records) and a cursor at its channel image data.
fn layer_info<'a>(mut at: Bytes<'a>, large: bool) -> Result<(Vec<Record>, Bytes<'a>), LayersError> {
    if at.remaining() == 0 {
        return Ok((Vec::new(), at));
    }
    // Negative: the first alpha channel holds the merged picture's transparency.
    let count = (at.u16("the layer count")? as i16).unsigned_abs();
    let mut records = Vec::new();
    for _ in 0..count {
        records.push(record(&mut at, large)?);
    }
    Ok((records, at))
}

/// Reads the layer and mask information section: the records, bottom first as stored, and
/// a cursor at their channel image data.
pub(super) fn read(
    mut section: Bytes<'_>,
    large: bool,
) -> Result<(Vec<Record>, Bytes<'_>), LayersError> {
    if section.remaining() == 0 {
        return Ok((Vec::new(), section));
    }
    let info = section.section(large, "the layer info")?;
    let (records, data) = layer_info(info, large)?;
    if !records.is_empty() {
        return Ok((records, data));
    }
    // 16- and 32-bit documents: the layers are in a tagged block after the global mask.
    if section.remaining() >= 4 {
        section.section(false, "the global layer mask")?;
    }
    while let Some((key, body)) = tagged(&mut section, large)? {
        if matches!(&key, b"Lr16" | b"Lr32" | b"Layr") {
            return layer_info(body, large);
        }
    }
    Ok((records, data))
}
