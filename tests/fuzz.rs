//! Fuzzing on stable with proptest: the OBJ and OFF readers, the SVG and `.poly` outline
//! readers (with the mesher on small outlines), the compiler on arbitrary small
//! connectivity, and the program verifier on mutated and random programs. Every input must
//! give a result or a typed, one-line error: no panic, no out-of-bounds access, no hang, no
//! huge allocation (see `fuzz_checks` for the properties, shared with the cargo-fuzz targets
//! in `fuzz/`).
//!
//! Case counts are small so that `cargo test` stays fast. For a long run set
//! `PROPTEST_CASES`, which replaces every count here (the test profile is optimised and keeps
//! debug assertions, which the VM uses to check its values):
//!
//! ```text
//! PROPTEST_CASES=1000000 cargo test --test fuzz
//! ```
//!
//! Inputs that once failed are kept at the end as `fuzz_*_regression_*` tests.

mod fuzz_checks;
mod layered;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use fuzz_checks::{self as check, Edit, Format, Mutation, Part};
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::select;

// ---------------------------------------------------------------------------------------------
// The largest single allocation made by this thread, to catch a declared count that reserves
// memory the input does not justify.

struct Tracking;

thread_local! {
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

fn note(size: usize) {
    let _ = LARGEST.try_with(|c| c.set(c.get().max(size)));
}

// SAFETY: forwards to the system allocator; the record is a plain thread-local Cell.
unsafe impl GlobalAlloc for Tracking {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Tracking = Tracking;

/// Runs `f` and checks that no single allocation exceeded `64 KiB + 64 * input_len` bytes.
fn bounded_allocation(input_len: usize, f: impl FnOnce()) {
    bounded_allocation_beyond(input_len, 0, f);
}

/// As [`bounded_allocation`], allowing `extra` bytes more (what a limit other than the
/// input's length bounds: an outline's flattened curves).
fn bounded_allocation_beyond(input_len: usize, extra: usize, f: impl FnOnce()) {
    LARGEST.with(|c| c.set(0));
    f();
    let largest = LARGEST.with(Cell::get);
    let limit = (64 << 10) + 64 * input_len + extra;
    assert!(
        largest <= limit,
        "an allocation of {largest} bytes for {input_len} bytes of input"
    );
}

fn read(text: &str, format: Format) {
    bounded_allocation(text.len(), || check::reader(text, format));
}

fn read_bytes(bytes: &[u8], format: Format) {
    bounded_allocation(bytes.len(), || check::reader_bytes(bytes, format));
}

/// `cases` unless `PROPTEST_CASES` says otherwise; failures are not persisted to files (a
/// failure found is kept as a named regression test instead).
fn config(cases: u32) -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(cases);
    ProptestConfig {
        cases,
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

// ---------------------------------------------------------------------------------------------
// Reader inputs.

fn words(list: &[&'static str]) -> impl Strategy<Value = String> {
    select(list.to_vec()).prop_map(String::from)
}

/// A token of a file: usually valid, rendered in context (`Ok`), sometimes a word as written
/// (`Err`): not a number, not finite, out of range, overflowing.
type Token<T> = Result<T, String>;

fn render<T: ToString>(token: &Token<T>) -> String {
    match token {
        Ok(x) => x.to_string(),
        Err(word) => word.clone(),
    }
}

/// A coordinate as written in a file.
fn number() -> impl Strategy<Value = Token<f64>> {
    prop_oneof![
        30 => (-4i32..5).prop_map(|x| Ok(f64::from(x))),
        10 => (-1e3f64..1e3).prop_map(Ok),
        1 => words(&[
            "nan", "NaN", "inf", "-inf", "infinity", "1e999", "-1e999", "1e-400", "abc", "+1",
            ".5", "5.", "1e", "0x10", "1_0", "--1", "1e308", "-0", "5e-324", "1e154", "",
        ])
        .prop_map(Err),
    ]
}

/// z: mostly 0 (a planar mesh).
fn z() -> impl Strategy<Value = Token<f64>> {
    prop_oneof![16 => Just(Ok(0.0)), 1 => number()]
}

/// An OBJ index: a valid positive one (possibly naming a later element), a valid negative
/// one (relative to the elements read so far), or a word.
#[derive(Clone, Debug)]
enum Index {
    Forward(u32),
    Back(u32),
    Word(String),
}

fn obj_index() -> impl Strategy<Value = Index> {
    prop_oneof![
        30 => any::<u32>().prop_map(Index::Forward),
        10 => any::<u32>().prop_map(Index::Back),
        1 => words(&[
            "0", "4294967295", "4294967296", "4294967297", "-4294967296", "9",
            "9223372036854775807", "-9223372036854775808", "99999999999999999999",
            "-99999999999999999999", "18446744073709551615", "x", "1.5", "+2", "", "-9",
        ])
        .prop_map(Index::Word),
    ]
}

/// The index in a file with `total` elements, `so_far` of them read.
fn render_index(index: &Index, total: usize, so_far: usize) -> String {
    match index {
        Index::Back(r) if so_far > 0 => format!("-{}", 1 + *r as usize % so_far),
        Index::Forward(r) | Index::Back(r) => (1 + *r as usize % total.max(1)).to_string(),
        Index::Word(word) => word.clone(),
    }
}

#[derive(Clone, Debug)]
enum ObjLine {
    V(Vec<Token<f64>>),
    Vt(Vec<Token<f64>>),
    /// Corners: vertex index, texture index, form (`v`, `v/vt`, `v/vt/vn`, `v//vn`).
    F(Vec<(Index, Index, u8)>),
    Other(String),
}

fn obj_line() -> impl Strategy<Value = ObjLine> {
    let v = prop_oneof![
        16 => vec(number(), 2..=2),
        8 => (vec(number(), 2..=2), z()).prop_map(|(mut xs, z)| {
            xs.push(z);
            xs
        }),
        1 => vec(number(), 0..9),
    ];
    let vt = prop_oneof![8 => vec(number(), 1..=3), 1 => vec(number(), 0..5)];
    let corner = || {
        let form = prop_oneof![6 => Just(0u8), 2 => Just(1u8), 1 => Just(2u8), 1 => Just(3u8)];
        (obj_index(), obj_index(), form)
    };
    let corners = prop_oneof![24 => vec(corner(), 3..=3), 1 => vec(corner(), 0..7)];
    prop_oneof![
        6 => v.prop_map(ObjLine::V),
        1 => vt.prop_map(ObjLine::Vt),
        5 => corners.prop_map(ObjLine::F),
        1 => words(&[
            "", "# comment", "vn 0 0 1", "g group", "s off", "usemtl x", "\t", "v", "f", "o",
            "l 1 2", "f 1 2 3 # c", "v 0 0 # c", "f\t1\t2\t3", "  v 1 1", "vp 0.5",
        ])
        .prop_map(ObjLine::Other),
    ]
}

fn join(lines: Vec<String>, eol: &str, bom: bool) -> String {
    let mut text = String::from(if bom { "\u{feff}" } else { "" });
    for line in lines {
        text += &line;
        text += eol;
    }
    text
}

fn obj_text() -> impl Strategy<Value = String> {
    let eol = select(vec!["\n", "\r\n", "\r"]);
    (vec(obj_line(), 0..30), eol, any::<bool>()).prop_map(|(lines, eol, bom)| {
        let count = |is: fn(&ObjLine) -> bool| lines.iter().filter(|&l| is(l)).count();
        let total = [
            count(|l| matches!(l, ObjLine::V(_))),
            count(|l| matches!(l, ObjLine::Vt(_))),
        ];
        let mut so_far = [0, 0];
        let mut text = Vec::new();
        for line in &lines {
            let numbers = |xs: &[Token<f64>]| xs.iter().map(render).collect::<Vec<_>>().join(" ");
            text.push(match line {
                ObjLine::V(xs) => {
                    so_far[0] += 1;
                    format!("v {}", numbers(xs))
                }
                ObjLine::Vt(xs) => {
                    so_far[1] += 1;
                    format!("vt {}", numbers(xs))
                }
                ObjLine::F(corners) => {
                    let corner = |(v, t, form): &(Index, Index, u8)| {
                        // No `vt` to name: the corner drops a valid texture index.
                        let no_vt = total[1] == 0 && !matches!(t, Index::Word(_));
                        let v = render_index(v, total[0], so_far[0]);
                        let t = render_index(t, total[1], so_far[1]);
                        match form {
                            0..=2 if no_vt => v,
                            0 => v,
                            1 => format!("{v}/{t}"),
                            2 => format!("{v}/{t}/1"),
                            _ => format!("{v}//1"),
                        }
                    };
                    let corners: Vec<String> = corners.iter().map(corner).collect();
                    format!("f {}", corners.join(" "))
                }
                ObjLine::Other(word) => word.clone(),
            });
        }
        join(text, eol, bom)
    })
}

/// An OFF count or corner count: usually the true one (`None`), sometimes another.
fn off_count() -> impl Strategy<Value = Option<String>> {
    prop_oneof![
        30 => Just(None),
        1 => (0usize..8).prop_map(|x| Some(x.to_string())),
        1 => words(&[
            "-1", "18446744073709551615", "18446744073709551616", "4294967296",
            "1000000000000", "99999999999999999999", "x", "3.0",
        ])
        .prop_map(Some),
    ]
}

/// An OFF index: one in range (taken modulo the vertex count), or a word.
fn off_index() -> impl Strategy<Value = Token<u32>> {
    prop_oneof![
        30 => any::<u32>().prop_map(Ok),
        1 => words(&[
            "-1", "4294967295", "4294967296", "9223372036854775807", "99999999999999999999",
            "x", "1.0", "9",
        ])
        .prop_map(Err),
    ]
}

fn off_text() -> impl Strategy<Value = String> {
    let header = prop_oneof![
        16 => Just("OFF"),
        1 => select(vec!["COFF", "NOFF", "STOFF", "", "off", "OFFX", "# c\nOFF", "PLY"]),
    ];
    let counts = (off_count(), off_count(), off_count(), 0u8..4);
    let vertex = prop_oneof![
        24 => (number(), number(), z()).prop_map(|(x, y, z)| vec![x, y, z]),
        1 => vec(number(), 0..6),
    ];
    let indices = prop_oneof![24 => vec(off_index(), 3..=3), 1 => vec(off_index(), 0..6)];
    let face = (off_count(), indices, any::<bool>());
    (
        header,
        counts,
        vec(vertex, 0..12),
        vec(face, 0..12),
        select(vec!["\n", "\r\n"]),
    )
        .prop_map(|(header, (nv, nf, ne, layout), vertices, faces, eol)| {
            let n = vertices.len();
            let nv = nv.unwrap_or_else(|| n.to_string());
            let nf = nf.unwrap_or_else(|| faces.len().to_string());
            let ne = ne.unwrap_or_else(|| "0".into());
            let counts = match layout {
                0 => format!("{nv} {nf} {ne}"),
                1 => format!("{nv} {nf}"),
                2 => format!("{nv}\n{nf} {ne}"),
                _ => format!("{nv} {nf} {ne} # counts"),
            };
            let mut lines = match header {
                "" => vec![counts],
                h if layout == 3 => vec![format!("{h} {counts}")],
                h => vec![h.to_owned(), counts],
            };
            for v in &vertices {
                lines.push(v.iter().map(render).collect::<Vec<_>>().join(" "));
            }
            for (k, indices, colour) in &faces {
                let k = k.clone().unwrap_or_else(|| indices.len().to_string());
                let indices = indices.iter().map(|i| match i {
                    Ok(i) => (*i as usize % n.max(1)).to_string(),
                    Err(word) => word.clone(),
                });
                let colour = if *colour { " 255 0 0" } else { "" };
                lines.push(format!(
                    "{k} {}{colour}",
                    indices.collect::<Vec<_>>().join(" ")
                ));
            }
            join(lines, eol, false)
        })
}

/// Bytes that spell OBJ and OFF tokens, densely.
fn texty_bytes() -> impl Strategy<Value = Vec<u8>> {
    vec(select(b"vtf OFF0123456789-+./#\n\r\te".to_vec()), 0..200)
}

/// A small valid mesh as OBJ and OFF text, to be corrupted byte by byte.
fn valid_texts() -> (String, String) {
    let m = bdmorph::generate::disk(1, 0.1);
    let mut obj = Vec::new();
    bdmorph::io::format_obj_2d(&mut obj, &m.positions, &m.faces, &["valid"]).expect("writes");
    let mut off = format!("OFF\n{} {} 0\n", m.positions.len(), m.faces.len());
    for p in &m.positions {
        off += &format!("{} {} 0\n", p[0], p[1]);
    }
    for f in &m.faces {
        off += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
    }
    (String::from_utf8(obj).expect("utf8"), off)
}

/// Byte edits: (position, byte, kind) with kind 0 replace, 1 insert, 2 delete.
fn byte_edits() -> impl Strategy<Value = Vec<(usize, u8, u8)>> {
    let byte = prop_oneof![
        3 => select(b"0123456789 -./\n#vfe".to_vec()),
        1 => any::<u8>(),
    ];
    vec((any::<usize>(), byte, 0u8..3), 1..8)
}

/// The test figure's layers.
static FIGURE: std::sync::LazyLock<Vec<layered::TestLayer>> =
    std::sync::LazyLock::new(layered::figure);

/// A small valid PSD and OpenRaster file (the test figure's six layers), to corrupt.
static VALID_PSD: std::sync::LazyLock<Vec<u8>> =
    std::sync::LazyLock::new(|| layered::write_psd(&layered::figure()));
/// The PSD reader's other paths, to corrupt: a PSB of 16 bits with ZIP-predicted channels
/// and a group; a greyscale document of 16 bits with its layers in a tagged block (`Lr16`) and
/// RLE channels; 32-bit floats with ZIP channels and no transparency.
static VALID_PSD_VARIANTS: std::sync::LazyLock<Vec<Vec<u8>>> = std::sync::LazyLock::new(|| {
    use layered::PsdSpec;
    [
        PsdSpec {
            depth: 16,
            compression: 3,
            psb: true,
            group: Some((2, false)),
            ..PsdSpec::default()
        },
        PsdSpec {
            mode: 1,
            depth: 16,
            compression: 1,
            tagged: true,
            ..PsdSpec::default()
        },
        PsdSpec {
            depth: 32,
            compression: 2,
            alpha: false,
            ..PsdSpec::default()
        },
    ]
    .iter()
    .map(|spec| layered::write_psd_spec(&FIGURE, spec))
    .collect()
});
static VALID_ORA: std::sync::LazyLock<Vec<u8>> =
    std::sync::LazyLock::new(|| layered::write_ora(&layered::figure(), 2));

/// A layered picture read within its memory budget: no allocation beyond the file's
/// [`bdmorph::parts::LayerBudget`].
fn layered(bytes: &[u8]) {
    let budget = bdmorph::parts::LayerBudget::of(bytes.len()) as usize;
    bounded_allocation_beyond(bytes.len(), budget, || check::layered_reader(bytes));
}

fn corrupt(text: &str, edits: &[(usize, u8, u8)]) -> Vec<u8> {
    corrupt_bytes(text.as_bytes(), edits)
}

fn corrupt_bytes(bytes: &[u8], edits: &[(usize, u8, u8)]) -> Vec<u8> {
    let mut bytes = bytes.to_vec();
    for &(at, byte, kind) in edits {
        let at = at % (bytes.len() + 1);
        match kind {
            0 if at < bytes.len() => bytes[at] = byte,
            2 if at < bytes.len() => {
                bytes.remove(at);
            }
            _ => bytes.insert(at, byte),
        }
    }
    bytes
}

proptest! {
    #![proptest_config(config(4096))]

    #[test]
    fn fuzz_obj_reader_arbitrary_bytes(bytes in vec(any::<u8>(), 0..300)) {
        read_bytes(&bytes, Format::Obj);
    }

    #[test]
    fn fuzz_off_reader_arbitrary_bytes(bytes in vec(any::<u8>(), 0..300)) {
        read_bytes(&bytes, Format::Off);
    }

    #[test]
    fn fuzz_readers_token_bytes(bytes in texty_bytes()) {
        read_bytes(&bytes, Format::Obj);
        read_bytes(&bytes, Format::Off);
    }

    #[test]
    fn fuzz_obj_reader_structured(text in obj_text()) {
        read(&text, Format::Obj);
    }

    #[test]
    fn fuzz_off_reader_structured(text in off_text()) {
        read(&text, Format::Off);
    }

    #[test]
    fn fuzz_readers_corrupted_valid_files(edits in byte_edits()) {
        let (obj, off) = valid_texts();
        read_bytes(&corrupt(&obj, &edits), Format::Obj);
        read_bytes(&corrupt(&off, &edits), Format::Off);
    }
}

// ---------------------------------------------------------------------------------------------
// Outline readers: `parse_svg` and `parse_poly` (and, for small outlines, the mesher).

/// An outline's curves flatten to as many points as their size over the tolerance asks,
/// whatever the input's length, up to `MAX_OUTLINE_POINTS` (of 16 bytes, in vectors that
/// may double): that, not the input, bounds its memory.
fn outline(bytes: &[u8], format: check::OutlineFormat) {
    let flattened = 2 * 16 * bdmorph::meshing::MAX_OUTLINE_POINTS;
    bounded_allocation_beyond(bytes.len(), flattened, || {
        check::outline_reader(bytes, format)
    });
}

/// A number as SVG or `.poly` text: small, huge, tiny, or not quite a number.
fn outline_number() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => (-50i32..50).prop_map(|x| x.to_string()),
        2 => (-100.0f64..100.0).prop_map(|x| format!("{x:.3}")),
        1 => words(&["1e154", "-1e300", "1e-40", "1e308", "1e9", "nan", "inf", ".5.5", "1e", "-", "0"]),
    ]
}

/// An SVG element: a shape with random numbers, a group opening or closing, or noise.
fn svg_element() -> impl Strategy<Value = String> {
    let n = outline_number;
    prop_oneof![
        (n(), n(), n()).prop_map(|(x, y, r)| format!("<circle cx=\"{x}\" cy=\"{y}\" r=\"{r}\"/>")),
        (n(), n(), n(), n()).prop_map(|(x, y, w, h)| format!(
            "<rect x=\"{x}\" y=\"{y}\" width=\"{w}\" height=\"{h}\" rx=\"2\"/>"
        )),
        vec(n(), 0..10).prop_map(|v| format!("<polygon points=\"{}\"/>", v.join(","))),
        vec(
            (
                select(vec!["M", "L", "C", "Q", "A", "Z", "H", "V", "a", "l"]),
                vec(n(), 0..8)
            ),
            1..8
        )
        .prop_map(|cmds| format!(
            "<path d=\"{}\"/>",
            cmds.iter()
                .map(|(c, v)| format!("{c}{}", v.join(" ")))
                .collect::<Vec<_>>()
                .join(" ")
        )),
        (
            select(vec!["translate", "scale", "rotate", "matrix", "skewX"]),
            vec(n(), 0..7)
        )
            .prop_map(|(t, v)| format!("<g transform=\"{t}({})\">", v.join(" "))),
        Just("<g>".to_string()),
        Just("</g>".to_string()),
        Just("<defs>".to_string()),
        Just("</defs>".to_string()),
    ]
}

fn svg_text() -> impl Strategy<Value = String> {
    (any::<bool>(), vec(svg_element(), 0..8)).prop_map(|(view_box, elements)| {
        let open = if view_box {
            "<svg viewBox=\"0 0 100 100\">"
        } else {
            "<svg>"
        };
        format!("{open}\n{}\n</svg>\n", elements.join("\n"))
    })
}

fn poly_text() -> impl Strategy<Value = String> {
    let n = outline_number;
    (
        prop_oneof![3 => (0usize..8).prop_map(|k| k.to_string()), 1 => words(&["1000000000", "100000000000000", "-1", "x"])],
        vec((n(), n()), 0..8),
        prop_oneof![3 => (0usize..8).prop_map(|k| k.to_string()), 1 => words(&["1000000000", "99999999999999", "-3"])],
        vec((0u32..9, 0u32..9), 0..8),
        vec((n(), n()), 0..3),
    )
        .prop_map(|(nv, vertices, ns, segments, holes)| {
            let mut t = format!("{nv} 2 0 0\n");
            for (k, (x, y)) in vertices.iter().enumerate() {
                t += &format!("{} {x} {y}\n", k + 1);
            }
            t += &format!("{ns} 0\n");
            for (k, (a, b)) in segments.iter().enumerate() {
                t += &format!("{} {a} {b}\n", k + 1);
            }
            t += &format!("{}\n", holes.len());
            for (k, (x, y)) in holes.iter().enumerate() {
                t += &format!("{} {x} {y}\n", k + 1);
            }
            t
        })
}

const VALID_SVG: &str = "<svg viewBox=\"0 0 100 100\">\n<g transform=\"translate(5 5)\">\n<rect x=\"10\" y=\"10\" width=\"60\" height=\"60\" rx=\"8\"/>\n<circle cx=\"40\" cy=\"40\" r=\"10\"/>\n</g>\n<path d=\"M80 80 C90 80 95 90 90 95 Q85 99 80 95 Z\"/>\n</svg>\n";
const VALID_POLY: &str = "8 2 0 0\n1 0 0\n2 4 0\n3 4 4\n4 0 4\n5 1 1\n6 3 1\n7 3 3\n8 1 3\n8 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n5 5 6\n6 6 7\n7 7 8\n8 8 5\n1\n1 2 2\n";

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn fuzz_svg_reader_arbitrary_bytes(bytes in vec(any::<u8>(), 0..300)) {
        outline(&bytes, check::OutlineFormat::Svg);
    }

    #[test]
    fn fuzz_poly_reader_arbitrary_bytes(bytes in vec(any::<u8>(), 0..300)) {
        outline(&bytes, check::OutlineFormat::Poly);
    }

    #[test]
    fn fuzz_svg_reader_structured(text in svg_text()) {
        outline(text.as_bytes(), check::OutlineFormat::Svg);
    }

    #[test]
    fn fuzz_poly_reader_structured(text in poly_text()) {
        outline(text.as_bytes(), check::OutlineFormat::Poly);
    }

    #[test]
    fn fuzz_outline_readers_corrupted_valid_files(edits in byte_edits()) {
        outline(&corrupt(VALID_SVG, &edits), check::OutlineFormat::Svg);
        outline(&corrupt(VALID_POLY, &edits), check::OutlineFormat::Poly);
    }

    #[test]
    fn fuzz_layered_readers_corrupted_valid_files(
        edits in byte_edits(),
        header_edits in byte_edits(),
        cut in proptest::option::weighted(0.25, any::<usize>()),
    ) {
        for valid in [&*VALID_PSD, &*VALID_ORA].into_iter().chain(VALID_PSD_VARIANTS.iter()) {
            // Edits anywhere, and edits within the first kilobyte (headers, records, the zip's
            // first entries), where they change the structure rather than pixels.
            let mut bytes = corrupt_bytes(valid, &edits);
            let head = header_edits.iter().map(|&(at, b, k)| (at % 1024, b, k)).collect::<Vec<_>>();
            bytes = corrupt_bytes(&bytes, &head);
            if let Some(cut) = cut {
                bytes.truncate(cut % (bytes.len() + 1));
            }
            layered(&bytes);
        }
    }

    #[test]
    fn fuzz_layered_readers_structured(xml_edits in byte_edits(), record_edits in vec((any::<usize>(), any::<u8>()), 1..6)) {
        // OpenRaster: a valid zip around a corrupted stack.xml.
        let figure = &*FIGURE;
        let stack = layered::ora_stack(figure, 2);
        layered(&layered::ora_with_stack(figure, &corrupt(&stack, &xml_edits)));
        // PSD: bytes replaced (lengths kept) in the header and the layer records.
        let mut psd = VALID_PSD.clone();
        for &(at, b) in &record_edits {
            psd[at % 700] = b;
        }
        layered(&psd);
        for valid in VALID_PSD_VARIANTS.iter() {
            let mut psd = valid.clone();
            for &(at, b) in &record_edits {
                psd[at % 900] = b;
            }
            layered(&psd);
        }
    }

    #[test]
    fn fuzz_layered_readers_arbitrary_bytes(head in prop_oneof![Just(b"8BPS".to_vec()), Just(b"PK\x03\x04".to_vec())], bytes in vec(any::<u8>(), 0..400)) {
        layered(&[head, bytes].concat());
    }

    #[test]
    fn fuzz_depth_reader_arbitrary_bytes(bytes in vec(any::<u8>(), 0..200)) {
        check::depth_reader(&bytes);
    }

    #[test]
    fn fuzz_depth_reader_numbers(words in vec(
        prop_oneof![Just("1"), Just("-9"), Just("10"), Just("#"), Just("\n"), Just("0x3"), Just("99999999999999999999"), Just(" ")],
        0..12,
    )) {
        check::depth_reader(words.concat().as_bytes());
    }
}

#[test]
fn valid_outlines_mesh() {
    for (text, format) in [
        (VALID_SVG, check::OutlineFormat::Svg),
        (VALID_POLY, check::OutlineFormat::Poly),
    ] {
        outline(text.as_bytes(), format);
    }
    assert!(bdmorph::meshing::parse_svg(VALID_SVG, None).is_ok());
    assert!(bdmorph::meshing::parse_poly(VALID_POLY).is_ok());
}

// ---------------------------------------------------------------------------------------------
// Compiler inputs.

fn coordinate() -> impl Strategy<Value = f64> {
    prop_oneof![
        8 => (-3i32..5).prop_map(f64::from),
        2 => -1e3f64..1e3,
        1 => any::<u8>().prop_map(|c| check::coordinate(0xF4 + c % 12)),
    ]
}

/// 1 to 12 vertices, up to 24 faces with indices in range or slightly out of it.
fn arbitrary_mesh() -> impl Strategy<Value = (Vec<[f64; 2]>, Vec<[u32; 3]>)> {
    (1u32..=12).prop_flat_map(|n| {
        let m = n + 2;
        (
            vec([coordinate(), coordinate()], n as usize),
            vec([0..m, 0..m, 0..m], 0..=24),
        )
    })
}

/// What can go wrong with a valid disk's face list.
#[derive(Clone, Debug)]
enum FaceEdit {
    Remove(usize),
    /// The face again, rotated (0..3) or reversed (3..6).
    Duplicate(usize, u8),
    Flip(usize),
    SetCorner(usize, usize, u32),
    Add([u32; 3]),
    AddVertex,
    SwapFaces(usize, usize),
}

fn face_edit() -> impl Strategy<Value = FaceEdit> {
    let i = any::<usize>();
    prop_oneof![
        i.prop_map(FaceEdit::Remove),
        (i, 0u8..6).prop_map(|(f, r)| FaceEdit::Duplicate(f, r)),
        i.prop_map(FaceEdit::Flip),
        (i, 0usize..3, 0u32..16).prop_map(|(f, c, v)| FaceEdit::SetCorner(f, c, v)),
        [0u32..16, 0u32..16, 0u32..16].prop_map(FaceEdit::Add),
        Just(FaceEdit::AddVertex),
        (i, i).prop_map(|(a, b)| FaceEdit::SwapFaces(a, b)),
    ]
}

/// A small valid disk (fan, grid or disk) with 0 to 3 edits of its faces.
fn edited_disk() -> impl Strategy<Value = (Vec<[f64; 2]>, Vec<[u32; 3]>)> {
    use bdmorph::generate;
    let base = prop_oneof![
        (3usize..9).prop_map(|k| generate::fan(k, 0.0)),
        (2usize..5, 2usize..5).prop_map(|(x, y)| generate::grid(x, y, 0.1)),
        Just(generate::disk(1, 0.1)),
    ];
    (base, vec(face_edit(), 0..4)).prop_map(|(mesh, edits)| {
        let (mut positions, mut faces) = (mesh.positions, mesh.faces);
        for edit in edits {
            let nf = faces.len().max(1);
            let n = positions.len() as u32;
            match edit {
                FaceEdit::Remove(f) if !faces.is_empty() => {
                    faces.remove(f % nf);
                }
                FaceEdit::Duplicate(f, r) if !faces.is_empty() => {
                    let mut t = faces[f % nf];
                    t.rotate_left(usize::from(r % 3));
                    if r >= 3 {
                        t.swap(0, 1);
                    }
                    faces.push(t);
                }
                FaceEdit::Flip(f) if !faces.is_empty() => faces[f % nf].swap(1, 2),
                FaceEdit::SetCorner(f, c, v) if !faces.is_empty() => faces[f % nf][c] = v % (n + 2),
                FaceEdit::Add(t) => faces.push(t.map(|v| v % (n + 2))),
                FaceEdit::AddVertex => positions.push([9.0, 9.0]),
                FaceEdit::SwapFaces(a, b) if !faces.is_empty() => faces.swap(a % nf, b % nf),
                _ => {}
            }
        }
        (positions, faces)
    })
}

proptest! {
    #![proptest_config(config(4096))]

    #[test]
    fn fuzz_compiler_arbitrary_connectivity((positions, faces) in arbitrary_mesh()) {
        check::compile_and_run(&positions, &faces);
    }

    #[test]
    fn fuzz_compiler_edited_disks((positions, faces) in edited_disk()) {
        check::compile_and_run(&positions, &faces);
    }

    #[test]
    fn fuzz_compiler_from_bytes(bytes in vec(any::<u8>(), 0..100)) {
        let (positions, faces) = check::mesh_from_bytes(&bytes);
        check::compile_and_run(&positions, &faces);
    }
}

// ---------------------------------------------------------------------------------------------
// Verifier inputs.

fn value() -> impl Strategy<Value = u32> {
    prop_oneof![
        6 => 0u32..16,
        2 => 0u32..200,
        1 => select(vec![u32::MAX, u32::MAX - 1, 0xFFFF, 0xFFFE, 0x1_0000, 1 << 31]),
        1 => any::<u32>(),
    ]
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let part = prop_oneof![
        1 => Just(Part::Counts),
        4 => Just(Part::Iteration),
        1 => Just(Part::Edges),
        1 => Just(Part::Unknowns),
        1 => Just(Part::ColPtr),
        1 => Just(Part::RowIdx),
        2 => Just(Part::Embed),
        1 => Just(Part::Root),
    ];
    let edit = prop_oneof![
        4 => value().prop_map(Edit::Set),
        3 => (-4i32..=4).prop_map(Edit::Add),
        1 => value().prop_map(Edit::Insert),
        1 => Just(Edit::Remove),
        1 => Just(Edit::Truncate),
        1 => any::<u32>().prop_map(Edit::Swap),
    ];
    (part, any::<u32>(), edit).prop_map(|(part, index, edit)| Mutation { part, index, edit })
}

proptest! {
    #![proptest_config(config(4096))]

    #[test]
    fn fuzz_verifier_mutated_programs(base in any::<usize>(), mutations in vec(mutation(), 1..6)) {
        let bases = check::base_programs();
        let mut parts = bases[base % bases.len()].clone();
        for m in mutations {
            check::mutate(&mut parts, m);
        }
        check::verifier(parts);
    }

    #[test]
    fn fuzz_verifier_random_parts(bytes in vec(any::<u8>(), 0..400)) {
        check::verifier(check::parts_from_bytes(&bytes));
    }

    #[test]
    fn fuzz_verifier_mutated_from_bytes(bytes in vec(any::<u8>(), 0..80)) {
        check::verifier(check::mutated_from_bytes(&bytes));
    }
}

/// A declared count far beyond what the input holds reserves nothing like it, and reading
/// stops at the end of the input.
#[test]
fn huge_declared_counts_allocate_little_and_end_quickly() {
    for text in [
        "OFF\n18446744073709551615 18446744073709551615 0\n0 0 0\n",
        "OFF\n1000000000000 1 0\n0 0 0\n1 0 0\n",
        "OFF\n3 1000000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n",
        "OFF 4294967296 4294967296\n",
    ] {
        read(text, Format::Off);
        let err = bdmorph::io::parse_off(text, std::path::Path::new("")).expect_err(text);
        assert!(err.to_string().contains("unexpected end of file"), "{err}");
    }
    // OBJ declares no counts; indices far beyond the vertices cost nothing per index either.
    let text = format!("v 0 0\nv 1 0\nv 0 1\n{}", "f 4294967296 2 3\n".repeat(1000));
    read(&text, Format::Obj);
}

#[test]
fn base_programs_pass_the_checks() {
    for parts in check::base_programs() {
        check::verifier(parts.clone());
    }
}

// ---------------------------------------------------------------------------------------------
// Regression tests: inputs the fuzzing found, minimised.

/// From `fuzz_verifier_mutated_from_bytes` (proptest; the run took minutes): the single
/// triangle's program claiming 2^32 - 1 vertices made the verifier fill a 16 GiB table, one
/// entry per claimed vertex, before checking anything else (20 s and 16 GiB per input).
#[test]
fn fuzz_verifier_regression_huge_vertex_count() {
    let mut parts = check::base_programs()[0].clone();
    let edit = Edit::Set(u32::MAX);
    check::mutate(
        &mut parts,
        Mutation {
            part: Part::Counts,
            index: 0,
            edit,
        },
    );
    assert_eq!(parts.n_vertices, u32::MAX);
    let err = bdmorph::Program::from_parts(parts.clone()).expect_err("refused");
    assert!(
        matches!(err, bdmorph_isa::VerifyError::Sizes { .. }),
        "{err}"
    );
    bounded_allocation(0, || check::verifier(parts));
}

/// From `fuzz_off_reader_structured` (proptest, minimised): a vertex with z = 1e308 was
/// refused with a message holding all 309 digits of z.
#[test]
fn fuzz_off_reader_regression_long_z_in_message() {
    let text = "OFF\n6 1 0\n0\n0\n1e308\n0 0 0\n0  255 0 0\n0  255 0 0\n0  255 0 0\n\
                0  255 0 0\n3 0 0 0\n";
    read(text, Format::Off);
    let mesh = bdmorph::io::parse_off(text, std::path::Path::new("z.off")).expect("parses");
    let err = bdmorph::PlanarMesh::from_surface(mesh, std::path::Path::new("z.off"));
    let expected = "z.off: vertex 0 (0-based) has z = 1e308; a planar mesh (z = 0) is required";
    assert_eq!(err.expect_err("not planar").to_string(), expected);
}

/// From reading the errors of `fuzz_obj_reader_structured` (proptest): a texture index out of
/// range was reported as a missing vertex ("vertex 9 does not exist (1 vertices)").
#[test]
fn fuzz_obj_reader_regression_texture_index_called_vertex() {
    let text = "v 0 0\nv 1 0\nv 0 1\nvt 0 0\nf 1/1 2/9 3/1\n";
    read(text, Format::Obj);
    let err = bdmorph::io::parse_obj(text, std::path::Path::new("t.obj")).expect_err("refused");
    assert_eq!(
        err.to_string(),
        "t.obj:5: texture coordinate 9 does not exist (1 'vt' lines)"
    );
}

// ---------------------------------------------------------------------------------------------
// Program files: `Program::from_bytes` on arbitrary bytes, and on damaged valid files and
// arbitrary sections whose length and checksum were made valid (so the damage reaches the
// section parser and the verifier).

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn fuzz_program_file_arbitrary_bytes(bytes in vec(any::<u8>(), 0..400)) {
        bounded_allocation(bytes.len(), || check::program_file(&bytes));
    }

    #[test]
    fn fuzz_program_file_damaged_with_valid_checksum(
        which in 0usize..8,
        edits in vec((any::<usize>(), any::<u8>()), 1..6),
        cut in any::<Option<usize>>(),
    ) {
        let mut bytes = check::base_file(which);
        let body = bytes.len() - 4;
        for (at, xor) in edits {
            bytes[at % body] ^= xor.max(1);
        }
        if let Some(cut) = cut {
            bytes.truncate(20.max(cut % body));
            bytes.extend_from_slice(&[0; 4]);
        }
        check::reseal(&mut bytes);
        bounded_allocation(bytes.len(), || check::program_file(&bytes));
    }

    #[test]
    fn fuzz_program_file_from_bytes(bytes in vec(any::<u8>(), 0..400)) {
        let file = check::file_from_bytes(&bytes);
        bounded_allocation(file.len(), || check::program_file(&file));
    }
}

#[test]
fn base_files_pass_the_checks() {
    for which in 0..check::base_programs().len() {
        let file = check::base_file(which);
        assert!(bdmorph::Program::from_bytes(&file).is_ok());
        check::program_file(&file);
        // Resealing an intact file changes nothing; a mode byte alone gives a base file.
        let mut resealed = file.clone();
        check::reseal(&mut resealed);
        assert_eq!(resealed, file);
        assert_eq!(check::file_from_bytes(&[2 * which as u8]), file);
    }
}

/// From cargo-fuzz `compiler` (libFuzzer, 13 s, 115,062 runs; artifact
/// crash-c6099d3a25f8d47d398e601fb2828cb1cef4b84b): coordinates near 1e150 passed the metric
/// check, and the layout overflowed to infinite positions (a debug assertion in the embed
/// stream; silent infinities in release). The VM now refuses such a layout before writing.
#[test]
fn fuzz_compiler_regression_layout_overflow() {
    let data = [
        15u8, 252, 254, 254, 255, 0, 130, 130, 132, 103, 0, 55, 201, 38, 219, 211, 141, 164, 0, 26,
    ];
    let (positions, faces) = check::mesh_from_bytes(&data);
    check::compile_and_run(&positions, &faces);
}

/// From `fuzz_svg_reader_structured` (proptest, minimised): an empty `points` list made a
/// path without a start, on which kurbo panicked ("uninitialized subpath").
#[test]
fn fuzz_svg_reader_regression_empty_points() {
    let text = "<svg>\n<polygon points=\"\"/>\n</svg>\n";
    outline(text.as_bytes(), check::OutlineFormat::Svg);
}

/// From `fuzz_svg_reader_arbitrary_bytes` and `fuzz_poly_reader_arbitrary_bytes` (proptest):
/// roxmltree's message quoted a line feed, and a `.poly` field was quoted whole (hundreds of
/// bytes of control characters): messages of several lines or far too long.
#[test]
fn fuzz_outline_readers_regression_quoted_text() {
    let svg = "<svg>\n<g>\n<rect width=\"1\" height=\"1\"\n</svg>";
    outline(svg.as_bytes(), check::OutlineFormat::Svg);
    let poly = format!("{}\u{e}\n", "x".repeat(400));
    outline(poly.as_bytes(), check::OutlineFormat::Poly);
}

#[test]
fn the_layered_seeds_read() {
    for valid in [&*VALID_PSD, &*VALID_ORA] {
        let l = bdmorph::parts::read_layered(valid).expect("a valid seed");
        assert_eq!(l.layers.len(), 6);
    }
}
