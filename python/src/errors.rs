//! The Python exceptions of the package and the guards the entry points use: solver errors
//! turned into the exception that names them ([`to_py`]), panics caught before they reach
//! the interpreter ([`guarded`]), and Ctrl-C heard during a long call ([`interruptible`]).

use pyo3::create_exception;
use pyo3::exceptions::{PyMemoryError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Duration;

/// How often a long call looks for a signal (Ctrl-C) while it runs.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

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
        Error::Memory(_) => PyMemoryError::new_err(text),
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

/// Run `work` (a run or a stretch of steps, with the GIL released) on a thread of its own,
/// while the calling thread, Python's, asks the interpreter for signals every
/// [`SIGNAL_POLL`]: a Ctrl-C (`KeyboardInterrupt`, or whatever a signal handler raised) sets
/// the flag `work` is handed, which it reads between steps to stop there, and is raised
/// once `work` has returned. Without a signal, `work`'s own result. Python runs signal
/// handlers only on its main thread, and the solver's loop runs on the rayon pool's
/// workers: so the watching is done here, not in the loop.
pub(crate) fn interruptible<R: Send>(
    py: Python<'_>,
    work: impl FnOnce(&AtomicBool) -> PyResult<R> + Send,
) -> PyResult<R> {
    let cancel = AtomicBool::new(false);
    let mut raised = None;
    let out = py.detach(|| {
        std::thread::scope(|scope| {
            let (done, finished) = mpsc::channel::<()>();
            let cancel = &cancel;
            let worker = scope.spawn(move || {
                let out = guarded(|| work(cancel));
                let _ = done.send(());
                out
            });
            while let Err(mpsc::RecvTimeoutError::Timeout) = finished.recv_timeout(SIGNAL_POLL) {
                if raised.is_none() {
                    if let Err(e) = Python::attach(|py| py.check_signals()) {
                        raised = Some(e);
                        cancel.store(true, Ordering::Relaxed);
                    }
                }
            }
            worker.join().unwrap_or_else(|_| {
                Err(PyRuntimeError::new_err(
                    "rkforge internal error: the thread of the run was lost",
                ))
            })
        })
    });
    match raised {
        Some(e) => Err(e),
        None => out,
    }
}
