//! `bdmorph blend K0 K1 ... --weights w0,w1,... -o OUT`.

use std::io::Write;

use bdmorph::Blend;

use super::morph::{check_options, check_size, morph_options, read_inputs, write_frames};
use super::output::{self, Plan};
use super::BlendArgs;

pub(super) fn run(args: BlendArgs) -> Result<(), String> {
    check_options(&args.out, &args.solver)?;
    if args.weights.len() != args.meshes.len() {
        return Err(format!(
            "--weights: {} values given for {} meshes (one weight per mesh)",
            args.weights.len(),
            args.meshes.len()
        ));
    }
    let plan = match &args.out.output {
        Some(path) => Some(Plan::new(path, args.out.format, 1)?),
        None => None,
    };
    if plan.as_ref().is_some_and(|p| p.format.is_animation()) && !args.out.quiet {
        eprintln!("bdmorph: warning: a blend is one frame; the animation will hold only it");
    }
    check_size(plan.as_ref(), &args.out)?;
    let inputs = read_inputs(&args.meshes, &args.out, plan.as_ref())?;
    let options = morph_options(&args.solver);
    let blend = match &args.solver.program {
        Some(path) => {
            let program = super::compile::load(path, &args.meshes[0], &inputs.keyframes[0])?;
            Blend::with_program(program, &inputs.keyframes, options)
        }
        None => Blend::with_options(&inputs.keyframes, options),
    };
    let mut blend = blend.map_err(|e| inputs.setup_error(e))?;
    let frame = blend
        .frame_weights(&args.weights)
        .map_err(|e| inputs.frame_error(e))?;
    if args.out.stats {
        // The frame's statistics, with its weights in place of a time.
        let json = frame.stats.to_json();
        let weights: Vec<String> = args.weights.iter().map(|w| format!("{w}")).collect();
        let json = json.replacen(
            "\"t\":null",
            &format!("\"weights\":[{}]", weights.join(",")),
            1,
        );
        writeln!(std::io::stdout().lock(), "{json}").map_err(|e| e.to_string())?;
    }
    if frame.stats.flipped_triangles > 0 && !args.out.quiet {
        eprintln!(
            "bdmorph: warning: {} flipped triangles",
            frame.stats.flipped_triangles
        );
    }
    let Some(plan) = plan else {
        return Ok(());
    };
    let frames = [output::Frame {
        index: 0,
        t: f64::NAN,
        positions: frame.positions.to_vec(),
        distortion: args.out.color_by.map(|_| frame.distortion.to_vec()),
    }];
    let names: Vec<String> = args
        .meshes
        .iter()
        .zip(&args.weights)
        .map(|(p, w)| format!("{w} {}", p.display()))
        .collect();
    let title = format!("bdmorph blend: {}", names.join(" + "));
    write_frames(&plan, &args.out, &inputs, blend.faces(), &title, &frames)
}
