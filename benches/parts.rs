//! A character in parts against the same number of vertices as one mesh: a frame of a 12-part
//! character of about 20K vertices in all (each part's BDMORPH frame, then the pieces placed
//! so that their joints meet) against a frame of one disk of about 20K vertices morphing
//! between two poses, in the same run. Also the placement alone (what parts add per frame).
//!
//! `cargo bench --bench parts`

use criterion::{criterion_group, criterion_main, Criterion};

use bdmorph::deform::PoseMethod;
use bdmorph::parts::{character, CharacterOptions, JointedDeformer, Layer, Layered, Placement};
use bdmorph::render::Image;
use bdmorph::{generate, KeyframePath, PlanarMesh};

/// A layer of a filled rectangle `[x0, y0, x1, y1]` (canvas pixels, rows from the top).
fn rect(name: &str, b: [i64; 4]) -> Layer {
    let (w, h) = ((b[2] - b[0]) as u32, (b[3] - b[1]) as u32);
    Layer {
        name: name.into(),
        image: Image {
            width: w,
            height: h,
            rgba: vec![200; (w * h * 4) as usize],
        },
        left: b[0],
        top: b[1],
    }
}

/// Twelve overlapping parts: torso, head, and two arms (upper, fore, hand) and two legs
/// (thigh, shin) each.
fn figure() -> Layered {
    let layers = vec![
        rect("torso", [300, 200, 500, 560]),
        rect("head", [340, 40, 460, 215]),
        rect("upper_l", [160, 210, 315, 260]),
        rect("fore_l", [40, 215, 175, 255]),
        rect("hand_l", [0, 205, 55, 265]),
        rect("upper_r", [485, 210, 640, 260]),
        rect("fore_r", [625, 215, 760, 255]),
        rect("hand_r", [745, 205, 800, 265]),
        rect("thigh_l", [310, 545, 380, 760]),
        rect("shin_l", [315, 745, 375, 980]),
        rect("thigh_r", [420, 545, 490, 760]),
        rect("shin_r", [425, 745, 485, 980]),
    ];
    Layered {
        width: 800,
        height: 1000,
        layers,
        notes: vec![],
    }
}

/// The character's rest mesh and a pose (hands and feet moved, the torso pinned; bounded
/// distortion, so that no triangle flips), its joints.
fn posed_character() -> (PlanarMesh, PlanarMesh, Vec<[u32; 2]>) {
    let c = character(
        &figure(),
        &CharacterOptions::default().with_vertices(20_000),
    )
    .expect("character");
    let joints: Vec<[u32; 2]> = c.joints.iter().map(|j| j.vertices).collect();
    let rest = c.mesh.clone();
    let extreme = |name: &str, key: &dyn Fn([f64; 2]) -> f64| {
        let p = c.parts.iter().find(|p| p.name == name).expect("part");
        (p.vertices[0]..p.vertices[1])
            .min_by(|&a, &b| {
                key(rest.positions[a as usize]).total_cmp(&key(rest.positions[b as usize]))
            })
            .expect("vertices")
    };
    let pins = [
        extreme("torso", &|p| p[1] - p[0]),
        extreme("torso", &|p| p[1] + p[0]),
        extreme("hand_l", &|p| p[0]),
        extreme("hand_r", &|p| -p[0]),
        extreme("shin_l", &|p| p[1]),
        extreme("shin_r", &|p| p[1]),
    ];
    let mut pose =
        JointedDeformer::new(&rest, &joints, PoseMethod::bounded(5.0)).expect("deformer");
    pose.set_pins(&pins).expect("pins");
    let at = |v: u32| rest.positions[v as usize];
    for k in 1..=6 {
        let s = f64::from(k) / 6.0;
        let targets = [
            at(pins[0]),
            at(pins[1]),
            [at(pins[2])[0] + 80.0 * s, at(pins[2])[1] + 160.0 * s],
            [at(pins[3])[0] - 40.0 * s, at(pins[3])[1] - 120.0 * s],
            [at(pins[4])[0] - 90.0 * s, at(pins[4])[1] + 70.0 * s],
            [at(pins[5])[0] + 30.0 * s, at(pins[5])[1] + 40.0 * s],
        ];
        pose.drag(&targets).expect("drag");
    }
    let posed = PlanarMesh {
        positions: pose.positions().to_vec(),
        faces: rest.faces.clone(),
    };
    (rest, posed, joints)
}

/// One disk of about `n` vertices and the same disk bent.
fn one_mesh(n: usize) -> (PlanarMesh, PlanarMesh) {
    let rest = generate::disk(generate::rings_for(n), 0.2);
    let bent = PlanarMesh {
        positions: rest
            .positions
            .iter()
            .map(|&[x, y]| {
                let a = 0.6 * x;
                let r = 2.0 - y;
                [r * a.sin(), 2.0 - r * a.cos()]
            })
            .collect(),
        faces: rest.faces.clone(),
    };
    (rest, bent)
}

fn frames(c: &mut Criterion) {
    let (rest, posed, joints) = posed_character();
    let n = rest.positions.len();
    let mut path = KeyframePath::new(&[rest.clone(), posed]).expect("path");
    let mut placement = Placement::new(&rest, &joints);
    let mut frame = vec![[0.0; 2]; n];
    let (one_rest, one_bent) = one_mesh(n);
    let mut one = KeyframePath::new(&[one_rest.clone(), one_bent]).expect("path");
    let mut one_frame = vec![[0.0; 2]; one_rest.positions.len()];
    let mut g = c.benchmark_group(format!(
        "parts_frame/{n}v_12parts_vs_{}v_one_mesh",
        one_rest.positions.len()
    ));
    let mut t = 0.0;
    let mut next = || {
        t = (t + 0.137) % 1.0;
        t
    };
    g.bench_function("character_12_parts", |b| {
        b.iter(|| {
            path.frame_into(next(), &mut frame).expect("frame");
            placement.apply(&mut frame)
        })
    });
    g.bench_function("one_mesh", |b| {
        b.iter(|| one.frame_into(next(), &mut one_frame).expect("frame"))
    });
    path.frame_into(0.5, &mut frame).expect("frame");
    g.bench_function("placement_alone", |b| {
        b.iter(|| placement.apply(&mut frame))
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = frames
}
criterion_main!(benches);
