//! Puts pictures side by side in one PNG (how the README's strips are made).
//!
//! `cargo run --release --example strip -- OUT.png IN1.png IN2.png ...`

use bdmorph::render::raster;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((out, inputs)) = args.split_first().filter(|(_, rest)| !rest.is_empty()) else {
        return Err("usage: strip OUT.png IN1.png IN2.png ...".into());
    };
    let images = inputs
        .iter()
        .map(|p| raster::read_image(std::path::Path::new(p)))
        .collect::<Result<Vec<_>, _>>()?;
    let strip = raster::strip(&images, images.len());
    bdmorph::io::write_bytes_atomic(std::path::Path::new(out), &raster::encode_png(&strip)?)?;
    Ok(())
}
