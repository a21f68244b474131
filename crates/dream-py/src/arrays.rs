//! Checked copies of NumPy arrays into Rust values: the only place that looks at shapes.

use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};

use crate::errors::{shape_error, PyDreamResult};

fn values_of<D: numpy::ndarray::Dimension>(array: &numpy::PyReadonlyArray<'_, f64, D>) -> Vec<f64> {
    match array.as_slice() {
        Ok(slice) => slice.to_vec(),
        Err(_) => array.as_array().iter().copied().collect(),
    }
}

/// Copies a `(rows, n)` float64 array (any strides) into a row-major vector; returns it with `n`.
pub fn rows_of(arg: &str, array: &PyReadonlyArray2<'_, f64>, rows: usize) -> PyDreamResult<(Vec<f64>, usize)> {
    let shape = array.shape();
    if shape[0] != rows {
        return Err(shape_error(arg, &format!("({rows}, n)"), shape));
    }
    Ok((values_of(array), shape[1]))
}

/// Copies an `(n, width)` float64 array into `n` fixed-size rows.
pub fn points_of<const W: usize>(arg: &str, array: &PyReadonlyArray2<'_, f64>) -> PyDreamResult<Vec<[f64; W]>> {
    let shape = array.shape();
    if shape[1] != W {
        return Err(shape_error(arg, &format!("(n, {W})"), shape));
    }
    let values = values_of(array);
    Ok(values.chunks_exact(W).map(|c| std::array::from_fn(|k| c[k])).collect())
}

/// Copies a float64 vector, checking its length when `len` is given.
pub fn vector_of(arg: &str, array: &PyReadonlyArray1<'_, f64>, len: Option<usize>) -> PyDreamResult<Vec<f64>> {
    let shape = array.shape();
    if let Some(want) = len {
        if shape[0] != want {
            return Err(shape_error(arg, &format!("({want},)"), shape));
        }
    }
    Ok(values_of(array))
}

/// Fails unless the two arrays describe the same number of robots.
pub fn same_count(arg: &str, expected: usize, got: usize, rows: usize) -> PyDreamResult<()> {
    if expected == got {
        Ok(())
    } else {
        Err(shape_error(arg, &format!("({rows}, {expected})"), &[rows, got]))
    }
}
