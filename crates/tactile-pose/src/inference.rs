//! A trained pose network at work: frames to grey pin images to target
//! values, on any runtime, in batches. `tactile predict` and the benches
//! go through [`PoseEstimator`].

use std::path::Path;

use rayon::prelude::*;
use tactile_core::dataset::Dataset;
use tactile_core::{Network, Runtime};
use tactile_estimate::regressor::decode;
use tactile_preprocess::PinImage;

use crate::Result;
use crate::artifact::PoseArtifact;
use crate::training::PREDICT_BATCH;

/// A loaded pose network with its preprocessing.
pub struct PoseEstimator {
    /// Architecture, preprocessing, targets.
    pub artifact: PoseArtifact,
    net: Box<dyn Network>,
}

/// Estimates for a dataset.
#[derive(Debug, Clone)]
pub struct PoseEstimates {
    /// Each frame's `file` label.
    pub files: Vec<String>,
    /// Target names, in column order.
    pub names: Vec<String>,
    /// Per frame, one value per target in the labels' units.
    pub values: Vec<Vec<f64>>,
    /// Preprocessing and network time per frame, ms.
    pub ms_per_frame: f64,
}

impl PoseEstimator {
    /// Load the network in `dir` onto `runtime` (`threads` intra-op
    /// threads for onnxruntime; 0 = its default).
    pub fn load(dir: impl AsRef<Path>, runtime: Runtime, threads: usize) -> Result<Self> {
        let (artifact, net) =
            tactile_onnx::load_network::<PoseArtifact>(dir.as_ref(), runtime, threads)?;
        Ok(Self { artifact, net })
    }

    /// Where it runs.
    pub fn runtime(&self) -> Runtime {
        self.net.runtime()
    }

    /// Target values of grey pin images, one row per image.
    pub fn predict(&mut self, pins: &[PinImage]) -> Result<Vec<Vec<f64>>> {
        let side = self.artifact.model.input_px;
        if let Some(bad) = pins.iter().find(|p| p.side != side) {
            return Err(tactile_core::Error::shape("pin image", side, bad.side).into());
        }
        let k = self.artifact.model.outputs;
        let mut out = Vec::with_capacity(pins.len());
        for chunk in pins.chunks(PREDICT_BATCH) {
            let x: Vec<f32> = chunk
                .iter()
                .flat_map(|p| p.pixels.iter().copied())
                .collect();
            let y = self.net.run([chunk.len(), 1, side, side], x)?;
            out.extend(
                y.chunks(k)
                    .map(|r| decode(&self.artifact.targets, &self.artifact.outputs, r)),
            );
        }
        Ok(out)
    }

    /// Every frame of a TacTip dataset.
    pub fn predict_dataset(&mut self, ds: &Dataset) -> Result<PoseEstimates> {
        let t0 = std::time::Instant::now();
        let cfg = self.artifact.preprocess.clone();
        let pins = tactile_cae::data::PinSet::from_dataset(ds, &cfg)?;
        let values = self.predict(&pins.images)?;
        Ok(PoseEstimates {
            files: pins.files,
            names: self
                .artifact
                .targets
                .iter()
                .map(|t| t.name.clone())
                .collect(),
            values,
            ms_per_frame: 1e3 * t0.elapsed().as_secs_f64() / ds.len().max(1) as f64,
        })
    }

    /// Preprocess raw frames in parallel (the same chain as training).
    pub fn preprocess(
        &self,
        frames: &[tactile_core::image_io::GreyImage],
    ) -> Result<Vec<PinImage>> {
        let cfg = &self.artifact.preprocess;
        frames
            .par_iter()
            .map(|f| Ok(tactile_preprocess::preprocess(f, cfg)?))
            .collect()
    }
}
