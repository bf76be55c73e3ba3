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
pub fn bounds(rgba: &[u8], w: u32, h: u32) -> [u32; 4] {
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

pub fn crop(rgba: &[u8], w: u32, b: [u32; 4]) -> Vec<u8> {
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

/// How [`write_psd_spec`] writes a PSD.
#[derive(Clone, Copy, Debug)]
pub struct PsdSpec {
    /// Colour mode: 1 greyscale (the red channel written as grey), 3 RGB (others written as
    /// RGB with that mode in the header, to test refusals).
    pub mode: u16,
    /// Bits per channel: 8, 16 (each 8-bit value `v` written as `v * 257 + 100`, clamped, so
    /// that reading rounds it back), 32 (floats: alpha `v / 255`, colour linear light).
    pub depth: u16,
    /// Channel compression: 0 raw, 1 RLE, 2 ZIP, 3 ZIP with prediction.
    pub compression: u16,
    /// Version 2 (PSB): 8-byte lengths.
    pub psb: bool,
    /// Each layer with a transparency channel (-1); without, the layer is opaque over its
    /// rectangle.
    pub alpha: bool,
    /// The layer info in a tagged block (`Lr16`, `Lr32`) after the global mask, as
    /// Photoshop writes 16- and 32-bit documents, instead of in the layer info section.
    pub tagged: bool,
    /// The last `n` layers inside a group `arms`, hidden or not.
    pub group: Option<(usize, bool)>,
}

impl Default for PsdSpec {
    fn default() -> Self {
        PsdSpec {
            mode: 3,
            depth: 8,
            compression: 0,
            psb: false,
            alpha: true,
            tagged: false,
            group: None,
        }
    }
}

/// A PSD file (version 1, 8-bit RGB, raw channels) of `layers` (bottom first), each layer's
/// record bounded by its pixels; hidden layers with flag bit 1 set, as Photoshop writes them.
pub fn write_psd(layers: &[TestLayer]) -> Vec<u8> {
    write_psd_with(layers, 3, 8)
}

/// [`write_psd`] with another colour mode and depth in the header (to test refusals).
pub fn write_psd_with(layers: &[TestLayer], mode: u16, depth: u16) -> Vec<u8> {
    write_psd_spec(
        layers,
        &PsdSpec {
            mode,
            depth,
            ..PsdSpec::default()
        },
    )
}

/// The 8-bit value `v` as [`PsdSpec::depth`] bytes (big-endian).
fn sample(v: u8, depth: u16, colour: bool, out: &mut Vec<u8>) {
    match depth {
        16 => {
            let s = if v == 255 {
                65535
            } else {
                u16::from(v) * 257 + 100
            };
            out.extend_from_slice(&s.to_be_bytes());
        }
        32 => {
            let x = f32::from(v) / 255.0;
            let x = if !colour {
                x
            } else if x <= 0.04045 {
                x / 12.92
            } else {
                ((x + 0.055) / 1.055).powf(2.4)
            };
            out.extend_from_slice(&x.to_be_bytes());
        }
        _ => out.push(v),
    }
}

/// PackBits: runs of three or more as repeats, the rest as literals.
pub fn pack_bits(row: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < row.len() {
        let mut run = 1;
        while i + run < row.len() && row[i + run] == row[i] && run < 128 {
            run += 1;
        }
        if run >= 3 {
            out.push((1 - run as i32) as i8 as u8);
            out.push(row[i]);
            i += run;
        } else {
            let start = i;
            while i < row.len() && i - start < 128 {
                let mut r = 1;
                while i + r < row.len() && row[i + r] == row[i] && r < 3 {
                    r += 1;
                }
                if r >= 3 {
                    break;
                }
                i += 1;
            }
            out.push((i - start - 1) as u8);
            out.extend_from_slice(&row[start..i]);
        }
    }
    out
}

/// A channel's image data (compression field first) of `rows`, each `row_bytes` long.
pub fn encode_channel(raw: &[u8], row_bytes: usize, depth: u16, spec: &PsdSpec) -> Vec<u8> {
    let mut out = spec.compression.to_be_bytes().to_vec();
    let rows: Vec<&[u8]> = if row_bytes == 0 {
        Vec::new()
    } else {
        raw.chunks(row_bytes).collect()
    };
    match spec.compression {
        1 => {
            let packed: Vec<Vec<u8>> = rows.iter().map(|r| pack_bits(r)).collect();
            for p in &packed {
                if spec.psb {
                    out.extend_from_slice(&(p.len() as u32).to_be_bytes());
                } else {
                    out.extend_from_slice(&(p.len() as u16).to_be_bytes());
                }
            }
            packed.iter().for_each(|p| out.extend_from_slice(p));
        }
        2 | 3 => {
            let mut data = Vec::new();
            for r in rows {
                let mut r = r.to_vec();
                if spec.compression == 3 {
                    predict(&mut r, depth);
                }
                data.extend_from_slice(&r);
            }
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            z.write_all(&data).expect("zlib");
            out.extend_from_slice(&z.finish().expect("zlib"));
        }
        _ => out.extend_from_slice(raw),
    }
    out
}

/// ZIP with prediction: each sample replaced by its difference from the one before.
fn predict(row: &mut [u8], depth: u16) {
    match depth {
        16 => {
            let mut prev = 0u16;
            for c in row.chunks_exact_mut(2) {
                let v = u16::from_be_bytes([c[0], c[1]]);
                c.copy_from_slice(&v.wrapping_sub(prev).to_be_bytes());
                prev = v;
            }
        }
        32 => {
            let w = row.len() / 4;
            let mut planes = vec![0u8; row.len()];
            for x in 0..w {
                for b in 0..4 {
                    planes[b * w + x] = row[x * 4 + b];
                }
            }
            for i in (1..planes.len()).rev() {
                planes[i] = planes[i].wrapping_sub(planes[i - 1]);
            }
            row.copy_from_slice(&planes);
        }
        _ => {
            for i in (1..row.len()).rev() {
                row[i] = row[i].wrapping_sub(row[i - 1]);
            }
        }
    }
}

/// One layer record: `rect` (top, left, bottom, right), its channels' (id, data), flags,
/// name, and an `lsct` divider type if any.
pub fn psd_record(
    rect: [i32; 4],
    channels: &[(i16, &[u8])],
    flags: u8,
    name: &str,
    divider: Option<u32>,
    psb: bool,
) -> Vec<u8> {
    let mut info = Vec::new();
    for v in rect {
        info.extend_from_slice(&v.to_be_bytes());
    }
    info.extend_from_slice(&(channels.len() as u16).to_be_bytes());
    for (id, data) in channels {
        info.extend_from_slice(&id.to_be_bytes());
        if psb {
            info.extend_from_slice(&(data.len() as u64).to_be_bytes());
        } else {
            info.extend_from_slice(&(data.len() as u32).to_be_bytes());
        }
    }
    info.extend_from_slice(b"8BIMnorm");
    info.extend_from_slice(&[255, 0, flags, 0]);
    let mut extra = Vec::new();
    extra.extend_from_slice(&0u32.to_be_bytes()); // mask
    extra.extend_from_slice(&0u32.to_be_bytes()); // blending ranges
    let ascii: Vec<u8> = name
        .bytes()
        .map(|b| if b.is_ascii() { b } else { b'?' })
        .collect();
    extra.push(ascii.len() as u8);
    extra.extend_from_slice(&ascii);
    while extra.len() % 4 != 0 {
        extra.push(0);
    }
    // The Unicode name.
    let units: Vec<u16> = name.encode_utf16().collect();
    let mut luni = (units.len() as u32).to_be_bytes().to_vec();
    units
        .iter()
        .for_each(|u| luni.extend_from_slice(&u.to_be_bytes()));
    while luni.len() % 4 != 0 {
        luni.push(0);
    }
    extra.extend_from_slice(b"8BIMluni");
    extra.extend_from_slice(&(luni.len() as u32).to_be_bytes());
    extra.extend_from_slice(&luni);
    if let Some(kind) = divider {
        extra.extend_from_slice(b"8BIMlsct");
        extra.extend_from_slice(&4u32.to_be_bytes());
        extra.extend_from_slice(&kind.to_be_bytes());
    }
    info.extend_from_slice(&(extra.len() as u32).to_be_bytes());
    info.extend_from_slice(&extra);
    info
}

/// A whole PSD: header, empty colour mode data and image resources, `records` (bottom first)
/// and their channel `data`, and a white merged picture (raw).
pub fn psd_file(
    (w, h): (u32, u32),
    spec: &PsdSpec,
    count: usize,
    records: &[u8],
    data: &[u8],
) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(b"8BPS");
    out.extend_from_slice(&(if spec.psb { 2u16 } else { 1 }).to_be_bytes());
    out.extend_from_slice(&[0; 6]);
    out.extend_from_slice(&3u16.to_be_bytes());
    out.extend_from_slice(&h.to_be_bytes());
    out.extend_from_slice(&w.to_be_bytes());
    out.extend_from_slice(&spec.depth.to_be_bytes());
    out.extend_from_slice(&spec.mode.to_be_bytes());
    out.extend_from_slice(&0u32.to_be_bytes()); // colour mode data
    out.extend_from_slice(&0u32.to_be_bytes()); // image resources
    let mut info = Vec::new();
    info.extend_from_slice(&(count as i16).to_be_bytes());
    info.extend_from_slice(records);
    info.extend_from_slice(data);
    if info.len() % 2 == 1 {
        info.push(0);
    }
    let long = |v: usize, out: &mut Vec<u8>| {
        if spec.psb {
            out.extend_from_slice(&(v as u64).to_be_bytes());
        } else {
            out.extend_from_slice(&(v as u32).to_be_bytes());
        }
    };
    let mut section = Vec::new();
    if spec.tagged {
        long(0, &mut section); // an empty layer info
        section.extend_from_slice(&0u32.to_be_bytes()); // global layer mask
        section.extend_from_slice(b"8BIM");
        section.extend_from_slice(if spec.depth == 32 { b"Lr32" } else { b"Lr16" });
        while info.len() % 4 != 0 {
            info.push(0);
        }
        long(info.len(), &mut section);
        section.extend_from_slice(&info);
    } else {
        long(info.len(), &mut section);
        section.extend_from_slice(&info);
        section.extend_from_slice(&0u32.to_be_bytes()); // global layer mask
    }
    long(section.len(), &mut out);
    out.extend_from_slice(&section);
    // The merged image: raw, three planes, white (cut to nothing beyond 64 MiB: the readers
    // do not read it).
    out.extend_from_slice(&0u16.to_be_bytes());
    let bps = usize::from(spec.depth / 8).max(1);
    let merged = (w as usize * h as usize * 3) * bps;
    if merged <= 64 << 20 {
        out.extend(std::iter::repeat_n(255u8, merged));
    }
    out
}

/// A PSD of `layers` (bottom first) as `spec` says: each layer's record bounded by its
/// pixels; hidden layers with flag bit 1 set, as Photoshop writes them.
pub fn write_psd_spec(layers: &[TestLayer], spec: &PsdSpec) -> Vec<u8> {
    let (w, h) = FIGURE_SIZE;
    let mut records = Vec::new();
    let mut data = Vec::new();
    let mut count = 0;
    let grouped_from = spec.group.map(|(n, _)| layers.len().saturating_sub(n));
    let bps = usize::from(spec.depth / 8).max(1);
    for (i, l) in layers.iter().enumerate() {
        if Some(i) == grouped_from {
            let empty = encode_channel(&[], 0, spec.depth, spec);
            let ch: Vec<(i16, &[u8])> = [-1i16, 0, 1, 2]
                .iter()
                .map(|&id| (id, &empty[..]))
                .collect();
            records.extend(psd_record(
                [0; 4],
                &ch,
                0x08,
                "</Layer group>",
                Some(3),
                spec.psb,
            ));
            for _ in 0..4 {
                data.extend_from_slice(&empty);
            }
            count += 1;
        }
        let b = bounds(&l.rgba, w, h);
        let pixels = crop(&l.rgba, w, b);
        let lw = (b[2] - b[0]) as usize;
        let ids: &[(i16, usize)] = match (spec.mode, spec.alpha) {
            (1, true) => &[(-1, 3), (0, 0)],
            (1, false) => &[(0, 0)],
            (_, true) => &[(-1, 3), (0, 0), (1, 1), (2, 2)],
            (_, false) => &[(0, 0), (1, 1), (2, 2)],
        };
        let encoded: Vec<(i16, Vec<u8>)> = ids
            .iter()
            .map(|&(id, c)| {
                let mut raw = Vec::new();
                pixels
                    .chunks_exact(4)
                    .for_each(|p| sample(p[c], spec.depth, id >= 0, &mut raw));
                (id, encode_channel(&raw, lw * bps, spec.depth, spec))
            })
            .collect();
        let ch: Vec<(i16, &[u8])> = encoded.iter().map(|(id, d)| (*id, &d[..])).collect();
        let rect = [b[1], b[0], b[3], b[2]].map(|v| v as i32);
        let flags = if l.hidden { 0x0a } else { 0x08 };
        records.extend(psd_record(rect, &ch, flags, &l.name, None, spec.psb));
        encoded.iter().for_each(|(_, d)| data.extend_from_slice(d));
        count += 1;
    }
    if let Some((_, hidden)) = spec.group {
        let empty = encode_channel(&[], 0, spec.depth, spec);
        let ch: Vec<(i16, &[u8])> = [-1i16, 0, 1, 2]
            .iter()
            .map(|&id| (id, &empty[..]))
            .collect();
        let flags = if hidden { 0x0a } else { 0x08 };
        records.extend(psd_record([0; 4], &ch, flags, "arms", Some(1), spec.psb));
        for _ in 0..4 {
            data.extend_from_slice(&empty);
        }
        count += 1;
    }
    psd_file(FIGURE_SIZE, spec, count, &records, &data)
}

/// A character painted as artists paint one: a torso (columns 120..180, rows 60..190) under two
/// arms that enter it at an angle, each arm's root well inside the torso. Also each arm's
/// shoulder, where its centre line crosses the torso's outline (pixels, rows from the top), and
/// its width. Bottom first: torso, left arm, right arm.
pub fn torso_under_arms() -> (Vec<TestLayer>, [([f64; 2], f64); 2]) {
    let layers = vec![
        shape("torso", [40, 60, 220], |x, y| {
            (120.0..=180.0).contains(&x) && (60.0..=190.0).contains(&y)
        }),
        // From (135, 95) to (60, 130), radius 12: it crosses x = 120 at a fifth of its length.
        shape(
            "arm_l",
            [40, 180, 60],
            capsule([135.0, 95.0], [60.0, 130.0], 12.0),
        ),
        // From (165, 85) to (250, 50), radius 11: it crosses x = 180 at 15/85 of its length.
        shape(
            "arm_r",
            [240, 160, 40],
            capsule([165.0, 85.0], [250.0, 50.0], 11.0),
        ),
    ];
    let shoulders = [
        ([120.0, 95.0 + 35.0 * 0.2], 24.0),
        ([180.0, 85.0 - 35.0 * 15.0 / 85.0], 22.0),
    ];
    (layers, shoulders)
}
