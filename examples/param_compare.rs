//! Every parameterisation method on one disk-topology mesh: energies (area-weighted means,
//! the mesh scaled to area 1), flipped and collapsed triangles, iterations and why they
//! stopped, set-up and total time, for BENCHMARKS.md.
//!
//! ```sh
//! cargo run --release --example param_compare -- ../shared/data/disk3d/libigl/camelhead.off
//! ```

use bdmorph::param::{ParamMethod, ParamOptions, Parameterization};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: param_compare MESH [METHOD...]")?;
    let mut mesh = bdmorph::io::read_mesh(std::path::Path::new(&path))?;
    // Scale to area 1, as the peers' figures are.
    let area: f64 = mesh
        .faces
        .iter()
        .map(|&[a, b, c]| {
            let p = |v: u32| mesh.positions[v as usize];
            let (e1, e2) = (
                [p(b)[0] - p(a)[0], p(b)[1] - p(a)[1], p(b)[2] - p(a)[2]],
                [p(c)[0] - p(a)[0], p(c)[1] - p(a)[1], p(c)[2] - p(a)[2]],
            );
            let x = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            0.5 * (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt()
        })
        .sum();
    let s = 1.0 / area.sqrt();
    for p in mesh.positions.iter_mut() {
        *p = p.map(|x| x * s);
    }
    let methods: Vec<String> = std::env::args().skip(2).collect();
    let methods = if methods.is_empty() {
        ["tutte", "lscm", "asap", "arap", "sd", "mips", "arap-newton"]
            .map(String::from)
            .to_vec()
    } else {
        methods
    };
    println!(
        "{path}: {} vertices, {} faces",
        mesh.positions.len(),
        mesh.faces.len()
    );
    for name in methods {
        let method: ParamMethod = name.parse()?;
        let started = std::time::Instant::now();
        let mut p = Parameterization::new(&mesh, method, ParamOptions::default())?;
        let mut trace = Vec::new();
        let report =
            p.solve_with(|i, r| trace.push((i, r.energy_after, started.elapsed().as_secs_f64())))?;
        let e = p.energies();
        println!(
            "{name:>12}: E_SD {:.5}  E_ARAP {:.5}  E_MIPS {:.5}  flipped {}  collapsed {}  largest distortion {:.3e}  iterations {} ({})  set-up {:.3} s  total {:.3} s",
            e.symmetric_dirichlet,
            e.arap,
            e.mips,
            e.flipped,
            e.collapsed,
            e.max_distortion,
            report.iterations,
            report.stop.name(),
            report.setup_seconds,
            report.setup_seconds + report.seconds
        );
        for (i, energy, t) in trace
            .iter()
            .filter(|(i, ..)| [1, 2, 3, 5, 10, 20, 50, 100, 200].contains(i))
        {
            println!(
                "{:>16} iteration {i:>3}: energy {energy:.6} at {t:.3} s",
                ""
            );
        }
    }
    Ok(())
}
