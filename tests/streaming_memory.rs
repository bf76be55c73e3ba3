//! The streaming encoders' memory does not grow with the number of frames: 400 frames of
//! 320x320 pixels (164 MB of RGBA in all) go through a `GifEncoder` and an `Mp4Encoder`
//! while a counting global allocator records the peak of the Rust heap, and the process's
//! peak resident size (`VmHWM`, which also sees OpenH264's C++ allocations) is read from
//! `/proc/self/status` where Linux lets it be reset. Run with `--nocapture` for the numbers.
//!
//! One test function runs everything in turn: the allocator's counters are global.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::{self, Seek, SeekFrom, Write};
use std::sync::atomic::{AtomicUsize, Ordering};

use bdmorph::generate;
use bdmorph::render::raster::{self, GifEncoder};
use bdmorph::render::video::Mp4Encoder;
use bdmorph::render::{Drawing, Image, ImageSize, Viewport};

struct Counting;

static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn grew(by: usize) {
    let now = CURRENT.fetch_add(by, Ordering::Relaxed) + by;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

// SAFETY: forwards to the system allocator; the counters are atomics.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        grew(layout.size());
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        grew(layout.size());
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size >= layout.size() {
            grew(new_size - layout.size());
        } else {
            CURRENT.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Runs `f` and returns its result and the peak of the Rust heap above what was allocated
/// when it started.
fn heap_peak<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let base = CURRENT.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let out = f();
    (out, PEAK.load(Ordering::Relaxed).saturating_sub(base))
}

/// A `kB` field of `/proc/self/status`, in bytes.
fn status_bytes(field: &str) -> Option<usize> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(field))?;
    let kb: usize = line[field.len()..]
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb * 1024)
}

/// Runs `f` and returns how far the process's peak resident size rose above its resident
/// size at the start, when Linux lets the peak be reset (`/proc/self/clear_refs`).
fn rss_rise<T>(f: impl FnOnce() -> T) -> (T, Option<usize>) {
    let reset = std::fs::write("/proc/self/clear_refs", "5").is_ok();
    let before = status_bytes("VmRSS:");
    let out = f();
    let after = status_bytes("VmHWM:");
    match (reset, before, after) {
        (true, Some(b), Some(a)) => (out, Some(a.saturating_sub(b))),
        _ => (out, None),
    }
}

/// A sink that keeps nothing: it counts the bytes and follows the position (the MP4 muxer
/// seeks back to fix a size).
#[derive(Default)]
struct Discard {
    pos: u64,
    len: u64,
}

impl Write for Discard {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.pos += buf.len() as u64;
        self.len = self.len.max(self.pos);
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

impl Seek for Discard {
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        self.pos = match to {
            SeekFrom::Start(p) => p,
            SeekFrom::End(d) => self.len.saturating_add_signed(d),
            SeekFrom::Current(d) => self.pos.saturating_add_signed(d),
        };
        Ok(self.pos)
    }
}

const SIDE: u32 = 320;
const FRAME_BYTES: usize = (SIDE * SIDE * 4) as usize;
/// Frames rendered and pushed at a time into the GIF encoder.
const BATCH: usize = 8;

/// Renders frame `i` of `n` of a twisting disk: a line drawing with anti-aliased edges (more
/// than 256 colours, so the GIF quantises).
struct Frames {
    mesh: bdmorph::PlanarMesh,
    view: Viewport,
}

impl Frames {
    fn new() -> Frames {
        let mesh = generate::disk(12, 0.1);
        let view = Viewport::fit([&mesh.positions[..]]);
        Frames { mesh, view }
    }

    fn render(&self, i: usize, n: usize) -> Image {
        let moved = generate::twist(&self.mesh, 3.0 * i as f64 / n as f64);
        let drawing = Drawing {
            faces: &moved.faces,
            corner_uv: None,
            texture: None,
            face_colours: None,
            depth: None,
        };
        let size = ImageSize {
            width: SIDE,
            height: SIDE,
        };
        raster::render(&moved.positions, &drawing, &self.view, size)
            .expect("within the picture budget")
    }
}

/// Renders `n` frames a batch at a time into a GIF: (bytes written, heap peak).
fn gif(frames: &Frames, n: usize) -> (u64, usize) {
    let (len, peak) = heap_peak(|| {
        let mut encoder = GifEncoder::new(Discard::default(), SIDE, SIDE, 4).expect("encoder");
        for start in (0..n).step_by(BATCH) {
            let batch: Vec<Image> = (start..n.min(start + BATCH))
                .map(|i| frames.render(i, n))
                .collect();
            encoder.push_batch(&batch).expect("push");
        }
        encoder.finish().expect("finish").len
    });
    (len, peak)
}

/// Renders `n` frames one at a time into an MP4: (bytes written, heap peak).
fn mp4(frames: &Frames, n: usize) -> (u64, usize) {
    heap_peak(|| {
        let mut encoder = Mp4Encoder::new(Discard::default(), SIDE, SIDE, 25).expect("encoder");
        for i in 0..n {
            encoder.push(&frames.render(i, n)).expect("push");
        }
        encoder.finish().expect("finish").len
    })
}

fn mb(bytes: usize) -> f64 {
    bytes as f64 / 1e6
}

#[test]
fn streaming_memory_does_not_grow_with_the_frame_count() {
    let frames = Frames::new();
    let all = 400 * FRAME_BYTES;
    eprintln!(
        "400 frames of {SIDE}x{SIDE}: {:.1} MB of RGBA ({:.2} MB a frame)",
        mb(all),
        mb(FRAME_BYTES)
    );

    // The GIF, batches of 8 frames: 50 frames, then 400.
    let (len_50, peak_50) = gif(&frames, 50);
    let ((len_400, peak_400), rss) = rss_rise(|| gif(&frames, 400));
    eprintln!(
        "GIF, batches of {BATCH}: heap peak {:.2} MB for 50 frames ({:.2} MB written), \
         {:.2} MB for 400 frames ({:.2} MB written); resident peak rose {}",
        mb(peak_50),
        len_50 as f64 / 1e6,
        mb(peak_400),
        len_400 as f64 / 1e6,
        rss.map_or("(not measurable here)".to_owned(), |r| format!(
            "{:.1} MB",
            mb(r)
        )),
    );
    // A batch of frames, a copy of each being quantised, and the quantiser's tables.
    assert!(
        peak_400 < 3 * BATCH * FRAME_BYTES,
        "GIF heap peak {peak_400} B for 400 frames"
    );
    assert!(
        peak_400 < peak_50 + FRAME_BYTES,
        "GIF heap peak grows with the frame count: {peak_50} B for 50, {peak_400} B for 400"
    );
    if let Some(rss) = rss {
        assert!(rss < all / 8, "GIF resident peak rose {rss} B");
    }

    // The MP4, one frame at a time.
    let (len_50, peak_50) = mp4(&frames, 50);
    let ((len_400, peak_400), rss) = rss_rise(|| mp4(&frames, 400));
    eprintln!(
        "MP4, one frame at a time: heap peak {:.2} MB for 50 frames ({:.2} MB written), \
         {:.2} MB for 400 frames ({:.2} MB written); resident peak rose {}",
        mb(peak_50),
        len_50 as f64 / 1e6,
        mb(peak_400),
        len_400 as f64 / 1e6,
        rss.map_or("(not measurable here)".to_owned(), |r| format!(
            "{:.1} MB",
            mb(r)
        )),
    );
    // The frame in hand and the renderer's picture it came from, its Y'CbCr planes, its
    // compressed picture and the muxer's chunk of about a second of video.
    assert!(
        peak_400 < 8 * FRAME_BYTES,
        "MP4 heap peak {peak_400} B for 400 frames"
    );
    assert!(
        peak_400 < peak_50 + FRAME_BYTES / 4,
        "MP4 heap peak grows with the frame count: {peak_50} B for 50, {peak_400} B for 400"
    );
    if let Some(rss) = rss {
        // OpenH264's reference pictures and working buffers are outside the Rust heap.
        assert!(rss < all / 8, "MP4 resident peak rose {rss} B");
    }

    // For scale: the whole-slice encoders need every frame at once (here 50 of them).
    let (_, whole) = heap_peak(|| {
        let images: Vec<Image> = (0..50).map(|i| frames.render(i, 50)).collect();
        raster::encode_gif(&images, 4).expect("gif").len()
    });
    eprintln!(
        "encode_gif of 50 frames held at once: heap peak {:.1} MB",
        mb(whole)
    );
    assert!(whole > 50 * FRAME_BYTES);
}
