//! Long work, off the editing path: exports, new meshes and opened files run on a thread of
//! their own (with one core's worth of rayon threads, the others left to drags and scrubs),
//! report progress, and stop early when cancelled. Each works on its own copy of what it
//! needs, taken when it starts; what it makes is applied to the document when it ends (a new
//! mesh as one undoable step), or said in a note.
//!
//! Exports are made by [`super::export`], the command line's exporter too.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;

use super::export::{export_with_drawings_to, ExportSettings};
use super::open::{open_with, OpenOptions, Opened};
use super::project::Project;
use crate::mesh::PlanarMesh;
use crate::meshing::{Meshed, Outline};
use crate::render::Image;

pub use super::export::MAX_EXPORT_FRAMES;

/// Progress of a job, shared with the session (and the pages).
#[derive(Debug, Default)]
pub struct Progress {
    /// Units done.
    pub done: AtomicU64,
    /// Units in all (0: unknown).
    pub total: AtomicU64,
    /// Set to stop the job early (shared with the budget handed to the library's loops).
    pub cancel: Arc<AtomicBool>,
}

impl Progress {
    /// A budget stopped when this job is cancelled, for the library's long loops.
    pub fn budget(&self) -> crate::Budget {
        crate::Budget::unlimited().with_cancel(self.cancel.clone())
    }

    /// Asks the job to stop (it stops at its next check).
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// `Err("cancelled")` once the job is asked to stop.
    pub fn cancelled(&self) -> Result<(), String> {
        if self.cancel.load(Ordering::Relaxed) {
            Err("cancelled".into())
        } else {
            Ok(())
        }
    }
}

/// Work to run off the editing path.
#[derive(Debug)]
pub enum Work {
    /// An export of the animation.
    Export(Box<ExportWork>),
    /// A new mesh from an outline.
    Mesh(MeshWork),
    /// A file opened.
    Open(OpenWork),
    /// A keyframe made from a drawing.
    Drawing(Box<DrawingWork>),
}

/// What a job made.
#[derive(Debug)]
pub enum Outcome {
    /// A file written.
    Exported {
        /// Where.
        path: PathBuf,
        /// Frames in it.
        frames: usize,
        /// The bytes written (every file of it: a folder's frames, a sheet's JSON).
        bytes: u64,
    },
    /// A new mesh (to carry the animation over to).
    Meshed {
        /// The outline it was made from.
        outline: Vec<Vec<[f64; 2]>>,
        /// The mesh.
        meshed: Box<Meshed>,
        /// The vertex count asked for.
        asked: usize,
        /// The rest mesh it replaces (it is applied only if that is still the document's).
        replaces: Box<PlanarMesh>,
        /// What was said about it.
        notes: Vec<String>,
    },
    /// A keyframe made from a drawing (to add if the rest mesh is still `replaces`).
    Drawn {
        /// The keyframe.
        keyframe: Box<crate::project::Keyframe>,
        /// What was done, in words.
        notes: Vec<String>,
        /// The rest mesh it was made for.
        replaces: Box<PlanarMesh>,
    },
    /// A document opened.
    Opened {
        /// It.
        opened: Box<Opened>,
        /// The file's name in the workspace.
        name: String,
    },
}

impl Work {
    /// What the job is, for the page ("export anim.mp4", ...).
    pub fn label(&self) -> String {
        match self {
            Work::Export(e) => format!(
                "exporting {}",
                e.path
                    .file_name()
                    .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
            ),
            Work::Mesh(m) => format!("meshing ({} vertices)", m.vertices),
            Work::Open(o) => format!("opening {}", o.name),
            Work::Drawing(d) => format!("laying the mesh over {}", d.name),
        }
    }

    /// Runs the job (on the caller's thread, with at most `threads` rayon threads).
    pub fn run(self, progress: &Progress, threads: usize) -> Result<Outcome, String> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.max(1))
            .build()
            .map_err(|e| e.to_string())?;
        pool.install(|| match self {
            Work::Export(e) => e.run(progress),
            Work::Mesh(m) => m.run(progress),
            Work::Open(o) => o.run(progress),
            Work::Drawing(d) => d.run(progress),
        })
    }
}

/// An export's inputs, copied from the document when it starts.
#[derive(Debug)]
pub struct ExportWork {
    /// What and how.
    pub settings: ExportSettings,
    /// The file (or folder) to write.
    pub path: PathBuf,
    /// Whether what is at `path` may be replaced (else the export is refused if something is
    /// there when it is done).
    pub overwrite: bool,
    /// The document (its keyframes, times, easings, mesh, depth).
    pub project: Project,
    /// The picture drawn on the mesh.
    pub texture: Option<Arc<Image>>,
    /// Per keyframe, its drawing's picture (made from a drawing, and read).
    pub drawings: Vec<Option<Arc<Image>>>,
}

impl ExportWork {
    fn run(self, progress: &Progress) -> Result<Outcome, String> {
        let drawings: Vec<Option<&Image>> = self.drawings.iter().map(|d| d.as_deref()).collect();
        let done = export_with_drawings_to(
            &self.project,
            self.texture.as_deref(),
            &drawings,
            &self.settings,
            &self.path,
            progress,
            self.overwrite,
        )?;
        let bytes = std::iter::once(&done.path)
            .chain(&done.also)
            .map(|p| size_written(p))
            .sum();
        Ok(Outcome::Exported {
            path: done.path,
            frames: done.frames,
            bytes,
        })
    }
}

/// The bytes of the file at `path`, or of the regular files in the folder at `path`.
pub fn size_written(path: &std::path::Path) -> u64 {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => std::fs::read_dir(path).map_or(0, |entries| {
            entries
                .filter_map(Result::ok)
                .filter_map(|e| e.metadata().ok())
                .filter(std::fs::Metadata::is_file)
                .map(|m| m.len())
                .sum()
        }),
        Ok(m) => m.len(),
        Err(_) => 0,
    }
}

/// A new mesh from an outline.
#[derive(Debug)]
pub struct MeshWork {
    /// The loops.
    pub loops: Vec<Vec<[f64; 2]>>,
    /// About how many vertices.
    pub vertices: usize,
    /// The picture's size in pixels, if the mesh is textured by it (its texture frame).
    pub picture: Option<[u32; 2]>,
    /// The rest mesh it replaces.
    pub replaces: PlanarMesh,
}

impl MeshWork {
    fn run(self, progress: &Progress) -> Result<Outcome, String> {
        progress.total.store(0, Ordering::Relaxed);
        let mut notes = Vec::new();
        let fitted = crate::meshing::fit_loops_to_vertices(&self.loops, self.vertices);
        if let Some(tolerance) = fitted.tolerance {
            notes.push(format!(
                "the outline was simplified to {} points (within {tolerance:.2} units) to leave room for {} vertices",
                fitted.loops.iter().map(Vec::len).sum::<usize>(),
                self.vertices
            ));
        }
        let mut outline = Outline::from_loops(&fitted.loops);
        if let Some([w, h]) = self.picture {
            outline.texture_frame = Some([0.0, 0.0, f64::from(w), f64::from(h)]);
        }
        // The mesher has no budget of its own (its work is bounded by the studio's vertex
        // cap, about a second at the largest): Cancel is heard between the stages here.
        let options = crate::meshing::MeshOptions::default().with_vertices(self.vertices);
        progress.cancelled()?;
        let meshed = crate::meshing::mesh_outline(&outline, &options).map_err(|e| e.to_string())?;
        progress.cancelled()?;
        Ok(Outcome::Meshed {
            outline: fitted.loops,
            meshed: Box::new(meshed),
            asked: self.vertices,
            replaces: Box::new(self.replaces),
            notes,
        })
    }
}

/// A file opened.
#[derive(Debug)]
pub struct OpenWork {
    /// Its name in the workspace.
    pub name: String,
    /// Its path.
    pub path: PathBuf,
    /// The workspace.
    pub workspace: PathBuf,
    /// How.
    pub options: OpenOptions,
}

impl OpenWork {
    fn run(self, progress: &Progress) -> Result<Outcome, String> {
        progress.cancelled()?;
        // Cancel is heard between a layered picture's layers and while its character is made.
        let opened = open_with(
            &self.path,
            &self.workspace,
            &self.options,
            &progress.budget(),
        )?;
        progress.cancelled()?;
        Ok(Outcome::Opened {
            opened: Box::new(opened),
            name: self.name,
        })
    }
}

/// A keyframe made from a drawing: its inputs, copied from the document when it starts.
#[derive(Debug)]
pub struct DrawingWork {
    /// The drawing's name in the workspace.
    pub name: String,
    /// Its pixels.
    pub drawing: Arc<Image>,
    /// The rest mesh in the rest picture's pixels (y up).
    pub mesh: PlanarMesh,
    /// The rest picture's height in pixels.
    pub picture_height: f64,
    /// The map from the rest picture's pixels (y up) to the mesh's frame: `[a, b, c, d, e, f]`
    /// takes `(x, y)` to `(a x + b y + c, d x + e y + f)`.
    pub to_mesh: [f64; 6],
    /// The point pairs (rest picture, drawing), pixels from the top-left corner.
    pub pairs: Vec<[[f64; 2]; 2]>,
    /// How the drawing's subject is told from its background.
    pub picture: crate::meshing::PictureOptions,
    /// When the keyframe goes.
    pub time: f64,
    /// The rest mesh it is made for.
    pub replaces: PlanarMesh,
}

impl DrawingWork {
    fn run(self, progress: &Progress) -> Result<Outcome, String> {
        use crate::inbetween::{fit_drawing, InbetweenOptions, Match};
        progress.total.store(0, Ordering::Relaxed);
        progress.cancelled()?;
        let matches: Vec<Match> = self.pairs.iter().map(|&[a, b]| Match { a, b }).collect();
        // Cancel is heard inside the fit's solves (its untangling and bounded stages).
        let options = InbetweenOptions::default()
            .with_picture(self.picture)
            .with_budget(progress.budget());
        let fit = fit_drawing(
            &self.mesh,
            self.picture_height,
            &self.drawing,
            &matches,
            &options,
        )
        .map_err(|e| format!("{}: {e}", self.name))?;
        progress.cancelled()?;
        let m = self.to_mesh;
        let positions = fit
            .positions
            .iter()
            .map(|p| {
                [
                    m[0] * p[0] + m[1] * p[1] + m[2],
                    m[3] * p[0] + m[4] * p[1] + m[5],
                ]
            })
            .collect();
        let r = &fit.report;
        let mut notes = vec![format!(
            "{}: the mesh laid over it without a flipped triangle (largest distortion {:.2}; its outline within {:.1} px of the mesh's)",
            self.name, r.max_distortion, r.outline_error
        )];
        for (k, pair) in r.pairs.iter().enumerate() {
            if let Some(reason) = &pair.reason {
                notes.push(format!("{}: pair {} not met: {reason}", self.name, k + 1));
            }
        }
        let mut keyframe = super::edit::keyframe_at(self.time, positions);
        keyframe.drawing = Some(crate::project::KeyframeDrawing {
            picture: self.name,
            texcoords: fit.texcoords,
            pairs: self.pairs,
        });
        Ok(Outcome::Drawn {
            keyframe: Box::new(keyframe),
            notes,
            replaces: Box::new(self.replaces),
        })
    }
}
