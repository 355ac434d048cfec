//! What the host's instance pointer points to, in FMI 2.0 and 3.0 alike: a [`Component`]
//! holding the API's model, its [`Log`] and the strings last handed out; made, called and
//! freed here, every call through the panic barrier ([`host::with`]). The exported functions
//! of [`crate::ffi`] and [`crate::ffi3`] are thin wrappers over these bodies, the
//! get/set loops of [`crate::values`] and the FMU states of [`crate::fmu_state`].

use crate::host::{self, Host, OK};
use crate::logging::{self, Callback, Env, Log};
use crate::slave::Slave;
use std::ffi::{c_char, c_int, c_void, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// The model behind a component: FMI 2.0's slave (a forging scene or a press plant) or FMI
/// 3.0's co-simulation of a forging scene.
pub trait Model {
    /// The names the API's headers give the arrays of value references and of values of a
    /// get or set call (in errors).
    const ARRAYS: [&'static str; 2];
    /// The slave, for the calls both APIs make alike.
    fn slave(&self) -> &dyn Slave;
    /// The slave, to change.
    fn slave_mut(&mut self) -> &mut dyn Slave;
}

impl Model for Box<dyn Slave> {
    const ARRAYS: [&'static str; 2] = ["vr", "value"];
    fn slave(&self) -> &dyn Slave {
        self.as_ref()
    }
    fn slave_mut(&mut self) -> &mut dyn Slave {
        self.as_mut()
    }
}

/// One instance as the host holds it.
pub struct Component<M> {
    /// The API's model.
    pub model: M,
    /// The host's logger and what it asked to be logged.
    pub log: Log,
    /// The strings handed out by the last `GetString`, alive until the next.
    pub strings: Vec<CString>,
}

impl<M> Component<M> {
    /// A component of `model` logging through `log`.
    pub fn new(model: M, log: Log) -> Component<M> {
        Component {
            model,
            log,
            strings: Vec::new(),
        }
    }
}

impl<M> Host for Component<M> {
    fn fail(&self, status: c_int, message: &str) -> c_int {
        self.log.log(status, message);
        status
    }
}

/// [`host::with`] on a component of model `M`: `body` runs on it inside the panic barrier.
pub fn with<M: Model>(
    c: *mut c_void,
    what: &str,
    body: impl FnOnce(&mut Component<M>) -> Result<c_int, String>,
) -> c_int {
    host::with::<Component<M>>(c, what, body)
}

/// The body of an instantiate function named `what`: `make` builds the component, checking
/// the host's arguments in the API's order; its error or panic is logged through `logger`
/// (the host's callback, its environment and instance name, [`logging::early`]) and gives
/// null.
///
/// # Safety
///
/// `logger` is as [`logging::early`] asks.
pub unsafe fn instantiate<M: Model>(
    what: &str,
    logger: (Option<Callback>, Env, *const c_char),
    make: impl FnOnce() -> Result<Component<M>, String>,
) -> *mut c_void {
    let failure = match catch_unwind(AssertUnwindSafe(make)) {
        Ok(Ok(c)) => return Box::into_raw(Box::new(c)) as *mut c_void,
        Ok(Err(msg)) => format!("{what}: {msg}"),
        Err(_) => format!("{what}: internal error (panic)"),
    };
    let (callback, env, name) = logger;
    // SAFETY: as the caller promises.
    unsafe { logging::early(callback, env, name, &failure) };
    std::ptr::null_mut()
}

/// `FreeInstance`: free the component behind `c`, catching a panic.
///
/// # Safety
///
/// `c` is null or a component of model `M` made by [`instantiate`] and not yet freed.
pub unsafe fn free<M: Model>(c: *mut c_void) {
    if !c.is_null() {
        // SAFETY: as the caller promises; the host frees it once.
        let _ = catch_unwind(AssertUnwindSafe(|| {
            drop(unsafe { Box::from_raw(c as *mut Component<M>) })
        }));
    }
}

/// A call of the slave's state machine (initialization, step, terminate, reset): `OK`, or
/// the slave's error.
pub fn call<M: Model>(
    c: *mut c_void,
    what: &str,
    body: impl FnOnce(&mut dyn Slave) -> rkforge_core::Result<()>,
) -> c_int {
    with::<M>(c, what, |comp| {
        body(comp.model.slave_mut())
            .map(|()| OK)
            .map_err(|e| e.to_string())
    })
}

/// `SetDebugLogging` with `on` and the `n` categories at `categories`.
///
/// # Safety
///
/// `categories` holds `n` NUL-terminated strings when `n` is not zero.
pub unsafe fn set_debug_logging<M: Model>(
    c: *mut c_void,
    what: &str,
    on: bool,
    n: usize,
    categories: *const *const c_char,
) -> c_int {
    with::<M>(c, what, |comp| {
        // SAFETY: as the caller promises.
        unsafe { comp.log.set(on, n, categories) }.map(|()| OK)
    })
}

/// A function of a capability the FMU does not declare: an error saying `why`.
pub fn not_provided<M: Model>(c: *mut c_void, what: &str, why: &str) -> c_int {
    with::<M>(c, what, |_| Err(why.into()))
}

/// The life-cycle entry points an API shares with the other, under its names: freeing the
/// instance, leaving initialization, terminating and resetting, each a thin wrapper over
/// [`free`] or [`call`]; `model` is the API's [`Model`].
macro_rules! entry_points {
    (
        model: $model:ty, free: $free:ident,
        exit_initialization: $exit:ident, terminate: $terminate:ident, reset: $reset:ident $(,)?
    ) => {
        #[no_mangle]
        pub unsafe extern "C" fn $free(c: *mut ::std::ffi::c_void) {
            // SAFETY: made by the API's instantiate function and not yet freed (the host's
            // duty).
            unsafe { $crate::component::free::<$model>(c) }
        }

        #[no_mangle]
        pub extern "C" fn $exit(c: *mut ::std::ffi::c_void) -> ::std::ffi::c_int {
            $crate::component::call::<$model>(c, stringify!($exit), |s| s.exit_initialization())
        }

        #[no_mangle]
        pub extern "C" fn $terminate(c: *mut ::std::ffi::c_void) -> ::std::ffi::c_int {
            $crate::component::call::<$model>(c, stringify!($terminate), |s| s.terminate())
        }

        #[no_mangle]
        pub extern "C" fn $reset(c: *mut ::std::ffi::c_void) -> ::std::ffi::c_int {
            $crate::component::call::<$model>(c, stringify!($reset), |s| {
                s.reset();
                Ok(())
            })
        }
    };
}
pub(crate) use entry_points;
