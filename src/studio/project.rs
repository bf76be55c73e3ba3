//! The studio's project file: one JSON document, versioned, with everything an animation
//! needs: the rest mesh (positions, triangles, texture coordinates), the texture's file (by a
//! path relative to the project file), the posing method, and the keyframes (each a pose, its
//! time in seconds, the easing of the segment that starts there, and its handles).
//!
//! ```json
//! {
//!   "format": "bdmorph-studio",
//!   "version": 1,
//!   "mesh": { "positions": [[0, 0], [1, 0], [0, 1]], "faces": [[0, 1, 2]], "texcoords": null },
//!   "texture": null,
//!   "method": { "name": "kvf", "weight": 100, "max_distortion": 3 },
//!   "fps": 25,
//!   "keyframes": [
//!     { "time": 0, "easing": "linear", "positions": [[0, 0], [1, 0], [0, 1]], "pins": [] }
//!   ]
//! }
//! ```
//!
//! A file is refused whole, with the reason, when it is not JSON, is another program's or
//! another version's, or is damaged (a pose with the wrong number of points, a triangle naming
//! a missing vertex, times out of order, an unknown easing, a pin out of range, ...).

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::mesh::PlanarMesh;

/// The `format` field of every project file.
pub const FORMAT: &str = "bdmorph-studio";
/// The version this studio writes and reads.
pub const VERSION: u32 = 1;

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
    /// The keyframes, in time order; the first is at time 0.
    pub keyframes: Vec<Keyframe>,
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
    /// `kvf`, `arap` or `bounded`.
    pub name: String,
    /// KVF's handle weight.
    pub weight: f64,
    /// The bounded method's bound `K`.
    pub max_distortion: f64,
}

impl Default for MethodData {
    fn default() -> Self {
        MethodData {
            name: "kvf".into(),
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
            keyframes: vec![Keyframe {
                time: 0.0,
                easing: "linear".into(),
                positions: mesh.positions.clone(),
                pins: Vec::new(),
            }],
        }
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
            Some(VERSION) => {}
            found => {
                return Err(ProjectError::Version {
                    found: found.unwrap_or(0),
                })
            }
        }
        let project: Project = serde_json::from_slice(bytes)?;
        project.check()?;
        Ok(project)
    }

    /// Reads and checks a project file.
    pub fn read(path: &Path) -> Result<Project, ProjectError> {
        Project::from_json(&std::fs::read(path)?)
    }

    /// The project as JSON.
    pub fn to_json(&self) -> Vec<u8> {
        // Serialising plain numbers, strings and vectors cannot fail.
        serde_json::to_vec_pretty(self).unwrap_or_default()
    }

    /// Writes the project atomically (a temporary file renamed over the target).
    pub fn write(&self, path: &Path) -> Result<(), ProjectError> {
        crate::io::write_bytes_atomic(path, &self.to_json())?;
        Ok(())
    }

    /// Checks everything a damaged file could get wrong.
    pub fn check(&self) -> Result<(), ProjectError> {
        let damaged = |why: String| Err(ProjectError::Damaged(why));
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
        if !["kvf", "arap", "bounded"].contains(&self.method.name.as_str()) {
            return damaged(format!("unknown method \"{}\"", self.method.name));
        }
        if !(self.method.weight > 0.0 && self.method.weight.is_finite()) {
            return damaged(format!("KVF weight {}", self.method.weight));
        }
        if !(self.method.max_distortion >= 1.0 && self.method.max_distortion.is_finite()) {
            return damaged(format!("distortion bound {}", self.method.max_distortion));
        }
        if !(self.fps > 0.0 && self.fps <= 240.0) {
            return damaged(format!("frame rate {}", self.fps));
        }
        if self.keyframes.is_empty() {
            return damaged("no keyframes".into());
        }
        let mut last = f64::NEG_INFINITY;
        for (k, key) in self.keyframes.iter().enumerate() {
            if key.positions.len() != n {
                return damaged(format!(
                    "keyframe {k} has {} points for {n} vertices",
                    key.positions.len()
                ));
            }
            if key.positions.iter().flatten().any(|c| !c.is_finite()) {
                return damaged(format!("keyframe {k} has a point that is not finite"));
            }
            if !(key.time.is_finite() && key.time > last) || (k == 0 && key.time != 0.0) {
                return damaged(format!(
                    "keyframe {k} at time {}: times start at 0 and increase",
                    key.time
                ));
            }
            last = key.time;
            if let Err(e) = key.easing.parse::<crate::Easing>() {
                return damaged(format!("keyframe {k}: {e}"));
            }
            if let Some(&v) = key.pins.iter().find(|&&v| v as usize >= n) {
                return damaged(format!("keyframe {k} pins vertex {v} of {n}"));
            }
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
        });
        let back = Project::from_json(&project.to_json()).expect("reads back");
        assert_eq!(back, project);

        let text = String::from_utf8(project.to_json()).expect("utf8");
        let broken = |from: &str, to: &str| {
            Project::from_json(text.replacen(from, to, 1).as_bytes())
                .expect_err("refused")
                .to_string()
        };
        assert!(broken("\"version\": 1", "\"version\": 2").contains("another version"));
        assert!(broken("bdmorph-studio", "something-else").contains("not a bdmorph studio"));
        assert!(broken("\"time\": 1.5", "\"time\": 0.0").contains("times start at 0"));
        assert!(broken("ease-in-out", "bouncy").contains("keyframe 1"));
        assert!(broken("\"name\": \"kvf\"", "\"name\": \"magic\"").contains("unknown method"));
        assert!(Project::from_json(b"{ not json").is_err());
        assert!(Project::from_json(&project.to_json()[..100]).is_err());
        let mut short = project.clone();
        short.keyframes[1].positions.pop();
        let e = Project::from_json(&short.to_json()).expect_err("refused");
        assert!(e.to_string().contains("keyframe 1 has"), "{e}");
        let mut pinned = project.clone();
        pinned.keyframes[1].pins.push(10_000);
        assert!(Project::from_json(&pinned.to_json()).is_err());
    }
}
