//! `bdmorph inbetween A.png B.png ...`.

use std::io::Write;

use bdmorph::inbetween::{CompatibleReport, Drawing, Inbetween, InbetweenOptions};
use bdmorph::meshing::PictureOptions;
use bdmorph::render::{raster, Image};

use super::morph::{
    check_kept, check_options, check_size, json_escape, morph_options, plan_of, progress_bar,
};
use super::output::{self, Crossfade, Format, Look, Plan};
use super::{times, InbetweenArgs};

/// Formats that can cross-fade two pictures, or carry positions.
fn check_format(plan: &Plan) -> Result<(), String> {
    match plan.format {
        Format::Svg | Format::Html => Err(format!(
            "{}: in-betweens are written as .obj, .png, .gif, .mp4, .apng or .webp (SVG and HTML \
             cannot cross-fade the two pictures)",
            plan.path.display()
        )),
        _ => Ok(()),
    }
}

pub(super) fn run(args: InbetweenArgs) -> Result<(), String> {
    // Everything that can be checked before computing is checked first.
    let times = times(args.t, args.frames)?;
    if let Some(t) = times.iter().find(|t| !(0.0..=1.0).contains(*t)) {
        return Err(format!("--t {t}: in-betweens are for t in [0, 1]"));
    }
    check_options(&args.out, &args.solver)?;
    if args.out.texture.is_some() {
        return Err("--texture: in-betweens are textured by the two drawings themselves".into());
    }
    if args.out.depth.is_some() {
        return Err("--depth is not available for in-betweens".into());
    }
    if args.solver.program.is_some() {
        return Err("--program is not available for in-betweens (the mesh is made here)".into());
    }
    let plan = plan_of(&args.out, times.len())?;
    if let Some(plan) = &plan {
        check_format(plan)?;
    }
    check_size(plan.as_ref(), &args.out)?;
    let read = |path: &std::path::Path| {
        raster::read_image(path).map_err(|e| format!("{}: {e}", path.display()))
    };
    let pictures: Vec<Image> = args
        .drawings
        .iter()
        .map(|p| read(p))
        .collect::<Result<_, _>>()?;
    let mut picture = PictureOptions::default();
    if let Some(paper) = args.paper {
        picture = picture.with_background(paper);
    }
    if let Some(t) = args.threshold {
        picture = picture.with_threshold(t);
    }
    let options = InbetweenOptions::default()
        .with_picture(picture)
        .with_vertices(args.vertices)
        .with_min_angle(args.min_angle)
        .with_morph(morph_options(&args.solver));
    let names = args
        .drawings
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(" -> ");
    let refs: Vec<&Image> = pictures.iter().collect();
    let mut inbetween =
        Inbetween::through(&refs, &args.matches, &options).map_err(|e| format!("{names}: {e}"))?;
    let path = inbetween.path().clone();
    let quiet = args.out.quiet;
    if let Some(first) = path.reports.first() {
        for (k, pair) in first.pairs.iter().enumerate() {
            if let (false, Some(reason)) = (pair.met, &pair.reason) {
                eprintln!("bdmorph: warning: --match {} is not met: {reason}", k + 1);
            }
        }
    }
    let mut stdout = std::io::stdout().lock();
    for (k, report) in path.reports.iter().enumerate() {
        if !quiet {
            eprintln!("bdmorph: {}", summary(report, Drawing(k + 1)));
            for note in &report.notes {
                eprintln!("bdmorph: note: {note}");
            }
        }
        if args.out.stats {
            writeln!(stdout, "{}", report_json(report, k + 1)).map_err(|e| e.to_string())?;
        }
    }
    let colour = args.out.color_by.is_some();
    let vertices = path.mesh.positions.len();
    let faces = path.mesh.faces.clone();
    if let Some(plan) = &plan {
        check_kept(plan, times.len(), vertices, colour.then_some(faces.len()))?;
    }
    let segments = path.layouts.len();
    let bar = progress_bar(times.len(), quiet, "morphing");
    let mut frames = Vec::with_capacity(if plan.is_some() { times.len() } else { 0 });
    let mut blends = Vec::with_capacity(times.len());
    for (index, &t) in times.iter().enumerate() {
        // Each segment eased on its own; the path's time from there.
        let (k, s) = inbetween.segment(t);
        let eased = args.easing.as_ref().map_or(s, |e| e.apply(s));
        let at = (k as f64 + eased) / segments as f64;
        let frame = inbetween
            .frame(at)
            .map_err(|e| format!("{names}: t = {t}: {e}"))?;
        if args.out.stats {
            writeln!(stdout, "{}", frame.stats.to_json()).map_err(|e| e.to_string())?;
        }
        if frame.stats.flipped_triangles > 0 && !quiet {
            eprintln!(
                "bdmorph: warning: t = {t}: {} flipped triangles",
                frame.stats.flipped_triangles
            );
        }
        if plan.is_some() {
            frames.push(output::Frame {
                index,
                t,
                positions: frame.positions.to_vec(),
                distortion: colour.then(|| frame.distortion.to_vec()),
            });
            blends.push((k, k + 1, args.crossfade.weight(eased)));
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    stdout.flush().map_err(|e| e.to_string())?;
    let Some(plan) = plan else {
        return Ok(());
    };
    let corner_uv: Vec<Vec<[[f64; 2]; 3]>> = path.texcoords.iter().map(|t| t.corner_uv()).collect();
    let title = format!("bdmorph: {names}");
    let look = Look {
        faces: &faces,
        texcoords: Some(&path.texcoords[0]),
        texture: Some((&pictures[0], corner_uv[0].as_slice())),
        size: args.out.size,
        fps: args.out.fps,
        title: &title,
        background: args.out.background.unwrap_or_default(),
        crossfade: Some(Crossfade {
            textures: pictures
                .iter()
                .zip(&corner_uv)
                .map(|(p, uv)| (p, uv.as_slice()))
                .collect(),
            blends: &blends,
        }),
        depth: None,
    };
    let bar = progress_bar(frames.len(), quiet, "rendering");
    let files = output::render(&plan, &look, &frames, || bar.inc(1))?;
    bar.finish_and_clear();
    output::write(&plan, &files)?;
    if !quiet {
        if plan.directory {
            eprintln!("wrote {} files to {}", files.len(), plan.path.display());
        } else {
            eprintln!("wrote {}", plan.path.display());
        }
    }
    Ok(())
}

/// One line about the compatible mesh over one drawing.
fn summary(r: &CompatibleReport, over: Drawing) -> String {
    let met = r.pairs.iter().filter(|p| p.met).count();
    let pairs = if r.pairs.is_empty() {
        String::new()
    } else {
        format!(", {met} of {} pairs met", r.pairs.len())
    };
    let added = if r.added_vertices > 0 {
        format!(
            " ({} added where A's mesh as meshed had no flip-free layout)",
            r.added_vertices
        )
    } else {
        String::new()
    };
    format!(
        "compatible mesh: {} vertices{added}, {} triangles, none flipped over {over}, largest distortion {:.2}{pairs}, in {:.2} s",
        r.vertices, r.faces, r.max_distortion, r.seconds
    )
}

/// The compatible mesh's statistics over drawing `over` (1 for B) as one line of JSON.
fn report_json(r: &CompatibleReport, over: usize) -> String {
    let pairs: Vec<String> = r
        .pairs
        .iter()
        .map(|p| {
            let error = if p.error.is_finite() {
                format!("{:e}", p.error)
            } else {
                "null".into()
            };
            let reason = p
                .reason
                .as_deref()
                .map_or("null".into(), |r| format!("\"{}\"", json_escape(r)));
            format!(
                "{{\"on_outline\":{},\"met\":{},\"error\":{error},\"reason\":{reason}}}",
                p.on_outline, p.met
            )
        })
        .collect();
    let notes: Vec<String> = r
        .notes
        .iter()
        .map(|n| format!("\"{}\"", json_escape(n)))
        .collect();
    format!(
        "{{\"compatible_mesh\":{{\"drawing\":{over},\"vertices\":{},\"added_vertices\":{},\"faces\":{},\"flipped\":{},\"outline_error\":{:e},\"max_distortion\":{},\"tolerance\":[{},{}],\"seconds\":{},\"pairs\":[{}],\"notes\":[{}]}}}}",
        r.vertices,
        r.added_vertices,
        r.faces,
        r.flipped,
        r.outline_error,
        r.max_distortion,
        r.tolerance[0],
        r.tolerance[1],
        r.seconds,
        pairs.join(","),
        notes.join(",")
    )
}
