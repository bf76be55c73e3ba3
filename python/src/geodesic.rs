//! `HeatGeodesics`: the heat method, prefactored once, each query a few back-substitutions.

use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use bdmorph::geodesic::{Boundary, ExactGeodesics as Exact, HeatGeodesics as Heat, HeatOptions};

use crate::arrays;
use crate::errors;

/// Source vertices: at least one, each below `n`.
fn sources_of(s: &PyReadonlyArray1<'_, i64>, n: usize) -> PyResult<Vec<u32>> {
    if s.as_array().is_empty() {
        return Err(errors::geodesic(
            "sources: give at least one source vertex (the list is empty)",
        ));
    }
    arrays::indices(s, n, "sources")
}

/// Geodesic distances on a triangle mesh by the heat method.
#[pyclass(module = "bdmorph._bdmorph")]
pub struct HeatGeodesics {
    inner: Heat,
    n: usize,
}

#[pymethods]
impl HeatGeodesics {
    #[new]
    #[pyo3(signature = (v, f, time_factor=None, boundary="robin", intrinsic_delaunay=true, refine=0.0, refine_budget=0.5))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        v: PyReadonlyArray2<'_, f64>,
        f: PyReadonlyArray2<'_, i64>,
        time_factor: Option<f64>,
        boundary: &str,
        intrinsic_delaunay: bool,
        refine: f64,
        refine_budget: f64,
    ) -> PyResult<HeatGeodesics> {
        let mesh = arrays::surface(&v, &f)?;
        let boundary = match boundary {
            "robin" => Boundary::Robin,
            "neumann" => Boundary::Neumann,
            "dirichlet" => Boundary::Dirichlet,
            "average" => Boundary::Average,
            other => {
                return Err(errors::GeodesicError::new_err(format!(
                "unknown boundary condition '{other}' (use robin, neumann, dirichlet or average)"
            )))
            }
        };
        let mut options = HeatOptions::default()
            .with_boundary(boundary)
            .with_intrinsic_delaunay(intrinsic_delaunay)
            .with_refinement(refine, refine_budget);
        if let Some(m) = time_factor {
            if !(m.is_finite() && m > 0.0) {
                return Err(errors::geodesic(format!(
                    "time_factor must be a finite number > 0, not {m}"
                )));
            }
            options = options.with_time_factor(m);
        }
        let n = mesh.positions.len();
        let inner = py
            .detach(|| Heat::new(&mesh, options))
            .map_err(errors::geodesic)?;
        Ok(HeatGeodesics { inner, n })
    }

    /// The distance of every vertex from the nearest of `sources`, as an array of n.
    fn distance<'py>(
        &mut self,
        py: Python<'py>,
        sources: PyReadonlyArray1<'_, i64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let sources = sources_of(&sources, self.n)?;
        let inner = &mut self.inner;
        let d = py
            .detach(|| inner.distance(&sources))
            .map_err(errors::geodesic)?;
        Ok(arrays::out1(py, d))
    }

    /// The distances from each source alone, as a k x n array.
    fn distances_each<'py>(
        &mut self,
        py: Python<'py>,
        sources: PyReadonlyArray1<'_, i64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let sources = sources_of(&sources, self.n)?;
        let inner = &mut self.inner;
        let rows = py
            .detach(|| inner.distances_each(&sources))
            .map_err(errors::geodesic)?;
        let k = rows.len();
        let flat: Vec<f64> = rows.into_iter().flatten().collect();
        Ok(numpy::ndarray::Array2::from_shape_vec((k, self.n), flat)
            .expect("k x n values")
            .into_pyarray(py))
    }

    /// What the set-up did: vertices, faces, flips, time, mean_edge, spacing, has_boundary,
    /// refined_vertices and refined_min_angle (degrees; 0 without refinement).
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.inner.stats();
        let d = PyDict::new(py);
        d.set_item("vertices", s.vertices)?;
        d.set_item("faces", s.faces)?;
        d.set_item("flips", s.flips)?;
        d.set_item("time", s.time)?;
        d.set_item("mean_edge", s.mean_edge)?;
        d.set_item("spacing", s.spacing)?;
        d.set_item("has_boundary", s.has_boundary)?;
        d.set_item("refined_vertices", s.refine.inserted + s.refine.split)?;
        d.set_item("refined_min_angle", s.refine.min_angle_degrees)?;
        Ok(d)
    }

    /// Vertices.
    #[getter]
    fn n_vertices(&self) -> usize {
        self.n
    }
}

use numpy::IntoPyArray;

/// Exact polyhedral geodesic distances and shortest paths (window propagation).
#[pyclass(module = "bdmorph._bdmorph")]
pub struct ExactGeodesics {
    inner: Exact,
    n: usize,
}

#[pymethods]
impl ExactGeodesics {
    #[new]
    fn new(v: PyReadonlyArray2<'_, f64>, f: PyReadonlyArray2<'_, i64>) -> PyResult<ExactGeodesics> {
        let mesh = arrays::surface(&v, &f)?;
        let n = mesh.positions.len();
        let inner = Exact::new(&mesh).map_err(errors::geodesic)?;
        Ok(ExactGeodesics { inner, n })
    }

    /// The exact distance of every vertex from the nearest of `sources`, an array of n.
    fn distance<'py>(
        &mut self,
        py: Python<'py>,
        sources: PyReadonlyArray1<'_, i64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let sources = sources_of(&sources, self.n)?;
        let inner = &mut self.inner;
        let d = py
            .detach(|| inner.distance(&sources))
            .map_err(errors::geodesic)?;
        Ok(arrays::out1(py, d))
    }

    /// The shortest path from vertex `a` to vertex `b`, as a k x 3 array of points.
    fn path<'py>(
        &mut self,
        py: Python<'py>,
        a: i64,
        b: i64,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let index = |v: i64, name: &str| -> PyResult<u32> {
            u32::try_from(v)
                .ok()
                .filter(|&v| (v as usize) < self.n)
                .ok_or_else(|| {
                    errors::geodesic(format!(
                        "{name}: vertex {v} does not exist (the mesh has {} vertices, numbered from 0)",
                        self.n
                    ))
                })
        };
        let (a, b) = (index(a, "a")?, index(b, "b")?);
        let inner = &mut self.inner;
        let path = py.detach(|| inner.path(a, b)).map_err(errors::geodesic)?;
        let k = path.points.len();
        let flat: Vec<f64> = path.points.iter().flat_map(|p| p.position).collect();
        Ok(numpy::ndarray::Array2::from_shape_vec((k, 3), flat)
            .expect("k x 3 values")
            .into_pyarray(py))
    }

    /// Windows made by the last query.
    #[getter]
    fn windows(&self) -> usize {
        self.inner.stats().windows
    }

    /// Vertices.
    #[getter]
    fn n_vertices(&self) -> usize {
        self.n
    }
}
