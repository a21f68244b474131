//! Bindings of `dream_core::voronoi`: disc-bounded Voronoi cells of the whole swarm.

use dream_core::geom::Arena;
use dream_core::voronoi as core;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

use crate::arrays::{both, count_of, indices_of, points_of, vector_of};
use crate::errors::PyDreamResult;

pub(crate) type CellArrays<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<i64>>,
);

/// `(centroids (n, 2), areas (n,), vertices (m, 2), offsets (n + 1,))` of every robot's cell
/// (without `neighbours`, each clipped by its virtual points alone).
#[pyfunction]
#[pyo3(signature = (positions, *, radius, bounds, virtual_indptr=None, virtual_points=None, resolution=64, neighbours=true))]
#[allow(clippy::too_many_arguments)]
pub fn voronoi_cells<'py>(
    py: Python<'py>,
    positions: Bound<'py, PyAny>,
    radius: f64,
    bounds: (f64, f64, f64, f64),
    virtual_indptr: Option<Bound<'py, PyAny>>,
    virtual_points: Option<Bound<'py, PyAny>>,
    resolution: i64,
    neighbours: bool,
) -> PyDreamResult<CellArrays<'py>> {
    let resolution = count_of("resolution", resolution)?;
    let points = points_of::<2>("positions", &positions)?;
    let arena = Arena::new(bounds.0, bounds.1, bounds.2, bounds.3)?;
    let agents = match both(("virtual_indptr", virtual_indptr), ("virtual_points", virtual_points))? {
        Some((indptr, found)) => Some((
            indices_of("virtual_indptr", &indptr)?,
            points_of::<2>("virtual_points", &found)?,
        )),
        None => None,
    };
    let cells = py.detach(|| {
        let agents = agents
            .as_ref()
            .map(|(indptr, found)| (indptr.as_slice(), found.as_slice()));
        core::voronoi_cells(&points, radius, &arena, agents, resolution, neighbours)
    })?;
    cell_arrays(py, cells)
}

pub(crate) fn cell_arrays(py: Python<'_>, cells: core::Cells) -> PyDreamResult<CellArrays<'_>> {
    let (n, m) = (cells.centroids.len(), cells.vertices.len());
    Ok((
        cells.centroids.into_flattened().into_pyarray(py).reshape([n, 2])?,
        cells.areas.into_pyarray(py),
        cells.vertices.into_flattened().into_pyarray(py).reshape([m, 2])?,
        cells.offsets.into_pyarray(py),
    ))
}

/// One robot's cell: `(centroid (2,), area, vertices (m, 2))`, clipped by `others` `(k, 2)` and `virtual_points` `(j, 2)`.
#[pyfunction]
#[pyo3(signature = (position, others, virtual_points, *, radius, bounds, resolution=64))]
pub fn voronoi_cell<'py>(
    py: Python<'py>,
    position: Bound<'py, PyAny>,
    others: Bound<'py, PyAny>,
    virtual_points: Bound<'py, PyAny>,
    radius: f64,
    bounds: (f64, f64, f64, f64),
    resolution: i64,
) -> PyDreamResult<(Bound<'py, PyArray1<f64>>, f64, Bound<'py, PyArray2<f64>>)> {
    let p = vector_of("position", &position, Some(2))?;
    let p = [p[0], p[1]];
    let others = points_of::<2>("others", &others)?;
    let agents = points_of::<2>("virtual_points", &virtual_points)?;
    let resolution = count_of("resolution", resolution)?;
    let arena = Arena::new(bounds.0, bounds.1, bounds.2, bounds.3)?;
    let polygon = core::voronoi_cell(p, &others, &agents, radius, &arena, resolution)?;
    let (area, centroid) = core::area_centroid(&polygon, p);
    let m = polygon.len();
    Ok((
        centroid.to_vec().into_pyarray(py),
        area,
        polygon.into_flattened().into_pyarray(py).reshape([m, 2])?,
    ))
}
