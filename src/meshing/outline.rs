//! The outline to mesh: a planar straight-line graph (vertices and the segments between them),
//! how its inside is told apart, and the checks every outline goes through before it is
//! triangulated (finite coordinates, no segment crossing, touching or overlapping another).

use std::collections::HashMap;

use robust::{orient2d, Coord};

use super::error::{Contact, MeshingError, Place};

/// How the inside of an [`Outline`] is told apart from the outside.
#[derive(Clone, Debug, PartialEq)]
pub enum Inside {
    /// By nesting: the segments form closed loops, and a point is inside when an odd number of
    /// loops surround it (a loop inside a piece is a hole, a loop inside that hole another
    /// piece). Loops must not touch. Pictures and SVG outlines.
    Parity,
    /// As Triangle does with a `.poly` file: every region reachable from outside the convex
    /// hull, or from one of these points, without crossing a segment is outside; the rest is
    /// inside. Segments may meet at shared vertices and need not form loops.
    HolePoints(Vec<[f64; 2]>),
}

/// What a segment of an outline came from, for messages: an element of the input (a `<path>`
/// on line 7, a `.poly` segment on line 12, a traced loop).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Element {
    /// How messages name it: `<path>`, `segment 4`, `outline 2`.
    pub name: String,
    /// Its 1-based line in the input, when known.
    pub line: Option<usize>,
}

/// A planar straight-line graph to mesh, in a y-up frame.
///
/// Make one with [`Outline::from_loops`], [`super::parse_poly`], [`super::parse_svg`] or
/// [`super::picture_outline`]; [`super::mesh_outline`] triangulates it.
#[derive(Clone, Debug, PartialEq)]
pub struct Outline {
    /// Vertex positions (y up).
    pub vertices: Vec<[f64; 2]>,
    /// Segments as pairs of 0-based indices into `vertices`.
    pub segments: Vec<[u32; 2]>,
    /// How the inside is told apart.
    pub inside: Inside,
    /// The rectangle `[x0, y0, width, height]` that texture coordinates span: a vertex at
    /// `(x, y)` gets `u = (x - x0) / width`, `v = (y - y0) / height`. `None`: the bounding box
    /// of the vertices, as a square (its larger side), so the aspect ratio is kept.
    pub texture_frame: Option<[f64; 4]>,
    /// Per segment, the index into `elements` of what it came from and its 0-based number
    /// within it. Empty, or one per segment.
    pub labels: Vec<[u32; 2]>,
    /// What segments came from (see `labels`).
    pub elements: Vec<Element>,
    /// When the input's y points down (SVG), the input's `y` is `flip_y - y`; messages give
    /// places in the input's coordinates.
    pub flip_y: Option<f64>,
}

impl Outline {
    /// Closed loops (each at least three points, the last joined to the first), with
    /// [`Inside::Parity`]; texture coordinates over the bounding box.
    pub fn from_loops<L: AsRef<[[f64; 2]]>>(loops: &[L]) -> Outline {
        let mut outline = Outline {
            vertices: Vec::new(),
            segments: Vec::new(),
            inside: Inside::Parity,
            texture_frame: None,
            labels: Vec::new(),
            elements: Vec::new(),
            flip_y: None,
        };
        for (i, l) in loops.iter().enumerate() {
            outline.push_loop(
                l.as_ref(),
                Element {
                    name: format!("outline {i}"),
                    line: None,
                },
            );
        }
        outline
    }

    /// Appends a closed loop that came from `element`.
    pub fn push_loop(&mut self, points: &[[f64; 2]], element: Element) {
        let first = self.vertices.len() as u32;
        let n = points.len() as u32;
        let e = self.elements.len() as u32;
        self.elements.push(element);
        self.vertices.extend_from_slice(points);
        for k in 0..n {
            self.segments.push([first + k, first + (k + 1) % n]);
            self.labels.push([e, k]);
        }
    }

    /// How messages name segment `s`: `<path> segment 3`, `segment 4`.
    fn describe(&self, s: usize) -> (String, Option<usize>) {
        let Some(&[e, k]) = self.labels.get(s) else {
            return (format!("segment {s}"), None);
        };
        let Some(el) = self.elements.get(e as usize) else {
            return (format!("segment {s}"), None);
        };
        let many = self.labels.iter().filter(|l| l[0] == e).nth(1).is_some();
        let name = if many {
            format!("{} segment {k}", el.name)
        } else {
            el.name.clone()
        };
        (name, el.line)
    }

    /// A point of the outline in the input's coordinates.
    pub(crate) fn in_input(&self, p: [f64; 2]) -> [f64; 2] {
        match self.flip_y {
            Some(h) => [p[0], h - p[1]],
            None => p,
        }
    }
}

/// An outline that passed the checks: no two vertices at the same place, no repeated or
/// zero-length segment, no segments crossing.
#[derive(Clone, Debug)]
pub(crate) struct Checked {
    pub vertices: Vec<[f64; 2]>,
    pub segments: Vec<[u32; 2]>,
    pub inside: Inside,
}

/// Checks an outline: finite coordinates, indices in range, no zero-length segment, no two
/// segments crossing, touching away from a shared vertex or overlapping; with
/// [`Inside::Parity`], loops that do not touch even at a vertex. Vertices at the same place
/// are merged and repeated segments dropped.
pub(crate) fn check(outline: &Outline) -> Result<Checked, MeshingError> {
    let n = outline.vertices.len();
    if outline.segments.is_empty() {
        return Err(MeshingError::NoOutline {
            place: Place::default(),
            what: "no segments",
        });
    }
    if let Some(v) = outline
        .vertices
        .iter()
        .position(|p| !(super::in_range(p[0]) && super::in_range(p[1])))
    {
        let p = outline.vertices[v];
        let value = if super::in_range(p[0]) { p[1] } else { p[0] };
        let (name, line) = match outline
            .segments
            .iter()
            .position(|s| s.contains(&(v as u32)))
        {
            Some(s) => outline.describe(s),
            None => (format!("vertex {v}"), None),
        };
        return Err(MeshingError::OutOfRange {
            place: Place::line(line),
            what: format!("{name}: a coordinate"),
            value,
        });
    }
    if let Some(s) = outline
        .segments
        .iter()
        .position(|s| s.iter().any(|&v| v as usize >= n))
    {
        return Err(MeshingError::Internal {
            place: Place::default(),
            message: format!("segment {s} refers to a vertex beyond the {n} vertices"),
        });
    }
    // Merge vertices at the same place (keeping the first), in order.
    let mut first_at: HashMap<[u64; 2], u32> = HashMap::with_capacity(n);
    let mut vertices = Vec::with_capacity(n);
    let mut map = Vec::with_capacity(n);
    for p in &outline.vertices {
        // -0.0 and 0.0 are the same place.
        let key = [(p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits()];
        let id = *first_at.entry(key).or_insert_with(|| {
            vertices.push(*p);
            (vertices.len() - 1) as u32
        });
        map.push(id);
    }
    let mut seen = std::collections::HashSet::with_capacity(outline.segments.len());
    let mut segments = Vec::with_capacity(outline.segments.len());
    let mut origin = Vec::with_capacity(outline.segments.len());
    for (s, seg) in outline.segments.iter().enumerate() {
        let [a, b] = seg.map(|v| map[v as usize]);
        if a == b {
            let (segment, line) = outline.describe(s);
            return Err(MeshingError::ZeroLength {
                place: Place::line(line),
                segment,
                at: outline.in_input(vertices[a as usize]),
            });
        }
        if seen.insert([a.min(b), a.max(b)]) {
            segments.push([a, b]);
            origin.push(s);
        }
    }
    if outline.inside == Inside::Parity {
        // Loops may not share a vertex: a vertex on more than two segments is a pinch.
        let mut degree = vec![0u32; vertices.len()];
        for s in &segments {
            degree[s[0] as usize] += 1;
            degree[s[1] as usize] += 1;
        }
        if let Some(v) = degree.iter().position(|&d| d > 2) {
            let on: Vec<usize> = (0..segments.len())
                .filter(|&s| segments[s].contains(&(v as u32)))
                .collect();
            let (a, b) = (origin[on[0]], origin[on[2]]);
            return Err(contact_error(outline, a, b, Contact::Touch, vertices[v]));
        }
    }
    if let Some(c) = crossings(&vertices, &segments)
        .into_iter()
        .min_by_key(|c| (c.first, c.second))
    {
        return Err(contact_error(
            outline,
            origin[c.first],
            origin[c.second],
            c.contact,
            c.at,
        ));
    }
    Ok(Checked {
        vertices,
        segments,
        inside: outline.inside.clone(),
    })
}

fn contact_error(
    outline: &Outline,
    a: usize,
    b: usize,
    contact: Contact,
    at: [f64; 2],
) -> MeshingError {
    let (a, b) = (a.min(b), a.max(b));
    let (first, line) = outline.describe(a);
    let (mut second, second_line) = outline.describe(b);
    if let Some(l) = second_line.filter(|&l| Some(l) != line) {
        second.push_str(&format!(" (line {l})"));
    }
    MeshingError::SelfIntersection {
        place: Place::line(line),
        first,
        second,
        contact,
        at: outline.in_input(at),
    }
}

/// Two segments that meet where they should not.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Crossing {
    /// The lower segment index.
    pub first: usize,
    /// The higher one.
    pub second: usize,
    /// How.
    pub contact: Contact,
    /// About where.
    pub at: [f64; 2],
}

fn coord(p: [f64; 2]) -> Coord<f64> {
    Coord { x: p[0], y: p[1] }
}

/// The sign of the turn `a -> b -> c`, exactly.
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    orient2d(coord(a), coord(b), coord(c))
}

/// Whether `p`, collinear with `a` and `b`, lies within the segment's bounding box.
fn within(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> bool {
    p[0] >= a[0].min(b[0])
        && p[0] <= a[0].max(b[0])
        && p[1] >= a[1].min(b[1])
        && p[1] <= a[1].max(b[1])
}

/// How segments `ab` and `cd` meet, if they do, and about where. Segments sharing a vertex
/// (index) meet there legitimately, and only overlap counts.
fn contact(p: &[[f64; 2]], s: [u32; 2], t: [u32; 2]) -> Option<(Contact, [f64; 2])> {
    let [a, b] = s.map(|v| p[v as usize]);
    let [c, d] = t.map(|v| p[v as usize]);
    let shared = s.iter().find(|v| t.contains(v));
    if let Some(&v) = shared {
        if s == t || s == [t[1], t[0]] {
            return Some((Contact::Overlap, p[v as usize]));
        }
        let o = p[v as usize];
        let q = if s[0] == v { b } else { a };
        let r = if t[0] == v { d } else { c };
        let along = (q[0] - o[0]) * (r[0] - o[0]) + (q[1] - o[1]) * (r[1] - o[1]);
        if orient(o, q, r) == 0.0 && along > 0.0 {
            return Some((Contact::Overlap, o));
        }
        return None;
    }
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    if o1 == 0.0 && o2 == 0.0 {
        // Collinear: they meet when one's end lies on the other.
        for (q, seg) in [(c, (a, b)), (d, (a, b)), (a, (c, d)), (b, (c, d))] {
            if within(seg.0, seg.1, q) {
                return Some((Contact::Overlap, q));
            }
        }
        return None;
    }
    if o1 * o2 > 0.0 || o3 * o4 > 0.0 {
        return None;
    }
    // They meet: at an end of one (touch) or properly (cross).
    for (o, q) in [(o1, c), (o2, d), (o3, a), (o4, b)] {
        if o == 0.0 {
            return Some((Contact::Touch, q));
        }
    }
    let t = o3 / (o3 - o4);
    Some((
        Contact::Cross,
        [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])],
    ))
}

/// Every pair of segments that cross, touch away from a shared vertex, or overlap, each pair
/// once (in order), found with a hashed uniform grid.
///
/// The cells are about as large as the mean segment, and a segment is entered in the cells
/// along it (the cells of the boxes of pieces of it no longer than a cell), not in every cell
/// of its bounding box: an outline is a set of curves, whose segments then meet a few cells
/// each, and a cell holds a few segments, so that the work grows as `n log n` (the sort of the
/// cell entries) with the number of segments `n`. (Cells as large as `extent / sqrt(n)`, one
/// segment per cell on average over the bounding box, hold `sqrt(n)` segments each along a
/// curve: `n^1.5` pairs.)
pub(crate) fn crossings(p: &[[f64; 2]], segments: &[[u32; 2]]) -> Vec<Crossing> {
    let n = segments.len();
    if n < 2 {
        return Vec::new();
    }
    let ends = |s: &[u32; 2]| s.map(|v| p[v as usize]);
    let bbox = |s: &[u32; 2]| {
        let [a, b] = ends(s);
        [
            a[0].min(b[0]),
            a[1].min(b[1]),
            a[0].max(b[0]),
            a[1].max(b[1]),
        ]
    };
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut total = 0.0;
    for s in segments {
        let b = bbox(s);
        lo = [lo[0].min(b[0]), lo[1].min(b[1])];
        hi = [hi[0].max(b[2]), hi[1].max(b[3])];
        total += (b[2] - b[0]).max(b[3] - b[1]);
    }
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    // At most 2^30 cells a side, so that a cell is a (row, column) pair of u32s.
    let mut cell = (total / n as f64).max(extent / f64::from(1u32 << 30));
    if !(cell.is_finite() && cell > 0.0) {
        cell = if extent.is_finite() && extent > 0.0 {
            extent
        } else {
            1.0
        };
    }
    let limit = f64::from(1u32 << 30);
    let col = |x: f64| ((x - lo[0]) / cell).clamp(0.0, limit) as u64;
    let row = |y: f64| ((y - lo[1]) / cell).clamp(0.0, limit) as u64;
    // (cell, segment) entries, a segment once per cell.
    let mut entries: Vec<(u64, u32)> = Vec::with_capacity(2 * n);
    let mut keys: Vec<u64> = Vec::new();
    let margin = cell * 1e-9;
    for (i, s) in segments.iter().enumerate() {
        let [a, b] = ends(s);
        let length = (b[0] - a[0]).abs().max((b[1] - a[1]).abs());
        let pieces = (length / cell).ceil().clamp(1.0, limit) as u64;
        keys.clear();
        for k in 0..pieces {
            let (t0, t1) = (k as f64 / pieces as f64, (k + 1) as f64 / pieces as f64);
            let q0 = [a[0] + t0 * (b[0] - a[0]), a[1] + t0 * (b[1] - a[1])];
            let q1 = if k + 1 == pieces {
                b
            } else {
                [a[0] + t1 * (b[0] - a[0]), a[1] + t1 * (b[1] - a[1])]
            };
            for r in row(q0[1].min(q1[1]) - margin)..=row(q0[1].max(q1[1]) + margin) {
                for c in col(q0[0].min(q1[0]) - margin)..=col(q0[0].max(q1[0]) + margin) {
                    keys.push(r << 32 | c);
                }
            }
        }
        keys.sort_unstable();
        keys.dedup();
        entries.extend(keys.iter().map(|&k| (k, i as u32)));
    }
    entries.sort_unstable();
    let mut found = Vec::new();
    let mut start = 0;
    while start < entries.len() {
        let key = entries[start].0;
        let end = start + entries[start..].partition_point(|e| e.0 == key);
        let here = &entries[start..end];
        for (x, &(_, i)) in here.iter().enumerate() {
            let bi = bbox(&segments[i as usize]);
            for &(_, j) in &here[x + 1..] {
                let bj = bbox(&segments[j as usize]);
                if bi[0].max(bj[0]) > bi[2].min(bj[2]) || bi[1].max(bj[1]) > bi[3].min(bj[3]) {
                    continue;
                }
                if let Some((contact, at)) = contact(p, segments[i as usize], segments[j as usize])
                {
                    found.push(Crossing {
                        first: i.min(j) as usize,
                        second: i.max(j) as usize,
                        contact,
                        at,
                    });
                }
            }
        }
        start = end;
    }
    // A pair that shares several cells is found in each.
    found.sort_by_key(|c| (c.first, c.second));
    found.dedup_by_key(|c| (c.first, c.second));
    found
}

/// Twice the signed area of a closed polygon (positive when counter-clockwise).
pub(crate) fn twice_area(points: &[[f64; 2]]) -> f64 {
    let n = points.len();
    (0..n)
        .map(|i| {
            let (a, b) = (points[i], points[(i + 1) % n]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum()
}

/// Whether `q` is inside the closed polygon (crossing number; a point on the boundary may go
/// either way).
pub(crate) fn contains(points: &[[f64; 2]], q: [f64; 2]) -> bool {
    let n = points.len();
    let mut inside = false;
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (points[i], points[j]);
        if (a[1] > q[1]) != (b[1] > q[1]) {
            let x = a[0] + (q[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if q[0] < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

/// The bounding box `[x0, y0, x1, y1]` of some points.
pub(crate) fn bounds(points: &[[f64; 2]]) -> [f64; 4] {
    points.iter().fold(
        [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ],
        |b, p| {
            [
                b[0].min(p[0]),
                b[1].min(p[1]),
                b[2].max(p[0]),
                b[3].max(p[1]),
            ]
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x: f64, y: f64, s: f64) -> Vec<[f64; 2]> {
        vec![[x, y], [x + s, y], [x + s, y + s], [x, y + s]]
    }

    #[test]
    fn nested_loops_pass_and_crossing_ones_are_named() {
        let ok = Outline::from_loops(&[square(0.0, 0.0, 10.0), square(2.0, 2.0, 3.0)]);
        assert_eq!(check(&ok).expect("nested squares").segments.len(), 8);
        let bad = Outline::from_loops(&[square(0.0, 0.0, 10.0), square(8.0, 2.0, 3.0)]);
        let e = check(&bad).unwrap_err();
        assert!(
            matches!(
                e,
                MeshingError::SelfIntersection {
                    contact: Contact::Cross,
                    ..
                }
            ),
            "{e}"
        );
        assert_eq!(
            e.to_string(),
            "outline 0 segment 1 crosses outline 1 segment 0 near (10, 2)"
        );
    }

    #[test]
    fn a_bow_tie_crosses_itself() {
        let e = check(&Outline::from_loops(&[vec![
            [0.0, 0.0],
            [2.0, 2.0],
            [2.0, 0.0],
            [0.0, 2.0],
        ]]))
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "outline 0 segment 0 crosses outline 0 segment 2 near (1, 1)"
        );
    }

    #[test]
    fn loops_sharing_a_vertex_touch() {
        let e = check(&Outline::from_loops(&[
            square(0.0, 0.0, 1.0),
            square(1.0, 1.0, 1.0),
        ]))
        .unwrap_err();
        assert!(
            matches!(e, MeshingError::SelfIntersection { contact: Contact::Touch, at, .. } if at == [1.0, 1.0]),
            "{e}"
        );
    }

    #[test]
    fn a_vertex_on_another_segment_touches_and_collinear_segments_overlap() {
        let touching = Outline::from_loops(&[
            square(0.0, 0.0, 4.0),
            vec![[4.0, 2.0], [6.0, 1.0], [6.0, 3.0]],
        ]);
        let e = check(&touching).unwrap_err();
        assert!(
            matches!(
                e,
                MeshingError::SelfIntersection {
                    contact: Contact::Touch,
                    ..
                }
            ),
            "{e}"
        );
        let overlapping = Outline::from_loops(&[
            square(0.0, 0.0, 4.0),
            vec![[4.0, 1.0], [6.0, 1.0], [4.0, 3.0]],
        ]);
        assert!(check(&overlapping).is_err());
        let found = crossings(&overlapping.vertices, &overlapping.segments);
        assert!(
            found.iter().any(|c| c.contact == Contact::Overlap),
            "{found:?}"
        );
    }

    #[test]
    fn the_grid_finds_what_brute_force_finds() {
        // Squares of growing size on a grid: the larger ones overlap their neighbours.
        let mut loops = vec![];
        for i in 0..20 {
            for j in 0..20 {
                loops.push(square(
                    i as f64 * 2.5,
                    j as f64 * 2.5,
                    1.0 + 0.05 * (i + j) as f64,
                ));
            }
        }
        let o = Outline::from_loops(&loops);
        let fast = crossings(&o.vertices, &o.segments);
        let mut slow = Vec::new();
        for i in 0..o.segments.len() {
            for j in i + 1..o.segments.len() {
                if contact(&o.vertices, o.segments[i], o.segments[j]).is_some() {
                    slow.push((i, j));
                }
            }
        }
        let mut fast: Vec<(usize, usize)> = fast.iter().map(|c| (c.first, c.second)).collect();
        fast.sort_unstable();
        assert_eq!(fast, slow);
        assert!(
            !slow.is_empty(),
            "the larger squares overlap their neighbours"
        );
    }

    #[test]
    fn areas_and_containment() {
        let s = square(0.0, 0.0, 2.0);
        assert_eq!(twice_area(&s), 8.0);
        assert!(contains(&s, [1.0, 1.0]));
        assert!(!contains(&s, [3.0, 1.0]));
    }
}
