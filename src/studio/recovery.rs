//! The undo history kept beside the autosave, so that work restored after a crash or a
//! `kill -9` can still be undone step by step.
//!
//! The file (`autosave-PID.history` in the studio's folder, moved to `recovered/` with its
//! autosave) is JSON: the history's generation, its states' numbers and each step's label and
//! edit ([`super::edit::Edit`]). It is written atomically on the autosave's schedule, off the
//! session's lock, only when the history changed; the autosave names the generation of the
//! history that goes with its document, and a history of another generation (the studio was
//! stopped between the two writes) is not used. At most [`HISTORY_FILE_BYTES`] of edits are
//! written (the newest steps; older ones are left out, as the history itself drops its oldest
//! past its memory limit), and files larger than [`MAX_HISTORY_FILE`] are not read.
//!
//! An edit read back is checked as every edit is when it is applied: a damaged step is
//! refused when undone, and changes nothing.

use std::path::Path;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::edit::Edit;
use super::history::{Snapshot, SnapshotStep};
use super::workspace::{read_regular, ReadError};

/// The most bytes of edits (as the history counts them) written beside an autosave: 64 MiB,
/// a quarter of the history's own limit ([`super::history::HISTORY_BYTES`]).
pub const HISTORY_FILE_BYTES: usize = 64 << 20;

/// The largest history file read back (its edits as JSON text take about 2.5 times their
/// memory).
pub const MAX_HISTORY_FILE: u64 = 4 * HISTORY_FILE_BYTES as u64;

const FORMAT: &str = "bdmorph-studio-history";

/// Why a kept history could not be written or read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum HistoryFileError {
    /// Not there, not a regular file, too large or unreadable.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// Not a kept history, or damaged.
    #[error("{path}: not a studio history ({why})")]
    Damaged {
        /// The file.
        path: String,
        /// Why.
        why: String,
    },
    /// It could not be written.
    #[error("the undo history could not be kept: {0}")]
    Write(String),
}

#[derive(Serialize)]
struct StepOut<'a> {
    label: &'a str,
    id: u64,
    edit: &'a Edit,
}

#[derive(Serialize)]
struct FileOut<'a> {
    format: &'static str,
    generation: u64,
    base: u64,
    saved: Option<u64>,
    dropped: usize,
    undo: Vec<StepOut<'a>>,
    redo: Vec<StepOut<'a>>,
}

#[derive(Deserialize)]
struct StepIn {
    label: String,
    id: u64,
    edit: Edit,
}

#[derive(Deserialize)]
struct FileIn {
    format: String,
    generation: u64,
    base: u64,
    saved: Option<u64>,
    dropped: usize,
    undo: Vec<StepIn>,
    redo: Vec<StepIn>,
}

fn steps_out(steps: &[SnapshotStep<Arc<Edit>>]) -> Vec<StepOut<'_>> {
    steps
        .iter()
        .map(|s| StepOut {
            label: &s.label,
            id: s.id,
            edit: &s.edit,
        })
        .collect()
}

/// Writes `snapshot` to `path` (atomically: a reader finds the old file or the new one).
pub fn write(path: &Path, snapshot: &Snapshot) -> Result<(), HistoryFileError> {
    let out = FileOut {
        format: FORMAT,
        generation: snapshot.generation,
        base: snapshot.base,
        saved: snapshot.saved,
        dropped: snapshot.dropped,
        undo: steps_out(&snapshot.undo),
        redo: steps_out(&snapshot.redo),
    };
    let bytes = serde_json::to_vec(&out).map_err(|e| HistoryFileError::Write(e.to_string()))?;
    crate::io::write_bytes_atomic(path, &bytes).map_err(|e| HistoryFileError::Write(e.to_string()))
}

/// Reads a history written by [`write()`].
pub fn read(path: &Path) -> Result<Snapshot<Edit>, HistoryFileError> {
    let bytes = read_regular(path, MAX_HISTORY_FILE)?;
    let damaged = |why: String| HistoryFileError::Damaged {
        path: path.display().to_string(),
        why,
    };
    let file: FileIn = serde_json::from_slice(&bytes).map_err(|e| damaged(e.to_string()))?;
    if file.format != FORMAT {
        return Err(damaged(format!("format \"{}\"", file.format)));
    }
    let steps = |s: Vec<StepIn>| -> Vec<SnapshotStep<Edit>> {
        s.into_iter()
            .map(|s| SnapshotStep {
                label: s.label,
                id: s.id,
                edit: s.edit,
            })
            .collect()
    };
    Ok(Snapshot {
        generation: file.generation,
        base: file.base,
        saved: file.saved,
        dropped: file.dropped,
        undo: steps(file.undo),
        redo: steps(file.redo),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::studio::history::History;

    #[test]
    fn a_history_is_written_and_read_back_within_its_bound() {
        let mut h = History::default();
        h.push("fps", Edit::Fps(12.0));
        h.push(
            "drag",
            Edit::Pose {
                keyframe: 0,
                positions: vec![[1.5, -2.25]; 100],
            },
        );
        h.push(
            "time",
            Edit::Time {
                keyframe: 1,
                time: 0.5,
            },
        );
        let step = h.take_undo().expect("time");
        h.undone(
            step,
            Edit::Time {
                keyframe: 1,
                time: 2.0,
            },
        );
        let dir = std::env::temp_dir().join(format!("bdmorph-history-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("h.history");
        write(&path, &h.snapshot(usize::MAX)).expect("written");
        let back = read(&path).expect("read");
        assert_eq!(back.generation, h.generation());
        let labels: Vec<&str> = back.undo.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(labels, ["fps", "drag"]);
        assert_eq!(back.redo.len(), 1);
        assert_eq!(back.undo[1].edit, *h.last_undo().expect("drag").edit);
        // Within a bound of one small step: only the newest fits... not the drag, so nothing
        // older than it either.
        let small = h.snapshot(200);
        assert!(small.undo.is_empty());
        assert_eq!(small.dropped, 2);
        // Damaged or foreign files are said so.
        std::fs::write(&path, b"{\"format\": \"other\"}").expect("write");
        assert!(read(&path).is_err());
        std::fs::write(&path, b"not json").expect("write");
        assert!(matches!(read(&path), Err(HistoryFileError::Damaged { .. })));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
