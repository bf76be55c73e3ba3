//! The page's text messages read within a memory bound per kind.
//!
//! A message's kind (its `op`) is read first, without keeping anything of the rest; a message
//! longer than its kind allows ([`limit_of`]) is refused with its size and the limit, before
//! it is parsed. The kinds that may be large (outlines, mesh and outline files' text, painted
//! triangles, draw orders, drags) are then parsed straight into their typed fields, so that
//! reading one holds at most 16 times its length at its peak besides the message itself
//! (`tests/studio_messages_fuzz.rs` checks it; a message of many one-point loops, the worst,
//! about 12 times), where serde's tree of values cost about 30 times and was kept. Every other kind is small
//! ([`SMALL_MESSAGE`]) and read through [`Request`]'s own parser. The text of a refused message
//! is dropped when the refusal is sent.

use std::borrow::Cow;

use serde::de::IgnoredAny;
use serde::Deserialize;

use super::protocol::Request;

/// The most bytes of a message of a small kind (every kind not listed in [`limit_of`]).
pub const SMALL_MESSAGE: usize = 64 << 10;
/// The most bytes of a drag (the keyframe's pins and their targets).
pub const MAX_DRAG_MESSAGE: usize = 1 << 20;
/// The most bytes of a whole outline (`outline_set`): room for
/// [`crate::project::MAX_OUTLINE_POINTS`] points written at full precision.
pub const MAX_OUTLINE_MESSAGE: usize = 16 << 20;
/// The most bytes of painted triangles or a draw order.
pub const MAX_FACES_MESSAGE: usize = 8 << 20;
/// The most bytes of a file's text sent in a message (`load_keyframe`, `import_outline`): as
/// large as an upload ([`super::workspace::MAX_UPLOAD`]).
pub const MAX_FILE_MESSAGE: usize = super::workspace::MAX_UPLOAD;
/// The most bytes of any text message.
pub const MAX_TEXT_MESSAGE: usize = MAX_FILE_MESSAGE;

/// The most bytes a message of kind `op` may have.
pub fn limit_of(op: &str) -> usize {
    match op {
        "drag" => MAX_DRAG_MESSAGE,
        "outline_set" => MAX_OUTLINE_MESSAGE,
        "paint_depth" | "paint_stiffness" | "part_order" => MAX_FACES_MESSAGE,
        "load_keyframe" | "import_outline" => MAX_FILE_MESSAGE,
        _ => SMALL_MESSAGE,
    }
}

/// Why a message was not read.
#[derive(Debug, thiserror::Error)]
pub enum MessageError {
    /// Longer than any message may be.
    #[error(
        "a message of {size} bytes: messages are at most {limit} bytes (send files as uploads)"
    )]
    TooLong {
        /// Its length.
        size: usize,
        /// The limit.
        limit: usize,
    },
    /// Longer than its kind may be.
    #[error("a '{op}' message of {size} bytes: at most {limit} bytes")]
    KindTooLong {
        /// Its kind.
        op: String,
        /// Its length.
        size: usize,
        /// The limit.
        limit: usize,
    },
    /// Not a request.
    #[error("bad request: {0}")]
    Bad(#[from] serde_json::Error),
}

#[derive(Deserialize)]
struct Op<'a> {
    #[serde(borrow)]
    op: Cow<'a, str>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OutlineSet {
    #[allow(dead_code)]
    op: IgnoredAny,
    loops: Vec<Vec<[f64; 2]>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Drag {
    #[allow(dead_code)]
    op: IgnoredAny,
    seq: u32,
    pins: Vec<u32>,
    targets: Vec<[f64; 2]>,
    #[serde(default)]
    moving: Option<Vec<u32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LoadKeyframe {
    #[allow(dead_code)]
    op: IgnoredAny,
    name: String,
    text: String,
    time: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ImportOutline {
    #[allow(dead_code)]
    op: IgnoredAny,
    name: String,
    text: String,
    vertices: usize,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PaintDepth {
    #[allow(dead_code)]
    op: IgnoredAny,
    #[serde(default)]
    faces: Vec<u32>,
    #[serde(default)]
    all: bool,
    level: i8,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PaintStiffness {
    #[allow(dead_code)]
    op: IgnoredAny,
    #[serde(default)]
    faces: Vec<u32>,
    #[serde(default)]
    all: bool,
    weight: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PartOrder {
    #[allow(dead_code)]
    op: IgnoredAny,
    order: Vec<u32>,
}

/// Reads a text message from the page, within its kind's bound.
///
/// # Errors
/// [`MessageError::TooLong`] or [`MessageError::KindTooLong`] (checked before parsing), or
/// [`MessageError::Bad`] for what is not a request.
pub fn parse_request(text: &str) -> Result<Request, MessageError> {
    let size = text.len();
    if size > MAX_TEXT_MESSAGE {
        return Err(MessageError::TooLong {
            size,
            limit: MAX_TEXT_MESSAGE,
        });
    }
    let op = serde_json::from_str::<Op<'_>>(text)?.op;
    let limit = limit_of(&op);
    if size > limit {
        return Err(MessageError::KindTooLong {
            op: op.into_owned(),
            size,
            limit,
        });
    }
    Ok(match &*op {
        "outline_set" => {
            let m: OutlineSet = serde_json::from_str(text)?;
            Request::OutlineSet { loops: m.loops }
        }
        "drag" => {
            let m: Drag = serde_json::from_str(text)?;
            Request::Drag {
                seq: m.seq,
                pins: m.pins,
                targets: m.targets,
                moving: m.moving,
            }
        }
        "load_keyframe" => {
            let m: LoadKeyframe = serde_json::from_str(text)?;
            Request::LoadKeyframe {
                name: m.name,
                text: m.text,
                time: m.time,
            }
        }
        "import_outline" => {
            let m: ImportOutline = serde_json::from_str(text)?;
            Request::ImportOutline {
                name: m.name,
                text: m.text,
                vertices: m.vertices,
            }
        }
        "paint_depth" => {
            let m: PaintDepth = serde_json::from_str(text)?;
            Request::PaintDepth {
                faces: m.faces,
                all: m.all,
                level: m.level,
            }
        }
        "paint_stiffness" => {
            let m: PaintStiffness = serde_json::from_str(text)?;
            Request::PaintStiffness {
                faces: m.faces,
                all: m.all,
                weight: m.weight,
            }
        }
        "part_order" => {
            let m: PartOrder = serde_json::from_str(text)?;
            Request::PartOrder { order: m.order }
        }
        _ => serde_json::from_str::<Request>(text)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_kinds_parse_as_the_request_parser_does() {
        for text in [
            r#"{"op":"outline_set","loops":[[[0,0],[1,0],[0,1]]]}"#,
            r#"{"loops":[],"op":"outline_set"}"#,
            r#"{"op":"drag","seq":3,"pins":[1,2],"targets":[[0.5,1],[2,3]]}"#,
            r#"{"op":"drag","seq":3,"pins":[1,2],"targets":[[0.5,1],[2,3]],"moving":[2]}"#,
            r#"{"op":"load_keyframe","name":"a.obj","text":"v 0 0\n","time":2}"#,
            r#"{"op":"import_outline","name":"a.svg","text":"<svg/>","vertices":300}"#,
            r#"{"op":"paint_depth","faces":[1,2],"level":-3}"#,
            r#"{"op":"paint_stiffness","all":true,"weight":10}"#,
            r#"{"op":"part_order","order":[2,0,1]}"#,
            r#"{"op":"select","keyframe":1}"#,
        ] {
            let ours = format!("{:?}", parse_request(text).unwrap());
            let theirs = format!("{:?}", serde_json::from_str::<Request>(text).unwrap());
            assert_eq!(ours, theirs, "{text}");
        }
        for bad in [
            r#"{"op":"outline_set","loops":[],"extra":1}"#,
            r#"{"op":"drag","seq":3,"pins":[1]}"#,
            r#"{"op":"no_such_thing"}"#,
            r#"{"loops":[]}"#,
            "not json",
        ] {
            assert!(
                matches!(parse_request(bad), Err(MessageError::Bad(_))),
                "{bad}"
            );
        }
    }

    #[test]
    fn each_kind_is_refused_over_its_limit_before_parsing() {
        let long_select = format!(
            r#"{{"op":"select","keyframe":1,"pad":"{}"}}"#,
            "x".repeat(SMALL_MESSAGE)
        );
        let e = parse_request(&long_select).unwrap_err();
        assert!(matches!(e, MessageError::KindTooLong { .. }), "{e}");
        assert!(e.to_string().contains("'select'"), "{e}");
        let points = "[1,2],".repeat(MAX_OUTLINE_MESSAGE / 6 + 1);
        let outline = format!(r#"{{"op":"outline_set","loops":[[{points}[0,0]]]}}"#);
        let e = parse_request(&outline).unwrap_err();
        assert!(
            e.to_string()
                .contains(&format!("at most {MAX_OUTLINE_MESSAGE} bytes")),
            "{e}"
        );
    }
}
