//! NumPy arrays in and out. The Python layer has already made them C-ordered float64 (`V`,
//! points) and int64 (`F`, indices); here every shape and index is checked again, so a call
//! straight into `_bdmorph` is refused cleanly too, never a crash.

use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use bdmorph::io::SurfaceMesh;
use bdmorph::PlanarMesh;

use crate::errors;

/// Triangles from an `m x 3` integer array whose entries index `n` vertices.
pub fn faces(f: &PyReadonlyArray2<'_, i64>, n: usize) -> PyResult<Vec<[u32; 3]>> {
    let a = f.as_array();
    if a.ncols() != 3 {
        return Err(errors::mesh(format!(
            "F must be m x 3 (one row of three vertex indices per triangle), not {} x {}",
            a.nrows(),
            a.ncols()
        )));
    }
    let mut out = Vec::with_capacity(a.nrows());
    for (i, row) in a.rows().into_iter().enumerate() {
        let mut face = [0u32; 3];
        for (k, &v) in row.iter().enumerate() {
            if v < 0 || v as u64 >= n as u64 {
                return Err(errors::mesh(format!(
                    "F: triangle {i} names vertex {v}, but V has {n} vertices (numbered from 0)"
                )));
            }
            face[k] = v as u32;
        }
        out.push(face);
    }
    Ok(out)
}

/// Points of the plane from an `n x 2` array, or `n x 3` with every `z` zero.
pub fn points2(v: &PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<Vec<[f64; 2]>> {
    let a = v.as_array();
    match a.ncols() {
        2 => Ok(a.rows().into_iter().map(|r| [r[0], r[1]]).collect()),
        3 => {
            if let Some((i, r)) = a.rows().into_iter().enumerate().find(|(_, r)| r[2] != 0.0) {
                return Err(errors::mesh(format!(
                    "{what}: vertex {i} has z = {}; a planar mesh has z = 0 everywhere (or give n x 2)",
                    r[2]
                )));
            }
            Ok(a.rows().into_iter().map(|r| [r[0], r[1]]).collect())
        }
        c => Err(errors::mesh(format!(
            "{what} must be n x 2 or n x 3, not {} x {c}",
            a.nrows()
        ))),
    }
}

/// Points of space from an `n x 3` array, or `n x 2` (then `z = 0`).
pub fn points3(v: &PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<Vec<[f64; 3]>> {
    let a = v.as_array();
    match a.ncols() {
        2 => Ok(a.rows().into_iter().map(|r| [r[0], r[1], 0.0]).collect()),
        3 => Ok(a.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect()),
        c => Err(errors::mesh(format!(
            "{what} must be n x 2 or n x 3, not {} x {c}",
            a.nrows()
        ))),
    }
}

/// A planar mesh, checked: finite, no degenerate or (unless `allow_inverted`) clockwise
/// triangle, every vertex used.
pub fn planar(
    v: &PyReadonlyArray2<'_, f64>,
    f: &PyReadonlyArray2<'_, i64>,
    what: &str,
    allow_inverted: bool,
) -> PyResult<PlanarMesh> {
    let positions = points2(v, what)?;
    let faces = faces(f, positions.len())?;
    let mesh = PlanarMesh { positions, faces };
    if allow_inverted {
        mesh.validate_allowing_inverted()
            .map_err(|e| errors::mesh(format!("{what}: {e}")))?;
    } else {
        mesh.validate()
            .map_err(|e| errors::mesh(format!("{what}: {e}")))?;
    }
    Ok(mesh)
}

/// A surface mesh (no texture coordinates).
pub fn surface(
    v: &PyReadonlyArray2<'_, f64>,
    f: &PyReadonlyArray2<'_, i64>,
) -> PyResult<SurfaceMesh> {
    let positions = points3(v, "V")?;
    let faces = faces(f, positions.len())?;
    Ok(SurfaceMesh {
        positions,
        faces,
        texcoords: None,
    })
}

/// Vertex indices from a 1-D integer array, each below `n`.
pub fn indices(s: &PyReadonlyArray1<'_, i64>, n: usize, what: &str) -> PyResult<Vec<u32>> {
    s.as_array()
        .iter()
        .map(|&v| {
            if v < 0 || v as u64 >= n as u64 {
                Err(errors::Error::new_err(format!(
                    "{what}: vertex {v} does not exist (the mesh has {n} vertices, numbered from 0)"
                )))
            } else {
                Ok(v as u32)
            }
        })
        .collect()
}

/// An `n x 2` float64 array.
pub fn out2<'py>(py: Python<'py>, p: &[[f64; 2]]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = p.iter().flatten().copied().collect();
    Array2::from_shape_vec((p.len(), 2), flat)
        .expect("n x 2 values")
        .into_pyarray(py)
}

/// An `n x 3` float64 array.
pub fn out3<'py>(py: Python<'py>, p: &[[f64; 3]]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = p.iter().flatten().copied().collect();
    Array2::from_shape_vec((p.len(), 3), flat)
        .expect("n x 3 values")
        .into_pyarray(py)
}

/// An `m x 3` int64 array of triangles.
pub fn out_faces<'py>(py: Python<'py>, f: &[[u32; 3]]) -> Bound<'py, PyArray2<i64>> {
    let flat: Vec<i64> = f.iter().flatten().map(|&v| i64::from(v)).collect();
    Array2::from_shape_vec((f.len(), 3), flat)
        .expect("m x 3 values")
        .into_pyarray(py)
}

/// A 1-D float64 array.
pub fn out1<'py>(py: Python<'py>, d: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    Array1::from_vec(d).into_pyarray(py)
}

/// A `k x n x 2` float64 array from `k` frames of `n` points, flattened.
pub fn out_frames<'py>(
    py: Python<'py>,
    k: usize,
    n: usize,
    flat: Vec<f64>,
) -> Bound<'py, PyArray3<f64>> {
    Array3::from_shape_vec((k, n, 2), flat)
        .expect("k x n x 2 values")
        .into_pyarray(py)
}
