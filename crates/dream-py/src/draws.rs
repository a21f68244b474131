//! Bindings of `dream_core::draws`: counter-based random draws.

use dream_core::draws::{self as core, Key, Loss};
use numpy::{IntoPyArray, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

use crate::arrays::{count_of, indices_in, Values};
use crate::errors::{value_error, PyDreamResult};

/// The `(rows, columns)` uniform draws in [0, 1) of stream `stream` at step `step`: `keys` are
/// 1-D int64 arrays, each of the kind `kinds` gives it in turn: `a` one word for every draw (one
/// value), `r` one per row, `c` one per column.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn draws<'py>(
    py: Python<'py>,
    seed: u64,
    stream: i64,
    step: i64,
    keys: Vec<Bound<'py, PyAny>>,
    kinds: &str,
    rows: i64,
    columns: i64,
) -> PyDreamResult<Bound<'py, PyArray2<f64>>> {
    let (rows, columns) = (count_of("rows", rows)?, count_of("columns", columns)?);
    if kinds.len() != keys.len() {
        return Err(value_error(format!(
            "`kinds` names {} keys, but {} are given",
            kinds.len(),
            keys.len()
        )));
    }
    let words: Vec<Values<'py, i64>> = keys
        .iter()
        .map(|key| indices_in("keys", key))
        .collect::<PyDreamResult<_>>()?;
    let keys: Vec<Key<'_>> = kinds
        .chars()
        .zip(&words)
        .map(|(kind, words)| match (kind, &words[..]) {
            ('a', &[word]) => Ok(Key::All(word)),
            ('a', other) => Err(value_error(format!(
                "a key of kind `a` holds one word, got {}",
                other.len()
            ))),
            ('r', words) => Ok(Key::Row(words)),
            ('c', words) => Ok(Key::Column(words)),
            (other, _) => Err(value_error(format!(
                "`kinds` holds {other:?}: each key is `a`, `r` or `c`"
            ))),
        })
        .collect::<PyDreamResult<_>>()?;
    let table = py.detach(|| core::draws(seed, stream, step, &keys, rows, columns))?;
    Ok(table.into_pyarray(py).reshape([rows, columns])?)
}

/// A radio's loss as Python gives it, `(seed, stream, step, keep, per_metre)` (see `Loss`).
pub type LossArgs = (u64, i64, i64, f64, f64);

/// The loss of `args`, if any, checked.
pub fn loss_of(args: Option<LossArgs>) -> PyDreamResult<Option<Loss>> {
    Ok(args
        .map(|(seed, stream, step, keep, per_metre)| Loss::new(seed, stream, step, keep, per_metre))
        .transpose()?)
}
