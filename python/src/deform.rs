//! `Deformer`: posing a planar mesh by handles (kvf, arap, bounded, sd), factored once per
//! set of pins (sd: once per mesh), each drag warm-started from the last pose.

use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use bdmorph::deform::{
    ArapOptions, BoundedPoseOptions, DragReport, DragStatus, KvfOptions, PoseMethod as Method,
    SdOptions,
};

use crate::arrays;
use crate::errors;

/// Refuses a handle weight (kvf, sd) that is not a finite number > 0.
fn check_weight(w: f64) -> PyResult<()> {
    if w.is_finite() && w > 0.0 {
        Ok(())
    } else {
        Err(errors::deform(format!(
            "weight must be a finite number > 0, not {w}"
        )))
    }
}

/// A planar mesh prepared for posing by handles.
#[pyclass(module = "bdmorph._bdmorph")]
pub struct Deformer {
    inner: bdmorph::deform::Deformer,
    n: usize,
    report: Option<DragReport>,
}

#[pymethods]
impl Deformer {
    #[new]
    #[pyo3(signature = (v, f, method="kvf", weight=None, max_distortion=None, iterations=None, tolerance=None, stiffness=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        v: PyReadonlyArray2<'_, f64>,
        f: PyReadonlyArray2<'_, i64>,
        method: &str,
        weight: Option<f64>,
        max_distortion: Option<f64>,
        iterations: Option<u32>,
        tolerance: Option<f64>,
        stiffness: Option<PyReadonlyArray1<'_, f64>>,
    ) -> PyResult<Deformer> {
        let mesh = arrays::planar(&v, &f, "V", false)?;
        if weight.is_some() && !matches!(method, "kvf" | "sd") {
            return Err(errors::deform(
                "only methods 'kvf' and 'sd' have a handle weight",
            ));
        }
        if max_distortion.is_some() && method != "bounded" {
            return Err(errors::deform("only method 'bounded' has max_distortion"));
        }
        if tolerance.is_some() && method == "bounded" {
            return Err(errors::deform(
                "method 'bounded' stops at its bound: it has no tolerance",
            ));
        }
        if iterations == Some(0) {
            return Err(errors::deform("iterations must be at least 1"));
        }
        // Refused here, each by its name (the library would find a bad weight only when the
        // pins are set, and takes any tolerance).
        if let Some(w) = weight {
            check_weight(w)?;
        }
        if let Some(k) = max_distortion {
            if !(k.is_finite() && k >= 1.0) {
                return Err(errors::deform(format!(
                    "max_distortion must be a finite number >= 1, not {k}"
                )));
            }
        }
        if let Some(t) = tolerance {
            if !(t.is_finite() && t >= 0.0) {
                return Err(errors::deform(format!(
                    "tolerance must be a finite number >= 0, not {t}"
                )));
            }
        }
        let method = match method {
            "kvf" => {
                let mut o = KvfOptions::default();
                if let Some(w) = weight {
                    o = o.with_weight(w);
                }
                if let Some(n) = iterations {
                    o = o.with_iterations(n);
                }
                if let Some(t) = tolerance {
                    o = o.with_tolerance(t);
                }
                Method::Kvf(o)
            }
            "arap" => {
                let mut o = ArapOptions::default();
                if let Some(n) = iterations {
                    o = o.with_iterations(n);
                }
                if let Some(t) = tolerance {
                    o = o.with_tolerance(t);
                }
                Method::Arap(o)
            }
            "bounded" => {
                let Some(k) = max_distortion else {
                    return Err(errors::deform(
                        "method 'bounded' needs max_distortion (the bound K >= 1)",
                    ));
                };
                let mut o = BoundedPoseOptions::new(k);
                if let Some(n) = iterations {
                    o = o.with_iterations(n);
                }
                Method::Bounded(o)
            }
            "sd" => {
                let mut o = SdOptions::default();
                if let Some(w) = weight {
                    o = o.with_weight(w);
                }
                if let Some(n) = iterations {
                    o = o.with_iterations(n);
                }
                if let Some(t) = tolerance {
                    o = o.with_tolerance(t);
                }
                Method::Sd(o)
            }
            other => {
                return Err(errors::deform(format!(
                    "unknown method '{other}' (use kvf, arap, bounded or sd)"
                )))
            }
        };
        let n = mesh.positions.len();
        let stiffness = stiffness.map(|w| w.as_array().to_vec());
        let inner = py
            .detach(|| {
                bdmorph::deform::Deformer::new(&mesh, method)?.with_stiffness(stiffness.as_deref())
            })
            .map_err(errors::deform)?;
        Ok(Deformer {
            inner,
            n,
            report: None,
        })
    }

    /// Sets the handles (vertex indices); the only step that factors.
    fn set_pins(&mut self, py: Python<'_>, pins: PyReadonlyArray1<'_, i64>) -> PyResult<()> {
        let pins = arrays::indices(&pins, self.n, "pins")?;
        let inner = &mut self.inner;
        py.detach(|| inner.set_pins(&pins)).map_err(errors::deform)
    }

    /// Moves the handles to `targets` (one row per pin, in the pins' order); returns the pose
    /// as an n x 2 array.
    fn drag<'py>(
        &mut self,
        py: Python<'py>,
        targets: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let targets = arrays::points2(&targets, "targets")?;
        let inner = &mut self.inner;
        let report = py.detach(|| inner.drag(&targets)).map_err(errors::deform)?;
        self.report = Some(report);
        Ok(arrays::out2(py, self.inner.positions()))
    }

    /// The handles' weight of kvf (refactors) or sd; the pins stay.
    fn set_weight(&mut self, py: Python<'_>, weight: f64) -> PyResult<()> {
        check_weight(weight)?;
        let inner = &mut self.inner;
        py.detach(|| inner.set_weight(weight))
            .map_err(errors::deform)
    }

    /// Each triangle's stiffness (a 1-D array, one weight per triangle, each finite and
    /// >= 1; None: all 1); refactors when pins are set (the pins and the pose stay).
    fn set_stiffness(
        &mut self,
        py: Python<'_>,
        weights: Option<PyReadonlyArray1<'_, f64>>,
    ) -> PyResult<()> {
        let weights = weights.map(|w| w.as_array().to_vec());
        let inner = &mut self.inner;
        py.detach(|| inner.set_stiffness(weights.as_deref()))
            .map_err(errors::deform)
    }

    /// The stiffness set (one weight per triangle), or None (all 1).
    #[getter]
    fn stiffness<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.inner.stiffness().map(|w| arrays::out1(py, w.to_vec()))
    }

    /// Puts the pose back to the rest shape.
    fn reset(&mut self) {
        self.inner.reset();
        self.report = None;
    }

    /// Replaces the pose (an n x 2 array), e.g. to undo.
    fn set_positions(&mut self, positions: PyReadonlyArray2<'_, f64>) -> PyResult<()> {
        let p = arrays::points2(&positions, "positions")?;
        self.inner.set_positions(&p).map_err(errors::deform)
    }

    /// The pose, n x 2.
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        arrays::out2(py, self.inner.positions())
    }

    /// The handles.
    #[getter]
    fn pins(&self) -> Vec<u32> {
        self.inner.pins().to_vec()
    }

    /// `kvf`, `arap`, `bounded` or `sd`.
    #[getter]
    fn method(&self) -> &'static str {
        self.inner.method().name()
    }

    /// What the last drag did (None before the first): iterations, energy, last_change,
    /// flipped_triangles, pin_residual, max_distortion, bound_met (None unless bounded),
    /// status ("moving", "converged", "stalled": no step could make progress, or
    /// "reverted": the method reached a point that is not finite, the pose before the drag
    /// is kept).
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(r) = &self.report else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("iterations", r.iterations)?;
        d.set_item("energy", r.energy)?;
        d.set_item("last_change", r.last_change)?;
        d.set_item("flipped_triangles", r.flipped_triangles)?;
        d.set_item("pin_residual", r.pin_residual)?;
        d.set_item("max_distortion", r.max_distortion)?;
        d.set_item("bound_met", r.bound_met)?;
        d.set_item(
            "status",
            match r.status {
                DragStatus::Converged => "converged",
                DragStatus::Stalled => "stalled",
                DragStatus::Reverted => "reverted",
                _ => "moving",
            },
        )?;
        Ok(Some(d))
    }
}
