//! Reading Triangle's `.poly` files: vertices, segments, holes.
//!
//! The format (Shewchuk's Triangle): `#` starts a comment; blank lines are skipped.
//!
//! ```text
//! <vertices> <dimension = 2> <attributes> <boundary markers 0 or 1>
//! <vertex> <x> <y> [attributes] [marker]        (one line per vertex, numbered from 0 or 1)
//! <segments> <boundary markers 0 or 1>
//! <segment> <vertex> <vertex> [marker]           (one line per segment)
//! <holes>
//! <hole> <x> <y>                                 (a point inside each hole)
//! [<regions>, then <region> <x> <y> <attribute> [<max area>] lines: read and ignored]
//! ```
//!
//! The inside is what Triangle keeps: every region reachable from outside the convex hull or
//! from a hole point without crossing a segment is removed. A missing hole section counts as
//! no holes. Vertices in a separate `.node` file (a vertex count of 0) are not supported.

use super::error::{MeshingError, Place};
use super::outline::{Element, Inside, Outline};
use super::{in_range, MAX_OUTLINE_POINTS};

/// The non-empty lines of a `.poly` file, as (1-based line, fields).
struct Records<'a> {
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    last: usize,
}

impl<'a> Records<'a> {
    fn next(&mut self) -> Option<(usize, Vec<&'a str>)> {
        for (i, line) in self.lines.by_ref() {
            self.last = i + 1;
            let data = line.split('#').next().unwrap_or("");
            let fields: Vec<&str> = data.split_whitespace().collect();
            if !fields.is_empty() {
                return Some((i + 1, fields));
            }
        }
        None
    }

    /// The next record, or an error saying what was expected.
    fn expect(&mut self, what: &str) -> Result<(usize, Vec<&'a str>), MeshingError> {
        self.next().ok_or_else(|| {
            error(
                self.last.max(1),
                format!("the file ends where {what} was expected"),
            )
        })
    }
}

fn error(line: usize, message: String) -> MeshingError {
    MeshingError::Poly {
        place: Place::line(Some(line)),
        message,
    }
}

/// A field as quoted in a message: at most 40 characters, control characters escaped.
fn shown(text: &str) -> String {
    let head: String = text.chars().take(40).collect();
    let more = if text.chars().nth(40).is_some() {
        "..."
    } else {
        ""
    };
    format!("{}{more}", head.escape_debug())
}

fn integer(line: usize, field: Option<&&str>, what: &str) -> Result<i64, MeshingError> {
    let text =
        field.ok_or_else(|| error(line, format!("expected {what}, found the end of the line")))?;
    text.parse().map_err(|_| {
        error(
            line,
            format!("expected {what} (an integer), found '{}'", shown(text)),
        )
    })
}

fn number(line: usize, field: Option<&&str>, what: &str) -> Result<f64, MeshingError> {
    let text =
        field.ok_or_else(|| error(line, format!("expected {what}, found the end of the line")))?;
    match text.parse::<f64>() {
        Ok(x) if x.is_finite() && in_range(x) => Ok(x),
        Ok(x) if x.is_finite() => Err(MeshingError::OutOfRange {
            place: Place::line(Some(line)),
            what: what.to_string(),
            value: x,
        }),
        _ => Err(error(
            line,
            format!("expected {what} (a finite number), found '{}'", shown(text)),
        )),
    }
}

/// Refuses a count of records (`what`, declared on `line`) larger than the lines left after
/// it can hold (one record a line): nothing is reserved for records the file does not have.
fn fits(line: usize, n: usize, total_lines: usize, what: &str) -> Result<(), MeshingError> {
    let left = total_lines.saturating_sub(line);
    if n > left {
        return Err(error(
            line,
            format!("{n} {what} declared, but only {left} lines follow"),
        ));
    }
    Ok(())
}

fn count(line: usize, field: Option<&&str>, what: &str) -> Result<usize, MeshingError> {
    let n = integer(line, field, what)?;
    usize::try_from(n).map_err(|_| error(line, format!("{what} is negative ({n})")))
}

/// Parses a `.poly` file's text into an outline with [`Inside::HolePoints`]. Messages name
/// the line (add the file with [`MeshingError::in_file`]).
///
/// ```
/// // A square with a square hole.
/// let text = "8 2 0 0\n\
///     1 0 0\n2 4 0\n3 4 4\n4 0 4\n5 1 1\n6 3 1\n7 3 3\n8 1 3\n\
///     8 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n5 5 6\n6 6 7\n7 7 8\n8 8 5\n\
///     1\n1 2 2\n";
/// let outline = bdmorph::meshing::parse_poly(text)?;
/// assert_eq!((outline.vertices.len(), outline.segments.len()), (8, 8));
/// let meshed = bdmorph::meshing::mesh_outline(&outline, &Default::default())?;
/// assert_eq!((meshed.stats.pieces, meshed.stats.holes), (1, 1));
/// # Ok::<(), bdmorph::meshing::MeshingError>(())
/// ```
///
/// # Errors
/// [`MeshingError::Poly`] for malformed lines, vertices not numbered consecutively from 0 or
/// 1, segments naming a vertex that does not exist, a dimension other than 2, or no vertices
/// (a separate `.node` file); [`MeshingError::NoOutline`] without segments.
pub fn parse_poly(text: &str) -> Result<Outline, MeshingError> {
    let mut records = Records {
        lines: text.lines().enumerate(),
        last: 0,
    };
    let total_lines = text.lines().count();
    let Some((line, header)) = records.next() else {
        return Err(MeshingError::NoOutline {
            place: Place::default(),
            what: "the file is empty",
        });
    };
    let nv = count(line, header.first(), "the number of vertices")?;
    if nv == 0 {
        return Err(error(
            line,
            "0 vertices: the vertices are in a separate .node file, which is not supported; put them in the .poly file".into(),
        ));
    }
    if header.len() > 1 {
        let dim = integer(line, header.get(1), "the dimension")?;
        if dim != 2 {
            return Err(error(line, format!("dimension {dim}: only 2 is supported")));
        }
    }
    fits(line, nv, total_lines, "vertices")?;
    if nv > MAX_OUTLINE_POINTS {
        return Err(MeshingError::TooManyPoints {
            place: Place::line(Some(line)),
            what: "the outline".into(),
            points: nv as u64,
            limit: MAX_OUTLINE_POINTS,
            tolerance_helps: false,
        });
    }
    let mut vertices = Vec::with_capacity(nv);
    let mut base = 0;
    for k in 0..nv {
        let (line, f) = records.expect(&format!("vertex {} of {nv}", k + 1))?;
        let index = integer(line, f.first(), "a vertex number")?;
        if k == 0 {
            if index != 0 && index != 1 {
                return Err(error(
                    line,
                    format!(
                        "the first vertex is numbered {index}; vertices are numbered from 0 or 1"
                    ),
                ));
            }
            base = index;
        } else if index != base + k as i64 {
            return Err(error(
                line,
                format!("vertex numbered {index}, expected {}", base + k as i64),
            ));
        }
        let x = number(line, f.get(1), "the vertex's x")?;
        let y = number(line, f.get(2), "the vertex's y")?;
        vertices.push([x, y]);
    }
    let (line, f) = records.expect("the number of segments")?;
    let ns = count(line, f.first(), "the number of segments")?;
    if ns == 0 {
        return Err(MeshingError::NoOutline {
            place: Place::line(Some(line)),
            what: "0 segments (a .poly outline needs segments around the shape)",
        });
    }
    fits(line, ns, total_lines, "segments")?;
    let last = base + nv as i64 - 1;
    let mut segments = Vec::with_capacity(ns);
    let mut labels = Vec::with_capacity(ns);
    let mut elements = Vec::with_capacity(ns);
    for k in 0..ns {
        let (line, f) = records.expect(&format!("segment {} of {ns}", k + 1))?;
        let index = integer(line, f.first(), "a segment number")?;
        let mut ends = [0u32; 2];
        for (e, end) in ends.iter_mut().enumerate() {
            let v = integer(line, f.get(1 + e), "a vertex number")?;
            if !(base..=last).contains(&v) {
                return Err(error(
                    line,
                    format!("segment {index} refers to vertex {v}, but the vertices are numbered {base} to {last}"),
                ));
            }
            *end = (v - base) as u32;
        }
        segments.push(ends);
        labels.push([k as u32, 0]);
        elements.push(Element {
            name: format!("segment {index}"),
            line: Some(line),
        });
    }
    let mut holes = Vec::new();
    if let Some((line, f)) = records.next() {
        let nh = count(line, f.first(), "the number of holes")?;
        fits(line, nh, total_lines, "holes")?;
        for k in 0..nh {
            let (line, f) = records.expect(&format!("hole {} of {nh}", k + 1))?;
            integer(line, f.first(), "a hole number")?;
            let x = number(line, f.get(1), "the hole's x")?;
            let y = number(line, f.get(2), "the hole's y")?;
            holes.push([x, y]);
        }
    }
    Ok(Outline {
        vertices,
        segments,
        inside: Inside::HolePoints(holes),
        texture_frame: None,
        labels,
        elements,
        flip_y: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const SQUARE: &str = "# a unit square\n4 2 0 1\n0 0 0 1\n1 1 0 1\n2 1 1 1\n3 0 1 1\n\n4 1\n0 0 1 1\n1 1 2 1\n2 2 3 1\n3 3 0 1\n0\n";

    #[test]
    fn reads_a_square_numbered_from_zero() {
        let o = parse_poly(SQUARE).expect("a square");
        assert_eq!(o.vertices, [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        assert_eq!(o.segments, [[0, 1], [1, 2], [2, 3], [3, 0]]);
        assert_eq!(o.inside, Inside::HolePoints(vec![]));
        assert_eq!(o.elements[2].line, Some(11));
    }

    #[test]
    fn a_missing_hole_section_is_no_holes() {
        let text = SQUARE
            .trim_end()
            .strip_suffix('0')
            .expect("ends with the hole count");
        assert_eq!(
            parse_poly(text).expect("no holes").inside,
            Inside::HolePoints(vec![])
        );
    }

    #[test]
    fn errors_name_their_line() {
        let cases = [
            (SQUARE.replace("1 1 2 1", "1 1 7 1"), "line 10: segment 1 refers to vertex 7, but the vertices are numbered 0 to 3"),
            (SQUARE.replace("2 1 1 1", "2 1 x 1"), "line 5: expected the vertex's y (a finite number), found 'x'"),
            (SQUARE.replace("2 1 1 1", "5 1 1 1"), "line 5: vertex numbered 5, expected 2"),
            (SQUARE.replace("4 2 0 1", "4 3 0 1"), "line 2: dimension 3: only 2 is supported"),
            (SQUARE.replace("4 2 0 1", "0 2 0 1"), "line 2: 0 vertices: the vertices are in a separate .node file, which is not supported; put them in the .poly file"),
            ("4 2 0 0\n1 0 0\n2 1 0\n".to_owned(), "line 1: 4 vertices declared, but only 2 lines follow"),
        ];
        for (text, message) in cases {
            assert_eq!(parse_poly(&text).unwrap_err().to_string(), message);
        }
    }
}
