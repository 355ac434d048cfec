//! The Python exceptions of the package and the two guards every entry point uses: solver
//! errors turned into the exception that names them ([`to_py`]), and panics caught before
//! they reach the interpreter ([`guarded`]).

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
