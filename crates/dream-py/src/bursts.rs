//! Bindings of `dream_core::bursts`: loss bursts on radio links.

use dream_core::bursts as core;
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;

use crate::arrays::{indices_in, vector_in};
use crate::errors::PyDreamResult;

/// Whether each message over `links` (int64, one a message) is sent in a loss burst, and the links
/// in a burst after them (int64, strictly increasing, as `lossy` before), each message's link
/// flipping state where its draw (`draws`, uniform) is below `leave` (in a burst) or `enter`.
#[pyfunction]
pub fn bursts<'py>(
    py: Python<'py>,
    lossy: Bound<'py, PyAny>,
    links: Bound<'py, PyAny>,
    draws: Bound<'py, PyAny>,
    enter: f64,
    leave: f64,
) -> PyDreamResult<(Bound<'py, PyArray1<bool>>, Bound<'py, PyArray1<i64>>)> {
    let lossy = indices_in("lossy", &lossy)?;
    let links = indices_in("links", &links)?;
    let draws = vector_in("draws", &draws, Some(links.len()))?;
    let (lossy, links, draws): (&[i64], &[i64], &[f64]) = (&lossy, &links, &draws);
    let (now, after) = py.detach(|| core::bursts(lossy, links, draws, enter, leave))?;
    Ok((now.into_pyarray(py), after.into_pyarray(py)))
}
