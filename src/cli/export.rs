//! `bdmorph export PROJECT.json -o OUT`: a studio project's animation, exported as the
//! studio's page exports it (the same frames, by the same code).

use std::path::Path;
use std::sync::atomic::Ordering;

use bdmorph::studio::export::{export_with_drawings, ExportFormat, ExportSettings};
use bdmorph::studio::jobs::Progress;
use bdmorph::studio::open::{open, OpenOptions};

use super::morph::progress_bar;
use super::ExportArgs;

/// The format `-o`'s ending (and `--sheet`) names, when `--format` does not.
fn format_of(out: &Path, sheet: bool) -> Result<ExportFormat, String> {
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let shown = out.display();
    Ok(match (ext.as_deref(), sheet) {
        (Some("png"), true) => ExportFormat::Sheet,
        (_, true) => return Err(format!("{shown}: a sprite sheet (--sheet) is a .png file")),
        (Some("gif"), _) => ExportFormat::Gif,
        (Some("mp4"), _) => ExportFormat::Mp4,
        (Some("apng"), _) => ExportFormat::Apng,
        (Some("webp"), _) => ExportFormat::Webp,
        (Some("html" | "htm"), _) => ExportFormat::Html,
        (Some("png"), _) => {
            return Err(format!(
                "{shown}: a .png holds one picture: give --sheet for a sprite sheet, -o NAME.apng for an animated PNG, or a folder (-o DIR) for PNG frames"
            ))
        }
        (None, _) => ExportFormat::Frames,
        (Some(other), _) => {
            return Err(format!(
                "{shown}: unknown ending '.{other}' (.gif, .mp4, .apng, .webp, .png with --sheet, .html, or a folder for PNG frames; or --format)"
            ))
        }
    })
}

/// `A-B` (inclusive, 0-based) as a frame range.
pub(super) fn parse_range(text: &str) -> Result<[usize; 2], String> {
    let bad = || format!("frame range '{text}' is not FIRST-LAST, for example 0-24");
    let (a, b) = text.split_once(['-', ':']).ok_or_else(bad)?;
    let a: usize = a.trim().parse().map_err(|_| bad())?;
    let b: usize = b.trim().parse().map_err(|_| bad())?;
    if a > b {
        return Err(format!(
            "frame range {a}-{b}: the first frame is after the last"
        ));
    }
    Ok([a, b])
}

/// The frames of `project`'s loop range, of its animation sampled at `frames` (default: its
/// duration times its frame rate, plus one), as the studio's Export dialog picks them.
fn loop_frames(
    project: &bdmorph::studio::project::Project,
    frames: Option<usize>,
) -> Result<[usize; 2], String> {
    let [from, to] = project
        .loop_range
        .ok_or("--loop-range: the project has no loop range (set one in the studio)")?;
    let count = frames.unwrap_or_else(|| bdmorph::studio::export::default_frames(project));
    let last = count.saturating_sub(1);
    let end = project.end();
    let at = |t: f64| -> usize {
        if end > 0.0 {
            ((t.min(end) / end * last as f64).round() as usize).min(last)
        } else {
            0
        }
    };
    Ok([at(from), at(to).max(at(from))])
}

pub(super) fn run(args: ExportArgs) -> Result<(), String> {
    let format = match args.format.as_deref() {
        Some(f) => f.parse()?,
        None => format_of(&args.output, args.sheet)?,
    };
    // As `morph --frames`: an animation of fewer than two frames is refused, not widened.
    if let Some(n) = args.frames.filter(|&n| n < 2) {
        return Err(format!("--frames {n}: at least 2 frames are needed"));
    }
    if args.sheet && format != ExportFormat::Sheet {
        return Err(
            "--sheet makes a sprite sheet: leave out --format, or give --format sheet".into(),
        );
    }
    let mut settings = ExportSettings {
        format,
        frames: args.frames,
        range: args.range,
        size: args.size,
        background: args.background.unwrap_or_default(),
    };
    settings.check()?;
    if args.size.is_some() && !format.draws() && !args.quiet {
        eprintln!("bdmorph: warning: --size does not apply to HTML or OBJ output");
    }
    let workspace = args
        .project
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    // Checked before it is opened: a picture given here would be meshed, then refused.
    if !args
        .project
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
    {
        return Err(format!(
            "{}: give a project the studio saved (.json)",
            args.project.display()
        ));
    }
    let opened = open(&args.project, workspace, &OpenOptions::default())?;
    if args.loop_range {
        settings.range = Some(loop_frames(&opened.project, args.frames)?);
    }
    for note in &opened.notes {
        if !args.quiet {
            eprintln!("bdmorph: note: {note}");
        }
    }
    if format.is_folder() {
        if let Ok(meta) = std::fs::symlink_metadata(&args.output) {
            let frames_only = meta.is_dir()
                && std::fs::read_dir(&args.output).is_ok_and(|mut d| {
                    d.all(|e| {
                        e.is_ok_and(|e| {
                            let n = e.file_name();
                            let n = n.to_string_lossy();
                            n.starts_with("frame_") && (n.ends_with(".png") || n.ends_with(".obj"))
                        })
                    })
                });
            if !frames_only {
                return Err(format!(
                    "{}: exists and is not a folder of earlier frames; it is not replaced",
                    args.output.display()
                ));
            }
        }
    }
    // Keyframes' drawings (named as the workspace names them).
    let folder = std::fs::canonicalize(workspace).unwrap_or_else(|_| workspace.to_path_buf());
    let drawings: Vec<Option<bdmorph::render::Image>> = opened
        .project
        .keyframes
        .iter()
        .enumerate()
        .map(|(k, key)| {
            let d = key.drawing.as_ref()?;
            match bdmorph::studio::open::read_texture(&folder.join(&d.picture), &d.picture) {
                Ok(t) => Some(t.image),
                Err(e) => {
                    if !args.quiet {
                        eprintln!(
                            "bdmorph: note: keyframe {} is drawn with the rest picture: its drawing {} could not be read ({e})",
                            k + 1,
                            d.picture
                        );
                    }
                    None
                }
            }
        })
        .collect();
    let drawing_refs: Vec<Option<&bdmorph::render::Image>> =
        drawings.iter().map(Option::as_ref).collect();
    let progress = Progress::default();
    let texture = opened.texture.as_ref().map(|t| &t.image);
    let finished = std::sync::atomic::AtomicBool::new(false);
    let done = std::thread::scope(|scope| {
        let bar = scope.spawn(|| {
            let bar = progress_bar(2, args.quiet, "export");
            while !finished.load(Ordering::Relaxed) {
                let total = progress.total.load(Ordering::Relaxed);
                if total > 0 {
                    bar.set_length(total);
                    bar.set_position(progress.done.load(Ordering::Relaxed));
                }
                std::thread::sleep(std::time::Duration::from_millis(100));
            }
            bar.finish_and_clear();
        });
        let done = export_with_drawings(
            &opened.project,
            texture,
            &drawing_refs,
            &settings,
            &args.output,
            &progress,
        );
        finished.store(true, Ordering::Relaxed);
        let _ = bar.join();
        done
    })?;
    if !args.quiet {
        let also: Vec<String> = done.also.iter().map(|p| p.display().to_string()).collect();
        eprintln!(
            "bdmorph: wrote {} ({} frames, {}x{}{}{})",
            done.path.display(),
            done.frames,
            done.size.width,
            done.size.height,
            if also.is_empty() { "" } else { "; and " },
            also.join(", ")
        );
    }
    Ok(())
}
