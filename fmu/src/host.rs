//! The C boundary the FMI 2.0 and 3.0 APIs ([`crate::ffi`], [`crate::ffi3`]) share: the
//! status codes (the same numbers in both), the panic barrier every exported function runs
//! its body in, the checked conversions of host pointers, and the outputs readable while a
//! step calls the host back (FMI 3.0 intermediate update).

use std::cell::{Cell, RefCell};
use std::ffi::{c_char, c_int, c_void, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::rc::Rc;

/// `fmi2OK` / `fmi3OK`.
pub const OK: c_int = 0;
/// `fmi2Warning` / `fmi3Warning`.
pub const WARNING: c_int = 1;
/// `fmi2Discard` / `fmi3Discard`.
pub const DISCARD: c_int = 2;
/// `fmi2Error` / `fmi3Error`.
pub const ERROR: c_int = 3;
/// `fmi2Fatal` / `fmi3Fatal`.
pub const FATAL: c_int = 4;

/// What the host's instance pointer points to (a `component::Component`), as the panic
/// barrier needs it: a way to report a failure to the host.
pub trait Host {
    /// Log `message` with `status` through the host's logger; returns `status`.
    fn fail(&self, status: c_int, message: &str) -> c_int;
}

/// The outputs of an instance while its step calls the host back (FMI 3.0 intermediate
/// update): the instance's address, the time (s) and the Float64 outputs by value
/// reference. Kept per thread: the host's callback runs on the thread that steps.
pub struct Intermediate {
    /// Address of the component being stepped.
    pub component: usize,
    /// Time after the solver step (s).
    pub time: f64,
    /// Float64 outputs by value reference.
    pub values: Vec<(u32, f64)>,
    /// Value reference of the independent variable `time`.
    pub time_vr: u32,
    /// Logs an error through the instance's logger (the instance itself is being stepped).
    pub report: Rc<dyn Fn(&str)>,
}

thread_local! {
    static STEPPING: Cell<usize> = const { Cell::new(0) };
    static INTERMEDIATE: RefCell<Option<Intermediate>> = const { RefCell::new(None) };
}

/// Call `host` (the host's intermediate-update callback) with `values` readable through
/// [`intermediate_value`], the component at `c` marked busy meanwhile: a call into it other
/// than an intermediate read answers `Error` without touching it (it is being stepped),
/// logged through `report` ([`refuse_intermediate`]).
pub fn during_intermediate<R>(
    c: usize,
    (time, time_vr): (f64, u32),
    values: Vec<(u32, f64)>,
    report: Rc<dyn Fn(&str)>,
    host: impl FnOnce() -> R,
) -> R {
    STEPPING.with(|s| s.set(c));
    INTERMEDIATE.with(|i| {
        *i.borrow_mut() = Some(Intermediate {
            component: c,
            time,
            values,
            time_vr,
            report,
        })
    });
    let r = host();
    INTERMEDIATE.with(|i| *i.borrow_mut() = None);
    STEPPING.with(|s| s.set(0));
    r
}

/// During an intermediate update of the component at `c`: the value of `vr` (`time` or an
/// output), `Some(None)` for a variable not readable then; `None` outside one.
pub fn intermediate_value(c: usize, vr: u32) -> Option<Option<f64>> {
    INTERMEDIATE.with(|i| {
        let i = i.borrow();
        let i = i.as_ref().filter(|i| i.component == c)?;
        Some(if vr == i.time_vr {
            Some(i.time)
        } else {
            i.values.iter().find(|(v, _)| *v == vr).map(|(_, x)| *x)
        })
    })
}

/// Whether the component at `c` is inside its own step's intermediate update.
pub fn in_intermediate(c: usize) -> bool {
    c != 0 && STEPPING.with(|s| s.get()) == c
}

/// A call `what` into the component at `c` inside its own step's intermediate update,
/// refused with `Error` and logged with `why` through the instance's logger.
pub fn refuse_intermediate(c: usize, what: &str, why: &str) -> c_int {
    let report = INTERMEDIATE.with(|i| {
        i.borrow()
            .as_ref()
            .filter(|i| i.component == c)
            .map(|i| i.report.clone())
    });
    if let Some(report) = report {
        report(&format!("{what}: {why}"));
    }
    ERROR
}

/// Run `body` on the component behind `c`, catching panics and turning errors into a
/// logged error status (a panic into `Fatal`). A call into a component that is inside its
/// own step's intermediate update answers `Error` without touching it.
pub fn with<C: Host>(
    c: *mut c_void,
    what: &str,
    body: impl FnOnce(&mut C) -> Result<c_int, String>,
) -> c_int {
    if c.is_null() {
        return ERROR;
    }
    if in_intermediate(c as usize) {
        return refuse_intermediate(
            c as usize,
            what,
            "not allowed inside this instance's intermediate update (it is being stepped): only fmi3GetFloat64 of `time` and the outputs",
        );
    }
    // SAFETY: a non-null component is a pointer returned by the instantiate function of its
    // API and not yet freed (the host's duty under the FMI standard); one call at a time.
    let comp = unsafe { &mut *(c as *mut C) };
    match catch_unwind(AssertUnwindSafe(|| body(comp))) {
        Ok(Ok(status)) => status,
        Ok(Err(msg)) => comp.fail(ERROR, &format!("{what}: {msg}")),
        Err(p) => {
            let why = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            comp.fail(FATAL, &format!("{what}: internal error (panic): {why}"))
        }
    }
}

/// A slice from a host pointer and length, refusing a null pointer with a non-zero length.
///
/// # Safety
///
/// `p` points to `n` readable values when it is not null.
pub unsafe fn slice<'a, T>(p: *const T, n: usize, name: &str) -> Result<&'a [T], String> {
    if n == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(format!("{name} is a null pointer for {n} values"));
    }
    // SAFETY: the host promises `n` readable values at `p` (FMI 2.0 2.1.7, FMI 3.0 2.2.6).
    Ok(unsafe { std::slice::from_raw_parts(p, n) })
}

/// A mutable slice from a host pointer and length, as [`slice`].
///
/// # Safety
///
/// `p` points to `n` writable values when it is not null.
pub unsafe fn slice_mut<'a, T>(p: *mut T, n: usize, name: &str) -> Result<&'a mut [T], String> {
    if n == 0 {
        return Ok(&mut []);
    }
    if p.is_null() {
        return Err(format!("{name} is a null pointer for {n} values"));
    }
    // SAFETY: the host promises `n` writable values at `p`.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

/// A host string, `None` when null.
///
/// # Safety
///
/// `p` is null or NUL-terminated.
pub unsafe fn text(p: *const c_char) -> Option<String> {
    if p.is_null() {
        return None;
    }
    // SAFETY: a non-null string from the host is NUL-terminated.
    Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
}
