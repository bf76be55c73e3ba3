//! `parameterize` and `bounded_distortion`: flattening a disk into the plane.

use numpy::{PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use bdmorph::param::bounded::{self, BoundedOptions};
use bdmorph::param::messages::{self, Spelling};
use bdmorph::param::{ParamMethod as Method, ParamOptions, Parameterization};

use crate::arrays;
use crate::errors;

/// Flattens a disk with `method`; returns `(uv, info)`.
#[pyfunction]
#[pyo3(signature = (v, f, method="arap", iterations=None, tolerance=None, collapse_barrier=None))]
pub fn parameterize<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'_, f64>,
    f: PyReadonlyArray2<'_, i64>,
    method: &str,
    iterations: Option<u32>,
    tolerance: Option<f64>,
    collapse_barrier: Option<f64>,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyDict>)> {
    let mesh = arrays::surface(&v, &f)?;
    let method: Method = method.parse().map_err(errors::param)?;
    let mut options = ParamOptions::default();
    if let Some(n) = iterations {
        options = options.with_iterations(n);
    }
    if let Some(t) = tolerance {
        if !(t.is_finite() && t >= 0.0) {
            return Err(errors::param(format!(
                "tolerance must be a finite number >= 0, not {t}"
            )));
        }
        options = options.with_tolerance(t);
    }
    if let Some(w) = collapse_barrier {
        options = options.with_collapse_barrier(w);
    }
    let name = method.name();
    let (uv, report, energies) = py
        .detach(|| {
            let mut p = Parameterization::new(&mesh, method, options.clone())?;
            let report = p.solve()?;
            Ok::<_, bdmorph::param::ParamError>((p.uv().to_vec(), report, p.energies()))
        })
        .map_err(errors::param)?;
    let info = PyDict::new(py);
    info.set_item("iterations", report.iterations)?;
    info.set_item("stop", report.stop.name())?;
    info.set_item("seconds", report.seconds)?;
    info.set_item("setup_seconds", report.setup_seconds)?;
    info.set_item("gradient_norm", report.gradient_norm)?;
    info.set_item("symmetric_dirichlet", energies.symmetric_dirichlet)?;
    info.set_item("arap", energies.arap)?;
    info.set_item("mips", energies.mips)?;
    info.set_item("flipped", energies.flipped)?;
    info.set_item("collapsed", energies.collapsed)?;
    info.set_item("max_distortion", energies.max_distortion)?;
    info.set_item(
        "message",
        messages::param_failure(name, &report, &energies, options, Spelling::PYTHON),
    )?;
    Ok((arrays::out2(py, &uv), info))
}

/// Flattens a disk with every triangle's conformal distortion at most `max_distortion`;
/// returns `(uv, info)`.
#[pyfunction]
#[pyo3(signature = (v, f, max_distortion, pin_vertices=None, pin_targets=None, init="tutte", iterations=None))]
#[allow(clippy::too_many_arguments)]
pub fn bounded_distortion<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'_, f64>,
    f: PyReadonlyArray2<'_, i64>,
    max_distortion: f64,
    pin_vertices: Option<PyReadonlyArray1<'_, i64>>,
    pin_targets: Option<PyReadonlyArray2<'_, f64>>,
    init: &str,
    iterations: Option<u32>,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyDict>)> {
    let mesh = arrays::surface(&v, &f)?;
    let n = mesh.positions.len();
    let pins: Vec<(u32, [f64; 2])> = match (pin_vertices, pin_targets) {
        (None, None) => Vec::new(),
        (Some(vs), Some(ts)) => {
            let vs = arrays::indices(&vs, n, "pins")?;
            let ts = arrays::points2(&ts, "pin targets")?;
            if vs.len() != ts.len() {
                return Err(errors::param(format!(
                    "{} pinned vertices but {} targets",
                    vs.len(),
                    ts.len()
                )));
            }
            vs.into_iter().zip(ts).collect()
        }
        _ => {
            return Err(errors::param(
                "give both the pinned vertices and their targets, or neither",
            ))
        }
    };
    let starts = match init {
        "tutte" => [Method::Tutte, Method::Lscm],
        "lscm" => [Method::Lscm, Method::Tutte],
        other => {
            return Err(errors::param(format!(
                "unknown start '{other}' (use tutte or lscm)"
            )))
        }
    };
    let mut options = BoundedOptions::new(max_distortion);
    if let Some(k) = iterations {
        options = options.with_iterations(k);
    }
    let flat = py
        .detach(|| bounded::flatten(&mesh, &pins, options, &starts, |_, _, _| {}))
        .map_err(errors::param)?;
    let report = flat.report();
    let info = PyDict::new(py);
    info.set_item("converged", report.converged)?;
    info.set_item("stalled", report.stalled)?;
    info.set_item("iterations", report.iterations)?;
    info.set_item("newton_iterations", report.newton_iterations)?;
    info.set_item("max_distortion", report.max_distortion)?;
    info.set_item("inverted", report.inverted)?;
    info.set_item("constraint_error", report.constraint_error)?;
    info.set_item("seconds", report.seconds)?;
    info.set_item("setup_seconds", flat.setup_seconds)?;
    info.set_item("start", flat.attempts[flat.kept].start.name())?;
    info.set_item("lower_bound", flat.lower_bound.bound)?;
    info.set_item("infeasible", flat.infeasible())?;
    info.set_item("worst", report.worst.clone())?;
    let message = (!report.converged)
        .then(|| messages::flattening_message(&flat, &|_| None, Spelling::PYTHON));
    info.set_item("message", message)?;
    Ok((arrays::out2(py, &flat.uv), info))
}
