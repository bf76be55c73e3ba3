//! The README's posing picture: the demo figure raising its right arm by the three methods of
//! `bdmorph::deform`, with the same handles and the same 20 mouse moves, and the KVF pose
//! morphed from the rest pose as a keyframe.
//!
//! ```sh
//! cargo run --release --example posing -- docs/posing.png
//! ```
//!
//! Handles: both feet and the top of the head held, the right hand dragged along an arc about
//! the shoulder, 65 degrees up. Top row: the rest pose, then KVF (default weight 100), ARAP,
//! and bounded distortion with `K = 1.3`, each after the drag and 20 more drags at the end
//! (a mouse held still). Bottom row: BDMORPH from the rest pose to the KVF pose at t = 0.25,
//! 0.5, 0.75, 1. Triangles coloured by conformal distortion from the rest pose (viridis, log
//! scale, one scale for the whole picture); the handles' triangles black. Prints each pose's
//! largest distortion, flips, pin residual and the time per drag.

use bdmorph::deform::{Deformer, PoseMethod};
use bdmorph::render::{colour, raster, Drawing, ImageSize, Viewport};
use bdmorph::{generate, KeyframePath, PathOptions, PlanarMesh};

/// How far the hand goes up, in degrees about the shoulder.
const RAISE: f64 = 65.0;

/// The bounded method's bound.
const BOUND: f64 = 1.3;

fn nearest(p: &[[f64; 2]], q: [f64; 2]) -> u32 {
    (0..p.len())
        .min_by(|&a, &b| {
            let d = |i: usize| (p[i][0] - q[0]).powi(2) + (p[i][1] - q[1]).powi(2);
            d(a).total_cmp(&d(b))
        })
        .expect("vertices") as u32
}

/// Each triangle's conformal distortion from `rest`.
fn distortion(rest: &PlanarMesh, pose: &[[f64; 2]]) -> Vec<f64> {
    let shape = bdmorph::distortion::RestShape::new(&rest.positions, &rest.faces);
    let mut each = vec![0.0; rest.faces.len()];
    shape.distortion_into(pose, &mut each);
    each
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "posing.png".into());
    let rest = generate::figure(0.01);
    let p = &rest.positions;
    let pins: Vec<u32> = [[-0.45, -1.5], [0.45, -1.5], [0.0, 2.8], [1.72, 1.4]]
        .into_iter()
        .map(|q| nearest(p, q))
        .collect();
    let start: Vec<[f64; 2]> = pins.iter().map(|&v| p[v as usize]).collect();
    let (hand, shoulder) = (start[3], [0.6, 1.35]);
    let r = (hand[0] - shoulder[0]).hypot(hand[1] - shoulder[1]);
    let a0 = (hand[1] - shoulder[1]).atan2(hand[0] - shoulder[0]);
    let mut frames: Vec<(Vec<[f64; 2]>, Vec<f64>)> = vec![(p.clone(), vec![1.0; rest.faces.len()])];
    let mut kvf_pose = None;
    for method in [
        PoseMethod::kvf(),
        PoseMethod::arap(),
        PoseMethod::bounded(BOUND),
    ] {
        let mut pose = Deformer::new(&rest, method.clone())?;
        pose.set_pins(&pins)?;
        let mut targets = start.clone();
        let started = std::time::Instant::now();
        for k in 1..=20 {
            let a = a0 + RAISE.to_radians() * f64::from(k) / 20.0;
            targets[3] = [shoulder[0] + r * a.cos(), shoulder[1] + r * a.sin()];
            pose.drag(&targets)?;
        }
        let per_drag = started.elapsed().as_secs_f64() / 20.0;
        let mut report = pose.drag(&targets)?;
        for _ in 0..19 {
            report = pose.drag(&targets)?;
        }
        eprintln!(
            "{}: largest distortion {:.3}, {} flipped, pin residual {:.1e}, bound met {:?}, {:.2} ms per drag",
            method.name(),
            report.max_distortion,
            report.flipped_triangles,
            report.pin_residual,
            report.bound_met,
            per_drag * 1e3
        );
        let positions = pose.positions().to_vec();
        if kvf_pose.is_none() {
            kvf_pose = Some(positions.clone());
        }
        let d = distortion(&rest, &positions);
        frames.push((positions, d));
    }
    // A harder drag, not drawn: the hand pulled into the chest in 20 moves (the test
    // `bounded_flips_nothing_on_a_drag_that_folds_the_others`), bounded with K = 3.
    for method in [
        PoseMethod::kvf(),
        PoseMethod::arap(),
        PoseMethod::bounded(3.0),
    ] {
        let mut pose = Deformer::new(&rest, method.clone())?;
        pose.set_pins(&pins)?;
        let mut targets = start.clone();
        let (mut most_flipped, mut unmet) = (0, 0);
        for k in 1..=20 {
            let s = f64::from(k) / 20.0;
            targets[3] = [hand[0] * (1.0 - s), hand[1] + (1.3 - hand[1]) * s];
            let report = pose.drag(&targets)?;
            most_flipped = most_flipped.max(report.flipped_triangles);
            unmet += usize::from(report.bound_met == Some(false));
        }
        let report = pose.drag(&targets)?;
        eprintln!(
            "into the chest, {}: at most {most_flipped} flipped during the drag, {unmet} moves over the bound; at the end largest distortion {:.3}, {} flipped, bound met {:?}",
            method.name(),
            report.max_distortion,
            report.flipped_triangles,
            report.bound_met
        );
    }
    let posed = PlanarMesh {
        positions: kvf_pose.expect("kvf ran"),
        faces: rest.faces.clone(),
    };
    let mut path = KeyframePath::with_options(&[rest.clone(), posed], PathOptions::default())?;
    for t in [0.25, 0.5, 0.75, 1.0] {
        let f = path.frame(t)?;
        eprintln!(
            "morph to the KVF pose, t = {t}: largest distortion {:.3}, {} flipped",
            f.stats.max_conformal_distortion, f.stats.flipped_triangles
        );
        frames.push((f.positions.to_vec(), f.distortion.to_vec()));
    }
    let max = colour::distortion_scale(frames.iter().map(|(_, d)| d.as_slice()));
    eprintln!("colour scale: 1 to {max:.3}");
    let size = ImageSize {
        width: 260,
        height: 260,
    };
    let handle_faces: Vec<bool> = rest
        .faces
        .iter()
        .map(|f| f.iter().any(|v| pins.contains(v)))
        .collect();
    // One view for every picture: the poses are drawn at the same scale and place.
    let view = Viewport::fit(frames.iter().map(|(p, _)| p.as_slice()));
    let images: Vec<_> = frames
        .iter()
        .map(|(positions, distortion)| {
            let mut colours = colour::shade_colours(&colour::distortion_shades(distortion, max));
            for (c, &h) in colours.iter_mut().zip(&handle_faces) {
                if h {
                    *c = [0, 0, 0];
                }
            }
            let drawing = Drawing {
                faces: &rest.faces,
                corner_uv: None,
                texture: None,
                face_colours: Some(&colours),
                depth: None,
            };
            raster::render(positions, &drawing, &view, size).expect("within the picture budget")
        })
        .collect();
    let sheet = raster::strip(&images, 4);
    bdmorph::io::write_bytes_atomic(std::path::Path::new(&out), &raster::encode_png(&sheet)?)?;
    eprintln!("wrote {out}");
    Ok(())
}
