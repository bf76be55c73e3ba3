//! `bdmorph morph SOURCE TARGET ...`.

use std::io::Write;
use std::path::PathBuf;

use bdmorph::io::{LineMap, TexCoords};
use bdmorph::located::Locate;
use bdmorph::render::{raster, Image};
use bdmorph::PlanarMesh;
use bdmorph::{
    KeyframePath, Located, MeshError, MeshFile, Morph, MorphError, MorphOptions, PathOptions,
};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;

use super::output::{self, Look, Plan};
use super::{times, MorphArgs, OutputArgs, SolverArgs};

/// Reads a planar mesh and checks it as a keyframe; errors name the file and the line. Also
/// returns its texture coordinates and the line of each vertex and face, for later errors.
pub(super) fn read(
    path: &std::path::Path,
) -> Result<(PlanarMesh, Option<TexCoords>, LineMap), String> {
    read_keyframe(path, false)
}

/// As [`read`], allowing a few inverted triangles when asked.
pub(super) fn read_keyframe(
    path: &std::path::Path,
    allow_inverted: bool,
) -> Result<(PlanarMesh, Option<TexCoords>, LineMap), String> {
    let file = MeshFile::read(path).map_err(|e| e.to_string())?;
    let mesh = if allow_inverted {
        file.planar_allowing_inverted()
    } else {
        file.planar()
    }
    .map_err(|e| e.to_string())?;
    let MeshFile {
        mesh: surface,
        lines,
        ..
    } = file;
    Ok((mesh, surface.texcoords, lines))
}

/// A progress bar on stderr, drawn only when stderr is a terminal and not `quiet`.
pub(super) fn progress_bar(len: usize, quiet: bool, what: &str) -> ProgressBar {
    let target = if quiet || len < 2 {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(Some(len as u64), target);
    if let Ok(style) = ProgressStyle::with_template("{msg:>10} [{bar:30}] {pos}/{len} {eta}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_owned());
    bar
}

/// Checks the output and solver options that can be checked before reading anything.
pub(super) fn check_options(out: &OutputArgs, solver: &SolverArgs) -> Result<(), String> {
    if out.output.is_none() && !out.stats {
        return Err("nothing to do: give -o OUT, --stats, or both".into());
    }
    if solver.tolerance.is_nan() || solver.tolerance <= 0.0 {
        return Err(format!("--tolerance {} must be positive", solver.tolerance));
    }
    if out.fps == 0 {
        return Err("--fps must be at least 1".into());
    }
    Ok(())
}

/// Where and how `frames` frames are written (`-o`, `--format`, `--sheet`); `None` without
/// `-o`.
pub(super) fn plan_of(out: &OutputArgs, frames: usize) -> Result<Option<Plan>, String> {
    out.output
        .as_ref()
        .map(|path| Plan::with_sheet(path, out.format, frames, out.sheet))
        .transpose()
}

/// Checks that the output can hold pictures of `--size` (and `--background`), and says when
/// they will be padded.
pub(super) fn check_size(plan: Option<&Plan>, out: &OutputArgs) -> Result<(), String> {
    if let (Some(plan), Some(background)) = (plan, out.background) {
        plan.check_background(background)?;
    }
    if out.sheet && plan.is_none() {
        return Err("--sheet needs -o NAME.png".into());
    }
    if let Some(note) = plan.map(|p| p.check_size(out.size)).transpose()?.flatten() {
        if !out.quiet {
            eprintln!("bdmorph: note: {note}");
        }
    }
    Ok(())
}

/// Reads every mesh (and the first one's texture coordinates) and the texture, warning about
/// options the output does not use.
pub(super) fn read_inputs(
    meshes: &[PathBuf],
    out: &OutputArgs,
    solver: &SolverArgs,
    plan: Option<&Plan>,
) -> Result<Inputs, String> {
    let mut keyframes = Vec::with_capacity(meshes.len());
    let mut lines = Vec::with_capacity(meshes.len());
    let mut texcoords = None;
    for (i, path) in meshes.iter().enumerate() {
        let (mesh, tex, map) = read_keyframe(path, solver.allow_inverted)?;
        if i == 0 {
            texcoords = tex;
        }
        keyframes.push(mesh);
        lines.push(map);
    }
    let texture = match &out.texture {
        Some(path) => Some(raster::read_image(path).map_err(|e| e.to_string())?),
        None => None,
    };
    let draws = plan.is_some_and(Plan::draws);
    if texture.is_some() && !draws && !out.quiet {
        eprintln!("bdmorph: warning: --texture only affects PNG, GIF, MP4 and HTML output");
    }
    if out.color_by.is_some() && !draws && !out.quiet {
        eprintln!("bdmorph: warning: --color-by only affects PNG, GIF, MP4, SVG and HTML output");
    }
    let depth = match &out.depth {
        Some(path) => {
            let first = &keyframes[0];
            Some(read_depth(path, first.positions.len(), &first.faces)?)
        }
        None => None,
    };
    if depth.is_some() && !draws && !out.quiet {
        eprintln!("bdmorph: warning: --depth only affects pictures (PNG, GIF, MP4, APNG, WebP, SVG, HTML)");
    }
    Ok(Inputs {
        paths: meshes.to_vec(),
        keyframes,
        lines,
        texcoords,
        texture,
        depth,
    })
}

/// The meshes and pictures a command works on.
pub(super) struct Inputs {
    /// The keyframes' files, in order.
    pub paths: Vec<PathBuf>,
    /// The keyframes, in order.
    pub keyframes: Vec<PlanarMesh>,
    /// Where each keyframe's vertices and faces are in its file.
    pub lines: Vec<LineMap>,
    /// The first keyframe's texture coordinates.
    pub texcoords: Option<TexCoords>,
    /// The texture image.
    pub texture: Option<Image>,
    /// The draw order (`--depth`): a level per face of the first mesh.
    pub depth: Option<Vec<i8>>,
}

/// Reads a depth file (`--depth`) for a mesh of `vertices` vertices and `faces`.
pub(super) fn read_depth(
    path: &std::path::Path,
    vertices: usize,
    faces: &[[u32; 3]],
) -> Result<Vec<i8>, String> {
    use bdmorph::render::depth::{parse_depth, MAX_DEPTH_FILE_BYTES};
    let shown = path.display();
    let bytes = bdmorph::io::read_input(path, MAX_DEPTH_FILE_BYTES)
        .map_err(|e| format!("{shown}: cannot read: {e}"))?;
    parse_depth(&String::from_utf8_lossy(&bytes), vertices, faces)
        .map_err(|e| format!("{shown}: {e}"))
}

/// The solver's options from the command line.
/// The solver's settings as morph options; `placement` unless `--placement` says otherwise.
pub(super) fn morph_options(solver: &SolverArgs, placement: bdmorph::Placement) -> MorphOptions {
    MorphOptions::default()
        .with_tolerance(solver.tolerance)
        .with_max_iterations(solver.max_iterations)
        .with_allow_inverted(solver.allow_inverted)
        .with_placement(solver.placement.unwrap_or(placement))
}

impl Inputs {
    /// `error`, about keyframe `k`, naming its file and the lines of the faces and vertices
    /// it is about.
    fn locate<E: Locate>(&self, k: usize, error: E) -> Located<E> {
        Located::new(
            &self.paths[k],
            &self.lines[k],
            &self.keyframes[k].faces,
            error,
        )
    }

    /// A set-up error, naming the file (and the line) of the keyframe at fault: keyframe `k`
    /// for an error that compares it with the first, the first one for its compilation.
    pub(super) fn setup_error(&self, e: MorphError) -> String {
        let pair = |k: usize, e: MeshError| {
            let first = match e {
                MeshError::FaceReversed { source_face, .. } => self.lines[0].face_line(source_face),
                _ => None,
            };
            let first = match first {
                Some(line) => format!("{}:{line}", self.paths[0].display()),
                None => self.paths[0].display().to_string(),
            };
            format!("{} (compared with {first})", self.locate(k, e))
        };
        match e {
            MorphError::Keyframe { index, source } => pair(index, source),
            // Morph::new compares its target with its source.
            MorphError::Mesh(
                e @ (MeshError::FaceMissing { .. }
                | MeshError::FaceReversed { .. }
                | MeshError::FaceRepeated { .. }),
            ) => pair(1, e),
            // Each mesh was checked when read: what is left is the first one's compilation.
            MorphError::Mesh(e @ MeshError::Topology(_)) => self.locate(0, e).to_string(),
            e @ MorphError::ProgramMismatch { .. } => self.locate(0, e).to_string(),
            other => {
                let names: Vec<String> =
                    self.paths.iter().map(|p| p.display().to_string()).collect();
                format!("{}: {other}", names.join(" -> "))
            }
        }
    }

    /// A frame's error; when it names triangles, with the first keyframe's file and their
    /// lines.
    pub(super) fn frame_error(&self, e: MorphError) -> String {
        let located = self.locate(0, e);
        if located.places.is_empty() {
            located.error.to_string()
        } else {
            located.to_string()
        }
    }
}

/// A morph between two meshes, or a path through several.
enum Animation {
    Morph(Morph),
    Path(KeyframePath),
}

impl Animation {
    fn frame(&mut self, t: f64) -> Result<bdmorph::Frame<'_>, MorphError> {
        match self {
            Animation::Morph(m) => m.frame(t),
            Animation::Path(p) => p.frame(t),
        }
    }

    fn faces(&self) -> &[[u32; 3]] {
        match self {
            Animation::Morph(m) => m.faces(),
            Animation::Path(p) => p.faces(),
        }
    }

    /// What the solver found: pieces, holes, inverted triangles.
    fn structure(&self) -> &bdmorph::morph::Structure {
        match self {
            Animation::Morph(m) => m.structure(),
            Animation::Path(p) => p.structure(),
        }
    }

    /// Per keyframe, its inverted triangles (allowed by --allow-inverted).
    fn inverted(&self) -> &[Vec<usize>] {
        &self.structure().inverted
    }

    /// The time of each keyframe.
    fn keyframe_times(&self) -> Vec<f64> {
        match self {
            Animation::Morph(_) => vec![0.0, 1.0],
            Animation::Path(p) => p.keyframe_times().to_vec(),
        }
    }
}

pub(super) fn run(args: MorphArgs) -> Result<(), String> {
    // Everything that can be checked before computing is checked first: bad input writes
    // nothing.
    let times = times(args.t, args.frames)?;
    check_options(&args.out, &args.solver)?;
    let segments = args.meshes.len() - 1;
    if !args.durations.is_empty() && args.durations.len() != segments {
        return Err(format!(
            "--durations: {} values given for {segments} segments (one per pair of consecutive meshes)",
            args.durations.len()
        ));
    }
    if args.easing.len() > 1 && args.easing.len() != segments {
        return Err(format!(
            "--easing: given {} times for {segments} segments (give it once, or once per segment)",
            args.easing.len()
        ));
    }
    let plan = plan_of(&args.out, times.len())?;
    check_size(plan.as_ref(), &args.out)?;
    let inputs = read_inputs(&args.meshes, &args.out, &args.solver, plan.as_ref())?;
    let options = morph_options(&args.solver, bdmorph::Placement::Anchor);
    let program = match &args.solver.program {
        Some(path) => Some(super::compile::load(
            path,
            &args.meshes[0],
            &inputs.keyframes[0],
        )?),
        None => None,
    };
    let keys = &inputs.keyframes;
    let as_path = keys.len() > 2 || !args.easing.is_empty() || !args.durations.is_empty();
    let path_options = PathOptions::default()
        .with_morph(options.clone())
        .with_durations(args.durations.clone())
        .with_easings(args.easing.clone());
    let build = |program: Option<bdmorph::Program>| {
        if as_path {
            match program {
                Some(p) => KeyframePath::with_program(p, keys, path_options.clone()),
                None => KeyframePath::with_options(keys, path_options.clone()),
            }
            .map(Animation::Path)
        } else {
            match program {
                Some(p) => Morph::with_program(p, &keys[0], &keys[1], options.clone()),
                None => Morph::new(&keys[0], &keys[1], options.clone()),
            }
            .map(Animation::Morph)
        }
    };
    // Stretches of t solved in parallel, each by its own engine warm-started from its own
    // first frame (one stretch, today's sequence, with one thread).
    let stretches = stretch_count(times.len(), rayon::current_num_threads());
    let mut engines = Vec::with_capacity(stretches);
    if stretches > 1 {
        // The stretches use the threads: each engine is analysed for one thread, so that its
        // frames do not also split their factorisations and solves (which only adds the
        // split's bookkeeping when every thread is busy: 1M vertices, 16 frames on two
        // threads, 16.0-16.7 s split against 13.1-13.8 s not).
        let built: Result<Vec<Animation>, MorphError> = (0..stretches)
            .into_par_iter()
            .map(|_| on_one_thread(|| build(program.clone())))
            .collect();
        engines.extend(built.map_err(|e| inputs.setup_error(e))?);
    } else {
        engines.push(build(program.clone()).map_err(|e| inputs.setup_error(e))?);
    }

    if !args.out.quiet {
        for v in engines[0]
            .structure()
            .pieces
            .iter()
            .flat_map(|p| &p.free_holes)
        {
            eprintln!(
                "bdmorph: note: the hole at vertex {v} (0-based) crosses itself or changes too \
                 much between keyframes for one filling: it is solved as a free boundary, \
                 closed at every frame (keyframes are still reached exactly)"
            );
        }
    }
    let colour = args.out.color_by.is_some();
    // Keyframes with inverted triangles (--allow-inverted), by the time they are at.
    let inverted = engines[0].inverted().to_vec();
    let folded: Vec<(f64, usize)> = engines[0]
        .keyframe_times()
        .into_iter()
        .enumerate()
        .filter(|&(k, _)| !inverted[k].is_empty())
        .map(|(k, t)| (t, k))
        .collect();
    let vertices = keys[0].positions.len();
    let faces_n = keys[0].faces.len();
    // OBJ frames stream to their directory a chunk at a time; every other output keeps the
    // frames' positions (pictures are framed to fit every frame, animations hold them all),
    // within MAX_KEPT_BYTES, checked before any frame is computed.
    let streams = plan
        .as_ref()
        .is_some_and(|p| p.directory && p.format == output::Format::Obj);
    if let Some(plan) = plan.as_ref().filter(|_| !streams) {
        check_kept(plan, times.len(), vertices, colour.then_some(faces_n))?;
    }
    let bar = progress_bar(times.len(), args.out.quiet, "morphing");
    let keep = plan.is_some();
    let solve = |engine: &mut Animation, range: std::ops::Range<usize>| {
        range
            .map(|index| {
                let t = times[index];
                let solved = engine.frame(t).map(|frame| Solved {
                    stats: frame.stats,
                    positions: keep.then(|| frame.positions.to_vec()),
                    distortion: (keep && colour).then(|| frame.distortion.to_vec()),
                    at_folded: folded.iter().find(|&&(at, _)| at == t).map(|&(_, k)| {
                        (
                            k,
                            max_distance(frame.positions, &inputs.keyframes[k].positions),
                        )
                    }),
                });
                bar.inc(1);
                solved
            })
            .collect::<Vec<_>>()
    };
    let animation_faces = engines[0].faces().to_vec();
    let mut frames = Vec::new();
    let mut stdout = std::io::stdout().lock();
    let mut failed = 0usize;
    let mut streamed = 0usize;
    let names: Vec<String> = args
        .meshes
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let title = format!("bdmorph: {}", names.join(" -> "));
    // A chunk of frames at a time: solved in parallel stretches (each engine warm-started
    // from its previous frame), reported in order, and (OBJ frames) written; memory does not
    // grow with the number of frames.
    for chunk_start in (0..times.len()).step_by(CHUNK) {
        let chunk_end = times.len().min(chunk_start + CHUNK);
        let ranges = stretch_ranges(chunk_end - chunk_start, stretches)
            .into_iter()
            .map(|r| chunk_start + r.start..chunk_start + r.end);
        let solved: Vec<Result<Solved, MorphError>> = engines
            .par_iter_mut()
            .zip(ranges.collect::<Vec<_>>())
            .map(|(engine, range)| solve(engine, range))
            .collect::<Vec<_>>()
            .into_iter()
            .flatten()
            .collect();
        for (index, solved) in (chunk_start..chunk_end).zip(solved) {
            let t = times[index];
            let frame = match solved {
                Ok(frame) => frame,
                // One frame: its error is the command's. Several: report it, write the others.
                Err(e) if times.len() == 1 => return Err(inputs.frame_error(e)),
                Err(e) => {
                    failed += 1;
                    let e = inputs.frame_error(e);
                    if args.out.stats {
                        writeln!(stdout, "{{\"t\":{t},\"error\":\"{}\"}}", json_escape(&e))
                            .map_err(|e| e.to_string())?;
                    }
                    eprintln!("bdmorph: error: {e}; frame skipped");
                    continue;
                }
            };
            report(&args.out, &inputs, &inverted, t, &frame, &mut stdout)?;
            if let Some(positions) = frame.positions {
                frames.push(output::Frame {
                    index,
                    t,
                    positions,
                    distortion: frame.distortion,
                });
            }
        }
        stdout.flush().map_err(|e| e.to_string())?;
        if let (true, Some(plan)) = (streams, plan.as_ref()) {
            streamed += write_files(plan, &args.out, &inputs, &animation_faces, &title, &frames)?;
            frames.clear();
        }
    }
    bar.finish_and_clear();
    let n_times = times.len();
    let writes = plan.is_some();
    let failures = move || {
        format!(
            "{failed} of {n_times} frames could not be computed (see above); the others were {}",
            if writes { "written" } else { "computed" }
        )
    };
    let Some(plan) = plan else {
        return if failed > 0 { Err(failures()) } else { Ok(()) };
    };
    if frames.is_empty() && streamed == 0 {
        return Err(format!(
            "no frame could be computed; nothing was written to {}",
            plan.path.display()
        ));
    }
    if streams {
        tell_written(&plan, &args.out, streamed);
    } else {
        write_frames(&plan, &args.out, &inputs, &animation_faces, &title, &frames)?;
    }
    if failed > 0 {
        return Err(failures());
    }
    Ok(())
}

/// Frames solved, reported and (OBJ frames) written at a time.
const CHUNK: usize = 512;

/// The most bytes of frame positions (and distortions) kept in memory for an output that
/// needs every frame before it is written: 2 GiB.
pub(super) const MAX_KEPT_BYTES: u64 = 2 << 30;

/// Refuses, before any frame is computed, an output whose frames would not fit in
/// [`MAX_KEPT_BYTES`].
pub(super) fn check_kept(
    plan: &Plan,
    frames: usize,
    vertices: usize,
    shaded_faces: Option<usize>,
) -> Result<(), String> {
    let per_frame = 16 * vertices as u64 + 8 * shaded_faces.unwrap_or(0) as u64 + 64;
    let bytes = per_frame.saturating_mul(frames as u64);
    if bytes <= MAX_KEPT_BYTES {
        return Ok(());
    }
    Err(format!(
        "{}: {frames} frames of {vertices} vertices need {:.1} GiB in memory before they are \
         written, over the {} GiB limit; ask for fewer frames, or write OBJ frames to a \
         directory (they stream)",
        plan.path.display(),
        bytes as f64 / f64::from(1u32 << 30),
        MAX_KEPT_BYTES >> 30
    ))
}

/// Reports one solved frame: its `--stats` line, and notes about keyframes with inverted
/// triangles and flipped triangles.
fn report(
    out: &OutputArgs,
    inputs: &Inputs,
    inverted: &[Vec<usize>],
    t: f64,
    frame: &Solved,
    stdout: &mut impl Write,
) -> Result<(), String> {
    let at_folded = frame.at_folded;
    if out.stats {
        let mut json = frame.stats.to_json();
        if let Some((k, deviation)) = at_folded {
            json.pop();
            json += &format!(
                ",\"keyframe\":{k},\"inverted_triangles\":{},\"keyframe_deviation\":{deviation:e}}}",
                inverted[k].len()
            );
        }
        writeln!(stdout, "{json}").map_err(|e| e.to_string())?;
    }
    if let (Some((k, deviation)), false) = (at_folded, out.quiet) {
        let size = inputs.keyframes[k].diameter();
        let inverted = &inverted[k];
        eprintln!(
            "bdmorph: note: t = {t} is keyframe {k} ({}), which has {} inverted \
             triangle{} (face {}, 0-based): the frame is the flat shape nearest its side \
             lengths, not that pose; it differs from it by up to {deviation:.3e} ({:.2}% \
             of its size)",
            inputs.paths[k].display(),
            inverted.len(),
            if inverted.len() == 1 { "" } else { "s" },
            listed(inverted),
            100.0 * deviation / size.max(f64::MIN_POSITIVE)
        );
    }
    if frame.stats.flipped_triangles > 0 && !out.quiet {
        eprintln!(
            "bdmorph: warning: t = {t}: {} flipped triangles",
            frame.stats.flipped_triangles
        );
    }
    Ok(())
}

/// One solved frame, as the command reports and writes it.
struct Solved {
    stats: bdmorph::FrameStats,
    /// Its positions, when written.
    positions: Option<Vec<[f64; 2]>>,
    /// Its triangles' distortion, when pictures are coloured by it.
    distortion: Option<Vec<f64>>,
    /// At a keyframe with inverted triangles: the keyframe and the frame's largest distance
    /// from it.
    at_folded: Option<(usize, f64)>,
}

/// Runs `f` in a pool of one thread of its own (so that what `f` builds is analysed for one
/// thread), or here if no thread can be started.
fn on_one_thread<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
        Ok(pool) => pool.install(f),
        Err(_) => f(),
    }
}

/// Frames per stretch below which another engine (its set-up, its cold first frame, its
/// memory) does not pay.
const MIN_STRETCH: usize = 8;

/// How many stretches of `frames` frames to solve in parallel on `threads` threads: one per
/// thread, each of at least [`MIN_STRETCH`] frames (one stretch with one thread).
pub(super) fn stretch_count(frames: usize, threads: usize) -> usize {
    threads.min(frames / MIN_STRETCH).max(1)
}

/// `stretches` consecutive ranges covering `0..frames`, as equal as can be (the first ones
/// one longer).
pub(super) fn stretch_ranges(frames: usize, stretches: usize) -> Vec<std::ops::Range<usize>> {
    let (each, extra) = (frames / stretches, frames % stretches);
    let mut start = 0;
    (0..stretches)
        .map(|k| {
            let len = each + usize::from(k < extra);
            let range = start..start + len;
            start += len;
            range
        })
        .collect()
}

/// Renders and writes computed frames as `plan` says, then tells where (unless quiet).
pub(super) fn write_frames(
    plan: &Plan,
    out: &OutputArgs,
    inputs: &Inputs,
    faces: &[[u32; 3]],
    title: &str,
    frames: &[output::Frame],
) -> Result<(), String> {
    let written = write_files(plan, out, inputs, faces, title, frames)?;
    tell_written(plan, out, written);
    Ok(())
}

/// Renders and writes computed frames as `plan` says; returns how many files were written.
fn write_files(
    plan: &Plan,
    out: &OutputArgs,
    inputs: &Inputs,
    faces: &[[u32; 3]],
    title: &str,
    frames: &[output::Frame],
) -> Result<usize, String> {
    if frames.is_empty() {
        return Ok(0);
    }
    if let Some(depth) = &inputs.depth {
        if depth.len() != faces.len() {
            return Err(format!(
                "--depth: {} levels for the {} triangles drawn",
                depth.len(),
                faces.len()
            ));
        }
    }
    let corner_uv = inputs.texture.as_ref().map(|_| {
        inputs
            .texcoords
            .clone()
            .unwrap_or_else(|| inputs.keyframes[0].normalized_texcoords())
            .corner_uv()
    });
    let look = Look {
        faces,
        texcoords: inputs.texcoords.as_ref(),
        texture: inputs.texture.as_ref().zip(corner_uv.as_deref()),
        size: out.size,
        fps: out.fps,
        title,
        background: out.background.unwrap_or_default(),
        crossfade: None,
        depth: inputs.depth.as_deref(),
    };
    let bar = progress_bar(frames.len(), out.quiet, "rendering");
    let files = output::render(plan, &look, frames, || bar.inc(1))?;
    bar.finish_and_clear();
    output::write(plan, &files)?;
    Ok(files.len())
}

/// Tells where the files went (unless quiet).
fn tell_written(plan: &Plan, out: &OutputArgs, files: usize) {
    if !out.quiet {
        if plan.directory {
            eprintln!("wrote {files} files to {}", plan.path.display());
        } else {
            eprintln!("wrote {}", plan.path.display());
        }
    }
}

/// Largest distance between corresponding positions.
pub(super) fn max_distance(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max)
}

/// The first few of `faces`, comma-separated, with how many more.
pub(super) fn listed(faces: &[usize]) -> String {
    const SHOWN: usize = 10;
    let mut text: Vec<String> = faces.iter().take(SHOWN).map(usize::to_string).collect();
    if faces.len() > SHOWN {
        text.push(format!("and {} more", faces.len() - SHOWN));
    }
    text.join(", ")
}

/// Escapes a message for a JSON string.
pub(super) fn json_escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out
}
