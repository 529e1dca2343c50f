//! `tactile evaluate`: every estimator of an encoder, or every target of a
//! pose network, scored on a labelled dataset, per class and per shape.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use tactile_burn::DeviceKind;
use tactile_core::dataset::Dataset;
use tactile_estimate::eval::scores_markdown;
use tactile_pipeline::tactip::Predictor;

#[derive(Args)]
pub(crate) struct EvaluateArgs {
    /// Trained encoder folder (its estimators scored), or a pose-network
    /// folder (`tactile train pose`; its every target scored).
    #[arg(long, visible_alias = "model")]
    encoder: PathBuf,
    /// An encoder's estimator folders (default: every folder in ENCODER with head.json, regressor.json or ensemble.json).
    #[arg(long, num_args = 1..)]
    heads: Vec<PathBuf>,
    /// Labelled dataset (e.g. held-out synthetic frames).
    #[arg(long)]
    data: PathBuf,
    /// Score only the rows of this split of the dataset's `split` column
    /// (`val` of the authors' train/val split; `test`).
    #[arg(long)]
    split: Option<String>,
    /// Also write the tables to this Markdown file.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Device the networks run on.
    #[arg(long, value_enum, default_value_t = DeviceKind::Flex)]
    device: DeviceKind,
}

/// Score every estimator on a dataset; the last line is the scores as JSON.
pub(crate) fn main(a: EvaluateArgs) -> Result<()> {
    let ds = Dataset::open_split(&a.data, a.split.as_deref())?;
    if let Some(out) = &a.out {
        tactile_core::dataset::check_output_file(out, &[&ds])?;
    }
    let mut p = Predictor::load(&a.encoder, &a.heads, a.device.runtime())?;
    let s = p.evaluate(&ds)?;
    for w in s.warnings() {
        tactile_core::note!("{w}");
    }
    let kind = match p {
        Predictor::Encoder(_) => "Encoder",
        Predictor::PoseNetwork(_) => "Pose network",
    };
    let split = match &a.split {
        Some(name) => format!("its '{}' split, ", tactile_core::dataset::split_name(name)),
        None => String::new(),
    };
    // Frames left out (cut short behind their header) are said here too.
    let frames = match s.frames {
        n if n == ds.len() => format!("{n} frames"),
        n => format!("{n} of its {} frames scored", ds.len()),
    };
    let md = format!(
        "{kind} {} on {} ({split}{frames}).\n\n{}",
        a.encoder.display(),
        a.data.display(),
        scores_markdown(&s)
    );
    say_raw!("{md}");
    if let Some(out) = &a.out {
        tactile_core::io::write_atomic(out, md.as_bytes())?;
    }
    say!("{}", serde_json::to_string(&s)?);
    Ok(())
}
