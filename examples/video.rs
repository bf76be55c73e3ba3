//! MP4 against GIF on the demo's morph: encoding time per frame and file size.
//!
//! The gingerbread figure of `bdmorph demo` waves in N frames (default 60) rendered at
//! SIZE x SIZE pixels (default 800), drawn three ways: flat with edges (a line drawing),
//! coloured by distortion, and textured (a procedural texture of stripes and dots). Each
//! animation is encoded as H.264 MP4 (`render::video`) and as GIF (`render::raster`), timed
//! without the rendering.
//!
//! ```sh
//! cargo run --release --example video [-- N SIZE]
//! ```

use std::time::Instant;

use bdmorph::render::{colour, raster, video, Drawing, Image, ImageSize, Viewport};
use bdmorph::{generate, Morph, MorphOptions};

/// Stripes with dots, in the texture's own pixels.
fn texture(size: u32) -> Image {
    let mut rgba = Vec::with_capacity((size * size * 4) as usize);
    for row in 0..size {
        for col in 0..size {
            let (x, y) = (f64::from(col) / 32.0, f64::from(row) / 32.0);
            let dot = ((x.fract() - 0.5).hypot(y.fract() - 0.5)) < 0.18;
            let stripe = ((x + y) as u32) % 2 == 0;
            let c: [u8; 4] = match (dot, stripe) {
                (true, _) => [250, 245, 235, 255],
                (false, true) => [190, 110, 50, 255],
                (false, false) => [150, 80, 40, 255],
            };
            rgba.extend_from_slice(&c);
        }
    }
    Image {
        width: size,
        height: size,
        rgba,
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let frames: usize = args.get(1).map_or(Ok(60), |a| a.parse())?;
    let side: u32 = args.get(2).map_or(Ok(800), |a| a.parse())?;
    let size = ImageSize {
        width: side,
        height: side,
    };
    let fps = 25;
    let source = generate::figure(0.01);
    let target = generate::wave(&source, 1.0);
    let mut morph = Morph::new(&source, &target, MorphOptions::default())?;
    let mut positions = Vec::with_capacity(frames);
    let mut distortion = Vec::with_capacity(frames);
    for i in 0..frames {
        let f = morph.frame(i as f64 / (frames - 1).max(1) as f64)?;
        positions.push(f.positions.to_vec());
        distortion.push(f.distortion.to_vec());
    }
    let view = Viewport::fit(positions.iter().map(Vec::as_slice));
    let max = colour::distortion_scale(distortion.iter().map(Vec::as_slice));
    let shades: Vec<Vec<[u8; 3]>> = distortion
        .iter()
        .map(|d| colour::shade_colours(&colour::distortion_shades(d, max)))
        .collect();
    let tex = texture(512);
    let corner_uv = source.normalized_texcoords().corner_uv();
    println!(
        "{} vertices, {} triangles; {frames} frames of {side}x{side} at {fps} fps",
        source.positions.len(),
        source.faces.len()
    );
    println!(
        "{:<12} {:>10} {:>12} {:>10} {:>12}",
        "look", "MP4 bytes", "MP4 ms/frame", "GIF bytes", "GIF ms/frame"
    );
    for look in ["flat", "distortion", "textured"] {
        let images: Vec<Image> = (0..frames)
            .map(|i| {
                let drawing = Drawing {
                    faces: &source.faces,
                    corner_uv: (look == "textured").then_some(corner_uv.as_slice()),
                    texture: (look == "textured").then_some(&tex),
                    face_colours: (look == "distortion").then(|| shades[i].as_slice()),
                    depth: None,
                };
                raster::render(&positions[i], &drawing, &view, size)
                    .expect("within the picture budget")
            })
            .collect();
        let start = Instant::now();
        let mp4 = video::encode_mp4(&images, fps)?;
        let mp4_ms = start.elapsed().as_secs_f64() * 1e3 / frames as f64;
        let start = Instant::now();
        let gif = raster::encode_gif(&images, (100 / fps) as u16)?;
        let gif_ms = start.elapsed().as_secs_f64() * 1e3 / frames as f64;
        println!(
            "{look:<12} {:>10} {mp4_ms:>12.1} {:>10} {gif_ms:>12.1}",
            mp4.len(),
            gif.len()
        );
        if let Some(dir) = std::env::var_os("BDMORPH_VIDEO_OUT") {
            let dir = std::path::PathBuf::from(dir);
            std::fs::create_dir_all(&dir)?;
            std::fs::write(dir.join(format!("{look}.mp4")), &mp4)?;
            std::fs::write(dir.join(format!("{look}.gif")), &gif)?;
        }
    }
    Ok(())
}
