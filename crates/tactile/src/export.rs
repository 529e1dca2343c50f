//! `tactile export`: a model folder to ONNX.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use tactile_pipeline::export::{Part, export_to};

#[derive(Args)]
pub(crate) struct ExportArgs {
    /// Model folder (CAE, pose network, detector, segmenter, depth or calibrated sensor model).
    #[arg(long)]
    model: PathBuf,
    /// Output .onnx file.
    #[arg(long)]
    out: PathBuf,
    /// For a CAE: the encoder (pin image -> features) or the whole
    /// autoencoder [default: encoder].
    #[arg(long, value_enum)]
    part: Option<Part>,
    /// Paper B models: a model that stands alone (docs/onnx.md): input
    /// `frame`, uint8 [N, H, W, 3] at the model's input size, normalisation
    /// and the sigmoid (or the millimetre scale) inside, named outputs
    /// (tendon_probability, mask_probability, depth_mm), the threshold,
    /// statistics, input size and version in its metadata.
    #[arg(long)]
    standalone: bool,
}

pub(crate) fn main(a: ExportArgs) -> Result<()> {
    let e = export_to(&a.model, &a.out, a.part, a.standalone)?;
    say!(
        "{} exported to {} ({} bytes)",
        e.kind,
        a.out.display(),
        e.bytes.len()
    );
    Ok(())
}
