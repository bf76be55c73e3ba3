//! `bdmorph demo`: a gingerbread figure that waves.

use bdmorph::io::TexCoords;
use bdmorph::render::{raster, Image};
use bdmorph::{generate, io, Morph, MorphOptions, PlanarMesh};

use super::morph::progress_bar;
use super::output::{self, Format, Look, Plan};
use super::{times, DemoArgs};

/// Icing on gingerbread, drawn in texture space: `uv` is the figure's bounding box scaled to
/// the unit square (see [`PlanarMesh::normalized_texcoords`]), so shapes are placed in the
/// outline's own coordinates.
fn gingerbread_texture(size: u32, mesh: &PlanarMesh) -> Image {
    let (lo, hi) = mesh.bounds();
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let icing = [250u8, 250, 245, 255];
    let button = [210u8, 40, 60, 255];
    let mut rgba = Vec::with_capacity((size * size * 4) as usize);
    for row in 0..size {
        for col in 0..size {
            // Pixel centre to outline coordinates (row 0 is the top: v = 1).
            let u = (f64::from(col) + 0.5) / f64::from(size);
            let v = 1.0 - (f64::from(row) + 0.5) / f64::from(size);
            let (x, y) = (lo[0] + u * extent, lo[1] + v * extent);
            let near = |cx: f64, cy: f64, r: f64| (x - cx).hypot(y - cy) < r;
            // Warm brown with a soft vertical gradient and a little grain.
            let grain = ((x * 37.0).sin() * (y * 41.0).sin() * 8.0) as i32;
            let shade = (y * 10.0) as i32;
            let mut c = [
                (178 + shade + grain).clamp(0, 255) as u8,
                (104 + shade / 2 + grain).clamp(0, 255) as u8,
                (48 + grain / 2).clamp(0, 255) as u8,
                255,
            ];
            let smile = {
                let d = (x.hypot(y - 2.32) - 0.25).abs();
                d < 0.035 && y < 2.22
            };
            let eyes = near(-0.18, 2.42, 0.07) || near(0.18, 2.42, 0.07);
            let buttons = near(0.0, 1.15, 0.09) || near(0.0, 0.7, 0.09) || near(0.0, 0.25, 0.09);
            // Zigzag icing across the wrists and ankles.
            let zig = |s: f64| 0.06 * ((s * 30.0).sin());
            let wrist = (x.abs() - 1.3 - zig(y)).abs() < 0.035 && y > 1.0;
            let ankle = (y + 1.2 - zig(x)).abs() < 0.035;
            if buttons {
                c = button;
            } else if smile || eyes || wrist || ankle {
                c = icing;
            }
            rgba.extend_from_slice(&c);
        }
    }
    Image {
        width: size,
        height: size,
        rgba,
    }
}

/// The figure as a picture to start from (`bdmorph mesh figure.png`): the icing texture inside
/// the outline, transparent outside, anti-aliased (3 x 3 samples per pixel).
fn figure_picture(size: u32, mesh: &PlanarMesh) -> Image {
    let mut picture = gingerbread_texture(size, mesh);
    let outline = generate::figure_outline();
    let (lo, hi) = mesh.bounds();
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let inside = |x: f64, y: f64| {
        // Even-odd crossings of a ray to the right.
        let mut odd = false;
        for (i, a) in outline.iter().enumerate() {
            let b = outline[(i + 1) % outline.len()];
            if (a[1] > y) != (b[1] > y) && x < a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1]) {
                odd = !odd;
            }
        }
        odd
    };
    for row in 0..size {
        for col in 0..size {
            let mut hits = 0u32;
            for sy in 0..3 {
                for sx in 0..3 {
                    let u = (f64::from(col) + (f64::from(sx) + 0.5) / 3.0) / f64::from(size);
                    let v = 1.0 - (f64::from(row) + (f64::from(sy) + 0.5) / 3.0) / f64::from(size);
                    hits += u32::from(inside(lo[0] + u * extent, lo[1] + v * extent));
                }
            }
            let at = 4 * (row as usize * size as usize + col as usize) + 3;
            picture.rgba[at] = (hits * 255 / 9) as u8;
        }
    }
    picture
}

pub(super) fn run(args: DemoArgs) -> Result<(), String> {
    let times = times(None, Some(args.frames))?;
    let mp4 = Plan::new(
        &args.output.join("morph.mp4"),
        Some(Format::Mp4),
        times.len(),
    )?;
    if let Some(note) = mp4.check_size(args.size)? {
        if !args.quiet {
            eprintln!("bdmorph: note: {note}");
        }
    }
    let source = generate::figure(0.01);
    let target = generate::wave(&source, 1.0);
    let texcoords: TexCoords = source.normalized_texcoords();
    let corner_uv = texcoords.corner_uv();
    let texture = gingerbread_texture(512, &source);
    let mut morph =
        Morph::new(&source, &target, MorphOptions::default()).map_err(|e| e.to_string())?;
    let stats = morph.program().stats();
    let mut frames = Vec::with_capacity(times.len());
    let mut iterations = 0;
    let mut flips = 0;
    let bar = progress_bar(times.len(), args.quiet, "morphing");
    for (index, &t) in times.iter().enumerate() {
        let f = morph.frame(t).map_err(|e| e.to_string())?;
        iterations += f.stats.newton_iterations;
        flips += f.stats.flipped_triangles;
        frames.push(output::Frame {
            index,
            t,
            positions: f.positions.to_vec(),
            distortion: None,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();

    let out = &args.output;
    let title = "bdmorph demo: a gingerbread figure waves";
    let look = Look {
        faces: morph.faces(),
        texcoords: Some(&texcoords),
        texture: Some((&texture, &corner_uv)),
        size: args.size,
        fps: 25,
        title,
        background: bdmorph::render::Background::WHITE,
        crossfade: None,
        depth: None,
    };
    let mut files = Vec::new();
    for (name, format) in [
        ("viewer.html", Format::Html),
        ("morph.gif", Format::Gif),
        ("morph.mp4", Format::Mp4),
    ] {
        let plan = Plan::new(&out.join(name), Some(format), frames.len())?;
        files.extend(output::render(&plan, &look, &frames, || {})?);
    }
    // A strip of five pictures, t = 0, 0.25, ..., 1.
    let picks: Vec<&[[f64; 2]]> = (0..5)
        .map(|k| frames[k * (frames.len() - 1) / 4].positions.as_slice())
        .collect();
    let view = bdmorph::render::Viewport::fit(frames.iter().map(|f| f.positions.as_slice()));
    let drawing = bdmorph::render::Drawing {
        faces: morph.faces(),
        corner_uv: Some(&corner_uv),
        texture: Some(&texture),
        face_colours: None,
        depth: None,
    };
    let images: Vec<Image> = picks
        .iter()
        .map(|p| raster::render(p, &drawing, &view, args.size))
        .collect::<Result<_, _>>()
        .map_err(|e| e.to_string())?;
    let strip = raster::strip(&images, images.len());
    files.push((
        out.join("frames.png"),
        raster::encode_png(&strip).map_err(|e| e.to_string())?,
    ));
    files.push((
        out.join("figure.png"),
        raster::encode_png(&figure_picture(512, &source)).map_err(|e| e.to_string())?,
    ));
    for (name, mesh) in [("source.obj", &source), ("target.obj", &target)] {
        let mut bytes = Vec::new();
        io::format_obj_2d_textured(
            &mut bytes,
            &mesh.positions,
            &mesh.faces,
            Some(&texcoords),
            &[title],
        )
        .map_err(|e| e.to_string())?;
        files.push((out.join(name), bytes));
    }
    std::fs::create_dir_all(out)
        .map_err(|e| format!("{}: cannot create directory: {e}", out.display()))?;
    for (path, bytes) in &files {
        io::write_bytes_atomic(path, bytes).map_err(|e| e.to_string())?;
    }
    if !args.quiet {
        println!(
            "bdmorph demo: a gingerbread figure ({} vertices, {} triangles) waves.",
            stats.vertices, stats.faces
        );
        println!(
            "{} frames, {} Newton iterations in all, {} flipped triangles.",
            frames.len(),
            iterations,
            flips
        );
        for (path, _) in &files {
            println!("  {}", path.display());
        }
        println!("Open {} in a browser.", out.join("viewer.html").display());
    }
    Ok(())
}
