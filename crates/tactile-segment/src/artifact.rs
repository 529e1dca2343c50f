//! A trained segmenter on disk: `segmenter.json` (the U-Net's size, the
//! training windows' channel statistics, the pixel threshold and the
//! post-processing settings) beside `segmenter.bpk`.

use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_burn::Artifact;
use tactile_onnx::{Exportable, export_batch_dynamic};
use tactile_preprocess::visuo::ChannelStats;

use crate::model::{UNet, UNetConfig};
use crate::postprocess::PostprocessConfig;

/// Everything needed to rebuild and run a saved segmenter.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SegmenterArtifact {
    /// The U-Net and its window side.
    #[serde(alias = "unet")]
    pub model: UNetConfig,
    /// Per-channel statistics of the training windows.
    pub stats: ChannelStats,
    /// Probability above which a pixel is tendon.
    pub threshold: f64,
    /// From mask to kept region and direction.
    pub postprocess: PostprocessConfig,
    /// Provenance.
    #[serde(default)]
    pub notes: serde_json::Value,
}

impl Artifact for SegmenterArtifact {
    type Model = UNet;
    const KIND: &'static str = "segmenter";
    const CONFIG_FILE: &'static str = "segmenter.json";
    const WEIGHTS_FILE: &'static str = "segmenter.bpk";

    fn init(&self, device: &Device) -> tactile_core::Result<UNet> {
        self.model.init(device)
    }

    fn check(&self, file: &std::path::Path) -> tactile_core::Result<()> {
        use tactile_burn::artifact::check_field;
        use tactile_core::error::in_config;
        in_config(file, self.model.check())?;
        in_config(file, self.stats.check(self.model.in_channels))?;
        let t = self.threshold;
        check_field(
            file,
            "threshold",
            (0.0..=1.0).contains(&t),
            t,
            "a probability in [0, 1]",
        )?;
        let p = &self.postprocess;
        let unit = |v: f64| (0.0..=1.0).contains(&v);
        check_field(
            file,
            "postprocess.edge_band",
            unit(p.edge_band),
            p.edge_band,
            "a fraction in [0, 1]",
        )?;
        check_field(
            file,
            "postprocess.edge_fraction",
            unit(p.edge_fraction),
            p.edge_fraction,
            "a fraction in [0, 1]",
        )?;
        let a = p.min_anisotropy;
        check_field(
            file,
            "postprocess.min_anisotropy",
            a.is_finite() && a >= 1.0,
            a,
            "a ratio of at least 1",
        )
    }
}

impl Exportable for SegmenterArtifact {
    /// `[N, 3, S, S]` normalised windows -> `[N, 1, S, S]` logits.
    fn onnx(&self, model: &UNet) -> tactile_onnx::Result<Vec<u8>> {
        let s = self.model.side;
        export_batch_dynamic(model, [1, 3, s, s], |m: &UNet, x| m.forward(x))
    }
}
