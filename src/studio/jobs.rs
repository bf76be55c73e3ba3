//! Long work, off the editing path: exports, new meshes and opened files run on a thread of
//! their own (with one core's worth of rayon threads, the others left to drags and scrubs),
//! report progress, and stop early when cancelled. Each works on its own copy of what it
//! needs, taken when it starts; what it makes is applied to the document when it ends (a new
//! mesh as one undoable step), or said in a note.
//!
//! Exports stream: frames are computed, drawn and handed to the encoder one at a time, so
//! memory does not grow with the number of frames (beyond the encoded output). The view is
//! fitted over every frame first (a pass that computes the frames without drawing them).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;

use super::engine::path_of;
use super::open::{open, OpenOptions, Opened};
use super::project::Project;
use crate::mesh::PlanarMesh;
use crate::meshing::{Meshed, Outline};
use crate::render::{colour, raster, Drawing, Image, ImageSize, Viewport};

/// The most frames an export makes.
pub const MAX_EXPORT_FRAMES: usize = 10_000;

/// Progress of a job, shared with the session (and the pages).
#[derive(Debug, Default)]
pub struct Progress {
    /// Units done.
    pub done: AtomicU64,
    /// Units in all (0: unknown).
    pub total: AtomicU64,
    /// Set to stop the job early.
    pub cancel: AtomicBool,
}

impl Progress {
    fn cancelled(&self) -> Result<(), String> {
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
        })
    }
}

/// An export's inputs, copied from the document when it starts.
#[derive(Debug)]
pub struct ExportWork {
    /// `gif`, `mp4`, `png` (a strip of five frames coloured by distortion), `html` or `obj`.
    pub format: String,
    /// The file (or folder, for `obj`) to write.
    pub path: PathBuf,
    /// Frames.
    pub frames: usize,
    /// The document (its keyframes, times, easings, mesh).
    pub project: Project,
    /// The picture drawn on the mesh.
    pub texture: Option<Arc<Image>>,
}

/// Where frames go, one at a time.
enum Sink {
    /// An animated GIF, encoded as the frames come, into a temporary file.
    Gif(
        Box<raster::GifEncoder<std::io::BufWriter<std::fs::File>>>,
        PathBuf,
    ),
    /// An MP4, encoded as the frames come, into a temporary file.
    Mp4(
        Box<crate::render::video::Mp4Encoder<std::io::BufWriter<std::fs::File>>>,
        PathBuf,
    ),
    /// A strip of coloured frames.
    Strip(Vec<Image>),
    /// The HTML viewer's frames (positions: what the page embeds).
    Html(Vec<(f64, Vec<[f64; 2]>)>),
    /// OBJ files in a folder being filled.
    Obj(PathBuf),
}

impl ExportWork {
    fn run(self, progress: &Progress) -> Result<Outcome, String> {
        let count = self.frames.clamp(2, MAX_EXPORT_FRAMES);
        let strip = self.format == "png";
        let picks: Vec<usize> = if strip {
            vec![0, count / 4, count / 2, 3 * count / 4, count - 1]
        } else {
            (0..count).collect()
        };
        progress
            .total
            .store(2 * picks.len() as u64, Ordering::Relaxed);
        let faces = self.project.mesh.faces.clone();
        let meshes: Vec<PlanarMesh> = self
            .project
            .keyframes
            .iter()
            .map(|k| PlanarMesh {
                positions: k.positions.clone(),
                faces: faces.clone(),
            })
            .collect();
        let duration = self.project.keyframes.last().map_or(0.0, |k| k.time);
        let mut path = if meshes.len() >= 2 {
            Some(path_of(&self.project, &meshes)?)
        } else {
            None
        };
        let mut frame = self.project.keyframes[0].positions.clone();
        let mut at = |i: usize, frame: &mut Vec<[f64; 2]>| -> Result<f64, String> {
            let t = i as f64 / (count - 1) as f64;
            if let Some(path) = path.as_mut() {
                path.frame_into(t, frame).map_err(|e| e.to_string())?;
            }
            Ok(t * duration)
        };
        // Pass 1: the view over every frame.
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for &i in &picks {
            progress.cancelled()?;
            at(i, &mut frame)?;
            for p in &frame {
                for d in 0..2 {
                    lo[d] = lo[d].min(p[d]);
                    hi[d] = hi[d].max(p[d]);
                }
            }
            progress.done.fetch_add(1, Ordering::Relaxed);
        }
        let view = Viewport::fit([lo, hi].iter().map(std::slice::from_ref));
        let corner_uv: Option<Vec<[[f64; 2]; 3]>> = self
            .project
            .mesh
            .texcoords
            .as_ref()
            .map(|uv| faces.iter().map(|f| f.map(|v| uv[v as usize])).collect());
        let texture = self.texture.as_deref().filter(|_| corner_uv.is_some());
        let size = ImageSize {
            width: 640,
            height: 640,
        };
        let shape = crate::distortion::RestShape::new(&self.project.mesh.positions, &faces);
        let mut distortion = vec![1.0; faces.len()];
        let temp_dir = |path: &PathBuf| {
            let name = path
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            path.with_file_name(format!(".{name}.part-{}", std::process::id()))
        };
        let file = |path: &PathBuf| {
            let temp = temp_dir(path);
            // A fresh file: a stale one (or a link of that name) is removed, not written through.
            let _ = std::fs::remove_file(&temp);
            std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&temp)
                .map(|f| (std::io::BufWriter::new(f), temp.clone()))
                .map_err(|e| format!("{}: {e}", temp.display()))
        };
        let mut sink = match self.format.as_str() {
            "gif" => {
                let (out, temp) = file(&self.path)?;
                let delay = (100.0 / self.project.fps).round().max(2.0) as u16;
                match raster::GifEncoder::new(out, size.width, size.height, delay) {
                    Ok(encoder) => Sink::Gif(Box::new(encoder), temp),
                    Err(e) => {
                        let _ = std::fs::remove_file(&temp);
                        return Err(format!("export: {e}"));
                    }
                }
            }
            "mp4" => {
                let (out, temp) = file(&self.path)?;
                let fps = self.project.fps.round().max(1.0) as u32;
                match crate::render::video::Mp4Encoder::new(out, size.width, size.height, fps) {
                    Ok(encoder) => Sink::Mp4(Box::new(encoder), temp),
                    Err(e) => {
                        let _ = std::fs::remove_file(&temp);
                        return Err(format!("export: {e}"));
                    }
                }
            }
            "png" => Sink::Strip(Vec::new()),
            "html" => Sink::Html(Vec::new()),
            "obj" => {
                // A fresh folder of our own: a stale one is removed (a link only unlinked, never
                // followed), and the frames go into one this export created.
                let dir = temp_dir(&self.path);
                let _ = std::fs::remove_dir_all(&dir);
                std::fs::create_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
                Sink::Obj(dir)
            }
            other => return Err(format!("unknown export format '{other}'")),
        };
        // The strip's colour scale: the largest distortion over its frames.
        let mut strip_frames = Vec::new();
        // Pass 2: each frame drawn and handed on.
        let result = (|| -> Result<(), String> {
            for (k, &i) in picks.iter().enumerate() {
                progress.cancelled()?;
                let time = at(i, &mut frame)?;
                let drawing = Drawing {
                    faces: &faces,
                    corner_uv: corner_uv.as_deref(),
                    texture,
                    face_colours: None,
                };
                match &mut sink {
                    Sink::Gif(encoder, _) => encoder
                        .push(&raster::render(&frame, &drawing, &view, size))
                        .map_err(|e| format!("export: {e}"))?,
                    Sink::Mp4(encoder, _) => encoder
                        .push(&raster::render(&frame, &drawing, &view, size))
                        .map_err(|e| format!("export: {e}"))?,
                    Sink::Strip(_) => {
                        shape.distortion_into(&frame, &mut distortion);
                        strip_frames.push((frame.clone(), distortion.clone()));
                    }
                    Sink::Html(frames) => frames.push((time, frame.clone())),
                    Sink::Obj(dir) => {
                        let file = dir.join(format!("frame_{k:04}.obj"));
                        crate::io::write_obj_2d(&file, &frame, &faces, &[])
                            .map_err(|e| e.to_string())?;
                    }
                }
                progress.done.fetch_add(1, Ordering::Relaxed);
            }
            Ok(())
        })();
        if let Err(e) = result {
            match &sink {
                Sink::Obj(dir) => {
                    let _ = std::fs::remove_dir_all(dir);
                }
                Sink::Gif(_, temp) | Sink::Mp4(_, temp) => {
                    let _ = std::fs::remove_file(temp);
                }
                _ => {}
            }
            return Err(e);
        }
        let failed = |e: &dyn std::fmt::Display| format!("export: {e}");
        match sink {
            Sink::Gif(encoder, temp) => {
                let finished = encoder
                    .finish()
                    .map_err(|e| failed(&e))
                    .and_then(|out| finish_file(out, &temp, &self.path));
                if finished.is_err() {
                    let _ = std::fs::remove_file(&temp);
                }
                finished?;
            }
            Sink::Mp4(encoder, temp) => {
                let finished = encoder
                    .finish()
                    .map_err(|e| failed(&e))
                    .and_then(|out| finish_file(out, &temp, &self.path));
                if finished.is_err() {
                    let _ = std::fs::remove_file(&temp);
                }
                finished?;
            }
            Sink::Strip(mut images) => {
                let max = colour::distortion_scale(strip_frames.iter().map(|f| f.1.as_slice()));
                for (positions, distortion) in &strip_frames {
                    let shades = colour::shade_colours(&colour::distortion_shades(distortion, max));
                    let drawing = Drawing {
                        faces: &faces,
                        corner_uv: None,
                        texture: None,
                        face_colours: Some(&shades),
                    };
                    images.push(raster::render(positions, &drawing, &view, size));
                }
                let bytes = raster::encode_png(&raster::strip(&images, images.len()))
                    .map_err(|e| failed(&e))?;
                crate::io::write_bytes_atomic(&self.path, &bytes).map_err(|e| failed(&e))?;
            }
            Sink::Html(frames) => {
                let png = match texture {
                    Some(t) => Some(raster::encode_png(t).map_err(|e| failed(&e))?),
                    None => None,
                };
                let frames: Vec<(f64, &[[f64; 2]])> =
                    frames.iter().map(|f| (f.0, f.1.as_slice())).collect();
                let page = crate::render::html::html(
                    "bdmorph studio export",
                    &frames,
                    &faces,
                    corner_uv.as_deref(),
                    png.as_deref(),
                    &view,
                );
                crate::io::write_bytes_atomic(&self.path, page.as_bytes())
                    .map_err(|e| failed(&e))?;
            }
            Sink::Obj(dir) => {
                // The finished folder replaces the old one whole (checked when the export was
                // asked for: a folder of earlier frames; a link is moved aside, not followed).
                if std::fs::symlink_metadata(&self.path).is_ok() {
                    let old = temp_dir(&self.path).with_extension("old");
                    let _ = std::fs::remove_dir_all(&old);
                    std::fs::rename(&self.path, &old).map_err(|e| failed(&e))?;
                    let _ = std::fs::remove_dir_all(&old);
                }
                std::fs::rename(&dir, &self.path).map_err(|e| failed(&e))?;
            }
        }
        Ok(Outcome::Exported {
            path: self.path,
            frames: picks.len(),
        })
    }
}

/// A finished temporary file flushed, synced and renamed over `path`.
fn finish_file(
    out: std::io::BufWriter<std::fs::File>,
    temp: &std::path::Path,
    path: &std::path::Path,
) -> Result<(), String> {
    let failed = |e: &dyn std::fmt::Display| format!("export: {e}");
    let file = out.into_inner().map_err(|e| failed(e.error()))?;
    file.sync_all().map_err(|e| failed(&e))?;
    std::fs::rename(temp, path).map_err(|e| failed(&e))
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
        let opened = open(&self.path, &self.workspace, &self.options)?;
        progress.cancelled()?;
        Ok(Outcome::Opened {
            opened: Box::new(opened),
            name: self.name,
        })
    }
}
