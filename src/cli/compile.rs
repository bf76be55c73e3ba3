//! `bdmorph compile SOURCE -o PROGRAM`, and loading program files for `morph --program`.

use std::path::Path;

use bdmorph::{Located, MeshKey, PlanarMesh, Program};

use super::CompileArgs;

pub(super) fn run(args: CompileArgs) -> Result<(), String> {
    // A program is binary: refuse to write one where a mesh is expected (such as over SOURCE).
    let ext = args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if let Some(ext @ ("obj" | "off")) = ext.as_deref() {
        return Err(format!(
            "{}: a program is not a .{ext} mesh; give it another extension, such as .bdm",
            args.output.display()
        ));
    }
    let (source, _, lines) = super::morph::read(&args.source)?;
    let program = bdmorph::compile(&source.positions, &source.faces)
        .map_err(|e| Located::new(&args.source, &lines, &source.faces, e).to_string())?;
    let bytes = program.to_bytes(&key(&source));
    bdmorph::io::write_bytes_atomic(&args.output, &bytes).map_err(|e| e.to_string())?;
    if !args.quiet {
        eprintln!(
            "wrote {}: {} bytes, {:.1} bytes per triangle ({} vertices, {} triangles)",
            args.output.display(),
            bytes.len(),
            bytes.len() as f64 / source.faces.len() as f64,
            source.positions.len(),
            source.faces.len()
        );
    }
    Ok(())
}

fn key(mesh: &PlanarMesh) -> MeshKey {
    MeshKey::of(mesh.positions.len(), &mesh.faces)
}

/// Loads the program file `path` and checks that it was compiled for `source` (read from
/// `source_path`): same vertex count, face count and faces hash.
pub(super) fn load(
    path: &Path,
    source_path: &Path,
    source: &PlanarMesh,
) -> Result<Program, String> {
    let bytes = bdmorph::io::read_input(path, bdmorph::io::MAX_INPUT_BYTES)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let (program, file) =
        Program::from_bytes(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    let mesh = key(source);
    let differs = if file.n_vertices != mesh.n_vertices {
        format!("{} vertices vs {}", file.n_vertices, mesh.n_vertices)
    } else if file.n_faces != mesh.n_faces {
        format!("{} faces vs {}", file.n_faces, mesh.n_faces)
    } else if file.faces_hash != mesh.faces_hash {
        format!(
            "faces hash {:016x} vs {:016x} (the same counts, but other triangles or another order)",
            file.faces_hash, mesh.faces_hash
        )
    } else {
        return Ok(program);
    };
    Err(format!(
        "{} was compiled for another mesh: {differs} in {}",
        path.display(),
        source_path.display()
    ))
}
