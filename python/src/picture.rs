//! Files and pictures: `read_mesh`, `write_obj`, `mesh_from_image`.

use std::path::PathBuf;

use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;

use bdmorph::meshing::{MeshOptions, PictureOptions};

use crate::arrays;
use crate::errors;

/// `(V, F)` as NumPy arrays.
type MeshArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>);

/// Reads an OBJ or OFF triangle mesh: `(V, F)`, V n x 3 float64, F m x 3 int64.
#[pyfunction]
pub fn read_mesh<'py>(py: Python<'py>, path: PathBuf) -> PyResult<MeshArrays<'py>> {
    let mesh = py
        .detach(|| bdmorph::io::read_mesh(&path))
        .map_err(errors::file)?;
    Ok((
        arrays::out3(py, &mesh.positions),
        arrays::out_faces(py, &mesh.faces),
    ))
}

/// Writes `V` (n x 2 or n x 3) and `F` as OBJ, atomically, every coordinate read back
/// bit for bit.
#[pyfunction]
pub fn write_obj(
    py: Python<'_>,
    path: PathBuf,
    v: PyReadonlyArray2<'_, f64>,
    f: PyReadonlyArray2<'_, i64>,
) -> PyResult<()> {
    let planar = v.as_array().ncols() == 2;
    let result = if planar {
        let p = arrays::points2(&v, "V")?;
        let faces = arrays::faces(&f, p.len())?;
        py.detach(|| bdmorph::io::write_obj_2d(&path, &p, &faces, &[]))
    } else {
        let p = arrays::points3(&v, "V")?;
        let faces = arrays::faces(&f, p.len())?;
        py.detach(|| bdmorph::io::write_obj_3d(&path, &p, &faces))
    };
    result.map_err(errors::file)
}

/// Meshes a picture's subject (its opaque part, or what differs from the background):
/// `(V, F)`, V n x 2 in the picture's pixels (y up), F m x 3.
#[pyfunction]
#[pyo3(signature = (path, vertices=2000, tolerance=None, min_angle=None, threshold=None))]
pub fn mesh_from_image<'py>(
    py: Python<'py>,
    path: PathBuf,
    vertices: usize,
    tolerance: Option<f64>,
    min_angle: Option<f64>,
    threshold: Option<f64>,
) -> PyResult<MeshArrays<'py>> {
    let mut options = MeshOptions::default().with_vertices(vertices);
    if let Some(t) = tolerance {
        options = options.with_tolerance(t);
    }
    if let Some(a) = min_angle {
        options = options.with_min_angle(a);
    }
    let mut picture = PictureOptions::default();
    picture.threshold = threshold;
    let meshed = py
        .detach(|| {
            let image = bdmorph::render::raster::read_image(&path).map_err(|e| e.to_string())?;
            bdmorph::meshing::mesh_picture(&image, &picture, &options)
                .map_err(|e| format!("{}: {e}", path.display()))
        })
        .map_err(errors::meshing)?;
    Ok((
        arrays::out2(py, &meshed.mesh.positions),
        arrays::out_faces(py, &meshed.mesh.faces),
    ))
}
