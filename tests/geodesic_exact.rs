//! Exact polyhedral geodesics: closed forms on developable surfaces (a tilted plane with an
//! irregular triangulation, a prism unrolled, a polyhedral cone unrolled), pygeodesic's MMP
//! distances on shared meshes, paths, several sources and pieces, typed errors.

mod common;

use bdmorph::generate;
use bdmorph::geodesic::{
    descend, ExactGeodesics, GeodesicError, HeatGeodesics, HeatOptions, OnSurface,
};
use bdmorph::SurfaceMesh;
use std::f64::consts::PI;

/// A small deterministic generator in `[0, 1)`.
fn noise(i: usize) -> f64 {
    let mut x = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 29;
    (x >> 11) as f64 / (1u64 << 53) as f64
}

fn largest_error(got: &[f64], want: &[f64]) -> f64 {
    got.iter()
        .zip(want)
        .map(|(g, w)| (g - w).abs())
        .fold(0.0, f64::max)
}

/// The rectangle `[0, 2] x [0, 1]` in a tilted plane of space, `nx` by `ny` cells with the
/// inner vertices moved at random (by up to 0.2 of a cell, so that no triangle turns over) and the diagonals chosen at
/// random: irregular, with slivers. Returns the mesh and each vertex's plane coordinates.
fn tilted_plane(nx: usize, ny: usize) -> (SurfaceMesh, Vec<[f64; 2]>) {
    let mut flat = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (mut x, mut y) = (2.0 * i as f64 / nx as f64, j as f64 / ny as f64);
            if i > 0 && i < nx && j > 0 && j < ny {
                let k = flat.len();
                x += (noise(2 * k) - 0.5) * 0.4 * 2.0 / nx as f64;
                y += (noise(2 * k + 1) - 0.5) * 0.4 / ny as f64;
            }
            flat.push([x, y]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut faces = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if noise(1000 + j * nx + i) < 0.5 {
                faces.push([a, b, c]);
                faces.push([a, c, d]);
            } else {
                faces.push([a, b, d]);
                faces.push([b, c, d]);
            }
        }
    }
    for f in &faces {
        let [a, b, c] = f.map(|v| flat[v as usize]);
        let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        assert!(area > 0.0, "a triangle turned over");
    }
    // An orthonormal frame of a tilted plane.
    let u = [0.6, 0.0, 0.8];
    let v = [0.0, 1.0, 0.0];
    let positions = flat
        .iter()
        .map(|&[x, y]| {
            [
                1.0 + x * u[0] + y * v[0],
                -2.0 + x * u[1] + y * v[1],
                0.5 + x * u[2] + y * v[2],
            ]
        })
        .collect();
    (
        SurfaceMesh {
            positions,
            faces,
            texcoords: None,
        },
        flat,
    )
}

#[test]
fn on_a_plane_the_distance_is_the_straight_line() {
    let (mesh, flat) = tilted_plane(24, 12);
    let mut exact = ExactGeodesics::new(&mesh).expect("set up");
    for source in [0usize, 13, 160, flat.len() / 2, flat.len() - 1] {
        let d = exact.distance(&[source as u32]).expect("query");
        let want: Vec<f64> = flat
            .iter()
            .map(|p| (p[0] - flat[source][0]).hypot(p[1] - flat[source][1]))
            .collect();
        let err = largest_error(&d, &want);
        eprintln!("plane from {source}: {err:e} ({:?})", exact.stats());
        assert!(err < 1e-12, "plane from {source}: {err}");
    }
}

/// An open prism of `n` sides (inscribed in the unit circle) and `rings` rows of vertices at
/// irregular heights: its side unrolls into a strip `n` chords wide.
fn prism(n: usize, rings: usize) -> (SurfaceMesh, Vec<f64>) {
    let mut heights = vec![0.0];
    for r in 1..rings {
        heights.push(heights[r - 1] + 0.2 + 0.3 * noise(r));
    }
    let mut positions = Vec::new();
    for &z in &heights {
        for i in 0..n {
            let t = 2.0 * PI * i as f64 / n as f64;
            positions.push([t.cos(), t.sin(), z]);
        }
    }
    let id = |i: usize, r: usize| (r * n + i % n) as u32;
    let mut faces = Vec::new();
    for r in 0..rings - 1 {
        for i in 0..n {
            faces.push([id(i, r), id(i + 1, r), id(i + 1, r + 1)]);
            faces.push([id(i, r), id(i + 1, r + 1), id(i, r + 1)]);
        }
    }
    (
        SurfaceMesh {
            positions,
            faces,
            texcoords: None,
        },
        heights,
    )
}

#[test]
fn on_a_prism_the_distance_is_the_straight_line_of_the_unrolled_strip() {
    let (n, rings) = (20, 9);
    let (mesh, heights) = prism(n, rings);
    let chord = 2.0 * (PI / n as f64).sin();
    let mut exact = ExactGeodesics::new(&mesh).expect("set up");
    for (i0, r0) in [(0, 0), (3, 4), (7, 8), (11, 2)] {
        let d = exact.distance(&[(r0 * n + i0) as u32]).expect("query");
        let mut want = Vec::new();
        for (r, z) in heights.iter().enumerate() {
            for i in 0..n {
                let around = (i as i64 - i0 as i64).unsigned_abs() as usize;
                let around = around.min(n - around) as f64 * chord;
                want.push(around.hypot(z - heights[r0]));
                let _ = r;
            }
        }
        let err = largest_error(&d, &want);
        eprintln!("prism from ({i0}, {r0}): {err:e}");
        assert!(err < 1e-12, "prism from ({i0}, {r0}): {err}");
    }
}

/// A polyhedral cone: the apex, and `rings` rows of `n` vertices on irregularly spaced
/// generators at irregular slant distances. Returns the mesh, each vertex's slant distance
/// and unrolled angle, and the total angle at the apex.
fn cone(n: usize, rings: usize) -> (SurfaceMesh, Vec<(f64, f64)>, f64) {
    let half = 0.5f64; // the half-angle of the cone, in radians
    let mut around = vec![0.0];
    for i in 1..n {
        around.push(around[i - 1] + 1.0 + 0.6 * noise(50 + i));
    }
    let total = around[n - 1] + 1.0 + 0.6 * noise(50 + n);
    let generators: Vec<[f64; 3]> = around
        .iter()
        .map(|a| {
            let t = 2.0 * PI * a / total;
            [half.sin() * t.cos(), half.sin() * t.sin(), half.cos()]
        })
        .collect();
    // Unrolled angles: the angles between consecutive generators, summed.
    let gap = |a: [f64; 3], b: [f64; 3]| (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).acos();
    let mut unrolled = vec![0.0];
    for i in 1..n {
        unrolled.push(unrolled[i - 1] + gap(generators[i - 1], generators[i]));
    }
    let theta = unrolled[n - 1] + gap(generators[n - 1], generators[0]);
    let mut positions = vec![[0.0; 3]];
    let mut polar = vec![(0.0, 0.0)];
    let mut s = 0.0;
    for r in 0..rings {
        s += 0.3 + 0.4 * noise(100 + r);
        for i in 0..n {
            positions.push(generators[i].map(|c| c * s));
            polar.push((s, unrolled[i]));
        }
    }
    let id = |i: usize, r: usize| (1 + r * n + i % n) as u32;
    let mut faces = Vec::new();
    for i in 0..n {
        faces.push([0, id(i, 0), id(i + 1, 0)]);
    }
    for r in 0..rings - 1 {
        for i in 0..n {
            faces.push([id(i, r), id(i, r + 1), id(i + 1, r + 1)]);
            faces.push([id(i, r), id(i + 1, r + 1), id(i + 1, r)]);
        }
    }
    (
        SurfaceMesh {
            positions,
            faces,
            texcoords: None,
        },
        polar,
        theta,
    )
}

#[test]
fn on_a_cone_the_distance_is_the_straight_line_of_the_unrolled_sector() {
    let (mesh, polar, theta) = cone(16, 7);
    assert!(theta < PI * 1.2, "the cone's total angle {theta}");
    let mut exact = ExactGeodesics::new(&mesh).expect("set up");
    for source in [0usize, 1, 20, 50, polar.len() - 1] {
        let d = exact.distance(&[source as u32]).expect("query");
        let (s0, a0) = polar[source];
        let want: Vec<f64> = polar
            .iter()
            .map(|&(s, a)| {
                let gap = (a - a0).abs();
                let gap = gap.min(theta - gap);
                // Never through the apex: `gap` stays below π.
                (s * s + s0 * s0 - 2.0 * s * s0 * gap.cos()).max(0.0).sqrt()
            })
            .collect();
        let err = largest_error(&d, &want);
        eprintln!("cone from {source}: {err:e}");
        assert!(err < 1e-12, "cone from {source}: {err}");
    }
}

/// Exact polyhedral distances from a file of `tests/data/` (pygeodesic 0.1.11's MMP
/// algorithm, 9 significant digits, written by `tools/exact_geodesics.py`).
fn exact_file(text: &str) -> Vec<f64> {
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.trim().parse().expect("a number"))
        .collect()
}

#[test]
fn shared_meshes_match_pygeodesic() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    let cases = [
        (
            "disk3d/ustc-cg/Isis_dABF.obj",
            0,
            include_str!("data/isis_exact_0.txt"),
        ),
        (
            "disk3d/ustc-cg/Isis_dABF.obj",
            53,
            include_str!("data/isis_exact_53.txt"),
        ),
        (
            "disk3d/ustc-cg/Nefertiti_face.obj",
            0,
            include_str!("data/nefertiti_exact_0.txt"),
        ),
        (
            "disk3d/ustc-cg/Nefertiti_face.obj",
            206,
            include_str!("data/nefertiti_exact_206.txt"),
        ),
        (
            "disk3d/libigl/camelhead.off",
            0,
            include_str!("data/camelhead_exact_0.txt"),
        ),
    ];
    for (rel, source, text) in cases {
        let mesh = bdmorph::io::read_mesh(dir.join(rel)).expect("mesh");
        let want = exact_file(text);
        let mut exact = ExactGeodesics::new(&mesh).expect("set up");
        let d = exact.distance(&[source]).expect("query");
        // The files keep 9 significant digits.
        let worst = d
            .iter()
            .zip(&want)
            .map(|(g, w)| (g - w).abs() / w.abs().max(1e-300))
            .filter(|e| e.is_finite())
            .fold(0.0, f64::max);
        eprintln!(
            "{rel} from {source}: {worst:e} relative ({:?})",
            exact.stats()
        );

        assert!(worst < 1e-8, "{rel} from {source}: {worst}");
        // A path that bends at saddles: to the farthest vertex, as long as its distance.
        let far = (0..d.len())
            .max_by(|&i, &j| d[i].total_cmp(&d[j]))
            .expect("vertices");
        let path = exact.path(source, far as u32).expect("path");
        assert!(
            (path.length() - d[far]).abs() < 1e-9 * d[far],
            "{rel}: path {} vs distance {}",
            path.length(),
            d[far]
        );
    }
}

#[test]
fn a_path_is_as_long_as_the_distance_and_lies_on_the_surface() {
    for mesh in [generate::icosphere(3), prism(20, 9).0, cone(16, 7).0] {
        let mut exact = ExactGeodesics::new(&mesh).expect("set up");
        let n = mesh.positions.len() as u32;
        for (a, b) in [(0, n - 1), (1, n / 2), (n / 3, 2 * n / 3 + 1)] {
            let d = exact.distance(&[a]).expect("query");
            let path = exact.path(a, b).expect("path");
            assert_eq!(path.points[0].on, OnSurface::Vertex(a));
            assert_eq!(path.points[path.points.len() - 1].on, OnSurface::Vertex(b));
            let err = (path.length() - d[b as usize]).abs();
            assert!(
                err < 1e-9,
                "{a} -> {b}: {} vs {}",
                path.length(),
                d[b as usize]
            );
            for p in &path.points {
                if let OnSurface::Edge { from, to, t } = p.on {
                    assert!(t > 0.0 && t < 1.0);
                    let (x, y) = (mesh.positions[from as usize], mesh.positions[to as usize]);
                    for k in 0..3 {
                        let want = x[k] + t * (y[k] - x[k]);
                        assert!((p.position[k] - want).abs() < 1e-12);
                    }
                }
            }
        }
    }
}

#[test]
fn several_sources_give_the_nearest_and_other_pieces_are_infinitely_far() {
    let a = generate::icosphere(2);
    let mut both = a.clone();
    let offset = a.positions.len() as u32;
    both.positions
        .extend(a.positions.iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
    both.faces
        .extend(a.faces.iter().map(|f| f.map(|v| v + offset)));
    let mut exact = ExactGeodesics::new(&both).expect("set up");
    let d0 = exact.distance(&[0]).expect("query");
    assert!(d0[..offset as usize].iter().all(|x| x.is_finite()));
    assert!(d0[offset as usize..].iter().all(|x| x.is_infinite()));
    let d7 = exact.distance(&[7]).expect("query");
    let both_sources = exact.distance(&[0, 7]).expect("query");
    for v in 0..offset as usize {
        assert!((both_sources[v] - d0[v].min(d7[v])).abs() < 1e-12);
    }
    assert!(matches!(
        exact.path(0, offset + 3),
        Err(GeodesicError::Unreachable { .. })
    ));
}

#[test]
fn bad_input_is_a_typed_error() {
    let sphere = generate::icosphere(1);
    let mut exact = ExactGeodesics::new(&sphere).expect("set up");
    assert!(matches!(exact.distance(&[]), Err(GeodesicError::NoSources)));
    assert!(matches!(
        exact.distance(&[10_000]),
        Err(GeodesicError::SourceOutOfRange { .. })
    ));
    let mut out = vec![0.0; 3];
    assert!(matches!(
        exact.distance_into(&[0], &mut out),
        Err(GeodesicError::OutputLength { .. })
    ));
    let mut tight = ExactGeodesics::new(&generate::icosphere(3))
        .expect("set up")
        .with_max_windows(10);
    assert!(matches!(
        tight.distance(&[0]),
        Err(GeodesicError::WindowBudget { windows: 10 })
    ));
    let mut flipped = sphere.clone();
    flipped.faces[0].swap(1, 2);
    assert!(ExactGeodesics::new(&flipped).is_err());
    let mut nan = sphere;
    nan.positions[3][1] = f64::NAN;
    assert!(matches!(
        ExactGeodesics::new(&nan),
        Err(GeodesicError::NonFinite { vertex: 3 })
    ));
}

/// Every point of a path lies on the mesh where it says, and consecutive points share a face.
fn check_on_surface(mesh: &SurfaceMesh, path: &bdmorph::geodesic::GeodesicPath) {
    let verts = |p: &bdmorph::geodesic::PathPoint| -> Vec<u32> {
        match p.on {
            OnSurface::Vertex(v) => vec![v],
            OnSurface::Edge { from, to, t } => {
                assert!(t > 0.0 && t < 1.0);
                let (x, y) = (mesh.positions[from as usize], mesh.positions[to as usize]);
                for k in 0..3 {
                    assert!((p.position[k] - (x[k] + t * (y[k] - x[k]))).abs() < 1e-12);
                }
                vec![from, to]
            }
        }
    };
    for w in path.points.windows(2) {
        let (a, b) = (verts(&w[0]), verts(&w[1]));
        assert!(
            mesh.faces
                .iter()
                .any(|f| a.iter().chain(&b).all(|v| f.contains(v))),
            "{:?} and {:?} share no face",
            w[0].on,
            w[1].on
        );
    }
}

#[test]
fn heat_paths_run_down_the_distance_close_to_the_shortest() {
    let (plane, flat) = tilted_plane(24, 12);
    let mut meshes = vec![("plane", plane), ("sphere", generate::icosphere(4))];
    if let Some(dir) = common::shared_data() {
        meshes.push((
            "camel head",
            bdmorph::io::read_mesh(dir.join("disk3d/libigl/camelhead.off")).expect("mesh"),
        ));
    }
    for (name, mesh) in &meshes {
        let mut heat = HeatGeodesics::new(mesh, HeatOptions::default()).expect("set up");
        let mut exact = ExactGeodesics::new(mesh).expect("set up");
        let n = mesh.positions.len() as u32;
        let mut worst: f64 = 0.0;
        for (a, b) in [(0, n - 1), (n / 3, 2 * n / 3 + 1), (7, n / 2)] {
            let d = heat.distance(&[a]).expect("query");
            let path = descend(mesh, &d, b).expect("a path down");
            assert_eq!(path.points[0].on, OnSurface::Vertex(a), "{name}");
            assert_eq!(path.points[path.points.len() - 1].on, OnSurface::Vertex(b));
            check_on_surface(mesh, &path);
            let shortest = exact.distance(&[a]).expect("exact")[b as usize];
            let ratio = path.length() / shortest;
            assert!(
                ratio >= 1.0 - 1e-9,
                "{name} {a} -> {b}: shorter than the shortest"
            );
            worst = worst.max(ratio);
            let exact_path = exact.path(a, b).expect("path");
            check_on_surface(mesh, &exact_path);
        }
        eprintln!("{name}: heat paths at most {worst:.4} times the shortest");
        assert!(worst < 1.03, "{name}: {worst}");
    }
    let _ = flat;
}

#[test]
fn a_field_with_a_false_minimum_is_a_typed_error() {
    let sphere = generate::icosphere(2);
    let mut d: Vec<f64> = sphere.positions.iter().map(|p| 1.0 - p[2]).collect();
    let top = (0..d.len())
        .min_by(|&i, &j| d[i].total_cmp(&d[j]))
        .expect("vertices");
    d[top] = 0.0;
    // A dent: the bottom vertex lower than all its neighbours, but not a source.
    let far = (0..d.len())
        .max_by(|&i, &j| d[i].total_cmp(&d[j]))
        .expect("vertices");
    d[far] = 0.5;
    let r = descend(&sphere, &d, far as u32);
    assert!(matches!(r, Err(GeodesicError::NoDescent { .. })), "{r:?}");
    assert!(matches!(
        descend(&sphere, &d[1..], 0),
        Err(GeodesicError::OutputLength { .. })
    ));
}
