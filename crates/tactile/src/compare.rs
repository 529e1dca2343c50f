//! `tactile compare`: feature sets against estimators on one split.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use tactile_bench::compare::{Compare, compare};
use tactile_estimate::Target;

use crate::args::Preprocess;

#[derive(Args)]
pub(crate) struct CompareArgs {
    /// Trained encoder (its preprocessing also makes the pixel baselines).
    #[arg(long)]
    encoder: PathBuf,
    /// Dataset with the target labels.
    #[arg(long)]
    data: PathBuf,
    /// Regression targets, e.g. x_mm,theta_deg:180,depth_mm.
    #[arg(long, value_delimiter = ',', num_args = 1.., required_unless_present = "classify")]
    targets: Vec<Target>,
    /// A class column to classify too (e.g. shape).
    #[arg(long)]
    classify: Option<String>,
    /// Without a `split` column: fraction of frames held out for testing.
    #[arg(long, default_value_t = 0.2)]
    test_fraction: f64,
    /// Fraction of the training frames for early stopping.
    #[arg(long, default_value_t = 0.2)]
    val_fraction: f64,
    /// Split and weight seed.
    #[arg(long, default_value_t = tactile_core::dataset::DEFAULT_SPLIT_SEED)]
    seed: u64,
    /// Also write the table to this Markdown file.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Preprocess with this preset or JSON file instead of the encoder's
    /// own (an encoder trained on one dataset applied to another).
    #[arg(long)]
    preprocess: Option<Preprocess>,
    /// Hidden widths of the regression MLP (the same for every feature set).
    #[arg(long, value_delimiter = ',', num_args = 1.., default_values_t = [256, 128])]
    hidden: Vec<usize>,
}

pub(crate) fn main(a: CompareArgs) -> Result<()> {
    if let Some(out) = &a.out {
        let ds = tactile_core::dataset::Dataset::open(&a.data)?;
        tactile_core::dataset::check_output_file(out, &[&ds])?;
    }
    let md = compare(&Compare {
        encoder: a.encoder,
        data: a.data,
        targets: a.targets,
        classify: a.classify,
        test_fraction: a.test_fraction,
        val_fraction: a.val_fraction,
        seed: a.seed,
        preprocess: a.preprocess.map(|p| (p.name, p.config)),
        hidden: a.hidden,
    })?;
    say_raw!("{md}");
    if let Some(out) = &a.out {
        tactile_core::io::write_atomic(out, md.as_bytes())?;
    }
    Ok(())
}
