//! A trained detector on disk: `detector.json` (architecture, training-set
//! channel statistics, the calibrated threshold, provenance) beside
//! `detector.bpk`.

use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_burn::Artifact;
use tactile_onnx::{Exportable, export_batch_dynamic};
use tactile_preprocess::profile::InputProfile;
use tactile_preprocess::visuo::ChannelStats;

use crate::model::{Detector, DetectorConfig};

/// Everything needed to rebuild and run a saved detector.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DetectorArtifact {
    /// The architecture and input size.
    #[serde(alias = "detector")]
    pub model: DetectorConfig,
    /// Per-channel statistics of the training frames.
    pub stats: ChannelStats,
    /// Probability above which a frame counts as showing a tendon.
    pub threshold: f64,
    /// The training frames' input statistics: frames far outside them are
    /// flagged as another sensor's and get no answer (`tactile train
    /// profile` adds it to a trained detector).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_profile: Option<InputProfile>,
    /// Provenance.
    #[serde(default)]
    pub notes: serde_json::Value,
}

impl Artifact for DetectorArtifact {
    type Model = Detector;
    const KIND: &'static str = "detector";
    const CONFIG_FILE: &'static str = "detector.json";
    const WEIGHTS_FILE: &'static str = "detector.bpk";

    fn init(&self, device: &Device) -> tactile_core::Result<Detector> {
        self.model.check()?;
        Ok(self.model.init(device))
    }

    fn check(&self, file: &std::path::Path) -> tactile_core::Result<()> {
        use tactile_burn::artifact::check_field;
        use tactile_core::error::in_config;
        in_config(file, self.model.check())?;
        in_config(file, self.stats.check(3))?;
        if let Some(p) = &self.input_profile {
            p.validate_reading(false)
                .map_err(|m| tactile_core::Error::Config(format!("{}: {m}", file.display())))?;
        }
        let t = self.threshold;
        check_field(
            file,
            "threshold",
            (0.0..=1.0).contains(&t),
            t,
            "a probability in [0, 1]",
        )
    }
}

impl Exportable for DetectorArtifact {
    /// `[N, 3, H, W]` normalised frames -> `[N, 1]` logits.
    fn onnx(&self, model: &Detector) -> tactile_onnx::Result<Vec<u8>> {
        let [w, h] = self.model.input_size;
        export_batch_dynamic(model, [1, 3, h, w], |m: &Detector, x| m.forward(x))
    }
}

impl DetectorArtifact {
    /// Whether probability `p` reaches the saved threshold.
    pub fn is_tendon(&self, p: f32) -> bool {
        p as f64 >= self.threshold
    }
}
