//! Command-line parsing and the subcommands.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

use bdmorph::{generate, io, FrameStats, Morph, MorphOptions, PlanarMesh};
use clap::{Args, Parser, Subcommand};

/// Bounded-distortion planar shape interpolation (BDMORPH).
#[derive(Parser, Debug)]
#[command(name = "bdmorph", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Morph between two planar meshes with the same triangles.
    ///
    /// Inputs are OBJ or OFF files with z = 0 (or two coordinates per `v` line); faces must be
    /// triangles (polygons are refused), counter-clockwise, forming a disk.
    ///
    /// Examples:
    ///   bdmorph morph man.obj man2.obj --t 0.5 -o half.obj
    ///   bdmorph morph man.obj man2.obj --frames 30 -o frames/
    ///   bdmorph morph man.obj man2.obj --frames 30 --stats
    #[command(verbatim_doc_comment)]
    Morph(MorphArgs),
    /// Morph a shape pair made in code and write the frames (no input files needed).
    Demo(DemoArgs),
}

#[derive(Args, Debug)]
struct MorphArgs {
    /// The source mesh (t = 0).
    source: PathBuf,
    /// The target mesh (t = 1), with the source's triangles.
    target: PathBuf,
    /// One frame at this time in [0, 1]; `-o` names an OBJ file.
    #[arg(long = "t", value_name = "T", conflicts_with = "frames")]
    t: Option<f64>,
    /// N frames at t = i / (N - 1); `-o` names a directory for frame_0000.obj, ...
    #[arg(long, value_name = "N")]
    frames: Option<usize>,
    /// Output: an OBJ file with --t, a directory with --frames. Optional with --stats.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    /// Print one JSON object of statistics per frame on stdout.
    #[arg(long)]
    stats: bool,
    /// Newton's tolerance on the gradient norm.
    #[arg(long, value_name = "TOL", default_value_t = 1e-10)]
    tolerance: f64,
    /// Newton's iteration limit per frame.
    #[arg(long, value_name = "N", default_value_t = 50)]
    max_iterations: u32,
    /// Print nothing but errors (and --stats).
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Args, Debug)]
struct DemoArgs {
    /// Directory to write the demo's meshes and frames into.
    #[arg(
        short = 'o',
        long = "output",
        value_name = "DIR",
        default_value = "bdmorph-demo"
    )]
    output: PathBuf,
    /// Number of frames.
    #[arg(long, value_name = "N", default_value_t = 11)]
    frames: usize,
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<(), String> {
    match cli.command {
        Command::Morph(args) => morph(args),
        Command::Demo(args) => demo(args),
    }
}

fn read(path: &Path) -> Result<PlanarMesh, String> {
    let mesh = PlanarMesh::read(path).map_err(|e| e.to_string())?;
    mesh.validate()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(mesh)
}

/// The frame times: one `t`, or `n` evenly spaced over [0, 1].
fn times(t: Option<f64>, frames: Option<usize>) -> Result<Vec<f64>, String> {
    match (t, frames) {
        (Some(t), None) if (0.0..=1.0).contains(&t) => Ok(vec![t]),
        (Some(t), None) => Err(format!("--t {t} is outside [0, 1]")),
        (None, Some(n)) if n >= 2 => Ok((0..n).map(|i| i as f64 / (n - 1) as f64).collect()),
        (None, Some(n)) => Err(format!("--frames {n}: at least 2 frames are needed")),
        _ => Err("give either --t T or --frames N".into()),
    }
}

fn morph(args: MorphArgs) -> Result<(), String> {
    let times = times(args.t, args.frames)?;
    if args.output.is_none() && !args.stats {
        return Err("nothing to do: give -o OUT, --stats, or both".into());
    }
    if args.tolerance.is_nan() || args.tolerance <= 0.0 {
        return Err(format!("--tolerance {} must be positive", args.tolerance));
    }
    let source = read(&args.source)?;
    let target = read(&args.target)?;
    let options = MorphOptions::default()
        .with_tolerance(args.tolerance)
        .with_max_iterations(args.max_iterations);
    let morph = Morph::new(&source, &target, options).map_err(|e| {
        format!(
            "{} -> {}: {e}",
            args.source.display(),
            args.target.display()
        )
    })?;
    let header = format!(
        "bdmorph frame of {} -> {}",
        args.source.display(),
        args.target.display()
    );
    run_frames(
        morph,
        &times,
        args.output.as_deref(),
        args.t.is_some(),
        args.stats,
        args.quiet,
        &header,
    )
}

/// Computes every frame first (so a failure writes nothing), then writes them atomically.
fn run_frames(
    mut morph: Morph,
    times: &[f64],
    output: Option<&Path>,
    single_file: bool,
    stats: bool,
    quiet: bool,
    header: &str,
) -> Result<(), String> {
    let keep = output.is_some();
    let mut frames: Vec<(f64, Vec<[f64; 2]>)> = Vec::new();
    let progress = !quiet && std::io::stderr().is_terminal() && times.len() > 1;
    let mut stdout = std::io::stdout().lock();
    for (i, &t) in times.iter().enumerate() {
        let frame = morph.frame(t).map_err(|e| e.to_string())?;
        if stats {
            writeln!(stdout, "{}", frame.stats.to_json()).map_err(|e| e.to_string())?;
        }
        if progress {
            eprint!("\rframe {}/{}", i + 1, times.len());
        }
        warn_flips(&frame.stats, quiet);
        if keep {
            frames.push((t, frame.positions.to_vec()));
        }
    }
    if progress {
        eprintln!();
    }
    let Some(out) = output else {
        return Ok(());
    };
    let faces = morph.faces();
    if single_file {
        let (t, pos) = &frames[0];
        write_frame(out, pos, faces, header, *t)?;
        if !quiet {
            eprintln!("wrote {}", out.display());
        }
    } else {
        std::fs::create_dir_all(out)
            .map_err(|e| format!("{}: cannot create directory: {e}", out.display()))?;
        for (i, (t, pos)) in frames.iter().enumerate() {
            write_frame(
                &out.join(format!("frame_{i:04}.obj")),
                pos,
                faces,
                header,
                *t,
            )?;
        }
        if !quiet {
            eprintln!("wrote {} frames to {}", frames.len(), out.display());
        }
    }
    Ok(())
}

fn warn_flips(stats: &FrameStats, quiet: bool) {
    if stats.flipped_triangles > 0 && !quiet {
        eprintln!(
            "bdmorph: warning: t = {}: {} flipped triangles",
            stats.t, stats.flipped_triangles
        );
    }
}

fn write_frame(
    path: &Path,
    positions: &[[f64; 2]],
    faces: &[[u32; 3]],
    header: &str,
    t: f64,
) -> Result<(), String> {
    let t_line = format!("t = {t}");
    io::write_obj_2d(path, positions, faces, &[header, &t_line]).map_err(|e| e.to_string())
}

fn demo(args: DemoArgs) -> Result<(), String> {
    let times = times(None, Some(args.frames))?;
    let source = generate::disk(16, 0.2);
    let target = generate::twist(&generate::bend(&source, 0.7), 1.2);
    let out = &args.output;
    std::fs::create_dir_all(out)
        .map_err(|e| format!("{}: cannot create directory: {e}", out.display()))?;
    for (name, mesh) in [("source.obj", &source), ("target.obj", &target)] {
        io::write_obj_2d(
            &out.join(name),
            &mesh.positions,
            &mesh.faces,
            &["bdmorph demo"],
        )
        .map_err(|e| e.to_string())?;
    }
    let morph = Morph::new(&source, &target, MorphOptions::default()).map_err(|e| e.to_string())?;
    let st = morph.program().stats();
    println!(
        "bdmorph demo: a jittered disk ({} vertices, {} triangles) bent and twisted;",
        st.vertices, st.faces
    );
    println!(
        "compiled to {} unknowns, {:.1} bytes of iteration stream per triangle",
        st.unknowns, st.iteration_bytes_per_face
    );
    let mut morph = morph;
    let mut all = Vec::new();
    for &t in &times {
        let f = morph.frame(t).map_err(|e| e.to_string())?;
        println!(
            "  t = {:.3}: {} Newton iterations, gradient norm {:.1e}, {} flipped triangles",
            t, f.stats.newton_iterations, f.stats.gradient_norm, f.stats.flipped_triangles
        );
        all.push((t, f.positions.to_vec()));
    }
    for (i, (t, pos)) in all.iter().enumerate() {
        write_frame(
            &out.join(format!("frame_{i:04}.obj")),
            pos,
            &source.faces,
            "bdmorph demo",
            *t,
        )?;
    }
    println!(
        "wrote source.obj, target.obj and frame_0000.obj .. frame_{:04}.obj to {}",
        all.len() - 1,
        out.display()
    );
    Ok(())
}
