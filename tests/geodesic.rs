//! Heat-method geodesics: accuracy against exact distances, the properties of a distance,
//! several sources, intrinsic Delaunay (flips across the boundary, mollification, the time
//! step), boundary conditions and the command line's note at boundary sources, errors.

mod common;

use bdmorph::generate;
use bdmorph::geodesic::intrinsic::TriangulationError;
use bdmorph::geodesic::{
    Anchor, Boundary, ExactGeodesics, GeodesicError, HeatGeodesics, HeatOptions, TimeScale,
};
use bdmorph::SurfaceMesh;
use std::f64::consts::FRAC_1_SQRT_2;

/// Mean of `|got - exact| / exact` over the vertices with `exact > 0`.
fn mean_relative_error(got: &[f64], exact: &[f64]) -> f64 {
    let (mut sum, mut count) = (0.0, 0);
    for (g, e) in got.iter().zip(exact) {
        if *e > 0.0 {
            sum += (g - e).abs() / e;
            count += 1;
        }
    }
    sum / f64::from(count)
}

/// Exact distances on a unit sphere from vertex `source`: the angle.
fn arccos(mesh: &SurfaceMesh, source: usize) -> Vec<f64> {
    let p = mesh.positions[source];
    mesh.positions
        .iter()
        .map(|q| {
            (p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
                .clamp(-1.0, 1.0)
                .acos()
        })
        .collect()
}

/// A flat rectangle `[0, 10] x [0, 1]` of `nx` by `ny` cells, each split along the diagonal
/// that makes the worst (most obtuse) triangles when the cells are long and thin, with the
/// rows sheared alternately so that no triangle is right-angled: geodesics are straight
/// lines, so the exact distance is the Euclidean one.
fn sliver_strip(nx: usize, ny: usize) -> SurfaceMesh {
    let mut positions = Vec::new();
    for j in 0..=ny {
        let shift = if j % 2 == 1 { 0.35 } else { 0.0 };
        for i in 0..=nx {
            let x = if i == 0 || i == nx {
                i as f64
            } else {
                i as f64 + shift
            };
            positions.push([10.0 * x / nx as f64, j as f64 / ny as f64, 0.0]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut faces = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    SurfaceMesh {
        positions,
        faces,
        texcoords: None,
    }
}

#[test]
fn sphere_distances_are_as_accurate_as_the_peers() {
    // The peers (libigl 2.6.3, potpourri3d 1.4.0, CGAL 5.5) reach 0.0188 on the shared
    // 642-vertex sphere (below). The generated icosphere of 3 subdivisions has 642 vertices
    // too, but other ones: about 0.02 there, less on finer spheres.
    for (subdivisions, bar) in [(3, 0.021), (4, 0.012)] {
        let sphere = generate::icosphere(subdivisions);
        let mut heat = HeatGeodesics::new(&sphere, HeatOptions::default()).expect("set up");
        assert!(!heat.stats().has_boundary);
        let n = sphere.positions.len();
        for source in [0, n / 3, n - 1] {
            let d = heat.distance(&[source as u32]).expect("query");
            let err = mean_relative_error(&d, &arccos(&sphere, source));
            eprintln!("icosphere({subdivisions}), source {source}: {err:.5}");
            assert!(err < bar, "source {source}: mean relative error {err}");
        }
    }
    let Some(dir) = common::shared_data() else {
        return;
    };
    let shared = bdmorph::io::read_mesh(dir.join("closed3d/odedstein/sphere.obj")).expect("sphere");
    let mut heat = HeatGeodesics::new(&shared, HeatOptions::default()).expect("set up");
    let d = heat.distance(&[0]).expect("query");
    let err = mean_relative_error(&d, &arccos(&shared, 0));
    eprintln!("shared sphere, source 0: mean relative error {err:.5}");
    assert!(err <= 0.0188, "mean relative error {err}");
}

#[test]
fn distances_behave_like_distances() {
    for (name, mesh) in [
        ("sphere", generate::icosphere(3)),
        ("hemisphere", generate::sphere_cap(4, 0.0)),
    ] {
        let mut heat = HeatGeodesics::new(&mesh, HeatOptions::default()).expect("set up");
        let n = mesh.positions.len() as u32;
        let picks: Vec<u32> = (0..8).map(|k| k * (n / 8) + 3).collect();
        let fields = heat.distances_each(&picks).expect("queries");
        let h = heat.stats().mean_edge;
        for (k, field) in fields.iter().enumerate() {
            assert_eq!(field[picks[k] as usize], 0.0, "{name}: zero at the source");
            assert!(field.iter().all(|&d| d >= 0.0 && d.is_finite()), "{name}");
        }
        for a in 0..picks.len() {
            for b in 0..picks.len() {
                let (dab, dba) = (fields[a][picks[b] as usize], fields[b][picks[a] as usize]);
                // Symmetric within the method's error (a few percent, or an edge up close).
                assert!(
                    (dab - dba).abs() <= 0.03 * dab.max(dba) + 0.5 * h,
                    "{name}: d({a}, {b}) = {dab}, d({b}, {a}) = {dba}"
                );
                for c in 0..picks.len() {
                    let dac = fields[a][picks[c] as usize];
                    let dcb = fields[c][picks[b] as usize];
                    assert!(
                        dab <= dac + dcb + 0.03 * dab + 0.5 * h,
                        "{name}: triangle inequality {dab} > {dac} + {dcb}"
                    );
                }
            }
        }
    }
}

#[test]
fn several_sources_give_the_nearest_ones_distance() {
    let mesh = generate::icosphere(4);
    let mut heat = HeatGeodesics::new(&mesh, HeatOptions::default()).expect("set up");
    let sources = [0u32, 700, 1900];
    let together = heat.distance(&sources).expect("query");
    let each = heat.distances_each(&sources).expect("queries");
    let h = heat.stats().mean_edge;
    let mut worst: f64 = 0.0;
    let mut mean = 0.0;
    for v in 0..mesh.positions.len() {
        let nearest = each.iter().map(|f| f[v]).fold(f64::INFINITY, f64::min);
        worst = worst.max((together[v] - nearest).abs());
        mean += (together[v] - nearest).abs();
    }
    mean /= mesh.positions.len() as f64;
    for &s in &sources {
        assert_eq!(together[s as usize], 0.0);
    }
    // Smoothed only along the ridges where two sources are equally near.
    assert!(mean < 0.5 * h, "mean difference {mean} (edge {h})");
    assert!(worst < 3.0 * h, "largest difference {worst} (edge {h})");
    // One field per source equals asking for each alone.
    let alone = heat.distance(&[700]).expect("query");
    assert!(alone
        .iter()
        .zip(&each[1])
        .all(|(a, b)| (a - b).abs() < 1e-9));
}

#[test]
fn intrinsic_delaunay_repairs_poor_triangles() {
    let strip = sliver_strip(40, 8);
    let source = 0usize;
    let p = strip.positions[source];
    let exact: Vec<f64> = strip
        .positions
        .iter()
        .map(|q| (q[0] - p[0]).hypot(q[1] - p[1]))
        .collect();
    let error = |options: HeatOptions| {
        let mut heat = HeatGeodesics::new(&strip, options).expect("set up");
        let d = heat.distance(&[source as u32]).expect("query");
        (mean_relative_error(&d, &exact), heat.stats().flips)
    };
    let (plain, no_flips) = error(HeatOptions::default().with_intrinsic_delaunay(false));
    let (idt, flips) = error(HeatOptions::default());
    eprintln!("sliver strip: plain {plain:.4}, intrinsic Delaunay {idt:.4} ({flips} flips)");
    assert_eq!(no_flips, 0);
    assert!(flips > 0);
    assert!(
        idt < 0.75 * plain,
        "intrinsic Delaunay {idt} vs plain {plain}"
    );
}

#[test]
fn boundary_conditions_are_all_usable() {
    let cap = generate::sphere_cap(4, 0.0);
    // The pole is vertex... the one with the largest z; distances from it are 1 - z's angle.
    let pole = (0..cap.positions.len())
        .max_by(|&a, &b| cap.positions[a][2].total_cmp(&cap.positions[b][2]))
        .expect("vertices");
    let exact = arccos(&cap, pole);
    for boundary in [
        Boundary::Robin,
        Boundary::Neumann,
        Boundary::Dirichlet,
        Boundary::Average,
    ] {
        let mut heat = HeatGeodesics::new(&cap, HeatOptions::default().with_boundary(boundary))
            .expect("set up");
        assert!(heat.stats().has_boundary);
        let d = heat.distance(&[pole as u32]).expect("query");
        let err = mean_relative_error(&d, &exact);
        eprintln!("hemisphere from the pole, {boundary:?}: {err:.4}");
        assert!(err < 0.03, "{boundary:?}: {err}");
        // A source on the boundary works too (Dirichlet and Average use Neumann for it).
        let rim = (0..cap.positions.len())
            .min_by(|&a, &b| cap.positions[a][2].total_cmp(&cap.positions[b][2]))
            .expect("vertices");
        let d = heat.distance(&[rim as u32]).expect("query");
        let err = mean_relative_error(&d, &arccos(&cap, rim));
        assert!(err < 0.05, "{boundary:?}, source on the rim: {err}");
    }
}

#[test]
fn shared_meshes_match_exact_geodesics_as_well_as_the_peers() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    // (mesh, source, the best peer's error, its name, our bar). The peers'
    // errors were measured by tools/geodesic_compare.py in one run with ours (potpourri3d
    // 1.4.0 robust and plain, libigl 2.6.3); ours now: Isis 0.00882 and 0.02206, Nefertiti
    // 0.01348 and 0.01834, camel head 0.01360 (with the defaults before issue 23's
    // measurements: 0.0155, 0.0219, 0.0166, 0.0380, 0.0137, where libigl's Neumann-Dirichlet
    // average was better from Nefertiti's 206 and potpourri3d's robust mode on the camel
    // head). The bars leave about 2% for round-off across platforms and hold our accuracy;
    // every case must also be at least as accurate as the best peer.
    let cases = [
        (
            "disk3d/ustc-cg/Isis_dABF.obj",
            0,
            0.01583,
            "pp3d robust",
            0.0090,
        ),
        (
            "disk3d/ustc-cg/Isis_dABF.obj",
            53,
            0.03255,
            "pp3d robust",
            0.0225,
        ),
        (
            "disk3d/ustc-cg/Nefertiti_face.obj",
            0,
            0.02061,
            "libigl",
            0.0138,
        ),
        (
            "disk3d/ustc-cg/Nefertiti_face.obj",
            206,
            0.02375,
            "libigl",
            0.0187,
        ),
        (
            "disk3d/libigl/camelhead.off",
            0,
            0.01369,
            "pp3d robust",
            0.0139,
        ),
    ];
    for (rel, source, peer, peer_name, bar) in cases {
        let mesh = bdmorph::io::read_mesh(dir.join(rel)).expect("mesh");
        // The reference: exact polyhedral distances (tests/geodesic_exact.rs checks them
        // against pygeodesic's and libigl's).
        let exact = ExactGeodesics::new(&mesh)
            .and_then(|mut e| e.distance(&[source as u32]))
            .expect("exact distances");
        let err = error_with(&mesh, HeatOptions::default(), source, &exact);
        let neumann = error_with(
            &mesh,
            HeatOptions::default().with_boundary(Boundary::Neumann),
            source,
            &exact,
        );
        eprintln!(
            "{rel} from {source}: {err:.5} (neumann {neumann:.5}; best peer {peer_name} {peer:.5})"
        );
        assert!(err <= bar, "{rel} from {source}: {err} > {bar}");
        assert!(
            err <= peer,
            "{rel} from {source}: {err} vs {peer_name} {peer}"
        );
    }
}

#[test]
fn components_without_a_source_are_infinitely_far() {
    let a = generate::icosphere(1);
    let mut both = a.clone();
    let offset = a.positions.len() as u32;
    both.positions
        .extend(a.positions.iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
    both.faces
        .extend(a.faces.iter().map(|f| f.map(|v| v + offset)));
    // And a vertex in no triangle.
    both.positions.push([9.0, 9.0, 9.0]);
    let mut heat = HeatGeodesics::new(&both, HeatOptions::default()).expect("set up");
    let d = heat.distance(&[0]).expect("query");
    assert!(d[..offset as usize].iter().all(|x| x.is_finite()));
    assert!(d[offset as usize..].iter().all(|x| x.is_infinite()));
    let d = heat.distance(&[0, offset + 1]).expect("query");
    assert!(d[..d.len() - 1].iter().all(|x| x.is_finite()));
    assert_eq!(d[offset as usize + 1], 0.0);
}

#[test]
fn bad_input_is_a_typed_error() {
    let sphere = generate::icosphere(1);
    let mut heat = HeatGeodesics::new(&sphere, HeatOptions::default()).expect("set up");
    assert!(matches!(heat.distance(&[]), Err(GeodesicError::NoSources)));
    assert!(matches!(
        heat.distance(&[9999]),
        Err(GeodesicError::SourceOutOfRange { vertex: 9999, .. })
    ));
    let empty = SurfaceMesh {
        positions: vec![[0.0; 3]; 3],
        faces: vec![],
        texcoords: None,
    };
    assert!(matches!(
        HeatGeodesics::new(&empty, HeatOptions::default()),
        Err(GeodesicError::Empty)
    ));
    let mut twisted = sphere.clone();
    twisted.faces[0].swap(0, 1);
    assert!(matches!(
        HeatGeodesics::new(&twisted, HeatOptions::default()),
        Err(GeodesicError::Triangulation(
            TriangulationError::NonManifoldEdge { .. }
        ))
    ));
    let mut nan = sphere.clone();
    nan.positions[3][1] = f64::NAN;
    assert!(matches!(
        HeatGeodesics::new(&nan, HeatOptions::default()),
        Err(GeodesicError::NonFinite { vertex: 3 })
    ));
    assert!(matches!(
        HeatGeodesics::new(&sphere, HeatOptions::default().with_time_factor(0.0)),
        Err(GeodesicError::TimeFactor(_))
    ));
    assert!(matches!(
        HeatGeodesics::new(&sphere, HeatOptions::default().with_absorption(-1.0)),
        Err(GeodesicError::Absorption(_))
    ));
    assert!(matches!(
        HeatGeodesics::new(&sphere, HeatOptions::default().with_mollify(f64::NAN)),
        Err(GeodesicError::Mollify(_))
    ));
}

/// A planar mesh as a surface at z = 0.
fn flat(mesh: &bdmorph::PlanarMesh) -> SurfaceMesh {
    SurfaceMesh {
        positions: mesh.positions.iter().map(|p| [p[0], p[1], 0.0]).collect(),
        faces: mesh.faces.clone(),
        texcoords: None,
    }
}

/// Euclidean distances from vertex `source` (exact on a convex planar mesh).
fn euclidean(mesh: &SurfaceMesh, source: usize) -> Vec<f64> {
    let p = mesh.positions[source];
    mesh.positions
        .iter()
        .map(|q| ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2)).sqrt())
        .collect()
}

/// The vertex nearest to `target`.
fn nearest(mesh: &SurfaceMesh, target: [f64; 3]) -> usize {
    let d = |p: &[f64; 3]| (0..3).map(|k| (p[k] - target[k]).powi(2)).sum::<f64>();
    (0..mesh.positions.len())
        .min_by(|&a, &b| d(&mesh.positions[a]).total_cmp(&d(&mesh.positions[b])))
        .expect("vertices")
}

fn error_with(mesh: &SurfaceMesh, options: HeatOptions, source: usize, exact: &[f64]) -> f64 {
    let mut heat = HeatGeodesics::new(mesh, options).expect("set up");
    let d = heat.distance(&[source as u32]).expect("query");
    mean_relative_error(&d, exact)
}

#[test]
fn robin_boundary_is_more_accurate_than_zero_flux_or_zero_heat() {
    // Geodesics that leave through the boundary: from inside a flat disk and a hemisphere.
    let disk = flat(&generate::disk(16, 0.2));
    let cap = generate::sphere_cap(4, 0.0);
    let cases = [
        (
            "flat disk, centre",
            &disk,
            nearest(&disk, [0.0, 0.0, 0.0]),
            false,
        ),
        (
            "flat disk, off centre",
            &disk,
            nearest(&disk, [0.45, 0.2, 0.0]),
            false,
        ),
        (
            "hemisphere, 45 degrees",
            &cap,
            nearest(&cap, [FRAC_1_SQRT_2, 0.0, FRAC_1_SQRT_2]),
            true,
        ),
    ];
    for (name, mesh, source, sphere) in cases {
        let exact = if sphere {
            arccos(mesh, source)
        } else {
            euclidean(mesh, source)
        };
        let err = |b: Boundary| {
            error_with(
                mesh,
                HeatOptions::default().with_boundary(b),
                source,
                &exact,
            )
        };
        let (robin, neumann, dirichlet, average) = (
            err(Boundary::Robin),
            err(Boundary::Neumann),
            err(Boundary::Dirichlet),
            err(Boundary::Average),
        );
        eprintln!("{name}: robin {robin:.5}, neumann {neumann:.5}, dirichlet {dirichlet:.5}, average {average:.5}");
        // Measured (robin / neumann / dirichlet / average): centre 0.00278 / 0.00288 /
        // 0.00273 / 0.00276 (the boundary is met head-on); off centre 0.00925 / 0.01103 /
        // 0.02402 / 0.01140; hemisphere 0.00683 / 0.00541 / 0.02431 / 0.00901. The default
        // absorption for a source off the boundary (0.7) was chosen on the shared meshes,
        // where it beats zero flux (BENCHMARKS.md); on this hemisphere zero flux is better
        // and absorption 0.2 better still (0.00323).
        let best = neumann.min(dirichlet).min(average);
        assert!(robin <= 1.3 * best, "{name}");
        assert!(robin < 0.01, "{name}: {robin}");
        if name != "flat disk, centre" {
            assert!(robin < 0.5 * dirichlet, "{name}");
        }
        if name == "flat disk, off centre" {
            assert!(robin < 0.9 * neumann.min(average), "{name}");
        }
    }
}

/// The rectangle `[0, nx] x [0, height]` in rows of vertices, alternate rows offset by half a
/// step (with the ends added), zipped into triangles. The second and the second-to-last rows
/// lie `squash` from the long sides, so every triangle on those sides is a sliver whose angle
/// opposite the boundary edge is nearly 180 degrees: the boundary edges' cotan weights are
/// strongly negative, and only flips across the boundary can remove them.
fn comb_strip(nx: usize, ny: usize, height: f64, squash: f64) -> SurfaceMesh {
    let mut rows: Vec<Vec<u32>> = Vec::new();
    let mut positions = Vec::new();
    for j in 0..=ny {
        let y = match j {
            0 => 0.0,
            1 => squash,
            j if j == ny - 1 => height - squash,
            j if j == ny => height,
            j => height * j as f64 / ny as f64,
        };
        let xs: Vec<f64> = if j % 2 == 0 {
            (0..=nx).map(|i| i as f64).collect()
        } else {
            let mut xs = vec![0.0];
            xs.extend((0..nx).map(|i| i as f64 + 0.5));
            xs.push(nx as f64);
            xs
        };
        let mut row = Vec::new();
        for x in xs {
            row.push(positions.len() as u32);
            positions.push([x, y, 0.0]);
        }
        rows.push(row);
    }
    let mut faces = Vec::new();
    for j in 0..ny {
        let (lower, upper) = (&rows[j], &rows[j + 1]);
        let (mut i, mut k) = (0, 0);
        while i + 1 < lower.len() || k + 1 < upper.len() {
            let advance_lower = k + 1 == upper.len()
                || (i + 1 < lower.len()
                    && positions[lower[i + 1] as usize][0] < positions[upper[k + 1] as usize][0]);
            if advance_lower {
                faces.push([lower[i], lower[i + 1], upper[k]]);
                i += 1;
            } else {
                faces.push([lower[i], upper[k + 1], upper[k]]);
                k += 1;
            }
        }
    }
    SurfaceMesh {
        positions,
        faces,
        texcoords: None,
    }
}

#[test]
fn flips_across_the_boundary_repair_obtuse_boundary_triangles() {
    let strip = comb_strip(30, 8, 4.0, 0.02);
    let on = HeatOptions::default();
    let off = HeatOptions::default().with_flip_boundary(false);
    let s_on = HeatGeodesics::new(&strip, on).expect("set up").stats();
    let s_off = HeatGeodesics::new(&strip, off).expect("set up").stats();
    // Flips across the boundary happened: faces made of both sheets are added.
    assert!(s_on.faces > s_off.faces, "{s_on:?} vs {s_off:?}");
    for target in [
        [0.0, 0.0, 0.0],
        [15.0, 0.0, 0.0],
        [15.5, 0.02, 0.0],
        [7.0, 2.0, 0.0],
    ] {
        let source = nearest(&strip, target);
        let exact = euclidean(&strip, source);
        let (e_on, e_off) = (
            error_with(&strip, on, source, &exact),
            error_with(&strip, off, source, &exact),
        );
        eprintln!("comb strip from {target:?}: across the boundary {e_on:.5}, inside {e_off:.5}");
        // Measured: 0.0347 / 0.0481, 0.0211 / 0.0454, 0.0401 / 0.0480, 0.0455 / 0.0549.
        // (This long strip of slivers is where the default absorption 0.7 of a source off
        // the boundary does worst: with absorption 0.2, 0.0222 and 0.0256 from the last two.)
        assert!(e_on < 0.97 * e_off, "from {target:?}: {e_on} vs {e_off}");
        assert!(e_on < 0.047, "from {target:?}: {e_on}");
    }
}

#[test]
fn the_doubled_surface_changes_nothing_when_no_boundary_edge_flips() {
    // A grid of right triangles: every boundary edge is opposite a 45 degree angle, so no
    // flip crosses the boundary, and the halved doubled surface is the mesh itself.
    let grid = flat(&generate::grid(12, 9, 0.0));
    let mut on = HeatGeodesics::new(&grid, HeatOptions::default()).expect("set up");
    let mut off = HeatGeodesics::new(&grid, HeatOptions::default().with_flip_boundary(false))
        .expect("set up");
    assert_eq!(on.stats().faces, grid.faces.len());
    assert_eq!(on.stats().flips, 2 * off.stats().flips);
    for source in [0u32, 50, 107] {
        let (a, b) = (
            on.distance(&[source]).expect("query"),
            off.distance(&[source]).expect("query"),
        );
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "source {source}: {worst}");
    }
}

#[test]
fn mollification_accepts_a_triangle_of_zero_area() {
    // A flat grid with a triangle of zero area glued to its bottom side: its third corner is
    // the midpoint of the side.
    let mut mesh = flat(&generate::grid(12, 8, 0.0));
    let (a, b) = (5u32, 6u32);
    let face = mesh
        .faces
        .iter()
        .find(|f| {
            (0..3).any(|k| (f[k], f[(k + 1) % 3]) == (a, b) || (f[k], f[(k + 1) % 3]) == (b, a))
        })
        .expect("a face on the bottom side");
    let k = (0..3)
        .find(|&k| face[k] == a || face[k] == b)
        .expect("corner");
    // The side as the face runs it, p -> q; the new face runs q -> p -> m.
    let (p, q) = if face[(k + 1) % 3] == a || face[(k + 1) % 3] == b {
        (face[k], face[(k + 1) % 3])
    } else {
        (face[(k + 2) % 3], face[k])
    };
    let m = mesh.positions.len() as u32;
    mesh.positions.push([5.5, 0.0, 0.0]);
    mesh.faces.push([q, p, m]);
    let degenerate = mesh.faces.len() - 1;
    assert!(matches!(
        HeatGeodesics::new(&mesh, HeatOptions::default().with_mollify(0.0)),
        Err(GeodesicError::Triangulation(
            TriangulationError::Degenerate { face, .. }
        )) if face == degenerate
    ));
    let mut heat = HeatGeodesics::new(&mesh, HeatOptions::default()).expect("mollified");
    let s = heat.stats();
    // Every edge grew by the margin, 1e-5 of the mean edge (about 1.12 here), and no more.
    assert!(s.mollified > 0.0 && s.mollified <= 1.5e-5, "{s:?}");
    // As accurate as on the grid without that triangle, from a corner and from its tip.
    let mut clean = HeatGeodesics::new(&flat(&generate::grid(12, 8, 0.0)), HeatOptions::default())
        .expect("set up");
    for source in [0u32, m] {
        let d = heat.distance(&[source]).expect("query");
        assert!(d.iter().all(|x| x.is_finite()));
        let err = mean_relative_error(&d, &euclidean(&mesh, source as usize));
        let reference = if source == 0 {
            let d = clean.distance(&[0]).expect("query");
            mean_relative_error(&d, &euclidean(&mesh, 0)[..d.len()])
        } else {
            0.05
        };
        eprintln!("grid with a needle, from {source}: {err:.5} (without it {reference:.5})");
        assert!(err < 1.1 * reference, "from {source}: {err}");
    }
    // On meshes whose triangles all have the margin, mollification changes nothing.
    let sphere = generate::icosphere(3);
    let mut a = HeatGeodesics::new(&sphere, HeatOptions::default()).expect("set up");
    let mut b =
        HeatGeodesics::new(&sphere, HeatOptions::default().with_mollify(0.0)).expect("set up");
    assert_eq!(a.stats().mollified, 0.0);
    assert_eq!(
        a.distance(&[5]).expect("query"),
        b.distance(&[5]).expect("query")
    );
}

#[test]
fn the_time_step_uses_the_intrinsic_triangulations_edges() {
    // Flips shorten edges: t = m h^2 with h measured on the triangulation the operators are
    // built on: by default its area-weighted vertex spacing, m = 0.5.
    let strip = sliver_strip(40, 8);
    let mean_edge = HeatOptions::default()
        .with_time_factor(1.0)
        .with_time_scale(TimeScale::MeanEdge);
    let idt = HeatGeodesics::new(&strip, mean_edge)
        .expect("set up")
        .stats();
    let plain = HeatGeodesics::new(&strip, mean_edge.with_intrinsic_delaunay(false))
        .expect("set up")
        .stats();
    assert!(idt.flips > 0);
    assert!(idt.mean_edge < 0.95 * plain.mean_edge, "{idt:?} {plain:?}");
    assert!((idt.time - idt.mean_edge * idt.mean_edge).abs() < 1e-15);
    assert!((plain.time - plain.mean_edge * plain.mean_edge).abs() < 1e-15);
    let default = HeatGeodesics::new(&strip, HeatOptions::default())
        .expect("set up")
        .stats();
    assert!((default.time - 0.5 * default.spacing * default.spacing).abs() < 1e-15);
    // On a uniform mesh the spacing is the side of its triangles: equilateral triangles of
    // side 1 on a sphere of many vertices come close (every vertex owns √3/2 of area).
    let sphere = HeatGeodesics::new(&generate::icosphere(4), HeatOptions::default())
        .expect("set up")
        .stats();
    assert!(
        (sphere.spacing / sphere.mean_edge - 1.0).abs() < 0.05,
        "{sphere:?}"
    );
}

#[test]
fn dirichlet_and_average_use_neumann_for_a_source_on_the_boundary() {
    let cap = generate::sphere_cap(3, 0.0);
    let rim = (0..cap.positions.len())
        .min_by(|&a, &b| cap.positions[a][2].total_cmp(&cap.positions[b][2]))
        .expect("vertices") as u32;
    let pole = nearest(&cap, [0.0, 0.0, 1.0]) as u32;
    let mut neumann = HeatGeodesics::new(
        &cap,
        HeatOptions::default().with_boundary(Boundary::Neumann),
    )
    .expect("set up");
    assert!(neumann.on_boundary(rim) && !neumann.on_boundary(pole));
    assert!(!neumann.on_boundary(u32::MAX));
    let from_rim = neumann.distance(&[rim]).expect("query");
    let from_both = neumann.distance(&[pole, rim]).expect("query");
    for boundary in [Boundary::Dirichlet, Boundary::Average] {
        let mut heat = HeatGeodesics::new(&cap, HeatOptions::default().with_boundary(boundary))
            .expect("set up");
        assert_eq!(heat.boundary(), boundary);
        // A field with a source on the boundary: exactly the Neumann field, alone or with an
        // interior source, and in a batch next to a field that does use the boundary
        // conditions.
        assert_eq!(
            heat.distance(&[rim]).expect("query"),
            from_rim,
            "{boundary:?}"
        );
        assert_eq!(
            heat.distance(&[pole, rim]).expect("query"),
            from_both,
            "{boundary:?}"
        );
        let each = heat.distances_each(&[pole, rim]).expect("queries");
        assert_eq!(each[1], from_rim, "{boundary:?}");
        assert_ne!(
            each[0],
            neumann.distance(&[pole]).expect("query"),
            "{boundary:?}"
        );
    }
}

#[test]
fn the_command_line_notes_when_dirichlet_or_average_falls_back_at_a_boundary_source() {
    let dir = std::env::temp_dir().join(format!("bdmorph-geodesic-note-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch folder");
    let cap = generate::sphere_cap(2, 0.0);
    let mut text = String::new();
    for p in &cap.positions {
        text.push_str(&format!("v {} {} {}\n", p[0], p[1], p[2]));
    }
    for f in &cap.faces {
        text.push_str(&format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1));
    }
    let mesh = dir.join("cap.obj");
    std::fs::write(&mesh, text).expect("write");
    let rim = (0..cap.positions.len())
        .min_by(|&a, &b| cap.positions[a][2].total_cmp(&cap.positions[b][2]))
        .expect("vertices");
    let pole = nearest(&cap, [0.0, 0.0, 1.0]);
    let run = |args: &[String]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_bdmorph"))
            .arg("geodesic")
            .arg(&mesh)
            .args(args)
            .arg("-o")
            .arg(dir.join("d.txt"))
            .output()
            .expect("runs");
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stderr).expect("utf8")
    };
    let args = |s: &str| s.split(' ').map(String::from).collect::<Vec<_>>();
    for bc in ["dirichlet", "average"] {
        let err = run(&args(&format!("--boundary {bc} --source {rim}")));
        let notes: Vec<&str> = err.lines().filter(|l| l.starts_with("note:")).collect();
        assert_eq!(notes.len(), 1, "{err}");
        assert!(
            notes[0].contains(&format!("source vertex {rim} "))
                && notes[0].contains(&format!("--boundary {bc}"))
                && notes[0].contains("--boundary neumann"),
            "{err}"
        );
        let err = run(&args(&format!(
            "--boundary {bc} --each-source {pole},{rim}"
        )));
        assert!(
            err.contains(&format!("note: source vertex {rim} ")) && err.contains("its field"),
            "{err}"
        );
        // No note when it does not apply.
        let err = run(&args(&format!("--boundary {bc} --source {pole}")));
        assert!(!err.contains("note:"), "{err}");
        let err = run(&args(&format!("--boundary {bc} --source {rim} --quiet")));
        assert!(err.is_empty(), "{err}");
    }
    for other in ["robin", "neumann"] {
        let err = run(&args(&format!("--boundary {other} --source {rim}")));
        assert!(!err.contains("note:"), "{err}");
    }
    let help = std::process::Command::new(env!("CARGO_BIN_EXE_bdmorph"))
        .args(["geodesic", "--help"])
        .output()
        .expect("runs");
    let help = String::from_utf8(help.stdout).expect("utf8");
    assert!(
        help.contains("a source on the boundary uses neumann"),
        "{help}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A tube of `nx` by `ny` squares of about side 1 around the z axis, cut open along one generator:
/// the first and last columns of vertices lie at the same places. Its geodesics cannot cross
/// the cut, so the exact distances are those of the unrolled rectangle (convex): planar.
fn cut_tube(nx: usize, ny: usize) -> (SurfaceMesh, Vec<[f64; 2]>) {
    let radius = nx as f64 / std::f64::consts::TAU;
    let mut positions = Vec::new();
    let mut unrolled = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let angle = i as f64 / radius;
            let angle = if i == nx { 0.0 } else { angle };
            positions.push([radius * angle.cos(), radius * angle.sin(), j as f64]);
            // The polyhedral tube's columns are a chord apart, not an arc.
            let chord = 2.0 * radius * (std::f64::consts::PI / nx as f64).sin();
            unrolled.push([i as f64 * chord, j as f64]);
        }
    }
    let at = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut faces = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            faces.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            faces.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    let mesh = SurfaceMesh {
        positions,
        faces,
        texcoords: None,
    };
    (mesh, unrolled)
}

#[test]
fn cuts_reflect_heat_unless_asked_to_absorb() {
    // The cut tube's boundary: its two rims (open, absorbing) and the cut's two sides
    // (coincident, zero flux by default).
    let (tube, unrolled) = cut_tube(24, 6);
    let source = (3 * 25 + 2) as u32; // two squares from the cut, half-way up
    let exact: Vec<f64> = unrolled
        .iter()
        .map(|p| {
            let q = unrolled[source as usize];
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt()
        })
        .collect();
    let error = |options: HeatOptions| {
        let mut heat = HeatGeodesics::new(&tube, options).expect("set up");
        mean_relative_error(&heat.distance(&[source]).expect("query"), &exact)
    };
    let (reflect, absorb) = (
        error(HeatOptions::default()),
        error(HeatOptions::default().with_absorb_at_cuts(true)),
    );
    eprintln!("cut tube: cuts reflect {reflect:.5}, absorb {absorb:.5}");
    assert!(reflect < absorb, "{reflect} vs {absorb}");
    // Measured 0.0446 and 0.0463 (right triangles all one way, on a coarse tube).
    assert!(reflect < 0.046, "{reflect}");
    // A mesh whose whole boundary is cuts has nothing to absorb: Robin is Neumann there.
    let (mut closed_tube, _) = cut_tube(24, 6);
    // Close the rims with a fan to a vertex each, leaving only the cut open.
    let (nx, ny) = (24usize, 6usize);
    for (j, z) in [(0usize, -1.0), (ny, ny as f64 + 1.0)] {
        let apex = closed_tube.positions.len() as u32;
        closed_tube.positions.push([0.0, 0.0, z]);
        for i in 0..nx {
            let (a, b) = ((j * (nx + 1) + i) as u32, (j * (nx + 1) + i + 1) as u32);
            closed_tube
                .faces
                .push(if j == 0 { [b, a, apex] } else { [a, b, apex] });
        }
    }
    let mut robin = HeatGeodesics::new(&closed_tube, HeatOptions::default()).expect("set up");
    let mut neumann = HeatGeodesics::new(
        &closed_tube,
        HeatOptions::default().with_boundary(Boundary::Neumann),
    )
    .expect("set up");
    assert_eq!(
        robin.distance(&[source]).expect("query"),
        neumann.distance(&[source]).expect("query")
    );
    assert_eq!(robin.stats().factor_nnz, neumann.stats().factor_nnz);
}

#[test]
fn boundary_sources_use_their_own_absorption() {
    let cap = generate::sphere_cap(4, 0.0);
    let rim = (0..cap.positions.len())
        .min_by(|&a, &b| cap.positions[a][2].total_cmp(&cap.positions[b][2]))
        .expect("vertices") as u32;
    let top = nearest(&cap, [0.0, 0.0, 1.0]) as u32;
    let mut both = HeatGeodesics::new(&cap, HeatOptions::default()).expect("set up");
    assert!(both.on_boundary(rim) && !both.on_boundary(top));
    let defaults = HeatOptions::default();
    let mut interior = HeatGeodesics::new(
        &cap,
        defaults.with_boundary_source_absorption(defaults.absorption),
    )
    .expect("set up");
    let mut boundary = HeatGeodesics::new(
        &cap,
        defaults.with_absorption(defaults.boundary_source_absorption),
    )
    .expect("set up");
    // Two heat systems only when the absorptions differ.
    assert!(both.stats().factor_nnz > interior.stats().factor_nnz);
    assert_eq!(interior.stats().factor_nnz, boundary.stats().factor_nnz);
    let from_top = both.distance(&[top]).expect("query");
    assert_eq!(from_top, interior.distance(&[top]).expect("query"));
    let from_rim = both.distance(&[rim]).expect("query");
    assert_eq!(from_rim, boundary.distance(&[rim]).expect("query"));
    assert_ne!(from_rim, interior.distance(&[rim]).expect("query"));
    // A field with both kinds of source is a boundary source's, and one batch can mix them.
    assert_eq!(
        both.distance(&[top, rim]).expect("query"),
        boundary.distance(&[top, rim]).expect("query")
    );
    let each = both.distances_each(&[rim, top]).expect("queries");
    assert_eq!(each, vec![from_rim, from_top]);
    // A negative absorption is refused, whichever.
    assert!(matches!(
        HeatGeodesics::new(&cap, defaults.with_boundary_source_absorption(-0.1)),
        Err(GeodesicError::Absorption(_))
    ));
}

#[test]
fn the_one_ring_anchor_makes_the_neighbours_exact_on_average() {
    // The distance to a mesh neighbour is the edge's length; the default anchor fits the
    // additive constant to the source's neighbours, the paper's puts zero at the source.
    let disk = flat(&generate::disk(12, 0.2));
    let source = nearest(&disk, [0.1, 0.05, 0.0]);
    let exact = euclidean(&disk, source);
    let mut ring: Vec<usize> = disk
        .faces
        .iter()
        .filter(|f| f.contains(&(source as u32)))
        .flat_map(|f| f.iter().map(|&v| v as usize))
        .filter(|&v| v != source)
        .collect();
    ring.sort_unstable();
    ring.dedup();
    let mut fitted = HeatGeodesics::new(&disk, HeatOptions::default()).expect("set up");
    let d = fitted.distance(&[source as u32]).expect("query");
    let misfit: f64 = ring.iter().map(|&v| d[v] - exact[v]).sum::<f64>() / ring.len() as f64;
    assert!(misfit.abs() < 1e-12, "{misfit}");
    assert_eq!(d[source], 0.0);
    let mut paper = HeatGeodesics::new(&disk, HeatOptions::default().with_anchor(Anchor::Sources))
        .expect("set up");
    let p = paper.distance(&[source as u32]).expect("query");
    // The same field but for the constant (away from the source, where nothing is clamped).
    let shift = d[ring[0]] - p[ring[0]];
    for v in 0..d.len() {
        if v != source && p[v] > 0.0 && d[v] > 0.0 {
            assert!((d[v] - p[v] - shift).abs() < 1e-9, "vertex {v}");
        }
    }
    let (e_fit, e_paper) = (
        mean_relative_error(&d, &exact),
        mean_relative_error(&p, &exact),
    );
    eprintln!("flat disk: one-ring anchor {e_fit:.5}, zero at the source {e_paper:.5}");
    assert!(e_fit < e_paper, "{e_fit} vs {e_paper}");
}
