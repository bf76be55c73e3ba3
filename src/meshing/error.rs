//! Why an input cannot be meshed: one typed error per cause, each shown as one line that names
//! the file (and the line, when there is one).

use std::fmt;
use std::path::PathBuf;

use crate::render::raster::RenderError;

/// Where in an input an error is: the file, when the input came from one, and the 1-based
/// line, when the error is about one. Shown as `FILE:LINE: `, `FILE: `, or nothing.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Place {
    /// The file.
    pub path: Option<PathBuf>,
    /// The 1-based line.
    pub line: Option<usize>,
}

impl Place {
    /// A place on a line of an input that has no file name yet (see [`MeshingError::in_file`]).
    pub fn line(line: Option<usize>) -> Place {
        Place { path: None, line }
    }
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.path, self.line) {
            (Some(p), Some(l)) => write!(f, "{}:{l}: ", p.display()),
            (Some(p), None) => write!(f, "{}: ", p.display()),
            (None, Some(l)) => write!(f, "line {l}: "),
            (None, None) => Ok(()),
        }
    }
}

/// How two segments of an outline meet where they should not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contact {
    /// They cross.
    Cross,
    /// One ends on the other (or they share a point without sharing a vertex).
    Touch,
    /// They lie on one line and overlap.
    Overlap,
}

impl fmt::Display for Contact {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Contact::Cross => "crosses",
            Contact::Touch => "touches",
            Contact::Overlap => "overlaps",
        })
    }
}

/// Why no subject was found in a picture.
#[derive(Clone, Debug, PartialEq)]
pub enum NoSubject {
    /// The picture has no pixels.
    Empty,
    /// Every pixel is at most this opaque (the threshold).
    Transparent {
        /// The opacity threshold, in [0, 1].
        threshold: f64,
    },
    /// No pixel differs from the background colour by more than the threshold.
    Background {
        /// The background colour.
        colour: [u8; 3],
        /// The colour-difference threshold, in [0, 1].
        threshold: f64,
    },
    /// No pixel is darker than the threshold.
    Bright {
        /// The brightness threshold, in [0, 1].
        threshold: f64,
    },
}

impl fmt::Display for NoSubject {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            NoSubject::Empty => f.write_str("the picture has no pixels"),
            NoSubject::Transparent { threshold } if threshold <= 0.0 => {
                f.write_str("the picture is fully transparent: nothing to mesh")
            }
            NoSubject::Transparent { threshold } => write!(
                f,
                "the picture is fully transparent (no pixel more opaque than --threshold {threshold}): nothing to mesh"
            ),
            NoSubject::Background { colour: [r, g, b], threshold } => write!(
                f,
                "no pixel differs from the background #{r:02x}{g:02x}{b:02x} by more than --threshold {threshold}: nothing to mesh"
            ),
            NoSubject::Bright { threshold } => write!(
                f,
                "no pixel is darker than --threshold {threshold}: nothing to mesh"
            ),
        }
    }
}

/// Why an input cannot be meshed. Every message is one line; errors about an input read from
/// a file start with its name (and the line, when there is one), e.g.
/// `star.svg:7: <path> crosses itself: its segment 3 crosses its segment 9 near (12.5, 40)`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshingError {
    /// The input file could not be read.
    #[error("{}: cannot read: {source}", .path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The input is neither a picture nor an outline file.
    #[error("{}: not a picture (.png, .jpg) or an outline (.poly, .svg)", .path.display())]
    UnknownInput {
        /// The file.
        path: PathBuf,
    },
    /// A picture could not be decoded (read from a file, the message names it).
    #[error(transparent)]
    Picture(#[from] RenderError),
    /// A picture's subject traces to so many loops, so long, that simplifying them would take
    /// time without bound (a noisy or half-transparent picture): refused right after tracing.
    #[error("{place}the subject traces to {loops} loops, the longest of {longest} points: over the {} (loops times points) an outline may have; noise, not a drawing: raise --threshold, or clean the picture's background", super::MAX_TRACE_WORK)]
    TooComplex {
        /// The file.
        place: Place,
        /// Loops traced.
        loops: usize,
        /// Points of the longest loop.
        longest: usize,
    },
    /// The picture is opaque everywhere and nothing says which pixels are the subject.
    #[error("{place}the picture has no transparent pixels: give --background COLOR (the colour around the subject: #rrggbb, a name, or auto for the colour of the picture's border) or --threshold L (the subject is the pixels darker than L, in [0, 1])")]
    NoTransparency {
        /// The file.
        place: Place,
    },
    /// The picture holds no subject.
    #[error("{place}{reason}")]
    NoSubject {
        /// The file.
        place: Place,
        /// Why.
        reason: NoSubject,
    },
    /// Every outline traced in a picture vanishes under the tolerance.
    #[error("{place}every outline is too small for the tolerance {tolerance} (the largest of {loops} encloses {largest_area:.3} square pixels, under ({tolerance} x 2)^2, or narrows to a line); lower --tolerance")]
    TooSmall {
        /// The file.
        place: Place,
        /// The number of outlines traced.
        loops: usize,
        /// The largest area one of them encloses.
        largest_area: f64,
        /// The tolerance.
        tolerance: f64,
    },
    /// One outline of an outline file vanishes under the tolerance.
    #[error("{place}{what} is too small for the tolerance {tolerance} (flattened, it encloses {area:.3e} square units, or narrows to a line); lower --tolerance or remove it")]
    LoopTooSmall {
        /// The file and the line of the element.
        place: Place,
        /// The element (`<path>`, `<circle>`, ...), and which of its closed parts.
        what: String,
        /// The area it encloses once flattened.
        area: f64,
        /// The tolerance.
        tolerance: f64,
    },
    /// Two segments of an outline cross, touch or overlap.
    #[error("{place}{first} {contact} {second} near ({}, {})", Num(.at[0]), Num(.at[1]))]
    SelfIntersection {
        /// The file and the line of the first segment.
        place: Place,
        /// The first segment, described (`segment 4 (line 12)`, `<path> segment 3`).
        first: String,
        /// The second segment, described likewise.
        second: String,
        /// How they meet.
        contact: Contact,
        /// Where, in the input's coordinates.
        at: [f64; 2],
    },
    /// A segment whose two ends are at the same place.
    #[error("{place}{segment} has zero length (both ends at ({}, {}))", Num(.at[0]), Num(.at[1]))]
    ZeroLength {
        /// The file and the line of the segment.
        place: Place,
        /// The segment, described.
        segment: String,
        /// Where, in the input's coordinates.
        at: [f64; 2],
    },
    /// A malformed `.poly` file, or one whose segments refer to missing vertices.
    #[error("{place}{message}")]
    Poly {
        /// The file and the line.
        place: Place,
        /// What is wrong.
        message: String,
    },
    /// A malformed or unsupported SVG file.
    #[error("{place}{message}")]
    Svg {
        /// The file and the line.
        place: Place,
        /// What is wrong.
        message: String,
    },
    /// The input holds no outline at all.
    #[error("{place}no outline to mesh: {what}")]
    NoOutline {
        /// The file.
        place: Place,
        /// What was looked for.
        what: &'static str,
    },
    /// The outline encloses no area (the hole points of a `.poly` file remove every region,
    /// or every loop is flat).
    #[error("{place}no region is left inside the outline{}", if *.hole_points { " (the hole points remove every region)" } else { "" })]
    NothingInside {
        /// The file.
        place: Place,
        /// Whether hole points removed regions.
        hole_points: bool,
    },
    /// A number of the input (a coordinate, a radius, a point after its transforms) is
    /// outside the range meshing supports: magnitudes up to [`super::MAX_COORDINATE`], and
    /// either 0 or at least [`super::MIN_COORDINATE`].
    #[error("{place}{what} is {}, outside the supported range (0, or magnitudes from {:e} to {:e})", Num(*.value), super::MIN_COORDINATE, super::MAX_COORDINATE)]
    OutOfRange {
        /// The file and the line.
        place: Place,
        /// What the number is (`<circle> r`, `vertex 3's x`, `<path> point (after transforms)`).
        what: String,
        /// The number.
        value: f64,
    },
    /// An outline would have more points than [`super::MAX_OUTLINE_POINTS`] (curves flattened
    /// to the tolerance, or a `.poly` file's vertices).
    #[error("{place}{what} would have about {points} points, more than the limit of {limit}{}", if *.tolerance_helps { "; raise --tolerance for fewer" } else { "" })]
    TooManyPoints {
        /// The file and the line.
        place: Place,
        /// What (`<path>`, `the outline`).
        what: String,
        /// About how many points.
        points: u64,
        /// The limit.
        limit: usize,
        /// Whether a larger tolerance gives fewer points (curves), or not (straight segments).
        tolerance_helps: bool,
    },
    /// The triangulation gave a triangle of (numerically) zero area, which the mesh readers
    /// refuse: the outline has a feature too thin for the precision of its coordinates.
    #[error("{place}the mesh would have a degenerate triangle (area {}) near ({}, {}): a feature of the outline is too thin there; widen it or remove it", Num(*.area), Num(.at[0]), Num(.at[1]))]
    Degenerate {
        /// The file.
        place: Place,
        /// The triangle's centroid, in the input's coordinates.
        at: [f64; 2],
        /// Its area.
        area: f64,
    },
    /// A meshing option is out of range.
    #[error("{option} {value}: {expected}")]
    BadOption {
        /// The option (`--vertices`, ...).
        option: &'static str,
        /// Its value.
        value: String,
        /// What it must be.
        expected: &'static str,
    },
    /// The triangulation failed on an input the checks accepted: a bug, not a property of the
    /// input.
    #[error("{place}internal error while triangulating: {message}")]
    Internal {
        /// The file.
        place: Place,
        /// What happened.
        message: String,
    },
}

impl MeshingError {
    /// The error with `path` as the file it is about (errors that already name a file keep it).
    pub fn in_file(mut self, path: impl Into<PathBuf>) -> MeshingError {
        let path = path.into();
        match &mut self {
            MeshingError::NoTransparency { place }
            | MeshingError::NoSubject { place, .. }
            | MeshingError::TooSmall { place, .. }
            | MeshingError::LoopTooSmall { place, .. }
            | MeshingError::SelfIntersection { place, .. }
            | MeshingError::ZeroLength { place, .. }
            | MeshingError::Poly { place, .. }
            | MeshingError::Svg { place, .. }
            | MeshingError::NoOutline { place, .. }
            | MeshingError::NothingInside { place, .. }
            | MeshingError::OutOfRange { place, .. }
            | MeshingError::TooManyPoints { place, .. }
            | MeshingError::TooComplex { place, .. }
            | MeshingError::Degenerate { place, .. }
            | MeshingError::Internal { place, .. } => {
                if place.path.is_none() {
                    place.path = Some(path);
                }
            }
            MeshingError::Read { .. }
            | MeshingError::UnknownInput { .. }
            | MeshingError::Picture(_)
            | MeshingError::BadOption { .. } => {}
        }
        self
    }

    /// The 1-based line of the input the error is on, when it is on one.
    pub fn line(&self) -> Option<usize> {
        match self {
            MeshingError::LoopTooSmall { place, .. }
            | MeshingError::SelfIntersection { place, .. }
            | MeshingError::ZeroLength { place, .. }
            | MeshingError::Poly { place, .. }
            | MeshingError::OutOfRange { place, .. }
            | MeshingError::TooManyPoints { place, .. }
            | MeshingError::Svg { place, .. } => place.line,
            _ => None,
        }
    }
}

/// A coordinate in a message: at most 6 significant digits.
pub(crate) struct Num(pub(crate) f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if x == 0.0 || !x.is_finite() {
            return write!(f, "{x}");
        }
        let digits = 5 - x.abs().log10().floor() as i32;
        if (0..=12).contains(&digits) {
            let s = format!("{x:.*}", digits as usize);
            let s = if s.contains('.') {
                s.trim_end_matches('0').trim_end_matches('.')
            } else {
                &s
            };
            f.write_str(s)
        } else {
            write!(f, "{x:.5e}")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_messages_are_short() {
        assert_eq!(Num(12.5).to_string(), "12.5");
        assert_eq!(Num(1.0 / 3.0).to_string(), "0.333333");
        assert_eq!(Num(-250.0).to_string(), "-250");
        assert_eq!(Num(1e-9).to_string(), "1.00000e-9");
    }

    #[test]
    fn places_name_the_file_and_line() {
        let e = MeshingError::Poly {
            place: Place::line(Some(4)),
            message: "segment 2 refers to vertex 9, but there are 4 vertices".into(),
        };
        assert_eq!(
            e.in_file("a.poly").to_string(),
            "a.poly:4: segment 2 refers to vertex 9, but there are 4 vertices"
        );
    }
}
