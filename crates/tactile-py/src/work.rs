//! Long work (training, evaluation, generating a dataset) off the
//! interpreter: it runs on a worker thread with the interpreter lock
//! released, while the calling thread checks for Ctrl-C every 100 ms. A
//! Ctrl-C asks the work to stop the way SIGINT stops the command line
//! (staging folders removed, a training folder left marked incomplete),
//! waits for it, then raises `KeyboardInterrupt`.

use std::time::Duration;

use pyo3::prelude::*;

/// Run `work` on a worker thread, stoppable with Ctrl-C.
pub(crate) fn interruptible<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    F: FnOnce() -> PyResult<T> + Send,
    T: Send,
{
    tactile_core::interrupt::reset();
    let (result, signal) = py.detach(|| {
        std::thread::scope(|s| {
            let handle = s.spawn(work);
            let mut signal: Option<PyErr> = None;
            while !handle.is_finished() {
                std::thread::sleep(Duration::from_millis(100));
                if signal.is_none()
                    && let Err(e) = Python::attach(|py| py.check_signals())
                {
                    tactile_core::interrupt::request();
                    signal = Some(e);
                }
            }
            let result = handle.join().unwrap_or_else(|_| {
                Err(pyo3::exceptions::PyRuntimeError::new_err(
                    "the work failed unexpectedly (a panic); nothing partial was kept",
                ))
            });
            (result, signal)
        })
    });
    tactile_core::interrupt::reset();
    match signal {
        // The signal's own exception (KeyboardInterrupt), after the work stopped.
        Some(e) => Err(e),
        None => result,
    }
}
