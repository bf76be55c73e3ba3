//! In-betweens of real animation: the walk cycles of Kenney's characters (CC0, 6 characters
//! × 8 drawings, `../shared/data/animation2d/kenney-characters/`, see its `SOURCES.md`).
//!
//! ```sh
//! cargo run --release --example walk_cycles                       # every character
//! cargo run --release --example walk_cycles -- --characters robot --vertices 1000
//! cargo run --release --example walk_cycles -- --placement anchor   # BDMORPH placed by anchor
//! ```
//!
//! For every drawing `i` of a cycle, the triples `(i − 1, i, i + 1)` and `(i − 2, i, i + 2)`
//! (cyclic): the in-between of the outer two is built (`Inbetween::new`, no point pairs)
//! and either accepted or refused with its one-line reason. For the accepted ones, the
//! middle frame (t = 0.5) of every method in [`METHODS`] is drawn and compared with the real
//! middle drawing: silhouette IoU (pixels of opacity at least one half) and mean colour error
//! (each picture over white, the mean of |Δ| over R, G and B, 0-255, over the union of the two
//! silhouettes), and swelling (the silhouette's area over the real drawing's, minus 1); and
//! in how many triples each method's IoU is at least straight lines'. The drawings are
//! 96 × 128 palette PNGs, scaled up 4 times by nearest
//! neighbour (384 × 512) before anything else.
//!
//! "With a folded frame" counts accepted triples where one of BDMORPH's frames at t = 0,
//! 0.05, ..., 1 has a flipped triangle (the compatible mesh itself never has one).
//!
//! Parameters were chosen on the training characters ([`TRAINING`]); the report is on the
//! others ([`HELD_OUT`]), worst case first. The program prints Markdown tables.
//!
//! To compare another way of making the middle frame, add a function to [`METHODS`]: it gets
//! the built in-between and both drawings, and returns the picture of its middle frame.

use std::path::PathBuf;
use std::time::Instant;

use bdmorph::inbetween::{linear_frame, ArapInterpolation, Inbetween, InbetweenOptions};
use bdmorph::render::{raster, Background, Drawing, Image, ImageSize, Viewport};

/// The characters whose triples the parameters were chosen on.
const TRAINING: [&str; 3] = ["female_adventurer", "male_adventurer", "robot"];
/// The characters reported on.
const HELD_OUT: [&str; 3] = ["female_person", "male_person", "zombie"];
/// Every character's folder and file prefix.
const CHARACTERS: [(&str, &str); 6] = [
    ("female_adventurer", "femaleAdventurer"),
    ("female_person", "femalePerson"),
    ("male_adventurer", "maleAdventurer"),
    ("male_person", "malePerson"),
    ("robot", "robot"),
    ("zombie", "zombie"),
];
/// The scale the drawings are meshed at.
const SCALE: u32 = 4;

/// What a method of making the middle frame gets.
struct Context<'a> {
    inbetween: &'a mut Inbetween,
    a: &'a Image,
    b: &'a Image,
}

/// A way of making the middle frame: its name and the function drawing it.
type Method = (&'static str, fn(&mut Context<'_>) -> Result<Image, String>);

/// The methods compared.
const METHODS: [Method; 5] = [
    ("bdmorph", bdmorph_frame),
    ("arap", arap_frame),
    ("linear", linear_mid),
    ("cross-dissolve", cross_dissolve),
    ("nearest key", nearest_key),
];

/// The mesh at `positions` drawn with both drawings' textures, cross-faded half and half
/// (as `bdmorph inbetween` draws t = 0.5 with its default smooth cross-fade).
fn draw(context: &Context<'_>, positions: &[[f64; 2]]) -> Image {
    let c = context.inbetween.compatible();
    let (uv_a, uv_b) = (c.texcoords_a.corner_uv(), c.texcoords_b.corner_uv());
    let (w, h) = (context.a.width, context.a.height);
    let view = Viewport {
        min: [0.0, 0.0],
        max: [f64::from(w), f64::from(h)],
    };
    let size = ImageSize {
        width: w,
        height: h,
    };
    let picture = |uv: &[[[f64; 2]; 3]], texture: &Image| {
        let drawing = Drawing {
            faces: &c.mesh.faces,
            corner_uv: Some(uv),
            texture: Some(texture),
            ..Drawing::default()
        };
        raster::render_on(positions, &drawing, &view, size, Background::Transparent)
            .expect("within the picture budget")
    };
    let (pa, pb) = (picture(&uv_a, context.a), picture(&uv_b, context.b));
    raster::crossfade(&pa, &pb, 0.5, Background::Transparent)
}

fn bdmorph_frame(context: &mut Context<'_>) -> Result<Image, String> {
    let positions = context
        .inbetween
        .frame(0.5)
        .map_err(|e| e.to_string())?
        .positions
        .to_vec();
    Ok(draw(context, &positions))
}

fn arap_frame(context: &mut Context<'_>) -> Result<Image, String> {
    let c = context.inbetween.compatible();
    let mut arap = ArapInterpolation::new(&c.mesh, &c.positions_b).map_err(|e| e.to_string())?;
    let positions = arap.frame(0.5).map_err(|e| e.to_string())?;
    Ok(draw(context, &positions))
}

fn linear_mid(context: &mut Context<'_>) -> Result<Image, String> {
    let c = context.inbetween.compatible();
    let positions = linear_frame(&c.mesh.positions, &c.positions_b, 0.5);
    Ok(draw(context, &positions))
}

fn cross_dissolve(context: &mut Context<'_>) -> Result<Image, String> {
    Ok(raster::crossfade(
        context.a,
        context.b,
        0.5,
        Background::Transparent,
    ))
}

fn nearest_key(context: &mut Context<'_>) -> Result<Image, String> {
    Ok(context.a.clone())
}

/// `image` scaled up `k` times by nearest neighbour.
fn scale(image: &Image, k: u32) -> Image {
    let (w, h) = (image.width * k, image.height * k);
    let mut rgba = vec![0u8; 4 * w as usize * h as usize];
    for y in 0..h {
        for x in 0..w {
            let s = 4 * ((y / k) * image.width + x / k) as usize;
            let d = 4 * (y * w + x) as usize;
            rgba[d..d + 4].copy_from_slice(&image.rgba[s..s + 4]);
        }
    }
    Image {
        width: w,
        height: h,
        rgba,
    }
}

/// What a middle frame is measured by against the real drawing.
#[derive(Clone, Copy)]
struct Score {
    /// Silhouette IoU.
    iou: f64,
    /// Mean colour error over the union of the silhouettes.
    colour: f64,
    /// The silhouette's area over the real drawing's, minus 1 (the swelling, or shrinking).
    swelling: f64,
}

/// Silhouette IoU, mean colour error and swelling of `frame` against the real drawing `truth`.
fn compare(frame: &Image, truth: &Image) -> Score {
    let (mut both, mut either, mut error) = (0usize, 0usize, 0.0);
    let (mut area_p, mut area_q) = (0usize, 0usize);
    for (p, q) in frame.rgba.chunks_exact(4).zip(truth.rgba.chunks_exact(4)) {
        let (in_p, in_q) = (p[3] >= 128, q[3] >= 128);
        area_p += usize::from(in_p);
        area_q += usize::from(in_q);
        if in_p && in_q {
            both += 1;
        }
        if !(in_p || in_q) {
            continue;
        }
        either += 1;
        let over_white = |px: &[u8], c: usize| {
            let a = f64::from(px[3]) / 255.0;
            a * f64::from(px[c]) + (1.0 - a) * 255.0
        };
        error += (0..3)
            .map(|c| (over_white(p, c) - over_white(q, c)).abs())
            .sum::<f64>()
            / 3.0;
    }
    if either == 0 {
        return Score {
            iou: 1.0,
            colour: 0.0,
            swelling: 0.0,
        };
    }
    Score {
        iou: both as f64 / either as f64,
        colour: error / either as f64,
        swelling: area_p as f64 / area_q.max(1) as f64 - 1.0,
    }
}

/// One triple's outcome.
struct Outcome {
    character: &'static str,
    triple: [usize; 3],
    /// The reason it was refused, or per method its score.
    result: Result<Vec<Score>, String>,
    /// Of BDMORPH's frames at t = 0, 0.05, ... 1, how many have a flipped triangle.
    folded_frames: usize,
    seconds: f64,
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn table(outcomes: &[&Outcome], title: &str) {
    let accepted: Vec<&Outcome> = outcomes
        .iter()
        .copied()
        .filter(|o| o.result.is_ok())
        .collect();
    println!(
        "\n### {title}: middle frame against the real drawing ({} accepted triples)\n",
        accepted.len()
    );
    println!(
        "| method | IoU worst | IoU median | colour error worst | colour error median | swelling worst | swelling median | IoU at least straight lines' |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    let linear = METHODS
        .iter()
        .position(|(name, _)| *name == "linear")
        .expect("straight lines are among the methods");
    for (m, (name, _)) in METHODS.iter().enumerate() {
        let scores: Vec<(Score, Score)> = accepted
            .iter()
            .filter_map(|o| o.result.as_ref().ok().map(|r| (r[m], r[linear])))
            .collect();
        let ious: Vec<f64> = scores.iter().map(|s| s.0.iou).collect();
        let errors: Vec<f64> = scores.iter().map(|s| s.0.colour).collect();
        let swellings: Vec<f64> = scores.iter().map(|s| s.0.swelling).collect();
        let worst_swelling = swellings
            .iter()
            .copied()
            .max_by(|a, b| a.abs().total_cmp(&b.abs()))
            .unwrap_or(f64::NAN);
        let at_least = scores.iter().filter(|s| s.0.iou >= s.1.iou).count();
        println!(
            "| {name} | {:.3} | {:.3} | {:.1} | {:.1} | {:+.1}% | {:+.1}% | {at_least}/{} |",
            ious.iter().copied().fold(f64::INFINITY, f64::min),
            median(ious),
            errors.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            median(errors),
            100.0 * worst_swelling,
            100.0 * median(swellings),
            scores.len()
        );
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let mut data = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/data/animation2d/kenney-characters"
    ));
    let mut vertices = InbetweenOptions::default().vertices;
    let mut only: Option<Vec<String>> = None;
    let mut strips: Option<PathBuf> = None;
    let mut placement = InbetweenOptions::default().morph.placement;
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--data" => data = PathBuf::from(args.next().ok_or("--data DIR")?),
            "--vertices" => vertices = args.next().ok_or("--vertices N")?.parse()?,
            "--placement" => {
                placement = args
                    .next()
                    .ok_or("--placement anchor|fit")?
                    .parse()
                    .map_err(|e: String| e)?
            }
            "--strips" => strips = Some(PathBuf::from(args.next().ok_or("--strips DIR")?)),
            "--characters" => {
                only = Some(
                    args.next()
                        .ok_or("--characters a,b")?
                        .split(',')
                        .map(String::from)
                        .collect(),
                )
            }
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    let defaults = InbetweenOptions::default();
    let morph = defaults.morph.clone().with_placement(placement);
    let options = defaults.with_vertices(vertices).with_morph(morph);
    println!(
        "Walk cycles from {} (drawings scaled up {SCALE}× by nearest neighbour), about {vertices} vertices, BDMORPH's frames placed by {placement:?}.",
        data.display()
    );
    let mut outcomes: Vec<Outcome> = Vec::new();
    for (folder, prefix) in CHARACTERS {
        if only
            .as_ref()
            .is_some_and(|o| !o.iter().any(|c| c == folder))
        {
            continue;
        }
        let drawings: Vec<Image> = (0..8)
            .map(|i| {
                let path = data.join(folder).join(format!("{prefix}_walk{i}.png"));
                raster::read_image(&path)
                    .map(|img| scale(&img, SCALE))
                    .map_err(|e| format!("{}: {e}", path.display()))
            })
            .collect::<Result<_, _>>()?;
        for stride in [1, 2] {
            for i in 0..8 {
                let triple = [(i + 8 - stride) % 8, i, (i + stride) % 8];
                let (a, m, b) = (
                    &drawings[triple[0]],
                    &drawings[triple[1]],
                    &drawings[triple[2]],
                );
                let started = Instant::now();
                let mut folded_frames = 0;
                let result = match Inbetween::new(a, b, &[], &options) {
                    Err(e) => Err(e.to_string()),
                    Ok(mut inbetween) => {
                        for k in 0..=20 {
                            match inbetween.frame(k as f64 / 20.0) {
                                Ok(frame) if frame.stats.flipped_triangles == 0 => {}
                                _ => folded_frames += 1,
                            }
                        }
                        let mut context = Context {
                            inbetween: &mut inbetween,
                            a,
                            b,
                        };
                        let frames = METHODS
                            .iter()
                            .map(|(name, method)| {
                                method(&mut context).map_err(|e| format!("{name}: {e}"))
                            })
                            .collect::<Result<Vec<_>, _>>();
                        if let (Some(dir), Ok(frames)) = (&strips, &frames) {
                            // A, the methods' middle frames, the real middle drawing, B.
                            let mut row = vec![a.clone()];
                            row.extend(frames.iter().cloned());
                            row.extend([m.clone(), b.clone()]);
                            let strip = raster::strip(&row, row.len());
                            let name =
                                format!("{folder}_{}_{}_{}.png", triple[0], triple[1], triple[2]);
                            std::fs::create_dir_all(dir)?;
                            std::fs::write(dir.join(name), raster::encode_png(&strip)?)?;
                        }
                        frames.map(|f| f.iter().map(|frame| compare(frame, m)).collect::<Vec<_>>())
                    }
                };
                let seconds = started.elapsed().as_secs_f64();
                match &result {
                    Ok(r) => eprintln!(
                        "{folder} {triple:?}: accepted in {seconds:.1} s, bdmorph IoU {:.3}",
                        r[0].iou
                    ),
                    Err(e) => eprintln!("{folder} {triple:?}: refused: {e}"),
                }
                outcomes.push(Outcome {
                    character: folder,
                    triple,
                    result,
                    folded_frames,
                    seconds,
                });
            }
        }
    }
    println!("\n### Acceptance\n");
    println!(
        "| character | set | consecutive | stride 2 | all | with a folded frame | slowest build (s) |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|");
    for (folder, _) in CHARACTERS {
        let mine: Vec<&Outcome> = outcomes.iter().filter(|o| o.character == folder).collect();
        if mine.is_empty() {
            continue;
        }
        let count = |stride: usize| {
            let of: Vec<&&Outcome> = mine
                .iter()
                .filter(|o| (o.triple[2] + 8 - o.triple[1]) % 8 == stride)
                .collect();
            (of.iter().filter(|o| o.result.is_ok()).count(), of.len())
        };
        let (c1, n1) = count(1);
        let (c2, n2) = count(2);
        let set = if TRAINING.contains(&folder) {
            "training"
        } else {
            "held out"
        };
        println!(
            "| {folder} | {set} | {c1}/{n1} | {c2}/{n2} | {}/{} | {} | {:.1} |",
            c1 + c2,
            n1 + n2,
            mine.iter()
                .filter(|o| o.result.is_ok() && o.folded_frames > 0)
                .count(),
            mine.iter().map(|o| o.seconds).fold(0.0, f64::max)
        );
    }
    for (name, set) in [("held out", &HELD_OUT[..]), ("training", &TRAINING[..])] {
        let of: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| set.contains(&o.character))
            .collect();
        if of.is_empty() {
            continue;
        }
        let ok = of.iter().filter(|o| o.result.is_ok()).count();
        println!(
            "\n{name}: {ok} of {} triples accepted ({:.0}%)",
            of.len(),
            100.0 * ok as f64 / of.len() as f64
        );
        for o in of.iter().filter(|o| o.result.is_err()) {
            if let Err(e) = &o.result {
                println!("- {} {:?}: {e}", o.character, o.triple);
            }
        }
        table(&of, name);
    }
    Ok(())
}
