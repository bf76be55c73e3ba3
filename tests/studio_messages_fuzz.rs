//! Fuzzing on stable with proptest: the studio's text messages as the server reads them
//! ([`bdmorph::studio::messages::parse_request`]). Every input gives a request or a typed,
//! one-line error, never a panic, and the memory it holds at its peak stays within a small
//! multiple of its length (the cargo-fuzz target `studio_messages` in `fuzz/` carries the
//! requests out as well). `PROPTEST_CASES` sets the case count for a long run.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use bdmorph::studio::messages::{parse_request, MessageError};
use proptest::prelude::*;

struct Tracking;

thread_local! {
    static LIVE: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

fn grow(size: isize) {
    let _ = LIVE.try_with(|live| {
        let now = live.get() + size;
        live.set(now);
        let _ = PEAK.try_with(|peak| peak.set(peak.get().max(now)));
    });
}

// SAFETY: forwards to the system allocator; the records are plain thread-local Cells.
unsafe impl GlobalAlloc for Tracking {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        grow(layout.size() as isize);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        grow(layout.size() as isize);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        grow(-(layout.size() as isize));
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        grow(new_size as isize - layout.size() as isize);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Tracking = Tracking;

/// Parses `text`, checking that the memory held at the peak (the result included) stays
/// within `64 KiB + 16 * len`.
fn parse_bounded(text: &str) -> Result<(), MessageError> {
    let start = LIVE.with(Cell::get);
    PEAK.with(|p| p.set(start));
    let parsed = parse_request(text).map(|_| ());
    let peak = PEAK.with(Cell::get) - start;
    let limit = (64 << 10) + 16 * text.len() as isize;
    assert!(
        peak <= limit,
        "{peak} bytes held for a message of {} bytes",
        text.len()
    );
    if let Err(e) = &parsed {
        assert!(!e.to_string().contains('\n'), "one line: {e}");
    }
    parsed
}

const OPS: &[&str] = &[
    "outline_set",
    "drag",
    "load_keyframe",
    "import_outline",
    "paint_depth",
    "paint_stiffness",
    "part_order",
    "select",
    "export",
    "save",
    "hello",
    "cancel",
    "nonsense",
];

const KEYS: &[&str] = &[
    "loops",
    "seq",
    "pins",
    "targets",
    "moving",
    "name",
    "text",
    "time",
    "vertices",
    "faces",
    "all",
    "level",
    "weight",
    "order",
    "keyframe",
    "format",
    "overwrite",
    "x",
];

fn value() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        Just("0".to_owned()),
        Just("-1".to_owned()),
        Just("1e308".to_owned()),
        Just("2.5".to_owned()),
        Just("true".to_owned()),
        Just("null".to_owned()),
        "[a-z]{0,8}".prop_map(|s| format!("\"{s}\"")),
    ];
    leaf.prop_recursive(4, 64, 8, |inner| {
        prop::collection::vec(inner, 0..8).prop_map(|v| format!("[{}]", v.join(",")))
    })
}

fn message() -> impl Strategy<Value = String> {
    (
        prop::sample::select(OPS),
        prop::collection::vec((prop::sample::select(KEYS), value()), 0..6),
    )
        .prop_map(|(op, fields)| {
            let mut parts = vec![format!("\"op\":\"{op}\"")];
            parts.extend(fields.into_iter().map(|(k, v)| format!("\"{k}\":{v}")));
            format!("{{{}}}", parts.join(","))
        })
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(512),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn fuzz_studio_messages_from_a_grammar(text in message()) {
        let _ = parse_bounded(&text);
    }

    #[test]
    fn fuzz_studio_messages_from_any_text(text in "\\PC{0,200}") {
        let _ = parse_bounded(&text);
    }
}

#[test]
fn a_large_outline_costs_a_few_times_its_length() {
    let points = "[1.5,2.5],".repeat(400_000);
    let text = format!(r#"{{"op":"outline_set","loops":[[{points}[0,0]]]}}"#);
    assert!(parse_bounded(&text).is_ok());
    // Many one-point loops: the most a message makes of its bytes (about 12 times).
    let loops = "[[1,2]],".repeat(400_000);
    let text = format!(r#"{{"op":"outline_set","loops":[{loops}[]]}}"#);
    assert!(parse_bounded(&text).is_ok());
}
