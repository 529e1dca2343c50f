//! `tactile sweep`: paper A's feature-count search.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use tactile_bench::sweep::{Sweep, sweep};

#[derive(Args)]
pub(crate) struct SweepArgs {
    /// Trained encoders to compare (e.g. 8, 16, 32 and 64 features).
    #[arg(long, num_args = 1.., required = true)]
    encoders: Vec<PathBuf>,
    /// Dataset with a class column (its split column when present).
    #[arg(long)]
    data: PathBuf,
    /// Class column for the accuracy.
    #[arg(long, default_value = "shape")]
    classify: String,
    /// Split and head seed.
    #[arg(long, default_value_t = tactile_core::dataset::DEFAULT_SPLIT_SEED)]
    seed: u64,
    /// Timed runs per latency measurement.
    #[arg(long, default_value_t = 30)]
    runs: usize,
    /// Markdown table; the plots go beside it (`NAME-features.png`, `NAME-latency.png`).
    #[arg(long)]
    out: Option<PathBuf>,
}

pub(crate) fn main(a: SweepArgs) -> Result<()> {
    if let Some(out) = &a.out {
        let ds = tactile_core::dataset::Dataset::open(&a.data)?;
        tactile_core::dataset::check_output_file(out, &[&ds])?;
    }
    let r = sweep(&Sweep {
        encoders: a.encoders,
        data: a.data,
        classify: a.classify,
        seed: a.seed,
        runs: a.runs,
    })?;
    say_raw!("{}", r.markdown);
    if let Some(out) = &a.out {
        r.write(out)?;
        say!("table and plots written beside {}", out.display());
    }
    Ok(())
}
