//! The studio's workspace: the folder it reads and writes (the opened file's, or the current
//! one), and its own state there, in `.bdmorph-studio/` (owner-only on Unix):
//!
//! - `token`: the page's secret, kept so that after a restart on the same workspace (and port)
//!   an open page reconnects by itself; `port`: the port last used, taken again when free.
//! - `autosave-PID.json`: the document of a running studio, written every few seconds while it
//!   has unsaved changes ([`AUTOSAVE_SECONDS`]) and when it stops, with the name of its project
//!   file; `autosave-PID.history` beside it: its undo history ([`super::recovery`]).
//! - `recovered/`: the autosaves of studios no longer running (stopped with unsaved changes,
//!   killed, crashed), moved there by the next start, which offers to restore them.
//!
//! The page names files by plain names only ([`Workspace::file`]): letters, digits, spaces,
//! `-`, `_` and `.`, not hidden, no folders. A name that is a symbolic link is followed only
//! when it resolves inside the workspace (a link leading out of it, or to nothing, is refused
//! with [`PathError`]); an export's frame folder must be a real folder of the workspace (not a
//! link), new or holding only frames of an earlier export ([`Workspace::frame_folder`]).
//!
//! Files are read through [`read_regular`]: regular files only (a pipe, device or folder is
//! refused before it is opened, and opened without blocking), of a bounded size.

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
    /// The root with every link resolved (what paths are checked against).
    canonical: PathBuf,
}

/// Why a name the page gave cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PathError {
    /// Not a plain file name.
    #[error("'{name}' is not a plain file name: the studio writes only into {}, by names of letters, digits, spaces, '-', '_' and '.'", .root.display())]
    NotPlain {
        /// The name.
        name: String,
        /// The workspace.
        root: PathBuf,
    },
    /// Not one of the endings wanted.
    #[error("'{name}' must end with {endings}")]
    Ending {
        /// The name.
        name: String,
        /// The endings wanted, said.
        endings: String,
    },
    /// A link that resolves outside the workspace.
    #[error("'{name}' is a link to {}, outside {}: the studio reads and writes only inside its folder", .target.display(), .root.display())]
    Outside {
        /// The name.
        name: String,
        /// Where it leads.
        target: PathBuf,
        /// The workspace.
        root: PathBuf,
    },
    /// A link to nothing.
    #[error("'{name}' is a link to nothing")]
    Dangling {
        /// The name.
        name: String,
    },
    /// A frame folder that is a link.
    #[error("'{name}' is a link: frames are exported only into a folder of the workspace's own")]
    LinkedFolder {
        /// The name.
        name: String,
    },
    /// A frame folder that exists as something else than a folder.
    #[error("'{name}' exists and is not a folder: frames are exported into a folder")]
    NotAFolder {
        /// The name.
        name: String,
    },
    /// A frame folder holding other things than frames (it would be replaced whole).
    #[error("'{name}' holds other files than exported frames ({found}): give a new folder name")]
    NotFrames {
        /// The name.
        name: String,
        /// The first other entry found.
        found: String,
    },
}

impl From<PathError> for String {
    fn from(e: PathError) -> String {
        e.to_string()
    }
}

/// Why a file could not be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReadError {
    /// Not a regular file (a folder, pipe, device or socket).
    #[error("{} is {kind}, not a file", .path.display())]
    NotAFile {
        /// The file.
        path: PathBuf,
        /// What it is.
        kind: &'static str,
    },
    /// Larger than the limit.
    #[error("{} is {} MiB; files of at most {} MiB are read", .path.display(), .bytes >> 20, .limit >> 20)]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size (at least; it may still grow).
        bytes: u64,
        /// The limit.
        limit: u64,
    },
    /// Reading failed.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

impl From<ReadError> for String {
    fn from(e: ReadError) -> String {
        e.to_string()
    }
}

/// What a file that is not a regular file is, in words.
fn kind_of_node(t: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a pipe (FIFO)";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() {
        "a folder"
    } else {
        "not a regular file"
    }
}

/// The bytes of `path` (links followed), which must be a regular file of at most `limit`
/// bytes. Its type and size are checked before it is opened, it is opened without blocking
/// (a pipe swapped in meanwhile does not hang), checked again once open, and read no further
/// than `limit` bytes.
pub fn read_regular(path: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    use std::io::Read;
    let io = |source| ReadError::Io {
        path: path.to_path_buf(),
        source,
    };
    let check = |meta: &std::fs::Metadata| {
        if !meta.is_file() {
            return Err(ReadError::NotAFile {
                path: path.to_path_buf(),
                kind: kind_of_node(&meta.file_type()),
            });
        }
        if meta.len() > limit {
            return Err(ReadError::TooLarge {
                path: path.to_path_buf(),
                bytes: meta.len(),
                limit,
            });
        }
        Ok(())
    };
    check(&std::fs::metadata(path).map_err(io)?)?;
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    check(&meta)?;
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(ReadError::TooLarge {
            path: path.to_path_buf(),
            bytes: bytes.len() as u64,
            limit,
        });
    }
    Ok(bytes)
}

/// How much of a `.json` file is read to tell whether it is a studio project.
pub const SNIFF_BYTES: u64 = 64 << 10;

/// Whether the file at `path` is a studio project: a regular file (opened without blocking)
/// whose first [`SNIFF_BYTES`] hold `"format": "bdmorph-studio"` (the first field the studio
/// writes). A sprite sheet's JSON, or any other program's, is not.
pub fn is_project_file(path: &Path) -> bool {
    use std::io::Read;
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let Ok(file) = options.open(path) else {
        return false;
    };
    if !file.metadata().is_ok_and(|m| m.is_file()) {
        return false;
    }
    let mut head = Vec::new();
    if file.take(SNIFF_BYTES).read_to_end(&mut head).is_err() {
        return false;
    }
    names_studio_format(&head)
}

/// Whether JSON text (perhaps cut short) has the key `"format"` with the value
/// `"bdmorph-studio"`.
fn names_studio_format(text: &[u8]) -> bool {
    let key = b"\"format\"";
    let value = super::project::FORMAT.as_bytes();
    let mut from = 0;
    while let Some(at) = text[from..].windows(key.len()).position(|w| w == key) {
        let mut rest = &text[from + at + key.len()..];
        let skip = |r: &mut &[u8]| {
            while let [b' ' | b'\t' | b'\n' | b'\r', tail @ ..] = *r {
                *r = tail;
            }
        };
        skip(&mut rest);
        if let [b':', tail @ ..] = rest {
            rest = tail;
            skip(&mut rest);
            if let [b'"', tail @ ..] = rest {
                if tail.starts_with(value) && tail.get(value.len()) == Some(&b'"') {
                    return true;
                }
            }
        }
        from += at + key.len();
    }
    false
}

/// Whether `name` is the name of a frame an OBJ export writes (`frame_0000.obj`, ...).
fn is_frame_name(name: &str, ending: &str) -> bool {
    name.strip_prefix("frame_")
        .and_then(|r| r.strip_suffix(ending))
        .is_some_and(|d| d.len() >= 4 && d.bytes().all(|b| b.is_ascii_digit()))
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
    /// The project file it saved to, if any (a name in the workspace).
    pub project: Option<String>,
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
    /// The project file a plain save wrote to (its name in the workspace).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    project_file: Option<String>,
    /// The generation of the undo history kept beside it, if one was.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    history: Option<u64>,
    project: Project,
}

/// What is written as a studio's autosave.
#[derive(Debug)]
pub struct AutosaveCopy {
    /// The document.
    pub project: Project,
    /// The file it was opened from.
    pub source: Option<String>,
    /// The project file a plain save writes to (its name in the workspace), if any.
    pub project_file: Option<String>,
    /// The session's version of the document.
    pub version: u64,
    /// The undo history's generation (that of the history kept beside it).
    pub generation: u64,
    /// The history, when it changed since it was last written.
    pub history: Option<super::history::Snapshot>,
}

/// Recovered work as it is restored.
#[derive(Debug)]
pub struct RecoveredWork {
    /// The document.
    pub project: Project,
    /// The file the studio that kept it had opened.
    pub source: Option<String>,
    /// The project file it saved to (a name in the workspace), if any.
    pub project_file: Option<String>,
    /// Its undo history, when one was kept with it and reads back.
    pub history: Option<super::history::Snapshot<super::edit::Edit>>,
    /// Why a history kept with it is not used, if one is not.
    pub history_note: Option<String>,
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
        "psd" | "ora" => "layered picture",
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
        let canonical = std::fs::canonicalize(&root).unwrap_or_else(|_| root.clone());
        Workspace { root, canonical }
    }

    /// Whether `path` (which must exist) resolves inside the workspace, every link followed.
    pub fn contains(&self, path: &Path) -> bool {
        std::fs::canonicalize(path).is_ok_and(|p| p.starts_with(&self.canonical))
    }

    /// Its folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    fn state_dir(&self) -> PathBuf {
        self.root.join(".bdmorph-studio")
    }

    /// The folder where the studio keeps its token, port and autosaves.
    pub fn state_folder(&self) -> PathBuf {
        self.state_dir()
    }

    /// A file of the workspace by a plain name with one of `endings` (any when empty).
    /// A name that is a link is taken only when it resolves inside the workspace.
    pub fn file(&self, name: &str, endings: &[&str]) -> Result<PathBuf, PathError> {
        if !is_plain(name) {
            return Err(PathError::NotPlain {
                name: name.to_owned(),
                root: self.root.clone(),
            });
        }
        let lower = name.to_ascii_lowercase();
        if !endings.is_empty() && !endings.iter().any(|e| lower.ends_with(e)) {
            return Err(PathError::Ending {
                name: name.to_owned(),
                endings: endings.join(" or "),
            });
        }
        let path = self.root.join(name);
        if std::fs::symlink_metadata(&path).is_ok_and(|m| m.file_type().is_symlink()) {
            let target = std::fs::canonicalize(&path).map_err(|_| PathError::Dangling {
                name: name.to_owned(),
            })?;
            if !target.starts_with(&self.canonical) {
                return Err(PathError::Outside {
                    name: name.to_owned(),
                    target,
                    root: self.root.clone(),
                });
            }
        }
        Ok(path)
    }

    /// A folder of the workspace for an export's frames (`ending`: `.png` or `.obj`), by a
    /// plain name: not a link, and new or holding only frames of that kind from an earlier
    /// export (replacing it, when the user asks, loses no other file).
    pub fn frame_folder(&self, name: &str, ending: &str) -> Result<PathBuf, PathError> {
        let path = self.file(name, &[])?;
        let Ok(meta) = std::fs::symlink_metadata(&path) else {
            return Ok(path);
        };
        let named = || name.to_owned();
        if meta.file_type().is_symlink() {
            return Err(PathError::LinkedFolder { name: named() });
        }
        if !meta.is_dir() {
            return Err(PathError::NotAFolder { name: named() });
        }
        let other = std::fs::read_dir(&path)
            .map_err(|e| PathError::NotFrames {
                name: named(),
                found: e.to_string(),
            })?
            .filter_map(Result::ok)
            .find(|e| {
                let frame = e.file_type().is_ok_and(|t| t.is_file())
                    && e.file_name()
                        .to_str()
                        .is_some_and(|n| is_frame_name(n, ending));
                !frame
            });
        match other {
            Some(e) => Err(PathError::NotFrames {
                name: named(),
                found: e.file_name().to_string_lossy().into_owned(),
            }),
            None => Ok(path),
        }
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
                // Links leading out of the workspace are not listed (nor opened).
                if !is_plain(&name) || self.file(&name, &[]).is_err() {
                    return None;
                }
                // Only studio projects among JSON files (not a sprite sheet's frames).
                if kind == "project" && !is_project_file(&e.path()) {
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

    /// Writes the autosave (atomically), without a history.
    pub fn autosave(&self, project: &Project, source: Option<&str>) -> Result<(), String> {
        self.write_autosave(project, source, None, None)
    }

    /// The undo history kept beside this studio's autosave.
    pub fn autosave_history_path(&self) -> PathBuf {
        self.state_dir()
            .join(format!("autosave-{}.history", std::process::id()))
    }

    /// Writes `copy` as the autosave: first its history when it has one (the history of
    /// generation `written` is already there), then the document naming the history's
    /// generation when that history is there. Both atomically.
    pub fn keep(&self, copy: &AutosaveCopy, written: Option<u64>) -> Result<Option<u64>, String> {
        private_dir(&self.state_dir()).map_err(|e| e.to_string())?;
        let mut kept =
            written.filter(|&g| g == copy.generation && self.autosave_history_path().is_file());
        let mut failed = None;
        if let Some(history) = &copy.history {
            match super::recovery::write(&self.autosave_history_path(), history) {
                Ok(()) => kept = Some(copy.generation),
                Err(e) => failed = Some(e.to_string()),
            }
        }
        self.write_autosave(
            &copy.project,
            copy.source.as_deref(),
            copy.project_file.as_deref(),
            kept,
        )?;
        match failed {
            Some(e) => Err(e),
            None => Ok(kept),
        }
    }

    fn write_autosave(
        &self,
        project: &Project,
        source: Option<&str>,
        project_file: Option<&str>,
        history: Option<u64>,
    ) -> Result<(), String> {
        private_dir(&self.state_dir()).map_err(|e| e.to_string())?;
        let body = Autosave {
            format: AUTOSAVE_FORMAT.into(),
            saved_at: now(),
            source: source.map(str::to_owned),
            project_file: project_file.map(str::to_owned),
            history,
            project: project.clone(),
        };
        let bytes = serde_json::to_vec(&body).map_err(|e| e.to_string())?;
        crate::io::write_bytes_atomic(self.autosave_path(), &bytes).map_err(|e| e.to_string())
    }

    /// Removes this studio's autosave and its history (the document is saved, or the studio
    /// stopped with nothing unsaved).
    pub fn clear_autosave(&self) {
        let _ = std::fs::remove_file(self.autosave_path());
        let _ = std::fs::remove_file(self.autosave_history_path());
    }

    /// The name of `path` when it is a file directly in the workspace.
    pub fn name_of(&self, path: &Path) -> Option<String> {
        let name = path.file_name()?.to_str()?;
        let parent = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        (is_plain(name) && std::fs::canonicalize(parent).ok()? == self.canonical)
            .then(|| name.to_owned())
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
            let stamp = now();
            let to = self
                .recovered_dir()
                .join(format!("recovered-{stamp}-{pid}.json"));
            // Its history first: recovered work is listed once its document is there.
            let history = self.state_dir().join(format!("autosave-{pid}.history"));
            if history.is_file() {
                let _ = std::fs::rename(
                    history,
                    self.recovered_dir()
                        .join(format!("recovered-{stamp}-{pid}.history")),
                );
            }
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
                    project: save.project_file,
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

    /// Recovered work as it is restored: its document, names and undo history.
    pub fn recovered_work(&self, name: &str) -> Result<RecoveredWork, String> {
        let (save, path) = self.read_recovered(name)?;
        let (history, history_note) = match save.history {
            None => (None, None),
            Some(generation) => match super::recovery::read(&path.with_extension("history")) {
                Ok(h) if h.generation == generation => (Some(h), None),
                Ok(_) => (
                    None,
                    Some("its undo history was of another moment (the studio stopped while writing it)".to_owned()),
                ),
                Err(e) => (None, Some(e.to_string())),
            },
        };
        Ok(RecoveredWork {
            project: save.project,
            source: save.source,
            project_file: save.project_file,
            history,
            history_note,
        })
    }

    /// Puts recovered work aside (into `recovered/discarded/`, not deleted), with its history.
    pub fn discard(&self, name: &str) -> Result<(), String> {
        let (_, path) = self.read_recovered(name)?;
        let aside = self.recovered_dir().join("discarded");
        private_dir(&aside).map_err(|e| e.to_string())?;
        let history = path.with_extension("history");
        if history.is_file() {
            let _ = std::fs::rename(
                &history,
                aside.join(Path::new(name).with_extension("history")),
            );
        }
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
            let path = match self.file(&candidate, &[]) {
                Ok(path) => path,
                // A link out of the workspace, or to nothing: another name.
                Err(PathError::Outside { .. } | PathError::Dangling { .. }) => continue,
                Err(e) => return Err(e.to_string()),
            };
            match std::fs::symlink_metadata(&path) {
                Err(_) => {
                    crate::io::write_bytes_atomic(&path, bytes)
                        .map_err(|e| format!("{candidate}: {e}"))?;
                    return Ok(candidate);
                }
                // The same file uploaded again (only a regular file of the same size is read).
                Ok(_) => {
                    let same = std::fs::metadata(&path)
                        .is_ok_and(|m| m.is_file() && m.len() == bytes.len() as u64)
                        && read_regular(&path, MAX_UPLOAD as u64).is_ok_and(|b| b == bytes);
                    if same {
                        return Ok(candidate);
                    }
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
    fn recovered_work_keeps_its_project_name_and_history() {
        use super::super::edit::Edit;
        use super::super::history::History;
        let ws = scratch("recover-history");
        let project = Project::new(&crate::generate::disk(3, 0.1), None);
        let mut history = History::default();
        history.push("frame rate 12", Edit::Fps(25.0));
        let copy = |history: &History, with: bool| AutosaveCopy {
            project: project.clone(),
            source: Some("a.png".into()),
            project_file: Some("walk.json".into()),
            version: 1,
            generation: history.generation(),
            history: with.then(|| history.snapshot(usize::MAX)),
        };
        let written = ws.keep(&copy(&history, true), None).expect("kept");
        assert_eq!(written, Some(history.generation()));
        // Kept again without the history (unchanged): it still goes with the document.
        assert_eq!(
            ws.keep(&copy(&history, false), written).expect("kept"),
            written
        );
        let dead = |ws: &Workspace| {
            let state = ws.root().join(".bdmorph-studio");
            std::fs::rename(ws.autosave_path(), state.join("autosave-4000000001.json"))
                .expect("rename");
            std::fs::rename(
                ws.autosave_history_path(),
                state.join("autosave-4000000001.history"),
            )
            .expect("rename");
            ws.collect_recoveries();
            ws.recovered()
        };
        let found = dead(&ws);
        assert_eq!(found[0].project.as_deref(), Some("walk.json"));
        let work = ws.recovered_work(&found[0].name).expect("reads");
        assert_eq!(work.project_file.as_deref(), Some("walk.json"));
        let kept = work.history.expect("its history");
        assert_eq!(kept.undo.len(), 1);
        assert_eq!(kept.undo[0].label, "frame rate 12");
        assert_eq!(kept.undo[0].edit, Edit::Fps(25.0));
        ws.discard(&found[0].name).expect("discards");
        // A history of another moment than the document is not used.
        ws.keep(&copy(&history, true), None).expect("kept");
        history.push("frame rate 30", Edit::Fps(12.0));
        super::super::recovery::write(&ws.autosave_history_path(), &history.snapshot(usize::MAX))
            .expect("written");
        let found = dead(&ws);
        let work = ws.recovered_work(&found[0].name).expect("reads");
        assert!(work.history.is_none());
        assert!(work.history_note.is_some());
    }

    #[test]
    fn only_studio_projects_are_listed_among_json_files() {
        let ws = scratch("sniff");
        let project = Project::new(&crate::generate::disk(3, 0.1), None);
        project
            .write(&ws.root().join("walk.json"))
            .expect("written");
        std::fs::write(
            ws.root().join("sheet.json"),
            br#"{"frames": [{"x": 0}], "meta": {"format": "RGBA8888"}}"#,
        )
        .expect("written");
        std::fs::write(
            ws.root().join("tricky.json"),
            br#"{"note": "\"format\": \"bdmorph-studio\" is", "format": "x"}"#,
        )
        .expect("written");
        std::fs::write(
            ws.root().join("spaced.json"),
            b"{\n  \"format\" :\t\"bdmorph-studio\" }",
        )
        .expect("written");
        let names: Vec<String> = ws.list().into_iter().map(|e| e.name).collect();
        assert_eq!(names, ["spaced.json", "walk.json"]);
        assert!(names_studio_format(
            br#"{"format":"bdmorph-studio","version":4"#
        ));
        assert!(!names_studio_format(
            br#"{"format":"bdmorph-studio-autosave"}"#
        ));
        assert!(!names_studio_format(br#"{"format":"bdmorph-studi"#));
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
