//! Characters in parts from layered pictures made in code: the readers (OpenRaster, PSD),
//! parts, order and textures as in the file, joints where layers overlap, posing through the
//! joints, and morphs whose tree of joints stays together.

mod layered;

use bdmorph::deform::{Deformer, PoseMethod};
use bdmorph::distortion::RestShape;
use bdmorph::parts::{
    character, read_layered, Character, CharacterOptions, LayersError, Placement, Weld,
};
use bdmorph::{Morph, MorphOptions, PlanarMesh};
use layered::{figure, write_ora, write_psd, write_psd_with, COLOURS, FIGURE_SIZE};

fn names(c: &Character) -> Vec<&str> {
    c.parts.iter().map(|p| p.name.as_str()).collect()
}

fn build(bytes: &[u8]) -> Character {
    let layered = read_layered(bytes).expect("reads");
    character(&layered, &CharacterOptions::default().with_vertices(1500)).expect("character")
}

/// The part whose name ends with `name`.
fn part(c: &Character, name: &str) -> usize {
    c.parts
        .iter()
        .position(|p| p.name.ends_with(name))
        .unwrap_or_else(|| panic!("no part {name}"))
}

#[test]
fn both_formats_give_the_parts_in_the_files_order_with_their_own_pixels() {
    let (w, h) = FIGURE_SIZE;
    for (format, bytes) in [
        ("ORA", write_ora(&figure(), 0)),
        ("PSD", write_psd(&figure())),
    ] {
        let layered = read_layered(&bytes).unwrap_or_else(|e| panic!("{format}: {e}"));
        assert_eq!((layered.width, layered.height), (w, h), "{format}");
        let got: Vec<&str> = layered.layers.iter().map(|l| l.name.as_str()).collect();
        let want: Vec<&str> = COLOURS.iter().map(|c| c.0).collect();
        assert_eq!(got, want, "{format}: order");
        for (layer, (_, colour)) in layered.layers.iter().zip(COLOURS) {
            // Every opaque pixel of the crop is the layer's own colour.
            let opaque: Vec<&[u8]> = layer
                .image
                .rgba
                .chunks_exact(4)
                .filter(|p| p[3] == 255)
                .collect();
            assert!(opaque.len() > 300, "{format} {}", layer.name);
            assert!(
                opaque.iter().all(|p| p[..3] == colour),
                "{format} {}",
                layer.name
            );
        }
        // The torso's crop sits where it was drawn (columns 125..175, rows 60..180).
        let torso = &layered.layers[0];
        assert_eq!((torso.left, torso.top), (125, 60), "{format}");
        assert_eq!(
            (torso.image.width, torso.image.height),
            (50, 120),
            "{format}"
        );
        let c = character(&layered, &CharacterOptions::default().with_vertices(1500))
            .expect("character");
        assert_eq!(names(&c), want, "{format}");
        // Texture: each part's triangles sample their own colour from the atlas.
        for p in &c.parts {
            let colour = COLOURS
                .iter()
                .find(|x| x.0 == p.name)
                .map(|x| x.1)
                .expect("colour");
            let mut right = 0;
            let faces = &c.mesh.faces[p.faces[0] as usize..p.faces[1] as usize];
            for f in faces {
                let uv = f.map(|v| c.texcoords[v as usize]);
                let (u, v) = (
                    (uv[0][0] + uv[1][0] + uv[2][0]) / 3.0,
                    (uv[0][1] + uv[1][1] + uv[2][1]) / 3.0,
                );
                let (x, y) = (
                    (u * f64::from(c.atlas.width)) as usize,
                    ((1.0 - v) * f64::from(c.atlas.height)) as usize,
                );
                let at = (y * c.atlas.width as usize + x) * 4;
                if c.atlas.rgba[at..at + 3] == colour && c.atlas.rgba[at + 3] == 255 {
                    right += 1;
                }
            }
            assert!(
                right * 100 >= faces.len() * 95,
                "{format} {}: {right} of {}",
                p.name,
                faces.len()
            );
        }
    }
}

#[test]
fn joints_are_found_where_the_layers_overlap_and_nowhere_else() {
    let c = build(&write_ora(&figure(), 0));
    let mut pairs: Vec<[&str; 2]> = c
        .joints
        .iter()
        .map(|j| {
            let mut p = [
                c.parts[j.parts[0]].name.as_str(),
                c.parts[j.parts[1]].name.as_str(),
            ];
            p.sort();
            p
        })
        .collect();
    pairs.sort();
    assert_eq!(
        pairs,
        vec![
            ["forearm_l", "upper_arm_l"],
            ["forearm_r", "upper_arm_r"],
            ["head", "torso"],
            ["torso", "upper_arm_l"],
            ["torso", "upper_arm_r"],
        ]
    );
    let h = f64::from(FIGURE_SIZE.1);
    for j in &c.joints {
        let [a, b] = j.vertices.map(|v| c.mesh.positions[v as usize]);
        assert_eq!(a, b, "a joint's vertices coincide on the rest shape");
        // Each joint lies in both parts' pixels: inside the overlap.
        let (x, y) = (a[0], h - a[1]);
        let in_part = |name: &str| {
            let l = figure()
                .into_iter()
                .find(|l| l.name == name)
                .expect("layer");
            l.rgba[((y as usize) * FIGURE_SIZE.0 as usize + x as usize) * 4 + 3] == 255
        };
        assert!(in_part(&c.parts[j.parts[0]].name) && in_part(&c.parts[j.parts[1]].name));
    }
    // The rest mesh is valid: every triangle counter-clockwise, none degenerate.
    c.mesh.validate().expect("valid");
    // Without joints asked, none.
    let layered = read_layered(&write_ora(&figure(), 0)).expect("reads");
    let none = character(&layered, &CharacterOptions::default().with_joints(false)).expect("c");
    assert!(none.joints.is_empty());
}

#[test]
fn hidden_layers_and_groups_are_left_out_with_a_note() {
    let mut layers = figure();
    layers[5].hidden = true;
    for (format, bytes) in [("ORA", write_ora(&layers, 0)), ("PSD", write_psd(&layers))] {
        let l = read_layered(&bytes).unwrap_or_else(|e| panic!("{format}: {e}"));
        assert_eq!(l.layers.len(), 5, "{format}");
        assert!(
            l.notes
                .iter()
                .any(|n| n.contains("forearm_r") && n.contains("hidden")),
            "{format}: {:?}",
            l.notes
        );
    }
    // A group in OpenRaster: its layers are named under it and flattened in order.
    let l = read_layered(&write_ora(&figure(), 2)).expect("grouped");
    assert_eq!(l.layers.len(), 6);
    assert_eq!(l.layers[5].name, "arms/forearm_r");
    assert_eq!(l.layers[4].name, "arms/upper_arm_r");
}

#[test]
fn damaged_unsupported_and_empty_files_are_one_clear_line_each() {
    let psd = write_psd(&figure());
    type Expected = fn(&LayersError) -> bool;
    let cases: Vec<(&str, Vec<u8>, Expected)> = vec![
        ("cmyk", write_psd_with(&figure(), 4, 8), |e| {
            matches!(e, LayersError::Unsupported { .. })
        }),
        ("1-bit RGB", write_psd_with(&figure(), 3, 1), |e| {
            matches!(e, LayersError::Unsupported { .. })
        }),
        ("not layered", b"hello".to_vec(), |e| {
            matches!(e, LayersError::UnknownFormat)
        }),
        (
            "all hidden",
            {
                let mut l = figure();
                l.iter_mut().for_each(|l| l.hidden = true);
                write_ora(&l, 0)
            },
            |e| matches!(e, LayersError::Empty { hidden: 6 }),
        ),
        (
            "zip, not ORA",
            {
                let mut z = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
                z.start_file("a.txt", zip::write::SimpleFileOptions::default())
                    .expect("zip");
                z.finish().expect("zip").into_inner()
            },
            |e| matches!(e, LayersError::Damaged { .. }),
        ),
    ];
    for (what, bytes, expected) in cases {
        let e = read_layered(&bytes).expect_err(what);
        assert!(expected(&e), "{what}: {e:?}");
        assert!(!e.to_string().contains('\n'), "{what}: {e}");
    }
    // Cut short anywhere: an error, never a panic.
    for format in [psd, write_ora(&figure(), 0)] {
        for cut in (0..format.len()).step_by(format.len() / 97 + 1) {
            if let Err(e) = read_layered(&format[..cut]) {
                assert!(!e.to_string().contains('\n'), "{e}");
            }
        }
    }
}

/// The figure's hand (the left forearm's leftmost vertex).
fn hand(c: &Character) -> u32 {
    let p = &c.parts[part(c, "forearm_l")];
    (p.vertices[0]..p.vertices[1])
        .min_by(|&a, &b| {
            c.mesh.positions[a as usize][0].total_cmp(&c.mesh.positions[b as usize][0])
        })
        .expect("vertices")
}

/// The figure posed by its hand: the torso's bottom corners pinned, the hand raised.
fn posed(c: &Character, method: PoseMethod) -> Vec<[f64; 2]> {
    let weld = Weld::new(
        &c.mesh,
        &c.joints.iter().map(|j| j.vertices).collect::<Vec<_>>(),
    );
    let torso = &c.parts[part(c, "torso")];
    let corner = |sign: f64| {
        (torso.vertices[0]..torso.vertices[1])
            .min_by(|&a, &b| {
                let k = |v: u32| {
                    let p = c.mesh.positions[v as usize];
                    p[1] - sign * p[0]
                };
                k(a).total_cmp(&k(b))
            })
            .expect("torso")
    };
    let pins = [corner(1.0), corner(-1.0), hand(c)];
    let mut pose = Deformer::new(&weld.mesh, method.clone()).expect("deformer");
    pose.set_pins(&pins.map(|v| weld.of[v as usize]))
        .expect("pins");
    let at = |v: u32| c.mesh.positions[v as usize];
    let h = at(pins[2]);
    // Raised in steps, as a drag does.
    for k in 1..=8 {
        let lift = 7.0 * f64::from(k);
        pose.drag(&[at(pins[0]), at(pins[1]), [h[0] + lift * 0.6, h[1] + lift]])
            .expect("drag");
    }
    let mut out = vec![[0.0; 2]; c.mesh.positions.len()];
    weld.scatter(pose.positions(), &mut out);
    out
}

#[test]
fn posing_the_hand_moves_the_whole_arm_and_nothing_tears() {
    let c = build(&write_psd(&figure()));
    let size = c.mesh.diameter();
    for method in [
        PoseMethod::arap(),
        PoseMethod::kvf(),
        PoseMethod::bounded(4.0),
    ] {
        let pose = posed(&c, method.clone());
        for j in &c.joints {
            let [a, b] = j.vertices.map(|v| pose[v as usize]);
            let gap = (a[0] - b[0]).hypot(a[1] - b[1]);
            assert!(gap <= 1e-9 * size, "{}: joint gap {gap}", method.name());
        }
        let moved = |name: &str| {
            let p = &c.parts[part(&c, name)];
            (p.vertices[0]..p.vertices[1])
                .map(|v| {
                    let (a, b) = (c.mesh.positions[v as usize], pose[v as usize]);
                    (a[0] - b[0]).hypot(a[1] - b[1])
                })
                .fold(0.0, f64::max)
        };
        // The forearm and the upper arm follow the hand; the far arm hardly moves.
        assert!(moved("forearm_l") > 30.0, "{}", method.name());
        assert!(
            moved("upper_arm_l") > 5.0,
            "{}: upper arm {}",
            method.name(),
            moved("upper_arm_l")
        );
        assert!(
            moved("forearm_r") < moved("upper_arm_l"),
            "{}",
            method.name()
        );
        let shape = RestShape::new(&c.mesh.positions, &c.mesh.faces);
        let mut d = vec![0.0; c.mesh.faces.len()];
        shape.distortion_into(&pose, &mut d);
        assert!(
            d.iter().all(|x| x.is_finite()),
            "{}: a flipped triangle",
            method.name()
        );
    }
}

#[test]
fn a_morph_between_two_poses_keeps_the_tree_of_joints_together() {
    let c = build(&write_ora(&figure(), 0));
    let size = c.mesh.diameter();
    let posed = PlanarMesh {
        positions: posed(&c, PoseMethod::arap()),
        faces: c.mesh.faces.clone(),
    };
    let joints: Vec<[u32; 2]> = c.joints.iter().map(|j| j.vertices).collect();
    let mut place = Placement::new(&c.mesh, &joints);
    assert_eq!(place.cycles(), 0);
    let mut morph = Morph::new(&c.mesh, &posed, MorphOptions::default()).expect("morph");
    let target = morph
        .frame(1.0)
        .expect("t = 1")
        .stats
        .max_conformal_distortion;
    let shape = RestShape::new(&c.mesh.positions, &c.mesh.faces);
    let mut d = vec![0.0; c.mesh.faces.len()];
    let mut worst_gap: f64 = 0.0;
    for k in 0..50 {
        let t = f64::from(k) / 49.0;
        let mut frame = morph.frame(t).expect("frame").positions.to_vec();
        let report = place.apply(&mut frame);
        worst_gap = worst_gap.max(report.largest_gap);
        let worst = shape.distortion_into(&frame, &mut d);
        assert!(
            d.iter().all(|x| x.is_finite()),
            "t = {t}: a flipped triangle"
        );
        assert!(
            worst <= target * (1.0 + 1e-6),
            "t = {t}: distortion {worst} over {target}"
        );
        if k == 0 || k == 49 {
            let want = if k == 0 {
                &c.mesh.positions
            } else {
                &posed.positions
            };
            let off = frame
                .iter()
                .zip(want)
                .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
                .fold(0.0, f64::max);
            assert!(off <= 1e-9 * size, "t = {t}: {off} from the keyframe");
        }
    }
    assert!(worst_gap <= 1e-12 * size, "joints apart by {worst_gap}");
}

/// Writes the test figure as `figure.psd` and `figure.ora` into `BDMORPH_FIGURE_DIR` (for trying
/// the studio and the command line by hand): `BDMORPH_FIGURE_DIR=/tmp/f cargo test --test parts
/// write_the_figure -- --ignored`.
#[test]
#[ignore = "writes files for trying by hand"]
fn write_the_figure() {
    let dir =
        std::path::PathBuf::from(std::env::var("BDMORPH_FIGURE_DIR").expect("BDMORPH_FIGURE_DIR"));
    std::fs::create_dir_all(&dir).expect("dir");
    std::fs::write(dir.join("figure.psd"), write_psd(&figure())).expect("psd");
    std::fs::write(dir.join("figure.ora"), write_ora(&figure(), 0)).expect("ora");
}

/// An ImageMagick that writes PSD (`magick`, or version 6's `convert`), if installed.
fn imagemagick() -> Option<std::path::PathBuf> {
    for name in ["magick", "convert-im6.q16", "convert"] {
        let ok = std::process::Command::new(name)
            .arg("-version")
            .output()
            .is_ok_and(|o| {
                o.status.success() && String::from_utf8_lossy(&o.stdout).contains("ImageMagick")
            });
        if ok {
            return Some(name.into());
        }
    }
    None
}

/// A PSD written by another program (ImageMagick, as `.ci/run` installs it): RLE channels,
/// and its default for layers read from PNG files (ZIP channels), the layers' names and places
/// as written, and a character made from it.
#[test]
fn a_psd_written_by_imagemagick_reads_as_written() {
    let Some(im) = imagemagick() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "ImageMagick is missing in CI"
        );
        eprintln!("ImageMagick is not installed: the PSD written by another program is not tried");
        return;
    };
    let dir = std::env::temp_dir().join(format!("bdmorph-parts-im-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let layers = figure();
    let (w, h) = FIGURE_SIZE;
    let mut args: Vec<String> = Vec::new();
    for l in &layers {
        // Each layer's crop, placed on the canvas.
        let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
        for y in 0..h {
            for x in 0..w {
                if l.rgba[((y * w + x) * 4 + 3) as usize] != 0 {
                    (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x + 1), y1.max(y + 1));
                }
            }
        }
        let mut crop = Vec::new();
        for y in y0..y1 {
            crop.extend_from_slice(
                &l.rgba[((y * w + x0) * 4) as usize..((y * w + x1) * 4) as usize],
            );
        }
        let file = dir.join(format!("{}.png", l.name));
        let png = bdmorph::render::raster::encode_png(&bdmorph::render::Image {
            width: x1 - x0,
            height: y1 - y0,
            rgba: crop,
        })
        .expect("png");
        std::fs::write(&file, png).expect("png");
        args.extend(["(", "-label", &l.name].map(String::from));
        args.push(file.display().to_string());
        args.extend([
            "-set".into(),
            "page".into(),
            format!("+{x0}+{y0}"),
            ")".into(),
        ]);
    }
    // The composite first (ImageMagick writes the first image as the merged one), RLE.
    args.extend(
        [
            "(",
            "-clone",
            "0--1",
            "-background",
            "none",
            "-layers",
            "merge",
        ]
        .map(String::from),
    );
    args.extend([
        "-set".into(),
        "page".into(),
        format!("{w}x{h}+0+0"),
        "-extent".into(),
        format!("{w}x{h}"),
        ")".into(),
    ]);
    args.extend(["-insert", "0"].map(String::from));
    // RLE as asked, and ImageMagick's default for layers read from PNG files: their ZIP
    // compression carried over to the PSD's channels (as `-compress Zip` asks too).
    let mut layered = None;
    for compress in [Some("RLE"), None, Some("Zip")] {
        let mut args = args.clone();
        if let Some(c) = compress {
            args.extend(["-compress".into(), c.into()]);
        }
        let out = dir.join(format!("im-{}.psd", compress.unwrap_or("default")));
        args.push(out.display().to_string());
        let run = std::process::Command::new(&im)
            .args(&args)
            .output()
            .expect("ImageMagick runs");
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let read = read_layered(&std::fs::read(&out).expect("psd"))
            .unwrap_or_else(|e| panic!("{compress:?}: {e}"));
        let names: Vec<&str> = read.layers.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(names, COLOURS.map(|c| c.0), "{compress:?}");
        assert_eq!((read.layers[0].left, read.layers[0].top), (125, 60));
        let mine = read_layered(&write_psd(&figure())).expect("mine");
        for (a, b) in read.layers.iter().zip(&mine.layers) {
            assert_eq!(
                (a.left, a.top, &a.image),
                (b.left, b.top, &b.image),
                "{compress:?}: {}",
                a.name
            );
        }
        layered = Some(read);
    }
    let layered = layered.expect("read");
    let c = character(&layered, &CharacterOptions::default()).expect("character");
    assert_eq!((c.parts.len(), c.joints.len()), (6, 5));
}

/// An arm painted over the torso (its root hidden inside the torso, as artists paint it) is
/// joined at the shoulder, where the arm's outline enters the torso's, not at the middle of
/// the overlap (mid upper arm).
#[test]
fn an_arm_painted_over_the_torso_is_joined_at_the_shoulder() {
    let (layers, shoulders) = layered::torso_under_arms();
    let h = f64::from(FIGURE_SIZE.1);
    for (format, bytes) in [("ORA", write_ora(&layers, 0)), ("PSD", write_psd(&layers))] {
        let layered = read_layered(&bytes).unwrap_or_else(|e| panic!("{format}: {e}"));
        for vertices in [600, 2000, 6000] {
            let c = character(
                &layered,
                &CharacterOptions::default().with_vertices(vertices),
            )
            .expect("character");
            assert_eq!(names(&c), ["torso", "arm_l", "arm_r"], "{format}");
            assert_eq!(c.joints.len(), 2, "{format} {vertices}: {:?}", c.joints);
            for (arm, (shoulder, width)) in ["arm_l", "arm_r"].iter().zip(shoulders) {
                let j = c
                    .joints
                    .iter()
                    .find(|j| j.parts.contains(&part(&c, arm)))
                    .unwrap_or_else(|| panic!("{format}: no joint on {arm}"));
                assert!(j.parts.contains(&part(&c, "torso")), "{format} {arm}");
                let [a, b] = j.vertices.map(|v| c.mesh.positions[v as usize]);
                assert_eq!(a, b, "{format} {arm}: the joint's vertices coincide");
                let off = (a[0] - shoulder[0]).hypot(h - a[1] - shoulder[1]);
                assert!(
                    off <= 0.1 * width,
                    "{format} {vertices} {arm}: the joint is {off:.2} px from the shoulder \
                     {shoulder:?} (at {:?}), more than a tenth of the arm's width {width}",
                    [a[0], h - a[1]]
                );
            }
            c.mesh.validate().expect("valid");
        }
    }
}
