//! Compiled programs as files: a versioned, checksummed, compact byte format.
//!
//! [`Program::to_bytes`] writes a program together with the [`MeshKey`] of the mesh it was
//! compiled for; [`Program::from_bytes`] reads it back, refusing anything it cannot trust:
//! another format ([`LoadError::BadMagic`]), another version
//! ([`LoadError::UnsupportedVersion`]; version 1 files included: compile the mesh again), a
//! length other than the one the header states ([`LoadError::Truncated`],
//! [`LoadError::TrailingBytes`]), a damaged byte ([`LoadError::ChecksumMismatch`]), content
//! that does not parse although its checksum holds ([`LoadError::BadVarint`],
//! [`LoadError::Malformed`]: a buggy writer or a forgery) and, last, a program the verifier
//! rejects ([`LoadError::Verify`], through [`Program::from_parts`]).
//!
//! Every count is checked against the bytes left in its section before anything is sized by
//! it (each element takes at least one byte), so no file can make the loader allocate more
//! than a small multiple of its own length.
//!
//! # Layout (format version 2)
//!
//! A fixed header, tagged sections, and a checksum. The header's integers are little-endian.
//! Everything in the sections is a *varint*: unsigned LEB128 (seven bits per byte, least
//! significant first, the high bit set on every byte but the last), at most 64 bits and 10
//! bytes, and as short as possible (a last byte `0x00` after another byte is refused). "Δ
//! from `x`" below means the varint of the zigzag-coded difference `value - x` (0, -1, 1, -2,
//! 2, ... coded as 0, 1, 2, 3, 4, ...).
//!
//! | offset  | size | content                                                             |
//! |---------|------|---------------------------------------------------------------------|
//! | 0       | 8    | magic `b"BDMORPH\0"`                                                |
//! | 8       | 4    | format version, `u32` (2)                                           |
//! | 12      | 8    | length of the file in bytes, checksum included, `u64`               |
//! | 20      | 4    | mesh key: vertices, `u32` (the program's `n_vertices`)              |
//! | 24      | 4    | mesh key: faces, `u32` (the program's `n_faces`)                    |
//! | 28      | 8    | mesh key: faces hash, `u64` (see [`MeshKey::of`])                   |
//! | 36      | ...  | sections, each: tag (one byte), payload length (varint), payload    |
//! | end - 4 | 4    | CRC-32C of every byte before it, `u32`                              |
//!
//! Sections 1 to 4 are required, in this order; section 5 is optional and comes last. A later
//! version may add optional sections after them with higher tags, in increasing order; this
//! one refuses any other tag. Each
//! payload must be read exactly to its end.
//!
//! **Section 1, layout**: the edge slots (the init stream) and the embed stream.
//!
//! | field                          | content                                                   |
//! |--------------------------------|-----------------------------------------------------------|
//! | `E`, `n_iter_edges`, `S`       | edge slots, slots written by the iteration stream, steps  |
//! | `p0`, `p1`, `edge`, `rev`      | embed root; slot `edge` is `[p0, p1]`, `[p1, p0]` if `rev` = 1 |
//! | `S` steps                      | `head`, `e_bc`, `e_ca`, and `c` when it is needed         |
//! | `N`                            | edge slots that neither the root nor a step defines       |
//! | `N` times `a`, `b`             | the vertices of those slots, in slot order                |
//!
//! The vertices of an edge slot are not listed when the walk defines them. A list of *known*
//! slots starts with the root's `edge`; each step appends its `e_bc` then its `e_ca`; a
//! cursor into it starts at 0. For each step:
//!
//! * `head` = 16 · zigzag(`skip`) + `flags`: the entry edge `e_ab` is the known slot at index
//!   `cursor + skip`, and the cursor moves just past it (a breadth-first walk has `skip` 0 or
//!   1 nearly always). `a`, `b` are the vertices of slot `e_ab`, swapped if `flags` has
//!   `REV_AB`;
//! * `e_bc`, `e_ca`: Δ from the previous step's `e_bc`, `e_ca` (0 before the first step);
//! * `c`: stored (Δ from the previous stored `c`, 0 at first) when `flags` has `PLACE` or
//!   neither `e_bc` nor `e_ca` is defined yet; otherwise the vertex of slot `e_bc` other than
//!   `b` (its second vertex, the first if `REV_BC`), or failing that of slot `e_ca` (its first
//!   vertex, the second if `REV_CA`);
//! * then slot `e_bc`, if not yet defined, becomes `[b, c]` (`[c, b]` if `REV_BC`), and slot
//!   `e_ca` becomes `[c, a]` (`[a, c]` if `REV_CA`).
//!
//! **Section 2, unknowns**: `U`, then the mesh vertex of each unknown as Δ from the previous
//! one's (0 for the first).
//!
//! **Section 3, iteration**: the number of temporaries, `W`, then the `W` words of the
//! iteration stream, one varint (at most 65535) each.
//!
//! **Section 4, Hessian**: the number of columns, then for each column `k` the number `m` of
//! rows below the diagonal, then those rows `r`, each stored as `2 (r - p - 1)` where `p` is
//! the column's previous row (`k` for the first), or as `2 zigzag(r - q) + 1` where `q` is the
//! last row of the previous column (0 for column 0): the writer takes the shorter (the first
//! on a tie), the reader accepts either. The diagonal row `k` is not stored; the column
//! pointers follow from the lengths.
//!
//! **Section 5, ordering** (optional, present when the program carries a fill-reducing
//! ordering of the unknowns): `U`, then `ordering[new] = old` for each `new`, each a Δ from
//! the previous one (0 before the first).
//!
//! The writer relies on what the verifier guarantees of every [`Program`] (each entry edge is
//! known, each step's edges join its vertices, each column starts with its diagonal and
//! increases): that makes the round trip exact. The reader relies on nothing: any bytes
//! decode to some parts or to an error, and the verifier decides about the parts.
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
//! #     embed: vec![EmbedStep { a: 0, b: 1, c: 2, e_ab: 0, e_bc: 1, e_ca: 2, flags: EmbedStep::PLACE }], ordering: None,
//! # })?;
//! // `program` was compiled from a mesh with 3 vertices and these faces.
//! let key = MeshKey::of(3, &faces);
//! let bytes = program.to_bytes(&key);
//! assert_eq!(&bytes[..8], b"BDMORPH\0");
//! assert_eq!(bytes.len(), program.file_sizes().total());
//! let (loaded, loaded_key) = Program::from_bytes(&bytes)?;
//! assert_eq!((loaded, loaded_key), (program, key));
//!
//! // One damaged byte is refused.
//! let mut damaged = bytes.clone();
//! damaged[40] ^= 0x10;
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

/// The format version this build writes and reads (it refuses every other, version 1
/// included).
pub const FORMAT_VERSION: u32 = 2;

/// Bytes before the first section: magic, version, file length and mesh key.
const HEADER_LEN: usize = 36;

/// Offset of the file length in the header.
const LENGTH_AT: usize = 12;

/// Bytes of the trailing checksum.
const CHECKSUM_LEN: usize = 4;

/// Section tags, in the order the sections must appear.
mod tag {
    pub const LAYOUT: u8 = 1;
    pub const UNKNOWNS: u8 = 2;
    pub const ITERATION: u8 = 3;
    pub const HESSIAN: u8 = 4;
    pub const ORDERING: u8 = 5;
}

/// Identifies the mesh a program was compiled for: its vertex and face counts and a hash of
/// its faces. A program may only run on a mesh with an equal key.
///
/// Positions are not part of the key: they only chose the layout's anchor vertex when the
/// program was compiled, and any positions with these faces can be morphed by it.
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
        /// Bytes the header says the file has (at least).
        needed: u64,
        /// Bytes present.
        available: u64,
    },
    /// The file is longer than its header says.
    #[error("damaged or not a program file: its header accounts for {expected} bytes, the file has {found}")]
    TrailingBytes {
        /// Bytes the header says the file has.
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
    /// A varint is longer than needed, longer than 10 bytes, or above 64 bits. The checksum
    /// held, so the writer was faulty (or the file forged).
    #[error("malformed program file: bad varint at byte {offset} (overlong or above 64 bits)")]
    BadVarint {
        /// Offset of the varint's first byte.
        offset: u64,
    },
    /// The content does not parse as this version's sections although the checksum held: a
    /// section is missing, repeated, unknown or out of order, ends inside a value or has bytes
    /// after its content, or a value or count is out of range.
    #[error("malformed program file at byte {offset}: {what}")]
    Malformed {
        /// Offset of the offending value (or section tag).
        offset: u64,
        /// What is wrong.
        what: &'static str,
    },
    /// The content is intact but the verifier rejects the program.
    #[error("invalid program: {0}")]
    Verify(#[from] VerifyError),
}

/// The size in bytes of each part of a program's file ([`Program::file_sizes`]), framing (tag
/// and payload length) included. The parts add up to the file's length.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FileSizes {
    /// Magic, version, file length and mesh key.
    pub header: usize,
    /// Section 1: the edge slots and the embed stream.
    pub layout: usize,
    /// Section 2: the mesh vertex of each unknown.
    pub unknowns: usize,
    /// Section 3: the iteration stream.
    pub iteration: usize,
    /// Section 4: the Hessian pattern.
    pub hessian: usize,
    /// Section 5 (optional, 0 when absent): the fill-reducing ordering of the unknowns.
    pub ordering: usize,
    /// The checksum.
    pub checksum: usize,
}

impl FileSizes {
    /// The file's length.
    pub fn total(&self) -> usize {
        self.header
            + self.layout
            + self.unknowns
            + self.iteration
            + self.hessian
            + self.ordering
            + self.checksum
    }
}

impl Program {
    /// The program as bytes (see the [module documentation](mod@crate::file) for the layout),
    /// with `key`, the key of the mesh it was compiled for. The same program and key always
    /// give the same bytes.
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
        self.encode(key).0
    }

    /// The size of each part of the program's file (the length of [`Program::to_bytes`] is
    /// their [total](FileSizes::total)). This encodes the whole program.
    pub fn file_sizes(&self) -> FileSizes {
        let key = MeshKey {
            n_vertices: self.n_vertices,
            n_faces: self.n_faces,
            faces_hash: 0,
        };
        self.encode(&key).1
    }

    /// Loads a program written by [`Program::to_bytes`], with the key of the mesh it was
    /// compiled for. Checks, in order: the magic bytes, the version, the file's length against
    /// the header's, the checksum, the sections, and then the program itself
    /// ([`Program::from_parts`]). Compare the key with [`MeshKey::of`] the mesh before running
    /// the program on it.
    pub fn from_bytes(bytes: &[u8]) -> Result<(Program, MeshKey), LoadError> {
        let available = bytes.len() as u64;
        let min_len = (HEADER_LEN + CHECKSUM_LEN) as u64;
        if bytes.len() < MAGIC.len() {
            return Err(if MAGIC.starts_with(bytes) {
                LoadError::Truncated {
                    needed: min_len,
                    available,
                }
            } else {
                LoadError::BadMagic
            });
        }
        if bytes[..MAGIC.len()] != MAGIC {
            return Err(LoadError::BadMagic);
        }
        // The version comes first, even from a file too short for a whole header: another
        // version may have another header.
        let truncated = LoadError::Truncated {
            needed: min_len,
            available,
        };
        let version = u32::from_le_bytes(le_bytes(bytes, 8).ok_or(truncated.clone())?);
        if version != FORMAT_VERSION {
            return Err(LoadError::UnsupportedVersion {
                found: version,
                supported: FORMAT_VERSION,
            });
        }
        // The stated length, before anything else is read.
        let len = u64::from_le_bytes(le_bytes(bytes, LENGTH_AT).ok_or(truncated.clone())?);
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
        if bytes.len() < HEADER_LEN + CHECKSUM_LEN {
            // Only a file that states a length shorter than any header gets here.
            return Err(truncated);
        }
        let (content, stored) = bytes.split_at(bytes.len() - CHECKSUM_LEN);
        let stored = u32::from_le_bytes(le_bytes(stored, 0).ok_or(truncated.clone())?);
        let computed = crc32c(content);
        if stored != computed {
            return Err(LoadError::ChecksumMismatch { stored, computed });
        }

        let word = |at| le_bytes(content, at).map(u32::from_le_bytes);
        let hash = le_bytes(content, 28).map(u64::from_le_bytes);
        let (Some(n_vertices), Some(n_faces), Some(faces_hash)) = (word(20), word(24), hash) else {
            return Err(truncated);
        };
        let key = MeshKey {
            n_vertices,
            n_faces,
            faces_hash,
        };
        let parts = decode(content, n_vertices, n_faces)?;
        Ok((Program::from_parts(parts)?, key))
    }

    /// The file and the size of each of its parts.
    fn encode(&self, key: &MeshKey) -> (Vec<u8>, FileSizes) {
        let mut out = Vec::with_capacity(HEADER_LEN + 8 * self.embed.len() + self.iteration.len());
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&[0; 8]); // the length, known at the end
        out.extend_from_slice(&key.n_vertices.to_le_bytes());
        out.extend_from_slice(&key.n_faces.to_le_bytes());
        out.extend_from_slice(&key.faces_hash.to_le_bytes());
        debug_assert_eq!(out.len(), HEADER_LEN);
        let mut sizes = FileSizes {
            header: HEADER_LEN,
            checksum: CHECKSUM_LEN,
            ..FileSizes::default()
        };
        let mut payload = Vec::new();
        sizes.layout = section(&mut out, &mut payload, tag::LAYOUT, |p| {
            self.encode_layout(p)
        });
        sizes.unknowns = section(&mut out, &mut payload, tag::UNKNOWNS, |p| {
            put(p, self.unknown_vertex.len() as u64);
            let mut prev = 0;
            for &v in &self.unknown_vertex {
                put_delta(p, prev, v);
                prev = v;
            }
        });
        sizes.iteration = section(&mut out, &mut payload, tag::ITERATION, |p| {
            put(p, u64::from(self.n_temps));
            put(p, self.iteration.len() as u64);
            p.reserve(self.iteration.len());
            for &word in &self.iteration {
                put(p, u64::from(word));
            }
        });
        sizes.hessian = section(&mut out, &mut payload, tag::HESSIAN, |p| {
            self.encode_hessian(p)
        });
        if let Some(ordering) = &self.ordering {
            sizes.ordering = section(&mut out, &mut payload, tag::ORDERING, |p| {
                put(p, ordering.len() as u64);
                let mut prev = 0;
                for &k in ordering {
                    put_delta(p, prev, k);
                    prev = k;
                }
            });
        }
        let len = (out.len() + CHECKSUM_LEN) as u64;
        out[LENGTH_AT..LENGTH_AT + 8].copy_from_slice(&len.to_le_bytes());
        let crc = crc32c(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        debug_assert_eq!(out.len(), sizes.total());
        (out, sizes)
    }

    /// Section 1. Mirrors [`decode_layout`]. Relies on the program being verified: every
    /// slot is in range, and every entry edge is known (so it has an index in `known_at`).
    fn encode_layout(&self, p: &mut Vec<u8>) {
        let n_edges = self.edges.len();
        put(p, n_edges as u64);
        put(p, u64::from(self.n_iter_edges));
        put(p, self.embed.len() as u64);
        let root = self.embed_root;
        put(p, u64::from(root.p0));
        put(p, u64::from(root.p1));
        put(p, u64::from(root.edge));
        let root_edge = root.edge as usize;
        put(p, u64::from(self.edges[root_edge] != [root.p0, root.p1]));
        let mut defined = vec![false; n_edges];
        defined[root_edge] = true;
        // The latest index of each slot in the list of known slots (root, then each step's
        // `e_bc` and `e_ca`); the root's, 0, starts every slot, and only the root's is read
        // before another is written.
        let mut known_at = vec![0u64; n_edges];
        let mut n_known = 1;
        let (mut cursor, mut prev_bc, mut prev_ca, mut prev_c) = (0i64, 0, 0, 0);
        for s in &self.embed {
            let at = known_at[s.e_ab as usize] as i64;
            put(p, (zigzag(at - cursor) << 4) | u64::from(s.flags & 0xF));
            cursor = at + 1;
            put_delta(p, prev_bc, s.e_bc);
            put_delta(p, prev_ca, s.e_ca);
            let (bc, ca) = (s.e_bc as usize, s.e_ca as usize);
            if s.flags & EmbedStep::PLACE != 0 || !(defined[bc] || defined[ca]) {
                put_delta(p, prev_c, s.c);
                prev_c = s.c;
            }
            defined[bc] = true;
            defined[ca] = true;
            for slot in [s.e_bc, s.e_ca] {
                known_at[slot as usize] = n_known;
                n_known += 1;
            }
            (prev_bc, prev_ca) = (s.e_bc, s.e_ca);
        }
        put(p, defined.iter().filter(|&&d| !d).count() as u64);
        for (&[a, b], &d) in self.edges.iter().zip(&defined) {
            if !d {
                put(p, u64::from(a));
                put(p, u64::from(b));
            }
        }
    }

    /// Section 4. Mirrors [`decode_hessian`].
    fn encode_hessian(&self, p: &mut Vec<u8>) {
        let h = &self.hessian;
        put(p, h.dim() as u64);
        let mut last = 0u32;
        for k in 0..h.dim() {
            let rows = &h.row_idx[h.col_ptr[k] as usize..h.col_ptr[k + 1] as usize];
            // The verifier guarantees at least the diagonal, `k`.
            let below = rows.get(1..).unwrap_or_default();
            put(p, below.len() as u64);
            let mut prev = k as u32;
            for &r in below {
                let near = (r > prev).then(|| u64::from(r - prev - 1) << 1);
                let far = (zigzag(i64::from(r) - i64::from(last)) << 1) | 1;
                put(
                    p,
                    near.filter(|&x| varint_len(x) <= varint_len(far))
                        .unwrap_or(far),
                );
                prev = r;
            }
            last = rows.last().copied().unwrap_or(last);
        }
    }
}

/// Appends a section: its tag, the length of what `fill` writes, and that. Returns the
/// section's size in bytes. `payload` is scratch space.
fn section(
    out: &mut Vec<u8>,
    payload: &mut Vec<u8>,
    tag: u8,
    fill: impl FnOnce(&mut Vec<u8>),
) -> usize {
    let start = out.len();
    payload.clear();
    fill(payload);
    out.push(tag);
    put(out, payload.len() as u64);
    out.extend_from_slice(payload);
    out.len() - start
}

/// Appends `x` as a varint.
#[inline]
fn put(out: &mut Vec<u8>, mut x: u64) {
    while x >= 0x80 {
        out.push(x as u8 | 0x80);
        x >>= 7;
    }
    out.push(x as u8);
}

/// Appends `x - prev` as a zigzag varint.
fn put_delta(out: &mut Vec<u8>, prev: u32, x: u32) {
    put(out, zigzag(i64::from(x) - i64::from(prev)));
}

/// Bytes of `x` as a varint.
fn varint_len(x: u64) -> u32 {
    (64 - (x | 1).leading_zeros()).div_ceil(7)
}

/// 0, -1, 1, -2, 2, ... as 0, 1, 2, 3, 4, ...
fn zigzag(x: i64) -> u64 {
    ((x << 1) ^ (x >> 63)) as u64
}

/// The inverse of [`zigzag`].
fn unzigzag(x: u64) -> i64 {
    (x >> 1) as i64 ^ -((x & 1) as i64)
}

/// The `N` bytes at `at`, if there are that many.
fn le_bytes<const N: usize>(bytes: &[u8], at: usize) -> Option<[u8; N]> {
    bytes.get(at..at.checked_add(N)?)?.try_into().ok()
}

const ENDS_INSIDE: &str = "a section ends inside a value";
const TOO_LARGE: &str = "a value does not fit in 32 bits";
const TOO_MANY: &str = "a count exceeds what the rest of its section can hold";
const BAD_SLOT: &str = "an edge slot out of range";

/// The parts in `content` (the file without its checksum, whose header was checked).
fn decode(content: &[u8], n_vertices: u32, n_faces: u32) -> Result<ProgramParts, LoadError> {
    let mut r = Reader {
        bytes: content,
        pos: HEADER_LEN,
    };
    let mut layout = None;
    let mut unknown_vertex = None;
    let mut iteration = None;
    let mut hessian = None;
    let mut ordering = None;
    let mut last_tag = 0;
    while r.pos < content.len() {
        let at = r.pos;
        let tag = r.byte()?;
        let len = r.varint()?;
        let start = r.pos;
        let end = usize::try_from(len)
            .ok()
            .and_then(|len| start.checked_add(len))
            .filter(|&end| end <= content.len())
            .ok_or(malformed(at, "a section runs past the end of the file"))?;
        if tag <= last_tag {
            return Err(malformed(at, "a section is repeated or out of order"));
        }
        last_tag = tag;
        let mut s = Reader {
            bytes: &content[..end],
            pos: start,
        };
        match tag {
            tag::LAYOUT => layout = Some(decode_layout(&mut s)?),
            tag::UNKNOWNS => unknown_vertex = Some(decode_unknowns(&mut s)?),
            tag::ITERATION => iteration = Some(decode_iteration(&mut s)?),
            tag::HESSIAN => hessian = Some(decode_hessian(&mut s)?),
            tag::ORDERING => ordering = Some(decode_unknowns(&mut s)?),
            _ => return Err(malformed(at, "a section this version does not know")),
        }
        if s.pos != end {
            return Err(malformed(s.pos, "a section has bytes after its content"));
        }
        r.pos = end;
    }
    let (Some(layout), Some(unknown_vertex), Some(iteration), Some(hessian)) =
        (layout, unknown_vertex, iteration, hessian)
    else {
        return Err(malformed(content.len(), "a required section is missing"));
    };
    let Layout {
        edges,
        n_iter_edges,
        embed_root,
        embed,
    } = layout;
    let (n_temps, iteration) = iteration;
    Ok(ProgramParts {
        n_vertices,
        n_faces,
        edges,
        unknown_vertex,
        n_iter_edges,
        n_temps,
        iteration,
        hessian,
        embed_root,
        embed,
        ordering,
    })
}

fn malformed(at: usize, what: &'static str) -> LoadError {
    LoadError::Malformed {
        offset: at as u64,
        what,
    }
}

/// What section 1 holds.
struct Layout {
    edges: Vec<[u32; 2]>,
    n_iter_edges: u32,
    embed_root: EmbedRoot,
    embed: Vec<EmbedStep>,
}

/// Section 1 (see the module documentation).
fn decode_layout(r: &mut Reader) -> Result<Layout, LoadError> {
    // Each edge slot is defined by the root, a step (two at most, in three bytes at least) or
    // an entry of the final list (two bytes at least), so there are fewer than bytes left.
    let n_edges = r.count(1)?;
    let n_iter_edges = r.u32()?;
    let n_steps = r.count(3)?;
    let p0 = r.u32()?;
    let p1 = r.u32()?;
    let at = r.pos;
    let root_edge = r.u32()? as usize;
    let rev = r.varint()?;
    if root_edge >= n_edges {
        return Err(malformed(at, BAD_SLOT));
    }
    if rev > 1 {
        return Err(malformed(at, "a root orientation other than 0 or 1"));
    }
    let mut edges = vec![[0, 0]; n_edges];
    let mut defined = vec![false; n_edges];
    edges[root_edge] = if rev == 1 { [p1, p0] } else { [p0, p1] };
    defined[root_edge] = true;
    let mut known = Vec::with_capacity(1 + 2 * n_steps);
    known.push(root_edge);
    let mut embed = Vec::with_capacity(n_steps);
    let (mut cursor, mut prev_bc, mut prev_ca, mut prev_c) = (0usize, 0, 0, 0);
    for _ in 0..n_steps {
        let at = r.pos;
        let head = r.varint()?;
        let flags = (head & 0xF) as u32;
        let index = i64::try_from(cursor)
            .ok()
            .and_then(|c| c.checked_add(unzigzag(head >> 4)))
            .and_then(|i| usize::try_from(i).ok())
            .filter(|&i| i < known.len())
            .ok_or_else(|| malformed(at, "a step enters through an edge that is not known yet"))?;
        cursor = index + 1;
        let e_ab = known[index];
        let [x, y] = edges[e_ab];
        let (a, b) = if flags & EmbedStep::REV_AB != 0 {
            (y, x)
        } else {
            (x, y)
        };
        let e_bc = r.slot(prev_bc, n_edges)?;
        let e_ca = r.slot(prev_ca, n_edges)?;
        let c = if flags & EmbedStep::PLACE != 0 || !(defined[e_bc] || defined[e_ca]) {
            prev_c = r.delta(prev_c)?;
            prev_c
        } else if defined[e_bc] {
            edges[e_bc][usize::from(flags & EmbedStep::REV_BC == 0)]
        } else {
            edges[e_ca][usize::from(flags & EmbedStep::REV_CA != 0)]
        };
        if !defined[e_bc] {
            edges[e_bc] = if flags & EmbedStep::REV_BC != 0 {
                [c, b]
            } else {
                [b, c]
            };
            defined[e_bc] = true;
        }
        if !defined[e_ca] {
            edges[e_ca] = if flags & EmbedStep::REV_CA != 0 {
                [a, c]
            } else {
                [c, a]
            };
            defined[e_ca] = true;
        }
        known.push(e_bc);
        known.push(e_ca);
        embed.push(EmbedStep {
            a,
            b,
            c,
            e_ab: e_ab as u32,
            e_bc: e_bc as u32,
            e_ca: e_ca as u32,
            flags,
        });
        (prev_bc, prev_ca) = (e_bc as u32, e_ca as u32);
    }
    let at = r.pos;
    let n_rest = r.u32()?;
    if defined.iter().filter(|&&d| !d).count() != n_rest as usize {
        return Err(malformed(
            at,
            "the count of edge slots outside the walk does not match",
        ));
    }
    for (edge, &d) in edges.iter_mut().zip(&defined) {
        if !d {
            *edge = [r.u32()?, r.u32()?];
        }
    }
    Ok(Layout {
        edges,
        n_iter_edges,
        embed_root: EmbedRoot {
            p0,
            p1,
            edge: root_edge as u32,
        },
        embed,
    })
}

/// Section 2 (and section 5, the same encoding): a count, then each value as a Δ from the
/// previous one.
fn decode_unknowns(r: &mut Reader) -> Result<Vec<u32>, LoadError> {
    let n = r.count(1)?;
    let mut out = Vec::with_capacity(n);
    let mut prev = 0;
    for _ in 0..n {
        prev = r.delta(prev)?;
        out.push(prev);
    }
    Ok(out)
}

/// Section 3: the number of temporaries and the stream.
fn decode_iteration(r: &mut Reader) -> Result<(u32, Vec<u16>), LoadError> {
    let n_temps = r.u32()?;
    let n = r.count(1)?;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let at = r.pos;
        let word = r.varint()?;
        out.push(u16::try_from(word).map_err(|_| malformed(at, "an iteration word above 65535"))?);
    }
    Ok((n_temps, out))
}

/// Section 4.
fn decode_hessian(r: &mut Reader) -> Result<HessianPattern, LoadError> {
    let dim = r.count(1)?;
    let mut col_ptr = Vec::with_capacity(dim + 1);
    let mut row_idx = Vec::with_capacity(dim);
    col_ptr.push(0u32);
    let mut last = 0u32;
    for k in 0..dim {
        let at = r.pos;
        let below = r.u32()?;
        // The diagonal, then the rows below it; each of those takes a byte at least.
        let k = k as u32;
        row_idx.push(k);
        let mut prev = k;
        for _ in 0..below {
            let at = r.pos;
            let code = r.varint()?;
            let row = if code & 1 == 0 {
                i64::from(prev).checked_add(1 + (code >> 1) as i64)
            } else {
                i64::from(last).checked_add(unzigzag(code >> 1))
            };
            prev = row
                .and_then(|row| u32::try_from(row).ok())
                .ok_or_else(|| malformed(at, TOO_LARGE))?;
            row_idx.push(prev);
        }
        last = prev;
        let end = u32::try_from(row_idx.len()).map_err(|_| malformed(at, TOO_LARGE))?;
        col_ptr.push(end);
    }
    Ok(HessianPattern { col_ptr, row_idx })
}

/// Reads the varints of one section (or of the section list), up to the end of `bytes`;
/// offsets in errors are offsets in the file.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl Reader<'_> {
    fn byte(&mut self) -> Result<u8, LoadError> {
        let b = *self
            .bytes
            .get(self.pos)
            .ok_or_else(|| malformed(self.pos, ENDS_INSIDE))?;
        self.pos += 1;
        Ok(b)
    }

    /// A canonical LEB128 varint of at most 64 bits.
    #[inline]
    fn varint(&mut self) -> Result<u64, LoadError> {
        // Most values take one byte.
        match self.bytes.get(self.pos) {
            Some(&b) if b < 0x80 => {
                self.pos += 1;
                Ok(u64::from(b))
            }
            _ => self.long_varint(),
        }
    }

    fn long_varint(&mut self) -> Result<u64, LoadError> {
        let at = self.pos;
        let mut x = 0u64;
        for i in 0..10 {
            let b = self.byte()?;
            x |= u64::from(b & 0x7F) << (7 * i);
            if b & 0x80 == 0 {
                // Overlong (a final zero group), or bits above the 64th.
                if (b == 0 && i > 0) || (i == 9 && b > 1) {
                    break;
                }
                return Ok(x);
            }
        }
        Err(LoadError::BadVarint { offset: at as u64 })
    }

    fn u32(&mut self) -> Result<u32, LoadError> {
        let at = self.pos;
        u32::try_from(self.varint()?).map_err(|_| malformed(at, TOO_LARGE))
    }

    /// A count of elements taking at least `min_bytes` bytes each, checked against the bytes
    /// left before anything is sized by it.
    fn count(&mut self, min_bytes: usize) -> Result<usize, LoadError> {
        let at = self.pos;
        let n = self.u32()? as usize;
        let left = self.bytes.len().saturating_sub(self.pos);
        if n > left / min_bytes {
            return Err(malformed(at, TOO_MANY));
        }
        Ok(n)
    }

    /// A value stored as a zigzag difference from `prev`.
    fn delta(&mut self, prev: u32) -> Result<u32, LoadError> {
        let at = self.pos;
        let d = unzigzag(self.varint()?);
        i64::from(prev)
            .checked_add(d)
            .and_then(|x| u32::try_from(x).ok())
            .ok_or_else(|| malformed(at, TOO_LARGE))
    }

    /// An edge slot below `n_edges`, stored as a zigzag difference from `prev`.
    fn slot(&mut self, prev: u32, n_edges: usize) -> Result<usize, LoadError> {
        let at = self.pos;
        let slot = self.delta(prev)? as usize;
        if slot >= n_edges {
            return Err(malformed(at, BAD_SLOT));
        }
        Ok(slot)
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

    /// Varints, for building sections by hand.
    fn varints(values: &[u64]) -> Vec<u8> {
        let mut out = Vec::new();
        for &x in values {
            put(&mut out, x);
        }
        out
    }

    /// The sections of a valid file: tag and payload.
    fn sections(bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
        let content = &bytes[..bytes.len() - CHECKSUM_LEN];
        let mut r = Reader {
            bytes: content,
            pos: HEADER_LEN,
        };
        let mut out = Vec::new();
        while r.pos < content.len() {
            let tag = r.byte().expect("tag");
            let len = r.varint().expect("length") as usize;
            out.push((tag, content[r.pos..r.pos + len].to_vec()));
            r.pos += len;
        }
        out
    }

    /// A file with `bytes`' header (its length corrected) and these sections, sealed with a
    /// valid checksum, as a forger (or a buggy writer) would make it.
    fn forge(bytes: &[u8], sections: &[(u8, Vec<u8>)]) -> Vec<u8> {
        let mut out = bytes[..HEADER_LEN].to_vec();
        for (tag, payload) in sections {
            out.push(*tag);
            put(&mut out, payload.len() as u64);
            out.extend_from_slice(payload);
        }
        reseal(&mut out);
        out
    }

    /// Appends a valid checksum to `content` after setting its length.
    fn reseal(content: &mut Vec<u8>) {
        let len = (content.len() + CHECKSUM_LEN) as u64;
        content[LENGTH_AT..LENGTH_AT + 8].copy_from_slice(&len.to_le_bytes());
        let crc = crc32c(content);
        content.extend_from_slice(&crc.to_le_bytes());
    }

    /// `forge` with section `tag`'s payload replaced.
    fn with_section(bytes: &[u8], tag: u8, payload: Vec<u8>) -> Vec<u8> {
        let mut s = sections(bytes);
        s[usize::from(tag) - 1].1 = payload;
        forge(bytes, &s)
    }

    fn malformed_what(result: Result<(Program, MeshKey), LoadError>) -> &'static str {
        match result {
            Err(LoadError::Malformed { what, .. }) => what,
            other => panic!("not Malformed: {other:?}"),
        }
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
    fn an_ordering_travels_in_section_5() {
        let (program, key) = hexagon();
        let mut parts = program.to_parts();
        assert_eq!(parts.ordering, None);
        parts.ordering = Some(vec![0]);
        let ordered = Program::from_parts(parts).expect("valid");
        let bytes = ordered.to_bytes(&key);
        let sizes = ordered.file_sizes();
        assert!(sizes.ordering > 0 && sizes.total() == bytes.len());
        assert_eq!(Program::from_bytes(&bytes), Ok((ordered, key)));
        assert_eq!(program.file_sizes().ordering, 0);
    }

    #[test]
    fn round_trip_and_layout() {
        let (program, key) = hexagon();
        let bytes = program.to_bytes(&key);
        let sizes = program.file_sizes();
        assert_eq!(bytes.len(), sizes.total());
        assert_eq!((sizes.header, sizes.checksum), (HEADER_LEN, CHECKSUM_LEN));
        assert_eq!(program.stats().file_bytes, bytes.len());
        assert_eq!(&bytes[..8], b"BDMORPH\0");
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4"));
        let long = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8"));
        assert_eq!([word(8), word(20), word(24)], [2, 7, 6]);
        assert_eq!(long(12), bytes.len() as u64);
        assert_eq!(long(28), key.faces_hash);
        let s = sections(&bytes);
        assert_eq!(s.iter().map(|x| x.0).collect::<Vec<_>>(), [1, 2, 3, 4]);
        let framed = |i: usize| 1 + varint_len(s[i].1.len() as u64) as usize + s[i].1.len();
        assert_eq!(
            [sizes.layout, sizes.unknowns, sizes.iteration, sizes.hessian],
            [framed(0), framed(1), framed(2), framed(3)]
        );
        // Layout: 12 slots, all written by the stream, 6 steps; the root 0 -> 1 through slot 0;
        // the first step (0, 1, 2) through slot 0 (skip 0), flags REV_CA | PLACE, slots 1 and
        // 2, and its new vertex 2.
        assert_eq!(s[0].1[..11], [12, 12, 6, 0, 1, 0, 0, 12, 2, 4, 4]);
        assert_eq!(s[1].1, [1, 0]); // one unknown, vertex 0
        assert_eq!(s[2].1[..3], [18, program.iteration().len() as u8, 2]);
        assert_eq!(s[3].1, [1, 0]); // one column, nothing below the diagonal
        let (back, back_key) = Program::from_bytes(&bytes).expect("loads");
        assert_eq!(back, program);
        assert_eq!(back_key, key);
        // Deterministic.
        assert_eq!(back.to_bytes(&back_key), bytes);
    }

    /// The hexagon's steps in another valid order (the walk goes around, then back to the
    /// first edge), and an edge slot that no triangle has: the file holds any valid program,
    /// not only breadth-first ones.
    #[test]
    fn any_valid_program_round_trips() {
        let mut parts = hexagon_parts();
        let s = parts.embed.clone();
        let mut last = s[5];
        last.flags |= EmbedStep::PLACE;
        let mut fifth = s[4];
        fifth.flags &= !EmbedStep::PLACE;
        parts.embed = vec![s[0], s[1], s[3], last, s[2], fifth];
        parts.edges.push([1, 3]);
        let program = Program::from_parts(parts).expect("valid");
        let key = MeshKey::of(7, &[]);
        let key = MeshKey { n_faces: 6, ..key };
        let bytes = program.to_bytes(&key);
        // The fifth step goes back to the root edge: skip -7.
        let layout = &sections(&bytes)[0].1;
        assert_eq!(layout[..3], [13, 12, 6]);
        assert_eq!(Program::from_bytes(&bytes), Ok((program, key)));
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
                match at {
                    0..=7 => assert_eq!(err, LoadError::BadMagic),
                    8..=11 => assert!(matches!(err, LoadError::UnsupportedVersion { .. })),
                    12..=19 => assert!(
                        matches!(
                            err,
                            LoadError::Truncated { .. } | LoadError::TrailingBytes { .. }
                        ),
                        "byte {at} ^ {mask:#x}: {err}"
                    ),
                    // Past the stated length, damage can only be caught by the checksum.
                    _ => assert!(
                        matches!(err, LoadError::ChecksumMismatch { .. }),
                        "byte {at} ^ {mask:#x}: {err}"
                    ),
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
        // A header stating a length shorter than any file.
        let mut short = bytes[..HEADER_LEN].to_vec();
        short[LENGTH_AT..LENGTH_AT + 8].copy_from_slice(&(HEADER_LEN as u64).to_le_bytes());
        assert!(matches!(
            Program::from_bytes(&short),
            Err(LoadError::Truncated {
                needed: 40,
                available: 36
            })
        ));
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
        // Version 1 (fixed-width records) is refused like any other: compile the mesh again.
        for version in [0, 1, 3, u32::MAX] {
            let mut newer = bytes.clone();
            newer[8..12].copy_from_slice(&u32::to_le_bytes(version));
            // Even with a header this build cannot parse.
            newer.truncate(14);
            let err = Program::from_bytes(&newer).expect_err("refused");
            assert_eq!(
                err,
                LoadError::UnsupportedVersion {
                    found: version,
                    supported: 2
                }
            );
            assert!(err.to_string().contains(&format!("version {version}")));
        }
    }

    #[test]
    fn bad_varints_are_refused() {
        let (program, key) = hexagon();
        let bytes = program.to_bytes(&key);
        let unknowns = |payload: &[u8]| with_section(&bytes, 2, payload.to_vec());
        // The unknowns' payload starts at byte 36 + the layout section + tag and length.
        let at = (HEADER_LEN + program.file_sizes().layout + 2) as u64;
        for payload in [
            &[1, 0x80, 0x00][..],   // overlong 0
            &[1, 0x81, 0x80, 0x00], // overlong 1
            &[
                1, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x02,
            ], // 65 bits
            &[
                1, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x81, 0x00,
            ], // 11 bytes
        ] {
            assert_eq!(
                Program::from_bytes(&unknowns(payload)),
                Err(LoadError::BadVarint { offset: at + 1 }),
                "{payload:x?}"
            );
        }
        // The largest varint is read (and refused as a vertex), the smallest is fine.
        let max = [
            1, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x01,
        ];
        assert_eq!(
            malformed_what(Program::from_bytes(&unknowns(&max))),
            TOO_LARGE
        );
        assert!(Program::from_bytes(&unknowns(&[1, 0])).is_ok());
        // Inside the section framing too.
        let mut b = bytes[..HEADER_LEN].to_vec();
        b.extend_from_slice(&[1, 0x80, 0x80, 0x00]);
        reseal(&mut b);
        assert_eq!(
            Program::from_bytes(&b),
            Err(LoadError::BadVarint { offset: 37 })
        );
    }

    #[test]
    fn sections_must_be_present_once_in_order_and_read_to_their_end() {
        let (program, key) = hexagon();
        let bytes = program.to_bytes(&key);
        let s = sections(&bytes);
        let what = |sections: &[(u8, Vec<u8>)]| {
            malformed_what(Program::from_bytes(&forge(&bytes, sections)))
        };
        assert_eq!(what(&s[..3]), "a required section is missing");
        assert_eq!(what(&[]), "a required section is missing");
        let mut swapped = s.clone();
        swapped.swap(1, 2);
        assert_eq!(what(&swapped), "a section is repeated or out of order");
        let mut twice = s.clone();
        twice.insert(2, s[1].clone());
        assert_eq!(what(&twice), "a section is repeated or out of order");
        for tag in [0, 6, 255] {
            let mut extra = s.clone();
            extra.push((tag, vec![]));
            let expected = if tag == 0 {
                "a section is repeated or out of order"
            } else {
                "a section this version does not know"
            };
            assert_eq!(what(&extra), expected);
        }
        let mut longer = s.clone();
        longer[3].1.push(0);
        assert_eq!(what(&longer), "a section has bytes after its content");
        let mut shorter = s.clone();
        shorter[0].1.pop();
        assert_eq!(what(&shorter), ENDS_INSIDE);
        // A section length past the end of the file.
        let mut b = bytes[..HEADER_LEN].to_vec();
        b.extend_from_slice(&[1, 100, 0]);
        reseal(&mut b);
        assert_eq!(
            Program::from_bytes(&b),
            Err(LoadError::Malformed {
                offset: 36,
                what: "a section runs past the end of the file"
            })
        );
    }

    #[test]
    fn resealed_nonsense_is_refused_without_large_allocations() {
        let (program, key) = hexagon();
        let bytes = program.to_bytes(&key);
        let s = sections(&bytes);
        // Counts claiming billions of entries: refused by the bytes left in their section
        // before anything is sized by them. (tests/fuzz.rs measures the allocations.)
        let huge = [u64::from(u32::MAX), 1 << 40, u64::MAX];
        for count in huge {
            for (tag, payload) in [
                (1, varints(&[count, 12, 6])),
                (1, varints(&[1, 0, count])),
                (2, varints(&[count, 0])),
                (3, varints(&[18, count, 1])),
                (4, varints(&[count, 0])),
            ] {
                let what = malformed_what(Program::from_bytes(&with_section(&bytes, tag, payload)));
                let expected = if count > u64::from(u32::MAX) {
                    TOO_LARGE
                } else {
                    TOO_MANY
                };
                assert_eq!(what, expected, "section {tag}, count {count}");
            }
        }
        // A column claiming 2^32 - 1 rows below the diagonal runs out of bytes.
        let what = malformed_what(Program::from_bytes(&with_section(
            &bytes,
            4,
            varints(&[1, u64::from(u32::MAX)]),
        )));
        assert_eq!(what, ENDS_INSIDE);
        // Values out of range.
        let forged = |tag: u8, payload: Vec<u8>| {
            malformed_what(Program::from_bytes(&with_section(&bytes, tag, payload)))
        };
        assert_eq!(
            forged(3, varints(&[18, 1, 1 << 16])),
            "an iteration word above 65535"
        );
        // Vertex 0 - 1, and row 0 + unzigzag(1) = -1 (the code 2 zigzag(-1) + 1 = 3).
        assert_eq!(forged(2, varints(&[1, 1])), TOO_LARGE);
        assert_eq!(forged(4, varints(&[1, 1, 3])), TOO_LARGE);
        // The layout: the root's slot, its orientation, a step's entry and slots, the count
        // of slots outside the walk.
        let n = s[0].1.len();
        let mut layout = s[0].1.clone();
        let mut edit = |at: usize, x: u8| {
            let old = layout[at];
            layout[at] = x;
            let what = malformed_what(Program::from_bytes(&with_section(
                &bytes,
                1,
                layout.clone(),
            )));
            layout[at] = old;
            what
        };
        assert_eq!(edit(5, 12), BAD_SLOT); // root slot 12 of 12
        assert_eq!(edit(6, 2), "a root orientation other than 0 or 1");
        assert_eq!(
            edit(7, 16 + 12),
            "a step enters through an edge that is not known yet"
        );
        assert_eq!(
            edit(7, 32 + 12),
            "a step enters through an edge that is not known yet"
        );
        assert_eq!(edit(8, 24), BAD_SLOT); // e_bc = 12
        assert_eq!(edit(9, 24), BAD_SLOT); // e_ca = 12
        assert_eq!(
            edit(n - 1, 1),
            "the count of edge slots outside the walk does not match"
        );
        // A vertex count of 2^32 - 1 would make the verifier allocate 16 GB per-vertex tables.
        let mut b = bytes[..bytes.len() - CHECKSUM_LEN].to_vec();
        b[20..24].copy_from_slice(&u32::MAX.to_le_bytes());
        reseal(&mut b);
        assert!(matches!(
            Program::from_bytes(&b),
            Err(LoadError::Verify(VerifyError::Sizes { .. }))
        ));
        // A new vertex that does not exist, with a valid checksum: the verifier refuses the
        // edge slot it makes.
        let mut layout = s[0].1.clone();
        layout[10] = 2 * 50; // c = 50
        let err = Program::from_bytes(&with_section(&bytes, 1, layout)).expect_err("refused");
        assert_eq!(err, LoadError::Verify(VerifyError::BadEdge { slot: 1 }));
        assert_eq!(err.to_string(), "invalid program: edge slot 1 is invalid");
    }

    #[test]
    fn messages_are_one_line() {
        let errors = [
            LoadError::BadMagic,
            LoadError::UnsupportedVersion {
                found: 1,
                supported: 2,
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
            LoadError::BadVarint { offset: 40 },
            LoadError::Malformed {
                offset: 40,
                what: TOO_MANY,
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
        assert_eq!(
            LoadError::Malformed {
                offset: 40,
                what: TOO_MANY
            }
            .to_string(),
            "malformed program file at byte 40: a count exceeds what the rest of its section can hold"
        );
    }

    #[test]
    fn varint_lengths_and_zigzag() {
        for (x, len) in [
            (0, 1),
            (127, 1),
            (128, 2),
            (16_383, 2),
            (16_384, 3),
            (u64::MAX, 10),
        ] {
            assert_eq!(varint_len(x), len);
            assert_eq!(varints(&[x]).len(), len as usize);
            let bytes = varints(&[x]);
            let mut r = Reader {
                bytes: &bytes,
                pos: 0,
            };
            assert_eq!(r.varint(), Ok(x));
        }
        for x in [0, -1, 1, -2, 2, i64::MIN, i64::MAX, -(1 << 32), 1 << 32] {
            assert_eq!(unzigzag(zigzag(x)), x);
        }
        assert_eq!([zigzag(0), zigzag(-1), zigzag(1), zigzag(-2)], [0, 1, 2, 3]);
    }

    #[test]
    #[should_panic(expected = "is not the key of this program's mesh")]
    fn writing_with_another_mesh_key_panics() {
        let (program, _) = hexagon();
        let _ = program.to_bytes(&MeshKey::of(8, &[[0, 1, 2]]));
    }
}
