//! SIGINT and SIGTERM (Ctrl-C and `kill`) as a flag that a run polls, so that it stops at the
//! next sample and finishes its files (the MCAP summary and footer, history, summary.json).
//! A second signal ends the process at once (exit status 130).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

/// The flag shared by every caller in the process (a handler can be installed only once).
static STOP: OnceLock<Result<Arc<AtomicBool>, String>> = OnceLock::new();

/// Install the handler (once per process) and return the flag it raises.
///
/// # Errors
///
/// The operating system refused the handler.
pub fn stop_flag() -> Result<Arc<AtomicBool>, String> {
    STOP.get_or_init(|| {
        let flag = Arc::new(AtomicBool::new(false));
        let f = Arc::clone(&flag);
        ctrlc::set_handler(move || {
            if f.swap(true, Ordering::SeqCst) {
                std::process::exit(130);
            }
        })
        .map_err(|e| format!("cannot handle SIGINT/SIGTERM: {e}"))?;
        Ok(flag)
    })
    .clone()
}
