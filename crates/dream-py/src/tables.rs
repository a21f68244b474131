//! Bindings of `dream_core::tables`: rows of per-robot tables, copied out and back.

use dream_core::tables::{self as core, Table, TableMut};
use numpy::{IntoPyArray, PyArray2, PyArrayMethods, PyReadonlyArray2, PyReadwriteArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::arrays::indices_of;
use crate::errors::{value_error, PyDreamResult};

/// The width of each of `tables` (shape and whether C-contiguous), which must all hold `n` rows
/// of uint8, C-contiguous.
fn widths_of<'a>(arg: &str, tables: impl Iterator<Item = (&'a [usize], bool)>, n: usize) -> PyDreamResult<Vec<usize>> {
    tables
        .enumerate()
        .map(|(t, (shape, contiguous))| {
            if !contiguous || shape[0] != n {
                return Err(value_error(format!(
                    "`{arg}` {t} must be a C-contiguous uint8 array of {n} rows, got shape {shape:?}{}",
                    if contiguous { "" } else { ", not contiguous" }
                )));
            }
            Ok(shape[1])
        })
        .collect()
}

/// The rows `rows` (increasing) of each of `tables` (C-contiguous `(n, width)` uint8, the bytes
/// of per-robot arrays): one `(len(rows), width)` uint8 array each.
#[pyfunction]
pub fn take_rows<'py>(
    py: Python<'py>,
    tables: Vec<PyReadonlyArray2<'py, u8>>,
    rows: Bound<'py, PyAny>,
) -> PyDreamResult<Vec<Bound<'py, PyArray2<u8>>>> {
    let rows = indices_of("rows", &rows)?;
    let Some(n) = tables.first().map(|t| t.shape()[0]) else {
        return Ok(Vec::new()); // no table: no rows to check against
    };
    let widths = widths_of("tables", tables.iter().map(|t| (t.shape(), t.is_c_contiguous())), n)?;
    let views: Vec<Table<'_>> = tables
        .iter()
        .zip(&widths)
        .map(|(table, &width)| Table {
            bytes: table.as_slice().unwrap_or_default(),
            width,
        })
        .collect();
    let taken = py.detach(|| core::take_rows(&views, n, &rows))?;
    taken
        .into_iter()
        .zip(widths)
        .map(|(bytes, width)| Ok(bytes.into_pyarray(py).reshape([rows.len(), width])?))
        .collect()
}

/// `values[t]` (C-contiguous `(len(rows), width)` uint8) written into each of `tables`
/// (C-contiguous `(n, width)` uint8, writable) at the rows `rows` (increasing).
#[pyfunction]
pub fn put_rows<'py>(
    py: Python<'py>,
    mut tables: Vec<PyReadwriteArray2<'py, u8>>,
    rows: Bound<'py, PyAny>,
    values: Vec<PyReadonlyArray2<'py, u8>>,
) -> PyDreamResult<()> {
    let rows = indices_of("rows", &rows)?;
    let Some(n) = tables.first().map(|t| t.shape()[0]) else {
        return Ok(());
    };
    let widths = widths_of("tables", tables.iter().map(|t| (t.shape(), t.is_c_contiguous())), n)?;
    widths_of(
        "values",
        values.iter().map(|v| (v.shape(), v.is_c_contiguous())),
        rows.len(),
    )?;
    let sources: Vec<&[u8]> = values.iter().map(|v| v.as_slice().unwrap_or_default()).collect();
    let mut views: Vec<TableMut<'_>> = tables
        .iter_mut()
        .zip(&widths)
        .map(|(table, &width)| TableMut {
            bytes: table.as_slice_mut().unwrap_or_default(),
            width,
        })
        .collect();
    py.detach(|| core::put_rows(&mut views, n, &rows, &sources))?;
    Ok(())
}
