//! Long work (training, evaluation, generating a dataset, a batch of
//! frames, a live source's wait) off the interpreter: it runs on a worker
//! thread with the interpreter lock released, while the calling thread
//! checks for Ctrl-C every 100 ms. A Ctrl-C asks the work to stop the way
//! SIGINT stops the command line (staging folders removed, a training
//! folder left marked incomplete), waits for it, then raises
//! `KeyboardInterrupt`.

use std::sync::mpsc::RecvTimeoutError;
use std::time::Duration;

use pyo3::prelude::*;

/// How often Ctrl-C is looked for while the work runs.
const POLL: Duration = Duration::from_millis(100);

/// Run `work` on a worker thread, stoppable with Ctrl-C.
pub(crate) fn interruptible<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    F: FnOnce() -> PyResult<T> + Send,
    T: Send,
{
    let (result, signal) = py.detach(|| {
        std::thread::scope(|s| {
            let (done, ended) = std::sync::mpsc::channel::<()>();
            let handle = s.spawn(move || {
                let result = work();
                // Wakes the wait below at once (a panic wakes it too, by
                // dropping `done`): a short call is not held to the poll.
                let _ = done.send(());
                result
            });
            let mut signal: Option<PyErr> = None;
            while let Err(RecvTimeoutError::Timeout) = ended.recv_timeout(POLL) {
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
    match signal {
        // The signal's own exception (KeyboardInterrupt), after the work
        // stopped. Only the call that saw the signal (Python raises it in
        // the main thread alone) asked for the stop, so only it withdraws
        // it: a call on another thread, a batch a ROS callback runs, never
        // clears a stop meant for this one.
        Some(e) => {
            tactile_core::interrupt::reset();
            Err(e)
        }
        None => result,
    }
}

/// `work` with the interpreter lock released: on a worker thread that
/// Ctrl-C stops ([`interruptible`]) when it `may_be_long` (a batch of
/// frames, a live source's wait), else on the calling thread, as
/// `Pipeline.process` runs, sparing a call of a millisecond or two the
/// worker's 50 us.
pub(crate) fn released<T, F>(py: Python<'_>, may_be_long: bool, work: F) -> PyResult<T>
where
    F: FnOnce() -> PyResult<T> + Send,
    T: Send,
{
    match may_be_long {
        true => interruptible(py, work),
        false => py.detach(work),
    }
}
