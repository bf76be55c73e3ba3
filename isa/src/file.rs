//! Compiled programs as files: a versioned, checksummed byte format.
//!
//! [`Program::to_bytes`] writes a program together with the [`MeshKey`] of the mesh it was
//! compiled for; [`Program::from_bytes`] reads it back, refusing anything it cannot trust:
//! another format ([`LoadError::BadMagic`]), another version
//! ([`LoadError::UnsupportedVersion`]), a length that does not match the header's counts
//! ([`LoadError::Truncated`], [`LoadError::TrailingBytes`]), a damaged byte
//! ([`LoadError::ChecksumMismatch`]) and, last, a program the verifier rejects
//! ([`LoadError::Verify`], through [`Program::from_parts`]). Section lengths are checked
//! against the file's length before anything is allocated, so no header can make the loader
//! allocate more than the file's own size justifies.
//!
//! # Layout (format version 1)
//!
//! Every integer is little-endian; there is no padding. `E`, `U`, `W`, `Z` and `S` are the
//! counts stored in the header; `O`, stored before the last section, is 0 or (for a valid
//! program) `U`.
//!
//! | offset         | size        | content                                                   |
//! |----------------|-------------|-----------------------------------------------------------|
//! | 0              | 8           | magic `b"BDMORPH\0"`                                      |
//! | 8              | 4           | format version, `u32` (1)                                 |
//! | 12             | 4           | mesh key: vertices, `u32` (the program's `n_vertices`)    |
//! | 16             | 4           | mesh key: faces, `u32` (the program's `n_faces`)          |
//! | 20             | 8           | mesh key: faces hash, `u64` (see [`MeshKey::of`])         |
//! | 28             | 4           | `E`: edge slots, `u32`                                    |
//! | 32             | 4           | `U`: unknowns, `u32`                                      |
//! | 36             | 4           | edge slots written by the iteration stream, `u32`         |
//! | 40             | 4           | temporaries, `u32`                                        |
//! | 44             | 4           | `W`: words of the iteration stream, `u32`                 |
//! | 48             | 4           | `Z`: stored values of the Hessian's lower triangle, `u32` |
//! | 52             | 4           | `S`: embed steps, `u32`                                   |
//! | 56             | `8 E`       | edges: two vertex indices (`u32`) per slot                |
//! | ...            | `4 U`       | the mesh vertex of each unknown (`u32`)                   |
//! | ...            | `2 W`       | the iteration stream (`u16` words)                        |
//! | ...            | `4 (U + 1)` | Hessian column pointers (`u32`)                           |
//! | ...            | `4 Z`       | Hessian row indices (`u32`)                               |
//! | ...            | 12          | embed root: `p0`, `p1`, edge slot (`u32` each)            |
//! | ...            | `28 S`      | embed steps: `a b c e_ab e_bc e_ca flags` (`u32` each)    |
//! | ...            | 4           | `O`: fill-reducing ordering's length, `u32` (0: none)     |
//! | ...            | `4 O`       | the ordering: `ordering[new] = old` (`u32`)               |
//! | end - 4        | 4           | CRC-32C of every byte before it, `u32`                    |
//!
//! The checksum is CRC-32C (Castagnoli: reflected polynomial `0x82F63B78`, initial value and
//! final XOR `0xFFFFFFFF`; the check value of `b"123456789"` is `0xE3069283`). It detects
//! every error confined to 32 consecutive bits (so any single flipped bit or byte), and any
//! other damage with probability 1 - 2^-32. It guards against accidents, not against forgery:
//! whatever passes it still goes through the verifier, which is what makes a loaded program
//! safe to run.
//!
//! ```
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! # use bdmorph_isa::{EmbedRoot, EmbedStep, HessianPattern, LoadError, MeshKey, Program, ProgramParts};
//! # // The smallest program: one triangle, no unknowns.
//! # let faces = [[0u32, 1, 2]];
//! # let program = Program::from_parts(ProgramParts {
//! #     n_vertices: 3, n_faces: 1, edges: vec![[0, 1], [1, 2], [2, 0]], unknown_vertex: vec![],
//! #     n_iter_edges: 0, n_temps: 0, iteration: vec![],
//! #     hessian: HessianPattern { col_ptr: vec![0], row_idx: vec![] },
//! #     embed_root: EmbedRoot { p0: 0, p1: 1, edge: 0 },
//! #     embed: vec![EmbedStep { a: 0, b: 1, c: 2, e_ab: 0, e_bc: 1, e_ca: 2, flags: EmbedStep::PLACE }],
//! #     ordering: None,
//! # })?;
//! // `program` was compiled from a mesh with 3 vertices and these faces.
//! let key = MeshKey::of(3, &faces);
//! let bytes = program.to_bytes(&key);
//! assert_eq!(&bytes[..8], b"BDMORPH\0");
//! let (loaded, loaded_key) = Program::from_bytes(&bytes)?;
//! assert_eq!((loaded, loaded_key), (program, key));
//!
//! // One damaged byte is refused.
//! let mut damaged = bytes.clone();
//! damaged[60] ^= 0x10;
//! assert!(matches!(
//!     Program::from_bytes(&damaged),
//!     Err(LoadError::ChecksumMismatch { .. })
//! ));
//! # Ok(())
//! # }
//! ```

use crate::program::{EmbedRoot, EmbedStep, HessianPattern, Program, ProgramParts};
use crate::verify::VerifyError;

/// The first eight bytes of every program file.
pub const MAGIC: [u8; 8] = *b"BDMORPH\0";

/// The format version this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;

/// Bytes before the first section: magic, version, mesh key and counts.
const HEADER_LEN: usize = 56;

/// Bytes of the trailing checksum.
const CHECKSUM_LEN: usize = 4;

/// Identifies the mesh a program was compiled for: its vertex and face counts and a hash of
/// its faces. A program may only run on a mesh with an equal key.
///
/// Positions are not part of the key: they only chose the layout's anchor vertex (and the
/// fill-reducing ordering) when the program was compiled, and any positions with these faces
/// can be morphed by it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MeshKey {
    /// Number of vertices.
    pub n_vertices: u32,
    /// Number of triangles.
    pub n_faces: u32,
    /// 64-bit FNV-1a hash of the faces (see [`MeshKey::of`]).
    pub faces_hash: u64,
}

impl MeshKey {
    /// The key of a mesh with `n_vertices` vertices and these triangles.
    ///
    /// The hash is 64-bit FNV-1a (offset basis `0xcbf29ce484222325`, prime `0x100000001b3`)
    /// over the face indices in order, each as four little-endian bytes, so it is the same on
    /// every platform. It depends on the order of the faces and on the order of each face's
    /// corners: the same triangles listed differently give another key. Counts above
    /// `u32::MAX` (which no program can have) saturate.
    ///
    /// ```
    /// use bdmorph_isa::MeshKey;
    /// let key = MeshKey::of(3, &[[0, 1, 2]]);
    /// assert_eq!((key.n_vertices, key.n_faces), (3, 1));
    /// assert_ne!(key, MeshKey::of(3, &[[1, 2, 0]]));
    /// assert_eq!(MeshKey::of(0, &[]).faces_hash, 0xcbf2_9ce4_8422_2325);
    /// ```
    pub fn of(n_vertices: usize, faces: &[[u32; 3]]) -> MeshKey {
        let mut hash = FNV_OFFSET;
        for &index in faces.iter().flatten() {
            for byte in index.to_le_bytes() {
                hash = (hash ^ u64::from(byte)).wrapping_mul(FNV_PRIME);
            }
        }
        MeshKey {
            n_vertices: u32::try_from(n_vertices).unwrap_or(u32::MAX),
            n_faces: u32::try_from(faces.len()).unwrap_or(u32::MAX),
            faces_hash: hash,
        }
    }
}

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// Why bytes could not be loaded as a program. Messages are one line.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum LoadError {
    /// The bytes do not start with [`MAGIC`].
    #[error("not a bdmorph program file (it does not start with the bytes \"BDMORPH\\0\")")]
    BadMagic,
    /// The file was written in a format version this build cannot read.
    #[error("program format version {found} is not supported (this build reads version {supported}); compile the mesh again")]
    UnsupportedVersion {
        /// The file's version.
        found: u32,
        /// The version this build reads ([`FORMAT_VERSION`]).
        supported: u32,
    },
    /// The file is shorter than its header says.
    #[error("truncated or damaged: its header needs {needed} bytes, the file has {available}")]
    Truncated {
        /// Bytes the header's counts need (at least).
        needed: u64,
        /// Bytes present.
        available: u64,
    },
    /// The file is longer than its header says.
    #[error("damaged or not a program file: its header accounts for {expected} bytes, the file has {found}")]
    TrailingBytes {
        /// Bytes the header's counts account for.
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// The content does not match its checksum.
    #[error("damaged: checksum mismatch (stored {stored:#010x}, computed {computed:#010x})")]
    ChecksumMismatch {
        /// The CRC-32C stored in the file.
        stored: u32,
        /// The CRC-32C of the content.
        computed: u32,
    },
    /// The content is intact but the verifier rejects the program.
    #[error("invalid program: {0}")]
    Verify(#[from] VerifyError),
}

impl Program {
    /// The program as bytes (see the [module documentation](mod@crate::file) for the layout),
    /// with `key`, the key of the mesh it was compiled for.
    ///
    /// # Panics
    /// If `key`'s vertex or face count differs from the program's: the key must describe
    /// the mesh the program was compiled from.
    pub fn to_bytes(&self, key: &MeshKey) -> Vec<u8> {
        assert!(
            key.n_vertices == self.n_vertices && key.n_faces == self.n_faces,
            "the mesh key ({} vertices, {} faces) is not the key of this program's mesh \
             ({} vertices, {} faces)",
            key.n_vertices,
            key.n_faces,
            self.n_vertices,
            self.n_faces
        );
        let counts = self.counts();
        let len = usize::try_from(counts.file_len()).expect("the program is in memory");
        let mut out = vec![0; len];
        let mut w = Writer { rest: &mut out };
        w.take(MAGIC.len()).copy_from_slice(&MAGIC);
        let header = [
            FORMAT_VERSION,
            key.n_vertices,
            key.n_faces,
            key.faces_hash as u32,
            (key.faces_hash >> 32) as u32,
            counts.edges,
            counts.unknowns,
            self.n_iter_edges,
            self.n_temps,
            counts.words,
            counts.nnz,
            counts.steps,
        ];
        let one = |&x: &u32| [x];
        w.records(header.iter().map(one));
        w.records(self.edges.iter().copied());
        w.records(self.unknown_vertex.iter().map(one));
        let words = w.take(2 * self.iteration.len());
        for (c, x) in words.chunks_exact_mut(2).zip(&self.iteration) {
            c.copy_from_slice(&x.to_le_bytes());
        }
        w.records(self.hessian.col_ptr.iter().map(one));
        w.records(self.hessian.row_idx.iter().map(one));
        let root = self.embed_root;
        w.records(std::iter::once([root.p0, root.p1, root.edge]));
        w.records(
            self.embed
                .iter()
                .map(|s| [s.a, s.b, s.c, s.e_ab, s.e_bc, s.e_ca, s.flags]),
        );
        let ordering = self.ordering.as_deref().unwrap_or_default();
        w.records(std::iter::once([counts.ordering]));
        w.records(ordering.iter().map(one));
        debug_assert_eq!(w.rest.len(), CHECKSUM_LEN);
        let (content, checksum) = out.split_at_mut(len - CHECKSUM_LEN);
        checksum.copy_from_slice(&crc32c(content).to_le_bytes());
        out
    }

    /// Loads a program written by [`Program::to_bytes`], with the key of the mesh it was
    /// compiled for. Checks, in order: the magic bytes, the version, the length against the
    /// header's counts, the checksum, and then the program itself ([`Program::from_parts`]).
    /// Compare the key with [`MeshKey::of`] the mesh before running the program on it.
    pub fn from_bytes(bytes: &[u8]) -> Result<(Program, MeshKey), LoadError> {
        let available = bytes.len() as u64;
        let truncated = |needed: usize| LoadError::Truncated {
            needed: needed as u64,
            available,
        };
        let min_len = HEADER_LEN + Counts::FIXED_SECTIONS + CHECKSUM_LEN;
        if bytes.len() < MAGIC.len() {
            return Err(if MAGIC.starts_with(bytes) {
                truncated(min_len)
            } else {
                LoadError::BadMagic
            });
        }
        if bytes[..MAGIC.len()] != MAGIC {
            return Err(LoadError::BadMagic);
        }
        // The version comes first, even from a file too short for a whole header: another
        // version may have another header.
        let version = bytes.get(8..12).ok_or_else(|| truncated(min_len))?;
        let version = u32::from_le_bytes([version[0], version[1], version[2], version[3]]);
        if version != FORMAT_VERSION {
            return Err(LoadError::UnsupportedVersion {
                found: version,
                supported: FORMAT_VERSION,
            });
        }
        let mut header = Reader::new(
            bytes
                .get(12..HEADER_LEN)
                .ok_or_else(|| truncated(min_len))?,
        );
        let n_vertices = header.u32();
        let n_faces = header.u32();
        let faces_hash = u64::from(header.u32()) | (u64::from(header.u32()) << 32);
        let key = MeshKey {
            n_vertices,
            n_faces,
            faces_hash,
        };
        let edges = header.u32();
        let unknowns = header.u32();
        let n_iter_edges = header.u32();
        let n_temps = header.u32();
        let mut counts = Counts {
            edges,
            unknowns,
            words: header.u32(),
            nnz: header.u32(),
            steps: header.u32(),
            ordering: 0,
        };

        // Lengths before anything is allocated: every section must lie in the file. The
        // ordering's length is the last word before the ordering itself.
        let at = usize::try_from(counts.file_len()).unwrap_or(usize::MAX) - CHECKSUM_LEN - 4;
        if let Some(o) = bytes.get(at..at + 4) {
            counts.ordering = u32::from_le_bytes([o[0], o[1], o[2], o[3]]);
        }
        let len = counts.file_len();
        if available < len {
            return Err(LoadError::Truncated {
                needed: len,
                available,
            });
        }
        if available > len {
            return Err(LoadError::TrailingBytes {
                expected: len,
                found: available,
            });
        }
        let (content, stored) = bytes.split_at(bytes.len() - CHECKSUM_LEN);
        let stored = u32::from_le_bytes([stored[0], stored[1], stored[2], stored[3]]);
        let computed = crc32c(content);
        if stored != computed {
            return Err(LoadError::ChecksumMismatch { stored, computed });
        }

        // The length matches the counts exactly, so each read below is in bounds and each
        // allocation is bounded by the file's size.
        let mut r = Reader::new(&content[HEADER_LEN..]);
        let n = |count: u32| count as usize;
        let edges = r.records(n(counts.edges), |c: [u32; 2]| c);
        let unknown_vertex = r.records(n(counts.unknowns), |[x]: [u32; 1]| x);
        let iteration = r.u16s(n(counts.words));
        let col_ptr = r.records(n(counts.unknowns) + 1, |[x]: [u32; 1]| x);
        let row_idx = r.records(n(counts.nnz), |[x]: [u32; 1]| x);
        let [p0, p1, edge] = r.records(1, |c: [u32; 3]| c)[0];
        let embed_root = EmbedRoot { p0, p1, edge };
        let embed = r.records(n(counts.steps), |[a, b, c, e_ab, e_bc, e_ca, flags]| {
            EmbedStep {
                a,
                b,
                c,
                e_ab,
                e_bc,
                e_ca,
                flags,
            }
        });
        let [o] = r.records(1, |c: [u32; 1]| c)[0];
        let ordering = (o > 0).then(|| r.records(n(o), |[x]: [u32; 1]| x));
        debug_assert!(r.bytes.is_empty());
        let program = Program::from_parts(ProgramParts {
            n_vertices,
            n_faces,
            edges,
            unknown_vertex,
            n_iter_edges,
            n_temps,
            iteration,
            hessian: HessianPattern { col_ptr, row_idx },
            embed_root,
            embed,
            ordering,
        })?;
        Ok((program, key))
    }

    fn counts(&self) -> Counts {
        // The verifier checked that every length fits in a u32.
        let n = |len: usize| len as u32;
        Counts {
            edges: n(self.edges.len()),
            unknowns: n(self.unknown_vertex.len()),
            words: n(self.iteration.len()),
            nnz: n(self.hessian.row_idx.len()),
            steps: n(self.embed.len()),
            ordering: n(self.ordering.as_ref().map_or(0, Vec::len)),
        }
    }
}

/// Writes little-endian values into a buffer of exactly the right length.
struct Writer<'a> {
    rest: &'a mut [u8],
}

impl<'a> Writer<'a> {
    /// The next `len` bytes.
    fn take(&mut self, len: usize) -> &'a mut [u8] {
        let (head, rest) = std::mem::take(&mut self.rest).split_at_mut(len);
        self.rest = rest;
        head
    }

    /// Records of `K` values each.
    fn records<const K: usize>(&mut self, items: impl ExactSizeIterator<Item = [u32; K]>) {
        let head = self.take(4 * K * items.len());
        for (c, item) in head.chunks_exact_mut(4 * K).zip(items) {
            for (d, x) in c.chunks_exact_mut(4).zip(item) {
                d.copy_from_slice(&x.to_le_bytes());
            }
        }
    }
}

/// The header's section counts.
#[derive(Clone, Copy)]
struct Counts {
    edges: u32,
    unknowns: u32,
    words: u32,
    nnz: u32,
    steps: u32,
    ordering: u32,
}

impl Counts {
    /// Sections whose size does not depend on the counts: the first column pointer, the
    /// embed root and the ordering's length.
    const FIXED_SECTIONS: usize = 4 + 12 + 4;

    /// The file length these counts make (cannot overflow: each count is below 2^32).
    fn file_len(self) -> u64 {
        let c = |x: u32| u64::from(x);
        (HEADER_LEN + Self::FIXED_SECTIONS + CHECKSUM_LEN) as u64
            + 8 * c(self.edges)
            + 4 * c(self.unknowns)
            + 2 * c(self.words)
            + 4 * c(self.unknowns)
            + 4 * c(self.nnz)
            + 28 * c(self.steps)
            + 4 * c(self.ordering)
    }
}

/// Reads little-endian integers from a slice whose length was checked beforehand.
struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Reader { bytes }
    }

    fn take<const N: usize>(&mut self) -> [u8; N] {
        let (head, rest) = self.bytes.split_at(N);
        self.bytes = rest;
        let mut out = [0; N];
        out.copy_from_slice(head);
        out
    }

    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }

    fn slice(&mut self, len: usize) -> &'a [u8] {
        let (head, rest) = self.bytes.split_at(len);
        self.bytes = rest;
        head
    }

    /// `n` words.
    fn u16s(&mut self, n: usize) -> Vec<u16> {
        self.slice(2 * n)
            .chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect()
    }

    /// `n` records of `K` values each, converted by `f`.
    fn records<const K: usize, T>(&mut self, n: usize, f: impl Fn([u32; K]) -> T) -> Vec<T> {
        self.slice(4 * K * n)
            .chunks_exact(4 * K)
            .map(|c| {
                f(std::array::from_fn(|i| {
                    u32::from_le_bytes([c[4 * i], c[4 * i + 1], c[4 * i + 2], c[4 * i + 3]])
                }))
            })
            .collect()
    }
}

/// CRC-32C lookup tables for slicing by 8: `TABLES[0]` is the byte-at-a-time table and
/// `TABLES[k][i]` advances `TABLES[k - 1][i]` by one more zero byte.
static CRC_TABLES: [[u32; 256]; 8] = crc_tables();

const fn crc_tables() -> [[u32; 256]; 8] {
    let mut t = [[0u32; 256]; 8];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut bit = 0;
        while bit < 8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0x82F6_3B78
            } else {
                c >> 1
            };
            bit += 1;
        }
        t[0][i] = c;
        i += 1;
    }
    let mut k = 1;
    while k < 8 {
        let mut i = 0;
        while i < 256 {
            let prev = t[k - 1][i];
            t[k][i] = (prev >> 8) ^ t[0][(prev & 0xFF) as usize];
            i += 1;
        }
        k += 1;
    }
    t
}

/// CRC-32C (Castagnoli) of `bytes`, eight bytes per step.
/// CRC-32C (Castagnoli) of `bytes`: the checksum that ends a program file. Public so that
/// tools (and fuzzers) can write files with a valid checksum around other damage.
pub fn crc32c(bytes: &[u8]) -> u32 {
    let t = &CRC_TABLES;
    let mut crc = !0u32;
    let mut chunks = bytes.chunks_exact(8);
    for c in &mut chunks {
        let x = crc ^ u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        crc = t[7][(x & 0xFF) as usize]
            ^ t[6][((x >> 8) & 0xFF) as usize]
            ^ t[5][((x >> 16) & 0xFF) as usize]
            ^ t[4][(x >> 24) as usize]
            ^ t[3][c[4] as usize]
            ^ t[2][c[5] as usize]
            ^ t[1][c[6] as usize]
            ^ t[0][c[7] as usize];
    }
    for &b in chunks.remainder() {
        crc = (crc >> 8) ^ t[0][((crc ^ u32::from(b)) & 0xFF) as usize];
    }
    !crc
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixture::hexagon_parts;

    fn hexagon() -> (Program, MeshKey) {
        let faces: Vec<[u32; 3]> = (0..6).map(|i| [0, 1 + i, 1 + (i + 1) % 6]).collect();
        let program = Program::from_parts(hexagon_parts()).expect("valid");
        (program, MeshKey::of(7, &faces))
    }

    /// Rewrites the checksum after editing `bytes`, as a forger (or a buggy writer) would.
    fn reseal(bytes: &mut [u8]) {
        let n = bytes.len() - CHECKSUM_LEN;
        let crc = crc32c(&bytes[..n]);
        bytes[n..].copy_from_slice(&crc.to_le_bytes());
    }

    fn set_u32(bytes: &mut [u8], at: usize, x: u32) {
        bytes[at..at + 4].copy_from_slice(&x.to_le_bytes());
    }

    #[test]
    fn crc32c_matches_its_check_value_and_the_bytewise_definition() {
        assert_eq!(crc32c(b"123456789"), 0xE306_9283);
        assert_eq!(crc32c(b""), 0);
        let bitwise = |bytes: &[u8]| {
            let mut crc = !0u32;
            for &b in bytes {
                crc ^= u32::from(b);
                for _ in 0..8 {
                    crc = if crc & 1 != 0 {
                        (crc >> 1) ^ 0x82F6_3B78
                    } else {
                        crc >> 1
                    };
                }
            }
            !crc
        };
        let data: Vec<u8> = (0..100u32).map(|i| (i * 37 + 11) as u8).collect();
        for start in 0..9 {
            for end in start..data.len() {
                assert_eq!(crc32c(&data[start..end]), bitwise(&data[start..end]));
            }
        }
    }

    #[test]
    fn the_faces_hash_is_fnv1a_over_little_endian_indices() {
        // Reference value computed independently (Python) over the same 36 bytes.
        let key = MeshKey::of(70_001, &[[0, 1, 2], [2, 1, 3], [70_000, 5, 4]]);
        assert_eq!(key.faces_hash, 0xac70_f1c3_01b6_5269);
        assert_eq!((key.n_vertices, key.n_faces), (70_001, 3));
        assert_ne!(
            key,
            MeshKey::of(70_001, &[[2, 1, 3], [0, 1, 2], [70_000, 5, 4]])
        );
    }

    #[test]
    fn round_trip_and_layout() {
        let (program, key) = hexagon();
        let bytes = program.to_bytes(&key);
        let st = program.stats();
        // Header, sections (the stats count every section but the root and the ordering's
        // length), checksum.
        assert_eq!(
            bytes.len(),
            HEADER_LEN + st.total_bytes + 12 + 4 + CHECKSUM_LEN
        );
        assert_eq!(&bytes[..8], b"BDMORPH\0");
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4"));
        assert_eq!(
            [word(8), word(12), word(16), word(28), word(32), word(36)],
            [1, 7, 6, 12, 1, 12]
        );
        assert_eq!(
            [word(40), word(44), word(48), word(52)],
            [18, program.iteration().len() as u32, 1, 6]
        );
        assert_eq!(
            u64::from(word(20)) | (u64::from(word(24)) << 32),
            key.faces_hash
        );
        assert_eq!([word(56), word(60), word(64)], [0, 1, 1]); // edge slots 0 and 1
        let (back, back_key) = Program::from_bytes(&bytes).expect("loads");
        assert_eq!(back, program);
        assert_eq!(back_key, key);
        // Deterministic.
        assert_eq!(back.to_bytes(&back_key), bytes);
    }

    #[test]
    fn the_ordering_round_trips_and_is_verified() {
        let (program, key) = hexagon();
        let mut parts = program.to_parts();
        parts.ordering = Some(vec![0]);
        let ordered = Program::from_parts(parts).expect("valid");
        let bytes = ordered.to_bytes(&key);
        assert_eq!(bytes.len(), program.to_bytes(&key).len() + 4);
        let n = bytes.len() - CHECKSUM_LEN;
        assert_eq!(&bytes[n - 8..n], &[1, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(Program::from_bytes(&bytes), Ok((ordered, key)));
        // An ordering that names no unknown, with a valid checksum.
        let mut b = bytes.clone();
        set_u32(&mut b, n - 4, 1);
        reseal(&mut b);
        assert_eq!(
            Program::from_bytes(&b),
            Err(LoadError::Verify(VerifyError::BadOrdering { entry: 0 }))
        );
        // An ordering length that disagrees with the file's.
        let mut b = bytes.clone();
        set_u32(&mut b, n - 8, 2);
        reseal(&mut b);
        assert!(matches!(
            Program::from_bytes(&b),
            Err(LoadError::Truncated { .. })
        ));
        let mut b = bytes;
        set_u32(&mut b, n - 8, 0);
        reseal(&mut b);
        assert!(matches!(
            Program::from_bytes(&b),
            Err(LoadError::TrailingBytes { .. })
        ));
    }

    #[test]
    fn every_flipped_bit_and_byte_is_refused() {
        let (program, key) = hexagon();
        let bytes = program.to_bytes(&key);
        let mut damaged = bytes.clone();
        for at in 0..bytes.len() {
            for mask in [0xFF, 1, 2, 4, 8, 16, 32, 64, 128] {
                damaged[at] ^= mask;
                let err = Program::from_bytes(&damaged).expect_err("damaged bytes must be refused");
                damaged[at] ^= mask;
                // Damage past the header can only be caught by the checksum, except in the
                // ordering's length, which must match the file's length.
                let ordering_length = bytes.len() - CHECKSUM_LEN - 4..bytes.len() - CHECKSUM_LEN;
                if at >= HEADER_LEN && !ordering_length.contains(&at) {
                    assert!(
                        matches!(err, LoadError::ChecksumMismatch { .. }),
                        "byte {at} ^ {mask:#x}: {err}"
                    );
                }
            }
        }
        assert_eq!(damaged, bytes);
    }

    #[test]
    fn every_truncation_and_any_extra_byte_is_refused() {
        let (program, key) = hexagon();
        let bytes = program.to_bytes(&key);
        for len in 0..bytes.len() {
            match Program::from_bytes(&bytes[..len]) {
                Err(LoadError::Truncated { needed, available }) => {
                    assert_eq!(available, len as u64);
                    assert!(needed > available);
                }
                other => panic!("length {len}: {other:?}"),
            }
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert_eq!(
            Program::from_bytes(&longer),
            Err(LoadError::TrailingBytes {
                expected: bytes.len() as u64,
                found: bytes.len() as u64 + 1
            })
        );
    }

    #[test]
    fn magic_and_version_are_checked_first() {
        let (program, key) = hexagon();
        let bytes = program.to_bytes(&key);
        let mut other = bytes.clone();
        other[0] = b'b';
        assert_eq!(Program::from_bytes(&other), Err(LoadError::BadMagic));
        assert_eq!(Program::from_bytes(b"v 0 0 0\n"), Err(LoadError::BadMagic));
        assert_eq!(Program::from_bytes(b"# a"), Err(LoadError::BadMagic));
        for version in [0, 2, u32::MAX] {
            let mut newer = bytes.clone();
            set_u32(&mut newer, 8, version);
            // Even with a header this build cannot parse.
            newer.truncate(20);
            let err = Program::from_bytes(&newer).expect_err("refused");
            assert_eq!(
                err,
                LoadError::UnsupportedVersion {
                    found: version,
                    supported: 1
                }
            );
            assert!(err.to_string().contains(&format!("version {version}")));
        }
    }

    #[test]
    fn resealed_nonsense_is_refused_without_large_allocations() {
        let (program, key) = hexagon();
        let bytes = program.to_bytes(&key);
        // Header counts claiming gigabytes: refused by length before any allocation.
        for at in [28, 32, 44, 48, 52] {
            let mut b = bytes.clone();
            set_u32(&mut b, at, u32::MAX);
            reseal(&mut b);
            assert!(
                matches!(Program::from_bytes(&b), Err(LoadError::Truncated { .. })),
                "count at {at}"
            );
        }
        // A vertex count of 2^32 - 1 would make the verifier allocate 16 GB per-vertex tables.
        let mut b = bytes.clone();
        set_u32(&mut b, 12, u32::MAX);
        reseal(&mut b);
        assert!(matches!(
            Program::from_bytes(&b),
            Err(LoadError::Verify(VerifyError::Sizes { .. }))
        ));
        // An edge naming a missing vertex, with a valid checksum: the verifier refuses it.
        let mut b = bytes.clone();
        set_u32(&mut b, HEADER_LEN + 8 * 3, 99);
        reseal(&mut b);
        let err = Program::from_bytes(&b).expect_err("refused");
        assert_eq!(err, LoadError::Verify(VerifyError::BadEdge { slot: 3 }));
        assert_eq!(err.to_string(), "invalid program: edge slot 3 is invalid");
    }

    #[test]
    fn messages_are_one_line() {
        let errors = [
            LoadError::BadMagic,
            LoadError::UnsupportedVersion {
                found: 2,
                supported: 1,
            },
            LoadError::Truncated {
                needed: 100,
                available: 10,
            },
            LoadError::TrailingBytes {
                expected: 100,
                found: 101,
            },
            LoadError::ChecksumMismatch {
                stored: 1,
                computed: 2,
            },
            LoadError::Verify(VerifyError::Decode { pc: 3 }),
        ];
        for e in errors {
            let text = e.to_string();
            assert!(!text.is_empty() && !text.contains('\n'), "{text}");
        }
        assert_eq!(
            LoadError::ChecksumMismatch {
                stored: 0xAB,
                computed: 0x1234_5678
            }
            .to_string(),
            "damaged: checksum mismatch (stored 0x000000ab, computed 0x12345678)"
        );
    }

    #[test]
    #[should_panic(expected = "is not the key of this program's mesh")]
    fn writing_with_another_mesh_key_panics() {
        let (program, _) = hexagon();
        let _ = program.to_bytes(&MeshKey::of(8, &[[0, 1, 2]]));
    }
}
