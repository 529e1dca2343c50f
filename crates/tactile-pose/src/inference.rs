//! A trained pose network at work: frames to grey pin images to target
//! values, on any runtime, in batches. `tactile predict` and the benches
//! go through [`PoseEstimator`].

use std::path::Path;

use rayon::prelude::*;
use tactile_burn::{Network, Runtime};
use tactile_core::dataset::Dataset;
use tactile_estimate::regressor::{Scaler, decode_columns};
use tactile_preprocess::PinImage;

use crate::Result;
use crate::artifact::{PoseArtifact, PoseEnsemble, check_alike};
use crate::training::PREDICT_BATCH;

/// A loaded pose network with its preprocessing, or an ensemble of them
/// ([`PoseEnsemble`]) whose estimates are averaged.
pub struct PoseEstimator {
    /// Architecture, preprocessing, targets (an ensemble's first member's).
    pub artifact: PoseArtifact,
    /// Each member's target scaling, network and uncertainty calibration.
    members: Vec<Member>,
}

/// One network of an estimator.
struct Member {
    /// Its target scaling.
    outputs: Scaler,
    /// Its network.
    net: Box<dyn Network>,
    /// Its calibration of the standard deviations, one factor per target
    /// (each member's own: members are calibrated one by one).
    std_scale: Option<Vec<f64>>,
}

/// Per frame the targets' values, and with uncertainty their standard
/// deviations (labels' units).
pub type ValuesWithStd = (Vec<Vec<f64>>, Option<Vec<Vec<f64>>>);

/// Estimates for a dataset.
#[derive(Debug, Clone)]
pub struct PoseEstimates {
    /// Each frame's `file` label.
    pub files: Vec<String>,
    /// Target names, in column order.
    pub names: Vec<String>,
    /// Per frame, one value per target in the labels' units.
    pub values: Vec<Vec<f64>>,
    /// Per frame, each value's calibrated standard deviation, labels' units,
    /// when the network gives an uncertainty.
    pub std: Option<Vec<Vec<f64>>>,
    /// Preprocessing and network time per frame, ms.
    pub ms_per_frame: f64,
}

impl PoseEstimator {
    /// Load the network in `dir` onto `runtime` (`threads` intra-op
    /// threads for onnxruntime; 0 = its default).
    /// An ensemble folder loads every member.
    pub fn load(dir: impl AsRef<Path>, runtime: Runtime, threads: usize) -> Result<Self> {
        let dir = dir.as_ref();
        let dirs = if PoseEnsemble::is_in(dir) {
            PoseEnsemble::read(dir)?.member_dirs(dir)
        } else {
            vec![dir.to_path_buf()]
        };
        let mut first: Option<PoseArtifact> = None;
        let mut members = Vec::with_capacity(dirs.len());
        for d in &dirs {
            let (artifact, net) = tactile_onnx::load_network::<PoseArtifact>(d, runtime, threads)?;
            match &first {
                Some(f) => check_alike(f, &artifact, d)?,
                None => first = Some(artifact.clone()),
            }
            members.push(Member {
                std_scale: artifact.std_scale.clone(),
                outputs: artifact.outputs,
                net,
            });
        }
        let artifact = first.ok_or_else(|| tactile_core::Error::not_found(dir, "pose network"))?;
        Ok(Self { artifact, members })
    }

    /// Where it runs.
    pub fn runtime(&self) -> Runtime {
        self.members
            .first()
            .map_or(Runtime::BurnFlex, |m| m.net.runtime())
    }

    /// Networks whose estimates are averaged (1 unless an ensemble).
    pub fn members(&self) -> usize {
        self.members.len()
    }

    /// Target values of grey pin images, one row per image.
    pub fn predict(&mut self, pins: &[PinImage]) -> Result<Vec<Vec<f64>>> {
        Ok(self.predict_with_std(pins)?.0)
    }

    /// Whether the network gives a standard deviation per value.
    pub fn has_uncertainty(&self) -> bool {
        self.artifact.model.has_uncertainty()
    }

    /// Target values of grey pin images, one row per image, and with
    /// uncertainty each value's standard deviation (labels' units). An
    /// ensemble's deviation adds its members' spread to their mean
    /// variance.
    pub fn predict_with_std(&mut self, pins: &[PinImage]) -> Result<ValuesWithStd> {
        let side = self.artifact.model.input_px;
        if let Some(bad) = pins.iter().find(|p| p.side != side) {
            return Err(tactile_core::Error::shape("pin image", side, bad.side).into());
        }
        if self.has_uncertainty() {
            return self.predict_uncertain(pins);
        }
        let k = self.artifact.model.outputs;
        let mut out = Vec::with_capacity(pins.len());
        for chunk in pins.chunks(PREDICT_BATCH) {
            let x: Vec<f32> = chunk
                .iter()
                .flat_map(|p| p.pixels.iter().copied())
                .collect();
            // Each member's columns in the targets' encoded units, averaged,
            // then decoded once (an angle's cos/sin pair averages well where
            // the angles themselves would not across the wrap). One member
            // gives exactly its own decoded row.
            let mut sum = vec![vec![0f64; k]; chunk.len()];
            let mut x = Some(x);
            let last = self.members.len().saturating_sub(1);
            for (m, member) in self.members.iter_mut().enumerate() {
                let input = if m == last { x.take() } else { x.clone() };
                let y = member
                    .net
                    .run([chunk.len(), 1, side, side], input.unwrap_or_default())?;
                for (acc, row) in sum.iter_mut().zip(y.chunks(k)) {
                    acc.iter_mut()
                        .zip(member.outputs.unscale(row))
                        .for_each(|(a, v)| *a += v);
                }
            }
            let n = self.members.len() as f64;
            out.extend(sum.iter_mut().map(|cols| {
                cols.iter_mut().for_each(|v| *v /= n);
                decode_columns(&self.artifact.targets, cols)
            }));
        }
        Ok((out, None))
    }

    /// [`Self::predict_with_std`] of networks with uncertainty (linear
    /// targets only, so a column is a target).
    fn predict_uncertain(&mut self, pins: &[PinImage]) -> Result<ValuesWithStd> {
        let side = self.artifact.model.input_px;
        let k = self.artifact.model.outputs;
        let n = self.members.len().max(1) as f64;
        let (mut values, mut std) = (Vec::new(), Vec::new());
        for chunk in pins.chunks(PREDICT_BATCH) {
            let x: Vec<f32> = chunk
                .iter()
                .flat_map(|p| p.pixels.iter().copied())
                .collect();
            // Per frame and target: sum of means, of squared means, of variances.
            let mut acc = vec![vec![[0f64; 3]; k]; chunk.len()];
            for member in self.members.iter_mut() {
                let y = member.net.run([chunk.len(), 1, side, side], x.clone())?;
                let (scaler, factor) = (&member.outputs, member.std_scale.as_deref());
                for (a, row) in acc.iter_mut().zip(y.chunks(2 * k)) {
                    let mean = scaler.unscale(&row[..k]);
                    for j in 0..k {
                        let sd = crate::uncertainty::scale(row[k + j])
                            * scaler.std[j]
                            * factor.map_or(1.0, |f| f[j]);
                        a[j][0] += mean[j];
                        a[j][1] += mean[j] * mean[j];
                        a[j][2] += sd * sd;
                    }
                }
            }
            for a in acc {
                values.push(a.iter().map(|s| s[0] / n).collect());
                std.push(
                    a.iter()
                        .map(|s| {
                            let m = s[0] / n;
                            (s[2] / n + (s[1] / n - m * m).max(0.0)).sqrt()
                        })
                        .collect(),
                );
            }
        }
        Ok((values, Some(std)))
    }

    /// Every frame of a TacTip dataset.
    pub fn predict_dataset(&mut self, ds: &Dataset) -> Result<PoseEstimates> {
        let t0 = std::time::Instant::now();
        let cfg = self.artifact.preprocess.clone();
        let pins = tactile_cae::data::PinSet::from_dataset(ds, &cfg)?;
        let (values, std) = self.predict_with_std(&pins.images)?;
        Ok(PoseEstimates {
            files: pins.files,
            names: self
                .artifact
                .targets
                .iter()
                .map(|t| t.name.clone())
                .collect(),
            values,
            std,
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use tactile_burn::Artifact;

    #[test]
    fn an_ensemble_averages_its_members_and_reads_nothing_outside_its_folder() {
        let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/pose-edge");
        let tmp = tempfile::tempdir().unwrap();
        // A second member: the same settings, fresh weights.
        let art = PoseArtifact::read(&shipped).unwrap();
        let other = tmp.path().join("other");
        let device = burn::tensor::Device::flex();
        art.save(&art.init(&device).unwrap(), &other).unwrap();
        let ens = tmp.path().join("ensemble");
        PoseEnsemble::assemble(&[shipped.clone(), other.clone()], &ens).unwrap();
        let s = art.model.input_px;
        let pins: Vec<PinImage> = (0..3)
            .map(|k| PinImage {
                side: s,
                pixels: (0..s * s)
                    .map(|i| ((i * (k + 3)) % 17) as f32 / 17.0)
                    .collect(),
            })
            .collect();
        let run = |d: &Path| {
            let mut p = PoseEstimator::load(d, Runtime::BurnFlex, 0).unwrap();
            (p.members(), p.predict(&pins).unwrap())
        };
        let ((n1, a), (_, b), (n, e)) = (run(&shipped), run(&other), run(&ens));
        assert_eq!((n1, n), (1, 2));
        // x_mm and depth_mm are linear: the ensemble's is the members' mean.
        for i in 0..pins.len() {
            for j in [0, 2] {
                let mean = (a[i][j] + b[i][j]) / 2.0;
                assert!((e[i][j] - mean).abs() < 1e-4, "{} vs {mean}", e[i][j]);
            }
        }
        // A member named by a path is refused, naming the file.
        std::fs::write(ens.join("ensemble.json"), r#"{"members": ["../other"]}"#).unwrap();
        let err = PoseEstimator::load(&ens, Runtime::BurnFlex, 0)
            .err()
            .unwrap()
            .to_string();
        assert!(
            err.contains("ensemble.json") && err.contains("plain folder name"),
            "{err}"
        );
        std::fs::write(ens.join("ensemble.json"), r#"{"members": []}"#).unwrap();
        assert!(PoseEstimator::load(&ens, Runtime::BurnFlex, 0).is_err());
        // An existing folder is left alone.
        assert!(PoseEnsemble::assemble(&[shipped], &ens).is_err());
        assert!(ens.join("member-1").is_dir());
    }
}
