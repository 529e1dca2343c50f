//! A trained segmenter on disk: `segmenter.json` (the U-Net's size, the
//! training windows' channel statistics, the pixel threshold and the
//! post-processing settings) beside `segmenter.bpk`.

use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_burn::Artifact;
use tactile_core::image_io::RgbImage;
use tactile_onnx::{Exportable, export_batch_dynamic};
use tactile_preprocess::visuo::{ChannelStats, FloatImage, SquareWindow, resize_rgb};

use crate::model::{UNet, UNetConfig};
use crate::postprocess::{Evidence, PostprocessConfig, Tendon, TendonMask, postprocess};
use crate::{Error, Result};

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

impl SegmenterArtifact {
    /// The square window the segmenter looks at.
    pub fn window(&self) -> SquareWindow {
        SquareWindow {
            side: self.model.side,
        }
    }

    /// The segmenter's (unrotated) window of an RGB frame of any size, at 8
    /// bits per channel as in training ([`FloatImage::quantised`]).
    pub fn frame_window(&self, frame: &RgbImage) -> Result<FloatImage> {
        let win = self.window();
        let (sw, sh) = win.scaled_size(frame.width(), frame.height());
        Ok(win.cut(&resize_rgb(frame, sw, sh)?, 0.0).quantised())
    }

    /// The normalised `3 x S x S` input of a window.
    pub fn window_input(&self, window: &FloatImage) -> Result<Vec<f32>> {
        let s = self.model.side;
        if (window.width, window.height) != (s, s) {
            return Err(Error::WindowSize {
                what: "window",
                expected: [s, s],
                found: [window.width, window.height],
            });
        }
        Ok(self.stats.to_chw(window)?)
    }

    /// Post-processed tendon from the window's per-pixel probabilities;
    /// `None` (a blank window: nothing to segment) gives an empty mask and
    /// hence no direction.
    pub fn tendon(&self, probabilities: Option<&[f32]>, window: &FloatImage) -> Result<Tendon> {
        let s = self.model.side;
        let mask = match probabilities {
            Some(p) => TendonMask::from_probabilities(s, s, p, self.threshold)?,
            None => TendonMask::empty(s, s),
        };
        let evidence = Evidence {
            probabilities,
            window: Some(window),
        };
        postprocess(&mask, evidence, &self.postprocess)
    }
}
