//! Intrinsic Delaunay refinement: the surface is unchanged (area, boundary length, the whole
//! angle at every vertex: 2π or π at the vertices it inserts, the input's own elsewhere),
//! every input vertex is kept with its number, the result is Delaunay with the angle bound
//! met where it can be, and it ends within its budget on adversarial meshes (needles,
//! slivers, a sharp cone, a sharp boundary corner). And the heat method on the refined
//! triangulation.

use std::f64::consts::PI;

use bdmorph::geodesic::intrinsic::{triangle_area, Intrinsic};
use bdmorph::geodesic::{HeatGeodesics, HeatOptions};
use bdmorph::SurfaceMesh;

/// A small deterministic generator in `[0, 1)`.
fn noise(i: usize) -> f64 {
    let mut x = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 29;
    (x >> 11) as f64 / (1u64 << 53) as f64
}

fn mesh(positions: Vec<[f64; 3]>, faces: Vec<[u32; 3]>) -> SurfaceMesh {
    SurfaceMesh {
        positions,
        faces,
        texcoords: None,
    }
}

/// A grid of `nx` by `ny` cells over `[0, w] x [0, 1]`, diagonals at random, heights `z(x, y)`.
fn grid(nx: usize, ny: usize, w: f64, z: impl Fn(f64, f64) -> f64) -> SurfaceMesh {
    let mut positions = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) = (w * i as f64 / nx as f64, j as f64 / ny as f64);
            positions.push([x, y, z(x, y)]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut faces = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if noise(j * nx + i) < 0.5 {
                faces.extend([[a, b, c], [a, c, d]]);
            } else {
                faces.extend([[a, b, d], [b, c, d]]);
            }
        }
    }
    mesh(positions, faces)
}

/// A cone over a regular `n`-gon with its apex at `height`: the apex's whole angle shrinks as
/// the apex rises (about 35° at height 10).
fn sharp_cone(n: usize, height: f64) -> SurfaceMesh {
    let mut positions = vec![[0.0, 0.0, height]];
    for i in 0..n {
        let t = 2.0 * PI * i as f64 / n as f64;
        positions.push([t.cos(), t.sin(), 0.0]);
    }
    let faces = (0..n as u32)
        .map(|i| [0, 1 + i, 1 + (i + 1) % n as u32])
        .collect();
    mesh(positions, faces)
}

/// A flat wedge of opening `degrees` and `rows` rows of vertices: a boundary corner as sharp
/// as its opening.
fn wedge(degrees: f64, rows: usize) -> SurfaceMesh {
    let a = degrees.to_radians();
    let mut positions = vec![[0.0, 0.0, 0.0]];
    let mut faces = Vec::new();
    for r in 1..=rows {
        // Row r has r + 1 vertices across the wedge.
        for k in 0..=r {
            let t = a * k as f64 / r as f64;
            let rad = r as f64;
            positions.push([rad * t.cos(), rad * t.sin(), 0.0]);
        }
    }
    let start = |r: usize| if r == 0 { 0 } else { 1 + (r - 1) * (r + 2) / 2 };
    for r in 0..rows {
        let (p, q) = (start(r), start(r + 1));
        for k in 0..=r {
            faces.push([(p + k) as u32, (q + k) as u32, (q + k + 1) as u32]);
            if k < r {
                faces.push([(p + k) as u32, (q + k + 1) as u32, (p + k + 1) as u32]);
            }
        }
    }
    mesh(positions, faces)
}

/// Per vertex, the sum of its corner angles; the total area; the boundary length; and which
/// vertices lie on the boundary.
struct Measures {
    whole: Vec<f64>,
    area: f64,
    boundary: f64,
    on_boundary: Vec<bool>,
}

fn measure(tri: &Intrinsic) -> Measures {
    let n = tri.n_vertices();
    let mut whole = vec![0.0; n];
    let mut area = 0.0;
    for f in 0..tri.n_faces() {
        let (v, l) = tri.face(f);
        area += triangle_area(l[0], l[1], l[2]);
        for i in 0..3 {
            let (a, b, c) = (l[i], l[(i + 1) % 3], l[(i + 2) % 3]);
            whole[v[i] as usize] += ((b * b + c * c - a * a) / (2.0 * b * c))
                .clamp(-1.0, 1.0)
                .acos();
        }
    }
    let mut on_boundary = vec![false; n];
    let mut boundary = 0.0;
    for (a, b, l) in tri.boundary_edges() {
        on_boundary[a as usize] = true;
        on_boundary[b as usize] = true;
        boundary += l;
    }
    Measures {
        whole,
        area,
        boundary,
        on_boundary,
    }
}

/// Refines `mesh` and checks everything that must hold whatever the mesh; returns the
/// statistics and the refined triangulation.
fn refine_and_check(
    name: &str,
    mesh: &SurfaceMesh,
    degrees: f64,
    budget: usize,
    doubled: bool,
) -> (bdmorph::geodesic::RefineStats, Intrinsic) {
    let mut tri = Intrinsic::from_mesh(&mesh.positions, &mesh.faces).expect("valid mesh");
    if doubled {
        assert!(
            tri.double_across_boundary() > 0,
            "{name}: no boundary to glue"
        );
    }
    let n = tri.n_vertices();
    let before = measure(&tri);
    let stats = tri.refine(degrees, budget);
    let after = measure(&tri);
    eprintln!("{name}: {stats:?}, {} -> {} vertices", n, tri.n_vertices());
    let added = tri.n_vertices() - n;
    assert_eq!(added, stats.inserted + stats.split, "{name}: counts");
    assert!(
        added <= budget,
        "{name}: {added} insertions over the budget {budget}"
    );
    if stats.budget_reached {
        assert_eq!(added, budget, "{name}: stopped at the cap before it");
    }
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-300);
    assert!(
        rel(after.area, before.area) < 1e-9,
        "{name}: area {} -> {}",
        before.area,
        after.area
    );
    assert!(
        rel(after.boundary, before.boundary) < 1e-9
            || before.boundary == 0.0 && after.boundary == 0.0,
        "{name}: boundary length {} -> {}",
        before.boundary,
        after.boundary
    );
    // The input's vertices keep their numbers and whole angles; the new ones are flat.
    for v in 0..n {
        assert!(after.whole[v] > 0.0, "{name}: vertex {v} lost");
        assert!(
            (after.whole[v] - before.whole[v]).abs() < 1e-8,
            "{name}: vertex {v}'s angle {} -> {}",
            before.whole[v],
            after.whole[v]
        );
        assert_eq!(
            after.on_boundary[v], before.on_boundary[v],
            "{name}: vertex {v}"
        );
    }
    for v in n..tri.n_vertices() {
        let want = if after.on_boundary[v] { PI } else { 2.0 * PI };
        assert!(
            (after.whole[v] - want).abs() < 1e-8,
            "{name}: inserted vertex {v} has angle {} (on boundary: {})",
            after.whole[v],
            after.on_boundary[v]
        );
    }
    assert!(
        tri.worst_cot_sum() > -1e-9,
        "{name}: not Delaunay ({})",
        tri.worst_cot_sum()
    );
    (stats, tri)
}

#[test]
fn refinement_meets_the_bound_and_keeps_the_surface() {
    let slivers = grid(30, 4, 60.0, |_, _| 0.0);
    let bumpy = grid(16, 12, 8.0, |x, y| 0.3 * (0.8 * x).sin() * (2.0 * y).cos());
    for (name, mesh) in [("sliver strip", &slivers), ("bumpy grid", &bumpy)] {
        let (stats, tri) = refine_and_check(name, mesh, 30.0, 100_000, false);
        assert!(stats.inserted + stats.split > 0, "{name}: nothing inserted");
        assert_eq!(stats.below_bound, 0, "{name}: {stats:?}");
        assert!(!stats.budget_reached);
        assert!(stats.min_angle_degrees >= 30.0 - 1e-6, "{name}: {stats:?}");
        assert!((tri.smallest_angle().to_degrees() - stats.min_angle_degrees).abs() < 1e-9);
        // The same on the mesh glued to its mirror image along the boundary (closed).
        let (stats, tri) = refine_and_check(name, mesh, 30.0, 100_000, true);
        assert_eq!(stats.below_bound, 0, "{name} doubled: {stats:?}");
        assert!(tri.boundary_edges().is_empty());
        // Faces with a new vertex have no mirror image: weight one half.
        let halves = tri.weighted_faces().iter().filter(|f| f.2 == 0.5).count();
        assert!(halves > 0);
        let area: f64 = tri
            .weighted_faces()
            .iter()
            .map(|(_, l, w)| w * triangle_area(l[0], l[1], l[2]))
            .sum();
        let plain = Intrinsic::from_mesh(&mesh.positions, &mesh.faces).expect("valid");
        let want: f64 = (0..plain.n_faces())
            .map(|f| {
                let l = plain.face(f).1;
                triangle_area(l[0], l[1], l[2])
            })
            .sum();
        assert!(
            (area - want).abs() < 1e-9 * want,
            "{name}: weighted area {area} vs {want}"
        );
    }
}

#[test]
fn refinement_ends_on_adversarial_meshes_within_its_budget() {
    // Needles: a row of cells a thousandth as tall as they are wide.
    let needles = grid(30, 2, 1.0, |_, y| 0.0 * y);
    let mut needles = needles;
    for p in &mut needles.positions {
        p[1] *= 1e-3;
    }
    let meshes = [
        ("needles", needles),
        ("sliver strip 200:1", grid(200, 1, 200.0, |_, _| 0.0)),
        ("sharp cone", sharp_cone(12, 10.0)),
        ("5 degree wedge", wedge(5.0, 12)),
    ];
    for (name, mesh) in &meshes {
        let n = mesh.positions.len();
        for budget in [0, 7, n, 20 * n] {
            let (stats, _) = refine_and_check(name, mesh, 30.0, budget, false);
            assert!(stats.inserted + stats.split <= budget);
            if budget == 0 {
                assert_eq!(stats.inserted + stats.split, 0);
            }
        }
    }
    // The cone's apex (about 35 degrees all round) cannot be helped: the triangles at it
    // are left, and refinement still ends before its budget.
    let (stats, _) = refine_and_check("sharp cone", &meshes[2].1, 30.0, 100_000, false);
    assert!(!stats.budget_reached, "{stats:?}");
    assert!(stats.below_bound > 0);
}

/// A latitude-longitude sphere: thin triangles at the poles.
fn uv_sphere(slices: usize, stacks: usize) -> SurfaceMesh {
    let mut positions = vec![[0.0, 0.0, 1.0]];
    for j in 1..stacks {
        let phi = PI * j as f64 / stacks as f64;
        for i in 0..slices {
            let t = 2.0 * PI * i as f64 / slices as f64;
            positions.push([phi.sin() * t.cos(), phi.sin() * t.sin(), phi.cos()]);
        }
    }
    positions.push([0.0, 0.0, -1.0]);
    let south = positions.len() as u32 - 1;
    let id = |i: usize, j: usize| (1 + (j - 1) * slices + i % slices) as u32;
    let mut faces = Vec::new();
    for i in 0..slices {
        faces.push([0, id(i, 1), id(i + 1, 1)]);
        faces.push([south, id(i + 1, stacks - 1), id(i, stacks - 1)]);
    }
    for j in 1..stacks - 1 {
        for i in 0..slices {
            faces.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
            faces.push([id(i, j), id(i + 1, j + 1), id(i + 1, j)]);
        }
    }
    mesh(positions, faces)
}

#[test]
fn heat_on_the_refined_triangulation_reads_back_at_the_mesh_vertices() {
    let sphere = uv_sphere(48, 24);
    let n = sphere.positions.len();
    let arc = |s: usize| -> Vec<f64> {
        let p = sphere.positions[s];
        sphere
            .positions
            .iter()
            .map(|q| {
                (p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
                    .clamp(-1.0, 1.0)
                    .acos()
            })
            .collect()
    };
    let error = |d: &[f64], exact: &[f64]| {
        let (mut e, mut k) = (0.0, 0);
        for (a, b) in d.iter().zip(exact) {
            if *b > 1e-9 {
                e += (a - b).abs() / b;
                k += 1;
            }
        }
        e / k as f64
    };
    let mut plain = HeatGeodesics::new(&sphere, HeatOptions::default()).expect("set up");
    let options = HeatOptions::default().with_refinement(30.0, 2.0);
    let mut refined = HeatGeodesics::new(&sphere, options).expect("set up");
    let stats = refined.stats();
    eprintln!("{:?}", stats.refine);
    assert!(stats.refine.inserted + stats.refine.split > 0);
    assert_eq!(stats.refine.below_bound, 0);
    assert_eq!(refined.n_vertices(), n);
    for s in [0usize, 1, 5 * 48 + 7, n / 2, n - 1] {
        let exact = arc(s);
        let d = refined.distance(&[s as u32]).expect("query");
        assert_eq!(d.len(), n);
        assert_eq!(d[s], 0.0);
        assert!(d.iter().all(|x| x.is_finite() && *x >= 0.0));
        let (e_refined, e_plain) = (
            error(&d, &exact),
            error(&plain.distance(&[s as u32]).expect("query"), &exact),
        );
        eprintln!("uv sphere from {s}: refined {e_refined:.5}, not refined {e_plain:.5}");
        assert!(e_refined < 0.03, "from {s}: {e_refined}");
    }
    // Typed errors for the options.
    for (angle, budget) in [
        (-1.0, 0.5),
        (f64::NAN, 0.5),
        (20.0, -0.1),
        (20.0, f64::INFINITY),
    ] {
        let bad = HeatOptions::default().with_refinement(angle, budget);
        assert!(matches!(
            HeatGeodesics::new(&sphere, bad),
            Err(bdmorph::geodesic::GeodesicError::Refine { .. })
        ));
    }
}
