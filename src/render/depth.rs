//! Depth files: the draw order of a mesh's triangles, for pictures of poses that overlap
//! themselves. A text file of whole numbers (levels from -9 to 9, higher drawn in front),
//! separated by white space, `#` starting a comment to the end of its line: one per face, or
//! one per vertex (a face then takes the highest level of its corners, so a part painted in
//! front keeps its border triangles in front too).
//!
//! ```
//! use bdmorph::render::depth::{parse_depth, DepthError};
//! let faces = [[0, 1, 2], [0, 2, 3]];
//! // Per face.
//! assert_eq!(parse_depth("1 -2", 4, &faces)?, vec![1, -2]);
//! // Per vertex: a face takes its highest corner.
//! assert_eq!(parse_depth("# levels\n0 0 3 0\n", 4, &faces)?, vec![3, 3]);
//! assert!(matches!(parse_depth("1 2 3", 4, &faces), Err(DepthError::Count { .. })));
//! # Ok::<(), DepthError>(())
//! ```

/// The deepest level either way.
pub const MAX_LEVEL: i8 = 9;
/// The largest depth file read.
pub const MAX_DEPTH_FILE_BYTES: u64 = 64 << 20;

/// Why a depth file could not be used. Messages are one line and quote at most 20
/// characters of the file.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[non_exhaustive]
pub enum DepthError {
    /// A word that is not a whole number.
    #[error("line {line}: '{word}' is not a whole number")]
    NotANumber {
        /// The line (1-based).
        line: usize,
        /// The word (at most 20 characters).
        word: String,
    },
    /// A level beyond [`MAX_LEVEL`].
    #[error("line {line}: level {level} is not between -{MAX_LEVEL} and {MAX_LEVEL}")]
    Level {
        /// The line (1-based).
        line: usize,
        /// The level.
        level: i64,
    },
    /// Neither one level per face nor one per vertex.
    #[error("{found} levels: give one per face ({faces}) or one per vertex ({vertices})")]
    Count {
        /// Levels found (counting stops past the larger of the two).
        found: usize,
        /// The mesh's faces.
        faces: usize,
        /// The mesh's vertices.
        vertices: usize,
    },
    /// A face names a vertex beyond `vertices`.
    #[error("a face names vertex {vertex} of {vertices}")]
    Face {
        /// The vertex.
        vertex: u32,
        /// The vertex count.
        vertices: usize,
    },
}

/// The per-face levels of a depth file's `text` for a mesh of `vertices` vertices and
/// `faces`: one level per face when the file has as many as there are faces (also when that
/// is the vertex count), else one per vertex.
pub fn parse_depth(text: &str, vertices: usize, faces: &[[u32; 3]]) -> Result<Vec<i8>, DepthError> {
    let most = vertices.max(faces.len());
    let mut levels: Vec<i8> = Vec::with_capacity(most.min(text.len() / 2 + 1));
    let mut found = 0usize;
    for (l, line) in text.lines().enumerate() {
        let line_no = l + 1;
        let content = line.split('#').next().unwrap_or("");
        for word in content.split_whitespace() {
            let level: i64 = word.parse().map_err(|_| DepthError::NotANumber {
                line: line_no,
                word: word
                    .chars()
                    .take(20)
                    .flat_map(char::escape_default)
                    .collect(),
            })?;
            if level.unsigned_abs() > MAX_LEVEL.unsigned_abs() as u64 {
                return Err(DepthError::Level {
                    line: line_no,
                    level,
                });
            }
            found += 1;
            if found > most {
                return Err(DepthError::Count {
                    found,
                    faces: faces.len(),
                    vertices,
                });
            }
            levels.push(level as i8);
        }
    }
    if found == faces.len() {
        return Ok(levels);
    }
    if found != vertices {
        return Err(DepthError::Count {
            found,
            faces: faces.len(),
            vertices,
        });
    }
    faces
        .iter()
        .map(|f| {
            f.iter()
                .map(|&v| {
                    levels.get(v as usize).copied().ok_or(DepthError::Face {
                        vertex: v,
                        vertices,
                    })
                })
                .try_fold(i8::MIN, |top, l| l.map(|l| top.max(l)))
        })
        .collect()
}
