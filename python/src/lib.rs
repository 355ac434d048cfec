//! `rkforge._rkforge`: the Rust half of the `rkforge` Python package (PyO3, abi3).
//!
//! Scenes with dotted-key overrides ([`scene`]), simulations that step with the GIL
//! released and whole runs with the command line's bits ([`simulation`]). Every error is a
//! Python exception naming the problem, and every entry point runs under
//! [`std::panic::catch_unwind`], so no Rust panic reaches the interpreter.

mod errors;
mod scene;
mod simulation;

use errors::{SceneError, SimulationError, StateError};
use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _rkforge(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<scene::Scene>()?;
    m.add_class::<simulation::Simulation>()?;
    m.add_function(wrap_pyfunction!(simulation::run_scene, m)?)?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("StateError", py.get_type::<StateError>())?;
    m.add("SimulationError", py.get_type::<SimulationError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // numpy's C API, imported now: imported at the first array instead, with a Ctrl-C
    // pending it failed, and the package panicked there.
    numpy::PyArray1::<f64>::zeros(py, 0, false);
    Ok(())
}
