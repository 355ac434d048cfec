//! Getting and setting variables through the C APIs, in FMI 2.0 and 3.0 alike: the host's
//! arrays of value references and values (one value per reference, checked), the loops over
//! them, and the strings handed back.

use crate::component::{with, Component, Model};
use crate::host::{slice, slice_mut, text, OK};
use rkforge_core::Error;
use std::ffi::{c_char, c_int, c_void, CString};

/// The host's arrays of one get or set call: the value references and how many, the values
/// and how many.
pub type Arrays<P> = ((*const u32, usize), (P, usize));

// Each call below is named twice, `(what, label)`: `what` prefixes its errors in the log,
// `label` names it in a count mismatch ([`scalars`]; only FMI 3.0 can have one).

/// Scalar variables only: one value per value reference (`label` names the call in the
/// error).
pub fn scalars(label: &str, n_vr: usize, n_values: usize) -> Result<(), String> {
    if n_vr == n_values {
        Ok(())
    } else {
        Err(format!(
            "{n_values} values for {n_vr} value references ({label}: every variable is a scalar)"
        ))
    }
}

/// The host's value references of a call `label` with `n_values` values, one value per
/// reference.
///
/// # Safety
///
/// `vr` holds `n_vr` readable value references when it is not null.
unsafe fn references<'a, M: Model>(
    label: &str,
    (vr, n_vr): (*const u32, usize),
    n_values: usize,
) -> Result<&'a [u32], String> {
    scalars(label, n_vr, n_values)?;
    // SAFETY: as the caller promises.
    unsafe { slice(vr, n_vr, M::ARRAYS[0]) }
}

/// A `Get<Type>` call named `what`: `get` of each value reference into the host's values.
///
/// # Safety
///
/// The arrays hold as many readable value references and writable values as they say, when
/// not null.
pub unsafe fn get<M: Model, T>(
    c: *mut c_void,
    (what, label): (&str, &str),
    (vr, (values, n_values)): Arrays<*mut T>,
    mut get: impl FnMut(&mut M, u32) -> rkforge_core::Result<T>,
) -> c_int {
    with::<M>(c, what, |comp| {
        // SAFETY: as the caller promises.
        let vrs = unsafe { references::<M>(label, vr, n_values) }?;
        let out = unsafe { slice_mut(values, n_values, M::ARRAYS[1]) }?;
        for (v, o) in vrs.iter().zip(out.iter_mut()) {
            *o = get(&mut comp.model, *v).map_err(|e| e.to_string())?;
        }
        Ok(OK)
    })
}

/// A `Set<Type>` call named `what`: `set` of each value reference to the host's value.
///
/// # Safety
///
/// The arrays hold as many readable value references and values as they say, when not null.
pub unsafe fn set<M: Model, T: Copy>(
    c: *mut c_void,
    (what, label): (&str, &str),
    (vr, (values, n_values)): Arrays<*const T>,
    mut set: impl FnMut(&mut M, u32, T) -> rkforge_core::Result<()>,
) -> c_int {
    with::<M>(c, what, |comp| {
        // SAFETY: as the caller promises.
        let vrs = unsafe { references::<M>(label, vr, n_values) }?;
        let vals = unsafe { slice(values, n_values, M::ARRAYS[1]) }?;
        for (v, x) in vrs.iter().zip(vals) {
            set(&mut comp.model, *v, *x).map_err(|e| e.to_string())?;
        }
        Ok(OK)
    })
}

/// A `GetString` call named `what`: the strings of `get`, kept in the component until the
/// next call, their pointers into the host's values.
///
/// # Safety
///
/// As [`get`].
pub unsafe fn get_strings<M: Model>(
    c: *mut c_void,
    (what, label): (&str, &str),
    (vr, (values, n_values)): Arrays<*mut *const c_char>,
    mut get: impl FnMut(&mut M, u32) -> rkforge_core::Result<String>,
) -> c_int {
    with::<M>(c, what, |comp: &mut Component<M>| {
        // SAFETY: as the caller promises.
        let vrs = unsafe { references::<M>(label, vr, n_values) }?;
        let out = unsafe { slice_mut(values, n_values, M::ARRAYS[1]) }?;
        comp.strings.clear();
        for v in vrs {
            let s = get(&mut comp.model, *v).map_err(|e| e.to_string())?;
            comp.strings.push(CString::new(s).unwrap_or_default());
        }
        for (o, s) in out.iter_mut().zip(&comp.strings) {
            *o = s.as_ptr();
        }
        Ok(OK)
    })
}

/// A `SetString` call named `what`: `set` of each value reference to the host's string.
///
/// # Safety
///
/// As [`set`]; each string is NUL-terminated.
pub unsafe fn set_strings<M: Model>(
    c: *mut c_void,
    call: (&str, &str),
    arrays: Arrays<*const *const c_char>,
    mut set: impl FnMut(&mut M, u32, &str) -> rkforge_core::Result<()>,
) -> c_int {
    // SAFETY: as the caller promises.
    unsafe {
        self::set::<M, _>(c, call, arrays, |m, v, p| {
            let s =
                text(p).ok_or_else(|| Error::Request("a String value is a null pointer".into()))?;
            set(m, v, &s)
        })
    }
}

/// A get or set call named `what` of a type the FMU has no variables of (`type_name`): fine
/// for no value references, an error otherwise.
pub fn none<M: Model>(c: *mut c_void, what: &str, n_vr: usize, type_name: &str) -> c_int {
    with::<M>(c, what, |_| {
        if n_vr == 0 {
            Ok(OK)
        } else {
            Err(format!("this FMU has no {type_name} variables"))
        }
    })
}
