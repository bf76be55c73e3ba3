//! The studio's workspace: the folder it reads and writes (the opened file's, or the current
//! one), and its own state there, in `.bdmorph-studio/` (owner-only on Unix):
//!
//! - `token`: the page's secret, kept so that after a restart on the same workspace (and port)
//!   an open page reconnects by itself; `port`: the port last used, taken again when free.
//! - `autosave-PID.json`: the document of a running studio, written every few seconds while it
//!   has unsaved changes ([`AUTOSAVE_SECONDS`]) and when it stops.
//! - `recovered/`: the autosaves of studios no longer running (stopped with unsaved changes,
//!   killed, crashed), moved there by the next start, which offers to restore them.
//!
//! The page names files by plain names only ([`Workspace::file`]): letters, digits, spaces,
//! `-`, `_` and `.`, not hidden, no folders.

use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};

use super::guard::Token;
use super::project::Project;

/// Seconds between autosaves of a document with unsaved changes.
pub const AUTOSAVE_SECONDS: u64 = 2;

/// The largest file the page may upload (64 MiB).
pub const MAX_UPLOAD: usize = 64 << 20;

/// The folder and its studio state.
#[derive(Clone, Debug)]
pub struct Workspace {
    root: PathBuf,
}

/// A file the studio can open, as listed to the page.
#[derive(Clone, Debug, Serialize)]
pub struct Entry {
    /// Its plain name.
    pub name: String,
    /// `picture`, `mesh`, `outline` or `project`.
    pub kind: &'static str,
    /// Its size in bytes.
    pub bytes: u64,
    /// When it was last changed (seconds since 1970).
    pub modified: u64,
}

/// Unsaved work of a studio no longer running.
#[derive(Clone, Debug, Serialize)]
pub struct Recovered {
    /// The recovery file's name (in `.bdmorph-studio/recovered/`).
    pub name: String,
    /// When it was written (seconds since 1970).
    pub saved_at: u64,
    /// The file that studio had opened, if any.
    pub source: Option<String>,
    /// Its keyframes.
    pub keyframes: usize,
    /// Its vertices.
    pub vertices: usize,
}

/// An autosave file's contents.
#[derive(Serialize, Deserialize)]
struct Autosave {
    format: String,
    saved_at: u64,
    source: Option<String>,
    project: Project,
}

const AUTOSAVE_FORMAT: &str = "bdmorph-studio-autosave";

fn now() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}

/// The kind of file a name is, by its extension.
pub fn kind_of(name: &str) -> Option<&'static str> {
    let lower = name.to_ascii_lowercase();
    let ext = lower.rsplit_once('.').map(|(_, e)| e)?;
    Some(match ext {
        "png" | "jpg" | "jpeg" => "picture",
        "obj" | "off" => "mesh",
        "svg" | "poly" => "outline",
        "json" => "project",
        _ => return None,
    })
}

/// Whether `name` is a plain file name: letters, digits, spaces, `-`, `_`, `.`; not hidden.
pub fn is_plain(name: &str) -> bool {
    !name.is_empty()
        && name.len() <= 200
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | '.' | ' '))
}

#[cfg(unix)]
fn private_dir(path: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::{DirBuilderExt, PermissionsExt};
    if !path.is_dir() {
        std::fs::DirBuilder::new()
            .recursive(true)
            .mode(0o700)
            .create(path)?;
    }
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o700))
}

#[cfg(not(unix))]
fn private_dir(path: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(path)
}

#[cfg(unix)]
fn write_private(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    use std::os::unix::fs::{OpenOptionsExt, PermissionsExt};
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .mode(0o600)
        .open(path)?;
    file.set_permissions(std::fs::Permissions::from_mode(0o600))?;
    file.write_all(bytes)
}

#[cfg(not(unix))]
fn write_private(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    std::fs::write(path, bytes)
}

/// Whether process `pid` runs (on Linux, by `/proc`; elsewhere unknown: `false`).
fn running(pid: u32) -> bool {
    pid == std::process::id() || Path::new(&format!("/proc/{pid}")).exists()
}

impl Workspace {
    /// The workspace at `root`.
    pub fn new(root: PathBuf) -> Workspace {
        Workspace { root }
    }

    /// Its folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    fn state_dir(&self) -> PathBuf {
        self.root.join(".bdmorph-studio")
    }

    /// A file of the workspace by a plain name with one of `endings` (any when empty).
    pub fn file(&self, name: &str, endings: &[&str]) -> Result<PathBuf, String> {
        if !is_plain(name) {
            return Err(format!(
                "'{name}' is not a plain file name: the studio writes only into {}, by names of letters, digits, spaces, '-', '_' and '.'",
                self.root.display()
            ));
        }
        let lower = name.to_ascii_lowercase();
        if !endings.is_empty() && !endings.iter().any(|e| lower.ends_with(e)) {
            return Err(format!("'{name}' must end with {}", endings.join(" or ")));
        }
        Ok(self.root.join(name))
    }

    /// The files the studio can open, by name.
    pub fn list(&self) -> Vec<Entry> {
        let Ok(dir) = std::fs::read_dir(&self.root) else {
            return Vec::new();
        };
        let mut entries: Vec<Entry> = dir
            .filter_map(Result::ok)
            .filter_map(|e| {
                let name = e.file_name().into_string().ok()?;
                let kind = kind_of(&name)?;
                let meta = e.metadata().ok().filter(std::fs::Metadata::is_file)?;
                if !is_plain(&name) {
                    return None;
                }
                let modified = meta
                    .modified()
                    .ok()
                    .and_then(|m| m.duration_since(UNIX_EPOCH).ok())
                    .map_or(0, |d| d.as_secs());
                Some(Entry {
                    name,
                    kind,
                    bytes: meta.len(),
                    modified,
                })
            })
            .collect();
        entries.sort_by(|a, b| a.name.cmp(&b.name));
        entries
    }

    /// The page's token: the one kept in the workspace, or a new one (kept, owner-only).
    /// When the workspace cannot keep it, a new one for this run and why.
    pub fn token(&self) -> Result<(Token, Option<String>), getrandom::Error> {
        let path = self.state_dir().join("token");
        if let Some(token) = std::fs::read_to_string(&path)
            .ok()
            .and_then(|t| Token::from_hex(t.trim()))
        {
            return Ok((token, None));
        }
        let token = Token::random()?;
        let kept = private_dir(&self.state_dir())
            .and_then(|()| write_private(&path, token.as_str().as_bytes()));
        let note = kept.err().map(|e| {
            format!(
                "the token is not kept in {} ({e}): after a restart, open the new URL",
                path.display()
            )
        });
        Ok((token, note))
    }

    /// The port the last studio in this workspace listened on.
    pub fn last_port(&self) -> Option<u16> {
        std::fs::read_to_string(self.state_dir().join("port"))
            .ok()?
            .trim()
            .parse()
            .ok()
            .filter(|&p| p != 0)
    }

    /// Remembers the port (for the next start).
    pub fn remember_port(&self, port: u16) {
        let _ = private_dir(&self.state_dir()).and_then(|()| {
            write_private(&self.state_dir().join("port"), port.to_string().as_bytes())
        });
    }

    /// This studio's autosave file.
    pub fn autosave_path(&self) -> PathBuf {
        self.state_dir()
            .join(format!("autosave-{}.json", std::process::id()))
    }

    /// Writes the autosave (atomically).
    pub fn autosave(&self, project: &Project, source: Option<&str>) -> Result<(), String> {
        private_dir(&self.state_dir()).map_err(|e| e.to_string())?;
        let body = Autosave {
            format: AUTOSAVE_FORMAT.into(),
            saved_at: now(),
            source: source.map(str::to_owned),
            project: project.clone(),
        };
        let bytes = serde_json::to_vec(&body).map_err(|e| e.to_string())?;
        crate::io::write_bytes_atomic(&self.autosave_path(), &bytes).map_err(|e| e.to_string())
    }

    /// Removes this studio's autosave (the document is saved, or the studio stopped with
    /// nothing unsaved).
    pub fn clear_autosave(&self) {
        let _ = std::fs::remove_file(self.autosave_path());
    }

    fn recovered_dir(&self) -> PathBuf {
        self.state_dir().join("recovered")
    }

    /// Moves the autosaves of studios no longer running to `recovered/` (at start).
    pub fn collect_recoveries(&self) {
        let Ok(dir) = std::fs::read_dir(self.state_dir()) else {
            return;
        };
        for entry in dir.filter_map(Result::ok) {
            let name = entry.file_name().to_string_lossy().into_owned();
            let Some(pid) = name
                .strip_prefix("autosave-")
                .and_then(|r| r.strip_suffix(".json"))
                .and_then(|p| p.parse::<u32>().ok())
            else {
                continue;
            };
            if running(pid) {
                continue;
            }
            if private_dir(&self.recovered_dir()).is_err() {
                return;
            }
            let to = self
                .recovered_dir()
                .join(format!("recovered-{}-{pid}.json", now()));
            let _ = std::fs::rename(entry.path(), to);
        }
    }

    /// Recovered work waiting to be restored or put aside, newest first.
    pub fn recovered(&self) -> Vec<Recovered> {
        let Ok(dir) = std::fs::read_dir(self.recovered_dir()) else {
            return Vec::new();
        };
        let mut found: Vec<Recovered> = dir
            .filter_map(Result::ok)
            .filter_map(|e| {
                let name = e.file_name().into_string().ok()?;
                if !name.starts_with("recovered-") || !name.ends_with(".json") {
                    return None;
                }
                let (save, _) = self.read_recovered(&name).ok()?;
                Some(Recovered {
                    name,
                    saved_at: save.saved_at,
                    source: save.source,
                    keyframes: save.project.keyframes.len(),
                    vertices: save.project.mesh.positions.len(),
                })
            })
            .collect();
        found.sort_by(|a, b| b.saved_at.cmp(&a.saved_at).then(b.name.cmp(&a.name)));
        found
    }

    fn read_recovered(&self, name: &str) -> Result<(Autosave, PathBuf), String> {
        if !is_plain(name) || !name.starts_with("recovered-") {
            return Err(format!("'{name}' is not recovered work"));
        }
        let path = self.recovered_dir().join(name);
        let bytes = std::fs::read(&path).map_err(|e| format!("{name}: {e}"))?;
        let save: Autosave =
            serde_json::from_slice(&bytes).map_err(|e| format!("{name}: damaged ({e})"))?;
        if save.format != AUTOSAVE_FORMAT {
            return Err(format!("{name}: not a studio autosave"));
        }
        save.project.check().map_err(|e| format!("{name}: {e}"))?;
        Ok((save, path))
    }

    /// The project of recovered work, and the file it was opened from.
    pub fn recovered_project(&self, name: &str) -> Result<(Project, Option<String>), String> {
        let (save, _) = self.read_recovered(name)?;
        Ok((save.project, save.source))
    }

    /// Puts recovered work aside (into `recovered/discarded/`, not deleted).
    pub fn discard(&self, name: &str) -> Result<(), String> {
        let (_, path) = self.read_recovered(name)?;
        let aside = self.recovered_dir().join("discarded");
        private_dir(&aside).map_err(|e| e.to_string())?;
        std::fs::rename(&path, aside.join(name)).map_err(|e| format!("{name}: {e}"))
    }

    /// Stores an uploaded file under a plain name made from `name` (a number added when a
    /// different file has that name); returns the name used.
    pub fn store(&self, name: &str, bytes: &[u8]) -> Result<String, String> {
        if bytes.len() > MAX_UPLOAD {
            return Err(format!(
                "{name}: {} MB; files of at most {} MB are taken",
                bytes.len() >> 20,
                MAX_UPLOAD >> 20
            ));
        }
        let base = Path::new(name)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let mut plain: String = base
            .chars()
            .map(|c| {
                if c.is_alphanumeric() || matches!(c, '-' | '_' | '.' | ' ') {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        plain = plain.trim_start_matches('.').chars().take(120).collect();
        if kind_of(&plain).is_none() {
            return Err(format!(
                "{name}: the studio opens pictures (.png, .jpg), meshes (.obj, .off), outlines (.svg, .poly) and projects (.json)"
            ));
        }
        let (stem, ext) = plain.rsplit_once('.').unwrap_or((&plain, ""));
        let (stem, ext) = (stem.to_owned(), ext.to_owned());
        for k in 0..1000 {
            let candidate = if k == 0 {
                plain.clone()
            } else {
                format!("{stem}-{k}.{ext}")
            };
            let path = self.file(&candidate, &[])?;
            match std::fs::read(&path) {
                Ok(existing) if existing == bytes => return Ok(candidate),
                Ok(_) => continue,
                Err(_) if path.exists() => continue,
                Err(_) => {
                    crate::io::write_bytes_atomic(&path, bytes)
                        .map_err(|e| format!("{candidate}: {e}"))?;
                    return Ok(candidate);
                }
            }
        }
        Err(format!("{name}: too many files of that name"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> Workspace {
        let dir = std::env::temp_dir().join(format!("bdmorph-ws-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("dir");
        Workspace::new(dir)
    }

    #[test]
    fn the_token_is_kept_owner_only_and_read_back() {
        let ws = scratch("token");
        let (a, note) = ws.token().expect("token");
        assert!(note.is_none(), "{note:?}");
        let (b, _) = ws.token().expect("token");
        assert_eq!(a, b);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode =
                |p: PathBuf| std::fs::metadata(p).expect("meta").permissions().mode() & 0o777;
            assert_eq!(mode(ws.root().join(".bdmorph-studio/token")), 0o600);
            assert_eq!(mode(ws.root().join(".bdmorph-studio")), 0o700);
        }
        ws.remember_port(8123);
        assert_eq!(ws.last_port(), Some(8123));
    }

    #[test]
    fn stale_autosaves_become_recovered_work() {
        let ws = scratch("recover");
        let project = Project::new(&crate::generate::disk(3, 0.1), None);
        ws.autosave(&project, Some("a.png")).expect("autosave");
        // As if another, dead process had written it.
        let dead = ws.root().join(".bdmorph-studio/autosave-4000000000.json");
        std::fs::rename(ws.autosave_path(), &dead).expect("rename");
        ws.collect_recoveries();
        assert!(!dead.exists());
        let found = ws.recovered();
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].source.as_deref(), Some("a.png"));
        let (back, _) = ws.recovered_project(&found[0].name).expect("reads");
        assert_eq!(back, project);
        ws.discard(&found[0].name).expect("discards");
        assert!(ws.recovered().is_empty());
        assert!(ws.recovered_project("../token").is_err());
    }

    #[test]
    fn uploads_get_plain_unused_names() {
        let ws = scratch("store");
        assert_eq!(ws.store("pic.png", b"one").expect("stored"), "pic.png");
        assert_eq!(ws.store("pic.png", b"one").expect("same"), "pic.png");
        assert_eq!(ws.store("pic.png", b"two").expect("other"), "pic-1.png");
        assert_eq!(
            ws.store("../x/.evil name!.obj", b"m").expect("plain"),
            "evil name_.obj"
        );
        assert!(ws.store("notes.txt", b"t").is_err());
        assert!(ws.file("../a.json", &[".json"]).is_err());
        assert!(ws.file("a.json", &[".gif"]).is_err());
    }
}
