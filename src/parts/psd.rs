//! Photoshop's PSD, through the `psd` crate: 8-bit RGB documents with their layers and groups.
//! The header is checked here first (the kind of document, and the canvas against the file's
//! memory budget) so that nothing is decoded for a file that cannot be read; the crate's own
//! panics on damaged files are caught and reported as damage.
//!
//! Visibility: Photoshop sets flag bit 1 on a *hidden* layer (the flags of a visible layer
//! are 0x08, of a hidden one 0x0a); `psd` 0.3.5's `visible()` returns that bit as it is
//! (chinedufn/psd#55, fixed after the release), so here it reads as "hidden". The crate's
//! version is pinned for that reason.

use std::panic::{catch_unwind, AssertUnwindSafe};

use super::layers::{apply_opacity, crop, one_line, Layer, Layered, LayersError, Spend};

const FORMAT: &str = "PSD";

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

/// The header's canvas size, after checking that the document is one that is read.
fn header(bytes: &[u8]) -> Result<(u32, u32), LayersError> {
    if bytes.len() < 26 {
        return Err(damaged("the header is cut short"));
    }
    let u16_at = |i: usize| u16::from_be_bytes([bytes[i], bytes[i + 1]]);
    let u32_at =
        |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    match u16_at(4) {
        1 => {}
        2 => return Err(unsupported("a large document (PSB); save it as PSD")),
        v => return Err(damaged(format!("version {v} (PSD files are version 1)"))),
    }
    let (height, width, depth, mode) = (u32_at(14), u32_at(18), u16_at(22), u16_at(24));
    if !(1..=30_000).contains(&width) || !(1..=30_000).contains(&height) {
        return Err(damaged(format!(
            "a canvas of {width} x {height} pixels (PSD canvases are 1 to 30000 a side)"
        )));
    }
    let mode_name = match mode {
        0 => "bitmap",
        1 => "greyscale",
        2 => "indexed colour",
        3 => "RGB",
        4 => "CMYK",
        7 => "multichannel",
        8 => "duotone",
        9 => "Lab colour",
        _ => "an unknown colour mode",
    };
    if mode != 3 {
        return Err(unsupported(format!(
            "{mode_name}; 8-bit RGB is read (convert the document to RGB)"
        )));
    }
    if depth != 8 {
        return Err(unsupported(format!(
            "{depth} bits per channel; 8-bit RGB is read (convert the document to 8 bits)"
        )));
    }
    Ok((width, height))
}

/// Checks that the four sections after the header (colour mode data, image resources, layers
/// and masks, image data) lie within the file, as their lengths say.
fn sections(bytes: &[u8]) -> Result<(), LayersError> {
    let mut at = 26usize;
    for name in [
        "colour mode data",
        "image resources",
        "layer and mask information",
    ] {
        let len = bytes
            .get(at..at + 4)
            .map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]) as usize)
            .ok_or_else(|| damaged(format!("the file ends before its {name}")))?;
        at = at
            .checked_add(4 + len)
            .filter(|&end| end <= bytes.len())
            .ok_or_else(|| damaged(format!("its {name} run past the end of the file")))?;
    }
    if bytes.len() < at + 2 {
        return Err(damaged("the file ends before its image data"));
    }
    Ok(())
}

thread_local! {
    /// Set while the `psd` crate runs on this thread: its panics are reported as damage, not
    /// printed.
    static QUIET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f` with the `psd` crate's panics caught and not printed (other threads' panics are
/// printed as before: the hook installed once defers to the previous one).
fn quietly<T>(f: impl FnOnce() -> T) -> std::thread::Result<T> {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(std::cell::Cell::get) {
                previous(info);
            }
        }));
    });
    QUIET.with(|q| q.set(true));
    let result = catch_unwind(AssertUnwindSafe(f));
    QUIET.with(|q| q.set(false));
    result
}

/// What the `psd` crate's panic said, if anything.
fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "its sections do not agree".into())
}

/// Reads a PSD file's bytes.
///
/// # Errors
/// [`LayersError::Unsupported`] for documents other than 8-bit RGB and for PSB,
/// [`LayersError::Damaged`] for files that do not read, [`LayersError::TooLarge`] beyond the
/// file's [`super::LayerBudget`].
pub fn read_psd(bytes: &[u8]) -> Result<Layered, LayersError> {
    let (width, height) = header(bytes)?;
    sections(bytes)?;
    let mut spend = Spend::new(bytes.len());
    let canvas = u64::from(width) * u64::from(height) * 4;
    // The crate decodes a layer to the whole canvas at a time.
    spend.take(canvas, true)?;
    let psd = quietly(|| psd::Psd::from_bytes(bytes))
        .map_err(|p| {
            let text = panic_text(p.as_ref());
            if text.contains("Zip compression") {
                unsupported("ZIP-compressed channels; save with RLE compression (Photoshop's own)")
            } else {
                damaged(text)
            }
        })?
        .map_err(|e| damaged(e.to_string()))?;
    let groups = psd.groups();
    // A group's path of names and whether it and every group around it are visible.
    let group_of = |mut id: Option<u32>| -> (String, bool, Option<String>) {
        let mut names = Vec::new();
        let mut visible = true;
        let mut hidden_group = None;
        let mut steps = 0;
        while let Some(g) = id.and_then(|i| groups.get(&i)) {
            names.push(g.name().to_owned());
            // Bit 1 set: hidden (see the module docs).
            if g.visible() {
                visible = false;
                hidden_group = Some(g.name().to_owned());
            }
            id = g.parent_id();
            steps += 1;
            if steps > groups.len() {
                break;
            }
        }
        names.reverse();
        (names.join("/"), visible, hidden_group)
    };
    let mut layers = Vec::new();
    let mut notes = Vec::new();
    let mut hidden_groups: Vec<String> = Vec::new();
    // The crate lists the topmost layer first (the file stores the bottom one first, and the
    // crate reverses them); parts are kept bottom first.
    for layer in psd.layers().iter().rev() {
        let (path, group_visible, hidden_group) = group_of(layer.parent_id());
        let name = if path.is_empty() {
            layer.name().to_owned()
        } else {
            format!("{path}/{}", layer.name())
        };
        if !group_visible {
            if let Some(g) = hidden_group {
                if !hidden_groups.contains(&g) {
                    notes.push(format!("group '{g}' is hidden: its layers are left out"));
                    hidden_groups.push(g);
                }
            }
            notes.push(format!("layer '{name}' is hidden: left out"));
            continue;
        }
        // Bit 1 set: hidden (see the module docs).
        if layer.visible() {
            notes.push(format!("layer '{name}' is hidden: left out"));
            continue;
        }
        let mode = format!("{:?}", layer.blend_mode());
        if mode != "Normal" && mode != "PassThrough" {
            notes.push(format!(
                "layer '{name}' blends by {mode}: drawn over the layers below as normal"
            ));
        }
        let mut rgba = quietly(|| layer.rgba())
            .map_err(|p| damaged(format!("layer '{name}': {}", panic_text(p.as_ref()))))?;
        apply_opacity(&mut rgba, layer.opacity());
        match crop(&rgba, width, height, 0, 0) {
            Some((image, left, top)) => {
                spend.take(image.rgba.len() as u64, false)?;
                layers.push(Layer {
                    name,
                    image,
                    left,
                    top,
                });
            }
            None => notes.push(format!("layer '{name}' has no visible pixel: left out")),
        }
    }
    Ok(Layered {
        width,
        height,
        layers,
        notes,
    })
}
