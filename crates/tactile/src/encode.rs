//! `tactile encode`: every frame of a TacTip dataset to a feature CSV.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use tactile_burn::DeviceKind;
use tactile_cae::TactipEncoder;
use tactile_cae::inference::write_features_csv;
use tactile_core::dataset::Dataset;

#[derive(Args)]
pub(crate) struct EncodeArgs {
    /// Model folder (cae.json + cae.bpk).
    #[arg(long)]
    model: PathBuf,
    /// Dataset folder.
    #[arg(long)]
    data: PathBuf,
    /// Output CSV (file,f0,f1,...).
    #[arg(long)]
    out: PathBuf,
    /// Device the encoder runs on.
    #[arg(long, value_enum, default_value_t = DeviceKind::Flex)]
    device: DeviceKind,
}

pub(crate) fn main(a: EncodeArgs) -> Result<()> {
    let ds = Dataset::open(&a.data)?;
    tactile_core::dataset::check_output_file(&a.out, &[&ds])?;
    tactile_core::dataset::refuse_misnamed_results(
        &a.out,
        tactile_core::dataset::ResultsFormat::Csv,
    )?;
    let mut enc = TactipEncoder::load(&a.model, a.device.runtime(), 0)?;
    if let Some(w) =
        tactile_pipeline::tactip::dataset_frame_warning(&ds, [&enc.artifact.preprocess])
    {
        tactile_core::note!("{w}");
    }
    let e = tactile_pipeline::tactip::encode_dataset(&mut enc, &ds)?;
    for w in &e.warnings {
        tactile_core::note!("{w}");
    }
    let (files, feats) = (e.files, e.features);
    write_features_csv(&a.out, &files, &feats)?;
    say!(
        "{} feature vectors of {} values written to {}",
        feats.len(),
        enc.feature_count(),
        a.out.display()
    );
    Ok(())
}
