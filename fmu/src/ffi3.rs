//! The FMI 3.0 Co-Simulation C API over the same [`Instance`] as FMI 2.0 ([`crate::ffi`]).
//!
//! Every exported function runs its body inside [`host::with`] (no panic crosses into the
//! host; an error is logged through the host's `logMessage` and returned as `fmi3Error`),
//! most of them a thin wrapper over a body shared with FMI 2.0 (the crate's `component`,
//! `values` and `fmu_state` modules). The variables are the 2.0 table's with the same value
//! references (`Float64`, `Int32`, `String`), plus the independent variable `time` and the
//! early-return switches (`Boolean` `<tool>.early_return.contact` and `.force`, `Float64`
//! `.force_level`): with `earlyReturnAllowed`, `fmi3DoStep` ends at the solver step where
//! an armed event happens, with `earlyReturn` and `lastSuccessfulTime`. With
//! `output.pressure_stations` in the scene, `<tool>.contact_pressure` is a `Float64` array
//! output (one value per station). With an `intermediateUpdate` callback, it is called
//! after every solver step (on the thread that steps, while the host waits in
//! `fmi3DoStep`); the time and the outputs are readable in it, and with early return
//! allowed it may ask the step to return there. Every function of the standard's headers is
//! exported (importers such as fmpy bind them all); the other types, Model Exchange,
//! Scheduled Execution, event mode, clocks and derivatives are not provided and answer
//! `fmi3Error` with a message naming what was asked.

#![allow(non_snake_case, non_camel_case_types, clippy::missing_safety_doc)]

use crate::component::{self, Component};
use crate::host::{self, slice, slice_mut, text, ERROR, OK};
use crate::instance::Instance;
use crate::logging::{self, Callback, Env, Fmi3LogMessage, Log};
use crate::slave::Slave;
use crate::{fmu_state, resources, values};
use rkforge_core::Error;
use std::ffi::{c_char, c_int, c_void};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::rc::Rc;
use std::sync::Arc;

/// `fmi3Status`.
pub type fmi3Status = c_int;
/// `fmi3ValueReference`.
type Vr = u32;
/// `fmi3IntermediateUpdateCallback`: called after every solver step of a `fmi3DoStep`.
type IntermediateUpdate =
    unsafe extern "C" fn(Env, f64, bool, bool, bool, bool, *mut bool, *mut f64);

/// The model of an FMI 3.0 component: the forging instance and what the importer asked at
/// instantiation.
struct Fmi3 {
    instance: Instance,
    time_vr: Vr,
    /// The importer allows `fmi3DoStep` to return early (`earlyReturnAllowed`).
    early_return: bool,
    /// The importer's intermediate-update callback.
    intermediate_update: Option<IntermediateUpdate>,
}

impl component::Model for Fmi3 {
    const ARRAYS: [&'static str; 2] = ["valueReferences", "values"];
    fn slave(&self) -> &dyn Slave {
        &self.instance
    }
    fn slave_mut(&mut self) -> &mut dyn Slave {
        &mut self.instance
    }
}

/// The host's environment pointer, carried into the stepping thread (the host's callback
/// is called there while the host waits in `fmi3DoStep`).
#[derive(Clone, Copy)]
struct HostEnv(Env);
// SAFETY: the pointer is only handed back to the host's own callback, synchronously, while
// the host's thread is blocked in fmi3DoStep.
unsafe impl Send for HostEnv {}

/// The instance's logger, carried into its step's intermediate updates to log the calls
/// refused there.
struct HostLog(Log);
// SAFETY: as `HostEnv`: the logger's environment and callback are only used synchronously,
// while the host's thread is blocked in fmi3DoStep.
unsafe impl Send for HostLog {}
unsafe impl Sync for HostLog {}

impl HostEnv {
    /// The pointer (a method, so that a closure captures the whole `HostEnv`).
    fn get(self) -> Env {
        self.0
    }
}

#[no_mangle]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    c: *mut c_void,
    on: bool,
    n: usize,
    categories: *const *const c_char,
) -> fmi3Status {
    // SAFETY: `n` category strings at `categories`.
    unsafe { component::set_debug_logging::<Fmi3>(c, "fmi3SetDebugLogging", on, n, categories) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instance_name: *const c_char,
    token: *const c_char,
    resource_path: *const c_char,
    _visible: bool,
    logging_on: bool,
    event_mode_used: bool,
    early_return_allowed: bool,
    _required_intermediate: *const Vr,
    _n_required_intermediate: usize,
    env: Env,
    log_message: Option<Fmi3LogMessage>,
    intermediate_update: Option<IntermediateUpdate>,
) -> *mut c_void {
    let callback = log_message.map(Callback::Fmi3);
    let make = || -> Result<Component<Fmi3>, String> {
        // SAFETY (all three): host strings, NUL-terminated when non-null.
        let name = unsafe { text(instance_name) }.ok_or("instanceName is null")?;
        if event_mode_used {
            return Err("eventModeUsed: this FMU has no event mode (hasEventMode = false)".into());
        }
        let folder = unsafe { text(resource_path) }
            .ok_or("resourcePath is null: the scene lives in resources/")?;
        let instance = resources::scene_instance(std::path::Path::new(&folder))?;
        let given = unsafe { text(token) };
        resources::check_token(given, "instantiationToken", instance.guid(), "scene")?;
        let model = Fmi3 {
            time_vr: instance.time_value_reference(),
            instance,
            early_return: early_return_allowed,
            intermediate_update,
        };
        Ok(Component::new(
            model,
            Log::new(callback, env, &name, logging_on),
        ))
    };
    // SAFETY: the host's callback and environment as received; FMI 3.0's logger takes no
    // instance name.
    unsafe {
        component::instantiate::<Fmi3>(
            "fmi3InstantiateCoSimulation",
            (callback, env, std::ptr::null()),
            make,
        )
    }
}

/// The instantiate function `what` of an interface type other than Co-Simulation: logs
/// that this FMU is Co-Simulation only and gives null.
///
/// # Safety
///
/// `env` is the environment the host gave with `log_message`.
unsafe fn co_simulation_only(
    what: &str,
    env: Env,
    log_message: Option<Fmi3LogMessage>,
) -> *mut c_void {
    let message = format!("{what}: this FMU is Co-Simulation only");
    // SAFETY: as the caller promises.
    unsafe {
        logging::early(
            log_message.map(Callback::Fmi3),
            env,
            std::ptr::null(),
            &message,
        )
    };
    std::ptr::null_mut()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    _instance_name: *const c_char,
    _token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    env: Env,
    log_message: Option<Fmi3LogMessage>,
) -> *mut c_void {
    // SAFETY: the host's callback and environment as received.
    unsafe { co_simulation_only("fmi3InstantiateModelExchange", env, log_message) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    _instance_name: *const c_char,
    _token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    env: Env,
    log_message: Option<Fmi3LogMessage>,
    _clock_update: *mut c_void,
    _lock: *mut c_void,
    _unlock: *mut c_void,
) -> *mut c_void {
    // SAFETY: the host's callback and environment as received.
    unsafe { co_simulation_only("fmi3InstantiateScheduledExecution", env, log_message) }
}

// Freeing, leaving initialization, terminating and resetting, over the bodies FMI 2.0 shares.
component::entry_points! {
    model: Fmi3, free: fmi3FreeInstance,
    exit_initialization: fmi3ExitInitializationMode, terminate: fmi3Terminate, reset: fmi3Reset,
}

#[no_mangle]
pub extern "C" fn fmi3EnterInitializationMode(
    c: *mut c_void,
    _tolerance_defined: bool,
    _tolerance: f64,
    start: f64,
    stop_defined: bool,
    stop: f64,
) -> fmi3Status {
    component::call::<Fmi3>(c, "fmi3EnterInitializationMode", |s| {
        s.setup_experiment(start, stop_defined.then_some(stop))?;
        s.enter_initialization()
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetFloat64(
    c: *mut c_void,
    vr: *const Vr,
    n_vr: usize,
    values: *mut f64,
    n_values: usize,
) -> fmi3Status {
    if host::in_intermediate(c as usize) {
        return intermediate_floats(c as usize, vr, n_vr, values, n_values);
    }
    component::with::<Fmi3>(c, "fmi3GetFloat64", |comp| {
        let (instance, time_vr) = (&mut comp.model.instance, comp.model.time_vr);
        // SAFETY: `n_vr` value references and `n_values` output slots from the host.
        let vrs = unsafe { slice(vr, n_vr, "valueReferences") }?;
        let out = unsafe { slice_mut(values, n_values, "values") }?;
        let sizes: Vec<usize> = vrs
            .iter()
            .map(|v| instance.array_len(*v).unwrap_or(1))
            .collect();
        let total: usize = sizes.iter().sum();
        if total != n_values {
            return Err(format!(
                "{n_values} values for {n_vr} value references holding {total} values"
            ));
        }
        let mut at = 0;
        for (v, n) in vrs.iter().zip(sizes) {
            if instance.array_len(*v).is_some() {
                let array = instance.get_real_array(*v).map_err(|e| e.to_string())?;
                out[at..at + n].copy_from_slice(&array);
            } else {
                out[at] = if *v == time_vr {
                    instance.time()
                } else {
                    instance.get_real(*v).map_err(|e| e.to_string())?
                };
            }
            at += n;
        }
        Ok(OK)
    })
}

/// `fmi3GetFloat64` inside an intermediate update: the time and the outputs after the
/// solver step, from [`host::intermediate_value`]; anything else is an error (the instance
/// is being stepped and is not touched).
unsafe fn intermediate_floats(
    c: usize,
    vr: *const Vr,
    n_vr: usize,
    values: *mut f64,
    n_values: usize,
) -> fmi3Status {
    let read = || -> Result<(), String> {
        values::scalars("Float64", n_vr, n_values)?;
        // SAFETY: as in fmi3GetFloat64.
        let vrs = unsafe { slice(vr, n_vr, "valueReferences") }?;
        let out = unsafe { slice_mut(values, n_values, "values") }?;
        for (v, o) in vrs.iter().zip(out.iter_mut()) {
            *o = host::intermediate_value(c, *v)
                .flatten()
                .ok_or("not an output")?;
        }
        Ok(())
    };
    match catch_unwind(AssertUnwindSafe(read)) {
        Ok(Ok(())) => OK,
        Ok(Err(why)) => host::refuse_intermediate(c, "fmi3GetFloat64", &format!("inside the intermediate update: {why} (only `time` and the outputs are readable then)")),
        Err(_) => host::refuse_intermediate(c, "fmi3GetFloat64", "inside the intermediate update: internal error (panic)"),
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetFloat64(
    c: *mut c_void,
    vr: *const Vr,
    n_vr: usize,
    values: *const f64,
    n_values: usize,
) -> fmi3Status {
    let arrays = ((vr, n_vr), (values, n_values));
    // SAFETY: the host's arrays, checked in values::set.
    unsafe {
        values::set::<Fmi3, _>(c, ("fmi3SetFloat64", "Float64"), arrays, |m, v, x| {
            if v == m.time_vr {
                return Err(Error::Request(
                    "`time` is the independent variable and cannot be set".into(),
                ));
            }
            m.instance.set_real(v, x)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetString(
    c: *mut c_void,
    vr: *const Vr,
    n_vr: usize,
    values: *mut *const c_char,
    n_values: usize,
) -> fmi3Status {
    let arrays = ((vr, n_vr), (values, n_values));
    // SAFETY: the host's arrays, checked in values::get_strings.
    unsafe {
        values::get_strings::<Fmi3>(c, ("fmi3GetString", "String"), arrays, |m, v| {
            m.instance.get_string(v)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetString(
    c: *mut c_void,
    vr: *const Vr,
    n_vr: usize,
    values: *const *const c_char,
    n_values: usize,
) -> fmi3Status {
    let arrays = ((vr, n_vr), (values, n_values));
    // SAFETY: the host's arrays, checked in values::set_strings; each string NUL-terminated.
    unsafe {
        values::set_strings::<Fmi3>(c, ("fmi3SetString", "fmi3SetString"), arrays, |m, v, x| {
            m.instance.set_string(v, x)
        })
    }
}

/// `fmi3Get<Type>` and `fmi3Set<Type>` of a type of scalar variables: the instance's getter
/// and setter over the host's arrays ([`values::get`], [`values::set`]).
macro_rules! scalars {
    ($($get:ident, $set:ident: $t:ty => $getter:ident, $setter:ident;)*) => {$(
        #[no_mangle]
        pub unsafe extern "C" fn $get(
            c: *mut c_void,
            vr: *const Vr,
            n_vr: usize,
            values: *mut $t,
            n_values: usize,
        ) -> fmi3Status {
            let (call, arrays) = (stringify!($get), ((vr, n_vr), (values, n_values)));
            // SAFETY: the host's arrays, checked in values::get.
            unsafe { values::get::<Fmi3, _>(c, (call, call), arrays, |m, v| m.instance.$getter(v)) }
        }

        #[no_mangle]
        pub unsafe extern "C" fn $set(
            c: *mut c_void,
            vr: *const Vr,
            n_vr: usize,
            values: *const $t,
            n_values: usize,
        ) -> fmi3Status {
            let (call, arrays) = (stringify!($set), ((vr, n_vr), (values, n_values)));
            // SAFETY: the host's arrays, checked in values::set.
            unsafe {
                values::set::<Fmi3, _>(c, (call, call), arrays, |m, v, x| m.instance.$setter(v, x))
            }
        }
    )*};
}

scalars! {
    fmi3GetInt32, fmi3SetInt32: i32 => get_integer, set_integer;
    fmi3GetBoolean, fmi3SetBoolean: bool => get_boolean, set_boolean;
}

/// Getters and setters of the types this FMU has no variables of: fine for no value
/// references, an error naming the type otherwise.
macro_rules! no_variables {
    ($($name:ident($t:ty), $type_name:literal;)*) => {$(
        #[no_mangle]
        pub unsafe extern "C" fn $name(
            c: *mut c_void,
            _vr: *const Vr,
            n_vr: usize,
            _values: $t,
            _n_values: usize,
        ) -> fmi3Status {
            values::none::<Fmi3>(c, stringify!($name), n_vr, $type_name)
        }
    )*};
}

no_variables! {
    fmi3GetFloat32(*mut f32), "Float32";
    fmi3SetFloat32(*const f32), "Float32";
    fmi3GetInt8(*mut i8), "Int8";
    fmi3SetInt8(*const i8), "Int8";
    fmi3GetUInt8(*mut u8), "UInt8";
    fmi3SetUInt8(*const u8), "UInt8";
    fmi3GetInt16(*mut i16), "Int16";
    fmi3SetInt16(*const i16), "Int16";
    fmi3GetUInt16(*mut u16), "UInt16";
    fmi3SetUInt16(*const u16), "UInt16";
    fmi3GetUInt32(*mut u32), "UInt32";
    fmi3SetUInt32(*const u32), "UInt32";
    fmi3GetInt64(*mut i64), "Int64";
    fmi3SetInt64(*const i64), "Int64";
    fmi3GetUInt64(*mut u64), "UInt64";
    fmi3SetUInt64(*const u64), "UInt64";
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetBinary(
    c: *mut c_void,
    _vr: *const Vr,
    n_vr: usize,
    _sizes: *mut usize,
    _values: *mut *const u8,
    _n_values: usize,
) -> fmi3Status {
    values::none::<Fmi3>(c, "fmi3GetBinary", n_vr, "Binary")
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetBinary(
    c: *mut c_void,
    _vr: *const Vr,
    n_vr: usize,
    _sizes: *const usize,
    _values: *const *const u8,
    _n_values: usize,
) -> fmi3Status {
    values::none::<Fmi3>(c, "fmi3SetBinary", n_vr, "Binary")
}

/// Functions of capabilities this FMU does not declare: always `fmi3Error` naming what was
/// asked.
macro_rules! not_provided {
    ($($name:ident($($arg:ident: $t:ty),*), $why:literal;)*) => {$(
        #[no_mangle]
        pub unsafe extern "C" fn $name(c: *mut c_void, $($arg: $t),*) -> fmi3Status {
            $(let _ = $arg;)*
            component::not_provided::<Fmi3>(c, stringify!($name), $why)
        }
    )*};
}

not_provided! {
    fmi3GetClock(vr: *const Vr, n: usize, values: *mut bool), "this FMU has no clocks";
    fmi3SetClock(vr: *const Vr, n: usize, values: *const bool), "this FMU has no clocks";
    fmi3EnterEventMode(), "this FMU has no event mode (hasEventMode = false)";
    fmi3EnterStepMode(), "this FMU has no event mode; it is in Step Mode after initialization";
    fmi3EnterConfigurationMode(), "this FMU has no structural parameters";
    fmi3ExitConfigurationMode(), "this FMU has no structural parameters";
    fmi3EvaluateDiscreteStates(), "this FMU has no event mode";
    fmi3UpdateDiscreteStates(a: *mut bool, b: *mut bool, d: *mut bool, e: *mut bool, f: *mut bool, g: *mut f64), "this FMU has no event mode";
    fmi3GetNumberOfVariableDependencies(vr: Vr, n: *mut usize), "variable dependencies are not provided";
    fmi3GetVariableDependencies(vr: Vr, a: *mut usize, b: *mut Vr, d: *mut usize, e: *mut c_int, n: usize), "variable dependencies are not provided";
    fmi3GetDirectionalDerivative(u: *const Vr, nu: usize, k: *const Vr, nk: usize, seed: *const f64, ns: usize, out: *mut f64, no: usize), "directional derivatives are not provided";
    fmi3GetAdjointDerivative(u: *const Vr, nu: usize, k: *const Vr, nk: usize, seed: *const f64, ns: usize, out: *mut f64, no: usize), "adjoint derivatives are not provided";
    fmi3GetOutputDerivatives(vr: *const Vr, n: usize, orders: *const i32, values: *mut f64, nv: usize), "output derivatives are not provided (maxOutputDerivativeOrder = 0)";
    fmi3GetIntervalDecimal(vr: *const Vr, n: usize, i: *mut f64, q: *mut c_int), "this FMU has no clocks";
    fmi3GetIntervalFraction(vr: *const Vr, n: usize, a: *mut u64, b: *mut u64, q: *mut c_int), "this FMU has no clocks";
    fmi3GetShiftDecimal(vr: *const Vr, n: usize, s: *mut f64), "this FMU has no clocks";
    fmi3GetShiftFraction(vr: *const Vr, n: usize, a: *mut u64, b: *mut u64), "this FMU has no clocks";
    fmi3SetIntervalDecimal(vr: *const Vr, n: usize, i: *const f64), "this FMU has no clocks";
    fmi3SetIntervalFraction(vr: *const Vr, n: usize, a: *const u64, b: *const u64), "this FMU has no clocks";
    fmi3SetShiftDecimal(vr: *const Vr, n: usize, s: *const f64), "this FMU has no clocks";
    fmi3SetShiftFraction(vr: *const Vr, n: usize, a: *const u64, b: *const u64), "this FMU has no clocks";
    fmi3EnterContinuousTimeMode(), "this FMU is Co-Simulation only (no Model Exchange)";
    fmi3CompletedIntegratorStep(no_set: bool, event: *mut bool, terminate: *mut bool), "this FMU is Co-Simulation only (no Model Exchange)";
    fmi3SetTime(time: f64), "this FMU is Co-Simulation only (no Model Exchange)";
    fmi3SetContinuousStates(x: *const f64, n: usize), "this FMU is Co-Simulation only (no Model Exchange)";
    fmi3GetContinuousStateDerivatives(dx: *mut f64, n: usize), "this FMU is Co-Simulation only (no Model Exchange)";
    fmi3GetEventIndicators(z: *mut f64, n: usize), "this FMU is Co-Simulation only (no Model Exchange)";
    fmi3GetContinuousStates(x: *mut f64, n: usize), "this FMU is Co-Simulation only (no Model Exchange)";
    fmi3GetNominalsOfContinuousStates(x: *mut f64, n: usize), "this FMU is Co-Simulation only (no Model Exchange)";
    fmi3GetNumberOfEventIndicators(n: *mut usize), "this FMU is Co-Simulation only (no Model Exchange)";
    fmi3GetNumberOfContinuousStates(n: *mut usize), "this FMU is Co-Simulation only (no Model Exchange)";
    fmi3ActivateModelPartition(clock: Vr, time: f64), "this FMU is Co-Simulation only (no Scheduled Execution)";
}

#[no_mangle]
pub unsafe extern "C" fn fmi3DoStep(
    c: *mut c_void,
    t: f64,
    h: f64,
    _no_set_state_prior: bool,
    event_handling_needed: *mut bool,
    terminate_simulation: *mut bool,
    early_return: *mut bool,
    last_successful_time: *mut f64,
) -> fmi3Status {
    component::with::<Fmi3>(c, "fmi3DoStep", |comp| {
        let model = &mut comp.model;
        // SAFETY: one writable value each, from the host.
        let event = unsafe { slice_mut(event_handling_needed, 1, "eventHandlingNeeded") }?;
        let terminate = unsafe { slice_mut(terminate_simulation, 1, "terminateSimulation") }?;
        let early = unsafe { slice_mut(early_return, 1, "earlyReturn") }?;
        let last = unsafe { slice_mut(last_successful_time, 1, "lastSuccessfulTime") }?;
        let stepped = match model.intermediate_update {
            Some(update) => {
                let (env, key, early, time_vr) = (
                    HostEnv(comp.log.env()),
                    c as usize,
                    model.early_return,
                    model.time_vr,
                );
                let log = Arc::new(HostLog(comp.log.clone()));
                let mut observe = move |time: f64, outputs: &[(Vr, f64)]| -> bool {
                    let (mut requested, mut when) = (false, 0.0);
                    let log = log.clone();
                    let report: Rc<dyn Fn(&str)> = Rc::new(move |m: &str| log.0.log(ERROR, m));
                    host::during_intermediate(
                        key,
                        (time, time_vr),
                        outputs.to_vec(),
                        report,
                        || {
                            // SAFETY: the host's callback with its environment and two
                            // writable locals, called synchronously.
                            unsafe {
                                update(
                                    env.get(),
                                    time,
                                    false,
                                    true,
                                    true,
                                    early,
                                    &mut requested,
                                    &mut when,
                                )
                            }
                        },
                    );
                    requested
                };
                model.instance.do_step_observed(t, h, early, &mut observe)
            }
            None if model.early_return => model.instance.do_step_early(t, h),
            None => model.instance.do_step(t, h).map(|()| None),
        };
        event[0] = false;
        terminate[0] = false;
        early[0] = matches!(stepped, Ok(Some(_)));
        last[0] = model.instance.time();
        stepped.map(|_| OK).map_err(|e| e.to_string())
    })
}

// The FMU-state functions, over the bodies FMI 2.0 shares.
fmu_state::entry_points! {
    model: Fmi3, byte: u8,
    get: fmi3GetFMUState, set: fmi3SetFMUState, free: fmi3FreeFMUState,
    size: fmi3SerializedFMUStateSize, serialize: fmi3SerializeFMUState,
    deserialize: fmi3DeserializeFMUState,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn null_instance_and_bad_instantiation_are_errors_not_crashes() {
        // SAFETY: null pointers are checked before use.
        let status = unsafe {
            fmi3DoStep(
                std::ptr::null_mut(),
                0.0,
                1.0,
                false,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            )
        };
        assert_eq!(status, ERROR);
        // SAFETY: valid literals and nulls.
        let c = unsafe {
            fmi3InstantiateCoSimulation(
                c"x".as_ptr(),
                std::ptr::null(),
                c"/nonexistent/".as_ptr(),
                false,
                false,
                false,
                false,
                std::ptr::null(),
                0,
                std::ptr::null_mut(),
                None,
                None,
            )
        };
        assert!(c.is_null());
    }
}
