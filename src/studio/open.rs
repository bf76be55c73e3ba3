//! Opening a file as a studio document: a project (`.json`), a mesh (`.obj`, `.off`) with the
//! picture of the same name beside it (or one given), or a picture (`.png`, `.jpg`), meshed by
//! its subject. Pictures without transparency are told from their background by its colour
//! (`auto`: the colour of the picture's border) unless settings say otherwise.
//!
//! What cannot be used is said, not fatal where the rest can be: a project whose picture is
//! missing opens untextured, with a note naming both files.
//!
//! Pictures are read as regular files of at most [`MAX_PICTURE_BYTES`] (a pipe, device or
//! folder is refused without blocking on it). A project opened from the page may name only a
//! picture inside the workspace ([`OpenOptions::pictures_inside`]); one outside is not read,
//! and the project opens without it, as without a missing one. A picture given on the command
//! line (`--texture`) is the user's own choice and may lie anywhere.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::project::{PictureSettings, Project};
use super::workspace::{read_regular, ReadError, Workspace, MAX_UPLOAD};
use crate::render::{raster, Image};

/// A picture drawn on the mesh, as decoded and as the page gets it.
#[derive(Debug)]
pub struct Texture {
    /// Its file (as the document names it).
    pub name: String,
    /// The pixels.
    pub image: Image,
    /// The file's bytes (served to the page as they are).
    pub bytes: Vec<u8>,
    /// Their media type.
    pub content_type: &'static str,
}

/// The largest picture file the studio reads (64 MiB, as large as an upload may be).
pub const MAX_PICTURE_BYTES: u64 = MAX_UPLOAD as u64;

/// Why a picture could not be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TextureError {
    /// Not a regular file, too large, or unreadable.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// Not a PNG or JPEG picture that decodes.
    #[error("{}: {source}", .path.display())]
    Decode {
        /// The file.
        path: PathBuf,
        /// Why.
        source: crate::render::raster::RenderError,
    },
    /// A layered picture (PSD, ORA) that does not read.
    #[error("{}: {why}", .path.display())]
    Layered {
        /// The file.
        path: PathBuf,
        /// Why.
        why: String,
    },
    /// Outside the workspace (named by a project from the page).
    #[error("{} is outside the workspace {}: the studio reads a project's picture only inside its folder", .path.display(), .workspace.display())]
    Outside {
        /// The file.
        path: PathBuf,
        /// The workspace.
        workspace: PathBuf,
    },
}

impl From<TextureError> for String {
    fn from(e: TextureError) -> String {
        e.to_string()
    }
}

/// Reads a picture file as a texture named `name`: a regular file (links followed) of at most
/// [`MAX_PICTURE_BYTES`].
pub fn read_texture(path: &Path, name: &str) -> Result<Texture, TextureError> {
    let bytes = read_regular(path, MAX_PICTURE_BYTES)?;
    if crate::parts::layered_format(&bytes).is_some() {
        return layered_texture(path, name, &bytes);
    }
    let image = raster::decode_image(&bytes).map_err(|source| TextureError::Decode {
        path: path.to_path_buf(),
        source,
    })?;
    let content_type = if bytes.starts_with(b"\x89PNG") {
        "image/png"
    } else {
        "image/jpeg"
    };
    Ok(Texture {
        name: name.to_owned(),
        image,
        bytes,
        content_type,
    })
}

/// A layered picture's texture: its layers packed into one picture as
/// [`crate::parts::atlas`] packs them (the same file always gives the same atlas).
fn layered_texture(path: &Path, name: &str, bytes: &[u8]) -> Result<Texture, TextureError> {
    let layered = || -> Result<Image, String> {
        let layered = crate::parts::read_layered(bytes).map_err(|e| e.to_string())?;
        Ok(crate::parts::atlas(&layered.layers)
            .map_err(|e| e.to_string())?
            .0)
    };
    let image = layered().map_err(|why| TextureError::Layered {
        path: path.to_path_buf(),
        why,
    })?;
    let bytes = raster::encode_png(&image).map_err(|source| TextureError::Decode {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(Texture {
        name: name.to_owned(),
        image,
        bytes,
        content_type: "image/png",
    })
}

/// A document opened from a file.
#[derive(Debug)]
pub struct Opened {
    /// The document.
    pub project: Project,
    /// Its picture, if it has one that could be read.
    pub texture: Option<Arc<Texture>>,
    /// Where a plain save writes (a project file), if anywhere.
    pub project_file: Option<PathBuf>,
    /// What was said about it (a missing picture, specks dropped, the background taken).
    pub notes: Vec<String>,
}

/// Whether any pixel of `image` is less than opaque.
fn has_transparency(image: &Image) -> bool {
    image.rgba.chunks_exact(4).any(|p| p[3] < 255)
}

/// The settings a picture is meshed with: `given`, or for an opaque picture without settings
/// the border's colour as background (with a note).
pub fn picture_settings(
    image: &Image,
    given: &PictureSettings,
    notes: &mut Vec<String>,
    shown: &str,
) -> PictureSettings {
    if given.background.is_some() || given.threshold.is_some() || has_transparency(image) {
        return given.clone();
    }
    notes.push(format!(
        "{shown} has no transparency: its subject was told from the colour of its border (background auto); change it in Outline mode"
    ));
    PictureSettings {
        background: Some("auto".into()),
        threshold: None,
    }
}

/// Texture coordinates per vertex from per-corner ones (`corners` parallel to `faces`), when
/// every corner of each vertex has the same one (no seams); `None` otherwise.
pub fn per_vertex_uv(
    t: &crate::io::TexCoords,
    faces: &[[u32; 3]],
    n: usize,
) -> Option<Vec<[f64; 2]>> {
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

/// Texture coordinates that lay `image` over a mesh without its own: the picture's pixels when
/// the mesh lies within them (a mesh made in the picture's pixel frame, y up), else the mesh's
/// bounding box stretched over the picture. Also whether it was by pixels.
pub fn fitted_uv(positions: &[[f64; 2]], image: &Image) -> (Vec<[f64; 2]>, bool) {
    let (w, h) = (f64::from(image.width), f64::from(image.height));
    let inside = positions
        .iter()
        .all(|p| (0.0..=w).contains(&p[0]) && (0.0..=h).contains(&p[1]));
    let (lo, hi) = positions.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    );
    let uv = positions
        .iter()
        .map(|p| {
            if inside {
                [p[0] / w, p[1] / h]
            } else {
                [
                    (p[0] - lo[0]) / (hi[0] - lo[0]).max(f64::MIN_POSITIVE),
                    (p[1] - lo[1]) / (hi[1] - lo[1]).max(f64::MIN_POSITIVE),
                ]
            }
        })
        .collect();
    (uv, inside)
}

/// How to open a file.
#[derive(Clone, Debug, Default)]
pub struct OpenOptions {
    /// For a picture: how its subject is told from its background.
    pub picture: PictureSettings,
    /// For a mesh: the picture to draw on it (else the one of the same name beside it).
    pub texture: Option<PathBuf>,
    /// For a picture: keep specks (pieces far smaller than the subject).
    pub keep_specks: bool,
    /// For a project: its picture is read only when it lies inside the workspace (every link
    /// resolved). Set for files opened from the page; a file named on the command line is the
    /// user's own choice.
    pub pictures_inside: bool,
}

/// Reads the picture a document names, at `path`: only inside `workspace` when `inside_only`.
pub fn read_named_texture(
    path: &Path,
    name: &str,
    workspace: &Path,
    inside_only: bool,
) -> Result<Texture, TextureError> {
    if inside_only && path.exists() && !Workspace::new(workspace.to_path_buf()).contains(path) {
        return Err(TextureError::Outside {
            path: path.to_path_buf(),
            workspace: workspace.to_path_buf(),
        });
    }
    read_texture(path, name)
}

/// The name a file is kept under in a document: relative to `workspace` when inside it.
pub fn name_in(workspace: &Path, file: &Path) -> String {
    let absolute = std::fs::canonicalize(file).unwrap_or_else(|_| file.to_path_buf());
    match absolute.strip_prefix(workspace) {
        Ok(inside) => inside.display().to_string(),
        Err(_) => absolute.display().to_string(),
    }
}

/// Opens `file` (see the [module docs](self)); textures are named relative to `workspace`.
pub fn open(file: &Path, workspace: &Path, options: &OpenOptions) -> Result<Opened, String> {
    open_with(file, workspace, options, &crate::Budget::unlimited())
}

/// As [`open`], stopping with "cancelled" (or the deadline's message) once `budget` is spent:
/// it is checked between a layered picture's layers and while its character is made.
pub fn open_with(
    file: &Path,
    workspace: &Path,
    options: &OpenOptions,
    budget: &crate::Budget,
) -> Result<Opened, String> {
    let shown = file.display().to_string();
    let ext = file
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let mut notes = Vec::new();
    match ext.as_str() {
        "json" => {
            let mut project = Project::read(file).map_err(|e| format!("{shown}: {e}"))?;
            // Keyframes' drawings, named as the workspace names them (read when shown).
            let folder = file.parent().unwrap_or(Path::new("."));
            let mut missing = Vec::new();
            for (k, key) in project.keyframes.iter_mut().enumerate() {
                let Some(d) = key.drawing.as_mut() else {
                    continue;
                };
                let path = folder.join(&d.picture);
                if !path.is_file() {
                    missing.push(format!("keyframe {}'s ({})", k + 1, d.picture));
                }
                d.picture = name_in(workspace, &path);
            }
            if !missing.is_empty() {
                notes.push(format!(
                    "{shown}: the drawing of {} is not there: drawn with the rest picture until it is",
                    missing.join(", ")
                ));
            }
            let texture = match project.texture.clone() {
                Some(t) => {
                    let path = file.parent().unwrap_or(Path::new(".")).join(&t);
                    let name = name_in(workspace, &path);
                    match read_named_texture(&path, &name, workspace, options.pictures_inside) {
                        Ok(texture) => {
                            project.texture = Some(name);
                            Some(Arc::new(texture))
                        }
                        Err(e) => {
                            notes.push(format!(
                                "{shown} opened without its picture: {} could not be read ({e})",
                                path.display()
                            ));
                            None
                        }
                    }
                }
                None => None,
            };
            Ok(Opened {
                project,
                texture,
                project_file: Some(file.to_path_buf()),
                notes,
            })
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
            let picture = match &options.texture {
                Some(given) => Some(given.clone()),
                None => ["png", "jpg", "jpeg"]
                    .iter()
                    .map(|e| file.with_extension(e))
                    .find(|p| p.is_file()),
            };
            let mut texture = None;
            if let Some(path) = picture {
                let name = name_in(workspace, &path);
                match read_texture(&path, &name) {
                    Ok(t) => {
                        if project.mesh.texcoords.is_none() {
                            let (uv, by_pixels) = fitted_uv(&planar.positions, &t.image);
                            project.mesh.texcoords = Some(uv);
                            notes.push(format!(
                                "{shown} has no texture coordinates: {} is laid over it by {}",
                                path.display(),
                                if by_pixels {
                                    "its pixels (the mesh lies within them)"
                                } else {
                                    "the mesh's bounding box"
                                }
                            ));
                        }
                        project.texture = Some(name);
                        texture = Some(Arc::new(t));
                    }
                    Err(e) if options.texture.is_some() => return Err(e.to_string()),
                    Err(e) => notes.push(format!("the picture beside it was not used: {e}")),
                }
            }
            Ok(Opened {
                project,
                texture,
                project_file: None,
                notes,
            })
        }
        "png" | "jpg" | "jpeg" => {
            let name = name_in(workspace, file);
            let texture = read_texture(file, &name)?;
            let settings = picture_settings(&texture.image, &options.picture, &mut notes, &shown);
            let picture_options = settings
                .options()
                .map_err(|e| format!("{shown}: {e}"))?
                .with_keep_specks(options.keep_specks);
            let meshed = crate::meshing::mesh_picture(
                &texture.image,
                &picture_options,
                &crate::meshing::MeshOptions::default(),
            )
            .map_err(|e| format!("{shown}: {e}"))?;
            // The outline the mesh was made from, to edit in Outline mode.
            let traced = crate::meshing::picture_outline(
                &texture.image,
                &picture_options,
                meshed.stats.tolerance,
            )
            .map_err(|e| format!("{shown}: {e}"))?;
            if meshed.stats.dropped_specks > 0 {
                let k = meshed.stats.dropped_specks;
                notes.push(format!(
                    "{k} speck{} left out of {shown} (pieces under {}% of the largest piece's area); open it with --keep-specks to keep them",
                    if k == 1 { "" } else { "s" },
                    crate::meshing::SPECK_AREA_FRACTION * 100.0
                ));
            }
            let uv = per_vertex_uv(
                &meshed.texcoords,
                &meshed.mesh.faces,
                meshed.mesh.positions.len(),
            );
            let mut project = Project::new(&meshed.mesh, uv);
            project.texture = Some(name);
            project.picture = settings;
            project.outline = super::session::loops_of(&traced.outline);
            Ok(Opened {
                project,
                texture: Some(Arc::new(texture)),
                project_file: None,
                notes,
            })
        }
        "psd" | "ora" => {
            let name = name_in(workspace, file);
            let bytes = read_regular(file, MAX_PICTURE_BYTES).map_err(|e| e.to_string())?;
            let (project, texture, layered_notes) =
                layered_project_with(&bytes, name, budget).map_err(|e| format!("{shown}: {e}"))?;
            notes.extend(layered_notes);
            Ok(Opened {
                project,
                texture: Some(Arc::new(texture)),
                project_file: None,
                notes,
            })
        }
        _ => Err(format!(
            "{shown}: the studio opens a project (.json), a mesh (.obj, .off), a picture (.png, .jpg) or a layered picture (.psd, .ora)"
        )),
    }
}

/// A project of a character in parts from a layered picture's bytes (see [`crate::parts`]):
/// one part per visible layer, its texture the layers' atlas (named `name`, the layered file),
/// joints where the layers overlap. Also what was left out, in words.
///
/// # Errors
/// The layered picture's or the character's, in one line.
pub fn layered_project(
    bytes: &[u8],
    name: String,
) -> Result<(Project, Texture, Vec<String>), String> {
    layered_project_with(bytes, name, &crate::Budget::unlimited())
}

/// As [`layered_project`], stopping once `budget` is spent (between layers, and while the
/// character's parts and joints are made).
///
/// # Errors
/// As [`layered_project`]; "... stopped: cancelled" when the budget's flag is set.
pub fn layered_project_with(
    bytes: &[u8],
    name: String,
    budget: &crate::Budget,
) -> Result<(Project, Texture, Vec<String>), String> {
    let layered = crate::parts::read_layered_with(bytes, budget).map_err(|e| e.to_string())?;
    let c =
        crate::parts::character_with(&layered, &crate::parts::CharacterOptions::default(), budget)
            .map_err(|e| e.to_string())?;
    let mut project = Project::new(&c.mesh, Some(c.texcoords.clone()));
    project.texture = Some(name.clone());
    project.parts = Some(
        c.parts
            .iter()
            .map(|p| super::project::PartData {
                name: p.name.clone(),
                vertices: p.vertices,
                faces: p.faces,
                ..super::project::PartData::default()
            })
            .collect(),
    );
    if !c.joints.is_empty() {
        project.joints = Some(c.joints.iter().map(|j| j.vertices).collect());
    }
    let png = raster::encode_png(&c.atlas).map_err(|e| e.to_string())?;
    let mut notes = c.notes;
    notes.push(format!(
        "{} parts and {} joints from the layers",
        c.parts.len(),
        c.joints.len()
    ));
    Ok((
        project,
        Texture {
            name,
            image: c.atlas,
            bytes: png,
            content_type: "image/png",
        },
        notes,
    ))
}
