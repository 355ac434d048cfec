//! The FMI 3.0 Co-Simulation C API over the same [`Instance`] as FMI 2.0 ([`crate::ffi`]).
//!
//! Every exported function runs its body inside [`host::with`] (no panic crosses into the
//! host; an error is logged through the host's `logMessage` and returned as `fmi3Error`).
//! The variables are the 2.0 table's with the same value references (`Float64`, `Int32`,
//! `String`), plus the independent variable `time` and the early-return switches (`Boolean`
//! `<tool>.early_return.contact` and `.force`, `Float64` `.force_level`): with
//! `earlyReturnAllowed`, `fmi3DoStep` ends at the solver step where an armed event happens,
//! with `earlyReturn` and `lastSuccessfulTime`. With `output.pressure_stations` in the
//! scene, `<tool>.contact_pressure` is a `Float64` array output (one value per station). With
//! an `intermediateUpdate` callback, it
//! is called after every solver step (on the thread that steps, while the host waits in
//! `fmi3DoStep`); the time and the outputs are readable in it, and with early return
//! allowed it may ask the step to return there. Every function of the standard's
//! headers is exported (importers such as fmpy bind them all); the other types, Model
//! Exchange, Scheduled Execution, event mode, clocks and derivatives are not provided and
//! answer `fmi3Error` with a message naming what was asked.

#![allow(non_snake_case, non_camel_case_types, clippy::missing_safety_doc)]

use crate::host::{self, slice, slice_mut, text, Host, ERROR, OK};
use crate::Instance;
use std::ffi::{c_char, c_int, c_void, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// `fmi3Status`.
pub type fmi3Status = c_int;
/// `fmi3ValueReference`.
type Vr = u32;
type Env = *mut c_void;
/// `fmi3LogMessageCallback`.
type LogMessage = unsafe extern "C" fn(Env, fmi3Status, *const c_char, *const c_char);
/// `fmi3IntermediateUpdateCallback`: called after every solver step of a `fmi3DoStep`.
type IntermediateUpdate =
    unsafe extern "C" fn(Env, f64, bool, bool, bool, bool, *mut bool, *mut f64);

/// What the host's `fmi3Instance` points to.
pub struct Component {
    instance: Instance,
    log_message: Option<LogMessage>,
    env: Env,
    logging: bool,
    categories: [bool; 3],
    strings: Vec<CString>,
    time_vr: Vr,
    /// The importer allows `fmi3DoStep` to return early (`earlyReturnAllowed`).
    early_return: bool,
    /// The importer's intermediate-update callback.
    intermediate_update: Option<IntermediateUpdate>,
}

/// The host's environment pointer, carried into the stepping thread (the host's callback
/// is called there while the host waits in `fmi3DoStep`).
#[derive(Clone, Copy)]
struct HostEnv(Env);
// SAFETY: the pointer is only handed back to the host's own callback, synchronously, while
// the host's thread is blocked in fmi3DoStep.
unsafe impl Send for HostEnv {}

impl HostEnv {
    /// The pointer (a method, so that a closure captures the whole `HostEnv`).
    fn get(self) -> Env {
        self.0
    }
}

impl Component {
    fn log(&self, status: fmi3Status, message: &str) {
        let category = host::category(status);
        if !(self.logging && (self.categories[category] || self.categories[2])) {
            return;
        }
        if let Some(log) = self.log_message {
            let msg = CString::new(message.replace('\0', " ")).unwrap_or_default();
            let cat = CString::new(host::CATEGORY_NAMES[category]).unwrap_or_default();
            // SAFETY: the host's callback for this environment, with valid C strings.
            unsafe { log(self.env, status, cat.as_ptr(), msg.as_ptr()) };
        }
    }
}

impl Host for Component {
    fn fail(&self, status: fmi3Status, message: &str) -> fmi3Status {
        self.log(status, message);
        status
    }
}

/// [`host::with`] on an FMI 3.0 [`Component`].
fn with(
    c: *mut c_void,
    what: &str,
    body: impl FnOnce(&mut Component) -> Result<fmi3Status, String>,
) -> fmi3Status {
    host::with::<Component>(c, what, body)
}

/// Scalar variables only: one value per value reference.
fn scalars(what: &str, n_vr: usize, n_values: usize) -> Result<(), String> {
    if n_vr == n_values {
        Ok(())
    } else {
        Err(format!(
            "{n_values} values for {n_vr} value references ({what}: every variable is a scalar)"
        ))
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
    with(c, "fmi3SetDebugLogging", |comp| {
        // SAFETY: `n` category strings at `categories`.
        let wanted = unsafe { host::wanted_categories(n, categories) }?;
        comp.logging = on;
        comp.categories = wanted;
        Ok(OK)
    })
}

/// Report a problem before an instance exists, through the host's `logMessage`.
unsafe fn log_early(log: Option<LogMessage>, env: Env, message: &str) {
    if let Some(log) = log {
        let msg = CString::new(message.replace('\0', " ")).unwrap_or_default();
        // SAFETY: the host's callback with valid C strings.
        unsafe { log(env, ERROR, c"logStatusError".as_ptr(), msg.as_ptr()) };
    }
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
    log_message: Option<LogMessage>,
    intermediate_update: Option<IntermediateUpdate>,
) -> *mut c_void {
    let made = catch_unwind(AssertUnwindSafe(|| -> Result<Box<Component>, String> {
        // SAFETY (all three): host strings, NUL-terminated when non-null.
        unsafe { text(instance_name) }.ok_or("instanceName is null")?;
        if event_mode_used {
            return Err("eventModeUsed: this FMU has no event mode (hasEventMode = false)".into());
        }
        let folder = unsafe { text(resource_path) }
            .ok_or("resourcePath is null: the scene lives in resources/")?;
        let path = std::path::Path::new(&folder).join("scene.toml");
        let scene = std::fs::read_to_string(&path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let instance =
            Instance::new(&scene, &path.display().to_string()).map_err(|e| e.to_string())?;
        if let Some(t) = unsafe { text(token) } {
            if t != instance.guid() {
                return Err(format!(
                    "instantiationToken {t} does not match the scene in resources/ ({})",
                    instance.guid()
                ));
            }
        }
        let time_vr = instance.time_value_reference();
        Ok(Box::new(Component {
            instance,
            log_message,
            env,
            logging: logging_on,
            categories: [true; 3],
            strings: Vec::new(),
            time_vr,
            early_return: early_return_allowed,
            intermediate_update,
        }))
    }));
    match made {
        Ok(Ok(c)) => Box::into_raw(c) as *mut c_void,
        Ok(Err(msg)) => {
            // SAFETY: the host's callback and environment as received.
            unsafe {
                log_early(
                    log_message,
                    env,
                    &format!("fmi3InstantiateCoSimulation: {msg}"),
                )
            };
            std::ptr::null_mut()
        }
        Err(_) => {
            // SAFETY: as above.
            unsafe {
                log_early(
                    log_message,
                    env,
                    "fmi3InstantiateCoSimulation: internal error (panic)",
                )
            };
            std::ptr::null_mut()
        }
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    _instance_name: *const c_char,
    _token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    env: Env,
    log_message: Option<LogMessage>,
) -> *mut c_void {
    // SAFETY: the host's callback and environment as received.
    unsafe {
        log_early(
            log_message,
            env,
            "fmi3InstantiateModelExchange: this FMU is Co-Simulation only",
        )
    };
    std::ptr::null_mut()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    _instance_name: *const c_char,
    _token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    env: Env,
    log_message: Option<LogMessage>,
    _clock_update: *mut c_void,
    _lock: *mut c_void,
    _unlock: *mut c_void,
) -> *mut c_void {
    // SAFETY: the host's callback and environment as received.
    unsafe {
        log_early(
            log_message,
            env,
            "fmi3InstantiateScheduledExecution: this FMU is Co-Simulation only",
        )
    };
    std::ptr::null_mut()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3FreeInstance(c: *mut c_void) {
    // SAFETY: made by fmi3InstantiateCoSimulation and not yet freed (the host's duty).
    unsafe { host::free::<Component>(c) }
}

#[no_mangle]
pub extern "C" fn fmi3EnterInitializationMode(
    c: *mut c_void,
    _tolerance_defined: bool,
    _tolerance: f64,
    start: f64,
    _stop_defined: bool,
    _stop: f64,
) -> fmi3Status {
    with(c, "fmi3EnterInitializationMode", |comp| {
        comp.instance
            .setup_experiment(start)
            .and_then(|()| comp.instance.enter_initialization())
            .map(|()| OK)
            .map_err(|e| e.to_string())
    })
}

#[no_mangle]
pub extern "C" fn fmi3ExitInitializationMode(c: *mut c_void) -> fmi3Status {
    with(c, "fmi3ExitInitializationMode", |comp| {
        comp.instance
            .exit_initialization()
            .map(|()| OK)
            .map_err(|e| e.to_string())
    })
}

#[no_mangle]
pub extern "C" fn fmi3Terminate(c: *mut c_void) -> fmi3Status {
    with(c, "fmi3Terminate", |comp| {
        comp.instance
            .terminate()
            .map(|()| OK)
            .map_err(|e| e.to_string())
    })
}

#[no_mangle]
pub extern "C" fn fmi3Reset(c: *mut c_void) -> fmi3Status {
    with(c, "fmi3Reset", |comp| {
        comp.instance.reset();
        Ok(OK)
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
    with(c, "fmi3GetFloat64", |comp| {
        // SAFETY: `n_vr` value references and `n_values` output slots from the host.
        let vrs = unsafe { slice(vr, n_vr, "valueReferences") }?;
        let out = unsafe { slice_mut(values, n_values, "values") }?;
        let sizes: Vec<usize> = vrs
            .iter()
            .map(|v| comp.instance.array_len(*v).unwrap_or(1))
            .collect();
        let total: usize = sizes.iter().sum();
        if total != n_values {
            return Err(format!(
                "{n_values} values for {n_vr} value references holding {total} values"
            ));
        }
        let mut at = 0;
        for (v, n) in vrs.iter().zip(sizes) {
            if comp.instance.array_len(*v).is_some() {
                let array = comp
                    .instance
                    .get_real_array(*v)
                    .map_err(|e| e.to_string())?;
                out[at..at + n].copy_from_slice(&array);
            } else {
                out[at] = if *v == comp.time_vr {
                    comp.instance.time()
                } else {
                    comp.instance.get_real(*v).map_err(|e| e.to_string())?
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
        scalars("Float64", n_vr, n_values)?;
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
        _ => ERROR,
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
    with(c, "fmi3SetFloat64", |comp| {
        scalars("Float64", n_vr, n_values)?;
        // SAFETY: `n_vr` value references and as many values from the host.
        let vrs = unsafe { slice(vr, n_vr, "valueReferences") }?;
        let vals = unsafe { slice(values, n_values, "values") }?;
        for (v, x) in vrs.iter().zip(vals) {
            if *v == comp.time_vr {
                return Err("`time` is the independent variable and cannot be set".into());
            }
            comp.instance.set_real(*v, *x).map_err(|e| e.to_string())?;
        }
        Ok(OK)
    })
}

/// `fmi3Get<Type>` of scalars: one value per value reference through `get`.
unsafe fn get_scalars<T>(
    c: *mut c_void,
    what: &str,
    (vr, n_vr): (*const Vr, usize),
    (values, n_values): (*mut T, usize),
    get: impl Fn(&mut Instance, Vr) -> crate::Result<T>,
) -> fmi3Status {
    with(c, what, |comp| {
        scalars(what, n_vr, n_values)?;
        // SAFETY: `n_vr` value references and as many output slots from the host.
        let vrs = unsafe { slice(vr, n_vr, "valueReferences") }?;
        let out = unsafe { slice_mut(values, n_values, "values") }?;
        for (v, o) in vrs.iter().zip(out.iter_mut()) {
            *o = get(&mut comp.instance, *v).map_err(|e| e.to_string())?;
        }
        Ok(OK)
    })
}

/// `fmi3Set<Type>` of scalars: one value per value reference through `set`.
unsafe fn set_scalars<T: Copy>(
    c: *mut c_void,
    what: &str,
    (vr, n_vr): (*const Vr, usize),
    (values, n_values): (*const T, usize),
    set: impl Fn(&mut Instance, Vr, T) -> Result<(), String>,
) -> fmi3Status {
    with(c, what, |comp| {
        scalars(what, n_vr, n_values)?;
        // SAFETY: `n_vr` value references and as many values from the host.
        let vrs = unsafe { slice(vr, n_vr, "valueReferences") }?;
        let vals = unsafe { slice(values, n_values, "values") }?;
        for (v, x) in vrs.iter().zip(vals) {
            set(&mut comp.instance, *v, *x)?;
        }
        Ok(OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt32(
    c: *mut c_void,
    vr: *const Vr,
    n_vr: usize,
    values: *mut i32,
    n_values: usize,
) -> fmi3Status {
    // SAFETY: the host's arrays, checked in get_scalars.
    unsafe {
        get_scalars(
            c,
            "fmi3GetInt32",
            (vr, n_vr),
            (values, n_values),
            Instance::get_integer,
        )
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetInt32(
    c: *mut c_void,
    vr: *const Vr,
    n_vr: usize,
    values: *const i32,
    n_values: usize,
) -> fmi3Status {
    // SAFETY: the host's arrays, checked in set_scalars.
    unsafe {
        set_scalars(
            c,
            "fmi3SetInt32",
            (vr, n_vr),
            (values, n_values),
            |i, v, x| i.set_integer(v, x).map_err(|e| e.to_string()),
        )
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetBoolean(
    c: *mut c_void,
    vr: *const Vr,
    n_vr: usize,
    values: *mut bool,
    n_values: usize,
) -> fmi3Status {
    // SAFETY: the host's arrays, checked in get_scalars.
    unsafe {
        get_scalars(
            c,
            "fmi3GetBoolean",
            (vr, n_vr),
            (values, n_values),
            |i, v| i.get_boolean(v),
        )
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetBoolean(
    c: *mut c_void,
    vr: *const Vr,
    n_vr: usize,
    values: *const bool,
    n_values: usize,
) -> fmi3Status {
    // SAFETY: the host's arrays, checked in set_scalars.
    unsafe {
        set_scalars(
            c,
            "fmi3SetBoolean",
            (vr, n_vr),
            (values, n_values),
            |i, v, x| i.set_boolean(v, x).map_err(|e| e.to_string()),
        )
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
    // SAFETY: the host's arrays, checked in set_scalars; each string NUL-terminated.
    unsafe {
        set_scalars(
            c,
            "fmi3SetString",
            (vr, n_vr),
            (values, n_values),
            |i, v, p| {
                let s = text(p).ok_or("a String value is a null pointer")?;
                i.set_string(v, &s).map_err(|e| e.to_string())
            },
        )
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
    with(c, "fmi3GetString", |comp| {
        scalars("String", n_vr, n_values)?;
        // SAFETY: as in fmi3GetFloat64.
        let vrs = unsafe { slice(vr, n_vr, "valueReferences") }?;
        let out = unsafe { slice_mut(values, n_values, "values") }?;
        comp.strings.clear();
        for v in vrs {
            let s = comp.instance.get_string(*v).map_err(|e| e.to_string())?;
            comp.strings.push(CString::new(s).unwrap_or_default());
        }
        for (o, s) in out.iter_mut().zip(&comp.strings) {
            *o = s.as_ptr();
        }
        Ok(OK)
    })
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
            with(c, stringify!($name), |_| {
                if n_vr == 0 {
                    Ok(OK)
                } else {
                    Err(concat!("this FMU has no ", $type_name, " variables").into())
                }
            })
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
    with(c, "fmi3GetBinary", |_| {
        if n_vr == 0 {
            Ok(OK)
        } else {
            Err("this FMU has no Binary variables".into())
        }
    })
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
    with(c, "fmi3SetBinary", |_| {
        if n_vr == 0 {
            Ok(OK)
        } else {
            Err("this FMU has no Binary variables".into())
        }
    })
}

/// Functions of capabilities this FMU does not declare: always `fmi3Error` naming what was
/// asked.
macro_rules! not_provided {
    ($($name:ident($($arg:ident: $t:ty),*), $why:literal;)*) => {$(
        #[no_mangle]
        pub unsafe extern "C" fn $name(c: *mut c_void, $($arg: $t),*) -> fmi3Status {
            $(let _ = $arg;)*
            with(c, stringify!($name), |_| Err($why.into()))
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
    with(c, "fmi3DoStep", |comp| {
        // SAFETY: one writable value each, from the host.
        let event = unsafe { slice_mut(event_handling_needed, 1, "eventHandlingNeeded") }?;
        let terminate = unsafe { slice_mut(terminate_simulation, 1, "terminateSimulation") }?;
        let early = unsafe { slice_mut(early_return, 1, "earlyReturn") }?;
        let last = unsafe { slice_mut(last_successful_time, 1, "lastSuccessfulTime") }?;
        let stepped = match comp.intermediate_update {
            Some(update) => {
                let (env, key, early, time_vr) = (
                    HostEnv(comp.env),
                    c as usize,
                    comp.early_return,
                    comp.time_vr,
                );
                let mut observe = move |time: f64, outputs: &[(Vr, f64)]| -> bool {
                    let (mut requested, mut when) = (false, 0.0);
                    host::during_intermediate(key, (time, time_vr), outputs.to_vec(), || {
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
                    });
                    requested
                };
                comp.instance.do_step_observed(t, h, early, &mut observe)
            }
            None if comp.early_return => comp.instance.do_step_early(t, h),
            None => comp.instance.do_step(t, h).map(|()| None),
        };
        event[0] = false;
        terminate[0] = false;
        early[0] = matches!(stepped, Ok(Some(_)));
        last[0] = comp.instance.time();
        stepped.map(|_| OK).map_err(|e| e.to_string())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetFMUState(c: *mut c_void, slot: *mut *mut c_void) -> fmi3Status {
    with(c, "fmi3GetFMUState", |comp| {
        // SAFETY: the host's slot for the state pointer.
        unsafe { host::get_state(&comp.instance, slot) }.map(|()| OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetFMUState(c: *mut c_void, state: *mut c_void) -> fmi3Status {
    with(c, "fmi3SetFMUState", |comp| {
        // SAFETY: made by fmi3GetFMUState / fmi3DeserializeFMUState and not yet freed.
        unsafe { host::set_state(&mut comp.instance, state) }.map(|()| OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3FreeFMUState(c: *mut c_void, slot: *mut *mut c_void) -> fmi3Status {
    with(c, "fmi3FreeFMUState", |_| {
        // SAFETY: the host's slot, holding a state made here or null.
        unsafe { host::free_state(slot) };
        Ok(OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    c: *mut c_void,
    state: *mut c_void,
    size: *mut usize,
) -> fmi3Status {
    with(c, "fmi3SerializedFMUStateSize", |comp| {
        // SAFETY: a state made here; one writable size slot.
        unsafe { host::state_size(&comp.instance, state, size) }.map(|()| OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    c: *mut c_void,
    state: *mut c_void,
    bytes: *mut u8,
    size: usize,
) -> fmi3Status {
    with(c, "fmi3SerializeFMUState", |comp| {
        // SAFETY: a state made here; `size` writable bytes.
        unsafe { host::serialize_state(&comp.instance, state, bytes, size) }.map(|()| OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    c: *mut c_void,
    bytes: *const u8,
    size: usize,
    slot: *mut *mut c_void,
) -> fmi3Status {
    with(c, "fmi3DeserializeFMUState", |comp| {
        // SAFETY: `size` readable bytes; one writable slot.
        unsafe { host::deserialize_state(&comp.instance, bytes, size, slot) }.map(|()| OK)
    })
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
