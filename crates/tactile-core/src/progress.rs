//! Progress on long work: a bar with position, rate and ETA on a terminal.

pub use indicatif::ProgressBar;
use indicatif::ProgressStyle;

/// [`progress_bar`], or one that draws nothing when `shown` is false (a
/// caller that asked for quiet work still counts through the same bar).
pub fn progress_bar_if(len: u64, what: &str, shown: bool) -> ProgressBar {
    let pb = progress_bar(len, what);
    if !shown {
        pb.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    pb
}

/// A progress bar with position, rate and ETA (drawn only on a terminal).
pub fn progress_bar(len: u64, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    let style = ProgressStyle::with_template(
        "{prefix} [{elapsed_precise}] {wide_bar} {pos}/{len} ETA {eta} {msg}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    pb.set_style(style);
    pb.set_prefix(what.to_string());
    pb
}

/// A spinner saying what is waited for (drawn only on a terminal), for a
/// wait of unknown length: a network camera's first answer.
pub fn spinner(what: &str) -> ProgressBar {
    let pb = ProgressBar::new_spinner();
    let style = ProgressStyle::with_template("{spinner} {msg} [{elapsed}]")
        .unwrap_or_else(|_| ProgressStyle::default_spinner());
    pb.set_style(style);
    pb.set_message(crate::printable(what).into_owned());
    pb.enable_steady_tick(std::time::Duration::from_millis(120));
    pb
}
