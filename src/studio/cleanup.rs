//! Temporary files left by interrupted writes, removed when the studio starts.
//!
//! Saves write `.NAME.tmp-PID-N` beside their file and exports `.NAME.part-PID` (a file, or a
//! folder of frames) before renaming them into place; a studio killed meanwhile leaves them.
//! At start the studio removes, in its workspace and its state folder (not in subfolders),
//! only entries of exactly those patterns that are older than its own start and whose process
//! is gone: regular files, and `.part-` folders holding nothing but frame files
//! (`frame_NNNN.png`, `frame_NNNN.obj`). Nothing else is touched.

use std::path::Path;
use std::time::SystemTime;

/// What was removed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cleaned {
    /// Files removed (frames in a removed folder included).
    pub files: usize,
    /// Their bytes.
    pub bytes: u64,
}

/// The process id in a temporary name of ours, `None` for any other name.
pub fn temporary_pid(name: &str) -> Option<u32> {
    let rest = name.strip_prefix('.')?;
    if let Some(at) = rest.rfind(".tmp-") {
        let (pid, n) = rest[at + 5..].split_once('-')?;
        let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
        return (at > 0 && digits(pid) && digits(n))
            .then(|| pid.parse().ok())
            .flatten();
    }
    let at = rest.rfind(".part-")?;
    let pid = &rest[at + 6..];
    (at > 0 && !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()))
        .then(|| pid.parse().ok())
        .flatten()
}

fn is_frame_file(name: &str) -> bool {
    name.strip_prefix("frame_")
        .and_then(|r| r.strip_suffix(".png").or_else(|| r.strip_suffix(".obj")))
        .is_some_and(|d| d.len() >= 4 && d.bytes().all(|b| b.is_ascii_digit()))
}

/// Whether process `pid` is running (and is not this one); on systems without `/proc`,
/// whether it is any other process is not known, and it is taken as running unless it is
/// this one.
fn other_process_running(pid: u32) -> bool {
    if pid == std::process::id() {
        return false;
    }
    let proc = Path::new("/proc");
    if proc.is_dir() {
        proc.join(pid.to_string()).exists()
    } else {
        true
    }
}

/// Removes the temporary entries of ours in `dir` older than `started` (see the module).
pub fn remove_stale_temporaries(dir: &Path, started: SystemTime) -> Cleaned {
    let mut cleaned = Cleaned::default();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return cleaned;
    };
    for entry in entries.filter_map(Result::ok) {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temporary_pid) else {
            continue;
        };
        let Ok(meta) = std::fs::symlink_metadata(entry.path()) else {
            continue;
        };
        let old = meta.modified().is_ok_and(|m| m < started);
        if !old || other_process_running(pid) {
            continue;
        }
        if meta.file_type().is_file() {
            if std::fs::remove_file(entry.path()).is_ok() {
                cleaned.files += 1;
                cleaned.bytes += meta.len();
            }
        } else if meta.file_type().is_dir() && name.to_str().is_some_and(|n| n.contains(".part-")) {
            remove_frame_folder(&entry.path(), &mut cleaned);
        }
    }
    cleaned
}

/// Removes a folder of frames, only if it holds nothing but frame files.
fn remove_frame_folder(dir: &Path, cleaned: &mut Cleaned) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut frames = Vec::new();
    for entry in entries {
        let Ok(entry) = entry else { return };
        let frame = entry.file_type().is_ok_and(|t| t.is_file())
            && entry.file_name().to_str().is_some_and(is_frame_file);
        if !frame {
            return;
        }
        frames.push(entry.path());
    }
    for frame in frames {
        let size = std::fs::symlink_metadata(&frame).map_or(0, |m| m.len());
        if std::fs::remove_file(&frame).is_ok() {
            cleaned.files += 1;
            cleaned.bytes += size;
        }
    }
    let _ = std::fs::remove_dir(dir);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_our_temporary_names_are_recognised() {
        assert_eq!(temporary_pid(".anim.json.tmp-123-4"), Some(123));
        assert_eq!(temporary_pid(".anim.gif.part-77"), Some(77));
        for other in [
            "anim.json.tmp-123-4",
            ".tmp-1-2",
            ".anim.json.tmp-12x-4",
            ".anim.json.tmp-123",
            ".anim.part-",
            ".anim.part-1a",
            ".bashrc",
            "notes.txt",
        ] {
            assert_eq!(temporary_pid(other), None, "{other}");
        }
    }
}
