//! Exports of a project's animation, shared by the studio's page (in the background, see
//! [`super::jobs`]) and the command line (`bdmorph export PROJECT.json`), so both make the
//! same frames from the same document.
//!
//! The frames are the animation sampled at the project's frame rate (`duration * fps + 1`
//! frames, the last on the last keyframe), or at a count asked for; a range of them may be
//! kept. Every frame is drawn in the view fitted over the frames kept (a first pass computes
//! them without drawing), at a size of the subject's own aspect unless one is asked for, on
//! white, a colour or transparency, in the draw order painted on the mesh ([`Project::depth`]).
//!
//! Frames stream: each is computed, drawn and handed to its encoder before the next, so
//! memory holds one picture and the encoded output (a sprite sheet holds the sheet).
//! Keyframes made from drawings ([`crate::project::KeyframeDrawing`]) bring their own
//! pictures: over a segment between two keyframes of different pictures, each frame is the
//! two pictures drawn on the frame's mesh and cross-faded (smoothly, along the segment's
//! eased time; [`export_with_drawings`]). HTML pages show the rest picture only.
//!
//! Nothing is left half-written: files are written under a temporary name and renamed
//! whole, folders filled under a temporary name and moved into place.
//!
//! ```no_run
//! use bdmorph::studio::export::{export, ExportSettings};
//! use bdmorph::studio::jobs::Progress;
//! use bdmorph::studio::project::Project;
//! let project = Project::read("wave.json".as_ref())?;
//! let settings: ExportSettings = ExportSettings::new("webp".parse()?).with_background("transparent".parse()?);
//! let done = export(&project, None, &settings, "wave.webp".as_ref(), &Progress::default())?;
//! println!("{} frames of {}x{}", done.frames, done.size.width, done.size.height);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;

use super::jobs::Progress;
use super::project::Project;
use crate::render::{
    apng, colour, depth_order, raster, sheet, webp, Background, Drawing, Image, ImageSize, Viewport,
};

/// The most frames an export makes.
pub const MAX_EXPORT_FRAMES: usize = 10_000;
/// The longer side of an export's pictures when no size is asked for.
pub const DEFAULT_LONG_SIDE: u32 = 640;

/// What an export writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportFormat {
    /// An animated GIF (opaque).
    Gif,
    /// An H.264 MP4 video (opaque; sides rounded up to even).
    Mp4,
    /// An animated PNG (lossless, with transparency).
    Apng,
    /// An animated WebP (lossless, with transparency).
    Webp,
    /// A sprite sheet: one PNG with every frame on a grid and a JSON file beside it.
    Sheet,
    /// A folder of PNG frames (`frame_0000.png`, ...).
    Frames,
    /// A strip of five frames coloured by their conformal distortion (PNG).
    Strip,
    /// A self-contained HTML viewer.
    Html,
    /// A folder of OBJ frames.
    Obj,
}

impl std::str::FromStr for ExportFormat {
    type Err = String;
    /// `gif`, `mp4`, `apng`, `webp`, `sheet`, `frames`, `png` (the strip), `html`, `obj`.
    fn from_str(s: &str) -> Result<ExportFormat, String> {
        Ok(match s {
            "gif" => ExportFormat::Gif,
            "mp4" => ExportFormat::Mp4,
            "apng" => ExportFormat::Apng,
            "webp" => ExportFormat::Webp,
            "sheet" => ExportFormat::Sheet,
            "frames" => ExportFormat::Frames,
            "png" | "strip" => ExportFormat::Strip,
            "html" => ExportFormat::Html,
            "obj" => ExportFormat::Obj,
            other => {
                return Err(format!(
                    "unknown export format '{other}' (gif, mp4, apng, webp, sheet, frames, png, html or obj)"
                ))
            }
        })
    }
}

impl ExportFormat {
    /// The file name endings it writes (none: a folder).
    pub fn endings(self) -> &'static [&'static str] {
        match self {
            ExportFormat::Gif => &[".gif"],
            ExportFormat::Mp4 => &[".mp4"],
            ExportFormat::Apng => &[".apng", ".png"],
            ExportFormat::Webp => &[".webp"],
            ExportFormat::Sheet | ExportFormat::Strip => &[".png"],
            ExportFormat::Html => &[".html", ".htm"],
            ExportFormat::Frames | ExportFormat::Obj => &[],
        }
    }

    /// The ending of each frame file of a folder export (`.png`, `.obj`; empty for the
    /// others).
    pub fn frame_ending(self) -> &'static str {
        match self {
            ExportFormat::Frames => ".png",
            ExportFormat::Obj => ".obj",
            _ => "",
        }
    }

    /// Whether it writes a folder.
    pub fn is_folder(self) -> bool {
        self.endings().is_empty()
    }

    /// Whether its pictures can be transparent.
    pub fn has_alpha(self) -> bool {
        matches!(
            self,
            ExportFormat::Apng | ExportFormat::Webp | ExportFormat::Sheet | ExportFormat::Frames
        )
    }

    /// Whether it draws pictures (and so takes a size and a background).
    pub fn draws(self) -> bool {
        !matches!(self, ExportFormat::Html | ExportFormat::Obj)
    }
}

/// How an export is made.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportSettings {
    /// What it writes.
    pub format: ExportFormat,
    /// How many frames the animation is sampled at (default: its duration times its frame
    /// rate, plus one).
    pub frames: Option<usize>,
    /// The frames kept, `[first, last]` (0-based, inclusive; default all).
    pub range: Option<[usize; 2]>,
    /// Picture size (default: the subject's aspect, [`DEFAULT_LONG_SIDE`] pixels on its
    /// longer side).
    pub size: Option<ImageSize>,
    /// What is behind the subject (default white).
    pub background: Background,
}

impl ExportSettings {
    /// The defaults for `format`.
    pub fn new(format: ExportFormat) -> ExportSettings {
        ExportSettings {
            format,
            frames: None,
            range: None,
            size: None,
            background: Background::WHITE,
        }
    }

    /// With a background.
    pub fn with_background(mut self, background: Background) -> ExportSettings {
        self.background = background;
        self
    }

    /// Checks what can be checked without the project: a transparent background on a
    /// format without transparency, a picture size the format cannot hold.
    pub fn check(&self) -> Result<(), String> {
        if self.background.is_transparent() && !self.format.has_alpha() {
            return Err(match self.format {
                ExportFormat::Mp4 | ExportFormat::Gif => format!(
                    "{} has no transparency: give a background colour, or export apng, webp, a sprite sheet or PNG frames",
                    if self.format == ExportFormat::Mp4 { "MP4" } else { "GIF" }
                ),
                _ => "a transparent background applies to apng, webp, sprite sheets and PNG frames".into(),
            });
        }
        if let Some([a, b]) = self.range {
            if a > b {
                return Err(format!(
                    "frame range {a}-{b}: the first frame is after the last"
                ));
            }
        }
        if let (Some(size), ExportFormat::Mp4) = (self.size, self.format) {
            #[cfg(feature = "video")]
            crate::render::video::video_size(size.width, size.height).map_err(|e| e.to_string())?;
            #[cfg(not(feature = "video"))]
            let _ = size;
        }
        if let (Some(size), ExportFormat::Webp) = (self.size, self.format) {
            if size.width > webp::MAX_WEBP_SIDE || size.height > webp::MAX_WEBP_SIDE {
                return Err(format!(
                    "WebP allows at most {} pixels a side",
                    webp::MAX_WEBP_SIDE
                ));
            }
        }
        Ok(())
    }
}

/// What an export made.
#[derive(Clone, Debug, PartialEq)]
pub struct Exported {
    /// Where.
    pub path: PathBuf,
    /// Frames written.
    pub frames: usize,
    /// The pictures' size.
    pub size: ImageSize,
    /// Files written besides `path` (the sprite sheet's JSON).
    pub also: Vec<PathBuf>,
}

/// The animation's frame count at its frame rate: `duration * fps + 1`.
pub fn default_frames(project: &Project) -> usize {
    ((project.end() * project.fps).round() as usize).saturating_add(1)
}

/// The frames `settings` keeps of the animation (indices into its `count` frames) and
/// `count`.
pub fn frames_kept(
    project: &Project,
    settings: &ExportSettings,
) -> Result<(Vec<usize>, usize), String> {
    let count = settings.frames.unwrap_or_else(|| default_frames(project));
    if count > MAX_EXPORT_FRAMES {
        let what = match settings.frames {
            Some(n) => format!("{n} frames"),
            None => {
                let duration = project.end();
                format!(
                    "the animation lasts {} s: over {MAX_EXPORT_FRAMES} frames at {} fps",
                    crate::morph::Readable(duration),
                    crate::morph::Readable(project.fps)
                )
            }
        };
        return Err(format!(
            "{what}: an export makes at most {MAX_EXPORT_FRAMES} (give fewer frames)"
        ));
    }
    let count = count.max(2);
    let picks: Vec<usize> = match settings.format {
        ExportFormat::Strip => vec![0, count / 4, count / 2, 3 * count / 4, count - 1],
        _ => {
            let [a, b] = settings.range.unwrap_or([0, count - 1]);
            if a > b || b >= count {
                return Err(format!(
                    "frame range {a}-{b}: the animation has frames 0-{}",
                    count - 1
                ));
            }
            (a..=b).collect()
        }
    };
    Ok((picks, count))
}

/// The frames of a project's animation, computed one at a time.
struct Animation {
    animation: crate::project::Animation,
    count: usize,
}

impl Animation {
    fn new(project: &Project, count: usize) -> Result<Animation, String> {
        if project.keyframes.len() < 2 {
            return Err("add a second keyframe to export an animation".into());
        }
        Ok(Animation {
            animation: crate::project::Animation::new(project)
                .map_err(|e| super::engine::people(&e))?,
            count,
        })
    }

    /// Frame `i` into `frame`; its time in seconds.
    fn frame(&mut self, i: usize, frame: &mut [[f64; 2]]) -> Result<f64, String> {
        let t = i as f64 / (self.count - 1) as f64;
        self.animation.frame_at(t, frame)?;
        Ok(t * self.animation.duration())
    }
}

/// A temporary name beside `path` for what becomes `path`.
fn temporary(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.part-{}", std::process::id()))
}

/// A fresh temporary file beside `path` (a stale one, or a link of that name, is removed,
/// not written through).
fn fresh_file(path: &Path) -> Result<(std::fs::File, PathBuf), String> {
    let temp = temporary(path);
    let _ = std::fs::remove_file(&temp);
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&temp)
        .map(|f| (f, temp.clone()))
        .map_err(|e| format!("{}: {e}", temp.display()))
}

/// A fresh temporary folder beside `path`.
fn fresh_folder(path: &Path) -> Result<PathBuf, String> {
    let dir = temporary(path);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    Ok(dir)
}

/// What an export found at its path when it was done: refused without `overwrite`.
fn exists(path: &Path) -> String {
    format!(
        "export: {} exists (it was made while the export ran): nothing was replaced",
        path.display()
    )
}

/// A finished temporary file synced and renamed over `path`; without `overwrite`, linked to
/// `path` only if nothing is there (no window in which another file could be replaced).
fn finish_file(
    file: std::fs::File,
    temp: &Path,
    path: &Path,
    overwrite: bool,
) -> Result<(), String> {
    file.sync_all().map_err(|e| failed(&e))?;
    if overwrite {
        return std::fs::rename(temp, path).map_err(|e| failed(&e));
    }
    let linked = std::fs::hard_link(temp, path);
    let _ = std::fs::remove_file(temp);
    match linked {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Err(exists(path)),
        Err(e) => Err(failed(&e)),
    }
}

/// `bytes` written to `path` whole: replacing a regular file with `overwrite`, else only
/// where nothing is.
fn write_whole(path: &Path, bytes: &[u8], overwrite: bool) -> Result<(), String> {
    if overwrite {
        return crate::io::write_bytes_atomic(path, bytes).map_err(|e| failed(&e));
    }
    let (mut file, temp) = fresh_file(path)?;
    let written = std::io::Write::write_all(&mut file, bytes).map_err(|e| failed(&e));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&temp);
        return Err(e);
    }
    finish_file(file, &temp, path, false)
}

/// A filled temporary folder moved to `path`, replacing what was there whole with
/// `overwrite` (a link is moved aside, not followed); without it, only onto a path where
/// nothing is.
fn finish_folder(dir: &Path, path: &Path, overwrite: bool) -> Result<(), String> {
    if !overwrite {
        if std::fs::symlink_metadata(path).is_ok() {
            return Err(exists(path));
        }
        // Renaming onto a folder made meanwhile fails unless it is empty.
        return std::fs::rename(dir, path).map_err(|e| failed(&e));
    }
    if std::fs::symlink_metadata(path).is_ok() {
        let old = temporary(path).with_extension("old");
        let _ = std::fs::remove_dir_all(&old);
        std::fs::rename(path, &old).map_err(|e| failed(&e))?;
        let _ = std::fs::remove_dir_all(&old);
    }
    std::fs::rename(dir, path).map_err(|e| failed(&e))
}

fn failed(e: &dyn std::fmt::Display) -> String {
    format!("export: {e}")
}

/// Where frames go, one at a time.
enum Sink {
    Gif(
        Box<raster::GifEncoder<std::io::BufWriter<std::fs::File>>>,
        PathBuf,
    ),
    #[cfg(feature = "video")]
    Mp4(
        Box<crate::render::video::Mp4Encoder<std::io::BufWriter<std::fs::File>>>,
        PathBuf,
    ),
    Apng(Box<apng::ApngEncoder<std::fs::File>>, PathBuf),
    Webp(Box<webp::WebpEncoder>),
    Sheet(sheet::SheetLayout, Image),
    Frames(PathBuf),
    Strip(Vec<(Vec<[f64; 2]>, Vec<f64>)>),
    Html(Vec<(f64, Vec<[f64; 2]>)>),
    Obj(PathBuf),
}

impl Sink {
    /// Removes what an unfinished export wrote.
    fn abandon(&self) {
        match self {
            Sink::Gif(_, temp) | Sink::Apng(_, temp) => {
                let _ = std::fs::remove_file(temp);
            }
            #[cfg(feature = "video")]
            Sink::Mp4(_, temp) => {
                let _ = std::fs::remove_file(temp);
            }
            Sink::Frames(dir) | Sink::Obj(dir) => {
                let _ = std::fs::remove_dir_all(dir);
            }
            _ => {}
        }
    }
}

/// Exports `project`'s animation to `path` as `settings` say, drawn with `texture` when the
/// mesh has texture coordinates. `progress` counts two units per frame (computed, then
/// drawn) and stops the export when cancelled.
pub fn export(
    project: &Project,
    texture: Option<&Image>,
    settings: &ExportSettings,
    path: &Path,
    progress: &Progress,
) -> Result<Exported, String> {
    export_with_drawings(project, texture, &[], settings, path, progress)
}

/// Texture coordinates at each corner of each triangle.
type CornerUv = Vec<[[f64; 2]; 3]>;

/// Keyframes' drawings, ready to draw frames with: per keyframe its picture and its
/// coordinates at each corner (`None`: the rest picture).
pub struct Looks<'a> {
    drawn: Vec<Option<(&'a Image, CornerUv)>>,
    /// Per keyframe, whether it is drawn with its own drawing.
    pub has_drawing: Vec<bool>,
}

impl<'a> Looks<'a> {
    /// The looks of `project`'s keyframes: `drawings[k]` is keyframe `k`'s drawing's picture
    /// (used when the rest picture, `textured`, is there to fade from).
    pub fn new(project: &Project, textured: bool, drawings: &[Option<&'a Image>]) -> Looks<'a> {
        let faces = &project.mesh.faces;
        let drawn: Vec<Option<(&Image, CornerUv)>> = project
            .keyframes
            .iter()
            .enumerate()
            .map(|(k, key)| {
                let d = key.drawing.as_ref()?;
                let image = (*drawings.get(k)?)?;
                if !textured {
                    return None;
                }
                let uv = faces
                    .iter()
                    .map(|f| f.map(|v| d.texcoords[v as usize]))
                    .collect();
                Some((image, uv))
            })
            .collect();
        let has_drawing = drawn.iter().map(Option::is_some).collect();
        Looks { drawn, has_drawing }
    }

    /// `positions` drawn as `drawing` says, with the pictures of `blend` (as [`blend_at`]
    /// gives it) cross-faded.
    pub fn render(
        &self,
        positions: &[[f64; 2]],
        drawing: &Drawing<'_>,
        blend: (usize, usize, f64),
        view: &Viewport,
        size: ImageSize,
        background: Background,
    ) -> Result<Image, raster::RenderError> {
        let (first, second, weight) = blend;
        if first == second && first == 0 {
            return raster::render_on(positions, drawing, view, size, background);
        }
        let textured = |look: usize| {
            let with = match look
                .checked_sub(1)
                .and_then(|k| self.drawn.get(k)?.as_ref())
            {
                Some((image, uv)) => Drawing {
                    texture: Some(image),
                    corner_uv: Some(uv),
                    ..*drawing
                },
                None => *drawing,
            };
            raster::render_on(positions, &with, view, size, Background::Transparent)
        };
        let under = textured(first)?;
        let over = if weight > 0.0 && second != first {
            textured(second)?
        } else {
            under.clone()
        };
        Ok(raster::crossfade(&under, &over, weight, background))
    }
}

/// The look of keyframe `k` alone (as [`blend_at`] gives looks).
pub fn keyframe_look(has_drawing: &[bool], k: usize) -> (usize, usize, f64) {
    let look = if has_drawing.get(k).copied().unwrap_or(false) {
        k + 1
    } else {
        0
    };
    (look, look, 0.0)
}

/// Which picture a frame is drawn with, per segment: the first keyframe's and the second's
/// (0 the rest picture, `k + 1` keyframe `k`'s drawing), and the second's share at `time`.
pub fn blend_at(project: &Project, has_drawing: &[bool], time: f64) -> (usize, usize, f64) {
    let keys = &project.keyframes;
    let look = |k: usize| {
        if has_drawing.get(k).copied().unwrap_or(false) {
            k + 1
        } else {
            0
        }
    };
    if keys.len() < 2 {
        return (look(0), look(0), 0.0);
    }
    let k = keys[..keys.len() - 1]
        .iter()
        .rposition(|key| key.time <= time)
        .unwrap_or(0);
    let (t0, t1) = (keys[k].time, keys[k + 1].time);
    let u = ((time - t0) / (t1 - t0)).clamp(0.0, 1.0);
    let eased = keys[k]
        .easing
        .parse::<crate::Easing>()
        .map_or(u, |e| e.apply(u));
    (
        look(k),
        look(k + 1),
        crate::inbetween::Crossfade::Smooth.weight(eased),
    )
}

/// [`export`], with each keyframe's own picture: `drawings[k]` is keyframe `k`'s drawing's
/// picture (`None`, or missing, for a keyframe without one or whose picture could not be
/// read: it shows the rest picture).
pub fn export_with_drawings(
    project: &Project,
    texture: Option<&Image>,
    drawings: &[Option<&Image>],
    settings: &ExportSettings,
    path: &Path,
    progress: &Progress,
) -> Result<Exported, String> {
    export_with_drawings_to(project, texture, drawings, settings, path, progress, true)
}

/// [`export_with_drawings`], replacing what is at `path` only with `overwrite`: without it,
/// the export is written beside and moved to `path` only if nothing is there when it is done
/// (else it is refused and what it wrote removed). A folder export never removes a file it
/// did not write unless it replaces the folder with `overwrite`.
#[allow(clippy::too_many_arguments)]
pub fn export_with_drawings_to(
    project: &Project,
    texture: Option<&Image>,
    drawings: &[Option<&Image>],
    settings: &ExportSettings,
    path: &Path,
    progress: &Progress,
    overwrite: bool,
) -> Result<Exported, String> {
    settings.check()?;
    let (picks, count) = frames_kept(project, settings)?;
    let mut animation = Animation::new(project, count)?;
    progress
        .total
        .store(2 * picks.len() as u64, Ordering::Relaxed);
    let faces = &project.mesh.faces;
    let mut frame = project.keyframes[0].positions.clone();
    // Pass 1: the view over every frame kept.
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for &i in &picks {
        progress.cancelled()?;
        animation.frame(i, &mut frame)?;
        for p in &frame {
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        progress.done.fetch_add(1, Ordering::Relaxed);
    }
    let view = Viewport::fit([lo, hi].iter().map(std::slice::from_ref));
    let size = settings
        .size
        .unwrap_or_else(|| ImageSize::fitting(&view, DEFAULT_LONG_SIDE));
    let corner_uv: Option<Vec<[[f64; 2]; 3]>> = project
        .mesh
        .texcoords
        .as_ref()
        .map(|uv| faces.iter().map(|f| f.map(|v| uv[v as usize])).collect());
    let texture = texture.filter(|_| corner_uv.is_some());
    let looks = Looks::new(project, texture.is_some(), drawings);
    let drawing = Drawing {
        faces,
        corner_uv: corner_uv.as_deref(),
        texture,
        face_colours: None,
        depth: project.depth.as_deref(),
    };
    let fps = project.fps.round().max(1.0) as u32;
    let frames = picks.len() as u32;
    let mut sink = match settings.format {
        ExportFormat::Gif => {
            let (file, temp) = fresh_file(path)?;
            let delay = (100.0 / project.fps).round().max(2.0) as u16;
            let out = std::io::BufWriter::new(file);
            match raster::GifEncoder::new(out, size.width, size.height, delay) {
                Ok(encoder) => Sink::Gif(Box::new(encoder), temp),
                Err(e) => {
                    let _ = std::fs::remove_file(&temp);
                    return Err(failed(&e));
                }
            }
        }
        #[cfg(feature = "video")]
        ExportFormat::Mp4 => {
            let (file, temp) = fresh_file(path)?;
            let out = std::io::BufWriter::new(file);
            match crate::render::video::Mp4Encoder::new(out, size.width, size.height, fps) {
                Ok(encoder) => Sink::Mp4(Box::new(encoder), temp),
                Err(e) => {
                    let _ = std::fs::remove_file(&temp);
                    return Err(failed(&e));
                }
            }
        }
        #[cfg(not(feature = "video"))]
        ExportFormat::Mp4 => return Err("this build has no MP4 video".into()),
        ExportFormat::Apng => {
            let (file, temp) = fresh_file(path)?;
            match apng::ApngEncoder::new(file, size.width, size.height, frames, fps) {
                Ok(encoder) => Sink::Apng(Box::new(encoder), temp),
                Err(e) => {
                    let _ = std::fs::remove_file(&temp);
                    return Err(failed(&e));
                }
            }
        }
        ExportFormat::Webp => Sink::Webp(Box::new(
            webp::WebpEncoder::new(size.width, size.height, fps).map_err(|e| failed(&e))?,
        )),
        ExportFormat::Sheet => {
            let layout =
                sheet::SheetLayout::new(frames, size.width, size.height).map_err(|e| failed(&e))?;
            let blank = layout.blank();
            Sink::Sheet(layout, blank)
        }
        ExportFormat::Frames => Sink::Frames(fresh_folder(path)?),
        ExportFormat::Strip => Sink::Strip(Vec::new()),
        ExportFormat::Html => Sink::Html(Vec::new()),
        ExportFormat::Obj => Sink::Obj(fresh_folder(path)?),
    };
    let shape = crate::distortion::RestShape::new(&project.mesh.positions, faces);
    let background = settings.background;
    // Pass 2: each frame drawn and handed on.
    let result = (|| -> Result<(), String> {
        for (k, &i) in picks.iter().enumerate() {
            progress.cancelled()?;
            let time = animation.frame(i, &mut frame)?;
            let picture = || {
                looks
                    .render(
                        &frame,
                        &drawing,
                        blend_at(project, &looks.has_drawing, time),
                        &view,
                        size,
                        background,
                    )
                    .map_err(|e| failed(&e))
            };
            match &mut sink {
                Sink::Gif(encoder, _) => encoder.push(&picture()?).map_err(|e| failed(&e))?,
                #[cfg(feature = "video")]
                Sink::Mp4(encoder, _) => encoder.push(&picture()?).map_err(|e| failed(&e))?,
                Sink::Apng(encoder, _) => encoder.push(&picture()?).map_err(|e| failed(&e))?,
                Sink::Webp(encoder) => encoder.push(&picture()?).map_err(|e| failed(&e))?,
                Sink::Sheet(layout, sheet) => layout.place(sheet, k as u32, &picture()?),
                Sink::Frames(dir) => {
                    let bytes = raster::encode_png(&picture()?).map_err(|e| failed(&e))?;
                    let file = dir.join(format!("frame_{k:04}.png"));
                    std::fs::write(&file, bytes).map_err(|e| format!("{}: {e}", file.display()))?;
                }
                Sink::Strip(frames) => {
                    let mut distortion = vec![1.0; faces.len()];
                    shape.distortion_into(&frame, &mut distortion);
                    frames.push((frame.clone(), distortion));
                }
                Sink::Html(frames) => frames.push((time, frame.clone())),
                Sink::Obj(dir) => {
                    let file = dir.join(format!("frame_{k:04}.obj"));
                    crate::io::write_obj_2d(&file, &frame, faces, &[])
                        .map_err(|e| e.to_string())?;
                }
            }
            progress.done.fetch_add(1, Ordering::Relaxed);
        }
        Ok(())
    })();
    if let Err(e) = result {
        sink.abandon();
        return Err(e);
    }
    let mut also = Vec::new();
    match sink {
        Sink::Gif(encoder, temp) => {
            let finished = encoder
                .finish()
                .map_err(|e| failed(&e))
                .and_then(|out| out.into_inner().map_err(|e| failed(e.error())))
                .and_then(|file| finish_file(file, &temp, path, overwrite));
            if finished.is_err() {
                let _ = std::fs::remove_file(&temp);
            }
            finished?;
        }
        #[cfg(feature = "video")]
        Sink::Mp4(encoder, temp) => {
            let finished = encoder
                .finish()
                .map_err(|e| failed(&e))
                .and_then(|out| out.into_inner().map_err(|e| failed(e.error())))
                .and_then(|file| finish_file(file, &temp, path, overwrite));
            if finished.is_err() {
                let _ = std::fs::remove_file(&temp);
            }
            finished?;
        }
        Sink::Apng(encoder, temp) => {
            let finished = encoder
                .finish()
                .map_err(|e| failed(&e))
                .and_then(|()| std::fs::File::open(&temp).map_err(|e| failed(&e)))
                .and_then(|file| finish_file(file, &temp, path, overwrite));
            if finished.is_err() {
                let _ = std::fs::remove_file(&temp);
            }
            finished?;
        }
        Sink::Webp(encoder) => {
            let bytes = encoder.finish().map_err(|e| failed(&e))?;
            write_whole(path, &bytes, overwrite)?;
        }
        Sink::Sheet(layout, sheet) => {
            let json_path = path.with_extension("json");
            let image_name = path
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            let png = raster::encode_png(&sheet).map_err(|e| failed(&e))?;
            write_whole(path, &png, overwrite)?;
            write_whole(
                &json_path,
                layout.json(&image_name, fps).as_bytes(),
                overwrite,
            )?;
            also.push(json_path);
        }
        Sink::Frames(dir) | Sink::Obj(dir) => {
            let moved = finish_folder(&dir, path, overwrite);
            if moved.is_err() {
                let _ = std::fs::remove_dir_all(&dir);
            }
            moved?;
        }
        Sink::Strip(frames) => {
            let max = colour::distortion_scale(frames.iter().map(|f| f.1.as_slice()));
            let mut images = Vec::with_capacity(frames.len());
            for (positions, distortion) in &frames {
                let shades = colour::shade_colours(&colour::distortion_shades(distortion, max));
                let drawing = Drawing {
                    faces,
                    face_colours: Some(&shades),
                    depth: project.depth.as_deref(),
                    ..Drawing::default()
                };
                images.push(
                    raster::render_on(positions, &drawing, &view, size, background)
                        .map_err(|e| failed(&e))?,
                );
            }
            let bytes = raster::encode_png(&raster::strip(&images, images.len()))
                .map_err(|e| failed(&e))?;
            write_whole(path, &bytes, overwrite)?;
        }
        Sink::Html(frames) => {
            let png = match texture {
                Some(t) => Some(raster::encode_png(t).map_err(|e| failed(&e))?),
                None => None,
            };
            let frames: Vec<(f64, &[[f64; 2]])> =
                frames.iter().map(|f| (f.0, f.1.as_slice())).collect();
            // The viewer draws triangles in their order: put them in the painted one.
            let order = project.depth.as_deref().and_then(depth_order);
            let (faces, corner_uv) = match &order {
                Some(order) => (
                    order.iter().map(|&f| faces[f]).collect::<Vec<_>>(),
                    corner_uv
                        .as_ref()
                        .map(|uv| order.iter().map(|&f| uv[f]).collect::<Vec<_>>()),
                ),
                None => (faces.clone(), corner_uv.clone()),
            };
            let page = crate::render::html::html(
                "bdmorph studio export",
                &frames,
                &faces,
                corner_uv.as_deref(),
                png.as_deref(),
                &view,
            );
            write_whole(path, page.as_bytes(), overwrite)?;
        }
    }
    Ok(Exported {
        path: path.to_path_buf(),
        frames: picks.len(),
        size,
        also,
    })
}
