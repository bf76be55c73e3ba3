//! `bdmorph._bdmorph`: the compiled half of the Python package (`python/bdmorph` is the
//! other: it checks and converts the inputs, then calls these). Arrays come in as C-ordered
//! float64 / int64 NumPy arrays and go out as new float64 arrays; every solve releases the GIL;
//! every error is a Python exception (a `ValueError` subclass) carrying the message the
//! command line prints.

mod arrays;
mod deform;
mod errors;
mod geodesic;
mod inbetween;
mod morph;
mod param;
mod picture;
mod project;
mod threads;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _bdmorph(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add_class::<morph::Morph>()?;
    m.add_class::<morph::Blend>()?;
    m.add_class::<morph::Path>()?;
    m.add_class::<geodesic::HeatGeodesics>()?;
    m.add_class::<geodesic::ExactGeodesics>()?;
    m.add_class::<deform::Deformer>()?;
    m.add_class::<project::Project>()?;
    m.add_function(wrap_pyfunction!(param::parameterize, m)?)?;
    m.add_function(wrap_pyfunction!(param::bounded_distortion, m)?)?;
    m.add_function(wrap_pyfunction!(picture::mesh_from_image, m)?)?;
    m.add_function(wrap_pyfunction!(picture::read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(picture::write_obj, m)?)?;
    m.add_function(wrap_pyfunction!(inbetween::compatible_mesh, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
