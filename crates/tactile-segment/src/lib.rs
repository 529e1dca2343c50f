//! Paper B's tendon segmenter: a small U-Net on a square window of the
//! visuo-tactile frame, then post-processing (largest region, LED-glare
//! override) and the region's direction by PCA.

pub mod data;
pub mod model;
pub mod postprocess;
pub mod training;

use std::path::Path;

use burn::tensor::activation::sigmoid;
use burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};
use tactile_core::module_io::{load_artifact, save_artifact};
use tactile_core::{Error, Result};
use tactile_preprocess::visuo::{ChannelStats, FloatImage, SquareWindow};

pub use data::SegmentSet;
pub use model::{UNet, UNetConfig};
pub use postprocess::{Direction, NoDirection, PostprocessConfig, Tendon, TendonMask, postprocess};

pub const CONFIG_FILE: &str = "segmenter.json";
pub const WEIGHTS_FILE: &str = "segmenter.bpk";

/// Everything needed to rebuild and run a saved segmenter.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SegmenterArtifact {
    pub unet: UNetConfig,
    pub stats: ChannelStats,
    /// Probability above which a pixel is tendon.
    pub threshold: f32,
    pub postprocess: PostprocessConfig,
    #[serde(default)]
    pub notes: serde_json::Value,
}

impl SegmenterArtifact {
    pub fn window(&self) -> SquareWindow {
        SquareWindow {
            side: self.unet.side,
        }
    }

    pub fn save(&self, model: &UNet, dir: impl AsRef<Path>) -> Result<()> {
        save_artifact(dir.as_ref(), (CONFIG_FILE, WEIGHTS_FILE), self, model)
    }

    pub fn load(dir: impl AsRef<Path>, device: &Device) -> Result<(Self, UNet)> {
        load_artifact(
            dir.as_ref(),
            (CONFIG_FILE, WEIGHTS_FILE),
            "segmenter",
            |a: &Self| a.unet.init(device),
        )
    }

    /// The segmenter's (unrotated) window of an RGB frame of any size, at 8
    /// bits per channel as in training ([`FloatImage::quantised`]).
    pub fn frame_window(&self, frame: &tactile_core::image_io::RgbImage) -> Result<FloatImage> {
        let win = self.window();
        let (sw, sh) = win.scaled_size(frame.width(), frame.height());
        Ok(win
            .cut(&tactile_preprocess::visuo::resize_rgb(frame, sw, sh)?, 0.0)
            .quantised())
    }

    /// Post-processed tendon from the window's per-pixel probabilities;
    /// `None` (a blank window: nothing to segment) gives an empty mask and
    /// hence no direction.
    pub fn tendon(&self, probabilities: Option<&[f32]>) -> Result<Tendon> {
        let s = self.unet.side;
        let mask = match probabilities {
            Some(p) => TendonMask::from_probabilities(s, s, p, self.threshold)?,
            None => TendonMask {
                width: s,
                height: s,
                pixels: vec![false; s * s],
            },
        };
        postprocess(&mask, &self.postprocess)
    }

    /// Normalised `[N, 3, S, S]` input from windows.
    pub fn input(&self, windows: &[FloatImage], device: &Device) -> Result<Tensor<4>> {
        let s = self.unet.side;
        let mut data = Vec::with_capacity(windows.len() * 3 * s * s);
        for w in windows {
            if (w.width, w.height) != (s, s) {
                return Err(Error::Invalid(format!(
                    "window is {}x{}, the segmenter takes {s}x{s}",
                    w.width, w.height
                )));
            }
            data.extend(self.stats.to_chw(w)?);
        }
        Ok(Tensor::from_data(
            TensorData::new(data, [windows.len(), 3, s, s]),
            device,
        ))
    }
}

/// A loaded segmenter with its post-processing, ready for frames of any size.
pub struct TendonSegmenter {
    pub artifact: SegmenterArtifact,
    pub model: UNet,
    pub device: Device,
}

impl TendonSegmenter {
    pub fn load(dir: impl AsRef<Path>, device: &Device) -> Result<Self> {
        let (artifact, model) = SegmenterArtifact::load(dir, device)?;
        Ok(Self {
            artifact,
            model,
            device: device.clone(),
        })
    }

    /// Predicted mask of the frame's window, post-processed: the kept region
    /// and its direction (or why there is none). A blank window (see
    /// [`tactile_preprocess::visuo::is_blank`]) gives an empty mask.
    pub fn segment(&self, frame: &tactile_core::image_io::RgbImage) -> Result<Tendon> {
        let cut = self.artifact.frame_window(frame)?;
        if tactile_preprocess::visuo::is_blank(&cut) {
            return self.artifact.tendon(None);
        }
        let x = self.artifact.input(&[cut], &self.device)?;
        let p = self.model.probabilities(x)?.remove(0);
        self.artifact.tendon(Some(&p))
    }

    /// [`Self::segment`] of a frame file; errors name the file.
    pub fn segment_file(&self, path: impl AsRef<Path>) -> Result<Tendon> {
        let path = path.as_ref();
        let frame = tactile_core::image_io::load_rgb(path)?;
        self.segment(&frame)
            .map_err(|e| Error::image(path, e.to_string()))
    }
}

impl UNet {
    /// Per-pixel tendon probabilities, one `S*S` vector per window.
    pub fn probabilities(&self, x: Tensor<4>) -> Result<Vec<Vec<f32>>> {
        let [n, _, h, w] = x.dims();
        let v = sigmoid(self.forward(x))
            .into_data()
            .try_to_vec::<f32>()
            .map_err(|e| Error::Invalid(format!("segmenter output: {e:?}")))?;
        Ok(v.chunks(h * w).take(n).map(<[f32]>::to_vec).collect())
    }
}
