//! The studio's edits: every change to the document ([`Project`]) is an [`Edit`], and applying
//! one returns its inverse, the edit that puts the document back exactly. Undo and redo are
//! nothing more than applying the inverse and keeping its own inverse ([`super::history`]).
//!
//! An edit is checked completely before the document changes: a refused edit changes nothing.
//! The document's own checks ([`Project::check`]) hold before and after every edit; what an
//! edit's result means for the engine (a method whose system cannot be factored, a pose that
//! cannot be posed) is checked by the session, which applies the inverse when that fails.
//!
//! Keyframes and vertices are numbered from 0 here; messages number them from 1, as the page
//! shows them.

use super::project::{
    check_depth, check_length, check_limits, check_loop_range, check_outline, check_pins,
    check_stiffness, Keyframe, MeshData, MethodData, PictureSettings, Project,
};

/// One change to the document (kept in the history, and beside the autosave as JSON: an edit
/// read back is checked as every edit is, when it is applied).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Edit {
    /// A keyframe's pose.
    Pose {
        /// The keyframe.
        keyframe: usize,
        /// One point per vertex.
        positions: Vec<[f64; 2]>,
    },
    /// A keyframe's handles.
    Pins {
        /// The keyframe.
        keyframe: usize,
        /// Vertex numbers, distinct.
        pins: Vec<u32>,
    },
    /// A keyframe inserted at place `at` (its time must fall between its neighbours').
    Insert {
        /// Its place.
        at: usize,
        /// The keyframe.
        keyframe: Keyframe,
    },
    /// The keyframe at place `at` removed (not the first).
    Delete {
        /// Its place.
        at: usize,
    },
    /// Keyframe `from`'s pose and pins moved to place `to` in the order (times and easings stay
    /// where they are on the timeline).
    Reorder {
        /// Its place.
        from: usize,
        /// Its new place.
        to: usize,
    },
    /// A keyframe's time (between its neighbours'; the first stays at 0).
    Time {
        /// The keyframe.
        keyframe: usize,
        /// Seconds.
        time: f64,
    },
    /// The easing of the segment starting at a keyframe.
    Easing {
        /// The keyframe.
        keyframe: usize,
        /// `linear`, `ease-in-out`, `cubic-bezier(x1,y1,x2,y2)`.
        easing: String,
    },
    /// The posing method and its parameters.
    Method(MethodData),
    /// The frame rate of playback and exports.
    Fps(f64),
    /// The range playback loops over, or the whole animation.
    LoopRange(Option<[f64; 2]>),
    /// The scene's length in seconds, or none (the animation ends at its last keyframe).
    Length(Option<f64>),
    /// The whole outline.
    Outline(Vec<Vec<[f64; 2]>>),
    /// A loop inserted into the outline at place `at`.
    AddLoop {
        /// Its place.
        at: usize,
        /// Its points.
        points: Vec<[f64; 2]>,
    },
    /// The loop at place `at` removed.
    RemoveLoop {
        /// Its place.
        at: usize,
    },
    /// A point of an outline loop moved.
    MovePoint {
        /// The loop.
        ring: usize,
        /// The point.
        index: usize,
        /// Its new place.
        to: [f64; 2],
    },
    /// A point inserted into an outline loop before `index` (`index` = the loop's length
    /// appends).
    InsertPoint {
        /// The loop.
        ring: usize,
        /// Its place.
        index: usize,
        /// The point.
        point: [f64; 2],
    },
    /// A point removed from an outline loop.
    RemovePoint {
        /// The loop.
        ring: usize,
        /// The point.
        index: usize,
    },
    /// How the picture's subject is told from its background.
    Picture(PictureSettings),
    /// The picture drawn on the mesh: its file and the mesh's texture coordinates.
    Texture {
        /// The picture's file (relative to the workspace), or none.
        texture: Option<String>,
        /// One texture coordinate per vertex, or none.
        texcoords: Option<Vec<[f64; 2]>>,
    },
    /// The whole document replaced (a new mesh with its keyframes carried over, a file
    /// opened, recovered work restored).
    Document(Box<Project>),
    /// The draw order painted on the triangles (see [`Project::depth`]).
    Depth(Option<Vec<i8>>),
    /// The stiffness painted on the triangles (see [`Project::stiffness`]).
    Stiffness(Option<Vec<f64>>),
    /// A part hidden or shown while editing, locked or unlocked (see
    /// [`super::project::PartData`]).
    PartFlags {
        /// The part (in the document's bottom-first list).
        part: usize,
        /// Hidden while editing.
        hidden: bool,
        /// Its vertices take no new pin.
        locked: bool,
    },
    /// Several edits as one step, applied in order.
    Batch(Vec<Edit>),
}

/// What an edit changed, for the caches that depend on it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Touched {
    /// The rest mesh (and so everything).
    pub mesh: bool,
    /// The keyframes' number, order or timing.
    pub keyframes: bool,
    /// A keyframe's pose, if one (with `keyframes`, any).
    pub pose: Option<usize>,
    /// A keyframe's pins.
    pub pins: Option<usize>,
    /// The method.
    pub method: bool,
    /// The outline.
    pub outline: bool,
    /// The frame rate or picture settings (state only).
    pub settings: bool,
    /// The texture.
    pub texture: bool,
    /// The depth or stiffness painted on the triangles.
    pub paint: bool,
}

impl Touched {
    fn or(self, other: Touched) -> Touched {
        let pick = |a: Option<usize>, b: Option<usize>, many: &mut bool| match (a, b) {
            (Some(x), Some(y)) if x != y => {
                *many = true;
                None
            }
            (a, b) => a.or(b),
        };
        let mut keyframes = self.keyframes || other.keyframes;
        let pose = pick(self.pose, other.pose, &mut keyframes);
        let mut method = self.method || other.method;
        let pins = pick(self.pins, other.pins, &mut method);
        Touched {
            mesh: self.mesh || other.mesh,
            keyframes,
            pose,
            pins,
            method,
            outline: self.outline || other.outline,
            settings: self.settings || other.settings,
            texture: self.texture || other.texture,
            paint: self.paint || other.paint,
        }
    }
}

/// Why an edit was refused (the document unchanged).
pub type Refusal = String;

fn no_keyframe(k: usize, len: usize) -> Refusal {
    format!("there is no keyframe {} (there are {len})", k + 1)
}

fn finite(points: &[[f64; 2]]) -> bool {
    points.iter().flatten().all(|c| c.is_finite())
}

impl Edit {
    /// About how many bytes the edit holds (for the history's budget).
    pub fn bytes(&self) -> usize {
        let points = |p: &[[f64; 2]]| 16 * p.len();
        let keyframe = |k: &Keyframe| 64 + points(&k.positions) + 4 * k.pins.len();
        64 + match self {
            Edit::Pose { positions, .. } => points(positions),
            Edit::Pins { pins, .. } => 4 * pins.len(),
            Edit::Insert { keyframe: k, .. } => keyframe(k),
            Edit::Outline(loops) => loops.iter().map(|l| 24 + points(l)).sum(),
            Edit::AddLoop { points: p, .. } => points(p),
            Edit::Texture { texcoords, .. } => texcoords.as_deref().map_or(0, points),
            Edit::Document(p) => {
                points(&p.mesh.positions)
                    + 12 * p.mesh.faces.len()
                    + p.mesh.texcoords.as_deref().map_or(0, points)
                    + p.outline.iter().map(|l| 24 + points(l)).sum::<usize>()
                    + p.keyframes.iter().map(keyframe).sum::<usize>()
            }
            Edit::Batch(edits) => edits.iter().map(Edit::bytes).sum(),
            Edit::Depth(d) => d.as_ref().map_or(0, Vec::len),
            Edit::Stiffness(w) => 8 * w.as_ref().map_or(0, Vec::len),
            _ => 0,
        }
    }

    /// The keyframe the edit is about, if one (selected when it is undone or redone).
    pub fn keyframe(&self) -> Option<usize> {
        match self {
            Edit::Pose { keyframe, .. }
            | Edit::Pins { keyframe, .. }
            | Edit::Time { keyframe, .. }
            | Edit::Easing { keyframe, .. } => Some(*keyframe),
            Edit::Insert { at, .. } => Some(*at),
            Edit::Delete { at } => Some(at.saturating_sub(1)),
            Edit::Reorder { to, .. } => Some(*to),
            Edit::Batch(edits) => edits.iter().rev().find_map(Edit::keyframe),
            _ => None,
        }
    }

    /// Applies the edit to `doc` if it is valid there; returns the inverse and what changed.
    /// A refused edit leaves `doc` unchanged.
    pub fn apply(self, doc: &mut Project) -> Result<(Edit, Touched), Refusal> {
        let n = doc.mesh.positions.len();
        let len = doc.keyframes.len();
        let touched = Touched::default();
        Ok(match self {
            Edit::Pose {
                keyframe,
                positions,
            } => {
                let key = doc
                    .keyframes
                    .get_mut(keyframe)
                    .ok_or_else(|| no_keyframe(keyframe, len))?;
                if positions.len() != n {
                    return Err(format!("{} points for {n} vertices", positions.len()));
                }
                if !finite(&positions) {
                    return Err("a point of the pose is not finite".into());
                }
                let old = std::mem::replace(&mut key.positions, positions);
                (
                    Edit::Pose {
                        keyframe,
                        positions: old,
                    },
                    Touched {
                        pose: Some(keyframe),
                        ..touched
                    },
                )
            }
            Edit::Pins { keyframe, pins } => {
                let key = doc
                    .keyframes
                    .get_mut(keyframe)
                    .ok_or_else(|| no_keyframe(keyframe, len))?;
                check_pins(&pins, n)?;
                let old = std::mem::replace(&mut key.pins, pins);
                (
                    Edit::Pins {
                        keyframe,
                        pins: old,
                    },
                    Touched {
                        pins: Some(keyframe),
                        ..touched
                    },
                )
            }
            Edit::Insert { at, keyframe } => {
                if at == 0 || at > len {
                    return Err(format!(
                        "a keyframe cannot go to place {} of {}",
                        at + 1,
                        len + 1
                    ));
                }
                check_limits(len + 1, n)?;
                let after = doc.keyframes[at - 1].time;
                let before = doc.keyframes.get(at).map_or(f64::INFINITY, |k| k.time);
                if !(keyframe.time > after && keyframe.time < before && keyframe.time.is_finite()) {
                    return Err(format!(
                        "a keyframe at {} s cannot go between {after} s and {before} s",
                        keyframe.time
                    ));
                }
                if keyframe.positions.len() != n || !finite(&keyframe.positions) {
                    return Err("the keyframe's pose does not fit the mesh".into());
                }
                keyframe
                    .easing
                    .parse::<crate::Easing>()
                    .map_err(|e| e.to_string())?;
                check_pins(&keyframe.pins, n)?;
                doc.keyframes.insert(at, keyframe);
                (
                    Edit::Delete { at },
                    Touched {
                        keyframes: true,
                        ..touched
                    },
                )
            }
            Edit::Delete { at } => {
                if at == 0 || at >= len {
                    return Err(if at == 0 {
                        "the first keyframe is the animation's start: it cannot be deleted".into()
                    } else {
                        no_keyframe(at, len)
                    });
                }
                let keyframe = doc.keyframes.remove(at);
                (
                    Edit::Insert { at, keyframe },
                    Touched {
                        keyframes: true,
                        ..touched
                    },
                )
            }
            Edit::Reorder { from, to } => {
                if from >= len || to >= len {
                    return Err(format!(
                        "keyframe {} cannot move to place {}: there are {len}",
                        from + 1,
                        to + 1
                    ));
                }
                let mut poses: Vec<_> = doc
                    .keyframes
                    .iter_mut()
                    .map(|k| {
                        (
                            std::mem::take(&mut k.positions),
                            std::mem::take(&mut k.pins),
                        )
                    })
                    .collect();
                let moved = poses.remove(from);
                poses.insert(to, moved);
                for (key, (positions, pins)) in doc.keyframes.iter_mut().zip(poses) {
                    key.positions = positions;
                    key.pins = pins;
                }
                (
                    Edit::Reorder { from: to, to: from },
                    Touched {
                        keyframes: true,
                        ..touched
                    },
                )
            }
            Edit::Time { keyframe, time } => {
                if keyframe >= len {
                    return Err(no_keyframe(keyframe, len));
                }
                if keyframe == 0 {
                    return Err("the first keyframe stays at 0 s".into());
                }
                let after = doc.keyframes[keyframe - 1].time;
                let before = doc
                    .keyframes
                    .get(keyframe + 1)
                    .map_or(f64::INFINITY, |k| k.time);
                if !(time > after && time < before && time.is_finite()) {
                    return Err(format!(
                        "keyframe {} must stay between {after} s and {before} s",
                        keyframe + 1
                    ));
                }
                let old = std::mem::replace(&mut doc.keyframes[keyframe].time, time);
                (
                    Edit::Time {
                        keyframe,
                        time: old,
                    },
                    Touched {
                        keyframes: true,
                        ..touched
                    },
                )
            }
            Edit::Easing { keyframe, easing } => {
                easing.parse::<crate::Easing>().map_err(|e| e.to_string())?;
                let key = doc
                    .keyframes
                    .get_mut(keyframe)
                    .ok_or_else(|| no_keyframe(keyframe, len))?;
                let old = std::mem::replace(&mut key.easing, easing);
                (
                    Edit::Easing {
                        keyframe,
                        easing: old,
                    },
                    Touched {
                        keyframes: true,
                        ..touched
                    },
                )
            }
            Edit::Method(method) => {
                method.check()?;
                let old = std::mem::replace(&mut doc.method, method);
                (
                    Edit::Method(old),
                    Touched {
                        method: true,
                        ..touched
                    },
                )
            }
            Edit::Fps(fps) => {
                if !(fps > 0.0 && fps <= 240.0) {
                    return Err(format!("frame rate {fps}: give one in (0, 240]"));
                }
                let old = std::mem::replace(&mut doc.fps, fps);
                (
                    Edit::Fps(old),
                    Touched {
                        settings: true,
                        ..touched
                    },
                )
            }
            Edit::Depth(depth) => {
                check_depth(depth.as_deref(), doc.mesh.faces.len())?;
                let old = std::mem::replace(&mut doc.depth, depth);
                (
                    Edit::Depth(old),
                    Touched {
                        paint: true,
                        ..touched
                    },
                )
            }
            Edit::Stiffness(weights) => {
                check_stiffness(weights.as_deref(), doc.mesh.faces.len())?;
                let old = std::mem::replace(&mut doc.stiffness, weights);
                (
                    Edit::Stiffness(old),
                    Touched {
                        paint: true,
                        method: true,
                        ..touched
                    },
                )
            }
            Edit::LoopRange(range) => {
                check_loop_range(range)?;
                let old = std::mem::replace(&mut doc.loop_range, range);
                (
                    Edit::LoopRange(old),
                    Touched {
                        settings: true,
                        ..touched
                    },
                )
            }
            Edit::Length(length) => {
                check_length(length)?;
                let old = std::mem::replace(&mut doc.length, length);
                (
                    Edit::Length(old),
                    Touched {
                        settings: true,
                        ..touched
                    },
                )
            }
            Edit::Outline(loops) => {
                check_outline(&loops)?;
                let old = std::mem::replace(&mut doc.outline, loops);
                (
                    Edit::Outline(old),
                    Touched {
                        outline: true,
                        ..touched
                    },
                )
            }
            Edit::AddLoop { at, points } => {
                if at > doc.outline.len() {
                    return Err(format!("there is no loop place {}", at + 1));
                }
                let mut trial = points.len();
                trial += doc.outline.iter().map(Vec::len).sum::<usize>();
                if trial > super::project::MAX_OUTLINE_POINTS || !finite(&points) {
                    return Err(check_outline(&[points]).err().unwrap_or_else(|| {
                        format!(
                            "the outline would have {trial} points; the studio takes at most {}",
                            super::project::MAX_OUTLINE_POINTS
                        )
                    }));
                }
                doc.outline.insert(at, points);
                (
                    Edit::RemoveLoop { at },
                    Touched {
                        outline: true,
                        ..touched
                    },
                )
            }
            Edit::RemoveLoop { at } => {
                if at >= doc.outline.len() {
                    return Err(format!("there is no loop {}", at + 1));
                }
                let points = doc.outline.remove(at);
                (
                    Edit::AddLoop { at, points },
                    Touched {
                        outline: true,
                        ..touched
                    },
                )
            }
            Edit::MovePoint { ring, index, to } => {
                if !finite(&[to]) {
                    return Err("the point is not finite".into());
                }
                let point = doc
                    .outline
                    .get_mut(ring)
                    .and_then(|l| l.get_mut(index))
                    .ok_or_else(|| {
                        format!("there is no point {} of loop {}", index + 1, ring + 1)
                    })?;
                let old = std::mem::replace(point, to);
                (
                    Edit::MovePoint {
                        ring,
                        index,
                        to: old,
                    },
                    Touched {
                        outline: true,
                        ..touched
                    },
                )
            }
            Edit::InsertPoint { ring, index, point } => {
                if !finite(&[point]) {
                    return Err("the point is not finite".into());
                }
                let total: usize = doc.outline.iter().map(Vec::len).sum();
                if total >= super::project::MAX_OUTLINE_POINTS {
                    return Err(format!(
                        "the outline has {total} points; the studio takes at most {}",
                        super::project::MAX_OUTLINE_POINTS
                    ));
                }
                let points = doc
                    .outline
                    .get_mut(ring)
                    .filter(|l| index <= l.len())
                    .ok_or_else(|| {
                        format!("there is no place {} in loop {}", index + 1, ring + 1)
                    })?;
                points.insert(index, point);
                (
                    Edit::RemovePoint { ring, index },
                    Touched {
                        outline: true,
                        ..touched
                    },
                )
            }
            Edit::RemovePoint { ring, index } => {
                let points = doc
                    .outline
                    .get_mut(ring)
                    .filter(|l| index < l.len())
                    .ok_or_else(|| {
                        format!("there is no point {} of loop {}", index + 1, ring + 1)
                    })?;
                let point = points.remove(index);
                (
                    Edit::InsertPoint { ring, index, point },
                    Touched {
                        outline: true,
                        ..touched
                    },
                )
            }
            Edit::Picture(settings) => {
                settings.options()?;
                let old = std::mem::replace(&mut doc.picture, settings);
                (
                    Edit::Picture(old),
                    Touched {
                        settings: true,
                        ..touched
                    },
                )
            }
            Edit::PartFlags {
                part,
                hidden,
                locked,
            } => {
                let count = doc.parts.as_ref().map_or(0, Vec::len);
                let p = doc
                    .parts
                    .as_mut()
                    .and_then(|parts| parts.get_mut(part))
                    .ok_or_else(|| format!("there is no part {} (there are {count})", part + 1))?;
                let old = Edit::PartFlags {
                    part,
                    hidden: std::mem::replace(&mut p.hidden, hidden),
                    locked: std::mem::replace(&mut p.locked, locked),
                };
                (
                    old,
                    Touched {
                        settings: true,
                        ..touched
                    },
                )
            }
            Edit::Texture { texture, texcoords } => {
                if let Some(uv) = &texcoords {
                    if uv.len() != n || !finite(uv) {
                        return Err(format!(
                            "{} texture coordinates for {n} vertices, or one not finite",
                            uv.len()
                        ));
                    }
                }
                let old = Edit::Texture {
                    texture: std::mem::replace(&mut doc.texture, texture),
                    texcoords: std::mem::replace(&mut doc.mesh.texcoords, texcoords),
                };
                (
                    old,
                    Touched {
                        texture: true,
                        ..touched
                    },
                )
            }
            Edit::Document(project) => {
                project.check().map_err(|e| e.to_string())?;
                let old = std::mem::replace(doc, *project);
                (
                    Edit::Document(Box::new(old)),
                    Touched {
                        mesh: true,
                        keyframes: true,
                        method: true,
                        outline: true,
                        settings: true,
                        texture: true,
                        paint: true,
                        ..touched
                    },
                )
            }
            Edit::Batch(edits) => {
                let mut inverses = Vec::with_capacity(edits.len());
                let mut all = touched;
                for edit in edits {
                    match edit.apply(doc) {
                        Ok((inverse, t)) => {
                            inverses.push(inverse);
                            all = all.or(t);
                        }
                        Err(e) => {
                            // Put back what the batch did so far, newest first.
                            for inverse in inverses.into_iter().rev() {
                                let _ = inverse.apply(doc);
                            }
                            return Err(e);
                        }
                    }
                }
                inverses.reverse();
                (Edit::Batch(inverses), all)
            }
        })
    }
}

/// A keyframe at `time` with `positions`, linear easing, no pins.
pub fn keyframe_at(time: f64, positions: Vec<[f64; 2]>) -> Keyframe {
    Keyframe {
        time,
        easing: "linear".into(),
        positions,
        pins: Vec::new(),
        drawing: None,
    }
}

/// The rest mesh data with `texcoords`.
pub fn mesh_data(mesh: &crate::mesh::PlanarMesh, texcoords: Option<Vec<[f64; 2]>>) -> MeshData {
    MeshData {
        positions: mesh.positions.clone(),
        faces: mesh.faces.clone(),
        texcoords,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate;

    fn project() -> Project {
        let mesh = generate::disk(4, 0.1);
        let mut p = Project::new(&mesh, None);
        p.keyframes
            .push(keyframe_at(1.0, generate::bend(&mesh, 0.3).positions));
        p.keyframes
            .push(keyframe_at(2.0, generate::bend(&mesh, 0.6).positions));
        p.outline = vec![vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]];
        p.parts = Some(vec![super::super::project::PartData {
            name: "all".into(),
            vertices: [0, p.mesh.positions.len() as u32],
            faces: [0, p.mesh.faces.len() as u32],
            ..Default::default()
        }]);
        p
    }

    /// Every edit, applied then undone by its inverse, gives the document back exactly, and
    /// the inverse's inverse is the edit again.
    #[test]
    fn every_edit_is_undone_exactly_by_its_inverse() {
        let start = project();
        let n = start.mesh.positions.len();
        let mut moved = start.keyframes[1].positions.clone();
        moved[3] = [9.0, 9.0];
        let edits = vec![
            Edit::Pose {
                keyframe: 1,
                positions: moved,
            },
            Edit::Pins {
                keyframe: 2,
                pins: vec![0, 5, 7],
            },
            Edit::Insert {
                at: 2,
                keyframe: keyframe_at(1.5, start.keyframes[0].positions.clone()),
            },
            Edit::Insert {
                at: 3,
                keyframe: keyframe_at(7.0, start.keyframes[0].positions.clone()),
            },
            Edit::Delete { at: 1 },
            Edit::Reorder { from: 0, to: 2 },
            Edit::Reorder { from: 2, to: 1 },
            Edit::Time {
                keyframe: 2,
                time: 5.0,
            },
            Edit::Easing {
                keyframe: 0,
                easing: "ease-in-out".into(),
            },
            Edit::Method(MethodData {
                name: "arap".into(),
                ..MethodData::default()
            }),
            Edit::Fps(12.0),
            Edit::LoopRange(Some([0.5, 1.5])),
            Edit::Length(Some(4.5)),
            Edit::Outline(vec![]),
            Edit::AddLoop {
                at: 1,
                points: vec![[5.0, 5.0]],
            },
            Edit::RemoveLoop { at: 0 },
            Edit::MovePoint {
                ring: 0,
                index: 1,
                to: [2.0, 2.0],
            },
            Edit::InsertPoint {
                ring: 0,
                index: 3,
                point: [0.5, 0.5],
            },
            Edit::RemovePoint { ring: 0, index: 0 },
            Edit::Picture(PictureSettings {
                background: Some("auto".into()),
                threshold: Some(0.3),
            }),
            Edit::Texture {
                texture: Some("a.png".into()),
                texcoords: Some(vec![[0.5, 0.5]; n]),
            },
            Edit::Document(Box::new(Project::new(&generate::grid(3, 3, 0.0), None))),
            Edit::PartFlags {
                part: 0,
                hidden: true,
                locked: false,
            },
            Edit::PartFlags {
                part: 0,
                hidden: false,
                locked: true,
            },
            Edit::Batch(vec![Edit::Fps(30.0), Edit::Delete { at: 2 }]),
        ];
        for edit in edits {
            // Kept beside the autosave as JSON: read back the same.
            let json = serde_json::to_string(&edit).expect("json");
            assert_eq!(serde_json::from_str::<Edit>(&json).expect("reads"), edit);
            let mut doc = start.clone();
            let (inverse, _) = edit
                .clone()
                .apply(&mut doc)
                .unwrap_or_else(|e| panic!("{edit:?}: {e}"));
            assert_ne!(doc, start, "{edit:?} changed nothing");
            doc.check().unwrap_or_else(|e| panic!("{edit:?}: {e}"));
            let (again, _) = inverse.apply(&mut doc).expect("the inverse applies");
            assert_eq!(doc, start, "{edit:?} undone");
            again.apply(&mut doc).expect("redo");
            let mut direct = start.clone();
            edit.apply(&mut direct).expect("applies");
            assert_eq!(doc, direct, "redo is the edit again");
        }
    }

    /// A refused edit leaves the document as it was, batches included.
    #[test]
    fn refused_edits_change_nothing() {
        let start = project();
        let n = start.mesh.positions.len();
        let refused = vec![
            Edit::Pose {
                keyframe: 7,
                positions: vec![],
            },
            Edit::Pose {
                keyframe: 1,
                positions: vec![[f64::NAN, 0.0]; n],
            },
            Edit::Pins {
                keyframe: 0,
                pins: vec![1, 1],
            },
            Edit::Pins {
                keyframe: 0,
                pins: vec![n as u32],
            },
            Edit::Insert {
                at: 0,
                keyframe: keyframe_at(0.5, start.keyframes[0].positions.clone()),
            },
            Edit::Insert {
                at: 1,
                keyframe: keyframe_at(1.5, start.keyframes[0].positions.clone()),
            },
            Edit::Delete { at: 0 },
            Edit::Delete { at: 3 },
            Edit::Reorder { from: 0, to: 3 },
            Edit::Time {
                keyframe: 1,
                time: 2.0,
            },
            Edit::Time {
                keyframe: 0,
                time: 0.5,
            },
            Edit::Easing {
                keyframe: 0,
                easing: "bouncy".into(),
            },
            Edit::Method(MethodData {
                weight: 1e-300,
                ..MethodData::default()
            }),
            Edit::Fps(0.0),
            Edit::LoopRange(Some([1.0, 1.0])),
            Edit::LoopRange(Some([f64::NAN, 1.0])),
            Edit::Length(Some(0.0)),
            Edit::Length(Some(f64::INFINITY)),
            Edit::MovePoint {
                ring: 0,
                index: 9,
                to: [0.0, 0.0],
            },
            Edit::RemoveLoop { at: 4 },
            Edit::Picture(PictureSettings {
                background: Some("plaid".into()),
                threshold: None,
            }),
            Edit::Texture {
                texture: None,
                texcoords: Some(vec![]),
            },
            Edit::PartFlags {
                part: 1,
                hidden: true,
                locked: true,
            },
            Edit::Batch(vec![Edit::Fps(30.0), Edit::Delete { at: 9 }]),
        ];
        for edit in refused {
            let mut doc = start.clone();
            assert!(edit.clone().apply(&mut doc).is_err(), "{edit:?} applied");
            assert_eq!(doc, start, "{edit:?} changed the document");
        }
    }
}
