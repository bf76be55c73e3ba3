//! Reading outlines from SVG: `<path>`, `<polygon>`, `<polyline>`, `<rect>`, `<circle>` and
//! `<ellipse>`, with their `transform`s and their groups' `transform`s; curves and arcs
//! flattened to a tolerance.
//!
//! roxmltree (a small read-only XML tree that knows each node's line) reads the document and
//! kurbo parses path data (every command, arcs included), applies transforms and flattens
//! curves to polylines within the tolerance; usvg would have added a full SVG tree with CSS,
//! fonts and text layout, none of which an outline needs.
//!
//! Every closed part of every shape is one loop, closed implicitly as a fill would be (a
//! `<polyline>` too); shapes inside shapes are holes by nesting parity (even-odd), and shapes
//! may not overlap, touch or cross themselves. `<line>`, `<text>`, `<use>` and `<image>` are
//! ignored, as is what is inside `<defs>`, `<clipPath>`, `<mask>`, `<symbol>`, `<marker>` and
//! `<pattern>`, and elements with `display="none"`. Lengths are user units (numbers, or `px`);
//! other units are refused. SVG's y points down: the outline is flipped (`y' = bottom - y`,
//! `bottom` the `viewBox`'s lower edge, else the `height`, else the lowest point) so that the
//! picture stays upright with y up.

use kurbo::{Affine, BezPath, PathEl, Shape};

use super::error::{MeshingError, Place};
use super::outline::{bounds, crossings, twice_area, Element, Outline};
use super::{in_range, DEFAULT_OUTLINE_TOLERANCE, MAX_OUTLINE_POINTS};

/// Whether a closed loop's segments cross, touch or overlap one another.
fn crosses_itself(part: &[[f64; 2]]) -> bool {
    let n = part.len() as u32;
    let segments: Vec<[u32; 2]> = (0..n).map(|k| [k, (k + 1) % n]).collect();
    !crossings(part, &segments).is_empty()
}

fn error(line: Option<usize>, message: String) -> MeshingError {
    MeshingError::Svg {
        place: Place::line(line),
        message,
    }
}

/// Elements whose content is not drawn directly.
const NOT_DRAWN: [&str; 12] = [
    "defs",
    "clipPath",
    "mask",
    "symbol",
    "marker",
    "pattern",
    "style",
    "script",
    "linearGradient",
    "radialGradient",
    "filter",
    "metadata",
];

/// A number with an optional `px` unit.
fn length(text: &str) -> Option<f64> {
    let t = text.trim();
    let t = t.strip_suffix("px").unwrap_or(t).trim_end();
    t.parse::<f64>().ok().filter(|x| x.is_finite())
}

/// Scans the numbers of `text`, calling `f` on each. Strict (`lenient == false`): the text
/// is numbers separated by commas and/or white space (also `1-2` and `.5.5`, as SVG allows),
/// and anything else, or a number that is not finite, makes it `None`. Lenient: other
/// characters (path commands) are skipped, and a number too large for `f64` is passed on as
/// an infinity.
fn scan(text: &str, lenient: bool, mut f: impl FnMut(f64)) -> Option<()> {
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_whitespace() || b[i] == b',' {
            i += 1;
            continue;
        }
        let start = i;
        if b[i] == b'+' || b[i] == b'-' {
            i += 1;
        }
        let mut dot = false;
        let mut digits = false;
        while i < b.len() && (b[i].is_ascii_digit() || (b[i] == b'.' && !dot)) {
            dot |= b[i] == b'.';
            digits |= b[i].is_ascii_digit();
            i += 1;
        }
        if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
            let mut j = i + 1;
            if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
                j += 1;
            }
            if j < b.len() && b[j].is_ascii_digit() {
                i = j;
                while i < b.len() && b[i].is_ascii_digit() {
                    i += 1;
                }
            }
        }
        if lenient && !digits {
            i = start + 1;
            continue;
        }
        let x: f64 = text.get(start..i)?.parse().ok()?;
        if !x.is_finite() && !lenient {
            return None;
        }
        f(x);
    }
    Some(())
}

/// The numbers of a list separated by commas and/or white space (`points`, `viewBox`,
/// transform arguments); also splits `1-2` and `.5.5` as SVG allows.
fn numbers(text: &str) -> Option<Vec<f64>> {
    let mut out = Vec::new();
    scan(text, false, |x| out.push(x))?;
    Some(out)
}

/// `text` as quoted in a message: at most 40 characters, the rest elided.
fn excerpt(text: &str) -> String {
    match text.char_indices().nth(40) {
        Some((i, _)) => format!("{}...", &text[..i]),
        None => text.to_string(),
    }
}

/// Parses a `transform` attribute.
fn transform(full: &str) -> Result<Affine, String> {
    let mut total = Affine::IDENTITY;
    let mut rest = full.trim();
    let text = excerpt(full);
    while !rest.is_empty() {
        let open = rest
            .find('(')
            .ok_or_else(|| format!("transform '{text}': expected '('"))?;
        let close = rest
            .find(')')
            .ok_or_else(|| format!("transform '{text}': expected ')'"))?;
        if close < open {
            return Err(format!("transform '{text}': unbalanced parentheses"));
        }
        let name = rest[..open].trim().trim_start_matches(',').trim();
        let args = numbers(&rest[open + 1..close])
            .ok_or_else(|| format!("transform '{text}': bad numbers"))?;
        let bad = || {
            format!(
                "transform '{text}': {name} does not take {} numbers",
                args.len()
            )
        };
        let t = match (name, args.as_slice()) {
            ("matrix", &[a, b, c, d, e, f]) => Affine::new([a, b, c, d, e, f]),
            ("translate", &[x]) => Affine::translate((x, 0.0)),
            ("translate", &[x, y]) => Affine::translate((x, y)),
            ("scale", &[s]) => Affine::scale(s),
            ("scale", &[sx, sy]) => Affine::scale_non_uniform(sx, sy),
            ("rotate", &[a]) => Affine::rotate(a.to_radians()),
            ("rotate", &[a, cx, cy]) => Affine::rotate_about(a.to_radians(), (cx, cy)),
            ("skewX", &[a]) => Affine::skew(a.to_radians().tan(), 0.0),
            ("skewY", &[a]) => Affine::skew(0.0, a.to_radians().tan()),
            ("matrix" | "translate" | "scale" | "rotate" | "skewX" | "skewY", _) => {
                return Err(bad())
            }
            _ => {
                return Err(format!(
                    "transform '{text}': unknown transform '{}'",
                    excerpt(name)
                ))
            }
        };
        total *= t;
        rest = rest[close + 1..].trim_start();
    }
    Ok(total)
}

/// A shape of the document: its path (transformed) and where it is.
struct Drawn {
    name: String,
    line: usize,
    path: BezPath,
}

/// The attribute `name` of a shape as a length (0 when absent).
fn attr_length(node: roxmltree::Node, name: &str, line: usize) -> Result<f64, MeshingError> {
    match node.attribute(name) {
        None => Ok(0.0),
        Some(text) => {
            let x = length(text).ok_or_else(|| {
                error(
                    Some(line),
                    format!(
                        "<{}> {name}=\"{}\" is not a number in user units (other units are not supported)",
                        node.tag_name().name(),
                        excerpt(text)
                    ),
                )
            })?;
            if !in_range(x) {
                return Err(MeshingError::OutOfRange {
                    place: Place::line(Some(line)),
                    what: format!("<{}> {name}", node.tag_name().name()),
                    value: x,
                });
            }
            Ok(x)
        }
    }
}

/// Refuses path data or a points list with a number outside the coordinate range, or with
/// arcs that would turn into more cubic curves than [`MAX_OUTLINE_POINTS`] allows (kurbo
/// turns an arc into cubics at an absolute tolerance of 0.1, more of them the larger its
/// radius), before it is parsed.
fn check_numbers(text: &str, tag: &str, what: &str, line: usize) -> Result<(), MeshingError> {
    let (mut count, mut largest, mut bad) = (0u64, 0.0f64, None);
    let _ = scan(text, true, |x| {
        count += 1;
        largest = largest.max(x.abs());
        if bad.is_none() && !in_range(x) {
            bad = Some(x);
        }
    });
    if let Some(value) = bad {
        return Err(MeshingError::OutOfRange {
            place: Place::line(Some(line)),
            what: format!("<{tag}> {what}: a number"),
            value,
        });
    }
    if tag == "path" && text.contains(['a', 'A']) {
        // At least 3 numbers per arc (flags and coordinates may run together); kurbo's
        // cubics per full turn of an arc of radius r.
        let arcs = count / 3 + 1;
        let per_arc = (1.1163 * largest / 0.1).powf(1.0 / 6.0).max(4.0).ceil() as u64;
        let cubics = arcs.saturating_mul(per_arc);
        if cubics > 2 * MAX_OUTLINE_POINTS as u64 {
            return Err(MeshingError::TooManyPoints {
                place: Place::line(Some(line)),
                what: format!("<{tag}>'s arcs"),
                points: cubics,
                limit: MAX_OUTLINE_POINTS,
                tolerance_helps: false,
            });
        }
    }
    Ok(())
}

/// The path of a shape element in its own coordinates, `None` for elements that are not
/// shapes or draw nothing.
fn shape_path(node: roxmltree::Node, line: usize) -> Result<Option<BezPath>, MeshingError> {
    let tag = node.tag_name().name();
    let get = |name: &str| attr_length(node, name, line);
    Ok(match tag {
        "path" => {
            let d = node.attribute("d").unwrap_or("");
            if d.trim().is_empty() {
                return Ok(None);
            }
            check_numbers(d, tag, "d", line)?;
            Some(BezPath::from_svg(d).map_err(|e| error(Some(line), format!("<path> d: {e}")))?)
        }
        "polygon" | "polyline" => {
            let text = node.attribute("points").unwrap_or("");
            check_numbers(text, tag, "points", line)?;
            let v = numbers(text).ok_or_else(|| {
                error(Some(line), format!("<{tag}> points: not a list of numbers"))
            })?;
            if v.is_empty() {
                return Ok(None);
            }
            if v.len() % 2 == 1 {
                return Err(error(
                    Some(line),
                    format!("<{tag}> points: an odd number of coordinates ({})", v.len()),
                ));
            }
            let mut path = BezPath::new();
            for (k, p) in v.chunks_exact(2).enumerate() {
                if k == 0 {
                    path.move_to((p[0], p[1]));
                } else {
                    path.line_to((p[0], p[1]));
                }
            }
            path.close_path();
            Some(path)
        }
        "rect" => {
            let (x, y, w, h) = (get("x")?, get("y")?, get("width")?, get("height")?);
            if w <= 0.0 || h <= 0.0 {
                return Ok(None);
            }
            let (rx, ry) = match (node.attribute("rx"), node.attribute("ry")) {
                (None, None) => (0.0, 0.0),
                (Some(_), None) => (get("rx")?, get("rx")?),
                (None, Some(_)) => (get("ry")?, get("ry")?),
                (Some(_), Some(_)) => (get("rx")?, get("ry")?),
            };
            let (rx, ry) = (rx.clamp(0.0, w / 2.0), ry.clamp(0.0, h / 2.0));
            let d = if rx > 0.0 && ry > 0.0 {
                let (x1, y1) = (x + w, y + h);
                format!(
                    "M{} {} H{} A{rx} {ry} 0 0 1 {x1} {} V{} A{rx} {ry} 0 0 1 {} {y1} H{} A{rx} {ry} 0 0 1 {x} {} V{} A{rx} {ry} 0 0 1 {} {y} Z",
                    x + rx, y, x1 - rx, y + ry, y1 - ry, x1 - rx, x + rx, y1 - ry, y + ry, x + rx
                )
            } else {
                format!("M{x} {y} H{} V{} H{x} Z", x + w, y + h)
            };
            Some(BezPath::from_svg(&d).map_err(|e| error(Some(line), format!("<rect>: {e}")))?)
        }
        "circle" | "ellipse" => {
            let (cx, cy) = (get("cx")?, get("cy")?);
            let (rx, ry) = if tag == "circle" {
                (get("r")?, get("r")?)
            } else {
                (get("rx")?, get("ry")?)
            };
            if rx <= 0.0 || ry <= 0.0 {
                return Ok(None);
            }
            // Cubic arcs far closer than any useful tolerance; flattening comes later.
            let e = kurbo::Ellipse::new((cx, cy), (rx, ry), 0.0);
            Some(e.to_path(1e-7 * rx.max(ry)))
        }
        _ => None,
    })
}

/// The 1-based line of a byte offset, from the offsets of the text's line feeds (roxmltree's
/// `text_pos_at` scans the text from its start on every call).
struct Lines(Vec<usize>);

impl Lines {
    fn new(text: &str) -> Lines {
        Lines(
            text.bytes()
                .enumerate()
                .filter(|&(_, b)| b == b'\n')
                .map(|(i, _)| i)
                .collect(),
        )
    }

    fn of(&self, offset: usize) -> usize {
        self.0.partition_point(|&i| i < offset) + 1
    }
}

/// Collects the shapes under `root`, with its transform `own`, in document order. The tree is
/// walked with a stack of its own, not by recursion: any depth of nesting is read (roxmltree
/// builds its tree without recursion too) on any thread's stack.
fn collect(
    lines: &Lines,
    root: roxmltree::Node,
    own: Affine,
    out: &mut Vec<Drawn>,
) -> Result<(), MeshingError> {
    // Per level, the element's children still to visit and the element's total transform.
    let mut stack = vec![(root.children(), own)];
    while let Some((children, parent)) = stack.last_mut() {
        let parent = *parent;
        let Some(child) = children.next() else {
            stack.pop();
            continue;
        };
        if !child.is_element() {
            continue;
        }
        let tag = child.tag_name().name();
        if NOT_DRAWN.contains(&tag)
            || child
                .attribute("display")
                .is_some_and(|d| d.trim() == "none")
        {
            continue;
        }
        let line = lines.of(child.range().start);
        let own = match child.attribute("transform") {
            Some(t) => {
                transform(t).map_err(|m| error(Some(line), format!("<{}> {m}", excerpt(tag))))?
            }
            None => Affine::IDENTITY,
        };
        let total = parent * own;
        if let Some(path) = shape_path(child, line)? {
            let path = total * path;
            check_points(&path, tag, line)?;
            out.push(Drawn {
                name: format!("<{tag}>"),
                line,
                path,
            });
        }
        stack.push((child.children(), total));
    }
    Ok(())
}

/// Refuses a shape with a point (after its transforms) outside the coordinate range.
fn check_points(path: &BezPath, tag: &str, line: usize) -> Result<(), MeshingError> {
    for el in path.elements() {
        let points: &[kurbo::Point] = match el {
            PathEl::MoveTo(p) | PathEl::LineTo(p) => std::slice::from_ref(p),
            PathEl::QuadTo(a, b) => &[*a, *b],
            PathEl::CurveTo(a, b, c) => &[*a, *b, *c],
            PathEl::ClosePath => &[],
        };
        for p in points {
            for x in [p.x, p.y] {
                if !in_range(x) {
                    return Err(MeshingError::OutOfRange {
                        place: Place::line(Some(line)),
                        what: format!("<{tag}> a point's coordinate after the transforms"),
                        value: x,
                    });
                }
            }
        }
    }
    Ok(())
}

/// About how many points (at most) flattening `path` to `tolerance` gives, and whether it
/// has curves: a line is one point, a curve about the square root of its control polygon's
/// length over the tolerance (kurbo flattens near-optimally).
fn estimate_points(path: &BezPath, tolerance: f64) -> (u64, bool) {
    let mut last = kurbo::Point::ZERO;
    let mut total = 0u64;
    let mut curves = false;
    let pieces = |length: f64| (length / tolerance).sqrt().ceil().min(1e18) as u64;
    for el in path.elements() {
        total = total.saturating_add(match *el {
            PathEl::MoveTo(p) | PathEl::LineTo(p) => {
                last = p;
                1
            }
            PathEl::QuadTo(a, b) => {
                curves = true;
                let n = pieces(last.distance(a) + a.distance(b));
                last = b;
                n.saturating_add(1)
            }
            PathEl::CurveTo(a, b, c) => {
                curves = true;
                let n = pieces(last.distance(a) + a.distance(b) + b.distance(c));
                last = c;
                n.saturating_mul(2).saturating_add(2)
            }
            PathEl::ClosePath => 1,
        });
    }
    (total, curves)
}

/// Points closer than this fraction of the tolerance are one point (a curve that closes
/// on its start up to round-off, for instance).
const SAME_POINT: f64 = 1e-3;

/// The closed parts of a flattened path, without repeated points; `None` past `limit` points.
fn flatten(path: &BezPath, tolerance: f64, limit: usize) -> Option<Vec<Vec<[f64; 2]>>> {
    let mut points = 0usize;
    let mut parts: Vec<Vec<[f64; 2]>> = Vec::new();
    let mut current: Vec<[f64; 2]> = Vec::new();
    let close =
        |p: &[f64; 2], q: &[f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]) <= SAME_POINT * tolerance;
    let mut finish = |current: &mut Vec<[f64; 2]>| {
        let mut part = std::mem::take(current);
        part.dedup_by(|p, q| close(p, q));
        while part.len() > 1 && close(&part[0], &part[part.len() - 1]) {
            part.pop();
        }
        if !part.is_empty() {
            parts.push(part);
        }
    };
    kurbo::flatten(path, tolerance, |el| {
        points += 1;
        if points > limit {
            return;
        }
        match el {
            PathEl::MoveTo(p) => {
                finish(&mut current);
                current.push([p.x, p.y]);
            }
            PathEl::LineTo(p) => current.push([p.x, p.y]),
            PathEl::ClosePath => finish(&mut current),
            PathEl::QuadTo(..) | PathEl::CurveTo(..) => {}
        }
    });
    finish(&mut current);
    (points <= limit).then_some(parts)
}

/// Parses an SVG document's shapes into an outline with [`super::Inside::Parity`], curves
/// flattened to `tolerance` (in user units after transforms; default 1/1000 of the shapes'
/// bounding-box diagonal), y flipped to point up. Messages name the element's line (add the
/// file with [`MeshingError::in_file`]).
///
/// ```
/// let text = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 50">
///   <path d="M 10 10 C 40 0, 60 0, 90 10 L 90 40 Q 50 60 10 40 Z"/>
///   <circle cx="50" cy="25" r="8"/>
/// </svg>"#;
/// let outline = bdmorph::meshing::parse_svg(text, Some(0.05))?;
/// // The viewBox spans the texture; y is flipped: the curve at the top of the drawing
/// // (small y) is at the top of the outline (large y).
/// assert_eq!(outline.texture_frame, Some([0.0, 0.0, 100.0, 50.0]));
/// assert!(outline.vertices.iter().any(|p| p[1] > 42.0));
/// let meshed = bdmorph::meshing::mesh_outline(&outline, &Default::default())?;
/// assert_eq!((meshed.stats.pieces, meshed.stats.holes), (1, 1));
/// # Ok::<(), bdmorph::meshing::MeshingError>(())
/// ```
///
/// # Errors
/// [`MeshingError::Svg`] for a document that is not XML, path data or attributes that cannot
/// be read, or lengths in units other than user units; [`MeshingError::NoOutline`] when no
/// shape is found; [`MeshingError::LoopTooSmall`] for a closed part that encloses less than
/// the tolerance squared once flattened; [`MeshingError::BadOption`] for a tolerance that is
/// not positive.
pub fn parse_svg(text: &str, tolerance: Option<f64>) -> Result<Outline, MeshingError> {
    if let Some(t) = tolerance {
        if !(t > 0.0 && t.is_finite()) {
            return Err(MeshingError::BadOption {
                option: "--tolerance",
                value: t.to_string(),
                expected: "a positive number",
            });
        }
    }
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        // roxmltree quotes the character it met, a line feed included: escaped, one line.
        let message: String = e
            .to_string()
            .chars()
            .map(|c| {
                if c.is_control() {
                    c.escape_default().to_string()
                } else {
                    c.to_string()
                }
            })
            .collect();
        let shown = match message.char_indices().nth(160) {
            Some((i, _)) => format!("{}...", &message[..i]),
            None => message,
        };
        error(
            Some(e.pos().row as usize),
            format!("not valid XML: {shown}"),
        )
    })?;
    let root = doc.root_element();
    let root_line = doc.text_pos_at(root.range().start).row as usize;
    if root.tag_name().name() != "svg" {
        return Err(error(
            Some(root_line),
            format!(
                "the root element is <{}>, not <svg>",
                excerpt(root.tag_name().name())
            ),
        ));
    }
    let view_box = match root.attribute("viewBox") {
        Some(v) => match numbers(v).as_deref() {
            Some(&[x, y, w, h]) if w > 0.0 && h > 0.0 => Some([x, y, w, h]),
            _ => {
                return Err(error(
                    Some(root_line),
                    format!(
                        "viewBox=\"{}\" is not four numbers with a positive width and height",
                        excerpt(v)
                    ),
                ))
            }
        },
        None => None,
    };
    let size = [root.attribute("width"), root.attribute("height")]
        .map(|a| a.and_then(length).filter(|&x| x > 0.0));
    let own = match root.attribute("transform") {
        Some(t) => transform(t).map_err(|m| error(Some(root_line), format!("<svg> {m}")))?,
        None => Affine::IDENTITY,
    };
    let lines = Lines::new(text);
    let mut shapes = Vec::new();
    collect(&lines, root, own, &mut shapes)?;
    if shapes.is_empty() {
        return Err(MeshingError::NoOutline {
            place: Place::default(),
            what: "no <path>, <polygon>, <polyline>, <rect>, <circle> or <ellipse>",
        });
    }
    let tolerance = match tolerance {
        Some(t) => t,
        None => {
            let b = shapes
                .iter()
                .map(|s| s.path.bounding_box())
                .reduce(|a, b| a.union(b))
                .unwrap_or_default();
            let diagonal = b.width().hypot(b.height());
            if !(diagonal > 0.0 && diagonal.is_finite()) {
                return Err(MeshingError::NoOutline {
                    place: Place::default(),
                    what: "every shape is a point",
                });
            }
            DEFAULT_OUTLINE_TOLERANCE * diagonal
        }
    };
    let mut estimate = 0u64;
    for s in &shapes {
        let (points, curves) = estimate_points(&s.path, tolerance);
        estimate = estimate.saturating_add(points);
        if estimate > MAX_OUTLINE_POINTS as u64 {
            return Err(MeshingError::TooManyPoints {
                place: Place::line(Some(s.line)),
                what: format!("the outline (up to {})", s.name),
                points: estimate,
                limit: MAX_OUTLINE_POINTS,
                tolerance_helps: curves,
            });
        }
    }
    let mut loops: Vec<(Vec<[f64; 2]>, Element)> = Vec::new();
    let mut left = MAX_OUTLINE_POINTS;
    for s in &shapes {
        let parts =
            flatten(&s.path, tolerance, left).ok_or_else(|| MeshingError::TooManyPoints {
                place: Place::line(Some(s.line)),
                what: format!("the outline (up to {})", s.name),
                points: (MAX_OUTLINE_POINTS + 1) as u64,
                limit: MAX_OUTLINE_POINTS,
                tolerance_helps: true,
            })?;
        left -= parts.iter().map(Vec::len).sum::<usize>().min(left);
        let many = parts.len() > 1;
        for (k, part) in parts.into_iter().enumerate() {
            let name = if many {
                format!("{} part {k}", s.name)
            } else {
                s.name.clone()
            };
            let area = twice_area(&part).abs() / 2.0;
            // A loop that crosses itself (a bow tie) may enclose no area in sum: the check
            // of the outline names the crossing.
            if part.len() < 3 || (area < tolerance * tolerance && !crosses_itself(&part)) {
                return Err(MeshingError::LoopTooSmall {
                    place: Place::line(Some(s.line)),
                    what: name,
                    area,
                    tolerance,
                });
            }
            loops.push((
                part,
                Element {
                    name,
                    line: Some(s.line),
                },
            ));
        }
    }
    let all: Vec<[f64; 2]> = loops.iter().flat_map(|(l, _)| l.iter().copied()).collect();
    let b = bounds(&all);
    // The frame the document is drawn in, in its own coordinates (y down).
    let frame = view_box.or(match size {
        [Some(w), Some(h)] => Some([0.0, 0.0, w, h]),
        _ => None,
    });
    let bottom = frame.map_or(b[3], |f| f[1] + f[3]);
    let mut outline = Outline::from_loops::<Vec<[f64; 2]>>(&[]);
    for (points, element) in loops {
        let flipped: Vec<[f64; 2]> = points.iter().map(|p| [p[0], bottom - p[1]]).collect();
        outline.push_loop(&flipped, element);
    }
    outline.flip_y = Some(bottom);
    outline.texture_frame = frame
        .filter(|f| b[0] >= f[0] && b[2] <= f[0] + f[2] && b[1] >= f[1] && b[3] <= f[1] + f[3])
        .map(|f| [f[0], 0.0, f[2], f[3]]);
    Ok(outline)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_transforms() {
        assert_eq!(
            numbers("1,2 3-4 .5.5 1e2"),
            Some(vec![1.0, 2.0, 3.0, -4.0, 0.5, 0.5, 100.0])
        );
        assert_eq!(numbers("1 x"), None);
        let t = transform("translate(10 20) scale(2)").expect("valid");
        assert_eq!(
            t * kurbo::Point::new(1.0, 1.0),
            kurbo::Point::new(12.0, 22.0)
        );
        let r = transform("rotate(90, 1, 1)").expect("valid") * kurbo::Point::new(2.0, 1.0);
        assert!((r.x - 1.0).abs() < 1e-12 && (r.y - 2.0).abs() < 1e-12);
        assert!(transform("spin(3)").is_err());
        assert!(transform("scale(1 2 3)").is_err());
    }

    #[test]
    fn shapes_groups_and_transforms_become_loops() {
        let text = r#"<svg xmlns="http://www.w3.org/2000/svg" width="200" height="100">
  <defs><rect width="5" height="5"/></defs>
  <g transform="translate(100 0)">
    <rect x="10" y="10" width="80" height="80" rx="10"/>
    <polygon points="30,30 70,30 50,70"/>
  </g>
  <ellipse cx="50" cy="50" rx="40" ry="20"/>
  <line x1="0" y1="0" x2="10" y2="10"/>
</svg>"#;
        let o = parse_svg(text, Some(0.1)).expect("valid");
        assert_eq!(o.elements.len(), 3);
        assert_eq!(
            o.elements[1],
            Element {
                name: "<polygon>".into(),
                line: Some(5)
            }
        );
        assert_eq!(o.texture_frame, Some([0.0, 0.0, 200.0, 100.0]));
        let b = bounds(&o.vertices);
        assert!(
            (b[0] - 10.0).abs() < 1e-9 && (b[2] - 190.0).abs() < 1e-9,
            "{b:?}"
        );
        // The polygon's apex (y = 70 down from the top) is at y = 30 up from the bottom.
        assert!(o.vertices.contains(&[150.0, 30.0]));
        let m =
            super::super::mesh_outline(&o, &super::super::MeshOptions::default()).expect("meshes");
        assert_eq!((m.stats.pieces, m.stats.holes), (2, 1));
    }

    #[test]
    fn errors_name_the_element_and_line() {
        let bad_path = "<svg>\n<path d=\"M 0 0 L 10 10 X\"/>\n</svg>";
        assert_eq!(
            parse_svg(bad_path, None).unwrap_err().to_string(),
            "line 2: <path> d: Unknown command, \"X\""
        );
        let units = "<svg>\n\n<circle r=\"3mm\"/>\n</svg>";
        assert_eq!(
            parse_svg(units, None).unwrap_err().to_string(),
            "line 3: <circle> r=\"3mm\" is not a number in user units (other units are not supported)"
        );
        let crossing = "<svg>\n<polygon points=\"0,0 10,10 10,0 0,4\"/>\n</svg>";
        let o = parse_svg(crossing, None).expect("parses");
        assert_eq!(
            super::super::mesh_outline(&o, &Default::default())
                .unwrap_err()
                .to_string(),
            "line 2: <polygon> segment 0 crosses <polygon> segment 2 near (2.85714, 2.85714)"
        );
        let tiny = "<svg>\n<rect width=\"100\" height=\"100\"/>\n<circle cx=\"50\" cy=\"50\" r=\"0.01\"/>\n</svg>";
        let e = parse_svg(tiny, Some(0.5)).unwrap_err();
        assert!(matches!(e, MeshingError::LoopTooSmall { .. }), "{e}");
        assert!(
            e.to_string()
                .starts_with("line 3: <circle> is too small for the tolerance 0.5"),
            "{e}"
        );
        assert!(matches!(
            parse_svg("<svg/>", None),
            Err(MeshingError::NoOutline { .. })
        ));
        assert!(matches!(
            parse_svg("<svg", None),
            Err(MeshingError::Svg { .. })
        ));
    }
}
