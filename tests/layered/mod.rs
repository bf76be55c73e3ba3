//! Layered pictures made in code for the tests: a figure of six overlapping parts, written as
//! OpenRaster (a zip of PNG layers and stack.xml) and as PSD (8-bit RGB, raw channels).
#![allow(dead_code)]

use std::io::Write as _;

/// A canvas-sized layer.
pub struct TestLayer {
    /// Its name.
    pub name: String,
    /// Canvas-sized RGBA.
    pub rgba: Vec<u8>,
    /// Hidden in the file.
    pub hidden: bool,
}

/// The canvas of [`figure`].
pub const FIGURE_SIZE: (u32, u32) = (300, 240);

/// Each part's colour: torso blue, head yellow, upper arms green, forearms red (left) and
/// magenta (right).
pub const COLOURS: [(&str, [u8; 3]); 6] = [
    ("torso", [40, 60, 220]),
    ("head", [230, 200, 40]),
    ("upper_arm_l", [40, 180, 60]),
    ("forearm_l", [220, 40, 40]),
    ("upper_arm_r", [40, 200, 120]),
    ("forearm_r", [200, 40, 200]),
];

/// A layer of `colour` filled where `inside(x, y)` holds (pixel centres, rows from the top).
pub fn shape(name: &str, colour: [u8; 3], inside: impl Fn(f64, f64) -> bool) -> TestLayer {
    let (w, h) = FIGURE_SIZE;
    let mut rgba = vec![0u8; (w * h * 4) as usize];
    for y in 0..h {
        for x in 0..w {
            if inside(f64::from(x) + 0.5, f64::from(y) + 0.5) {
                let at = ((y * w + x) * 4) as usize;
                rgba[at..at + 4].copy_from_slice(&[colour[0], colour[1], colour[2], 255]);
            }
        }
    }
    TestLayer {
        name: name.into(),
        rgba,
        hidden: false,
    }
}

/// A capsule from `a` to `b` of radius `r`.
fn capsule(a: [f64; 2], b: [f64; 2], r: f64) -> impl Fn(f64, f64) -> bool {
    move |x, y| {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let t = (((x - a[0]) * dx + (y - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
        let (px, py) = (a[0] + t * dx, a[1] + t * dy);
        (x - px).hypot(y - py) <= r
    }
}

/// The figure, bottom first: a torso, a head over it, and two arms of two segments each,
/// overlapping where they join (shoulders, elbows, neck).
pub fn figure() -> Vec<TestLayer> {
    vec![
        shape("torso", COLOURS[0].1, |x, y| {
            (125.0..=175.0).contains(&x) && (60.0..=180.0).contains(&y)
        }),
        shape(
            "head",
            COLOURS[1].1,
            capsule([150.0, 44.0], [150.0, 46.0], 24.0),
        ),
        shape(
            "upper_arm_l",
            COLOURS[2].1,
            capsule([135.0, 80.0], [85.0, 80.0], 10.0),
        ),
        shape(
            "forearm_l",
            COLOURS[3].1,
            capsule([92.0, 80.0], [35.0, 80.0], 9.0),
        ),
        shape(
            "upper_arm_r",
            COLOURS[4].1,
            capsule([165.0, 80.0], [215.0, 80.0], 10.0),
        ),
        shape(
            "forearm_r",
            COLOURS[5].1,
            capsule([208.0, 80.0], [265.0, 80.0], 9.0),
        ),
    ]
}

/// The bounding box of a layer's visible pixels: left, top, right, bottom (exclusive).
fn bounds(rgba: &[u8], w: u32, h: u32) -> [u32; 4] {
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for y in 0..h {
        for x in 0..w {
            if rgba[((y * w + x) * 4 + 3) as usize] != 0 {
                x0 = x0.min(x);
                y0 = y0.min(y);
                x1 = x1.max(x + 1);
                y1 = y1.max(y + 1);
            }
        }
    }
    if x0 >= x1 {
        [0, 0, 0, 0]
    } else {
        [x0, y0, x1, y1]
    }
}

fn crop(rgba: &[u8], w: u32, b: [u32; 4]) -> Vec<u8> {
    let mut out = Vec::new();
    for y in b[1]..b[3] {
        out.extend_from_slice(&rgba[((y * w + b[0]) * 4) as usize..((y * w + b[2]) * 4) as usize]);
    }
    out
}

fn png(width: u32, height: u32, rgba: &[u8]) -> Vec<u8> {
    bdmorph::render::raster::encode_png(&bdmorph::render::Image {
        width,
        height,
        rgba: rgba.to_vec(),
    })
    .expect("png")
}

/// The `stack.xml` of [`write_ora`].
pub fn ora_stack(layers: &[TestLayer], grouped: usize) -> String {
    let (w, h) = FIGURE_SIZE;
    let mut entries = Vec::new();
    for (i, l) in layers.iter().enumerate() {
        let b = bounds(&l.rgba, w, h);
        entries.push(format!(
            "<layer name=\"{}\" src=\"data/layer{i}.png\" x=\"{}\" y=\"{}\" visibility=\"{}\" opacity=\"1.0\"/>",
            l.name,
            b[0],
            b[1],
            if l.hidden { "hidden" } else { "visible" }
        ));
    }
    // stack.xml lists the topmost first.
    entries.reverse();
    let (inner, outer) = entries.split_at(grouped.min(entries.len()));
    let mut xml =
        format!("<?xml version='1.0' encoding='UTF-8'?>\n<image w=\"{w}\" h=\"{h}\"><stack>");
    if !inner.is_empty() {
        xml.push_str("<stack name=\"arms\">");
        xml.push_str(&inner.concat());
        xml.push_str("</stack>");
    }
    xml.push_str(&outer.concat());
    xml.push_str("</stack></image>");
    xml
}

/// An OpenRaster file of `layers` (bottom first): each layer's PNG cropped to its pixels and
/// placed by x and y; hidden ones marked; the last `grouped` layers inside a group `arms`.
pub fn write_ora(layers: &[TestLayer], grouped: usize) -> Vec<u8> {
    ora_with_stack(layers, ora_stack(layers, grouped).as_bytes())
}

/// An OpenRaster file of `layers`' PNGs (`data/layer{i}.png`) with `stack` as its stack.xml.
pub fn ora_with_stack(layers: &[TestLayer], stack: &[u8]) -> Vec<u8> {
    let (w, h) = FIGURE_SIZE;
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let stored =
        zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    let deflated = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    zip.start_file("mimetype", stored).expect("zip");
    zip.write_all(b"image/openraster").expect("zip");
    for (i, l) in layers.iter().enumerate() {
        let b = bounds(&l.rgba, w, h);
        zip.start_file(format!("data/layer{i}.png"), deflated)
            .expect("zip");
        zip.write_all(&png(b[2] - b[0], b[3] - b[1], &crop(&l.rgba, w, b)))
            .expect("zip");
    }
    zip.start_file("stack.xml", deflated).expect("zip");
    zip.write_all(stack).expect("zip");
    zip.finish().expect("zip").into_inner()
}

/// A PSD file (version 1, 8-bit RGB, raw channels) of `layers` (bottom first), each layer's
/// record bounded by its pixels; hidden layers with flag bit 1 set, as Photoshop writes them.
pub fn write_psd(layers: &[TestLayer]) -> Vec<u8> {
    write_psd_with(layers, 3, 8)
}

/// [`write_psd`] with another colour mode and depth in the header (to test refusals).
pub fn write_psd_with(layers: &[TestLayer], mode: u16, depth: u16) -> Vec<u8> {
    let (w, h) = FIGURE_SIZE;
    let mut out = Vec::new();
    out.extend_from_slice(b"8BPS");
    out.extend_from_slice(&1u16.to_be_bytes());
    out.extend_from_slice(&[0; 6]);
    out.extend_from_slice(&3u16.to_be_bytes());
    out.extend_from_slice(&h.to_be_bytes());
    out.extend_from_slice(&w.to_be_bytes());
    out.extend_from_slice(&depth.to_be_bytes());
    out.extend_from_slice(&mode.to_be_bytes());
    out.extend_from_slice(&0u32.to_be_bytes()); // colour mode data
    out.extend_from_slice(&0u32.to_be_bytes()); // image resources
    let mut info = Vec::new();
    info.extend_from_slice(&(layers.len() as i16).to_be_bytes());
    let mut data = Vec::new();
    for l in layers {
        let b = bounds(&l.rgba, w, h);
        let (lw, lh) = (b[2] - b[0], b[3] - b[1]);
        for v in [b[1], b[0], b[3], b[2]] {
            info.extend_from_slice(&(v as i32).to_be_bytes());
        }
        info.extend_from_slice(&4u16.to_be_bytes());
        for id in [-1i16, 0, 1, 2] {
            info.extend_from_slice(&id.to_be_bytes());
            info.extend_from_slice(&(2 + lw * lh).to_be_bytes());
        }
        info.extend_from_slice(b"8BIMnorm");
        info.extend_from_slice(&[255, 0, if l.hidden { 0x0a } else { 0x08 }, 0]);
        let mut extra = Vec::new();
        extra.extend_from_slice(&0u32.to_be_bytes()); // mask
        extra.extend_from_slice(&0u32.to_be_bytes()); // blending ranges
        let name = l.name.as_bytes();
        extra.push(name.len() as u8);
        extra.extend_from_slice(name);
        while extra.len() % 4 != 0 {
            extra.push(0);
        }
        info.extend_from_slice(&(extra.len() as u32).to_be_bytes());
        info.extend_from_slice(&extra);
        let pixels = crop(&l.rgba, w, b);
        for channel in [3usize, 0, 1, 2] {
            data.extend_from_slice(&0u16.to_be_bytes());
            data.extend(pixels.chunks_exact(4).map(|p| p[channel]));
        }
    }
    info.extend_from_slice(&data);
    if info.len() % 2 == 1 {
        info.push(0);
    }
    let mut section = Vec::new();
    section.extend_from_slice(&(info.len() as u32).to_be_bytes());
    section.extend_from_slice(&info);
    section.extend_from_slice(&0u32.to_be_bytes()); // global layer mask
    out.extend_from_slice(&(section.len() as u32).to_be_bytes());
    out.extend_from_slice(&section);
    // The merged image: raw, three planes, white.
    out.extend_from_slice(&0u16.to_be_bytes());
    out.extend(std::iter::repeat_n(255u8, (w * h * 3) as usize));
    out
}
