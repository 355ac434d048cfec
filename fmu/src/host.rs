//! What the FMI 2.0 and 3.0 C APIs ([`crate::ffi`], [`crate::ffi3`]) share: the status
//! codes (the same numbers in both), the panic barrier every exported function runs its body
//! in, the checked conversions of host pointers, and the FMU state handles (a boxed
//! [`Saved`]).

use crate::{Saved, Slave};
use std::cell::{Cell, RefCell};
use std::ffi::{c_char, c_int, c_void, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

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

/// The log categories both APIs declare (`modelDescription.xml`'s `LogCategories`).
pub const CATEGORY_NAMES: [&str; 3] = ["logStatusWarning", "logStatusError", "logAll"];

/// The category a message of `status` is logged under (an index into [`CATEGORY_NAMES`]).
pub fn category(status: c_int) -> usize {
    match status {
        OK => 2,
        WARNING => 0,
        _ => 1,
    }
}

/// The categories a `SetDebugLogging` call asks for: all when it names none.
///
/// # Safety
///
/// `categories` holds `n` NUL-terminated strings when `n` is not zero.
pub unsafe fn wanted_categories(
    n: usize,
    categories: *const *const c_char,
) -> Result<[bool; 3], String> {
    // SAFETY: `n` category strings at `categories`.
    let list = unsafe { slice(categories, n, "categories") }?;
    let mut wanted = [n == 0; 3];
    for &p in list {
        let name = unsafe { text(p) }.ok_or("a category is a null pointer")?;
        let k = CATEGORY_NAMES
            .iter()
            .position(|c| *c == name)
            .ok_or_else(|| format!("unknown log category `{name}`"))?;
        wanted[k] = true;
    }
    Ok(wanted)
}

/// Free the component behind `c` (made by `Box::into_raw` of a `Box<C>`), catching a panic.
///
/// # Safety
///
/// `c` is null or a component of type `C` made by its API's instantiate function and not
/// yet freed.
pub unsafe fn free<C>(c: *mut c_void) {
    if !c.is_null() {
        // SAFETY: as the caller promises; the host frees it once.
        let _ = catch_unwind(AssertUnwindSafe(|| {
            drop(unsafe { Box::from_raw(c as *mut C) })
        }));
    }
}

/// What the host's instance pointer points to: a slave and the host's logger.
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
}

thread_local! {
    static STEPPING: Cell<usize> = const { Cell::new(0) };
    static INTERMEDIATE: RefCell<Option<Intermediate>> = const { RefCell::new(None) };
}

/// Call `host` (the host's intermediate-update callback) with `values` readable through
/// [`intermediate_value`], the component at `c` marked busy meanwhile: a call into it other
/// than an intermediate read answers `Error` without touching it (it is being stepped).
pub fn during_intermediate<R>(
    c: usize,
    (time, time_vr): (f64, u32),
    values: Vec<(u32, f64)>,
    host: impl FnOnce() -> R,
) -> R {
    STEPPING.with(|s| s.set(c));
    INTERMEDIATE.with(|i| {
        *i.borrow_mut() = Some(Intermediate {
            component: c,
            time,
            values,
            time_vr,
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

/// Run `body` on the component behind `c`, catching panics and turning errors into a
/// logged error status (a panic into `Fatal`). A call into a component that is inside its
/// own step's intermediate update answers `Error` without touching it.
pub fn with<C: Host>(
    c: *mut c_void,
    what: &str,
    body: impl FnOnce(&mut C) -> Result<c_int, String>,
) -> c_int {
    if c.is_null() || in_intermediate(c as usize) {
        return ERROR;
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

/// `GetFMUState`: a new handle holding the slave's [`Slave::save`] in the host's slot (the
/// state the slot held, if any, is freed).
///
/// # Safety
///
/// `slot` is a writable pointer slot holding null or a state made here.
pub unsafe fn get_state(slave: &dyn Slave, slot: *mut *mut c_void) -> Result<(), String> {
    // SAFETY: one writable slot for the state pointer.
    let slot = unsafe { slice_mut(slot, 1, "FMUState") }?;
    if !slot[0].is_null() {
        // SAFETY: a non-null state given back to us was made here and not yet freed.
        drop(unsafe { Box::from_raw(slot[0] as *mut Saved) });
    }
    slot[0] = Box::into_raw(Box::new(slave.save())) as *mut c_void;
    Ok(())
}

/// The saved state behind a handle.
///
/// # Safety
///
/// `handle` is null or a state made here and not yet freed.
pub unsafe fn state<'a>(handle: *mut c_void) -> Result<&'a Saved, String> {
    if handle.is_null() {
        return Err("FMUState is null".into());
    }
    // SAFETY: made by get_state / deserialize_state and not yet freed.
    Ok(unsafe { &*(handle as *const Saved) })
}

/// `SetFMUState`.
///
/// # Safety
///
/// As [`state`].
pub unsafe fn set_state(slave: &mut dyn Slave, handle: *mut c_void) -> Result<(), String> {
    let saved = unsafe { state(handle) }?;
    slave.load(saved).map_err(|e| e.to_string())
}

/// `FreeFMUState`: free the state in the host's slot and null it.
///
/// # Safety
///
/// `slot` is null or a slot holding null or a state made here.
pub unsafe fn free_state(slot: *mut *mut c_void) {
    if slot.is_null() {
        return;
    }
    // SAFETY: `slot` points to a slot holding a state made here, or null.
    let slot = unsafe { &mut *slot };
    if !slot.is_null() {
        drop(unsafe { Box::from_raw(*slot as *mut Saved) });
        *slot = std::ptr::null_mut();
    }
}

/// `SerializedFMUStateSize`.
///
/// # Safety
///
/// As [`state`]; `size` is one writable value.
pub unsafe fn state_size(
    slave: &dyn Slave,
    handle: *mut c_void,
    size: *mut usize,
) -> Result<(), String> {
    let n = slave
        .serialize(unsafe { state(handle) }?)
        .map_err(|e| e.to_string())?
        .len();
    unsafe { slice_mut(size, 1, "size") }?[0] = n;
    Ok(())
}

/// `SerializeFMUState` into `size` bytes at `bytes` (`size` must be the serialized size).
///
/// # Safety
///
/// As [`state`]; `bytes` holds `size` writable bytes.
pub unsafe fn serialize_state(
    slave: &dyn Slave,
    handle: *mut c_void,
    bytes: *mut u8,
    size: usize,
) -> Result<(), String> {
    let data = slave
        .serialize(unsafe { state(handle) }?)
        .map_err(|e| e.to_string())?;
    if data.len() != size {
        return Err(format!(
            "size {size} does not match the serialized size {}",
            data.len()
        ));
    }
    unsafe { slice_mut(bytes, size, "serializedState") }?.copy_from_slice(&data);
    Ok(())
}

/// `DeserializeFMUState`: a new state from `size` serialized bytes, into the host's slot.
///
/// # Safety
///
/// `bytes` holds `size` readable bytes; `slot` is one writable pointer slot.
pub unsafe fn deserialize_state(
    slave: &dyn Slave,
    bytes: *const u8,
    size: usize,
    slot: *mut *mut c_void,
) -> Result<(), String> {
    let data = unsafe { slice(bytes, size, "serializedState") }?;
    let saved = slave.deserialize(data).map_err(|e| e.to_string())?;
    let slot = unsafe { slice_mut(slot, 1, "FMUState") }?;
    slot[0] = Box::into_raw(Box::new(saved)) as *mut c_void;
    Ok(())
}
