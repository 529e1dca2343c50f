//! A trained detector on disk: `detector.json` (architecture, training-set
//! channel statistics, the calibrated threshold, provenance) beside
//! `detector.bpk`.

use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_burn::Artifact;
use tactile_core::image_io::RgbImage;
use tactile_onnx::{Exportable, export_batch_dynamic};
use tactile_preprocess::profile::{InputProfile, descriptor};
use tactile_preprocess::visuo::{ChannelStats, FloatImage, resize_rgb};

use crate::Result;
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
            p.validate()
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
    /// The normalised `3 x H x W` network input of an RGB frame of any size
    /// (resized, then rounded to the input's bits as in training, see
    /// [`FloatImage::quantised_to`](tactile_preprocess::visuo::FloatImage::quantised_to)).
    /// No gate is applied: a frame's answer is
    /// [`TendonDetector::assess`](crate::TendonDetector::assess)'s.
    pub fn frame_input(&self, frame: &RgbImage) -> Result<Vec<f32>> {
        self.network_input(self.frame_image(frame)?)
    }

    /// The frame as the detector sees it (resized to its input, rounded
    /// to its bits per channel), from which both its input and its input
    /// statistics are taken.
    pub fn frame_image(&self, frame: &RgbImage) -> Result<FloatImage> {
        let [w, h] = self.model.input_size;
        Ok(resize_rgb(frame, w, h)?.quantised_to(self.model.bits()))
    }

    /// The normalised `3 x H x W` network input of a frame image made by
    /// [`Self::frame_image`].
    pub fn network_input(&self, img: FloatImage) -> Result<Vec<f32>> {
        Ok(self.stats.to_chw(&self.model.network_view(img))?)
    }

    /// How far `frame` lies from the training frames' input statistics
    /// ([`InputProfile::score`]), when the detector has a profile.
    pub fn input_score(&self, image: &FloatImage) -> Result<Option<f32>> {
        match &self.input_profile {
            Some(p) => Ok(Some(p.score(&descriptor(image)?))),
            None => Ok(None),
        }
    }

    /// Whether probability `p` reaches the saved threshold.
    pub fn is_tendon(&self, p: f32) -> bool {
        p as f64 >= self.threshold
    }
}
