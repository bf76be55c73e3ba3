//! Where frames go: the anchor (a vertex and an edge) against the fit to the keyframes.

use bdmorph::{generate, KeyframePath, Morph, MorphOptions, PathOptions, Placement};

fn size(p: &[[f64; 2]]) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for q in p {
        for d in 0..2 {
            lo[d] = lo[d].min(q[d]);
            hi[d] = hi[d].max(q[d]);
        }
    }
    (hi[0] - lo[0]).hypot(hi[1] - lo[1])
}

/// The largest and the median distance between `a` and `b` over the vertices `which`.
fn drift(a: &[[f64; 2]], b: &[[f64; 2]], which: &[usize]) -> (f64, f64) {
    let mut d: Vec<f64> = which
        .iter()
        .map(|&v| (a[v][0] - b[v][0]).hypot(a[v][1] - b[v][1]))
        .collect();
    d.sort_by(f64::total_cmp);
    (d[d.len() - 1], d[d.len() / 2])
}

/// [`generate::figure`] leaning: everything above the hips turned by `angle` about the
/// middle of the hips, blended in smoothly from `y = -0.3` to `y = 0.4`; the legs stay.
fn lean(mesh: &bdmorph::PlanarMesh, angle: f64) -> bdmorph::PlanarMesh {
    let pivot = [0.0, -0.3];
    bdmorph::PlanarMesh {
        positions: mesh
            .positions
            .iter()
            .map(|p| {
                let s = ((p[1] + 0.3) / 0.7).clamp(0.0, 1.0);
                let a = angle * s * s * (3.0 - 2.0 * s);
                let (x, y) = (p[0] - pivot[0], p[1] - pivot[1]);
                let (sn, c) = a.sin_cos();
                [pivot[0] + c * x - sn * y, pivot[1] + sn * x + c * y]
            })
            .collect(),
        faces: mesh.faces.clone(),
    }
}

#[test]
fn legs_that_hold_still_while_the_body_leans_hold_still_in_between() {
    // The figure leans from the hips: the legs stand still while the body (where the
    // anchor, the vertex nearest the middle, is) turns above them.
    let rest = generate::figure(0.005);
    let raised = lean(&rest, 0.6);
    // The vertices the pose does not move: the legs.
    let still: Vec<usize> = (0..rest.positions.len())
        .filter(|&v| rest.positions[v] == raised.positions[v])
        .collect();
    assert!(still.len() >= 50, "{}", still.len());
    let s = size(&rest.positions);
    let mut worst = [0.0f64; 2];
    for (i, placement) in [Placement::Anchor, Placement::Fit].into_iter().enumerate() {
        let options = MorphOptions::default().with_placement(placement);
        let mut morph = Morph::new(&rest, &raised, options).expect("morphs");
        for t in [0.0, 1.0] {
            let f = morph.frame(t).expect("frame");
            let key = if t == 0.0 { &rest } else { &raised };
            let (miss, _) = drift(
                f.positions,
                &key.positions,
                &(0..key.positions.len()).collect::<Vec<_>>(),
            );
            assert!(
                miss < 1e-9 * s,
                "{placement}: t = {t} misses the keyframe by {miss:e}"
            );
        }
        for k in 1..10 {
            let t = f64::from(k) / 10.0;
            let f = morph.frame(t).expect("frame");
            assert_eq!(f.stats.flipped_triangles, 0);
            let (max, _) = drift(f.positions, &rest.positions, &still);
            worst[i] = worst[i].max(max / s);
        }
    }
    eprintln!(
        "still part's largest drift over the figure's size: anchor {:.2e}, fit {:.2e}",
        worst[0], worst[1]
    );
    // The fit holds the legs where they stand, the anchor lets them slide.
    assert!(worst[1] < 0.3 * worst[0], "{worst:?}");
    assert!(worst[1] < 1e-2, "{worst:?}");
}

#[test]
fn fit_placement_reaches_every_keyframe_of_a_path_and_is_continuous() {
    let rest = generate::figure(0.01);
    let keys = [
        rest.clone(),
        generate::raise_arm(&rest, 1.0),
        generate::wave(&rest, 1.0),
        generate::raise_arm(&rest, -0.4),
    ];
    let options =
        PathOptions::default().with_morph(MorphOptions::default().with_placement(Placement::Fit));
    let mut path = KeyframePath::with_options(&keys, options).expect("path");
    let s = size(&rest.positions);
    let all: Vec<usize> = (0..rest.positions.len()).collect();
    for (k, &t) in path.keyframe_times().to_vec().iter().enumerate() {
        let f = path.frame(t).expect("frame");
        let (miss, _) = drift(f.positions, &keys[k].positions, &all);
        assert!(miss < 1e-9 * s, "keyframe {k}: {miss:e}");
    }
    // Continuous: fine steps move every vertex a little.
    let mut previous = path.frame(0.0).expect("frame").positions.to_vec();
    for i in 1..=600 {
        let f = path.frame(f64::from(i) / 600.0).expect("frame");
        let (step, _) = drift(f.positions, &previous, &all);
        assert!(step < 0.02 * s, "step {i}: {step}");
        previous = f.positions.to_vec();
    }
}
