//! `bdmorph info MESH`.

use bdmorph::info::{morphable, MeshInfo};
use bdmorph::MeshFile;

use super::InfoArgs;

pub(super) fn run(args: InfoArgs) -> Result<(), String> {
    let file = MeshFile::read(&args.mesh).map_err(|e| e.to_string())?;
    let i = MeshInfo::of(&file.mesh);
    let yes = |b: bool| if b { "yes" } else { "no" };
    println!("{}", args.mesh.display());
    println!(
        "  vertices {}, faces {}, edges {}",
        i.vertices, i.faces, i.edges
    );
    println!(
        "  boundary loops {} ({} boundary edges), interior vertices {}",
        i.boundary_loops, i.boundary_edges, i.interior_vertices
    );
    println!(
        "  Euler characteristic {}, connected components {}",
        i.euler, i.components
    );
    println!(
        "  planar (z = 0): {}, texture coordinates: {}",
        yes(i.planar),
        yes(i.texcoords)
    );
    // Said as `morph` would say it, with the file and the line.
    match morphable(&file) {
        Ok(what) => println!("  morphable: yes ({what})"),
        Err(why) => println!("  morphable: no: {why}"),
    }
    Ok(())
}
