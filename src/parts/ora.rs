//! OpenRaster (`.ora`), as Krita, GIMP and MyPaint write it: a zip holding `mimetype`
//! (`image/openraster`), `stack.xml` (the layers and groups, topmost first) and one PNG per
//! layer.

use std::io::{Cursor, Read};

use super::layers::{apply_opacity, crop, one_line, Layer, Layered, LayersError, Spend, MAX_PARTS};
use crate::render::raster;
use crate::Budget;

const FORMAT: &str = "ORA";

/// The largest `stack.xml` read (16 MiB).
const MAX_STACK_BYTES: u64 = 16 << 20;
/// The deepest nesting of groups followed.
const MAX_DEPTH: usize = 64;

fn damaged(why: impl Into<String>) -> LayersError {
    LayersError::Damaged {
        format: FORMAT,
        why: one_line(&why.into()),
    }
}

/// Reads an entry of at most `limit` bytes (its declared size checked first, then what is
/// inflated, so a lying header cannot make it larger). A layer's PNG over `limit` is over the
/// file's pixel budget ([`LayersError::TooLarge`]); another entry (`mimetype`, `stack.xml`)
/// over its own size limit is damage, said with its name.
fn entry(
    archive: &mut zip::ZipArchive<Cursor<&[u8]>>,
    name: &str,
    limit: u64,
) -> Result<Vec<u8>, LayersError> {
    let over = |size: u64| {
        if name == "mimetype" || name == "stack.xml" {
            damaged(format!(
                "{name} is {size} bytes, more than the {limit} bytes it may have"
            ))
        } else {
            LayersError::TooLarge {
                needed: size,
                budget: limit,
            }
        }
    };
    let file = archive
        .by_name(name)
        .map_err(|e| damaged(format!("{name}: {e}")))?;
    if file.size() > limit {
        return Err(over(file.size()));
    }
    let mut out = Vec::with_capacity(file.size() as usize);
    file.take(limit + 1)
        .read_to_end(&mut out)
        .map_err(|e| damaged(format!("{name}: {e}")))?;
    if out.len() as u64 > limit {
        return Err(over(out.len() as u64));
    }
    Ok(out)
}

/// A layer of `stack.xml`, in stacking order (topmost first).
struct Entry {
    name: String,
    src: String,
    x: i64,
    y: i64,
    opacity: f64,
    visible: bool,
}

fn attr_f64(node: roxmltree::Node<'_, '_>, name: &str, default: f64) -> Result<f64, LayersError> {
    match node.attribute(name) {
        None => Ok(default),
        Some(text) => text
            .trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| damaged(format!("stack.xml: {name}=\"{text}\" is not a number"))),
    }
}

/// Walks a `<stack>`'s children (topmost first) into `out`.
fn walk(
    stack: roxmltree::Node<'_, '_>,
    prefix: &str,
    visible: bool,
    depth: usize,
    out: &mut Vec<Entry>,
    notes: &mut Vec<String>,
) -> Result<(), LayersError> {
    if depth > MAX_DEPTH {
        return Err(damaged(format!(
            "stack.xml nests groups more than {MAX_DEPTH} deep"
        )));
    }
    for node in stack.children().filter(|n| n.is_element()) {
        let name = node.attribute("name").unwrap_or("").to_owned();
        let shown = if prefix.is_empty() {
            name.clone()
        } else {
            format!("{prefix}/{name}")
        };
        let own = node.attribute("visibility") != Some("hidden");
        match node.tag_name().name() {
            "stack" => {
                if !own && visible {
                    notes.push(format!(
                        "group '{shown}' is hidden: its layers are left out"
                    ));
                }
                walk(node, &shown, visible && own, depth + 1, out, notes)?;
            }
            "layer" => {
                let src = node
                    .attribute("src")
                    .ok_or_else(|| damaged(format!("stack.xml: layer '{shown}' has no src")))?;
                let x = attr_f64(node, "x", 0.0)?;
                let y = attr_f64(node, "y", 0.0)?;
                if x.abs() > 1e7 || y.abs() > 1e7 {
                    return Err(damaged(format!(
                        "stack.xml: layer '{shown}' lies too far away"
                    )));
                }
                if let Some(op) = node.attribute("composite-op") {
                    if op != "svg:src-over" {
                        notes.push(format!(
                            "layer '{shown}' blends by {op}: drawn over the layers below as normal"
                        ));
                    }
                }
                out.push(Entry {
                    name: shown,
                    src: src.to_owned(),
                    x: x.round() as i64,
                    y: y.round() as i64,
                    opacity: attr_f64(node, "opacity", 1.0)?.clamp(0.0, 1.0),
                    visible: visible && own,
                });
            }
            // Text, filters and other elements are not layers of pixels.
            _ => {}
        }
    }
    Ok(())
}

/// The width and height a PNG's header declares.
fn png_size(bytes: &[u8]) -> Option<(u32, u32)> {
    if !bytes.starts_with(b"\x89PNG\r\n\x1a\n") || bytes.get(12..16) != Some(b"IHDR") {
        return None;
    }
    let w = u32::from_be_bytes(bytes.get(16..20)?.try_into().ok()?);
    let h = u32::from_be_bytes(bytes.get(20..24)?.try_into().ok()?);
    Some((w, h))
}

/// Reads an OpenRaster file's bytes.
///
/// # Errors
/// [`LayersError::Damaged`] for a zip or `stack.xml` that does not read or a layer's PNG that
/// does not decode, [`LayersError::TooLarge`] beyond the file's [`super::LayerBudget`],
/// [`LayersError::TooManyLayers`] beyond [`MAX_PARTS`] layers with pixels.
pub fn read_ora(bytes: &[u8]) -> Result<Layered, LayersError> {
    read_ora_with(bytes, &Budget::unlimited())
}

/// [`read_ora`], checking `budget` between layers.
///
/// # Errors
/// Those of [`read_ora`]; [`LayersError::Stopped`] when the budget runs out or is cancelled.
pub fn read_ora_with(bytes: &[u8], budget: &Budget) -> Result<Layered, LayersError> {
    let mut spend = Spend::new(bytes.len());
    let mut archive =
        zip::ZipArchive::new(Cursor::new(bytes)).map_err(|e| damaged(e.to_string()))?;
    let mimetype = entry(&mut archive, "mimetype", 64)?;
    if mimetype.trim_ascii() != b"image/openraster" {
        return Err(damaged("the mimetype entry is not image/openraster"));
    }
    let stack = entry(&mut archive, "stack.xml", MAX_STACK_BYTES)?;
    let text = std::str::from_utf8(&stack).map_err(|_| damaged("stack.xml is not UTF-8"))?;
    let doc = roxmltree::Document::parse(text).map_err(|e| damaged(format!("stack.xml: {e}")))?;
    let image = doc.root_element();
    if image.tag_name().name() != "image" {
        return Err(damaged("stack.xml's root is not <image>"));
    }
    let size = |name: &str| -> Result<u32, LayersError> {
        image
            .attribute(name)
            .and_then(|t| t.trim().parse::<u32>().ok())
            .filter(|&v| v > 0)
            .ok_or_else(|| {
                damaged(format!(
                    "stack.xml: the image's {name} is not a positive whole number"
                ))
            })
    };
    let (width, height) = (size("w")?, size("h")?);
    let root = image
        .children()
        .find(|n| n.has_tag_name("stack"))
        .ok_or_else(|| damaged("stack.xml has no <stack>"))?;
    let mut entries = Vec::new();
    let mut notes = Vec::new();
    walk(root, "", true, 0, &mut entries, &mut notes)?;
    let mut layers = Vec::new();
    // stack.xml lists the topmost first; parts are kept bottom first.
    for e in entries.iter().rev() {
        budget.check()?;
        if !e.visible {
            notes.push(format!("layer '{}' is hidden: left out", e.name));
            continue;
        }
        let png = entry(&mut archive, &e.src, spend_left(&spend))?;
        let (w, h) = png_size(&png)
            .ok_or_else(|| damaged(format!("layer '{}': {} is not a PNG", e.name, e.src)))?;
        spend.take(u64::from(w) * u64::from(h) * 4, true)?;
        let mut decoded = raster::decode_image(&png)
            .map_err(|err| damaged(format!("layer '{}': {}: {err}", e.name, e.src)))?;
        apply_opacity(&mut decoded.rgba, (e.opacity * 255.0).round() as u8);
        match crop(&decoded.rgba, decoded.width, decoded.height, e.x, e.y) {
            Some((image, left, top)) => {
                spend.take(image.rgba.len() as u64, false)?;
                layers.push(Layer {
                    name: e.name.clone(),
                    image,
                    left,
                    top,
                });
                if layers.len() > MAX_PARTS {
                    return Err(LayersError::TooManyLayers { max: MAX_PARTS });
                }
            }
            None => notes.push(format!("layer '{}' has no visible pixel: left out", e.name)),
        }
    }
    Ok(Layered {
        width,
        height,
        layers,
        notes,
    })
}

/// Bytes left to decode into (the budget less what is kept).
fn spend_left(spend: &Spend) -> u64 {
    spend.left()
}
