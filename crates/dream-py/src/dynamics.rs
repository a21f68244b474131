//! Bindings of `dream_core::dynamics`: the Fast backend's step and the rps validation counts.

use dream_core::dynamics::{self, BoundaryCount, Checks, Wheels};
use dream_core::geom::Arena;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

use crate::arrays::{rows_in, rows_of, same_count, vector_in};
use crate::errors::PyDreamResult;

fn into_rows<'py>(py: Python<'py>, values: Vec<f64>, rows: usize, n: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
    values.into_pyarray(py).reshape([rows, n])
}

/// Poses `(3, n)` after one Euler step of the unicycle model with commands `(2, n)`.
#[pyfunction]
pub fn unicycle_step<'py>(
    py: Python<'py>,
    poses: Bound<'py, PyAny>,
    velocities: Bound<'py, PyAny>,
    dt: f64,
) -> PyDreamResult<Bound<'py, PyArray2<f64>>> {
    let (mut p, n) = rows_of("poses", &poses, 3)?; // a copy: the new poses
    let (u, m) = rows_in("velocities", &velocities, 2)?;
    same_count("velocities", n, m, 2)?;
    let u: &[f64] = &u;
    py.detach(|| dynamics::unicycle_step(&mut p, u, n, dt))?;
    Ok(into_rows(py, p, 3, n)?)
}

/// Commands `(2, n)` with |v| and |w| clipped to their limits, signs kept.
#[pyfunction]
pub fn threshold_velocities<'py>(
    py: Python<'py>,
    velocities: Bound<'py, PyAny>,
    max_linear: f64,
    max_angular: f64,
) -> PyDreamResult<Bound<'py, PyArray2<f64>>> {
    let (mut u, n) = rows_of("velocities", &velocities, 2)?;
    dynamics::threshold_velocities(&mut u, n, max_linear, max_angular)?;
    Ok(into_rows(py, u, 2, n)?)
}

/// Commands `(2, n)` whose wheel speeds are clipped to `max_wheel` (rps 2.1).
#[pyfunction]
#[pyo3(signature = (velocities, *, wheel_radius, base_length, max_wheel))]
pub fn threshold_wheels<'py>(
    py: Python<'py>,
    velocities: Bound<'py, PyAny>,
    wheel_radius: f64,
    base_length: f64,
    max_wheel: f64,
) -> PyDreamResult<Bound<'py, PyArray2<f64>>> {
    let (mut u, n) = rows_of("velocities", &velocities, 2)?;
    let wheels = Wheels::new(wheel_radius, base_length, max_wheel)?;
    dynamics::threshold_wheels(&mut u, n, &wheels)?;
    Ok(into_rows(py, u, 2, n)?)
}

/// `(boundary, collision, actuator)` violation counts of one iteration, by rps's criteria
/// (0.0.0's by default; 2.1's with `collider_offset=0.025, boundary_per_iteration=True`), and
/// the robots in a collision `(m,)` int64, ascending (the robots of the pairs counted).
#[pyfunction]
#[pyo3(signature = (
    poses, velocities, bounds, *, diameter, wheel_radius, base_length, max_wheel,
    collider_offset = 0.0, boundary_per_iteration = false,
))]
#[allow(clippy::too_many_arguments)]
pub fn validate<'py>(
    py: Python<'py>,
    poses: Bound<'py, PyAny>,
    velocities: Bound<'py, PyAny>,
    bounds: (f64, f64, f64, f64),
    diameter: f64,
    wheel_radius: f64,
    base_length: f64,
    max_wheel: f64,
    collider_offset: f64,
    boundary_per_iteration: bool,
) -> PyDreamResult<(u64, u64, u64, Bound<'py, PyArray1<i64>>)> {
    let (p, n) = rows_in("poses", &poses, 3)?;
    let (u, m) = rows_in("velocities", &velocities, 2)?;
    same_count("velocities", n, m, 2)?;
    let (p, u): (&[f64], &[f64]) = (&p, &u);
    let arena = Arena::new(bounds.0, bounds.1, bounds.2, bounds.3)?;
    let wheels = Wheels::new(wheel_radius, base_length, max_wheel)?;
    let boundary = if boundary_per_iteration {
        BoundaryCount::Iterations
    } else {
        BoundaryCount::Robots
    };
    let checks = Checks::new(diameter, collider_offset, boundary)?;
    let (counts, robots) = py.detach(|| dynamics::validate_each(p, u, n, &arena, &checks, &wheels))?;
    let robots: Vec<i64> = robots.into_iter().map(|i| i as i64).collect();
    Ok((
        counts.boundary,
        counts.collision,
        counts.actuator,
        robots.into_pyarray(py),
    ))
}

/// `(n,)` bool: the robots in a collision by rps's criteria (the pairs `validate` counts: colliders
/// `collider_offset` ahead of the centres, within `diameter`).
#[pyfunction]
#[pyo3(signature = (poses, *, diameter, collider_offset = 0.0))]
pub fn colliding<'py>(
    py: Python<'py>,
    poses: Bound<'py, PyAny>,
    diameter: f64,
    collider_offset: f64,
) -> PyDreamResult<Bound<'py, PyArray1<bool>>> {
    let (p, n) = rows_of("poses", &poses, 3)?;
    let checks = Checks::new(diameter, collider_offset, BoundaryCount::Robots)?;
    Ok(py.detach(|| dynamics::colliding(&p, n, &checks))?.into_pyarray(py))
}

/// Unicycle commands `(2, n)` from single-integrator velocities `(2, n)` at poses `(3, n)`.
#[pyfunction]
pub fn dxi_to_dxu<'py>(
    py: Python<'py>,
    dxi: Bound<'py, PyAny>,
    poses: Bound<'py, PyAny>,
    vel_gain: f64,
    ang_gain: f64,
) -> PyDreamResult<Bound<'py, PyArray2<f64>>> {
    let (d, n) = rows_of("dxi", &dxi, 2)?;
    let (p, m) = rows_of("poses", &poses, 3)?;
    same_count("poses", n, m, 3)?;
    let dxu = py.detach(|| dynamics::dxi_to_dxu(&d, &p, n, vel_gain, ang_gain))?;
    Ok(into_rows(py, dxu, 2, n)?)
}

/// Velocities `(2, n)` of the points `projection` ahead of robots of headings `(n,)` driven by
/// unicycle commands `(2, n)`.
#[pyfunction]
pub fn dxu_to_dxi<'py>(
    py: Python<'py>,
    dxu: Bound<'py, PyAny>,
    headings: Bound<'py, PyAny>,
    projection: f64,
) -> PyDreamResult<Bound<'py, PyArray2<f64>>> {
    let (u, n) = rows_in("dxu", &dxu, 2)?;
    let theta = vector_in("headings", &headings, Some(n))?;
    let (u, theta): (&[f64], &[f64]) = (&u, &theta);
    let dxi = py.detach(|| dynamics::dxu_to_dxi(u, theta, n, projection))?;
    Ok(into_rows(py, dxi, 2, n)?)
}

/// Commands `(2, n)` clipped to the speed limits, then slowed so that no wheel is too fast.
#[pyfunction]
#[pyo3(signature = (dxu, *, max_linear, max_angular, wheel_radius, base_length, max_wheel))]
pub fn actuator_limit<'py>(
    py: Python<'py>,
    dxu: Bound<'py, PyAny>,
    max_linear: f64,
    max_angular: f64,
    wheel_radius: f64,
    base_length: f64,
    max_wheel: f64,
) -> PyDreamResult<Bound<'py, PyArray2<f64>>> {
    let (mut u, n) = rows_of("dxu", &dxu, 2)?;
    let wheels = Wheels::new(wheel_radius, base_length, max_wheel)?;
    dynamics::actuator_limit(&mut u, n, max_linear, max_angular, &wheels)?;
    Ok(into_rows(py, u, 2, n)?)
}
