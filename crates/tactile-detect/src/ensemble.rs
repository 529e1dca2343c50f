//! Detectors trained apart, answering as one network: the mean of their
//! logits. Near the label's threshold each detector's errors are partly
//! its own training's; networks that err on different frames (one trained
//! with photometric augmentation, one on more light presses) cancel part
//! of them, at the sum of their costs.
//!
//! An ensemble folder holds `ensemble.json` naming member detector
//! folders inside it ([`Ensemble`]). They read a frame alike (input size,
//! bits, exposure normalisation) and share one threshold; each keeps its
//! own channel statistics, so the network takes the input normalised with
//! the first member's and renormalises it for the others inside its graph.
//! It is one burn module, so every runtime, the ONNX export and the
//! standalone export take it as they take one detector.

use std::path::Path;

use burn::module::{Module, Param};
use burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};
use tactile_burn::Artifact;
use tactile_burn::ensemble::Ensemble;
use tactile_burn::runtime::Forward;
use tactile_onnx::{Exportable, export_batch_dynamic};

use crate::Result;
use crate::artifact::DetectorArtifact;
use crate::model::Detector;

/// Per channel `x * gain + shift`: an input normalised with one member's
/// statistics, normalised with another's.
#[derive(Module, Debug)]
pub struct Renormalise {
    /// `[1, 3, 1, 1]`.
    pub gain: Param<Tensor<4>>,
    /// `[1, 3, 1, 1]`.
    pub shift: Param<Tensor<4>>,
}

/// The networks of an ensemble.
#[derive(Module, Debug)]
pub struct DetectorEnsemble {
    /// The member detectors.
    pub members: Vec<Detector>,
    /// Per member, from the first member's normalisation to its own.
    pub renormalise: Vec<Renormalise>,
}

impl DetectorEnsemble {
    /// The mean of the members' tendon logits.
    ///
    /// # Shapes
    /// - `x`: `[N, 3, H, W]`, normalised with the first member's statistics
    /// - output: `[N, 1]`
    pub fn forward(&self, x: Tensor<4>) -> Tensor<2> {
        let n = self.members.len() as f64;
        let mut sum: Option<Tensor<2>> = None;
        for (m, r) in self.members.iter().zip(&self.renormalise) {
            let z = m.forward(x.clone() * r.gain.val() + r.shift.val());
            sum = Some(match sum {
                Some(s) => s + z,
                None => z,
            });
        }
        match sum {
            Some(s) => s / n,
            None => Tensor::zeros([x.dims()[0], 1], &x.device()),
        }
    }
}

impl Forward for DetectorEnsemble {
    fn forward_data(&self, x: Tensor<4>) -> TensorData {
        self.forward(x).into_data()
    }

    fn for_inference(self) -> Self {
        Self {
            members: self
                .members
                .into_iter()
                .map(Forward::for_inference)
                .collect(),
            renormalise: self.renormalise,
        }
    }
}

/// A detector ensemble on disk: `ensemble.json` and its member folders.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct DetectorEnsembleArtifact {
    /// The member folder names and provenance.
    #[serde(flatten)]
    pub ensemble: Ensemble,
    /// The members' configs, read with `ensemble.json` (not written into it).
    #[serde(skip)]
    pub members: Vec<DetectorArtifact>,
}

/// Members must read a frame alike and share the threshold; their
/// architecture, width and statistics may differ.
pub fn check_alike(
    first: &DetectorArtifact,
    other: &DetectorArtifact,
    dir: &Path,
) -> tactile_core::Result<()> {
    let (a, b) = (&first.model, &other.model);
    let same_input = a.input_size == b.input_size
        && a.bits() == b.bits()
        && a.normalises_exposure() == b.normalises_exposure();
    if !same_input || first.threshold != other.threshold {
        return Err(tactile_core::Error::model(
            dir.join(DetectorArtifact::CONFIG_FILE),
            format!(
                "its input ({}x{}, {} bits, exposure normalised: {}) or threshold ({}) differ from the first member's ({}x{}, {} bits, {}, {})",
                b.input_size[0],
                b.input_size[1],
                b.bits(),
                b.normalises_exposure(),
                other.threshold,
                a.input_size[0],
                a.input_size[1],
                a.bits(),
                a.normalises_exposure(),
                first.threshold
            ),
        ));
    }
    Ok(())
}

/// The config a detector folder is used with: its own, or an ensemble's
/// first member's (input, statistics, threshold, input profile).
pub fn read_config(dir: &Path) -> Result<DetectorArtifact> {
    if DetectorEnsembleArtifact::is_in(dir) {
        Ok(DetectorEnsembleArtifact::read(dir)?.lead()?.clone())
    } else {
        Ok(DetectorArtifact::read(dir)?)
    }
}

/// Whether `dir` holds a detector: one network or an ensemble.
pub fn is_detector(dir: &Path) -> bool {
    DetectorArtifact::is_in(dir) || Ensemble::is_of::<DetectorArtifact>(dir)
}

/// The ONNX graph of the detector in `dir` (one network or an ensemble)
/// with the config it is used with (see [`read_config`]).
pub fn detector_onnx(dir: &Path) -> Result<(DetectorArtifact, Vec<u8>)> {
    let device = tactile_burn::DeviceKind::Flex.device();
    if DetectorEnsembleArtifact::is_in(dir) {
        let l = DetectorEnsembleArtifact::load(dir, &device)?;
        Ok((l.artifact.lead()?.clone(), l.artifact.onnx(&l.model)?))
    } else {
        let l = DetectorArtifact::load(dir, &device)?;
        let bytes = l.artifact.onnx(&l.model)?;
        Ok((l.artifact, bytes))
    }
}

impl DetectorEnsembleArtifact {
    /// The first member's config: the input, statistics, threshold and
    /// input profile the ensemble as a whole is used with.
    pub fn lead(&self) -> Result<&DetectorArtifact> {
        self.members.first().ok_or_else(|| {
            tactile_core::Error::Invalid("a detector ensemble without members".into()).into()
        })
    }

    /// Copy the detector folders `members` into a new ensemble folder `out`
    /// (staged; an existing `out` is left alone). A calibration folded into
    /// a member (alone, or as part of an ensemble it is taken from) is
    /// unfolded in its copy, so the ensemble averages the logits as the
    /// members were trained and is calibrated again as a whole.
    pub fn assemble(members: &[std::path::PathBuf], out: &Path) -> Result<Ensemble> {
        Ok(Ensemble::assemble::<DetectorArtifact>(
            members,
            out,
            check_alike,
            |_| Ok(serde_json::json!({})),
            crate::calibrate::unfold_calibration,
        )?)
    }

    fn renormalise(&self, device: &Device) -> Vec<Renormalise> {
        let Some(lead) = self.members.first().map(|m| &m.stats) else {
            return Vec::new();
        };
        let t = |v: Vec<f32>| {
            Param::from_tensor(Tensor::from_data(TensorData::new(v, [1, 3, 1, 1]), device))
        };
        self.members
            .iter()
            .map(|m| {
                // x0 = (v - m0) / s0 and xk = (v - mk) / sk, so
                // xk = x0 * s0 / sk + (m0 - mk) / sk.
                let s = &m.stats;
                let gain = (0..3).map(|c| lead.std[c] / s.std[c]).collect();
                let shift = (0..3)
                    .map(|c| (lead.mean[c] - s.mean[c]) / s.std[c])
                    .collect();
                Renormalise {
                    gain: t(gain),
                    shift: t(shift),
                }
            })
            .collect()
    }
}

impl Artifact for DetectorEnsembleArtifact {
    type Model = DetectorEnsemble;
    const KIND: &'static str = "detector ensemble";
    const CONFIG_FILE: &'static str = Ensemble::FILE;
    /// Each member keeps its own weights file.
    const WEIGHTS_FILE: &'static str = DetectorArtifact::WEIGHTS_FILE;

    fn init(&self, device: &Device) -> tactile_core::Result<DetectorEnsemble> {
        Ok(DetectorEnsemble {
            members: Ensemble::init_members(&self.members, device, Self::KIND)?,
            renormalise: self.renormalise(device),
        })
    }

    /// `ensemble.json` (checked by [`Ensemble::read`]) and every member's
    /// config, which must agree with the first's.
    fn read_unfinished(dir: &Path) -> tactile_core::Result<Self> {
        let (ensemble, members) = Ensemble::read_with_configs::<DetectorArtifact>(dir, Self::KIND)?;
        for (d, m) in ensemble.member_dirs(dir).iter().zip(&members).skip(1) {
            check_alike(&members[0], m, d)?;
        }
        Ok(Self { ensemble, members })
    }

    fn load_unfinished(
        dir: &Path,
        device: &Device,
    ) -> tactile_core::Result<tactile_burn::Loaded<Self>> {
        let artifact = Self::read_unfinished(dir)?;
        let members = artifact
            .ensemble
            .load_members::<DetectorArtifact>(dir, device)?;
        let model = DetectorEnsemble {
            members,
            renormalise: artifact.renormalise(device),
        };
        Ok(tactile_burn::Loaded {
            artifact,
            model,
            dir: dir.to_path_buf(),
            device: device.clone(),
        })
    }

    /// Every member into its folder (weights, then config), then
    /// `ensemble.json`, each atomically.
    fn save(&self, model: &DetectorEnsemble, dir: &Path) -> tactile_core::Result<()> {
        self.ensemble
            .save_members(&self.members, &model.members, dir)
    }
}

impl Exportable for DetectorEnsembleArtifact {
    /// `[N, 3, H, W]` frames normalised with the first member's statistics
    /// -> `[N, 1]` mean logits.
    fn onnx(&self, model: &DetectorEnsemble) -> tactile_onnx::Result<Vec<u8>> {
        let [w, h] = self
            .lead()
            .map_err(|e| tactile_onnx::Error::Export(e.to_string()))?
            .model
            .input_size;
        export_batch_dynamic(model, [1, 3, h, w], |m: &DetectorEnsemble, x| m.forward(x))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::TendonDetector;
    use tactile_burn::Runtime;

    fn root() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
    }

    fn logits(m: &Detector, x: Vec<f32>, [w, h]: [usize; 2], device: &Device) -> Vec<f32> {
        let x = Tensor::<4>::from_data(TensorData::new(x, [1, 3, h, w]), device);
        m.forward(x).into_data().try_to_vec::<f32>().unwrap()
    }

    #[test]
    fn an_ensemble_gives_its_members_mean_logit_and_reads_nothing_outside_its_folder() {
        let shipped = root().join("models/detector");
        let shipped = match DetectorEnsembleArtifact::is_in(&shipped) {
            true => shipped.join("member-0"),
            false => shipped,
        };
        let tmp = tempfile::tempdir().unwrap();
        let device = Device::flex();
        let lead = read_config(&shipped).unwrap();
        // A second member: fresh weights and other channel statistics,
        // so the renormalisation inside the graph is exercised.
        let mut art = lead.clone();
        art.stats.mean = vec![0.40, 0.55, 0.62];
        art.stats.std = vec![0.18, 0.31, 0.24];
        // Fresh weights were never calibrated.
        if let serde_json::Value::Object(notes) = &mut art.notes {
            notes.remove("calibration");
        }
        let other = tmp.path().join("other");
        art.save(&art.model.init(&device), &other).unwrap();
        let ens = tmp.path().join("ensemble");
        DetectorEnsembleArtifact::assemble(&[shipped.clone(), other.clone()], &ens).unwrap();

        let load = |d: &Path| DetectorArtifact::load(d, &device).unwrap().model;
        // The shipped member carries its ensemble's calibration; the
        // ensemble averages the logits as trained, so compare with a copy
        // whose calibration is unfolded, which is the calibrated logit
        // mapped back through the noted scale.
        let scale = lead.notes["calibration"]["scale"].as_f64();
        let unfolded = tmp.path().join("unfolded");
        std::fs::create_dir_all(&unfolded).unwrap();
        for f in [
            DetectorArtifact::CONFIG_FILE,
            DetectorArtifact::WEIGHTS_FILE,
        ] {
            std::fs::copy(shipped.join(f), unfolded.join(f)).unwrap();
        }
        crate::calibrate::unfold_calibration(&unfolded).unwrap();
        assert!(
            read_config(&unfolded)
                .unwrap()
                .notes
                .get("calibration")
                .is_none()
        );
        let (a, b) = (load(&unfolded), load(&other));
        let calibrated = load(&shipped);
        let e = DetectorEnsembleArtifact::load(&ens, &device).unwrap();
        assert_eq!(e.model.members.len(), 2);
        let size = lead.model.input_size;
        for i in 0..4 {
            let frame = tactile_core::image_io::load_rgb(
                root().join(format!("samples/palpation/{i:06}.png")),
            )
            .unwrap();
            let img = lead.model.frame_image(&frame).unwrap();
            let xa = lead.model.network_input(img.clone(), &lead.stats).unwrap();
            let za = logits(&a, xa.clone(), size, &device);
            if let Some(scale) = scale {
                // Threshold 0.5: the calibration's fixed point is logit 0.
                let zc = logits(&calibrated, xa, size, &device)[0] as f64;
                assert!(
                    (za[0] as f64 - zc / scale).abs() < 1e-3 * (1.0 + za[0].abs() as f64),
                    "unfolded {} vs calibrated {zc} / {scale}",
                    za[0]
                );
            }
            let zb = logits(
                &b,
                art.model.network_input(img.clone(), &art.stats).unwrap(),
                size,
                &device,
            );
            let x = lead.model.network_input(img, &lead.stats).unwrap();
            let ze = e.model.forward(Tensor::<4>::from_data(
                TensorData::new(x, [1, 3, size[1], size[0]]),
                &device,
            ));
            let ze = ze.into_data().try_to_vec::<f32>().unwrap();
            let mean = (za[0] + zb[0]) / 2.0;
            assert!(
                (ze[0] - mean).abs() < 1e-3 * (1.0 + mean.abs()),
                "{} vs {mean}",
                ze[0]
            );
        }
        // The runtime path takes the folder as one detector, with the
        // first member's threshold and input profile.
        let det = TendonDetector::load(&ens, Runtime::BurnFlex, 0).unwrap();
        assert_eq!(det.artifact.threshold, lead.threshold);
        assert_eq!(
            det.artifact.input_profile.is_some(),
            lead.input_profile.is_some()
        );
        // A member named by a path is refused, naming the file.
        std::fs::write(ens.join("ensemble.json"), r#"{"members": ["../other"]}"#).unwrap();
        let err = TendonDetector::load(&ens, Runtime::BurnFlex, 0)
            .err()
            .unwrap()
            .to_string();
        assert!(
            err.contains("ensemble.json") && err.contains("plain folder name"),
            "{err}"
        );
        // Members that read frames differently are refused, naming the one.
        let mut small = lead.clone();
        small.model.input_size = [64, 48];
        let odd = tmp.path().join("odd");
        small.save(&small.model.init(&device), &odd).unwrap();
        let err = DetectorEnsembleArtifact::assemble(&[shipped, odd], &tmp.path().join("e2"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("odd") && err.contains("64x48"), "{err}");
        assert!(!tmp.path().join("e2").exists());
    }
}
