//! `bdmorph mesh CHARACTER.psd|.ora -o OUT.json|OUT.obj`: a character in parts from a layered
//! picture, as a studio project (the parts, their joints and draw order; its picture the
//! layered file itself) or as OBJ (one group and one material per part, with its MTL and the
//! parts' texture beside it, for other programs).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use bdmorph::parts::{self, Character, CharacterOptions};
use bdmorph::render::raster;
use bdmorph::studio::project::{PartData, Project};

use super::MeshArgs;

/// Whether `path` is a layered picture (by its extension or its first bytes).
pub(super) fn is_layered(path: &Path) -> bool {
    if parts::is_layered_path(path) {
        return true;
    }
    // Only a regular file is opened to look (a FIFO would block the open).
    if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
        return false;
    }
    let mut head = [0u8; 4];
    std::fs::File::open(path)
        .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head))
        .is_ok()
        && &head == b"8BPS"
}

/// `path` as seen from the folder `from` (relative when both are, or share a root), else
/// absolute.
fn relative(path: &Path, from: &Path) -> String {
    let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let (target, base) = (abs(path), abs(from));
    let t: Vec<_> = target.components().collect();
    let b: Vec<_> = base.components().collect();
    let common = t.iter().zip(&b).take_while(|(x, y)| x == y).count();
    if common == 0 {
        return target.display().to_string();
    }
    let mut out = PathBuf::new();
    for _ in common..b.len() {
        out.push("..");
    }
    for c in &t[common..] {
        out.push(c);
    }
    out.display().to_string()
}

/// The OBJ text of a character: `mtllib`, positions, texture coordinates, and per part a group
/// and a material.
fn obj_text(c: &Character, mtl_name: &str, title: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# {title}");
    let _ = writeln!(s, "mtllib {mtl_name}");
    for p in &c.mesh.positions {
        let _ = writeln!(s, "v {} {} 0", p[0], p[1]);
    }
    for t in &c.texcoords {
        let _ = writeln!(s, "vt {} {}", t[0], t[1]);
    }
    for part in &c.parts {
        let name = obj_name(&part.name);
        let _ = writeln!(s, "g {name}\nusemtl {name}");
        for f in &c.mesh.faces[part.faces[0] as usize..part.faces[1] as usize] {
            let [a, b, d] = f.map(|v| v + 1);
            let _ = writeln!(s, "f {a}/{a} {b}/{b} {d}/{d}");
        }
    }
    s
}

/// A part's name as one OBJ token.
fn obj_name(name: &str) -> String {
    let n: String = name
        .chars()
        .map(|c| if c.is_whitespace() { '_' } else { c })
        .collect();
    if n.is_empty() {
        "part".into()
    } else {
        n
    }
}

pub(super) fn run(args: &MeshArgs) -> Result<(), String> {
    let shown = args.input.display().to_string();
    let ignored: Vec<&str> = [
        (args.tolerance.is_some(), "--tolerance"),
        (args.background.is_some(), "--background"),
        (args.threshold.is_some(), "--threshold"),
        (args.keep_specks, "--keep-specks"),
    ]
    .iter()
    .filter(|(given, _)| *given)
    .map(|&(_, name)| name)
    .collect();
    let output = args
        .output
        .as_ref()
        .ok_or("nothing to do: give -o OUT.json (a studio project) or -o OUT.obj")?;
    let ext = output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if ext != "json" && ext != "obj" {
        return Err(format!(
            "{}: a layered picture meshes to .json (a studio project with its parts and joints) or .obj (a group per part)",
            output.display()
        ));
    }
    let layered = parts::read_layered_file(&args.input).map_err(|e| format!("{shown}: {e}"))?;
    let options = CharacterOptions::default()
        .with_vertices(args.vertices)
        .with_min_angle(args.min_angle);
    let c = parts::character(&layered, &options).map_err(|e| format!("{shown}: {e}"))?;
    if !args.quiet {
        if !ignored.is_empty() {
            eprintln!(
                "bdmorph: warning: {} only apply to flat pictures: each layer is told by its own transparency",
                ignored.join(", ")
            );
        }
        for note in &c.notes {
            eprintln!("bdmorph: note: {note}");
        }
    }
    let folder = output
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if ext == "json" {
        let mut project = Project::new(&c.mesh, Some(c.texcoords.clone()));
        project.texture = Some(relative(&args.input, folder));
        project.parts = Some(
            c.parts
                .iter()
                .map(|p| PartData {
                    name: p.name.clone(),
                    vertices: p.vertices,
                    faces: p.faces,
                    ..PartData::default()
                })
                .collect(),
        );
        if !c.joints.is_empty() {
            project.joints = Some(c.joints.iter().map(|j| j.vertices).collect());
        }
        bdmorph::io::write_bytes_atomic(output, &project.to_json())
            .map_err(|e| format!("{}: {e}", output.display()))?;
    } else {
        let stem = output
            .file_stem()
            .map_or_else(|| "character".into(), |s| s.to_string_lossy().into_owned());
        let (mtl, png) = (format!("{stem}.mtl"), format!("{stem}.png"));
        let mut mtl_text = String::new();
        for part in &c.parts {
            let _ = writeln!(
                mtl_text,
                "newmtl {}\nKd 1 1 1\nd 1\nmap_Kd {png}\n",
                obj_name(&part.name)
            );
        }
        let title = format!(
            "bdmorph mesh {shown}: {} parts, {} joints, {} vertices, {} triangles",
            c.parts.len(),
            c.joints.len(),
            c.mesh.positions.len(),
            c.mesh.faces.len()
        );
        let png_bytes = raster::encode_png(&c.atlas).map_err(|e| e.to_string())?;
        for (path, bytes) in [
            (folder.join(&png), png_bytes),
            (folder.join(&mtl), mtl_text.into_bytes()),
            (output.clone(), obj_text(&c, &mtl, &title).into_bytes()),
        ] {
            bdmorph::io::write_bytes_atomic(&path, &bytes)
                .map_err(|e| format!("{}: {e}", path.display()))?;
        }
    }
    if !args.quiet {
        eprintln!(
            "bdmorph: {}: {} parts, {} joints, {} vertices, {} triangles",
            output.display(),
            c.parts.len(),
            c.joints.len(),
            c.mesh.positions.len(),
            c.mesh.faces.len()
        );
    }
    Ok(())
}
