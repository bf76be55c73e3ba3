//! The guarantee: a layout with flipped triangles re-embedded bijectively, refining A's mesh
//! where the mesh as it is has no flip-free layout.
//!
//! A region `R` of triangles around the flips is grown until it is a topological disk whose
//! boundary, at its current places over B, is a simple counter-clockwise polygon `P` (the
//! mesh's own outline on B always is, so the growth ends at the latest with the whole piece).
//! Then two maps onto one convex polygon `C` (`P`'s corners on a circle, in order):
//! - `T_A`: Tutte's embedding of `R` (uniform weights, boundary on `C`), a bijection onto `C`
//!   that is affine on every triangle of `R` (Tutte 1963, Floater 2003);
//! - `T_B`: a triangulation of `P` with no vertex inside (constrained Delaunay), drawn with
//!   the same corners on `C`: any triangulation of a simple polygon is outerplanar, so drawn
//!   with its corners in convex position it is a triangulation of `C`.
//!
//! `T_B⁻¹ ∘ T_A` is a bijection from `R` (in A) onto `P` (in B) that keeps `R`'s boundary
//! where it is. It is affine on every cell of the overlay of the two triangulations of `C`;
//! so `R` is refined by inserting `T_B`'s diagonals (chords of `C`) into `T_A(R)`, splitting
//! every edge a chord crosses, and every vertex is placed in B by the affine map of the
//! triangle of `T_B` holding it. Each refined triangle is the image of a cell under two
//! orientation-preserving affine maps, so none is flipped in A or in B. This is the
//! composition of Tutte embeddings onto a common convex polygon: the guarantee of
//! Progressive Embedding (Shen, Jiang, Zorin, Panozzo 2019) for one disk with its boundary
//! fixed onto a simple polygon, at the cost of the vertices the chords add.
//!
//! In floating point, a chord passing within [`SNAP`] (relative) of a vertex of `T_A(R)` is
//! taken through that vertex instead of cutting a sliver, and the result is checked: a
//! triangle not above the validity threshold in A or B makes the attempt fail and retry with
//! `C` parameterised differently.

use std::collections::HashMap;

use robust::{orient2d, Coord};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

use super::foldover::signed_area;
use crate::mesh::PlanarMesh;

/// A chord crossing an edge this close (as a fraction of the edge) to one of its ends goes
/// through that end.
const SNAP: f64 = 1e-4;
/// Attempts per region (the circle's parameterisation differs between them).
const ATTEMPTS: usize = 3;
/// Growth steps of a region, at most.
const MAX_GROWTH: usize = 400;

/// A refined mesh and its flip-free layout.
pub(crate) struct Embedded {
    /// The mesh: the first vertices are the input's, at the same places; new ones follow.
    pub mesh: PlanarMesh,
    /// The layout over B, one position per vertex.
    pub layout: Vec<[f64; 2]>,
    /// Per new vertex (in order, from the input's vertex count), the input triangle holding
    /// it in A and its barycentric coordinates there: its place in any layout of the input
    /// that is affine per triangle.
    pub new_vertices: Vec<(u32, [f64; 3])>,
    /// Per triangle of the refined mesh, the input triangle holding it.
    pub origin: Vec<u32>,
    /// Vertices that were held and had to move (inside a re-embedded region).
    pub released: Vec<u32>,
}

/// Why a layout could not be re-embedded.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum EmbedFailure {
    /// A region around the flips encloses a hole of the mesh (so it is not a disk) before
    /// its boundary over B is simple.
    EnclosesHole,
    /// The mesh's own boundary over B is not a simple polygon: no bijection exists.
    BoundaryNotSimple,
    /// Every attempt left a triangle at or below the validity threshold (a precision limit).
    Precision { region_faces: usize },
}

impl std::fmt::Display for EmbedFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EmbedFailure::EnclosesHole => write!(f, "the flipped region surrounds a hole"),
            EmbedFailure::BoundaryNotSimple => write!(f, "the outline over the drawing crosses itself"),
            EmbedFailure::Precision { region_faces } => write!(
                f,
                "a region of {region_faces} triangles could not be re-embedded within floating-point precision"
            ),
        }
    }
}

/// Re-embeds `layout` (of `mesh`, the vertices `fixed` held) where a triangle's area is at
/// most `bad_area` (see the module docs), so that every refined triangle's area is above
/// `min_area_a` in A and `min_area_b` in B. A held vertex inside a re-embedded region is let
/// go (and listed).
pub(crate) fn embed(
    mesh: &PlanarMesh,
    layout: &[[f64; 2]],
    fixed: &[bool],
    bad_area: f64,
    min_area_a: f64,
    min_area_b: f64,
) -> Result<Embedded, EmbedFailure> {
    let n0 = mesh.positions.len();
    let identity: Vec<u32> = (0..mesh.faces.len() as u32).collect();
    let bad: Vec<usize> = (0..mesh.faces.len())
        .filter(|&f| signed_area(layout, &mesh.faces[f]) <= bad_area)
        .collect();
    // Disjoint regions around every flip, all embedded on the mesh as it is (a region
    // grown into another's refinement would meet its thin new triangles); a region that
    // cannot be embedded within precision makes them all grow and try again.
    let mut tried = 0;
    let mut done = None;
    'rings: for rings in [0, 2, 6] {
        let regions = disjoint_regions(&mesh.faces, &mesh.positions, layout, &bad, rings)?;
        let mut results = Vec::with_capacity(regions.len());
        let mut next = n0 as u32;
        for region in &regions {
            let result = (0..ATTEMPTS).find_map(|attempt| {
                embed_region(
                    &mesh.positions,
                    &mesh.faces,
                    &identity,
                    layout,
                    region,
                    attempt,
                    next,
                    min_area_a,
                    min_area_b,
                )
            });
            match result {
                Some(r) => {
                    next += r.new_a.len() as u32;
                    results.push(r);
                }
                None => {
                    tried = region.faces.len();
                    continue 'rings;
                }
            }
        }
        done = Some((regions, results));
        break;
    }
    let Some((regions, results)) = done else {
        return Err(EmbedFailure::Precision {
            region_faces: tried,
        });
    };
    let mut positions = mesh.positions.clone();
    let mut layout = layout.to_vec();
    let mut released = Vec::new();
    let mut in_region = vec![false; mesh.faces.len()];
    for region in &regions {
        for &f in &region.faces {
            in_region[f] = true;
        }
        // Held vertices inside a region moved.
        released.extend(
            region
                .interior
                .iter()
                .copied()
                .filter(|&v| fixed[v as usize]),
        );
    }
    let mut faces = Vec::with_capacity(mesh.faces.len());
    let mut origin = Vec::with_capacity(mesh.faces.len());
    for (f, tri) in mesh.faces.iter().enumerate() {
        if !in_region[f] {
            faces.push(*tri);
            origin.push(f as u32);
        }
    }
    for result in &results {
        faces.extend_from_slice(&result.faces);
        origin.extend_from_slice(&result.origin);
        for (v, b) in &result.placed {
            layout[*v as usize] = *b;
        }
        positions.extend_from_slice(&result.new_a);
        layout.extend_from_slice(&result.new_b);
    }
    // Barycentric coordinates of the new vertices in the input triangles holding them.
    let mut holder = vec![u32::MAX; positions.len()];
    for (f, tri) in faces.iter().enumerate() {
        for &v in tri {
            if v as usize >= n0 && holder[v as usize] == u32::MAX {
                holder[v as usize] = origin[f];
            }
        }
    }
    let mut new_vertices = Vec::with_capacity(positions.len() - n0);
    for v in n0..positions.len() {
        let o = holder[v];
        let o = if o == u32::MAX { 0 } else { o };
        let t = mesh.faces[o as usize].map(|w| mesh.positions[w as usize]);
        new_vertices.push((o, barycentric(t, positions[v])));
    }
    Ok(Embedded {
        mesh: PlanarMesh { positions, faces },
        layout,
        new_vertices,
        origin,
        released,
    })
}

/// The barycentric coordinates of `p` in the triangle `t`.
pub(crate) fn barycentric(t: [[f64; 2]; 3], p: [f64; 2]) -> [f64; 3] {
    let [a, b, c] = t;
    let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if det == 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let l1 = ((p[0] - a[0]) * (c[1] - a[1]) - (p[1] - a[1]) * (c[0] - a[0])) / det;
    let l2 = ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / det;
    [1.0 - l1 - l2, l1, l2]
}

/// A region: its faces, its boundary loop (counter-clockwise) and its interior vertices.
struct Region {
    faces: Vec<usize>,
    boundary: Vec<u32>,
    interior: Vec<u32>,
}

/// Disjoint regions (sharing no triangle) around the `bad` faces, each grown by [`grow`]
/// from a group of bad faces joined by vertices; regions that overlap are grown again from
/// their groups together.
fn disjoint_regions(
    faces: &[[u32; 3]],
    rest: &[[f64; 2]],
    layout: &[[f64; 2]],
    bad: &[usize],
    rings: usize,
) -> Result<Vec<Region>, EmbedFailure> {
    // Groups of bad faces sharing a vertex.
    let mut group_of_vertex: HashMap<u32, usize> = HashMap::new();
    let mut parent: Vec<usize> = (0..bad.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for (k, &f) in bad.iter().enumerate() {
        for &v in &faces[f] {
            if let Some(&other) = group_of_vertex.get(&v) {
                let (x, y) = (root(&mut parent, k), root(&mut parent, other));
                parent[x] = y;
            } else {
                group_of_vertex.insert(v, k);
            }
        }
    }
    let mut groups: HashMap<usize, Vec<usize>> = HashMap::new();
    for (k, &f) in bad.iter().enumerate() {
        groups.entry(root(&mut parent, k)).or_default().push(f);
    }
    let mut seeds: Vec<Vec<usize>> = groups.into_values().collect();
    seeds.sort();
    loop {
        let regions: Vec<Region> = seeds
            .iter()
            .map(|s| grow(faces, rest, layout, s, bad, rings))
            .collect::<Result<_, _>>()?;
        let mut owner = vec![usize::MAX; faces.len()];
        let mut overlap = None;
        'find: for (r, region) in regions.iter().enumerate() {
            for &f in &region.faces {
                if owner[f] != usize::MAX && owner[f] != r {
                    overlap = Some((owner[f], r));
                    break 'find;
                }
                owner[f] = r;
            }
        }
        let Some((x, y)) = overlap else {
            return Ok(regions);
        };
        let merged = seeds.remove(y);
        seeds[x].extend(merged);
    }
}

/// Grows a disk region from the faces `seeds` (at least `rings` + 1 rings around them, and
/// every bad face it meets) until its boundary over B is a simple counter-clockwise polygon.
fn grow(
    faces: &[[u32; 3]],
    rest: &[[f64; 2]],
    layout: &[[f64; 2]],
    seeds: &[usize],
    bad: &[usize],
    rings: usize,
) -> Result<Region, EmbedFailure> {
    let n = layout.len();
    let mut star: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (f, tri) in faces.iter().enumerate() {
        for &v in tri {
            star[v as usize].push(f as u32);
        }
    }
    let mut edge_face: HashMap<(u32, u32), usize> = HashMap::with_capacity(3 * faces.len());
    for (f, tri) in faces.iter().enumerate() {
        for k in 0..3 {
            edge_face.insert((tri[k], tri[(k + 1) % 3]), f);
        }
    }
    // The seeds' piece: the faces joined to them across edges.
    let seed = seeds[0];
    let mut piece = vec![false; faces.len()];
    piece[seed] = true;
    let mut stack = vec![seed];
    while let Some(f) = stack.pop() {
        let tri = faces[f];
        for k in 0..3 {
            if let Some(&g) = edge_face.get(&(tri[(k + 1) % 3], tri[k])) {
                if !piece[g] {
                    piece[g] = true;
                    stack.push(g);
                }
            }
        }
    }
    let piece_faces = piece.iter().filter(|&&x| x).count();
    let mut is_bad = vec![false; faces.len()];
    for &f in bad {
        is_bad[f] = true;
    }
    let mut inside = vec![false; faces.len()];
    for &f in seeds {
        inside[f] = true;
    }
    for _ in 0..=rings {
        add_ring(faces, &star, &mut inside);
    }
    for _ in 0..MAX_GROWTH {
        // Bad faces touching the region join it.
        loop {
            let mut joined = false;
            for f in 0..faces.len() {
                if is_bad[f] && !inside[f] && faces[f].iter().any(|&v| touches(&star, &inside, v)) {
                    inside[f] = true;
                    joined = true;
                }
            }
            if !joined {
                break;
            }
        }
        fill_pockets(faces, &edge_face, &piece, &mut inside);
        let whole = inside.iter().filter(|&&x| x).count() >= piece_faces;
        match boundary_loop(faces, rest, &edge_face, &inside) {
            Loops::One(boundary) => {
                let polygon: Vec<[f64; 2]> = boundary.iter().map(|&v| layout[v as usize]).collect();
                if twice_area(&polygon) > 0.0 && is_simple(&polygon) {
                    let mut in_boundary = vec![false; n];
                    for &v in &boundary {
                        in_boundary[v as usize] = true;
                    }
                    let mut interior: Vec<u32> = (0..faces.len())
                        .filter(|&f| inside[f])
                        .flat_map(|f| faces[f])
                        .filter(|&v| !in_boundary[v as usize])
                        .collect();
                    interior.sort_unstable();
                    interior.dedup();
                    return Ok(Region {
                        faces: (0..faces.len()).filter(|&f| inside[f]).collect(),
                        boundary,
                        interior,
                    });
                }
                if whole {
                    return Err(EmbedFailure::BoundaryNotSimple);
                }
            }
            Loops::Touching(v) => {
                for &g in &star[v as usize] {
                    inside[g as usize] = true;
                }
                continue;
            }
            // Pieces grow until they join.
            Loops::Pieces => {}
            // An inner loop: the region surrounds a hole of the mesh (pockets without one
            // were filled).
            Loops::Inner => return Err(EmbedFailure::EnclosesHole),
        }
        add_ring(faces, &star, &mut inside);
    }
    Err(EmbedFailure::EnclosesHole)
}

fn touches(star: &[Vec<u32>], inside: &[bool], v: u32) -> bool {
    star[v as usize].iter().any(|&g| inside[g as usize])
}

/// Adds every face sharing a vertex with the region.
fn add_ring(faces: &[[u32; 3]], star: &[Vec<u32>], inside: &mut [bool]) {
    let mut touched = vec![false; star.len()];
    for (f, tri) in faces.iter().enumerate() {
        if inside[f] {
            for &v in tri {
                touched[v as usize] = true;
            }
        }
    }
    for (v, t) in touched.iter().enumerate() {
        if *t {
            for &g in &star[v] {
                inside[g as usize] = true;
            }
        }
    }
}

/// Adds to the region every component of the piece's other faces (joined across edges)
/// that has no edge on the mesh's boundary: pockets the region surrounds.
fn fill_pockets(
    faces: &[[u32; 3]],
    edge_face: &HashMap<(u32, u32), usize>,
    piece: &[bool],
    inside: &mut [bool],
) {
    let mut seen = vec![false; faces.len()];
    for start in 0..faces.len() {
        if !piece[start] || inside[start] || seen[start] {
            continue;
        }
        let mut component = vec![start];
        seen[start] = true;
        let mut open = false;
        let mut i = 0;
        while i < component.len() {
            let f = component[i];
            i += 1;
            let tri = faces[f];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                match edge_face.get(&(b, a)) {
                    None => open = true,
                    Some(&g) => {
                        if !inside[g] && !seen[g] {
                            seen[g] = true;
                            component.push(g);
                        }
                    }
                }
            }
        }
        if !open {
            for f in component {
                inside[f] = true;
            }
        }
    }
}

enum Loops {
    One(Vec<u32>),
    /// The boundary passes twice through this vertex.
    Touching(u32),
    /// The region is in several pieces.
    Pieces,
    /// The region surrounds a hole of the mesh.
    Inner,
}

/// The region's boundary: its loop of edges (region on the left), or what keeps it from
/// being one: a vertex where it touches itself, several outer loops (the region is in
/// pieces, counter-clockwise in A), or an inner loop (clockwise in A: it surrounds a hole of
/// the mesh).
fn boundary_loop(
    faces: &[[u32; 3]],
    rest: &[[f64; 2]],
    edge_face: &HashMap<(u32, u32), usize>,
    inside: &[bool],
) -> Loops {
    let mut next: HashMap<u32, u32> = HashMap::new();
    let mut touching = None;
    for (f, tri) in faces.iter().enumerate() {
        if !inside[f] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let out = edge_face.get(&(b, a)).is_none_or(|&g| !inside[g]);
            if out && next.insert(a, b).is_some() {
                touching = Some(a);
            }
        }
    }
    if let Some(v) = touching {
        return Loops::Touching(v);
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut seen: std::collections::HashSet<u32> = std::collections::HashSet::new();
    let mut loops: Vec<Vec<u32>> = Vec::new();
    for s0 in starts {
        if seen.contains(&s0) {
            continue;
        }
        let mut l = Vec::new();
        let mut v = s0;
        while seen.insert(v) {
            l.push(v);
            match next.get(&v) {
                Some(&w) => v = w,
                None => return Loops::Inner,
            }
        }
        loops.push(l);
    }
    if loops.len() == 1 {
        return Loops::One(loops.pop().unwrap_or_default());
    }
    let outer = |l: &Vec<u32>| {
        let p: Vec<[f64; 2]> = l.iter().map(|&v| rest[v as usize]).collect();
        twice_area(&p) > 0.0
    };
    if loops.iter().all(outer) {
        Loops::Pieces
    } else {
        Loops::Inner
    }
}

fn twice_area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum()
}

fn coord(p: [f64; 2]) -> Coord<f64> {
    Coord { x: p[0], y: p[1] }
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    orient2d(coord(a), coord(b), coord(c))
}

/// Whether segments `ab` and `cd` meet (touching included).
fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
        return true;
    }
    let on = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        r[0] >= p[0].min(q[0])
            && r[0] <= p[0].max(q[0])
            && r[1] >= p[1].min(q[1])
            && r[1] <= p[1].max(q[1])
    };
    (o1 == 0.0 && on(a, b, c))
        || (o2 == 0.0 && on(a, b, d))
        || (o3 == 0.0 && on(c, d, a))
        || (o4 == 0.0 && on(c, d, b))
}

/// Whether the closed polygon `p` is simple: no two of its segments meet except
/// neighbours at their shared corner (exact predicates).
pub(crate) fn is_simple(p: &[[f64; 2]]) -> bool {
    let n = p.len();
    if n < 3 {
        return false;
    }
    // Distinct corners.
    let mut sorted: Vec<[f64; 2]> = p.to_vec();
    sorted.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    if sorted.windows(2).any(|w| w[0] == w[1]) {
        return false;
    }
    // Segments bucketed on a grid.
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for q in p {
        for k in 0..2 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    let cells = ((n as f64).sqrt().ceil() as usize).max(1);
    let w = ((hi[0] - lo[0]) / cells as f64).max(f64::MIN_POSITIVE);
    let h = ((hi[1] - lo[1]) / cells as f64).max(f64::MIN_POSITIVE);
    let cell = |x: f64, lo: f64, s: f64| (((x - lo) / s) as usize).min(cells - 1);
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); cells * cells];
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        let (i0, i1) = (
            cell(a[0].min(b[0]), lo[0], w),
            cell(a[0].max(b[0]), lo[0], w),
        );
        let (j0, j1) = (
            cell(a[1].min(b[1]), lo[1], h),
            cell(a[1].max(b[1]), lo[1], h),
        );
        for j in j0..=j1 {
            for k in i0..=i1 {
                grid[j * cells + k].push(i as u32);
            }
        }
    }
    for bucket in &grid {
        for (x, &i) in bucket.iter().enumerate() {
            for &j in &bucket[x + 1..] {
                let (i, j) = (i as usize, j as usize);
                let neighbours = (i + 1) % n == j || (j + 1) % n == i;
                let (a, b) = (p[i], p[(i + 1) % n]);
                let (c, d) = (p[j], p[(j + 1) % n]);
                if neighbours {
                    // Neighbours share one corner: they must not overlap beyond it.
                    let (shared, other_i, other_j) = if (i + 1) % n == j {
                        (b, a, d)
                    } else {
                        (a, b, c)
                    };
                    if orient(other_i, shared, other_j) == 0.0 {
                        let dot = (other_i[0] - shared[0]) * (other_j[0] - shared[0])
                            + (other_i[1] - shared[1]) * (other_j[1] - shared[1]);
                        if dot > 0.0 {
                            return false;
                        }
                    }
                    continue;
                }
                if segments_meet(a, b, c, d) {
                    return false;
                }
            }
        }
    }
    true
}

/// What embedding one region gave: its refined faces (global vertex numbers; new vertices
/// numbered from the mesh's count on), their input triangles, the new vertices' places in A
/// and B, and the region's old interior vertices' places in B.
struct RegionResult {
    faces: Vec<[u32; 3]>,
    origin: Vec<u32>,
    new_a: Vec<[f64; 2]>,
    new_b: Vec<[f64; 2]>,
    placed: Vec<(u32, [f64; 2])>,
}

/// A triangulation being refined in `T_A`'s plane.
struct Work {
    /// Per local vertex: its place on the circle's disk, in A, and its global number
    /// (`u32::MAX` for a new vertex).
    t: Vec<[f64; 2]>,
    a: Vec<[f64; 2]>,
    global: Vec<u32>,
    faces: Vec<[u32; 3]>,
    origin: Vec<u32>,
    edge_face: HashMap<(u32, u32), usize>,
    /// Directed edges along an inserted chord.
    chord: std::collections::HashSet<(u32, u32)>,
    /// Per local vertex, whether it is on the circle.
    on_circle: Vec<bool>,
}

impl Work {
    fn set_face(&mut self, f: usize, tri: [u32; 3]) {
        for k in 0..3 {
            self.edge_face.insert((tri[k], tri[(k + 1) % 3]), f);
        }
        self.faces[f] = tri;
    }

    fn push_face(&mut self, tri: [u32; 3], origin: u32) {
        self.faces.push([0; 3]);
        self.origin.push(origin);
        let f = self.faces.len() - 1;
        self.set_face(f, tri);
    }

    /// The faces around vertex `v` (one of them `hint`), as `(face, next, previous)` with
    /// `face = (v, next, previous)` counter-clockwise.
    fn around(&self, v: u32, hint: usize) -> Vec<(usize, u32, u32)> {
        let corner = |f: usize| {
            let tri = self.faces[f];
            let k = tri.iter().position(|&x| x == v).unwrap_or(0);
            (f, tri[(k + 1) % 3], tri[(k + 2) % 3])
        };
        let mut out = vec![corner(hint)];
        // Counter-clockwise: the face across (v, previous).
        loop {
            let (_, _, pv) = out[out.len() - 1];
            match self.edge_face.get(&(v, pv)) {
                Some(&g) if g == hint => return out,
                Some(&g) if out.len() < 4096 => out.push(corner(g)),
                _ => break,
            }
        }
        // An open star: clockwise from the hint, across (next, v).
        let (_, mut nx, _) = corner(hint);
        while let Some(&g) = self.edge_face.get(&(nx, v)) {
            if out.len() >= 4096 {
                break;
            }
            let c = corner(g);
            nx = c.1;
            out.push(c);
        }
        out
    }

    /// Splits edge `(a, b)` (of face `f = (c, a, b)`) at fraction `s` from `a`; returns the
    /// new vertex.
    fn split(&mut self, f: usize, c: u32, a: u32, b: u32, s: f64) -> u32 {
        let lerp = |p: [f64; 2], q: [f64; 2]| [p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])];
        let x = self.t.len() as u32;
        self.t.push(lerp(self.t[a as usize], self.t[b as usize]));
        self.a.push(lerp(self.a[a as usize], self.a[b as usize]));
        self.global.push(u32::MAX);
        let g = self.edge_face.get(&(b, a)).copied();
        self.edge_face.remove(&(a, b));
        let o = self.origin[f];
        self.set_face(f, [c, a, x]);
        self.push_face([c, x, b], o);
        if let Some(g) = g {
            self.edge_face.remove(&(b, a));
            let tri = self.faces[g];
            let k = tri.iter().position(|&y| y == b).unwrap_or(0);
            let r = tri[(k + 2) % 3];
            let og = self.origin[g];
            // g = (b, a, r).
            self.set_face(g, [b, x, r]);
            self.push_face([x, a, r], og);
        }
        x
    }

    /// Inserts the chord from `u` to `v` (vertices on the circle).
    fn insert_chord(&mut self, u: u32, v: u32, star_hint: &mut HashMap<u32, usize>) -> bool {
        let mut cur = u;
        let target = self.t[v as usize];
        for _ in 0..100_000 {
            if self.edge_face.contains_key(&(cur, v)) || self.edge_face.contains_key(&(v, cur)) {
                self.chord.insert((cur, v));
                self.chord.insert((v, cur));
                return true;
            }
            let hint = match star_hint.get(&cur) {
                Some(&f) if self.faces[f].contains(&cur) => f,
                _ => match (0..self.faces.len()).find(|&f| self.faces[f].contains(&cur)) {
                    Some(f) => f,
                    None => return false,
                },
            };
            let pc = self.t[cur as usize];
            let mut step = None;
            for (f, a, b) in self.around(cur, hint) {
                let (pa, pb) = (self.t[a as usize], self.t[b as usize]);
                let oa = orient(pc, target, pa);
                let ob = orient(pc, target, pb);
                // The chord's direction is within the face's corner at `cur`: `a` right of
                // (or on) the chord, `b` left of (or on) it.
                if oa > 0.0 || ob < 0.0 {
                    continue;
                }
                let ahead = |p: [f64; 2]| {
                    (p[0] - pc[0]) * (target[0] - pc[0]) + (p[1] - pc[1]) * (target[1] - pc[1])
                        > 0.0
                };
                if oa == 0.0 && ahead(pa) {
                    step = Some(Step::Vertex(a));
                    break;
                }
                if ob == 0.0 && ahead(pb) {
                    step = Some(Step::Vertex(b));
                    break;
                }
                if oa < 0.0 && ob > 0.0 {
                    let s = oa / (oa - ob);
                    step = Some(if s < SNAP && self.global_inside(a) {
                        Step::Vertex(a)
                    } else if s > 1.0 - SNAP && self.global_inside(b) {
                        Step::Vertex(b)
                    } else {
                        Step::Split(f, a, b, s)
                    });
                    break;
                }
            }
            let Some(step) = step else { return false };
            let next = match step {
                Step::Vertex(w) => w,
                Step::Split(f, a, b, s) => {
                    let x = self.split(f, cur, a, b, s);
                    star_hint.insert(x, f);
                    x
                }
            };
            self.chord.insert((cur, next));
            self.chord.insert((next, cur));
            if let Some(&f) = self
                .edge_face
                .get(&(next, cur))
                .or(self.edge_face.get(&(cur, next)))
            {
                star_hint.insert(next, f);
            }
            cur = next;
            if cur == v {
                return true;
            }
        }
        false
    }

    /// Whether local vertex `w` may take a chord through it: not on the circle.
    fn global_inside(&self, w: u32) -> bool {
        self.on_circle.get(w as usize).is_none_or(|&c| !c)
    }
}

enum Step {
    Vertex(u32),
    Split(usize, u32, u32, f64),
}

/// The circle's corners for the region's boundary polygon `p`: by arc length over B, evenly,
/// or half of each, per attempt.
fn circle(p: &[[f64; 2]], attempt: usize) -> Vec<[f64; 2]> {
    let n = p.len();
    let lengths: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % n]);
            (b[0] - a[0]).hypot(b[1] - a[1])
        })
        .collect();
    let total: f64 = lengths.iter().sum();
    let share = match attempt {
        0 => 1.0,
        1 => 0.0,
        _ => 0.5,
    };
    let mut s = 0.0;
    (0..n)
        .map(|i| {
            let t = std::f64::consts::TAU * s;
            s += share * lengths[i] / total.max(f64::MIN_POSITIVE) + (1.0 - share) / n as f64;
            [t.cos(), t.sin()]
        })
        .collect()
}

/// A triangulation of the simple counter-clockwise polygon `p` without inner vertices
/// (constrained Delaunay), as triangles of corner indices, counter-clockwise.
pub(crate) fn triangulate_polygon(p: &[[f64; 2]]) -> Option<Vec<[u32; 3]>> {
    type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;
    let n = p.len();
    let points: Vec<Point2<f64>> = p.iter().map(|q| Point2::new(q[0], q[1])).collect();
    let edges: Vec<[usize; 2]> = (0..n).map(|i| [i, (i + 1) % n]).collect();
    let mut conflicts = 0;
    let cdt = Cdt::try_bulk_load_cdt(points, edges, |_| conflicts += 1).ok()?;
    if conflicts > 0 || cdt.num_vertices() != n {
        return None;
    }
    let index: HashMap<(u64, u64), u32> = p
        .iter()
        .enumerate()
        .map(|(i, q)| ((q[0].to_bits(), q[1].to_bits()), i as u32))
        .collect();
    let mut tris: Vec<[u32; 3]> = Vec::new();
    for f in cdt.inner_faces() {
        let mut tri = [0u32; 3];
        for (k, v) in f.vertices().iter().enumerate() {
            let q = v.position();
            tri[k] = *index.get(&(q.x.to_bits(), q.y.to_bits()))?;
        }
        let [a, b, c] = tri.map(|v| p[v as usize]);
        if orient(a, b, c) < 0.0 {
            tri.swap(1, 2);
        }
        tris.push(tri);
    }
    // Inside: flood from the triangles on the polygon's edges (counter-clockwise, the
    // polygon on their left) across edges that are not the polygon's.
    let mut edge_tri: HashMap<(u32, u32), usize> = HashMap::new();
    for (t, tri) in tris.iter().enumerate() {
        for k in 0..3 {
            edge_tri.insert((tri[k], tri[(k + 1) % 3]), t);
        }
    }
    let polygon_edge = |a: u32, b: u32| (a + 1) % n as u32 == b || (b + 1) % n as u32 == a;
    let mut inside = vec![false; tris.len()];
    let mut stack = Vec::new();
    for i in 0..n as u32 {
        let j = (i + 1) % n as u32;
        let t = *edge_tri.get(&(i, j))?;
        if !inside[t] {
            inside[t] = true;
            stack.push(t);
        }
    }
    while let Some(t) = stack.pop() {
        let tri = tris[t];
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            if polygon_edge(a, b) {
                continue;
            }
            if let Some(&u) = edge_tri.get(&(b, a)) {
                if !inside[u] {
                    inside[u] = true;
                    stack.push(u);
                }
            }
        }
    }
    let kept: Vec<[u32; 3]> = tris
        .into_iter()
        .zip(inside)
        .filter(|(_, i)| *i)
        .map(|(t, _)| t)
        .collect();
    (kept.len() == n - 2).then_some(kept)
}

/// Tutte's embedding (uniform weights) of the local mesh `faces` with the vertices
/// `0..boundary.len()` at `boundary`: the interior vertices' places.
fn tutte(faces: &[[u32; 3]], nv: usize, boundary: &[[f64; 2]]) -> Option<Vec<[f64; 2]>> {
    let nb = boundary.len();
    let k = nv - nb;
    let mut t = vec![[0.0; 2]; nv];
    t[..nb].copy_from_slice(boundary);
    if k == 0 {
        return Some(t);
    }
    let mut edges: Vec<(u32, u32)> = faces
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let mut pairs: Vec<(u32, u32)> = (0..k as u32).map(|i| (i, i)).collect();
    let mut values = vec![0.0; k];
    let mut rhs = vec![0.0; 2 * k];
    for &(a, b) in &edges {
        for (p, q) in [(a, b), (b, a)] {
            if (p as usize) < nb {
                continue;
            }
            let ip = p as usize - nb;
            values[ip] += 1.0;
            if (q as usize) < nb {
                rhs[ip] += boundary[q as usize][0];
                rhs[k + ip] += boundary[q as usize][1];
            } else if p > q {
                pairs.push((ip as u32, (q as usize - nb) as u32));
                values.push(-1.0);
            }
        }
    }
    let mut chol = bdmorph_cholesky::Cholesky::assemble(k, &pairs, &values, 2).ok()?;
    chol.solve_in_place(&mut rhs, 2).ok()?;
    for i in 0..k {
        t[nb + i] = [rhs[i], rhs[k + i]];
    }
    t.iter()
        .all(|p| p[0].is_finite() && p[1].is_finite())
        .then_some(t)
}

#[allow(clippy::too_many_arguments)]
fn embed_region(
    positions: &[[f64; 2]],
    faces: &[[u32; 3]],
    origin: &[u32],
    layout: &[[f64; 2]],
    region: &Region,
    attempt: usize,
    first_new: u32,
    min_area_a: f64,
    min_area_b: f64,
) -> Option<RegionResult> {
    let nb = region.boundary.len();
    let mut local: HashMap<u32, u32> = HashMap::new();
    let mut global: Vec<u32> = Vec::new();
    for &v in region.boundary.iter().chain(&region.interior) {
        local.insert(v, global.len() as u32);
        global.push(v);
    }
    let nv = global.len();
    let local_faces: Vec<[u32; 3]> = region
        .faces
        .iter()
        .map(|&f| faces[f].map(|v| local[&v]))
        .collect();
    let polygon: Vec<[f64; 2]> = region
        .boundary
        .iter()
        .map(|&v| layout[v as usize])
        .collect();
    let corners = circle(&polygon, if attempt == 1 { 1 } else { 0 });
    let t = tutte(&local_faces, nv, &corners)?;
    // B's side: the polygon triangulated without inner vertices, drawn on the same circle.
    let b_points = polygon.clone();
    let b_tris = triangulate_polygon(&polygon)?;
    let tb = corners.clone();
    let mut work = Work {
        t,
        a: global.iter().map(|&v| positions[v as usize]).collect(),
        global,
        faces: Vec::with_capacity(3 * local_faces.len()),
        origin: Vec::with_capacity(3 * local_faces.len()),
        edge_face: HashMap::with_capacity(9 * local_faces.len()),
        chord: std::collections::HashSet::new(),
        on_circle: (0..nv).map(|v| v < nb).collect(),
    };
    for (tri, &f) in local_faces.iter().zip(&region.faces) {
        work.push_face(*tri, origin[f]);
    }
    // B's diagonals (chords of the circle) into A's triangulation.
    let mut b_edges: Vec<(u32, u32)> = b_tris
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .filter(|&(a, b)| {
            let n = nb as u32;
            !(a < n && b < n && ((a + 1) % n == b || (b + 1) % n == a))
        })
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    b_edges.sort_unstable();
    b_edges.dedup();
    let mut hint: HashMap<u32, usize> = HashMap::new();
    for (f, tri) in work.faces.iter().enumerate() {
        for &v in tri {
            hint.insert(v, f);
        }
    }
    for &(u, v) in &b_edges {
        if !work.insert_chord(u, v, &mut hint) {
            return None;
        }
        work.on_circle.resize(work.t.len(), false);
    }
    // The cells between B's edges, each inside one triangle of B's.
    let nf = work.faces.len();
    let mut cell = vec![usize::MAX; nf];
    let mut cells = 0;
    for start in 0..nf {
        if cell[start] != usize::MAX {
            continue;
        }
        cell[start] = cells;
        let mut stack = vec![start];
        while let Some(f) = stack.pop() {
            let tri = work.faces[f];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if work.chord.contains(&(a, b)) {
                    continue;
                }
                if let Some(&g) = work.edge_face.get(&(b, a)) {
                    if cell[g] == usize::MAX {
                        cell[g] = cells;
                        stack.push(g);
                    }
                }
            }
        }
        cells += 1;
    }
    let mut largest = vec![(f64::NEG_INFINITY, 0usize); cells];
    for f in 0..nf {
        let area = signed_area(&work.t, &work.faces[f]);
        if area > largest[cell[f]].0 {
            largest[cell[f]] = (area, f);
        }
    }
    let disk_tri = |i: usize| b_tris[i].map(|v| tb[v as usize]);
    let holder: Vec<usize> = largest
        .iter()
        .map(|&(_, f)| {
            let [p, q, r] = work.faces[f].map(|v| work.t[v as usize]);
            let c = [(p[0] + q[0] + r[0]) / 3.0, (p[1] + q[1] + r[1]) / 3.0];
            (0..b_tris.len())
                .map(|i| {
                    let l = barycentric(disk_tri(i), c);
                    (l[0].min(l[1]).min(l[2]), i)
                })
                .max_by(|x, y| x.0.total_cmp(&y.0))
                .map_or(0, |(_, i)| i)
        })
        .collect();
    // Places over B.
    let nl = work.t.len();
    let mut b = vec![[f64::NAN; 2]; nl];
    b[..nb].copy_from_slice(&polygon);
    for f in 0..nf {
        let i = holder[cell[f]];
        for &v in &work.faces[f] {
            if !b[v as usize][0].is_nan() {
                continue;
            }
            let l = barycentric(disk_tri(i), work.t[v as usize]);
            let [p, q, r] = b_tris[i].map(|w| b_points[w as usize]);
            b[v as usize] = [
                l[0] * p[0] + l[1] * q[0] + l[2] * r[0],
                l[0] * p[1] + l[1] * q[1] + l[2] * r[1],
            ];
        }
    }
    // Every refined triangle valid in A and in B.
    let mut fail = None;
    for tri in &work.faces {
        if signed_area(&work.a, tri) <= min_area_a || signed_area(&b, tri) <= min_area_b {
            fail = Some(tri);
            break;
        }
    }
    if fail.is_some() {
        return None;
    }
    // Global numbers for the new vertices.
    let _ = positions.len();
    let mut next = first_new;
    let mut numbers = work.global.clone();
    let mut new_a = Vec::new();
    let mut new_b = Vec::new();
    for v in 0..nl {
        if numbers[v] == u32::MAX {
            numbers[v] = next;
            next += 1;
            new_a.push(work.a[v]);
            new_b.push(b[v]);
        }
    }
    Some(RegionResult {
        faces: work
            .faces
            .iter()
            .map(|tri| tri.map(|v| numbers[v as usize]))
            .collect(),
        origin: work.origin.clone(),
        new_a,
        new_b,
        placed: (nb..nv).map(|v| (work.global[v], b[v])).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 6x6 grid of squares, each cut in two, on [0, 6]².
    fn grid() -> PlanarMesh {
        let id = |i: u32, j: u32| j * 7 + i;
        let mut faces = Vec::new();
        for j in 0..6 {
            for i in 0..6 {
                faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let positions = (0..49)
            .map(|v| [f64::from(v % 7), f64::from(v / 7)])
            .collect();
        PlanarMesh { positions, faces }
    }

    #[test]
    fn a_grid_laid_over_a_slotted_square_is_refined_into_a_bijection() {
        let mesh = grid();
        // The boundary, counter-clockwise from (0, 0), onto a square with a deep slot cut
        // down from the middle of its top side: corners of the grid's triangles that have
        // all three vertices on the boundary cannot stay unflipped.
        let on = |p: [f64; 2]| p[0] == 0.0 || p[1] == 0.0 || p[0] == 6.0 || p[1] == 6.0;
        let mut layout = mesh.positions.clone();
        let fixed: Vec<bool> = mesh.positions.iter().map(|&p| on(p)).collect();
        for (v, p) in mesh.positions.iter().enumerate() {
            if p[1] == 6.0 {
                // The top side folds down into a slot 0.6 wide and 5 deep.
                let x = p[0];
                layout[v] = if x < 3.0 {
                    [
                        x.min(2.7),
                        6.0 - (x - 2.7).max(0.0) * 0.0
                            - if x > 2.0 { 5.0 * (x - 2.0) } else { 0.0 },
                    ]
                } else if x > 3.0 {
                    [
                        x.max(3.3),
                        6.0 - if x < 4.0 { 5.0 * (4.0 - x) } else { 0.0 },
                    ]
                } else {
                    [3.0, 1.0]
                };
            }
        }
        let polygon: Vec<[f64; 2]> = {
            // The boundary loop in order, for the check that it is simple.
            let mut l = Vec::new();
            for i in 0..7 {
                l.push(i);
            }
            for j in 1..7 {
                l.push(j * 7 + 6);
            }
            for i in (0..6).rev() {
                l.push(42 + i);
            }
            for j in (1..6).rev() {
                l.push(j * 7);
            }
            l.iter().map(|&v: &u32| layout[v as usize]).collect()
        };
        assert!(is_simple(&polygon), "{polygon:?}");
        let before = mesh
            .faces
            .iter()
            .filter(|f| signed_area(&layout, f) <= 0.0)
            .count();
        assert!(before > 0);
        let e = embed(&mesh, &layout, &fixed, 1e-12, 1e-14, 1e-14).unwrap();
        assert!(e.mesh.positions.len() > mesh.positions.len());
        assert!(e.mesh.faces.iter().all(|f| e.mesh.signed_area(f) > 0.0));
        assert!(e.mesh.faces.iter().all(|f| signed_area(&e.layout, f) > 0.0));
        // The input's vertices keep their places in A; held ones in B too.
        for v in 0..mesh.positions.len() {
            assert_eq!(e.mesh.positions[v], mesh.positions[v]);
            if fixed[v] {
                assert_eq!(e.layout[v], layout[v]);
            }
        }
        // New vertices are where their barycentric coordinates say, in A.
        for (k, (f, l)) in e.new_vertices.iter().enumerate() {
            let t = mesh.faces[*f as usize].map(|w| mesh.positions[w as usize]);
            let p = e.mesh.positions[mesh.positions.len() + k];
            let q = [
                l[0] * t[0][0] + l[1] * t[1][0] + l[2] * t[2][0],
                l[0] * t[0][1] + l[1] * t[1][1] + l[2] * t[2][1],
            ];
            assert!((p[0] - q[0]).hypot(p[1] - q[1]) < 1e-9);
            assert!(l.iter().all(|&x| x > -1e-9));
        }
        // The areas add up to the slotted square's.
        let area: f64 = e.mesh.faces.iter().map(|f| signed_area(&e.layout, f)).sum();
        assert!((area - 0.5 * twice_area(&polygon)).abs() < 1e-9);
    }

    #[test]
    fn polygons_are_simple_or_not() {
        let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!(is_simple(&square));
        let bow = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(!is_simple(&bow));
        let touching = [[0.0, 0.0], [2.0, 0.0], [1.0, 0.0], [1.0, 1.0]];
        assert!(!is_simple(&touching));
        let tris = triangulate_polygon(&square).unwrap();
        assert_eq!(tris.len(), 2);
    }
}
