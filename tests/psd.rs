//! Photoshop documents written in code, read back: every colour mode, depth and compression
//! read (greyscale and RGB, with and without transparency; 8, 16 and 32 bits; raw, RLE, ZIP,
//! ZIP with prediction; PSD and PSB; groups shown and hidden), each pixel-exact against the
//! layers written (16 bits rounded to 8; 32-bit floats within one level); and hostile files,
//! each refused in one line or read within a memory bound proportional to the file, measured
//! by a counting allocator in this test binary.

mod layered;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use bdmorph::parts::{read_layered, LayerBudget, Layered, LayersError, MAX_PARTS};
use layered::{figure, psd_file, psd_record, write_psd_spec, PsdSpec, TestLayer, FIGURE_SIZE};

// ---------------------------------------------------------------------------------------------
// The peak of the bytes this thread holds, to bound what reading a file takes.

struct Counting;

thread_local! {
    static NOW: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

fn add(delta: isize) {
    let _ = NOW.try_with(|n| {
        n.set(n.get() + delta);
        let _ = PEAK.try_with(|p| p.set(p.get().max(n.get())));
    });
}

// SAFETY: forwards to the system allocator; the counts are plain thread-local Cells.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        add(layout.size() as isize);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        add(layout.size() as isize);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        add(-(layout.size() as isize));
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        add(new_size as isize - layout.size() as isize);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Reads `bytes`, giving the result and the most bytes held at once while reading.
fn measured(bytes: &[u8]) -> (Result<Layered, LayersError>, usize) {
    let start = NOW.with(Cell::get);
    PEAK.with(|p| p.set(start));
    let result = read_layered(bytes);
    let peak = PEAK.with(Cell::get) - start;
    (result, peak.max(0) as usize)
}

/// The bound every read keeps: the file's decoded-pixel budget plus a constant times its
/// size (records, names) plus a fixed allowance.
fn bound(len: usize) -> usize {
    LayerBudget::of(len) as usize + 16 * len + (1 << 20)
}

// ---------------------------------------------------------------------------------------------
// What each layer should read as.

/// The layer as it should read: cropped to its pixels (its whole rectangle without
/// transparency), greyscale as the red channel.
fn expected(l: &TestLayer, spec: &PsdSpec) -> (Vec<u8>, [u32; 4]) {
    let (w, h) = FIGURE_SIZE;
    let b = layered::bounds(&l.rgba, w, h);
    let mut px = layered::crop(&l.rgba, w, b);
    for p in px.chunks_exact_mut(4) {
        if spec.mode == 1 {
            p[1] = p[0];
            p[2] = p[0];
        }
        if !spec.alpha {
            p[3] = 255;
        }
    }
    (px, b)
}

fn check(spec: &PsdSpec, layers: &[TestLayer], prefix: &[&str]) {
    let bytes = write_psd_spec(layers, spec);
    let (read, peak) = measured(&bytes);
    let read = read.unwrap_or_else(|e| panic!("{spec:?}: {e}"));
    assert!(peak <= bound(bytes.len()), "{spec:?}: {peak} bytes");
    let shown: Vec<&TestLayer> = layers.iter().filter(|l| !l.hidden).collect();
    assert_eq!(read.layers.len(), shown.len(), "{spec:?}: {:?}", read.notes);
    for ((l, got), prefix) in shown.iter().zip(&read.layers).zip(prefix) {
        let (px, b) = expected(l, spec);
        assert_eq!(got.name, format!("{prefix}{}", l.name), "{spec:?}");
        assert_eq!(
            (got.left, got.top, got.image.width, got.image.height),
            (i64::from(b[0]), i64::from(b[1]), b[2] - b[0], b[3] - b[1]),
            "{spec:?} {}",
            l.name
        );
        let tolerance = if spec.depth == 32 { 1 } else { 0 };
        let worst = px
            .iter()
            .zip(&got.image.rgba)
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap_or(0);
        assert!(worst <= tolerance, "{spec:?} {}: off by {worst}", l.name);
    }
}

#[test]
fn every_mode_depth_and_compression_reads_as_written() {
    let layers = figure();
    let plain = vec![""; layers.len()];
    for mode in [1, 3] {
        for depth in [8, 16, 32] {
            for compression in 0..4 {
                for psb in [false, true] {
                    for alpha in [true, false] {
                        let spec = PsdSpec {
                            mode,
                            depth,
                            compression,
                            psb,
                            alpha,
                            tagged: false,
                            group: None,
                        };
                        check(&spec, &layers, &plain);
                    }
                }
            }
        }
    }
    // 16 and 32 bits as Photoshop writes them: the layers in a tagged block (Lr16, Lr32).
    for depth in [16, 32] {
        for psb in [false, true] {
            let spec = PsdSpec {
                depth,
                compression: 1,
                psb,
                tagged: true,
                ..PsdSpec::default()
            };
            check(&spec, &layers, &plain);
        }
    }
}

#[test]
fn groups_name_their_layers_and_a_hidden_group_hides_them() {
    let layers = figure();
    let spec = PsdSpec {
        compression: 1,
        group: Some((2, false)),
        ..PsdSpec::default()
    };
    let prefix = ["", "", "", "", "arms/", "arms/"];
    check(&spec, &layers, &prefix);
    let hidden = PsdSpec {
        group: Some((2, true)),
        ..spec
    };
    let read = read_layered(&write_psd_spec(&layers, &hidden)).expect("reads");
    assert_eq!(read.layers.len(), 4);
    assert!(
        read.notes
            .iter()
            .any(|n| n.contains("group 'arms' is hidden")),
        "{:?}",
        read.notes
    );
    assert!(read.notes.iter().any(|n| n.contains("arms/forearm_r")));
}

#[test]
fn other_colour_modes_and_depths_are_refused_in_one_line() {
    for (mode, depth, says) in [
        (4, 8, "CMYK"),
        (9, 8, "Lab"),
        (8, 8, "duotone"),
        (2, 8, "indexed"),
        (0, 1, "bitmap"),
        (7, 8, "multichannel"),
        (3, 1, "1 bits"),
    ] {
        let spec = PsdSpec {
            mode,
            depth,
            ..PsdSpec::default()
        };
        let e = read_layered(&write_psd_spec(&figure(), &spec)).expect_err(says);
        assert!(matches!(e, LayersError::Unsupported { .. }), "{e:?}");
        let text = e.to_string();
        assert!(text.contains(says) && !text.contains('\n'), "{text}");
    }
}

// ---------------------------------------------------------------------------------------------
// Hostile files.

/// An 8-bit RGB document of `w` x `h` whose layers are `records` (count, bytes) followed by
/// `data`, with `resources` as its image resources.
fn doc(w: u32, h: u32, resources: &[u8], count: usize, records: &[u8], data: &[u8]) -> Vec<u8> {
    let spec = PsdSpec::default();
    let mut f = psd_file((w, h), &spec, count, records, data);
    // Put the resources in (the writer leaves them empty: its length is at byte 30).
    let tail = f.split_off(34);
    f.truncate(30);
    f.extend_from_slice(&(resources.len() as u32).to_be_bytes());
    f.extend_from_slice(resources);
    f.extend_from_slice(&tail);
    f
}

/// A 30 x 30 opaque red layer at (`left`, `top`), RLE, with its channel data.
fn red(left: i32, top: i32, name: &str) -> (Vec<u8>, Vec<u8>) {
    let spec = PsdSpec {
        compression: 1,
        ..PsdSpec::default()
    };
    let plane = |v: u8| layered::encode_channel(&[v; 900], 30, 8, &spec);
    let chans = [
        (-1i16, plane(255)),
        (0, plane(220)),
        (1, plane(30)),
        (2, plane(30)),
    ];
    let refs: Vec<(i16, &[u8])> = chans.iter().map(|(i, d)| (*i, &d[..])).collect();
    let rec = psd_record(
        [top, left, top + 30, left + 30],
        &refs,
        0x08,
        name,
        None,
        false,
    );
    (rec, chans.iter().flat_map(|c| c.1.clone()).collect())
}

/// A layer record with arbitrary fields and channel lengths.
fn record(rect: [i32; 4], channels: &[(i16, u32)], extra_blocks: &[u8]) -> Vec<u8> {
    let mut r = Vec::new();
    rect.iter()
        .for_each(|v| r.extend_from_slice(&v.to_be_bytes()));
    r.extend_from_slice(&(channels.len() as u16).to_be_bytes());
    for (id, len) in channels {
        r.extend_from_slice(&id.to_be_bytes());
        r.extend_from_slice(&len.to_be_bytes());
    }
    r.extend_from_slice(b"8BIMnorm");
    r.extend_from_slice(&[255, 0, 8, 0]);
    let mut extra = vec![0u8; 8];
    extra.extend_from_slice(&[3, b'b', b'a', b'd']);
    extra.extend_from_slice(extra_blocks);
    r.extend_from_slice(&(extra.len() as u32).to_be_bytes());
    r.extend_from_slice(&extra);
    r
}

/// The slices resource (1050) declaring 0xFFFFFFFF of everything, padded to `size` bytes.
fn slices_resource(size: usize) -> Vec<u8> {
    let mut data = Vec::new();
    data.extend_from_slice(&6u32.to_be_bytes()); // version
    data.extend_from_slice(&[0; 16]); // bounds
    data.extend_from_slice(&u32::MAX.to_be_bytes()); // group name length
    data.extend_from_slice(&u32::MAX.to_be_bytes()); // slice count
    data.extend_from_slice(&16u32.to_be_bytes()); // descriptor version
    data.extend_from_slice(&u32::MAX.to_be_bytes()); // class name length
    data.extend_from_slice(b"VlLs");
    data.extend_from_slice(&u32::MAX.to_be_bytes());
    data.resize(size, 0xff);
    let mut r = b"8BIM".to_vec();
    r.extend_from_slice(&1050u16.to_be_bytes());
    r.extend_from_slice(&[0, 0]); // empty name
    r.extend_from_slice(&(data.len() as u32).to_be_bytes());
    r.extend_from_slice(&data);
    r
}

/// A tagged block holding a descriptor whose `VlLs` list declares 0xFFFFFFFF items.
fn vlls_block() -> Vec<u8> {
    let mut d = 16u32.to_be_bytes().to_vec();
    d.extend_from_slice(&[0, 0, 0, 0]);
    d.extend_from_slice(&u32::MAX.to_be_bytes());
    d.extend_from_slice(b"VlLs");
    d.extend_from_slice(&u32::MAX.to_be_bytes());
    d.extend_from_slice(&[0xff; 64]);
    let mut b = b"8BIMvstk".to_vec();
    b.extend_from_slice(&(d.len() as u32).to_be_bytes());
    b.extend_from_slice(&d);
    b
}

/// A zlib stream of `n` zero bytes.
fn zeros_zlib(n: usize) -> Vec<u8> {
    use std::io::Write as _;
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    let chunk = vec![0u8; 1 << 20];
    let mut left = n;
    while left > 0 {
        let k = left.min(chunk.len());
        z.write_all(&chunk[..k]).expect("zlib");
        left -= k;
    }
    z.finish().expect("zlib")
}

fn hostile_cases() -> Vec<(&'static str, Vec<u8>)> {
    let (r1, d1) = red(10, 10, "ok");
    let mut cases = Vec::new();
    cases.push((
        "resource 1050 declaring 0xFFFFFFFF counts (148 KB)",
        doc(64, 64, &slices_resource(148 << 10), 1, &r1, &d1),
    ));
    {
        let mut r = record([0; 4], &[], &vlls_block());
        r.extend_from_slice(&r1);
        cases.push((
            "a VlLs list of 0xFFFFFFFF items",
            doc(64, 64, &[], 2, &r, &d1),
        ));
    }
    cases.push((
        "32767 layers declared, one written",
        doc(64, 64, &[], 32767, &r1, &d1),
    ));
    cases.push((
        "a channel's length past the end",
        doc(
            64,
            64,
            &[],
            1,
            &record([0, 0, 30, 30], &[(0, 0xffff_fff0)], &[]),
            &[0, 0],
        ),
    ));
    cases.push((
        "65535 channels declared",
        doc(
            64,
            64,
            &[],
            1,
            &{
                let mut r = record([0, 0, 30, 30], &[], &[]);
                r[16..18].copy_from_slice(&[0xff, 0xff]);
                r
            },
            &[],
        ),
    ));
    {
        // RLE row counts that say more than the channel holds.
        let mut data = 1u16.to_be_bytes().to_vec();
        for _ in 0..30 {
            data.extend_from_slice(&0xffffu16.to_be_bytes());
        }
        data.extend_from_slice(&[0x81, 0]);
        let r = record([0, 0, 30, 30], &[(0, data.len() as u32)], &[]);
        cases.push(("RLE row counts lying", doc(64, 64, &[], 1, &r, &data)));
    }
    {
        // A 30 x 30 layer whose ZIP channel inflates to 64 MiB.
        let mut data = 2u16.to_be_bytes().to_vec();
        data.extend_from_slice(&zeros_zlib(64 << 20));
        let ids = [
            (-1i16, data.len() as u32),
            (0, data.len() as u32),
            (1, data.len() as u32),
            (2, data.len() as u32),
        ];
        let r = record([0, 0, 30, 30], &ids, &[]);
        let all: Vec<u8> = data.iter().copied().cycle().take(data.len() * 4).collect();
        cases.push((
            "a ZIP bomb channel (64 MiB of zeros)",
            doc(64, 64, &[], 1, &r, &all),
        ));
        // The same stream for a layer declaring 30000 x 30000.
        let r = record([0, 0, 30000, 30000], &ids, &[]);
        cases.push((
            "a ZIP channel for a 30000 x 30000 layer",
            doc(30000, 30000, &[], 1, &r, &all),
        ));
    }
    cases.push((
        "a layer outside the canvas",
        doc(64, 64, &[], 1, &red(1000, -1000, "far").0, &d1),
    ));
    {
        let (r, d) = red(-15, 50, "half out");
        cases.push((
            "a layer half outside the canvas",
            doc(64, 64, &[], 1, &r, &d),
        ));
    }
    {
        let r = record([40, 40, 10, 10], &[(0, 2), (1, 2), (2, 2)], &[]);
        cases.push(("an inverted rectangle", doc(64, 64, &[], 1, &r, &[0; 6])));
        let r = record([i32::MIN, i32::MIN, i32::MAX, i32::MAX], &[(0, 2 + 8)], &[]);
        cases.push((
            "a rectangle of 2^32 a side",
            doc(64, 64, &[], 1, &r, &[0, 1, 0, 0, 0, 0, 0, 0, 0, 0]),
        ));
    }
    cases.push(("a canvas of 0 x 64", doc(0, 64, &[], 1, &r1, &d1)));
    cases.push(("a canvas of 30001 x 64", doc(30001, 64, &[], 1, &r1, &d1)));
    {
        // Groups nested 20000 deep.
        let mut r = Vec::new();
        for _ in 0..20000 {
            r.extend_from_slice(&record([0; 4], &[], b"8BIMlsct\0\0\0\x04\0\0\0\x01"));
        }
        cases.push(("groups nested 20000 deep", doc(64, 64, &[], 20000, &r, &[])));
    }
    {
        // 64 groups nested, each named with 255 bytes, around 20000 hidden layers: names and
        // notes stay proportional to the file.
        let long = "g".repeat(255);
        let mut r = Vec::new();
        for _ in 0..20000 {
            let mut l = record([0; 4], &[], &[]);
            l[28] = 0x0a; // hidden
            r.extend_from_slice(&l);
        }
        for _ in 0..64 {
            r.extend_from_slice(&psd_record([0; 4], &[], 0x08, &long, Some(1), false));
        }
        cases.push((
            "20000 hidden layers under 64 groups of long names",
            doc(64, 64, &[], 20064, &r, &[]),
        ));
    }
    {
        // More layers with pixels than a character has parts.
        let mut r = Vec::new();
        let mut d = Vec::new();
        for i in 0..(MAX_PARTS as i32 + 10) {
            r.extend_from_slice(&record(
                [i % 60, 0, i % 60 + 1, 1],
                &[(0, 3), (1, 3), (2, 3)],
                &[],
            ));
            d.extend_from_slice(&[0, 0, 7, 0, 0, 7, 0, 0, 7]);
        }
        cases.push((
            "more layers than parts",
            doc(64, 64, &[], MAX_PARTS + 10, &r, &d),
        ));
    }
    {
        // PSB: a layer info length of 2^63.
        let spec = PsdSpec {
            psb: true,
            ..PsdSpec::default()
        };
        let mut f = write_psd_spec(&figure(), &spec);
        f[34 + 8..34 + 16].copy_from_slice(&(1u64 << 63).to_be_bytes());
        cases.push(("a PSB layer info of 2^63 bytes", f));
    }
    cases
}

#[test]
fn hostile_files_are_refused_in_one_line_or_read_within_bounds() {
    println!("| case | file | outcome | peak memory |");
    println!("|---|---|---|---|");
    for (what, bytes) in hostile_cases() {
        let (result, peak) = measured(&bytes);
        let outcome = match &result {
            Ok(l) => format!(
                "read: {} layer(s), {} note(s)",
                l.layers.len(),
                l.notes.len()
            ),
            Err(e) => {
                let text = e.to_string();
                assert!(!text.contains('\n'), "{what}: {text}");
                assert!(
                    !text.contains("unwrap") && !text.contains("panick"),
                    "{what}: {text}"
                );
                format!("refused: {text}")
            }
        };
        println!("| {what} | {} B | {outcome} | {} B |", bytes.len(), peak);
        assert!(peak <= bound(bytes.len()), "{what}: {peak} bytes held");
    }
}

#[test]
fn layers_outside_the_canvas_are_clipped_or_left_out() {
    let (r1, d1) = red(-15, 50, "half");
    let l = read_layered(&doc(64, 64, &[], 1, &r1, &d1)).expect("reads");
    assert_eq!(l.layers.len(), 1);
    let part = &l.layers[0];
    assert_eq!(
        (part.left, part.top, part.image.width, part.image.height),
        (0, 50, 15, 14)
    );
    assert_eq!(&part.image.rgba[..4], &[220, 30, 30, 255]);
    let (r2, d2) = red(1000, 10, "far");
    let e = read_layered(&doc(64, 64, &[], 1, &r2, &d2)).expect_err("nothing on the canvas");
    assert!(matches!(e, LayersError::Empty { .. }), "{e:?}");
}

#[test]
fn a_file_cut_anywhere_is_refused_in_one_line() {
    for spec in [
        PsdSpec::default(),
        PsdSpec {
            compression: 3,
            depth: 16,
            psb: true,
            group: Some((2, false)),
            ..PsdSpec::default()
        },
        PsdSpec {
            compression: 1,
            tagged: true,
            depth: 16,
            ..PsdSpec::default()
        },
    ] {
        let bytes = write_psd_spec(&figure(), &spec);
        let step = bytes.len() / 1500 + 1;
        for cut in (0..bytes.len()).step_by(step).chain(0..200) {
            let (result, peak) = measured(&bytes[..cut]);
            if let Err(e) = result {
                assert!(!e.to_string().contains('\n'), "{e}");
            }
            assert!(peak <= bound(cut), "cut at {cut}: {peak}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Many layers: read (or refused) with work proportional to the layers' own rectangles.

/// `n` layers of `side` x `side` at (`x`, `y`) each, on a `w` x `h` canvas (0 = empty
/// rectangles), RLE.
fn many(n: usize, side: i32, w: u32, h: u32, at: impl Fn(usize) -> (i32, i32)) -> Vec<u8> {
    let spec = PsdSpec {
        compression: 1,
        ..PsdSpec::default()
    };
    let s = side.max(0) as usize;
    let plane = |v: u8| layered::encode_channel(&vec![v; s * s], s, 8, &spec);
    let chans = [
        (-1i16, plane(255)),
        (0, plane(200)),
        (1, plane(100)),
        (2, plane(50)),
    ];
    let refs: Vec<(i16, &[u8])> = chans.iter().map(|(i, d)| (*i, &d[..])).collect();
    let mut records = Vec::new();
    let mut data = Vec::new();
    for i in 0..n {
        let (x, y) = at(i);
        records.extend(psd_record(
            [y, x, y + side, x + side],
            &refs,
            0x08,
            &format!("l{i}"),
            None,
            false,
        ));
        chans.iter().for_each(|c| data.extend_from_slice(&c.1));
    }
    psd_file((w, h), &spec, n, &records, &data)
}

#[test]
fn files_of_many_layers_finish_within_bounds() {
    let cases: Vec<(&str, Vec<u8>)> = vec![
        (
            "3000 empty visible layers on 4000 x 4000",
            many(3000, 0, 4000, 4000, |_| (0, 0)),
        ),
        (
            "2000 overlapping 30 x 30 layers",
            many(2000, 30, 400, 400, |i| {
                ((i % 37) as i32 * 3, (i % 41) as i32 * 3)
            }),
        ),
        (
            "500 overlapping 20 x 20 layers",
            many(500, 20, 200, 200, |i| {
                ((i % 13) as i32 * 5, (i % 17) as i32 * 5)
            }),
        ),
        (
            "256 overlapping 20 x 20 layers",
            many(MAX_PARTS, 20, 200, 200, |i| {
                ((i % 13) as i32 * 5, (i % 17) as i32 * 5)
            }),
        ),
        (
            "256 20 x 20 layers in one place",
            many(MAX_PARTS, 20, 200, 200, |_| (90, 90)),
        ),
        (
            "500 20 x 20 layers in one place",
            many(500, 20, 200, 200, |_| (90, 90)),
        ),
    ];
    let dir = std::env::var_os("BDMORPH_PSD_DIR").map(std::path::PathBuf::from);
    for (i, (what, bytes)) in cases.into_iter().enumerate() {
        if let Some(dir) = &dir {
            std::fs::write(dir.join(format!("many{i}.psd")), &bytes).expect("writes");
        }
        let started = std::time::Instant::now();
        let (result, peak) = measured(&bytes);
        let read_time = started.elapsed();
        assert!(peak <= bound(bytes.len()), "{what}: {peak}");
        let outcome = match result {
            Ok(l) => {
                let started = std::time::Instant::now();
                let c = bdmorph::parts::character(&l, &bdmorph::parts::CharacterOptions::default());
                format!(
                    "{} layers read; character: {} in {:.2?}",
                    l.layers.len(),
                    match c {
                        Ok(c) => format!("{} parts, {} joints", c.parts.len(), c.joints.len()),
                        Err(e) => format!("refused: {e}"),
                    },
                    started.elapsed()
                )
            }
            Err(e) => format!("refused: {e}"),
        };
        println!(
            "{what}: {} B, read in {read_time:.2?} (peak {peak} B): {outcome}",
            bytes.len()
        );
    }
}

#[test]
fn reading_stops_when_cancelled() {
    let flag = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(true));
    let budget = bdmorph::Budget::unlimited().with_cancel(flag);
    let bytes = write_psd_spec(&figure(), &PsdSpec::default());
    let e = bdmorph::parts::read_layered_with(&bytes, &budget).expect_err("cancelled");
    assert!(
        matches!(e, LayersError::Stopped(bdmorph::Stopped::Cancelled)),
        "{e:?}"
    );
    let l = read_layered(&bytes).expect("reads");
    let e =
        bdmorph::parts::character_with(&l, &bdmorph::parts::CharacterOptions::default(), &budget)
            .expect_err("cancelled");
    assert!(e.to_string().contains("cancelled"), "{e}");
}

/// How fast a large file reads (printed, not asserted): 8 layers of 1500 x 1500 with varied
/// pixels on a 3000 x 3000 canvas, RLE and ZIP with prediction.
#[test]
fn a_large_layered_file_reads_in_one_pass() {
    let (w, h) = (1500usize, 1500usize);
    for compression in [1, 3] {
        let spec = PsdSpec {
            compression,
            ..PsdSpec::default()
        };
        let mut records = Vec::new();
        let mut data = Vec::new();
        for i in 0..8usize {
            let plane = |c: usize| {
                let raw: Vec<u8> = (0..w * h)
                    .map(|p| ((p % w) / (3 + c) + (p / w) / (5 + i)) as u8)
                    .collect();
                layered::encode_channel(&raw, w, 8, &spec)
            };
            let chans = [
                (-1i16, plane(9)),
                (0, plane(0)),
                (1, plane(1)),
                (2, plane(2)),
            ];
            let refs: Vec<(i16, &[u8])> = chans.iter().map(|(id, d)| (*id, &d[..])).collect();
            let (x, y) = ((i % 4) as i32 * 500, (i / 4) as i32 * 1500);
            records.extend(psd_record(
                [y, x, y + h as i32, x + w as i32],
                &refs,
                0x08,
                &format!("l{i}"),
                None,
                false,
            ));
            chans.iter().for_each(|c| data.extend_from_slice(&c.1));
        }
        let bytes = psd_file((3000, 3000), &spec, 8, &records, &data);
        let started = std::time::Instant::now();
        let (read, peak) = measured(&bytes);
        let took = started.elapsed();
        let read = read.expect("reads");
        assert_eq!(read.layers.len(), 8);
        assert!(peak <= bound(bytes.len()));
        println!(
            "compression {compression}: {} MB file, 8 layers of 1500 x 1500 read in {took:.2?} (peak {} MB)",
            bytes.len() >> 20,
            peak >> 20
        );
    }
}
