//! A trained pose network on disk: `pose.json` (architecture, the
//! preprocessing that makes its pin images, its targets and their
//! standardisation, provenance) beside `pose.bpk`.

use std::path::Path;

use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_core::Artifact;
use tactile_estimate::Target;
use tactile_estimate::regressor::Scaler;
use tactile_onnx::{Exportable, export_batch_dynamic};
use tactile_preprocess::PreprocessConfig;

use crate::model::{PoseNet, PoseNetConfig};

/// Everything needed to rebuild and use a saved pose network.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PoseArtifact {
    /// The architecture.
    pub model: PoseNetConfig,
    /// How a frame becomes the grey pin image it reads.
    pub preprocess: PreprocessConfig,
    /// What it predicts, in column order.
    pub targets: Vec<Target>,
    /// Standardisation of the encoded target columns.
    pub outputs: Scaler,
    /// Free-form provenance: how it was trained, on what, with which result.
    #[serde(default)]
    pub notes: serde_json::Value,
}

impl PoseArtifact {
    /// Output columns the targets take.
    pub fn columns(&self) -> usize {
        self.targets.iter().map(Target::width).sum()
    }
}

impl Artifact for PoseArtifact {
    type Model = PoseNet;
    const KIND: &'static str = "pose network";
    const CONFIG_FILE: &'static str = "pose.json";
    const WEIGHTS_FILE: &'static str = "pose.bpk";

    fn init(&self, device: &Device) -> tactile_core::Result<PoseNet> {
        self.model.check()?;
        Ok(self.model.init(device))
    }

    fn check(&self, file: &Path) -> tactile_core::Result<()> {
        use tactile_core::artifact::in_config;
        in_config(file, self.model.check())?;
        in_config(file, self.preprocess.check())?;
        let bad = |m: String| Err(tactile_core::Error::model(file, m));
        if self.preprocess.output_px != self.model.input_px {
            return bad(format!(
                "preprocessing makes {0}x{0} pin images, the network takes {1}x{1}",
                self.preprocess.output_px, self.model.input_px
            ));
        }
        if self.targets.is_empty() || self.columns() != self.model.outputs {
            return bad(format!(
                "{} targets take {} columns, the network gives {}",
                self.targets.len(),
                self.columns(),
                self.model.outputs
            ));
        }
        in_config(
            file,
            tactile_estimate::mlp::check_scaler(
                "target scaling",
                &self.outputs.mean,
                &self.outputs.std,
                self.model.outputs,
            ),
        )
    }
}

impl Exportable for PoseArtifact {
    /// `[N, 1, S, S]` grey pin images -> `[N, K]` standardised columns.
    fn onnx(&self, model: &PoseNet) -> tactile_onnx::Result<Vec<u8>> {
        let s = self.model.input_px;
        export_batch_dynamic(model, [1, 1, s, s], |m: &PoseNet, x| m.forward(x))
    }
}
