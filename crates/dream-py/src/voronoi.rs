//! Bindings of `dream_core::voronoi`: disc-bounded Voronoi cells of the whole swarm.

use dream_core::dynamics::Arena;
use dream_core::voronoi as core;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

use crate::arrays::{both, count_of, indices_of, points_of};
use crate::errors::PyDreamResult;

type CellArrays<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<i64>>,
);

/// `(centroids (n, 2), areas (n,), vertices (m, 2), offsets (n + 1,))` of every robot's cell.
#[pyfunction]
#[pyo3(signature = (positions, *, radius, bounds, virtual_indptr=None, virtual_points=None, resolution=64))]
pub fn voronoi_cells<'py>(
    py: Python<'py>,
    positions: Bound<'py, PyAny>,
    radius: f64,
    bounds: (f64, f64, f64, f64),
    virtual_indptr: Option<Bound<'py, PyAny>>,
    virtual_points: Option<Bound<'py, PyAny>>,
    resolution: i64,
) -> PyDreamResult<CellArrays<'py>> {
    let resolution = count_of("resolution", resolution)?;
    let points = points_of::<2>("positions", &positions)?;
    let arena = Arena::new(bounds.0, bounds.1, bounds.2, bounds.3)?;
    let agents = match both(("virtual_indptr", virtual_indptr), ("virtual_points", virtual_points))? {
        Some((indptr, found)) => Some((indices_of("virtual_indptr", &indptr)?, points_of::<2>("virtual_points", &found)?)),
        None => None,
    };
    let cells = py.detach(|| {
        let agents = agents.as_ref().map(|(indptr, found)| (indptr.as_slice(), found.as_slice()));
        core::voronoi_cells(&points, radius, &arena, agents, resolution)
    })?;
    let (n, m) = (cells.centroids.len(), cells.vertices.len());
    Ok((
        cells.centroids.into_flattened().into_pyarray(py).reshape([n, 2])?,
        cells.areas.into_pyarray(py),
        cells.vertices.into_flattened().into_pyarray(py).reshape([m, 2])?,
        cells.offsets.into_pyarray(py),
    ))
}
