//! Meshes and deformations made in code, for tests, benchmarks and the demo.
//!
//! Everything here is deterministic (jitter comes from a hash of the vertex index, not from a
//! random generator), so a test or a benchmark sees the same mesh on every machine.
//!
//! ```
//! use bdmorph::generate;
//! let source = generate::disk(10, 0.2);
//! assert_eq!(source.positions.len(), 3 * 10 * 11 + 1);
//! let target = generate::twist(&source, 1.0);
//! assert_eq!(target.faces, source.faces);
//! ```

use std::f64::consts::TAU;

use crate::io::SurfaceMesh;
use crate::mesh::PlanarMesh;
use crate::render::Image;

/// A number in [-1, 1) from an integer, by a fixed hash (SplitMix64).
fn hash_unit(i: u64) -> f64 {
    let mut z = i.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// A triangulated unit disk: a centre vertex and `rings` concentric rings, ring `r` holding
/// `6 r` vertices (`3 rings (rings + 1) + 1` vertices in all). Consecutive rings are zipped by
/// angle. Interior vertices are jittered by up to `jitter` times the ring spacing (keep it
/// below about 0.3 for valid triangles).
pub fn disk(rings: usize, jitter: f64) -> PlanarMesh {
    let rings = rings.max(1);
    let h = 1.0 / rings as f64;
    let mut positions = vec![[0.0, 0.0]];
    let mut ring_start = vec![0usize];
    for r in 1..=rings {
        ring_start.push(positions.len());
        let n = 6 * r;
        // Offset alternate rings by half a step so zipped triangles are well shaped.
        let offset = if r % 2 == 0 { 0.5 } else { 0.0 };
        for i in 0..n {
            let a = (i as f64 + offset) / n as f64 * TAU;
            let mut p = [r as f64 * h * a.cos(), r as f64 * h * a.sin()];
            if r < rings {
                let id = positions.len() as u64;
                p[0] += jitter * h * hash_unit(2 * id);
                p[1] += jitter * h * hash_unit(2 * id + 1);
            }
            positions.push(p);
        }
    }
    let mut faces = Vec::new();
    // Centre fan.
    for i in 0..6u32 {
        faces.push([0, 1 + i, 1 + (i + 1) % 6]);
    }
    for r in 2..=rings {
        let (inner, outer) = (ring_start[r - 1], ring_start[r]);
        let (ni, no) = (6 * (r - 1), 6 * r);
        let offset_i = if (r - 1) % 2 == 0 { 0.5 } else { 0.0 };
        let offset_o = if r % 2 == 0 { 0.5 } else { 0.0 };
        let angle_i = |k: usize| (k as f64 + offset_i) / ni as f64;
        let angle_o = |k: usize| (k as f64 + offset_o) / no as f64;
        let (mut i, mut o) = (0usize, 0usize);
        while i < ni || o < no {
            let vi = (inner + i % ni) as u32;
            let vo = (outer + o % no) as u32;
            let advance_outer = i >= ni || (o < no && angle_o(o + 1) <= angle_i(i + 1));
            if advance_outer {
                faces.push([vi, vo, (outer + (o + 1) % no) as u32]);
                o += 1;
            } else {
                faces.push([vi, vo, (inner + (i + 1) % ni) as u32]);
                i += 1;
            }
        }
    }
    PlanarMesh { positions, faces }
}

/// The number of rings that makes [`disk`] have about `vertices` vertices.
pub fn rings_for(vertices: usize) -> usize {
    // 3 r^2 + 3 r + 1 = v.
    let r = ((12.0 * vertices as f64 - 3.0).max(0.0).sqrt() - 3.0) / 6.0;
    r.round().max(1.0) as usize
}

/// An `nx` by `ny` grid of vertices over `[0, nx - 1] x [0, ny - 1]`, two triangles per cell
/// with alternating diagonals; interior vertices jittered by up to `jitter`.
pub fn grid(nx: usize, ny: usize, jitter: f64) -> PlanarMesh {
    let (nx, ny) = (nx.max(2), ny.max(2));
    let mut positions = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let mut p = [i as f64, j as f64];
            if i > 0 && j > 0 && i + 1 < nx && j + 1 < ny {
                let id = (j * nx + i) as u64;
                p[0] += jitter * hash_unit(2 * id);
                p[1] += jitter * hash_unit(2 * id + 1);
            }
            positions.push(p);
        }
    }
    let id = |i: usize, j: usize| (j * nx + i) as u32;
    let mut faces = Vec::with_capacity(2 * (nx - 1) * (ny - 1));
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            if (i + j) % 2 == 0 {
                faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            } else {
                faces.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                faces.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
    PlanarMesh { positions, faces }
}

/// A fan of `n` triangles around one interior vertex at the origin, rim on the unit circle,
/// the rim radii varied by up to `jitter`.
pub fn fan(n: usize, jitter: f64) -> PlanarMesh {
    let n = n.max(3);
    let mut positions = vec![[0.0, 0.0]];
    for i in 0..n {
        let a = i as f64 / n as f64 * TAU;
        let r = 1.0 + jitter * hash_unit(i as u64);
        positions.push([r * a.cos(), r * a.sin()]);
    }
    let faces = (0..n as u32)
        .map(|i| [0, 1 + i, 1 + (i + 1) % n as u32])
        .collect();
    PlanarMesh { positions, faces }
}

fn map(mesh: &PlanarMesh, f: impl Fn([f64; 2]) -> [f64; 2]) -> PlanarMesh {
    PlanarMesh {
        positions: mesh.positions.iter().map(|&p| f(p)).collect(),
        faces: mesh.faces.clone(),
    }
}

/// Rotates each point about the centre of the bounding box by `angle * (1 - (r / R)^2)`
/// radians, `R` the largest distance from the centre: the middle turns by `angle`, the rim not
/// at all. Area preserving and orientation preserving.
pub fn twist(mesh: &PlanarMesh, angle: f64) -> PlanarMesh {
    let (c, radius) = centre_and_radius(mesh);
    map(mesh, |p| {
        let (x, y) = (p[0] - c[0], p[1] - c[1]);
        let r2 = (x * x + y * y) / (radius * radius);
        let a = angle * (1.0 - r2);
        let (s, co) = a.sin_cos();
        [c[0] + co * x - s * y, c[1] + s * x + co * y]
    })
}

/// Bends the shape: a point at horizontal offset `x` from the centre (relative to the radius)
/// is turned about a pivot below the shape, by `amount * x` radians, as a strip is bent into
/// an arc. Smooth and orientation preserving for `|amount|` below about 1.
pub fn bend(mesh: &PlanarMesh, amount: f64) -> PlanarMesh {
    let (c, radius) = centre_and_radius(mesh);
    map(mesh, |p| {
        let x = (p[0] - c[0]) / radius;
        let y = (p[1] - c[1]) / radius;
        if amount.abs() < 1e-12 {
            return p;
        }
        // Arc of radius rho = 1/amount: x runs along the arc, y across it.
        let rho = 1.0 / amount;
        let a = x * amount;
        let rr = rho - y;
        [
            c[0] + radius * rr * a.sin(),
            c[1] + radius * (rho - rr * a.cos()),
        ]
    })
}

/// Stretches the shape non-uniformly: `x` by a factor growing from `1 / s` on the left to `s`
/// on the right, smoothly. Orientation preserving for `s > 0`.
pub fn stretch(mesh: &PlanarMesh, s: f64) -> PlanarMesh {
    let (c, radius) = centre_and_radius(mesh);
    let k = s.max(1e-3).ln();
    map(mesh, |p| {
        let x = (p[0] - c[0]) / radius;
        // x' = (exp(k x) - 1) / k has derivative exp(k x) > 0.
        let xs = if k.abs() < 1e-12 {
            x
        } else {
            ((k * x).exp() - 1.0) / k
        };
        [c[0] + radius * xs, p[1]]
    })
}

fn centre_and_radius(mesh: &PlanarMesh) -> ([f64; 2], f64) {
    let (lo, hi) = mesh.bounds();
    let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let r = mesh
        .positions
        .iter()
        .map(|p| (p[0] - c[0]).hypot(p[1] - c[1]))
        .fold(0.0, f64::max);
    (c, if r > 0.0 { r } else { 1.0 })
}

/// The outline of a gingerbread figure (head, arms, legs), counter-clockwise, about 3.6 units
/// wide and 4.3 tall, feet at `y = -1.5`.
pub fn figure_outline() -> Vec<[f64; 2]> {
    // The right half from the crotch up to the neck; the head arc; the left half mirrored.
    let right: [[f64; 2]; 13] = [
        [0.15, -1.3],
        [0.2, -1.5],
        [0.75, -1.5],
        [0.8, -1.35],
        [0.6, -0.2],
        [0.62, 0.9],
        [0.6, 1.1],
        [1.4, 1.15],
        [1.65, 1.2],
        [1.75, 1.4],
        [1.65, 1.6],
        [1.3, 1.62],
        [0.5, 1.6],
    ];
    let mut outline = vec![[0.0, -0.3]];
    outline.extend(right);
    let (centre, radius) = ([0.0, 2.3], 0.5);
    for i in 0..=20 {
        let a = (-55.0 + 290.0 * f64::from(i) / 20.0_f64).to_radians();
        outline.push([centre[0] + radius * a.cos(), centre[1] + radius * a.sin()]);
    }
    outline.extend(right.iter().rev().map(|p| [-p[0], p[1]]));
    outline
}

/// A gingerbread figure triangulated by a refined constrained Delaunay triangulation (spade):
/// triangles of area at most `max_area` (in units of the outline, see [`figure_outline`]) and
/// no angle below 25 degrees. `max_area = 0.01` gives about 900 vertices.
pub fn figure(max_area: f64) -> PlanarMesh {
    polygons(&[figure_outline()], max_area)
}

/// Closed polygons (each a list of corners, either orientation) triangulated by a refined
/// constrained Delaunay triangulation (spade): the region of odd winding number (inside an
/// outline and outside the holes in it), triangles of area at most `max_area` and no angle
/// below 25 degrees, counter-clockwise. Disjoint outlines give several pieces. The polygons
/// must be simple and not cross each other; otherwise the mesh is empty.
pub fn polygons(loops: &[Vec<[f64; 2]>], max_area: f64) -> PlanarMesh {
    use spade::{
        AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
    };
    let empty = PlanarMesh {
        positions: Vec::new(),
        faces: Vec::new(),
    };
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    for outline in loops {
        if cdt
            .add_constraint_edges(outline.iter().map(|p| Point2::new(p[0], p[1])), true)
            .is_err()
        {
            return empty;
        }
    }
    let result = cdt.refine(
        RefinementParameters::<f64>::new()
            .exclude_outer_faces(true)
            .with_max_allowed_area(max_area.max(1e-5))
            .with_angle_limit(AngleLimit::from_deg(25.0)),
    );
    let excluded: std::collections::HashSet<_> = result.excluded_faces.into_iter().collect();
    // Keep the inner faces and number only the vertices they use, in first-use order.
    let mut index = vec![u32::MAX; cdt.num_vertices()];
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    for face in cdt.inner_faces() {
        if excluded.contains(&face.fix()) {
            continue;
        }
        let tri = face.vertices().map(|v| {
            let i = v.fix().index();
            if index[i] == u32::MAX {
                index[i] = positions.len() as u32;
                let p = v.position();
                positions.push([p.x, p.y]);
            }
            index[i]
        });
        faces.push(tri);
    }
    let mut mesh = PlanarMesh { positions, faces };
    for f in &mut mesh.faces {
        if mesh_signed_area(&mesh.positions, f) < 0.0 {
            f.swap(1, 2);
        }
    }
    mesh
}

/// A circle of `n` corners, radius `r`, centre `c`, counter-clockwise.
pub fn circle(c: [f64; 2], r: f64, n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            [c[0] + r * a.cos(), c[1] + r * a.sin()]
        })
        .collect()
}

/// An annulus: the unit disk with a hole of radius 0.4 in the middle, triangles of area at
/// most `max_area` (`0.005` gives about 500 vertices).
pub fn annulus(max_area: f64) -> PlanarMesh {
    polygons(
        &[circle([0.0, 0.0], 1.0, 48), circle([0.0, 0.0], 0.4, 20)],
        max_area,
    )
}

/// A figure with a hand on its hip: a body (1 wide, 4 tall, from the origin up) with a head,
/// and an arm (0.4 wide) from the shoulder (`y` 3 to 3.4) down to the hand, which rests on
/// the hip (`y` 0.6 to 1): the arm and the body enclose a hole (`x` 1 to 1.6, `y` 1 to 3),
/// as in a picture of such a figure meshed. Outlines are sampled every 0.05 (finer for
/// `max_area` below 0.005); triangles of area at most `max_area` (`0.005` gives about 1,300
/// vertices, `0.0006` about 9,000). See [`arm_across`].
pub fn hand_on_hip(max_area: f64) -> PlanarMesh {
    let step = (0.7 * max_area.max(1e-6).sqrt()).min(0.05);
    // The head: a circle on the neck (the body's top, `x` from `0.5 - w` to `0.5 + w`).
    let (centre, r) = ([0.5, 4.45], 0.5);
    let w = (r * r - (4.0f64 - centre[1]).powi(2)).sqrt();
    let mut outline = polyline(
        &[
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 0.6],
            [2.0, 0.6],
            [2.0, 3.4],
            [1.0, 3.4],
            [1.0, 4.0],
            [0.5 + w, 4.0],
        ],
        step,
    );
    let from = (4.0 - centre[1]).atan2(w);
    let sweep = TAU - 2.0 * (std::f64::consts::FRAC_PI_2 + from);
    let steps = (3.2 / step).ceil().max(64.0) as u32;
    for i in 1..steps {
        let a = from + sweep * f64::from(i) / f64::from(steps);
        outline.push([centre[0] + r * a.cos(), centre[1] + r * a.sin()]);
    }
    let mut back = polyline(&[[0.5 - w, 4.0], [0.0, 4.0], [0.0, 0.0]], step);
    back.pop();
    outline.extend(back);
    let mut hole = polyline(
        &[[1.0, 1.0], [1.0, 3.0], [1.6, 3.0], [1.6, 1.0], [1.0, 1.0]],
        0.05,
    );
    hole.pop();
    polygons(&[outline, hole], max_area)
}

/// The polyline through `corners`, sampled every `step` or less, both ends included.
fn polyline(corners: &[[f64; 2]], step: f64) -> Vec<[f64; 2]> {
    let mut out = Vec::new();
    for w in corners.windows(2) {
        let (a, b) = (w[0], w[1]);
        let k = ((a[0] - b[0]).hypot(a[1] - b[1]) / step).ceil().max(1.0) as usize;
        for j in 0..k {
            let s = j as f64 / k as f64;
            out.push([a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])]);
        }
    }
    out.extend(corners.last().copied());
    out
}

/// [`hand_on_hip`]'s arm swung across the body by `reach` at the elbow (mid-height of the
/// hole), the hand and the shoulder staying: every vertex right of the hole's middle
/// (`x > 1.3`) moves left by `reach` times a smooth bump over the hole's height. That is a
/// shear of the arm, so no triangle flips; from `reach > 0.6` the arm lies over the body and
/// the hole's outline crosses itself.
pub fn arm_across(figure: &PlanarMesh, reach: f64) -> PlanarMesh {
    let bump = |y: f64| {
        if y <= 1.0 || y >= 3.0 {
            0.0
        } else {
            (std::f64::consts::PI * (y - 1.0) / 2.0).sin().powi(2)
        }
    };
    PlanarMesh {
        positions: figure
            .positions
            .iter()
            .map(|&[x, y]| {
                if x > 1.3 {
                    [x - reach * bump(y), y]
                } else {
                    [x, y]
                }
            })
            .collect(),
        faces: figure.faces.clone(),
    }
}

/// A plate, 3 by 1.2, with two round holes, triangles of area at most `max_area` (`0.005`
/// gives about 600 vertices).
pub fn plate_with_two_holes(max_area: f64) -> PlanarMesh {
    let plate = vec![[-1.5, -0.6], [1.5, -0.6], [1.5, 0.6], [-1.5, 0.6]];
    polygons(
        &[
            plate,
            circle([-0.75, 0.0], 0.3, 16),
            circle([0.75, 0.05], 0.25, 14),
        ],
        max_area,
    )
}

fn mesh_signed_area(p: &[[f64; 2]], f: &[u32; 3]) -> f64 {
    let [a, b, c] = f.map(|v| p[v as usize]);
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Cubic smoothstep from 0 at `edge0` to 1 at `edge1` (either order).
fn smoothstep(edge0: f64, edge1: f64, x: f64) -> f64 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

fn rotate_about(p: [f64; 2], pivot: [f64; 2], angle: f64) -> [f64; 2] {
    let (s, c) = angle.sin_cos();
    let (x, y) = (p[0] - pivot[0], p[1] - pivot[1]);
    [pivot[0] + c * x - s * y, pivot[1] + s * x + c * y]
}

/// [`figure`] with its right arm raised by `angle` radians about the shoulder and nothing else
/// moved: the arm's rotation is blended in smoothly from the shoulder outwards (the weight of
/// [`wave`]'s arm), so the map stays smooth, and every point left of `x = 0.65` or below
/// `y = 0.6` keeps its place.
pub fn raise_arm(mesh: &PlanarMesh, angle: f64) -> PlanarMesh {
    map(mesh, |p| {
        let arm = smoothstep(0.65, 1.25, p[0]) * smoothstep(0.6, 1.0, p[1]);
        if arm > 0.0 {
            rotate_about(p, [0.55, 1.35], angle * arm)
        } else {
            p
        }
    })
}

/// A waving pose of [`figure`]: the right arm raised, the left lowered, the legs apart and the
/// head tilted, each by a rotation blended in smoothly along the limb (`amount = 1` for the
/// full pose). For meshes of the figure's outline only.
pub fn wave(mesh: &PlanarMesh, amount: f64) -> PlanarMesh {
    map(mesh, |p| {
        // Every weight is a function of the rest position p, and the regions barely overlap,
        // so the map stays smooth and its Jacobian positive.
        let arm = smoothstep(0.65, 1.25, p[0].abs()) * smoothstep(0.6, 1.0, p[1]);
        let leg = smoothstep(-0.3, -1.0, p[1]);
        let head = smoothstep(1.65, 2.0, p[1]) * (1.0 - smoothstep(0.5, 0.65, p[0].abs()));
        let right = p[0] > 0.0;
        let mut q = p;
        if arm > 0.0 {
            // The right arm waves up, the left one hangs down a little.
            let (pivot, angle) = if right {
                ([0.55, 1.35], 0.9)
            } else {
                ([-0.55, 1.35], 0.5)
            };
            q = rotate_about(q, pivot, amount * angle * arm);
        }
        if leg > 0.0 {
            let (pivot, angle) = if right {
                ([0.35, -0.25], 0.35)
            } else {
                ([-0.35, -0.25], -0.35)
            };
            q = rotate_about(q, pivot, amount * angle * leg);
        }
        if head > 0.0 {
            q = rotate_about(q, [0.0, 1.75], amount * 0.3 * head);
        }
        q
    })
}

/// A unit sphere: the icosahedron subdivided `subdivisions` times (each triangle into four),
/// vertices projected onto the sphere; `10 · 4^s + 2` vertices, outward-facing triangles.
/// Vertex 0 is `(0, 1, φ)` normalised, as in the usual icosahedron.
pub fn icosphere(subdivisions: u32) -> SurfaceMesh {
    let phi = (1.0 + 5f64.sqrt()) / 2.0;
    let mut positions: Vec<[f64; 3]> = [
        [-1.0, phi, 0.0],
        [1.0, phi, 0.0],
        [-1.0, -phi, 0.0],
        [1.0, -phi, 0.0],
        [0.0, -1.0, phi],
        [0.0, 1.0, phi],
        [0.0, -1.0, -phi],
        [0.0, 1.0, -phi],
        [phi, 0.0, -1.0],
        [phi, 0.0, 1.0],
        [-phi, 0.0, -1.0],
        [-phi, 0.0, 1.0],
    ]
    .iter()
    .map(|&p| normalize(p))
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoint = std::collections::HashMap::new();
        let mut mid = |a: u32, b: u32, positions: &mut Vec<[f64; 3]>| -> u32 {
            *midpoint.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (positions[a as usize], positions[b as usize]);
                positions.push(normalize([p[0] + q[0], p[1] + q[1], p[2] + q[2]]));
                (positions.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(4 * faces.len());
        for &[a, b, c] in &faces {
            let (ab, bc, ca) = (
                mid(a, b, &mut positions),
                mid(b, c, &mut positions),
                mid(c, a, &mut positions),
            );
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    SurfaceMesh {
        positions,
        faces,
        texcoords: None,
    }
}

/// The part of [`icosphere`] with `z >= z_min`, re-indexed: a spherical cap (a hemisphere for
/// `z_min = 0`), a disk-topology surface with a boundary. Faces with any vertex below `z_min`
/// are dropped.
pub fn sphere_cap(subdivisions: u32, z_min: f64) -> SurfaceMesh {
    let sphere = icosphere(subdivisions);
    let keep: Vec<bool> = sphere
        .positions
        .iter()
        .map(|p| p[2] >= z_min - 1e-12)
        .collect();
    let mut index = vec![u32::MAX; sphere.positions.len()];
    let mut positions = Vec::new();
    for (v, p) in sphere.positions.iter().enumerate() {
        if keep[v] {
            index[v] = positions.len() as u32;
            positions.push(*p);
        }
    }
    let faces = sphere
        .faces
        .iter()
        .filter(|f| f.iter().all(|&v| keep[v as usize]))
        .map(|f| f.map(|v| index[v as usize]))
        .collect();
    SurfaceMesh {
        positions,
        faces,
        texcoords: None,
    }
}

/// A coarse "finger": an open tube of unit radius along `z` with `rings` rings of `around`
/// vertices (`spacing` apart, alternate rings turned by half a step), closed at the top by a
/// fan to one tip vertex; open (the disk's boundary) at `z = 0`. Flattening it needs a scale
/// that falls exponentially towards the tip, which coarse triangles cannot follow with low
/// distortion: a hard case for bounded-distortion mappings, like the fingers of a hand.
pub fn finger(around: u32, rings: u32, spacing: f64) -> SurfaceMesh {
    let around = around.max(3);
    let rings = rings.max(1);
    let mut positions = Vec::with_capacity((around * rings + 1) as usize);
    for r in 0..rings {
        for i in 0..around {
            let a =
                std::f64::consts::TAU * (f64::from(i) + 0.5 * f64::from(r % 2)) / f64::from(around);
            positions.push([a.cos(), a.sin(), spacing * f64::from(r)]);
        }
    }
    let tip = positions.len() as u32;
    positions.push([0.0, 0.0, spacing * f64::from(rings - 1) + 0.8]);
    let id = |r: u32, i: u32| r * around + i % around;
    let mut faces = Vec::with_capacity((2 * around * rings) as usize);
    for r in 0..rings - 1 {
        for i in 0..around {
            if r % 2 == 0 {
                faces.push([id(r, i), id(r, i + 1), id(r + 1, i)]);
                faces.push([id(r, i + 1), id(r + 1, i + 1), id(r + 1, i)]);
            } else {
                faces.push([id(r, i), id(r, i + 1), id(r + 1, i + 1)]);
                faces.push([id(r, i), id(r + 1, i + 1), id(r + 1, i)]);
            }
        }
    }
    for i in 0..around {
        faces.push([id(rings - 1, i), id(rings - 1, i + 1), tip]);
    }
    SurfaceMesh {
        positions,
        faces,
        texcoords: None,
    }
}

fn normalize(p: [f64; 3]) -> [f64; 3] {
    let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    [p[0] / n, p[1] / n, p[2] / n]
}

/// A picture made in code, for meshing: `width` x `height` pixels, opaque where
/// `distance(x, y)` (a signed distance in pixels, negative inside; `x` from the left and `y`
/// from the top of the picture, sampled at pixel centres) is negative and transparent
/// elsewhere, with a one-pixel anti-aliased edge (opacity `0.5 - distance`, clamped). The
/// colours vary so that a texture shows its orientation: a hue ramp from left to right,
/// lighter towards the top, and a checkerboard with 8 squares across.
pub fn picture(width: u32, height: u32, distance: impl Fn(f64, f64) -> f64) -> Image {
    let mut rgba = Vec::with_capacity(4 * width as usize * height as usize);
    let side = f64::from(width.max(1)) / 8.0;
    for py in 0..height {
        for px in 0..width {
            let (x, y) = (f64::from(px) + 0.5, f64::from(py) + 0.5);
            let alpha = (0.5 - distance(x, y)).clamp(0.0, 1.0);
            let u = x / f64::from(width);
            let light = 1.0 - 0.5 * y / f64::from(height);
            let check = if ((x / side) as i64 + (y / side) as i64) % 2 == 0 {
                1.0
            } else {
                0.8
            };
            let shade = |c: f64| (255.0 * (c * light * check).clamp(0.0, 1.0)).round() as u8;
            rgba.extend([
                shade(0.3 + 0.7 * u),
                shade(0.6 - 0.3 * u),
                shade(1.0 - 0.8 * u),
                (255.0 * alpha).round() as u8,
            ]);
        }
    }
    Image {
        width,
        height,
        rgba,
    }
}

/// The signed distance from `p` to the segment `ab`, less `radius`: a capsule.
pub fn capsule_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2], radius: f64) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy) - radius
}

/// A disk of radius `r` about `centre` with a round hole of radius `hole_r` about
/// `hole_centre`, on a `size` x `size` [`picture`] (pixels from the top-left corner): one
/// piece with one hole.
pub fn ring_picture(
    size: u32,
    centre: [f64; 2],
    r: f64,
    hole_centre: [f64; 2],
    hole_r: f64,
) -> Image {
    picture(size, size, move |x, y| {
        let outer = capsule_distance([x, y], centre, centre, r);
        outer.max(-capsule_distance([x, y], hole_centre, hole_centre, hole_r))
    })
}

/// A figure drawn with capsules on a `size` x `size` [`picture`]: a head, a body, two arms and
/// two legs, one piece without holes. `arm` raises the figure's right arm (on the picture's
/// left) from hanging down (0) by that angle in radians (π: straight up); `bend` leans the
/// upper body (body, head and arms) about the hips by that angle (positive: to the
/// picture's right). Two drawings of one subject for in-betweens.
pub fn figure_picture(size: u32, arm: f64, bend: f64) -> Image {
    let s = f64::from(size);
    // In units of the picture, y up; the hips at (0.5, 0.42).
    let hips = [0.5, 0.42];
    let (sin, cos) = (-bend).sin_cos();
    let lean = move |p: [f64; 2]| {
        let (dx, dy) = (p[0] - hips[0], p[1] - hips[1]);
        [hips[0] + cos * dx - sin * dy, hips[1] + sin * dx + cos * dy]
    };
    let neck = lean([0.5, 0.66]);
    let head = lean([0.5, 0.79]);
    let (left_shoulder, right_shoulder) = (lean([0.43, 0.63]), lean([0.57, 0.63]));
    // The right arm (on the picture's left) hangs down and out, raised by `arm`.
    let hang = (-122f64).to_radians() - bend;
    let a = hang - arm;
    let left_hand = [
        left_shoulder[0] + 0.24 * a.cos(),
        left_shoulder[1] + 0.24 * a.sin(),
    ];
    let b = (-58f64).to_radians() - bend;
    let right_hand = [
        right_shoulder[0] + 0.24 * b.cos(),
        right_shoulder[1] + 0.24 * b.sin(),
    ];
    let (left_foot, right_foot) = ([0.4, 0.08], [0.6, 0.08]);
    picture(size, size, move |x, y| {
        let p = [x / s, 1.0 - y / s];
        let d = capsule_distance(p, hips, neck, 0.075)
            .min(capsule_distance(p, head, head, 0.085))
            .min(capsule_distance(p, left_shoulder, left_hand, 0.035))
            .min(capsule_distance(p, right_shoulder, right_hand, 0.035))
            .min(capsule_distance(p, [0.46, 0.42], left_foot, 0.04))
            .min(capsule_distance(p, [0.54, 0.42], right_foot, 0.04));
        s * d
    })
}

/// The meshing benchmark's subject on a `size` x `size` [`picture`]: a round body with a
/// hole and an arm, and a separate disk (two pieces, one hole).
pub fn picture_subject(size: u32) -> Image {
    let s = f64::from(size);
    picture(size, size, |x, y| {
        let p = [x / s, y / s];
        let body = capsule_distance(p, [0.45, 0.55], [0.45, 0.55], 0.3);
        let arm = capsule_distance(p, [0.6, 0.45], [0.9, 0.15], 0.04);
        let hole = capsule_distance(p, [0.4, 0.6], [0.4, 0.6], 0.1);
        let disk = capsule_distance(p, [0.82, 0.8], [0.82, 0.8], 0.1);
        s * body.min(arm).max(-hole).min(disk)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all_ccw(m: &PlanarMesh) -> bool {
        m.faces.iter().all(|f| m.signed_area(f) > 0.0)
    }

    #[test]
    fn fingers_are_disks_open_at_the_base() {
        let m = finger(6, 8, 0.6);
        assert_eq!(m.positions.len(), 6 * 8 + 1);
        let mut count = std::collections::HashMap::new();
        for f in &m.faces {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        let boundary: Vec<_> = count
            .iter()
            .filter(|(_, &c)| c == 1)
            .map(|(e, _)| *e)
            .collect();
        assert!(count.values().all(|&c| c <= 2));
        // Euler characteristic 1 (a disk), and the boundary is the base ring.
        assert_eq!(m.positions.len() + m.faces.len(), count.len() + 1);
        assert_eq!(boundary.len(), 6);
        assert!(boundary.iter().all(|&(a, b)| a < 6 && b < 6));
        // Consistent orientation: every interior edge is used once each way.
        let mut directed = std::collections::HashSet::new();
        for f in &m.faces {
            for k in 0..3 {
                assert!(directed.insert((f[k], f[(k + 1) % 3])), "{f:?}");
            }
        }
    }

    #[test]
    fn disks_are_valid_and_sized_as_documented() {
        for rings in [1, 2, 5, 20] {
            let m = disk(rings, 0.25);
            assert_eq!(m.positions.len(), 3 * rings * (rings + 1) + 1);
            assert_eq!(m.faces.len(), 6 * rings * rings);
            assert!(all_ccw(&m), "rings {rings}");
            m.validate().expect("valid disk");
        }
        assert_eq!(rings_for(1000), 18);
        assert_eq!(rings_for(3 * 57 * 58 + 1), 57);
    }

    #[test]
    fn grids_and_fans_are_valid() {
        let g = grid(7, 5, 0.2);
        assert!(all_ccw(&g));
        g.validate().expect("valid grid");
        let f = fan(9, 0.3);
        assert!(all_ccw(&f));
        f.validate().expect("valid fan");
    }

    #[test]
    fn figure_is_a_valid_disk_and_waves_without_flips() {
        let m = figure(0.01);
        assert!(m.positions.len() > 500, "{} vertices", m.positions.len());
        m.validate().expect("valid figure");
        bdmorph_compiler::compile(&m.positions, &m.faces).expect("a disk");
        let w = wave(&m, 1.0);
        assert!(
            all_ccw(&w),
            "the waving pose keeps every triangle counter-clockwise"
        );
        assert_eq!(figure(0.01), m, "deterministic");
    }

    #[test]
    fn deformations_keep_orientation() {
        let m = disk(12, 0.2);
        for d in [twist(&m, 1.5), bend(&m, 0.8), stretch(&m, 2.0)] {
            assert!(all_ccw(&d));
            assert_eq!(d.faces, m.faces);
        }
    }
}
