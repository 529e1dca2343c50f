//! `tactile demo`: the shipped encoder and shape head classify sample
//! frames, printing their features.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

#[derive(Args)]
pub(crate) struct DemoArgs {
    /// Model folder with cae.json/cae.bpk and head/ (also shipped:
    /// models/cae-shapes, trained on the real shapes set).
    #[arg(long, default_value = "models/cae-synth")]
    model: PathBuf,
    /// A TacTip dataset; the demo uses its `test` split (or all frames).
    /// The default is shipped: virtual TacTip frames of a held-out seed.
    #[arg(long, default_value = "samples/virtual-tactip")]
    data: PathBuf,
    /// Frames per class to show (1-10000).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    per_class: u32,
}

pub(crate) fn main(a: DemoArgs) -> Result<()> {
    let demo = tactile_pipeline::demo::classify_samples(&a.model, &a.data, a.per_class as usize)
        .with_context(|| {
            format!(
                "the demo classifies the TacTip frames of {} with the encoder and head of {}",
                a.data.display(),
                a.model.display()
            )
        })?;
    say!(
        "encoder {:?}, {} features per frame; head classes {}",
        demo.widths,
        demo.feature_count,
        demo.classes.join(", ")
    );
    for f in &demo.frames {
        let fs: Vec<String> = f.features.iter().map(|v| format!("{v:.2}")).collect();
        say!(
            "{:<28} true {:<11} predicted {:<11} features [{}]",
            tactile_core::one_cell(&f.file),
            tactile_core::one_cell(&f.truth),
            tactile_core::one_cell(&f.predicted),
            fs.join(" ")
        );
    }
    say!(
        "{}/{} frames classified correctly",
        demo.correct(),
        demo.frames.len()
    );
    Ok(())
}
