//! FMU states across the C boundary, in FMI 2.0 and 3.0 alike: a handle is a boxed
//! [`Saved`] (the slave's own state, serialized only when the host asks for bytes); these are
//! the bodies of `GetFMUState`, `SetFMUState`, `FreeFMUState` and the serialization calls.

use crate::component::{with, Model};
use crate::host::{slice, slice_mut, OK};
use crate::slave::Saved;
use std::ffi::{c_int, c_void};

/// The saved state behind a handle.
///
/// # Safety
///
/// `handle` is null or a state made here and not yet freed.
unsafe fn state<'a>(handle: *mut c_void) -> Result<&'a Saved, String> {
    if handle.is_null() {
        return Err("FMUState is null".into());
    }
    // SAFETY: made by `get` or `deserialize` and not yet freed.
    Ok(unsafe { &*(handle as *const Saved) })
}

/// A new handle holding `saved` in the host's one-value slot.
///
/// # Safety
///
/// `slot` is one writable pointer slot.
unsafe fn hand_out(slot: *mut *mut c_void, saved: Saved) -> Result<(), String> {
    // SAFETY: as the caller promises.
    let slot = unsafe { slice_mut(slot, 1, "FMUState") }?;
    slot[0] = Box::into_raw(Box::new(saved)) as *mut c_void;
    Ok(())
}

/// `GetFMUState`: a new handle holding the slave's [`crate::Slave::save`] in the host's slot
/// (the state the slot held, if any, is freed).
///
/// # Safety
///
/// `slot` is a writable pointer slot holding null or a state made here.
pub unsafe fn get<M: Model>(c: *mut c_void, what: &str, slot: *mut *mut c_void) -> c_int {
    with::<M>(c, what, |comp| {
        // SAFETY: as the caller promises; a non-null state given back to us was made here
        // and not yet freed.
        unsafe {
            free(slot);
            hand_out(slot, comp.model.slave().save())
        }
        .map(|()| OK)
    })
}

/// `SetFMUState`: the slave continues from the state behind `handle`.
///
/// # Safety
///
/// `handle` is null or a state made here and not yet freed.
pub unsafe fn set<M: Model>(c: *mut c_void, what: &str, handle: *mut c_void) -> c_int {
    with::<M>(c, what, |comp| {
        // SAFETY: as the caller promises.
        let saved = unsafe { state(handle) }?;
        comp.model
            .slave_mut()
            .load(saved)
            .map(|()| OK)
            .map_err(|e| e.to_string())
    })
}

/// Free the state in the host's slot and null it.
///
/// # Safety
///
/// `slot` is null or a slot holding null or a state made here.
unsafe fn free(slot: *mut *mut c_void) {
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

/// `FreeFMUState`: free the state in the host's slot and null it.
///
/// # Safety
///
/// As [`free`].
pub unsafe fn release<M: Model>(c: *mut c_void, what: &str, slot: *mut *mut c_void) -> c_int {
    with::<M>(c, what, |_| {
        // SAFETY: as the caller promises.
        unsafe { free(slot) };
        Ok(OK)
    })
}

/// The serialized bytes of the state behind `handle`.
///
/// # Safety
///
/// As [`state`].
unsafe fn bytes_of<M: Model>(model: &M, handle: *mut c_void) -> Result<Vec<u8>, String> {
    // SAFETY: as the caller promises.
    let saved = unsafe { state(handle) }?;
    model.slave().serialize(saved).map_err(|e| e.to_string())
}

/// `SerializedFMUStateSize`, into the host's one-value `size`.
///
/// # Safety
///
/// As [`state`]; `size` is one writable value.
pub unsafe fn size<M: Model>(
    c: *mut c_void,
    what: &str,
    handle: *mut c_void,
    size: *mut usize,
) -> c_int {
    with::<M>(c, what, |comp| {
        // SAFETY: as the caller promises.
        let n = unsafe { bytes_of(&comp.model, handle) }?.len();
        unsafe { slice_mut(size, 1, "size") }?[0] = n;
        Ok(OK)
    })
}

/// `SerializeFMUState` into `size` bytes at `bytes` (`size` must be the serialized size);
/// a byte is `fmi2Byte` or `fmi3Byte`.
///
/// # Safety
///
/// As [`state`]; `bytes` holds `size` writable bytes.
pub unsafe fn serialize<M: Model, B>(
    c: *mut c_void,
    what: &str,
    handle: *mut c_void,
    (bytes, size): (*mut B, usize),
) -> c_int {
    with::<M>(c, what, |comp| {
        // SAFETY: as the caller promises.
        let data = unsafe { bytes_of(&comp.model, handle) }?;
        if data.len() != size {
            return Err(format!(
                "size {size} does not match the serialized size {}",
                data.len()
            ));
        }
        unsafe { slice_mut(bytes.cast::<u8>(), size, "serializedState") }?.copy_from_slice(&data);
        Ok(OK)
    })
}

/// `DeserializeFMUState`: a new state from `size` serialized bytes, into the host's slot.
///
/// # Safety
///
/// `bytes` holds `size` readable bytes; `slot` is one writable pointer slot.
pub unsafe fn deserialize<M: Model, B>(
    c: *mut c_void,
    what: &str,
    (bytes, size): (*const B, usize),
    slot: *mut *mut c_void,
) -> c_int {
    with::<M>(c, what, |comp| {
        // SAFETY: as the caller promises.
        let data = unsafe { slice(bytes.cast::<u8>(), size, "serializedState") }?;
        let saved = comp
            .model
            .slave()
            .deserialize(data)
            .map_err(|e| e.to_string())?;
        unsafe { hand_out(slot, saved) }.map(|()| OK)
    })
}

/// The six FMU-state entry points of an API under its names, each a thin wrapper over the
/// body above of the same role: `model` is the API's [`Model`], `byte` its byte type
/// (`fmi2Byte`, `fmi3Byte`).
macro_rules! entry_points {
    (@slot $model:ty, $name:ident = $body:ident) => {
        #[no_mangle]
        pub unsafe extern "C" fn $name(
            c: *mut ::std::ffi::c_void,
            slot: *mut *mut ::std::ffi::c_void,
        ) -> ::std::ffi::c_int {
            // SAFETY: the host's slot for the state pointer, holding null or a state made
            // here.
            unsafe { $crate::fmu_state::$body::<$model>(c, stringify!($name), slot) }
        }
    };
    (
        model: $model:ty, byte: $byte:ty,
        get: $get:ident, set: $set:ident, free: $free:ident,
        size: $size:ident, serialize: $serialize:ident, deserialize: $deserialize:ident $(,)?
    ) => {
        $crate::fmu_state::entry_points!(@slot $model, $get = get);

        #[no_mangle]
        pub unsafe extern "C" fn $set(
            c: *mut ::std::ffi::c_void,
            state: *mut ::std::ffi::c_void,
        ) -> ::std::ffi::c_int {
            // SAFETY: made by the get or deserialize function and not yet freed.
            unsafe { $crate::fmu_state::set::<$model>(c, stringify!($set), state) }
        }
        $crate::fmu_state::entry_points!(@slot $model, $free = release);

        #[no_mangle]
        pub unsafe extern "C" fn $size(
            c: *mut ::std::ffi::c_void,
            state: *mut ::std::ffi::c_void,
            size: *mut usize,
        ) -> ::std::ffi::c_int {
            // SAFETY: a state made here; one writable size slot.
            unsafe { $crate::fmu_state::size::<$model>(c, stringify!($size), state, size) }
        }

        #[no_mangle]
        pub unsafe extern "C" fn $serialize(
            c: *mut ::std::ffi::c_void,
            state: *mut ::std::ffi::c_void,
            bytes: *mut $byte,
            size: usize,
        ) -> ::std::ffi::c_int {
            // SAFETY: a state made here; `size` writable bytes.
            unsafe {
                $crate::fmu_state::serialize::<$model, $byte>(
                    c,
                    stringify!($serialize),
                    state,
                    (bytes, size),
                )
            }
        }

        #[no_mangle]
        pub unsafe extern "C" fn $deserialize(
            c: *mut ::std::ffi::c_void,
            bytes: *const $byte,
            size: usize,
            slot: *mut *mut ::std::ffi::c_void,
        ) -> ::std::ffi::c_int {
            // SAFETY: `size` readable bytes; one writable slot.
            unsafe {
                $crate::fmu_state::deserialize::<$model, $byte>(
                    c,
                    stringify!($deserialize),
                    (bytes, size),
                    slot,
                )
            }
        }
    };
}
pub(crate) use entry_points;
