//! The README's in-betweens picture: two drawings of a figure made in code (the second with
//! its arm raised 115° and its body bent 11°), and the in-betweens BDMORPH makes between them
//! on their compatible mesh, each textured by a smooth cross-fade of the two pictures.
//!
//! ```sh
//! cargo run --release --example inbetweens -- docs/inbetween-strip.png
//! ```
//!
//! Left to right: drawing A as drawn, the in-betweens at t = 0, 0.25, 0.5, 0.75, 1, drawing B
//! as drawn. Prints the compatible mesh's report and each frame's largest distortion.

use bdmorph::generate;
use bdmorph::inbetween::{Crossfade, Inbetween, InbetweenOptions};
use bdmorph::render::{raster, Background, Drawing, Image, ImageSize, Viewport};

/// The picture's pixels in their own frame, on white.
fn on_white(picture: &Image) -> Image {
    let clear = Image {
        width: picture.width,
        height: picture.height,
        rgba: vec![0; picture.rgba.len()],
    };
    raster::crossfade(picture, &clear, 0.0, Background::WHITE)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "inbetween-strip.png".into());
    let size = 256;
    let a = generate::figure_picture(size, 0.0, 0.0);
    let b = generate::figure_picture(size, 2.0, 0.2);
    let mut inbetween = Inbetween::new(&a, &b, &[], &InbetweenOptions::default())?;
    let c = inbetween.compatible().clone();
    println!("{:?}", c.report);
    let (uv_a, uv_b) = (c.texcoords_a.corner_uv(), c.texcoords_b.corner_uv());
    let view = Viewport {
        min: [0.0, 0.0],
        max: [f64::from(size), f64::from(size)],
    };
    let image = ImageSize {
        width: size,
        height: size,
    };
    let mut cells = vec![on_white(&a)];
    for k in 0..=4 {
        let t = f64::from(k) / 4.0;
        let frame = inbetween.frame(t)?;
        println!(
            "t = {t}: largest distortion {:.3}, flipped {}",
            frame.stats.max_conformal_distortion, frame.stats.flipped_triangles
        );
        let positions = frame.positions.to_vec();
        let draw = |texture: &Image, uv: &[[[f64; 2]; 3]]| {
            let drawing = Drawing {
                faces: &c.mesh.faces,
                corner_uv: Some(uv),
                texture: Some(texture),
                ..Drawing::default()
            };
            raster::render_on(&positions, &drawing, &view, image, Background::Transparent)
                .expect("within the picture budget")
        };
        let (first, second) = (draw(&a, &uv_a), draw(&b, &uv_b));
        cells.push(raster::crossfade(
            &first,
            &second,
            Crossfade::Smooth.weight(t),
            Background::WHITE,
        ));
    }
    cells.push(on_white(&b));
    let strip = raster::strip(&cells, cells.len());
    std::fs::write(&out, raster::encode_png(&strip)?)?;
    println!("wrote {out}");
    Ok(())
}
