//! Compatible meshes that exist are found, and drawings whose holes differ are in-betweened:
//! pictures made here (a detailed figure with an arm raised, legs that close a hole, point
//! pairs on outline corners), with what must hold of every compatible mesh.

use bdmorph::generate;
use bdmorph::inbetween::{compatible_mesh, CompatibleMesh, Inbetween, InbetweenOptions, Match};
use bdmorph::render::{raster, Background, Drawing, Image, ImageSize, Viewport};

fn options(vertices: usize) -> InbetweenOptions {
    InbetweenOptions::default().with_vertices(vertices)
}

fn signed_area(p: &[[f64; 2]], f: &[u32; 3]) -> f64 {
    let (a, b, c) = (p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]);
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
}

/// Every triangle counter-clockwise over A and over B, and the frames between flip-free.
fn check_flip_free(c: &CompatibleMesh) {
    assert_eq!(c.report.flipped, 0);
    assert!(c.mesh.faces.iter().all(|f| c.mesh.signed_area(f) > 0.0));
    assert!(c
        .mesh
        .faces
        .iter()
        .all(|f| signed_area(&c.positions_b, f) > 0.0));
    let mut inbetween =
        Inbetween::from_compatible(c.clone(), InbetweenOptions::default().morph).unwrap();
    for k in 0..=20 {
        let t = k as f64 / 20.0;
        let frame = inbetween.frame(t).unwrap();
        assert_eq!(frame.stats.flipped_triangles, 0, "t = {t}");
    }
}

/// A figure drawn with capsules, in the picture's units (x right, y up, [0, 1]²): a head
/// with ears and a tuft, a neck, a torso and hips, two legs with feet, and two arms bent at
/// the elbow with a hand of three fingers each, hanging close to the body. The figure's
/// left arm (on the picture's right) is raised by `raise` radians about its shoulder.
struct Figure {
    capsules: Vec<([f64; 2], [f64; 2], f64)>,
}

impl Figure {
    fn new(raise: f64) -> Figure {
        let mut capsules = vec![
            ([0.5, 0.84], [0.5, 0.84], 0.075),
            ([0.425, 0.84], [0.425, 0.84], 0.02),
            ([0.575, 0.84], [0.575, 0.84], 0.02),
            ([0.5, 0.91], [0.53, 0.95], 0.012),
            ([0.5, 0.77], [0.5, 0.71], 0.03),
            ([0.5, 0.66], [0.5, 0.5], 0.085),
            ([0.46, 0.44], [0.54, 0.44], 0.06),
        ];
        for side in [-1.0, 1.0] {
            let x = |u: f64| 0.5 + side * (u - 0.5);
            capsules.push(([x(0.54), 0.42], [x(0.56), 0.26], 0.04));
            capsules.push(([x(0.56), 0.26], [x(0.56), 0.1], 0.033));
            capsules.push(([x(0.56), 0.08], [x(0.62), 0.07], 0.02));
        }
        // Arms: (shoulder, upper arm and forearm angles in degrees), the picture's left one
        // first.
        for (shoulder, upper, fore, lift) in [
            ([0.41, 0.64], -105.0f64, -100.0f64, 0.0),
            ([0.59, 0.64], -75.0, -80.0, raise),
        ] {
            let at = |p: [f64; 2], angle: f64, length: f64| {
                let a = angle.to_radians() + lift;
                [p[0] + length * a.cos(), p[1] + length * a.sin()]
            };
            let elbow = at(shoulder, upper, 0.15);
            let wrist = at(elbow, fore, 0.13);
            let palm = at(wrist, fore, 0.02);
            capsules.push((shoulder, elbow, 0.028));
            capsules.push((elbow, wrist, 0.024));
            capsules.push((palm, palm, 0.022));
            for spread in [-22.0, 0.0, 22.0] {
                let base = at(palm, fore + spread, 0.015);
                capsules.push((base, at(base, fore + spread, 0.03), 0.006));
            }
        }
        Figure { capsules }
    }

    fn picture(&self, size: u32) -> Image {
        let s = f64::from(size);
        let capsules = self.capsules.clone();
        generate::picture(size, size, move |x, y| {
            let p = [x / s, 1.0 - y / s];
            s * capsules
                .iter()
                .map(|&(a, b, r)| generate::capsule_distance(p, a, b, r))
                .fold(f64::INFINITY, f64::min)
        })
    }
}

/// The unit direction from `p` to `q`.
fn along(p: [f64; 2], q: [f64; 2]) -> [f64; 2] {
    let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
    let l = dx.hypot(dy);
    [dx / l, dy / l]
}

/// The direction from `p` to `q` turned a quarter counter-clockwise: for the raised arm,
/// which goes down and right, its outer side.
fn outward(p: [f64; 2], q: [f64; 2]) -> [f64; 2] {
    let d = along(p, q);
    [-d[1], d[0]]
}

/// In pixels from the top-left corner of a `size` picture, the point of the figure's unit
/// frame `p` pushed `out` (a unit direction) by `r`.
fn pixel(size: u32, p: [f64; 2], out: [f64; 2], r: f64) -> [f64; 2] {
    let s = f64::from(size);
    [(p[0] + r * out[0]) * s, (1.0 - (p[1] + r * out[1])) * s]
}

#[test]
fn a_detailed_figure_with_one_arm_raised_35_degrees_needs_no_pairs() {
    let size = 512;
    let (fa, fb) = (Figure::new(0.0), Figure::new(35f64.to_radians()));
    let (a, b) = (fa.picture(size), fb.picture(size));
    let c = compatible_mesh(&a, &b, &[], &options(1600)).unwrap();
    assert!(
        (2500..4200).contains(&c.report.faces),
        "{} triangles",
        c.report.faces
    );
    check_flip_free(&c);
    // More vertices do not make it fail.
    let fine = compatible_mesh(&a, &b, &[], &options(3000)).unwrap();
    check_flip_free(&fine);
    // Nor do correct pairs on the raised arm: the middle fingertip, the elbow's outer side
    // and the top of the shoulder, on both outlines.
    let pair = |k: usize, out: fn([f64; 2], [f64; 2]) -> [f64; 2], r: f64| {
        let place = |f: &Figure| {
            let (p, q, _) = f.capsules[k];
            pixel(size, q, out(p, q), r)
        };
        Match {
            a: place(&fa),
            b: place(&fb),
        }
    };
    // Capsules of the raised arm: upper arm, forearm, palm, then three fingers.
    let arm = fa.capsules.len() - 6;
    let matches = [
        pair(arm + 4, along, 0.006),
        pair(arm, outward, 0.028),
        Match {
            a: pixel(size, [0.59, 0.64], [0.0, 1.0], 0.028),
            b: pixel(size, [0.59, 0.64], [0.0, 1.0], 0.028),
        },
    ];
    let paired = compatible_mesh(&a, &b, &matches, &options(1600)).unwrap();
    check_flip_free(&paired);
    for (k, p) in paired.report.pairs.iter().enumerate() {
        assert!(p.on_outline && p.met, "pair {}: {p:?}", k + 1);
    }
}

/// A body on two legs joined at the feet by a bar (a hole between the legs) when `closed`,
/// or with the legs apart and no bar (a gap open at the bottom, no hole), on a 256-pixel
/// picture.
fn legs(closed: bool) -> Image {
    generate::picture(256, 256, move |x, y| {
        let p = [x, y];
        let mut d = generate::capsule_distance(p, [128.0, 60.0], [128.0, 110.0], 45.0)
            .min(generate::capsule_distance(
                p,
                [105.0, 120.0],
                [90.0, 215.0],
                16.0,
            ))
            .min(generate::capsule_distance(
                p,
                [151.0, 120.0],
                [166.0, 215.0],
                16.0,
            ));
        if closed {
            d = d.min(generate::capsule_distance(
                p,
                [90.0, 215.0],
                [166.0, 215.0],
                14.0,
            ));
        }
        d
    })
}

/// The point between the legs, in pixels from the top-left corner.
const BETWEEN: [f64; 2] = [128.0, 185.0];

/// The mesh at `positions` drawn with `picture` through `texcoords`, on the picture's own
/// pixels.
fn draw(
    c: &CompatibleMesh,
    positions: &[[f64; 2]],
    uv: &[[[f64; 2]; 3]],
    picture: &Image,
) -> Image {
    let drawing = Drawing {
        faces: &c.mesh.faces,
        corner_uv: Some(uv),
        texture: Some(picture),
        ..Drawing::default()
    };
    let view = Viewport {
        min: [0.0, 0.0],
        max: [256.0, 256.0],
    };
    let size = ImageSize {
        width: 256,
        height: 256,
    };
    raster::render_on(positions, &drawing, &view, size, Background::Transparent)
        .expect("within the picture budget")
}

/// Whether a triangle of the layout `positions` holds the point `p` (pixels, y up).
fn covered(c: &CompatibleMesh, positions: &[[f64; 2]], p: [f64; 2]) -> bool {
    c.mesh.faces.iter().any(|f| {
        let [a, b, q] = f.map(|v| positions[v as usize]);
        let side = |u: [f64; 2], w: [f64; 2]| {
            (w[0] - u[0]) * (p[1] - u[1]) - (w[1] - u[1]) * (p[0] - u[0])
        };
        side(a, b) >= 0.0 && side(b, q) >= 0.0 && side(q, a) >= 0.0
    })
}

fn alpha_at(image: &Image, p: [f64; 2]) -> u8 {
    image.rgba[4 * (p[1] as usize * image.width as usize + p[0] as usize) + 3]
}

#[test]
fn a_hole_in_one_drawing_only_is_a_transparent_region_of_the_other() {
    let (closed, open) = (legs(true), legs(false));
    let up = [BETWEEN[0], 256.0 - BETWEEN[1]];
    // A has the hole, B does not.
    let c = compatible_mesh(&closed, &open, &[], &options(900)).unwrap();
    check_flip_free(&c);
    let notes = c.report.notes.join("; ");
    assert!(notes.contains("transparent region"), "{notes}");
    // At t = 0 the mesh covers the hole and draws it transparent.
    assert!(covered(&c, &c.mesh.positions, up));
    let start = draw(&c, &c.mesh.positions, &c.texcoords_a.corner_uv(), &closed);
    assert_eq!(alpha_at(&start, BETWEEN), 0);
    // The region shrinks over B: the triangles inside the hole in A take less than half
    // their area there.
    let hole: Vec<&[u32; 3]> = c
        .mesh
        .faces
        .iter()
        .filter(|f| {
            let [p, q, r] = f.map(|v| c.mesh.positions[v as usize]);
            let m = [(p[0] + q[0] + r[0]) / 3.0, (p[1] + q[1] + r[1]) / 3.0];
            (m[0] - up[0]).abs() < 10.0 && (m[1] - up[1]).abs() < 10.0
        })
        .collect();
    assert!(!hole.is_empty());
    let area = |p: &[[f64; 2]]| hole.iter().map(|f| signed_area(p, f)).sum::<f64>();
    let (in_a, in_b) = (area(&c.mesh.positions), area(&c.positions_b));
    assert!(
        in_b < 0.5 * in_a,
        "the hole's triangles: {in_a} px² in A, {in_b} in B"
    );

    // B has the hole, A does not: the mesh covers it over B, transparent at t = 1.
    let d = compatible_mesh(&open, &closed, &[], &options(900)).unwrap();
    check_flip_free(&d);
    let notes = d.report.notes.join("; ");
    assert!(notes.contains("covered by the mesh"), "{notes}");
    assert!(covered(&d, &d.positions_b, up));
    let end = draw(&d, &d.positions_b, &d.texcoords_b.corner_uv(), &closed);
    assert_eq!(alpha_at(&end, BETWEEN), 0);
}

#[test]
fn pinholes_are_filled_and_said() {
    // A disk with a hole 8 pixels across, and the same disk moved.
    let a = generate::ring_picture(200, [100.0, 100.0], 70.0, [90.0, 110.0], 4.0);
    let b = generate::picture(200, 200, |x, y| {
        generate::capsule_distance([x, y], [105.0, 95.0], [105.0, 95.0], 70.0)
    });
    let c = compatible_mesh(&a, &b, &[], &options(500)).unwrap();
    check_flip_free(&c);
    assert!(
        c.report
            .notes
            .iter()
            .any(|n| n.contains("1 pinhole in drawing A filled")),
        "{:?}",
        c.report.notes
    );
    // Under a smaller pinhole area, the hole is a transparent region instead.
    let kept = compatible_mesh(&a, &b, &[], &options(500).with_pinhole(1.0)).unwrap();
    check_flip_free(&kept);
    assert!(
        kept.report
            .notes
            .iter()
            .any(|n| n.contains("transparent region")),
        "{:?}",
        kept.report.notes
    );
}

#[test]
fn pairs_on_outline_corners_are_met() {
    // A square and the same square turned: the pairs' points project onto the outline's
    // corners (clicked just outside them), where a corner of the outline already is.
    let square = |turn: f64| {
        let (s, c) = turn.sin_cos();
        generate::picture(200, 200, move |x, y| {
            let (u, v) = (x - 100.0, y - 100.0);
            let (u, v) = (c * u + s * v, -s * u + c * v);
            u.abs().max(v.abs()) - 60.0
        })
    };
    let (a, b) = (square(0.0), square(0.3));
    let corner_b = |u: f64, v: f64| {
        let (s, c) = 0.3f64.sin_cos();
        [100.0 + c * u - s * v, 100.0 + s * u + c * v]
    };
    let matches = [
        Match {
            a: [39.0, 39.0],
            b: corner_b(-61.0, -61.0),
        },
        Match {
            a: [161.0, 161.0],
            b: corner_b(61.0, 61.0),
        },
    ];
    for vertices in [300, 700] {
        let c = compatible_mesh(&a, &b, &matches, &options(vertices)).unwrap();
        check_flip_free(&c);
        assert!(c.report.pairs.iter().all(|p| p.met), "{:?}", c.report.pairs);
    }
}

mod fuzz {
    //! Drawings of random capsules with random point pairs on their outlines (corners and
    //! ends of capsules included) at random mesh sizes: a flip-free compatible mesh, or a
    //! one-line error that is not an internal one.

    use super::*;
    use bdmorph::inbetween::InbetweenError;
    use proptest::prelude::*;

    type Capsule = ([f64; 4], f64);

    fn blobs(size: u32, capsules: Vec<Capsule>) -> Image {
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

    fn capsule() -> impl Strategy<Value = Capsule> {
        (
            [0.2..0.8f64, 0.2..0.8f64, 0.2..0.8f64, 0.2..0.8f64],
            0.03..0.2f64,
        )
    }

    /// A point on capsule `k`'s outline (at its first end, in direction `angle`), in pixels.
    fn on(capsules: &[Capsule], size: f64, k: usize, angle: f64) -> [f64; 2] {
        let ([ax, ay, _, _], r) = capsules[k % capsules.len()];
        [
            (ax + r * angle.cos()) * size + 0.3,
            (ay + r * angle.sin()) * size,
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]
        #[test]
        fn pairs_on_outlines_give_a_mesh_or_one_line(
            a in proptest::collection::vec(capsule(), 1..4),
            b in proptest::collection::vec(capsule(), 1..4),
            picks in proptest::collection::vec((0..4usize, 0.0..6.3f64, 0.0..6.3f64), 0..4),
            vertices in 100..2500usize,
        ) {
            let size = 160.0;
            let matches: Vec<Match> = picks
                .iter()
                .map(|&(k, ta, tb)| Match { a: on(&a, size, k, ta), b: on(&b, size, k, tb) })
                .collect();
            let (pa, pb) = (blobs(160, a), blobs(160, b));
            match compatible_mesh(&pa, &pb, &matches, &options(vertices)) {
                Ok(c) => {
                    prop_assert_eq!(c.report.flipped, 0);
                    prop_assert!(c.mesh.faces.iter().all(|f| c.mesh.signed_area(f) > 0.0));
                    prop_assert!(c.mesh.faces.iter().all(|f| signed_area(&c.positions_b, f) > 0.0));
                }
                Err(e) => {
                    let text = e.to_string();
                    prop_assert!(!matches!(e, InbetweenError::Internal(_)), "{}", text);
                    prop_assert!(text.lines().count() == 1, "{}", text);
                    prop_assert!(!text.contains("zero length") && !text.contains("degenerate"), "{}", text);
                }
            }
        }
    }
}
