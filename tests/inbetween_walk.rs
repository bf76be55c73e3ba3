//! In-betweens of real animation drawings: a few triples of Kenney's walk cycles (CC0, in
//! the shared data) that `examples/walk_cycles.rs` runs in full, here asserting that they
//! are accepted: a compatible mesh flip-free over both drawings, and the morph's frames made.
//! The drawings are scaled up 4 times by nearest neighbour, as the example does.

mod common;

use bdmorph::inbetween::{Inbetween, InbetweenOptions};
use bdmorph::render::{raster, Image};

fn scale(image: &Image, k: u32) -> Image {
    let (w, h) = (image.width * k, image.height * k);
    let mut rgba = vec![0u8; 4 * w as usize * h as usize];
    for y in 0..h {
        for x in 0..w {
            let s = 4 * ((y / k) * image.width + x / k) as usize;
            let d = 4 * (y * w + x) as usize;
            rgba[d..d + 4].copy_from_slice(&image.rgba[s..s + 4]);
        }
    }
    Image {
        width: w,
        height: h,
        rgba,
    }
}

fn walk(dir: &std::path::Path, folder: &str, prefix: &str, i: usize) -> Image {
    let path = dir
        .join("animation2d/kenney-characters")
        .join(folder)
        .join(format!("{prefix}_walk{i}.png"));
    let image = raster::read_image(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    scale(&image, 4)
}

#[test]
fn walk_cycle_triples_are_accepted() {
    let Some(dir) = common::shared_data() else {
        return;
    };
    // Held-out characters: consecutive drawings whose holes differ (a gap between the legs
    // in one only), and a stride-2 pair; one at 4,000 vertices.
    for (folder, prefix, a, b, vertices) in [
        ("female_person", "femalePerson", 0, 2, 2000),
        ("male_person", "malePerson", 2, 4, 2000),
        ("zombie", "zombie", 6, 0, 2000),
        ("zombie", "zombie", 1, 3, 4000),
    ] {
        let (da, db) = (walk(&dir, folder, prefix, a), walk(&dir, folder, prefix, b));
        let options = InbetweenOptions::default().with_vertices(vertices);
        let mut inbetween = Inbetween::new(&da, &db, &[], &options)
            .unwrap_or_else(|e| panic!("{folder} {a} -> {b}: {e}"));
        let c = inbetween.compatible();
        assert_eq!(c.report.flipped, 0);
        let area = |p: &[[f64; 2]], f: &[u32; 3]| {
            let [x, y, z] = f.map(|v| p[v as usize]);
            (y[0] - x[0]) * (z[1] - x[1]) - (y[1] - x[1]) * (z[0] - x[0])
        };
        assert!(c
            .mesh
            .faces
            .iter()
            .all(|f| area(&c.mesh.positions, f) > 0.0));
        assert!(c.mesh.faces.iter().all(|f| area(&c.positions_b, f) > 0.0));
        for k in 0..=10 {
            let t = k as f64 / 10.0;
            inbetween
                .frame(t)
                .unwrap_or_else(|e| panic!("{folder} {a} -> {b}, t = {t}: {e}"));
        }
    }
}
