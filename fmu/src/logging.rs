//! The host's logger, in the form of either API (`fmi2CallbackLogger`,
//! `fmi3LogMessageCallback`): the log categories both declare, which of them the host wants
//! (`SetDebugLogging`), and the messages sent, also before an instance exists.

use crate::host::{slice, text, ERROR, OK, WARNING};
use std::ffi::{c_char, c_int, c_void, CStr, CString};

/// The host's environment pointer, handed back with every callback.
pub type Env = *mut c_void;

/// `fmi2CallbackLogger`: printf-style, with the instance name.
pub type Fmi2Logger =
    unsafe extern "C" fn(Env, *const c_char, c_int, *const c_char, *const c_char, ...);

/// `fmi3LogMessageCallback`.
pub type Fmi3LogMessage = unsafe extern "C" fn(Env, c_int, *const c_char, *const c_char);

/// The log categories both APIs declare (`modelDescription.xml`'s `LogCategories`).
pub const CATEGORY_NAMES: [&CStr; 3] = [c"logStatusWarning", c"logStatusError", c"logAll"];

/// The category a message of `status` is logged under (an index into [`CATEGORY_NAMES`]).
fn category(status: c_int) -> usize {
    match status {
        OK => 2,
        WARNING => 0,
        _ => 1,
    }
}

/// The host's logger callback.
#[derive(Clone, Copy)]
pub enum Callback {
    /// FMI 2.0's.
    Fmi2(Fmi2Logger),
    /// FMI 3.0's.
    Fmi3(Fmi3LogMessage),
}

impl Callback {
    /// Send `message` with `status` under `category`; `name` is the instance's (FMI 2.0).
    ///
    /// # Safety
    ///
    /// `env` is the environment the host gave with this callback; `name` is NUL-terminated.
    unsafe fn send(
        self,
        env: Env,
        name: *const c_char,
        status: c_int,
        category: &CStr,
        message: &str,
    ) {
        let msg = CString::new(message.replace('\0', " ")).unwrap_or_default();
        match self {
            // SAFETY: the host's logger for this environment; the format string is a
            // literal "%s" and its one argument a valid NUL-terminated string.
            Callback::Fmi2(logger) => unsafe {
                logger(
                    env,
                    name,
                    status,
                    category.as_ptr(),
                    c"%s".as_ptr(),
                    msg.as_ptr(),
                )
            },
            // SAFETY: the host's callback for this environment, with valid C strings.
            Callback::Fmi3(log) => unsafe { log(env, status, category.as_ptr(), msg.as_ptr()) },
        }
    }
}

/// Report an error before an instance exists (a failed instantiation) through the host's
/// logger, if it gave one, whatever the logging asked for.
///
/// # Safety
///
/// `env` is the environment the host gave with `callback`; `name` is null (then the message
/// names `rkforge`) or the host's NUL-terminated instance name.
pub unsafe fn early(callback: Option<Callback>, env: Env, name: *const c_char, message: &str) {
    if let Some(callback) = callback {
        let name = if name.is_null() {
            c"rkforge".as_ptr()
        } else {
            name
        };
        // SAFETY: as the caller promises.
        unsafe { callback.send(env, name, ERROR, c"logStatusError", message) };
    }
}

/// The logging of one instance: the host's logger and what the host asked it to log.
#[derive(Clone)]
pub struct Log {
    callback: Option<Callback>,
    env: Env,
    name: CString,
    on: bool,
    categories: [bool; 3],
}

impl Log {
    /// The logging of the instance `name`, through `callback` with `env`; `on` as the
    /// host's `loggingOn`, every category wanted.
    pub fn new(callback: Option<Callback>, env: Env, name: &str, on: bool) -> Log {
        Log {
            callback,
            env,
            name: CString::new(name.replace('\0', " ")).unwrap_or_default(),
            on,
            categories: [true; 3],
        }
    }

    /// The host's environment pointer.
    pub fn env(&self) -> Env {
        self.env
    }

    /// Log `message` with `status`: an error always (as the FMU SDK's template does: with
    /// debug logging off, fmpy's default, a failed call would otherwise say nothing of what
    /// failed), a warning or an info message if logging is on for its category.
    pub fn log(&self, status: c_int, message: &str) {
        let category = category(status);
        let wanted = self.on && (self.categories[category] || self.categories[2]);
        if !(wanted || status >= ERROR) {
            return;
        }
        if let Some(callback) = self.callback {
            // SAFETY: the host gave this callback with this environment; the name is ours.
            unsafe {
                callback.send(
                    self.env,
                    self.name.as_ptr(),
                    status,
                    CATEGORY_NAMES[category],
                    message,
                )
            };
        }
    }

    /// `SetDebugLogging`: logging `on`, for the `n` categories at `categories` (all when
    /// `n` is zero).
    ///
    /// # Safety
    ///
    /// `categories` holds `n` NUL-terminated strings when `n` is not zero.
    pub unsafe fn set(
        &mut self,
        on: bool,
        n: usize,
        categories: *const *const c_char,
    ) -> Result<(), String> {
        // SAFETY: `n` category strings at `categories`.
        let list = unsafe { slice(categories, n, "categories") }?;
        let mut wanted = [n == 0; 3];
        for &p in list {
            let name = unsafe { text(p) }.ok_or("a category is a null pointer")?;
            let k = CATEGORY_NAMES
                .iter()
                .position(|c| c.to_bytes() == name.as_bytes())
                .ok_or_else(|| format!("unknown log category `{name}`"))?;
            wanted[k] = true;
        }
        self.on = on;
        self.categories = wanted;
        Ok(())
    }
}
