//! `bdmorph info MESH`.

use bdmorph::info::{check_morphable, MeshInfo};
use bdmorph::io;

use super::InfoArgs;

pub(super) fn run(args: InfoArgs) -> Result<(), String> {
    let mesh = io::read_mesh(&args.mesh).map_err(|e| e.to_string())?;
    let i = MeshInfo::of(&mesh);
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
    match check_morphable(&mesh, &args.mesh) {
        Ok(()) => println!("  morphable: yes (a counter-clockwise planar disk)"),
        Err(why) => println!("  morphable: no: {why}"),
    }
    Ok(())
}
