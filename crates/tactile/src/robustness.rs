//! `tactile robustness`: estimator errors under perturbed camera conditions.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use tactile_bench::robustness::{Robustness, robustness};

#[derive(Args)]
pub(crate) struct RobustnessArgs {
    /// Trained encoder folder.
    #[arg(long)]
    encoder: PathBuf,
    /// Estimator folders (default: every folder in ENCODER with head.json, regressor.json or ensemble.json).
    #[arg(long, num_args = 1..)]
    heads: Vec<PathBuf>,
    /// Labelled dataset of raw frames (held-out synthetic TacTip frames).
    #[arg(long)]
    data: PathBuf,
    /// Use at most this many frames (the first ones).
    #[arg(long)]
    limit: Option<usize>,
    /// Markdown table; the plot goes beside it.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Seed of the perturbations.
    #[arg(long, default_value_t = 11)]
    seed: u64,
}

pub(crate) fn main(a: RobustnessArgs) -> Result<()> {
    if let Some(out) = &a.out {
        let ds = tactile_core::dataset::Dataset::open(&a.data)?;
        tactile_bench::output::check_page(out, &[&ds])?;
    }
    let r = robustness(&Robustness {
        encoder: a.encoder,
        heads: a.heads,
        data: a.data,
        limit: a.limit,
        seed: a.seed,
    })?;
    say_raw!("{}", r.markdown);
    if let Some(out) = &a.out {
        r.write(out)?;
        tactile_core::note!("wrote {} and its plot", out.display());
    }
    Ok(())
}
