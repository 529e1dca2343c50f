//! Ctrl-C and SIGTERM as an orderly stop. A front end calls [`install`];
//! long loops (dataset generation, training, the palpation run) call
//! [`check`] between items and return [`Error::Interrupted`], so staging
//! folders are removed and a model folder is left marked incomplete
//! instead of the process dying half-way. A second signal ends the process
//! at once, except while a [`Hold`] is held (a page's files being put in
//! place): then it ends as that is let go.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::{Error, Result};

fn flag() -> &'static AtomicBool {
    static FLAG: AtomicBool = AtomicBool::new(false);
    &FLAG
}

/// Turn SIGINT and SIGTERM into a stop request; a second one ends the
/// process at once, or, while a [`Hold`] is held, as soon as it is let go.
/// The signals are read by a thread of their own (`signal-hook`'s
/// iterator), so what a signal does is ordinary code.
pub fn install() -> Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let cannot =
        |e: std::io::Error| Error::Invalid(format!("cannot install the signal handler: {e}"));
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]).map_err(cannot)?;
    std::thread::Builder::new()
        .name("tactile-signals".into())
        .spawn(move || {
            for _ in signals.forever() {
                let mut holds = holds();
                match on_signal(requested(), &mut holds) {
                    OnSignal::Stop => request(),
                    OnSignal::Exit => signal_hook::low_level::exit(EXIT_CODE),
                    OnSignal::ExitWhenLetGo => {}
                }
            }
        })
        .map_err(cannot)?;
    Ok(())
}

/// The exit status of a process ended by a second signal (128 + SIGINT).
const EXIT_CODE: i32 = 130;

/// Holds taken, and whether a second signal waits for them.
#[derive(Debug, Default)]
struct Holds {
    count: usize,
    exit_pending: bool,
}

fn holds() -> std::sync::MutexGuard<'static, Holds> {
    static HOLDS: std::sync::Mutex<Holds> = std::sync::Mutex::new(Holds {
        count: 0,
        exit_pending: false,
    });
    HOLDS
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// What a signal does.
#[derive(Debug, PartialEq, Eq)]
enum OnSignal {
    /// The first: ask the work to stop.
    Stop,
    /// A second with no hold: end the process now.
    Exit,
    /// A second while held: end it when the last hold is let go.
    ExitWhenLetGo,
}

fn on_signal(already_requested: bool, holds: &mut Holds) -> OnSignal {
    match (already_requested, holds.count) {
        (false, _) => OnSignal::Stop,
        (true, 0) => OnSignal::Exit,
        (true, _) => {
            holds.exit_pending = true;
            OnSignal::ExitWhenLetGo
        }
    }
}

/// While held, a second signal does not end the process until it is let
/// go: taken while a set of files that belong together is put in place
/// (a bench page's Markdown, JSON and pictures), so an impatient second
/// Ctrl-C cannot leave this run's Markdown beside the last run's JSON.
#[must_use = "the hold ends when it is dropped"]
pub struct Hold(());

/// Take a [`Hold`] (keep it short: it delays a second Ctrl-C).
pub fn hold() -> Hold {
    holds().count += 1;
    Hold(())
}

impl Drop for Hold {
    fn drop(&mut self) {
        let mut holds = holds();
        holds.count = holds.count.saturating_sub(1);
        if holds.count == 0 && holds.exit_pending {
            signal_hook::low_level::exit(EXIT_CODE);
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The first signal asks the work to stop; a second ends the process
    /// at once, or, while a hold is held, once the last is let go.
    #[test]
    fn a_second_signal_waits_for_a_hold_only() {
        let mut h = Holds::default();
        assert_eq!(on_signal(false, &mut h), OnSignal::Stop);
        assert_eq!(on_signal(true, &mut h), OnSignal::Exit);
        assert!(!h.exit_pending);
        h.count = 2;
        assert_eq!(on_signal(false, &mut h), OnSignal::Stop);
        assert!(!h.exit_pending, "a first signal never ends the process");
        assert_eq!(on_signal(true, &mut h), OnSignal::ExitWhenLetGo);
        assert!(h.exit_pending);
        // Holds taken and let go (no signal pending here) leave no count.
        let (a, b) = (hold(), hold());
        assert_eq!(holds().count, 2);
        drop(a);
        drop(b);
        assert_eq!(holds().count, 0);
    }
}
