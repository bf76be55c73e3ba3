//! Reading triangle meshes from OBJ and OFF files, and writing planar meshes as OBJ.
//!
//! The readers are hand-written and allocate nothing per token. Every error names the file
//! and the 1-based line. Only triangles are accepted: polygons with more corners are refused
//! ([`ReadError::NotATriangle`]), not triangulated. The `*_with_lines` readers also return
//! where each vertex and face was read ([`LineMap`]), so that later errors about a face or a
//! vertex can name its line too (see [`crate::located`]).
//!
//! ```
//! use bdmorph::io::{format_obj_2d, parse_obj};
//! use std::path::Path;
//!
//! let text = "# a triangle\nv 0 0\nv 1 0\nv 0 1\nf 1 2 3\n";
//! let mesh = parse_obj(text, Path::new("tri.obj"))?;
//! assert_eq!(mesh.faces, vec![[0, 1, 2]]);
//! assert!(mesh.is_planar());
//!
//! let planar: Vec<[f64; 2]> = mesh.positions.iter().map(|p| [p[0], p[1]]).collect();
//! let mut out = Vec::new();
//! format_obj_2d(&mut out, &planar, &mesh.faces, &["a triangle"])?;
//! let written = String::from_utf8(out)?;
//! assert_eq!(written, "# a triangle\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
//! assert_eq!(parse_obj(&written, Path::new(""))?, mesh);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::fmt;
use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::str::SplitAsciiWhitespace;
use std::sync::atomic::{AtomicU32, Ordering};

/// A triangle mesh as read from a file: 3D positions (z = 0 for 2-coordinate `v` lines),
/// triangles as 0-based vertex indices.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceMesh {
    /// Vertex positions `[x, y, z]`, in file order.
    pub positions: Vec<[f64; 3]>,
    /// Triangles as 0-based indices into `positions`, in file order, corners as written.
    pub faces: Vec<[u32; 3]>,
    /// Texture coordinates, when the file has `vt` lines and every face names one per corner.
    pub texcoords: Option<TexCoords>,
}

/// Texture coordinates of an OBJ file: the `vt` values and, per face, the `vt` index of each
/// corner (so seams, where one vertex has several texture coordinates, are kept).
#[derive(Clone, Debug, PartialEq)]
pub struct TexCoords {
    /// The `vt` values `(u, v)` in file order.
    pub uv: Vec<[f64; 2]>,
    /// Per face, the 0-based index into `uv` of each corner; parallel to the faces.
    pub corners: Vec<[u32; 3]>,
}

impl TexCoords {
    /// The `(u, v)` of each corner of each face.
    pub fn corner_uv(&self) -> Vec<[[f64; 2]; 3]> {
        self.corners
            .iter()
            .map(|c| c.map(|i| self.uv.get(i as usize).copied().unwrap_or([0.0, 0.0])))
            .collect()
    }
}

impl SurfaceMesh {
    /// True when every z coordinate is exactly 0 (so the mesh can be treated as 2D).
    pub fn is_planar(&self) -> bool {
        self.positions.iter().all(|p| p[2] == 0.0)
    }
}

/// Where each vertex and face of a mesh file was read: the 1-based line of its `v` or `f`
/// line in an OBJ file, of the line its record starts on in an OFF file. Kept by
/// [`read_mesh_with_lines`] (and [`crate::located::MeshFile`]) so that errors about a face or
/// a vertex, found after reading, can point at its line.
///
/// ```
/// use bdmorph::io::parse_obj_with_lines;
/// use std::path::Path;
///
/// let text = "# a square\nv 0 0\nv 1 0\nv 1 1\nv 0 1\n\nf 1 2 3\nf 1 3 4\n";
/// let (mesh, lines) = parse_obj_with_lines(text, Path::new("square.obj"))?;
/// assert_eq!(mesh.faces.len(), 2);
/// assert_eq!(lines.face_line(1), Some(8)); // face 1 (0-based) is the second 'f' line
/// assert_eq!(lines.vertex_line(0), Some(2));
/// assert_eq!(lines.face_line(2), None); // no such face
/// # Ok::<(), bdmorph::io::ReadError>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LineMap {
    /// Per vertex, its line; 0 where unknown (a line beyond `u32::MAX`).
    vertices: Vec<u32>,
    /// Per face, its line; 0 where unknown.
    faces: Vec<u32>,
}

impl LineMap {
    /// A map from the lines of each vertex and each face (1-based; 0 for unknown), for meshes
    /// read by other means.
    pub fn new(vertex_lines: &[usize], face_lines: &[usize]) -> LineMap {
        let encode = |lines: &[usize]| lines.iter().map(|&l| encode_line(l)).collect();
        LineMap {
            vertices: encode(vertex_lines),
            faces: encode(face_lines),
        }
    }

    /// The 1-based line vertex `v` (0-based) was read from, when known.
    pub fn vertex_line(&self, v: usize) -> Option<usize> {
        decode_line(self.vertices.get(v))
    }

    /// The 1-based line face `f` (0-based) was read from, when known.
    pub fn face_line(&self, f: usize) -> Option<usize> {
        decode_line(self.faces.get(f))
    }
}

/// A line as stored in a [`LineMap`]: 0 for a line too far to store (and so unknown).
fn encode_line(line: usize) -> u32 {
    u32::try_from(line).unwrap_or(0)
}

fn decode_line(stored: Option<&u32>) -> Option<usize> {
    stored.filter(|&&l| l != 0).map(|&l| l as usize)
}

/// Why a mesh file could not be read. Every message is one line and names the file (and the
/// line, when there is one), e.g. `man.obj:12: expected a number after 'v', found 'abc'`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReadError {
    /// The file could not be opened or read.
    #[error("{}: cannot read: {source}", Shown(.path))]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
    /// Malformed content.
    #[error("{}:{line}: {message}", Shown(.path))]
    Parse {
        /// The file (empty when parsing a string that has no file name).
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A face refers to a vertex that does not exist.
    #[error("{}:{line}: vertex {index} does not exist ({vertex_count} vertices)", Shown(.path))]
    IndexOutOfRange {
        /// The file.
        path: PathBuf,
        /// 1-based line number of the face.
        line: usize,
        /// The index as written in the file (1-based or negative in OBJ, 0-based in OFF).
        index: i64,
        /// The number of vertices it was checked against: those read so far for a negative
        /// OBJ index, all of the file's vertices otherwise.
        vertex_count: usize,
    },
    /// A face refers to a texture coordinate (`vt`) that does not exist.
    #[error("{}:{line}: texture coordinate {index} does not exist ({count} 'vt' lines)", Shown(.path))]
    TexCoordOutOfRange {
        /// The file.
        path: PathBuf,
        /// 1-based line number of the face.
        line: usize,
        /// The index as written in the file (1-based or negative).
        index: i64,
        /// The number of texture coordinates it was checked against (as for vertices).
        count: usize,
    },
    /// A polygon with more than 3 corners (refused, not triangulated).
    #[error("{}:{line}: face has {corners} corners; only triangles are supported", Shown(.path))]
    NotATriangle {
        /// The file.
        path: PathBuf,
        /// 1-based line number of the face.
        line: usize,
        /// Number of corners of the face.
        corners: usize,
    },
    /// The extension is neither `.obj` nor `.off` (case-insensitive).
    #[error("{}: unknown mesh format (expected .obj or .off)", Shown(.path))]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// The file is empty (or holds only whitespace).
    #[error("{}: the file is empty", Shown(.path))]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// The file has no faces (and maybe no vertices either).
    #[error("{}: the mesh has {}", Shown(.path), NoFacesOf(*.vertices))]
    NoFaces {
        /// The file.
        path: PathBuf,
        /// The number of vertices it has (for OFF: declares).
        vertices: usize,
    },
    /// A control character that no text file holds (NUL, for instance): a binary file.
    #[error("{}:{line}: binary data (byte 0x{byte:02x}), not a text mesh file", Shown(.path))]
    Binary {
        /// The file.
        path: PathBuf,
        /// 1-based line of the first such byte.
        line: usize,
        /// The byte.
        byte: u8,
    },
}

impl ReadError {
    /// The 1-based line the error is on, when it is on one.
    pub fn line(&self) -> Option<usize> {
        match self {
            ReadError::Parse { line, .. }
            | ReadError::IndexOutOfRange { line, .. }
            | ReadError::TexCoordOutOfRange { line, .. }
            | ReadError::NotATriangle { line, .. }
            | ReadError::Binary { line, .. } => Some(*line),
            ReadError::Io { .. }
            | ReadError::UnknownFormat { .. }
            | ReadError::Empty { .. }
            | ReadError::NoFaces { .. } => None,
        }
    }
}

/// "no vertices and no faces" or "N vertices but no faces".
struct NoFacesOf(usize);

impl fmt::Display for NoFacesOf {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            0 => f.write_str("no vertices and no faces"),
            1 => f.write_str("1 vertex but no faces"),
            n => write!(f, "{n} vertices but no faces"),
        }
    }
}

/// Why a mesh file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// Creating, writing or renaming the file failed, or the data cannot be written as valid
    /// OBJ (`source` then has kind [`io::ErrorKind::InvalidInput`]).
    #[error("{}: cannot write: {source}", Shown(.path))]
    Io {
        /// The destination file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
}

/// Displays a path, or `<string>` for the empty path used when parsing text without a file.
pub(crate) struct Shown<'a>(pub(crate) &'a Path);

impl fmt::Display for Shown<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.as_os_str().is_empty() {
            f.write_str("<string>")
        } else {
            self.0.display().fmt(f)
        }
    }
}

/// Reads an `.obj` or `.off` file (extension compared case-insensitively).
///
/// Bytes that are not UTF-8 (say Latin-1 in a comment) are replaced, not rejected: they only
/// matter where numbers are expected, and there they give a parse error with a line. Control
/// characters that text does not hold (NUL, for instance) are refused as binary data
/// ([`ReadError::Binary`]), whichever the parser.
pub fn read_mesh(path: impl AsRef<Path>) -> Result<SurfaceMesh, ReadError> {
    let path = path.as_ref();
    read_mesh_with_lines(path).map(|(mesh, _)| mesh)
}

/// The largest input file read: 1 GiB (a mesh of tens of millions of triangles, a picture
/// at the largest size decoded).
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// Reads an input file whole, refusing, before opening it, anything but a regular file (a
/// FIFO would block, a device such as `/dev/zero` never ends, a directory is no file) and a
/// file over `limit` bytes; the read itself stops at `limit` (a file growing meanwhile).
///
/// # Errors
/// The I/O error, or one of kind `InvalidInput` saying what the path is or how large.
pub fn read_input(path: impl AsRef<Path>, limit: u64) -> io::Result<Vec<u8>> {
    let path = path.as_ref();
    use std::io::Read;
    let meta = fs::metadata(path)?;
    if !meta.is_file() {
        let what = if meta.is_dir() {
            "a directory"
        } else {
            "not a regular file (a pipe, socket or device)"
        };
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("is {what}"),
        ));
    }
    let too_large = |size: u64| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "is {size} bytes, over the {} MiB an input file may have",
                limit >> 20
            ),
        )
    };
    if meta.len() > limit {
        return Err(too_large(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    File::open(path)?.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

/// As [`read_mesh`], also returning the line each vertex and face was read from.
pub fn read_mesh_with_lines(path: impl AsRef<Path>) -> Result<(SurfaceMesh, LineMap), ReadError> {
    let path = path.as_ref();
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    let parse = match ext.to_ascii_lowercase().as_str() {
        "obj" => parse_obj_with_lines,
        "off" => parse_off_with_lines,
        _ => return Err(ReadError::UnknownFormat { path: path.into() }),
    };
    let bytes = read_input(path, MAX_INPUT_BYTES).map_err(|source| ReadError::Io {
        path: path.into(),
        source,
    })?;
    parse(&String::from_utf8_lossy(&bytes), path)
}

/// Where in the input we are, for error messages.
#[derive(Clone, Copy)]
struct At<'a> {
    path: &'a Path,
    line: usize,
}

impl At<'_> {
    fn parse(self, message: String) -> ReadError {
        let (path, line) = (self.path.into(), self.line);
        ReadError::Parse {
            path,
            line,
            message,
        }
    }

    fn out_of_range(self, index: i64, vertex_count: usize) -> ReadError {
        let (path, line) = (self.path.into(), self.line);
        ReadError::IndexOutOfRange {
            path,
            line,
            index,
            vertex_count,
        }
    }

    fn texture_out_of_range(self, index: i64, count: usize) -> ReadError {
        let (path, line) = (self.path.into(), self.line);
        ReadError::TexCoordOutOfRange {
            path,
            line,
            index,
            count,
        }
    }

    /// "expected {what}, found '{word}'".
    fn expected(self, what: impl fmt::Display, word: &str) -> ReadError {
        self.parse(format!("expected {what}, found '{}'", snippet(word)))
    }

    fn not_a_triangle(self, corners: usize) -> ReadError {
        let (path, line) = (self.path.into(), self.line);
        ReadError::NotATriangle {
            path,
            line,
            corners,
        }
    }
}

/// Refuses binary data and empty text, before parsing.
fn check_text(text: &str, path: &Path) -> Result<(), ReadError> {
    // Control characters other than tab, line breaks, vertical tab, form feed and a DOS
    // end-of-file mark (0x1a).
    let control = |b: &u8| matches!(b, 0..=8 | 0x0e..=0x19 | 0x1b..=0x1f | 0x7f);
    if let Some(at) = text.bytes().position(|b| control(&b)) {
        let bytes = text.as_bytes();
        return Err(ReadError::Binary {
            path: path.into(),
            line: 1 + bytes[..at].iter().filter(|&&b| b == b'\n').count(),
            byte: bytes[at],
        });
    }
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.trim_ascii().is_empty() {
        return Err(ReadError::Empty { path: path.into() });
    }
    Ok(())
}

fn no_faces(path: &Path, vertices: usize) -> ReadError {
    ReadError::NoFaces {
        path: path.into(),
        vertices,
    }
}

/// Whether `word` is an integer literal (so that failing to parse it means out of range).
fn is_integer(word: &str) -> bool {
    let digits = word.strip_prefix(['+', '-']).unwrap_or(word);
    !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit())
}

/// A token for an error message, shortened so that a garbage line cannot flood the terminal.
fn snippet(token: &str) -> String {
    match token.char_indices().nth(40) {
        Some((end, _)) => format!("{}...", &token[..end]),
        None => token.to_owned(),
    }
}

/// Parses a finite coordinate; `after` says what it follows, for the error message.
fn coordinate(word: &str, after: &str, at: At) -> Result<f64, ReadError> {
    let message = match word.parse::<f64>() {
        Ok(x) if x.is_finite() => return Ok(x),
        Ok(_) => format!("coordinate '{}' after {after} is not finite", snippet(word)),
        Err(_) => return Err(at.expected(format_args!("a number after {after}"), word)),
    };
    Err(at.parse(message))
}

/// Lines without a byte-order mark (which would hide the first keyword).
fn lines(text: &str) -> std::iter::Enumerate<std::str::Lines<'_>> {
    text.strip_prefix('\u{feff}')
        .unwrap_or(text)
        .lines()
        .enumerate()
}

/// The words of a line before any `#` comment (`lines()` has already removed `\n` or `\r\n`).
fn words(line: &str) -> SplitAsciiWhitespace<'_> {
    line.split_once('#')
        .map_or(line, |(before, _)| before)
        .split_ascii_whitespace()
}

/// Parses Wavefront OBJ text. `path` is only used in error messages (it may be empty).
///
/// Reads `v x y [z [w]]` (z = 0 when absent; w and any vertex colour after x y z are ignored)
/// `vt u [v [w]]`, and `f a b c` with corners `v`, `v/vt`, `v/vt/vn` or `v//vn` (normals are
/// ignored). Indices are 1-based; negative ones count back from the last element read so far;
/// positive ones may refer to elements defined later in the file. When every face names a
/// `vt` per corner, [`SurfaceMesh::texcoords`] keeps them. Every other keyword (`vn`, `g`,
/// `o`, `s`, `usemtl`, `mtllib`, `l`, ...) is ignored. Polygons with more than three corners
/// are refused ([`ReadError::NotATriangle`]), not triangulated.
pub fn parse_obj(text: &str, path: impl AsRef<Path>) -> Result<SurfaceMesh, ReadError> {
    let path = path.as_ref();
    parse_obj_with_lines(text, path).map(|(mesh, _)| mesh)
}

/// As [`parse_obj`], also returning the line of each `v` and `f` line (after a byte-order
/// mark, if any; lines end at `\n`, so CRLF files count as they look).
pub fn parse_obj_with_lines(
    text: &str,
    path: impl AsRef<Path>,
) -> Result<(SurfaceMesh, LineMap), ReadError> {
    let path = path.as_ref();
    check_text(text, path)?;
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut faces: Vec<[u32; 3]> = Vec::new();
    let mut map = LineMap::default();
    let mut uv: Vec<[f64; 2]> = Vec::new();
    // Per face, the vt index of each corner, while every face so far has them.
    let mut uv_corners: Option<Vec<[u32; 3]>> = Some(Vec::new());
    // Positive indices past the vertices read so far, as (line, index): checked at the end.
    let mut forward: Vec<(usize, i64)> = Vec::new();
    let mut forward_uv: Vec<(usize, i64)> = Vec::new();
    for (i, line) in lines(text) {
        let at = At { path, line: i + 1 };
        let mut words = words(line);
        match words.next() {
            Some("v") => {
                positions.push(obj_vertex(words, at)?);
                map.vertices.push(encode_line(at.line));
            }
            Some("vt") => uv.push(obj_texcoord(words, at)?),
            Some("f") => {
                let counts = [positions.len(), uv.len()];
                let (face, tex) = obj_face(words, counts, [&mut forward, &mut forward_uv], at)?;
                faces.push(face);
                map.faces.push(encode_line(at.line));
                match (tex, uv_corners.as_mut()) {
                    (Some(t), Some(all)) => all.push(t),
                    _ => uv_corners = None,
                }
            }
            _ => {}
        }
    }
    for (texture, pending, count) in [
        (false, &forward, positions.len()),
        (true, &forward_uv, uv.len()),
    ] {
        if let Some(&(line, index)) = pending.iter().find(|&&(_, i)| i as u64 > count as u64) {
            let at = At { path, line };
            return Err(match texture {
                false => at.out_of_range(index, count),
                true => at.texture_out_of_range(index, count),
            });
        }
    }
    if faces.is_empty() || positions.is_empty() {
        return Err(no_faces(path, positions.len()));
    }
    let texcoords = uv_corners
        .filter(|_| !uv.is_empty())
        .map(|corners| TexCoords { uv, corners });
    let mesh = SurfaceMesh {
        positions,
        faces,
        texcoords,
    };
    Ok((mesh, map))
}

fn obj_texcoord(words: SplitAsciiWhitespace<'_>, at: At) -> Result<[f64; 2], ReadError> {
    let mut t = [0.0; 2];
    let mut count = 0;
    for word in words {
        let x = coordinate(word, "'vt'", at)?;
        if let Some(slot) = t.get_mut(count) {
            *slot = x;
        }
        count += 1;
    }
    match count {
        1..=3 => Ok(t),
        _ => Err(at.parse(format!("'vt' needs 1 to 3 numbers, found {count}"))),
    }
}

fn obj_vertex(words: SplitAsciiWhitespace<'_>, at: At) -> Result<[f64; 3], ReadError> {
    let mut p = [0.0; 3];
    let mut count = 0;
    for word in words {
        let x = coordinate(word, "'v'", at)?;
        if let Some(slot) = p.get_mut(count) {
            *slot = x;
        }
        count += 1;
    }
    match count {
        0 | 1 => Err(at.parse(format!("'v' needs at least 2 coordinates, found {count}"))),
        2..=7 => Ok(p),
        _ => Err(at.parse(format!("'v' has {count} numbers; expected x y [z [w]]"))),
    }
}

/// One face: its vertex indices and, when every corner names one, its `vt` indices.
type ObjFace = ([u32; 3], Option<[u32; 3]>);

fn obj_face(
    words: SplitAsciiWhitespace<'_>,
    counts: [usize; 2],
    forward: [&mut Vec<(usize, i64)>; 2],
    at: At,
) -> Result<ObjFace, ReadError> {
    let [forward_v, forward_t] = forward;
    let mut face = [0u32; 3];
    let mut tex = [0u32; 3];
    let mut all_tex = true;
    let mut corners = 0;
    for word in words {
        if corners < 3 {
            let bad = || at.expected("a vertex index after 'f'", word);
            let mut parts = word.split('/');
            let vertex = parts.next().unwrap_or("");
            let vt = parts.next().unwrap_or("");
            let vn = parts.next().unwrap_or("");
            if parts.next().is_some() || !(vn.is_empty() || vn.parse::<i64>().is_ok()) {
                return Err(bad());
            }
            face[corners] =
                obj_index(false, vertex, counts[0], forward_v, at).map_err(|e| match e {
                    IndexError::Syntax => bad(),
                    IndexError::Read(e) => e,
                })?;
            if vt.is_empty() {
                all_tex = false;
            } else {
                tex[corners] =
                    obj_index(true, vt, counts[1], forward_t, at).map_err(|e| match e {
                        IndexError::Syntax => at.expected("a texture index after '/'", word),
                        IndexError::Read(e) => e,
                    })?;
            }
        }
        corners += 1;
    }
    match corners {
        3 => Ok((face, all_tex.then_some(tex))),
        0..=2 => Err(at.parse(format!("'f' needs 3 corners, found {corners}"))),
        _ => Err(at.not_a_triangle(corners)),
    }
}

enum IndexError {
    Syntax,
    Read(ReadError),
}

/// Resolves one 1-based (or negative, relative) OBJ index of a vertex or a `texture`
/// coordinate against the `count` elements read so far; positive indices beyond them are
/// remembered in `forward` and checked at the end.
fn obj_index(
    texture: bool,
    word: &str,
    count: usize,
    forward: &mut Vec<(usize, i64)>,
    at: At,
) -> Result<u32, IndexError> {
    let what = if texture { "texture" } else { "vertex" };
    let out_of_range = |index| match texture {
        false => at.out_of_range(index, count),
        true => at.texture_out_of_range(index, count),
    };
    let index: i64 = match word.parse() {
        Ok(index) => index,
        Err(_) if is_integer(word) => {
            let message = format!("{what} index {} is out of range", snippet(word));
            return Err(IndexError::Read(at.parse(message)));
        }
        Err(_) => return Err(IndexError::Syntax),
    };
    let read = IndexError::Read;
    let count = i64::try_from(count).unwrap_or(i64::MAX);
    let zero_based = match index {
        0 => {
            return Err(read(
                at.parse(format!("{what} index 0 is invalid (OBJ counts from 1)")),
            ))
        }
        i if i > count => {
            forward.push((at.line, i));
            i - 1
        }
        i if i > 0 => i - 1,
        i if i + count >= 0 => i + count,
        i => return Err(read(out_of_range(i))),
    };
    u32::try_from(zero_based).map_err(|_| read(out_of_range(index)))
}

/// The words of OFF text with `#` comments removed, keeping track of the line number.
struct Tokens<'t, 'p> {
    path: &'p Path,
    lines: std::iter::Enumerate<std::str::Lines<'t>>,
    words: SplitAsciiWhitespace<'t>,
    line: usize,
}

impl<'t, 'p> Tokens<'t, 'p> {
    fn next(&mut self) -> Option<&'t str> {
        loop {
            if let Some(word) = self.words.next() {
                return Some(word);
            }
            let (i, line) = self.lines.next()?;
            self.line = i + 1;
            self.words = words(line);
        }
    }

    fn at(&self) -> At<'p> {
        At {
            path: self.path,
            line: self.line,
        }
    }

    /// Parses the next word as the `what` that is expected there.
    fn parse<T: std::str::FromStr>(
        &mut self,
        what: fmt::Arguments,
    ) -> Result<(T, At<'p>), ReadError> {
        let word = self.next();
        let at = self.at();
        let Some(word) = word else {
            return Err(at.parse(format!("unexpected end of file: expected {what}")));
        };
        match word.parse() {
            Ok(value) => Ok((value, at)),
            Err(_) if is_integer(word) => {
                Err(at.parse(format!("{what} is out of range: {}", snippet(word))))
            }
            Err(_) => Err(at.expected(what, word)),
        }
    }

    /// Drops what is left of the current line (an edge count, colours, normals, ...).
    fn skip_rest_of_line(&mut self) {
        self.words = "".split_ascii_whitespace();
    }
}

/// Parses OFF text. `path` is only used in error messages (it may be empty).
///
/// Accepts an optional `OFF` header (also `COFF`, `NOFF`, `STOFF`, ...), `#` comments, and the
/// counts `nv nf [ne]` on the header line or after it. Then come `nv` vertices `x y z` and `nf`
/// faces `3 i j k` with 0-based indices. A record may continue over several lines; whatever
/// follows its last value on the same line (edge count, colours, normals) is ignored, so one
/// line must not hold several records.
pub fn parse_off(text: &str, path: impl AsRef<Path>) -> Result<SurfaceMesh, ReadError> {
    let path = path.as_ref();
    parse_off_with_lines(text, path).map(|(mesh, _)| mesh)
}

/// As [`parse_off`], also returning the line each vertex and face record starts on.
pub fn parse_off_with_lines(
    text: &str,
    path: impl AsRef<Path>,
) -> Result<(SurfaceMesh, LineMap), ReadError> {
    let path = path.as_ref();
    check_text(text, path)?;
    let (lines, words) = (lines(text), "".split_ascii_whitespace());
    let mut t = Tokens {
        path,
        lines,
        words,
        line: 1,
    };
    let Some(first) = t.next() else {
        return Err(no_faces(path, 0)); // only comments
    };
    let nv: usize = match first.strip_suffix("OFF") {
        Some(p) if p.bytes().all(|b| b"STCN".contains(&b)) => {
            t.parse(format_args!("the vertex count"))?.0
        }
        _ => first
            .parse()
            .map_err(|_| t.at().expected("'OFF' or the vertex count", first))?,
    };
    let (nf, _): (usize, _) = t.parse(format_args!("the face count"))?;
    t.skip_rest_of_line();
    if nf == 0 {
        return Err(no_faces(path, nv));
    }
    // Capped, so that a bogus count cannot reserve absurd amounts of memory.
    let mut positions = Vec::with_capacity(nv.min(text.len() / 6));
    let mut map = LineMap {
        vertices: Vec::with_capacity(positions.capacity()),
        faces: Vec::new(),
    };
    for v in 0..nv {
        let mut p = [0.0; 3];
        for (i, x) in p.iter_mut().enumerate() {
            let (value, at): (f64, _) =
                t.parse(format_args!("a coordinate of vertex {v} (0-based)"))?;
            if !value.is_finite() {
                let message = format!("a coordinate of vertex {v} (0-based) is not finite");
                return Err(at.parse(message));
            }
            if i == 0 {
                map.vertices.push(encode_line(at.line));
            }
            *x = value;
        }
        t.skip_rest_of_line();
        positions.push(p);
    }
    let mut faces = Vec::with_capacity(nf.min(text.len() / 8));
    map.faces.reserve(faces.capacity());
    for f in 0..nf {
        let start = match t.parse(format_args!("the corner count of face {f} (0-based)"))? {
            (3, at) => at,
            (k @ 0..=2, at) => {
                let message = format!("face {f} (0-based) has {k} corners; need 3");
                return Err(at.parse(message));
            }
            (k, at) => return Err(at.not_a_triangle(k)),
        };
        let mut face = [0u32; 3];
        for corner in &mut face {
            let (index, at): (i64, _) =
                t.parse(format_args!("a vertex index of face {f} (0-based)"))?;
            let valid = usize::try_from(index).ok().filter(|&i| i < nv);
            let valid = valid.and_then(|i| u32::try_from(i).ok());
            *corner = valid.ok_or_else(|| at.out_of_range(index, nv))?;
        }
        t.skip_rest_of_line();
        faces.push(face);
        map.faces.push(encode_line(start.line));
    }
    let mesh = SurfaceMesh {
        positions,
        faces,
        texcoords: None,
    };
    Ok((mesh, map))
}

/// Writes a planar mesh as OBJ: optional `# comment` header lines, then `v x y 0` per vertex
/// (shortest text that reads back bit-identically), then `f a b c` (1-based).
///
/// Atomic: writes a temporary file in the same directory (`.NAME.tmp-PID-N`), syncs it, then
/// renames it over the destination. On any error the temporary file is removed and the
/// destination is untouched. The new file gets default permissions, not those of a file it
/// replaces. Data that [`format_obj_2d`] refuses is an error too.
pub fn write_obj_2d(
    path: impl AsRef<Path>,
    positions: &[[f64; 2]],
    faces: &[[u32; 3]],
    header: &[&str],
) -> Result<(), WriteError> {
    let path = path.as_ref();
    write_obj_2d_textured(path, positions, faces, None, header)
}

/// As [`write_obj_2d`], with texture coordinates: the `vt` lines, and faces as
/// `f a/ta b/tb c/tc` with the corners' texture indices (see [`format_obj_2d_textured`]).
pub fn write_obj_2d_textured(
    path: impl AsRef<Path>,
    positions: &[[f64; 2]],
    faces: &[[u32; 3]],
    texcoords: Option<&TexCoords>,
    header: &[&str],
) -> Result<(), WriteError> {
    let path = path.as_ref();
    write_atomic(path, |file| {
        format_obj_2d_textured(file, positions, faces, texcoords, header)
    })
}

/// Writes a surface mesh as OBJ: `v x y z` per vertex (shortest text that reads back
/// bit-identically), then `f a b c` (1-based). Atomic, and refused before writing anything
/// for a coordinate that is not finite or a face that names a missing vertex, as
/// [`write_obj_2d`].
///
/// ```
/// let dir = std::env::temp_dir().join(format!("bdmorph-doc-obj3d-{}", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// let path = dir.join("tri.obj");
/// bdmorph::io::write_obj_3d(&path, &[[0.0, 0.0, 1.5], [1.0, 0.0, 0.0], [0.0, 1.0, 0.1]], &[[0, 1, 2]])?;
/// let back = bdmorph::io::read_mesh(&path)?;
/// assert_eq!(back.positions[2], [0.0, 1.0, 0.1]);
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_obj_3d(
    path: impl AsRef<Path>,
    positions: &[[f64; 3]],
    faces: &[[u32; 3]],
) -> Result<(), WriteError> {
    let path = path.as_ref();
    write_atomic(path, |file| format_obj_3d(file, positions, faces))
}

/// Same as [`write_obj_3d`] but into any writer, without atomicity.
pub fn format_obj_3d<W: Write>(
    out: W,
    positions: &[[f64; 3]],
    faces: &[[u32; 3]],
) -> io::Result<()> {
    let invalid = |message| Err(io::Error::new(io::ErrorKind::InvalidInput, message));
    let n = positions.len();
    if let Some(i) = positions
        .iter()
        .position(|p| !p.iter().all(|x| x.is_finite()))
    {
        return invalid(format!("vertex {i} is not finite: {:?}", positions[i]));
    }
    if let Some(i) = faces
        .iter()
        .position(|f| f.iter().any(|&v| v as usize >= n))
    {
        return invalid(format!("face {i} {:?} needs a vertex beyond {n}", faces[i]));
    }
    let mut out = BufWriter::new(out);
    for p in positions {
        out.write_all(b"v")?;
        for &x in p {
            out.write_all(b" ")?;
            write_coordinate(&mut out, x)?;
        }
        out.write_all(b"\n")?;
    }
    for face in faces {
        let [a, b, c] = face.map(|v| u64::from(v) + 1);
        writeln!(out, "f {a} {b} {c}")?;
    }
    out.flush()
}

/// Writes `bytes` to `path` atomically (temporary file in the same directory, sync, rename):
/// on any error the destination is untouched and the temporary file removed.
pub fn write_bytes_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<(), WriteError> {
    let path = path.as_ref();
    write_atomic(path, |file| file.write_all(bytes))
}

/// Runs `fill` on a fresh temporary file next to `path`, then renames it over `path`.
fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut File) -> io::Result<()>,
) -> Result<(), WriteError> {
    static COUNTER: AtomicU32 = AtomicU32::new(0);
    let error = |source| WriteError::Io {
        path: path.into(),
        source,
    };
    let no_name = || io::Error::new(io::ErrorKind::InvalidInput, "the path has no file name");
    let name = path.file_name().ok_or_else(|| error(no_name()))?;
    // Only a regular file is replaced: never a device, pipe, socket, folder or link (the
    // rename would put a new file in its place).
    if let Ok(meta) = fs::symlink_metadata(path) {
        if !meta.file_type().is_file() {
            return Err(error(io::Error::new(
                io::ErrorKind::InvalidInput,
                "not a regular file (a device, pipe, socket, folder or link): it is not replaced",
            )));
        }
    }
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let mut temp = std::ffi::OsString::from(".");
    temp.push(name);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    temp.push(format!(".tmp-{}-{n}", std::process::id()));
    let temp = dir.join(temp);
    let mut file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&temp)
        .map_err(error)?;
    let written = fill(&mut file).and_then(|()| file.sync_all());
    drop(file); // closed before the rename, which some platforms require
    if let Err(source) = written.and_then(|()| fs::rename(&temp, path)) {
        let _ = fs::remove_file(&temp); // best effort: the first error is the one to report
        return Err(error(source));
    }
    #[cfg(unix)] // best effort: make the rename itself durable
    if let Ok(dir) = File::open(dir) {
        let _ = dir.sync_all();
    }
    Ok(())
}

/// Same as [`write_obj_2d`] but into any writer, without atomicity (output is buffered here).
///
/// Each header string becomes one `# ...` comment line per line it contains. Coordinates are
/// written in the shortest form that parses back to the same bits (`{}`, or `{:e}` for very
/// small or large magnitudes). Fails with [`io::ErrorKind::InvalidInput`], before writing
/// anything, if a coordinate is not finite or a face refers to a missing vertex.
pub fn format_obj_2d<W: Write>(
    out: W,
    positions: &[[f64; 2]],
    faces: &[[u32; 3]],
    header: &[&str],
) -> io::Result<()> {
    format_obj_2d_textured(out, positions, faces, None, header)
}

/// As [`format_obj_2d`], with optional texture coordinates: `vt u v` lines after the
/// vertices, and each face as `f a/ta b/tb c/tc`. Fails with [`io::ErrorKind::InvalidInput`]
/// before writing anything if the texture corners do not match the faces.
pub fn format_obj_2d_textured<W: Write>(
    out: W,
    positions: &[[f64; 2]],
    faces: &[[u32; 3]],
    texcoords: Option<&TexCoords>,
    header: &[&str],
) -> io::Result<()> {
    let invalid = |message| Err(io::Error::new(io::ErrorKind::InvalidInput, message));
    let n = positions.len();
    if let Some(i) = positions
        .iter()
        .position(|p| !p.iter().all(|x| x.is_finite()))
    {
        return invalid(format!("vertex {i} is not finite: {:?}", positions[i]));
    }
    if let Some(i) = faces
        .iter()
        .position(|f| f.iter().any(|&v| v as usize >= n))
    {
        return invalid(format!("face {i} {:?} needs a vertex beyond {n}", faces[i]));
    }
    if let Some(t) = texcoords {
        let nt = t.uv.len();
        if t.corners.len() != faces.len()
            || t.corners.iter().flatten().any(|&i| i as usize >= nt)
            || !t.uv.iter().flatten().all(|x| x.is_finite())
        {
            return invalid("texture coordinates do not match the faces".to_owned());
        }
    }
    let mut out = BufWriter::new(out);
    for text in header {
        if text.is_empty() {
            out.write_all(b"#\n")?;
        }
        for line in text.lines() {
            let gap = if line.is_empty() { "" } else { " " };
            writeln!(out, "#{gap}{line}")?;
        }
    }
    for &[x, y] in positions {
        out.write_all(b"v ")?;
        write_coordinate(&mut out, x)?;
        out.write_all(b" ")?;
        write_coordinate(&mut out, y)?;
        out.write_all(b" 0\n")?;
    }
    match texcoords {
        None => {
            for face in faces {
                let [a, b, c] = face.map(|v| u64::from(v) + 1);
                writeln!(out, "f {a} {b} {c}")?;
            }
        }
        Some(t) => {
            for &[u, v] in &t.uv {
                out.write_all(b"vt ")?;
                write_coordinate(&mut out, u)?;
                out.write_all(b" ")?;
                write_coordinate(&mut out, v)?;
                out.write_all(b"\n")?;
            }
            for (face, tex) in faces.iter().zip(&t.corners) {
                let [a, b, c] = face.map(|v| u64::from(v) + 1);
                let [ta, tb, tc] = tex.map(|v| u64::from(v) + 1);
                writeln!(out, "f {a}/{ta} {b}/{tb} {c}/{tc}")?;
            }
        }
    }
    out.flush()
}

/// Both `{}` and `{:e}` print the shortest digits that round-trip; `{:e}` is far shorter for
/// tiny values such as `1e-17` or huge ones such as `f64::MAX`.
fn write_coordinate(out: &mut impl Write, x: f64) -> io::Result<()> {
    if x == 0.0 || (1e-5..1e16).contains(&x.abs()) {
        write!(out, "{x}")
    } else {
        write!(out, "{x:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obj(text: &str) -> Result<SurfaceMesh, ReadError> {
        parse_obj(text, Path::new("t.obj"))
    }

    fn off(text: &str) -> Result<SurfaceMesh, ReadError> {
        parse_off(text, Path::new("t.off"))
    }

    /// The error message, which names the file and the line.
    fn fails(result: Result<SurfaceMesh, ReadError>) -> String {
        result.unwrap_err().to_string()
    }

    /// The error's variant and fields.
    fn debug(result: Result<SurfaceMesh, ReadError>) -> String {
        format!("{:?}", result.unwrap_err())
    }

    /// A fresh, empty directory for one test.
    fn scratch_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("bdmorph-io-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let names = fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name());
        let mut names: Vec<String> = names.map(|n| n.to_string_lossy().into_owned()).collect();
        names.sort();
        names
    }

    #[test]
    fn obj_variants_from_the_wild() {
        let text = "# exported\r\n#vertices: 5\r\n\r\nmtllib missing.mtl\r\ng body\r\n\
                    v 1.234500e+02 -0 \r\nv +1 2 3   # trailing comment\r\nv 0 1 2 0.5\r\n\
                    v 1E-3 .5 -7.\r\nv 4 5 6\r\nvt 0.5 0.5\r\nvn 0 0 1\r\nusemtl skin\r\ns off\r\n\
                    f 1/1 2/1 3/1\r\nf 2//1 3//1 4//1\r\nf 3/1/1 4/1/1 5/1/1\r\nf -1 -2 -5\r\n\
                    o other\r\nl 1 2\r\np 3\r\nvp 0.5\r\nf 1 2 5";
        let mesh = obj(text).unwrap();
        let [a, b, c, d, _] = mesh.positions[..] else {
            panic!("{mesh:?}")
        };
        assert_eq!([a, b], [[123.45, -0.0, 0.0], [1.0, 2.0, 3.0]]);
        assert_eq!([c, d], [[0.0, 1.0, 2.0], [0.001, 0.5, -7.0]]);
        assert!(a[1].is_sign_negative());
        assert_eq!(
            mesh.faces,
            [[0, 1, 2], [1, 2, 3], [2, 3, 4], [4, 3, 0], [0, 1, 4]]
        );
        assert!(!mesh.is_planar());
        // Two coordinates give z = 0; a positive index may point at a later vertex.
        let mesh = obj("f 1 2 3\nv 0 0\nv 1 0\nv 0 1\n").unwrap();
        assert_eq!(
            (mesh.positions[2], mesh.faces[0]),
            ([0.0, 1.0, 0.0], [0, 1, 2])
        );
        assert!(mesh.is_planar());
    }

    #[test]
    fn obj_errors_name_the_file_and_line() {
        let tri = "v 0 0\nv 1 0\nv 0 1\n"; // so the lines below start at 4
        #[rustfmt::skip]
        let cases = [
            ("v 1 abc\n", "t.obj:4: expected a number after 'v', found 'abc'"),
            ("\r\nv 1 inf 0\r\n", "t.obj:5: coordinate 'inf' after 'v' is not finite"),
            ("v 1 2 NaN\n", "t.obj:4: coordinate 'NaN' after 'v' is not finite"),
            ("v 1 1e999\n", "t.obj:4: coordinate '1e999' after 'v' is not finite"),
            ("v 1\n", "t.obj:4: 'v' needs at least 2 coordinates, found 1"),
            ("v 1 2 3 4 5 6 7 8\n", "t.obj:4: 'v' has 8 numbers; expected x y [z [w]]"),
            ("f 1 2\n", "t.obj:4: 'f' needs 3 corners, found 2"),
            ("f 0 1 2\n", "t.obj:4: vertex index 0 is invalid (OBJ counts from 1)"),
            ("f 1 2 x\n", "t.obj:4: expected a vertex index after 'f', found 'x'"),
            ("f 1/a 2 3\n", "t.obj:4: expected a texture index after '/', found '1/a'"),
            ("f 1/1/1/1 2 3\n", "t.obj:4: expected a vertex index after 'f', found '1/1/1/1'"),
            ("f 1.5 2 3\n", "t.obj:4: expected a vertex index after 'f', found '1.5'"),
            ("f -1 -2 -4\nv 1 1\n", "t.obj:4: vertex -4 does not exist (3 vertices)"),
            ("f 1 2 3\nf 1 2 5\nv 1 1\n# end", "t.obj:5: vertex 5 does not exist (4 vertices)"),
            ("v 1 1\nf 1 2 4 3\n", "t.obj:5: face has 4 corners; only triangles are supported"),
            ("# no faces\n", "t.obj: the mesh has 3 vertices but no faces"),
            ("f 1 2 99999999999999999999\n", "t.obj:4: vertex index 99999999999999999999 is out of range"),
            ("f 1 2/-99999999999999999999 3\n", "t.obj:4: texture index -99999999999999999999 is out of range"),
            ("v 1 1\0\n", "t.obj:4: binary data (byte 0x00), not a text mesh file"),
        ];
        for (body, expected) in cases {
            assert_eq!(fails(obj(&format!("{tri}{body}"))), expected);
        }
        let far = debug(obj(&format!("{tri}f 1 2 3\nf 3 2 -9")));
        assert_eq!(
            far,
            r#"IndexOutOfRange { path: "t.obj", line: 5, index: -9, vertex_count: 3 }"#
        );
        let quad = debug(obj(&format!("{tri}v 1 1\nf 1 2 4 3")));
        assert_eq!(
            quad,
            r#"NotATriangle { path: "t.obj", line: 5, corners: 4 }"#
        );
        assert!(debug(obj("v 1 x")).starts_with(r#"Parse { path: "t.obj", line: 1, "#));
        assert_eq!(debug(obj("")), r#"Empty { path: "t.obj" }"#);
        assert_eq!(fails(obj(" \r\n\t\n")), "t.obj: the file is empty");
        let comments = fails(obj("# nothing\ng group\n"));
        assert_eq!(comments, "t.obj: the mesh has no vertices and no faces");
        assert_eq!(
            fails(obj("v 0 0\n")),
            "t.obj: the mesh has 1 vertex but no faces"
        );
        // Latin-1 in a comment and a DOS end-of-file mark are text; other controls are not.
        let latin1 = String::from_utf8_lossy(b"# caf\xe9\nv 0 0\nv 1 0\nv 0 1\nf 1 2 3\n\x1a");
        assert!(obj(&latin1).is_ok());
        let binary = debug(obj("\u{feff}# ok\r\n\x7fELF"));
        assert_eq!(binary, r#"Binary { path: "t.obj", line: 2, byte: 127 }"#);
        let unnamed = fails(parse_obj("v 1 abc", Path::new("")));
        assert_eq!(
            unnamed,
            "<string>:1: expected a number after 'v', found 'abc'"
        );
        let long = fails(obj(&format!("v 1 {}", "x".repeat(10_000))));
        assert!(long.len() < 100 && long.ends_with("xxx...'"), "{long}");
    }

    #[test]
    fn off_counts_on_header_line_comments_and_loose_layout() {
        let mesh = off("OFF 4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n").unwrap();
        assert_eq!(mesh.positions[2], [1.0, 1.0, 0.0]);
        assert_eq!(mesh.faces, vec![[0, 1, 2], [0, 2, 3]]);
        assert!(mesh.is_planar());
        let commented = "# made by hand\r\nOFF # header\r\n\r\n# counts next\r\n4 2 4\r\n\
                         0 0 0 # first\r\n1 0 0 \r\n1 1 0\r\n# between vertices\r\n0 1 0\r\n\
                         3 0 1 2 255 0 0\r\n3 0 2 3 0.1 0.2 0.3 1\r\n";
        assert_eq!(off(commented).unwrap(), mesh);
        // No keyword, a BOM, colours after coordinates, records split over lines.
        let loose = "\u{feff}4 2\n0 0\n0 0.5 0.5 0.5\n1 0 0\n1 1 0\n0 1 0\n3\n0 1 2\n3 0 2\n3\n";
        assert_eq!(off(loose).unwrap(), mesh);
        let coff = "COFF\n3 1 0\n0 0 1 255 0 0 255\n1 0 1 0 255 0 255\n0 1 1 0 0 255 9\n3 2 1 0";
        assert_eq!(off(coff).unwrap().faces, vec![[2, 1, 0]]);
    }

    /// The line map names each `v` and `f` line (OBJ) or the line each record starts on
    /// (OFF), through a byte-order mark, CRLF, comments, other keywords and blank lines.
    #[test]
    fn line_maps_name_each_vertex_and_face_line() {
        let text = "\u{feff}# header\r\nv 0 0\r\ng part\r\nv 1 0 # x\r\n\r\nf 1 2 3\r\nvt 0 0\r\n\
                    v 0 1\r\nf 3 2 -1\r\n";
        let (mesh, lines) = parse_obj_with_lines(text, Path::new("t.obj")).unwrap();
        assert_eq!(mesh, obj(text).unwrap());
        let vertices: Vec<_> = (0..4).map(|v| lines.vertex_line(v)).collect();
        assert_eq!(vertices, [Some(2), Some(4), Some(8), None]);
        let faces: Vec<_> = (0..3).map(|f| lines.face_line(f)).collect();
        assert_eq!(faces, [Some(6), Some(9), None]);
        // OFF: a record's first line, also when it continues on the next one.
        let text = "OFF\n# counts\n3 2 0\n0 0 0\n1\n0 0\n\n0 1 0\n3 0 1 2\n3\n2 1 0\n";
        let (mesh, lines) = parse_off_with_lines(text, Path::new("t.off")).unwrap();
        assert_eq!(mesh, off(text).unwrap());
        let vertices: Vec<_> = (0..3).map(|v| lines.vertex_line(v)).collect();
        assert_eq!(vertices, [Some(4), Some(5), Some(8)]);
        assert_eq!(
            [lines.face_line(0), lines.face_line(1)],
            [Some(9), Some(10)]
        );
        // Built by hand: 0 and lines beyond u32 are unknown.
        let far = usize::try_from(1u64 << 32).unwrap_or(0);
        let lines = LineMap::new(&[3, 0], &[far, 7]);
        assert_eq!(
            [lines.vertex_line(0), lines.vertex_line(1)],
            [Some(3), None]
        );
        assert_eq!([lines.face_line(0), lines.face_line(1)], [None, Some(7)]);
        assert_eq!(LineMap::default().face_line(0), None);
    }

    #[test]
    fn off_errors_name_the_file_and_line() {
        let head = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n"; // so faces start at line 6
        #[rustfmt::skip]
        let cases = [
            ("4 0 1 2 0\n", "t.off:6: face has 4 corners; only triangles are supported"),
            ("# c\n3 0 1\n3\n", "t.off:8: vertex 3 does not exist (3 vertices)"),
            ("3 0 -1 2\n", "t.off:6: vertex -1 does not exist (3 vertices)"),
            ("2 0 1\n", "t.off:6: face 0 (0-based) has 2 corners; need 3"),
            ("3 0 1", "t.off:6: unexpected end of file: expected a vertex index of face 0 (0-based)"),
            ("x 0 1 2", "t.off:6: expected the corner count of face 0 (0-based), found 'x'"),
            ("3 0 1 y", "t.off:6: expected a vertex index of face 0 (0-based), found 'y'"),
            ("3 0 1 -9223372036854775809", "t.off:6: a vertex index of face 0 (0-based) is out of range: -9223372036854775809"),
        ];
        for (body, expected) in cases {
            assert_eq!(fails(off(&format!("{head}{body}"))), expected);
        }
        #[rustfmt::skip]
        let cases = [
            ("OFF\n3 1 0\n0 0 0\n1 x 0\n", "t.off:4: expected a coordinate of vertex 1 (0-based), found 'x'"),
            ("OFF\n3 1 0\n0 0 0\n1 0 0", "t.off:4: unexpected end of file: expected a coordinate of vertex 2 (0-based)"),
            ("OFF\n3 1 0\n0 0 0\n1 inf 0\n", "t.off:4: a coordinate of vertex 1 (0-based) is not finite"),
            ("PLY\n3 1 0\n", "t.off:1: expected 'OFF' or the vertex count, found 'PLY'"),
            ("\n\nOFF\nthree 1 0\n", "t.off:4: expected the vertex count, found 'three'"),
            ("OFF 3", "t.off:1: unexpected end of file: expected the face count"),
            ("OFF\n0 0 0\n", "t.off: the mesh has no vertices and no faces"),
            ("OFF\n3 0 0\n", "t.off: the mesh has 3 vertices but no faces"),
            ("# only a comment\n", "t.off: the mesh has no vertices and no faces"),
            ("\n \n", "t.off: the file is empty"),
            ("OFF\n3 1\n0 0 0\n\0", "t.off:4: binary data (byte 0x00), not a text mesh file"),
            ("OFF\n-3 1 0\n", "t.off:2: the vertex count is out of range: -3"),
            ("OFF 99999999999999999999 1", "t.off:1: the vertex count is out of range: 99999999999999999999"),
            ("OFF\n0 1 0\n3 0 1 2\n", "t.off:3: vertex 0 does not exist (0 vertices)"),
        ];
        for (text, expected) in cases {
            assert_eq!(fails(off(text)), expected);
        }
        let quad = debug(off(&format!("{head}\n4 0 1 2 0")));
        assert_eq!(
            quad,
            r#"NotATriangle { path: "t.off", line: 7, corners: 4 }"#
        );
        let far = debug(off(&format!("{head}3 0 1 3")));
        assert_eq!(
            far,
            r#"IndexOutOfRange { path: "t.off", line: 6, index: 3, vertex_count: 3 }"#
        );
    }

    #[test]
    fn read_mesh_dispatches_on_extension() {
        let dir = scratch_dir("read");
        let upper = dir.join("TRI.OBJ");
        fs::write(&upper, "v 0 0\nv 1 0\nv 0 1\nf 1 2 3\n").unwrap();
        let off_file = dir.join("tri.Off");
        fs::write(&off_file, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
        assert_eq!(read_mesh(&upper).unwrap().faces, vec![[0, 1, 2]]);
        assert_eq!(read_mesh(&off_file).unwrap(), read_mesh(&upper).unwrap());
        for name in ["tri.stl", "noext", "obj"] {
            let message = format!("{}: unknown mesh format (expected .obj or .off)", name);
            assert!(
                fails(read_mesh(dir.join(name))).ends_with(&message),
                "{name}"
            );
        }
        let missing = dir.join("missing.obj");
        let err = read_mesh(&missing).unwrap_err();
        assert!(matches!(err, ReadError::Io { .. }));
        let expected = format!("{}: cannot read: ", missing.display());
        assert!(err.to_string().starts_with(&expected), "{err}");
        assert!(std::error::Error::source(&err).is_some());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn format_then_parse_round_trips_bit_for_bit() {
        let positions = vec![
            [0.1 + 0.2, -0.0],
            [std::f64::consts::PI, -1e-17],
            [5e-324, f64::MAX],
            [-f64::MIN_POSITIVE, 1e15 + 0.5],
            [1.0 / 3.0, -2.5e-5],
            [1.0, 0.0],
        ];
        let faces = vec![[0, 1, 2], [2, 3, 4], [5, 4, 0]];
        let mut out = Vec::new();
        let header = ["by a test", "", "two\nlines"];
        format_obj_2d(&mut out, &positions, &faces, &header).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.starts_with("# by a test\n#\n# two\n# lines\nv 0.30000000000000004 -0 0\n"));
        assert!(
            text.contains("\nv 5e-324 1.7976931348623157e308 0\n"),
            "{text}"
        );
        assert!(
            text.ends_with("\nv 1 0 0\nf 1 2 3\nf 3 4 5\nf 6 5 1\n"),
            "{text}"
        );
        let mesh = parse_obj(&text, Path::new("")).unwrap();
        assert!(mesh.is_planar());
        assert_eq!(mesh.faces, faces);
        let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        for (read, written) in mesh.positions.iter().zip(&positions) {
            assert_eq!(bits(&read[..2]), bits(written));
        }
        let not_finite: (&[[f64; 2]], &[[u32; 3]]) = (&[[f64::NAN, 0.0]], &[]);
        for (p, f) in [not_finite, (&positions, &[[0, 1, 6]])] {
            let mut out = Vec::new();
            let err = format_obj_2d(&mut out, p, f, &[]).unwrap_err();
            assert_eq!((err.kind(), out.len()), (io::ErrorKind::InvalidInput, 0));
        }
    }

    #[test]
    fn write_obj_2d_replaces_atomically_and_cleans_up() {
        let dir = scratch_dir("write");
        let path = dir.join("out.obj");
        let tri = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        write_obj_2d(&path, &tri, &[[0, 1, 2]], &["first"]).unwrap();
        let square = [[0.0, 0.0], [2.0, 0.0], [0.0, 2.0], [2.0, 2.0]];
        write_obj_2d(&path, &square, &[[0, 1, 2], [1, 3, 2]], &[]).unwrap();
        let mesh = read_mesh(&path).unwrap();
        assert_eq!((mesh.positions.len(), mesh.faces.len()), (4, 2));
        assert_eq!(entries(&dir), ["out.obj"]);
        // Failing once the temporary file exists: destination untouched, nothing left over.
        let before = fs::read(&path).unwrap();
        let err = write_obj_2d(&path, &[[f64::INFINITY, 0.0]], &[], &[]).unwrap_err();
        let expected = format!("{}: cannot write: vertex 0 is not finite", path.display());
        assert!(err.to_string().starts_with(&expected), "{err}");
        assert_eq!(fs::read(&path).unwrap(), before);
        assert_eq!(entries(&dir), ["out.obj"]);
        // A directory that does not exist: an error, and nothing is created anywhere.
        let nowhere = dir.join("no/such/dir/out.obj");
        let WriteError::Io { source, .. } = write_obj_2d(&nowhere, &tri, &[], &[]).unwrap_err();
        assert_eq!(source.kind(), io::ErrorKind::NotFound);
        assert_eq!(entries(&dir), ["out.obj"]);
        // The destination is a non-empty directory: the rename fails, the temporary file goes.
        let sub = dir.join("sub.obj");
        fs::create_dir(&sub).unwrap();
        fs::write(sub.join("keep"), "x").unwrap();
        assert!(write_obj_2d(&sub, &tri, &[[0, 1, 2]], &[]).is_err());
        assert_eq!(entries(&dir), ["out.obj", "sub.obj"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    /// tobj re-indexes vertices per `v/vt/vn` combination, so triangle corners are compared by
    /// position, in order.
    #[test]
    fn texture_coordinates_are_read_per_corner_and_written_back() {
        let text = "v 0 0\nv 1 0\nv 0 1\nv 1 1\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1 0\n\
                    f 1/1 2/2 3/3\nf 2/2/1 4/-1 3/3\n";
        let m = parse_obj(text, Path::new("t.obj")).unwrap();
        let t = m.texcoords.clone().expect("texture coordinates");
        assert_eq!(t.uv.len(), 4);
        assert_eq!(t.corners, vec![[0, 1, 2], [1, 3, 2]]);
        assert_eq!(t.corner_uv()[1], [[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        let planar: Vec<[f64; 2]> = m.positions.iter().map(|p| [p[0], p[1]]).collect();
        let mut out = Vec::new();
        format_obj_2d_textured(&mut out, &planar, &m.faces, Some(&t), &[]).unwrap();
        let written = String::from_utf8(out).unwrap();
        assert!(written.contains("f 2/2 4/4 3/3"), "{written}");
        let back = parse_obj(&written, Path::new("w.obj")).unwrap();
        assert_eq!(back.texcoords, Some(t));
        // A face without vt drops texture coordinates for the whole mesh.
        let partial = "v 0 0\nv 1 0\nv 0 1\nvt 0 0\nf 1/1 2/1 3/1\nf 1 2 3\n";
        assert_eq!(
            parse_obj(partial, Path::new("p.obj")).unwrap().texcoords,
            None
        );
        // A texture index out of range names its line.
        let bad = "v 0 0\nv 1 0\nv 0 1\nvt 0 0\nf 1/1 2/9 3/1\n";
        let err = parse_obj(bad, Path::new("b.obj")).unwrap_err().to_string();
        assert_eq!(
            err,
            "b.obj:5: texture coordinate 9 does not exist (1 'vt' lines)"
        );
        let bad = "v 0 0\nv 1 0\nv 0 1\nvt 0 0\nf 1/1 2/-2 3/1\n";
        let err = parse_obj(bad, Path::new("b.obj")).unwrap_err().to_string();
        assert_eq!(
            err,
            "b.obj:5: texture coordinate -2 does not exist (1 'vt' lines)"
        );
    }

    #[test]
    fn write_bytes_atomic_writes_and_replaces() {
        let dir = std::env::temp_dir().join(format!("bdmorph-io-bytes-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("x.bin");
        write_bytes_atomic(&path, b"one").unwrap();
        write_bytes_atomic(&path, b"two").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"two");
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        assert!(write_bytes_atomic(dir.join("missing/x.bin"), b"x").is_err());
        // What is not a regular file is never replaced.
        #[cfg(unix)]
        {
            let link = dir.join("link.bin");
            std::os::unix::fs::symlink(&path, &link).unwrap();
            let err = write_bytes_atomic(&link, b"three").unwrap_err().to_string();
            assert!(err.contains("not a regular file"), "{err}");
            assert!(fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink());
            assert_eq!(fs::read(&path).unwrap(), b"two");
        }
        let folder = dir.join("folder");
        fs::create_dir(&folder).unwrap();
        assert!(write_bytes_atomic(&folder, b"x").is_err());
        assert!(folder.is_dir());
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn agrees_with_tobj() {
        let texts = [
            "v 0 0 0\nv 1 0 0.5\nv 0 1 -0.25\nv 1 1 1e-3\nvt 0 0\nvt 1 0\nvt 0 1\n\
             f 1/1 2/2 3/3\nf 2/2 4/1 3/3\n",
            "v 0.5 0.25 1\nv -1 0 2\nv 3 3 3\nv 4 4.5 4\nvn 0 0 1\n\
             f 1//1 2//1 3//1\nf 3//1 2//1 4//1\nf -1//1 -2//1 -3//1\n",
            "# corner\r\nv 1.5e+00 2 3\r\nv 4 5 6\r\nv 7 8 9.25\r\nvt 0 0\r\nvn 1 0 0\r\n\
             g part\r\nusemtl none\r\nf 1/1/1 2/1/1 3/1/1\r\ng other\r\nf 3/1/1 1/1/1 2/1/1\r\n",
        ];
        let mut options = tobj::LoadOptions::default();
        (options.triangulate, options.single_index) = (false, false);
        for text in texts {
            let mesh = obj(text).unwrap();
            let corners = mesh
                .faces
                .iter()
                .flatten()
                .map(|&v| mesh.positions[v as usize]);
            let ours: Vec<f64> = corners.flatten().collect();
            let loaded = tobj::load_obj_buf(&mut text.as_bytes(), &options, |_| Ok(<_>::default()));
            let mut theirs = Vec::new();
            for model in loaded.unwrap().0 {
                for &i in &model.mesh.indices {
                    let corner = &model.mesh.positions[i as usize * 3..][..3];
                    theirs.extend(corner.iter().map(|&x| f64::from(x)));
                }
            }
            assert_eq!(theirs.len(), ours.len(), "{text}");
            for (a, b) in theirs.iter().zip(&ours) {
                assert!((a - b).abs() <= 1e-6 * b.abs().max(1.0), "{text}");
            }
        }
    }

    /// Every mesh in the shared corpus parses; some have their V/F counts checked.
    #[test]
    fn shared_data_files_parse() {
        let root = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data"));
        if !root.is_dir() {
            eprintln!("skipping: ../shared/data not found");
            return;
        }
        let mut counts = vec![
            ("morph2d/isadorable-man/man.obj", 214, 332),
            ("morph2d/isadorable-man/man2.obj", 214, 332),
            ("morph2d/ustc-hw8-leaf/0.000000.obj", 3000, 5782),
            ("closed3d/libigl/bunny.off", 3485, 6966),
            ("closed3d/libigl/decimated-knight.off", 502, 1000),
            ("closed3d/keenan-spot/spot.obj", 2930, 5856),
            ("closed3d/odedstein/spot_low_resolution.obj", 829, 1654),
            ("disk3d/libigl/camelhead.off", 11381, 22704),
        ];
        let mut stack = vec![root.to_path_buf()];
        while let Some(dir) = stack.pop() {
            for entry in fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
                if path.is_dir() {
                    stack.push(path);
                } else if ["obj", "off"].iter().any(|e| ext.eq_ignore_ascii_case(e)) {
                    let mesh = read_mesh(&path).unwrap_or_else(|e| panic!("{e}"));
                    let name = path.strip_prefix(root).unwrap().to_string_lossy();
                    let name = name.replace('\\', "/");
                    assert_eq!(mesh.is_planar(), name.starts_with("morph2d/"), "{name}");
                    if let Some(at) = counts.iter().position(|c| c.0 == name) {
                        let (_, v, f) = counts.swap_remove(at);
                        assert_eq!((mesh.positions.len(), mesh.faces.len()), (v, f), "{name}");
                    }
                }
            }
        }
        assert!(counts.is_empty(), "not found: {counts:?}");
    }
}
