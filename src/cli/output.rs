//! Output formats: choosing one, rendering every frame to bytes, writing atomically.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use bdmorph::io::{self, TexCoords};
use bdmorph::render::{
    apng, colour, depth_order, html, raster, sheet, svg, video, webp, Background, Drawing, Image,
    ImageSize, Viewport,
};
use rayon::prelude::*;

/// An output format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Wavefront OBJ: `v x y 0` lines in the source's order, the source's faces (and `vt`).
    Obj,
    /// SVG: filled triangles with edges.
    Svg,
    /// PNG: an anti-aliased picture, optionally textured.
    Png,
    /// GIF: an animated loop of all frames.
    Gif,
    /// MP4: an H.264 video of all frames (sides rounded up to even).
    Mp4,
    /// HTML: a self-contained viewer with a slider and play/pause.
    Html,
    /// APNG: an animated PNG of all frames, lossless, with transparency.
    Apng,
    /// WebP: an animated WebP of all frames, lossless, with transparency.
    Webp,
}

impl Format {
    /// The format named by a file extension, if any.
    pub fn from_extension(path: &Path) -> Option<Result<Format, String>> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "obj" => Ok(Format::Obj),
            "svg" => Ok(Format::Svg),
            "png" => Ok(Format::Png),
            "gif" => Ok(Format::Gif),
            "mp4" => Ok(Format::Mp4),
            "html" | "htm" => Ok(Format::Html),
            "apng" => Ok(Format::Apng),
            "webp" => Ok(Format::Webp),
            other => Err(format!(
                "{}: unknown output extension '.{other}' (use .obj, .svg, .png, .gif, .mp4, .apng, .webp or .html, or --format)",
                path.display()
            )),
        })
    }

    /// Whether one file holds every frame.
    pub fn is_animation(self) -> bool {
        matches!(
            self,
            Format::Gif | Format::Mp4 | Format::Html | Format::Apng | Format::Webp
        )
    }

    /// Whether its pictures can be transparent.
    pub fn has_alpha(self) -> bool {
        matches!(self, Format::Png | Format::Apng | Format::Webp)
    }

    fn extension(self) -> &'static str {
        match self {
            Format::Obj => "obj",
            Format::Svg => "svg",
            Format::Png => "png",
            Format::Gif => "gif",
            Format::Mp4 => "mp4",
            Format::Html => "html",
            Format::Apng => "apng",
            Format::Webp => "webp",
        }
    }
}

/// Where and how the frames are written.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The file, or the directory of per-frame files.
    pub path: PathBuf,
    /// The format.
    pub format: Format,
    /// Per-frame files in a directory.
    pub directory: bool,
    /// Every frame in one PNG sprite sheet, with a JSON file beside it.
    pub sheet: bool,
}

impl Plan {
    /// Decides the output from `-o`, `--format` and the number of frames.
    pub fn new(path: &Path, format: Option<Format>, frames: usize) -> Result<Plan, String> {
        Plan::with_sheet(path, format, frames, false)
    }

    /// As [`Plan::new`], with `--sheet`: every frame in one PNG sprite sheet (`-o` a .png).
    pub fn with_sheet(
        path: &Path,
        format: Option<Format>,
        frames: usize,
        sheet: bool,
    ) -> Result<Plan, String> {
        let from_ext = Format::from_extension(path).transpose()?;
        let format = format.or(from_ext).unwrap_or(Format::Obj);
        if sheet {
            if format != Format::Png {
                return Err(format!(
                    "{}: a sprite sheet (--sheet) is a .png file",
                    path.display()
                ));
            }
            return Ok(Plan {
                path: path.to_path_buf(),
                format,
                directory: false,
                sheet: true,
            });
        }
        let directory = frames > 1 && !format.is_animation();
        if directory && from_ext.is_some() {
            return Err(format!(
                "{}: with --frames, -o names a directory for {} frames (frame_0000.{}, ...); \
                 give a directory, or a .gif, .mp4 or .html file",
                path.display(),
                format.extension(),
                format.extension()
            ));
        }
        Ok(Plan {
            path: path.to_path_buf(),
            format,
            directory,
            sheet: false,
        })
    }

    /// Checks, before any frame is computed, that pictures of `size` can be written in this
    /// format; returns a note when the size will be adjusted (MP4 rounds odd sides up).
    pub fn check_size(&self, size: ImageSize) -> Result<Option<String>, String> {
        if self.format != Format::Mp4 {
            return Ok(None);
        }
        let (w, h) = video::video_size(size.width, size.height).map_err(|e| {
            format!(
                "{}: --size {}x{}: {e}",
                self.path.display(),
                size.width,
                size.height
            )
        })?;
        Ok(((w, h) != (size.width, size.height)).then(|| {
            format!(
                "H.264 needs even sides: the {}x{} pictures are padded with white to {w}x{h}",
                size.width, size.height
            )
        }))
    }

    /// Checks that the format can show `background` (transparency needs PNG, APNG or WebP).
    pub fn check_background(&self, background: Background) -> Result<(), String> {
        if background.is_transparent() && !self.format.has_alpha() {
            return Err(format!(
                "{}: {} has no transparency: give a background colour, or write .png, .apng or .webp",
                self.path.display(),
                self.format.extension().to_ascii_uppercase()
            ));
        }
        Ok(())
    }

    /// Whether the format draws pictures (and so can use a texture).
    pub fn draws(&self) -> bool {
        self.format != Format::Obj
    }
}

/// How frames look, shared by every renderer.
pub struct Look<'a> {
    /// Triangles.
    pub faces: &'a [[u32; 3]],
    /// The source's texture coordinates (written to OBJ frames).
    pub texcoords: Option<&'a TexCoords>,
    /// The texture and the coordinates of each corner in it, when texturing.
    pub texture: Option<(&'a Image, &'a [[[f64; 2]; 3]])>,
    /// Picture size.
    pub size: ImageSize,
    /// Playback speed of animations.
    pub fps: u32,
    /// A title or header line.
    pub title: &'a str,
    /// What is behind the subject in pictures.
    pub background: Background,
    /// The draw order: a depth level per face (higher in front), if any.
    pub depth: Option<&'a [i8]>,
    /// Textures cross-faded frame by frame instead of `texture` (in-betweens of drawings).
    pub crossfade: Option<Crossfade<'a>>,
}

/// Textures cross-faded frame by frame: two of them per frame, and how much of the second.
pub struct Crossfade<'a> {
    /// The textures, each with its coordinates at each corner (parallel to the faces).
    pub textures: Vec<(&'a Image, &'a [[[f64; 2]; 3]])>,
    /// Per frame (in the order of the frames rendered): the first texture, the second, and
    /// the second's share in [0, 1].
    pub blends: &'a [(usize, usize, f64)],
}

/// One computed frame.
pub struct Frame {
    /// Its index among the requested frames (which names its file).
    pub index: usize,
    /// Its time (NaN for a blend).
    pub t: f64,
    /// Its positions.
    pub positions: Vec<[f64; 2]>,
    /// The conformal distortion of each triangle, when pictures are coloured by it.
    pub distortion: Option<Vec<f64>>,
}

/// Per-frame shades (and the scale's maximum) when frames carry their distortion.
fn distortion_shading(frames: &[Frame]) -> Option<(Vec<Vec<u8>>, f64)> {
    if frames.iter().any(|f| f.distortion.is_none()) {
        return None;
    }
    let max = colour::distortion_scale(frames.iter().filter_map(|f| f.distortion.as_deref()));
    let shades = frames
        .iter()
        .map(|f| colour::distortion_shades(f.distortion.as_deref().unwrap_or(&[]), max))
        .collect();
    Some((shades, max))
}

/// Makes frame `i`'s file: its path and bytes.
type MakeFile<'a> = dyn Fn(usize, &Frame) -> Result<(PathBuf, Vec<u8>), String> + Sync + 'a;

/// Renders every frame into files in memory: `(path, bytes)`. Frames are drawn and encoded
/// in parallel on rayon's pool (each on its own, so the bytes do not depend on the number of
/// threads); an animation's pictures are drawn a batch at a time and pushed into its
/// encoder, so only its compressed bytes grow with the number of frames. `progress` is
/// called once per frame, from any thread.
pub fn render(
    plan: &Plan,
    look: &Look,
    frames: &[Frame],
    progress: impl Fn() + Sync,
) -> Result<Vec<(PathBuf, Vec<u8>)>, String> {
    let view = Viewport::fit(frames.iter().map(|f| f.positions.as_slice()));
    let shading = distortion_shading(frames);
    let colours: Vec<Option<Vec<[u8; 3]>>> = frames
        .iter()
        .enumerate()
        .map(|(i, _)| {
            shading
                .as_ref()
                .map(|(shades, _)| colour::shade_colours(&shades[i]))
        })
        .collect();
    let drawing = |i: usize| Drawing {
        faces: look.faces,
        corner_uv: look.texture.map(|(_, uv)| uv),
        texture: look.texture.map(|(img, _)| img),
        face_colours: colours[i].as_deref(),
        depth: look.depth,
    };
    let name = |i: usize| {
        if plan.directory {
            plan.path
                .join(format!("frame_{i:04}.{}", plan.format.extension()))
        } else {
            plan.path.clone()
        }
    };
    let err = |e: raster::RenderError| e.to_string();
    // Every frame's file (or picture), in order, made in parallel.
    let each = |make: &MakeFile| {
        frames
            .par_iter()
            .enumerate()
            .map(|(i, f)| {
                let file = make(i, f);
                progress();
                file
            })
            .collect::<Result<Vec<_>, String>>()
    };
    // A frame's picture: its drawing, or with cross-faded textures the two of the frame.
    let draw = |i: usize, f: &Frame| match &look.crossfade {
        Some(fade) if colours[i].is_none() && !fade.textures.is_empty() => {
            let (first, second, weight) = fade.blends.get(i).copied().unwrap_or((0, 0, 0.0));
            let textured = |k: usize| {
                let (texture, uv) = fade.textures[k.min(fade.textures.len() - 1)];
                let with = Drawing {
                    corner_uv: Some(uv),
                    texture: Some(texture),
                    ..drawing(i)
                };
                raster::render_on(
                    &f.positions,
                    &with,
                    &view,
                    look.size,
                    Background::Transparent,
                )
            };
            let under = textured(first)?;
            let over = if weight > 0.0 {
                textured(second)?
            } else {
                under.clone()
            };
            Ok(raster::crossfade(&under, &over, weight, look.background))
        }
        _ => raster::render_on(&f.positions, &drawing(i), &view, look.size, look.background),
    };
    let picture = |i: usize, f: &Frame| {
        let img = draw(i, f).map_err(err);
        progress();
        img
    };
    let mut files = Vec::new();
    match plan.format {
        Format::Obj => {
            files = each(&|_, f| {
                let mut bytes = Vec::new();
                let t_line = if f.t.is_nan() {
                    String::new()
                } else {
                    format!("t = {}", f.t)
                };
                io::format_obj_2d_textured(
                    &mut bytes,
                    &f.positions,
                    look.faces,
                    look.texcoords,
                    &[look.title, &t_line],
                )
                .map_err(|e| format!("{}: {e}", name(f.index).display()))?;
                Ok((name(f.index), bytes))
            })?;
        }
        Format::Svg => {
            files = each(&|i, f| {
                let svg = svg::svg(&f.positions, &drawing(i), &view, look.size);
                Ok((name(f.index), svg.into_bytes()))
            })?;
        }
        Format::Png if plan.sheet => {
            let (w, h) = (look.size.width, look.size.height);
            let layout = sheet::SheetLayout::new(frames.len() as u32, w, h).map_err(err)?;
            let mut picture_sheet = layout.blank();
            let mut k = 0;
            in_batches(frames, &picture, &mut |images| {
                for img in images {
                    layout.place(&mut picture_sheet, k, img);
                    k += 1;
                }
                Ok(())
            })?;
            let json_name = plan.path.with_extension("json");
            let image_name = plan
                .path
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            files.push((
                plan.path.clone(),
                raster::encode_png(&picture_sheet).map_err(err)?,
            ));
            files.push((json_name, layout.json(&image_name, look.fps).into_bytes()));
        }
        Format::Png => {
            files = each(&|i, f| {
                let img = draw(i, f).map_err(err)?;
                Ok((name(f.index), raster::encode_png(&img).map_err(err)?))
            })?;
        }
        Format::Apng => {
            let (w, h) = (look.size.width, look.size.height);
            let mut bytes = Vec::new();
            let mut apng = apng::ApngEncoder::new(&mut bytes, w, h, frames.len() as u32, look.fps)
                .map_err(err)?;
            in_batches(frames, &picture, &mut |images| {
                images
                    .iter()
                    .try_for_each(|img| apng.push(img))
                    .map_err(err)
            })?;
            apng.finish().map_err(err)?;
            files.push((name(0), bytes));
        }
        Format::Webp => {
            let (w, h) = (look.size.width, look.size.height);
            let mut webp = webp::WebpEncoder::new(w, h, look.fps).map_err(err)?;
            let mut pushed = Vec::new();
            in_batches(frames, &picture, &mut |images| {
                pushed.extend_from_slice(images);
                Ok(())
            })?;
            for img in &pushed {
                webp.push(img).map_err(err)?;
            }
            files.push((name(0), webp.finish().map_err(err)?));
        }
        Format::Gif => {
            let delay = (100 / look.fps.clamp(1, 100)) as u16;
            let (w, h) = (look.size.width, look.size.height);
            let mut gif = raster::GifEncoder::new(Vec::new(), w, h, delay).map_err(err)?;
            in_batches(frames, &picture, &mut |images| {
                gif.push_batch(images).map_err(err)
            })?;
            files.push((name(0), gif.finish().map_err(err)?));
        }
        Format::Mp4 => {
            let fail = |e: video::VideoError| format!("{}: {e}", name(0).display());
            let (w, h) = (look.size.width, look.size.height);
            let mut mp4 =
                video::Mp4Encoder::new(Cursor::new(Vec::new()), w, h, look.fps).map_err(fail)?;
            in_batches(frames, &picture, &mut |images| {
                images
                    .iter()
                    .try_for_each(|img| mp4.push(img))
                    .map_err(fail)
            })?;
            files.push((name(0), mp4.finish().map_err(fail)?.into_inner()));
        }
        Format::Html => {
            let texture_png = match look.texture {
                Some((img, _)) => Some(raster::encode_png(img).map_err(err)?),
                None => None,
            };
            let refs: Vec<(f64, &[[f64; 2]])> = frames
                .iter()
                .map(|f| (f.t, f.positions.as_slice()))
                .collect();
            // The viewer draws triangles in their order: the painted one.
            let order = look.depth.and_then(depth_order);
            let ordered_faces: Vec<[u32; 3]>;
            let ordered_uv: Vec<[[f64; 2]; 3]>;
            let mut faces = look.faces;
            let mut corner_uv = look.texture.map(|(_, uv)| uv);
            if let Some(order) = &order {
                ordered_faces = order.iter().map(|&f| look.faces[f]).collect();
                faces = &ordered_faces;
                if let Some(uv) = corner_uv {
                    ordered_uv = order.iter().map(|&f| uv[f]).collect();
                    corner_uv = Some(&ordered_uv);
                }
            }
            let shading = shading.as_ref().map(|(shades, max)| html::Shading {
                shades,
                label: "conformal distortion",
                max: *max,
            });
            let reordered_shades: Option<Vec<Vec<u8>>> = match (&order, &shading) {
                (Some(order), Some(s)) => Some(
                    s.shades
                        .iter()
                        .map(|frame| order.iter().map(|&f| frame[f]).collect())
                        .collect(),
                ),
                _ => None,
            };
            let shading = match (&reordered_shades, shading) {
                (Some(shades), Some(s)) => Some(html::Shading {
                    shades: shades.as_slice(),
                    ..s
                }),
                (_, s) => s,
            };
            let page = html::html_shaded(
                look.title,
                &refs,
                faces,
                corner_uv,
                texture_png.as_deref(),
                shading.as_ref(),
                &view,
            );
            files.push((name(0), page.into_bytes()));
            for _ in frames {
                progress();
            }
        }
    }
    Ok(files)
}

/// Draws the frames' pictures a batch of 2 x threads at a time (in parallel on rayon's pool)
/// and hands the batches in order to `push`, drawing the next batch while `push` encodes the
/// current one: an animation holds two batches of pictures, never every frame.
fn in_batches(
    frames: &[Frame],
    picture: &(dyn Fn(usize, &Frame) -> Result<Image, String> + Sync),
    push: &mut (dyn FnMut(&[Image]) -> Result<(), String> + Send),
) -> Result<(), String> {
    let batch = 2 * rayon::current_num_threads();
    let draw = |start: usize| -> Result<Vec<Image>, String> {
        let end = frames.len().min(start.saturating_add(batch));
        frames
            .get(start..end)
            .unwrap_or_default()
            .par_iter()
            .enumerate()
            .map(|(k, f)| picture(start + k, f))
            .collect()
    };
    let mut start = 0;
    let mut current = draw(start)?;
    while !current.is_empty() {
        start += batch;
        let (pushed, next) = rayon::join(|| push(&current), || draw(start));
        pushed?;
        current = next?;
    }
    Ok(())
}

/// Writes rendered files, each atomically; creates the directory of per-frame output.
pub fn write(plan: &Plan, files: &[(PathBuf, Vec<u8>)]) -> Result<(), String> {
    if plan.directory {
        std::fs::create_dir_all(&plan.path)
            .map_err(|e| format!("{}: cannot create directory: {e}", plan.path.display()))?;
    }
    for (path, bytes) in files {
        io::write_bytes_atomic(path, bytes).map_err(|e| e.to_string())?;
    }
    Ok(())
}
