//! The command line on layered pictures made in code: `mesh` to a project and to OBJ, refusals,
//! and `render` of a posed character whose parts draw in their order.

mod layered;

use std::path::{Path, PathBuf};
use std::process::Command;

use bdmorph::render::raster;
use bdmorph::studio::project::{Keyframe, Project};
use layered::{figure, write_ora, write_psd, write_psd_with, COLOURS};

fn bdmorph() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bdmorph"))
}

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-parts-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// Runs bdmorph in `dir`; (success, stderr).
fn run(dir: &Path, args: &[&str]) -> (bool, String) {
    let out = bdmorph()
        .current_dir(dir)
        .args(args)
        .output()
        .expect("runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn ok(dir: &Path, args: &[&str]) -> String {
    let (success, stderr) = run(dir, args);
    assert!(success, "{args:?}: {stderr}");
    stderr
}

#[test]
fn mesh_makes_a_project_of_parts_and_an_obj_of_groups() {
    let dir = scratch("mesh");
    std::fs::write(dir.join("figure.psd"), write_psd(&figure())).expect("psd");
    std::fs::write(dir.join("figure.ora"), write_ora(&figure(), 0)).expect("ora");
    let said = ok(&dir, &["mesh", "figure.psd", "-o", "figure.json"]);
    assert!(said.contains("6 parts, 5 joints"), "{said}");
    let doc = Project::read(&dir.join("figure.json")).expect("project");
    let names: Vec<&str> = doc
        .parts
        .as_ref()
        .expect("parts")
        .iter()
        .map(|p| p.name.as_str())
        .collect();
    assert_eq!(names, COLOURS.map(|c| c.0));
    assert_eq!(doc.joints.as_ref().map(Vec::len), Some(5));
    assert_eq!(doc.texture.as_deref(), Some("figure.psd"));

    ok(
        &dir,
        &[
            "mesh",
            "figure.ora",
            "-o",
            "figure.obj",
            "--vertices",
            "800",
        ],
    );
    let obj = std::fs::read_to_string(dir.join("figure.obj")).expect("obj");
    assert_eq!(obj.lines().filter(|l| l.starts_with("g ")).count(), 6);
    assert!(obj.contains("mtllib figure.mtl"));
    let mtl = std::fs::read_to_string(dir.join("figure.mtl")).expect("mtl");
    assert_eq!(mtl.matches("newmtl ").count(), 6);
    assert!(mtl.contains("map_Kd figure.png"));
    let atlas = raster::read_image(dir.join("figure.png")).expect("atlas");
    assert!(atlas.width > 50 && atlas.height > 50);
    // Other programs read the OBJ: tobj finds the six groups with their materials.
    let (models, materials) =
        tobj::load_obj(dir.join("figure.obj"), &tobj::LoadOptions::default()).expect("tobj");
    assert_eq!(models.len(), 6);
    assert_eq!(materials.expect("mtl").len(), 6);
}

#[test]
fn unreadable_layered_pictures_are_one_line_and_write_nothing() {
    let dir = scratch("refuse");
    let mut hidden = figure();
    hidden.iter_mut().for_each(|l| l.hidden = true);
    let cases: [(&str, Vec<u8>, &str); 4] = [
        ("cmyk.psd", write_psd_with(&figure(), 4, 8), "CMYK"),
        ("lab.psd", write_psd_with(&figure(), 9, 8), "Lab colour"),
        ("hidden.ora", write_ora(&hidden, 0), "no visible layer"),
        ("cut.psd", write_psd(&figure())[..400].to_vec(), "damaged"),
    ];
    for (name, bytes, says) in cases {
        std::fs::write(dir.join(name), bytes).expect("write");
        let (success, stderr) = run(&dir, &["mesh", name, "-o", "out.json"]);
        assert!(!success, "{name}");
        assert!(stderr.contains(says), "{name}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{name}: {stderr}");
        assert!(
            !dir.join("out.json").exists(),
            "{name}: something was written"
        );
    }
}

/// Pixels of `rgb` in a PNG.
fn count(path: &Path, rgb: [u8; 3]) -> usize {
    let img = raster::read_image(path).expect("png");
    img.rgba
        .chunks_exact(4)
        .filter(|p| p[3] > 200 && p[..3].iter().zip(rgb).all(|(&a, b)| a.abs_diff(b) < 30))
        .count()
}

#[test]
fn render_draws_a_posed_character_with_its_parts_in_order() {
    let dir = scratch("render");
    std::fs::write(dir.join("figure.ora"), write_ora(&figure(), 0)).expect("ora");
    ok(
        &dir,
        &[
            "mesh",
            "figure.ora",
            "-o",
            "figure.json",
            "--vertices",
            "1200",
        ],
    );
    let mut doc = Project::read(&dir.join("figure.json")).expect("project");
    let parts = doc.parts.clone().expect("parts");
    let joints = doc.joints.clone().expect("joints");
    // Keyframe 2: the left arm swung down across the torso, turned rigidly about the shoulder.
    let part = |name: &str| parts.iter().find(|p| p.name == name).expect("part");
    let (torso, upper) = (part("torso"), part("upper_arm_l"));
    let shoulder = joints
        .iter()
        .find(|[a, b]| {
            let inside = |p: &bdmorph::studio::project::PartData, v: u32| {
                (p.vertices[0]..p.vertices[1]).contains(&v)
            };
            (inside(torso, *a) && inside(upper, *b)) || (inside(torso, *b) && inside(upper, *a))
        })
        .map(|[a, _]| doc.mesh.positions[*a as usize])
        .expect("shoulder joint");
    let (s, c) = (150f64.to_radians().sin(), 150f64.to_radians().cos());
    let mut swung = doc.mesh.positions.clone();
    for name in ["upper_arm_l", "forearm_l"] {
        let p = part(name);
        for v in p.vertices[0]..p.vertices[1] {
            let [x, y] = swung[v as usize];
            let (dx, dy) = (x - shoulder[0], y - shoulder[1]);
            swung[v as usize] = [shoulder[0] + c * dx - s * dy, shoulder[1] + s * dx + c * dy];
        }
    }
    doc.keyframes.push(Keyframe {
        time: 1.0,
        easing: "linear".into(),
        positions: swung,
        pins: vec![],
        drawing: None,
    });
    doc.fps = 10.0;
    doc.write(&dir.join("figure.json")).expect("saved");

    ok(
        &dir,
        &[
            "render",
            "figure.json",
            "-o",
            "frames",
            "--background",
            "transparent",
        ],
    );
    let last = dir.join("frames").join("frame_0010.png");
    let red_in_front = count(&last, COLOURS[3].1);
    let blue_behind = count(&last, COLOURS[0].1);
    assert!(red_in_front > 200, "forearm pixels {red_in_front}");
    // The same frame with the torso painted in front of every other part.
    let mut front = doc.clone();
    let mut depth = vec![0i8; front.mesh.faces.len()];
    depth[torso.faces[0] as usize..torso.faces[1] as usize].fill(1);
    front.depth = Some(depth);
    front.write(&dir.join("front.json")).expect("saved");
    ok(
        &dir,
        &[
            "render",
            "front.json",
            "-o",
            "front",
            "--background",
            "transparent",
        ],
    );
    let covered = dir.join("front").join("frame_0010.png");
    let red_behind = count(&covered, COLOURS[3].1);
    let blue_front = count(&covered, COLOURS[0].1);
    assert!(
        red_behind + 100 < red_in_front,
        "forearm {red_in_front} -> {red_behind}"
    );
    assert!(
        blue_front > blue_behind + 100,
        "torso {blue_behind} -> {blue_front}"
    );

    // `render` is `export`: the same bytes.
    ok(
        &dir,
        &[
            "render",
            "figure.json",
            "-o",
            "a.apng",
            "--background",
            "transparent",
        ],
    );
    ok(
        &dir,
        &[
            "export",
            "figure.json",
            "-o",
            "b.apng",
            "--background",
            "transparent",
        ],
    );
    assert_eq!(
        std::fs::read(dir.join("a.apng")).expect("a"),
        std::fs::read(dir.join("b.apng")).expect("b")
    );
}
