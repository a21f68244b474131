//! Bindings of `dream_core::guard`: the motion guard of the robots deciding now.

use dream_core::guard as core;
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;

use crate::arrays::{indices_in, vector_in};
use crate::errors::PyDreamResult;

/// `(m,)` bool: which robots stop, driving at `speeds` along `headings` `(m,)` towards the robots
/// they see at `dx`, `dy` (CSR rows by `offsets`), closer than `near` within `horizon`.
#[pyfunction]
#[pyo3(signature = (speeds, headings, offsets, dx, dy, *, near, horizon))]
#[allow(clippy::too_many_arguments)]
pub fn motion_guard<'py>(
    py: Python<'py>,
    speeds: Bound<'py, PyAny>,
    headings: Bound<'py, PyAny>,
    offsets: Bound<'py, PyAny>,
    dx: Bound<'py, PyAny>,
    dy: Bound<'py, PyAny>,
    near: f64,
    horizon: f64,
) -> PyDreamResult<Bound<'py, PyArray1<bool>>> {
    let speeds = vector_in("speeds", &speeds, None)?;
    let headings = vector_in("headings", &headings, Some(speeds.len()))?;
    let offsets = indices_in("offsets", &offsets)?;
    let dx = vector_in("dx", &dx, None)?;
    let dy = vector_in("dy", &dy, Some(dx.len()))?;
    let (speeds, headings, offsets, dx, dy): (&[f64], &[f64], &[i64], &[f64], &[f64]) =
        (&speeds, &headings, &offsets, &dx, &dy);
    let out = py.detach(|| core::stopping(speeds, headings, offsets, dx, dy, near, horizon))?;
    Ok(out.into_pyarray(py))
}
