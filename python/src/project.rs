//! `Project`: a project the studio saved (one mesh or a character in parts), read and animated
//! as the studio plays and exports it.

use std::path::PathBuf;

use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::arrays;
use crate::errors;

/// A saved studio project.
#[pyclass(module = "bdmorph._bdmorph")]
pub struct Project {
    doc: bdmorph::project::Project,
    animation: Option<bdmorph::project::Animation>,
    frame: Vec<[f64; 2]>,
}

#[pymethods]
impl Project {
    #[new]
    fn new(py: Python<'_>, path: PathBuf) -> PyResult<Project> {
        let doc = py
            .detach(|| bdmorph::project::Project::read(&path))
            .map_err(|e| errors::file(format!("{}: {e}", path.display())))?;
        let n = doc.mesh.positions.len();
        Ok(Project {
            doc,
            animation: None,
            frame: vec![[0.0; 2]; n],
        })
    }

    /// The rest mesh `(V, F)`.
    fn rest<'py>(&self, py: Python<'py>) -> (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>) {
        (
            arrays::out2(py, &self.doc.mesh.positions),
            arrays::out_faces(py, &self.doc.mesh.faces),
        )
    }

    /// The keyframes' times, in seconds.
    #[getter]
    fn times(&self) -> Vec<f64> {
        self.doc.keyframes.iter().map(|k| k.time).collect()
    }

    /// The last keyframe's time, in seconds.
    #[getter]
    fn duration(&self) -> f64 {
        self.doc.keyframes.last().map_or(0.0, |k| k.time)
    }

    /// The parts, bottom first: dicts of `name`, `vertices` and `faces` (`(first, end)`).
    #[getter]
    fn parts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for p in self.doc.parts.as_deref().unwrap_or(&[]) {
            let d = PyDict::new(py);
            d.set_item("name", &p.name)?;
            d.set_item("vertices", (p.vertices[0], p.vertices[1]))?;
            d.set_item("faces", (p.faces[0], p.faces[1]))?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// The joints, `k x 2` vertex pairs (int64).
    #[getter]
    fn joints<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let rows: Vec<Vec<i64>> = self
            .doc
            .joints
            .as_deref()
            .unwrap_or(&[])
            .iter()
            .map(|j| vec![i64::from(j[0]), i64::from(j[1])])
            .collect();
        if rows.is_empty() {
            return Ok(numpy::PyArray2::zeros(py, [0, 2], false));
        }
        numpy::PyArray2::from_vec2(py, &rows).map_err(|e| errors::mesh(e.to_string()))
    }

    /// The parts' names in draw order, bottom first (each drawn over the ones before it).
    #[getter]
    fn draw_order(&self) -> Vec<String> {
        self.doc
            .parts
            .as_deref()
            .unwrap_or(&[])
            .iter()
            .map(|p| p.name.clone())
            .collect()
    }

    /// The animation at `time` seconds (clamped to it): every vertex's position, `n x 2`.
    fn positions<'py>(
        &mut self,
        py: Python<'py>,
        time: f64,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.compute(py, time)?;
        Ok(arrays::out2(py, &self.frame))
    }

    /// The animation at `time` seconds: each part's positions by its name (one entry, `mesh`,
    /// for a project without parts).
    fn frame<'py>(&mut self, py: Python<'py>, time: f64) -> PyResult<Bound<'py, PyDict>> {
        self.compute(py, time)?;
        let out = PyDict::new(py);
        match self.doc.parts.as_deref() {
            Some(parts) if !parts.is_empty() => {
                for p in parts {
                    let (a, b) = (p.vertices[0] as usize, p.vertices[1] as usize);
                    out.set_item(&p.name, arrays::out2(py, &self.frame[a..b]))?;
                }
            }
            _ => out.set_item("mesh", arrays::out2(py, &self.frame))?,
        }
        Ok(out)
    }
}

impl Project {
    fn compute(&mut self, py: Python<'_>, time: f64) -> PyResult<()> {
        if !time.is_finite() {
            return Err(errors::morph_text(format!(
                "time must be a finite number, not {time}"
            )));
        }
        if self.animation.is_none() {
            let doc = &self.doc;
            let animation = py
                .detach(|| bdmorph::project::Animation::new(doc))
                .map_err(errors::morph_text)?;
            self.animation = Some(animation);
        }
        let (animation, frame) = (&mut self.animation, &mut self.frame);
        let animation = animation
            .as_mut()
            .ok_or_else(|| errors::morph_text("no animation"))?;
        py.detach(|| animation.frame_into(time, frame))
            .map_err(errors::morph_text)?;
        Ok(())
    }
}
