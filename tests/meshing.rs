//! Meshing pictures and outlines made in code: orientation, minimum angle, vertex count,
//! boundary within the tolerance of the traced outline, holes and pieces kept, texture
//! coordinates; and the errors of degenerate inputs.

use bdmorph::generate::{self, capsule_distance};
use bdmorph::info::MeshInfo;
use bdmorph::meshing::{
    self, Background, Contact, MeshOptions, Meshed, MeshingError, NoSubject, PictureOptions,
};
use bdmorph::render::Image;
use bdmorph::{PlanarMesh, SurfaceMesh};

/// A picture of the subject whose signed distance (in pixels) is `d`.
fn picture(w: u32, h: u32, d: impl Fn([f64; 2]) -> f64) -> Image {
    generate::picture(w, h, |x, y| d([x, y]))
}

fn circle(p: [f64; 2], c: [f64; 2], r: f64) -> f64 {
    capsule_distance(p, c, c, r)
}

/// Boundary loops and connected pieces.
fn topology(m: &PlanarMesh) -> (usize, usize) {
    let info = MeshInfo::of(&SurfaceMesh {
        positions: m.positions.iter().map(|p| [p[0], p[1], 0.0]).collect(),
        faces: m.faces.clone(),
        texcoords: None,
    });
    (info.boundary_loops, info.components)
}

/// The edges with one triangle.
fn boundary_edges(m: &PlanarMesh) -> Vec<[u32; 2]> {
    let mut count = std::collections::HashMap::new();
    for f in &m.faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut edges: Vec<[u32; 2]> = count
        .into_iter()
        .filter(|&(_, c)| c == 1)
        .map(|((a, b), _)| [a, b])
        .collect();
    edges.sort_unstable();
    edges
}

fn distance_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    capsule_distance(p, a, b, 0.0)
}

/// The largest distance from any of `points` to the nearest of `segments`.
fn farthest_from(points: &[[f64; 2]], segments: &[[[f64; 2]; 2]]) -> f64 {
    points
        .iter()
        .map(|&p| {
            segments
                .iter()
                .map(|s| distance_to_segment(p, s[0], s[1]))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

/// The checks every mesh passes: counter-clockwise triangles, the minimum angle, about the
/// requested vertex count, one texture coordinate per vertex in [0, 1].
fn check(m: &Meshed, vertices: usize, min_angle: f64) {
    let mesh = &m.mesh;
    assert!(
        mesh.faces.iter().all(|f| mesh.signed_area(f) > 0.0),
        "every triangle counter-clockwise"
    );
    let angle = meshing::min_angle(mesh);
    assert!(angle >= min_angle - 1e-9, "smallest angle {angle}");
    assert_eq!(angle, m.stats.min_angle);
    let off = mesh.positions.len().abs_diff(vertices) as f64 / vertices as f64;
    assert!(
        off <= 0.1,
        "{} vertices for {vertices} requested",
        mesh.positions.len()
    );
    assert_eq!(m.texcoords.uv.len(), mesh.positions.len());
    assert_eq!(m.texcoords.corners, mesh.faces);
    assert!(m
        .texcoords
        .uv
        .iter()
        .flatten()
        .all(|t| (0.0..=1.0).contains(t)));
    assert_eq!(m.stats.vertices, mesh.positions.len());
    assert_eq!(m.stats.faces, mesh.faces.len());
    assert!(m.stats.refinement_complete);
}

/// The mesh's boundary and the traced outline are within `tolerance` of each other (both
/// ways), and every traced loop is accounted for.
fn check_boundary(image: &Image, picture: &PictureOptions, m: &Meshed, tolerance: f64) {
    let traced = meshing::picture_outline(image, picture, Some(tolerance)).expect("traces");
    let traced_segments: Vec<[[f64; 2]; 2]> = traced
        .traced
        .iter()
        .flat_map(|l| (0..l.len()).map(move |k| [l[k], l[(k + 1) % l.len()]]))
        .collect();
    let boundary: Vec<[[f64; 2]; 2]> = boundary_edges(&m.mesh)
        .iter()
        .map(|e| e.map(|v| m.mesh.positions[v as usize]))
        .collect();
    let boundary_points: Vec<[f64; 2]> = boundary.iter().map(|s| s[0]).collect();
    let traced_points: Vec<[f64; 2]> = traced.traced.concat();
    let out = farthest_from(&boundary_points, &traced_segments);
    let back = farthest_from(&traced_points, &boundary);
    assert!(
        out <= tolerance + 1e-9,
        "a boundary vertex {out} from the traced outline"
    );
    assert!(
        back <= tolerance + 1e-9,
        "a traced point {back} from the boundary"
    );
    // Texture coordinates are the pixel positions.
    for (p, t) in m.mesh.positions.iter().zip(&m.texcoords.uv) {
        let expected = [
            p[0] / f64::from(image.width),
            p[1] / f64::from(image.height),
        ];
        assert!((t[0] - expected[0]).abs() < 1e-12 && (t[1] - expected[1]).abs() < 1e-12);
    }
}

#[test]
fn a_disk_is_a_morphable_disk_within_the_tolerance() {
    let (w, h) = (400, 300);
    let image = picture(w, h, |p| circle(p, [200.0, 150.0], 100.0));
    let options = MeshOptions::default().with_vertices(1500);
    let m = meshing::mesh_picture(&image, &PictureOptions::default(), &options).expect("meshes");
    check(&m, 1500, meshing::DEFAULT_MIN_ANGLE);
    check_boundary(&image, &PictureOptions::default(), &m, 1.0);
    assert_eq!(topology(&m.mesh), (1, 1));
    assert_eq!((m.stats.pieces, m.stats.holes), (1, 0));
    m.mesh.validate().expect("valid");
    bdmorph::compile(&m.mesh.positions, &m.mesh.faces).expect("a disk that can be morphed");
    // Pixels from the bottom-left corner: the circle's centre (200, 150 from the top) is at
    // y = 300 - 150; its boundary within the tolerance plus the anti-aliasing of the circle.
    for e in boundary_edges(&m.mesh) {
        let p = m.mesh.positions[e[0] as usize];
        let r = (p[0] - 200.0).hypot(p[1] - 150.0);
        assert!(
            (r - 100.0).abs() < 1.0 + 0.1,
            "boundary vertex at radius {r}"
        );
    }
    // Deterministic.
    let again =
        meshing::mesh_picture(&image, &PictureOptions::default(), &options).expect("meshes");
    assert_eq!(again.mesh, m.mesh);
}

#[test]
fn the_picture_is_upright_with_y_up() {
    // A disk near the top-left of the picture lands near the top-left of the mesh: large y.
    let image = picture(200, 100, |p| circle(p, [40.0, 30.0], 20.0));
    let m = meshing::mesh_picture(
        &image,
        &PictureOptions::default(),
        &MeshOptions::default().with_vertices(300),
    )
    .expect("meshes");
    let n = m.mesh.positions.len() as f64;
    let centre = m
        .mesh
        .positions
        .iter()
        .fold([0.0, 0.0], |c, p| [c[0] + p[0] / n, c[1] + p[1] / n]);
    assert!(
        (centre[0] - 40.0).abs() < 1.0 && (centre[1] - 70.0).abs() < 1.0,
        "{centre:?}"
    );
    // The texture coordinate of the centre is the picture's (40 / 200, 1 - 30 / 100).
    let t = m
        .texcoords
        .uv
        .iter()
        .fold([0.0, 0.0], |c, t| [c[0] + t[0] / n, c[1] + t[1] / n]);
    assert!(
        (t[0] - 0.2).abs() < 0.01 && (t[1] - 0.7).abs() < 0.01,
        "{t:?}"
    );
}

#[test]
fn a_ring_keeps_its_hole() {
    let image = picture(300, 300, |p| {
        circle(p, [150.0, 150.0], 120.0).max(-circle(p, [150.0, 150.0], 50.0))
    });
    let m = meshing::mesh_picture(&image, &PictureOptions::default(), &MeshOptions::default())
        .expect("meshes");
    check(&m, meshing::DEFAULT_VERTICES, meshing::DEFAULT_MIN_ANGLE);
    check_boundary(&image, &PictureOptions::default(), &m, 1.0);
    assert_eq!(topology(&m.mesh), (2, 1));
    assert_eq!((m.stats.pieces, m.stats.holes), (1, 1));
    // Nothing inside the hole.
    for f in &m.mesh.faces {
        let c = f.iter().fold([0.0, 0.0], |c, &v| {
            let p = m.mesh.positions[v as usize];
            [c[0] + p[0] / 3.0, c[1] + p[1] / 3.0]
        });
        assert!((c[0] - 150.0).hypot(c[1] - 150.0) > 49.0);
    }
}

#[test]
fn two_pieces_and_an_island_in_a_hole() {
    let image = picture(400, 200, |p| {
        let ring = circle(p, [100.0, 100.0], 90.0).max(-circle(p, [100.0, 100.0], 50.0));
        let island = circle(p, [100.0, 100.0], 25.0);
        let other = circle(p, [300.0, 100.0], 60.0);
        ring.min(island).min(other)
    });
    let options = MeshOptions::default()
        .with_vertices(3000)
        .with_min_angle(30.0);
    let m = meshing::mesh_picture(&image, &PictureOptions::default(), &options).expect("meshes");
    check(&m, 3000, 30.0);
    check_boundary(&image, &PictureOptions::default(), &m, 1.0);
    assert_eq!(topology(&m.mesh), (4, 3));
    assert_eq!((m.stats.pieces, m.stats.holes), (3, 1));
}

#[test]
fn a_thin_limb_is_kept_with_good_triangles() {
    // A body with an arm 6 pixels wide and 200 long.
    let image = picture(400, 200, |p| {
        circle(p, [80.0, 100.0], 60.0).min(capsule_distance(p, [120.0, 100.0], [340.0, 60.0], 3.0))
    });
    let options = MeshOptions::default().with_vertices(1200);
    let m = meshing::mesh_picture(&image, &PictureOptions::default(), &options).expect("meshes");
    check(&m, 1200, meshing::DEFAULT_MIN_ANGLE);
    check_boundary(&image, &PictureOptions::default(), &m, 1.0);
    assert_eq!(topology(&m.mesh), (1, 1));
    // The arm reaches its tip (x = 343 at y = 200 - 60), and is triangulated along its length.
    let tip = m.mesh.positions.iter().map(|p| p[0]).fold(0.0, f64::max);
    assert!(tip > 341.0, "the arm ends at x = {tip}");
    let along_arm = m
        .mesh
        .faces
        .iter()
        .filter(|f| f.iter().all(|&v| m.mesh.positions[v as usize][0] > 200.0))
        .count();
    assert!(along_arm > 20, "{along_arm} triangles on the outer arm");
    bdmorph::compile(&m.mesh.positions, &m.mesh.faces).expect("a disk");
}

#[test]
fn vertex_counts_follow_the_request() {
    let image = generate::picture_subject(512);
    for n in [300, 2000, 8000] {
        let m = meshing::mesh_picture(
            &image,
            &PictureOptions::default(),
            &MeshOptions::default().with_vertices(n),
        )
        .expect("meshes");
        check(&m, n, meshing::DEFAULT_MIN_ANGLE);
        assert_eq!((m.stats.pieces, m.stats.holes), (2, 1));
    }
}

#[test]
fn the_tolerance_sets_the_outline() {
    let image = picture(300, 300, |p| circle(p, [150.0, 150.0], 130.0));
    let coarse =
        meshing::picture_outline(&image, &PictureOptions::default(), Some(3.0)).expect("traces");
    let fine =
        meshing::picture_outline(&image, &PictureOptions::default(), Some(0.25)).expect("traces");
    assert!(coarse.outline.vertices.len() * 2 < fine.outline.vertices.len());
    for tolerance in [0.25, 3.0] {
        let options = MeshOptions::default()
            .with_vertices(800)
            .with_tolerance(tolerance);
        let m =
            meshing::mesh_picture(&image, &PictureOptions::default(), &options).expect("meshes");
        check_boundary(&image, &PictureOptions::default(), &m, tolerance);
    }
}

#[test]
fn opaque_pictures_need_a_background_or_a_threshold() {
    // A dark disk on a white background, no transparency.
    let mut image = picture(200, 200, |p| circle(p, [100.0, 100.0], 70.0));
    for px in image.rgba.chunks_exact_mut(4) {
        let a = f64::from(px[3]) / 255.0;
        for c in &mut px[..3] {
            *c = (a * 0.3 * f64::from(*c) + (1.0 - a) * 255.0).round() as u8;
        }
        px[3] = 255;
    }
    let e = meshing::mesh_picture(&image, &PictureOptions::default(), &MeshOptions::default())
        .unwrap_err();
    assert!(matches!(e, MeshingError::NoTransparency { .. }), "{e}");
    for picture in [
        PictureOptions::default().with_background(Background::Colour([255, 255, 255])),
        PictureOptions::default().with_background(Background::Auto),
        PictureOptions::default().with_threshold(0.5),
    ] {
        let m = meshing::mesh_picture(&image, &picture, &MeshOptions::default().with_vertices(600))
            .expect("meshes");
        check(&m, 600, meshing::DEFAULT_MIN_ANGLE);
        assert_eq!(topology(&m.mesh), (1, 1));
        let area: f64 = m.mesh.faces.iter().map(|f| m.mesh.signed_area(f)).sum();
        let disk = std::f64::consts::PI * 70.0 * 70.0;
        assert!(
            (area - disk).abs() < 0.03 * disk,
            "area {area} for {disk} ({picture:?})"
        );
    }
}

#[test]
fn empty_transparent_and_speck_pictures_are_refused() {
    let empty = Image {
        width: 0,
        height: 0,
        rgba: Vec::new(),
    };
    let e = meshing::mesh_picture(&empty, &PictureOptions::default(), &MeshOptions::default())
        .unwrap_err();
    assert!(
        matches!(
            e,
            MeshingError::NoSubject {
                reason: NoSubject::Empty,
                ..
            }
        ),
        "{e}"
    );
    let clear = picture(50, 50, |_| 10.0);
    let e = meshing::mesh_picture(&clear, &PictureOptions::default(), &MeshOptions::default())
        .unwrap_err();
    assert!(
        matches!(
            e,
            MeshingError::NoSubject {
                reason: NoSubject::Transparent { .. },
                ..
            }
        ),
        "{e}"
    );
    // Specks of a pixel or two: too small for a tolerance of 1 pixel.
    let specks = picture(50, 50, |p| {
        circle(p, [10.5, 10.5], 0.8).min(circle(p, [30.5, 40.5], 1.1))
    });
    let e = meshing::mesh_picture(&specks, &PictureOptions::default(), &MeshOptions::default())
        .unwrap_err();
    match e {
        MeshingError::TooSmall {
            loops, tolerance, ..
        } => assert_eq!((loops, tolerance), (2, 1.0)),
        other => panic!("{other}"),
    }
    // A finer tolerance keeps them.
    let m = meshing::mesh_picture(
        &specks,
        &PictureOptions::default(),
        &MeshOptions::default().with_vertices(20).with_tolerance(0.1),
    )
    .expect("meshes at 0.1 pixels");
    assert_eq!(m.stats.pieces, 2);
    // A speck beside a subject is left out, and counted.
    let beside = picture(100, 100, |p| {
        circle(p, [40.0, 50.0], 30.0).min(circle(p, [90.5, 90.5], 0.8))
    });
    let m = meshing::mesh_picture(
        &beside,
        &PictureOptions::default(),
        &MeshOptions::default().with_vertices(300),
    )
    .expect("meshes");
    assert_eq!((m.stats.pieces, m.stats.dropped_outlines), (1, 1));
}

#[test]
fn an_svg_with_curves_and_a_hole() {
    // A shape of lines, a cubic, a quadratic and an arc, with a circular hole of radius 10
    // at (50, 40), inside a group with a transform (scale 2).
    let text = r#"<?xml version="1.0"?>
<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 200 200">
  <g transform="scale(2)">
    <path d="M 10 70 L 10 30 C 10 0, 90 0, 90 30 L 90 50 Q 90 70 70 70 A 20 20 0 0 1 30 70 Z"/>
    <circle cx="50" cy="40" r="10"/>
  </g>
</svg>"#;
    let tolerance = 0.05;
    let outline = meshing::parse_svg(text, Some(tolerance)).expect("parses");
    assert_eq!(outline.texture_frame, Some([0.0, 0.0, 200.0, 200.0]));
    let m = meshing::mesh_outline(&outline, &MeshOptions::default().with_vertices(2500))
        .expect("meshes");
    check(&m, 2500, meshing::DEFAULT_MIN_ANGLE);
    assert_eq!(topology(&m.mesh), (2, 1));
    assert_eq!((m.stats.pieces, m.stats.holes), (1, 1));
    // The hole's boundary: scaled by 2, centre (100, 80) in the file, y flipped to 200 - 80;
    // every vertex on it within the tolerance of the circle of radius 20.
    let mut on_hole = 0;
    for e in boundary_edges(&m.mesh) {
        let p = m.mesh.positions[e[0] as usize];
        let r = (p[0] - 100.0).hypot(p[1] - 120.0);
        if r < 30.0 {
            on_hole += 1;
            assert!(
                (r - 20.0).abs() <= tolerance + 1e-9,
                "hole vertex at radius {r}"
            );
        }
    }
    assert!(on_hole >= 20, "{on_hole} vertices around the hole");
    // The cubic's top (file y = 2 * 7.5 = 15) is at the top of the mesh (y = 200 - 15), the
    // arc's bottom (file y = 2 * 90) at its bottom.
    let top = m.mesh.positions.iter().map(|p| p[1]).fold(0.0, f64::max);
    assert!((top - 185.0).abs() < tolerance + 1e-9, "top at {top}");
    let bottom = m
        .mesh
        .positions
        .iter()
        .map(|p| p[1])
        .fold(f64::INFINITY, f64::min);
    assert!(
        (bottom - 20.0).abs() < tolerance + 1e-9,
        "bottom at {bottom}"
    );
    // Texture coordinates span the viewBox.
    for (p, t) in m.mesh.positions.iter().zip(&m.texcoords.uv) {
        assert!((t[0] - p[0] / 200.0).abs() < 1e-12 && (t[1] - p[1] / 200.0).abs() < 1e-12);
    }
}

#[test]
fn self_intersecting_and_too_small_svg_outlines_are_refused() {
    let crossing = r#"<svg viewBox="0 0 100 100">
<rect x="10" y="10" width="50" height="50"/>
<polygon points="50,50 90,50 90,90"/>
</svg>"#;
    let o = meshing::parse_svg(crossing, None).expect("parses");
    let e = meshing::mesh_outline(&o, &MeshOptions::default()).unwrap_err();
    match &e {
        MeshingError::SelfIntersection {
            place, contact, at, ..
        } => {
            assert_eq!(place.line, Some(2));
            assert_eq!(*contact, Contact::Cross);
            assert_eq!(*at, [60.0, 50.0]);
        }
        other => panic!("{other}"),
    }
    assert_eq!(
        e.in_file("crossing.svg").to_string(),
        "crossing.svg:2: <rect> segment 1 crosses <polygon> segment 0 (line 3) near (60, 50)"
    );
    let tiny = r#"<svg><rect width="100" height="100"/><circle cx="50" cy="50" r="0.05"/></svg>"#;
    let e = meshing::parse_svg(tiny, Some(0.5)).unwrap_err();
    assert!(matches!(e, MeshingError::LoopTooSmall { .. }), "{e}");
}

/// A square `[0, 4]^2` with a square `[1, 3]^2` inside, numbered from 1; `holes` hole points.
fn nested_squares(holes: &str) -> String {
    format!(
        "# two squares\n8 2 0 0\n1 0 0\n2 4 0\n3 4 4\n4 0 4\n5 1 1\n6 3 1\n7 3 3\n8 1 3\n\
         8 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n5 5 6\n6 6 7\n7 7 8\n8 8 5\n{holes}"
    )
}

#[test]
fn poly_holes_come_from_hole_points() {
    let options = MeshOptions::default().with_vertices(600);
    // With a hole point, the inner square is a hole (refined by parity, outside skipped).
    let holed = meshing::parse_poly(&nested_squares("1\n1 2 2\n")).expect("parses");
    let m = meshing::mesh_outline(&holed, &options).expect("meshes");
    check(&m, 600, meshing::DEFAULT_MIN_ANGLE);
    assert_eq!(topology(&m.mesh), (2, 1));
    let area: f64 = m.mesh.faces.iter().map(|f| m.mesh.signed_area(f)).sum();
    assert!((area - 12.0).abs() < 1e-9, "area {area}");
    // Without one, as in Triangle, the inner square is part of the shape (an inner boundary):
    // everything is refined, then the outside removed.
    let filled = meshing::parse_poly(&nested_squares("0\n")).expect("parses");
    let m = meshing::mesh_outline(&filled, &options).expect("meshes");
    check(&m, 600, meshing::DEFAULT_MIN_ANGLE);
    assert_eq!(topology(&m.mesh), (1, 1));
    let area: f64 = m.mesh.faces.iter().map(|f| m.mesh.signed_area(f)).sum();
    assert!((area - 16.0).abs() < 1e-9, "area {area}");
    // The inner square's segments are kept as edges: 8 units of edges lie along them.
    let mut edges: Vec<(u32, u32)> = m
        .mesh
        .faces
        .iter()
        .flat_map(|f| (0..3).map(move |k| (f[k].min(f[(k + 1) % 3]), f[k].max(f[(k + 1) % 3]))))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let on_side = |p: [f64; 2], q: [f64; 2]| {
        let inside = |x: f64| (1.0..=3.0).contains(&x);
        ((p[0] == q[0] && (p[0] == 1.0 || p[0] == 3.0)) && inside(p[1]) && inside(q[1]))
            || ((p[1] == q[1] && (p[1] == 1.0 || p[1] == 3.0)) && inside(p[0]) && inside(q[0]))
    };
    let along: f64 = edges
        .iter()
        .map(|&(a, b)| (m.mesh.positions[a as usize], m.mesh.positions[b as usize]))
        .filter(|&(p, q)| on_side(p, q))
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .sum();
    assert!(
        (along - 8.0).abs() < 1e-9,
        "{along} units of edges along the inner square"
    );
    // Texture coordinates: the bounding box as a square.
    for (p, t) in m.mesh.positions.iter().zip(&m.texcoords.uv) {
        assert!((t[0] - p[0] / 4.0).abs() < 1e-12 && (t[1] - p[1] / 4.0).abs() < 1e-12);
    }
    // A hole point outside every region changes nothing; hole points in both regions leave
    // nothing.
    let none = meshing::parse_poly(&nested_squares("2\n1 2 2\n2 0.5 0.5\n")).expect("parses");
    let e = meshing::mesh_outline(&none, &options).unwrap_err();
    assert!(
        matches!(
            e,
            MeshingError::NothingInside {
                hole_points: true,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn poly_errors_name_their_line() {
    let bad = nested_squares("0\n").replace("6 6 7", "6 6 9");
    let e = meshing::parse_poly(&bad)
        .unwrap_err()
        .in_file("squares.poly");
    assert_eq!(e.line(), Some(17));
    assert_eq!(
        e.to_string(),
        "squares.poly:17: segment 6 refers to vertex 9, but the vertices are numbered 1 to 8"
    );
    // Crossing segments: name both and their lines.
    let crossing = nested_squares("0\n").replace("5 1 1\n", "5 1 -1\n");
    let o = meshing::parse_poly(&crossing).expect("parses");
    let e = meshing::mesh_outline(&o, &MeshOptions::default())
        .unwrap_err()
        .in_file("squares.poly");
    assert_eq!(
        e.to_string(),
        "squares.poly:12: segment 1 crosses segment 5 (line 16) near (2, 0)"
    );
}

#[test]
fn only_a_sharper_corner_of_the_outline_keeps_smaller_angles() {
    // A wedge with a 15 degree tip at the origin and a round back of radius 100: no
    // triangulation can have angles above 15 degrees at the tip, and refinement leaves the
    // few triangles nearest it alone.
    let half = 7.5f64.to_radians();
    let mut wedge = vec![[0.0, 0.0]];
    wedge.extend((0..=20).map(|i| {
        let a = -half + 2.0 * half * f64::from(i) / 20.0;
        [100.0 * a.cos(), 100.0 * a.sin()]
    }));
    let outline = meshing::Outline::from_loops(&[wedge]);
    for n in [200, 2000] {
        let m = meshing::mesh_outline(&outline, &MeshOptions::default().with_vertices(n))
            .expect("meshes");
        let skinny: Vec<&[u32; 3]> = m
            .mesh
            .faces
            .iter()
            .filter(|f| {
                let one = PlanarMesh {
                    positions: f.map(|v| m.mesh.positions[v as usize]).to_vec(),
                    faces: vec![[0, 1, 2]],
                };
                meshing::min_angle(&one) < meshing::DEFAULT_MIN_ANGLE
            })
            .collect();
        assert!(
            !skinny.is_empty() && skinny.len() <= 4,
            "{} skinny",
            skinny.len()
        );
        for f in skinny {
            let near = f
                .iter()
                .map(|&v| m.mesh.positions[v as usize][0].hypot(m.mesh.positions[v as usize][1]))
                .fold(f64::INFINITY, f64::min);
            assert!(near < 10.0, "a skinny triangle {near} from the tip");
        }
        assert!(m.stats.min_angle > 14.0, "{}", m.stats.min_angle);
        assert!(m.mesh.faces.iter().all(|f| m.mesh.signed_area(f) > 0.0));
    }
}

/// A subject: a body (a disk of radius 110) with an arm, in a 400 x 300 picture.
fn body(p: [f64; 2]) -> f64 {
    circle(p, [170.0, 150.0], 110.0).min(capsule_distance(p, [250.0, 120.0], [360.0, 60.0], 12.0))
}

#[test]
fn specks_are_left_out_unless_kept() {
    // Dust around the body: two specks of a few pixels, and a speck ring (a hole in it).
    let dusty = |p: [f64; 2]| {
        let ring = circle(p, [60.0, 260.0], 5.0).max(-circle(p, [60.0, 260.0], 2.5));
        body(p)
            .min(circle(p, [330.0, 250.0], 2.0))
            .min(capsule_distance(p, [20.0, 30.0], [24.0, 33.0], 1.5))
            .min(ring)
    };
    let image = picture(400, 300, dusty);
    let clean = picture(400, 300, body);
    let options = MeshOptions::default().with_vertices(800);
    let m = meshing::mesh_picture(&image, &PictureOptions::default(), &options).expect("meshes");
    check(&m, 800, meshing::DEFAULT_MIN_ANGLE);
    assert_eq!((m.stats.pieces, m.stats.holes), (1, 0));
    assert_eq!((m.stats.dropped_specks, m.stats.dropped_outlines), (3, 0));
    // The specks constrain nothing: the mesh is the clean picture's.
    let c = meshing::mesh_picture(&clean, &PictureOptions::default(), &options).expect("meshes");
    assert_eq!(c.stats.dropped_specks, 0);
    assert_eq!(m.mesh, c.mesh);
    let traced =
        meshing::picture_outline(&image, &PictureOptions::default(), None).expect("traces");
    assert_eq!((traced.dropped_specks, traced.dropped), (3, 0));
    assert_eq!(
        traced.traced.len(),
        5,
        "every traced loop, dropped ones too"
    );
    // Kept on request: four pieces, the ring with its hole.
    let keep = PictureOptions::default().with_keep_specks(true);
    let k = meshing::mesh_picture(&image, &keep, &options).expect("meshes");
    check(&k, 800, meshing::DEFAULT_MIN_ANGLE);
    assert_eq!((k.stats.pieces, k.stats.holes), (4, 1));
    assert_eq!(k.stats.dropped_specks, 0);
    let traced = meshing::picture_outline(&image, &keep, None).expect("traces");
    assert_eq!(
        (traced.dropped_specks, traced.outline.elements.len()),
        (0, 5)
    );
}

#[test]
fn detached_parts_are_not_specks() {
    // Two figures of similar size, and a ball (3% of the larger) apart from both.
    let image = picture(500, 300, |p| {
        circle(p, [120.0, 150.0], 100.0)
            .min(circle(p, [370.0, 150.0], 80.0))
            .min(circle(p, [250.0, 270.0], 17.0))
    });
    let m = meshing::mesh_picture(
        &image,
        &PictureOptions::default(),
        &MeshOptions::default().with_vertices(1000),
    )
    .expect("meshes");
    check(&m, 1000, meshing::DEFAULT_MIN_ANGLE);
    assert_eq!((m.stats.pieces, m.stats.dropped_specks), (3, 0));
    // Alone, the largest piece is kept however small the picture's subject is.
    let tiny = picture(40, 40, |p| circle(p, [20.0, 20.0], 4.0));
    let m = meshing::mesh_picture(
        &tiny,
        &PictureOptions::default(),
        &MeshOptions::default().with_vertices(30),
    )
    .expect("meshes");
    assert_eq!((m.stats.pieces, m.stats.dropped_specks), (1, 0));
}

#[test]
fn outlines_keep_their_small_pieces() {
    // A rectangle and a square of 0.01% of its area: an outline is the user's geometry.
    let svg = r#"<svg viewBox="0 0 1000 1000"><rect x="10" y="10" width="900" height="900"/><rect x="950" y="950" width="9" height="9"/></svg>"#;
    let outline = meshing::parse_svg(svg, None).expect("parses");
    let m = meshing::mesh_outline(&outline, &MeshOptions::default().with_vertices(600))
        .expect("meshes");
    assert_eq!((m.stats.pieces, m.stats.dropped_specks), (2, 0));
    let dir = std::env::temp_dir().join(format!("bdmorph-meshing-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("small.svg");
    std::fs::write(&path, svg).expect("writes");
    let m = meshing::mesh_file(
        &path,
        &PictureOptions::default(),
        &MeshOptions::default().with_vertices(600),
    )
    .expect("meshes");
    assert_eq!((m.stats.pieces, m.stats.dropped_specks), (2, 0));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A picture of the region `r < radius(angle)` around the centre of a `size` square.
fn polar(size: u32, radius: impl Fn(f64) -> f64) -> Image {
    let c = f64::from(size) / 2.0;
    generate::picture(size, size, |x, y| {
        let (dx, dy) = (x - c, y - c);
        dx.hypot(dy) - radius(dy.atan2(dx))
    })
}

/// Detailed pictures: outlines of 300 to 1000 vertices at the default tolerance.
fn detailed() -> Vec<(&'static str, Image)> {
    let gear = polar(800, |a| 320.0 + 4.0 * (4.0 * (200.0 * a).sin()).tanh());
    let hairy = polar(800, |a| {
        300.0 + 3.0 * (300.0 * a).sin() + 25.0 * (3.0 * a).sin()
    });
    // A hard mask (no anti-aliasing): a leaf with a serrated edge, and a hole.
    let mut leaf = generate::picture(600, 600, |x, y| {
        let (u, v) = ((x - 300.0) / 270.0, (y - 300.0) / 150.0);
        let blade =
            (u * u + v * v).sqrt() * 150.0 - 150.0 + 5.0 * (80.0 * v.atan2(u)).sin().powi(2);
        blade.max(20.0 - (x - 200.0).hypot(y - 300.0))
    });
    for p in leaf.rgba.chunks_exact_mut(4) {
        p[3] = if p[3] >= 128 { 255 } else { 0 };
    }
    // A cloud with a second, smaller one.
    let cloud = generate::picture(700, 500, |x, y| {
        let scalloped = |cx: f64, cy: f64, r: f64, n: u32| {
            let (dx, dy) = (x - cx, y - cy);
            let mut d = dx.hypot(dy) - r;
            for k in 0..n {
                let a = f64::from(k) / f64::from(n) * std::f64::consts::TAU;
                d = d.min((dx - r * a.cos()).hypot(dy - r * a.sin()) - 8.0);
            }
            d
        };
        scalloped(260.0, 250.0, 200.0, 90).min(scalloped(590.0, 110.0, 70.0, 30))
    });
    vec![
        ("gear", gear),
        ("hairy blob", hairy),
        ("serrated leaf", leaf),
        ("clouds", cloud),
    ]
}

/// The smallest angle between two segments of an outline meeting at a vertex, in degrees.
fn sharpest_corner(outline: &meshing::Outline) -> f64 {
    let mut ends: Vec<Vec<usize>> = vec![Vec::new(); outline.vertices.len()];
    for s in &outline.segments {
        ends[s[0] as usize].push(s[1] as usize);
        ends[s[1] as usize].push(s[0] as usize);
    }
    let mut sharpest = 180.0f64;
    for (v, e) in ends.iter().enumerate() {
        if let [a, b] = e[..] {
            let o = outline.vertices[v];
            let (p, q) = (outline.vertices[a], outline.vertices[b]);
            let (u, w) = ([p[0] - o[0], p[1] - o[1]], [q[0] - o[0], q[1] - o[1]]);
            let angle = (u[0] * w[1] - u[1] * w[0])
                .abs()
                .atan2(u[0] * w[0] + u[1] * w[1]);
            sharpest = sharpest.min(angle.to_degrees());
        }
    }
    sharpest
}

#[test]
fn detailed_pictures_meet_the_vertex_count() {
    let mut worst: f64 = 0.0;
    for (name, image) in detailed() {
        let outline =
            meshing::picture_outline(&image, &PictureOptions::default(), None).expect("traces");
        let traced = outline.outline.vertices.len();
        assert!(traced > 300, "{name}: {traced} outline vertices");
        let pieces = if name == "clouds" { 2 } else { 1 };
        for n in [300, 500, 1000, 3000] {
            let options = MeshOptions::default().with_vertices(n);
            let m = meshing::mesh_picture(&image, &PictureOptions::default(), &options)
                .expect("meshes");
            let off = (m.stats.vertices as f64 - n as f64) / n as f64;
            worst = worst.max(off.abs());
            assert!(
                off.abs() <= 0.1,
                "{name}: {} vertices for {n} ({:?})",
                m.stats.vertices,
                m.stats.off_target
            );
            let t = m.stats.tolerance.expect("a picture's tolerance");
            let simplified = meshing::picture_outline(&image, &PictureOptions::default(), Some(t))
                .expect("traces")
                .outline;
            // Near corners below 60 degrees (the leaf's notches, 30 to 33) the refinement can
            // leave a triangle a few degrees under the minimum angle (24.1 on the leaf at 3000
            // vertices, at the default tolerance): not what this test is about.
            check(&m, n, 20.0);
            if sharpest_corner(&simplified) >= 60.0 {
                assert!(m.stats.min_angle >= meshing::DEFAULT_MIN_ANGLE - 1e-9);
            }
            assert_eq!(m.stats.requested_vertices, n);
            assert_eq!(m.stats.off_target, None, "{name} at {n}");
            assert_eq!(m.stats.pieces, pieces, "{name} at {n}");
            // The outline takes at most its share, at a tolerance no finer than the default,
            // and the boundary is within the tolerance used.
            assert!(t >= meshing::DEFAULT_PICTURE_TOLERANCE);
            assert!(
                m.stats.outline_vertices as f64 <= meshing::OUTLINE_VERTEX_SHARE * n as f64
                    || t == meshing::DEFAULT_PICTURE_TOLERANCE,
                "{name} at {n}: {} outline vertices",
                m.stats.outline_vertices
            );
            assert_eq!(
                (m.stats.dropped_outlines, m.stats.dropped_specks),
                (0, 0),
                "{name} at {n}"
            );
            check_boundary(&image, &PictureOptions::default(), &m, t);
        }
    }
    println!("worst miss {:.1}%", 100.0 * worst);
}

#[test]
fn a_missed_vertex_count_says_why() {
    let gear = polar(800, |a| 320.0 + 4.0 * (4.0 * (200.0 * a).sin()).tanh());
    // An explicit fine tolerance: the outline alone has more than 60 vertices.
    let explicit = MeshOptions::default().with_vertices(60).with_tolerance(0.5);
    let m = meshing::mesh_picture(&gear, &PictureOptions::default(), &explicit).expect("meshes");
    assert!(m.stats.vertices > 66);
    assert_eq!(m.stats.requested_vertices, 60);
    assert_eq!(m.stats.tolerance, Some(0.5));
    match &m.stats.off_target {
        Some(
            why @ meshing::OffTarget::Tolerance {
                tolerance,
                outline_vertices,
            },
        ) => {
            assert_eq!(
                (*tolerance, *outline_vertices),
                (0.5, m.stats.outline_vertices)
            );
            assert!(
                why.to_string()
                    .starts_with("the outline simplified to --tolerance 0.5 alone has "),
                "{why}"
            );
        }
        other => panic!("{other:?}"),
    }
    // Without it, the tolerance is raised to fit.
    let auto = MeshOptions::default().with_vertices(60);
    let m = meshing::mesh_picture(&gear, &PictureOptions::default(), &auto).expect("meshes");
    assert_eq!(m.stats.off_target, None);
    assert!(m.stats.vertices.abs_diff(60) <= 6, "{}", m.stats.vertices);
    // Holes the default tolerance keeps are not dropped to fit: 60 holes need more than a
    // fifth of 300 vertices.
    let holey = picture(500, 500, |p| {
        let mut d = circle(p, [250.0, 250.0], 220.0);
        for i in 0..60 {
            let r = 60.0 + 50.0 * f64::from(i / 20);
            let a = f64::from(i % 20) / 20.0 * std::f64::consts::TAU;
            d = d.max(-circle(p, [250.0 + r * a.cos(), 250.0 + r * a.sin()], 4.0));
        }
        d
    });
    let m = meshing::mesh_picture(
        &holey,
        &PictureOptions::default(),
        &MeshOptions::default().with_vertices(300),
    )
    .expect("meshes");
    assert_eq!(m.stats.holes, 60);
    assert!(m.stats.vertices > 330, "{}", m.stats.vertices);
    assert!(
        matches!(
            m.stats.off_target,
            Some(meshing::OffTarget::Loops { loops: 61, .. })
        ),
        "{:?}",
        m.stats.off_target
    );
    // Long thin spikes: a 300-vertex mesh could show them, so they are not simplified away,
    // and they need more vertices.
    let spikes = polar(700, |a| {
        180.0 + 120.0 * (0.5 + 0.5 * (120.0 * a).cos()).powi(6)
    });
    let m = meshing::mesh_picture(
        &spikes,
        &PictureOptions::default(),
        &MeshOptions::default().with_vertices(300),
    )
    .expect("meshes");
    assert!(
        m.stats.outline_vertices >= 240,
        "{}",
        m.stats.outline_vertices
    );
    assert!(
        matches!(
            m.stats.off_target,
            Some(meshing::OffTarget::Detail { .. } | meshing::OffTarget::MinAngle { .. })
        ),
        "{:?}",
        m.stats.off_target
    );
}

#[test]
fn hand_drawn_loops_are_fitted_to_a_vertex_count() {
    // The loops traced from a detailed picture, as the studio's user might draw them.
    let (_, gear) = detailed().swap_remove(0);
    let traced = meshing::picture_outline(&gear, &PictureOptions::default(), Some(0.2))
        .expect("traces")
        .traced;
    for n in [300, 1000] {
        let fitted = meshing::fit_loops_to_vertices(&traced, n);
        assert!(fitted.fits && fitted.tolerance.is_some());
        let used: usize = fitted.loops.iter().map(Vec::len).sum();
        assert!(
            used as f64 <= meshing::OUTLINE_VERTEX_SHARE * n as f64,
            "{used}"
        );
        let m = meshing::mesh_outline(
            &meshing::Outline::from_loops(&fitted.loops),
            &MeshOptions::default().with_vertices(n),
        )
        .expect("meshes");
        check(&m, n, meshing::DEFAULT_MIN_ANGLE);
    }
    let few = meshing::fit_loops_to_vertices(&traced, 1_000_000);
    assert_eq!((few.loops, few.tolerance), (traced, None));
}

#[test]
fn a_hundred_thousand_nested_groups_read_on_a_2_mib_stack() {
    let depth = 100_000;
    let mut text = String::from("<svg>\n");
    text.push_str(&"<g>".repeat(depth));
    text.push_str("\n<rect width=\"10\" height=\"5\"/>\n");
    text.push_str(&"</g>".repeat(depth));
    text.push_str("</svg>");
    // The stack of a tokio worker thread (the studio's).
    let outline = std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(move || meshing::parse_svg(&text, None))
        .expect("spawns")
        .join()
        .expect("no stack overflow")
        .expect("reads");
    assert_eq!(outline.elements.len(), 1);
    assert_eq!(outline.elements[0].line, Some(3));
}

#[test]
fn a_bow_tie_polygon_is_said_to_cross_itself() {
    let text = "<svg>\n<polygon points=\"0,0 10,10 10,0 0,10\"/>\n</svg>";
    let o = meshing::parse_svg(text, None).expect("parses");
    let e = meshing::mesh_outline(&o, &MeshOptions::default()).unwrap_err();
    assert_eq!(
        e.in_file("bow.svg").to_string(),
        "bow.svg:2: <polygon> segment 0 crosses <polygon> segment 2 near (5, 5)"
    );
}

#[test]
fn coordinates_out_of_range_are_named_with_their_line() {
    let overflow =
        "<svg>\n<polygon points=\"0,0 1e308,0 0,1e308\" transform=\"scale(10)\"/>\n</svg>";
    let e = meshing::parse_svg(overflow, None).unwrap_err();
    assert!(matches!(e, MeshingError::OutOfRange { .. }), "{e}");
    assert!(
        e.to_string()
            .starts_with("line 2: <polygon> points: a number is 1.00000e308, outside the supported range (0, or magnitudes from 1e-30 to 1e9)"),
        "{e}"
    );
    let huge = "3 2 0 0\n1 0 0\n2 1e12 0\n3 0 1\n3 0\n1 1 2\n2 2 3\n3 3 1\n";
    assert_eq!(
        meshing::parse_poly(huge).unwrap_err().in_file("h.poly").to_string(),
        "h.poly:3: the vertex's x is 1.00000e12, outside the supported range (0, or magnitudes from 1e-30 to 1e9)"
    );
    let tiny = huge.replace("1e12", "1e-40");
    assert!(meshing::parse_poly(&tiny)
        .unwrap_err()
        .to_string()
        .starts_with("line 3: the vertex's x is 1.00000e-40, outside"));
    // Outlines made in code (the studio's) go through the same check.
    let o = meshing::Outline::from_loops(&[vec![[0.0, 0.0], [1e12, 0.0], [0.0, 1.0]]]);
    let e = meshing::mesh_outline(&o, &MeshOptions::default()).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("outline 0 segment 0: a coordinate is 1.00000e12, outside"),
        "{e}"
    );
}

#[test]
fn a_mesh_the_readers_would_refuse_is_not_made() {
    // A spike 1e-16 wide at its base: meshed, it needs a triangle of area about 1e-32,
    // which the mesh readers (and `bdmorph info`) refuse as degenerate.
    let spike = "6 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0.5 1e-16\n5 0.49 1\n6 0 1\n\
                 6 0\n1 1 2\n2 2 3\n3 3 4\n4 4 5\n5 5 6\n6 6 1\n0\n";
    let o = meshing::parse_poly(spike).expect("parses");
    let e = meshing::mesh_outline(&o, &MeshOptions::default().with_vertices(200)).unwrap_err();
    assert!(matches!(e, MeshingError::Degenerate { .. }), "{e}");
    let message = e.in_file("spike.poly").to_string();
    assert!(
        message.starts_with(
            "spike.poly: the mesh would have a degenerate triangle (area 9.09949e-33) near (0.5, 5.46406e-17)"
        ),
        "{message}"
    );
    // A dip of 1e-17 in an edge meshes into triangles the readers accept.
    let dip = "5 2 0 0\n1 0 0\n2 0.5 -1e-17\n3 1 0\n4 1 1\n5 0 1\n5 0\n1 1 2\n2 2 3\n3 3 4\n4 4 5\n5 5 1\n0\n";
    let o = meshing::parse_poly(dip).expect("parses");
    let m = meshing::mesh_outline(&o, &MeshOptions::default().with_vertices(200)).expect("meshes");
    m.mesh.validate().expect("a mesh the readers accept");
}
