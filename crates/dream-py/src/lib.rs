//! `dream._core`: thin pyo3 bindings of dream-core. Each binding checks shapes, copies in,
//! releases the GIL around the kernel, moves the result out and maps errors to `ValueError`.

mod arrays;
mod bursts;
mod draws;
mod dynamics;
mod errors;
mod guard;
mod heard;
mod hrvo;
mod length;
mod neighbours;
mod obstacles;
mod raycast;
mod reduce;
mod sidestep;
mod tables;
mod voronoi;

use pyo3::prelude::*;

#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(bursts::bursts, m)?)?;
    m.add_function(wrap_pyfunction!(draws::draws, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::unicycle_step, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::threshold_velocities, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::threshold_wheels, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::validate, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::colliding, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::dxi_to_dxu, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::dxu_to_dxi, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::actuator_limit, m)?)?;
    m.add_function(wrap_pyfunction!(length::hypot, m)?)?;
    m.add_function(wrap_pyfunction!(neighbours::neighbours, m)?)?;
    m.add_function(wrap_pyfunction!(neighbours::far_from, m)?)?;
    m.add_function(wrap_pyfunction!(neighbours::perceive, m)?)?;
    m.add_function(wrap_pyfunction!(neighbours::linked, m)?)?;
    m.add_function(wrap_pyfunction!(hrvo::hrvo, m)?)?;
    m.add_function(wrap_pyfunction!(hrvo::hrvo_rows, m)?)?;
    m.add_class::<hrvo::PyHrvoPlanner>()?;
    m.add_function(wrap_pyfunction!(voronoi::voronoi_cells, m)?)?;
    m.add_function(wrap_pyfunction!(voronoi::voronoi_cell, m)?)?;
    m.add_function(wrap_pyfunction!(heard::heard_cells, m)?)?;
    m.add_function(wrap_pyfunction!(obstacles::virtual_agents, m)?)?;
    m.add_function(wrap_pyfunction!(raycast::distance_rays, m)?)?;
    m.add_function(wrap_pyfunction!(reduce::segment_reduce, m)?)?;
    m.add_function(wrap_pyfunction!(reduce::segment_any, m)?)?;
    m.add_function(wrap_pyfunction!(reduce::segment_nearest, m)?)?;
    m.add_function(wrap_pyfunction!(reduce::segment_nearest_to, m)?)?;
    m.add_function(wrap_pyfunction!(guard::motion_guard, m)?)?;
    m.add_function(wrap_pyfunction!(sidestep::sidestep_ask, m)?)?;
    m.add_function(wrap_pyfunction!(sidestep::sidestep_mark, m)?)?;
    m.add_function(wrap_pyfunction!(tables::take_rows, m)?)?;
    m.add_function(wrap_pyfunction!(tables::put_rows, m)?)?;
    Ok(())
}
