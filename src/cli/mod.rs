//! Command-line parsing and the subcommands.

mod blend;
mod compile;
mod demo;
mod export;
mod geodesic;
mod inbetween;
mod info;
mod layered;
mod mesh;
mod morph;
mod output;
mod param;

use std::path::PathBuf;

use bdmorph::render::{Background, ImageSize};
use bdmorph::Easing;
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
    /// Threads for rendering and encoding frames, solving stretches of t and large
    /// factorisations (default: every core; 1 = one thread throughout). Outputs agree across
    /// thread counts to the solver's tolerance, and are byte-identical for the same count.
    #[arg(long, global = true, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    threads: Option<u32>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Morph between two planar meshes with the same triangles, or along a path of several.
    ///
    /// Inputs: OBJ or OFF files with z = 0 (or two coordinates per `v` line). Faces must be
    /// triangles (quads and polygons are refused, not triangulated), counter-clockwise
    /// (--allow-inverted accepts a few clockwise ones in a keyframe). A mesh may have holes
    /// (filled with hidden triangles for the solve, never drawn or written) and several
    /// pieces (each morphs alone). Every mesh must have the first one's triangles, in any
    /// order, corners rotated or not; frames follow the first one's order.
    ///
    /// With more than two meshes (or with --easing or --durations) the frames walk a path
    /// through them in order, keyframe k reached at t = k / n (or after the first k
    /// durations), each segment eased as asked, passing exactly through every keyframe.
    ///
    /// The output format follows the extension of -o (or --format): .obj, .svg or .png for
    /// one frame (--t) or for a directory of frame_NNNN files (--frames, -o DIR; .obj by
    /// default); .gif (an animated loop), .mp4 (an H.264 video, encoded in-process by
    /// OpenH264; odd --size sides are padded with white to even, 16x16 to 3840x2160) or .html
    /// (a self-contained viewer with a slider) hold all frames in one file. With --texture,
    /// PNG, GIF, MP4 and HTML output is textured through the source's `vt` (or its normalised
    /// positions when it has none), and OBJ frames carry the source's `vt`.
    ///
    /// Examples:
    ///   bdmorph morph man.obj man2.obj --t 0.5 -o half.obj
    ///   bdmorph morph man.obj man2.obj --frames 30 -o frames/
    ///   bdmorph morph man.obj man2.obj --frames 30 --format png --size 400x400 -o pngs/
    ///   bdmorph morph man.obj man2.obj --frames 60 -o morph.gif
    ///   bdmorph morph man.obj man2.obj --frames 60 --fps 30 --size 1280x720 -o morph.mp4
    ///   bdmorph morph man.obj man2.obj --frames 60 --texture skin.png -o viewer.html
    ///   bdmorph morph man.obj man2.obj --frames 11 --stats
    ///   bdmorph morph man.obj man2.obj --program man.bdm --t 0.5 -o half.obj
    ///   bdmorph morph man.obj man2.obj --t 1.1 -o beyond.obj
    ///   bdmorph morph man.obj man2.obj man3.obj man.obj --frames 90 --easing ease-in-out -o loop.gif
    ///   bdmorph morph a.obj b.obj c.obj --frames 40 --durations 1,3 -o frames/
    ///   bdmorph morph man.obj man2.obj --frames 30 --color-by distortion -o viewer.html
    ///   bdmorph morph rest.obj drawn.obj --frames 30 --allow-inverted -o frames/
    #[command(verbatim_doc_comment)]
    Morph(MorphArgs),
    /// Blend any number of keyframes with weights: one frame.
    ///
    /// The frame's squared edge lengths are the weighted sums of the keyframes' (convex
    /// weights keep every triangle Euclidean), flattened with no flipped triangle; the anchor
    /// vertex and edge angle are blended likewise (angles unwrapped from the first
    /// keyframe's). Weights must sum to 1; slightly negative ones extrapolate while every
    /// triangle stays Euclidean, and otherwise the first triangle to break is named.
    /// Output formats as for `morph` with one frame (.obj, .svg, .png, .html).
    ///
    /// Examples:
    ///   bdmorph blend man.obj man2.obj man3.obj --weights 0.2,0.3,0.5 -o mix.obj
    ///   bdmorph blend man.obj man2.obj man3.obj --weights 0.5,0,0.5 --color-by distortion -o mix.png
    ///   bdmorph blend man.obj man2.obj man3.obj --weights 0.1,0.4,0.5 --stats
    #[command(verbatim_doc_comment)]
    Blend(BlendArgs),
    /// Geodesic distances on a 3D triangle mesh by the heat method, or exact ones, and paths.
    ///
    /// The mesh (OBJ or OFF, any triangle mesh: closed, with boundaries, several pieces) is
    /// prepared once (intrinsic Delaunay triangulation, cotan Laplacian, two Cholesky
    /// factorisations); each field is then two back-substitutions. Vertices are 0-based.
    ///
    /// --source V (repeatable): one field, the distance to the nearest source, written one
    /// value per line in vertex order. --each-source V1,V2,...: one field per source, one line
    /// per vertex with one column per source, separated by spaces. Vertices on pieces of the
    /// mesh without a source are `inf`. -o OUT.png draws the field(s) as a colour map with
    /// isolines (an orthographic view along the mesh's thinnest direction; one picture per
    /// field, side by side); -o OUT.html puts the same pictures in a page.
    ///
    /// Boundaries: --boundary robin (the default) lets the boundary absorb part of the heat,
    /// and works for sources anywhere. With --boundary dirichlet or average, a field with a
    /// source on the boundary is computed with neumann conditions instead (zero heat on the
    /// boundary would contradict that source), and a one-line note on stderr says so.
    ///
    /// --exact: exact polyhedral distances (window propagation) instead, with the same
    /// outputs. --path A,B: the shortest path from vertex A to vertex B, down the heat
    /// method's distance (exact with --exact), written to -o OUT.txt (one point "x y z" per
    /// line) or OUT.obj (the points and one polyline).
    ///
    /// Examples:
    ///   bdmorph geodesic camelhead.off --source 0 -o distance.txt
    ///   bdmorph geodesic camelhead.off --source 0 --source 500 -o nearest.png
    ///   bdmorph geodesic sphere.obj --each-source 0,10,20 -o fields.txt
    ///   bdmorph geodesic bunny.off --source 0 --stats -o bunny.html
    ///   bdmorph geodesic camelhead.off --exact --source 0 -o exact.txt
    ///   bdmorph geodesic camelhead.off --path 0,5000 --exact -o path.obj
    #[command(verbatim_doc_comment)]
    Geodesic(GeodesicArgs),
    /// Flatten a disk-topology 3D mesh into the plane (a parameterisation).
    ///
    /// Methods: tutte (uniform weights, boundary on a circle; never flips), lscm (least-
    /// squares conformal, free boundary), asap and arap (local/global iterations from Tutte),
    /// sd, mips and arap-newton (projected Newton on the symmetric Dirichlet, MIPS or ARAP
    /// energy from Tutte; never flips a triangle). The mesh must be a manifold disk (one
    /// boundary loop); closed meshes, meshes with holes and non-manifold ones are refused.
    ///
    /// -o OUT.obj writes the input's `v` lines, one `vt` per vertex (the parameter-plane
    /// coordinates) and the faces as `f a/a b/b c/c`; -o OUT.png draws the flattened mesh
    /// with a checkerboard texture (flipped triangles red) beside the 3D mesh with the same
    /// checkerboard through the map.
    ///
    /// --method bounded pushes the starting map (--init tutte or lscm) under the bound
    /// --max-distortion K on every triangle's conformal distortion, without inverted
    /// triangles, keeping the --pin constraints (Kovalsky et al. 2015); when the bound cannot
    /// be met it says so, names the worst triangles and exits with 1 (the map found is still
    /// written).
    ///
    /// Examples:
    ///   bdmorph param camelhead.off --method sd -o camel_uv.obj
    ///   bdmorph param camelhead.off --method arap --iterations 100 -o camel_arap.png
    ///   bdmorph param camelhead.off --method mips --stats
    ///   bdmorph param camelhead.off --method bounded --max-distortion 3 -o camel_k3.obj
    #[command(verbatim_doc_comment)]
    Param(ParamArgs),
    /// Deform a planar mesh by handles: bounded distortion (the default), ARAP or KVF.
    ///
    /// The vertices given by --pin move to their targets (--drag X,Y:TX,TY moves the vertex
    /// nearest (X, Y) to (TX, TY), and --fix X,Y keeps the vertex nearest (X, Y) where it
    /// is: handles by place, for meshes whose vertex numbers nobody knows, such as those made
    /// by `bdmorph mesh`); the rest follows with a flip-free
    /// map whose conformal distortion (largest over smallest singular value of each
    /// triangle's affine map) is at most --max-distortion, by the large-scale bounded
    /// distortion method (Kovalsky et al. 2015) from the identity. The result can be a
    /// morphing target: it has the input's triangles. When the bound cannot be met with
    /// those pins, the command says so and names the worst triangles (exit code 1; the
    /// closest map found is still written).
    ///
    /// --method arap poses as rigidly as possible instead (hard pins, local/global iterations
    /// on a prefactored Laplacian; no distortion bound, flipped triangles reported), and
    /// --method kvf by as-Killing-as-possible vector fields, the original BDMORPH editor's
    /// deformation (soft handles, --pin-weight; flipped triangles reported), and --method sd
    /// by the symmetric Dirichlet energy (soft handles; no triangle flips or is crushed, a
    /// handle stops short where following it would crush the mesh: the pin residual says how
    /// far).
    ///
    /// --stats prints one JSON object: method, iterations, largest conformal distortion,
    /// flipped triangles, pin residual, seconds (and, for bounded, its full report).
    ///
    /// -o OUT.obj writes `v x y 0` lines and the input's faces; .svg and .png draw it.
    ///
    /// Examples:
    ///   bdmorph deform man.obj --pin 0:0,0 --pin 120:1.5,2 --max-distortion 3 -o posed.obj
    ///   bdmorph deform figure.obj --fix 180,40 --drag 330,340:380,470 --max-distortion 4 -o wave.obj
    ///   bdmorph deform figure.obj --method arap --fix 180,40 --drag 330,340:380,470 -o wave.obj
    ///   bdmorph deform figure.obj --method kvf --fix 180,40 --drag 330,340:380,470 -o wave.obj
    #[command(verbatim_doc_comment)]
    Deform(DeformArgs),
    /// Mesh a picture's subject, or an outline, into triangles ready to morph.
    ///
    /// INPUT is a picture (PNG or JPEG) or an outline (Triangle's .poly, or SVG: <path>,
    /// <polygon>, <polyline>, <rect>, <circle>, <ellipse>, with transforms; curves flattened
    /// to --tolerance). A picture's subject is its opaque pixels; for a picture without
    /// transparency give --background COLOR (#rrggbb, a name, or auto for the colour of the
    /// picture's border) or --threshold L (the pixels darker than L). Its outlines are traced,
    /// simplified to --tolerance pixels (outlines smaller than that are left out; without
    /// --tolerance, raised from 1 until the outline takes at most a fifth of --vertices),
    /// specks left out (pieces under 1% of the largest piece's area, unless --keep-specks),
    /// and triangulated with their holes, however many pieces: a constrained Delaunay
    /// triangulation refined until no angle is below --min-angle (except at sharper corners
    /// of the outline itself) and about --vertices vertices are placed (a note says why
    /// when the count is missed by more than 10%).
    ///
    /// -o OUT.obj writes `v x y 0` lines (y up, counter-clockwise triangles) and one `vt` per
    /// vertex. From a picture, positions are in pixels from its bottom-left corner and
    /// vt = (x / width, y / height): the picture textures the mesh upright (`morph --texture
    /// picture.png` with no further flags). From an outline, vt spans the SVG's viewBox (or
    /// width and height), else the outline's bounding box as a square. .svg or .png draw the
    /// mesh (a picture's mesh textured by it).
    ///
    /// A layered picture (.psd or .psb: RGB or greyscale, 8, 16 or 32 bits; .ora: OpenRaster,
    /// as Krita, GIMP and MyPaint write it; at most 256 layers with pixels) makes a character in parts: every visible layer a part (groups flattened,
    /// hidden layers skipped with a note) meshed from its own transparency, the vertices shared
    /// out by area, stacked in the file's order, with a joint wherever two layers overlap.
    /// -o OUT.json writes a studio project (its picture: the layered file); -o OUT.obj writes
    /// one group and one material per part, OUT.mtl and the parts' texture OUT.png beside it.
    ///
    /// Errors (nothing is written): a picture that is fully transparent or holds no subject,
    /// outlines that cross or touch themselves or each other (the segments and where), an
    /// outline too small for the tolerance, a .poly segment naming a missing vertex.
    ///
    /// Examples:
    ///   bdmorph mesh cat.png -o cat.obj
    ///   bdmorph mesh cat.png --vertices 5000 --tolerance 0.5 -o cat.obj
    ///   bdmorph mesh scan.jpg --background white -o scan.obj
    ///   bdmorph mesh drawing.png --threshold 0.5 --stats -o drawing.obj
    ///   bdmorph mesh logo.svg --vertices 3000 -o logo.obj
    ///   bdmorph mesh part.poly --min-angle 30 -o part.obj
    ///   bdmorph mesh character.psd -o character.json     (a character in parts, for the studio)
    ///   bdmorph mesh character.ora -o character.obj      (a group and a material per part)
    ///   then, with vertex numbers read from cat.obj:
    ///   bdmorph deform cat.obj --pin 12:40,300 --pin 815:420,360 --max-distortion 3 -o posed.obj
    ///   bdmorph morph cat.obj posed.obj --frames 30 --texture cat.png -o cat.gif
    #[command(verbatim_doc_comment)]
    Mesh(MeshArgs),
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
    /// In-betweens of two drawings of one subject (pictures with transparency), or a path
    /// through several.
    ///
    /// Drawing A is meshed, and the same triangles are laid over drawing B without a flipped
    /// triangle: A's outline goes onto B's by a correspondence found automatically (a rigid
    /// alignment, then a warping that matches corners and turning), the inside follows by
    /// as-rigid-as-possible posing, untangling and a bounded-distortion mapping. BDMORPH
    /// then morphs A's layout into B's, each frame textured by a cross-fade of the two
    /// pictures (--crossfade). The drawings must have the same pieces and holes. With more
    /// than two (A B C ...), one mesh of A is laid over each, and the frames walk through
    /// them in order, drawing k at t = k / (n - 1).
    ///
    /// --match AX,AY:BX,BY (repeatable) says that point (AX, AY) of drawing A becomes point
    /// (BX, BY) of drawing B, in pixels from each picture's top-left corner: on both outlines
    /// it pins the correspondence there; inside both drawings it pins a vertex. A pair that
    /// no flip-free mesh can meet is let go with a warning naming it.
    ///
    /// Outputs and options as for `morph`: .obj frames in a directory (the default, with A's
    /// texture coordinates), .png frames, .gif, .mp4, .apng, .webp; --size, --fps,
    /// --background transparent, --easing, --color-by distortion, --stats (a first line for
    /// the compatible mesh, then one per frame).
    ///
    /// Examples:
    ///   bdmorph inbetween a.png b.png --frames 24 -o walk.mp4
    ///   bdmorph inbetween a.png b.png --match 120,80:160,40 --frames 12 -o frames/
    ///   bdmorph inbetween a.png b.png --frames 30 --background transparent -o walk.webp
    ///   bdmorph inbetween a.png b.png --t 0.5 -o half.png
    ///   bdmorph inbetween a.png b.png c.png --frames 36 -o path.gif
    ///   bdmorph inbetween scan1.jpg scan2.jpg --paper white --frames 24 -o walk.mp4
    #[command(verbatim_doc_comment)]
    Inbetween(InbetweenArgs),
    /// Describe a mesh file: counts, boundary loops, and whether it can be morphed.
    ///
    /// Example:
    ///   bdmorph info man.obj
    #[command(verbatim_doc_comment)]
    Info(InfoArgs),
    /// Morph a figure made in code and write a viewer, a GIF, an MP4 and a picture strip.
    ///
    /// A gingerbread figure is triangulated (constrained Delaunay, refined), posed waving by
    /// a smooth deformation, and morphed; the results go to DIR (default ./bdmorph-demo).
    ///
    /// Example:
    ///   bdmorph demo -o my-demo
    #[command(verbatim_doc_comment)]
    Demo(DemoArgs),
    /// The studio: an animation editor in the browser, on the live engine.
    ///
    /// Serves the editor on 127.0.0.1 (never another interface) and prints exactly one line
    /// on stdout, the URL to open (it carries this run's token; nothing is served without
    /// it), then logs on stderr until Ctrl-C. FILE is a picture (meshed by its subject and
    /// drawn on the mesh; a picture without transparency is told from its background, by
    /// default the colour of its border), a mesh (OBJ/OFF, drawn with the picture of the same
    /// name beside it or --texture) or a project the studio saved; without one the studio
    /// starts from the sample figure. Saves and exports go into FILE's folder (or the current
    /// one), by plain file names. Unsaved changes are kept in that folder's .bdmorph-studio/
    /// (every 2 seconds and at Ctrl-C) and offered by the next studio there if this one did
    /// not stop cleanly; a restart on the same folder reuses the port and the page's token,
    /// so an open page reconnects by itself.
    ///
    /// Examples:
    ///   bdmorph studio
    ///   bdmorph studio figure.png --open
    ///   bdmorph studio scan.jpg --background white --threshold 0.3
    ///   bdmorph studio character.obj --texture character-skin.png
    ///   bdmorph studio wave.json --port 8300
    #[command(verbatim_doc_comment)]
    Studio(StudioArgs),
    /// Export a project the studio saved: its animation as the studio's page exports it.
    ///
    /// The frames are the animation at the project's frame rate (its duration times the
    /// rate, plus one), or --frames of them; --range keeps some. Pictures are framed on the
    /// subject, in its own aspect (640 pixels on the longer side) unless --size says
    /// otherwise, drawn with the project's picture and in the draw order painted on it, on
    /// white, a colour or transparency (--background).
    ///
    /// The format follows the ending of -o (or --format): .gif, .mp4 (opaque), .apng or
    /// .webp (animated, with transparency), .png with --sheet (a sprite sheet, and a .json
    /// beside it with each frame's rectangle, the frame size and the fps, as game engines'
    /// sprite-sheet importers read it), .html (a viewer), or a folder for PNG frames
    /// (--format obj for OBJ frames).
    ///
    /// Examples:
    ///   bdmorph export wave.json -o wave.mp4
    ///   bdmorph export wave.json -o wave.webp --background transparent
    ///   bdmorph export wave.json -o wave.apng --background transparent --size 800x600
    ///   bdmorph export wave.json -o sheet.png --sheet --background transparent --size 256x256
    ///   bdmorph export wave.json -o frames/ --background transparent --range 0-24
    ///   bdmorph export wave.json -o loop.gif --loop-range
    ///   bdmorph export wave.json -o wave.gif --background '#202020'
    #[command(verbatim_doc_comment)]
    Export(ExportArgs),
    /// Render a saved project's animation: the same as `export` (any project, of one mesh or
    /// of a character in parts), for batch rendering without the page.
    ///
    /// Examples:
    ///   bdmorph render character.json -o walk.mp4
    ///   bdmorph render character.json -o walk.apng --background transparent
    ///   bdmorph render character.json -o frames/
    #[command(verbatim_doc_comment)]
    Render(ExportArgs),
}

#[derive(Args, Debug)]
struct ExportArgs {
    /// The project (.json) the studio saved; its picture is read from beside it.
    #[arg(value_name = "PROJECT")]
    project: PathBuf,
    /// The file (or folder, for frames) to write.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: PathBuf,
    /// The format, instead of the ending of -o: gif, mp4, apng, webp, sheet, frames
    /// (PNG), png (a strip of five frames coloured by distortion), html or obj.
    #[arg(long, value_name = "FORMAT")]
    format: Option<String>,
    /// A sprite sheet: -o names its PNG; its JSON goes beside it.
    #[arg(long)]
    sheet: bool,
    /// Picture size, WxH (default: the subject's aspect, 640 pixels on the longer side).
    #[arg(long, value_name = "WxH", allow_hyphen_values = true)]
    size: Option<ImageSize>,
    /// The animation sampled at N frames (default: duration x fps + 1).
    #[arg(long, value_name = "N")]
    frames: Option<usize>,
    /// The frames kept, FIRST-LAST (0-based, inclusive), for example 0-24 (default: the
    /// whole animation, to the scene's length when the project sets one).
    #[arg(long, value_name = "FIRST-LAST", value_parser = export::parse_range)]
    range: Option<[usize; 2]>,
    /// Only the project's loop range (the frames from its start to its end), as the studio's
    /// Export dialog offers it.
    #[arg(long, conflicts_with = "range")]
    loop_range: bool,
    /// transparent (APNG, WebP, sprite sheets, PNG frames), or a colour: #rrggbb, #rgb,
    /// white, black, grey, ... (default white).
    #[arg(long, value_name = "transparent|COLOR", allow_hyphen_values = true)]
    background: Option<Background>,
    /// Print nothing but errors.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Args, Debug)]
struct MorphArgs {
    /// The keyframes: SOURCE (t = 0) and TARGET (t = 1), or K0 K1 ... Kn for a path through
    /// them (keyframe k at t = k / n), all with the first one's triangles.
    #[arg(value_name = "MESH", num_args = 2.., required = true)]
    meshes: Vec<PathBuf>,
    /// One frame at this time: in [0, 1] for a path; for two meshes slightly outside works
    /// too (extrapolation) while the extrapolated edge lengths stay Euclidean.
    #[arg(
        long = "t",
        value_name = "T",
        conflicts_with = "frames",
        allow_hyphen_values = true
    )]
    t: Option<f64>,
    /// N frames at t = i / (N - 1).
    #[arg(long, value_name = "N")]
    frames: Option<usize>,
    /// Relative durations of the path's segments, one per pair of consecutive meshes
    /// (default: all equal).
    #[arg(long, value_name = "D1,D2,...", value_delimiter = ',')]
    durations: Vec<f64>,
    /// Easing of the path's segments: linear, ease-in-out or cubic-bezier(x1,y1,x2,y2).
    /// Once for every segment, or once per segment in order.
    #[arg(long, value_name = "EASING", value_parser = parse_easing)]
    easing: Vec<Easing>,
    #[command(flatten)]
    out: OutputArgs,
    #[command(flatten)]
    solver: SolverArgs,
}

#[derive(Args, Debug)]
struct InbetweenArgs {
    /// The drawings: A (t = 0) and B (t = 1), pictures with transparency (PNG) of one
    /// subject with the same pieces and holes; or A B C ... for a path through them (drawing
    /// k at t = k / (n - 1)).
    #[arg(value_name = "DRAWING", num_args = 2.., required = true)]
    drawings: Vec<PathBuf>,
    /// A point of A and the point of B it becomes, AX,AY:BX,BY in pixels from each picture's
    /// top-left corner (repeatable).
    #[arg(long = "match", value_name = "AX,AY:BX,BY", value_parser = parse_match)]
    matches: Vec<bdmorph::inbetween::Match>,
    /// One frame at this time in [0, 1].
    #[arg(
        long = "t",
        value_name = "T",
        conflicts_with = "frames",
        allow_hyphen_values = true
    )]
    t: Option<f64>,
    /// N frames at t = i / (N - 1).
    #[arg(long, value_name = "N")]
    frames: Option<usize>,
    /// Easing of t (of each segment of a path): linear, ease-in-out or
    /// cubic-bezier(x1,y1,x2,y2).
    #[arg(long, value_name = "EASING", value_parser = parse_easing)]
    easing: Option<Easing>,
    /// How the pictures cross-fade along t: smooth (3t² - 2t³), linear or cut (A's picture
    /// to t = 0.5, then B's).
    #[arg(long, value_name = "CURVE", default_value = "smooth")]
    crossfade: bdmorph::inbetween::Crossfade,
    /// How the frames between the drawings are made, on the same compatible mesh: bdmorph
    /// (bounded distortion, the default), arap (as-rigid-as-possible interpolation of each
    /// triangle's rotation and stretch) or linear (every vertex on a straight line).
    #[arg(long, value_name = "METHOD", value_enum, default_value = "bdmorph")]
    method: InbetweenMethod,
    /// About how many vertices the mesh has.
    #[arg(long, value_name = "N", default_value_t = bdmorph::meshing::DEFAULT_VERTICES)]
    vertices: usize,
    /// The smallest angle of A's triangles, in degrees (at most 33).
    #[arg(long, value_name = "DEG", default_value_t = bdmorph::meshing::DEFAULT_MIN_ANGLE)]
    min_angle: f64,
    /// For opaque drawings (scans): the colour around the subject, as `mesh --background`
    /// takes it (#rrggbb, #rgb, white, ..., or auto: the picture's border). Without it the
    /// subject is the pictures' opaque part.
    #[arg(long, value_name = "COLOR", value_parser = parse_background)]
    paper: Option<bdmorph::meshing::Background>,
    /// In [0, 1): the opacity above which a pixel is the subject (default 0.5); with
    /// --paper, the colour difference (default 0.2).
    #[arg(long, value_name = "L")]
    threshold: Option<f64>,
    #[command(flatten)]
    out: OutputArgs,
    #[command(flatten)]
    solver: SolverArgs,
}

/// `AX,AY:BX,BY`: a point pair.
fn parse_match(text: &str) -> Result<bdmorph::inbetween::Match, String> {
    let (a, b) = text
        .split_once(':')
        .ok_or_else(|| format!("'{text}': give a pair as AX,AY:BX,BY"))?;
    let point = |s: &str| -> Result<[f64; 2], String> {
        let (x, y) = s
            .split_once(',')
            .ok_or_else(|| format!("'{s}': give a point as X,Y"))?;
        let number = |v: &str| {
            v.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("'{v}' is not a number of pixels"))
        };
        Ok([number(x)?, number(y)?])
    };
    Ok(bdmorph::inbetween::Match {
        a: point(a)?,
        b: point(b)?,
    })
}

#[derive(Args, Debug)]
struct BlendArgs {
    /// The keyframes K0 K1 ..., all with K0's triangles.
    #[arg(value_name = "MESH", num_args = 2.., required = true)]
    meshes: Vec<PathBuf>,
    /// One weight per keyframe, summing to 1 (slightly negative ones extrapolate).
    #[arg(
        long,
        value_name = "W0,W1,...",
        value_delimiter = ',',
        required = true,
        allow_hyphen_values = true
    )]
    weights: Vec<f64>,
    #[command(flatten)]
    out: OutputArgs,
    #[command(flatten)]
    solver: SolverArgs,
}

/// Where and how frames are written, shared by `morph` and `blend`.
#[derive(Args, Debug)]
struct OutputArgs {
    /// Output file, or directory for per-frame files. Optional with --stats.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    /// Output format, instead of the extension of -o.
    #[arg(long, value_enum, value_name = "FORMAT")]
    format: Option<Format>,
    /// Picture size for PNG, GIF, MP4 and SVG output, as WxH (MP4 pads odd sides to even).
    #[arg(
        long,
        value_name = "WxH",
        default_value = "800x800",
        allow_hyphen_values = true
    )]
    size: ImageSize,
    /// An image (PNG or JPEG) to map onto the triangles in PNG, GIF, MP4 and HTML output.
    #[arg(long, value_name = "IMAGE")]
    texture: Option<PathBuf>,
    /// Colour the triangles of PNG, GIF, MP4, SVG and HTML output by their conformal distortion
    /// from the first mesh (viridis, log scale from 1 to the largest over all frames).
    #[arg(
        long = "color-by",
        alias = "colour-by",
        value_enum,
        value_name = "WHAT"
    )]
    color_by: Option<ColorBy>,
    /// Frames per second of GIF, MP4, APNG, WebP and HTML playback (and of a sprite sheet's
    /// JSON).
    #[arg(long, value_name = "FPS", default_value_t = 25)]
    fps: u32,
    /// What is behind the subject in PNG, APNG, WebP, GIF and MP4 pictures: transparent
    /// (PNG, APNG, WebP) or a colour: #rrggbb, #rgb, white, black, grey, ... (default white).
    #[arg(long, value_name = "transparent|COLOR", allow_hyphen_values = true)]
    background: Option<Background>,
    /// With --frames and -o NAME.png: every frame in one sprite sheet, and NAME.json beside it
    /// with each frame's rectangle, the frame size and the fps.
    #[arg(long)]
    sheet: bool,
    /// The draw order where a pose overlaps itself: a text file of levels (-9 to 9, higher in
    /// front), one per face of the first mesh or one per vertex (a face takes its highest
    /// corner's).
    #[arg(long, value_name = "FILE")]
    depth: Option<PathBuf>,
    /// Print one JSON object of statistics per frame on stdout.
    #[arg(long)]
    stats: bool,
    /// Print nothing but errors (and --stats).
    #[arg(short, long)]
    quiet: bool,
}

/// How `inbetween` makes the frames between the drawings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum InbetweenMethod {
    /// Bounded-distortion interpolation (BDMORPH).
    Bdmorph,
    /// As-rigid-as-possible interpolation (Alexa, Cohen-Or and Levin 2000).
    Arap,
    /// Straight lines.
    Linear,
}

/// What to colour triangles by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum ColorBy {
    /// The conformal distortion from the first mesh.
    Distortion,
}

/// The solver's settings, shared by `morph` and `blend`.
#[derive(Args, Debug)]
struct SolverArgs {
    /// A program compiled for the first mesh by `bdmorph compile`, used instead of compiling
    /// again.
    #[arg(long, value_name = "PROGRAM")]
    program: Option<PathBuf>,
    /// Newton's tolerance on the gradient norm.
    #[arg(long, value_name = "TOL", default_value_t = 1e-10)]
    tolerance: f64,
    /// Newton's iteration limit per frame.
    #[arg(long, value_name = "N", default_value_t = 50)]
    max_iterations: u32,
    /// Accept keyframes with a few inverted (clockwise) triangles, as a pose drawn by hand
    /// may have: their side lengths are morphed as they are, and at such a keyframe the
    /// frame is the flat shape nearest them, not the pose (a note on stderr, and
    /// `keyframe_deviation` in --stats, say how far). Without it they are refused, listed.
    #[arg(long)]
    allow_inverted: bool,
    /// How each frame is placed: `anchor` (by a vertex near the middle and one of its edges,
    /// the original program's; the default of `morph` and `blend`) or `fit` (by the rotation,
    /// scale and translation that best fit the keyframes, the vertices that hold still between
    /// them weighing most, so that they hold still in between and the frame does not swell;
    /// the default of `inbetween`). Keyframes are reached exactly either way.
    #[arg(long, value_name = "HOW", value_parser = parse_placement)]
    placement: Option<bdmorph::Placement>,
}

fn parse_placement(text: &str) -> Result<bdmorph::Placement, String> {
    text.parse()
}

fn parse_easing(text: &str) -> Result<Easing, String> {
    text.parse()
        .map_err(|e: bdmorph::path::EasingError| e.to_string())
}

#[derive(Args, Debug)]
struct GeodesicArgs {
    /// The mesh (OBJ or OFF).
    mesh: PathBuf,
    /// A source vertex (0-based); give several for the distance to the nearest.
    #[arg(long = "source", value_name = "V", conflicts_with = "each_source")]
    sources: Vec<u32>,
    /// One field per source vertex.
    #[arg(long = "each-source", value_name = "V1,V2,...", value_delimiter = ',')]
    each_source: Vec<u32>,
    /// Output: .txt (distances), .png or .html (pictures); with --path, .txt (one point
    /// "x y z" per line) or .obj (the points and one polyline).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    /// Exact polyhedral distances (window propagation, Chen and Han improved by Xin and
    /// Wang) instead of the heat method: slower to compute, no set-up to amortise, exact.
    #[arg(long)]
    exact: bool,
    /// The shortest path on the surface from vertex A to vertex B, written as a polyline with
    /// a point wherever it crosses an edge: exact with --exact, else traced down the heat
    /// method's distance from A (fast, approximate).
    #[arg(long, value_name = "A,B", value_parser = parse_vertex_pair, conflicts_with_all = ["sources", "each_source"])]
    path: Option<(u32, u32)>,
    /// The heat flows for t = M h^2, h measured on the (intrinsic Delaunay) triangulation as
    /// --time-scale says.
    #[arg(long, value_name = "M", default_value_t = 0.5)]
    time_factor: f64,
    /// The length h of t = M h^2: spacing (the area-weighted vertex spacing, which follows
    /// the coarse parts of a mesh of varying resolution) or mean-edge (the paper's).
    #[arg(long, value_enum, value_name = "H", default_value = "spacing")]
    time_scale: TimeScaleArg,
    /// How the distance's additive constant is fixed: one-ring (fitted to the exact
    /// distances of the sources' neighbours, the edges' lengths) or sources (zero at the
    /// sources, the paper's).
    #[arg(long, value_enum, value_name = "A", default_value = "one-ring")]
    anchor: AnchorArg,
    /// Boundary conditions of the heat flow on meshes with a boundary. With dirichlet or
    /// average, a field with a source on the boundary uses neumann (a note on stderr says
    /// so): zero heat on the boundary would contradict that source.
    #[arg(long, value_enum, value_name = "BC", default_value = "robin")]
    boundary: BoundaryArg,
    /// The absorption r of --boundary robin, for fields whose sources are all off the
    /// boundary: the boundary absorbs heat at the rate kappa = r / sqrt(t) (0 is neumann).
    #[arg(long, value_name = "R", default_value_t = 0.7)]
    absorption: f64,
    /// The absorption of --boundary robin for fields with a source on the boundary.
    #[arg(long, value_name = "R", default_value_t = 0.2)]
    boundary_source_absorption: f64,
    /// Let --boundary robin absorb along cuts too (boundary edges lying on another boundary
    /// edge, the two sides of a seam); by default cuts have zero flux.
    #[arg(long)]
    absorb_at_cuts: bool,
    /// Build the operators on the mesh's own triangles, not its intrinsic Delaunay
    /// triangulation (less accurate on poor triangles).
    #[arg(long)]
    no_intrinsic_delaunay: bool,
    /// Keep the intrinsic Delaunay flips off the boundary edges (by default they may flip
    /// across the boundary, on the mesh glued to its mirror image).
    #[arg(long)]
    no_flip_boundary: bool,
    /// Intrinsic mollification margin, relative to the mean edge length: every edge grows by
    /// the least amount that gives each triangle this margin in the triangle inequality, so
    /// degenerate triangles are accepted (0: off).
    #[arg(long, value_name = "DELTA", default_value_t = 1e-5)]
    mollify: f64,
    /// Intrinsic Delaunay refinement: insert vertices on the surface until every triangle's
    /// angles are at least DEGREES (at most 30; 0: off, the default), solve on the refined
    /// triangulation and read the distances at the mesh's vertices.
    #[arg(long, value_name = "DEGREES", default_value_t = 0.0)]
    refine: f64,
    /// The most vertices --refine inserts, as a fraction of the mesh's vertices.
    #[arg(long, value_name = "FRACTION", default_value_t = 0.5)]
    refine_budget: f64,
    /// Picture size for PNG and HTML output, as WxH (per field).
    #[arg(
        long,
        value_name = "WxH",
        default_value = "800x800",
        allow_hyphen_values = true
    )]
    size: ImageSize,
    /// Print set-up and query times and counts as one JSON object on stdout.
    #[arg(long)]
    stats: bool,
    /// Print nothing but errors (and --stats).
    #[arg(short, long)]
    quiet: bool,
}

/// The time scale, on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum TimeScaleArg {
    /// The area-weighted vertex spacing; the default.
    Spacing,
    /// The mean edge length.
    MeanEdge,
}

/// The anchor of the distance, on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum AnchorArg {
    /// Fitted to the sources' neighbours; the default.
    OneRing,
    /// Zero at the sources.
    Sources,
}

/// Boundary conditions, on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum BoundaryArg {
    /// Partly absorbing (see --absorption); the default.
    Robin,
    /// Zero flux.
    Neumann,
    /// Zero heat (neumann for a field with a source on the boundary).
    Dirichlet,
    /// The mean of neumann and dirichlet (a third back-substitution per field; neumann for a
    /// field with a source on the boundary).
    Average,
}

#[derive(Args, Debug)]
struct ParamArgs {
    /// The mesh (OBJ or OFF): a disk-topology triangle mesh.
    mesh: PathBuf,
    /// tutte, lscm, asap, arap, sd, mips, arap-newton, or bounded (with --max-distortion).
    #[arg(long, value_name = "METHOD", default_value = "sd", value_parser = parse_method)]
    method: ParamMethod,
    /// For --method bounded: the bound K >= 1 on every triangle's conformal distortion.
    #[arg(long, value_name = "K")]
    max_distortion: Option<f64>,
    /// For --method bounded: the starting map.
    #[arg(long, value_enum, value_name = "INIT", default_value = "tutte")]
    init: InitArg,
    /// For --method bounded: a positional constraint, vertex V (0-based) at (X, Y);
    /// repeatable.
    #[arg(long = "pin", value_name = "V:X,Y", value_parser = parse_pin, allow_hyphen_values = true)]
    pins: Vec<(u32, [f64; 2])>,
    /// The most iterations of an iterative method (default 100 for asap and arap, 200 for
    /// the projected Newton methods, which usually stop much sooner).
    #[arg(long, value_name = "N")]
    iterations: Option<u32>,
    /// For --method arap-newton: the weight of the collapse barrier added to ARAP (default
    /// 1e-4); 0 minimises plain ARAP, which can squash triangles flat and stall.
    #[arg(long, value_name = "W", allow_hyphen_values = true)]
    collapse_barrier: Option<f64>,
    /// Output: .obj (the mesh with `vt`) or .png (a picture of the flattened mesh).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    /// Size of each of the two pictures of PNG output, as WxH.
    #[arg(
        long,
        value_name = "WxH",
        default_value = "600x600",
        allow_hyphen_values = true
    )]
    size: ImageSize,
    /// Print one JSON line per iteration and a summary line on stdout.
    #[arg(long)]
    stats: bool,
    /// Print nothing but errors (and --stats).
    #[arg(short, long)]
    quiet: bool,
}

/// A parameterisation method on the command line: one of the library's, or bounded
/// distortion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ParamMethod {
    Param(bdmorph::param::ParamMethod),
    Bounded,
}

fn parse_method(text: &str) -> Result<ParamMethod, String> {
    if text == "bounded" {
        return Ok(ParamMethod::Bounded);
    }
    text.parse()
        .map(ParamMethod::Param)
        .map_err(|e: String| e.replace("or arap-newton)", "arap-newton or bounded)"))
}

/// The starting map of a bounded-distortion parameterisation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum InitArg {
    /// Tutte's embedding.
    Tutte,
    /// The least-squares conformal map.
    Lscm,
}

/// `V:X,Y`.
fn parse_pin(text: &str) -> Result<(u32, [f64; 2]), String> {
    let bad = || format!("pin '{text}' is not V:X,Y (a vertex index, a colon, two numbers)");
    let (v, xy) = text.split_once(':').ok_or_else(bad)?;
    let (x, y) = xy.split_once(',').ok_or_else(bad)?;
    let v: u32 = v.trim().parse().map_err(|_| bad())?;
    let x: f64 = x.trim().parse().map_err(|_| bad())?;
    let y: f64 = y.trim().parse().map_err(|_| bad())?;
    if !(x.is_finite() && y.is_finite()) {
        return Err(bad());
    }
    Ok((v, [x, y]))
}

/// `deform --method`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum DeformMethod {
    /// Bounded distortion (Kovalsky et al. 2015), every triangle's distortion at most K.
    Bounded,
    /// As-rigid-as-possible with hard pins (local/global).
    Arap,
    /// As-Killing-as-possible vector fields (the original editor's), soft handles weighted
    /// by --pin-weight.
    Kvf,
    /// Symmetric Dirichlet with soft handles (--pin-weight) by projected Newton: no triangle
    /// flips or is crushed; a handle stops short where following it would crush the mesh.
    Sd,
}

/// Parses `X,Y`: two finite numbers.
fn parse_point(text: &str) -> Result<[f64; 2], String> {
    let bad = || format!("'{text}' is not X,Y (two numbers)");
    let (x, y) = text.split_once(',').ok_or_else(bad)?;
    let x: f64 = x.trim().parse().map_err(|_| bad())?;
    let y: f64 = y.trim().parse().map_err(|_| bad())?;
    if !(x.is_finite() && y.is_finite()) {
        return Err(bad());
    }
    Ok([x, y])
}

/// Parses `X,Y:TX,TY`: a place and its target.
fn parse_drag(text: &str) -> Result<([f64; 2], [f64; 2]), String> {
    let bad = |_| format!("drag '{text}' is not X,Y:TX,TY (a place, a colon, its target)");
    let (from, to) = text.split_once(':').ok_or_else(|| bad(String::new()))?;
    Ok((
        parse_point(from).map_err(bad)?,
        parse_point(to).map_err(bad)?,
    ))
}

#[derive(Args, Debug)]
struct StudioArgs {
    /// A picture (.png, .jpg), mesh (.obj, .off) or studio project (.json) to open.
    file: Option<PathBuf>,
    /// The port to listen on (default: the one the last studio in this folder used, if it is
    /// free, else any free one; 0: any free one).
    #[arg(long)]
    port: Option<u16>,
    /// Start the system's browser on the URL.
    #[arg(long)]
    open: bool,
    /// For a picture: the background colour around the subject (#rrggbb, #rgb, white,
    /// black, ..., or auto: the colour of the picture's border), as for `mesh`. Default: the
    /// picture's transparency, or auto for a picture without any.
    #[arg(long, value_name = "COLOR", value_parser = parse_background)]
    background: Option<bdmorph::meshing::Background>,
    /// For a picture: the threshold in [0, 1), as for `mesh`.
    #[arg(long, value_name = "L")]
    threshold: Option<f64>,
    /// For a mesh: the picture drawn on it (by its texture coordinates; without them laid
    /// over it by its pixels or its bounding box). Default: the picture of the same name
    /// beside it.
    #[arg(long, value_name = "PICTURE")]
    texture: Option<PathBuf>,
    /// For a picture: keep specks (pieces under 1% of the largest piece's area), which are
    /// dropped by default.
    #[arg(long)]
    keep_specks: bool,
}

#[derive(Args, Debug)]
struct DeformArgs {
    /// The planar mesh (OBJ or OFF, z = 0).
    mesh: PathBuf,
    /// A handle: vertex V (0-based) moves to (X, Y); repeatable. At least one handle
    /// (--pin, --drag or --fix) is needed.
    #[arg(long = "pin", value_name = "V:X,Y", value_parser = parse_pin, required_unless_present_any = ["drags", "fixes"], allow_hyphen_values = true)]
    pins: Vec<(u32, [f64; 2])>,
    /// A handle by place: the vertex nearest (X, Y) moves to (TX, TY); repeatable.
    #[arg(long = "drag", value_name = "X,Y:TX,TY", value_parser = parse_drag, allow_hyphen_values = true)]
    drags: Vec<([f64; 2], [f64; 2])>,
    /// A handle by place: the vertex nearest (X, Y) stays where it is; repeatable.
    #[arg(long = "fix", value_name = "X,Y", value_parser = parse_point, allow_hyphen_values = true)]
    fixes: Vec<[f64; 2]>,
    /// How the mesh follows the handles: bounded (bounded distortion, needs
    /// --max-distortion), arap (as-rigid-as-possible with hard pins; no bound, flips
    /// reported), kvf (as-Killing-as-possible fields with soft handles, the original
    /// editor's; no bound, flips reported) or sd (symmetric Dirichlet with soft handles:
    /// nothing flips or is crushed).
    #[arg(long, value_enum, default_value_t = DeformMethod::Bounded)]
    method: DeformMethod,
    /// The bound K >= 1 on every triangle's conformal distortion (--method bounded).
    #[arg(long, value_name = "K", required_if_eq("method", "bounded"))]
    max_distortion: Option<f64>,
    /// The most iterations (default 5000 for bounded, 1000 local/global steps for arap,
    /// 1000 field steps for kvf).
    #[arg(long, value_name = "N")]
    iterations: Option<u32>,
    /// The handles' weight of kvf and sd, relative to the mesh's stiffness (default 100):
    /// larger holds the handles closer to their targets.
    #[arg(long, value_name = "W")]
    pin_weight: Option<f64>,
    /// Output: .obj, .svg or .png.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    /// Picture size for SVG and PNG output, as WxH.
    #[arg(
        long,
        value_name = "WxH",
        default_value = "800x800",
        allow_hyphen_values = true
    )]
    size: ImageSize,
    /// Print one JSON object of statistics on stdout.
    #[arg(long)]
    stats: bool,
    /// Print nothing but errors (and --stats).
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Args, Debug)]
struct MeshArgs {
    /// A picture (.png, .jpg) or an outline (.poly, .svg).
    input: PathBuf,
    /// Output: .obj (the mesh with texture coordinates), or .svg or .png (a picture of it).
    /// Optional with --stats.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    /// About how many vertices (within 10%, or a note says why not; a picture's outline is
    /// simplified further to fit unless --tolerance is given).
    #[arg(long, value_name = "N", default_value_t = bdmorph::meshing::DEFAULT_VERTICES)]
    vertices: usize,
    /// How far the mesh's boundary may stray from the traced outline, in pixels (default 1,
    /// raised when the outline alone would take more than a fifth of --vertices);
    /// for SVG, how far curves may stray from their polylines, in the file's units after
    /// transforms (default 1/1000 of the outline's bounding-box diagonal). Unused for .poly.
    #[arg(long, value_name = "T")]
    tolerance: Option<f64>,
    /// The smallest angle of any triangle, in degrees (at most 33).
    #[arg(long, value_name = "DEG", default_value_t = bdmorph::meshing::DEFAULT_MIN_ANGLE)]
    min_angle: f64,
    /// The background colour around the subject: #rrggbb, #rgb, white, black, red, green,
    /// blue, grey, or auto (the picture's border). The subject is what differs from it by more
    /// than --threshold (default 0.2: the largest channel difference, in [0, 1]).
    #[arg(long, value_name = "COLOR", value_parser = parse_background)]
    background: Option<bdmorph::meshing::Background>,
    /// In [0, 1): the opacity above which a pixel is the subject (default 0.5); with
    /// --background, the colour difference (default 0.2); for an opaque picture without
    /// --background, the brightness below which it is (no default).
    #[arg(long, value_name = "L")]
    threshold: Option<f64>,
    /// Keep specks: pieces of a picture's subject under 1% of the largest piece's area
    /// (dust), otherwise left out with a note. Outlines (.svg, .poly) are always kept whole.
    #[arg(long)]
    keep_specks: bool,
    /// Picture size for SVG and PNG output, as WxH.
    #[arg(
        long,
        value_name = "WxH",
        default_value = "800x800",
        allow_hyphen_values = true
    )]
    size: ImageSize,
    /// Print one JSON object of statistics on stdout.
    #[arg(long)]
    stats: bool,
    /// Print nothing but errors (and --stats).
    #[arg(short, long)]
    quiet: bool,
}

fn parse_background(text: &str) -> Result<bdmorph::meshing::Background, String> {
    text.parse()
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
    /// Picture size of the GIF, the MP4 and each picture of the strip, as WxH.
    #[arg(
        long,
        value_name = "WxH",
        default_value = "360x360",
        allow_hyphen_values = true
    )]
    size: ImageSize,
    /// Print nothing but errors.
    #[arg(short, long)]
    quiet: bool,
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<(), String> {
    let threads = match cli.threads {
        Some(n) => n as usize,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("bdmorph-{i}"))
        .build_global()
        .map_err(|e| format!("--threads {threads}: cannot start the threads: {e}"))?;
    match cli.command {
        Command::Morph(args) => morph::run(args),
        Command::Blend(args) => blend::run(args),
        Command::Geodesic(args) => geodesic::run(args),
        Command::Param(args) => param::run(args),
        Command::Deform(args) => param::deform(args),
        Command::Mesh(args) => mesh::run(args),
        Command::Compile(args) => compile::run(args),
        Command::Inbetween(args) => inbetween::run(args),
        Command::Info(args) => info::run(args),
        Command::Demo(args) => demo::run(args),
        Command::Export(args) | Command::Render(args) => export::run(args),
        Command::Studio(args) => bdmorph::studio::run(bdmorph::studio::StudioOptions {
            file: args.file,
            port: args.port,
            open: args.open,
            opening: bdmorph::studio::open::OpenOptions {
                picture: bdmorph::studio::project::PictureSettings {
                    background: args.background.map(|b| match b {
                        bdmorph::meshing::Background::Auto => "auto".to_owned(),
                        bdmorph::meshing::Background::Colour([r, g, b]) => {
                            format!("#{r:02x}{g:02x}{b:02x}")
                        }
                    }),
                    threshold: args.threshold,
                },
                texture: args.texture,
                keep_specks: args.keep_specks,
                // The file named here is the user's own choice, and so is its picture.
                pictures_inside: false,
            },
            limits: bdmorph::studio::listen::ConnectionLimits::from_env(),
        })
        .map_err(|e| e.to_string()),
    }
}

/// The most frames one command computes: 100,000 (at 60 frames a second, 27 minutes of
/// animation). Their times are held (8 bytes each); their positions are streamed or counted
/// against what `morph` keeps in memory.
pub const MAX_FRAMES: usize = 100_000;

/// The frame times: one `t` (any finite number: the solver checks how far it may go), or `n`
/// evenly spaced over [0, 1] (at most [`MAX_FRAMES`]).
fn times(t: Option<f64>, frames: Option<usize>) -> Result<Vec<f64>, String> {
    match (t, frames) {
        (Some(t), None) if t.is_finite() => Ok(vec![t]),
        (Some(t), None) => Err(format!("--t {t} is not a finite number")),
        (None, Some(n)) if n > MAX_FRAMES => Err(format!(
            "--frames {n}: more than the {MAX_FRAMES} frames one command computes"
        )),
        (None, Some(n)) if n >= 2 => Ok((0..n).map(|i| i as f64 / (n - 1) as f64).collect()),
        (None, Some(n)) => Err(format!("--frames {n}: at least 2 frames are needed")),
        _ => Err("give either --t T or --frames N".into()),
    }
}

/// `A,B`: two vertex indices.
fn parse_vertex_pair(text: &str) -> Result<(u32, u32), String> {
    let (a, b) = text
        .split_once(',')
        .ok_or_else(|| format!("'{text}': give two vertices as A,B"))?;
    let vertex = |s: &str| {
        s.trim()
            .parse::<u32>()
            .map_err(|_| format!("'{s}' is not a vertex index (0, 1, 2, ...)"))
    };
    Ok((vertex(a)?, vertex(b)?))
}
