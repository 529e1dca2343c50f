//! Benchmark helpers: the machine description every table carries, and
//! median timing.

use std::time::Instant;

/// What a benchmark ran on.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Machine {
    /// CPU model name.
    pub cpu: String,
    /// Logical cores available to this process.
    pub logical_cores: usize,
    /// Operating system and architecture.
    pub os: String,
}

impl Machine {
    /// Read the CPU model and core count of this machine.
    pub fn detect() -> Self {
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|s| {
                s.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split(':').nth(1))
                    .map(|s| s.trim().to_string())
            })
            .unwrap_or_else(|| "unknown CPU".into());
        Self {
            cpu,
            logical_cores: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            os: format!("{} {}", std::env::consts::OS, std::env::consts::ARCH),
        }
    }

    /// One line for the top of a report.
    pub fn describe(&self) -> String {
        format!(
            "{} ({} logical cores, {})",
            self.cpu, self.logical_cores, self.os
        )
    }
}

/// Timed runs one measurement may take: a median settles long before,
/// and every run's time is kept until the median is taken.
pub const MAX_RUNS: usize = 100_000;

/// Before a bench's work: `runs` timed runs per measurement (`--runs`) is
/// 1 to [`MAX_RUNS`].
pub fn check_runs(runs: usize) -> crate::Result<()> {
    if (1..=MAX_RUNS).contains(&runs) {
        return Ok(());
    }
    Err(crate::Error::Config(format!(
        "timed runs: must be 1 to {MAX_RUNS} per measurement, got {runs}"
    )))
}

/// Run `f` `warmup` times, then `runs` times (1 to [`MAX_RUNS`]; a bench
/// checks its flag with [`check_runs`] first), and return the median
/// seconds.
pub fn median_seconds(warmup: usize, runs: usize, mut f: impl FnMut()) -> f64 {
    for _ in 0..warmup {
        f();
    }
    let mut t: Vec<f64> = (0..runs.clamp(1, MAX_RUNS))
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timed_runs_are_bounded_before_their_times_are_held() {
        assert!(check_runs(0).is_err() && check_runs(MAX_RUNS + 1).is_err());
        check_runs(1).unwrap();
        check_runs(MAX_RUNS).unwrap();
        // Past the bound the times of MAX_RUNS runs are kept, no more.
        let mut calls = 0usize;
        let t = median_seconds(2, usize::MAX, || calls += 1);
        assert!(t.is_finite() && t >= 0.0);
        assert_eq!(calls, 2 + MAX_RUNS);
    }
}
