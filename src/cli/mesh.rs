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

/// The statistics line of `--stats`.
fn stats_json(m: &Meshed) -> String {
    let s = &m.stats;
    format!(
        "{{\"vertices\":{},\"faces\":{},\"pieces\":{},\"holes\":{},\"min_angle\":{},\"outline_vertices\":{},\"dropped_outlines\":{},\"refinement_complete\":{},\"passes\":{},\"seconds\":{}}}",
        s.vertices,
        s.faces,
        s.pieces,
        s.holes,
        json(s.min_angle),
        s.outline_vertices,
        s.dropped_outlines,
        s.refinement_complete,
        s.passes,
        json(s.seconds)
    )
}

fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

pub(super) fn run(args: MeshArgs) -> Result<(), String> {
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
    let kind = std::fs::read(&args.input)
        .ok()
        .and_then(|bytes| InputKind::of(&args.input, &bytes));
    if kind.is_some_and(|k| k != InputKind::Picture)
        && (args.background.is_some() || args.threshold.is_some())
        && !args.quiet
    {
        eprintln!("bdmorph: warning: --background and --threshold only apply to pictures");
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
        if s.outline_vertices >= args.vertices {
            eprintln!(
                "bdmorph: note: the outline alone has {} vertices, --vertices asked for {}; raise --tolerance for fewer",
                s.outline_vertices, args.vertices
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
