//! `bdmorph param MESH --method M [--iterations N] -o OUT`.

use std::fmt::Write as _;
use std::io::Write as _;

use bdmorph::param::bounded::{self, BoundedDistortion, BoundedOptions, BoundedReport, Flattening};
use bdmorph::param::messages::{
    flattening_message, fmt_distortion, param_failure, worst_faces, Spelling,
};
use bdmorph::param::{ParamMethod as Method, ParamOptions, Parameterization};
use bdmorph::render::{raster, surface, Drawing, Image, Viewport};

use super::morph::progress_bar;
use super::output;
use super::{DeformArgs, InitArg, ParamArgs, ParamMethod};

/// The method's command-line name.
fn method_name(m: Method) -> &'static str {
    m.name()
}

/// A JSON number, `null` when not finite.
fn json(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        "null".into()
    }
}

pub(super) fn run(args: ParamArgs) -> Result<(), String> {
    let ext = args.output.as_ref().map(|p| {
        p.extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default()
    });
    match ext.as_deref() {
        None if !args.stats => return Err("nothing to do: give -o OUT, --stats, or both".into()),
        None | Some("obj" | "png") => {}
        Some(other) => {
            return Err(format!(
                "{}: unknown output extension '.{other}' (use .obj or .png)",
                args.output
                    .as_ref()
                    .map(|p| p.display().to_string())
                    .unwrap_or_default()
            ))
        }
    }
    let bdmorph::MeshFile {
        mesh,
        lines: mesh_lines,
        ..
    } = bdmorph::MeshFile::read(&args.mesh).map_err(|e| e.to_string())?;
    let in_file = |e: bdmorph::param::ParamError| {
        bdmorph::Located::new(&args.mesh, &mesh_lines, &mesh.faces, e).to_string()
    };
    let line = |f| mesh_lines.face_line(f);
    let (name, uv, e, iterations, seconds, setup_seconds, stop, unmet) = match args.method {
        ParamMethod::Param(method) => {
            let mut options = ParamOptions::default();
            if let Some(n) = args.iterations {
                options = options.with_iterations(n);
            }
            if let Some(w) = args.collapse_barrier {
                options = options.with_collapse_barrier(w);
            }
            let name = method_name(method);
            let mut p = Parameterization::new(&mesh, method, options.clone()).map_err(in_file)?;
            let limit = args.iterations.unwrap_or(200) as usize;
            let iterative = !matches!(method, Method::Tutte | Method::Lscm);
            let bar = progress_bar(if iterative { limit } else { 0 }, args.quiet, name);
            let mut lines = String::new();
            let report = p
                .solve_with(|i, r| {
                    bar.set_position(u64::from(i));
                    if args.stats {
                        let _ = writeln!(
                            lines,
                            "{{\"iteration\":{i},\"energy\":{},\"gradient_norm\":{},\"step\":{}}}",
                            json(r.energy_after),
                            json(r.gradient_norm),
                            json(r.step)
                        );
                    }
                })
                .map_err(in_file)?;
            bar.finish_and_clear();
            if args.stats {
                write!(std::io::stdout().lock(), "{lines}").map_err(|e| e.to_string())?;
            }
            let energies = p.energies();
            let unmet = param_failure(name, &report, &energies, options, Spelling::CLI);
            (
                name,
                p.uv().to_vec(),
                energies,
                report.iterations,
                report.seconds,
                report.setup_seconds,
                report.stop.name(),
                unmet,
            )
        }
        ParamMethod::Bounded => {
            let k = args
                .max_distortion
                .ok_or("--method bounded needs --max-distortion K")?;
            // The chosen start first; when it does not meet the bound, the other one.
            let starts = match args.init {
                InitArg::Tutte => [Method::Tutte, Method::Lscm],
                InitArg::Lscm => [Method::Lscm, Method::Tutte],
            };
            let mut options = BoundedOptions::new(k);
            if let Some(n) = args.iterations {
                options = options.with_iterations(n);
            }
            let bar = progress_bar(options.iterations as usize, args.quiet, "bounded");
            let flat = bounded::flatten(&mesh, &args.pins, options, &starts, |i, it, worst| {
                bar.set_position(u64::from(it));
                bar.set_message(format!("{} start, K {worst:.3}", method_name(starts[i])));
            })
            .map_err(in_file)?;
            bar.finish_and_clear();
            if args.stats {
                writeln!(std::io::stdout().lock(), "{}", flattening_json(&flat))
                    .map_err(|e| e.to_string())?;
            }
            let report = flat.report();
            let unmet =
                (!report.converged).then(|| flattening_message(&flat, &line, Spelling::CLI));
            let stop = if report.converged {
                "converged"
            } else if report.stalled {
                "stalled"
            } else {
                "iteration-limit"
            };
            let iterations = flat.attempts.iter().map(|a| a.report.iterations).sum();
            let seconds = flat.attempts.iter().map(|a| a.report.seconds).sum();
            let energies = bdmorph::param::energies(&mesh, &flat.uv).map_err(in_file)?;
            (
                "bounded",
                flat.uv.clone(),
                energies,
                iterations,
                seconds,
                flat.setup_seconds,
                stop,
                unmet,
            )
        }
    };
    if args.stats {
        writeln!(
            std::io::stdout().lock(),
            "{{\"method\":\"{name}\",\"vertices\":{},\"faces\":{},\"iterations\":{},\"seconds\":{},\"setup_seconds\":{},\"stop\":\"{stop}\",\"stalled\":{},\"symmetric_dirichlet\":{},\"arap\":{},\"mips\":{},\"flipped\":{},\"collapsed\":{},\"max_distortion\":{}}}",
            mesh.positions.len(),
            mesh.faces.len(),
            iterations,
            seconds,
            setup_seconds,
            stop == "stalled",
            json(e.symmetric_dirichlet),
            json(e.arap),
            json(e.mips),
            e.flipped,
            e.collapsed,
            json(e.max_distortion)
        )
        .map_err(|e| e.to_string())?;
    }
    let Some(path) = &args.output else {
        return unmet.map_or(Ok(()), Err);
    };
    let uv = &uv;
    let bytes = if ext.as_deref() == Some("png") {
        let img =
            picture(&mesh.positions, uv, &mesh.faces, args.size).map_err(|e| e.to_string())?;
        raster::encode_png(&img).map_err(|e| e.to_string())?
    } else {
        let mut text = String::with_capacity(64 * mesh.positions.len());
        let _ = writeln!(
            text,
            "# bdmorph param --method {name}: {} (E_SD {}, E_ARAP {}, E_MIPS {}, {} flipped)",
            args.mesh.display(),
            json(e.symmetric_dirichlet),
            json(e.arap),
            json(e.mips),
            e.flipped
        );
        for q in &mesh.positions {
            let _ = writeln!(text, "v {} {} {}", q[0], q[1], q[2]);
        }
        for t in uv {
            let _ = writeln!(text, "vt {} {}", t[0], t[1]);
        }
        for f in &mesh.faces {
            let [a, b, c] = f.map(|v| v + 1);
            let _ = writeln!(text, "f {a}/{a} {b}/{b} {c}/{c}");
        }
        text.into_bytes()
    };
    bdmorph::io::write_bytes_atomic(path, &bytes).map_err(|e| e.to_string())?;
    if !args.quiet {
        eprintln!(
            "wrote {} ({name}: set-up {:.2} s, {} iterations in {:.2} s; E_SD {:.5}, E_ARAP {:.5}, E_MIPS {:.5}, {} flipped)",
            path.display(),
            setup_seconds,
            iterations,
            seconds,
            e.symmetric_dirichlet,
            e.arap,
            e.mips,
            e.flipped
        );
    }
    unmet.map_or(Ok(()), Err)
}

/// Runs the bounded-distortion iterations with a progress bar (showing the largest
/// distortion) and, with `stats`, prints the report as JSON.
fn run_bounded(
    bd: &mut BoundedDistortion,
    uv: &mut [[f64; 2]],
    iterations: u32,
    label: &str,
    quiet: bool,
    stats: bool,
    in_file: &dyn Fn(bdmorph::param::ParamError) -> String,
) -> Result<BoundedReport, String> {
    let bar = progress_bar(iterations as usize, quiet, label);
    let report = bd
        .solve_with(uv, |i, worst| {
            bar.set_position(u64::from(i));
            bar.set_message(format!("K {worst:.3}"));
        })
        .map_err(in_file)?;
    bar.finish_and_clear();
    if stats {
        writeln!(std::io::stdout().lock(), "{}", bounded_json(&report))
            .map_err(|e| e.to_string())?;
    }
    Ok(report)
}

/// The bounded-distortion report as one line of JSON.
fn bounded_json(r: &BoundedReport) -> String {
    let worst: Vec<String> = r
        .worst
        .iter()
        .take(5)
        .map(|(f, d)| format!("[{f},{}]", json(*d)))
        .collect();
    format!(
        "{{\"converged\":{},\"stalled\":{},\"iterations\":{},\"newton_iterations\":{},\"max_distortion\":{},\"inverted\":{},\"constraint_error\":{},\"seconds\":{},\"worst\":[{}]}}",
        r.converged,
        r.stalled,
        r.iterations,
        r.newton_iterations,
        json(r.max_distortion),
        r.inverted,
        json(r.constraint_error),
        r.seconds,
        worst.join(",")
    )
}

/// A bounded-distortion parameterisation as one line of JSON: the kept map's report, which
/// start it came from, every start tried, and the angle argument's lower bound.
fn flattening_json(flat: &Flattening) -> String {
    let report = bounded_json(flat.report());
    let attempts: Vec<String> = flat
        .attempts
        .iter()
        .map(|a| {
            format!(
                "{{\"start\":\"{}\",\"converged\":{},\"stalled\":{},\"iterations\":{},\"newton_iterations\":{},\"max_distortion\":{},\"inverted\":{},\"seconds\":{}}}",
                method_name(a.start),
                a.report.converged,
                a.report.stalled,
                a.report.iterations,
                a.report.newton_iterations,
                json(a.report.max_distortion),
                a.report.inverted,
                a.report.seconds
            )
        })
        .collect();
    format!(
        "{},\"start\":\"{}\",\"starts\":[{}],\"setup_seconds\":{},\"lower_bound\":{},\"lower_bound_vertex\":{},\"infeasible\":{}}}",
        report.trim_end_matches('}'),
        method_name(flat.attempts[flat.kept].start),
        attempts.join(","),
        flat.setup_seconds,
        json(flat.lower_bound.bound),
        flat.lower_bound
            .vertex
            .map_or("null".to_string(), |v| v.to_string()),
        flat.infeasible()
    )
}

/// Why the bound was not met, naming the worst triangles (and their lines in the file, by
/// `line`).
fn unmet_message(r: &BoundedReport, k: f64, line: &dyn Fn(usize) -> Option<usize>) -> String {
    let why = if r.stalled {
        "neither alternating projections nor the Newton finish could lower it further: a local minimum, which does not prove the bound infeasible for this mesh and these handles"
    } else {
        "the iteration limit was reached; --iterations raises it"
    };
    format!(
        "the distortion bound {k} was not met after {} iterations ({} of them Newton): largest distortion {}, {} inverted triangles; worst (0-based): {} ({why})",
        r.iterations,
        r.newton_iterations,
        fmt_distortion(r.max_distortion),
        r.inverted,
        worst_faces(r, line)
    )
}

/// Two pictures side by side: the flattened mesh with a checkerboard texture (16 squares
/// across its longer side; flipped triangles red), and the 3D mesh with the same
/// checkerboard through the map (squares that stay square mean little distortion).
fn picture(
    positions: &[[f64; 3]],
    uv: &[[f64; 2]],
    faces: &[[u32; 3]],
    size: bdmorph::render::ImageSize,
) -> Result<Image, raster::RenderError> {
    let side = 512u32;
    let cell = side / 16;
    let mut rgba = Vec::with_capacity((side * side * 4) as usize);
    for y in 0..side {
        for x in 0..side {
            // The colours of `surface::render_checker`, so both pictures match.
            let c: [u8; 3] = if ((x / cell) + (y / cell)) % 2 == 0 {
                [60, 90, 150]
            } else {
                [235, 238, 245]
            };
            rgba.extend_from_slice(&[c[0], c[1], c[2], 255]);
        }
    }
    let texture = Image {
        width: side,
        height: side,
        rgba,
    };
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in uv {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-300);
    let corner_uv: Vec<[[f64; 2]; 3]> = faces
        .iter()
        .map(|f| {
            f.map(|v| {
                let p = uv.get(v as usize).copied().unwrap_or([0.0; 2]);
                [(p[0] - lo[0]) / span, (p[1] - lo[1]) / span]
            })
        })
        .collect();
    let drawing = Drawing {
        faces,
        corner_uv: Some(&corner_uv),
        texture: Some(&texture),
        face_colours: None,
        depth: None,
    };
    let view = Viewport::fit([uv]);
    let flat = raster::render(uv, &drawing, &view, size)?;
    let checker = surface::render_checker(positions, faces, uv, size)?;
    Ok(raster::strip(&[flat, checker], 2))
}

/// The handles: --pin's vertices, then --drag's and --fix's places turned into their
/// nearest vertices (said on stderr unless quiet). Two handles on one vertex are refused.
fn handles(args: &DeformArgs, mesh: &bdmorph::PlanarMesh) -> Result<Vec<(u32, [f64; 2])>, String> {
    let positions = &mesh.positions;
    let nearest = |p: [f64; 2]| -> u32 { mesh.nearest_vertex(p).unwrap_or(0) };
    let mut pins = args.pins.clone();
    let mut picked = Vec::new();
    for &(from, to) in &args.drags {
        let v = nearest(from);
        picked.push(format!("--drag {},{} is vertex {v}", from[0], from[1]));
        pins.push((v, to));
    }
    for &at in &args.fixes {
        let v = nearest(at);
        picked.push(format!("--fix {},{} is vertex {v}", at[0], at[1]));
        if let Some(&p) = positions.get(v as usize) {
            pins.push((v, p));
        }
    }
    let mut seen = std::collections::HashMap::new();
    for (i, &(v, _)) in pins.iter().enumerate() {
        if let Some(first) = seen.insert(v, i) {
            return Err(format!(
                "handles {first} and {i} (in the order --pin, --drag, --fix; 0-based) are both \
                 on vertex {v}: give each vertex one handle"
            ));
        }
    }
    if !picked.is_empty() && !args.quiet {
        eprintln!("bdmorph: {} (0-based)", picked.join(", "));
    }
    Ok(pins)
}

/// A pose, why its bound was not met (if it was not), and a one-line summary.
type Posed = (Vec<[f64; 2]>, Option<String>, String);

/// `deform --method kvf|sd|arap` through [`bdmorph::deform::Deformer`]: the pose, nothing unmet
/// (neither has a bound to miss), and a summary; `--stats` prints the method, time, largest
/// conformal distortion, flips and pin residual.
///
/// ARAP's hard pins go to their targets in one drag iterated to convergence. KVF moves its
/// handles there as a mouse would, in [`KVF_MOVES`] even moves of a few steps each, then
/// iterates at the targets to convergence: its steps follow the handles, and one jump of
/// the whole way would ask a single field for a large rotation. The symmetric Dirichlet
/// method (`sd`) is moved the same way.
fn deformer_pose(
    args: &DeformArgs,
    planar: &bdmorph::PlanarMesh,
    pins: &[(u32, [f64; 2])],
) -> Result<Posed, String> {
    use bdmorph::deform::{ArapOptions, Deformer, KvfOptions, PoseMethod as Method, SdOptions};
    let in_file = |e: bdmorph::deform::DeformError| format!("{}: {e}", args.mesh.display());
    let started = std::time::Instant::now();
    let limit = args.iterations.unwrap_or(1000);
    let method = match args.method {
        super::DeformMethod::Kvf => {
            let mut options = KvfOptions::default();
            if let Some(w) = args.pin_weight {
                options = options.with_weight(w);
            }
            Method::Kvf(options)
        }
        super::DeformMethod::Sd => {
            let mut options = SdOptions::default();
            if let Some(w) = args.pin_weight {
                options = options.with_weight(w);
            }
            Method::Sd(options)
        }
        _ => Method::Arap(
            ArapOptions::default()
                .with_iterations(limit)
                .with_tolerance(1e-10),
        ),
    };
    let name = method.name();
    let mut pose = Deformer::new(planar, method).map_err(in_file)?;
    let vertices: Vec<u32> = pins.iter().map(|p| p.0).collect();
    let targets: Vec<[f64; 2]> = pins.iter().map(|p| p.1).collect();
    pose.set_pins(&vertices).map_err(in_file)?;
    let mut iterations = 0;
    let mut report = None;
    if name == "kvf" || name == "sd" {
        let from: Vec<[f64; 2]> = vertices
            .iter()
            .map(|&v| planar.positions[v as usize])
            .collect();
        let mut moving = from.clone();
        for k in 1..=KVF_MOVES {
            let s = f64::from(k) / f64::from(KVF_MOVES);
            for ((m, a), b) in moving.iter_mut().zip(&from).zip(&targets) {
                *m = [a[0] + (b[0] - a[0]) * s, a[1] + (b[1] - a[1]) * s];
            }
            let r = pose.drag(&moving).map_err(in_file)?;
            iterations += r.iterations;
        }
        while iterations < limit {
            let r = pose.drag(&targets).map_err(in_file)?;
            iterations += r.iterations;
            let done = r.last_change <= 1e-10;
            report = Some(r);
            if done {
                break;
            }
        }
    }
    let report = match report {
        Some(r) => r,
        None => {
            let r = pose.drag(&targets).map_err(in_file)?;
            iterations += r.iterations;
            r
        }
    };
    let seconds = started.elapsed().as_secs_f64();
    if args.stats {
        let json = format!(
            "{{\"method\":\"{name}\",\"iterations\":{iterations},\"energy\":{:e},\"max_conformal_distortion\":{},\"flipped_triangles\":{},\"pin_residual\":{:e},\"last_change\":{:e},\"seconds\":{:e}}}",
            report.energy,
            json(report.max_distortion),
            report.flipped_triangles,
            report.pin_residual,
            report.last_change,
            seconds
        );
        writeln!(std::io::stdout().lock(), "{json}").map_err(|e| e.to_string())?;
    }
    if report.flipped_triangles > 0 && !args.quiet {
        eprintln!(
            "bdmorph: warning: {} flipped triangles ({name} does not prevent them; --method bounded does)",
            report.flipped_triangles
        );
    }
    if report.last_change > 1e-10 && !args.quiet {
        eprintln!(
            "bdmorph: warning: {name} stopped after {iterations} iterations still moving (last step {:.1e} of the size); raise --iterations",
            report.last_change
        );
    }
    let summary = format!(
        "{name}, {iterations} iterations in {seconds:.2} s; largest distortion {:.4}, {} flipped, handles met to {:.1e}",
        report.max_distortion, report.flipped_triangles, report.pin_residual
    );
    Ok((pose.positions().to_vec(), None, summary))
}

/// The moves `deform --method kvf` takes its handles to their targets in.
const KVF_MOVES: u32 = 10;

pub(super) fn deform(args: DeformArgs) -> Result<(), String> {
    let plan = match &args.output {
        Some(path) => Some(output::Plan::new(path, None, 1)?),
        None if args.stats => None,
        None => return Err("nothing to do: give -o OUT, --stats, or both".into()),
    };
    if plan.as_ref().is_some_and(|p| p.format.is_animation()) {
        return Err("deform writes one shape: use .obj, .svg or .png".into());
    }
    let (planar, texcoords, lines) = super::morph::read(&args.mesh)?;
    let mesh = bdmorph::SurfaceMesh {
        positions: planar.positions.iter().map(|p| [p[0], p[1], 0.0]).collect(),
        faces: planar.faces.clone(),
        texcoords: None,
    };
    let in_file = |e: bdmorph::param::ParamError| {
        bdmorph::Located::new(&args.mesh, &lines, &planar.faces, e).to_string()
    };
    if args.method == super::DeformMethod::Bounded && args.max_distortion.is_none() {
        return Err("--method bounded (the default) needs --max-distortion K".into());
    }
    let pins = handles(&args, &planar)?;
    let (uv, unmet, summary) = match args.method {
        super::DeformMethod::Arap | super::DeformMethod::Kvf | super::DeformMethod::Sd => {
            deformer_pose(&args, &planar, &pins)?
        }
        super::DeformMethod::Bounded => {
            let k = args.max_distortion.unwrap_or(f64::NAN);
            let iterations = args.iterations.unwrap_or(5000);
            let options = BoundedOptions::new(k).with_iterations(iterations);
            let mut bd = BoundedDistortion::new(&mesh, &pins, options).map_err(in_file)?;
            let mut uv = planar.positions.clone();
            let report = run_bounded(
                &mut bd,
                &mut uv,
                iterations,
                "deforming",
                args.quiet,
                false,
                &in_file,
            )?;
            if args.stats {
                // The bounded report, with the keys every method's --stats has.
                let all = bounded_json(&report);
                let flipped = report.inverted;
                let json = format!(
                    "{{\"method\":\"bounded\",\"max_conformal_distortion\":{},\"flipped_triangles\":{flipped},\"pin_residual\":{:e},{}",
                    json(report.max_distortion),
                    report.constraint_error,
                    &all[1..]
                );
                writeln!(std::io::stdout().lock(), "{json}").map_err(|e| e.to_string())?;
            }
            let line = |f| lines.face_line(f);
            let unmet = (!report.converged).then(|| unmet_message(&report, k, &line));
            let summary = format!(
                "{} iterations in {:.2} s; largest distortion {:.4}, {} inverted, constraints met to {:.1e}",
                report.iterations,
                report.seconds,
                report.max_distortion,
                report.inverted,
                report.constraint_error
            );
            (uv, unmet, summary)
        }
    };
    if let Some(plan) = plan {
        let title = format!("bdmorph deform: {}", args.mesh.display());
        let look = output::Look {
            faces: &planar.faces,
            texcoords: texcoords.as_ref(),
            texture: None,
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
            positions: uv,
            distortion: None,
        }];
        let files = output::render(&plan, &look, &frames, || {})?;
        output::write(&plan, &files)?;
        if !args.quiet {
            eprintln!("wrote {} ({summary})", plan.path.display());
        }
    }
    unmet.map_or(Ok(()), Err)
}
