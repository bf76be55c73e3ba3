//! The studio's document and its file: one JSON document, versioned, with everything an
//! animation needs: the rest mesh (positions, triangles, texture coordinates), the texture's
//! file (by a path relative to the project file), the outline the mesh was made from, how the
//! picture's subject was told from its background, the posing method, and the keyframes (each
//! a pose, its time in seconds, the easing of the segment that starts there, and its handles).
//!
//! ```json
//! {
//!   "format": "bdmorph-studio",
//!   "version": 4,
//!   "mesh": { "positions": [[0, 0], [1, 0], [0, 1]], "faces": [[0, 1, 2]], "texcoords": null },
//!   "texture": null,
//!   "method": { "name": "sd", "weight": 100, "max_distortion": 3 },
//!   "fps": 25,
//!   "outline": [[[0, 0], [1, 0], [0, 1]]],
//!   "picture": { "background": null, "threshold": null },
//!   "keyframes": [
//!     { "time": 0, "easing": "linear", "positions": [[0, 0], [1, 0], [0, 1]], "pins": [] }
//!   ]
//! }
//! ```
//!
//! Version 1 files (without `outline` and `picture`), version 2 files (without keyframes'
//! drawings) and version 3 files (without parts' `hidden` and `locked` and the scene's
//! `length`) are read as well; a project without a `length` plays and exports from 0 to its
//! last keyframe, as before. A file is refused whole,
//! with the reason, when it is not JSON, is another program's or a newer version's, is damaged
//! (a pose with the wrong number of points or a point that is not finite, a triangle naming a
//! missing vertex, times out of order, an unknown easing, a pin out of range or twice, ...), or
//! is beyond the studio's limits ([`MAX_KEYFRAMES`], [`MAX_KEYFRAME_POINTS`],
//! [`MAX_OUTLINE_POINTS`]). Nothing that fails these checks is ever written.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::mesh::PlanarMesh;

/// The `format` field of every project file.
pub const FORMAT: &str = "bdmorph-studio";
/// The version this studio writes (it reads this one and versions 1, 2 and 3).
pub const VERSION: u32 = 4;
/// The longest scene, in seconds (a day).
pub const MAX_LENGTH: f64 = 86_400.0;

/// The most keyframes a project holds.
pub const MAX_KEYFRAMES: usize = 1000;
/// The most keyframe points (keyframes times vertices) a project holds: 20 million points,
/// 320 MB of poses (100 keyframes of a 200,000-vertex mesh, 1,000 of a 20,000-vertex one).
pub const MAX_KEYFRAME_POINTS: usize = 20_000_000;
/// The largest project file read: 1 GiB (the most keyframe points, written as JSON text, fit
/// in it with room to spare). Larger files are refused before they are read.
pub const MAX_PROJECT_BYTES: u64 = crate::io::MAX_INPUT_BYTES;
/// The most points of all outline loops together.
pub const MAX_OUTLINE_POINTS: usize = 200_000;
/// The smallest and largest handle weight (of `sd` and `kvf`) the studio takes (beyond them
/// the posing system cannot be factored reliably).
pub const KVF_WEIGHTS: (f64, f64) = (1e-3, 1e6);
/// The largest distortion bound the studio takes.
pub const MAX_BOUND: f64 = 1e4;

/// A project.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Project {
    /// Always [`FORMAT`].
    pub format: String,
    /// Always [`VERSION`].
    pub version: u32,
    /// The rest shape.
    pub mesh: MeshData,
    /// The texture's file, relative to the project file (or absolute), if any.
    pub texture: Option<String>,
    /// How poses follow their handles.
    pub method: MethodData,
    /// Playback and export frame rate.
    pub fps: f64,
    /// The loops the mesh was made from (or is being drawn), in the mesh's frame: the region
    /// of odd winding is meshed. Empty when the mesh came from elsewhere.
    #[serde(default)]
    pub outline: Vec<Vec<[f64; 2]>>,
    /// How the picture's subject is told from its background when it is traced.
    #[serde(default)]
    pub picture: PictureSettings,
    /// The keyframes, in time order; the first is at time 0.
    pub keyframes: Vec<Keyframe>,
    /// The range playback loops over, `[from, to]` seconds (`from < to`), or the whole
    /// animation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loop_range: Option<[f64; 2]>,
    /// The scene's length in seconds, set by the animator: playback and exports cover
    /// `[0, length]`, the last keyframe's pose held after it (a length before the last
    /// keyframe counts as the last keyframe's time: see [`Project::end`]). `None`: the
    /// animation ends at its last keyframe, as projects saved before version 4 play.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<f64>,
    /// The draw order: a depth level per triangle (from -[`MAX_DEPTH`] to [`MAX_DEPTH`]),
    /// painted on the rest mesh; where a pose overlaps itself the higher level is drawn in
    /// front. `None`: every triangle at level 0, drawn in triangle order.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth: Option<Vec<i8>>,
    /// Stiffness: a weight per triangle (1 normal, up to [`MAX_STIFFNESS`]), painted on the
    /// rest mesh; stiff triangles keep their shape while the rest bends (see
    /// [`crate::deform::Deformer::set_stiffness`]). `None`: all 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<Vec<f64>>,
    /// A character's parts (one per layer of the layered picture it was made from), bottom
    /// first: each a range of vertices and of triangles. `None`: one mesh, no parts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parts: Option<Vec<PartData>>,
    /// Joints: pairs of vertices (of different pieces) that stay together. Posing treats them
    /// as one vertex; the animation places each piece so that they meet (see
    /// [`crate::parts`]). `None`: no joints.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joints: Option<Vec<[u32; 2]>>,
    /// How the animation's frames are placed: `"fit"` (by the similarity that best fits the
    /// keyframes, so that parts that hold still between keyframes hold still in between;
    /// what [`Project::new`] sets) or `"anchor"` (by a vertex and an edge, as projects saved
    /// without this field play). See [`crate::Placement`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub placement: Option<String>,
}

/// A part of a character: a layer's mesh within the project's.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PartData {
    /// The layer's name.
    pub name: String,
    /// Its vertices, `[first, end)`.
    pub vertices: [u32; 2],
    /// Its triangles, `[first, end)` (parts are drawn in triangle order).
    pub faces: [u32; 2],
    /// Hidden while editing (exports and `bdmorph render` draw every part). Absent: shown.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub hidden: bool,
    /// Locked: its vertices take no new pin in the studio. Absent: unlocked.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub locked: bool,
}

/// Whether `parts` lie within `n` vertices and `m` triangles and do not share any.
pub fn check_parts(parts: Option<&[PartData]>, n: usize, m: usize) -> Result<(), String> {
    let Some(parts) = parts else { return Ok(()) };
    for p in parts {
        if p.name.len() > 1000 {
            return Err("a part's name is longer than 1000 bytes".into());
        }
        let ok = p.vertices[0] <= p.vertices[1]
            && p.vertices[1] as usize <= n
            && p.faces[0] <= p.faces[1]
            && p.faces[1] as usize <= m;
        if !ok {
            return Err(format!(
                "part '{}': its vertices or triangles are beyond the mesh's",
                p.name
            ));
        }
    }
    for range in [|p: &PartData| p.vertices, |p: &PartData| p.faces] {
        let mut spans: Vec<[u32; 2]> = parts.iter().map(range).collect();
        spans.sort_unstable();
        if spans.windows(2).any(|w| w[1][0] < w[0][1]) {
            return Err("two parts share vertices or triangles".into());
        }
    }
    Ok(())
}

/// `doc` with its parts drawn in `order` (indices into its parts, bottom first, each once):
/// the triangles regrouped part by part in that order (the depth and stiffness painted go
/// with them), the parts listed in it. Also the edit's label.
pub fn with_part_order(doc: &Project, order: &[u32]) -> Result<(Project, String), String> {
    let parts = doc.parts.as_deref().ok_or("the document has no parts")?;
    let mut seen = vec![false; parts.len()];
    if order.len() != parts.len()
        || order.iter().any(|&i| {
            let fresh = seen.get(i as usize).is_some_and(|s| !s);
            if fresh {
                seen[i as usize] = true;
            }
            !fresh
        })
    {
        return Err(format!(
            "a draw order lists each of the {} parts once",
            parts.len()
        ));
    }
    let m = doc.mesh.faces.len();
    // New triangle order: the parts' triangles in the new order, then any outside every part.
    let mut in_part = vec![false; m];
    let mut old_of_new: Vec<usize> = Vec::with_capacity(m);
    let mut new_parts = Vec::with_capacity(parts.len());
    for &i in order {
        let p = &parts[i as usize];
        let first = old_of_new.len() as u32;
        for f in p.faces[0]..p.faces[1] {
            in_part[f as usize] = true;
            old_of_new.push(f as usize);
        }
        new_parts.push(PartData {
            name: p.name.clone(),
            vertices: p.vertices,
            faces: [first, old_of_new.len() as u32],
            hidden: p.hidden,
            locked: p.locked,
        });
    }
    old_of_new.extend((0..m).filter(|&f| !in_part[f]));
    let mut out = doc.clone();
    out.mesh.faces = old_of_new.iter().map(|&f| doc.mesh.faces[f]).collect();
    out.depth = doc
        .depth
        .as_ref()
        .map(|d| old_of_new.iter().map(|&f| d[f]).collect());
    out.stiffness = doc
        .stiffness
        .as_ref()
        .map(|w| old_of_new.iter().map(|&f| w[f]).collect());
    out.parts = Some(new_parts);
    // The label names the part that moved the most places.
    let moved = order
        .iter()
        .enumerate()
        .max_by_key(|&(at, &i)| (at as i64 - i64::from(i)).abs())
        .map(|(at, &i)| (parts[i as usize].name.clone(), at as i64 - i64::from(i)));
    let label = match moved {
        Some((name, d)) if d > 0 => format!("draw {name} further in front"),
        Some((name, d)) if d < 0 => format!("draw {name} further behind"),
        _ => "draw order".to_owned(),
    };
    Ok((out, label))
}

/// Whether `joints` name two different vertices each, within `n`.
pub fn check_joints(joints: Option<&[[u32; 2]]>, n: usize) -> Result<(), String> {
    let Some(joints) = joints else { return Ok(()) };
    for &[a, b] in joints {
        if a as usize >= n || b as usize >= n || a == b {
            return Err(format!(
                "a joint ties vertices {a} and {b}: two different vertices of the {n} are needed"
            ));
        }
    }
    Ok(())
}

/// The deepest depth level either way (levels run from `-MAX_DEPTH` to `MAX_DEPTH`).
pub const MAX_DEPTH: i8 = 9;
/// The largest stiffness weight.
pub const MAX_STIFFNESS: f64 = 1e6;

/// Whether `depth` has one level per triangle of `faces`, each within [`MAX_DEPTH`].
pub fn check_depth(depth: Option<&[i8]>, faces: usize) -> Result<(), String> {
    let Some(depth) = depth else { return Ok(()) };
    if depth.len() != faces {
        return Err(format!(
            "{} depth levels for {faces} triangles",
            depth.len()
        ));
    }
    if let Some(f) = depth
        .iter()
        .position(|d| d.unsigned_abs() > MAX_DEPTH.unsigned_abs())
    {
        return Err(format!(
            "triangle {}: depth level {} is not between -{MAX_DEPTH} and {MAX_DEPTH}",
            f + 1,
            depth[f]
        ));
    }
    Ok(())
}

/// Whether `stiffness` has one weight per triangle of `faces`, each in `[1, MAX_STIFFNESS]`.
pub fn check_stiffness(stiffness: Option<&[f64]>, faces: usize) -> Result<(), String> {
    let Some(weights) = stiffness else {
        return Ok(());
    };
    if weights.len() != faces {
        return Err(format!(
            "{} stiffness weights for {faces} triangles",
            weights.len()
        ));
    }
    if let Some(f) = weights
        .iter()
        .position(|w| !(1.0..=MAX_STIFFNESS).contains(w))
    {
        return Err(format!(
            "triangle {}: stiffness {} is not between 1 and {MAX_STIFFNESS}",
            f + 1,
            weights[f]
        ));
    }
    Ok(())
}

/// The scene's length: none, or a number of seconds in (0, [`MAX_LENGTH`]].
///
/// # Errors
/// A length that is not finite, not positive or too long, in words.
pub fn check_length(length: Option<f64>) -> Result<(), String> {
    match length {
        Some(l) if !(l.is_finite() && l > 0.0 && l <= MAX_LENGTH) => Err(format!(
            "scene length {l} s: give one in (0, {MAX_LENGTH}] seconds"
        )),
        _ => Ok(()),
    }
}

/// Whether a loop range is `[from, to]` with `0 <= from < to`, both finite.
pub fn check_loop_range(range: Option<[f64; 2]>) -> Result<(), String> {
    match range {
        Some([from, to]) if !(from.is_finite() && to.is_finite() && from >= 0.0 && from < to) => {
            Err(format!(
                "loop range {from} s to {to} s: give 0 <= from < to"
            ))
        }
        _ => Ok(()),
    }
}

/// How the picture's subject is told from its background (as `bdmorph mesh --background
/// --threshold` takes them).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PictureSettings {
    /// `auto`, a colour (`#rrggbb`, `white`, ...), or `None` for the picture's transparency.
    pub background: Option<String>,
    /// The threshold in [0, 1) (see `bdmorph mesh --threshold`), or the default.
    pub threshold: Option<f64>,
}

impl PictureSettings {
    /// The meshing options these settings stand for.
    pub fn options(&self) -> Result<crate::meshing::PictureOptions, String> {
        let mut options = crate::meshing::PictureOptions::default();
        if let Some(b) = &self.background {
            options = options.with_background(b.parse()?);
        }
        if let Some(t) = self.threshold {
            if !(0.0..1.0).contains(&t) {
                return Err(format!("threshold {t}: give one in [0, 1)"));
            }
            options = options.with_threshold(t);
        }
        Ok(options)
    }
}

/// The rest mesh.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeshData {
    /// One point per vertex.
    pub positions: Vec<[f64; 2]>,
    /// Counter-clockwise triangles.
    pub faces: Vec<[u32; 3]>,
    /// One texture coordinate per vertex, if the mesh is textured.
    pub texcoords: Option<Vec<[f64; 2]>>,
}

/// The posing method and its parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MethodData {
    /// `sd`, `kvf`, `arap` or `bounded`.
    pub name: String,
    /// The handles' weight of `sd` and `kvf`.
    pub weight: f64,
    /// The bounded method's bound `K`.
    pub max_distortion: f64,
}

impl MethodData {
    /// Whether the method is one the studio knows, with parameters it can use.
    pub fn check(&self) -> Result<(), String> {
        if !["sd", "kvf", "arap", "bounded"].contains(&self.name.as_str()) {
            return Err(format!(
                "unknown method \"{}\" (sd, kvf, arap or bounded)",
                self.name
            ));
        }
        let (lo, hi) = KVF_WEIGHTS;
        if !(self.weight >= lo && self.weight <= hi) {
            return Err(format!(
                "handle weight {}: give one from {lo} to {hi}",
                self.weight
            ));
        }
        if !(self.max_distortion >= 1.0 && self.max_distortion <= MAX_BOUND) {
            return Err(format!(
                "distortion bound {}: give one from 1 to {MAX_BOUND}",
                self.max_distortion
            ));
        }
        Ok(())
    }
}

/// Whether `keyframes` keyframes of `vertices` points each are within the studio's limits.
pub fn check_limits(keyframes: usize, vertices: usize) -> Result<(), String> {
    if keyframes > MAX_KEYFRAMES {
        return Err(format!(
            "{keyframes} keyframes: a project holds at most {MAX_KEYFRAMES}"
        ));
    }
    if keyframes.saturating_mul(vertices) > MAX_KEYFRAME_POINTS {
        return Err(format!(
            "{keyframes} keyframes of {vertices} vertices: a project holds at most {MAX_KEYFRAME_POINTS} keyframe points ({} keyframes of this mesh)",
            MAX_KEYFRAME_POINTS / vertices.max(1)
        ));
    }
    Ok(())
}

/// Whether an outline's points are finite and within [`MAX_OUTLINE_POINTS`].
pub fn check_outline(loops: &[Vec<[f64; 2]>]) -> Result<(), String> {
    let points: usize = loops.iter().map(Vec::len).sum();
    if points > MAX_OUTLINE_POINTS {
        return Err(format!(
            "the outline has {points} points; the studio takes at most {MAX_OUTLINE_POINTS}"
        ));
    }
    if loops.iter().flatten().flatten().any(|c| !c.is_finite()) {
        return Err("an outline point is not finite".into());
    }
    Ok(())
}

/// Whether `pins` name distinct vertices of `n`.
pub fn check_pins(pins: &[u32], n: usize) -> Result<(), String> {
    let mut seen = std::collections::HashSet::with_capacity(pins.len());
    for &v in pins {
        if v as usize >= n {
            return Err(format!("a pin names vertex {} of {n}", u64::from(v) + 1));
        }
        if !seen.insert(v) {
            return Err(format!("vertex {} is pinned twice", u64::from(v) + 1));
        }
    }
    Ok(())
}

impl Default for MethodData {
    /// What new projects pose with: `sd` (symmetric Dirichlet, soft handles of weight 100),
    /// which neither flips nor crushes a triangle. Project files name their method, so an
    /// older project keeps the one it names (`kvf`, before).
    fn default() -> Self {
        MethodData {
            name: "sd".into(),
            weight: 100.0,
            max_distortion: 3.0,
        }
    }
}

/// A keyframe.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Keyframe {
    /// When it is reached, in seconds.
    pub time: f64,
    /// The easing of the segment from this keyframe to the next (`linear`, `ease-in-out`,
    /// `cubic-bezier(x1,y1,x2,y2)`).
    pub easing: String,
    /// The pose, one point per vertex.
    pub positions: Vec<[f64; 2]>,
    /// The handles it was posed with (vertex numbers).
    pub pins: Vec<u32>,
    /// The drawing it was made from, if any: its picture is cross-faded in over the segment
    /// that ends here and out over the one that starts here.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drawing: Option<KeyframeDrawing>,
}

/// The most point pairs a keyframe's drawing keeps.
pub const MAX_DRAWING_PAIRS: usize = 200;

/// A keyframe made from a drawing of the subject: the rest mesh laid over the drawing's
/// picture (see [`crate::inbetween::fit_drawing`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KeyframeDrawing {
    /// The picture's file, relative to the project file (as [`Project::texture`]).
    pub picture: String,
    /// One texture coordinate per vertex in that picture (`x / width`, `y / height`, y up).
    pub texcoords: Vec<[f64; 2]>,
    /// The point pairs it was made with: a point in the rest picture and one in the drawing,
    /// each in pixels from the top-left corner.
    pub pairs: Vec<[[f64; 2]; 2]>,
}

/// Checks a keyframe's drawing against a mesh of `n` vertices.
pub fn check_drawing(drawing: &KeyframeDrawing, n: usize) -> Result<(), String> {
    if drawing.picture.is_empty() || drawing.picture.len() > 4096 {
        return Err("a drawing's picture has no name, or one over 4096 bytes".into());
    }
    if drawing.texcoords.len() != n || drawing.texcoords.iter().flatten().any(|c| !c.is_finite()) {
        return Err(format!(
            "its drawing has {} texture coordinates for {n} vertices, or one not finite",
            drawing.texcoords.len()
        ));
    }
    if drawing.pairs.len() > MAX_DRAWING_PAIRS {
        return Err(format!(
            "its drawing has {} point pairs (at most {MAX_DRAWING_PAIRS})",
            drawing.pairs.len()
        ));
    }
    if drawing
        .pairs
        .iter()
        .flatten()
        .flatten()
        .any(|c| !c.is_finite())
    {
        return Err("its drawing has a point pair that is not finite".into());
    }
    Ok(())
}

/// Why a project could not be read or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ProjectError {
    /// The file could not be read.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// The file could not be written (nothing was replaced).
    #[error(transparent)]
    Write(#[from] crate::io::WriteError),
    /// Not JSON, or not the project's shape.
    #[error("not a bdmorph studio project: {0}")]
    Json(#[from] serde_json::Error),
    /// Another program's JSON.
    #[error("not a bdmorph studio project (format \"{0}\")")]
    Format(String),
    /// Another version's file.
    #[error("written by another version of the studio (project version {found}; this one reads version {VERSION})")]
    Version {
        /// The file's version.
        found: u32,
    },
    /// The file is damaged: the reason.
    #[error("damaged project: {0}")]
    Damaged(String),
}

impl Project {
    /// A project with `mesh` as its rest shape and one keyframe, the rest pose, at time 0.
    pub fn new(mesh: &PlanarMesh, texcoords: Option<Vec<[f64; 2]>>) -> Project {
        Project {
            format: FORMAT.into(),
            version: VERSION,
            mesh: MeshData {
                positions: mesh.positions.clone(),
                faces: mesh.faces.clone(),
                texcoords,
            },
            texture: None,
            method: MethodData::default(),
            fps: 25.0,
            outline: Vec::new(),
            picture: PictureSettings::default(),
            keyframes: vec![Keyframe {
                time: 0.0,
                easing: "linear".into(),
                positions: mesh.positions.clone(),
                pins: Vec::new(),
                drawing: None,
            }],
            loop_range: None,
            length: None,
            depth: None,
            stiffness: None,
            parts: None,
            joints: None,
            placement: Some(crate::Placement::Fit.to_string()),
        }
    }

    /// How the animation's frames are placed: [`Project::placement`], anchor when absent.
    ///
    /// # Errors
    /// A name that is neither `fit` nor `anchor`, in words.
    pub fn placement(&self) -> Result<crate::Placement, String> {
        self.placement
            .as_deref()
            .map_or(Ok(crate::Placement::Anchor), str::parse)
    }

    /// The last keyframe's time, in seconds.
    pub fn last_key(&self) -> f64 {
        self.keyframes.last().map_or(0.0, |k| k.time)
    }

    /// Where playback and exports end, in seconds: the scene's [`Project::length`] when one
    /// is set (never before the last keyframe), else the last keyframe's time.
    pub fn end(&self) -> f64 {
        let last = self.last_key();
        self.length.map_or(last, |l| l.max(last))
    }

    /// The rest mesh.
    pub fn rest(&self) -> PlanarMesh {
        PlanarMesh {
            positions: self.mesh.positions.clone(),
            faces: self.mesh.faces.clone(),
        }
    }

    /// Parses and checks a project.
    pub fn from_json(bytes: &[u8]) -> Result<Project, ProjectError> {
        // The envelope first, so another program's or version's file says so rather than
        // failing on a field it does not have.
        #[derive(Deserialize)]
        struct Envelope {
            format: Option<String>,
            version: Option<u32>,
        }
        let envelope: Envelope = serde_json::from_slice(bytes)?;
        match envelope.format.as_deref() {
            Some(FORMAT) => {}
            other => return Err(ProjectError::Format(other.unwrap_or("none").into())),
        }
        match envelope.version {
            Some(1..=3 | VERSION) => {}
            found => {
                return Err(ProjectError::Version {
                    found: found.unwrap_or(0),
                })
            }
        }
        let mut project: Project = serde_json::from_slice(bytes)?;
        project.version = VERSION;
        project.check()?;
        Ok(project)
    }

    /// Reads and checks a project file: a regular file (a pipe, device or folder is refused
    /// before it is opened) of at most [`MAX_PROJECT_BYTES`].
    pub fn read(path: &Path) -> Result<Project, ProjectError> {
        Project::from_json(&crate::io::read_input(path, MAX_PROJECT_BYTES)?)
    }

    /// The project as JSON.
    pub fn to_json(&self) -> Vec<u8> {
        // Serialising plain numbers, strings and vectors cannot fail.
        serde_json::to_vec_pretty(self).unwrap_or_default()
    }

    /// Checks the project, then writes it atomically (a temporary file renamed over the
    /// target): a project that fails [`Project::check`] is never written.
    pub fn write(&self, path: &Path) -> Result<(), ProjectError> {
        self.check()?;
        crate::io::write_bytes_atomic(path, &self.to_json())?;
        Ok(())
    }

    /// Checks everything a damaged file could get wrong.
    pub fn check(&self) -> Result<(), ProjectError> {
        let damaged = |why: String| Err(ProjectError::Damaged(why));
        if let Err(e) = self.placement() {
            return damaged(e);
        }
        let n = self.mesh.positions.len();
        let rest = self.rest();
        if let Err(e) = rest.validate() {
            return damaged(format!("the mesh: {e}"));
        }
        if let Some(uv) = &self.mesh.texcoords {
            if uv.len() != n || uv.iter().flatten().any(|c| !c.is_finite()) {
                return damaged(format!(
                    "{} texture coordinates for {n} vertices, or one not finite",
                    uv.len()
                ));
            }
        }
        if let Err(e) = self.method.check() {
            return damaged(e);
        }
        if !(self.fps > 0.0 && self.fps <= 240.0) {
            return damaged(format!("frame rate {}", self.fps));
        }
        if self.keyframes.is_empty() {
            return damaged("no keyframes".into());
        }
        if let Err(e) = check_limits(self.keyframes.len(), n) {
            return damaged(e);
        }
        if let Err(e) = check_outline(&self.outline) {
            return damaged(e);
        }
        if let Err(e) = self.picture.options() {
            return damaged(format!("picture settings: {e}"));
        }
        if let Err(e) = check_loop_range(self.loop_range) {
            return damaged(e);
        }
        if let Err(e) = check_length(self.length) {
            return damaged(e);
        }
        let m = self.mesh.faces.len();
        if let Err(e) = check_depth(self.depth.as_deref(), m) {
            return damaged(e);
        }
        if let Err(e) = check_stiffness(self.stiffness.as_deref(), m) {
            return damaged(e);
        }
        if let Err(e) = check_parts(self.parts.as_deref(), n, m) {
            return damaged(e);
        }
        if let Err(e) = check_joints(self.joints.as_deref(), n) {
            return damaged(e);
        }
        let mut last = f64::NEG_INFINITY;
        for (k, key) in self.keyframes.iter().enumerate() {
            // Keyframes are numbered from 1, as the page shows them.
            let shown = k + 1;
            if key.positions.len() != n {
                return damaged(format!(
                    "keyframe {shown} has {} points for {n} vertices",
                    key.positions.len()
                ));
            }
            if key.positions.iter().flatten().any(|c| !c.is_finite()) {
                return damaged(format!("keyframe {shown} has a point that is not finite"));
            }
            if !(key.time.is_finite() && key.time > last) || (k == 0 && key.time != 0.0) {
                return damaged(format!(
                    "keyframe {shown} at time {}: times start at 0 and increase",
                    key.time
                ));
            }
            last = key.time;
            if let Err(e) = key.easing.parse::<crate::Easing>() {
                return damaged(format!("keyframe {shown}: {e}"));
            }
            if let Err(e) = check_pins(&key.pins, n) {
                return damaged(format!("keyframe {shown}: {e}"));
            }
            if let Some(d) = &key.drawing {
                if let Err(e) = check_drawing(d, n) {
                    return damaged(format!("keyframe {shown}: {e}"));
                }
            }
        }
        Ok(())
    }
}

/// The path through `meshes` (the keyframes' poses, with `doc`'s triangles) with the
/// document's times and easings and its placement; keyframes with flipped triangles are
/// accepted (`--allow-inverted`) and reached exactly ([`crate::MorphOptions::with_reach_inverted`]).
///
/// # Errors
/// The path's, when the keyframes cannot be morphed.
pub fn path_of(
    doc: &Project,
    meshes: &[PlanarMesh],
) -> Result<crate::KeyframePath, crate::MorphError> {
    use crate::{Easing, MorphOptions, PathOptions};
    let keys = &doc.keyframes;
    let durations: Vec<f64> = keys.windows(2).map(|w| w[1].time - w[0].time).collect();
    let easings: Vec<Easing> = keys[..keys.len().saturating_sub(1)]
        .iter()
        .map(|k| k.easing.parse().unwrap_or(Easing::Linear))
        .collect();
    let placement = doc.placement().unwrap_or_default();
    let options = PathOptions::default()
        .with_durations(durations)
        .with_easings(easings)
        .with_morph(
            MorphOptions::default()
                .with_allow_inverted(true)
                .with_reach_inverted(true)
                .with_placement(placement),
        );
    crate::KeyframePath::with_options(meshes, options)
}

/// A project's animation, frame by frame, as the studio plays and exports it: the path through
/// its keyframes (their times and easings), and for a character in parts, its pieces placed so
/// that their joints meet ([`crate::parts::Placement`]).
///
/// ```
/// use bdmorph::project::{Animation, Keyframe, Project};
/// let rest = bdmorph::generate::grid(4, 3, 0.0);
/// let mut doc = Project::new(&rest, None);
/// let moved: Vec<[f64; 2]> = rest.positions.iter().map(|p| [p[0] + 1.0, p[1]]).collect();
/// doc.keyframes.push(Keyframe { time: 2.0, easing: "linear".into(), positions: moved, pins: vec![], drawing: None });
/// let mut animation = Animation::new(&doc)?;
/// let mut frame = vec![[0.0; 2]; rest.positions.len()];
/// assert_eq!(animation.frame_into(1.0, &mut frame)?, 1.0);
/// assert!((frame[0][0] - 0.5).abs() < 1e-9);
/// # Ok::<(), String>(())
/// ```
#[derive(Debug)]
pub struct Animation {
    path: crate::KeyframePath,
    placement: Option<crate::parts::Placement>,
    /// Where it ends ([`Project::end`]).
    duration: f64,
    /// The last keyframe's time (the path's end; its pose is held from there on).
    last: f64,
}

impl Animation {
    /// The animation of `doc` (at least two keyframes).
    ///
    /// # Errors
    /// One keyframe only, or keyframes that cannot be morphed (the path's error, in words).
    pub fn new(doc: &Project) -> Result<Animation, String> {
        if doc.keyframes.len() < 2 {
            return Err("the project has one keyframe: add a second to animate it".into());
        }
        let meshes: Vec<PlanarMesh> = doc
            .keyframes
            .iter()
            .map(|k| PlanarMesh {
                positions: k.positions.clone(),
                faces: doc.mesh.faces.clone(),
            })
            .collect();
        let placement = doc
            .joints
            .as_deref()
            .filter(|j| !j.is_empty())
            .map(|j| crate::parts::Placement::new(&doc.rest(), j));
        Ok(Animation {
            path: path_of(doc, &meshes).map_err(|e| e.to_string())?,
            placement,
            duration: doc.end(),
            last: doc.last_key(),
        })
    }

    /// How long it lasts, in seconds: the scene's length when the project sets one, else
    /// the last keyframe's time ([`Project::end`]).
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// The animation at `time` seconds (clamped to it) into `out` (one point per vertex); the
    /// time used. After the last keyframe, its pose is held.
    ///
    /// # Errors
    /// The path's, in words.
    pub fn frame_into(&mut self, time: f64, out: &mut [[f64; 2]]) -> Result<f64, String> {
        let time = if time.is_finite() {
            time.clamp(0.0, self.duration)
        } else {
            0.0
        };
        let t = if self.last > 0.0 {
            time.min(self.last) / self.last
        } else {
            0.0
        };
        self.path_at(t, out)?;
        Ok(time)
    }

    /// The animation at `t` in [0, 1] of its duration into `out`.
    ///
    /// # Errors
    /// The path's, in words.
    pub fn frame_at(&mut self, t: f64, out: &mut [[f64; 2]]) -> Result<(), String> {
        // Without a length of its own the animation is its path, frame for frame.
        let t = if self.duration > self.last && self.last > 0.0 {
            (t * self.duration).min(self.last) / self.last
        } else {
            t
        };
        self.path_at(t, out)
    }

    /// The path at `t` in [0, 1] of its keyframes' span, placed.
    fn path_at(&mut self, t: f64, out: &mut [[f64; 2]]) -> Result<(), String> {
        self.path.frame_into(t, out).map_err(|e| e.to_string())?;
        if let Some(placement) = self.placement.as_mut() {
            placement.apply(out);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate;

    #[test]
    fn a_project_round_trips_and_damage_is_named() {
        let mesh = generate::disk(4, 0.1);
        let mut project = Project::new(&mesh, None);
        project.keyframes.push(Keyframe {
            time: 1.5,
            easing: "ease-in-out".into(),
            positions: generate::bend(&mesh, 0.3).positions,
            pins: vec![0, 3],
            drawing: Some(KeyframeDrawing {
                picture: "b.png".into(),
                texcoords: vec![[0.25, 0.5]; mesh.positions.len()],
                pairs: vec![[[1.0, 2.0], [3.0, 4.0]]],
            }),
        });
        let back = Project::from_json(&project.to_json()).expect("reads back");
        assert_eq!(back, project);

        let text = String::from_utf8(project.to_json()).expect("utf8");
        let broken = |from: &str, to: &str| {
            Project::from_json(text.replacen(from, to, 1).as_bytes())
                .expect_err("refused")
                .to_string()
        };
        assert!(broken("\"version\": 4", "\"version\": 5").contains("another version"));
        assert!(broken("bdmorph-studio", "something-else").contains("not a bdmorph studio"));
        assert!(broken("\"time\": 1.5", "\"time\": 0.0").contains("times start at 0"));
        assert!(broken("ease-in-out", "bouncy").contains("keyframe 2"));
        assert!(broken("\"b.png\"", "\"\"").contains("picture has no name"));
        let mut short = project.clone();
        if let Some(d) = short.keyframes[1].drawing.as_mut() {
            d.texcoords.pop();
        }
        assert!(short
            .check()
            .expect_err("refused")
            .to_string()
            .contains("keyframe 2: its drawing has"));
        assert!(broken("\"name\": \"sd\"", "\"name\": \"magic\"").contains("unknown method"));
        assert!(Project::from_json(b"{ not json").is_err());
        assert!(Project::from_json(&project.to_json()[..100]).is_err());
        let mut short = project.clone();
        short.keyframes[1].positions.pop();
        let e = Project::from_json(&short.to_json()).expect_err("refused");
        assert!(e.to_string().contains("keyframe 2 has"), "{e}");
        let mut pinned = project.clone();
        pinned.keyframes[1].pins.push(10_000);
        assert!(Project::from_json(&pinned.to_json()).is_err());
        let mut twice = project.clone();
        twice.keyframes[1].pins.push(0);
        let e = Project::from_json(&twice.to_json()).expect_err("refused");
        assert!(e.to_string().contains("pinned twice"), "{e}");
        // Nothing that fails the checks is written.
        let mut nan = project.clone();
        nan.keyframes[1].positions[2][0] = f64::NAN;
        let path = std::env::temp_dir().join(format!("bdmorph-nan-{}.json", std::process::id()));
        assert!(nan.write(&path).is_err());
        assert!(!path.exists());
        let mut weak = project.clone();
        weak.method.weight = 1e-300;
        assert!(weak.check().is_err());
    }

    #[test]
    fn version_1_files_are_read() {
        let mesh = generate::disk(3, 0.1);
        let project = Project::new(&mesh, None);
        let mut value: serde_json::Value =
            serde_json::from_slice(&project.to_json()).expect("json");
        let object = value.as_object_mut().expect("object");
        object.remove("outline");
        object.remove("picture");
        object.insert("version".into(), 1.into());
        let back = Project::from_json(value.to_string().as_bytes()).expect("reads");
        assert_eq!(back, project);
        // Version 2 (outline and picture, no drawings) too.
        let mut value: serde_json::Value =
            serde_json::from_slice(&project.to_json()).expect("json");
        value["version"] = 2.into();
        let back = Project::from_json(value.to_string().as_bytes()).expect("reads");
        assert_eq!(back, project);
        // Version 3 (parts without hidden and locked) too: every part shown and unlocked.
        let mut parted = project.clone();
        parted.parts = Some(vec![PartData {
            name: "body".into(),
            vertices: [0, mesh.positions.len() as u32],
            faces: [0, mesh.faces.len() as u32],
            ..PartData::default()
        }]);
        let mut value: serde_json::Value = serde_json::from_slice(&parted.to_json()).expect("json");
        assert!(
            value["parts"][0].get("hidden").is_none(),
            "absent when false"
        );
        value["version"] = 3.into();
        let back = Project::from_json(value.to_string().as_bytes()).expect("reads");
        assert_eq!(back, parted);
        let mut flagged = parted.clone();
        if let Some(p) = flagged.parts.as_mut() {
            p[0].hidden = true;
            p[0].locked = true;
        }
        let back = Project::from_json(&flagged.to_json()).expect("reads");
        assert_eq!(back, flagged);
    }

    #[test]
    fn a_part_order_regroups_the_triangles_and_their_paint() {
        // Two pieces of two triangles each, as two parts.
        let mut positions = Vec::new();
        let mut faces = Vec::new();
        for k in 0..2u32 {
            let x = f64::from(k) * 3.0;
            positions.extend([[x, 0.0], [x + 1.0, 0.0], [x + 1.0, 1.0], [x, 1.0]]);
            let o = 4 * k;
            faces.extend([[o, o + 1, o + 2], [o, o + 2, o + 3]]);
        }
        let mesh = PlanarMesh { positions, faces };
        let mut doc = Project::new(&mesh, None);
        doc.parts = Some(vec![
            PartData {
                name: "a".into(),
                vertices: [0, 4],
                faces: [0, 2],
                ..PartData::default()
            },
            PartData {
                name: "b".into(),
                vertices: [4, 8],
                faces: [2, 4],
                hidden: true,
                locked: true,
            },
        ]);
        doc.depth = Some(vec![1, 2, 3, 4]);
        let (out, label) = with_part_order(&doc, &[1, 0]).expect("reordered");
        assert_eq!(out.mesh.faces[..2], mesh.faces[2..]);
        assert_eq!(out.depth, Some(vec![3, 4, 1, 2]));
        let names: Vec<&str> = out
            .parts
            .as_ref()
            .expect("parts")
            .iter()
            .map(|p| p.name.as_str())
            .collect();
        assert_eq!(names, ["b", "a"]);
        assert_eq!(out.parts.as_ref().expect("parts")[0].faces, [0, 2]);
        // Hidden and locked go with their part.
        assert!(out.parts.as_ref().expect("parts")[0].hidden);
        assert!(out.parts.as_ref().expect("parts")[0].locked);
        assert!(!out.parts.as_ref().expect("parts")[1].locked);
        assert!(label.contains("draw"), "{label}");
        out.check().expect("a valid project");
        for bad in [&[0u32][..], &[0, 0], &[0, 2], &[]] {
            assert!(with_part_order(&doc, bad).is_err(), "{bad:?}");
        }
        assert!(with_part_order(&Project::new(&mesh, None), &[0]).is_err());
    }
}
