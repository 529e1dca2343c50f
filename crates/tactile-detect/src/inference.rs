//! The detector at work: a frame of any size in, a tendon probability out,
//! on any runtime. `tactile run`, `tactile eval detector`, the Python
//! package and the benches all go through [`TendonDetector`].

use std::path::Path;

use tactile_core::image_io::RgbImage;
use tactile_core::runtime::sigmoid;
use tactile_core::{Artifact, Network, Runtime};

use crate::Result;
use crate::artifact::DetectorArtifact;
use crate::ensemble::DetectorEnsembleArtifact;

/// A loaded detector, ready for frames of any size.
pub struct TendonDetector {
    /// Architecture, statistics and threshold.
    pub artifact: DetectorArtifact,
    net: Box<dyn Network>,
}

/// What the detector makes of one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Assessment {
    /// Tendon probability; 0 for a blank frame or one out of distribution.
    pub probability: f32,
    /// Distance from the training frames' input statistics, in spreads
    /// (None without an input profile).
    pub input_score: Option<f32>,
    /// Far outside the training frames: another sensor, an image that is
    /// not a sensor frame; no tendon, direction or depth is given.
    pub out_of_distribution: bool,
}

impl TendonDetector {
    /// Load the detector in `dir` onto `runtime` (`threads` intra-op
    /// threads for onnxruntime; 0 = its default). An ensemble folder
    /// ([`DetectorEnsembleArtifact`]) loads as one network, used with its
    /// first member's config.
    pub fn load(dir: impl AsRef<Path>, runtime: Runtime, threads: usize) -> Result<Self> {
        let dir = dir.as_ref();
        let (artifact, net) = if DetectorEnsembleArtifact::is_in(dir) {
            let (e, net) =
                tactile_onnx::load_network::<DetectorEnsembleArtifact>(dir, runtime, threads)?;
            (e.lead()?.clone(), net)
        } else {
            tactile_onnx::load_network::<DetectorArtifact>(dir, runtime, threads)?
        };
        Ok(Self { artifact, net })
    }

    /// Where the network runs.
    pub fn runtime(&self) -> Runtime {
        self.net.runtime()
    }

    /// Tendon probability of an RGB frame of any size (resized to the
    /// input). A blank frame (black, saturated, one colour) cannot show a
    /// tendon and gets 0 without running the network, whose answer on such
    /// far-from-training inputs would be arbitrary.
    pub fn probability(&mut self, frame: &RgbImage) -> Result<f32> {
        match self.artifact.frame_input(frame)? {
            None => Ok(0.0),
            Some(x) => Ok(self.probabilities(&x, 1)?[0]),
        }
    }

    /// The tendon probability and, with an input profile, how far the
    /// frame lies from the training frames (see [`Assessment`]).
    pub fn assess(&mut self, frame: &RgbImage) -> Result<Assessment> {
        let img = self.artifact.frame_image(frame)?;
        let input_score = self.artifact.input_score(&img)?;
        let out_of_distribution = match (&self.artifact.input_profile, input_score) {
            (Some(p), Some(s)) => s > p.threshold,
            _ => false,
        };
        let probability = if out_of_distribution || tactile_preprocess::visuo::is_blank(&img) {
            0.0
        } else {
            self.probabilities(&self.artifact.network_input(img)?, 1)?[0]
        };
        Ok(Assessment {
            probability,
            input_score,
            out_of_distribution,
        })
    }

    /// Tendon probabilities of `n` normalised inputs laid end to end (as
    /// [`DetectorArtifact::frame_input`] makes them).
    pub fn probabilities(&mut self, inputs: &[f32], n: usize) -> Result<Vec<f32>> {
        let [w, h] = self.artifact.model.input_size;
        let z = self.net.run([n, 3, h, w], inputs.to_vec())?;
        Ok(z.into_iter().map(sigmoid).collect())
    }

    /// Tendon probability of a frame file; errors name the file.
    pub fn probability_of_file(&mut self, path: impl AsRef<Path>) -> Result<f32> {
        let path = path.as_ref();
        let frame = tactile_core::image_io::load_rgb(path)?;
        self.probability(&frame)
            .map_err(|e| tactile_core::Error::image(path, e.to_string()).into())
    }

    /// Whether probability `p` reaches the saved threshold.
    pub fn is_tendon(&self, p: f32) -> bool {
        self.artifact.is_tendon(p)
    }
}
