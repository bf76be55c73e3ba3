//! Command-line parsing and the subcommands.

mod compile;
mod demo;
mod info;
mod morph;
mod output;

use std::path::PathBuf;

use bdmorph::render::ImageSize;
use clap::{Args, Parser, Subcommand};

pub use output::Format;

/// Bounded-distortion planar shape interpolation (BDMORPH).
///
/// Morphs between two planar triangle meshes with the same triangles, frame by frame, with no
/// flipped triangle and bounded distortion. Inputs are OBJ (2 or 3 coordinates per `v`, `vt`,
/// `f a`, `a/b`, `a/b/c`, `a//c`, negative indices, CRLF) or OFF. Faces must be triangles:
/// quads and polygons are refused, not triangulated.
#[derive(Parser, Debug)]
#[command(
    name = "bdmorph",
    version,
    about,
    long_about,
    after_help = "Run `bdmorph demo` to see it work without input files."
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Morph between two planar meshes with the same triangles.
    ///
    /// Inputs: OBJ or OFF files with z = 0 (or two coordinates per `v` line). Faces must be
    /// triangles (quads and polygons are refused, not triangulated), counter-clockwise,
    /// forming one disk; SOURCE and TARGET must list the same triangles.
    ///
    /// The output format follows the extension of -o (or --format): .obj, .svg or .png for
    /// one frame (--t) or for a directory of frame_NNNN files (--frames, -o DIR; .obj by
    /// default); .gif (an animated loop) or .html (a self-contained viewer with a slider)
    /// hold all frames in one file. With --texture, PNG, GIF and HTML output is textured
    /// through the source's `vt` (or its normalised positions when it has none), and OBJ
    /// frames carry the source's `vt`.
    ///
    /// Examples:
    ///   bdmorph morph man.obj man2.obj --t 0.5 -o half.obj
    ///   bdmorph morph man.obj man2.obj --frames 30 -o frames/
    ///   bdmorph morph man.obj man2.obj --frames 30 --format png --size 400x400 -o pngs/
    ///   bdmorph morph man.obj man2.obj --frames 60 -o morph.gif
    ///   bdmorph morph man.obj man2.obj --frames 60 --texture skin.png -o viewer.html
    ///   bdmorph morph man.obj man2.obj --frames 11 --stats
    ///   bdmorph morph man.obj man2.obj --program man.bdm --t 0.5 -o half.obj
    #[command(verbatim_doc_comment)]
    Morph(MorphArgs),
    /// Compile a mesh's triangles once into a program file, for `morph --program`.
    ///
    /// SOURCE is read and checked as `morph` does, and its connectivity is compiled into the
    /// solver's command streams, Hessian pattern and layout order. The file also records
    /// SOURCE's vertex and face counts and a hash of its faces: `morph --program` refuses it
    /// for a mesh with other triangles. The file is versioned and checksummed, and verified
    /// again when loaded.
    ///
    /// Example:
    ///   bdmorph compile man.obj -o man.bdm
    ///   bdmorph morph man.obj man2.obj --program man.bdm --frames 30 -o frames/
    #[command(verbatim_doc_comment)]
    Compile(CompileArgs),
    /// Describe a mesh file: counts, boundary loops, and whether it can be morphed.
    ///
    /// Example:
    ///   bdmorph info man.obj
    #[command(verbatim_doc_comment)]
    Info(InfoArgs),
    /// Morph a figure made in code and write a viewer, a GIF and a picture strip.
    ///
    /// A gingerbread figure is triangulated (constrained Delaunay, refined), posed waving by
    /// a smooth deformation, and morphed; the results go to DIR (default ./bdmorph-demo).
    ///
    /// Example:
    ///   bdmorph demo -o my-demo
    #[command(verbatim_doc_comment)]
    Demo(DemoArgs),
}

#[derive(Args, Debug)]
struct MorphArgs {
    /// The source mesh (t = 0).
    source: PathBuf,
    /// The target mesh (t = 1), with the source's triangles.
    target: PathBuf,
    /// One frame at this time in [0, 1].
    #[arg(long = "t", value_name = "T", conflicts_with = "frames")]
    t: Option<f64>,
    /// N frames at t = i / (N - 1).
    #[arg(long, value_name = "N")]
    frames: Option<usize>,
    /// Output file, or directory for per-frame files. Optional with --stats.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    /// Output format, instead of the extension of -o.
    #[arg(long, value_enum, value_name = "FORMAT")]
    format: Option<Format>,
    /// Picture size for PNG, GIF and SVG output, as WxH.
    #[arg(long, value_name = "WxH", default_value = "800x800")]
    size: ImageSize,
    /// An image (PNG or JPEG) to map onto the triangles in PNG, GIF and HTML output.
    #[arg(long, value_name = "IMAGE")]
    texture: Option<PathBuf>,
    /// Frames per second of GIF and HTML playback.
    #[arg(long, value_name = "FPS", default_value_t = 25)]
    fps: u32,
    /// Print one JSON object of statistics per frame on stdout.
    #[arg(long)]
    stats: bool,
    /// A program compiled for SOURCE by `bdmorph compile`, used instead of compiling again.
    #[arg(long, value_name = "PROGRAM")]
    program: Option<PathBuf>,
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
struct CompileArgs {
    /// The mesh to compile (OBJ or OFF): a counter-clockwise planar disk.
    source: PathBuf,
    /// The program file to write.
    #[arg(short = 'o', long = "output", value_name = "PROGRAM")]
    output: PathBuf,
    /// Print nothing but errors.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Args, Debug)]
struct InfoArgs {
    /// The mesh (OBJ or OFF).
    mesh: PathBuf,
}

#[derive(Args, Debug)]
struct DemoArgs {
    /// Directory to write the demo's files into.
    #[arg(
        short = 'o',
        long = "output",
        value_name = "DIR",
        default_value = "bdmorph-demo"
    )]
    output: PathBuf,
    /// Number of frames.
    #[arg(long, value_name = "N", default_value_t = 40)]
    frames: usize,
    /// Picture size of the GIF and of each picture of the strip, as WxH.
    #[arg(long, value_name = "WxH", default_value = "360x360")]
    size: ImageSize,
    /// Print nothing but errors.
    #[arg(short, long)]
    quiet: bool,
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<(), String> {
    match cli.command {
        Command::Morph(args) => morph::run(args),
        Command::Compile(args) => compile::run(args),
        Command::Info(args) => info::run(args),
        Command::Demo(args) => demo::run(args),
    }
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
