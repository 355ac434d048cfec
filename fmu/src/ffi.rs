//! The FMI 2.0 Co-Simulation C API.
//!
//! Every exported function is a thin wrapper over a body it shares with FMI 3.0 (the crate's
//! `component`, `values` and `fmu_state` modules), run inside the panic barrier
//! ([`crate::host::with`]), so no panic crosses into the host; a panic becomes `fmi2Fatal`
//! with a log message. Pointers from the host are checked there (null, and
//! lengths before building slices); everything else is the safe [`Slave`]: a forging
//! [`crate::Instance`] or a press plant ([`crate::press::Press`]).

#![allow(non_snake_case, non_camel_case_types, clippy::missing_safety_doc)]

use crate::component::{self, Component};
use crate::host::{slice_mut, text, DISCARD, OK};
use crate::instance::Phase;
use crate::logging::{Callback, Env, Fmi2Logger, Log};
use crate::slave::Slave;
use crate::{fmu_state, resources, values};
use std::ffi::{c_char, c_int, c_uint, c_void};

/// `fmi2Status` (the same codes as `fmi3Status`, [`crate::host`]).
pub type fmi2Status = c_int;

/// The model of an FMI 2.0 component: a forging scene or a press plant.
type Fmi2 = Box<dyn Slave>;

/// `fmi2CallbackFunctions`.
#[repr(C)]
pub struct CallbackFunctions {
    logger: Option<Fmi2Logger>,
    allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    step_finished: Option<unsafe extern "C" fn(Env, fmi2Status)>,
    component_environment: Env,
}

#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: *const c_char,
    fmu_type: c_int,
    guid: *const c_char,
    resource_location: *const c_char,
    functions: *const CallbackFunctions,
    _visible: c_int,
    logging_on: c_int,
) -> *mut c_void {
    // SAFETY: checked non-null; copied out, the host may free its struct afterwards.
    let (logger, env) = if functions.is_null() {
        (None, std::ptr::null_mut())
    } else {
        unsafe { ((*functions).logger, (*functions).component_environment) }
    };
    let callback = logger.map(Callback::Fmi2);
    let make = || -> Result<Component<Fmi2>, String> {
        if fmu_type != 1 {
            return Err(
                "this FMU supports Co-Simulation only (fmuType must be fmi2CoSimulation)".into(),
            );
        }
        // SAFETY (all three): host strings, NUL-terminated when non-null.
        let name = unsafe { text(instance_name) }.ok_or("instanceName is null")?;
        let uri = unsafe { text(resource_location) }
            .ok_or("fmuResourceLocation is null: the scene lives in resources/")?;
        let folder = resources::uri_to_path(&uri)
            .ok_or_else(|| format!("fmuResourceLocation `{uri}` is not a file: URI"))?;
        let model = resources::slave(&folder)?;
        resources::check_token(unsafe { text(guid) }, "GUID", model.guid(), "model")?;
        let log = Log::new(callback, env, &name, logging_on != 0);
        Ok(Component::new(model, log))
    };
    // SAFETY: the host's logger, environment and instance name as received.
    unsafe {
        component::instantiate::<Fmi2>("fmi2Instantiate", (callback, env, instance_name), make)
    }
}

// Freeing, leaving initialization, terminating and resetting, over the bodies FMI 3.0 shares.
component::entry_points! {
    model: Fmi2, free: fmi2FreeInstance,
    exit_initialization: fmi2ExitInitializationMode, terminate: fmi2Terminate, reset: fmi2Reset,
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: *mut c_void,
    on: c_int,
    n: usize,
    categories: *const *const c_char,
) -> fmi2Status {
    // SAFETY: `n` category strings at `categories`.
    unsafe {
        component::set_debug_logging::<Fmi2>(c, "fmi2SetDebugLogging", on != 0, n, categories)
    }
}

#[no_mangle]
pub extern "C" fn fmi2SetupExperiment(
    c: *mut c_void,
    _tol_defined: c_int,
    _tol: f64,
    start: f64,
    stop_defined: c_int,
    stop: f64,
) -> fmi2Status {
    let stop = (stop_defined != 0).then_some(stop);
    component::call::<Fmi2>(c, "fmi2SetupExperiment", |s| {
        s.setup_experiment(start, stop)
    })
}

#[no_mangle]
pub extern "C" fn fmi2EnterInitializationMode(c: *mut c_void) -> fmi2Status {
    component::call::<Fmi2>(c, "fmi2EnterInitializationMode", |s| {
        s.enter_initialization()
    })
}

/// `fmi2Get<Type>` and `fmi2Set<Type>` of a type of variables: the slave's getter and
/// setter over the host's arrays ([`values::get`], [`values::set`]).
macro_rules! scalars {
    ($($get:ident, $set:ident: $t:ty => $getter:ident, $setter:ident;)*) => {$(
        #[no_mangle]
        pub unsafe extern "C" fn $get(
            c: *mut c_void,
            vr: *const c_uint,
            n: usize,
            values: *mut $t,
        ) -> fmi2Status {
            let call = (stringify!($get), stringify!($get));
            // SAFETY: `n` value references and `n` output slots from the host.
            unsafe { values::get::<Fmi2, _>(c, call, ((vr, n), (values, n)), |s, v| s.$getter(v)) }
        }

        #[no_mangle]
        pub unsafe extern "C" fn $set(
            c: *mut c_void,
            vr: *const c_uint,
            n: usize,
            values: *const $t,
        ) -> fmi2Status {
            let call = (stringify!($set), stringify!($set));
            // SAFETY: `n` value references and `n` values from the host.
            unsafe {
                values::set::<Fmi2, _>(c, call, ((vr, n), (values, n)), |s, v, x| s.$setter(v, x))
            }
        }
    )*};
}

scalars! {
    fmi2GetReal, fmi2SetReal: f64 => get_real, set_real;
    fmi2GetInteger, fmi2SetInteger: c_int => get_integer, set_integer;
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetString(
    c: *mut c_void,
    vr: *const c_uint,
    n: usize,
    values: *mut *const c_char,
) -> fmi2Status {
    let arrays = ((vr, n), (values, n));
    // SAFETY: `n` value references and `n` output slots from the host.
    unsafe {
        values::get_strings::<Fmi2>(c, ("fmi2GetString", "String"), arrays, |s, v| {
            s.get_string(v)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetString(
    c: *mut c_void,
    vr: *const c_uint,
    n: usize,
    values: *const *const c_char,
) -> fmi2Status {
    let arrays = ((vr, n), (values, n));
    // SAFETY: `n` value references and `n` NUL-terminated strings from the host.
    unsafe {
        values::set_strings::<Fmi2>(c, ("fmi2SetString", "String"), arrays, |s, v, x| {
            s.set_string(v, x)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: *mut c_void,
    _vr: *const c_uint,
    n: usize,
    _values: *mut c_int,
) -> fmi2Status {
    values::none::<Fmi2>(c, "fmi2GetBoolean", n, "Boolean")
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: *mut c_void,
    _vr: *const c_uint,
    n: usize,
    _values: *const c_int,
) -> fmi2Status {
    values::none::<Fmi2>(c, "fmi2SetBoolean", n, "Boolean")
}

#[no_mangle]
pub extern "C" fn fmi2DoStep(c: *mut c_void, t: f64, h: f64, _no_prior: c_int) -> fmi2Status {
    component::call::<Fmi2>(c, "fmi2DoStep", |s| s.do_step(t, h))
}

// The FMU-state functions, over the bodies FMI 3.0 shares.
fmu_state::entry_points! {
    model: Fmi2, byte: c_char,
    get: fmi2GetFMUstate, set: fmi2SetFMUstate, free: fmi2FreeFMUstate,
    size: fmi2SerializedFMUstateSize, serialize: fmi2SerializeFMUstate,
    deserialize: fmi2DeSerializeFMUstate,
}

#[no_mangle]
pub extern "C" fn fmi2CancelStep(c: *mut c_void) -> fmi2Status {
    component::not_provided::<Fmi2>(
        c,
        "fmi2CancelStep",
        "steps run synchronously; there is nothing to cancel",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: *mut c_void,
    _vr: *const c_uint,
    _n: usize,
    _order: *const c_int,
    _v: *const f64,
) -> fmi2Status {
    component::not_provided::<Fmi2>(
        c,
        "fmi2SetRealInputDerivatives",
        "input derivatives are not supported (canInterpolateInputs = false)",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: *mut c_void,
    _vr: *const c_uint,
    _n: usize,
    _order: *const c_int,
    _v: *mut f64,
) -> fmi2Status {
    component::not_provided::<Fmi2>(
        c,
        "fmi2GetRealOutputDerivatives",
        "output derivatives are not provided (maxOutputDerivativeOrder = 0)",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: *mut c_void,
    _u: *const c_uint,
    _nu: usize,
    _z: *const c_uint,
    _nz: usize,
    _dv: *const f64,
    _dz: *mut f64,
) -> fmi2Status {
    component::not_provided::<Fmi2>(
        c,
        "fmi2GetDirectionalDerivative",
        "directional derivatives are not provided",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStatus(
    c: *mut c_void,
    _kind: c_int,
    _value: *mut c_int,
) -> fmi2Status {
    component::with::<Fmi2>(c, "fmi2GetStatus", |_| Ok(DISCARD))
}

/// `fmi2Get<Type>Status` named `what` of the one `kind` of that type the FMU reports: the
/// slave's answer in the host's one `value` (`Discard` for another kind).
///
/// # Safety
///
/// `value` is one writable value.
unsafe fn status<T>(
    c: *mut c_void,
    what: &str,
    (kind, reported): (c_int, c_int),
    value: *mut T,
    answer: impl FnOnce(&dyn Slave) -> T,
) -> fmi2Status {
    component::with::<Fmi2>(c, what, |comp| {
        if kind != reported {
            return Ok(DISCARD);
        }
        // SAFETY: as the caller promises.
        let out = unsafe { slice_mut(value, 1, "value") }?;
        out[0] = answer(comp.model.as_ref());
        Ok(OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: *mut c_void,
    kind: c_int,
    value: *mut f64,
) -> fmi2Status {
    // SAFETY: one writable value; `fmi2LastSuccessfulTime`.
    unsafe { status(c, "fmi2GetRealStatus", (kind, 2), value, |s| s.time()) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: *mut c_void,
    _kind: c_int,
    _value: *mut c_int,
) -> fmi2Status {
    component::with::<Fmi2>(c, "fmi2GetIntegerStatus", |_| Ok(DISCARD))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: *mut c_void,
    kind: c_int,
    value: *mut c_int,
) -> fmi2Status {
    // SAFETY: one writable value; `fmi2Terminated`.
    unsafe {
        status(c, "fmi2GetBooleanStatus", (kind, 3), value, |s| {
            c_int::from(s.phase() == Phase::Terminated)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: *mut c_void,
    _kind: c_int,
    _value: *mut *const c_char,
) -> fmi2Status {
    component::with::<Fmi2>(c, "fmi2GetStringStatus", |_| Ok(DISCARD))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::host::ERROR;

    #[test]
    fn null_component_and_bad_instantiation_are_errors_not_crashes() {
        assert_eq!(fmi2DoStep(std::ptr::null_mut(), 0.0, 1.0, 1), ERROR);
        // SAFETY: all pointers null or valid literals.
        let c = unsafe {
            fmi2Instantiate(
                c"x".as_ptr(),
                1,
                std::ptr::null(),
                c"file:///nonexistent".as_ptr(),
                std::ptr::null(),
                0,
                0,
            )
        };
        assert!(c.is_null());
    }
}
