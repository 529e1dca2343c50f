//! A trained pose network at work: frames to grey pin images to target
//! values, on any runtime, in batches. `tactile predict` and the benches
//! go through [`PoseEstimator`].

use std::path::Path;

use tactile_burn::{Network, Runtime};
use tactile_core::dataset::Dataset;
use tactile_core::image_io::GreyImage;
use tactile_estimate::regressor::{Scaler, decode_columns};
use tactile_preprocess::{PinImage, PreprocessConfig};

use crate::Result;
use crate::artifact::{PoseArtifact, PoseEnsemble, check_alike};
use crate::training::PREDICT_BATCH;
use crate::uncertainty::{Mixture, deviation};
use tactile_cae::data::{DATASET_CHUNK, Undecodable};

/// A loaded pose network with its preprocessing, or an ensemble of them
/// ([`PoseEnsemble`]) whose estimates are averaged. The members of a
/// multi-scale ensemble read the frame each through its own preprocessing
/// (a 128 px and a 64 px pin image, say): each distinct one is a *scale*.
pub struct PoseEstimator {
    /// Architecture, preprocessing, targets (an ensemble's first member's).
    pub artifact: PoseArtifact,
    /// Each member's target scaling, network and uncertainty calibration.
    members: Vec<Member>,
    /// The members' distinct preprocessings, the first member's first.
    scales: Vec<PreprocessConfig>,
    /// An ensemble's own calibration: one factor per target on its
    /// combined deviation (see [`tactile_burn::ensemble::Ensemble::std_scale`]).
    std_factor: Option<Vec<f64>>,
    /// The folder it was loaded from (an ensemble's own).
    dir: std::path::PathBuf,
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
    /// Index of its preprocessing in [`PoseEstimator::scales`].
    scale: usize,
    /// Side of its pin image.
    side: usize,
}

pub use tactile_estimate::uncertainty::ValuesWithStd;

/// Estimates for a dataset.
#[derive(Debug, Clone)]
pub struct PoseEstimates {
    /// Each frame's `file` label.
    pub files: Vec<String>,
    /// Each of those frames' row in the dataset
    /// ([`tactile_cae::data::PinSet::rows`]), for scoring its estimates
    /// against its labels.
    pub rows: Vec<usize>,
    /// Target names, in column order.
    pub names: Vec<String>,
    /// Per frame, one value per target in the labels' units.
    pub values: Vec<Vec<f64>>,
    /// Per frame, each value's calibrated standard deviation, labels' units,
    /// when the network gives an uncertainty.
    pub std: Option<Vec<Vec<f64>>>,
    /// Preprocessing and network time per frame, ms.
    pub ms_per_frame: f64,
    /// The `file` labels of frames one grey level throughout their crop
    /// (no pins to read: their estimates mean nothing).
    pub flat: Vec<String>,
    /// The frames unlike its training frames
    /// ([`tactile_cae::data::PinSet::foreign`]; none without a pin profile).
    pub foreign: Vec<tactile_cae::data::ForeignFrame>,
    /// The warning naming the first frame that could not be decoded past
    /// its header and counting them, when any was left out
    /// ([`tactile_cae::data::PinSet::for_each_chunk_with`]).
    pub undecodable: Option<String>,
}

impl PoseEstimator {
    /// Load the network in `dir` onto `runtime` (`threads` intra-op
    /// threads for onnxruntime; 0 = its default).
    /// An ensemble folder loads every member.
    pub fn load(dir: impl AsRef<Path>, runtime: Runtime, threads: usize) -> Result<Self> {
        let dir = dir.as_ref();
        let ensemble = if PoseEnsemble::is_in(dir) {
            Some(PoseEnsemble::read(dir)?)
        } else {
            None
        };
        let dirs = ensemble
            .as_ref()
            .map_or_else(|| vec![dir.to_path_buf()], |e| e.member_dirs(dir));
        let mut first: Option<PoseArtifact> = None;
        let mut members = Vec::with_capacity(dirs.len());
        let mut scales: Vec<PreprocessConfig> = Vec::new();
        for d in &dirs {
            let (artifact, net) = tactile_onnx::load_network::<PoseArtifact>(d, runtime, threads)?;
            match &first {
                Some(f) => check_alike(f, &artifact, d)?,
                None => first = Some(artifact.clone()),
            }
            let scale = match scales
                .iter()
                .position(|s| same_preprocessing(s, &artifact.preprocess))
            {
                Some(k) => k,
                None => {
                    scales.push(artifact.preprocess.clone());
                    scales.len() - 1
                }
            };
            members.push(Member {
                std_scale: artifact.std_scale.clone(),
                outputs: artifact.outputs,
                side: artifact.model.input_px,
                net,
                scale,
            });
        }
        let artifact = first.ok_or_else(|| tactile_core::Error::not_found(dir, "pose network"))?;
        let std_factor = match &ensemble {
            Some(e) => e.std_scale(dir, artifact.targets.len())?,
            None => None,
        };
        Ok(Self {
            artifact,
            members,
            scales,
            std_factor,
            dir: dir.to_path_buf(),
        })
    }

    /// When its notes say it (an ensemble's every member) trained on every
    /// frame of `ds`, the words saying so: scores on `ds` are on frames it
    /// fitted ([`tactile_burn::artifact::scored_on_fitted`]).
    pub fn scored_on_fitted(&self, ds: &Dataset) -> Option<String> {
        tactile_burn::artifact::scored_on_fitted::<PoseArtifact>(&self.dir, ds)
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

    /// The distinct preprocessings its members read frames with (one
    /// unless a multi-scale ensemble), the first member's first: what
    /// [`Self::predict_scales_with_std`] takes pin images of.
    pub fn scales(&self) -> &[PreprocessConfig] {
        &self.scales
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
    /// variance. A multi-scale ensemble needs a pin image per scale:
    /// [`Self::predict_scales_with_std`] or [`Self::predict_frames_with_std`].
    pub fn predict_with_std(&mut self, pins: &[PinImage]) -> Result<ValuesWithStd> {
        self.predict_scales_with_std(&[pins])
    }

    /// [`Self::predict_with_std`] of raw frames, each preprocessed once
    /// per scale (in parallel, the chain training used).
    pub fn predict_frames_with_std(&mut self, frames: &[GreyImage]) -> Result<ValuesWithStd> {
        let pins = self.preprocess(frames)?;
        let views: Vec<&[PinImage]> = pins.iter().map(Vec::as_slice).collect();
        self.predict_scales_with_std(&views)
    }

    /// [`Self::predict_with_std`] given, per scale of [`Self::scales`], the
    /// same frames' pin images through that scale's preprocessing.
    pub fn predict_scales_with_std(&mut self, pins: &[&[PinImage]]) -> Result<ValuesWithStd> {
        if pins.len() != self.scales.len() {
            let sides: Vec<String> = self
                .scales
                .iter()
                .map(|s| format!("{0}x{0}", s.output_px))
                .collect();
            return Err(tactile_core::Error::Invalid(format!(
                "the model reads each frame as {} pin image(s) ({}), given {}: give it frames",
                self.scales.len(),
                sides.join(", "),
                pins.len()
            ))
            .into());
        }
        let frames = pins.first().map_or(0, |p| p.len());
        if pins.iter().any(|p| p.len() != frames) {
            return Err(tactile_core::Error::Invalid(
                "each scale needs a pin image of every frame".into(),
            )
            .into());
        }
        for m in &self.members {
            if let Some(bad) = pins[m.scale].iter().find(|p| p.side != m.side) {
                return Err(tactile_core::Error::shape("pin image", m.side, bad.side).into());
            }
        }
        if self.has_uncertainty() {
            return self.predict_uncertain(pins, frames);
        }
        let k = self.artifact.model.outputs;
        let mut out = Vec::with_capacity(frames);
        for start in (0..frames).step_by(PREDICT_BATCH) {
            let range = start..(start + PREDICT_BATCH).min(frames);
            // Each member's columns in the targets' encoded units, averaged,
            // then decoded once (an angle's cos/sin pair averages well where
            // the angles themselves would not across the wrap). One member
            // gives exactly its own decoded row.
            let mut sum = vec![vec![0f64; k]; range.len()];
            for member in self.members.iter_mut() {
                let y = member.run(&pins[member.scale][range.clone()])?;
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

    /// [`Self::predict_scales_with_std`] of networks with uncertainty
    /// (linear targets only, so a column is a target).
    fn predict_uncertain(&mut self, pins: &[&[PinImage]], frames: usize) -> Result<ValuesWithStd> {
        let k = self.artifact.model.outputs;
        let (mut values, mut std) = (Vec::new(), Vec::new());
        for start in (0..frames).step_by(PREDICT_BATCH) {
            let range = start..(start + PREDICT_BATCH).min(frames);
            // Per frame and target, the members' estimates.
            let mut acc = vec![vec![Mixture::default(); k]; range.len()];
            for member in self.members.iter_mut() {
                let y = member.run(&pins[member.scale][range.clone()])?;
                let (scaler, factor) = (&member.outputs, member.std_scale.as_deref());
                for (a, row) in acc.iter_mut().zip(y.chunks(2 * k)) {
                    let mean = scaler.unscale(&row[..k]);
                    for j in 0..k {
                        let f = factor.map_or(1.0, |f| f[j]);
                        a[j].add(mean[j], deviation(row[k + j], scaler.std[j], f));
                    }
                }
            }
            let factor = |j: usize| self.std_factor.as_deref().map_or(1.0, |f| f[j]);
            for a in acc {
                values.push(a.iter().map(Mixture::mean).collect());
                std.push(
                    a.iter()
                        .enumerate()
                        .map(|(j, m)| m.std() * factor(j))
                        .collect(),
                );
            }
        }
        Ok((values, Some(std)))
    }

    /// Every frame of a TacTip dataset, a chunk at a time; a frame that
    /// cannot be decoded past its header is left out and named in
    /// [`PoseEstimates::undecodable`], so the others keep their estimates
    /// ([`tactile_cae::data::PinSet::for_each_chunk_with`]); the others'
    /// rows are [`PoseEstimates::rows`].
    pub fn predict_dataset(&mut self, ds: &Dataset) -> Result<PoseEstimates> {
        let t0 = std::time::Instant::now();
        let (mut files, mut values) = (Vec::with_capacity(ds.len()), Vec::with_capacity(ds.len()));
        let mut rows = Vec::with_capacity(ds.len());
        let mut std: Option<Vec<Vec<f64>>> = None;
        let (mut flat, mut foreign) = (Vec::new(), Vec::new());
        let scales = self.scales.clone();
        // The first member's profile, of the first scale's pin images.
        let profile = self.artifact.input_profile.clone();
        let each = |mut sets: Vec<tactile_cae::data::PinSet>| {
            let views: Vec<&[PinImage]> = sets.iter().map(|s| s.images.as_slice()).collect();
            let (v, s) = self.predict_scales_with_std(&views)?;
            values.extend(v);
            if let Some(s) = s {
                std.get_or_insert_with(Vec::new).extend(s);
            }
            let first = sets.swap_remove(0);
            if let Some(p) = &profile {
                foreign.extend(first.foreign(p));
            }
            files.extend(first.files);
            rows.extend(first.rows);
            flat.extend(first.flat);
            Ok::<(), crate::Error>(())
        };
        let undecodable = tactile_cae::data::PinSet::for_each_chunk_with(
            ds,
            &scales,
            DATASET_CHUNK,
            Undecodable::Skip,
            each,
        )?;
        Ok(PoseEstimates {
            files,
            rows,
            names: self
                .artifact
                .targets
                .iter()
                .map(|t| t.name.clone())
                .collect(),
            values,
            std,
            ms_per_frame: 1e3 * t0.elapsed().as_secs_f64() / ds.len().max(1) as f64,
            flat,
            foreign,
            undecodable,
        })
    }

    /// Preprocess raw frames in parallel (the same chain as training), once
    /// per scale of [`Self::scales`].
    pub fn preprocess(&self, frames: &[GreyImage]) -> Result<Vec<Vec<PinImage>>> {
        self.scales
            .iter()
            .map(|cfg| Ok(tactile_preprocess::preprocess_each(frames, cfg)?))
            .collect()
    }
}

impl Member {
    /// Its network's raw output rows for `pins` (one batch).
    fn run(&mut self, pins: &[PinImage]) -> Result<Vec<f32>> {
        let x: Vec<f32> = pins.iter().flat_map(|p| p.pixels.iter().copied()).collect();
        Ok(self.net.run([pins.len(), 1, self.side, self.side], x)?)
    }
}

/// Whether two members read frames alike (their preprocessing, compared
/// as written to `pose.json`).
fn same_preprocessing(a: &PreprocessConfig, b: &PreprocessConfig) -> bool {
    serde_json::to_value(a).ok() == serde_json::to_value(b).ok()
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
        let e = PoseEnsemble::assemble(&[shipped.clone(), other.clone()], &ens)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("already exists and is left alone"), "{e}");
        // One model alone is no average: refused before anything is read.
        let e = PoseEnsemble::assemble(std::slice::from_ref(&shipped), &tmp.path().join("one"))
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("an ensemble averages 2 to 8 models trained apart, got 1"),
            "{e}"
        );
        assert!(!tmp.path().join("one").exists());
        assert!(ens.join("member-1").is_dir());
        // One model given twice, as its folder twice or as a plain copy, is
        // refused naming both, and no folder appears: it would count its
        // error twice and hide the spread. Before, it was averaged.
        let copy = tmp.path().join("copy");
        std::fs::create_dir(&copy).unwrap();
        for f in [PoseArtifact::CONFIG_FILE, PoseArtifact::WEIGHTS_FILE] {
            std::fs::copy(shipped.join(f), copy.join(f)).unwrap();
        }
        for (second, name) in [(&shipped, "twice"), (&copy, "copied")] {
            let out = tmp.path().join(name);
            let err =
                PoseEnsemble::assemble(&[shipped.clone(), other.clone(), second.clone()], &out)
                    .err()
                    .unwrap()
                    .to_string();
            assert!(
                err.contains(&second.display().to_string())
                    && err.contains(&format!("the same model as {}", shipped.display())),
                "{name}: {err}"
            );
            assert!(!out.exists(), "{name}");
        }
    }
}
