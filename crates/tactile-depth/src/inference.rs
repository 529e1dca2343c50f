//! The depth network (one, or an ensemble) at work: a frame of any size in, the camera-to-skin
//! distance of every pixel out (millimetres, at the network's input size),
//! on any runtime. `tactile run`, `tactile eval depth`, the Python package
//! and the benches all go through [`DepthEstimator`].

use std::path::{Path, PathBuf};

use tactile_burn::{Artifact, Network, Runtime};
use tactile_core::image_io::RgbImage;

use tactile_gelsight::IndentationMap;

use crate::Result;
use crate::artifact::DepthArtifact;
use crate::ensemble::DepthEnsembleArtifact;
use crate::prepare::FourthChannel;
use crate::prior::PriorSource;

/// A loaded depth network, ready for frames of any size.
pub struct DepthEstimator {
    /// Architecture, statistics and depth scale.
    pub artifact: DepthArtifact,
    net: Box<dyn Network>,
    /// The calibration a network with a prior corrects, and its folder.
    prior: Option<(PriorSource, PathBuf)>,
}

impl DepthEstimator {
    /// Load the depth network in `dir` (one, or an ensemble of them:
    /// [`crate::ensemble`]) onto `runtime` (`threads` intra-op threads for
    /// onnxruntime; 0 = its default).
    pub fn load(dir: impl AsRef<Path>, runtime: Runtime, threads: usize) -> Result<Self> {
        let dir = dir.as_ref();
        let (artifact, net) = if DepthEnsembleArtifact::is_in(dir) {
            let (e, net) =
                tactile_onnx::load_network::<DepthEnsembleArtifact>(dir, runtime, threads)?;
            (e.lead()?, net)
        } else {
            tactile_onnx::load_network::<DepthArtifact>(dir, runtime, threads)?
        };
        let prior = match &artifact.prior {
            Some(p) => {
                let folder = p.folder(dir);
                Some((PriorSource::load(&folder, runtime, threads)?, folder))
            }
            None => None,
        };
        Ok(Self {
            artifact,
            net,
            prior,
        })
    }

    /// The folder of the calibration a network with a prior corrects
    /// (`None` for a network of the frame alone).
    pub fn prior_folder(&self) -> Option<&Path> {
        self.prior.as_ref().map(|(_, f)| f.as_path())
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
    /// is required exactly when the network takes the mask channel. A
    /// network with a prior reconstructs the frame through its calibration
    /// first (the frame must be of the calibrated size).
    pub fn depth_mm(&mut self, frame: &RgbImage, mask: Option<&[bool]>) -> Result<Vec<f32>> {
        let size = self.artifact.model.input_size;
        let prior = match self.prior.as_mut() {
            Some((p, _)) => Some(p.prior_mm(frame, Path::new("the frame"), size)?),
            None => None,
        };
        self.depth_mm_of_frame(frame, mask, prior.as_deref())
    }

    /// [`Self::depth_mm`] of a frame whose calibration's reconstruction
    /// was made already (the pipeline makes it on every frame of a
    /// calibrated sensor); a network without a prior ignores it.
    pub fn depth_mm_reconstructed(
        &mut self,
        frame: &RgbImage,
        reconstruction: &IndentationMap,
    ) -> Result<Vec<f32>> {
        let prior = match self.artifact.model.takes_prior() {
            true => Some(crate::prior::map_at(
                reconstruction,
                self.artifact.model.input_size,
            )?),
            false => None,
        };
        self.depth_mm_of_frame(frame, None, prior.as_deref())
    }

    fn depth_mm_of_frame(
        &mut self,
        frame: &RgbImage,
        mask: Option<&[bool]>,
        prior_mm: Option<&[f32]>,
    ) -> Result<Vec<f32>> {
        let a = &self.artifact;
        let fourth = match (mask, prior_mm) {
            (_, Some(p)) => FourthChannel::Prior(p, a.scale),
            (Some(m), None) => FourthChannel::Mask(m),
            (None, None) => FourthChannel::Nothing,
        };
        let x = a.model.frame_input(frame, &a.stats, fourth)?;
        Ok(self.depth_mm_of_inputs(&x, 1)?.remove(0))
    }
}
