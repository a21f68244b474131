//! `dream._core`: thin pyo3 bindings of dream-core. Each binding checks shapes, copies in,
//! releases the GIL around the kernel, moves the result out and maps errors to `ValueError`.

mod arrays;
mod dynamics;
mod errors;

use pyo3::prelude::*;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(dynamics::unicycle_step, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::threshold_velocities, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::validate, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::dxi_to_dxu, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::actuator_limit, m)?)?;
    Ok(())
}
