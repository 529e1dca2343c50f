//! The segmenter at work: a frame of any size in, the kept tendon region
//! and its direction out, on any runtime. `tactile run`, `tactile eval
//! segmenter`, the Python package and the benches all go through
//! [`TendonSegmenter`].

use std::path::Path;

use tactile_burn::runtime::sigmoid;
use tactile_burn::{Network, Runtime};
use tactile_core::image_io::RgbImage;
use tactile_preprocess::visuo::{FloatImage, is_blank};

use crate::Result;
use crate::artifact::SegmenterArtifact;
use crate::postprocess::Tendon;

/// A loaded segmenter with its post-processing, ready for frames of any size.
pub struct TendonSegmenter {
    /// Window, statistics, threshold and post-processing.
    pub artifact: SegmenterArtifact,
    net: Box<dyn Network>,
}

/// What the segmenter made of one frame.
#[derive(Debug, Clone)]
pub struct Segmentation {
    /// The window it looked at (`S x S x 3`, in [0, 1]).
    pub window: FloatImage,
    /// Per-pixel probabilities (`None` for a blank window).
    pub probabilities: Option<Vec<f32>>,
    /// The kept region and its direction.
    pub tendon: Tendon,
}

impl TendonSegmenter {
    /// Load the segmenter in `dir` onto `runtime` (`threads` intra-op
    /// threads for onnxruntime; 0 = its default).
    pub fn load(dir: impl AsRef<Path>, runtime: Runtime, threads: usize) -> Result<Self> {
        let (artifact, net) =
            tactile_onnx::load_network::<SegmenterArtifact>(dir.as_ref(), runtime, threads)?;
        Ok(Self { artifact, net })
    }

    /// Where the network runs.
    pub fn runtime(&self) -> Runtime {
        self.net.runtime()
    }

    /// Per-pixel probabilities of `n` normalised windows laid end to end,
    /// one `S * S` vector per window.
    pub fn probabilities(&mut self, inputs: &[f32], n: usize) -> Result<Vec<Vec<f32>>> {
        let s = self.artifact.model.side;
        let z = self.net.run([n, 3, s, s], inputs.to_vec())?;
        Ok(z.chunks(s * s)
            .map(|c| c.iter().copied().map(sigmoid).collect())
            .collect())
    }

    /// Segment a window already cut (see
    /// [`UNetConfig::frame_window`](crate::UNetConfig::frame_window)). A blank window (see
    /// [`is_blank`]) gives an empty mask without running the network.
    pub fn segment_window(&mut self, window: FloatImage) -> Result<Segmentation> {
        let probabilities = if is_blank(&window) {
            None
        } else {
            let x = self
                .artifact
                .model
                .window_input(&window, &self.artifact.stats)?;
            self.probabilities(&x, 1)?.pop()
        };
        let a = &self.artifact;
        let tendon = crate::postprocess::window_tendon(
            a.model.side,
            probabilities.as_deref(),
            &window,
            a.threshold,
            &a.postprocess,
        )?;
        Ok(Segmentation {
            window,
            probabilities,
            tendon,
        })
    }

    /// Segment the window of an RGB frame of any size: the kept region and
    /// its direction (or why there is none).
    pub fn segment(&mut self, frame: &RgbImage) -> Result<Segmentation> {
        let window = self.artifact.model.frame_window(frame)?;
        self.segment_window(window)
    }

    /// [`Self::segment`] of a frame file; errors name the file.
    pub fn segment_file(&mut self, path: impl AsRef<Path>) -> Result<Segmentation> {
        let path = path.as_ref();
        let frame = tactile_core::image_io::load_rgb(path)?;
        self.segment(&frame)
            .map_err(|e| tactile_core::Error::image(path, e.to_string()).into())
    }
}
