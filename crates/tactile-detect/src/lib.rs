//! Paper B's tendon detector: does this visuo-tactile frame show a tendon
//! under the skin? A MobileNetV3-small-style network (or the ResNet-18-style
//! baseline) on the frame resized to a fixed input and normalised with
//! training-set statistics saved beside the weights.

pub mod data;
pub mod model;
pub mod training;

use std::path::Path;

use burn::tensor::activation::sigmoid;
use burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};
use tactile_core::module_io::{load_artifact, save_artifact};
use tactile_core::{Error, Result};
use tactile_preprocess::visuo::{ChannelStats, FloatImage};

pub use data::{DetectionSet, SoftLabels};
pub use model::{Architecture, Detector, DetectorConfig};

/// File names inside a detector folder.
pub const CONFIG_FILE: &str = "detector.json";
pub const WEIGHTS_FILE: &str = "detector.bpk";

/// Everything needed to rebuild and run a saved detector.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DetectorArtifact {
    pub detector: DetectorConfig,
    /// Per-channel statistics of the training frames.
    pub stats: ChannelStats,
    /// Probability above which a frame counts as showing a tendon.
    pub threshold: f64,
    #[serde(default)]
    pub notes: serde_json::Value,
}

impl DetectorArtifact {
    pub fn save(&self, model: &Detector, dir: impl AsRef<Path>) -> Result<()> {
        save_artifact(dir.as_ref(), (CONFIG_FILE, WEIGHTS_FILE), self, model)
    }

    pub fn load(dir: impl AsRef<Path>, device: &Device) -> Result<(Self, Detector)> {
        load_artifact(
            dir.as_ref(),
            (CONFIG_FILE, WEIGHTS_FILE),
            "detector",
            |a: &Self| Ok(a.detector.init(device)),
        )
    }

    /// The normalised `3 x H x W` input of an RGB frame of any size
    /// (resized, then 8 bits per channel as in training, see
    /// [`FloatImage::quantised`]), or `None` for a blank frame (see
    /// [`is_blank`]), which shows no tendon.
    pub fn frame_input(
        &self,
        frame: &tactile_core::image_io::RgbImage,
    ) -> Result<Option<Vec<f32>>> {
        let [w, h] = self.detector.input_size;
        let img = tactile_preprocess::visuo::resize_rgb(frame, w, h)?.quantised();
        if is_blank(&img) {
            return Ok(None);
        }
        Ok(Some(self.stats.to_chw(&img)?))
    }

    /// Normalised `[N, 3, H, W]` input from frames already at the input size.
    pub fn input(&self, frames: &[FloatImage], device: &Device) -> Result<Tensor<4>> {
        let [w, h] = self.detector.input_size;
        let mut data = Vec::with_capacity(frames.len() * 3 * w * h);
        for f in frames {
            if (f.width, f.height) != (w, h) {
                return Err(Error::Invalid(format!(
                    "frame is {}x{}, the detector takes {w}x{h}: resize it first",
                    f.width, f.height
                )));
            }
            data.extend(self.stats.to_chw(f)?);
        }
        Ok(Tensor::from_data(
            TensorData::new(data, [frames.len(), 3, h, w]),
            device,
        ))
    }
}

pub use tactile_preprocess::visuo::{BLANK_FRAME_STD, is_blank};

/// A loaded detector, ready for frames of any size.
pub struct TendonDetector {
    pub artifact: DetectorArtifact,
    pub model: Detector,
    pub device: Device,
}

impl TendonDetector {
    pub fn load(dir: impl AsRef<Path>, device: &Device) -> Result<Self> {
        let (artifact, model) = DetectorArtifact::load(dir, device)?;
        Ok(Self {
            artifact,
            model,
            device: device.clone(),
        })
    }

    /// Tendon probability of an RGB frame of any size (resized to the
    /// input). A blank frame (black, saturated, one colour: no pixel
    /// differs from the mean by [`BLANK_FRAME_STD`]) cannot show a tendon
    /// and gets 0 without running the network, whose answer on such
    /// far-from-training inputs would be arbitrary.
    pub fn probability(&self, frame: &tactile_core::image_io::RgbImage) -> Result<f32> {
        let [w, h] = self.artifact.detector.input_size;
        match self.artifact.frame_input(frame)? {
            None => Ok(0.0),
            Some(x) => {
                let t = Tensor::from_data(TensorData::new(x, [1, 3, h, w]), &self.device);
                Ok(self.model.probabilities(t)?[0])
            }
        }
    }

    /// Tendon probability of a frame file; errors name the file.
    pub fn probability_of_file(&self, path: impl AsRef<Path>) -> Result<f32> {
        let path = path.as_ref();
        let frame = tactile_core::image_io::load_rgb(path)?;
        self.probability(&frame)
            .map_err(|e| Error::image(path, e.to_string()))
    }

    /// Whether the probability reaches the saved threshold.
    pub fn is_tendon(&self, p: f32) -> bool {
        p as f64 >= self.artifact.threshold
    }
}

impl Detector {
    /// Tendon probabilities of a normalised batch.
    pub fn probabilities(&self, x: Tensor<4>) -> Result<Vec<f32>> {
        sigmoid(self.forward(x))
            .into_data()
            .try_to_vec::<f32>()
            .map_err(|e| Error::Invalid(format!("detector output: {e:?}")))
    }
}
