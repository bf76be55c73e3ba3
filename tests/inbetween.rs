//! In-betweens of two drawings: the compatible mesh and the morph between its layouts, on
//! pictures made here.

mod common;

use bdmorph::generate;
use bdmorph::inbetween::{
    compatible_mesh, CompatibleMesh, Inbetween, InbetweenError, InbetweenOptions, Match,
};
use bdmorph::render::{raster, Background, Drawing, Image, ImageSize, Viewport};
use common::max_distance;

fn figure_pair() -> (Image, Image) {
    (
        generate::figure_picture(256, 0.0, 0.0),
        generate::figure_picture(256, 2.0, 0.2),
    )
}

fn options(vertices: usize) -> InbetweenOptions {
    InbetweenOptions::default().with_vertices(vertices)
}

fn signed_area(p: &[[f64; 2]], f: &[u32; 3]) -> f64 {
    let (a, b, c) = (p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]);
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
}

/// Checks what every compatible mesh must be: flip-free over A and B, B's outline
/// reproduced within the tolerance it was simplified to.
fn check_compatible(c: &CompatibleMesh) {
    let r = &c.report;
    assert_eq!(r.flipped, 0);
    assert!(c.mesh.faces.iter().all(|f| c.mesh.signed_area(f) > 0.0));
    assert!(c
        .mesh
        .faces
        .iter()
        .all(|f| signed_area(&c.positions_b, f) > 0.0));
    assert!(
        r.outline_error <= r.tolerance[1],
        "B's outline is {} px from the mesh, over the tolerance {}",
        r.outline_error,
        r.tolerance[1]
    );
    assert!(r.max_distortion.is_finite() && r.max_distortion >= 1.0);
    assert_eq!(c.texcoords_a.uv.len(), c.mesh.positions.len());
    assert_eq!(c.texcoords_b.uv.len(), c.mesh.positions.len());
}

#[test]
fn a_figure_and_the_figure_with_an_arm_raised_and_the_body_bent() {
    let (a, b) = figure_pair();
    let mut inbetween = Inbetween::new(&a, &b, &[], &options(1500)).unwrap();
    let c = inbetween.compatible().clone();
    check_compatible(&c);
    let size = c.mesh.diameter();
    // The endpoints reproduce A's and B's layouts.
    let start = inbetween.frame(0.0).unwrap().positions.to_vec();
    assert!(max_distance(&start, &c.mesh.positions) < 1e-8 * size);
    let end = inbetween.frame(1.0).unwrap().positions.to_vec();
    assert!(max_distance(&end, &c.positions_b) < 1e-8 * size);
    // 50 in-betweens: none flipped, none more distorted from A than B's layout is (up to
    // the solver's tolerance).
    let endpoint = c.report.max_distortion;
    for k in 0..50 {
        let t = k as f64 / 49.0;
        let frame = inbetween.frame(t).unwrap();
        assert_eq!(frame.stats.flipped_triangles, 0, "t = {t}");
        assert!(
            frame.stats.max_conformal_distortion <= endpoint * 1.001,
            "t = {t}: distortion {} over the endpoint's {endpoint}",
            frame.stats.max_conformal_distortion
        );
    }
}

/// The share of the subject's inner pixels (opaque, two pixels from any transparent one)
/// whose colour in `drawn` differs from `picture` by more than 24 levels in a channel, and
/// the mean difference there.
fn pixel_disagreement(picture: &Image, drawn: &Image) -> (f64, f64) {
    let (w, h) = (picture.width as i64, picture.height as i64);
    let alpha = |x: i64, y: i64| {
        if x < 0 || y < 0 || x >= w || y >= h {
            0
        } else {
            picture.rgba[4 * (y * w + x) as usize + 3]
        }
    };
    let (mut inner, mut off, mut sum) = (0usize, 0usize, 0.0);
    for y in 0..h {
        for x in 0..w {
            let solid = (-2..=2).all(|dy| (-2..=2).all(|dx| alpha(x + dx, y + dy) == 255));
            if !solid {
                continue;
            }
            inner += 1;
            let i = 4 * (y * w + x) as usize;
            let d = (0..3)
                .map(|c| (i32::from(picture.rgba[i + c]) - i32::from(drawn.rgba[i + c])).abs())
                .max()
                .unwrap_or(0);
            sum += f64::from(d);
            if d > 24 {
                off += 1;
            }
        }
    }
    assert!(inner > 1000, "the subject has {inner} inner pixels");
    (off as f64 / inner as f64, sum / inner as f64)
}

#[test]
fn frames_at_0_and_1_look_like_the_pictures() {
    let (a, b) = figure_pair();
    let mut inbetween = Inbetween::new(&a, &b, &[], &options(1500)).unwrap();
    let c = inbetween.compatible().clone();
    let uv_a = c.texcoords_a.corner_uv();
    let uv_b = c.texcoords_b.corner_uv();
    // The pictures' own pixel frames: one world unit a pixel.
    let view = Viewport {
        min: [0.0, 0.0],
        max: [256.0, 256.0],
    };
    let size = ImageSize {
        width: 256,
        height: 256,
    };
    for (t, picture, uv) in [(0.0, &a, &uv_a), (1.0, &b, &uv_b)] {
        let positions = inbetween.frame(t).unwrap().positions.to_vec();
        let drawing = Drawing {
            faces: &c.mesh.faces,
            corner_uv: Some(uv),
            texture: Some(picture),
            ..Drawing::default()
        };
        let drawn = raster::render_on(&positions, &drawing, &view, size, Background::Transparent)
            .expect("within the picture budget");
        let (off, mean) = pixel_disagreement(picture, &drawn);
        // Stated tolerance: under 1% of the subject's inner pixels off by more than 24
        // levels (the texture is sampled bilinearly through the mesh), a mean under 3.
        assert!(off < 0.01 && mean < 3.0, "t = {t}: {off} off, mean {mean}");
    }
}

#[test]
fn a_shape_with_a_hole_in_both_drawings() {
    let a = generate::ring_picture(200, [100.0, 100.0], 70.0, [100.0, 100.0], 25.0);
    let b = generate::ring_picture(200, [110.0, 95.0], 65.0, [85.0, 110.0], 20.0);
    let mut inbetween = Inbetween::new(&a, &b, &[], &options(800)).unwrap();
    let c = inbetween.compatible().clone();
    check_compatible(&c);
    for k in 0..=10 {
        let frame = inbetween.frame(k as f64 / 10.0).unwrap();
        assert_eq!(frame.stats.flipped_triangles, 0);
    }
}

#[test]
fn a_different_number_of_pieces_is_refused_in_one_line() {
    let disk = generate::picture(160, 160, |x, y| {
        generate::capsule_distance([x, y], [80.0, 80.0], [80.0, 80.0], 60.0)
    });
    let two = generate::picture(160, 160, |x, y| {
        generate::capsule_distance([x, y], [40.0, 80.0], [40.0, 80.0], 30.0).min(
            generate::capsule_distance([x, y], [120.0, 80.0], [120.0, 80.0], 30.0),
        )
    });
    let e = compatible_mesh(&disk, &two, &[], &options(400)).unwrap_err();
    assert!(matches!(e, InbetweenError::Topology(_)));
    let text = e.to_string();
    assert_eq!(text.lines().count(), 1);
    assert!(
        text.contains("drawing A has 1 piece and drawing B has 2 pieces"),
        "{text}"
    );
}

/// The vertex of `mesh` nearest `p`, at most `within` px away.
fn vertex_at(c: &CompatibleMesh, p: [f64; 2], within: f64) -> usize {
    let (d, v) = c
        .mesh
        .positions
        .iter()
        .enumerate()
        .map(|(v, q)| ((q[0] - p[0]).hypot(q[1] - p[1]), v))
        .min_by(|x, y| x.0.total_cmp(&y.0))
        .unwrap();
    assert!(d <= within, "no vertex at {p:?} (nearest {d} px away)");
    v
}

#[test]
fn point_pairs_are_met_or_said_unmet() {
    let (a, b) = figure_pair();
    let h = 256.0;
    // Top of the head (on both outlines), a point in the chest (inside both), and a point
    // of B outside the drawing.
    let head_a = [128.0, h - (0.79 + 0.085) * h];
    let head_b = {
        let (s, c) = (-0.2f64).sin_cos();
        let (dx, dy) = (0.0, 0.79 + 0.085 - 0.42);
        [
            (0.5 + c * dx - s * dy) * h,
            h - (0.42 + s * dx + c * dy) * h,
        ]
    };
    let matches = [
        Match {
            a: head_a,
            b: head_b,
        },
        Match {
            a: [128.0, h - 0.55 * h],
            b: [135.0, h - 0.55 * h],
        },
        Match {
            a: [128.0, h - 0.3 * h],
            b: [250.0, 10.0],
        },
    ];
    let c = compatible_mesh(&a, &b, &matches, &options(1500)).unwrap();
    check_compatible(&c);
    let r = &c.report.pairs;
    assert_eq!(r.len(), 3);
    // The outline pair: A's point is a vertex and lands on B's point (within the distance
    // of B's point from B's outline; A's point is taken onto A's outline, here 0.2 px).
    assert!(r[0].on_outline && r[0].met, "{:?}", r[0]);
    let v = vertex_at(&c, [head_a[0], h - head_a[1]], 1.0);
    let q = c.positions_b[v];
    let target = [head_b[0], h - head_b[1]];
    assert!((q[0] - target[0]).hypot(q[1] - target[1]) <= r[0].error + 1e-6);
    assert!(r[0].error < 2.0);
    // The interior pair: a vertex on A's point lands exactly on B's.
    assert!(!r[1].on_outline && r[1].met, "{:?}", r[1]);
    let v = vertex_at(&c, [128.0, 0.55 * h], 1e-9);
    let q = c.positions_b[v];
    assert!((q[0] - 135.0).hypot(q[1] - 0.55 * h) < 1e-6);
    // The pair outside B: said, the others met.
    assert!(!r[2].met);
    let reason = r[2].reason.as_deref().unwrap();
    assert!(reason.contains("outside the drawing"), "{reason}");
}

#[test]
fn unreadable_pairs_are_refused_naming_the_pair() {
    let (a, b) = figure_pair();
    let h = 256.0;
    let on_a_inside_b = Match {
        a: [128.0, h - (0.79 + 0.085) * h],
        b: [135.0, h - 0.55 * h],
    };
    let e = compatible_mesh(&a, &b, &[on_a_inside_b], &options(600)).unwrap_err();
    let text = e.to_string();
    assert!(
        text.starts_with("pair 1:") && text.contains("on the outline"),
        "{text}"
    );
}

#[test]
fn a_path_through_three_drawings_on_one_mesh() {
    let a = generate::figure_picture(200, 0.0, 0.0);
    let b = generate::figure_picture(200, 1.2, 0.1);
    let c = generate::figure_picture(200, 2.0, -0.1);
    let mut inbetween = Inbetween::through(&[&a, &b, &c], &[], &options(900)).unwrap();
    let path = inbetween.path().clone();
    assert_eq!(inbetween.drawings(), 3);
    assert_eq!(path.layouts.len(), 2);
    assert_eq!(path.texcoords.len(), 3);
    for (k, layout) in path.layouts.iter().enumerate() {
        assert!(
            path.mesh.faces.iter().all(|f| signed_area(layout, f) > 0.0),
            "layout {k} has a flipped triangle"
        );
        let r = &path.reports[k];
        assert!(r.outline_error <= r.tolerance[1], "{r:?}");
    }
    let size = path.mesh.diameter();
    // Every drawing's layout at its time, and nothing flipped between.
    for (t, expected) in [
        (0.0, &path.mesh.positions),
        (0.5, &path.layouts[0]),
        (1.0, &path.layouts[1]),
    ] {
        let at = inbetween.frame(t).unwrap().positions.to_vec();
        assert!(max_distance(&at, expected) < 1e-8 * size, "t = {t}");
    }
    assert_eq!(inbetween.segment(0.25), (0, 0.5));
    assert_eq!(inbetween.segment(1.0), (1, 1.0));
    for k in 0..=30 {
        let frame = inbetween.frame(k as f64 / 30.0).unwrap();
        assert_eq!(frame.stats.flipped_triangles, 0);
    }
}

#[test]
fn a_fine_mesh_is_laid_over_b_from_a_coarse_one() {
    // Beyond 3000 vertices the layout over B starts from a 2000-vertex mesh of the same
    // outline, interpolated.
    let a = generate::figure_picture(400, 0.0, 0.0);
    let b = generate::figure_picture(400, 2.0, 0.2);
    let c = compatible_mesh(&a, &b, &[], &options(5000)).unwrap();
    assert!(c.mesh.positions.len() > 4500, "{}", c.mesh.positions.len());
    check_compatible(&c);
}

mod hostile {
    //! Drawings of random capsules (some touching the edge, some thin, some apart) and random
    //! point pairs: a compatible mesh that is flip-free, or a one-line error; never a panic.

    use super::*;
    use proptest::prelude::*;

    fn blobs(size: u32, capsules: Vec<([f64; 4], f64)>) -> Image {
        let s = f64::from(size);
        generate::picture(size, size, move |x, y| {
            capsules
                .iter()
                .map(|&([ax, ay, bx, by], r)| {
                    generate::capsule_distance([x, y], [ax * s, ay * s], [bx * s, by * s], r * s)
                })
                .fold(f64::INFINITY, f64::min)
        })
    }

    fn capsule() -> impl Strategy<Value = ([f64; 4], f64)> {
        (
            [0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64],
            0.005..0.3f64,
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]
        #[test]
        fn any_two_drawings_give_a_mesh_or_one_line(
            a in proptest::collection::vec(capsule(), 1..4),
            b in proptest::collection::vec(capsule(), 1..4),
            pairs in proptest::collection::vec([-50.0..150.0f64, -50.0..150.0f64, -50.0..150.0f64, -50.0..150.0f64], 0..3),
        ) {
            let (a, b) = (blobs(96, a), blobs(96, b));
            let matches: Vec<Match> = pairs.iter().map(|p| Match { a: [p[0], p[1]], b: [p[2], p[3]] }).collect();
            match compatible_mesh(&a, &b, &matches, &options(300)) {
                Ok(c) => check_compatible(&c),
                Err(e) => {
                    let text = e.to_string();
                    prop_assert!(!text.is_empty() && text.lines().count() == 1, "{text}");
                }
            }
        }
    }
}

/// The studio's case: a mesh made from drawing A by `mesh_picture` (not re-meshed) laid over
/// drawing B, with one pair on the outline and one inside.
#[test]
fn a_picture_mesh_laid_over_another_drawing_keeps_its_triangles() {
    use bdmorph::inbetween::fit_drawing;
    use bdmorph::meshing::{mesh_picture, MeshOptions, PictureOptions};
    let (a, b) = figure_pair();
    let meshed = mesh_picture(
        &a,
        &PictureOptions::default(),
        &MeshOptions::default().with_vertices(800),
    )
    .unwrap();
    // The mesh in A's pixels, y up, from its texture coordinates.
    let uv = meshed.texcoords.uv.clone();
    let mut mesh = meshed.mesh.clone();
    for (p, t) in mesh.positions.iter_mut().zip(&uv) {
        *p = [t[0] * 256.0, t[1] * 256.0];
    }
    let plain = fit_drawing(&mesh, 256.0, &b, &[], &options(800)).unwrap();
    let r = &plain.report;
    assert_eq!(r.vertices, mesh.positions.len());
    assert_eq!(r.flipped, 0);
    assert!(mesh
        .faces
        .iter()
        .all(|f| signed_area(&plain.positions, f) > 0.0));
    // B's corners between the mesh's boundary vertices are cut by at most a few pixels.
    assert!(
        r.outline_error < 4.0,
        "B's outline {} px from the mesh",
        r.outline_error
    );
    assert!(r.max_distortion.is_finite());
    for (p, t) in plain.positions.iter().zip(&plain.texcoords) {
        assert!((p[0] / 256.0 - t[0]).abs() < 1e-12 && (p[1] / 256.0 - t[1]).abs() < 1e-12);
    }
    // An interior pair: the body's middle in A goes 6 px right in B.
    let inside = Match {
        a: [128.0, 150.0],
        b: [134.0, 150.0],
    };
    let paired = fit_drawing(&mesh, 256.0, &b, &[inside], &options(800)).unwrap();
    let report = &paired.report.pairs[0];
    assert!(report.met && !report.on_outline, "{report:?}");
    // The vertex used is the nearest to A's point; it lands at the same offset from B's.
    let pa = [128.0, 256.0 - 150.0];
    let v = (0..mesh.positions.len())
        .min_by(|&i, &j| {
            let d = |k: usize| {
                let q = mesh.positions[k];
                (q[0] - pa[0]).hypot(q[1] - pa[1])
            };
            d(i).total_cmp(&d(j))
        })
        .unwrap();
    let q = mesh.positions[v];
    let want = [134.0 + q[0] - pa[0], 256.0 - 150.0 + q[1] - pa[1]];
    let got = paired.positions[v];
    assert!(
        (got[0] - want[0]).hypot(got[1] - want[1]) < 1e-6,
        "{got:?} against {want:?}"
    );
    assert!((report.error - (q[0] - pa[0]).hypot(q[1] - pa[1])).abs() < 1e-9);
    // A drawing with a hole the mesh lacks: the mesh covers it (B's picture is
    // transparent there), and a note says so.
    let holed = generate::ring_picture(256, [128.0, 128.0], 90.0, [128.0, 128.0], 30.0);
    let disk = generate::picture(256, 256, |x, y| {
        generate::capsule_distance([x, y], [128.0, 128.0], [128.0, 128.0], 90.0)
    });
    let round = fit_drawing(&mesh, 256.0, &disk, &[], &options(800)).unwrap();
    assert_eq!(round.report.flipped, 0);
    let covered = fit_drawing(&mesh, 256.0, &holed, &[], &options(800)).unwrap();
    assert_eq!(covered.report.flipped, 0);
    assert!(
        covered
            .report
            .notes
            .iter()
            .any(|n| n.contains("covered by the mesh")),
        "{:?}",
        covered.report.notes
    );
    // A mesh with a hole laid over a drawing without it is refused in one line.
    let ring = compatible_mesh(&holed, &holed, &[], &options(600))
        .unwrap()
        .mesh;
    let e = fit_drawing(&ring, 256.0, &disk, &[], &options(600)).unwrap_err();
    assert!(e.to_string().contains("hole"), "{e}");
    assert!(!e.to_string().contains('\n'));
}
