//! The package's exceptions: `bdmorph.Error` (a `ValueError`) and one subclass per system,
//! each carrying the library's message (the command line's).
//!
//! They are declared in the module `bdmorph` (their `__module__`), where the package
//! re-exports them, so that pickle finds them by name: an error raised in a
//! `multiprocessing` or `ProcessPoolExecutor` worker reaches the parent as itself, its
//! message (its only argument) intact.

use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

create_exception!(
    bdmorph,
    Error,
    PyValueError,
    "Any error of bdmorph (a ValueError): the message says what and where."
);
create_exception!(
    bdmorph,
    MeshError,
    Error,
    "A mesh that cannot be used: shapes, indices, non-finite or inverted triangles..."
);
create_exception!(
    bdmorph,
    MorphError,
    Error,
    "A morph, blend or path that cannot be prepared or computed."
);
create_exception!(
    bdmorph,
    GeodesicError,
    Error,
    "Heat-method geodesics that cannot be prepared or queried."
);
create_exception!(
    bdmorph,
    ParamError,
    Error,
    "A parameterisation that cannot be computed."
);
create_exception!(
    bdmorph,
    DeformError,
    Error,
    "Posing by handles: bad pins, targets or options."
);
create_exception!(
    bdmorph,
    MeshingError,
    Error,
    "A picture or outline that cannot be meshed."
);
create_exception!(
    bdmorph,
    InbetweenError,
    Error,
    "Two drawings that cannot be given a compatible mesh: their topology, a point pair..."
);
create_exception!(
    bdmorph,
    FileError,
    Error,
    "A file that cannot be read or written."
);

/// Adds the exceptions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<Error>())?;
    m.add("MeshError", py.get_type::<MeshError>())?;
    m.add("MorphError", py.get_type::<MorphError>())?;
    m.add("GeodesicError", py.get_type::<GeodesicError>())?;
    m.add("ParamError", py.get_type::<ParamError>())?;
    m.add("DeformError", py.get_type::<DeformError>())?;
    m.add("MeshingError", py.get_type::<MeshingError>())?;
    m.add("FileError", py.get_type::<FileError>())?;
    m.add("InbetweenError", py.get_type::<InbetweenError>())?;
    Ok(())
}

/// A library message with the options it names spelled as Python's keywords
/// (`allow_inverted=True`, not the Rust option's name).
fn said(e: &impl std::fmt::Display) -> String {
    bdmorph::Spelling::PYTHON.respell(&e.to_string())
}

/// A mesh error as `MeshError`.
pub fn mesh(e: impl std::fmt::Display) -> PyErr {
    MeshError::new_err(said(&e))
}

/// A morph error as `MorphError`, or `MeshError` when it is about the meshes.
pub fn morph(e: bdmorph::MorphError) -> PyErr {
    match e {
        bdmorph::MorphError::Mesh(m) => MeshError::new_err(said(&m)),
        other => MorphError::new_err(said(&other)),
    }
}

/// A geodesic error.
pub fn geodesic(e: impl std::fmt::Display) -> PyErr {
    GeodesicError::new_err(said(&e))
}

/// A parameterisation error.
pub fn param(e: impl std::fmt::Display) -> PyErr {
    ParamError::new_err(said(&e))
}

/// A posing error.
pub fn deform(e: impl std::fmt::Display) -> PyErr {
    DeformError::new_err(said(&e))
}

/// A meshing error.
pub fn meshing(e: impl std::fmt::Display) -> PyErr {
    MeshingError::new_err(said(&e))
}

/// An in-betweens error.
pub fn inbetween(e: impl std::fmt::Display) -> PyErr {
    InbetweenError::new_err(said(&e))
}

/// A file error.
pub fn file(e: impl std::fmt::Display) -> PyErr {
    FileError::new_err(said(&e))
}

/// A morph error as [`morph`] gives it, its message led by `at` (which frame of a batch).
pub fn morph_at(e: bdmorph::MorphError, at: &str) -> PyErr {
    match e {
        bdmorph::MorphError::Mesh(m) => MeshError::new_err(format!("{at}: {}", said(&m))),
        other => MorphError::new_err(format!("{at}: {}", said(&other))),
    }
}

/// A morph error given in words (a project's animation) as `MorphError`.
pub fn morph_text(e: impl std::fmt::Display) -> PyErr {
    MorphError::new_err(said(&e))
}
