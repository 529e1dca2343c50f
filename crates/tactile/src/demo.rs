//! `tactile demo`: the shipped encoder and shape head classify sample
//! frames, printing their features.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use tactile_burn::{DeviceKind, Runtime};
use tactile_cae::TactipEncoder;
use tactile_cae::data::PinSet;
use tactile_core::dataset::Dataset;
use tactile_estimate::ClassifierHead;

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
    let mut enc = TactipEncoder::load(&a.model, Runtime::BurnFlex, 0)
        .with_context(|| format!("loading the demo's encoder from {}", a.model.display()))?;
    let head = ClassifierHead::load(a.model.join("head"), &DeviceKind::Flex.device())?;
    let ds = Dataset::open(&a.data)
        .with_context(|| format!("the demo reads TacTip frames from {}", a.data.display()))?;
    let rows = ds
        .split_indices("test")
        .unwrap_or_else(|| (0..ds.len()).collect());
    let mut picked = Vec::new();
    for class in head.classes() {
        picked.extend(
            rows.iter()
                .copied()
                .filter(|&i| ds.text_opt(i, "shape") == Some(class.as_str()))
                .take(a.per_class as usize),
        );
    }
    let set = PinSet::from_rows(&ds, &picked, &enc.artifact.preprocess)?;
    let feats = enc.encode(&set.images)?;
    let pred = head.predict(&feats)?;
    say!(
        "encoder {:?}, {} features per frame; head classes {}",
        enc.artifact.model.widths,
        enc.feature_count(),
        head.classes().join(", ")
    );
    let mut right = 0;
    for (((file, f), p), &row) in set.files.iter().zip(&feats).zip(&pred).zip(&picked) {
        let truth = ds.text_opt(row, "shape").unwrap_or("?");
        let guess = &head.classes()[*p];
        right += usize::from(truth == guess);
        let fs: Vec<String> = f.iter().map(|v| format!("{v:.2}")).collect();
        say!(
            "{file:<28} true {truth:<11} predicted {guess:<11} features [{}]",
            fs.join(" ")
        );
    }
    say!("{right}/{} frames classified correctly", feats.len());
    Ok(())
}
