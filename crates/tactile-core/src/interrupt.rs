//! Ctrl-C and SIGTERM as an orderly stop. A front end calls [`install`];
//! long loops (dataset generation, training, the palpation run) call
//! [`check`] between items and return [`Error::Interrupted`], so staging
//! folders are removed and a model folder is left marked incomplete
//! instead of the process dying half-way. A second signal ends the process
//! at once.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::{Error, Result};

fn flag() -> &'static Arc<AtomicBool> {
    static FLAG: std::sync::OnceLock<Arc<AtomicBool>> = std::sync::OnceLock::new();
    FLAG.get_or_init(|| Arc::new(AtomicBool::new(false)))
}

/// Turn SIGINT and SIGTERM into a stop request (a second one exits at once).
pub fn install() -> Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    use signal_hook::flag::{register, register_conditional_shutdown};
    for sig in [SIGINT, SIGTERM] {
        // Registered first, so it sees the flag before the second
        // registration sets it: exit on the second signal.
        register_conditional_shutdown(sig, 130, Arc::clone(flag()))
            .and_then(|_| register(sig, Arc::clone(flag())))
            .map_err(|e| Error::Invalid(format!("cannot install the signal handler: {e}")))?;
    }
    Ok(())
}

/// True once a stop was requested.
pub fn requested() -> bool {
    flag().load(Ordering::Relaxed)
}

/// Ask long work to stop (what the signal handler does; also for tests
/// and embedding programs).
pub fn request() {
    flag().store(true, Ordering::Relaxed);
}

/// Forget a stop request once the work it stopped has ended: for an
/// embedding program (the Python package) that goes on after a Ctrl-C.
pub fn reset() {
    flag().store(false, Ordering::Relaxed);
}

/// `Err(Interrupted)` once a stop was requested.
pub fn check() -> Result<()> {
    if requested() {
        Err(Error::Interrupted)
    } else {
        Ok(())
    }
}
