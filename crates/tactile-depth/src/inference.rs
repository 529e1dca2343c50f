//! The depth network at work: a frame of any size in, the camera-to-skin
//! distance of every pixel out (millimetres, at the network's input size),
//! on any runtime. `tactile run`, `tactile eval depth`, the Python package
//! and the benches all go through [`DepthEstimator`].

use std::path::Path;

use tactile_burn::{Network, Runtime};
use tactile_core::image_io::RgbImage;

use crate::Result;
use crate::artifact::DepthArtifact;

/// A loaded depth network, ready for frames of any size.
pub struct DepthEstimator {
    /// Architecture, statistics and depth scale.
    pub artifact: DepthArtifact,
    net: Box<dyn Network>,
}

impl DepthEstimator {
    /// Load the depth network in `dir` onto `runtime` (`threads` intra-op
    /// threads for onnxruntime; 0 = its default).
    pub fn load(dir: impl AsRef<Path>, runtime: Runtime, threads: usize) -> Result<Self> {
        let (artifact, net) =
            tactile_onnx::load_network::<DepthArtifact>(dir.as_ref(), runtime, threads)?;
        Ok(Self { artifact, net })
    }

    /// Where the network runs.
    pub fn runtime(&self) -> Runtime {
        self.net.runtime()
    }

    /// Depth in mm of `n` normalised inputs laid end to end, one
    /// `width * height` map (row-major) per input.
    pub fn depth_mm_of_inputs(&mut self, inputs: &[f32], n: usize) -> Result<Vec<Vec<f32>>> {
        let [w, h] = self.artifact.model.input_size;
        let c = self.artifact.model.in_channels;
        let z = self.net.run([n, c, h, w], inputs.to_vec())?;
        let scale = self.artifact.scale;
        Ok(z.chunks(w * h)
            .map(|m| m.iter().map(|&v| scale.to_mm(v)).collect())
            .collect())
    }

    /// Depth in mm at the network's input size (`width * height` values,
    /// row-major) of an RGB frame of any size; `mask` (at the input size)
    /// is required exactly when the network takes the mask channel.
    pub fn depth_mm(&mut self, frame: &RgbImage, mask: Option<&[bool]>) -> Result<Vec<f32>> {
        let a = &self.artifact;
        let x = a.model.frame_input(frame, &a.stats, mask)?;
        Ok(self.depth_mm_of_inputs(&x, 1)?.remove(0))
    }
}
