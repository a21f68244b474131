//! Checked copies of NumPy arrays into Rust vectors: the only place that looks at shapes.

use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};

use crate::errors::{shape_error, PyDreamResult};

/// Copies a `(rows, n)` float64 array (any strides) into a row-major vector; returns it with `n`.
pub fn rows_of(arg: &str, array: &PyReadonlyArray2<'_, f64>, rows: usize) -> PyDreamResult<(Vec<f64>, usize)> {
    let shape = array.shape();
    if shape[0] != rows {
        return Err(shape_error(arg, &format!("({rows}, n)"), shape));
    }
    let values = match array.as_slice() {
        Ok(slice) => slice.to_vec(),
        Err(_) => array.as_array().iter().copied().collect(),
    };
    Ok((values, shape[1]))
}

/// Fails unless the two arrays describe the same number of robots.
pub fn same_count(arg: &str, expected: usize, got: usize, rows: usize) -> PyDreamResult<()> {
    if expected == got {
        Ok(())
    } else {
        Err(shape_error(arg, &format!("({rows}, {expected})"), &[rows, got]))
    }
}
