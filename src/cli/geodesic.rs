//! `bdmorph geodesic MESH --source V ... -o OUT`.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;
use std::time::Instant;

use bdmorph::geodesic::{
    descend, Anchor, Boundary, ExactGeodesics, GeodesicPath, HeatGeodesics, HeatOptions, TimeScale,
};
use bdmorph::render::{html, raster, surface, Image};

use super::{AnchorArg, BoundaryArg, GeodesicArgs, TimeScaleArg};

/// What `-o` asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Output {
    Text,
    Png,
    Html,
}

fn output_kind(path: &Path) -> Result<Output, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        None | Some("txt") => Ok(Output::Text),
        Some("png") => Ok(Output::Png),
        Some("html" | "htm") => Ok(Output::Html),
        Some(other) => Err(format!(
            "{}: unknown output extension '.{other}' (use .txt, .png or .html)",
            path.display()
        )),
    }
}

pub(super) fn run(args: GeodesicArgs) -> Result<(), String> {
    if let Some((a, b)) = args.path {
        return shortest_path(&args, a, b);
    }
    let each = !args.each_source.is_empty();
    let sources = if each {
        &args.each_source
    } else {
        &args.sources
    };
    if sources.is_empty() {
        return Err("give --source V (repeatable) or --each-source V1,V2,...".into());
    }
    if args.output.is_none() && !args.stats {
        return Err("nothing to do: give -o OUT, --stats, or both".into());
    }
    let kind = match &args.output {
        Some(path) => Some(output_kind(path)?),
        None => None,
    };
    let file = bdmorph::MeshFile::read(&args.mesh).map_err(|e| e.to_string())?;
    let mesh = &file.mesh;
    if let Some(&v) = sources
        .iter()
        .find(|&&v| v as usize >= mesh.positions.len())
    {
        return Err(format!(
            "{}: source vertex {v} does not exist (the mesh has {} vertices, numbered from 0)",
            args.mesh.display(),
            mesh.positions.len()
        ));
    }
    let options = heat_options(&args);
    let (fields, setup, query) = if args.exact {
        exact_fields(&args, &file, sources, each)?
    } else {
        heat_fields(&args, &file, options, sources, each)?
    };
    let (Some(path), Some(kind)) = (&args.output, kind) else {
        return Ok(());
    };
    let bytes = match kind {
        Output::Text => text(&fields).into_bytes(),
        Output::Png | Output::Html => {
            let pictures: Vec<Image> = fields
                .iter()
                .map(|f| surface::render_field(&mesh.positions, &mesh.faces, f, args.size))
                .collect::<Result<_, _>>()
                .map_err(|e| e.to_string())?;
            match kind {
                Output::Png => {
                    let sheet = raster::strip(&pictures, pictures.len().min(4));
                    raster::encode_png(&sheet).map_err(|e| e.to_string())?
                }
                _ => {
                    let mut pages = Vec::with_capacity(pictures.len());
                    let captions: Vec<String> = if each {
                        sources
                            .iter()
                            .map(|s| format!("distance from vertex {s}"))
                            .collect()
                    } else {
                        vec![format!(
                            "distance to the nearest of vertices {}",
                            list(sources)
                        )]
                    };
                    for (img, caption) in pictures.iter().zip(captions) {
                        pages.push((caption, raster::encode_png(img).map_err(|e| e.to_string())?));
                    }
                    let first_max = fields[0]
                        .iter()
                        .copied()
                        .filter(|d| d.is_finite())
                        .fold(0.0, f64::max);
                    let legend = format!(
                        "Colour: distance from 0 (dark purple) to the largest of each picture \
                         (yellow; {first_max:.4} in the first). Isolines every {} in the first \
                         picture. Grey: unreachable from the sources.",
                        surface::isoline_spacing(first_max)
                    );
                    html::picture_page(
                        &format!("bdmorph geodesic: {}", args.mesh.display()),
                        &legend,
                        &pages,
                    )
                    .into_bytes()
                }
            }
        }
    };
    bdmorph::io::write_bytes_atomic(path, &bytes).map_err(|e| e.to_string())?;
    if !args.quiet {
        eprintln!(
            "wrote {} ({} field{}; set-up {:.0} ms, {:.1} ms per field)",
            path.display(),
            fields.len(),
            if fields.len() == 1 { "" } else { "s" },
            setup * 1e3,
            query * 1e3 / fields.len() as f64
        );
    }
    Ok(())
}

/// The heat method's options from the command line.
fn heat_options(args: &GeodesicArgs) -> HeatOptions {
    HeatOptions::default()
        .with_time_factor(args.time_factor)
        .with_boundary(match args.boundary {
            BoundaryArg::Robin => Boundary::Robin,
            BoundaryArg::Neumann => Boundary::Neumann,
            BoundaryArg::Dirichlet => Boundary::Dirichlet,
            BoundaryArg::Average => Boundary::Average,
        })
        .with_absorption(args.absorption)
        .with_boundary_source_absorption(args.boundary_source_absorption)
        .with_absorb_at_cuts(args.absorb_at_cuts)
        .with_time_scale(match args.time_scale {
            TimeScaleArg::Spacing => TimeScale::Spacing,
            TimeScaleArg::MeanEdge => TimeScale::MeanEdge,
        })
        .with_anchor(match args.anchor {
            AnchorArg::OneRing => Anchor::OneRing,
            AnchorArg::Sources => Anchor::Sources,
        })
        .with_intrinsic_delaunay(!args.no_intrinsic_delaunay)
        .with_flip_boundary(!args.no_flip_boundary)
        .with_mollify(args.mollify)
        .with_refinement(args.refine, args.refine_budget)
}

/// The fields by the heat method, with the set-up and query times in seconds (and the
/// `--stats` line).
fn heat_fields(
    args: &GeodesicArgs,
    file: &bdmorph::MeshFile,
    options: HeatOptions,
    sources: &[u32],
    each: bool,
) -> Result<(Vec<Vec<f64>>, f64, f64), String> {
    let started = Instant::now();
    let mut heat =
        HeatGeodesics::new(&file.mesh, options).map_err(|e| file.locate(e).to_string())?;
    let setup = started.elapsed().as_secs_f64();
    if !args.quiet {
        if let Some(note) = boundary_source_note(&heat, sources, each) {
            eprintln!("{note}");
        }
    }
    let started = Instant::now();
    let fields: Vec<Vec<f64>> = if each {
        heat.distances_each(sources)
    } else {
        heat.distance(sources).map(|d| vec![d])
    }
    .map_err(|e| file.locate(e).to_string())?;
    let query = started.elapsed().as_secs_f64();
    if args.stats {
        let s = heat.stats();
        writeln!(
            std::io::stdout().lock(),
            "{{\"vertices\":{},\"faces\":{},\"flips\":{},\"has_boundary\":{},\"mollified\":{:e},\"time\":{:e},\"factor_nnz\":{},\"refined_vertices\":{},\"refined_min_angle\":{:.3},\"setup_seconds\":{:e},\"fields\":{},\"query_seconds\":{:e}}}",
            s.vertices, s.faces, s.flips, s.has_boundary, s.mollified, s.time, s.factor_nnz,
            s.refine.inserted + s.refine.split, s.refine.min_angle_degrees, setup, fields.len(), query
        )
        .map_err(|e| e.to_string())?;
    }
    Ok((fields, setup, query))
}

/// The exact fields, with the set-up and query times in seconds (and the `--stats` line).
fn exact_fields(
    args: &GeodesicArgs,
    file: &bdmorph::MeshFile,
    sources: &[u32],
    each: bool,
) -> Result<(Vec<Vec<f64>>, f64, f64), String> {
    let started = Instant::now();
    let mut exact = ExactGeodesics::new(&file.mesh).map_err(|e| file.locate(e).to_string())?;
    let setup = started.elapsed().as_secs_f64();
    let started = Instant::now();
    let (mut windows, mut held) = (0, 0);
    let mut fields = Vec::new();
    let groups: Vec<&[u32]> = if each {
        sources.chunks(1).collect()
    } else {
        vec![sources]
    };
    for group in groups {
        fields.push(
            exact
                .distance(group)
                .map_err(|e| file.locate(e).to_string())?,
        );
        windows += exact.stats().windows;
        held = held.max(exact.stats().held);
    }
    let query = started.elapsed().as_secs_f64();
    if args.stats {
        writeln!(
            std::io::stdout().lock(),
            "{{\"vertices\":{},\"faces\":{},\"exact\":true,\"windows\":{},\"windows_held\":{},\"setup_seconds\":{:e},\"fields\":{},\"query_seconds\":{:e}}}",
            file.mesh.positions.len(), file.mesh.faces.len(), windows, held, setup, fields.len(), query
        )
        .map_err(|e| e.to_string())?;
    }
    Ok((fields, setup, query))
}

/// `--path A,B`: the shortest path (exact with `--exact`, else down the heat method's
/// distance from A), written as text or an OBJ polyline.
fn shortest_path(args: &GeodesicArgs, a: u32, b: u32) -> Result<(), String> {
    let Some(out) = &args.output else {
        return Err("--path A,B writes the path: give -o OUT.txt or -o OUT.obj".into());
    };
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let obj = match ext.as_deref() {
        None | Some("txt") => false,
        Some("obj") => true,
        Some(other) => {
            return Err(format!(
                "{}: unknown path output extension '.{other}' (use .txt or .obj)",
                out.display()
            ))
        }
    };
    let file = bdmorph::MeshFile::read(&args.mesh).map_err(|e| e.to_string())?;
    let n = file.mesh.positions.len();
    if let Some(v) = [a, b].into_iter().find(|&v| v as usize >= n) {
        return Err(format!(
            "{}: vertex {v} does not exist (the mesh has {n} vertices, numbered from 0)",
            args.mesh.display()
        ));
    }
    let started = Instant::now();
    let (path, windows) = if args.exact {
        let mut exact = ExactGeodesics::new(&file.mesh).map_err(|e| file.locate(e).to_string())?;
        let path = exact.path(a, b).map_err(|e| file.locate(e).to_string())?;
        (path, Some(exact.stats().windows))
    } else {
        // Down the heat method's distance from A, starting at B.
        let mut heat = HeatGeodesics::new(&file.mesh, heat_options(args))
            .map_err(|e| file.locate(e).to_string())?;
        let d = heat
            .distance(&[a])
            .map_err(|e| file.locate(e).to_string())?;
        let path = descend(&file.mesh, &d, b).map_err(|e| file.locate(e).to_string())?;
        (path, None)
    };
    let seconds = started.elapsed().as_secs_f64();
    let text = if obj {
        path_obj(&path, a, b)
    } else {
        path_text(&path)
    };
    bdmorph::io::write_bytes_atomic(out, text.as_bytes()).map_err(|e| e.to_string())?;
    if args.stats {
        writeln!(
            std::io::stdout().lock(),
            "{{\"points\":{},\"length\":{:e},\"exact\":{},\"windows\":{},\"seconds\":{:e}}}",
            path.points.len(),
            path.length(),
            args.exact,
            windows.unwrap_or(0),
            seconds
        )
        .map_err(|e| e.to_string())?;
    }
    if !args.quiet {
        eprintln!(
            "wrote {} ({} path from vertex {a} to vertex {b}: length {}, {} points, {:.0} ms)",
            out.display(),
            if args.exact {
                "the exact shortest"
            } else {
                "the heat method's"
            },
            path.length(),
            path.points.len(),
            seconds * 1e3
        );
    }
    Ok(())
}

fn path_text(path: &GeodesicPath) -> String {
    let mut out = String::new();
    for p in &path.points {
        let [x, y, z] = p.position;
        let _ = writeln!(out, "{x} {y} {z}");
    }
    out
}

fn path_obj(path: &GeodesicPath, a: u32, b: u32) -> String {
    let mut out = format!(
        "# bdmorph geodesic --path: the shortest path from vertex {a} to vertex {b}, length {}\n",
        path.length()
    );
    for p in &path.points {
        let [x, y, z] = p.position;
        let _ = writeln!(out, "v {x} {y} {z}");
    }
    out.push('l');
    for i in 1..=path.points.len() {
        let _ = write!(out, " {i}");
    }
    out.push('\n');
    out
}

/// The note for `--boundary dirichlet|average` when a source lies on the boundary: those
/// fields are computed with Neumann conditions ([`Boundary::Dirichlet`]). `None` when it
/// does not apply.
fn boundary_source_note(heat: &HeatGeodesics, sources: &[u32], each: bool) -> Option<String> {
    let name = match heat.boundary() {
        Boundary::Dirichlet => "dirichlet",
        Boundary::Average => "average",
        _ => return None,
    };
    let mut on: Vec<u32> = Vec::new();
    for &s in sources {
        if heat.on_boundary(s) && !on.contains(&s) {
            on.push(s);
        }
    }
    if on.is_empty() {
        return None;
    }
    let which = if on.len() == 1 {
        format!("source vertex {} is", on[0])
    } else {
        format!("source vertices {} are", list(&on))
    };
    let fields = if !each {
        "the field is".to_string()
    } else if on.len() == 1 {
        "its field is".to_string()
    } else {
        "their fields are".to_string()
    };
    Some(format!(
        "note: {which} on the mesh's boundary, where --boundary {name} cannot hold (zero heat at \
         a source), so {fields} computed with --boundary neumann"
    ))
}

fn list(sources: &[u32]) -> String {
    sources
        .iter()
        .map(u32::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// One line per vertex, one column per field.
fn text(fields: &[Vec<f64>]) -> String {
    let n = fields.first().map_or(0, Vec::len);
    let mut out = String::with_capacity(n * fields.len() * 12);
    for v in 0..n {
        for (k, f) in fields.iter().enumerate() {
            if k > 0 {
                out.push(' ');
            }
            let d = f[v];
            if d.is_finite() {
                let _ = write!(out, "{d}");
            } else {
                out.push_str("inf");
            }
        }
        out.push('\n');
    }
    out
}
