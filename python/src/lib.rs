//! `rkforge._rkforge`: the Rust half of the `rkforge` Python package (PyO3, abi3).
//!
//! Scenes with dotted-key overrides ([`scene`]), simulations that step with the GIL
//! released and whole runs with the command line's bits ([`simulation`]). Every error is a
//! Python exception naming the problem, and every entry point runs under
//! [`std::panic::catch_unwind`], so no Rust panic reaches the interpreter.

mod scene;
mod simulation;

use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};

create_exception!(
    rkforge,
    SceneError,
    PyValueError,
    "A scene that cannot be read or is not valid: the key and its line, or the dotted key of an override, are named."
);
create_exception!(
    rkforge,
    StateError,
    PyValueError,
    "A saved state that cannot be restored (corrupt, or saved from another scene)."
);
create_exception!(
    rkforge,
    SimulationError,
    PyRuntimeError,
    "A simulation that failed: divergence, energy balance or stability, with the step and time named."
);

/// The Python exception for an error of the solver crate.
pub(crate) fn to_py(e: rkforge_core::Error) -> PyErr {
    use rkforge_core::Error;
    let text = e.to_string();
    match e {
        Error::SceneSyntax { .. } | Error::SceneValue { .. } | Error::Override { .. } => {
            SceneError::new_err(text)
        }
        Error::State(_) => StateError::new_err(text),
        Error::Request(_) => PyValueError::new_err(text),
        _ => SimulationError::new_err(text),
    }
}

/// Run `f`, turning a panic into a `RuntimeError` instead of letting it unwind into Python.
pub(crate) fn guarded<T>(f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|panic| {
        let message = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        Err(PyRuntimeError::new_err(format!(
            "rkforge internal error (a Rust panic, caught): {message}"
        )))
    })
}

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
    Ok(())
}
