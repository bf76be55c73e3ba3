//! The studio's session: one document ([`Project`]), its history ([`History`]), the view every
//! page shares (the keyframe shown or the time scrubbed to, the mode, the loop being drawn),
//! and the engine's caches ([`Engine`]).
//!
//! Every change to the document is an [`Edit`] carried out by [`Session::commit`]: applied,
//! its result checked by the engine, and either kept with its inverse on the history or undone
//! whole. A refused request changes nothing, history included. Drags are the one change made
//! in place, many times a second: a stroke is one history step (the pose before it), each
//! move checked before it is kept.
//!
//! Pages are told what changed ([`Session::updates`]): each page's task remembers which
//! revision of each part it has ([`Revs`]) and gets only the parts that moved on, so a second
//! tab, or a page reloaded, shows exactly what the first does.

use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::Arc;

use super::edit::{keyframe_at, Edit, Touched};
use super::engine::{people, Engine};
use super::export::{ExportFormat, ExportSettings};
use super::history::History;
use super::jobs::{DrawingWork, ExportWork, MeshWork, OpenWork, Outcome, Progress, Work};
use super::open::{
    fitted_uv, per_vertex_uv, read_named_texture, read_texture, OpenOptions, Texture,
};
use super::project::{Keyframe, PictureSettings, Project};
use super::protocol::{
    frame_bytes, ghost_bytes, kind, mesh_bytes, paint_bytes, upload, Request, MAX_GHOSTS,
};
use super::workspace::{kind_of, read_regular, AutosaveCopy, Recovered, Workspace, MAX_UPLOAD};
use crate::mesh::PlanarMesh;
use crate::render::{colour, raster, Background, Drawing, ImageSize, Viewport};

/// Why a session could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SessionError {
    /// The document cannot be used, and why.
    #[error("{0}")]
    Refused(String),
    /// The document's file is damaged.
    #[error(transparent)]
    Project(#[from] super::project::ProjectError),
}

/// One message to a page.
#[derive(Clone, Debug, PartialEq)]
pub enum Answer {
    /// JSON text.
    Text(String),
    /// A binary message (see [`kind`]).
    Binary(Vec<u8>),
}

/// What the pages show: a keyframe, or the animation at a time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shown {
    /// The keyframe being posed.
    Keyframe,
    /// The animation's frame at this time.
    Time(f64),
}

/// The view every page shares (not part of the document, not undone).
#[derive(Clone, Debug)]
pub struct View {
    /// The keyframe being posed (and shown, when [`Shown::Keyframe`]).
    pub current: usize,
    /// What is shown.
    pub shown: Shown,
    /// `pose` or `outline`.
    pub mode: &'static str,
    /// The outline loop being drawn, if one.
    pub drawing: Option<usize>,
}

/// Revisions of the parts of what a page shows; a page's task keeps the ones it has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Revs {
    /// The state (small JSON: keyframes' times and marks, view, history, job, notes).
    pub state: u64,
    /// The rest mesh.
    pub mesh: u64,
    /// The shown keyframe's pins.
    pub pins: u64,
    /// The outline.
    pub outline: u64,
    /// The shape shown.
    pub shown: u64,
    /// The picture.
    pub texture: u64,
    /// The depth and stiffness painted.
    pub paint: u64,
}

/// A message for every page until dismissed.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Note {
    /// Its number.
    pub id: u64,
    /// Its text.
    pub text: String,
    /// Whether it reports a failure.
    pub error: bool,
}

/// Work running in the background.
#[derive(Debug)]
pub struct Job {
    /// What it is.
    pub label: String,
    /// How far it is.
    pub progress: Arc<Progress>,
}

/// What a request asks of the server besides the updates every page gets.
#[derive(Debug, Default)]
pub struct Reply {
    /// Messages for the page that asked only (errors, lists).
    pub answers: Vec<Answer>,
    /// Work to start in the background.
    pub work: Option<(Work, Arc<Progress>)>,
}

/// The most pixels of an exported frame in the studio: 3840 x 2160 (an MP4's largest), so
/// that one frame is drawn and encoded within about a second and Cancel is heard between
/// frames (`bdmorph export` makes larger ones).
pub const MAX_EXPORT_PIXELS: u64 = 3840 * 2160;
/// The fewest vertices the studio meshes an outline with.
pub const MIN_MESH_VERTICES: usize = 50;
/// The most vertices the studio meshes an outline with (`bdmorph mesh` makes larger meshes,
/// which the studio opens).
pub const MAX_MESH_VERTICES: usize = 200_000;
/// How far (in mesh diameters, from the rest mesh's centre) a drag target may go.
pub const MAX_DRAG_REACH: f64 = 20.0;
/// Points of each outline loop a drawing's correspondence preview shows.
const CORRESPONDENCE_POINTS: usize = 24;
/// The most notes kept (the oldest go first).
const MAX_NOTES: usize = 20;

/// The engine state of one studio.
pub struct Session {
    doc: Project,
    history: History,
    view: View,
    engine: Engine,
    workspace: Workspace,
    project_file: Option<PathBuf>,
    source: Option<String>,
    texture: Option<Arc<Texture>>,
    /// Pictures read before, by name (undo and redo of a new picture do not read it again),
    /// within [`super::pictures::PICTURE_CACHE_BYTES`].
    textures: super::pictures::PictureCache,
    /// The picture the session started with (perhaps given on the command line, from outside
    /// the workspace): kept, never read again.
    given_texture: Option<Arc<Texture>>,
    revs: Revs,
    tick: u64,
    notes: Vec<Note>,
    job: Option<Job>,
    recovered: Vec<Recovered>,
    dragging: bool,
    /// Bumped on every change to the document (for autosaves).
    version: u64,
    shown_cache: Option<(u64, Vec<u8>)>,
    /// Each keyframe's pose revision (new when its pose may have changed), for the pages'
    /// copies of keyframe poses (onion skins, thumbnails).
    pose_revs: Vec<u64>,
    /// The size and centre of the rest mesh (for the reach of drags).
    reach: ([f64; 2], f64),
}

impl std::fmt::Debug for Session {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("vertices", &self.doc.mesh.positions.len())
            .field("keyframes", &self.doc.keyframes.len())
            .field("workspace", &self.workspace.root())
            .finish_non_exhaustive()
    }
}

/// A size in bytes for people: `812 bytes`, `41.3 kB`, `7.9 MB`.
pub fn human_bytes(bytes: u64) -> String {
    if bytes < 1000 {
        format!("{bytes} bytes")
    } else if bytes < 1_000_000 {
        format!("{:.1} kB", bytes as f64 / 1e3)
    } else {
        format!("{:.1} MB", bytes as f64 / 1e6)
    }
}

/// An outline's segments as closed loops (following each vertex's outgoing segment).
pub fn loops_of(outline: &crate::meshing::Outline) -> Vec<Vec<[f64; 2]>> {
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

fn reach_of(mesh: &PlanarMesh) -> ([f64; 2], f64) {
    let (lo, hi) = mesh.positions.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    );
    let size = (hi[0] - lo[0]).hypot(hi[1] - lo[1]).max(f64::MIN_POSITIVE);
    ([(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0], size)
}

/// Keyframe `k` as people count it.
fn nth(k: usize) -> usize {
    k + 1
}

/// A request carried out, or why not.
type Done = Result<(), String>;

impl Session {
    /// A session on `project` in `workspace`; `project_file` is where a plain save writes,
    /// `source` the name of the file it was opened from, `texture` its picture.
    pub fn new(
        project: Project,
        workspace: PathBuf,
        project_file: Option<PathBuf>,
        texture: Option<Arc<Texture>>,
    ) -> Result<Session, SessionError> {
        project.check()?;
        let engine = Engine::new(&project, 0).map_err(SessionError::Refused)?;
        let reach = reach_of(&engine.rest);
        let mut session = Session {
            doc: project,
            history: History::default(),
            view: View {
                current: 0,
                shown: Shown::Keyframe,
                mode: "pose",
                drawing: None,
            },
            engine,
            workspace: Workspace::new(workspace),
            project_file,
            source: None,
            textures: {
                let mut cache = super::pictures::PictureCache::default();
                if let Some(t) = &texture {
                    cache.insert(t.clone());
                }
                cache
            },
            given_texture: texture.clone(),
            texture,
            revs: Revs::default(),
            tick: 0,
            notes: Vec::new(),
            job: None,
            recovered: Vec::new(),
            dragging: false,
            version: 0,
            shown_cache: None,
            pose_revs: Vec::new(),
            reach,
        };
        session.bump_all();
        session.renew_pose_revs();
        Ok(session)
    }

    /// The name of the file the document was opened from (for autosaves).
    pub fn set_source(&mut self, source: Option<String>) {
        self.source = source;
    }

    /// Adds a note for every page.
    pub fn note(&mut self, text: impl Into<String>, error: bool) {
        self.tick += 1;
        self.notes.push(Note {
            id: self.tick,
            text: text.into(),
            error,
        });
        if self.notes.len() > MAX_NOTES {
            self.notes.remove(0);
        }
        self.bump_state();
    }

    /// Looks for recovered work in the workspace (at start) and offers it.
    pub fn offer_recoveries(&mut self) {
        self.workspace.collect_recoveries();
        self.recovered = self.workspace.recovered();
        self.bump_state();
    }

    /// Recovered work on offer.
    pub fn recovered(&self) -> &[Recovered] {
        &self.recovered
    }

    /// The document.
    pub fn project(&self) -> &Project {
        &self.doc
    }

    /// The history.
    pub fn history(&self) -> &History {
        &self.history
    }

    /// Sets the history's limits (the defaults are [`super::history::HISTORY_BYTES`] and
    /// [`super::history::HISTORY_STEPS`]).
    pub fn limit_history(&mut self, bytes: usize, steps: usize) {
        self.history.set_limits(bytes, steps);
        self.bump_state();
    }

    /// The shared view.
    pub fn view(&self) -> &View {
        &self.view
    }

    /// The workspace.
    pub fn workspace(&self) -> &Workspace {
        &self.workspace
    }

    /// The picture drawn on the mesh.
    pub fn texture(&self) -> Option<&Arc<Texture>> {
        self.texture.as_ref()
    }

    /// Bumped on every change to the document.
    pub fn version(&self) -> u64 {
        self.version
    }

    /// Whether the document has changes not saved.
    pub fn dirty(&self) -> bool {
        self.history.dirty()
    }

    /// The name of the file the document came from.
    pub fn source(&self) -> Option<&str> {
        self.source.as_deref()
    }

    /// The revisions now.
    pub fn revs(&self) -> Revs {
        self.revs
    }

    fn next(&mut self) -> u64 {
        self.tick += 1;
        self.tick
    }

    /// Every keyframe's pose revision renewed (the keyframes were added, removed, reordered or
    /// the mesh replaced).
    fn renew_pose_revs(&mut self) {
        let len = self.doc.keyframes.len();
        self.pose_revs = (0..len).map(|_| 0).collect();
        for k in 0..len {
            self.pose_revs[k] = self.next();
        }
    }

    fn bump_state(&mut self) {
        self.revs.state = self.next();
    }

    fn bump_shown(&mut self) {
        self.revs.shown = self.next();
        self.shown_cache = None;
    }

    fn bump_all(&mut self) {
        let t = self.next();
        self.revs = Revs {
            state: t,
            mesh: t,
            pins: t,
            outline: t,
            shown: t,
            texture: t,
            paint: t,
        };
        self.shown_cache = None;
    }

    /// The revisions and messages after a change that touched `touched`.
    fn changed(&mut self, touched: Touched) {
        self.version += 1;
        self.bump_state();
        if touched.mesh || touched.keyframes || self.pose_revs.len() != self.doc.keyframes.len() {
            self.renew_pose_revs();
        } else if let Some(k) = touched.pose {
            self.pose_revs[k] = self.next();
        }
        if touched.mesh {
            self.bump_all();
            self.reach = reach_of(&self.engine.rest);
        }
        if touched.outline {
            self.revs.outline = self.next();
        }
        if touched.paint || touched.mesh {
            self.revs.paint = self.next();
        }
        if touched.texture {
            self.revs.texture = self.next();
            self.revs.mesh = self.next();
        }
        if touched.pins.is_some() || touched.keyframes || touched.mesh {
            self.revs.pins = self.next();
        }
        if touched.keyframes || touched.pose.is_some() || touched.mesh {
            self.refresh_shown();
        }
    }

    /// The shape shown after the keyframes changed: the same keyframe, or the frame at the
    /// same time computed again (the keyframe, if it cannot be).
    fn refresh_shown(&mut self) {
        if let Shown::Time(t) = self.view.shown {
            if let Err(e) = self.engine.compute(&self.doc, t) {
                self.view.shown = Shown::Keyframe;
                self.note(format!("the animation cannot be played: {e}"), true);
            }
        }
        self.bump_shown();
    }

    /// Applies `edit` as one history step called `label`; refused whole (the document, its
    /// history and the engine as they were) when the edit or its result is not valid.
    pub fn commit(&mut self, label: impl Into<String>, edit: Edit) -> Done {
        self.dragging = false;
        let select = edit.keyframe();
        let inverse = self.apply(edit)?;
        self.history.push(label, inverse);
        if let Some(k) = select {
            self.show_keyframe(k.min(self.doc.keyframes.len() - 1));
        }
        Ok(())
    }

    /// Applies an edit and brings the engine in step; the inverse, or nothing changed.
    fn apply(&mut self, edit: Edit) -> Result<Edit, String> {
        let (inverse, touched) = edit.apply(&mut self.doc)?;
        self.view.current = self.view.current.min(self.doc.keyframes.len() - 1);
        if touched.texture || touched.mesh {
            self.load_texture();
        }
        if let Err(e) = self.engine.sync(&self.doc, touched, self.view.current) {
            // Undo the edit, and bring the engine back with it.
            if let Ok((_, back)) = inverse.apply(&mut self.doc) {
                self.view.current = self.view.current.min(self.doc.keyframes.len() - 1);
                if back.texture || back.mesh {
                    self.load_texture();
                }
                let _ = self.engine.sync(&self.doc, back, self.view.current);
            }
            return Err(e);
        }
        if touched.outline {
            if let Some(d) = self.view.drawing {
                if d >= self.doc.outline.len() {
                    self.view.drawing = None;
                }
            }
        }
        self.changed(touched);
        Ok(inverse)
    }

    /// The document's picture, read (or found among those read before) by its name.
    fn load_texture(&mut self) {
        let wanted = self.doc.texture.clone();
        if self.texture.as_ref().map(|t| &t.name) == wanted.as_ref() {
            return;
        }
        self.texture = match wanted {
            None => None,
            Some(name) => match self
                .textures
                .get(&name)
                .or_else(|| self.given_texture.clone().filter(|t| t.name == name))
            {
                Some(t) => Some(t.clone()),
                // Named by the document: read only inside the workspace.
                None => match read_named_texture(
                    &self.workspace.root().join(&name),
                    &name,
                    self.workspace.root(),
                    true,
                ) {
                    Ok(t) => {
                        let t = Arc::new(t);
                        self.textures.insert(t.clone());
                        Some(t)
                    }
                    Err(e) => {
                        self.note(format!("the picture could not be read: {e}"), true);
                        None
                    }
                },
            },
        };
        self.revs.texture = self.next();
    }

    /// Shows and poses keyframe `k`.
    fn show_keyframe(&mut self, k: usize) {
        self.dragging = false;
        self.view.current = k;
        self.view.shown = Shown::Keyframe;
        if let Err(e) = self.engine.load(&self.doc, k, false) {
            self.note(e, true);
        }
        self.bump_state();
        self.revs.pins = self.next();
        self.bump_shown();
    }

    /// Undoes (or redoes) the newest step.
    fn undo_redo(&mut self, undo: bool) -> Done {
        self.dragging = false;
        let step = if undo {
            self.history.take_undo()
        } else {
            self.history.take_redo()
        };
        let Some(step) = step else {
            return Err(if undo {
                "nothing to undo"
            } else {
                "nothing to redo"
            }
            .into());
        };
        let select = step.edit.keyframe();
        match self.apply(Edit::clone(&step.edit)) {
            Ok(inverse) => {
                if undo {
                    self.history.undone(step, inverse);
                } else {
                    self.history.redone(step, inverse);
                }
            }
            Err(e) => {
                if undo {
                    self.history.restore_undo(step);
                } else {
                    self.history.restore_redo(step);
                }
                return Err(e);
            }
        }
        if let Some(k) = select {
            self.show_keyframe(k.min(self.doc.keyframes.len() - 1));
        }
        self.bump_state();
        Ok(())
    }

    fn current_key(&self) -> &Keyframe {
        &self.doc.keyframes[self.view.current]
    }

    /// The end of the timeline ([`super::scene::timeline_end`]).
    fn duration(&self) -> f64 {
        super::scene::timeline_end(&self.doc)
    }

    /// The keyframe at time `t` (within a microsecond), if one.
    fn keyframe_at_time(&self, t: f64) -> Option<usize> {
        self.doc
            .keyframes
            .iter()
            .position(|k| (k.time - t).abs() < 1e-6)
    }

    /// Where a keyframe at `time` goes in the order.
    fn place_for(&self, time: f64) -> usize {
        self.doc
            .keyframes
            .iter()
            .position(|k| k.time > time)
            .unwrap_or(self.doc.keyframes.len())
    }

    /// A pin on `vertex` of what is shown (a frame between keyframes becomes one first).
    fn pin_add(&mut self, vertex: u32) -> Done {
        let n = self.doc.mesh.positions.len();
        if vertex as usize >= n {
            return Err(format!("there is no vertex there (the mesh has {n})"));
        }
        if let Shown::Time(t) = self.view.shown {
            if let Some(k) = self.keyframe_at_time(t) {
                self.show_keyframe(k);
            } else {
                let at = self.place_for(t);
                let key = Keyframe {
                    pins: vec![vertex],
                    ..keyframe_at(t, self.engine.frame.clone())
                };
                return self.commit(
                    format!("pin on a new keyframe {} at {t:.2} s", nth(at)),
                    Edit::Insert { at, keyframe: key },
                );
            }
        }
        let k = self.view.current;
        let mut pins = self.current_key().pins.clone();
        if pins.contains(&vertex) {
            return Err("that vertex is already pinned".into());
        }
        pins.push(vertex);
        self.commit(
            format!("pin on keyframe {}", nth(k)),
            Edit::Pins { keyframe: k, pins },
        )
    }

    /// The triangles a brush stroke names, checked: all of them, or `faces` (each once).
    fn stroke_faces(&self, faces: &[u32], all: bool) -> Result<Vec<usize>, String> {
        let m = self.doc.mesh.faces.len();
        if all {
            return Ok((0..m).collect());
        }
        if faces.is_empty() {
            return Err("the stroke painted no triangle".into());
        }
        if faces.len() > m {
            return Err(format!("{} triangles named; the mesh has {m}", faces.len()));
        }
        let mut out: Vec<usize> = Vec::with_capacity(faces.len());
        for &f in faces {
            if f as usize >= m {
                return Err(format!(
                    "there is no triangle {} (the mesh has {m})",
                    u64::from(f) + 1
                ));
            }
            out.push(f as usize);
        }
        out.sort_unstable();
        out.dedup();
        Ok(out)
    }

    /// A depth brush stroke: `faces` (or all) to `level`, one undo step.
    fn paint_depth(&mut self, faces: &[u32], all: bool, level: i8) -> Done {
        let max = super::project::MAX_DEPTH;
        if level.unsigned_abs() > max.unsigned_abs() {
            return Err(format!(
                "depth level {level}: give one from -{max} to {max}"
            ));
        }
        let faces = self.stroke_faces(faces, all)?;
        let m = self.doc.mesh.faces.len();
        let mut depth = self.doc.depth.clone().unwrap_or_else(|| vec![0; m]);
        for &f in &faces {
            depth[f] = level;
        }
        let depth = (depth.iter().any(|&d| d != 0)).then_some(depth);
        if depth == self.doc.depth {
            return Ok(());
        }
        let label = if all {
            format!("set every triangle's depth to {level}")
        } else {
            format!("paint depth {level} on {} triangles", faces.len())
        };
        self.commit(label, Edit::Depth(depth))
    }

    /// A stiffness brush stroke: `faces` (or all) get `weight`, one undo step.
    fn paint_stiffness(&mut self, faces: &[u32], all: bool, weight: f64) -> Done {
        let max = super::project::MAX_STIFFNESS;
        if !(1.0..=max).contains(&weight) {
            return Err(format!("stiffness {weight}: give a weight from 1 to {max}"));
        }
        let faces = self.stroke_faces(faces, all)?;
        let m = self.doc.mesh.faces.len();
        let mut weights = self.doc.stiffness.clone().unwrap_or_else(|| vec![1.0; m]);
        for &f in &faces {
            weights[f] = weight;
        }
        let weights = (weights.iter().any(|&w| w != 1.0)).then_some(weights);
        if weights == self.doc.stiffness {
            return Ok(());
        }
        let label = match (all, weight == 1.0) {
            (true, true) => "clear the stiffness".to_owned(),
            (true, false) => "make every triangle stiff".to_owned(),
            (false, true) => format!("relax {} triangles", faces.len()),
            (false, false) => format!("stiffen {} triangles", faces.len()),
        };
        self.commit(label, Edit::Stiffness(weights))
    }

    fn pin_move(&mut self, from: u32, to: u32) -> Done {
        let n = self.doc.mesh.positions.len();
        if to as usize >= n {
            return Err(format!("there is no vertex there (the mesh has {n})"));
        }
        if self.view.shown != Shown::Keyframe {
            return Err("a frame between keyframes is shown: its pins are a keyframe's".into());
        }
        let k = self.view.current;
        let mut pins = self.current_key().pins.clone();
        let Some(at) = pins.iter().position(|&v| v == from) else {
            return Err("that vertex has no pin".into());
        };
        if from == to {
            return Ok(());
        }
        if pins.contains(&to) {
            return Err("that vertex is already pinned".into());
        }
        pins[at] = to;
        self.commit(
            format!("move a pin on keyframe {}", nth(k)),
            Edit::Pins { keyframe: k, pins },
        )
    }

    /// Keyframe `keyframe` moved to `time`; with `ripple`, the later ones by the same time.
    fn set_time(&mut self, keyframe: usize, time: f64, ripple: bool) -> Done {
        let len = self.doc.keyframes.len();
        if !ripple || keyframe == 0 || keyframe >= len || keyframe + 1 == len {
            return self.commit(
                format!("time of keyframe {}", nth(keyframe)),
                Edit::Time { keyframe, time },
            );
        }
        let shift = time - self.doc.keyframes[keyframe].time;
        if !shift.is_finite() {
            return Err(format!("keyframe {} cannot go to {time} s", nth(keyframe)));
        }
        // Later keyframes first when moving later, earlier first when moving earlier, so that
        // each step keeps the order.
        let mut order: Vec<usize> = (keyframe..len).collect();
        if shift > 0.0 {
            order.reverse();
        }
        let edits = order
            .into_iter()
            .map(|k| Edit::Time {
                keyframe: k,
                time: self.doc.keyframes[k].time + shift,
            })
            .collect();
        self.commit(
            format!(
                "move keyframes {} to {} by {shift:+.3} s",
                nth(keyframe),
                nth(len - 1)
            ),
            Edit::Batch(edits),
        )?;
        self.show_keyframe(keyframe);
        Ok(())
    }

    fn drag(&mut self, pins: &[u32], targets: &[[f64; 2]], moving: Option<&[u32]>) -> Done {
        if self.view.shown != Shown::Keyframe {
            return Err("a frame between keyframes is shown: pin it to make it a keyframe".into());
        }
        let k = self.view.current;
        if self.current_key().pins != pins {
            return Err("the pins changed (in another tab?): drag again".into());
        }
        if pins.is_empty() {
            return Err("pin a vertex first".into());
        }
        if targets.len() != pins.len() {
            return Err(format!("{} targets for {} pins", targets.len(), pins.len()));
        }
        // The pins another page moves stay where the keyframe has them now.
        let kept: Vec<[f64; 2]>;
        let targets = match moving {
            Some(moving) => {
                if let Some(v) = moving.iter().find(|v| !pins.contains(v)) {
                    return Err(format!("vertex {v} is not pinned: drag again"));
                }
                let now = &self.current_key().positions;
                kept = pins
                    .iter()
                    .zip(targets)
                    .map(|(v, t)| {
                        if moving.contains(v) {
                            *t
                        } else {
                            now.get(*v as usize).copied().unwrap_or(*t)
                        }
                    })
                    .collect();
                &kept[..]
            }
            None => targets,
        };
        let (centre, size) = self.reach;
        if let Some(far) = targets.iter().position(|t| {
            !(t[0].is_finite() && t[1].is_finite())
                || (t[0] - centre[0]).hypot(t[1] - centre[1]) > MAX_DRAG_REACH * size
        }) {
            return Err(format!(
                "pin {} was dragged too far from the mesh (more than {MAX_DRAG_REACH} times its size)",
                far + 1
            ));
        }
        let before = (!self.dragging).then(|| self.current_key().positions.clone());
        let flips = self.engine.flips[k];
        self.engine.drag(&mut self.doc, k, targets)?;
        // A stroke is one step: the pose before its first move.
        let first = before.is_some();
        if let Some(positions) = before {
            self.history.push(
                format!("drag on keyframe {}", nth(k)),
                Edit::Pose {
                    keyframe: k,
                    positions,
                },
            );
            self.dragging = true;
        }
        self.version += 1;
        self.pose_revs[k] = self.next();
        // The state (undo label, the keyframe's flips) changes with a stroke's first move,
        // or when the flips do; the shape with every move.
        if first || flips != self.engine.flips[k] {
            self.bump_state();
        }
        self.bump_shown();
        Ok(())
    }

    /// Shows the animation at `time`; on a keyframe's time, that keyframe (posed).
    fn scrub(&mut self, time: f64) -> Done {
        self.dragging = false;
        let duration = self.duration();
        let at = if time.is_finite() {
            time.clamp(0.0, duration)
        } else {
            0.0
        };
        if let Some(k) = self.keyframe_at_time(at) {
            self.show_keyframe(k);
            return Ok(());
        }
        let time = self.engine.compute(&self.doc, time)?;
        // The pages learn a new time from the frame itself; the state changes only when a
        // keyframe was shown before (not at every step of a scrub).
        let was_time = matches!(self.view.shown, Shown::Time(_));
        self.view.shown = Shown::Time(time);
        self.bump_shown();
        if !was_time {
            self.bump_state();
        }
        Ok(())
    }

    fn add_keyframe(&mut self, time: f64, copy: Option<usize>) -> Done {
        let from = copy.unwrap_or(self.view.current);
        let Some(source) = self.doc.keyframes.get(from) else {
            return Err(format!("there is no keyframe {} to copy", nth(from)));
        };
        if self.keyframe_at_time(time).is_some() {
            return Err(format!("there is already a keyframe at {time} s"));
        }
        let key = Keyframe {
            pins: source.pins.clone(),
            drawing: source.drawing.clone(),
            ..keyframe_at(time, source.positions.clone())
        };
        let at = self.place_for(time);
        self.commit(
            format!("add keyframe {}", nth(at)),
            Edit::Insert { at, keyframe: key },
        )
    }

    fn frame_to_keyframe(&mut self, time: f64) -> Done {
        let time = self.engine.compute(&self.doc, time)?;
        if let Some(k) = self.keyframe_at_time(time) {
            return Err(format!("keyframe {} is at {time} s already", nth(k)));
        }
        let at = self.place_for(time);
        let key = keyframe_at(time, self.engine.frame.clone());
        self.commit(
            format!("keyframe {} from the frame at {time:.2} s", nth(at)),
            Edit::Insert { at, keyframe: key },
        )
    }

    fn load_keyframe(&mut self, name: &str, text: &str, time: f64) -> Done {
        let path = std::path::Path::new(name);
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        let surface = match ext.as_str() {
            "obj" => crate::io::parse_obj(text, path),
            "off" => crate::io::parse_off(text, path),
            _ => {
                return Err(format!(
                    "{name}: a keyframe is read from an .obj or .off file"
                ))
            }
        }
        .map_err(|e| e.to_string())?;
        let planar = PlanarMesh::from_surface(surface, path).map_err(|e| format!("{name}: {e}"))?;
        let n = self.doc.mesh.positions.len();
        if planar.positions.len() != n {
            return Err(format!(
                "{name} has {} vertices; the project has {n}",
                planar.positions.len()
            ));
        }
        self.engine
            .rest
            .match_faces(&planar.faces)
            .map_err(|e| format!("{name}: {}", super::engine::keyframe_problem(&e)))?;
        planar
            .validate_allowing_inverted()
            .map_err(|e| format!("{name}: {}", super::engine::keyframe_problem(&e)))?;
        if self.keyframe_at_time(time).is_some() {
            return Err(format!("there is already a keyframe at {time} s"));
        }
        let at = self.place_for(time);
        self.commit(
            format!("keyframe {} from {name}", nth(at)),
            Edit::Insert {
                at,
                keyframe: keyframe_at(time, planar.positions),
            },
        )
    }

    fn set_method(&mut self, name: &str, weight: Option<f64>, bound: Option<f64>) -> Done {
        let mut method = self.doc.method.clone();
        method.name = name.to_owned();
        if let Some(w) = weight {
            method.weight = w;
        }
        if let Some(k) = bound {
            method.max_distortion = k;
        }
        if method == self.doc.method {
            return Ok(());
        }
        self.commit(format!("method {name}"), Edit::Method(method))
    }

    fn repair(&mut self, keyframe: Option<usize>) -> Done {
        let k = keyframe.unwrap_or(self.view.current);
        let Some(key) = self.doc.keyframes.get(k) else {
            return Err(format!("there is no keyframe {}", nth(k)));
        };
        let before = self.engine.flips[k];
        if before == 0 {
            return Err(format!("keyframe {} has no flipped triangle", nth(k)));
        }
        let repaired = crate::deform::untangle(
            &self.engine.rest,
            &key.positions,
            &key.pins,
            &crate::deform::UntangleOptions::default(),
        )
        .map_err(|e| people(&e.to_string()))?;
        let r = repaired.report;
        if !r.success {
            // The pose is left as it was: a repair never trades a fold for a blob.
            let best = if r.best_flipped > 0 {
                format!("the best attempt left {} of them flipped", r.best_flipped)
            } else {
                format!(
                    "unfolding them needs a distortion of {:.1}",
                    r.best_distortion
                )
            };
            return Err(format!(
                "keyframe {}: the {before} flipped triangles cannot be repaired within distortion {:.1} ({best}); the pose is unchanged: drag the folded part back part of the way, or move or remove the pins that hold the fold",
                nth(k),
                r.limit
            ));
        }
        self.commit(
            format!("repair keyframe {}", nth(k)),
            Edit::Pose {
                keyframe: k,
                positions: repaired.positions,
            },
        )?;
        self.note(
            format!(
                "keyframe {}: {before} flipped triangles repaired; largest distortion {:.1} (bound {:.1})",
                nth(k),
                r.max_distortion,
                r.limit
            ),
            false,
        );
        Ok(())
    }

    fn trace(
        &mut self,
        tolerance: Option<f64>,
        settings: PictureSettings,
        vertices: Option<usize>,
    ) -> Done {
        let Some(texture) = self.texture.clone() else {
            return Err(
                "there is no picture to trace: open one, or attach one to this mesh".into(),
            );
        };
        let options = settings.options()?;
        let traced = crate::meshing::picture_outline(&texture.image, &options, tolerance)
            .map_err(|e| e.to_string())?;
        let mut loops = loops_of(&traced.outline);
        if let Some(v) = vertices {
            loops = crate::meshing::fit_loops_to_vertices(&loops, v).loops;
        }
        let mut edits = Vec::new();
        if settings != self.doc.picture {
            edits.push(Edit::Picture(settings));
        }
        edits.push(Edit::Outline(loops));
        self.view.drawing = None;
        self.commit("trace the picture", Edit::Batch(edits))?;
        if traced.dropped_specks > 0 {
            self.note(
                format!(
                    "{} speck{} left out of the outline (pieces under {}% of the largest piece's area)",
                    traced.dropped_specks,
                    if traced.dropped_specks == 1 { "" } else { "s" },
                    crate::meshing::SPECK_AREA_FRACTION * 100.0
                ),
                false,
            );
        }
        Ok(())
    }

    fn outline_remove(&mut self, ring: usize, index: usize) -> Done {
        let Some(points) = self.doc.outline.get(ring) else {
            return Err(format!("there is no loop {}", ring + 1));
        };
        if points.len() <= 3 && self.view.drawing != Some(ring) {
            return self.commit("remove a loop", Edit::RemoveLoop { at: ring });
        }
        self.commit("remove an outline point", Edit::RemovePoint { ring, index })
    }

    /// Starts meshing the document's outline in the background.
    fn mesh_outline(&mut self, loops: Vec<Vec<[f64; 2]>>, vertices: usize) -> Result<Work, String> {
        if !(MIN_MESH_VERTICES..=MAX_MESH_VERTICES).contains(&vertices) {
            return Err(format!(
                "{vertices} vertices: the studio meshes between {MIN_MESH_VERTICES} and {MAX_MESH_VERTICES} (bdmorph mesh makes more)"
            ));
        }
        let loops: Vec<Vec<[f64; 2]>> = loops.into_iter().filter(|l| l.len() >= 3).collect();
        if loops.is_empty() {
            return Err("draw or trace a loop of three points or more first".into());
        }
        let points: usize = loops.iter().map(Vec::len).sum();
        if points > MAX_MESH_VERTICES {
            return Err(format!(
                "the outline has {points} points: more than the {MAX_MESH_VERTICES} vertices the studio meshes"
            ));
        }
        Ok(Work::Mesh(MeshWork {
            loops,
            vertices,
            picture: self
                .texture
                .as_ref()
                .map(|t| [t.image.width, t.image.height]),
            replaces: self.engine.rest.clone(),
        }))
    }

    /// A new mesh made in the background becomes the document's, the animation carried over.
    fn meshed(
        &mut self,
        outline: Vec<Vec<[f64; 2]>>,
        meshed: crate::meshing::Meshed,
        asked: usize,
        replaces: &PlanarMesh,
        notes: Vec<String>,
    ) -> Done {
        if *replaces != self.engine.rest {
            return Err("the mesh changed while the new one was made: it was not used".into());
        }
        let n = meshed.mesh.positions.len();
        if n > MAX_MESH_VERTICES {
            return Err(format!(
                "the new mesh has {n} vertices: more than the {MAX_MESH_VERTICES} the studio takes (bdmorph mesh makes larger meshes, which the studio opens)"
            ));
        }
        let off_target = meshed.stats.off_target.clone();
        let carried = super::carry::carry(&self.engine.rest, &self.doc.keyframes, &meshed.mesh);
        let uv = per_vertex_uv(&meshed.texcoords, &meshed.mesh.faces, n)
            .filter(|_| self.texture.is_some());
        let mut project = self.doc.clone();
        project.mesh = super::edit::mesh_data(&meshed.mesh, uv);
        project.outline = outline;
        project.keyframes = carried.keyframes;
        // A mesh made again from an outline is one mesh: a character's parts and joints do not
        // carry over to it.
        project.parts = None;
        project.joints = None;
        // The depth and stiffness painted go to the new triangles over the old ones.
        if project.depth.is_some() || project.stiffness.is_some() {
            let map = super::carry::carry_faces(&self.engine.rest, &meshed.mesh);
            project.depth = project
                .depth
                .map(|d| map.iter().map(|&f| d[f as usize]).collect());
            project.stiffness = project
                .stiffness
                .map(|w| map.iter().map(|&f| w[f as usize]).collect());
        }
        // The first keyframe is the rest shape of the new mesh.
        project.keyframes[0].positions = meshed.mesh.positions.clone();
        super::project::check_limits(project.keyframes.len(), n)?;
        let flipped: Vec<usize> = project
            .keyframes
            .iter()
            .map(|k| super::engine::flipped(&meshed.mesh.faces, &k.positions))
            .collect();
        let keys = project.keyframes.len();
        self.commit(
            format!("new mesh ({n} vertices)"),
            Edit::Document(Box::new(project)),
        )?;
        self.view.mode = "pose";
        self.view.drawing = None;
        for note in notes {
            self.note(note, false);
        }
        let mut said = format!("new mesh: {n} vertices");
        let off = (n as f64 - asked as f64).abs() / asked as f64;
        if off > crate::meshing::VERTEX_COUNT_SLACK {
            use crate::meshing::OffTarget;
            let why = match off_target {
                Some(OffTarget::MinAngle { .. }) => {
                    "the smallest angle allowed needs more vertices around narrow parts and sharp corners".to_owned()
                }
                Some(
                    OffTarget::Outline { outline_vertices }
                    | OffTarget::Loops { outline_vertices, .. }
                    | OffTarget::Detail { outline_vertices, .. }
                    | OffTarget::Tolerance { outline_vertices, .. },
                ) => format!(
                    "the outline's {outline_vertices} points are needed to keep its pieces, holes and detail"
                ),
                _ if n < asked => "the outline encloses too little area for more".to_owned(),
                _ => "the refinement came no closer".to_owned(),
            };
            said.push_str(&format!(" for {asked} asked: {why}"));
        }
        if keys > 1 {
            said.push_str(&format!("; {keys} keyframes carried over"));
            if carried.outside > 0 {
                said.push_str(&format!(
                    ", {} new vertices outside the old mesh placed by its nearest triangles",
                    carried.outside
                ));
            }
            let with_flips: Vec<String> = flipped
                .iter()
                .enumerate()
                .filter(|(_, &f)| f > 0)
                .map(|(k, f)| format!("keyframe {} ({f})", nth(k)))
                .collect();
            if !with_flips.is_empty() {
                said.push_str(&format!(
                    "; flipped triangles in {} (Repair fixes them)",
                    with_flips.join(", ")
                ));
            }
        }
        self.note(said, false);
        Ok(())
    }

    fn save(&mut self, name: Option<&str>, overwrite: bool) -> Result<PathBuf, String> {
        let path = match (name, &self.project_file) {
            (Some(name), _) => {
                let path = self.workspace.file(name, &[".json"])?;
                if path.exists() && !overwrite && self.project_file.as_ref() != Some(&path) {
                    return Err(format!("{name} exists: save over it?"));
                }
                path
            }
            (None, Some(path)) => path.clone(),
            (None, None) => return Err("give the project a file name (.json)".into()),
        };
        let mut doc = self.doc.clone();
        // The pictures, relative to the project's folder (the workspace).
        if let Some(dir) = path.parent() {
            let relative = |name: &mut String| {
                let absolute = self.workspace.root().join(&*name);
                if let Ok(inside) = absolute.strip_prefix(dir) {
                    *name = inside.display().to_string();
                }
            };
            if let Some(t) = &mut doc.texture {
                relative(t);
            }
            for d in doc.keyframes.iter_mut().filter_map(|k| k.drawing.as_mut()) {
                relative(&mut d.picture);
            }
        }
        doc.write(&path).map_err(|e| e.to_string())?;
        self.project_file = Some(path.clone());
        self.history.mark_saved();
        self.workspace.clear_autosave();
        self.bump_state();
        Ok(path)
    }

    /// What the autosave keeps, when the document has unsaved changes (written off the lock):
    /// the document, its names, and its undo history when `history_written` (the generation
    /// of the history written last) is not the history's generation now.
    pub fn autosave_copy(&self, history_written: Option<u64>) -> Option<AutosaveCopy> {
        let generation = self.history.generation();
        self.dirty().then(|| AutosaveCopy {
            project: self.doc.clone(),
            source: self.source.clone(),
            project_file: self
                .project_file
                .as_deref()
                .and_then(|p| self.workspace.name_of(p)),
            version: self.version,
            generation,
            history: (history_written != Some(generation))
                .then(|| self.history.snapshot(super::recovery::HISTORY_FILE_BYTES)),
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn export(
        &mut self,
        format: &str,
        name: &str,
        frames: Option<u32>,
        time: Option<f64>,
        size: Option<[u32; 2]>,
        range: Option<[u32; 2]>,
        background: Option<&str>,
        overwrite: bool,
    ) -> Result<Option<Work>, String> {
        let background: Background = match background {
            Some(b) => b.parse()?,
            None => Background::WHITE,
        };
        let size = match size {
            Some([w, h]) => Some(format!("{w}x{h}").parse::<ImageSize>()?),
            None => None,
        };
        if format == "still" {
            let path = self.workspace.file(name, &[".png"])?;
            self.export_still(&path, time, size, background)?;
            self.note(format!("exported {}", path.display()), false);
            return Ok(None);
        }
        let format: ExportFormat = format.parse()?;
        let settings = ExportSettings {
            format,
            frames: frames.map(|f| f as usize),
            range: range.map(|r| r.map(|v| v as usize)),
            size,
            background,
        };
        settings.check()?;
        let path = if format.is_folder() {
            self.workspace.frame_folder(name, format.frame_ending())?
        } else {
            self.workspace.file(name, format.endings())?
        };
        if let Some(size) = settings.size {
            let pixels = u64::from(size.width) * u64::from(size.height);
            if pixels > MAX_EXPORT_PIXELS {
                return Err(format!(
                    "frames of {} x {} pixels: the studio exports frames of at most {MAX_EXPORT_PIXELS} pixels (3840 x 2160); the command line's bdmorph export makes larger ones",
                    size.width, size.height
                ));
            }
        }
        if self.doc.keyframes.len() < 2 {
            return Err("add a second keyframe to export an animation".into());
        }
        super::export::frames_kept(&self.doc, &settings)?;
        let drawings: Vec<Option<Arc<crate::render::Image>>> = (0..self.doc.keyframes.len())
            .map(|k| self.drawing_picture(k).map(|t| Arc::new(t.image.clone())))
            .collect();
        let unread: Vec<String> = self
            .doc
            .keyframes
            .iter()
            .zip(&drawings)
            .enumerate()
            .filter_map(|(k, (key, read))| {
                let d = key.drawing.as_ref()?;
                read.is_none()
                    .then(|| format!("keyframe {}'s ({})", k + 1, d.picture))
            })
            .collect();
        if !unread.is_empty() {
            self.note(
                format!(
                    "the drawing of {} could not be read: the export draws the rest picture there",
                    unread.join(", ")
                ),
                false,
            );
        }
        Ok(Some(Work::Export(Box::new(ExportWork {
            settings,
            path,
            overwrite,
            project: self.doc.clone(),
            texture: self.texture.as_ref().map(|t| Arc::new(t.image.clone())),
            drawings,
        }))))
    }

    /// The path an export of `format` named `name` writes, if something is already there
    /// (for a sprite sheet: its picture or its JSON file).
    fn export_exists(&self, format: &str, name: &str) -> Result<Option<PathBuf>, String> {
        let endings: &[&str] = if format == "still" {
            &[".png"]
        } else {
            format.parse::<ExportFormat>()?.endings()
        };
        let path = self.workspace.file(name, endings)?;
        let mut taken = vec![path.clone()];
        if format == "sheet" {
            taken.push(path.with_extension("json"));
        }
        Ok(taken
            .into_iter()
            .find(|p| std::fs::symlink_metadata(p).is_ok()))
    }

    /// One frame as a PNG picture (of `size`, or the subject's aspect 800 pixels on its longer
    /// side): the animation at `time`, or the keyframe shown; drawn with the picture when the
    /// project has one, else coloured by distortion; in the painted draw order.
    fn export_still(
        &mut self,
        path: &std::path::Path,
        time: Option<f64>,
        size: Option<ImageSize>,
        background: Background,
    ) -> Done {
        let (positions, at) = match time {
            Some(t) => {
                if !(t.is_finite() && t >= 0.0) {
                    return Err(format!("time {t}: give one of 0 or more seconds"));
                }
                let t = self.engine.compute(&self.doc, t.min(self.duration()))?;
                (self.engine.frame.clone(), Some(t))
            }
            None => (self.current_key().positions.clone(), None),
        };
        // Keyframes' drawings, read (or kept) before the rest is borrowed.
        let pictures: Vec<Option<Arc<Texture>>> = (0..self.doc.keyframes.len())
            .map(|k| self.drawing_picture(k))
            .collect();
        self.engine.measure(&positions);
        let faces = &self.engine.rest.faces;
        let corner_uv: Option<Vec<[[f64; 2]; 3]>> = self
            .doc
            .mesh
            .texcoords
            .as_ref()
            .map(|uv| faces.iter().map(|f| f.map(|v| uv[v as usize])).collect());
        let texture = self
            .texture
            .as_ref()
            .map(|t| &t.image)
            .filter(|_| corner_uv.is_some());
        let shades = match texture {
            Some(_) => None,
            None => {
                let d = &self.engine.distortion;
                let max = colour::distortion_scale(std::iter::once(d.as_slice()));
                Some(colour::shade_colours(&colour::distortion_shades(d, max)))
            }
        };
        let drawing = Drawing {
            faces,
            corner_uv: corner_uv.as_deref(),
            texture,
            face_colours: shades.as_deref(),
            depth: self.doc.depth.as_deref(),
        };
        let view = Viewport::fit(std::iter::once(positions.as_slice()));
        let size = size.unwrap_or_else(|| ImageSize::fitting(&view, 800));
        let images: Vec<Option<&crate::render::Image>> = pictures
            .iter()
            .map(|p| p.as_ref().map(|t| &t.image))
            .collect();
        let looks = super::export::Looks::new(&self.doc, texture.is_some(), &images);
        let blend = match at {
            Some(t) => super::export::blend_at(&self.doc, &looks.has_drawing, t),
            None => super::export::keyframe_look(&looks.has_drawing, self.view.current),
        };
        let image = looks
            .render(&positions, &drawing, blend, &view, size, background)
            .map_err(|e| format!("export: {e}"))?;
        let bytes = raster::encode_png(&image).map_err(|e| format!("export: {e}"))?;
        crate::io::write_bytes_atomic(path, &bytes).map_err(|e| format!("export: {e}"))
    }

    fn open_work(&self, name: &str) -> Result<Work, String> {
        if kind_of(name).is_none() {
            return Err(format!(
                "{name}: the studio opens pictures (.png, .jpg), layered pictures (.psd, .ora), meshes (.obj, .off), outlines (.svg, .poly) and projects (.json)"
            ));
        }
        let path = self.workspace.file(name, &[])?;
        if !path.is_file() {
            return Err(format!(
                "{name} is not in {}",
                self.workspace.root().display()
            ));
        }
        Ok(Work::Open(OpenWork {
            name: name.to_owned(),
            path,
            workspace: self.workspace.root().to_path_buf(),
            // Tracing settings belong to the picture they were chosen for: a newly opened
            // picture gets its own (transparency when it has any, else its border's colour),
            // never the previous document's.
            options: OpenOptions {
                pictures_inside: true,
                ..OpenOptions::default()
            },
        }))
    }

    fn opened(&mut self, opened: super::open::Opened, name: String) -> Done {
        if let Some(t) = &opened.texture {
            self.textures.insert(t.clone());
        }
        self.commit(
            format!("open {name}"),
            Edit::Document(Box::new(opened.project)),
        )?;
        // As opened, the document is its file (undo goes back to the one before, unsaved).
        self.history.mark_saved();
        self.workspace.clear_autosave();
        self.project_file = opened.project_file;
        self.source = Some(name.clone());
        self.show_keyframe(0);
        self.view.mode = "pose";
        self.view.drawing = None;
        for n in opened.notes {
            self.note(n, false);
        }
        self.note(
            format!("opened {name} (Undo goes back to what was open before)"),
            false,
        );
        Ok(())
    }

    fn attach_picture(&mut self, name: &str) -> Done {
        let path = self.workspace.file(name, &[".png", ".jpg", ".jpeg"])?;
        let texture = read_texture(&path, name)?;
        let uv = match &self.doc.mesh.texcoords {
            Some(uv) => uv.clone(),
            None => fitted_uv(&self.doc.mesh.positions, &texture.image).0,
        };
        // The tracing settings were the previous picture's: this one gets its own, as a
        // picture opened does.
        let mut notes = Vec::new();
        let settings = super::open::picture_settings(
            &texture.image,
            &PictureSettings::default(),
            &mut notes,
            name,
        );
        let texture = Arc::new(texture);
        self.textures.insert(texture);
        let mut edit = Edit::Texture {
            texture: Some(name.to_owned()),
            texcoords: Some(uv),
        };
        if self.doc.picture != settings {
            edit = Edit::Batch(vec![edit, Edit::Picture(settings)]);
        }
        self.commit(format!("picture {name}"), edit)
    }

    /// A picture of the workspace, read once and kept.
    fn picture(&mut self, name: &str) -> Result<Arc<Texture>, String> {
        if let Some(t) = self.textures.get(name) {
            return Ok(t);
        }
        let path = self.workspace.file(name, &[".png", ".jpg", ".jpeg"])?;
        let texture = Arc::new(read_texture(&path, name).map_err(|e| format!("{name}: {e}"))?);
        self.textures.insert(texture.clone());
        Ok(texture)
    }

    /// The workspace's files (and recovered work) for the pages; `stored`: the file just
    /// stored.
    fn files_json(&self, stored: Option<&str>) -> String {
        serde_json::json!({
            "type": "files",
            "files": self.workspace.list(),
            "recovered": self.workspace.recovered(),
            "workspace": self.workspace.root().display().to_string(),
            "stored": stored,
        })
        .to_string()
    }

    /// A picture of the workspace by its plain name (read once and kept).
    ///
    /// # Errors
    /// When it is not a picture of the workspace or cannot be read.
    pub fn workspace_picture(&mut self, name: &str) -> Result<Arc<Texture>, String> {
        if !super::workspace::is_plain(name) {
            return Err(format!("{name}: not a plain file name"));
        }
        self.picture(name)
    }

    /// The picture of keyframe `k`'s drawing, if it has one that can be read.
    pub fn drawing_picture(&mut self, k: usize) -> Option<Arc<Texture>> {
        let name = self.doc.keyframes.get(k)?.drawing.as_ref()?.picture.clone();
        self.picture(&name).ok()
    }

    /// Keyframe `k`'s drawing's texture coordinates as little-endian `f32` pairs (`u`, `v`
    /// with v up), if it has a drawing.
    pub fn drawing_texcoords(&self, k: usize) -> Option<Vec<u8>> {
        let d = self.doc.keyframes.get(k)?.drawing.as_ref()?;
        Some(
            d.texcoords
                .iter()
                .flatten()
                .flat_map(|&c| (c as f32).to_le_bytes())
                .collect(),
        )
    }

    /// The work that makes a keyframe from the drawing `name` with the point `pairs`.
    fn drawing_work(
        &mut self,
        name: &str,
        pairs: Vec<[[f64; 2]; 2]>,
        time: Option<f64>,
    ) -> Result<Work, String> {
        use crate::project::MAX_DRAWING_PAIRS;
        if self.doc.parts.is_some() {
            return Err(
                "a character in parts cannot take a drawing as a keyframe: pose it instead".into(),
            );
        }
        let (Some(rest_picture), Some(uv)) =
            (self.texture.clone(), self.doc.mesh.texcoords.clone())
        else {
            return Err("the rest mesh has no picture: open a picture of the subject first, then add other drawings of it".into());
        };
        if pairs.len() > MAX_DRAWING_PAIRS {
            return Err(format!(
                "{} point pairs: at most {MAX_DRAWING_PAIRS}",
                pairs.len()
            ));
        }
        if pairs.iter().flatten().flatten().any(|c| !c.is_finite()) {
            return Err("a point pair that is not finite".into());
        }
        let time = time.unwrap_or(self.doc.last_key() + 1.0);
        if !(time.is_finite() && time > 0.0 && time <= 1e6) {
            return Err(format!(
                "a keyframe at {time} s: give a time after the first keyframe"
            ));
        }
        if self.keyframe_at_time(time).is_some() {
            return Err(format!("there is already a keyframe at {time} s"));
        }
        let n = self.doc.mesh.positions.len();
        super::project::check_limits(self.doc.keyframes.len() + 1, n)?;
        let drawing = self.picture(name)?;
        let (w, h) = (
            f64::from(rest_picture.image.width),
            f64::from(rest_picture.image.height),
        );
        let mesh = PlanarMesh {
            positions: uv.iter().map(|t| [t[0] * w, t[1] * h]).collect(),
            faces: self.doc.mesh.faces.clone(),
        };
        if mesh.faces.iter().any(|f| mesh.signed_area(f) <= 0.0) {
            return Err("the rest mesh's texture coordinates are folded or mirrored: drawings are laid over a mesh made from its picture".into());
        }
        let to_mesh = affine_fit(&mesh.positions, &self.doc.mesh.positions)
            .ok_or("the rest mesh is not its picture's shape (its texture coordinates are not an affine image of it): drawings are laid over a mesh made from its picture")?;
        Ok(Work::Drawing(Box::new(DrawingWork {
            name: name.to_owned(),
            drawing: Arc::new(drawing.image.clone()),
            mesh,
            picture_height: h,
            to_mesh,
            pairs,
            picture: self.doc.picture.options()?,
            time,
            replaces: self.doc.rest(),
        })))
    }

    /// A keyframe made from a drawing, added if the rest mesh is still the one it was made for.
    fn drawn(&mut self, keyframe: Keyframe, notes: Vec<String>, replaces: &PlanarMesh) -> Done {
        if self.doc.mesh.positions != replaces.positions || self.doc.mesh.faces != replaces.faces {
            return Err(
                "the rest mesh changed while the drawing was laid over it: add the drawing again"
                    .into(),
            );
        }
        let time = keyframe.time;
        if self.keyframe_at_time(time).is_some() {
            return Err(format!("there is already a keyframe at {time} s"));
        }
        let name = keyframe
            .drawing
            .as_ref()
            .map_or_else(String::new, |d| d.picture.clone());
        let at = self.place_for(time);
        self.commit(
            format!("keyframe {} from {name}", nth(at)),
            Edit::Insert { at, keyframe },
        )?;
        self.show_keyframe(at);
        for n in notes {
            self.note(n, false);
        }
        Ok(())
    }

    fn recover(&mut self, name: &str) -> Done {
        let work = self.workspace.recovered_work(name)?;
        self.commit(
            "restore recovered work",
            Edit::Document(Box::new(work.project)),
        )?;
        // Its undo history on top: undo goes back through its edits, then to what was open.
        let steps = work.history.as_ref().map_or(0, |h| h.undo.len());
        if let Some(history) = work.history {
            self.history.graft(history);
        }
        if let Some(why) = work.history_note {
            self.note(
                format!("recovered work restored without its undo history: {why}"),
                false,
            );
        }
        self.source = work.source;
        // Its project file, when it is still a name in the workspace: Save writes there.
        self.project_file = work
            .project_file
            .and_then(|n| self.workspace.file(&n, &[".json"]).ok());
        self.show_keyframe(0);
        // Restored: it is now this studio's work, autosaved as such.
        let _ = self.workspace.discard(name);
        self.recovered = self.workspace.recovered();
        self.note(
            if steps > 0 {
                format!("recovered work restored with its {steps} undo steps (Undo goes back through them, then to what was open before); save it to keep it")
            } else {
                "recovered work restored (Undo goes back to what was open before); save it to keep it".to_owned()
            },
            false,
        );
        Ok(())
    }

    /// The state as JSON for the pages.
    pub fn state_json(&self) -> String {
        let keys: Vec<serde_json::Value> = self
            .doc
            .keyframes
            .iter()
            .zip(&self.engine.flips)
            .map(|(k, &flipped)| {
                serde_json::json!({
                    "time": k.time,
                    "easing": k.easing,
                    "pins": k.pins.len(),
                    "flipped": flipped,
                    "drawing": k.drawing.as_ref().map(|d| &d.picture),
                })
            })
            .zip(&self.pose_revs)
            .map(|(mut key, rev)| {
                key["rev"] = serde_json::json!(rev & 0xffff_ffff);
                key
            })
            .collect();
        let job = self.job.as_ref().map(|j| {
            serde_json::json!({
                "label": j.label,
                "done": j.progress.done.load(Ordering::Relaxed),
                "total": j.progress.total.load(Ordering::Relaxed),
            })
        });
        let shown = match self.view.shown {
            Shown::Keyframe => serde_json::json!({"keyframe": self.view.current}),
            Shown::Time(t) => serde_json::json!({"time": t}),
        };
        serde_json::json!({
            "type": "state",
            "vertices": self.doc.mesh.positions.len(),
            "faces": self.doc.mesh.faces.len(),
            "pieces": self.engine.pieces.vertices.len(),
            "parts": self.doc.parts,
            "joints": self.doc.joints,
            "keyframes": keys,
            "current": self.view.current,
            "shown": shown,
            "mode": self.view.mode,
            "drawing": self.view.drawing,
            "method": self.doc.method,
            "fps": self.doc.fps,
            "loop_range": self.doc.loop_range,
            "duration": self.doc.end(),
            "length": self.doc.length,
            "timeline": self.duration(),
            "textured": self.texture.is_some() && self.doc.mesh.texcoords.is_some(),
            "texture_rev": self.revs.texture,
            "texture_name": self.texture.as_ref().map(|t| t.name.clone()),
            "picture": self.texture.as_ref().map(|t| [t.image.width, t.image.height]),
            "picture_settings": self.doc.picture,
            "anchors": self.engine.anchors,
            "pin_error": self.engine.pin_error,
            "path_error": self.engine.path_error,
            "undo": self.history.last_undo().map(|s| s.label.clone()),
            "redo": self.history.last_redo().map(|s| s.label.clone()),
            "history": {"steps": self.history.undo_len(), "dropped": self.history.dropped()},
            "dirty": self.dirty(),
            "project": self.project_file.as_ref().and_then(|p| p.file_name()).map(|p| p.to_string_lossy().into_owned()),
            "source": self.source,
            "workspace": self.workspace.root().display().to_string(),
            "job": job,
            "notes": self.notes,
            "recovered": self.recovered,
        })
        .to_string()
    }

    /// The points of the shape shown: the keyframe posed, or the frame at the time shown.
    fn shown_positions(&self) -> &[[f64; 2]] {
        match self.view.shown {
            Shown::Keyframe => &self.doc.keyframes[self.view.current].positions,
            Shown::Time(_) => &self.engine.frame,
        }
    }

    /// The shown shape as a binary message tagged `seq`.
    fn shown_bytes(&mut self, seq: u32) -> Vec<u8> {
        let fresh = matches!(&self.shown_cache, Some((rev, _)) if *rev == self.revs.shown);
        if !fresh {
            let (bytes_kind, time, keyframe, positions) = match self.view.shown {
                Shown::Keyframe => (
                    kind::POSE,
                    self.doc.keyframes[self.view.current].time,
                    Some(self.view.current),
                    std::mem::take(&mut self.doc.keyframes[self.view.current].positions),
                ),
                Shown::Time(t) => (kind::FRAME, t, None, std::mem::take(&mut self.engine.frame)),
            };
            let (worst, flipped) = self.engine.measure(&positions);
            let bytes = frame_bytes(
                bytes_kind,
                0,
                time,
                keyframe,
                &positions,
                &self.engine.distortion,
                worst,
                flipped,
            );
            match self.view.shown {
                Shown::Keyframe => self.doc.keyframes[self.view.current].positions = positions,
                Shown::Time(_) => self.engine.frame = positions,
            }
            self.shown_cache = Some((self.revs.shown, bytes));
        }
        let mut bytes = self
            .shown_cache
            .as_ref()
            .map(|(_, b)| b.clone())
            .unwrap_or_default();
        if bytes.len() >= 8 {
            bytes[4..8].copy_from_slice(&seq.to_le_bytes());
        }
        bytes
    }

    /// What a page that has `seen` lacks, in order (mesh, state, pins, outline, the shape
    /// shown, tagged `seq`); `seen` is brought up to date.
    pub fn updates(&mut self, seen: &mut Revs, seq: u32) -> Vec<Answer> {
        let mut out = Vec::new();
        let now = self.revs;
        if seen.mesh != now.mesh {
            out.push(Answer::Binary(mesh_bytes(
                &self.doc.mesh.positions,
                &self.doc.mesh.faces,
                self.doc.mesh.texcoords.as_deref(),
            )));
        }
        if seen.state != now.state || seen.texture != now.texture {
            out.push(Answer::Text(self.state_json()));
        }
        if seen.paint != now.paint || seen.mesh != now.mesh {
            out.push(Answer::Binary(paint_bytes(
                self.doc.mesh.faces.len(),
                self.doc.depth.as_deref(),
                self.doc.stiffness.as_deref(),
            )));
        }
        if seen.pins != now.pins || seen.mesh != now.mesh {
            out.push(Answer::Text(
                serde_json::json!({"type": "pins", "keyframe": self.view.current, "pins": self.current_key().pins})
                    .to_string(),
            ));
        }
        if seen.outline != now.outline {
            out.push(Answer::Text(
                serde_json::json!({"type": "outline", "loops": self.doc.outline}).to_string(),
            ));
        }
        if seen.shown != now.shown || seen.mesh != now.mesh {
            out.push(Answer::Binary(self.shown_bytes(seq)));
        }
        *seen = now;
        out
    }

    /// The running job, if any.
    pub fn job(&self) -> Option<&Job> {
        self.job.as_ref()
    }

    /// Marks the progress of the running job as changed (for the pages).
    pub fn job_progressed(&mut self) {
        if self.job.is_some() {
            self.bump_state();
        }
    }

    fn start(&mut self, work: Work) -> Result<(Work, Arc<Progress>), String> {
        if let Some(job) = &self.job {
            return Err(format!(
                "{} is running: wait for it or cancel it",
                job.label
            ));
        }
        let progress = Arc::new(Progress::default());
        self.job = Some(Job {
            label: work.label(),
            progress: progress.clone(),
        });
        self.bump_state();
        Ok((work, progress))
    }

    /// A background job ended with `result`: its outcome applied, or its failure noted.
    pub fn finish(&mut self, result: Result<Outcome, String>) {
        let label = self.job.take().map(|j| j.label).unwrap_or_default();
        self.bump_state();
        let applied = match result {
            Err(e) if e == "cancelled" => {
                self.note(format!("{label}: cancelled"), false);
                return;
            }
            Err(e) => Err(e),
            Ok(Outcome::Exported {
                path,
                frames,
                bytes,
            }) => {
                self.note(
                    format!(
                        "exported {} ({frames} frames, {} written)",
                        path.display(),
                        human_bytes(bytes)
                    ),
                    false,
                );
                Ok(())
            }
            Ok(Outcome::Meshed {
                outline,
                meshed,
                asked,
                replaces,
                notes,
            }) => self.meshed(outline, *meshed, asked, &replaces, notes),
            Ok(Outcome::Opened { opened, name }) => self.opened(*opened, name),
            Ok(Outcome::Drawn {
                keyframe,
                notes,
                replaces,
            }) => self.drawn(*keyframe, notes, &replaces),
        };
        if let Err(e) = applied {
            self.note(format!("{label}: {e}"), true);
        }
    }

    /// Runs work now, on this thread (for tests and benchmarks: the server runs it in the
    /// background).
    pub fn run_now(&mut self, work: (Work, Arc<Progress>)) {
        let (work, progress) = work;
        let result = work.run(&progress, 1);
        self.finish(result);
    }

    /// Carries out a request: what only the asking page gets, and work to start. A refused
    /// request changes nothing and answers with the reason.
    pub fn handle(&mut self, request: Request) -> Reply {
        let seq = match &request {
            Request::Drag { seq, .. } | Request::Scrub { seq, .. } => Some(*seq),
            _ => None,
        };
        match self.try_handle(request) {
            Ok(reply) => reply,
            Err(e) => Reply {
                answers: vec![Answer::Text(
                    serde_json::json!({"type": "error", "message": e, "seq": seq}).to_string(),
                )],
                work: None,
            },
        }
    }

    /// Handles an upload (a binary message): the file stored in the workspace, then opened,
    /// attached or kept.
    pub fn handle_upload(&mut self, message: &[u8]) -> Reply {
        let result = (|| -> Result<Reply, String> {
            let (header, bytes) = upload(message)?;
            let name = self.workspace.store(&header.name, bytes)?;
            self.note(
                format!("{} stored in the workspace as {name}", header.name),
                false,
            );
            match header.then.as_str() {
                "open" => self.try_handle(Request::Open { name }),
                "attach" => self.try_handle(Request::AttachPicture { name }),
                // Kept only: the list of files comes back, naming it.
                "store" => Ok(Reply {
                    answers: vec![Answer::Text(self.files_json(Some(&name)))],
                    work: None,
                }),
                other => Err(format!("unknown upload action '{other}'")),
            }
        })();
        result.unwrap_or_else(|e| Reply {
            answers: vec![Answer::Text(
                serde_json::json!({"type": "error", "message": e}).to_string(),
            )],
            work: None,
        })
    }

    fn try_handle(&mut self, request: Request) -> Result<Reply, String> {
        let mut reply = Reply::default();
        // A stroke ends with drag_end, an edit, or a change of what is shown; not with a
        // request that only reads (another tab's hello, a file list).
        match request {
            Request::Hello => {}
            Request::Select { keyframe } => {
                if keyframe >= self.doc.keyframes.len() {
                    return Err(format!("there is no keyframe {}", nth(keyframe)));
                }
                self.show_keyframe(keyframe);
            }
            Request::Mode { mode } => {
                self.view.mode = match mode.as_str() {
                    "pose" => "pose",
                    "outline" => "outline",
                    other => return Err(format!("unknown mode '{other}'")),
                };
                if self.view.mode == "pose" {
                    self.view.drawing = None;
                }
                self.dragging = false;
                self.bump_state();
            }
            Request::PinAdd { vertex } => self.pin_add(vertex)?,
            Request::PinRemove { vertex } => {
                let k = self.view.current;
                let mut pins = self.current_key().pins.clone();
                let Some(at) = pins.iter().position(|&v| v == vertex) else {
                    return Err("that vertex has no pin".into());
                };
                pins.remove(at);
                self.commit(
                    format!("unpin on keyframe {}", nth(k)),
                    Edit::Pins { keyframe: k, pins },
                )?;
            }
            Request::PinMove { from, to } => self.pin_move(from, to)?,
            Request::Ghosts { keyframes } => {
                if keyframes.len() > MAX_GHOSTS {
                    return Err(format!(
                        "{} keyframe poses asked for at once; at most {MAX_GHOSTS}",
                        keyframes.len()
                    ));
                }
                for k in keyframes {
                    let key = self
                        .doc
                        .keyframes
                        .get(k)
                        .ok_or_else(|| format!("there is no keyframe {}", nth(k)))?;
                    let rev = self.pose_revs.get(k).copied().unwrap_or(0);
                    reply
                        .answers
                        .push(Answer::Binary(ghost_bytes(k, rev, &key.positions)));
                }
            }
            Request::PinsClear => {
                let k = self.view.current;
                if self.current_key().pins.is_empty() {
                    return Err("there are no pins to clear".into());
                }
                self.commit(
                    format!("clear the pins of keyframe {}", nth(k)),
                    Edit::Pins {
                        keyframe: k,
                        pins: Vec::new(),
                    },
                )?;
            }
            Request::Drag {
                pins,
                targets,
                moving,
                ..
            } => self.drag(&pins, &targets, moving.as_deref())?,
            Request::DragEnd => {
                self.dragging = false;
                // The pages learn the dragged keyframe's new pose revision.
                self.bump_state();
            }
            Request::Method {
                name,
                weight,
                max_distortion,
            } => self.set_method(&name, weight, max_distortion)?,
            Request::Undo => self.undo_redo(true)?,
            Request::Redo => self.undo_redo(false)?,
            Request::Reset => {
                let k = self.view.current;
                let rest = self.engine.rest.positions.clone();
                if self.current_key().positions == rest {
                    return Err(format!("keyframe {} is at rest already", nth(k)));
                }
                self.commit(
                    format!("reset keyframe {}", nth(k)),
                    Edit::Pose {
                        keyframe: k,
                        positions: rest,
                    },
                )?;
            }
            Request::Repair { keyframe } => self.repair(keyframe)?,
            Request::AddKeyframe { time, copy } => self.add_keyframe(time, copy)?,
            Request::DeleteKeyframe { keyframe } => {
                self.commit(
                    format!("delete keyframe {}", nth(keyframe)),
                    Edit::Delete { at: keyframe },
                )?;
            }
            Request::MoveKeyframe { keyframe, to } => {
                self.commit(
                    format!("move keyframe {} to place {}", nth(keyframe), nth(to)),
                    Edit::Reorder { from: keyframe, to },
                )?;
            }
            Request::SetTime {
                keyframe,
                time,
                ripple,
            } => self.set_time(keyframe, time, ripple)?,
            Request::SetEasing { keyframe, easing } => {
                self.commit(
                    format!("easing after keyframe {}", nth(keyframe)),
                    Edit::Easing { keyframe, easing },
                )?;
            }
            Request::FrameToKeyframe { time } => self.frame_to_keyframe(time)?,
            Request::LoadKeyframe { name, text, time } => self.load_keyframe(&name, &text, time)?,
            Request::TraceOutline {
                tolerance,
                background,
                threshold,
                vertices,
            } => self.trace(
                tolerance,
                PictureSettings {
                    background,
                    threshold,
                },
                vertices,
            )?,
            Request::OutlineSet { loops } => {
                self.view.drawing = None;
                let label = if loops.is_empty() {
                    "clear the outline"
                } else {
                    "set the outline"
                };
                self.commit(label, Edit::Outline(loops))?;
            }
            Request::OutlineNewLoop => {
                let at = self.doc.outline.len();
                self.commit(
                    "new loop",
                    Edit::AddLoop {
                        at,
                        points: Vec::new(),
                    },
                )?;
                self.view.drawing = Some(at);
                self.bump_state();
            }
            Request::OutlinePoint { point } => {
                let Some(ring) = self.view.drawing else {
                    return Err("no loop is being drawn: start one with New loop".into());
                };
                let index = self.doc.outline[ring].len();
                self.commit("outline point", Edit::InsertPoint { ring, index, point })?;
                self.view.drawing = Some(ring);
                self.bump_state();
            }
            Request::OutlineClose => {
                self.view.drawing = None;
                self.bump_state();
            }
            Request::OutlineMove { ring, index, to } => {
                self.commit("move an outline point", Edit::MovePoint { ring, index, to })?;
            }
            Request::OutlineInsert { ring, index, point } => {
                self.commit(
                    "add an outline point",
                    Edit::InsertPoint { ring, index, point },
                )?;
            }
            Request::OutlineRemove { ring, index } => self.outline_remove(ring, index)?,
            Request::OutlineRemoveLoop { ring } => {
                let (label, edit, drawing) =
                    super::loops::remove_loop(&self.doc, ring, self.view.drawing)
                        .map_err(|e| e.to_string())?;
                self.commit(label, edit)?;
                self.view.drawing = drawing;
            }
            Request::MeshOutline { vertices } => {
                let work = self.mesh_outline(self.doc.outline.clone(), vertices)?;
                reply.work = Some(self.start(work)?);
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
                    return Err(format!(
                        "{name}: outlines are read from .svg or .poly files"
                    ));
                }
                .map_err(|e| format!("{name}: {e}"))?;
                let work = self.mesh_outline(loops_of(&outline), vertices)?;
                reply.work = Some(self.start(work)?);
            }
            Request::Fps { fps } => {
                if fps != self.doc.fps {
                    self.commit("frame rate", Edit::Fps(fps))?;
                }
            }
            Request::PaintDepth { faces, all, level } => self.paint_depth(&faces, all, level)?,
            Request::PartFlags {
                part,
                hidden,
                locked,
            } => {
                if let Some((label, edit)) =
                    super::part_flags::edit(&self.doc, part, hidden, locked)?
                {
                    self.commit(label, edit)?;
                }
            }
            Request::JointAdd { at } => {
                let shown = self.shown_positions();
                let (project, label) = super::rig::add_joint(&self.doc, shown, at)?;
                self.commit(label, Edit::Document(Box::new(project)))?
            }
            Request::JointMove { joint, to } => {
                let shown = self.shown_positions();
                let (project, label) = super::rig::move_joint(&self.doc, shown, joint, to)?;
                self.commit(label, Edit::Document(Box::new(project)))?
            }
            Request::JointRemove { joint } => {
                let (project, label) = super::rig::remove_joint(&self.doc, joint)?;
                self.commit(label, Edit::Document(Box::new(project)))?
            }
            Request::PartOrder { order } => {
                let (project, label) = super::project::with_part_order(&self.doc, &order)?;
                self.commit(label, Edit::Document(Box::new(project)))?
            }
            Request::PaintStiffness { faces, all, weight } => {
                self.paint_stiffness(&faces, all, weight)?
            }
            Request::LoopRange { range } => {
                if range == self.doc.loop_range {
                    return Ok(reply);
                }
                let label = match range {
                    Some([from, to]) => format!("loop from {from:.2} s to {to:.2} s"),
                    None => "loop over the whole animation".to_owned(),
                };
                self.commit(label, Edit::LoopRange(range))?;
            }
            Request::Length { length } => {
                let (label, edit) =
                    super::scene::length_edit(&self.doc, length).map_err(|e| e.to_string())?;
                self.commit(label, edit)?;
            }
            Request::ReplaceKeyframe { keyframe, copy } => {
                let (label, edit) = super::scene::replace_edit(&self.doc, keyframe, copy)
                    .map_err(|e| e.to_string())?;
                self.commit(label, edit)?;
            }
            Request::Scrub { time, .. } => self.scrub(time)?,
            Request::Save { name, overwrite } => {
                let path = self.save(name.as_deref(), overwrite.unwrap_or(false))?;
                self.note(format!("saved {}", path.display()), false);
            }
            Request::Export {
                format,
                name,
                frames,
                time,
                size,
                range,
                background,
                overwrite,
            } => {
                if !overwrite {
                    if let Some(path) = self.export_exists(&format, &name)? {
                        reply.answers.push(Answer::Text(
                            serde_json::json!({
                                "type": "exists",
                                "op": "export",
                                "name": name,
                                "path": path.display().to_string(),
                            })
                            .to_string(),
                        ));
                        return Ok(reply);
                    }
                }
                let work = self.export(
                    &format,
                    &name,
                    frames,
                    time,
                    size,
                    range,
                    background.as_deref(),
                    overwrite,
                )?;
                if let Some(work) = work {
                    reply.work = Some(self.start(work)?);
                }
            }
            Request::Cancel => match &self.job {
                Some(job) => job.progress.cancel(),
                None => return Err("nothing is running".into()),
            },
            Request::ListFiles => {
                reply.answers.push(Answer::Text(self.files_json(None)));
            }
            Request::Open { name } => {
                if kind_of(&name) == Some("outline") {
                    let path = self.workspace.file(&name, &[])?;
                    let bytes = read_regular(&path, MAX_UPLOAD as u64)?;
                    let text = String::from_utf8(bytes)
                        .map_err(|_| format!("{name}: not text (UTF-8)"))?;
                    let vertices = self.doc.mesh.positions.len().clamp(MIN_MESH_VERTICES, 2000);
                    return self.try_handle(Request::ImportOutline {
                        name,
                        text,
                        vertices,
                    });
                }
                let work = self.open_work(&name)?;
                reply.work = Some(self.start(work)?);
            }
            Request::AttachPicture { name } => self.attach_picture(&name)?,
            Request::DrawingPreview { name, pairs } => {
                let Work::Drawing(w) = self.drawing_work(&name, pairs, None)? else {
                    return Err("no drawing to preview".into());
                };
                let matches: Vec<crate::inbetween::Match> = w
                    .pairs
                    .iter()
                    .map(|&[a, b]| crate::inbetween::Match { a, b })
                    .collect();
                let options = crate::inbetween::InbetweenOptions::default().with_picture(w.picture);
                let loops = crate::inbetween::outline_correspondence(
                    &w.mesh,
                    w.picture_height,
                    &w.drawing,
                    &matches,
                    &options,
                    CORRESPONDENCE_POINTS,
                )
                .map_err(|e| format!("{name}: {e}"))?;
                reply.answers.push(Answer::Text(
                    serde_json::json!({"type": "correspondence", "name": name, "loops": loops})
                        .to_string(),
                ));
            }
            Request::DrawingKeyframe { name, pairs, time } => {
                let work = self.drawing_work(&name, pairs, time)?;
                reply.work = Some(self.start(work)?);
            }
            Request::Recover { name } => self.recover(&name)?,
            Request::Discard { name } => {
                self.workspace.discard(&name)?;
                self.recovered = self.workspace.recovered();
                self.bump_state();
            }
            Request::Dismiss { note } => {
                self.notes.retain(|n| n.id != note);
                self.bump_state();
            }
        }
        Ok(reply)
    }
}

/// The affine map `[a, b, c, d, e, f]` (`(x, y)` to `(a x + b y + c, d x + e y + f)`) that
/// takes `from` to `to` by least squares, if it does so to within a millionth of `to`'s size.
fn affine_fit(from: &[[f64; 2]], to: &[[f64; 2]]) -> Option<[f64; 6]> {
    if from.len() != to.len() || from.len() < 3 {
        return None;
    }
    // Centred, for a well-conditioned 2x2 system.
    let mean = |ps: &[[f64; 2]]| {
        let n = ps.len() as f64;
        let s = ps.iter().fold([0.0; 2], |a, p| [a[0] + p[0], a[1] + p[1]]);
        [s[0] / n, s[1] / n]
    };
    let (mf, mt) = (mean(from), mean(to));
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    let mut r = [[0.0; 2]; 2];
    for (p, q) in from.iter().zip(to) {
        let (x, y) = (p[0] - mf[0], p[1] - mf[1]);
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
        for (d, rd) in r.iter_mut().enumerate() {
            let t = q[d] - mt[d];
            rd[0] += x * t;
            rd[1] += y * t;
        }
    }
    let det = sxx * syy - sxy * sxy;
    if det.abs() <= 1e-300 || det.is_nan() {
        return None;
    }
    let mut m = [0.0; 6];
    for d in 0..2 {
        let a = (syy * r[d][0] - sxy * r[d][1]) / det;
        let b = (sxx * r[d][1] - sxy * r[d][0]) / det;
        m[3 * d] = a;
        m[3 * d + 1] = b;
        m[3 * d + 2] = mt[d] - a * mf[0] - b * mf[1];
    }
    let size = to
        .iter()
        .map(|q| (q[0] - mt[0]).hypot(q[1] - mt[1]))
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let fits = from.iter().zip(to).all(|(p, q)| {
        let x = m[0] * p[0] + m[1] * p[1] + m[2];
        let y = m[3] * p[0] + m[4] * p[1] + m[5];
        (x - q[0]).hypot(y - q[1]) <= 1e-6 * size
    });
    (fits && m.iter().all(|c| c.is_finite())).then_some(m)
}
