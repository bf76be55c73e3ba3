//! What the page and the server say to each other over the socket.
//!
//! The page sends JSON requests ([`Request`], `{"op": "...", ...}`) and, to upload a file, one
//! binary message ([`upload`]). The server answers the page that asked with errors and lists
//! (`{"type": "error"|"ack"|"files", ...}`), and sends every page what its view of the
//! document lacks, as changes: the state (`{"type": "state"}`: small, whatever the size of the
//! mesh), the current keyframe's pins (`{"type": "pins"}`), the outline (`{"type":
//! "outline"}`), and binary messages for the rest mesh ([`kind::MESH`]) and for the shape shown
//! ([`kind::POSE`], [`kind::FRAME`]).
//!
//! Keyframes and vertices are numbered from 0 in requests and answers; the page shows them
//! from 1, and so do messages meant for people.

use serde::Deserialize;

/// Binary message kinds (the first `u32` of each binary message).
pub mod kind {
    /// The keyframe being posed.
    pub const POSE: u32 = 1;
    /// The rest mesh: positions, triangles, texture coordinates.
    pub const MESH: u32 = 2;
    /// A frame of the animation at a time.
    pub const FRAME: u32 = 3;
    /// A keyframe's pose, asked for by a page for its onion skins and key thumbnails.
    pub const GHOST: u32 = 4;
    /// The depth and stiffness painted on the triangles.
    pub const PAINT: u32 = 5;
    /// A file uploaded by the page (page to server).
    pub const UPLOAD: u32 = 10;
}

/// What the page asks for (`{"op": "...", ...}`).
#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "op", rename_all = "snake_case", deny_unknown_fields)]
pub enum Request {
    /// Everything, as to a new page.
    Hello,
    /// Show and pose keyframe `keyframe`.
    Select {
        /// Its index.
        keyframe: usize,
    },
    /// The page's mode: `pose` or `outline`.
    Mode {
        /// The mode.
        mode: String,
    },
    /// A pin on `vertex` of the shape shown. When a frame between keyframes is shown, it
    /// becomes a keyframe first (one undo step with the pin).
    PinAdd {
        /// The vertex.
        vertex: u32,
    },
    /// The pin on `vertex` removed.
    PinRemove {
        /// The vertex.
        vertex: u32,
    },
    /// Every pin of the keyframe shown removed.
    PinsClear,
    /// The pin on `from` moved to vertex `to` of the keyframe shown: the handle is placed
    /// again, the pose does not move.
    PinMove {
        /// The pinned vertex.
        from: u32,
        /// The vertex the pin goes to.
        to: u32,
    },
    /// The pins moved: `pins` (the keyframe's pins, in order, as the page knows them) to
    /// `targets`. Answered with the pose; one undo step per stroke (until `drag_end`).
    Drag {
        /// Echoed in the answer.
        seq: u32,
        /// The pins the page knows (must be the keyframe's).
        pins: Vec<u32>,
        /// One target per pin.
        targets: Vec<[f64; 2]>,
        /// The pins this page moves (vertex numbers, among `pins`): the others keep where
        /// the keyframe has them now, so that two pages dragging different pins at once both
        /// move theirs. Absent: every pin goes to its target.
        #[serde(default)]
        moving: Option<Vec<u32>>,
    },
    /// The mouse was released: the next drag starts a new undo step.
    DragEnd,
    /// The posing method and its parameter.
    Method {
        /// `kvf`, `arap` or `bounded`.
        name: String,
        /// KVF's handle weight.
        weight: Option<f64>,
        /// The bounded method's `K`.
        max_distortion: Option<f64>,
    },
    /// Undo the newest step.
    Undo,
    /// Redo the newest undone step.
    Redo,
    /// The keyframe shown back to the rest shape.
    Reset,
    /// Flipped triangles of keyframe `keyframe` (default: the one shown) repaired by the
    /// bounded-distortion method.
    Repair {
        /// Its index.
        keyframe: Option<usize>,
    },
    /// A new keyframe at `time`: a copy of keyframe `copy` (default: the one shown).
    AddKeyframe {
        /// Seconds.
        time: f64,
        /// The keyframe to copy.
        copy: Option<usize>,
    },
    /// Delete a keyframe (not the first).
    DeleteKeyframe {
        /// Its index.
        keyframe: usize,
    },
    /// Reorder: keyframe `keyframe`'s pose moves to place `to` (times and easings stay).
    MoveKeyframe {
        /// Its index.
        keyframe: usize,
        /// Its new index.
        to: usize,
    },
    /// Move a keyframe in time (not the first); with `ripple`, every later keyframe moves by
    /// the same time (one undo step).
    SetTime {
        /// Its index.
        keyframe: usize,
        /// Seconds.
        time: f64,
        /// Whether the later keyframes move with it.
        #[serde(default)]
        ripple: bool,
    },
    /// The easing of the segment starting at a keyframe.
    SetEasing {
        /// Its index.
        keyframe: usize,
        /// `linear`, `ease-in-out`, `cubic-bezier(x1,y1,x2,y2)`.
        easing: String,
    },
    /// The animation's frame at `time` becomes a keyframe.
    FrameToKeyframe {
        /// Seconds.
        time: f64,
    },
    /// A keyframe read from a mesh file's text (OBJ or OFF, by the name's extension) with the
    /// project's triangles (in any order), at `time`.
    LoadKeyframe {
        /// The file's name (for its format and in messages).
        name: String,
        /// Its text.
        text: String,
        /// Seconds.
        time: f64,
    },
    /// The picture's outline traced (with these background settings, which are kept) and
    /// made the document's outline.
    TraceOutline {
        /// Pixels (default: chosen for the vertex count, or 1).
        tolerance: Option<f64>,
        /// `auto`, a colour, or absent for the picture's transparency.
        background: Option<String>,
        /// The threshold in [0, 1).
        threshold: Option<f64>,
        /// The vertex count the outline is for (its tolerance follows).
        vertices: Option<usize>,
    },
    /// The whole outline replaced (`[]` clears it).
    OutlineSet {
        /// The loops.
        loops: Vec<Vec<[f64; 2]>>,
    },
    /// A new, empty loop, drawn by `outline_point` until `outline_close`.
    OutlineNewLoop,
    /// A point appended to the loop being drawn.
    OutlinePoint {
        /// The point.
        point: [f64; 2],
    },
    /// The loop being drawn is done.
    OutlineClose,
    /// A point of a loop moved.
    OutlineMove {
        /// The loop.
        ring: usize,
        /// The point.
        index: usize,
        /// Its new place.
        to: [f64; 2],
    },
    /// A point inserted before `index` in a loop.
    OutlineInsert {
        /// The loop.
        ring: usize,
        /// Its place.
        index: usize,
        /// The point.
        point: [f64; 2],
    },
    /// A point removed (a closed loop left with fewer than three points goes).
    OutlineRemove {
        /// The loop.
        ring: usize,
        /// The point.
        index: usize,
    },
    /// A whole loop of the outline removed (one undo step).
    OutlineRemoveLoop {
        /// The loop.
        ring: usize,
    },
    /// A new mesh from the document's outline, about `vertices` vertices; the animation is
    /// carried over to it (one undo step).
    MeshOutline {
        /// About how many vertices.
        vertices: usize,
    },
    /// A new outline and mesh from an outline file's text (`.svg` or `.poly`).
    ImportOutline {
        /// The file's name.
        name: String,
        /// Its text.
        text: String,
        /// About how many vertices.
        vertices: usize,
    },
    /// The frame rate of playback and exports.
    Fps {
        /// Frames per second, in (0, 240].
        fps: f64,
    },
    /// Paint a depth level on triangles (one brush stroke: one undo step): `faces` (all of
    /// them when `all`) go to `level` (-9 to 9; higher is drawn in front).
    PaintDepth {
        /// The triangles painted.
        #[serde(default)]
        faces: Vec<u32>,
        /// Every triangle instead.
        #[serde(default)]
        all: bool,
        /// The level.
        level: i8,
    },
    /// Paint stiffness on triangles (one brush stroke: one undo step): `faces` (all of them
    /// when `all`) get the weight `weight` (1 normal, up to 10^6).
    PaintStiffness {
        /// The triangles painted.
        #[serde(default)]
        faces: Vec<u32>,
        /// Every triangle instead.
        #[serde(default)]
        all: bool,
        /// The weight.
        weight: f64,
    },
    /// A part hidden or shown while editing, locked or unlocked (one undo step, saved).
    PartFlags {
        /// The part, by its index in the document's list (bottom first).
        part: usize,
        /// Hidden while editing (exports draw every part).
        hidden: bool,
        /// Its vertices take no new pin.
        locked: bool,
    },
    /// A joint between the two front-most parts under `at` (a point of the shape shown), one
    /// undo step (see [`super::rig`]).
    JointAdd {
        /// The point, in the mesh's frame.
        at: [f64; 2],
    },
    /// Joint `joint` (from 0) moved to `to` (a point of the shape shown), between the same two
    /// parts; one undo step.
    JointMove {
        /// The joint.
        joint: usize,
        /// Where to.
        to: [f64; 2],
    },
    /// Joint `joint` (from 0) removed; one undo step.
    JointRemove {
        /// The joint.
        joint: usize,
    },
    /// A character's draw order (one undo step): `order` lists the parts (by their index in
    /// the document's list) bottom first; each is drawn over the ones before it.
    PartOrder {
        /// Every part once, bottom first.
        order: Vec<u32>,
    },
    /// The range playback loops over, `[from, to]` seconds, or `null` for the whole animation.
    LoopRange {
        /// The range.
        range: Option<[f64; 2]>,
    },
    /// The scene's length in seconds, or `null`: it ends at the last keyframe (one undo
    /// step).
    Length {
        /// Seconds.
        length: Option<f64>,
    },
    /// Keyframe `keyframe`'s pose and pins replaced by keyframe `copy`'s (a paste onto a
    /// keyframe; one undo step).
    ReplaceKeyframe {
        /// The keyframe replaced.
        keyframe: usize,
        /// The keyframe copied.
        copy: usize,
    },
    /// Show the animation's frame at `time`.
    Scrub {
        /// Echoed in the answer.
        seq: u32,
        /// Seconds.
        time: f64,
    },
    /// Save the project: as `name` in the workspace (save as), or to its file.
    Save {
        /// A plain file name ending `.json`.
        name: Option<String>,
        /// Whether an existing file of that name may be replaced.
        overwrite: Option<bool>,
    },
    /// Export the animation into the workspace (in the background): `gif`, `mp4`, `apng`,
    /// `webp`, `sheet` (a sprite sheet PNG and its JSON), `frames` (a folder of PNG frames),
    /// `png` (a strip of five frames coloured by distortion), `html`, `obj` (a folder of
    /// frames) or `still` (one frame as PNG).
    Export {
        /// The format.
        format: String,
        /// A plain file (or folder, for `obj` and `frames`) name.
        name: String,
        /// Frames (default: the duration times the frame rate, plus one).
        frames: Option<u32>,
        /// For `still`: the animation's frame at this time (default: the keyframe shown).
        time: Option<f64>,
        /// Picture size `[width, height]` (default: the subject's aspect, 640 pixels on its
        /// longer side).
        #[serde(default)]
        size: Option<[u32; 2]>,
        /// Frames `[first, last]` of the animation's frames (0-based, inclusive).
        #[serde(default)]
        range: Option<[u32; 2]>,
        /// `transparent` or a colour (`#rrggbb`, `white`, ...); default white.
        #[serde(default)]
        background: Option<String>,
        /// Whether an existing file or folder of that name may be replaced (without it, an
        /// existing one is answered with `{"type": "exists", "op": "export", "name", "path"}`
        /// and nothing is written).
        #[serde(default)]
        overwrite: bool,
    },
    /// Cancel the work running in the background.
    Cancel,
    /// The files of the workspace the studio can open (answered with `{"type": "files"}`).
    ListFiles,
    /// Open a file of the workspace: a picture, mesh, outline or project (one undo step).
    Open {
        /// Its plain name.
        name: String,
    },
    /// A picture of the workspace drawn on the mesh (one undo step).
    AttachPicture {
        /// Its plain name.
        name: String,
    },
    /// A keyframe made from another drawing of the subject (a picture of the workspace): the
    /// rest mesh laid over it, in the background; the keyframe is added when it is done (one
    /// undo step), at `time` or a second after the last keyframe.
    DrawingKeyframe {
        /// The drawing's plain name.
        name: String,
        /// Point pairs: a point in the rest picture and the same point in the drawing, each
        /// in pixels from the top-left corner (at most [`crate::project::MAX_DRAWING_PAIRS`]).
        #[serde(default)]
        pairs: Vec<[[f64; 2]; 2]>,
        /// When, in seconds (after the first keyframe).
        #[serde(default)]
        time: Option<f64>,
    },
    /// Where the rest mesh's outline goes on a drawing (the correspondence a drawing keyframe
    /// would use, with these pairs), answered to the asking page only with
    /// `{"type": "correspondence", "name", "loops": [[[ax, ay], [bx, by]], ...]}` (pixels from
    /// the top-left corners), or refused with the reason (different pieces or holes, ...).
    DrawingPreview {
        /// The drawing's plain name.
        name: String,
        /// Point pairs, as [`Request::DrawingKeyframe`] takes them.
        #[serde(default)]
        pairs: Vec<[[f64; 2]; 2]>,
    },
    /// Restore recovered work (one undo step).
    Recover {
        /// The recovery file's name, as listed.
        name: String,
    },
    /// Put recovered work aside without restoring it.
    Discard {
        /// The recovery file's name, as listed.
        name: String,
    },
    /// The poses of some keyframes (at most [`MAX_GHOSTS`]), answered to the asking page
    /// only, one [`kind::GHOST`] message each ([`ghost_bytes`]).
    Ghosts {
        /// Their indices.
        keyframes: Vec<usize>,
    },
    /// A note dismissed.
    Dismiss {
        /// Its number.
        note: u64,
    },
}

/// A binary upload: `[kind::UPLOAD, header length]` as little-endian `u32`, the header (JSON
/// `{"name": ..., "then": "open"|"attach"|"store"}`), then the file's bytes.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UploadHeader {
    /// The file's name (a plain name is made of it).
    pub name: String,
    /// What to do once stored.
    pub then: String,
}

/// Splits an upload message into its header and bytes.
pub fn upload(message: &[u8]) -> Result<(UploadHeader, &[u8]), String> {
    let word = |at: usize| {
        message
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    if word(0) != Some(kind::UPLOAD) {
        return Err("the only binary request is an upload".into());
    }
    let length = word(4).ok_or("an upload without its header")? as usize;
    let header = message
        .get(8..8usize.saturating_add(length))
        .ok_or("an upload's header runs past its end")?;
    let header: UploadHeader =
        serde_json::from_slice(header).map_err(|e| format!("an upload's header: {e}"))?;
    Ok((header, &message[8 + length..]))
}

/// The most keyframe poses one [`Request::Ghosts`] asks for.
pub const MAX_GHOSTS: usize = 64;

/// A keyframe's pose as a binary message: `[kind::GHOST, keyframe, n, revision]` as u32 (the
/// revision is the keyframe's `rev` in the state, low 32 bits), then `2n` f32 positions.
pub fn ghost_bytes(keyframe: usize, revision: u64, positions: &[[f64; 2]]) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 + 8 * positions.len());
    for x in [
        kind::GHOST,
        keyframe as u32,
        positions.len() as u32,
        revision as u32,
    ] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    for p in positions {
        out.extend_from_slice(&(p[0] as f32).to_le_bytes());
        out.extend_from_slice(&(p[1] as f32).to_le_bytes());
    }
    out
}

/// The bytes before a frame's positions ([`frame_bytes`]).
pub const FRAME_HEADER: usize = 40;

/// A frame as a binary message: `[kind, seq, n, m]` as u32, `[largest distortion]` f32,
/// `[flipped]` u32, `[time]` f32, `[keyframe]` u32 (or `u32::MAX`), `[time]` again as f64
/// (the time shown, exactly as the server holds it: what the page's playhead and every
/// command at the playhead use), then `2n` f32 positions and `m` f32 distortions (flipped
/// triangles as f32 infinity).
#[allow(clippy::too_many_arguments)]
pub fn frame_bytes(
    kind: u32,
    seq: u32,
    time: f64,
    keyframe: Option<usize>,
    positions: &[[f64; 2]],
    distortion: &[f64],
    worst: f64,
    flipped: usize,
) -> Vec<u8> {
    let mut out = Vec::with_capacity(FRAME_HEADER + 8 * positions.len() + 4 * distortion.len());
    for x in [kind, seq, positions.len() as u32, distortion.len() as u32] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out.extend_from_slice(&(worst as f32).to_le_bytes());
    out.extend_from_slice(&(flipped as u32).to_le_bytes());
    out.extend_from_slice(&(time as f32).to_le_bytes());
    out.extend_from_slice(&keyframe.map_or(u32::MAX, |k| k as u32).to_le_bytes());
    out.extend_from_slice(&time.to_le_bytes());
    for p in positions {
        out.extend_from_slice(&(p[0] as f32).to_le_bytes());
        out.extend_from_slice(&(p[1] as f32).to_le_bytes());
    }
    for d in distortion {
        out.extend_from_slice(&(*d as f32).to_le_bytes());
    }
    out
}

/// The rest mesh as a binary message ([`kind::MESH`]): header `[kind, n, m, textured]`, then
/// `2n` f32 positions, `3m` u32 triangles, and `2n` f32 texture coordinates when textured.
pub fn mesh_bytes(
    positions: &[[f64; 2]],
    faces: &[[u32; 3]],
    texcoords: Option<&[[f64; 2]]>,
) -> Vec<u8> {
    let (n, m) = (positions.len(), faces.len());
    let mut out = Vec::with_capacity(16 + 16 * n + 12 * m);
    for x in [
        kind::MESH,
        n as u32,
        m as u32,
        u32::from(texcoords.is_some()),
    ] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    for p in positions {
        out.extend_from_slice(&(p[0] as f32).to_le_bytes());
        out.extend_from_slice(&(p[1] as f32).to_le_bytes());
    }
    for f in faces {
        for v in f {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    if let Some(uv) = texcoords {
        for p in uv {
            out.extend_from_slice(&(p[0] as f32).to_le_bytes());
            out.extend_from_slice(&(p[1] as f32).to_le_bytes());
        }
    }
    out
}

/// The painted depth and stiffness ([`kind::PAINT`]): header `[kind, m, has_depth,
/// has_stiffness]`, then `m` i8 levels padded to a multiple of 4 bytes when there is a
/// depth, then `m` f32 weights when there is a stiffness.
pub fn paint_bytes(faces: usize, depth: Option<&[i8]>, stiffness: Option<&[f64]>) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 + 5 * faces);
    for x in [
        kind::PAINT,
        faces as u32,
        u32::from(depth.is_some()),
        u32::from(stiffness.is_some()),
    ] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    if let Some(d) = depth {
        out.extend(d.iter().map(|&v| v as u8));
        out.resize(16 + d.len().next_multiple_of(4), 0);
    }
    if let Some(w) = stiffness {
        for v in w {
            out.extend_from_slice(&(*v as f32).to_le_bytes());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uploads_are_split_and_checked() {
        let header = br#"{"name":"a.png","then":"open"}"#;
        let mut message = Vec::new();
        message.extend_from_slice(&kind::UPLOAD.to_le_bytes());
        message.extend_from_slice(&(header.len() as u32).to_le_bytes());
        message.extend_from_slice(header);
        message.extend_from_slice(b"PNGDATA");
        let (h, bytes) = upload(&message).expect("an upload");
        assert_eq!(
            (h.name.as_str(), h.then.as_str(), bytes),
            ("a.png", "open", &b"PNGDATA"[..])
        );
        assert!(upload(&message[..10]).is_err());
        assert!(upload(b"").is_err());
        let mut long = message.clone();
        long[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(upload(&long).is_err());
        let mut other = message;
        other[0] = 7;
        assert!(upload(&other).is_err());
    }

    #[test]
    fn the_mesh_message_holds_positions_triangles_and_texture_coordinates() {
        let bytes = mesh_bytes(
            &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            &[[0, 1, 2]],
            Some(&[[0.5, 0.5]; 3]),
        );
        assert_eq!(bytes.len(), 16 + 24 + 12 + 24);
        assert_eq!(
            f32::from_le_bytes(bytes[24..28].try_into().expect("x")),
            1.0
        );
        assert_eq!(u32::from_le_bytes(bytes[48..52].try_into().expect("c")), 2);
        assert_eq!(
            f32::from_le_bytes(bytes[52..56].try_into().expect("u")),
            0.5
        );
        assert_eq!(mesh_bytes(&[[0.0, 0.0]], &[], None).len(), 24);
    }
}
