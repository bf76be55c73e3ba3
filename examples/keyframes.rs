//! The README's keyframe picture: three poses of the gingerbread figure, a path through them
//! and blends of them, every triangle coloured by its conformal distortion from the rest pose.
//!
//! ```sh
//! cargo run --release --example keyframes -- docs/keyframes.png
//! ```
//!
//! K0 is the rest pose, K1 waves (`generate::wave`), K2 raises both arms (`generate::bend`,
//! 0.45). Top row: the path K0 -> K1 -> K2 (ease-in-out) at t = 0, 0.25, 0.5, 0.75, 1, passing
//! through K0, K1 and K2 at t = 0, 0.5 and 1. Bottom row: blends with weights (0.6, 0.2, 0.2),
//! (0.2, 0.6, 0.2), (0.2, 0.2, 0.6), (1/3, 1/3, 1/3) and (-0.1, 0.55, 0.55) (slightly outside
//! the simplex). Colours: viridis on a log scale from 1 (dark) to the largest distortion in
//! the picture (yellow).

use bdmorph::render::{colour, raster, Drawing, ImageSize, Viewport};
use bdmorph::{generate, Blend, Easing, KeyframePath, PathOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "keyframes.png".into());
    let rest = generate::figure(0.01);
    let keys = [
        rest.clone(),
        generate::wave(&rest, 1.0),
        generate::bend(&rest, 0.45),
    ];
    let mut frames: Vec<(Vec<[f64; 2]>, Vec<f64>)> = Vec::new();
    let mut path =
        KeyframePath::with_options(&keys, PathOptions::default().with_easing(Easing::EaseInOut))?;
    for i in 0..5 {
        let f = path.frame(f64::from(i) / 4.0)?;
        eprintln!(
            "path t = {}: max distortion {:.3}, {} flipped",
            f.stats.t, f.stats.max_conformal_distortion, f.stats.flipped_triangles
        );
        frames.push((f.positions.to_vec(), f.distortion.to_vec()));
    }
    let mut blend = Blend::new(&keys)?;
    let third = 1.0 / 3.0;
    for w in [
        [0.6, 0.2, 0.2],
        [0.2, 0.6, 0.2],
        [0.2, 0.2, 0.6],
        [third, third, 1.0 - 2.0 * third],
        [-0.1, 0.55, 0.55],
    ] {
        let f = blend.frame_weights(&w)?;
        eprintln!(
            "blend {w:?}: max distortion {:.3}, {} flipped",
            f.stats.max_conformal_distortion, f.stats.flipped_triangles
        );
        frames.push((f.positions.to_vec(), f.distortion.to_vec()));
    }
    let max = colour::distortion_scale(frames.iter().map(|(_, d)| d.as_slice()));
    eprintln!("colour scale: 1 to {max:.3}");
    let size = ImageSize {
        width: 240,
        height: 240,
    };
    let images: Vec<_> = frames
        .iter()
        .map(|(positions, distortion)| {
            // Each picture fits its own frame, so the poses are comparable in size.
            let view = Viewport::fit([positions.as_slice()]);
            let colours = colour::shade_colours(&colour::distortion_shades(distortion, max));
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
    let sheet = raster::strip(&images, 5);
    std::fs::write(&out, raster::encode_png(&sheet)?)?;
    eprintln!("wrote {out}");
    Ok(())
}
