//! Hostile and careless input to every command, run as the real program under a 1 GiB
//! address-space limit and a 5 s CPU limit (`prlimit`): each must be refused with exit code 1
//! (bad input) or 2 (bad usage), in exactly one line on stderr naming the file or option at
//! fault, leaving no file behind; or, for the few marked so, done within the same bounds
//! with a note saying what was left out (exit 0). A run that aborts, runs out of memory or
//! time, or hangs (60 s, for a blocked read) fails.
//!
//! The inputs are made here, in code: malformed and truncated meshes, counts that claim more
//! than their file holds, non-finite and overflowing numbers, files that are not files
//! (FIFOs, devices, directories), nested and oversized outlines, decompression bombs,
//! options out of range. A table of every case (exit code, time, message) is printed:
//!
//! ```text
//! cargo test --test hostile -- --nocapture
//! ```
//!
//! Also here: the requests that are large but legitimate, which must succeed within the same
//! memory (frames and `--stats` lines stream) or stop by themselves (iterations converge).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The program under test.
const BIN: &str = env!("CARGO_BIN_EXE_bdmorph");

/// Address space allowed to each run.
const MEMORY: u64 = 1 << 30;

/// CPU seconds allowed to each run.
const CPU_SECONDS: u32 = 5;

/// Wall-clock seconds after which a run counts as hung (a blocked read uses no CPU).
const HANG: Duration = Duration::from_secs(60);

/// A fresh scratch directory for one case.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-hostile-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch directory");
    dir
}

/// The names in `dir`, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("readable")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// What a run did.
struct Outcome {
    code: Option<i32>,
    stdout: String,
    stderr: String,
    elapsed: Duration,
}

/// Runs the program in `dir` with `args` under the limits; `None` if it hung.
fn run_limited(dir: &Path, args: &[String]) -> Option<Outcome> {
    let mut command = Command::new("prlimit");
    command
        .arg(format!("--as={MEMORY}"))
        .arg(format!("--cpu={CPU_SECONDS}"))
        .arg("--")
        .arg(BIN)
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let started = Instant::now();
    let mut child = command
        .spawn()
        .expect("prlimit (util-linux) runs the program under its limits");
    // Read the pipes on threads, so that a chatty child never blocks on a full pipe.
    let mut out = child.stdout.take().expect("piped");
    let mut err = child.stderr.take().expect("piped");
    let out = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = std::io::Read::read_to_end(&mut out, &mut s);
        s
    });
    let err = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = std::io::Read::read_to_end(&mut err, &mut s);
        s
    });
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if started.elapsed() > HANG {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let elapsed = started.elapsed();
    let text = |v: Vec<u8>| String::from_utf8_lossy(&v).into_owned();
    Some(Outcome {
        code: status.code(),
        stdout: text(out.join().expect("stdout reader")),
        stderr: text(err.join().expect("stderr reader")),
        elapsed,
    })
}

/// One hostile input: files to make, the arguments, and what the refusal must name.
struct Case {
    name: &'static str,
    /// Files written into the case's directory before the run.
    files: Vec<(&'static str, Vec<u8>)>,
    /// Named pipes made in the case's directory.
    fifos: Vec<&'static str>,
    /// Symbolic links made in the case's directory: (name, target).
    links: Vec<(&'static str, &'static str)>,
    /// The arguments (paths relative to the case's directory).
    args: Vec<String>,
    /// Exit code expected: 1 (bad input) or 2 (bad usage).
    code: i32,
    /// Texts the one error line must contain (the file or option, and the reason's words).
    says: Vec<&'static str>,
    /// Done within bounds instead of refused: exit 0, the first line on stderr a note that
    /// says `says` (what was left out), outputs written.
    done: bool,
}

fn words(text: &str) -> Vec<String> {
    text.split_whitespace().map(str::to_owned).collect()
}

fn case(name: &'static str, args: &str, code: i32, says: &[&'static str]) -> Case {
    Case {
        name,
        files: Vec::new(),
        fifos: Vec::new(),
        links: Vec::new(),
        args: words(args),
        code,
        says: says.to_vec(),
        done: false,
    }
}

impl Case {
    fn file(mut self, name: &'static str, bytes: impl Into<Vec<u8>>) -> Case {
        self.files.push((name, bytes.into()));
        self
    }
    fn fifo(mut self, name: &'static str) -> Case {
        self.fifos.push(name);
        self
    }
    fn link(mut self, name: &'static str, target: &'static str) -> Case {
        self.links.push((name, target));
        self
    }
    /// Done within bounds (exit 0) with a note saying `says`, rather than refused.
    fn done(mut self) -> Case {
        self.done = true;
        self.code = 0;
        self
    }
    /// The two good keyframes used by most cases.
    fn pair(self) -> Case {
        self.file("a.obj", SQUARE).file("b.obj", SQUARE_MOVED)
    }
}

/// A square of four triangles around a centre vertex.
const SQUARE: &str = "v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.5 0.5\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n";
/// The same square with its centre and a corner moved.
const SQUARE_MOVED: &str =
    "v 0 0\nv 1 0\nv 1.2 1\nv 0 1\nv 0.6 0.5\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n";
/// The square with its centre moved outside: exactly one triangle clockwise.
const ONE_INVERTED: &str =
    "v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 1.5 0.5\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n";
/// A tetrahedron: a closed surface.
const TETRAHEDRON: &str =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";

/// An `n` x `n` grid of unit squares' corners in the plane, two triangles per square; with
/// `hole`, the middle square left out.
fn grid(n: usize, hole: bool) -> String {
    let mut s = String::new();
    for j in 0..n {
        for i in 0..n {
            s += &format!(
                "v {} {} 0\n",
                i as f64 / (n - 1) as f64,
                j as f64 / (n - 1) as f64
            );
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            if hole && (i, j) == (n / 2 - 1, n / 2 - 1) {
                continue;
            }
            let a = j * n + i + 1;
            let (b, c, d) = (a + 1, a + n, a + n + 1);
            s += &format!("f {a} {b} {d}\nf {a} {d} {c}\n");
        }
    }
    s
}

/// An SVG holding one `<path>` of `d`.
fn svg_path(d: &str) -> String {
    format!("<svg xmlns=\"http://www.w3.org/2000/svg\"><path d=\"{d}\"/></svg>")
}

/// A PNG whose header claims `w` x `h` pixels, with a little compressed data.
fn png_claiming(w: u32, h: u32) -> Vec<u8> {
    png_padded(w, h, 0)
}

/// As [`png_claiming`], with `padding` bytes of a private ancillary chunk (which decoders
/// skip): as large as a real, well compressed picture of that size (a flat 16000 x 16000
/// PNG is about a megabyte).
fn png_padded(w: u32, h: u32, padding: usize) -> Vec<u8> {
    fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc32(&body).to_be_bytes());
    }
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 6, 0, 0, 0]);
    // A stored (uncompressed) zlib stream of zeros: valid, small.
    let zeros = [0u8; 1024];
    let mut idat = vec![0x78, 0x01, 1];
    idat.extend_from_slice(&(zeros.len() as u16).to_le_bytes());
    idat.extend_from_slice(&(!(zeros.len() as u16)).to_le_bytes());
    idat.extend_from_slice(&zeros);
    idat.extend_from_slice(&adler32(&zeros).to_be_bytes());
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    chunk(&mut out, b"IHDR", &ihdr);
    if padding > 0 {
        chunk(&mut out, b"prIv", &vec![0; padding]);
    }
    chunk(&mut out, b"IDAT", &idat);
    chunk(&mut out, b"IEND", &[]);
    out
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

fn adler32(bytes: &[u8]) -> u32 {
    let (mut a, mut b) = (1u32, 0u32);
    for &x in bytes {
        a = (a + u32::from(x)) % 65521;
        b = (b + a) % 65521;
    }
    (b << 16) | a
}

/// An RGBA PNG of `w` x `h` pixels whose alpha is `alpha(x, y)` (black), stored without
/// compression.
fn png_alpha(w: u32, h: u32, alpha: impl Fn(u32, u32) -> u8) -> Vec<u8> {
    let mut raw = Vec::new();
    for y in 0..h {
        raw.push(0);
        for x in 0..w {
            raw.extend_from_slice(&[0, 0, 0, alpha(x, y)]);
        }
    }
    // Stored deflate blocks of at most 65535 bytes each.
    let mut idat = vec![0x78, 0x01];
    let blocks: Vec<&[u8]> = raw.chunks(65535).collect();
    for (k, block) in blocks.iter().enumerate() {
        idat.push(u8::from(k + 1 == blocks.len()));
        idat.extend_from_slice(&(block.len() as u16).to_le_bytes());
        idat.extend_from_slice(&(!(block.len() as u16)).to_le_bytes());
        idat.extend_from_slice(block);
    }
    idat.extend_from_slice(&adler32(&raw).to_be_bytes());
    let mut out = png_claiming(w, h);
    // Replace the claiming PNG's IDAT and IEND (after the 8-byte signature and 25-byte IHDR).
    out.truncate(8 + 25);
    for (kind, data) in [(*b"IDAT", idat), (*b"IEND", Vec::new())] {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend_from_slice(&data);
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc32(&body).to_be_bytes());
    }
    out
}

/// A studio project of a textured square (texture `t.png`) with keyframes at 0 and `last`
/// seconds.
fn project(last: &str) -> String {
    let square = "[[0,0],[1,0],[1,1],[0,1]]";
    format!(
        "{{\"format\":\"bdmorph-studio\",\"version\":3,\"mesh\":{{\"positions\":{square},\"faces\":[[0,1,2],[0,2,3]],\"texcoords\":{square}}},\"texture\":\"t.png\",\"method\":{{\"name\":\"sd\",\"weight\":100,\"max_distortion\":3}},\"fps\":25,\"outline\":[{square}],\"picture\":{{\"background\":null,\"threshold\":null}},\"keyframes\":[{{\"time\":0,\"easing\":\"linear\",\"positions\":{square},\"pins\":[]}},{{\"time\":{last},\"easing\":\"linear\",\"positions\":[[0,0],[1,0],[1.2,1],[0,1]],\"pins\":[]}}]}}"
    )
}

/// Pseudo-random bytes (a fixed LCG: the same every run).
fn noise(n: usize, seed: u64) -> Vec<u8> {
    let mut x = seed;
    (0..n)
        .map(|_| {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (x >> 56) as u8
        })
        .collect()
}

fn cases() -> Vec<Case> {
    let big_grid = grid(40, false);
    vec![
        // --- morph: counts and numbers from the command line
        case("morph, frames: a billion", "morph a.obj b.obj --frames 1000000000 -o out", 1, &["--frames 1000000000", "100000"]).pair(),
        case("morph, frames: a hundred million, stats", "morph a.obj b.obj --frames 100000000 --stats", 1, &["--frames"]).pair(),
        case("morph, frames: negative", "morph a.obj b.obj --frames -1 --stats", 2, &["--frames"]).pair(),
        case("morph, frames: one", "morph a.obj b.obj --frames 1 --stats", 1, &["--frames 1"]).pair(),
        case("morph, frames: kept frames over the memory limit", "morph a.obj g.obj --frames 100000 -o out.gif", 1, &["out.gif", "GiB"]).file("a.obj", big_grid.clone()).file("g.obj", big_grid.clone()),
        case("morph, t: not a number", "morph a.obj b.obj --t NaN --stats", 1, &["--t"]).pair(),
        case("morph, t: infinite", "morph a.obj b.obj --t inf --stats", 1, &["--t"]).pair(),
        case("morph, tolerance: negative", "morph a.obj b.obj --t 0.5 --tolerance -1 --stats", 1, &["--tolerance"]).pair(),
        case("morph, fps: zero", "morph a.obj b.obj --frames 3 --fps 0 -o out.gif", 1, &["--fps"]).pair(),
        case("morph, size: a billion pixels", "morph a.obj b.obj --t 0.5 --size 100000x100000 -o out.png", 2, &["--size"]).pair(),
        case("morph, size: zero", "morph a.obj b.obj --t 0.5 --size 0x0 -o out.png", 2, &["--size"]).pair(),
        case("morph, durations: wrong count", "morph a.obj b.obj --frames 3 --durations 1,2,3 --stats", 1, &["--durations"]).pair(),
        case("morph, easing: unknown", "morph a.obj b.obj --frames 3 --easing wobble --stats", 2, &["--easing"]).pair(),
        case("morph, output: unknown extension", "morph a.obj b.obj --t 0.5 -o out.xyz", 1, &["out.xyz"]).pair(),
        case("morph, output: in a missing directory", "morph a.obj b.obj --t 0.5 -o missing/deeper/out.png", 1, &["missing/deeper/out.png"]).pair(),
        // --- morph: the mesh files
        case("morph, mesh: missing", "morph nothere.obj b.obj --t 0.5 --stats", 1, &["nothere.obj"]).pair(),
        case("morph, mesh: empty", "morph e.obj b.obj --t 0.5 --stats", 1, &["e.obj"]).pair().file("e.obj", ""),
        case("morph, mesh: random bytes", "morph r.obj b.obj --t 0.5 --stats", 1, &["r.obj"]).pair().file("r.obj", noise(4096, 1)),
        case("morph, mesh: a face past the vertices", "morph f.obj b.obj --t 0.5 --stats", 1, &["f.obj"]).pair().file("f.obj", "v 0 0\nv 1 0\nv 0 1\nf 1 2 4000000000\n"),
        case("morph, mesh: NaN coordinate", "morph n.obj b.obj --t 0.5 --stats", 1, &["n.obj"]).pair().file("n.obj", SQUARE.replace("v 1 1", "v NaN 1")),
        case("morph, mesh: coordinate overflowing to infinity", "morph n.obj b.obj --t 0.5 --stats", 1, &["n.obj"]).pair().file("n.obj", SQUARE.replace("v 1 1", &format!("v 1{} 1", "0".repeat(400)))),
        case("morph, mesh: a quad", "morph q.obj b.obj --t 0.5 --stats", 1, &["q.obj"]).pair().file("q.obj", "v 0 0\nv 1 0\nv 1 1\nv 0 1\nf 1 2 3 4\n"),
        case("morph, mesh: OFF claiming a billion vertices", "morph c.off b.obj --t 0.5 --stats", 1, &["c.off"]).pair().file("c.off", "OFF\n1000000000 1000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
        case("morph, mesh: OFF claiming 1e14 vertices", "morph c.off b.obj --t 0.5 --stats", 1, &["c.off"]).pair().file("c.off", "OFF\n100000000000000 1 0\n0 0 0\n"),
        case("morph, mesh: a FIFO", "morph p.obj b.obj --t 0.5 --stats", 1, &["p.obj", "regular file"]).pair().fifo("p.obj"),
        case("morph, mesh: a link to /dev/zero", "morph z.obj b.obj --t 0.5 --stats", 1, &["z.obj", "regular file"]).pair().link("z.obj", "/dev/zero"),
        case("morph, mesh: a directory", "morph d.obj b.obj --t 0.5 --stats", 1, &["d.obj"]).pair().link("d.obj", "/tmp"),
        case("morph, mesh: different triangles", "morph a.obj t.obj --t 0.5 --stats", 1, &["t.obj"]).pair().file("t.obj", "v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.5 0.5\nf 1 2 3\nf 1 3 4\nf 2 3 5\nf 4 1 5\n"),
        case("morph, mesh: one inverted triangle", "morph a.obj i.obj --t 0.5 --stats", 1, &["i.obj", "--allow-inverted"]).pair().file("i.obj", ONE_INVERTED),
        case("morph, texture: random bytes", "morph a.obj b.obj --t 0.5 --texture t.png -o out.png", 1, &["t.png"]).pair().file("t.png", noise(2048, 2)),
        case("morph, texture: a FIFO", "morph a.obj b.obj --t 0.5 --texture t.png -o out.png", 1, &["t.png"]).pair().fifo("t.png"),
        case("morph, texture: a decompression bomb", "morph a.obj b.obj --t 0.5 --texture t.png -o out.png", 1, &["t.png", "16384"]).pair().file("t.png", png_claiming(100_000, 100_000)),
        case("morph, program: random bytes", "morph a.obj b.obj --t 0.5 --program p.bdm --stats", 1, &["p.bdm"]).pair().file("p.bdm", noise(512, 3)),
        // --- blend
        case("blend: weights not a number", "blend a.obj b.obj --weights NaN,1 -o out.obj", 1, &["weight"]).pair(),
        case("blend: weights of the wrong count", "blend a.obj b.obj --weights 1,2,3 -o out.obj", 1, &["weight"]).pair(),
        // --- param
        case("param: unknown method", "param g.obj --method nonsense -o out.obj", 2, &["--method"]).file("g.obj", grid(5, false)),
        case("param: one vertex pinned twice", "param g.obj --method bounded --max-distortion 2 --pin 0:0,0 --pin 0:1,1 -o out.obj", 1, &["g.obj", "pinned twice"]).file("g.obj", grid(5, false)),
        case("param: a pin on a missing vertex", "param g.obj --method bounded --max-distortion 2 --pin 999999:0,0 -o out.obj", 1, &["999999"]).file("g.obj", grid(5, false)),
        case("param: a pin to NaN", "param g.obj --method bounded --max-distortion 2 --pin 0:nan,0 -o out.obj", 2, &["--pin", "0:nan,0"]).file("g.obj", grid(5, false)),
        case("param: a bound below 1", "param g.obj --method bounded --max-distortion 0.5 -o out.obj", 1, &["0.5"]).file("g.obj", grid(5, false)),
        case("param: holes", "param h.obj --method arap -o out.obj", 1, &["h.obj", "holes", "parameterisation"]).file("h.obj", grid(6, true)),
        case("param: a closed surface", "param t.obj -o out.obj", 1, &["t.obj", "closed"]).file("t.obj", TETRAHEDRON),
        case("param: iterations negative", "param g.obj --method arap --iterations -5 -o out.obj", 2, &["--iterations"]).file("g.obj", grid(5, false)),
        // --- deform
        case("deform: a pin on a missing vertex", "deform a.obj --method arap --pin 4000000000:0,0 -o out.obj", 1, &["4000000000"]).file("a.obj", SQUARE),
        case("deform: one vertex pinned twice", "deform a.obj --method arap --pin 0:0,0 --pin 0:1,1 -o out.obj", 1, &["both on vertex 0"]).file("a.obj", SQUARE),
        case("deform: a pin that is not a pin", "deform a.obj --method arap --pin zero -o out.obj", 2, &["--pin"]).file("a.obj", SQUARE),
        // --- geodesic
        case("geodesic: a missing source vertex", "geodesic g.obj --source 999999 -o out.txt", 1, &["999999"]).file("g.obj", grid(5, false)),
        case("geodesic: a negative source", "geodesic g.obj --source -1 -o out.txt", 2, &["--source"]).file("g.obj", grid(5, false)),
        // --- mesh: outlines and pictures
        case("mesh: a poly coordinate not a number", "mesh n.poly -o out.obj", 1, &["n.poly"]).file("n.poly", "3 2 0 0\n1 0 0\n2 nan 0\n3 0 1\n3 0\n1 1 2\n2 2 3\n3 3 1\n0\n"),
        case("mesh: poly claiming a billion vertices", "mesh c.poly -o out.obj", 1, &["c.poly"]).file("c.poly", "1000000000 2 0 0\n1 0 0\n2 1 0\n3 0 1\n3 0\n1 1 2\n"),
        case("mesh: poly claiming 1e14 vertices", "mesh c.poly -o out.obj", 1, &["c.poly"]).file("c.poly", "100000000000000 2 0 0\n"),
        case("mesh: a circle of radius 1e154", "mesh c.svg -o out.obj", 1, &["c.svg"]).file("c.svg", "<svg xmlns=\"http://www.w3.org/2000/svg\"><circle r=\"1e154\"/></svg>"),
        case("mesh: a bow tie", "mesh b.svg -o out.obj", 1, &["b.svg", "cross"]).file("b.svg", "<svg xmlns=\"http://www.w3.org/2000/svg\"><polygon points=\"0,0 10,10 10,0 0,10\"/></svg>"),
        case("mesh: a coordinate overflowing to infinity", "mesh o.svg -o out.obj", 1, &["o.svg"]).file("o.svg", svg_path(&format!("M 0 0 L 1{} 0 L 0 10 Z", "0".repeat(400)))),
        case("mesh: not XML", "mesh x.svg -o out.obj", 1, &["x.svg"]).file("x.svg", "<svg><g></svg"),
        case("mesh: entity expansion", "mesh x.svg -o out.obj", 1, &["x.svg"]).file("x.svg", format!("<?xml version=\"1.0\"?><!DOCTYPE svg [<!ENTITY a \"{}\"><!ENTITY b \"{}\"><!ENTITY c \"{}\">]><svg xmlns=\"http://www.w3.org/2000/svg\"><desc>&c;&c;&c;&c;</desc></svg>", "x".repeat(1000), "&a;".repeat(1000), "&b;".repeat(1000))),
        case("mesh: no shapes", "mesh e.svg -o out.obj", 1, &["e.svg"]).file("e.svg", "<svg xmlns=\"http://www.w3.org/2000/svg\"></svg>"),
        case("mesh: a picture of random bytes", "mesh r.png -o out.obj", 1, &["r.png"]).file("r.png", { let mut b = b"\x89PNG\r\n\x1a\n".to_vec(); b.extend(noise(4096, 4)); b }),
        case("mesh: a decompression bomb", "mesh b.png -o out.obj", 1, &["b.png", "16384"]).file("b.png", png_claiming(100_000, 100_000)),
        case("mesh: a picture claiming 16000 x 16000 pixels in 1 KB", "mesh b.png -o out.obj", 1, &["b.png", "claims"]).file("b.png", png_claiming(16_000, 16_000)),
        case("mesh: a FIFO", "mesh p.svg -o out.obj", 1, &["p.svg", "regular file"]).fifo("p.svg"),
        case("mesh: tolerance zero", "mesh s.svg --tolerance 0 -o out.obj", 1, &["--tolerance"]).file("s.svg", svg_path("M 0 0 L 10 0 L 10 10 Z")),
        case("mesh: tolerance not a number", "mesh s.svg --tolerance NaN -o out.obj", 1, &["--tolerance"]).file("s.svg", svg_path("M 0 0 L 10 0 L 10 10 Z")),
        // --- pictures over the decoded-size budget (64 Mpx), as real files of their size
        case("mesh: a valid 1 MB PNG of 16000 x 16000", "mesh b.png -o out.obj", 1, &["b.png", "16000x16000", "67108864"]).file("b.png", png_padded(16_000, 16_000, 1 << 20)),
        case("morph, texture: a 1 MB PNG of 16000 x 16000", "morph a.obj b.obj --t 0.5 --texture t.png -o out.png", 1, &["t.png", "16000x16000", "67108864"]).pair().file("t.png", png_padded(16_000, 16_000, 1 << 20)),
        case("export: a project textured by a 1 MB PNG of 16000 x 16000 (exported without it)", "export p.json -o out.gif", 1, &["t.png", "16000x16000", "without its picture"]).file("p.json", project("1")).file("t.png", png_padded(16_000, 16_000, 1 << 20)).done(),
        case("export: a keyframe drawn by a 1 MB PNG of 16000 x 16000 (exported without it)", "export p.json -o out.gif", 0, &["d.png", "16000x16000", "rest picture"]).file("p.json", project("1").replace("\"time\":1,", "\"time\":1,\"drawing\":{\"picture\":\"d.png\",\"texcoords\":[[0,0],[1,0],[1,1],[0,1]],\"pairs\":[]},")).file("t.png", png_alpha(8, 8, |_, _| 255)).file("d.png", png_padded(16_000, 16_000, 1 << 20)).done(),
        case("inbetween: a 1 MB PNG of 16000 x 16000", "inbetween b.png b.png --t 0.5 -o out.png", 1, &["b.png", "16000x16000"]).file("b.png", png_padded(16_000, 16_000, 1 << 20)),
        // --- in-betweens of noise and patterns
        case("inbetween: a 600 x 600 checkerboard with itself", "inbetween c.png c.png --t 0.5 -o out.png", 1, &["c.png", "5000 pieces", "64"]).file("c.png", png_alpha(600, 600, |x, y| if (x / 6 + y / 6) % 2 == 0 { 255 } else { 0 })),
        case("inbetween: random transparency with itself", "inbetween r.png r.png --t 0.5 -o out.png", 1, &["r.png", "loops", "--threshold"]).file("r.png", { let n = noise(600 * 600, 9); png_alpha(600, 600, move |x, y| n[(y * 600 + x) as usize]) }),
        case("inbetween: size 16384 x 16384", "inbetween a.png a.png --t 0.5 --size 16384x16384 -o out.png", 2, &["--size", "67108864"]).file("a.png", png_alpha(20, 20, |x, y| if (5..15).contains(&x) && (5..15).contains(&y) { 255 } else { 0 })),
        // --- pipes and devices as depth and project files
        case("morph, depth: a FIFO", "morph a.obj b.obj --t 0.5 --depth d.txt -o out.png", 1, &["d.txt", "regular file"]).pair().fifo("d.txt"),
        case("morph, depth: a link to /dev/zero", "morph a.obj b.obj --t 0.5 --depth d.txt -o out.png", 1, &["d.txt", "regular file"]).pair().link("d.txt", "/dev/zero"),
        case("export: the project a FIFO", "export p.json -o out.gif", 1, &["p.json", "regular file"]).fifo("p.json"),
        case("export: the project a link to /dev/zero", "export z.json -o out.gif", 1, &["z.json", "regular file"]).link("z.json", "/dev/zero"),
        case("studio: the project a FIFO", "studio p.json", 1, &["p.json", "regular file"]).fifo("p.json"),
        case("studio: the project a link to /dev/zero", "studio z.json", 1, &["z.json", "regular file"]).link("z.json", "/dev/zero"),
        // --- numbers and counts
        case("morph, t: 1e308", "morph a.obj b.obj --t 1e308 --stats", 1, &["1e308"]).pair(),
        case("morph, t: minus infinity", "morph a.obj b.obj --t -inf --stats", 1, &["--t -inf"]).pair(),
        case("morph, size: negative", "morph a.obj b.obj --t 0.5 --size -5x5 -o out.png", 2, &["--size", "-5x5"]).pair(),
        case("morph, size: 16384 x 16384", "morph a.obj b.obj --t 0.5 --size 16384x16384 -o out.png", 2, &["--size", "67108864"]).pair(),
        case("export: frames zero", "export p.json --frames 0 -o out.gif", 1, &["--frames 0", "2 frames"]).file("p.json", project("1")).file("t.png", png_alpha(8, 8, |_, _| 255)),
        case("export: frames one", "export p.json --frames 1 -o out.gif", 1, &["--frames 1", "2 frames"]).file("p.json", project("1")).file("t.png", png_alpha(8, 8, |_, _| 255)),
        case("export: a keyframe at 1e6 s", "export p.json -o out.gif", 1, &["frames", "10000"]).file("p.json", project("1e6")).file("t.png", png_alpha(8, 8, |_, _| 255)),
        case("export: a keyframe at 1e300 s", "export p.json -o out.gif", 1, &["frames", "10000"]).file("p.json", project("1e300")).file("t.png", png_alpha(8, 8, |_, _| 255)),
        // --- compile and info
        case("compile: holes", "compile h.obj -o out.bdm", 1, &["h.obj", "holes"]).file("h.obj", grid(6, true)),
        case("info: a link to /dev/zero", "info z.obj", 1, &["z.obj"]).link("z.obj", "/dev/zero"),
        case("info: random bytes", "info r.off", 1, &["r.off"]).file("r.off", noise(4096, 5)),
        // --- demo
        case("demo: a billion frames", "demo --frames 1000000000 -o out", 1, &["--frames"]),
        // --- the command line itself
        case("unknown command", "explode a.obj", 2, &["explode"]),
    ]
}

#[test]
fn every_hostile_input_is_refused_in_one_line_within_bounds() {
    assert!(
        Command::new("prlimit").arg("--version").output().is_ok(),
        "prlimit (util-linux) is needed to run the program under memory and CPU limits"
    );
    let cases = cases();
    assert!(cases.len() >= 50, "{} cases", cases.len());
    let mut failures = Vec::new();
    let mut table = String::from("| input | exit | ms | message |\n|---|---|---|---|\n");
    for (k, c) in cases.iter().enumerate() {
        let dir = scratch(&format!("{k}"));
        for (name, bytes) in &c.files {
            std::fs::write(dir.join(name), bytes).expect("input written");
        }
        for name in &c.fifos {
            let made = Command::new("mkfifo").arg(dir.join(name)).status();
            assert!(made.is_ok_and(|s| s.success()), "mkfifo {name}");
        }
        for (name, target) in &c.links {
            std::os::unix::fs::symlink(target, dir.join(name)).expect("link made");
        }
        let before = entries(&dir);
        let Some(out) = run_limited(&dir, &c.args) else {
            failures.push(format!("{}: hung for {} s", c.name, HANG.as_secs()));
            continue;
        };
        let after = entries(&dir);
        let lines: Vec<&str> = out.stderr.lines().collect();
        let line = lines.first().copied().unwrap_or("");
        let _ = writeln!(
            table,
            "| {} | {} | {} | {} |",
            c.name,
            out.code.map_or("signal".into(), |c| c.to_string()),
            out.elapsed.as_millis(),
            line.chars().take(140).collect::<String>()
        );
        let mut wrong = Vec::new();
        if out.code != Some(c.code) {
            wrong.push(format!("exit {:?}, expected {}", out.code, c.code));
        }
        if c.done {
            if !line.starts_with("bdmorph: note: ") {
                wrong.push("no note on stderr".into());
            }
        } else if lines.len() != 1 || !line.starts_with("bdmorph: error: ") {
            wrong.push(format!("{} lines on stderr", lines.len()));
        }
        for says in &c.says {
            if !line.contains(says) {
                wrong.push(format!("the message does not say {says:?}"));
            }
        }
        if after != before && !c.done {
            wrong.push(format!("files left: {before:?} became {after:?}"));
        }
        if !wrong.is_empty() {
            failures.push(format!(
                "{}: {} (stderr: {:?}, stdout: {} bytes)",
                c.name,
                wrong.join("; "),
                out.stderr.chars().take(600).collect::<String>(),
                out.stdout.len()
            ));
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    println!("{table}");
    assert!(
        failures.is_empty(),
        "{} of {} hostile inputs were not refused cleanly:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

use std::fmt::Write as _;

/// `--stats` lines stream: 100,000 frames (the most one command computes) in 1 GiB.
#[test]
fn the_most_frames_stream_their_stats_within_the_memory_limit() {
    let dir = scratch("stats");
    std::fs::write(dir.join("a.obj"), SQUARE).expect("written");
    std::fs::write(dir.join("b.obj"), SQUARE_MOVED).expect("written");
    let out = run_limited(
        &dir,
        &words("morph a.obj b.obj --frames 100000 --stats --threads 1"),
    )
    .expect("finishes");
    assert_eq!(out.code, Some(0), "{}", out.stderr);
    assert_eq!(out.stdout.lines().count(), 100_000);
    let last = out.stdout.lines().last().expect("a last line");
    assert!(last.starts_with("{\"t\":1,"), "{last}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// OBJ frames stream to their directory: every file written, in 1 GiB.
#[test]
fn obj_frames_stream_to_their_directory() {
    let dir = scratch("frames");
    std::fs::write(dir.join("a.obj"), SQUARE).expect("written");
    std::fs::write(dir.join("b.obj"), SQUARE_MOVED).expect("written");
    let out = run_limited(
        &dir,
        &words("morph a.obj b.obj --frames 1200 -o frames --threads 2"),
    )
    .expect("finishes");
    assert_eq!(out.code, Some(0), "{}", out.stderr);
    let files = entries(&dir.join("frames"));
    assert_eq!(files.len(), 1200);
    assert_eq!(files[0], "frame_0000.obj");
    assert_eq!(files[1199], "frame_1199.obj");
    let last = std::fs::read_to_string(dir.join("frames/frame_1199.obj")).expect("read");
    assert!(last.contains("t = 1"), "{last}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Local/global ARAP and ASAP on a flat grid (whose minimum energy is zero) stop by themselves,
/// converged, with a billion iterations allowed.
#[test]
fn local_global_iterations_stop_by_themselves() {
    let dir = scratch("converge");
    std::fs::write(dir.join("g.obj"), grid(30, false)).expect("written");
    for method in ["arap", "asap"] {
        let args = words(&format!(
            "param g.obj --method {method} --iterations 1000000000 --stats -o out.obj"
        ));
        let out = run_limited(&dir, &args).expect("finishes");
        assert_eq!(out.code, Some(0), "{method}: {}", out.stderr);
        let report = out.stdout.lines().last().expect("a report");
        assert!(
            report.contains("\"stop\":\"converged\""),
            "{method}: {report}"
        );
        let iterations: u64 = report
            .split("\"iterations\":")
            .nth(1)
            .and_then(|r| r.split(',').next())
            .and_then(|n| n.parse().ok())
            .expect("an iteration count");
        assert!(iterations < 100_000, "{method}: {iterations} iterations");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Outputs onto a character device or a FIFO are refused, never renamed over: as root (CI
/// runs as root; `mknod` needs it), a device like `/dev/null` (1, 3) and a FIFO are made in
/// a fresh folder, `morph -o` and `compile -o` are pointed at each, and afterwards they are
/// still a device and a FIFO and nothing else is in the folder.
#[test]
fn outputs_onto_a_device_or_a_fifo_leave_them_as_they_are() {
    use std::os::unix::fs::FileTypeExt;
    let uid = Command::new("id").arg("-u").output().expect("id -u");
    if String::from_utf8_lossy(&uid.stdout).trim() != "0" {
        println!("skipped: not root, so no device node can be made (CI runs this as root)");
        return;
    }
    let dir = scratch("devices");
    std::fs::write(dir.join("a.obj"), SQUARE).expect("written");
    std::fs::write(dir.join("b.obj"), SQUARE_MOVED).expect("written");
    for name in ["dev.obj", "dev.bdm"] {
        let made = Command::new("mknod")
            .arg(dir.join(name))
            .args(["c", "1", "3"])
            .status();
        assert!(made.is_ok_and(|s| s.success()), "mknod {name}");
    }
    for name in ["fifo.obj", "fifo.bdm"] {
        let made = Command::new("mkfifo").arg(dir.join(name)).status();
        assert!(made.is_ok_and(|s| s.success()), "mkfifo {name}");
    }
    let before = entries(&dir);
    for (args, out) in [
        ("morph a.obj b.obj --t 0.5 -o dev.obj", "dev.obj"),
        ("morph a.obj b.obj --t 0.5 -o fifo.obj", "fifo.obj"),
        ("compile a.obj -o dev.bdm", "dev.bdm"),
        ("compile a.obj -o fifo.bdm", "fifo.bdm"),
    ] {
        let run = run_limited(&dir, &words(args)).expect("does not hang");
        println!(
            "| {args} | {} | {} |",
            run.code.map_or("signal".into(), |c| c.to_string()),
            run.stderr.trim()
        );
        assert_eq!(run.code, Some(1), "{args}: {}", run.stderr);
        assert_eq!(run.stderr.lines().count(), 1, "{args}: {}", run.stderr);
        assert!(
            run.stderr.contains(out) && run.stderr.contains("not a regular file"),
            "{args}: {}",
            run.stderr
        );
    }
    for name in ["dev.obj", "dev.bdm"] {
        let kind = std::fs::symlink_metadata(dir.join(name)).expect("still there");
        assert!(
            kind.file_type().is_char_device(),
            "{name} is no longer a device"
        );
    }
    for name in ["fifo.obj", "fifo.bdm"] {
        let kind = std::fs::symlink_metadata(dir.join(name)).expect("still there");
        assert!(kind.file_type().is_fifo(), "{name} is no longer a FIFO");
    }
    assert_eq!(entries(&dir), before, "files appeared or went");
    let _ = std::fs::remove_dir_all(&dir);
}
