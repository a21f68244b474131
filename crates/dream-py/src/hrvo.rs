//! Bindings of `dream_core::hrvo`: the batch call and a per-robot planner.

use dream_core::geom::Arena;
use dream_core::geom::Vec2;
use dream_core::hrvo::{self as core, HrvoParams, Neighbour};
use dream_core::parallel::map_range;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use std::f64::consts::PI;

use crate::arrays::{both, indices_of, points_of, vector_of};
use crate::errors::{value_error, PyDreamResult};

fn params(
    safety: f64,
    v_max: f64,
    bounds: Option<(f64, f64, f64, f64)>,
    include_preferred: bool,
) -> PyDreamResult<HrvoParams> {
    let bounds = bounds.map(|b| Arena::new(b.0, b.1, b.2, b.3)).transpose()?;
    Ok(HrvoParams {
        safety,
        v_max,
        bounds,
        include_preferred,
    }
    .validated()?)
}

fn vec2(arg: &str, array: &Bound<'_, PyAny>) -> PyDreamResult<Vec2> {
    let v = vector_of(arg, array, Some(2))?;
    Ok([v[0], v[1]])
}

/// HRVO velocities `(n, 2)` of the whole swarm; neighbours from CSR `(indptr, indices)` or within `radius`.
#[pyfunction]
#[pyo3(signature = (positions, velocities, preferred, indptr, indices, *, radius, safety, v_max, bounds, candidates, include_preferred))]
#[allow(clippy::too_many_arguments)]
pub fn hrvo<'py>(
    py: Python<'py>,
    positions: Bound<'py, PyAny>,
    velocities: Bound<'py, PyAny>,
    preferred: Bound<'py, PyAny>,
    indptr: Option<Bound<'py, PyAny>>,
    indices: Option<Bound<'py, PyAny>>,
    radius: f64,
    safety: f64,
    v_max: f64,
    bounds: Option<(f64, f64, f64, f64)>,
    candidates: Bound<'py, PyAny>,
    include_preferred: bool,
) -> PyDreamResult<Bound<'py, PyArray2<f64>>> {
    let p = points_of::<2>("positions", &positions)?;
    let v = points_of::<2>("velocities", &velocities)?;
    let pref = points_of::<2>("preferred", &preferred)?;
    let grid = points_of::<2>("candidates", &candidates)?;
    let csr = match both(("indptr", indptr), ("indices", indices))? {
        Some((a, b)) => Some((indices_of("indptr", &a)?, indices_of("indices", &b)?)),
        None => None,
    };
    let params = params(safety, v_max, bounds, include_preferred)?;
    let chosen = py.detach(|| {
        let csr = csr.as_ref().map(|(a, b)| (a.as_slice(), b.as_slice()));
        core::hrvo_batch(&p, &v, &pref, csr, radius, &grid, &params)
    })?;
    let n = chosen.len();
    Ok(chosen.into_flattened().into_pyarray(py).reshape([n, 2])?)
}

/// HRVO velocities `(m, 2)` of the deciding robots, each from its own detections `(k, 4)`
/// (row r's: `offsets[r]..offsets[r + 1]`); row r is `HrvoPlanner.velocity`'s answer for them.
#[pyfunction]
#[pyo3(signature = (velocities, preferred, positions, offsets, detections, *, safety, v_max, bounds, candidates, include_preferred, towards=false))]
#[allow(clippy::too_many_arguments)]
pub fn hrvo_rows<'py>(
    py: Python<'py>,
    velocities: Bound<'py, PyAny>,
    preferred: Bound<'py, PyAny>,
    positions: Bound<'py, PyAny>,
    offsets: Bound<'py, PyAny>,
    detections: Bound<'py, PyAny>,
    safety: f64,
    v_max: f64,
    bounds: Option<(f64, f64, f64, f64)>,
    candidates: Bound<'py, PyAny>,
    include_preferred: bool,
    towards: bool,
) -> PyDreamResult<Bound<'py, PyArray2<f64>>> {
    let v = points_of::<2>("velocities", &velocities)?;
    let pref = points_of::<2>("preferred", &preferred)?;
    let p = points_of::<2>("positions", &positions)?;
    let offsets = indices_of("offsets", &offsets)?;
    let mut seen = detections_of(&detections)?;
    if towards {
        // Bearings towards the detected robots, as the movement sensor's angles from them: the
        // reference's flip, to the bit.
        seen = map_range(seen.len(), 1.0, |e| {
            let [distance, bearing, vx, vy] = seen[e];
            [
                distance,
                if bearing > 0.0 { bearing - PI } else { bearing + PI },
                vx,
                vy,
            ]
        });
    }
    let grid = points_of::<2>("candidates", &candidates)?;
    let params = params(safety, v_max, bounds, include_preferred)?;
    let chosen = py.detach(|| core::hrvo_rows(&v, &pref, &p, &offsets, &seen, &grid, &params))?;
    let m = chosen.len();
    Ok(chosen.into_flattened().into_pyarray(py).reshape([m, 2])?)
}

/// Detections `(k, 4)`, or their four columns `(k,)` each (distance, angle, vx, vy): a movement
/// sensor's columns go in without being stacked first.
fn detections_of(object: &Bound<'_, PyAny>) -> PyDreamResult<Vec<[f64; 4]>> {
    let Ok(columns) = object.cast::<PyTuple>() else {
        return points_of::<4>("detections", object);
    };
    if columns.len() != 4 {
        return Err(value_error(format!(
            "`detections` columns must be (distance, angle, vx, vy), got {} columns",
            columns.len()
        )));
    }
    let distance = vector_of("detections", &columns.get_item(0)?, None)?;
    let rest: Vec<Vec<f64>> = (1..4)
        .map(|c| vector_of("detections", &columns.get_item(c)?, Some(distance.len())))
        .collect::<PyDreamResult<_>>()?;
    Ok(map_range(distance.len(), 1.0, |e| {
        [distance[e], rest[0][e], rest[1][e], rest[2][e]]
    }))
}

/// A robot's HRVO planner: parameters and candidate grid, fixed; one call per decision.
#[pyclass(name = "HrvoPlanner", module = "dream._core", frozen)]
pub struct PyHrvoPlanner {
    params: HrvoParams,
    grid: Vec<Vec2>,
}

#[pymethods]
impl PyHrvoPlanner {
    #[new]
    #[pyo3(signature = (candidates, *, safety, v_max, bounds, include_preferred))]
    fn new(
        candidates: Bound<'_, PyAny>,
        safety: f64,
        v_max: f64,
        bounds: Option<(f64, f64, f64, f64)>,
        include_preferred: bool,
    ) -> PyDreamResult<Self> {
        let grid = points_of::<2>("candidates", &candidates)?;
        dream_core::error::check_finite("candidates", grid.as_flattened())?;
        Ok(Self {
            params: params(safety, v_max, bounds, include_preferred)?,
            grid,
        })
    }

    /// The velocity `(2,)` for seed-format `detections` `(k, 4)` `[distance, angle, vx, vy]`.
    fn velocity<'py>(
        &self,
        py: Python<'py>,
        detections: Bound<'py, PyAny>,
        velocity: Bound<'py, PyAny>,
        preferred: Bound<'py, PyAny>,
        position: Bound<'py, PyAny>,
    ) -> PyDreamResult<Bound<'py, PyArray1<f64>>> {
        let around: Vec<Neighbour> = points_of::<4>("detections", &detections)?
            .into_iter()
            .map(Neighbour::from_detection)
            .collect();
        let chosen = core::hrvo_one(
            vec2("velocity", &velocity)?,
            vec2("preferred", &preferred)?,
            vec2("position", &position)?,
            &around,
            &self.grid,
            &self.params,
        )?;
        Ok(chosen.to_vec().into_pyarray(py))
    }
}
