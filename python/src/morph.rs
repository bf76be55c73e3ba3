//! `Morph`, `Blend` and `Path`: frames computed by the compiled engine, the GIL released.

use numpy::{PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyBaseException;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use bdmorph::{Easing, FrameStats, MorphOptions, PathOptions, PlanarMesh};

use crate::arrays;
use crate::errors;
use crate::threads::Threads;

/// The options every morph takes.
fn options(
    tolerance: Option<f64>,
    max_iterations: Option<u32>,
    allow_inverted: bool,
    warm_start: bool,
    placement: &str,
) -> PyResult<MorphOptions> {
    let placement: bdmorph::Placement = placement.parse().map_err(errors::MorphError::new_err)?;
    let mut o = MorphOptions::default()
        .with_allow_inverted(allow_inverted)
        .with_warm_start(warm_start)
        .with_placement(placement);
    if let Some(t) = tolerance {
        if !(t.is_finite() && t > 0.0) {
            return Err(errors::MorphError::new_err(format!(
                "tolerance must be a finite number > 0, not {t}"
            )));
        }
        o = o.with_tolerance(t);
    }
    if let Some(n) = max_iterations {
        if n == 0 {
            return Err(errors::MorphError::new_err(
                "max_iterations must be at least 1",
            ));
        }
        o = o.with_max_iterations(n);
    }
    Ok(o)
}

/// What a batch (`frames`) does with a frame that cannot be computed: `"raise"` the error
/// (its message led by which frame), or `"nan"`: fill that frame with NaN, go on, and list
/// the failure.
#[derive(Clone, Copy, PartialEq, Eq)]
enum OnError {
    Raise,
    Nan,
}

impl OnError {
    fn parse(s: &str) -> PyResult<OnError> {
        match s {
            "raise" => Ok(OnError::Raise),
            "nan" => Ok(OnError::Nan),
            other => Err(errors::MorphError::new_err(format!(
                "on_error must be 'raise' or 'nan', not '{other}'"
            ))),
        }
    }
}

/// A batch's frames (flattened), the last good frame's statistics and the failures (index,
/// error); or, with [`OnError::Raise`], the first failure.
type Batch = (
    Vec<f64>,
    Option<FrameStats>,
    Vec<(usize, bdmorph::MorphError)>,
);

/// Solves `count` frames of `n` vertices, frame `i` by `solve(i, buffer)`.
fn batch(
    count: usize,
    n: usize,
    buffer: &mut [[f64; 2]],
    on_error: OnError,
    mut solve: impl FnMut(usize, &mut [[f64; 2]]) -> Result<FrameStats, bdmorph::MorphError>,
) -> Result<Batch, (usize, bdmorph::MorphError)> {
    let mut flat = Vec::with_capacity(count * n * 2);
    let mut last = None;
    let mut failures = Vec::new();
    for i in 0..count {
        match solve(i, buffer) {
            Ok(stats) => {
                last = Some(stats);
                flat.extend(buffer.iter().flatten());
            }
            Err(e) if on_error == OnError::Nan => {
                failures.push((i, e));
                flat.extend(std::iter::repeat_n(f64::NAN, n * 2));
            }
            Err(e) => return Err((i, e)),
        }
    }
    Ok((flat, last, failures))
}

/// A batch's result for Python: the `k x n x 2` frames and the failures as
/// `(index, exception)` pairs.
type Frames<'py> = (Bound<'py, PyArray3<f64>>, Vec<(usize, Py<PyBaseException>)>);

/// The failures of a batch as `(index, exception)` pairs.
fn failures(
    py: Python<'_>,
    f: Vec<(usize, bdmorph::MorphError)>,
) -> Vec<(usize, Py<PyBaseException>)> {
    f.into_iter()
        .map(|(i, e)| (i, errors::morph(e).into_value(py)))
        .collect()
}

/// Checks that every pose lists as many vertices as the first, before any mesh is built (a
/// short pose would otherwise be blamed on `F`).
fn same_counts(poses: &[(&str, &PyReadonlyArray2<'_, f64>)]) -> PyResult<()> {
    let Some((first, v)) = poses.first() else {
        return Ok(());
    };
    let n = v.as_array().nrows();
    for (name, v) in &poses[1..] {
        let m = v.as_array().nrows();
        if m != n {
            return Err(errors::mesh(format!(
                "{name} has {m} vertices but {first} has {n}: every pose lists the same vertices, in the same order"
            )));
        }
    }
    Ok(())
}

/// A frame's statistics as a dict (`t`, `newton_iterations`, `factorizations`,
/// `cg_iterations`, `gradient_norm`, `flipped_triangles`, `max_conformal_distortion`,
/// `seconds`).
fn stats_dict<'py>(
    py: Python<'py>,
    s: Option<&FrameStats>,
) -> PyResult<Option<Bound<'py, PyDict>>> {
    let Some(s) = s else { return Ok(None) };
    let d = PyDict::new(py);
    d.set_item("t", s.t)?;
    d.set_item("newton_iterations", s.newton_iterations)?;
    d.set_item("factorizations", s.factorizations)?;
    d.set_item("cg_iterations", s.cg_iterations)?;
    d.set_item("gradient_norm", s.gradient_norm)?;
    d.set_item("flipped_triangles", s.flipped_triangles)?;
    d.set_item("max_conformal_distortion", s.max_conformal_distortion)?;
    d.set_item("seconds", s.seconds)?;
    Ok(Some(d))
}

/// Keyframes sharing the triangles `f`.
fn keyframes(
    vs: &[PyReadonlyArray2<'_, f64>],
    f: &PyReadonlyArray2<'_, i64>,
    allow_inverted: bool,
) -> PyResult<Vec<PlanarMesh>> {
    let names: Vec<String> = (0..vs.len()).map(|i| format!("keyframe {i}")).collect();
    let poses: Vec<(&str, &PyReadonlyArray2<'_, f64>)> =
        names.iter().map(String::as_str).zip(vs).collect();
    same_counts(&poses)?;
    vs.iter()
        .enumerate()
        .map(|(i, v)| arrays::planar(v, f, &format!("keyframe {i}"), allow_inverted))
        .collect()
}

/// A morph between two poses of one planar mesh.
#[pyclass(module = "bdmorph._bdmorph")]
pub struct Morph {
    inner: bdmorph::Morph,
    threads: Threads,
    n: usize,
    buffer: Vec<[f64; 2]>,
    stats: Option<FrameStats>,
}

#[pymethods]
impl Morph {
    #[new]
    #[pyo3(signature = (v0, v1, f, tolerance=None, max_iterations=None, allow_inverted=false, warm_start=true, threads=None, placement="anchor"))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        v0: PyReadonlyArray2<'_, f64>,
        v1: PyReadonlyArray2<'_, f64>,
        f: PyReadonlyArray2<'_, i64>,
        tolerance: Option<f64>,
        max_iterations: Option<u32>,
        allow_inverted: bool,
        warm_start: bool,
        threads: Option<usize>,
        placement: &str,
    ) -> PyResult<Morph> {
        let options = options(
            tolerance,
            max_iterations,
            allow_inverted,
            warm_start,
            placement,
        )?;
        same_counts(&[("V0", &v0), ("V1", &v1)])?;
        let source = arrays::planar(&v0, &f, "V0", allow_inverted)?;
        let target = arrays::planar(&v1, &f, "V1", allow_inverted)?;
        let n = source.positions.len();
        let threads = Threads::new(threads)?;
        let inner = py
            .detach(|| threads.run(|| bdmorph::Morph::new(&source, &target, options)))
            .map_err(errors::morph)?;
        Ok(Morph {
            inner,
            threads,
            n,
            buffer: vec![[0.0; 2]; n],
            stats: None,
        })
    }

    /// The frame at `t` (0: V0, 1: V1) as an n x 2 array.
    fn frame<'py>(&mut self, py: Python<'py>, t: f64) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (inner, buffer, threads) = (&mut self.inner, &mut self.buffer, &self.threads);
        let stats = py
            .detach(|| threads.run(|| inner.frame_into(t, buffer)))
            .map_err(errors::morph)?;
        self.stats = Some(stats);
        Ok(arrays::out2(py, &self.buffer))
    }

    /// The frames at each of `ts` as a k x n x 2 array, and the failures (`on_error="nan"`:
    /// those frames are NaN) as `(index, exception)` pairs.
    #[pyo3(signature = (ts, on_error="raise"))]
    fn frames<'py>(
        &mut self,
        py: Python<'py>,
        ts: PyReadonlyArray1<'_, f64>,
        on_error: &str,
    ) -> PyResult<Frames<'py>> {
        let on_error = OnError::parse(on_error)?;
        let ts = ts.as_array().to_vec();
        let (n, inner) = (self.n, &mut self.inner);
        let (buffer, threads) = (&mut self.buffer, &self.threads);
        let (flat, last, failed) = py
            .detach(|| {
                threads.run(|| {
                    batch(ts.len(), n, buffer, on_error, |i, out| {
                        inner.frame_into(ts[i], out)
                    })
                })
            })
            .map_err(|(i, e)| errors::morph_at(e, &format!("ts[{i}]")))?;
        if last.is_some() {
            self.stats = last;
        }
        Ok((
            arrays::out_frames(py, ts.len(), n, flat),
            failures(py, failed),
        ))
    }

    /// The last frame's statistics (None before the first frame).
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        stats_dict(py, self.stats.as_ref())
    }

    /// Threads of the pool the frames are solved in.
    #[getter]
    fn threads(&self) -> usize {
        self.threads.count()
    }

    /// The per-triangle conformal distortion of the last frame from V0.
    #[getter]
    fn distortion<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        arrays::out1(py, self.inner.distortion().to_vec())
    }

    /// Vertices.
    #[getter]
    fn n_vertices(&self) -> usize {
        self.n
    }
}

/// A blend of several poses by weights.
#[pyclass(module = "bdmorph._bdmorph")]
pub struct Blend {
    inner: bdmorph::Blend,
    threads: Threads,
    n: usize,
    k: usize,
    buffer: Vec<[f64; 2]>,
    stats: Option<FrameStats>,
}

#[pymethods]
impl Blend {
    #[new]
    #[pyo3(signature = (keyframes, f, tolerance=None, max_iterations=None, allow_inverted=false, warm_start=true, threads=None, placement="anchor"))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        keyframes: Vec<PyReadonlyArray2<'_, f64>>,
        f: PyReadonlyArray2<'_, i64>,
        tolerance: Option<f64>,
        max_iterations: Option<u32>,
        allow_inverted: bool,
        warm_start: bool,
        threads: Option<usize>,
        placement: &str,
    ) -> PyResult<Blend> {
        let options = options(
            tolerance,
            max_iterations,
            allow_inverted,
            warm_start,
            placement,
        )?;
        let keys = self::keyframes(&keyframes, &f, allow_inverted)?;
        let n = keys.first().map_or(0, |k| k.positions.len());
        let k = keys.len();
        let threads = Threads::new(threads)?;
        let inner = py
            .detach(|| threads.run(|| bdmorph::Blend::with_options(&keys, options)))
            .map_err(errors::morph)?;
        Ok(Blend {
            inner,
            threads,
            n,
            k,
            buffer: vec![[0.0; 2]; n],
            stats: None,
        })
    }

    /// The blend with `weights` (one per keyframe, summing to 1) as an n x 2 array.
    fn frame<'py>(
        &mut self,
        py: Python<'py>,
        weights: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let w = weights.as_array().to_vec();
        let (inner, buffer, threads) = (&mut self.inner, &mut self.buffer, &self.threads);
        let stats = py
            .detach(|| threads.run(|| inner.frame_weights_into(&w, buffer)))
            .map_err(errors::morph)?;
        self.stats = Some(stats);
        Ok(arrays::out2(py, &self.buffer))
    }

    /// The blends for each row of `weights` (k x keyframes) as a k x n x 2 array, and the
    /// failures (`on_error="nan"`: those frames are NaN) as `(index, exception)` pairs.
    #[pyo3(signature = (weights, on_error="raise"))]
    fn frames<'py>(
        &mut self,
        py: Python<'py>,
        weights: PyReadonlyArray2<'_, f64>,
        on_error: &str,
    ) -> PyResult<Frames<'py>> {
        let on_error = OnError::parse(on_error)?;
        let w = weights.as_array();
        if w.ncols() != self.k {
            return Err(errors::MorphError::new_err(format!(
                "weights must be k x {} (one column per keyframe), not {} x {}",
                self.k,
                w.nrows(),
                w.ncols()
            )));
        }
        let rows: Vec<Vec<f64>> = w.rows().into_iter().map(|r| r.to_vec()).collect();
        let (n, inner) = (self.n, &mut self.inner);
        let (buffer, threads) = (&mut self.buffer, &self.threads);
        let (flat, last, failed) = py
            .detach(|| {
                threads.run(|| {
                    batch(rows.len(), n, buffer, on_error, |i, out| {
                        inner.frame_weights_into(&rows[i], out)
                    })
                })
            })
            .map_err(|(i, e)| errors::morph_at(e, &format!("weights row {i}")))?;
        if last.is_some() {
            self.stats = last;
        }
        Ok((
            arrays::out_frames(py, rows.len(), n, flat),
            failures(py, failed),
        ))
    }

    /// The last frame's statistics (None before the first frame).
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        stats_dict(py, self.stats.as_ref())
    }

    /// Threads of the pool the frames are solved in.
    #[getter]
    fn threads(&self) -> usize {
        self.threads.count()
    }

    /// Keyframes.
    #[getter]
    fn n_keyframes(&self) -> usize {
        self.k
    }
}

/// A path through several poses, each segment with its duration and easing.
#[pyclass(module = "bdmorph._bdmorph")]
pub struct Path {
    inner: bdmorph::KeyframePath,
    threads: Threads,
    n: usize,
    buffer: Vec<[f64; 2]>,
    stats: Option<FrameStats>,
}

#[pymethods]
impl Path {
    #[new]
    #[pyo3(signature = (keyframes, f, durations=None, easings=None, tolerance=None, max_iterations=None, allow_inverted=false, warm_start=true, threads=None, placement="anchor"))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        keyframes: Vec<PyReadonlyArray2<'_, f64>>,
        f: PyReadonlyArray2<'_, i64>,
        durations: Option<Vec<f64>>,
        easings: Option<Vec<String>>,
        tolerance: Option<f64>,
        max_iterations: Option<u32>,
        allow_inverted: bool,
        warm_start: bool,
        threads: Option<usize>,
        placement: &str,
    ) -> PyResult<Path> {
        let morph = options(
            tolerance,
            max_iterations,
            allow_inverted,
            warm_start,
            placement,
        )?;
        let keys = self::keyframes(&keyframes, &f, allow_inverted)?;
        let n = keys.first().map_or(0, |k| k.positions.len());
        let mut options = PathOptions::default().with_morph(morph);
        if let Some(d) = durations {
            options = options.with_durations(d);
        }
        if let Some(e) = easings {
            let parsed: Result<Vec<Easing>, _> = e.iter().map(|s| s.parse::<Easing>()).collect();
            options = options
                .with_easings(parsed.map_err(|e| errors::MorphError::new_err(e.to_string()))?);
        }
        let threads = Threads::new(threads)?;
        let inner = py
            .detach(|| threads.run(|| bdmorph::KeyframePath::with_options(&keys, options)))
            .map_err(errors::morph)?;
        Ok(Path {
            inner,
            threads,
            n,
            buffer: vec![[0.0; 2]; n],
            stats: None,
        })
    }

    /// The frame at `t` in [0, 1] along the whole path as an n x 2 array.
    fn frame<'py>(&mut self, py: Python<'py>, t: f64) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (inner, buffer, threads) = (&mut self.inner, &mut self.buffer, &self.threads);
        let stats = py
            .detach(|| threads.run(|| inner.frame_into(t, buffer)))
            .map_err(errors::morph)?;
        self.stats = Some(stats);
        Ok(arrays::out2(py, &self.buffer))
    }

    /// The frames at each of `ts` as a k x n x 2 array, and the failures (`on_error="nan"`:
    /// those frames are NaN) as `(index, exception)` pairs.
    #[pyo3(signature = (ts, on_error="raise"))]
    fn frames<'py>(
        &mut self,
        py: Python<'py>,
        ts: PyReadonlyArray1<'_, f64>,
        on_error: &str,
    ) -> PyResult<Frames<'py>> {
        let on_error = OnError::parse(on_error)?;
        let ts = ts.as_array().to_vec();
        let (n, inner) = (self.n, &mut self.inner);
        let (buffer, threads) = (&mut self.buffer, &self.threads);
        let (flat, last, failed) = py
            .detach(|| {
                threads.run(|| {
                    batch(ts.len(), n, buffer, on_error, |i, out| {
                        inner.frame_into(ts[i], out)
                    })
                })
            })
            .map_err(|(i, e)| errors::morph_at(e, &format!("ts[{i}]")))?;
        if last.is_some() {
            self.stats = last;
        }
        Ok((
            arrays::out_frames(py, ts.len(), n, flat),
            failures(py, failed),
        ))
    }

    /// The path's `t` at each keyframe.
    #[getter]
    fn keyframe_times(&self) -> Vec<f64> {
        self.inner.keyframe_times().to_vec()
    }

    /// The last frame's statistics (None before the first frame).
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        stats_dict(py, self.stats.as_ref())
    }

    /// Threads of the pool the frames are solved in.
    #[getter]
    fn threads(&self) -> usize {
        self.threads.count()
    }
}
