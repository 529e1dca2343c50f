//! A trained depth network on disk: `depth.json` (architecture, the
//! training frames' channel statistics, the depth scale, whether the mask
//! or a calibration's reconstruction is an input) beside `depth.bpk`.

use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_burn::Artifact;
use tactile_onnx::{Exportable, export_batch_dynamic};
use tactile_preprocess::visuo::ChannelStats;

use crate::model::{DepthNet, DepthNetConfig};

/// How depth is represented inside the network: `(depth_mm - offset_mm) /
/// unit_mm`. With `unit_mm = 1` the network works in millimetres; 1000
/// would be metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DepthScale {
    /// Depth the model's 0 stands for (the training mean), mm.
    pub offset_mm: f32,
    /// Millimetres per model unit.
    pub unit_mm: f32,
}

impl DepthScale {
    /// Millimetres to model units.
    pub fn to_model(&self, depth_mm: f32) -> f32 {
        (depth_mm - self.offset_mm) / self.unit_mm
    }

    /// Model units to millimetres.
    pub fn to_mm(&self, v: f32) -> f32 {
        v * self.unit_mm + self.offset_mm
    }
}

/// Everything needed to rebuild and run a saved depth network.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DepthArtifact {
    /// Encoder, decoder, head and input size.
    #[serde(alias = "net")]
    pub model: DepthNetConfig,
    /// Per-channel statistics of the training frames.
    pub stats: ChannelStats,
    /// Millimetres and model units.
    pub scale: DepthScale,
    /// True when the fourth input channel is the tendon mask.
    pub with_mask: bool,
    /// The sensor calibration whose reconstruction it corrects (its
    /// fourth channel); `None` for a network of the frame alone.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prior: Option<crate::prior::CalibrationPrior>,
    /// What its maps hold: camera-to-skin distance (the virtual sensor) or
    /// a calibrated sensor's indentation.
    #[serde(default)]
    pub depth_maps: tactile_core::spec::DepthMaps,
    /// Provenance.
    #[serde(default)]
    pub notes: serde_json::Value,
}

impl Artifact for DepthArtifact {
    type Model = DepthNet;
    const KIND: &'static str = "depth model";
    const CONFIG_FILE: &'static str = "depth.json";
    const WEIGHTS_FILE: &'static str = "depth.bpk";

    fn init(&self, device: &Device) -> tactile_core::Result<DepthNet> {
        self.model.init(device)
    }

    fn check(&self, file: &std::path::Path) -> tactile_core::Result<()> {
        use tactile_burn::artifact::check_field;
        use tactile_core::error::in_config;
        in_config(file, self.model.check())?;
        in_config(file, self.stats.check(3))?;
        let s = &self.scale;
        check_field(
            file,
            "scale.unit_mm",
            s.unit_mm.is_finite() && s.unit_mm > 0.0,
            s.unit_mm,
            "a positive number of millimetres",
        )?;
        check_field(
            file,
            "scale.offset_mm",
            s.offset_mm.is_finite(),
            s.offset_mm,
            "a finite number of millimetres",
        )?;
        check_field(
            file,
            "prior",
            !(self.with_mask && self.prior.is_some()),
            "a prior and with_mask",
            "a mask channel or a prior, not both",
        )?;
        check_field(
            file,
            "model.residual_channel",
            self.model.residual_channel == self.prior.as_ref().map(|_| 3),
            format!("{:?}", self.model.residual_channel),
            "3 with a prior, none without",
        )?;
        let c = self.model.in_channels;
        check_field(
            file,
            "model.in_channels",
            c == 3 + usize::from(self.with_mask || self.prior.is_some()),
            c,
            "3, or 4 with the mask channel (with_mask) or a prior",
        )
    }
}

impl Exportable for DepthArtifact {
    /// `[N, C, H, W]` normalised frames (C = 3, or 4 with the mask or the
    /// prior in model units) -> `[N, 1, H, W]` depth in model units.
    fn onnx(&self, model: &DepthNet) -> tactile_onnx::Result<Vec<u8>> {
        let [w, h] = self.model.input_size;
        let c = self.model.in_channels;
        export_batch_dynamic(model, [1, c, h, w], |m: &DepthNet, x| m.forward(x))
    }
}
