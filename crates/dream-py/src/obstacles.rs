//! Bindings of `dream_core::obstacles`: virtual agents that keep Voronoi cells off obstacles.

use dream_core::obstacles::{self as core, Obstacles};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

use crate::arrays::{indices_of, points_of};
use crate::errors::PyDreamResult;

/// Virtual agents `(indptr (n + 1,), points (m, 2))` of every robot for convex obstacles given
/// as CSR `(vertices (v, 2), offsets (k + 1,))`.
#[pyfunction]
#[pyo3(signature = (positions, vertices, offsets, *, range, offset))]
pub fn virtual_agents<'py>(
    py: Python<'py>,
    positions: Bound<'py, PyAny>,
    vertices: Bound<'py, PyAny>,
    offsets: Bound<'py, PyAny>,
    range: f64,
    offset: f64,
) -> PyDreamResult<(Bound<'py, PyArray1<i64>>, Bound<'py, PyArray2<f64>>)> {
    let points = points_of::<2>("positions", &positions)?;
    let corners = points_of::<2>("vertices", &vertices)?;
    let offsets = indices_of("offsets", &offsets)?;
    let (indptr, agents) = py.detach(|| {
        let obstacles = Obstacles::new(&corners, &offsets)?;
        core::virtual_agents(&points, &obstacles, range, offset)
    })?;
    let m = agents.len();
    Ok((
        indptr.into_pyarray(py),
        agents.into_flattened().into_pyarray(py).reshape([m, 2])?,
    ))
}
