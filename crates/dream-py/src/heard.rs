//! Bindings of `dream_core::heard`: the Voronoi cells of robots that know the others by radio.

use dream_core::geom::Arena;
use dream_core::heard;
use pyo3::prelude::*;

use crate::arrays::{count_of, indices_in, points_in};
use crate::draws::{loss_of, LossArgs};
use crate::errors::PyDreamResult;
use crate::voronoi::{cell_arrays, CellArrays};

/// The cells `(centroids (k, 2), areas (k,), vertices (m, 2), offsets (k + 1,))` of robots
/// `hearers` `(k,)` at `here` `(k, 2)`, each clipped by what its range radio hears (`said` and
/// `said_now` `(n, 2)` of the robots at `positions` `(n, 2)`), by the robots it sees that no
/// message accounts for and by its virtual agents (both CSR); with the radio's `loss` `(seed,
/// stream, step, keep, per_metre)`, as `perceive` draws it, and without the messages of the
/// links `lost` (`i * n + j`, strictly increasing).
#[pyfunction]
#[pyo3(signature = (here, hearers, positions, said, said_now, *, range, seen_indptr, seen_points, same, virtual_indptr, virtual_points, radius, bounds, resolution=64, loss=None, lost=None))]
#[allow(clippy::too_many_arguments)]
pub fn heard_cells<'py>(
    py: Python<'py>,
    here: Bound<'py, PyAny>,
    hearers: Bound<'py, PyAny>,
    positions: Bound<'py, PyAny>,
    said: Bound<'py, PyAny>,
    said_now: Bound<'py, PyAny>,
    range: f64,
    seen_indptr: Bound<'py, PyAny>,
    seen_points: Bound<'py, PyAny>,
    same: f64,
    virtual_indptr: Bound<'py, PyAny>,
    virtual_points: Bound<'py, PyAny>,
    radius: f64,
    bounds: (f64, f64, f64, f64),
    resolution: i64,
    loss: Option<LossArgs>,
    lost: Option<Bound<'py, PyAny>>,
) -> PyDreamResult<CellArrays<'py>> {
    let resolution = count_of("resolution", resolution)?;
    let arena = Arena::new(bounds.0, bounds.1, bounds.2, bounds.3)?;
    // Every array read in place: the positions and messages of every robot are tens of
    // megabytes at a million, copied on one core.
    let here = points_in::<2>("here", &here)?;
    let ids = indices_in("hearers", &hearers)?;
    let positions = points_in::<2>("positions", &positions)?;
    // One array for both (no turns): read and checked once.
    let said_once = said_now.is(&said);
    let said = points_in::<2>("said", &said)?;
    let said_now = if said_once {
        None
    } else {
        Some(points_in::<2>("said_now", &said_now)?)
    };
    let seen_offsets = indices_in("seen_indptr", &seen_indptr)?;
    let seen = points_in::<2>("seen_points", &seen_points)?;
    let agents_offsets = indices_in("virtual_indptr", &virtual_indptr)?;
    let agents = points_in::<2>("virtual_points", &virtual_points)?;
    let lost = lost.map(|links| indices_in("lost", &links)).transpose()?;
    let radio = heard::Radio {
        positions: &positions,
        range,
        said: &said,
        said_now: said_now.as_deref().unwrap_or(&said),
        loss: loss_of(loss)?,
        lost: lost.as_deref().unwrap_or_default(),
    };
    let hearers = heard::Hearers {
        ids: &ids,
        here: &here,
        seen_offsets: &seen_offsets,
        seen: &seen,
        same,
        agents_offsets: &agents_offsets,
        agents: &agents,
    };
    let cells = py.detach(|| heard::heard_cells(&radio, &hearers, radius, &arena, resolution))?;
    cell_arrays(py, cells)
}
