//! `tactile report`: regenerate `docs/results.md` and the README headline.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use tactile_bench::report::{Report, report};

#[derive(Args)]
pub(crate) struct ReportArgs {
    /// The real TacTip data (`polic-shapes` inside).
    #[arg(long, default_value = "../shared/real")]
    real: PathBuf,
    /// Shipped models.
    #[arg(long, default_value = "models")]
    models: PathBuf,
    /// Where held-out synthetic sets are generated (kept for reuse).
    #[arg(long, default_value = "data/report")]
    work: PathBuf,
    /// The page; its tables and plots go into a folder beside it.
    #[arg(long, default_value = "docs/results.md")]
    out: PathBuf,
    /// Also put the headline table into this file, between the lines
    /// `<!-- headline:begin -->` and `<!-- headline:end -->` (the README).
    #[arg(long)]
    readme: Option<PathBuf>,
    /// Sequences of 25 frames in the held-out test set (seed 200).
    #[arg(long, default_value_t = 40)]
    sequences: usize,
    /// Sequences of 15 frames at the deepest presses (seed 300).
    #[arg(long, default_value_t = 16)]
    extreme_sequences: usize,
    /// Timed runs per latency in the model benches (median reported).
    #[arg(long, default_value_t = 20)]
    runs: usize,
}

pub(crate) fn main(a: ReportArgs) -> Result<()> {
    tactile_bench::output::check_page(&a.out, &[])?;
    report(&Report {
        real: a.real,
        models: a.models,
        work: a.work,
        out: a.out.clone(),
        readme: a.readme.clone(),
        sequences: a.sequences,
        extreme_sequences: a.extreme_sequences,
        runs: a.runs,
    })?;
    if let Some(readme) = &a.readme {
        say!("headline table in {}", readme.display());
    }
    say!("wrote {} and the tables beside it", a.out.display());
    Ok(())
}
