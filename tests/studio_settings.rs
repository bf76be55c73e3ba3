//! Settings belong to what they describe, in a real browser (Debian's Chromium, real mouse and
//! keyboard): a picture's tracing settings are its own (never the previous file's); work
//! restored after `kill -9` keeps its project's name and its undo history; a part's lock and
//! hide are saved; notes fade (errors stay) and equal ones are shown once; the Open list
//! offers only studio projects among JSON files.
//!
//! Without Chromium the tests are skipped, except in CI (`CI` set), where they fail.
//! Screenshots go to a scratch folder, printed, and kept.

mod layered;
mod studio_common;
mod studio_page;

use std::path::Path;
use std::time::{Duration, Instant};

use bdmorph::render::Image;
use bdmorph::studio::project::Project;
use headless_chrome::browser::tab::ModifierKey;
use studio_common::{scratch, Studio};
use studio_page::*;

/// A baseline greyscale JPEG whose 8 x 8 blocks are each one grey level (`level(bx, by)`):
/// only DC coefficients (quantised by 1), the standard luminance DC table, an AC table of
/// end-of-block alone. Enough for an opaque photo-like picture made in code (the crates here
/// decode JPEG but none encodes it).
fn jpeg_blocks(width: u16, height: u16, level: impl Fn(usize, usize) -> u8) -> Vec<u8> {
    assert!(width % 8 == 0 && height % 8 == 0);
    let mut out = vec![0xFF, 0xD8];
    // Quantisation: all ones.
    out.extend([0xFF, 0xDB, 0, 67, 0]);
    out.extend([1u8; 64]);
    // Frame: 8 bits, one component, no subsampling.
    out.extend([0xFF, 0xC0, 0, 11, 8]);
    out.extend(height.to_be_bytes());
    out.extend(width.to_be_bytes());
    out.extend([1, 1, 0x11, 0]);
    // DC table (class 0, id 0): the standard luminance one.
    let dc_counts = [0u8, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0];
    out.extend([0xFF, 0xC4, 0, 3 + 16 + 12, 0x00]);
    out.extend(dc_counts);
    out.extend(0u8..12);
    // AC table (class 1, id 0): end of block, one bit.
    out.extend([0xFF, 0xC4, 0, 3 + 16 + 1, 0x10, 1]);
    out.extend([0u8; 15]);
    out.push(0x00);
    // Scan.
    out.extend([0xFF, 0xDA, 0, 8, 1, 1, 0x00, 0, 63, 0]);
    // The DC codes of categories 0..=11: 00, 010 ... 110, then 1110, 11110, ... (ones and a
    // zero, `cat - 2` bits).
    let dc_code = |cat: u32| -> (u32, u32) {
        match cat {
            0 => (0b00, 2),
            1..=5 => (0b010 + cat - 1, 3),
            _ => ((1 << (cat - 2)) - 2, cat - 2),
        }
    };
    let mut bits: Vec<bool> = Vec::new();
    let put = |code: u32, len: u32, bits: &mut Vec<bool>| {
        for i in (0..len).rev() {
            bits.push(code >> i & 1 == 1);
        }
    };
    let mut previous = 0i32;
    for by in 0..usize::from(height / 8) {
        for bx in 0..usize::from(width / 8) {
            let dc = 8 * (i32::from(level(bx, by)) - 128);
            let diff = dc - previous;
            previous = dc;
            let cat = 32 - diff.unsigned_abs().leading_zeros();
            let (code, len) = dc_code(cat);
            put(code, len, &mut bits);
            if cat > 0 {
                let value = if diff < 0 { diff - 1 } else { diff } as u32;
                put(value & ((1 << cat) - 1), cat, &mut bits);
            }
            put(0, 1, &mut bits); // end of block
        }
    }
    while bits.len() % 8 != 0 {
        bits.push(true);
    }
    for byte in bits.chunks(8) {
        let b = byte.iter().fold(0u8, |a, &bit| a << 1 | u8::from(bit));
        out.push(b);
        if b == 0xFF {
            out.push(0);
        }
    }
    out.extend([0xFF, 0xD9]);
    out
}

/// A figure on transparency (its transparent pixels white): a dark body, a thin light arm
/// (close to white: told from the background only by its opacity), a dark hand. The arm's
/// axis, in pixels from the top-left corner.
fn figure_with_a_thin_arm() -> (Image, [[f64; 2]; 2]) {
    let (w, h) = (200u32, 200u32);
    let arm = [[95.0, 105.0], [152.0, 55.0]];
    let mut rgba = Vec::with_capacity((4 * w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let p = [f64::from(x) + 0.5, f64::from(y) + 0.5];
            let body = (p[0] - 70.0).hypot(p[1] - 120.0) < 35.0;
            let hand = (p[0] - 160.0).hypot(p[1] - 45.0) < 14.0;
            let [a, b] = arm;
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let s =
                (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
            let on_arm = (a[0] + s * dx - p[0]).hypot(a[1] + s * dy - p[1]) < 3.5;
            rgba.extend(if body || hand {
                [40, 40, 40, 255]
            } else if on_arm {
                [232, 232, 232, 255]
            } else {
                [255, 255, 255, 0]
            });
        }
    }
    (
        Image {
            width: w,
            height: h,
            rgba,
        },
        arm,
    )
}

/// Whether `p` lies in a triangle of the mesh.
fn covered(positions: &[[f64; 2]], faces: &[[u32; 3]], p: [f64; 2]) -> bool {
    faces.iter().any(|f| {
        let [a, b, c] = f.map(|v| positions[v as usize]);
        let side = |u: [f64; 2], v: [f64; 2]| {
            (v[0] - u[0]) * (p[1] - u[1]) - (v[1] - u[1]) * (p[0] - u[0])
        };
        let (s1, s2, s3) = (side(a, b), side(b, c), side(c, a));
        (s1 >= 0.0 && s2 >= 0.0 && s3 >= 0.0) || (s1 <= 0.0 && s2 <= 0.0 && s3 <= 0.0)
    })
}

/// Clicks the Open dialog's row for `name`.
fn open_from_list(page: &PageTab, name: &str) {
    page.click_on("#open");
    page.wait("document.getElementById('open-dialog').open", 10);
    page.wait(
        &format!("[...document.querySelectorAll('#open-list button.file')].some((b) => b.textContent.startsWith('{name} '))"),
        10,
    );
    let index = page.num(&format!(
        "[...document.querySelectorAll('#open-list button.file')].findIndex((b) => b.textContent.startsWith('{name} '))"
    ));
    page.click_on(&format!(
        "#open-list button.file:nth-child({})",
        index as usize + 1
    ));
}

/// The server's document, saved by a socket of the test's own to `name` (read back).
fn document(studio: &Studio, dir: &Path, name: &str) -> Project {
    let mut c = studio.client();
    let request = serde_json::json!({"op": "save", "name": name, "overwrite": true}).to_string();
    assert_eq!(c.request(&request), None);
    Project::read(&dir.join(name)).expect("saved")
}

/// Item 1: an opaque JPEG (traced by its border's colour), then a PNG with transparency and a
/// thin arm: the PNG is traced by its transparency, as `bdmorph mesh` traces it: one piece,
/// the arm in the mesh.
#[test]
fn a_picture_opened_after_another_is_traced_by_its_own_settings() {
    let Some(browser) = browser() else { return };
    let dir = scratch("s1-tracing");
    // The JPEG: a dark square on a light ground, opaque.
    let jpeg = jpeg_blocks(160, 160, |bx, by| {
        if (5..15).contains(&bx) && (5..15).contains(&by) {
            40
        } else {
            235
        }
    });
    std::fs::write(dir.join("photo.jpg"), &jpeg).expect("jpeg");
    let decoded = bdmorph::render::raster::decode_image(&jpeg).expect("the JPEG decodes");
    assert!(decoded.rgba.chunks(4).all(|p| p[3] == 255), "opaque");
    assert!(decoded.rgba[..4]
        .iter()
        .take(3)
        .all(|&c| c.abs_diff(235) <= 2));
    let (figure, arm) = figure_with_a_thin_arm();
    write_png(&dir.join("figure.png"), &figure);
    // `bdmorph mesh`'s choice for the PNG: its transparency, one piece with the arm.
    let meshed = bdmorph::meshing::mesh_picture(
        &figure,
        &bdmorph::meshing::PictureOptions::default(),
        &bdmorph::meshing::MeshOptions::default(),
    )
    .expect("meshed");
    let along = |s: f64| {
        let p = [
            arm[0][0] + s * (arm[1][0] - arm[0][0]),
            arm[0][1] + s * (arm[1][1] - arm[0][1]),
        ];
        // The mesh's frame: pixels, y up.
        [p[0], f64::from(figure.height) - p[1]]
    };
    let samples: Vec<[f64; 2]> = (2..=8).map(|k| along(f64::from(k) / 10.0)).collect();
    assert!(samples
        .iter()
        .all(|&p| covered(&meshed.mesh.positions, &meshed.mesh.faces, p)));

    let studio = Studio::start(&dir, None);
    let page = PageTab::open(&browser, &studio.url, &dir);
    open_from_list(&page, "photo.jpg");
    page.wait(
        "studio.state.source === 'photo.jpg' && studio.state.picture_settings.background === 'auto'",
        30,
    );
    page.shot("s1-0-photo.png");
    open_from_list(&page, "figure.png");
    page.wait("studio.state.source === 'figure.png'", 30);
    page.settle();
    assert_eq!(
        page.eval("studio.state.picture_settings"),
        serde_json::json!({"background": null, "threshold": null}),
        "the PNG's own settings: its transparency"
    );
    assert_eq!(
        page.num("studio.state.pieces"),
        1.0,
        "one piece, the hand on the arm"
    );
    // The arm is drawn: with the picture off, the mesh's colours lie along it.
    if page.eval("document.getElementById('texture').checked") == true {
        page.click_on("#texture");
    }
    page.settle();
    let shot = page.shot("s1-1-figure.png");
    for (k, p) in samples.iter().enumerate() {
        let at = page.eval(&format!("studio.toPage({}, {})", p[0], p[1]));
        let at = [at[0].as_f64().expect("x"), at[1].as_f64().expect("y")];
        let drawn = shot.count_near(at, 2.0, undistorted);
        assert!(drawn > 0, "arm sample {k} at {at:?} is drawn by the mesh");
    }
    // The server's document: the arm's pixels are covered by its triangles.
    let doc = document(&studio, &dir, "check.json");
    for p in &samples {
        assert!(
            covered(&doc.mesh.positions, &doc.mesh.faces, *p),
            "{p:?} in the mesh"
        );
    }
    assert_eq!(doc.picture.background, None);
}

/// The document as a page of the test's own sees it: the keyframes (time, easing, pins), the
/// frame rate, and every keyframe's pose bit for bit.
fn signature(studio: &Studio) -> serde_json::Value {
    use tungstenite::Message;
    let mut c = studio.client();
    c.sync();
    let keys = c.state["keyframes"].as_array().expect("keyframes").clone();
    let wanted: Vec<usize> = (0..keys.len()).collect();
    c.ws.send(Message::Text(
        serde_json::json!({"op": "ghosts", "keyframes": wanted})
            .to_string()
            .into(),
    ))
    .expect("sends");
    let mut poses: Vec<Option<Vec<u32>>> = vec![None; keys.len()];
    let start = Instant::now();
    while poses.iter().any(Option::is_none) {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the keyframes' poses"
        );
        if let Ok(Message::Binary(b)) = c.ws.read() {
            let kind = u32::from_le_bytes(b[..4].try_into().expect("kind"));
            if kind != 4 {
                continue;
            }
            let k = u32::from_le_bytes(b[4..8].try_into().expect("k")) as usize;
            let bits = b[16..]
                .chunks(4)
                .map(|w| u32::from_le_bytes(w.try_into().expect("f32")))
                .collect();
            poses[k] = Some(bits);
        }
    }
    serde_json::json!({
        "keys": keys.iter().map(|k| serde_json::json!([k["time"], k["easing"], k["pins"]])).collect::<Vec<_>>(),
        "fps": c.state["fps"],
        "poses": poses,
    })
}

/// Item 2: named edits, `kill -9`, a restart: the restored work shows its project's name, and
/// undo steps back through the edits made before, exactly, to the saved project (clean).
#[test]
fn restored_work_keeps_its_name_and_its_undo_history() {
    let Some(browser) = browser() else { return };
    let dir = scratch("s2-restore");
    let mut studio = Studio::start(&dir, None);
    let page = PageTab::open(&browser, &studio.url, &dir);
    page.click_on("#save-as");
    page.wait("document.getElementById('prompt-dialog').open", 10);
    page.set_value("#prompt-value", "walk.json");
    page.click_on("#prompt-ok");
    page.wait(
        "studio.state.project === 'walk.json' && !studio.state.dirty",
        10,
    );
    let mut signatures = vec![signature(&studio)];
    let mut labels = Vec::new();
    let mut done = |page: &PageTab, steps: f64, signatures: &mut Vec<serde_json::Value>| {
        page.wait(
            &format!("studio.state.history.steps === {steps} && !studio.busy()"),
            20,
        );
        labels.push(page.eval("studio.state.undo"));
        signatures.push(signature(&studio));
    };
    // A pin, a second pin, a drag, a keyframe added, its time, the frame rate.
    page.click(page.vertex(0));
    done(&page, 1.0, &mut signatures);
    let right = page.extreme(page.piece(true), 1.0, 0.0);
    let at = page.vertex(right);
    page.click(at);
    done(&page, 2.0, &mut signatures);
    page.drag(at, [at[0] + 50.0, at[1] - 40.0], 8);
    done(&page, 3.0, &mut signatures);
    page.click_on("#add-key");
    done(&page, 4.0, &mut signatures);
    page.set_value("#key-time", "1.5");
    done(&page, 5.0, &mut signatures);
    page.set_value("#fps", "12");
    done(&page, 6.0, &mut signatures);
    assert!(page.eval("studio.state.dirty") == true);
    // The autosave has the last edit and names its history (written beside it).
    let state = dir.join(".bdmorph-studio");
    let autosave = state.join(format!("autosave-{}.json", studio.child.id()));
    let start = Instant::now();
    loop {
        let kept: serde_json::Value = std::fs::read(&autosave)
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok())
            .unwrap_or_default();
        if kept["project"]["fps"] == 12.0 && kept["history"].is_u64() {
            assert_eq!(kept["project_file"], "walk.json");
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the autosave: {kept}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    assert!(state
        .join(format!("autosave-{}.history", studio.child.id()))
        .is_file());
    // kill -9, and a studio started again in the folder: the page reconnects by itself.
    studio.child.kill().expect("kill -9");
    let _ = studio.child.wait();
    page.wait("!studio.connected", 20);
    let again = Studio::start(&dir, None);
    page.wait("studio.connected", 30);
    page.wait("!document.getElementById('banner-recovered').hidden", 10);
    let offered = page.eval("document.getElementById('recovered-text').textContent");
    assert!(
        offered.as_str().unwrap_or("").contains("walk.json"),
        "{offered}"
    );
    page.shot("s2-0-offered.png");
    page.click_on("#recovered-restore");
    page.wait(
        "studio.state.keyframes.length === 2 && studio.state.fps === 12",
        20,
    );
    page.settle();
    assert_eq!(page.eval("studio.state.project"), "walk.json");
    assert_eq!(
        page.eval("document.getElementById('doc-name').textContent"),
        "walk.json"
    );
    assert!(page
        .eval("document.title")
        .as_str()
        .unwrap_or("")
        .contains("walk.json"));
    page.shot("s2-1-restored.png");
    assert_eq!(signature(&again), signatures[6], "restored as it was");
    // Undo goes back through the edits made before the kill, each exactly.
    assert_eq!(
        page.num("studio.state.history.steps"),
        7.0,
        "six edits and the restore"
    );
    for k in (0..6).rev() {
        assert_eq!(page.eval("studio.state.undo"), labels[k], "step {}", k + 1);
        page.undo();
        assert_eq!(
            signature(&again),
            signatures[k],
            "undone to before step {}",
            k + 1
        );
    }
    // Back at the saved project: clean again.
    page.wait("!studio.state.dirty", 10);
    assert_eq!(page.eval("studio.state.undo"), "restore recovered work");
    // And redo runs forward through them again.
    page.key("z", &[ModifierKey::Ctrl, ModifierKey::Shift]);
    page.wait("studio.state.history.steps === 2 && !studio.busy()", 10);
    assert_eq!(signature(&again), signatures[1]);
    page.shot("s2-2-undone.png");
}

/// Item 3: a part hidden and another locked: undoable steps, kept across a reload of the
/// page, saved with the project (version 4) and shown so by a studio opening it.
#[test]
fn part_lock_and_hide_are_saved_and_undone() {
    let Some(browser) = browser() else { return };
    let dir = scratch("s3-parts");
    std::fs::write(
        dir.join("figure.psd"),
        layered::write_psd(&layered::figure()),
    )
    .expect("psd");
    let mut studio = Studio::start(&dir, Some("figure.psd"));
    let page = PageTab::open(&browser, &studio.url, &dir);
    page.wait("!!studio.texture && !!studio.state.parts", 30);
    if page.eval("document.getElementById('edges').checked") == true {
        page.click_on("#edges");
    }
    page.settle();
    let magenta = |c: [u8; 3]| c[0] > 170 && c[1] < 80 && c[2] > 170;
    let shown = page
        .shot("s3-0-opened.png")
        .count_in(page.canvas(), magenta);
    assert!(shown > 100, "the right forearm is drawn: {shown}");
    let part = |name: &str| {
        page.num(&format!(
            "studio.state.parts.findIndex((p) => p.name === '{name}')"
        ))
    };
    let forearm = part("forearm_r");
    let upper = part("upper_arm_l");
    page.click_on(".part-row[data-part='forearm_r'] button[title^='Hide']");
    page.wait(
        &format!("studio.state.parts[{forearm}].hidden === true"),
        10,
    );
    page.click_on(".part-row[data-part='upper_arm_l'] button[title^='Lock']");
    page.wait(&format!("studio.state.parts[{upper}].locked === true"), 10);
    assert_eq!(page.eval("studio.state.undo"), "lock upper_arm_l");
    page.settle();
    let hidden = page
        .shot("s3-1-hidden.png")
        .count_in(page.canvas(), magenta);
    assert!(hidden * 10 < shown, "hidden: {shown} -> {hidden}");
    // Undo and redo.
    page.undo();
    assert_eq!(
        page.eval(&format!("!!studio.state.parts[{upper}].locked")),
        false
    );
    page.key("z", &[ModifierKey::Ctrl, ModifierKey::Shift]);
    page.wait(&format!("studio.state.parts[{upper}].locked === true"), 10);
    // A reload keeps them (they are the document's, not the page's).
    page.reload();
    page.wait(
        &format!("!!studio.state.parts && studio.state.parts[{forearm}].hidden === true"),
        20,
    );
    page.wait(
        "!!document.querySelector(\".part-row[data-part='forearm_r'] button[title^='Show']\") && !!document.querySelector(\".part-row[data-part='upper_arm_l'] button[title^='Unlock']\")",
        10,
    );

    page.shot("s3-1b-reloaded.png");
    // Saved with the project, and a studio opening it shows them.
    page.click_on("#save-as");
    page.wait("document.getElementById('prompt-dialog').open", 10);
    page.set_value("#prompt-value", "character.json");
    page.click_on("#prompt-ok");
    page.wait(
        "studio.state.project === 'character.json' && !studio.state.dirty",
        10,
    );
    let text = std::fs::read_to_string(dir.join("character.json")).expect("saved");
    let saved: serde_json::Value = serde_json::from_str(&text).expect("json");
    assert_eq!(saved["version"], 4);
    let parts = saved["parts"].as_array().expect("parts");
    for p in parts {
        let name = p["name"].as_str().unwrap_or("");
        assert_eq!(p["hidden"] == true, name == "forearm_r", "{p}");
        assert_eq!(p["locked"] == true, name == "upper_arm_l", "{p}");
    }
    studio.interrupt();
    let other = Studio::start(&dir, Some("character.json"));
    let page = PageTab::open(&browser, &other.url, &dir);
    page.wait("!!studio.texture && !!studio.state.parts", 30);
    if page.eval("document.getElementById('edges').checked") == true {
        page.click_on("#edges");
    }
    page.settle();
    assert_eq!(
        page.eval(&format!("studio.state.parts[{forearm}].hidden")),
        true
    );
    assert_eq!(
        page.eval(&format!("studio.state.parts[{upper}].locked")),
        true
    );
    let reopened = page
        .shot("s3-2-reopened.png")
        .count_in(page.canvas(), magenta);
    assert!(reopened * 10 < shown, "still hidden: {reopened}");
}

/// The notes' texts shown, each as drawn (with its count).
fn note_texts(page: &PageTab) -> Vec<String> {
    page.eval("[...document.querySelectorAll('#notes .note')].map((n) => n.textContent)")
        .as_array()
        .expect("notes")
        .iter()
        .map(|t| t.as_str().unwrap_or("").to_owned())
        .collect()
}

/// Item 4: a note fades by itself; an error stays; six equal errors are one note, "×6".
#[test]
fn notes_fade_errors_stay_and_equal_ones_are_merged() {
    let Some(browser) = browser() else { return };
    let dir = scratch("s4-notes");
    let (figure, _) = figure_with_a_thin_arm();
    write_png(&dir.join("figure.png"), &figure);
    let studio = Studio::start(&dir, None);
    let page = PageTab::open(&browser, &studio.url, &dir);
    open_from_list(&page, "figure.png");
    page.wait("studio.state.source === 'figure.png'", 30);
    page.wait(
        "document.getElementById('notes').textContent.includes('opened figure.png')",
        10,
    );
    page.shot("s4-0-note.png");
    // Gone by itself (a generous wait: it fades after a few seconds).
    page.wait(
        "!document.getElementById('notes').textContent.includes('opened figure.png')",
        30,
    );
    // Still the server's: only this page stopped showing it.
    let mut c = studio.client();
    c.sync();
    assert!(c.notes().iter().any(|n| n.contains("opened figure.png")));
    // Delete on the first keyframe, six times: one error, ×6.
    page.click(page.vertex(0)); // focus on the canvas (a pin)
    page.wait("studio.pins.length === 1", 10);
    for _ in 0..6 {
        page.key("Delete", &[]);
    }
    page.wait(
        "document.getElementById('notes').textContent.includes('×6')",
        10,
    );
    let notes = note_texts(&page);
    let deleting: Vec<&String> = notes
        .iter()
        .filter(|n| n.contains("cannot be deleted"))
        .collect();
    assert_eq!(deleting.len(), 1, "{notes:?}");
    assert!(deleting[0].contains("×6"), "{notes:?}");
    page.shot("s4-1-merged.png");
    // An error stays past the notes' time.
    std::thread::sleep(Duration::from_secs(9));
    let notes = note_texts(&page);
    assert!(
        notes.iter().any(|n| n.contains("cannot be deleted")),
        "{notes:?}"
    );
    // Dismissed with one click, all six.
    page.click_on("#notes .note.error .dismiss");
    page.wait(
        "!document.getElementById('notes').textContent.includes('cannot be deleted')",
        10,
    );
}

/// Item 5: the Open list offers a project but not a sprite sheet's JSON beside it.
#[test]
fn the_open_list_offers_only_studio_projects() {
    let Some(browser) = browser() else { return };
    let dir = scratch("s5-open");
    let mesh = bdmorph::generate::disk(6, 0.1);
    let mut project = Project::new(&mesh, None);
    project.keyframes.push(bdmorph::studio::edit::keyframe_at(
        1.0,
        bdmorph::generate::bend(&mesh, 0.3).positions,
    ));
    project.write(&dir.join("walk.json")).expect("project");
    let exported = std::process::Command::new(env!("CARGO_BIN_EXE_bdmorph"))
        .args([
            "export",
            "walk.json",
            "-o",
            "sheet.png",
            "--sheet",
            "--size",
            "64x64",
        ])
        .current_dir(&dir)
        .output()
        .expect("runs");
    assert!(
        exported.status.success(),
        "{}",
        String::from_utf8_lossy(&exported.stderr)
    );
    assert!(
        dir.join("sheet.json").is_file(),
        "the sheet's JSON is there"
    );
    let studio = Studio::start(&dir, None);
    let page = PageTab::open(&browser, &studio.url, &dir);
    page.click_on("#open");
    page.wait("document.getElementById('open-dialog').open", 10);
    page.wait(
        "document.querySelectorAll('#open-list button.file').length > 0",
        10,
    );
    let listed = page
        .eval("[...document.querySelectorAll('#open-list button.file')].map((b) => b.textContent)");
    let listed: Vec<&str> = listed
        .as_array()
        .expect("rows")
        .iter()
        .map(|r| r.as_str().unwrap_or(""))
        .collect();
    page.shot("s5-0-open.png");
    assert!(
        listed.iter().any(|r| r.starts_with("walk.json (project")),
        "{listed:?}"
    );
    assert!(
        listed.iter().any(|r| r.starts_with("sheet.png (picture")),
        "{listed:?}"
    );
    assert!(
        !listed.iter().any(|r| r.starts_with("sheet.json")),
        "{listed:?}"
    );
}
