//! The detector at work: a frame of any size in, a tendon probability out,
//! on any runtime. `tactile run`, `tactile eval detector`, the Python
//! package and the benches all go through [`TendonDetector`].

use std::path::Path;

use tactile_burn::runtime::sigmoid;
use tactile_burn::{Artifact, Network, Runtime};
use tactile_core::image_io::RgbImage;
use tactile_preprocess::visuo::FloatImage;

use crate::Result;
use crate::artifact::DetectorArtifact;
use crate::ensemble::DetectorEnsembleArtifact;

/// A loaded detector, ready for frames of any size.
pub struct TendonDetector {
    /// Architecture, statistics and threshold.
    pub artifact: DetectorArtifact,
    net: Box<dyn Network>,
}

/// Why a frame got no answer from the network: the gates every caller
/// shares (`tactile run`, `tactile eval detector`, Python, the benches).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Gate {
    /// No channel varies (black, saturated, one colour): no tendon can
    /// show, and a network's answer on such an input would be arbitrary.
    Blank,
    /// Far outside the training frames' input statistics (another
    /// sensor, an image that is not a sensor frame), or of another camera
    /// mode (grey where they were in colour).
    Foreign,
}

impl Gate {
    /// The gate's name in records ("blank", "foreign").
    pub fn name(self) -> &'static str {
        match self {
            Gate::Blank => "blank",
            Gate::Foreign => "foreign",
        }
    }
}

/// What the detector makes of one frame: the one answer every caller gets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Assessment {
    /// Tendon probability; 0 for a gated frame.
    pub probability: f32,
    /// The decision: `probability` against the saved threshold.
    pub tendon: bool,
    /// The gate that stopped the frame before the network, if any.
    pub gate: Option<Gate>,
    /// Distance from the training frames' input statistics, in spreads
    /// (None without an input profile).
    pub input_score: Option<f32>,
    /// Far outside the training frames (`gate` is [`Gate::Foreign`]): no
    /// tendon, direction or depth is given.
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

    /// Tendon probability of an RGB frame of any size: [`Self::assess`]'s.
    pub fn probability(&mut self, frame: &RgbImage) -> Result<f32> {
        Ok(self.assess(frame)?.probability)
    }

    /// The answer for an RGB frame of any size (resized to the input).
    pub fn assess(&mut self, frame: &RgbImage) -> Result<Assessment> {
        let img = self.artifact.model.frame_image(frame)?;
        Ok(self.assess_images(vec![img])?.remove(0))
    }

    /// The gate a frame image (made by
    /// [`DetectorConfig::frame_image`](crate::DetectorConfig::frame_image))
    /// meets, and its input score (how far it lies from the training
    /// frames' input statistics, when the detector has a profile). The
    /// input profile is asked first: a frame outside it is foreign even
    /// when it is also blank. A frame of another camera mode than the
    /// training frames (grey to a detector of colour frames) is foreign
    /// unless blank: a black or saturated frame is grey too.
    pub fn gate(&self, img: &FloatImage) -> Result<(Option<Gate>, Option<f32>)> {
        let blank = tactile_preprocess::visuo::is_blank(img);
        let (input_score, foreign) = match &self.artifact.input_profile {
            Some(p) => {
                let s = p.score_frame(img)?;
                (
                    Some(s),
                    s > p.threshold || (!blank && p.other_camera_mode(img)),
                )
            }
            None => (None, false),
        };
        let gate = if foreign {
            Some(Gate::Foreign)
        } else if blank {
            Some(Gate::Blank)
        } else {
            None
        };
        Ok((gate, input_score))
    }

    /// The answer for a frame that met `gate` and, when it passed, whose
    /// network probability is `network`: the one rule that turns both
    /// into a decision.
    pub fn answer(
        &self,
        (gate, input_score): (Option<Gate>, Option<f32>),
        network: Option<f32>,
    ) -> Assessment {
        let probability = match gate {
            Some(_) => 0.0,
            None => network.unwrap_or(0.0),
        };
        Assessment {
            probability,
            tendon: gate.is_none() && self.is_tendon(probability),
            gate,
            input_score,
            out_of_distribution: gate == Some(Gate::Foreign),
        }
    }

    /// The answer for a frame image whose `gate` was asked already
    /// ([`Self::gate`]; a caller that acts on the gate first, as a
    /// calibrated sensor's pipeline does before reconstructing): the
    /// network runs only when no gate stopped it.
    pub fn assess_gated(
        &mut self,
        img: FloatImage,
        gate: (Option<Gate>, Option<f32>),
    ) -> Result<Assessment> {
        let network = match gate.0 {
            Some(_) => None,
            None => {
                let input = self
                    .artifact
                    .model
                    .network_input(img, &self.artifact.stats)?;
                self.network_probabilities(&input, 1)?.into_iter().next()
            }
        };
        Ok(self.answer(gate, network))
    }

    /// The answers for frame images made by
    /// [`DetectorConfig::frame_image`](crate::DetectorConfig::frame_image), the network run once on the
    /// frames no gate stopped.
    pub fn assess_images(&mut self, images: Vec<FloatImage>) -> Result<Vec<Assessment>> {
        let gates = images
            .iter()
            .map(|img| self.gate(img))
            .collect::<Result<Vec<_>>>()?;
        let mut inputs = Vec::new();
        let mut passed = 0;
        for (img, (gate, _)) in images.into_iter().zip(&gates) {
            if gate.is_none() {
                inputs.extend(
                    self.artifact
                        .model
                        .network_input(img, &self.artifact.stats)?,
                );
                passed += 1;
            }
        }
        let mut p = if passed > 0 {
            self.network_probabilities(&inputs, passed)?.into_iter()
        } else {
            Vec::new().into_iter()
        };
        Ok(gates
            .into_iter()
            .map(|g| {
                let network = if g.0.is_none() { p.next() } else { None };
                self.answer(g, network)
            })
            .collect())
    }

    /// The network's own tendon probabilities of `n` normalised inputs laid
    /// end to end (as [`DetectorConfig::network_input`](crate::DetectorConfig::network_input) makes them), no
    /// gate applied: for training, calibration and the ungated scores of
    /// an evaluation. A frame's answer is [`Self::assess`]'s.
    pub fn network_probabilities(&mut self, inputs: &[f32], n: usize) -> Result<Vec<f32>> {
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
