//! The studio's engine state: one project, the keyframe being posed with its [`Deformer`], the
//! compiled [`Path`] through the keyframes for playback, and undo. Every operation the page asks
//! for is a method here, answering with the new state (JSON) or a frame (binary), so the server
//! only moves bytes.
//!
//! Frames travel as little-endian binary ([`frame_bytes`]): a 32-byte header (kind, sequence
//! number, vertices, faces, largest distortion, flipped triangles, time) and then the
//! positions and each triangle's distortion as `f32`.

use std::path::{Path as FsPath, PathBuf};

use rayon::prelude::*;
use serde::Deserialize;

use super::project::{Keyframe, Project, ProjectError};
use crate::deform::{Deformer, KvfOptions, Method};
use crate::distortion::RestShape;
use crate::mesh::PlanarMesh;
use crate::render::{colour, raster, Drawing, Image, ImageSize, Viewport};
use crate::{Easing, Path, PathOptions};

/// Binary message kinds (the first `u32` of each binary message).
pub mod kind {
    /// A pose after a drag (or a keyframe shown).
    pub const POSE: u32 = 1;
    /// The rest mesh: positions, triangles, texture coordinates.
    pub const MESH: u32 = 2;
    /// A frame of the animation at a time.
    pub const FRAME: u32 = 3;
}

/// What the page asks for (`{"op": "...", ...}`).
#[derive(Debug, Deserialize)]
#[serde(tag = "op", rename_all = "snake_case", deny_unknown_fields)]
pub enum Request {
    /// The state and the mesh.
    Hello,
    /// Pose keyframe `keyframe`.
    Select {
        /// Its index.
        keyframe: usize,
    },
    /// The handles of the keyframe being posed (factors the system).
    Pins {
        /// Vertex numbers.
        pins: Vec<u32>,
    },
    /// The handles moved: one target per pin.
    Drag {
        /// Echoed in the answer.
        seq: u32,
        /// Targets.
        targets: Vec<[f64; 2]>,
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
    /// Undo the last drag or reset of the keyframe being posed.
    Undo,
    /// Redo it.
    Redo,
    /// The keyframe being posed back to the rest shape.
    Reset,
    /// A new keyframe at `time`: a copy of keyframe `copy` (default: the one being posed,
    /// a clone; the page's "add" copies the first).
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
    /// Move a keyframe in time (not the first).
    SetTime {
        /// Its index.
        keyframe: usize,
        /// Seconds.
        time: f64,
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
    /// A keyframe read from a mesh file's text (OBJ or OFF, by the name's extension) with
    /// the project's triangles (in any order), at `time`.
    LoadKeyframe {
        /// The file's name (for its format and in messages).
        name: String,
        /// Its text.
        text: String,
        /// Seconds.
        time: f64,
    },
    /// The picture's outline, traced and simplified to `tolerance` pixels (default 1), as
    /// loops to edit (answered with `{"type": "outline", "loops": [...]}`).
    TraceOutline {
        /// Pixels.
        tolerance: Option<f64>,
    },
    /// A new mesh from closed loops (the region of odd winding: outlines, holes, pieces),
    /// about `vertices` vertices; the project starts over from it (the picture kept).
    MeshOutline {
        /// Each loop's points, in the mesh's frame (the picture's pixels, y up).
        loops: Vec<Vec<[f64; 2]>>,
        /// About how many vertices.
        vertices: usize,
    },
    /// A new mesh from an outline file's text (`.svg` or `.poly`, by the name's extension).
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
    /// The animation's frame at `time`.
    Scrub {
        /// Echoed in the answer.
        seq: u32,
        /// Seconds.
        time: f64,
    },
    /// Save the project into the workspace as `name` (a plain file name ending `.json`), or
    /// to the file it was opened from.
    Save {
        /// The file name.
        name: Option<String>,
    },
    /// Export the animation into the workspace: `gif`, `mp4`, `png` (a strip), `html` (the
    /// self-contained viewer) or `obj` (a folder of frames).
    Export {
        /// The format.
        format: String,
        /// A plain file (or folder, for `obj`) name.
        name: String,
        /// Frames (default: the duration times the frame rate, at least 2).
        frames: Option<u32>,
        /// For `still`: the animation's frame at this time (default: the keyframe being
        /// posed).
        time: Option<f64>,
    },
}

/// Why an operation failed: said to the page, the session unchanged.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SessionError {
    /// A request the session cannot carry out, and why.
    #[error("{0}")]
    Refused(String),
    /// Posing failed.
    #[error(transparent)]
    Deform(#[from] crate::deform::DeformError),
    /// Morphing failed.
    #[error(transparent)]
    Morph(#[from] crate::MorphError),
    /// Reading or writing the project failed.
    #[error(transparent)]
    Project(#[from] ProjectError),
}

fn refused<T>(why: impl Into<String>) -> Result<T, SessionError> {
    Err(SessionError::Refused(why.into()))
}

/// A pose's undo record.
#[derive(Clone, Debug)]
struct Snapshot {
    keyframe: usize,
    positions: Vec<[f64; 2]>,
}

/// The engine state of one studio.
pub struct Session {
    project: Project,
    rest: PlanarMesh,
    shape: RestShape,
    current: usize,
    deformer: Deformer,
    pins: Vec<u32>,
    path: Option<Path>,
    dragging: bool,
    undo: Vec<Snapshot>,
    redo: Vec<Snapshot>,
    distortion: Vec<f64>,
    frame: Vec<[f64; 2]>,
    workspace: PathBuf,
    project_file: Option<PathBuf>,
    texture: Option<Image>,
    /// Each piece's anchor edge: where the morph places and turns the piece.
    anchors: Vec<[u32; 2]>,
}

impl std::fmt::Debug for Session {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("vertices", &self.rest.positions.len())
            .field("keyframes", &self.project.keyframes.len())
            .field("workspace", &self.workspace)
            .finish_non_exhaustive()
    }
}

/// The most undo steps kept.
const UNDO_STEPS: usize = 100;

impl Session {
    /// A session on `project`; saves and exports go into `workspace`, `project_file` is where
    /// a plain "save" writes (if it was opened from one), `texture` the picture drawn on it.
    pub fn new(
        project: Project,
        workspace: PathBuf,
        project_file: Option<PathBuf>,
        texture: Option<Image>,
    ) -> Result<Session, SessionError> {
        project.check()?;
        let rest = project.rest();
        let deformer = Deformer::new(&rest, method_of(&project)?)?;
        let shape = RestShape::new(&rest.positions, &rest.faces);
        let m = rest.faces.len();
        // The anchors depend on the triangles only: the rest shape twice compiles them.
        let anchors = Path::new(&[rest.clone(), rest.clone()])?
            .structure()
            .pieces
            .iter()
            .map(|p| p.anchor_edge)
            .collect();
        let mut session = Session {
            distortion: vec![1.0; m],
            frame: rest.positions.clone(),
            shape,
            rest,
            deformer,
            pins: Vec::new(),
            path: None,
            dragging: false,
            undo: Vec::new(),
            redo: Vec::new(),
            current: 0,
            project,
            workspace,
            project_file,
            texture,
            anchors,
        };
        session.select(0)?;
        Ok(session)
    }

    /// The project as it stands.
    pub fn project(&self) -> &Project {
        &self.project
    }

    /// The texture, if any.
    pub fn texture(&self) -> Option<&Image> {
        self.texture.as_ref()
    }

    /// The state as JSON for the page.
    pub fn state_json(&self, message: Option<&str>) -> String {
        let keys: Vec<serde_json::Value> = self
            .project
            .keyframes
            .iter()
            .map(|k| serde_json::json!({"time": k.time, "easing": k.easing, "pins": k.pins}))
            .collect();
        serde_json::json!({
            "type": "state",
            "vertices": self.rest.positions.len(),
            "faces": self.rest.faces.len(),
            "keyframes": keys,
            "current": self.current,
            "method": self.project.method,
            "fps": self.project.fps,
            "duration": self.duration(),
            "textured": self.texture.is_some() && self.project.mesh.texcoords.is_some(),
            "anchors": self.anchors,
            "picture": self.texture.as_ref().map(|t| [t.width, t.height]),
            "can_undo": !self.undo.is_empty(),
            "can_redo": !self.redo.is_empty(),
            "project": self.project_file.as_ref().map(|p| p.display().to_string()),
            "workspace": self.workspace.display().to_string(),
            "message": message,
        })
        .to_string()
    }

    /// The animation's length in seconds (the last keyframe's time).
    pub fn duration(&self) -> f64 {
        self.project.keyframes.last().map_or(0.0, |k| k.time)
    }

    /// The rest mesh as a binary message ([`kind::MESH`]): header `[kind, n, m, textured]`,
    /// then `2n` f32 positions, `3m` u32 triangles, and `2n` f32 texture coordinates when
    /// textured.
    pub fn mesh_bytes(&self) -> Vec<u8> {
        let (n, m) = (self.rest.positions.len(), self.rest.faces.len());
        let uv = self.project.mesh.texcoords.as_ref();
        let mut out = Vec::with_capacity(16 + 8 * n + 12 * m + 8 * n);
        for x in [kind::MESH, n as u32, m as u32, u32::from(uv.is_some())] {
            out.extend_from_slice(&x.to_le_bytes());
        }
        for p in &self.rest.positions {
            out.extend_from_slice(&(p[0] as f32).to_le_bytes());
            out.extend_from_slice(&(p[1] as f32).to_le_bytes());
        }
        for f in &self.rest.faces {
            for v in f {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        if let Some(uv) = uv {
            for p in uv {
                out.extend_from_slice(&(p[0] as f32).to_le_bytes());
                out.extend_from_slice(&(p[1] as f32).to_le_bytes());
            }
        }
        out
    }

    /// The keyframe being posed, as a [`kind::POSE`] frame.
    pub fn pose_bytes(&mut self, seq: u32) -> Vec<u8> {
        let positions = self.deformer.positions().to_vec();
        self.frame_of(kind::POSE, seq, f64::NAN, &positions)
    }

    fn frame_of(&mut self, kind: u32, seq: u32, time: f64, positions: &[[f64; 2]]) -> Vec<u8> {
        let worst = self.shape.distortion_into(positions, &mut self.distortion);
        let flipped = self.distortion.iter().filter(|d| d.is_infinite()).count();
        frame_bytes(kind, seq, time, positions, &self.distortion, worst, flipped)
    }

    /// Poses keyframe `k`.
    pub fn select(&mut self, k: usize) -> Result<(), SessionError> {
        let Some(key) = self.project.keyframes.get(k) else {
            return refused(format!("there is no keyframe {k}"));
        };
        let (positions, pins) = (key.positions.clone(), key.pins.clone());
        self.deformer.set_positions(&positions)?;
        self.current = k;
        self.pins.clear();
        if !pins.is_empty() {
            self.set_pins(&pins)?;
        }
        self.dragging = false;
        Ok(())
    }

    /// The handles of the keyframe being posed.
    pub fn set_pins(&mut self, pins: &[u32]) -> Result<(), SessionError> {
        if pins.is_empty() {
            self.pins.clear();
            self.project.keyframes[self.current].pins.clear();
            return Ok(());
        }
        self.deformer.set_pins(pins)?;
        self.pins = pins.to_vec();
        self.project.keyframes[self.current].pins = pins.to_vec();
        self.dragging = false;
        Ok(())
    }

    /// Moves the handles; the pose becomes the keyframe's.
    pub fn drag(
        &mut self,
        targets: &[[f64; 2]],
    ) -> Result<crate::deform::DragReport, SessionError> {
        if self.pins.is_empty() {
            return refused("pin some vertices first");
        }
        if !self.dragging {
            self.remember();
            self.dragging = true;
        }
        let report = self.deformer.drag(targets)?;
        let k = self.current;
        self.project.keyframes[k]
            .positions
            .copy_from_slice(self.deformer.positions());
        self.path = None;
        Ok(report)
    }

    /// Ends a drag (the next one is a new undo step).
    pub fn drag_end(&mut self) {
        self.dragging = false;
    }

    fn remember(&mut self) {
        self.undo.push(Snapshot {
            keyframe: self.current,
            positions: self.project.keyframes[self.current].positions.clone(),
        });
        if self.undo.len() > UNDO_STEPS {
            self.undo.remove(0);
        }
        self.redo.clear();
    }

    fn restore(&mut self, from_undo: bool) -> Result<(), SessionError> {
        let (take, keep) = if from_undo {
            (&mut self.undo, &mut self.redo)
        } else {
            (&mut self.redo, &mut self.undo)
        };
        let Some(snap) = take.pop() else {
            return refused(if from_undo {
                "nothing to undo"
            } else {
                "nothing to redo"
            });
        };
        let Some(key) = self.project.keyframes.get_mut(snap.keyframe) else {
            return refused("that keyframe was deleted");
        };
        keep.push(Snapshot {
            keyframe: snap.keyframe,
            positions: key.positions.clone(),
        });
        key.positions = snap.positions;
        self.path = None;
        self.select(snap.keyframe)
    }

    /// Sets the posing method.
    pub fn set_method(
        &mut self,
        name: &str,
        weight: Option<f64>,
        max_distortion: Option<f64>,
    ) -> Result<(), SessionError> {
        let mut method = self.project.method.clone();
        method.name = name.to_owned();
        if let Some(w) = weight {
            method.weight = w;
        }
        if let Some(k) = max_distortion {
            method.max_distortion = k;
        }
        let mut trial = self.project.clone();
        trial.method = method;
        trial.check()?;
        let mut deformer = Deformer::new(&self.rest, method_of(&trial)?)?;
        deformer.set_positions(self.deformer.positions())?;
        if !self.pins.is_empty() {
            deformer.set_pins(&self.pins)?;
        }
        self.deformer = deformer;
        self.project.method = trial.method;
        Ok(())
    }

    /// Adds a copy of the keyframe being posed at `time` and poses it.
    pub fn add_keyframe(&mut self, time: f64, copy: Option<usize>) -> Result<(), SessionError> {
        let from = copy.unwrap_or(self.current);
        let Some(source) = self.project.keyframes.get(from) else {
            return refused(format!("there is no keyframe {from} to copy"));
        };
        let key = Keyframe {
            time,
            easing: "linear".into(),
            positions: source.positions.clone(),
            pins: if from == self.current {
                self.pins.clone()
            } else {
                source.pins.clone()
            },
        };
        self.insert(key)
    }

    fn insert(&mut self, key: Keyframe) -> Result<(), SessionError> {
        if !(key.time.is_finite() && key.time > 0.0) {
            return refused(format!(
                "a new keyframe's time must be after 0, not {}",
                key.time
            ));
        }
        if self.project.keyframes.iter().any(|k| k.time == key.time) {
            return refused(format!("there is already a keyframe at {} s", key.time));
        }
        let at = self
            .project
            .keyframes
            .iter()
            .position(|k| k.time > key.time)
            .unwrap_or(self.project.keyframes.len());
        self.project.keyframes.insert(at, key);
        self.undo.clear();
        self.redo.clear();
        self.path = None;
        self.select(at)
    }

    /// Deletes keyframe `k` (not the first: it is the animation's start).
    pub fn delete_keyframe(&mut self, k: usize) -> Result<(), SessionError> {
        if k == 0 || k >= self.project.keyframes.len() {
            return refused(format!("keyframe {k} cannot be deleted"));
        }
        self.project.keyframes.remove(k);
        self.undo.clear();
        self.redo.clear();
        self.path = None;
        self.select(self.current.min(self.project.keyframes.len() - 1))
    }

    /// Moves keyframe `k`'s pose (positions and pins) to place `to` in the order, the poses
    /// between shifting by one; the times and easings stay where they are on the timeline.
    pub fn move_keyframe(&mut self, k: usize, to: usize) -> Result<(), SessionError> {
        let n = self.project.keyframes.len();
        if k >= n || to >= n {
            return refused(format!(
                "keyframe {k} cannot move to place {to}: there are {n} keyframes"
            ));
        }
        let mut poses: Vec<_> = self
            .project
            .keyframes
            .iter_mut()
            .map(|key| {
                (
                    std::mem::take(&mut key.positions),
                    std::mem::take(&mut key.pins),
                )
            })
            .collect();
        let moved = poses.remove(k);
        poses.insert(to, moved);
        for (key, (positions, pins)) in self.project.keyframes.iter_mut().zip(poses) {
            key.positions = positions;
            key.pins = pins;
        }
        self.undo.clear();
        self.redo.clear();
        self.path = None;
        self.select(to)
    }

    /// Moves keyframe `k` to `time`, keeping the order (between its neighbours).
    pub fn set_time(&mut self, k: usize, time: f64) -> Result<(), SessionError> {
        let keys = &self.project.keyframes;
        if k == 0 || k >= keys.len() {
            return refused(format!("keyframe {k}'s time cannot change"));
        }
        let after = keys[k - 1].time;
        let before = keys.get(k + 1).map_or(f64::INFINITY, |n| n.time);
        if !(time > after && time < before) {
            return refused(format!(
                "keyframe {k} must stay between {after} s and {before} s"
            ));
        }
        self.project.keyframes[k].time = time;
        self.path = None;
        Ok(())
    }

    /// Sets the easing of the segment starting at keyframe `k`.
    pub fn set_easing(&mut self, k: usize, easing: &str) -> Result<(), SessionError> {
        if let Err(e) = easing.parse::<Easing>() {
            return refused(e.to_string());
        }
        let Some(key) = self.project.keyframes.get_mut(k) else {
            return refused(format!("there is no keyframe {k}"));
        };
        key.easing = easing.to_owned();
        self.path = None;
        Ok(())
    }

    /// The compiled path through the keyframes (compiled again after any change).
    fn path(&mut self) -> Result<&mut Path, SessionError> {
        if self.project.keyframes.len() < 2 {
            return refused("add a second keyframe to play");
        }
        if self.path.is_none() {
            let keys = &self.project.keyframes;
            let meshes: Vec<PlanarMesh> = keys
                .iter()
                .map(|k| PlanarMesh {
                    positions: k.positions.clone(),
                    faces: self.rest.faces.clone(),
                })
                .collect();
            let durations: Vec<f64> = keys.windows(2).map(|w| w[1].time - w[0].time).collect();
            let easings: Vec<Easing> = keys[..keys.len() - 1]
                .iter()
                .map(|k| k.easing.parse().unwrap_or(Easing::Linear))
                .collect();
            let options = PathOptions::default()
                .with_durations(durations)
                .with_easings(easings);
            self.path = Some(Path::with_options(&meshes, options)?);
        }
        self.path
            .as_mut()
            .ok_or_else(|| SessionError::Refused("no path".into()))
    }

    /// The animation at `time` seconds (clamped to the animation) into the frame buffer.
    fn compute(&mut self, time: f64) -> Result<f64, SessionError> {
        let duration = self.duration();
        let time = if time.is_finite() {
            time.clamp(0.0, duration)
        } else {
            0.0
        };
        let t = if duration > 0.0 { time / duration } else { 0.0 };
        let mut frame = std::mem::take(&mut self.frame);
        let result = self.path().and_then(|p| Ok(p.frame_into(t, &mut frame)?));
        self.frame = frame;
        result?;
        Ok(time)
    }

    /// The animation's frame at `time`, as a [`kind::FRAME`] message.
    pub fn scrub(&mut self, seq: u32, time: f64) -> Result<Vec<u8>, SessionError> {
        let time = self.compute(time)?;
        let positions = std::mem::take(&mut self.frame);
        let bytes = self.frame_of(kind::FRAME, seq, time, &positions);
        self.frame = positions;
        Ok(bytes)
    }

    /// The picture's traced outline as loops.
    pub fn trace_outline(
        &self,
        tolerance: Option<f64>,
    ) -> Result<Vec<Vec<[f64; 2]>>, SessionError> {
        let Some(image) = &self.texture else {
            return refused("there is no picture to trace: open one (bdmorph studio picture.png)");
        };
        let traced = crate::meshing::picture_outline(
            image,
            &crate::meshing::PictureOptions::default(),
            tolerance,
        )
        .map_err(|e| SessionError::Refused(e.to_string()))?;
        Ok(loops_of(&traced.outline))
    }

    /// Starts the project over from `outline`, meshed with about `vertices` vertices; the
    /// picture (if any) stays, spanning its own pixels.
    pub fn remesh(
        &mut self,
        mut outline: crate::meshing::Outline,
        vertices: usize,
    ) -> Result<(), SessionError> {
        if !(MIN_MESH_VERTICES..=MAX_MESH_VERTICES).contains(&vertices) {
            return refused(format!(
                "{vertices} vertices: the studio meshes between {MIN_MESH_VERTICES} and {MAX_MESH_VERTICES} (use bdmorph mesh for more)"
            ));
        }
        if let Some(t) = &self.texture {
            outline.texture_frame = Some([0.0, 0.0, f64::from(t.width), f64::from(t.height)]);
        }
        let options = crate::meshing::MeshOptions::default().with_vertices(vertices);
        let meshed = crate::meshing::mesh_outline(&outline, &options)
            .map_err(|e| SessionError::Refused(e.to_string()))?;
        let uv = per_vertex_uv(
            &meshed.texcoords,
            &meshed.mesh.faces,
            meshed.mesh.positions.len(),
        );
        let mut project = Project::new(&meshed.mesh, uv);
        project.texture = self.project.texture.clone();
        project.method = self.project.method.clone();
        project.fps = self.project.fps;
        *self = Session::new(project, self.workspace.clone(), None, self.texture.clone())?;
        Ok(())
    }

    /// A keyframe from a mesh file's text, at `time`.
    pub fn load_keyframe(&mut self, name: &str, text: &str, time: f64) -> Result<(), SessionError> {
        let path = FsPath::new(name);
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        let surface = match ext.as_str() {
            "obj" => crate::io::parse_obj(text, path),
            "off" => crate::io::parse_off(text, path),
            _ => {
                return refused(format!(
                    "{name}: a keyframe is read from an .obj or .off file"
                ))
            }
        }
        .map_err(|e| SessionError::Refused(e.to_string()))?;
        let planar = PlanarMesh::from_surface(surface, path)
            .map_err(|e| SessionError::Refused(format!("{name}: {e}")))?;
        if planar.positions.len() != self.rest.positions.len() {
            return refused(format!(
                "{name} has {} vertices; the project has {}",
                planar.positions.len(),
                self.rest.positions.len()
            ));
        }
        self.rest
            .match_faces(&planar.faces)
            .map_err(|e| SessionError::Refused(format!("{name}: {e}")))?;
        planar
            .validate()
            .map_err(|e| SessionError::Refused(format!("{name}: {e}")))?;
        let key = Keyframe {
            time,
            easing: "linear".into(),
            positions: planar.positions,
            pins: Vec::new(),
        };
        self.insert(key)
    }

    /// The frame at `time` becomes a keyframe there (and is posed).
    pub fn frame_to_keyframe(&mut self, time: f64) -> Result<(), SessionError> {
        let time = self.compute(time)?;
        let key = Keyframe {
            time,
            easing: "linear".into(),
            positions: self.frame.clone(),
            pins: Vec::new(),
        };
        self.insert(key)
    }

    /// A file name in the workspace: plain (no folders, not hidden), with one of `endings`.
    fn workspace_file(&self, name: &str, endings: &[&str]) -> Result<PathBuf, SessionError> {
        let plain = !name.is_empty()
            && name.len() <= 200
            && !name.starts_with('.')
            && name
                .chars()
                .all(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | '.' | ' '));
        if !plain {
            return refused(format!(
                "'{name}' is not a plain file name: the studio writes only into {}, by names of letters, digits, spaces, '-', '_' and '.'",
                self.workspace.display()
            ));
        }
        let lower = name.to_ascii_lowercase();
        if !endings.is_empty() && !endings.iter().any(|e| lower.ends_with(e)) {
            return refused(format!("'{name}' must end with {}", endings.join(" or ")));
        }
        Ok(self.workspace.join(name))
    }

    /// Saves the project (atomically): into the workspace as `name`, or where it was opened.
    pub fn save(&mut self, name: Option<&str>) -> Result<PathBuf, SessionError> {
        let path = match (name, &self.project_file) {
            (Some(name), _) => self.workspace_file(name, &[".json"])?,
            (None, Some(path)) => path.clone(),
            (None, None) => return refused("give the project a file name (.json)"),
        };
        self.project.write(&path)?;
        self.project_file = Some(path.clone());
        Ok(path)
    }

    /// Renders the animation into the workspace as `name`.
    pub fn export(
        &mut self,
        format: &str,
        name: &str,
        frames: Option<u32>,
    ) -> Result<PathBuf, SessionError> {
        let endings: &[&str] = match format {
            "gif" => &[".gif"],
            "mp4" => &[".mp4"],
            "png" => &[".png"],
            "html" => &[".html"],
            "obj" => &[],
            "still" => return self.export_still(name, None),
            other => return refused(format!("unknown export format '{other}'")),
        };
        let path = self.workspace_file(name, endings)?;
        let duration = self.duration();
        let count = frames
            .unwrap_or((duration * self.project.fps).round() as u32 + 1)
            .clamp(2, 2000) as usize;
        let mut poses: Vec<(f64, Vec<[f64; 2]>, Vec<f64>)> = Vec::with_capacity(count);
        for i in 0..count {
            let time = duration * i as f64 / (count - 1) as f64;
            self.compute(time)?;
            self.shape
                .distortion_into(&self.frame, &mut self.distortion);
            poses.push((time, self.frame.clone(), self.distortion.clone()));
        }
        let faces = self.rest.faces.clone();
        let corner_uv: Option<Vec<[[f64; 2]; 3]>> = self
            .project
            .mesh
            .texcoords
            .as_ref()
            .map(|uv| faces.iter().map(|f| f.map(|v| uv[v as usize])).collect());
        let texture = self.texture.as_ref().filter(|_| corner_uv.is_some());
        let view = Viewport::fit(poses.iter().map(|p| p.1.as_slice()));
        let size = ImageSize {
            width: 640,
            height: 640,
        };
        let render = |positions: &[[f64; 2]], shades: Option<&[[u8; 3]]>| {
            let drawing = Drawing {
                faces: &faces,
                corner_uv: corner_uv.as_deref(),
                texture,
                face_colours: shades,
            };
            raster::render(positions, &drawing, &view, size)
        };
        let failed = |e: &dyn std::fmt::Display| SessionError::Refused(format!("export: {e}"));
        match format {
            "gif" | "mp4" | "png" => {
                let images: Vec<Image> = if format == "png" {
                    let max = colour::distortion_scale(poses.iter().map(|p| p.2.as_slice()));
                    let picks = [0, count / 4, count / 2, 3 * count / 4, count - 1];
                    picks
                        .par_iter()
                        .map(|&i| {
                            let shades =
                                colour::shade_colours(&colour::distortion_shades(&poses[i].2, max));
                            render(&poses[i].1, Some(&shades))
                        })
                        .collect()
                } else {
                    poses.par_iter().map(|p| render(&p.1, None)).collect()
                };
                let bytes = match format {
                    "gif" => {
                        let delay = (100.0 / self.project.fps).round().max(2.0) as u16;
                        raster::encode_gif(&images, delay).map_err(|e| failed(&e))?
                    }
                    "mp4" => {
                        crate::render::video::encode_mp4(&images, self.project.fps.round() as u32)
                            .map_err(|e| failed(&e))?
                    }
                    _ => raster::encode_png(&raster::strip(&images, images.len()))
                        .map_err(|e| failed(&e))?,
                };
                crate::io::write_bytes_atomic(&path, &bytes).map_err(|e| failed(&e))?;
            }
            "html" => {
                let png = match texture {
                    Some(t) => Some(raster::encode_png(t).map_err(|e| failed(&e))?),
                    None => None,
                };
                let frames: Vec<(f64, &[[f64; 2]])> =
                    poses.iter().map(|p| (p.0, p.1.as_slice())).collect();
                let page = crate::render::html::html(
                    "bdmorph studio export",
                    &frames,
                    &faces,
                    corner_uv.as_deref(),
                    png.as_deref(),
                    &view,
                );
                crate::io::write_bytes_atomic(&path, page.as_bytes()).map_err(|e| failed(&e))?;
            }
            _ => {
                std::fs::create_dir_all(&path).map_err(|e| failed(&e))?;
                for (i, p) in poses.iter().enumerate() {
                    let file = path.join(format!("frame_{i:04}.obj"));
                    crate::io::write_obj_2d(&file, &p.1, &faces, &[]).map_err(|e| failed(&e))?;
                }
            }
        }
        Ok(path)
    }

    /// One frame as a PNG picture (a screenshot of the shape, 800 pixels square): the
    /// animation at `time`, or the keyframe being posed; drawn with the picture when the
    /// project has one, else coloured by distortion.
    pub fn export_still(&mut self, name: &str, time: Option<f64>) -> Result<PathBuf, SessionError> {
        let path = self.workspace_file(name, &[".png"])?;
        let positions = match time {
            Some(t) => {
                if !(t.is_finite() && t >= 0.0) {
                    return refused(format!("time {t}: give one of 0 or more seconds"));
                }
                self.compute(t.min(self.duration()))?;
                self.frame.clone()
            }
            None => self.deformer.positions().to_vec(),
        };
        self.shape.distortion_into(&positions, &mut self.distortion);
        let faces = &self.rest.faces;
        let corner_uv: Option<Vec<[[f64; 2]; 3]>> = self
            .project
            .mesh
            .texcoords
            .as_ref()
            .map(|uv| faces.iter().map(|f| f.map(|v| uv[v as usize])).collect());
        let texture = self.texture.as_ref().filter(|_| corner_uv.is_some());
        let shades = match texture {
            Some(_) => None,
            None => {
                let max = colour::distortion_scale(std::iter::once(self.distortion.as_slice()));
                Some(colour::shade_colours(&colour::distortion_shades(
                    &self.distortion,
                    max,
                )))
            }
        };
        let drawing = Drawing {
            faces,
            corner_uv: corner_uv.as_deref(),
            texture,
            face_colours: shades.as_deref(),
        };
        let view = Viewport::fit(std::iter::once(positions.as_slice()));
        let size = ImageSize {
            width: 800,
            height: 800,
        };
        let image = raster::render(&positions, &drawing, &view, size);
        let failed = |e: &dyn std::fmt::Display| SessionError::Refused(format!("export: {e}"));
        let bytes = raster::encode_png(&image).map_err(|e| failed(&e))?;
        crate::io::write_bytes_atomic(&path, &bytes).map_err(|e| failed(&e))?;
        Ok(path)
    }

    /// Carries out a request: the answers to send, in order (text is JSON state, bytes are
    /// binary frames). A failed request changes nothing and answers with the state and the
    /// reason.
    pub fn handle(&mut self, request: Request) -> Vec<Answer> {
        match self.try_handle(request) {
            Ok(answers) => answers,
            Err(e) => vec![Answer::Text(self.state_json(Some(&format!("error: {e}"))))],
        }
    }

    fn try_handle(&mut self, request: Request) -> Result<Vec<Answer>, SessionError> {
        use Answer::{Binary, Text};
        Ok(match request {
            Request::Hello => vec![
                Text(self.state_json(None)),
                Binary(self.mesh_bytes()),
                Binary(self.pose_bytes(0)),
            ],
            Request::Select { keyframe } => {
                self.select(keyframe)?;
                vec![Text(self.state_json(None)), Binary(self.pose_bytes(0))]
            }
            Request::Pins { pins } => {
                self.set_pins(&pins)?;
                vec![Text(self.state_json(None))]
            }
            Request::Drag { seq, targets } => {
                self.drag(&targets)?;
                vec![Binary(self.pose_bytes(seq))]
            }
            Request::DragEnd => {
                self.drag_end();
                vec![Text(self.state_json(None))]
            }
            Request::Method {
                name,
                weight,
                max_distortion,
            } => {
                self.set_method(&name, weight, max_distortion)?;
                vec![Text(self.state_json(None))]
            }
            Request::Undo | Request::Redo => {
                self.restore(matches!(request, Request::Undo))?;
                vec![Text(self.state_json(None)), Binary(self.pose_bytes(0))]
            }
            Request::Reset => {
                self.remember();
                let rest = self.rest.positions.clone();
                self.deformer.set_positions(&rest)?;
                self.project.keyframes[self.current].positions = rest;
                self.path = None;
                vec![Text(self.state_json(None)), Binary(self.pose_bytes(0))]
            }
            Request::AddKeyframe { time, copy } => {
                self.add_keyframe(time, copy)?;
                vec![Text(self.state_json(None)), Binary(self.pose_bytes(0))]
            }
            Request::DeleteKeyframe { keyframe } => {
                self.delete_keyframe(keyframe)?;
                vec![Text(self.state_json(None)), Binary(self.pose_bytes(0))]
            }
            Request::MoveKeyframe { keyframe, to } => {
                self.move_keyframe(keyframe, to)?;
                vec![Text(self.state_json(None)), Binary(self.pose_bytes(0))]
            }
            Request::SetTime { keyframe, time } => {
                self.set_time(keyframe, time)?;
                vec![Text(self.state_json(None))]
            }
            Request::SetEasing { keyframe, easing } => {
                self.set_easing(keyframe, &easing)?;
                vec![Text(self.state_json(None))]
            }
            Request::FrameToKeyframe { time } => {
                self.frame_to_keyframe(time)?;
                vec![Text(self.state_json(None)), Binary(self.pose_bytes(0))]
            }
            Request::Scrub { seq, time } => vec![Binary(self.scrub(seq, time)?)],
            Request::LoadKeyframe { name, text, time } => {
                self.load_keyframe(&name, &text, time)?;
                let said = format!("loaded {name} as a keyframe at {time} s");
                vec![
                    Text(self.state_json(Some(&said))),
                    Binary(self.pose_bytes(0)),
                ]
            }
            Request::TraceOutline { tolerance } => {
                let loops = self.trace_outline(tolerance)?;
                vec![Text(
                    serde_json::json!({"type": "outline", "loops": loops}).to_string(),
                )]
            }
            Request::MeshOutline { loops, vertices } => {
                if loops.iter().any(|l| l.len() < 3) || loops.is_empty() {
                    return refused("each loop needs at least three points");
                }
                self.remesh(crate::meshing::Outline::from_loops(&loops), vertices)?;
                let said = format!("meshed: {} vertices", self.rest.positions.len());
                vec![
                    Text(self.state_json(Some(&said))),
                    Binary(self.mesh_bytes()),
                    Binary(self.pose_bytes(0)),
                ]
            }
            Request::ImportOutline {
                name,
                text,
                vertices,
            } => {
                let lower = name.to_ascii_lowercase();
                let outline = if lower.ends_with(".svg") {
                    crate::meshing::parse_svg(&text, None)
                } else if lower.ends_with(".poly") {
                    crate::meshing::parse_poly(&text)
                } else {
                    return refused(format!(
                        "{name}: outlines are read from .svg or .poly files"
                    ));
                }
                .map_err(|e| SessionError::Refused(format!("{name}: {e}")))?;
                self.remesh(outline, vertices)?;
                let said = format!("meshed {name}: {} vertices", self.rest.positions.len());
                vec![
                    Text(self.state_json(Some(&said))),
                    Binary(self.mesh_bytes()),
                    Binary(self.pose_bytes(0)),
                ]
            }
            Request::Fps { fps } => {
                if !(fps > 0.0 && fps <= 240.0) {
                    return refused(format!("frame rate {fps}: give one in (0, 240]"));
                }
                self.project.fps = fps;
                vec![Text(self.state_json(None))]
            }
            Request::Save { name } => {
                let path = self.save(name.as_deref())?;
                let said = format!("saved {}", path.display());
                vec![Text(self.state_json(Some(&said)))]
            }
            Request::Export {
                format,
                name,
                frames,
                time,
            } => {
                let path = if format == "still" {
                    self.export_still(&name, time)?
                } else {
                    self.export(&format, &name, frames)?
                };
                let said = format!("exported {}", path.display());
                vec![Text(self.state_json(Some(&said)))]
            }
        })
    }
}

/// One message to the page.
#[derive(Clone, Debug, PartialEq)]
pub enum Answer {
    /// JSON text.
    Text(String),
    /// A binary message (see [`kind`]).
    Binary(Vec<u8>),
}

/// The posing method a project names.
fn method_of(project: &Project) -> Result<Method, SessionError> {
    let m = &project.method;
    Ok(match m.name.as_str() {
        "kvf" => Method::Kvf(KvfOptions::default().with_weight(m.weight)),
        "arap" => Method::arap(),
        "bounded" => Method::bounded(m.max_distortion),
        other => return refused(format!("unknown method '{other}'")),
    })
}

/// A frame as a binary message: `[kind, seq, n, m]` as u32, `[largest distortion]` f32,
/// `[flipped]` u32, `[time]` f32, a reserved u32, then `2n` f32 positions and `m` f32
/// distortions (flipped triangles as f32 infinity).
pub fn frame_bytes(
    kind: u32,
    seq: u32,
    time: f64,
    positions: &[[f64; 2]],
    distortion: &[f64],
    worst: f64,
    flipped: usize,
) -> Vec<u8> {
    let mut out = Vec::with_capacity(32 + 8 * positions.len() + 4 * distortion.len());
    for x in [kind, seq, positions.len() as u32, distortion.len() as u32] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out.extend_from_slice(&(worst as f32).to_le_bytes());
    out.extend_from_slice(&(flipped as u32).to_le_bytes());
    out.extend_from_slice(&(time as f32).to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    for p in positions {
        out.extend_from_slice(&(p[0] as f32).to_le_bytes());
        out.extend_from_slice(&(p[1] as f32).to_le_bytes());
    }
    for d in distortion {
        out.extend_from_slice(&(*d as f32).to_le_bytes());
    }
    out
}

/// Opens what `bdmorph studio FILE` names: a project file (`.json`), a mesh (`.obj`, `.off`),
/// or a picture (`.png`, `.jpg`, `.jpeg`: meshed by its opaque subject, about 2000 vertices,
/// and drawn on the mesh). The texture of a project or mesh is the PNG beside it with the same
/// stem, or the project's own.
pub fn open(file: &FsPath) -> Result<(Project, Option<Image>), String> {
    let shown = file.display();
    let ext = file
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match ext.as_str() {
        "json" => {
            let project = Project::read(file).map_err(|e| format!("{shown}: {e}"))?;
            let texture = match &project.texture {
                Some(t) => {
                    let path = file.parent().unwrap_or(FsPath::new(".")).join(t);
                    Some(raster::read_image(&path).map_err(|e| format!("{}: {e}", path.display()))?)
                }
                None => None,
            };
            Ok((project, texture))
        }
        "obj" | "off" => {
            let read = crate::MeshFile::read(file).map_err(|e| e.to_string())?;
            let planar = read.planar().map_err(|e| e.to_string())?;
            let uv = read
                .mesh
                .texcoords
                .as_ref()
                .and_then(|t| per_vertex_uv(t, &planar.faces, planar.positions.len()));
            let mut project = Project::new(&planar, uv);
            let beside = file.with_extension("png");
            let texture = if project.mesh.texcoords.is_some() && beside.is_file() {
                project.texture = beside.file_name().map(|n| n.to_string_lossy().into_owned());
                raster::read_image(&beside).ok()
            } else {
                None
            };
            Ok((project, texture))
        }
        "png" | "jpg" | "jpeg" => {
            let image = raster::read_image(file).map_err(|e| format!("{shown}: {e}"))?;
            let meshed = crate::meshing::mesh_picture(
                &image,
                &crate::meshing::PictureOptions::default(),
                &crate::meshing::MeshOptions::default(),
            )
            .map_err(|e| format!("{shown}: {e}"))?;
            let uv = per_vertex_uv(&meshed.texcoords, &meshed.mesh.faces, meshed.mesh.positions.len());
            let mut project = Project::new(&meshed.mesh, uv);
            project.texture = file.file_name().map(|n| n.to_string_lossy().into_owned());
            Ok((project, Some(image)))
        }
        _ => Err(format!(
            "{shown}: the studio opens a project (.json), a mesh (.obj, .off) or a picture (.png, .jpg)"
        )),
    }
}

/// The fewest vertices the studio meshes an outline with.
pub const MIN_MESH_VERTICES: usize = 50;
/// The most vertices the studio meshes an outline with (one request stays interactive;
/// `bdmorph mesh` makes larger meshes, which the studio opens).
pub const MAX_MESH_VERTICES: usize = 200_000;

/// An outline's segments as closed loops (following each vertex's outgoing segment).
fn loops_of(outline: &crate::meshing::Outline) -> Vec<Vec<[f64; 2]>> {
    let n = outline.vertices.len();
    let mut next = vec![u32::MAX; n];
    for &[a, b] in &outline.segments {
        if let Some(slot) = next.get_mut(a as usize) {
            *slot = b;
        }
    }
    let mut seen = vec![false; n];
    let mut loops = Vec::new();
    for start in 0..n {
        if seen[start] || next[start] == u32::MAX {
            continue;
        }
        let mut l = Vec::new();
        let mut v = start;
        while !seen[v] {
            seen[v] = true;
            l.push(outline.vertices[v]);
            match next[v] {
                u32::MAX => break,
                w => v = w as usize,
            }
        }
        if l.len() >= 3 {
            loops.push(l);
        }
    }
    loops
}

/// Texture coordinates per vertex from per-corner ones (`corners` parallel to `faces`), when
/// every corner of each vertex has the same one (no seams); `None` otherwise.
fn per_vertex_uv(t: &crate::io::TexCoords, faces: &[[u32; 3]], n: usize) -> Option<Vec<[f64; 2]>> {
    if t.corners.len() != faces.len() {
        return None;
    }
    let mut uv: Vec<Option<[f64; 2]>> = vec![None; n];
    for (face, corners) in faces.iter().zip(&t.corners) {
        for (&v, &c) in face.iter().zip(corners) {
            let value = *t.uv.get(c as usize)?;
            match uv.get_mut(v as usize)? {
                Some(seen) if *seen != value => return None,
                slot => *slot = Some(value),
            }
        }
    }
    uv.into_iter().map(|u| u.or(Some([0.0, 0.0]))).collect()
}
