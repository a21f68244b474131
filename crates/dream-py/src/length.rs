//! Bindings of `dream_core::length`: lengths rounded as Python's `math.hypot`.

use dream_core::length;
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;

use crate::arrays::vector_of;
use crate::errors::PyDreamResult;

/// `math.hypot(x[i], y[i])` for the 1-D arrays `x` and `y` of one length.
#[pyfunction]
pub fn hypot<'py>(
    py: Python<'py>,
    x: Bound<'py, PyAny>,
    y: Bound<'py, PyAny>,
) -> PyDreamResult<Bound<'py, PyArray1<f64>>> {
    let xs = vector_of("x", &x, None)?;
    let ys = vector_of("y", &y, Some(xs.len()))?;
    Ok(py.detach(|| length::hypots(&xs, &ys)).into_pyarray(py))
}
