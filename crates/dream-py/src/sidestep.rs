//! Bindings of `dream_core::sidestep`: the swarm engine's side-step counters and sides, read and
//! written in place at the rows deciding.

use dream_core::sidestep;
use numpy::{IntoPyArray, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

use crate::arrays::{flags_of, indices_in, points_in, vector_in, writable_in};
use crate::errors::PyDreamResult;

/// What the robots `rows` (increasing) ask HRVO for, `(k, 2)`: `want` `(k, 2)`, turned to each
/// robot's side in `sides` `(n,)` while its counter in `counters` `(n,)` int64 is above zero,
/// which counts down in place; with `steer` `(k,)` bool, only the rows it flags.
#[pyfunction]
#[pyo3(signature = (want, rows, counters, sides, steer=None))]
pub fn sidestep_ask<'py>(
    py: Python<'py>,
    want: Bound<'py, PyAny>,
    rows: Bound<'py, PyAny>,
    counters: Bound<'py, PyAny>,
    sides: Bound<'py, PyAny>,
    steer: Option<Bound<'py, PyAny>>,
) -> PyDreamResult<Bound<'py, PyArray2<f64>>> {
    let want = points_in::<2>("want", &want)?;
    let rows = indices_in("rows", &rows)?;
    let mut counters = writable_in::<i64>("counters", &counters, "int64", None)?;
    let counters = counters.as_slice_mut().unwrap_or_default(); // C-contiguous: checked
    let sides = vector_in("sides", &sides, Some(counters.len()))?;
    let steer = steer.map(|flags| flags_of("steer", &flags, rows.len())).transpose()?;
    let (want, rows, sides): (&[f64], &[i64], &[f64]) = (want.as_flattened(), &rows, &sides);
    let steer = steer.as_deref();
    let asked = py.detach(|| sidestep::ask(want, rows, counters, sides, steer))?;
    Ok(asked.into_pyarray(py).reshape([rows.len(), 2])?)
}

/// Marks the robots `rows` that HRVO stopped (`chosen` `(k, 2)` zero) though they wished to
/// move (`want` `(k, 2)`): in place, each counter in `counters` `(n,)` int64 set to `updates`
/// and each side in `sides` `(n,)` float64 to its right, or flipped if it was stepping aside;
/// with `steer` `(k,)` bool, only the rows it flags.
#[pyfunction]
#[pyo3(signature = (chosen, want, rows, counters, sides, updates, steer=None))]
#[allow(clippy::too_many_arguments)]
pub fn sidestep_mark<'py>(
    py: Python<'py>,
    chosen: Bound<'py, PyAny>,
    want: Bound<'py, PyAny>,
    rows: Bound<'py, PyAny>,
    counters: Bound<'py, PyAny>,
    sides: Bound<'py, PyAny>,
    updates: i64,
    steer: Option<Bound<'py, PyAny>>,
) -> PyDreamResult<()> {
    let chosen = points_in::<2>("chosen", &chosen)?;
    let want = points_in::<2>("want", &want)?;
    let rows = indices_in("rows", &rows)?;
    let mut counters = writable_in::<i64>("counters", &counters, "int64", None)?;
    let counters = counters.as_slice_mut().unwrap_or_default(); // C-contiguous: checked
    let mut sides = writable_in::<f64>("sides", &sides, "float64", Some(counters.len()))?;
    let sides = sides.as_slice_mut().unwrap_or_default();
    let steer = steer.map(|flags| flags_of("steer", &flags, rows.len())).transpose()?;
    let (chosen, want, rows): (&[f64], &[f64], &[i64]) = (chosen.as_flattened(), want.as_flattened(), &rows);
    let steer = steer.as_deref();
    py.detach(|| sidestep::mark(chosen, want, rows, counters, sides, updates, steer))?;
    Ok(())
}
