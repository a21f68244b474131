//! Bindings of `dream_core::hrvo`: the batch call and a per-robot planner.

use dream_core::geom::Arena;
use dream_core::geom::Vec2;
use dream_core::hrvo::{self as core, Detections, HrvoParams, Neighbour};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::arrays::{
    both, columns_in, flags_of, indices_in, indices_of, points_in, points_of, vector_in, vector_of, Columns, Values,
};
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
/// With `relative`, the detections are `(k, 5)`: distance, the offset `(dx, dy)` of the robot
/// detected, its velocity.
#[pyfunction]
#[pyo3(signature = (velocities, preferred, positions, offsets, detections, *, safety, v_max, bounds, candidates, include_preferred, relative=false, steer=None))]
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
    relative: bool,
    steer: Option<Bound<'py, PyAny>>,
) -> PyDreamResult<Bound<'py, PyArray2<f64>>> {
    let v = points_in::<2>("velocities", &velocities)?;
    let pref = points_in::<2>("preferred", &preferred)?;
    let p = points_in::<2>("positions", &positions)?;
    let offsets = indices_in("offsets", &offsets)?;
    let sensed = if relative {
        Sensed::Offsets(detections_of(&detections, "(distance, dx, dy, vx, vy)")?)
    } else {
        Sensed::Polar(detections_of(&detections, "(distance, angle, vx, vy)")?)
    };
    let seen = match &sensed {
        Sensed::Offsets(columns) => Detections::Offsets(columns.get()),
        Sensed::Polar(columns) => Detections::Polar(columns.get()),
    };
    let grid = points_of::<2>("candidates", &candidates)?;
    let params = params(safety, v_max, bounds, include_preferred)?;
    let steer = steer.map(|flags| flags_of("steer", &flags, p.len())).transpose()?;
    let (v, pref, p, offsets): (&[Vec2], &[Vec2], &[Vec2], &[i64]) = (&v, &pref, &p, &offsets);
    let steer = steer.as_deref();
    let chosen = py.detach(|| core::hrvo_rows(v, pref, p, offsets, seen, &grid, &params, steer))?;
    let m = chosen.len();
    Ok(chosen.into_flattened().into_pyarray(py).reshape([m, 2])?)
}

/// Detections `(k, W)`, or their `W` columns `(k,)` each (`names`), as columns: a movement
/// sensor's columns read where they lie, an array's copied column by column where it is laid out
/// in rows.
fn detections_of<'py, const W: usize>(
    object: &Bound<'py, PyAny>,
    names: &str,
) -> PyDreamResult<DetectionColumns<'py, W>> {
    let Ok(columns) = object.cast::<PyTuple>() else {
        return Ok(DetectionColumns::Stacked(columns_in::<W>("detections", object)?));
    };
    if columns.len() != W {
        return Err(value_error(format!(
            "`detections` columns must be {names}, got {} columns",
            columns.len()
        )));
    }
    let first = vector_in("detections", &columns.get_item(0)?, None)?;
    let len = first.len();
    let mut all = vec![first];
    for c in 1..W {
        all.push(vector_in("detections", &columns.get_item(c)?, Some(len))?);
    }
    Ok(DetectionColumns::Listed(all))
}

/// The detections' columns of either kind.
enum Sensed<'py> {
    Offsets(DetectionColumns<'py, 5>),
    Polar(DetectionColumns<'py, 4>),
}

/// Detections' `W` columns (see [`detections_of`]).
enum DetectionColumns<'py, const W: usize> {
    Listed(Vec<Values<'py, f64>>),
    Stacked(Columns<'py, W>),
}

impl<const W: usize> DetectionColumns<'_, W> {
    fn get(&self) -> [&[f64]; W] {
        match self {
            DetectionColumns::Listed(columns) => std::array::from_fn(|c| &*columns[c]),
            DetectionColumns::Stacked(columns) => columns.get(),
        }
    }
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
