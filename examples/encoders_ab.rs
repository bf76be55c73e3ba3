//! The whole-slice encoders (`encode_gif`, `encode_mp4`: every frame in memory) against the
//! streaming ones (`GifEncoder`, `Mp4Encoder`), on the same frames, measured in turns: each
//! round renders N frames of a twisting disk at S x S pixels once, then times, in rotating
//! order, the GIF as one slice, in batches of 2 x threads, one frame at a time, and the MP4
//! as one slice and one frame at a time (encoding only; the frames are already drawn).
//! Checks that every way gives the same bytes, and prints the median wall-clock and CPU
//! time (every thread's, where Linux reports it) of each.
//!
//! ```sh
//! cargo run --release --example encoders_ab -- 200 640 5     # N [S [rounds]]
//! ```

use std::io::Cursor;
use std::time::Instant;

use bdmorph::generate;
use bdmorph::render::raster::{self, GifEncoder};
use bdmorph::render::video::{self, Mp4Encoder};
use bdmorph::render::{Drawing, Image, ImageSize, Viewport};

fn arg<T: std::str::FromStr>(i: usize, default: T) -> T {
    std::env::args()
        .nth(i)
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// CPU seconds used so far by every thread of the process (user and system; Linux's
/// `/proc/self/stat` counts in 1/100 s), or NaN elsewhere.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // The fields after the command name (which is in parentheses): utime and stime are the
    // 12th and 13th.
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or(vec![], |(_, rest)| rest.split_whitespace().collect());
    let ticks = |k: usize| fields.get(k).and_then(|f| f.parse::<f64>().ok());
    match (ticks(11), ticks(12)) {
        (Some(user), Some(system)) => (user + system) / 100.0,
        _ => f64::NAN,
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

type Way = (&'static str, fn(&[Image], u32) -> Vec<u8>);

fn gif_whole(frames: &[Image], _: u32) -> Vec<u8> {
    raster::encode_gif(frames, 4).expect("gif")
}

fn gif_batches(frames: &[Image], side: u32) -> Vec<u8> {
    let mut encoder = GifEncoder::new(Vec::new(), side, side, 4).expect("encoder");
    for batch in frames.chunks(2 * rayon::current_num_threads()) {
        encoder.push_batch(batch).expect("push");
    }
    encoder.finish().expect("finish")
}

fn gif_each(frames: &[Image], side: u32) -> Vec<u8> {
    let mut encoder = GifEncoder::new(Vec::new(), side, side, 4).expect("encoder");
    for frame in frames {
        encoder.push(frame).expect("push");
    }
    encoder.finish().expect("finish")
}

fn mp4_whole(frames: &[Image], _: u32) -> Vec<u8> {
    video::encode_mp4(frames, 25).expect("mp4")
}

fn mp4_each(frames: &[Image], side: u32) -> Vec<u8> {
    let mut encoder = Mp4Encoder::new(Cursor::new(Vec::new()), side, side, 25).expect("encoder");
    for frame in frames {
        encoder.push(frame).expect("push");
    }
    encoder.finish().expect("finish").into_inner()
}

fn main() {
    let n: usize = arg(1, 200);
    let side: u32 = arg(2, 640);
    let rounds: usize = arg(3, 5);
    let mesh = generate::disk(20, 0.2);
    let view = Viewport::fit([&mesh.positions[..]]);
    let size = ImageSize {
        width: side,
        height: side,
    };
    let frames: Vec<Image> = (0..n)
        .map(|i| {
            let moved = generate::twist(&mesh, 3.0 * i as f64 / n as f64);
            let drawing = Drawing {
                faces: &moved.faces,
                corner_uv: None,
                texture: None,
                face_colours: None,
                depth: None,
            };
            raster::render(&moved.positions, &drawing, &view, size)
                .expect("within the picture budget")
        })
        .collect();
    let ways: [Way; 5] = [
        ("GIF, one slice (encode_gif)", gif_whole),
        ("GIF, batches of 2 x threads", gif_batches),
        ("GIF, one frame at a time", gif_each),
        ("MP4, one slice (encode_mp4)", mp4_whole),
        ("MP4, one frame at a time", mp4_each),
    ];
    println!(
        "{n} frames of {side}x{side}, {} threads, {rounds} rounds",
        rayon::current_num_threads()
    );
    let mut times = vec![Vec::new(); ways.len()];
    let mut cpu = vec![Vec::new(); ways.len()];
    let mut bytes: Vec<Option<Vec<u8>>> = vec![None; ways.len()];
    for round in 0..rounds {
        for k in 0..ways.len() {
            let w = (k + round) % ways.len();
            let (start, cpu_start) = (Instant::now(), cpu_seconds());
            let out = ways[w].1(&frames, side);
            times[w].push(start.elapsed().as_secs_f64());
            cpu[w].push(cpu_seconds() - cpu_start);
            bytes[w].get_or_insert(out);
        }
    }
    assert_eq!(bytes[0], bytes[1], "GIF batches");
    assert_eq!(bytes[0], bytes[2], "GIF one at a time");
    assert_eq!(bytes[3], bytes[4], "MP4 one at a time");
    for (w, (name, _)) in ways.iter().enumerate() {
        let mut t = times[w].clone();
        let (lo, hi) = (
            t.iter().copied().fold(f64::INFINITY, f64::min),
            t.iter().copied().fold(0.0, f64::max),
        );
        println!(
            "{name:30} median {:6.2} s  (min {lo:.2}, max {hi:.2}; CPU {:.2} s; {:.1} MB)",
            median(&mut t),
            median(&mut cpu[w]),
            bytes[w].as_ref().map_or(0, Vec::len) as f64 / 1e6
        );
    }
}
