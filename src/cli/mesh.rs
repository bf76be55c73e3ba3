//! `bdmorph mesh INPUT -o OUT.obj`: a mesh from a picture or an outline.

use std::io::Write as _;

use bdmorph::meshing::{self, InputKind, MeshOptions, Meshed, PictureOptions};
use bdmorph::render::raster;

use super::output::{self, Format};
use super::MeshArgs;

/// A JSON number, `null` when not finite.
fn json(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        "null".into()
    }
}

/// A JSON string.
fn json_string(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if u32::from(c) < 0x20 => out.push_str(&format!("\\u{:04x}", u32::from(c))),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The statistics line of `--stats`.
fn stats_json(m: &Meshed) -> String {
    let s = &m.stats;
    format!(
        "{{\"vertices\":{},\"requested_vertices\":{},\"off_target\":{},\"faces\":{},\"pieces\":{},\"holes\":{},\"min_angle\":{},\"outline_vertices\":{},\"tolerance\":{},\"dropped_outlines\":{},\"dropped_specks\":{},\"refinement_complete\":{},\"passes\":{},\"seconds\":{}}}",
        s.vertices,
        s.requested_vertices,
        s.off_target
            .as_ref()
            .map_or_else(|| "null".to_string(), |o| json_string(&o.to_string())),
        s.faces,
        s.pieces,
        s.holes,
        json(s.min_angle),
        s.outline_vertices,
        s.tolerance.map_or_else(|| "null".to_string(), json),
        s.dropped_outlines,
        s.dropped_specks,
        s.refinement_complete,
        s.passes,
        json(s.seconds)
    )
}

fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

pub(super) fn run(args: MeshArgs) -> Result<(), String> {
    if super::layered::is_layered(&args.input) {
        return super::layered::run(&args);
    }
    let plan = match &args.output {
        Some(path) => Some(output::Plan::new(path, None, 1)?),
        None if args.stats => None,
        None => return Err("nothing to do: give -o OUT.obj, --stats, or both".into()),
    };
    if plan.as_ref().is_some_and(|p| p.format.is_animation()) {
        return Err("mesh writes one mesh: use .obj (or .svg or .png for a picture of it)".into());
    }
    let mut options = MeshOptions::default()
        .with_vertices(args.vertices)
        .with_min_angle(args.min_angle);
    if let Some(t) = args.tolerance {
        options = options.with_tolerance(t);
    }
    let mut picture = PictureOptions::default();
    if let Some(b) = args.background {
        picture = picture.with_background(b);
    }
    if let Some(t) = args.threshold {
        picture = picture.with_threshold(t);
    }
    picture = picture.with_keep_specks(args.keep_specks);
    let kind = bdmorph::io::read_input(&args.input, bdmorph::io::MAX_INPUT_BYTES)
        .ok()
        .and_then(|bytes| InputKind::of(&args.input, &bytes));
    let picture_only: Vec<&str> = [
        (args.background.is_some(), "--background"),
        (args.threshold.is_some(), "--threshold"),
        (args.keep_specks, "--keep-specks"),
    ]
    .iter()
    .filter(|(given, _)| *given)
    .map(|&(_, name)| name)
    .collect();
    if kind.is_some_and(|k| k != InputKind::Picture) && !picture_only.is_empty() && !args.quiet {
        let (names, verb) = match picture_only.as_slice() {
            [one] => (one.to_string(), "applies"),
            [rest @ .., last] => (format!("{} and {last}", rest.join(", ")), "apply"),
            [] => unreachable!("checked above"),
        };
        eprintln!("bdmorph: warning: {names} only {verb} to pictures");
    }
    let meshed = meshing::mesh_file(&args.input, &picture, &options).map_err(|e| e.to_string())?;
    if args.stats {
        writeln!(std::io::stdout().lock(), "{}", stats_json(&meshed)).map_err(|e| e.to_string())?;
    }
    let s = &meshed.stats;
    if let Some(plan) = plan {
        let title = format!(
            "bdmorph mesh {}: {}, {}, {}, {}, smallest angle {:.2} degrees",
            args.input.display(),
            plural(s.vertices, "vertex", "vertices"),
            plural(s.faces, "triangle", "triangles"),
            plural(s.pieces, "piece", "pieces"),
            plural(s.holes, "hole", "holes"),
            s.min_angle
        );
        let texture = if plan.format == Format::Png && kind == Some(InputKind::Picture) {
            Some(raster::read_image(&args.input).map_err(|e| e.to_string())?)
        } else {
            None
        };
        let corner_uv = meshed.texcoords.corner_uv();
        let look = output::Look {
            faces: &meshed.mesh.faces,
            texcoords: Some(&meshed.texcoords),
            texture: texture.as_ref().map(|t| (t, corner_uv.as_slice())),
            size: args.size,
            fps: 25,
            title: &title,
            background: bdmorph::render::Background::WHITE,
            crossfade: None,
            depth: None,
        };
        let frames = [output::Frame {
            index: 0,
            t: f64::NAN,
            positions: meshed.mesh.positions.clone(),
            distortion: None,
        }];
        let files = output::render(&plan, &look, &frames, || {})?;
        output::write(&plan, &files)?;
        if !args.quiet {
            eprintln!(
                "wrote {} ({}, {}, {}, {}, smallest angle {:.2} degrees, {:.2} s)",
                plan.path.display(),
                plural(s.vertices, "vertex", "vertices"),
                plural(s.faces, "triangle", "triangles"),
                plural(s.pieces, "piece", "pieces"),
                plural(s.holes, "hole", "holes"),
                s.min_angle,
                s.seconds
            );
        }
    }
    if !args.quiet {
        if s.dropped_outlines > 0 {
            eprintln!(
                "bdmorph: note: {} too small for the tolerance left out (lower --tolerance to keep {})",
                plural(s.dropped_outlines, "outline", "outlines"),
                if s.dropped_outlines == 1 { "it" } else { "them" }
            );
        }
        if s.dropped_specks > 0 {
            let percent = 100.0 * meshing::SPECK_AREA_FRACTION;
            eprintln!(
                "bdmorph: note: dropped {} ({} under {percent}% of the largest piece's area); --keep-specks keeps {}",
                plural(s.dropped_specks, "speck", "specks"),
                if s.dropped_specks == 1 { "a piece" } else { "pieces" },
                if s.dropped_specks == 1 { "it" } else { "them" }
            );
        }
        if let Some(why) = &s.off_target {
            eprintln!(
                "bdmorph: note: {}, not about {} as asked: {why}",
                plural(s.vertices, "vertex", "vertices"),
                s.requested_vertices
            );
        }
        if !s.refinement_complete {
            eprintln!(
                "bdmorph: warning: the refinement ran out of vertices before meeting the minimum angle everywhere (smallest {:.2} degrees); lower --min-angle",
                s.min_angle
            );
        }
    }
    Ok(())
}
