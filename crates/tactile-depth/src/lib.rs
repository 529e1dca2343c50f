//! Paper B's depth reconstruction: from one visuo-tactile RGB frame (and
//! optionally the tendon mask as a fourth channel) to the camera-to-skin
//! distance of every pixel. Files hold metres; the network works in
//! millimetres around the training mean (metres stalled paper B's
//! training: the targets barely vary).

pub mod data;
pub mod model;
pub mod torchvision;
pub mod training;

use std::path::Path;

use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_core::module_io::{load_artifact, save_artifact};
use tactile_core::{Error, Result};
use tactile_preprocess::visuo::ChannelStats;

pub use data::DepthSet;
pub use model::{DenseNetConfig, DepthNet, DepthNetConfig, HeadKind};

pub const CONFIG_FILE: &str = "depth.json";
pub const WEIGHTS_FILE: &str = "depth.bpk";

/// How depth is represented inside the network: `(depth_mm - offset_mm) /
/// unit_mm`. With `unit_mm = 1` the network works in millimetres; 1000
/// would be metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DepthScale {
    pub offset_mm: f32,
    pub unit_mm: f32,
}

impl DepthScale {
    pub fn to_model(&self, depth_mm: f32) -> f32 {
        (depth_mm - self.offset_mm) / self.unit_mm
    }

    pub fn to_mm(&self, v: f32) -> f32 {
        v * self.unit_mm + self.offset_mm
    }
}

/// Which loss trains the network.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LossKind {
    L1,
    Mse,
    /// L1 + gradient + SSIM (DenseTact).
    L1GradSsim,
}

impl std::str::FromStr for LossKind {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "l1" => Ok(Self::L1),
            "mse" => Ok(Self::Mse),
            "l1-grad-ssim" => Ok(Self::L1GradSsim),
            o => Err(Error::Config(format!(
                "unknown loss '{o}': expected l1, mse or l1-grad-ssim"
            ))),
        }
    }
}

/// Everything needed to rebuild and run a saved depth network.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DepthArtifact {
    pub net: DepthNetConfig,
    pub stats: ChannelStats,
    pub scale: DepthScale,
    /// True when the fourth input channel is the tendon mask.
    pub with_mask: bool,
    #[serde(default)]
    pub notes: serde_json::Value,
}

impl DepthArtifact {
    pub fn save(&self, model: &DepthNet, dir: impl AsRef<Path>) -> Result<()> {
        save_artifact(dir.as_ref(), (CONFIG_FILE, WEIGHTS_FILE), self, model)
    }

    pub fn load(dir: impl AsRef<Path>, device: &Device) -> Result<(Self, DepthNet)> {
        load_artifact(
            dir.as_ref(),
            (CONFIG_FILE, WEIGHTS_FILE),
            "depth model",
            |a: &Self| a.net.init(device),
        )
    }

    /// The normalised `C x H x W` input of an RGB frame of any size
    /// (resized, then 8 bits per channel as in training, see
    /// [`FloatImage::quantised`](tactile_preprocess::visuo::FloatImage::quantised));
    /// `mask` (at the input size) is required exactly when the network
    /// takes the mask channel.
    pub fn frame_input(
        &self,
        frame: &tactile_core::image_io::RgbImage,
        mask: Option<&[bool]>,
    ) -> Result<Vec<f32>> {
        let [w, h] = self.net.input_size;
        let img = tactile_preprocess::visuo::resize_rgb(frame, w, h)?.quantised();
        let mut x = self.stats.to_chw(&img)?;
        match (self.with_mask, mask) {
            (true, Some(m)) if m.len() == w * h => x.extend(m.iter().map(|&b| b as u8 as f32)),
            (true, _) => {
                return Err(Error::Invalid(format!(
                    "this depth network takes a {w}x{h} tendon mask as a fourth channel"
                )));
            }
            (false, _) => {}
        }
        Ok(x)
    }
}

/// Depth metrics of predictions against truth, in millimetres.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct DepthScores {
    pub frames: usize,
    /// Mean absolute error inside the sensing window.
    pub mae_mm: f64,
    /// Mean absolute error over the tendon mask (frames with a tendon).
    pub mae_tendon_mm: Option<f64>,
    pub rmse_mm: f64,
    /// Mean SSIM over frames (dynamic range: the 12-18 mm of the spec).
    pub ssim: f64,
}

/// Dynamic range used by SSIM, mm (sensors.md: depths lie in 12-18 mm).
pub const DEPTH_RANGE_MM: f64 = 6.0;

/// Accumulates per-frame metrics.
#[derive(Default)]
pub struct DepthScorer {
    n: usize,
    mae: f64,
    rmse_sq: f64,
    ssim: f64,
    tendon_abs: f64,
    tendon_px: usize,
}

impl DepthScorer {
    /// Add one frame (`w x h` maps in mm).
    pub fn add(
        &mut self,
        pred: &[f32],
        truth: &[f32],
        window: &[bool],
        mask: &[bool],
        (w, h): (usize, usize),
    ) {
        use tactile_core::metrics::{masked_mae, masked_rmse, ssim};
        self.n += 1;
        self.mae += masked_mae(pred, truth, Some(window)).unwrap_or(0.0);
        self.rmse_sq += masked_rmse(pred, truth, Some(window))
            .unwrap_or(0.0)
            .powi(2);
        self.ssim += ssim(pred, truth, w, h, DEPTH_RANGE_MM);
        for i in 0..pred.len() {
            if mask[i] {
                self.tendon_abs += (pred[i] as f64 - truth[i] as f64).abs();
                self.tendon_px += 1;
            }
        }
    }

    pub fn finish(&self) -> DepthScores {
        let n = self.n.max(1) as f64;
        DepthScores {
            frames: self.n,
            mae_mm: self.mae / n,
            mae_tendon_mm: (self.tendon_px > 0).then(|| self.tendon_abs / self.tendon_px as f64),
            rmse_mm: (self.rmse_sq / n).sqrt(),
            ssim: self.ssim / n,
        }
    }
}

/// A loaded depth network, ready for frames of any size.
pub struct DepthEstimator {
    pub artifact: DepthArtifact,
    pub model: DepthNet,
    pub device: Device,
}

impl DepthEstimator {
    pub fn load(dir: impl AsRef<Path>, device: &Device) -> Result<Self> {
        let (artifact, model) = DepthArtifact::load(dir, device)?;
        Ok(Self {
            artifact,
            model,
            device: device.clone(),
        })
    }

    /// Depth in mm at the network's input size (`width * height` values,
    /// row-major) for an RGB frame of any size; `mask` (at the input size)
    /// is required exactly when the network takes the mask channel.
    pub fn depth_mm(
        &self,
        frame: &tactile_core::image_io::RgbImage,
        mask: Option<&[bool]>,
    ) -> Result<Vec<f32>> {
        use burn::tensor::{Tensor, TensorData};
        let [w, h] = self.artifact.net.input_size;
        let x = self.artifact.frame_input(frame, mask)?;
        let c = self.artifact.net.in_channels;
        let t = Tensor::<4>::from_data(TensorData::new(x, [1, c, h, w]), &self.device);
        let v = self
            .model
            .forward(t)
            .into_data()
            .try_to_vec::<f32>()
            .map_err(|e| Error::Invalid(format!("depth output: {e:?}")))?;
        Ok(v.into_iter()
            .map(|m| self.artifact.scale.to_mm(m))
            .collect())
    }
}
