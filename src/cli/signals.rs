//! Ctrl-C and SIGTERM for the verbs that serve a page until stopped
//! (`web serve`, `--pick`): the signal sets a flag instead of ending the
//! process, so the verb finishes its work (a report printed, a temporary
//! export removed, a manifest pointed at the saved landmarks).

use std::sync::atomic::{AtomicBool, Ordering};

/// Set by SIGINT or SIGTERM once [`stop_on_signals`] ran.
static STOP: AtomicBool = AtomicBool::new(false);

#[cfg(unix)]
extern "C" fn on_stop_signal(_: libc::c_int) {
    // Only an atomic store: async-signal-safe.
    STOP.store(true, Ordering::Relaxed);
}

/// Makes SIGINT and SIGTERM set the returned flag instead of ending the
/// process.
pub fn stop_on_signals() -> &'static AtomicBool {
    #[cfg(unix)]
    // SAFETY: the handler only stores to an atomic.
    unsafe {
        let h = on_stop_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
        libc::signal(libc::SIGINT, h);
        libc::signal(libc::SIGTERM, h);
    }
    &STOP
}
