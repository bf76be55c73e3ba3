//! `bdmorph blend K0 K1 ... --weights w0,w1,... -o OUT`.

use std::io::Write;

use bdmorph::Blend;

use super::morph::{
    check_options, check_size, listed, max_distance, morph_options, read_inputs, write_frames,
};
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
    let inputs = read_inputs(&args.meshes, &args.out, &args.solver, plan.as_ref())?;
    let options = morph_options(&args.solver, bdmorph::Placement::Anchor);
    let blend = match &args.solver.program {
        Some(path) => {
            let program = super::compile::load(path, &args.meshes[0], &inputs.keyframes[0])?;
            Blend::with_program(program, &inputs.keyframes, options)
        }
        None => Blend::with_options(&inputs.keyframes, options),
    };
    let mut blend = blend.map_err(|e| inputs.setup_error(e))?;
    let inverted = blend.structure().inverted.clone();
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
    // Weights that pick one keyframe with inverted triangles: the frame is not that pose.
    let picked = args.weights.iter().position(|&w| w == 1.0);
    if let Some(k) = picked.filter(|&k| !inverted[k].is_empty()) {
        if !args.out.quiet {
            let deviation = max_distance(frame.positions, &inputs.keyframes[k].positions);
            eprintln!(
                "bdmorph: note: the weights pick keyframe {k} ({}), which has {} inverted \
                 triangles (face {}, 0-based): the frame is the flat shape nearest its side \
                 lengths, not that pose; it differs from it by up to {deviation:.3e}",
                inputs.paths[k].display(),
                inverted[k].len(),
                listed(&inverted[k]),
            );
        }
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
