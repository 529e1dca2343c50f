//! `tactile encode`: every frame of a TacTip dataset to a feature CSV.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use tactile_burn::DeviceKind;
use tactile_cae::TactipEncoder;
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
    let mut enc = TactipEncoder::load(&a.model, a.device.runtime(), 0)?;
    let e = tactile_pipeline::tactip::encode_dataset_to(&mut enc, &ds, Some(&a.out))?;
    for w in &e.warnings {
        tactile_core::note!("{w}");
    }
    say!(
        "{} feature vectors of {} values written to {}",
        e.features.len(),
        enc.feature_count(),
        a.out.display()
    );
    Ok(())
}
