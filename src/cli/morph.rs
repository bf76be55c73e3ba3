//! `bdmorph morph SOURCE TARGET ...`.

use std::io::Write;
use std::path::Path;

use bdmorph::render::raster;
use bdmorph::{Morph, MorphOptions, PlanarMesh};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::output::{self, Look, Plan};
use super::{times, MorphArgs};

pub(super) fn read(path: &Path) -> Result<(PlanarMesh, Option<bdmorph::io::TexCoords>), String> {
    let (mesh, tex) = PlanarMesh::read_textured(path).map_err(|e| e.to_string())?;
    mesh.validate()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok((mesh, tex))
}

/// A progress bar on stderr, drawn only when stderr is a terminal and not `quiet`.
pub(super) fn progress_bar(len: usize, quiet: bool, what: &str) -> ProgressBar {
    let target = if quiet || len < 2 {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(Some(len as u64), target);
    if let Ok(style) = ProgressStyle::with_template("{msg:>10} [{bar:30}] {pos}/{len} {eta}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_owned());
    bar
}

pub(super) fn run(args: MorphArgs) -> Result<(), String> {
    // Everything that can be checked before computing is checked first: bad input writes
    // nothing.
    let times = times(args.t, args.frames)?;
    if args.output.is_none() && !args.stats {
        return Err("nothing to do: give -o OUT, --stats, or both".into());
    }
    if args.tolerance.is_nan() || args.tolerance <= 0.0 {
        return Err(format!("--tolerance {} must be positive", args.tolerance));
    }
    if args.fps == 0 {
        return Err("--fps must be at least 1".into());
    }
    let plan = match &args.output {
        Some(path) => Some(Plan::new(path, args.format, times.len())?),
        None => None,
    };
    let (source, texcoords) = read(&args.source)?;
    let (target, _) = read(&args.target)?;
    let texture = match &args.texture {
        Some(path) => Some(raster::read_image(path).map_err(|e| e.to_string())?),
        None => None,
    };
    if texture.is_some() && !plan.as_ref().is_some_and(Plan::draws) && !args.quiet {
        eprintln!("bdmorph: warning: --texture only affects PNG, GIF and HTML output");
    }
    let options = MorphOptions::default()
        .with_tolerance(args.tolerance)
        .with_max_iterations(args.max_iterations);
    let morph = match &args.program {
        Some(path) => {
            let program = super::compile::load(path, &args.source, &source)?;
            Morph::with_program(program, &source, &target, options)
        }
        None => Morph::new(&source, &target, options),
    };
    let mut morph = morph.map_err(|e| {
        format!(
            "{} -> {}: {e}",
            args.source.display(),
            args.target.display()
        )
    })?;

    let bar = progress_bar(times.len(), args.quiet, "morphing");
    let mut frames = Vec::with_capacity(if plan.is_some() { times.len() } else { 0 });
    let mut stdout = std::io::stdout().lock();
    let mut failed = 0usize;
    for (index, &t) in times.iter().enumerate() {
        let frame = match morph.frame(t) {
            Ok(frame) => frame,
            // One frame: its error is the command's. Several: report it, write the others.
            Err(e) if times.len() == 1 => return Err(e.to_string()),
            Err(e) => {
                failed += 1;
                if args.stats {
                    writeln!(
                        stdout,
                        "{{\"t\":{t},\"error\":\"{}\"}}",
                        json_escape(&e.to_string())
                    )
                    .map_err(|e| e.to_string())?;
                }
                bar.suspend(|| eprintln!("bdmorph: error: {e}; frame skipped"));
                bar.inc(1);
                continue;
            }
        };
        if args.stats {
            writeln!(stdout, "{}", frame.stats.to_json()).map_err(|e| e.to_string())?;
        }
        if frame.stats.flipped_triangles > 0 && !args.quiet {
            bar.suspend(|| {
                eprintln!(
                    "bdmorph: warning: t = {t}: {} flipped triangles",
                    frame.stats.flipped_triangles
                );
            });
        }
        if plan.is_some() {
            frames.push((index, t, frame.positions.to_vec()));
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let n_times = times.len();
    let writes = plan.is_some();
    let failures = move || {
        format!(
            "{failed} of {n_times} frames could not be computed (see above); the others were {}",
            if writes { "written" } else { "computed" }
        )
    };
    let Some(plan) = plan else {
        return if failed > 0 { Err(failures()) } else { Ok(()) };
    };
    if frames.is_empty() {
        return Err(format!(
            "no frame could be computed; nothing was written to {}",
            plan.path.display()
        ));
    }

    let corner_uv = texture.as_ref().map(|_| {
        texcoords
            .clone()
            .unwrap_or_else(|| source.normalized_texcoords())
            .corner_uv()
    });
    let title = format!(
        "bdmorph: {} -> {}",
        args.source.display(),
        args.target.display()
    );
    let look = Look {
        faces: morph.faces(),
        texcoords: texcoords.as_ref(),
        texture: texture.as_ref().zip(corner_uv.as_deref()),
        size: args.size,
        fps: args.fps,
        title: &title,
    };
    let bar = progress_bar(frames.len(), args.quiet, "rendering");
    let files = output::render(&plan, &look, &frames, || bar.inc(1))?;
    bar.finish_and_clear();
    output::write(&plan, &files)?;
    if !args.quiet {
        if plan.directory {
            eprintln!("wrote {} files to {}", files.len(), plan.path.display());
        } else {
            eprintln!("wrote {}", plan.path.display());
        }
    }
    if failed > 0 {
        return Err(failures());
    }
    Ok(())
}

/// Escapes a message for a JSON string.
fn json_escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out
}
