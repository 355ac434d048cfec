//! The FMI 2.0 Co-Simulation C API.
//!
//! Every exported function is a thin forwarder that runs its body inside
//! [`std::panic::catch_unwind`], so no panic crosses into the host; a panic becomes
//! `fmi2Fatal` with a log message. Pointers from the host are checked here (null, and
//! lengths before building slices); everything else is the safe [`Instance`].

#![allow(non_snake_case, non_camel_case_types, clippy::missing_safety_doc)]

use crate::{press, Instance, Phase, Slave};
use std::ffi::{c_char, c_int, c_uint, c_void, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// `fmi2Status` (the same codes as `fmi3Status`, [`crate::host`]).
pub type fmi2Status = c_int;
use crate::host::{self, slice, slice_mut, text, Host, DISCARD, ERROR, OK};

type Env = *mut c_void;
type Logger =
    unsafe extern "C" fn(Env, *const c_char, fmi2Status, *const c_char, *const c_char, ...);

/// `fmi2CallbackFunctions`.
#[repr(C)]
pub struct CallbackFunctions {
    logger: Option<Logger>,
    allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    step_finished: Option<unsafe extern "C" fn(Env, fmi2Status)>,
    component_environment: Env,
}

/// What the host's `fmi2Component` points to.
pub struct Component {
    model: Box<dyn Slave>,
    name: CString,
    logger: Option<Logger>,
    env: Env,
    logging: bool,
    categories: [bool; 3],
    strings: Vec<CString>,
}

impl Component {
    fn log(&self, status: fmi2Status, message: &str) {
        let category = host::category(status);
        if !(self.logging && (self.categories[category] || self.categories[2])) {
            return;
        }
        if let Some(logger) = self.logger {
            let msg = CString::new(message.replace('\0', " ")).unwrap_or_default();
            let cat = CString::new(host::CATEGORY_NAMES[category]).unwrap_or_default();
            // SAFETY: the host gave this logger for this environment; the format string is a
            // literal "%s" and its one argument a valid NUL-terminated string.
            unsafe {
                logger(
                    self.env,
                    self.name.as_ptr(),
                    status,
                    cat.as_ptr(),
                    c"%s".as_ptr(),
                    msg.as_ptr(),
                )
            };
        }
    }
}

impl Host for Component {
    fn fail(&self, status: fmi2Status, message: &str) -> fmi2Status {
        self.log(status, message);
        status
    }
}

/// [`host::with`] on an FMI 2.0 [`Component`].
fn with(
    c: *mut c_void,
    what: &str,
    body: impl FnOnce(&mut Component) -> Result<fmi2Status, String>,
) -> fmi2Status {
    host::with::<Component>(c, what, body)
}

/// The slave the FMU's resources describe: a press plant (`press.toml`: `press = "crank"`)
/// or a forging scene (`scene.toml`).
fn slave(folder: &std::path::Path) -> Result<Box<dyn Slave>, String> {
    let press = folder.join("press.toml");
    if press.is_file() {
        let text = std::fs::read_to_string(&press)
            .map_err(|e| format!("cannot read {}: {e}", press.display()))?;
        let name = text
            .lines()
            .find_map(|l| l.trim().strip_prefix("press = "))
            .map(|v| v.trim().trim_matches('"'))
            .unwrap_or_default();
        let kind = press::parse(name).ok_or_else(|| {
            format!(
                "{}: `press = \"{name}\"` is no press of rkforge",
                press.display()
            )
        })?;
        return Ok(Box::new(press::Press::new(kind)));
    }
    let path = folder.join("scene.toml");
    let scene = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    Ok(Box::new(
        Instance::new(&scene, &path.display().to_string()).map_err(|e| e.to_string())?,
    ))
}

/// The folder of a `file:` URI (`file:///a/b%20c`, `file:/a/b`).
fn uri_to_path(uri: &str) -> Option<std::path::PathBuf> {
    let rest = uri
        .strip_prefix("file://")
        .map(|r| r.strip_prefix("localhost").unwrap_or(r))
        .or_else(|| uri.strip_prefix("file:"))?;
    let mut out = Vec::new();
    let b = rest.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = std::str::from_utf8(&b[i + 1..i + 3]).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    Some(std::path::PathBuf::from(String::from_utf8(out).ok()?))
}

#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// Report a problem before a component exists, through the host's logger.
unsafe fn log_early(f: *const CallbackFunctions, name: *const c_char, message: &str) {
    if f.is_null() {
        return;
    }
    // SAFETY: checked non-null; the host's callback struct lives through fmi2Instantiate.
    let f = unsafe { &*f };
    if let Some(logger) = f.logger {
        let msg = CString::new(message.replace('\0', " ")).unwrap_or_default();
        let name = if name.is_null() {
            c"rkforge".as_ptr()
        } else {
            name
        };
        // SAFETY: as in Component::log.
        unsafe {
            logger(
                f.component_environment,
                name,
                ERROR,
                c"logStatusError".as_ptr(),
                c"%s".as_ptr(),
                msg.as_ptr(),
            )
        };
    }
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
    let made = catch_unwind(AssertUnwindSafe(|| -> Result<Box<Component>, String> {
        if fmu_type != 1 {
            return Err(
                "this FMU supports Co-Simulation only (fmuType must be fmi2CoSimulation)".into(),
            );
        }
        // SAFETY (all three): host strings, NUL-terminated when non-null.
        let name = unsafe { text(instance_name) }.ok_or("instanceName is null")?;
        let uri = unsafe { text(resource_location) }
            .ok_or("fmuResourceLocation is null: the scene lives in resources/")?;
        let folder = uri_to_path(&uri)
            .ok_or_else(|| format!("fmuResourceLocation `{uri}` is not a file: URI"))?;
        let model = slave(&folder)?;
        if let Some(g) = unsafe { text(guid) } {
            if g != model.guid() {
                return Err(format!(
                    "GUID {g} does not match the model in resources/ ({})",
                    model.guid()
                ));
            }
        }
        // SAFETY: checked non-null; copied out, the host may free its struct afterwards.
        let (logger, env) = if functions.is_null() {
            (None, std::ptr::null_mut())
        } else {
            unsafe { ((*functions).logger, (*functions).component_environment) }
        };
        Ok(Box::new(Component {
            model,
            name: CString::new(name.replace('\0', " ")).unwrap_or_default(),
            logger,
            env,
            logging: logging_on != 0,
            categories: [true; 3],
            strings: Vec::new(),
        }))
    }));
    match made {
        Ok(Ok(c)) => Box::into_raw(c) as *mut c_void,
        Ok(Err(msg)) => {
            // SAFETY: pointers as received from the host.
            unsafe { log_early(functions, instance_name, &format!("fmi2Instantiate: {msg}")) };
            std::ptr::null_mut()
        }
        Err(_) => {
            // SAFETY: as above.
            unsafe {
                log_early(
                    functions,
                    instance_name,
                    "fmi2Instantiate: internal error (panic)",
                )
            };
            std::ptr::null_mut()
        }
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: *mut c_void) {
    // SAFETY: made by fmi2Instantiate and not yet freed (the host's duty).
    unsafe { host::free::<Component>(c) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: *mut c_void,
    on: c_int,
    n: usize,
    categories: *const *const c_char,
) -> fmi2Status {
    with(c, "fmi2SetDebugLogging", |comp| {
        // SAFETY: `n` category strings at `categories`.
        let wanted = unsafe { host::wanted_categories(n, categories) }?;
        comp.logging = on != 0;
        comp.categories = wanted;
        Ok(OK)
    })
}

#[no_mangle]
pub extern "C" fn fmi2SetupExperiment(
    c: *mut c_void,
    _tol_defined: c_int,
    _tol: f64,
    start: f64,
    _stop_defined: c_int,
    _stop: f64,
) -> fmi2Status {
    with(c, "fmi2SetupExperiment", |comp| {
        comp.model
            .setup_experiment(start)
            .map(|_| OK)
            .map_err(|e| e.to_string())
    })
}

#[no_mangle]
pub extern "C" fn fmi2EnterInitializationMode(c: *mut c_void) -> fmi2Status {
    with(c, "fmi2EnterInitializationMode", |comp| {
        comp.model
            .enter_initialization()
            .map(|_| OK)
            .map_err(|e| e.to_string())
    })
}

#[no_mangle]
pub extern "C" fn fmi2ExitInitializationMode(c: *mut c_void) -> fmi2Status {
    with(c, "fmi2ExitInitializationMode", |comp| {
        comp.model
            .exit_initialization()
            .map(|_| OK)
            .map_err(|e| e.to_string())
    })
}

#[no_mangle]
pub extern "C" fn fmi2Terminate(c: *mut c_void) -> fmi2Status {
    with(c, "fmi2Terminate", |comp| {
        comp.model
            .terminate()
            .map(|_| OK)
            .map_err(|e| e.to_string())
    })
}

#[no_mangle]
pub extern "C" fn fmi2Reset(c: *mut c_void) -> fmi2Status {
    with(c, "fmi2Reset", |comp| {
        comp.model.reset();
        Ok(OK)
    })
}

macro_rules! getter {
    ($fname:ident, $t:ty, $get:ident, $conv:expr) => {
        #[no_mangle]
        pub unsafe extern "C" fn $fname(
            c: *mut c_void,
            vr: *const c_uint,
            n: usize,
            values: *mut $t,
        ) -> fmi2Status {
            with(c, stringify!($fname), |comp| {
                // SAFETY: `n` value references and `n` output slots from the host.
                let vrs = unsafe { slice(vr, n, "vr") }?;
                let out = unsafe { slice_mut(values, n, "value") }?;
                for (v, o) in vrs.iter().zip(out.iter_mut()) {
                    let x = comp.model.$get(*v).map_err(|e| e.to_string())?;
                    *o = $conv(x);
                }
                Ok(OK)
            })
        }
    };
}

getter!(fmi2GetReal, f64, get_real, |x| x);
getter!(fmi2GetInteger, c_int, get_integer, |x| x);

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: *mut c_void,
    _vr: *const c_uint,
    n: usize,
    _values: *mut c_int,
) -> fmi2Status {
    with(c, "fmi2GetBoolean", |_| {
        if n == 0 {
            Ok(OK)
        } else {
            Err("this FMU has no Boolean variables".into())
        }
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetString(
    c: *mut c_void,
    vr: *const c_uint,
    n: usize,
    values: *mut *const c_char,
) -> fmi2Status {
    with(c, "fmi2GetString", |comp| {
        // SAFETY: as in the getters above.
        let vrs = unsafe { slice(vr, n, "vr") }?;
        let out = unsafe { slice_mut(values, n, "value") }?;
        comp.strings.clear();
        for v in vrs {
            let s = comp.model.get_string(*v).map_err(|e| e.to_string())?;
            comp.strings.push(CString::new(s).unwrap_or_default());
        }
        for (o, s) in out.iter_mut().zip(&comp.strings) {
            *o = s.as_ptr();
        }
        Ok(OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetReal(
    c: *mut c_void,
    vr: *const c_uint,
    n: usize,
    values: *const f64,
) -> fmi2Status {
    with(c, "fmi2SetReal", |comp| {
        // SAFETY: `n` value references and `n` values from the host.
        let vrs = unsafe { slice(vr, n, "vr") }?;
        let vals = unsafe { slice(values, n, "value") }?;
        for (v, x) in vrs.iter().zip(vals) {
            comp.model.set_real(*v, *x).map_err(|e| e.to_string())?;
        }
        Ok(OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetInteger(
    c: *mut c_void,
    vr: *const c_uint,
    n: usize,
    values: *const c_int,
) -> fmi2Status {
    with(c, "fmi2SetInteger", |comp| {
        // SAFETY: as in fmi2SetReal.
        let vrs = unsafe { slice(vr, n, "vr") }?;
        let vals = unsafe { slice(values, n, "value") }?;
        for (v, x) in vrs.iter().zip(vals) {
            comp.model.set_integer(*v, *x).map_err(|e| e.to_string())?;
        }
        Ok(OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: *mut c_void,
    _vr: *const c_uint,
    n: usize,
    _values: *const c_int,
) -> fmi2Status {
    with(c, "fmi2SetBoolean", |_| {
        if n == 0 {
            Ok(OK)
        } else {
            Err("this FMU has no Boolean variables".into())
        }
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetString(
    c: *mut c_void,
    vr: *const c_uint,
    n: usize,
    values: *const *const c_char,
) -> fmi2Status {
    with(c, "fmi2SetString", |comp| {
        // SAFETY: as in fmi2SetReal; each string NUL-terminated.
        let vrs = unsafe { slice(vr, n, "vr") }?;
        let vals = unsafe { slice(values, n, "value") }?;
        for (v, p) in vrs.iter().zip(vals) {
            let s = unsafe { text(*p) }.ok_or("a String value is a null pointer")?;
            comp.model.set_string(*v, &s).map_err(|e| e.to_string())?;
        }
        Ok(OK)
    })
}

#[no_mangle]
pub extern "C" fn fmi2DoStep(c: *mut c_void, t: f64, h: f64, _no_prior: c_int) -> fmi2Status {
    with(c, "fmi2DoStep", |comp| {
        comp.model
            .do_step(t, h)
            .map(|_| OK)
            .map_err(|e| e.to_string())
    })
}

#[no_mangle]
pub extern "C" fn fmi2CancelStep(c: *mut c_void) -> fmi2Status {
    with(c, "fmi2CancelStep", |_| {
        Err("steps run synchronously; there is nothing to cancel".into())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: *mut c_void,
    _vr: *const c_uint,
    _n: usize,
    _order: *const c_int,
    _v: *const f64,
) -> fmi2Status {
    with(c, "fmi2SetRealInputDerivatives", |_| {
        Err("input derivatives are not supported (canInterpolateInputs = false)".into())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: *mut c_void,
    _vr: *const c_uint,
    _n: usize,
    _order: *const c_int,
    _v: *mut f64,
) -> fmi2Status {
    with(c, "fmi2GetRealOutputDerivatives", |_| {
        Err("output derivatives are not provided (maxOutputDerivativeOrder = 0)".into())
    })
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
    with(c, "fmi2GetDirectionalDerivative", |_| {
        Err("directional derivatives are not provided".into())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStatus(
    c: *mut c_void,
    _kind: c_int,
    _value: *mut c_int,
) -> fmi2Status {
    with(c, "fmi2GetStatus", |_| Ok(DISCARD))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: *mut c_void,
    kind: c_int,
    value: *mut f64,
) -> fmi2Status {
    with(c, "fmi2GetRealStatus", |comp| {
        if kind != 2 {
            return Ok(DISCARD);
        }
        // SAFETY: one writable value.
        let out = unsafe { slice_mut(value, 1, "value") }?;
        out[0] = comp.model.time();
        Ok(OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: *mut c_void,
    _kind: c_int,
    _value: *mut c_int,
) -> fmi2Status {
    with(c, "fmi2GetIntegerStatus", |_| Ok(DISCARD))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: *mut c_void,
    kind: c_int,
    value: *mut c_int,
) -> fmi2Status {
    with(c, "fmi2GetBooleanStatus", |comp| {
        if kind != 3 {
            return Ok(DISCARD);
        }
        // SAFETY: one writable value.
        let out = unsafe { slice_mut(value, 1, "value") }?;
        out[0] = c_int::from(comp.model.phase() == Phase::Terminated);
        Ok(OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: *mut c_void,
    _kind: c_int,
    _value: *mut *const c_char,
) -> fmi2Status {
    with(c, "fmi2GetStringStatus", |_| Ok(DISCARD))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(c: *mut c_void, slot: *mut *mut c_void) -> fmi2Status {
    with(c, "fmi2GetFMUstate", |comp| {
        // SAFETY: the host's slot for the state pointer.
        unsafe { host::get_state(comp.model.as_ref(), slot) }.map(|()| OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: *mut c_void, state: *mut c_void) -> fmi2Status {
    with(c, "fmi2SetFMUstate", |comp| {
        // SAFETY: made by fmi2GetFMUstate / fmi2DeSerializeFMUstate and not yet freed.
        unsafe { host::set_state(comp.model.as_mut(), state) }.map(|()| OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: *mut c_void, slot: *mut *mut c_void) -> fmi2Status {
    with(c, "fmi2FreeFMUstate", |_| {
        // SAFETY: the host's slot, holding a state made here or null.
        unsafe { host::free_state(slot) };
        Ok(OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: *mut c_void,
    state: *mut c_void,
    size: *mut usize,
) -> fmi2Status {
    with(c, "fmi2SerializedFMUstateSize", |comp| {
        // SAFETY: a state made here; one writable size slot.
        unsafe { host::state_size(comp.model.as_ref(), state, size) }.map(|()| OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: *mut c_void,
    state: *mut c_void,
    bytes: *mut c_char,
    size: usize,
) -> fmi2Status {
    with(c, "fmi2SerializeFMUstate", |comp| {
        // SAFETY: a state made here; `size` writable bytes.
        unsafe { host::serialize_state(comp.model.as_ref(), state, bytes as *mut u8, size) }
            .map(|()| OK)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: *mut c_void,
    bytes: *const c_char,
    size: usize,
    slot: *mut *mut c_void,
) -> fmi2Status {
    with(c, "fmi2DeSerializeFMUstate", |comp| {
        // SAFETY: `size` readable bytes; one writable slot.
        unsafe { host::deserialize_state(comp.model.as_ref(), bytes as *const u8, size, slot) }
            .map(|()| OK)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_uris_become_paths() {
        assert_eq!(
            uri_to_path("file:///tmp/a%20b/resources").unwrap(),
            std::path::PathBuf::from("/tmp/a b/resources")
        );
        assert_eq!(
            uri_to_path("file:/tmp/x").unwrap(),
            std::path::PathBuf::from("/tmp/x")
        );
        assert_eq!(
            uri_to_path("file://localhost/tmp/x").unwrap(),
            std::path::PathBuf::from("/tmp/x")
        );
        assert!(uri_to_path("http://example.org/x").is_none());
    }

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
