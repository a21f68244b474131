//! Bindings of `dream_core::raycast`: the distance sensors of the whole swarm.

use dream_core::raycast::{self, Ray, Sensors, Wall};
use numpy::{IntoPyArray, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

use crate::arrays::{count_of, indices_of, points_of, rows_of};
use crate::errors::PyDreamResult;

/// Readings `(k, n)` of the `k` rays `(3, k)` of robots `robots` (all when `None`) at `poses`
/// `(3, n)` against walls `(m, 4)` (`[ax, ay, bx, by]`) and the other robots; -1 for nothing.
#[pyfunction]
#[pyo3(signature = (poses, walls, rays, *, centre_offset, robot_diameter, range, robots = None))]
#[allow(clippy::too_many_arguments)]
pub fn distance_rays<'py>(
    py: Python<'py>,
    poses: Bound<'py, PyAny>,
    walls: Bound<'py, PyAny>,
    rays: Bound<'py, PyAny>,
    centre_offset: f64,
    robot_diameter: f64,
    range: f64,
    robots: Option<Bound<'py, PyAny>>,
) -> PyDreamResult<Bound<'py, PyArray2<f64>>> {
    let (p, n) = rows_of("poses", &poses, 3)?;
    let walls: Vec<Wall> = points_of::<4>("walls", &walls)?
        .into_iter()
        .map(|w| Wall {
            a: [w[0], w[1]],
            b: [w[2], w[3]],
        })
        .collect();
    let (r, k) = rows_of("rays", &rays, 3)?;
    let rays = (0..k)
        .map(|j| Ray {
            x: r[j],
            y: r[k + j],
            angle: r[2 * k + j],
        })
        .collect();
    let sensors = Sensors::new(rays, centre_offset, robot_diameter / 2.0, range)?;
    let sources = match robots {
        Some(ids) => Some(
            indices_of("robots", &ids)?
                .into_iter()
                .map(|i| count_of("robots", i))
                .collect::<PyDreamResult<Vec<usize>>>()?,
        ),
        None => None,
    };
    let readings = py.detach(|| raycast::distance_rays(&p, n, &walls, &sensors, sources.as_deref()))?;
    Ok(readings.into_pyarray(py).reshape([k, n])?)
}
