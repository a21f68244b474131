//! Bindings of `dream_core::reduce`: a robot's neighbourhood summed, averaged, searched.

use dream_core::reduce::{self as core, Reduce};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

use crate::arrays::{flags_of, indices_in, indices_of, matrix_in, points_of, vector_of};
use crate::errors::{value_error, PyDreamResult};

/// `op` ("sum", "mean", "min" or "max") of each row's entries of `values` `(k, w)`: `(m, w)`;
/// with `index` `(e,)`, entry e is row `index[e]` of `values`.
#[pyfunction]
#[pyo3(signature = (values, offsets, op, index=None))]
pub fn segment_reduce<'py>(
    py: Python<'py>,
    values: Bound<'py, PyAny>,
    offsets: Bound<'py, PyAny>,
    op: &str,
    index: Option<Bound<'py, PyAny>>,
) -> PyDreamResult<Bound<'py, PyArray2<f64>>> {
    let op = match op {
        "sum" => Reduce::Sum,
        "mean" => Reduce::Mean,
        "min" => Reduce::Min,
        "max" => Reduce::Max,
        _ => return Err(value_error(format!("`op` must be sum, mean, min or max, got {op:?}"))),
    };
    let (values, width) = matrix_in("values", &values)?;
    let offsets = indices_in("offsets", &offsets)?;
    if width == 0 {
        return Err(value_error(
            "`values` must have at least one column, got shape (k, 0)".into(),
        ));
    }
    let index = index.map(|index| indices_in("index", &index)).transpose()?;
    let (v, o, i): (&[f64], &[i64], Option<&[i64]>) = (&values, &offsets, index.as_deref());
    let out = py.detach(|| core::reduce(v, width, o, i, op))?;
    let rows = offsets.len().saturating_sub(1);
    Ok(out.into_pyarray(py).reshape([rows, width])?)
}

/// Whether any entry of each row of `flags` `(k,)` is set: `(m,)` bool.
#[pyfunction]
pub fn segment_any<'py>(
    py: Python<'py>,
    flags: Bound<'py, PyAny>,
    offsets: Bound<'py, PyAny>,
) -> PyDreamResult<Bound<'py, PyArray1<bool>>> {
    let offsets = indices_of("offsets", &offsets)?;
    let total = offsets.last().copied().unwrap_or(0).max(0) as usize;
    let flags = flags_of("flags", &flags, total)?;
    Ok(py.detach(|| core::any(&flags, &offsets))?.into_pyarray(py))
}

/// The entry of each row with the smallest of `keys` `(e,)`, as an index into them, -1 for none:
/// `(m,)`; with `k`, each row's `k` smallest, smallest first, -1 in the slots left: `(m, k)`.
#[pyfunction]
#[pyo3(signature = (keys, offsets, k=None))]
pub fn segment_nearest<'py>(
    py: Python<'py>,
    keys: Bound<'py, PyAny>,
    offsets: Bound<'py, PyAny>,
    k: Option<usize>,
) -> PyDreamResult<Bound<'py, PyAny>> {
    let keys = vector_of("keys", &keys, None)?;
    let offsets = indices_of("offsets", &offsets)?;
    let Some(k) = k else {
        return Ok(py
            .detach(|| core::nearest(&keys, &offsets))?
            .into_pyarray(py)
            .into_any());
    };
    let out = py.detach(|| core::nearest_k(&keys, &offsets, k))?;
    let rows = offsets.len().saturating_sub(1);
    Ok(out.into_pyarray(py).reshape([rows, k])?.into_any())
}

/// Each row's `k` entries whose point of `points` `(e, 2)` lies nearest the row's origin of
/// `origins` `(m, 2)`, nearest first, -1 in the slots left: `(m, k)`; with `index` `(e,)`, entry
/// e's point is row `index[e]` of `points`.
#[pyfunction]
#[pyo3(signature = (points, offsets, origins, k, index=None))]
pub fn segment_nearest_to<'py>(
    py: Python<'py>,
    points: Bound<'py, PyAny>,
    offsets: Bound<'py, PyAny>,
    origins: Bound<'py, PyAny>,
    k: usize,
    index: Option<Bound<'py, PyAny>>,
) -> PyDreamResult<Bound<'py, PyArray2<i64>>> {
    let points = points_of::<2>("points", &points)?;
    let offsets = indices_of("offsets", &offsets)?;
    let origins = points_of::<2>("origins", &origins)?;
    let index = index.map(|index| indices_of("index", &index)).transpose()?;
    let out = py.detach(|| core::nearest_k_to(&points, &offsets, &origins, index.as_deref(), k))?;
    let rows = offsets.len().saturating_sub(1);
    Ok(out.into_pyarray(py).reshape([rows, k])?)
}
