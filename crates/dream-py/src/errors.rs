//! Maps core errors to Python exceptions: bad input is a `ValueError` naming the argument,
//! impossible geometry a `dream.errors.GeometryError` (a `ValueError` too), a buffer that could
//! not be allocated a `MemoryError`.

use dream_core::GeomError;
use pyo3::exceptions::{PyMemoryError, PyValueError};
use pyo3::PyErr;

pyo3::import_exception!(dream.errors, GeometryError);

/// Error of a binding: either a core error or one already raised on the Python side.
pub enum PyDreamError {
    Core(GeomError),
    Python(PyErr),
}

pub type PyDreamResult<T> = Result<T, PyDreamError>;

impl From<GeomError> for PyDreamError {
    fn from(err: GeomError) -> Self {
        Self::Core(err)
    }
}

impl From<PyErr> for PyDreamError {
    fn from(err: PyErr) -> Self {
        Self::Python(err)
    }
}

impl From<PyDreamError> for PyErr {
    fn from(err: PyDreamError) -> Self {
        match err {
            PyDreamError::Core(e @ GeomError::DegenerateObstacle(_)) => GeometryError::new_err(e.to_string()),
            PyDreamError::Core(e @ GeomError::OutOfMemory { .. }) => PyMemoryError::new_err(e.to_string()),
            PyDreamError::Core(e) => PyValueError::new_err(e.to_string()),
            PyDreamError::Python(e) => e,
        }
    }
}

/// A `ValueError` with `message`.
pub fn value_error(message: String) -> PyDreamError {
    PyDreamError::Python(PyValueError::new_err(message))
}

/// A `ValueError` for an array of the wrong shape.
pub fn shape_error(arg: &str, expected: &str, got: &[usize]) -> PyDreamError {
    PyDreamError::Python(PyValueError::new_err(format!(
        "`{arg}` must have shape {expected}, got {got:?}"
    )))
}
