//! `bdmorph param MESH --method M [--iterations N] -o OUT`.

use std::fmt::Write as _;
use std::io::Write as _;

use bdmorph::param::{Method, ParamOptions, Parameterization};
use bdmorph::render::{raster, surface, Drawing, Image, Viewport};

use super::morph::progress_bar;
use super::ParamArgs;

fn method_name(m: Method) -> &'static str {
    match m {
        Method::Tutte => "tutte",
        Method::Lscm => "lscm",
        Method::Asap => "asap",
        Method::Arap => "arap",
        Method::SymmetricDirichlet => "sd",
        Method::Mips => "mips",
        Method::ArapNewton => "arap-newton",
    }
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
    let mesh = bdmorph::io::read_mesh(&args.mesh).map_err(|e| e.to_string())?;
    let mut options = ParamOptions::default();
    if let Some(n) = args.iterations {
        options = options.with_iterations(n);
    }
    let name = method_name(args.method);
    let mut p = Parameterization::new(&mesh, args.method, options)
        .map_err(|e| format!("{}: {e}", args.mesh.display()))?;
    let limit = args.iterations.unwrap_or(200) as usize;
    let iterative = !matches!(args.method, Method::Tutte | Method::Lscm);
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
        .map_err(|e| format!("{}: {e}", args.mesh.display()))?;
    bar.finish_and_clear();
    let e = p.energies();
    if args.stats {
        let mut out = std::io::stdout().lock();
        write!(out, "{lines}").map_err(|e| e.to_string())?;
        writeln!(
            out,
            "{{\"method\":\"{name}\",\"vertices\":{},\"faces\":{},\"iterations\":{},\"seconds\":{},\"symmetric_dirichlet\":{},\"arap\":{},\"mips\":{},\"flipped\":{}}}",
            mesh.positions.len(),
            mesh.faces.len(),
            report.iterations,
            report.seconds,
            json(e.symmetric_dirichlet),
            json(e.arap),
            json(e.mips),
            e.flipped
        )
        .map_err(|e| e.to_string())?;
    }
    let Some(path) = &args.output else {
        return Ok(());
    };
    let uv = p.uv();
    let bytes = if ext.as_deref() == Some("png") {
        let img = picture(&mesh.positions, uv, &mesh.faces, args.size);
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
            "wrote {} ({name}: {} iterations in {:.2} s; E_SD {:.5}, E_ARAP {:.5}, E_MIPS {:.5}, {} flipped)",
            path.display(),
            report.iterations,
            report.seconds,
            e.symmetric_dirichlet,
            e.arap,
            e.mips,
            e.flipped
        );
    }
    Ok(())
}

/// Two pictures side by side: the flattened mesh (triangles with edges, flipped ones red),
/// and the 3D mesh textured with a checkerboard through the map (squares that stay square
/// mean little distortion).
fn picture(
    positions: &[[f64; 3]],
    uv: &[[f64; 2]],
    faces: &[[u32; 3]],
    size: bdmorph::render::ImageSize,
) -> Image {
    let drawing = Drawing {
        faces,
        corner_uv: None,
        texture: None,
        face_colours: None,
    };
    let view = Viewport::fit([uv]);
    let flat = raster::render(uv, &drawing, &view, size);
    let checker = surface::render_checker(positions, faces, uv, size);
    raster::strip(&[flat, checker], 2)
}
