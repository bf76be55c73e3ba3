//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

use bdmorph::PlanarMesh;

/// Largest distance between corresponding vertices.
pub fn max_distance(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max)
}

/// `b` moved by the rigid motion that takes `b[i]` to `a[i]` and the direction `b[i] -> b[j]`
/// to `a[i] -> a[j]`.
pub fn align(a: &[[f64; 2]], b: &[[f64; 2]], i: usize, j: usize) -> Vec<[f64; 2]> {
    let ang = |p: &[[f64; 2]]| (p[j][1] - p[i][1]).atan2(p[j][0] - p[i][0]);
    let (s, c) = (ang(a) - ang(b)).sin_cos();
    b.iter()
        .map(|p| {
            let (x, y) = (p[0] - b[i][0], p[1] - b[i][1]);
            [a[i][0] + c * x - s * y, a[i][1] + s * x + c * y]
        })
        .collect()
}

/// The shared disk-topology meshes the parameterisation issues name (camel head, cow, bunny
/// head, hand), relative to the shared data folder.
pub const SHARED_DISKS: [&str; 4] = [
    "disk3d/libigl/camelhead.off",
    "disk3d/ustc-cg/Cow_dABF.obj",
    "disk3d/ustc-cg/Bunny_head.obj",
    "disk3d/odedstein/hand_lowres.obj",
];

/// The shared test data folder, or `None` after saying clearly that it is missing. In CI
/// (`CI` set) a missing folder is a failure, not a skip.
pub fn shared_data() -> Option<PathBuf> {
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data"));
    if dir.is_dir() {
        return Some(dir);
    }
    assert!(
        std::env::var_os("CI").is_none(),
        "../shared/data is missing, but CI must have it"
    );
    eprintln!(
        "SKIPPED: {} not found; this test needs the shared meshes",
        dir.display()
    );
    None
}

/// Reads a planar mesh from the shared data folder.
pub fn read(dir: &std::path::Path, rel: &str) -> PlanarMesh {
    PlanarMesh::read(dir.join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}
