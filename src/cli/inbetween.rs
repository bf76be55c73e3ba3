//! `bdmorph inbetween A.png B.png ...`.

use std::io::Write;
use std::path::Path;

use bdmorph::distortion::RestShape;
use bdmorph::inbetween::{
    linear_frame, ArapInterpolation, CompatiblePath, CompatibleReport, Drawing, Inbetween,
    InbetweenOptions,
};
use bdmorph::io::{self, TexCoords};
use bdmorph::meshing::{Background, PictureOptions};
use bdmorph::project::{Keyframe, KeyframeDrawing, PictureSettings, Project};
use bdmorph::render::{raster, Image};
use bdmorph::studio::open::per_vertex_uv;
use bdmorph::Easing;
use bdmorph::{FrameStats, PlanarMesh};

use super::morph::{
    check_kept, check_options, check_size, json_escape, morph_options, plan_of, progress_bar,
};
use super::output::{self, Crossfade, Format, Look, Plan};
use super::{times, InbetweenArgs, InbetweenMethod};

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
    // `-o NAME.json`: a studio project of the drawings (it plays these very frames).
    let project_out = args.out.output.clone().filter(|p| {
        p.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"))
    });
    if project_out.is_some() {
        check_project_options(&args)?;
    }
    let plan = match project_out {
        Some(_) => None,
        None => plan_of(&args.out, times.len())?,
    };
    if let Some(plan) = &plan {
        check_format(plan)?;
    }
    check_size(plan.as_ref(), &args.out)?;
    // The errors of `read_image` name the file.
    let read = |path: &std::path::Path| raster::read_image(path).map_err(|e| e.to_string());
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
        .with_morph(morph_options(&args.solver, bdmorph::Placement::Fit));
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
    if let Some(out) = &project_out {
        let project = project_of(&args, out, &path, times.len())?;
        io::write_bytes_atomic(out, &project.to_json()).map_err(|e| e.to_string())?;
        if !quiet {
            eprintln!(
                "wrote {} (open it with: bdmorph studio {})",
                out.display(),
                out.display()
            );
        }
        return Ok(());
    }
    let colour = args.out.color_by.is_some();
    let vertices = path.mesh.positions.len();
    let faces = path.mesh.faces.clone();
    if let Some(plan) = &plan {
        check_kept(plan, times.len(), vertices, colour.then_some(faces.len()))?;
    }
    let segments = path.layouts.len();
    // The baselines' frames: drawing k's layout, and per segment ARAP's interpolation (made
    // when first needed).
    let layout = |k: usize| {
        if k == 0 {
            path.mesh.positions.as_slice()
        } else {
            path.layouts[k - 1].as_slice()
        }
    };
    let mut arap: Vec<Option<ArapInterpolation>> = (0..segments).map(|_| None).collect();
    let rest = RestShape::new(&path.mesh.positions, &faces);
    let bar = progress_bar(times.len(), quiet, "morphing");
    let mut frames = Vec::with_capacity(if plan.is_some() { times.len() } else { 0 });
    let mut blends = Vec::with_capacity(times.len());
    for (index, &t) in times.iter().enumerate() {
        // Each segment eased on its own; the path's time from there.
        let (k, s) = inbetween.segment(t);
        let eased = args.easing.as_ref().map_or(s, |e| e.apply(s));
        let at = (k as f64 + eased) / segments as f64;
        let (positions, distortion, stats) = match args.method {
            InbetweenMethod::Bdmorph => {
                let frame = inbetween
                    .frame(at)
                    .map_err(|e| format!("{names}: t = {t}: {e}"))?;
                (
                    frame.positions.to_vec(),
                    frame.distortion.to_vec(),
                    frame.stats,
                )
            }
            method => {
                let started = std::time::Instant::now();
                let (a, b) = (layout(k), layout(k + 1));
                let positions = if method == InbetweenMethod::Linear {
                    linear_frame(a, b, eased)
                } else {
                    if arap[k].is_none() {
                        let from = PlanarMesh {
                            positions: a.to_vec(),
                            faces: faces.clone(),
                        };
                        arap[k] = Some(
                            ArapInterpolation::new(&from, b)
                                .map_err(|e| format!("{names}: {e}"))?,
                        );
                    }
                    let interpolation = arap[k].as_mut().expect("made above");
                    interpolation
                        .frame(eased)
                        .map_err(|e| format!("{names}: t = {t}: {e}"))?
                };
                let (distortion, stats) = measure(&rest, &positions, t, started);
                (positions, distortion, stats)
            }
        };
        if args.out.stats {
            writeln!(stdout, "{}", stats.to_json()).map_err(|e| e.to_string())?;
        }
        if stats.flipped_triangles > 0 && !quiet {
            eprintln!(
                "bdmorph: warning: t = {t}: {} flipped triangles",
                stats.flipped_triangles
            );
        }
        if plan.is_some() {
            frames.push(output::Frame {
                index,
                t,
                positions,
                distortion: colour.then_some(distortion),
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

/// Options that a project (`-o NAME.json`) cannot carry.
fn check_project_options(args: &InbetweenArgs) -> Result<(), String> {
    let refuse = |what: &str| {
        Err(format!(
            "{what}: a project (-o NAME.json) is played by the studio, which morphs by BDMORPH \
             through its keyframes; give --frames N for its length"
        ))
    };
    if args.method != InbetweenMethod::Bdmorph {
        return refuse("--method");
    }
    if args.t.is_some() {
        return refuse("--t");
    }
    if args.out.format.is_some() {
        return refuse("--format");
    }
    Ok(())
}

/// `file`'s name as a project in `dir` keeps it: relative to `dir` when inside it, else
/// absolute.
fn name_for(dir: &Path, file: &Path) -> String {
    let absolute = std::fs::canonicalize(file).unwrap_or_else(|_| file.to_path_buf());
    let dir = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
    match absolute.strip_prefix(&dir) {
        Ok(inside) => inside.display().to_string(),
        Err(_) => absolute.display().to_string(),
    }
}

/// The easing's text as projects (and `--easing`) write it.
fn easing_text(easing: Option<&Easing>) -> String {
    match easing {
        None | Some(Easing::Linear) => "linear".into(),
        Some(Easing::EaseInOut) => "ease-in-out".into(),
        Some(Easing::CubicBezier([a, b, c, d])) => format!("cubic-bezier({a},{b},{c},{d})"),
    }
}

/// The studio project of the drawings: the compatible mesh (drawing A's layout, textured by
/// it) and one keyframe per other drawing (its layout, textured by it), `frames` frames long
/// at `--fps`, with the command's placement and easing: the studio plays and exports the
/// frames this command would write.
fn project_of(
    args: &InbetweenArgs,
    out: &Path,
    path: &CompatiblePath,
    frames: usize,
) -> Result<Project, String> {
    let dir = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let n = path.mesh.positions.len();
    let uv = |t: &TexCoords| {
        per_vertex_uv(t, &path.mesh.faces, n).ok_or_else(|| {
            "the compatible mesh's texture coordinates are not one per vertex".to_string()
        })
    };
    let mut project = Project::new(&path.mesh, Some(uv(&path.texcoords[0])?));
    project.texture = Some(name_for(dir, &args.drawings[0]));
    project.fps = f64::from(args.out.fps);
    project.placement = Some(
        args.solver
            .placement
            .unwrap_or(bdmorph::Placement::Fit)
            .to_string(),
    );
    project.picture = PictureSettings {
        background: args.paper.as_ref().map(|p| match p {
            Background::Auto => "auto".to_string(),
            Background::Colour([r, g, b]) => format!("#{r:02x}{g:02x}{b:02x}"),
        }),
        threshold: args.threshold,
    };
    let easing = easing_text(args.easing.as_ref());
    project.keyframes[0].easing = easing.clone();
    let segments = path.layouts.len();
    let duration = (frames.max(2) - 1) as f64 / project.fps;
    for (k, layout) in path.layouts.iter().enumerate() {
        project.keyframes.push(Keyframe {
            time: duration * (k + 1) as f64 / segments as f64,
            easing: easing.clone(),
            positions: layout.clone(),
            pins: Vec::new(),
            drawing: Some(KeyframeDrawing {
                picture: name_for(dir, &args.drawings[k + 1]),
                texcoords: uv(&path.texcoords[k + 1])?,
                pairs: Vec::new(),
            }),
        });
    }
    project.check().map_err(|e| e.to_string())?;
    Ok(project)
}

/// A baseline's frame measured as the morph measures its own: each triangle's conformal
/// distortion from drawing A's layout (infinite for a flipped one) and the statistics.
fn measure(
    rest: &RestShape,
    positions: &[[f64; 2]],
    t: f64,
    started: std::time::Instant,
) -> (Vec<f64>, FrameStats) {
    let mut distortion = vec![0.0; rest.faces().len()];
    rest.distortion_into(positions, &mut distortion);
    let flipped = rest
        .faces()
        .iter()
        .filter(|f| {
            let [a, b, c] = f.map(|v| positions[v as usize]);
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) <= 0.0
        })
        .count();
    let largest = if flipped > 0 {
        f64::INFINITY
    } else {
        distortion.iter().copied().fold(1.0, f64::max)
    };
    let stats = FrameStats {
        t,
        newton_iterations: 0,
        factorizations: 0,
        cg_iterations: 0,
        gradient_norm: 0.0,
        flipped_triangles: flipped,
        max_conformal_distortion: largest,
        seconds: started.elapsed().as_secs_f64(),
    };
    (distortion, stats)
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
