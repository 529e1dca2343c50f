//! Any model folder of the workspace to ONNX: the folder says which model
//! it holds (its config file), the model says how it exports.

use std::path::Path;

use tactile_cae::CaeArtifact;
use tactile_core::{Artifact, DeviceKind};
use tactile_depth::DepthArtifact;
use tactile_detect::DetectorArtifact;
use tactile_onnx::Exportable;
use tactile_segment::SegmenterArtifact;

use crate::Result;

/// Which part of a CAE folder to export (other models export their network).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Part {
    /// The network used at inference (for a CAE: pin image -> features).
    Encoder,
    /// A CAE's whole autoencoder (pin image -> reconstruction).
    Autoencoder,
}

/// An exported model.
pub struct Exported {
    /// What it is ("detector", "CAE encoder", ...).
    pub kind: &'static str,
    /// The ONNX protobuf.
    pub bytes: Vec<u8>,
}

fn export<A>(dir: &Path) -> Result<Vec<u8>>
where
    A: Exportable,
    A::Model: tactile_core::runtime::Forward + Send + 'static,
{
    let l = A::load(dir, &DeviceKind::Flex.device())?;
    Ok(l.artifact.onnx(&l.model)?)
}

/// Export the model in `dir`.
pub fn export_model(dir: &Path, part: Part) -> Result<Exported> {
    let (kind, bytes) = if DetectorArtifact::is_in(dir) {
        ("detector", export::<DetectorArtifact>(dir)?)
    } else if SegmenterArtifact::is_in(dir) {
        ("segmenter", export::<SegmenterArtifact>(dir)?)
    } else if DepthArtifact::is_in(dir) {
        ("depth network", export::<DepthArtifact>(dir)?)
    } else if part == Part::Autoencoder {
        let l = CaeArtifact::load(dir, &DeviceKind::Flex.device())?;
        let px = l.artifact.model.input_px;
        (
            "CAE autoencoder",
            tactile_cae::export::autoencoder_onnx(&l.model, px)?,
        )
    } else {
        ("CAE encoder", export::<CaeArtifact>(dir)?)
    };
    Ok(Exported { kind, bytes })
}
