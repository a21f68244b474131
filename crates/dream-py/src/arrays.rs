//! Checked reads of NumPy arrays into Rust values: the only place that looks at shapes.
//!
//! Bindings take arrays as plain Python objects and read them here, so that a wrong dtype or
//! dimensionality is a `ValueError` naming the argument, like a wrong shape. The `*_in` readers
//! borrow a C-ordered array's values in place ([`Values`]); the `*_of` readers copy them.

use numpy::{PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::errors::{shape_error, value_error, PyDreamResult};

/// An array's values in row-major order: borrowed from a C-ordered array for as long as this
/// lives (no copy: a million robots' columns are megabytes a call, copied on one core), copied
/// from any other. Dereferences to the values.
pub struct Values<'py, T: numpy::Element> {
    borrowed: Option<PyReadonlyArrayDyn<'py, T>>,
    copied: Vec<T>,
}

impl<T: numpy::Element + Copy> Values<'_, T> {
    /// The values as a vector of their own (copied if borrowed).
    pub fn into_vec(self) -> Vec<T> {
        match self.borrowed {
            Some(_) => self.to_vec(),
            None => self.copied,
        }
    }
}

impl<T: numpy::Element> std::ops::Deref for Values<'_, T> {
    type Target = [T];

    fn deref(&self) -> &[T] {
        match &self.borrowed {
            // Borrowed only where `as_slice` succeeded (see `borrow_values`).
            Some(array) => array.as_slice().unwrap_or_default(),
            None => &self.copied,
        }
    }
}

/// The float64 (or int64, bool, via `T`) values of `object` in row-major order, with its shape.
fn borrow_values<'py, T: numpy::Element + Copy>(
    arg: &str,
    object: &Bound<'py, PyAny>,
    kind: &str,
) -> PyDreamResult<(Values<'py, T>, Vec<usize>)> {
    let array = object
        .cast::<PyArrayDyn<T>>()
        .map_err(|_| value_error(format!("`{arg}` must be a NumPy array of {kind}")))?;
    let readonly = array.try_readonly().map_err(|e| value_error(format!("`{arg}`: {e}")))?;
    let shape = readonly.shape().to_vec();
    // `as_slice` also accepts Fortran order, whose memory is not row-major: only trust C order.
    let values = if readonly.is_c_contiguous() && readonly.as_slice().is_ok() {
        Values {
            borrowed: Some(readonly),
            copied: Vec::new(),
        }
    } else {
        // Lane by lane: a lane's strided iterator is a plain loop, where the whole array's
        // iterator works out every element's index (a transposed (2, 1,000,000) array copied
        // 2.5 times slower so).
        let view = readonly.as_array();
        let mut copied = Vec::with_capacity(view.len());
        if view.ndim() == 0 {
            copied.extend(view.iter().copied());
        } else {
            for lane in view.rows() {
                copied.extend(lane.iter().copied());
            }
        }
        Values { borrowed: None, copied }
    };
    Ok((values, shape))
}

/// `read(values, shape)` on the values of `object` (see [`borrow_values`]).
fn with_values<T: numpy::Element + Copy, R>(
    arg: &str,
    object: &Bound<'_, PyAny>,
    kind: &str,
    read: impl FnOnce(&[T], &[usize]) -> PyDreamResult<R>,
) -> PyDreamResult<R> {
    let (values, shape) = borrow_values(arg, object, kind)?;
    read(&values, &shape)
}

/// The values of `object` in row-major order, copied, with its shape.
fn values_of<T: numpy::Element + Copy>(
    arg: &str,
    object: &Bound<'_, PyAny>,
    kind: &str,
) -> PyDreamResult<(Vec<T>, Vec<usize>)> {
    let (values, shape) = borrow_values(arg, object, kind)?;
    Ok((values.into_vec(), shape))
}

/// A `(rows, n)` float64 array's values, row-major and borrowed where it can be (see
/// [`Values`]), with `n`.
pub fn rows_in<'py>(arg: &str, object: &Bound<'py, PyAny>, rows: usize) -> PyDreamResult<(Values<'py, f64>, usize)> {
    let (values, shape) = borrow_values(arg, object, "float64")?;
    if shape.len() != 2 || shape[0] != rows {
        return Err(shape_error(arg, &format!("({rows}, n)"), &shape));
    }
    Ok((values, shape[1]))
}

/// Copies a `(rows, n)` float64 array into a row-major vector; returns it with `n`.
pub fn rows_of(arg: &str, object: &Bound<'_, PyAny>, rows: usize) -> PyDreamResult<(Vec<f64>, usize)> {
    rows_in(arg, object, rows).map(|(values, n)| (values.into_vec(), n))
}

/// A `(k, w)` float64 array's values, row-major and borrowed where it can be (see [`Values`]),
/// with `w`.
pub fn matrix_in<'py>(arg: &str, object: &Bound<'py, PyAny>) -> PyDreamResult<(Values<'py, f64>, usize)> {
    let (values, shape) = borrow_values(arg, object, "float64")?;
    if shape.len() != 2 {
        return Err(shape_error(arg, "(k, w)", &shape));
    }
    Ok((values, shape[1]))
}

/// An `(n, W)` float64 array's `n` rows, borrowed where it can be (see [`Values`]).
/// Dereferences to the rows.
pub struct Points<'py, const W: usize>(Values<'py, f64>);

impl<const W: usize> std::ops::Deref for Points<'_, W> {
    type Target = [[f64; W]];

    fn deref(&self) -> &[[f64; W]] {
        // `points_in` checked the shape: the values are whole rows of W.
        self.0.as_chunks::<W>().0
    }
}

/// An `(n, W)` float64 array's rows, borrowed where it can be (see [`Values`]).
pub fn points_in<'py, const W: usize>(arg: &str, object: &Bound<'py, PyAny>) -> PyDreamResult<Points<'py, W>> {
    let (values, shape) = borrow_values(arg, object, "float64")?;
    if shape.len() != 2 || shape[1] != W {
        return Err(shape_error(arg, &format!("(n, {W})"), &shape));
    }
    Ok(Points(values))
}

/// Copies an `(n, W)` float64 array into `n` fixed-size rows.
pub fn points_of<const W: usize>(arg: &str, object: &Bound<'_, PyAny>) -> PyDreamResult<Vec<[f64; W]>> {
    points_in::<W>(arg, object).map(|points| points.to_vec())
}

/// The `W` columns of an `(n, W)` float64 array: each borrowed where it lies contiguous (Fortran
/// order: a transposed `(W, n)` array, as poses' rows `x[:2].T`), else copied by a strided pass.
pub struct Columns<'py, const W: usize> {
    array: PyReadonlyArrayDyn<'py, f64>,
    copied: [Option<Vec<f64>>; W],
}

impl<const W: usize> Columns<'_, W> {
    /// The columns, each `(n,)`.
    pub fn get(&self) -> [&[f64]; W] {
        std::array::from_fn(|k| match &self.copied[k] {
            Some(values) => values.as_slice(),
            // Not copied only where the column lies contiguous (see `columns_in`).
            None => self
                .array
                .as_array()
                .index_axis_move(numpy::ndarray::Axis(1), k)
                .to_slice()
                .unwrap_or_default(),
        })
    }
}

/// The `W` columns of an `(n, W)` float64 array (see [`Columns`]).
pub fn columns_in<'py, const W: usize>(arg: &str, object: &Bound<'py, PyAny>) -> PyDreamResult<Columns<'py, W>> {
    let array = object
        .cast::<PyArrayDyn<f64>>()
        .map_err(|_| value_error(format!("`{arg}` must be a NumPy array of float64")))?;
    let readonly = array.try_readonly().map_err(|e| value_error(format!("`{arg}`: {e}")))?;
    let shape = readonly.shape().to_vec();
    if shape.len() != 2 || shape[1] != W {
        return Err(shape_error(arg, &format!("(n, {W})"), &shape));
    }
    let view = readonly.as_array();
    let copied = std::array::from_fn(|k| {
        let column = view.index_axis(numpy::ndarray::Axis(1), k);
        column.as_slice().is_none().then(|| column.iter().copied().collect())
    });
    Ok(Columns {
        array: readonly,
        copied,
    })
}

/// A 1-D float64 array's values, borrowed where it can be (see [`Values`]), checking its length
/// when `len` is given.
pub fn vector_in<'py>(arg: &str, object: &Bound<'py, PyAny>, len: Option<usize>) -> PyDreamResult<Values<'py, f64>> {
    let (values, shape) = borrow_values(arg, object, "float64")?;
    if shape.len() != 1 || len.is_some_and(|want| shape[0] != want) {
        let expected = len.map_or("(n,)".to_string(), |want| format!("({want},)"));
        return Err(shape_error(arg, &expected, &shape));
    }
    Ok(values)
}

/// Copies a 1-D float64 array, checking its length when `len` is given.
pub fn vector_of(arg: &str, object: &Bound<'_, PyAny>, len: Option<usize>) -> PyDreamResult<Vec<f64>> {
    vector_in(arg, object, len).map(Values::into_vec)
}

/// A 1-D int64 array (CSR offsets and indices), borrowed where it can be (see [`Values`]): a
/// million robots' message indices are tens of megabytes, copied on one core.
pub fn indices_in<'py>(arg: &str, object: &Bound<'py, PyAny>) -> PyDreamResult<Values<'py, i64>> {
    let (values, shape) = borrow_values::<i64>(arg, object, "int64")?;
    if shape.len() != 1 {
        return Err(shape_error(arg, "(n,)", &shape));
    }
    Ok(values)
}

/// Copies a 1-D int64 array (CSR offsets and indices).
pub fn indices_of(arg: &str, object: &Bound<'_, PyAny>) -> PyDreamResult<Vec<i64>> {
    indices_in(arg, object).map(Values::into_vec)
}

/// `read(values)` on a 1-D int64 array, borrowed where it is C-ordered (a large graph, read in
/// part), copied otherwise.
pub fn with_indices<R>(
    arg: &str,
    object: &Bound<'_, PyAny>,
    read: impl FnOnce(&[i64]) -> PyDreamResult<R>,
) -> PyDreamResult<R> {
    with_values(arg, object, "int64", |values, shape| {
        if shape.len() != 1 {
            return Err(shape_error(arg, "(n,)", shape));
        }
        read(values)
    })
}

/// Copies a `(len,)` bool array (which robots to answer for).
pub fn flags_of(arg: &str, object: &Bound<'_, PyAny>, len: usize) -> PyDreamResult<Vec<bool>> {
    let (values, shape) = values_of::<bool>(arg, object, "bool")?;
    if shape != [len] {
        return Err(shape_error(arg, &format!("({len},)"), &shape));
    }
    Ok(values)
}

/// A count given from Python (`int`): negative values are a `ValueError` naming `arg`.
pub fn count_of(arg: &str, value: i64) -> PyDreamResult<usize> {
    usize::try_from(value).map_err(|_| value_error(format!("`{arg}` must be >= 0, got {value}")))
}

/// Both halves of an optional CSR pair, or neither.
pub fn both<T>(first: (&str, Option<T>), second: (&str, Option<T>)) -> PyDreamResult<Option<(T, T)>> {
    match (first.1, second.1) {
        (Some(a), Some(b)) => Ok(Some((a, b))),
        (None, None) => Ok(None),
        _ => Err(value_error(format!(
            "give both `{}` and `{}`, or neither",
            first.0, second.0
        ))),
    }
}

/// Fails unless the two arrays describe the same number of robots.
pub fn same_count(arg: &str, expected: usize, got: usize, rows: usize) -> PyDreamResult<()> {
    if expected == got {
        Ok(())
    } else {
        Err(shape_error(arg, &format!("({rows}, {expected})"), &[rows, got]))
    }
}

/// A 1-D C-contiguous array of `kind` (`T`) of `len` values, written in place: a table of the
/// swarm engine's that a kernel updates at some rows.
pub fn writable_in<'py, T: numpy::Element>(
    arg: &str,
    object: &Bound<'py, PyAny>,
    kind: &str,
    len: Option<usize>,
) -> PyDreamResult<numpy::PyReadwriteArray1<'py, T>> {
    let array = object
        .cast::<numpy::PyArray1<T>>()
        .map_err(|_| value_error(format!("`{arg}` must be a 1-D NumPy array of {kind}")))?;
    let writable = array
        .try_readwrite()
        .map_err(|e| value_error(format!("`{arg}` must be writable: {e}")))?;
    if !writable.is_c_contiguous() {
        return Err(value_error(format!(
            "`{arg}` must be C-contiguous (it is written in place)"
        )));
    }
    if let Some(want) = len.filter(|&want| writable.len() != want) {
        return Err(shape_error(arg, &format!("({want},)"), writable.shape()));
    }
    Ok(writable)
}
