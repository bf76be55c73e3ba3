//! `compatible_mesh`: one mesh of drawing A laid over drawing B, for in-betweens.

use std::path::PathBuf;

use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use bdmorph::inbetween::{InbetweenOptions, Match};

use crate::arrays;
use crate::errors;

/// `(VA, F, VB, report)`.
type Compatible<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<i64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyDict>,
);

/// The compatible mesh of drawings `a` and `b` (pictures with transparency): `(VA, F, VB,
/// report)`, VA and VB n x 2 in each picture's pixels (y up), F m x 3, every triangle
/// counter-clockwise in both. `matches` (k x 4: AX, AY, BX, BY in pixels from each
/// picture's top-left corner) pairs points of A with the points of B they become.
#[pyfunction]
#[pyo3(signature = (a, b, matches=None, vertices=2000))]
pub fn compatible_mesh<'py>(
    py: Python<'py>,
    a: PathBuf,
    b: PathBuf,
    matches: Option<PyReadonlyArray2<'_, f64>>,
    vertices: usize,
) -> PyResult<Compatible<'py>> {
    let pairs: Vec<Match> = match &matches {
        None => Vec::new(),
        Some(m) => {
            let m = m.as_array();
            if m.ncols() != 4 {
                return Err(errors::inbetween(format!(
                    "matches must be k x 4 (AX, AY, BX, BY), not k x {}",
                    m.ncols()
                )));
            }
            m.rows()
                .into_iter()
                .enumerate()
                .map(|(k, r)| {
                    if r.iter().all(|v| v.is_finite()) {
                        Ok(Match {
                            a: [r[0], r[1]],
                            b: [r[2], r[3]],
                        })
                    } else {
                        Err(errors::inbetween(format!(
                            "matches row {k} holds a value that is not a finite number"
                        )))
                    }
                })
                .collect::<PyResult<_>>()?
        }
    };
    let options = InbetweenOptions::default().with_vertices(vertices);
    let made = py
        .detach(|| {
            let read = |p: &PathBuf| {
                bdmorph::render::raster::read_image(p).map_err(|e| format!("{}: {e}", p.display()))
            };
            let (ia, ib) = (read(&a)?, read(&b)?);
            bdmorph::inbetween::compatible_mesh(&ia, &ib, &pairs, &options)
                .map_err(|e| e.to_string())
        })
        .map_err(errors::inbetween)?;
    let r = &made.report;
    let report = PyDict::new(py);
    report.set_item("vertices", r.vertices)?;
    report.set_item("faces", r.faces)?;
    report.set_item("max_distortion", r.max_distortion)?;
    report.set_item("outline_error", r.outline_error)?;
    report.set_item("tolerance", (r.tolerance[0], r.tolerance[1]))?;
    report.set_item("seconds", r.seconds)?;
    let list = PyList::empty(py);
    for p in &r.pairs {
        let d = PyDict::new(py);
        d.set_item("on_outline", p.on_outline)?;
        d.set_item("met", p.met)?;
        d.set_item("error", p.error)?;
        d.set_item("reason", p.reason.as_deref())?;
        list.append(d)?;
    }
    report.set_item("pairs", list)?;
    Ok((
        arrays::out2(py, &made.mesh.positions),
        arrays::out_faces(py, &made.mesh.faces),
        arrays::out2(py, &made.positions_b),
        report,
    ))
}
