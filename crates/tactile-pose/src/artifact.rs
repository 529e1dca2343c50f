//! A trained pose network on disk: `pose.json` (architecture, the
//! preprocessing that makes its pin images, its targets and their
//! standardisation, provenance) beside `pose.bpk`.

use std::path::Path;

use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_burn::Artifact;
use tactile_burn::ensemble::Ensemble;
use tactile_estimate::Target;
use tactile_estimate::regressor::Scaler;
use tactile_onnx::{Exportable, export_batch_dynamic};
use tactile_preprocess::PreprocessConfig;
use tactile_preprocess::profile::InputProfile;

use crate::model::{PoseNet, PoseNetConfig};

/// Everything needed to rebuild and use a saved pose network.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PoseArtifact {
    /// The architecture.
    pub model: PoseNetConfig,
    /// How a frame becomes the grey pin image it reads.
    pub preprocess: PreprocessConfig,
    /// What it predicts, in column order.
    pub targets: Vec<Target>,
    /// Standardisation of the encoded target columns.
    pub outputs: Scaler,
    /// With uncertainty: per target, the factor that turns the network's
    /// Laplace scale into a standard deviation whose ±1 interval holds
    /// 68.3 % of the calibration frames' errors (see
    /// [`crate::uncertainty`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std_scale: Option<Vec<f64>>,
    /// Its training frames' pin profile ([`InputProfile::fit_pins`]):
    /// frames far from it (another sensor, another scale) are named in a
    /// warning by `predict`. Absent in models trained before it (`tactile
    /// train profile` adds it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_profile: Option<InputProfile>,
    /// Free-form provenance: how it was trained, on what, with which result.
    #[serde(default)]
    pub notes: serde_json::Value,
}

impl PoseArtifact {
    /// Output columns the targets take.
    pub fn columns(&self) -> usize {
        self.targets.iter().map(Target::width).sum()
    }
}

impl Artifact for PoseArtifact {
    type Model = PoseNet;
    const KIND: &'static str = "pose network";
    const CONFIG_FILE: &'static str = "pose.json";
    const WEIGHTS_FILE: &'static str = "pose.bpk";

    fn init(&self, device: &Device) -> tactile_core::Result<PoseNet> {
        self.model.check()?;
        Ok(self.model.init(device))
    }

    fn check(&self, file: &Path) -> tactile_core::Result<()> {
        use tactile_core::error::in_config;
        in_config(file, self.model.check())?;
        if let Some(p) = &self.input_profile {
            p.validate_reading(true)
                .map_err(|m| tactile_core::Error::Config(format!("{}: {m}", file.display())))?;
        }
        in_config(file, self.preprocess.check())?;
        let bad = |m: String| Err(tactile_core::Error::model(file, m));
        if self.preprocess.output_px != self.model.input_px {
            return bad(format!(
                "preprocessing makes {0}x{0} pin images, the network takes {1}x{1}",
                self.preprocess.output_px, self.model.input_px
            ));
        }
        if self.targets.is_empty() || self.columns() != self.model.outputs {
            return bad(format!(
                "{} targets take {} columns, the network gives {}",
                self.targets.len(),
                self.columns(),
                self.model.outputs
            ));
        }
        if self.model.has_uncertainty() {
            crate::uncertainty::check_std_scale(&self.targets, self.std_scale.as_deref())
                .map_err(|e| tactile_core::Error::model(file, e))?;
        }
        in_config(
            file,
            tactile_estimate::mlp::check_scaler(
                "target scaling",
                &self.outputs.mean,
                &self.outputs.std,
                self.model.outputs,
            ),
        )
    }
}

impl Exportable for PoseArtifact {
    /// `[N, 1, S, S]` grey pin images -> `[N, K]` standardised columns
    /// (`[N, 2K]` with uncertainty: the columns, then their log Laplace
    /// scales; `pose.json`'s `outputs` and `std_scale` turn both into the
    /// labels' units).
    fn onnx(&self, model: &PoseNet) -> tactile_onnx::Result<Vec<u8>> {
        let s = self.model.input_px;
        export_batch_dynamic(model, [1, 1, s, s], |m: &PoseNet, x| m.forward(x))
    }
}

/// A folder of pose networks trained alike but for their seed, whose
/// estimates are averaged (see [`Ensemble`]; `tactile bench pose` reports
/// the gain beside the summed latency).
pub struct PoseEnsemble;

impl PoseEnsemble {
    /// Whether `dir` holds an ensemble of pose networks.
    pub fn is_in(dir: &Path) -> bool {
        Ensemble::is_of::<PoseArtifact>(dir)
    }

    /// Read and check `dir/ensemble.json` (see [`Ensemble::read`]).
    pub fn read(dir: &Path) -> tactile_core::Result<Ensemble> {
        Ensemble::read::<PoseArtifact>(dir)
    }

    /// Copy the pose-network folders `members` into a new ensemble folder
    /// `out` (see [`Ensemble::assemble`]). Their targets must agree (their
    /// preprocessing need not: a multi-scale ensemble); the ensemble's `excluded_test` is theirs, which they
    /// must share.
    pub fn assemble(members: &[std::path::PathBuf], out: &Path) -> tactile_core::Result<Ensemble> {
        let notes = |arts: &[PoseArtifact]| {
            let tests: Vec<_> = arts.iter().map(|a| a.notes.get("excluded_test")).collect();
            let mut notes = serde_json::json!({});
            match tests.first() {
                Some(first) if tests.iter().any(|t| t != first) => {
                    return Err(tactile_core::Error::Invalid(
                        "the members left out different test frames; an ensemble's score would mix them"
                            .into(),
                    ));
                }
                Some(Some(t)) => notes["excluded_test"] = (*t).clone(),
                _ => {}
            }
            // A member that trained on every split makes the ensemble one.
            if arts
                .iter()
                .any(|a| tactile_core::dataset::Provenance::read(&a.notes).every_split)
            {
                notes["every_split"] = true.into();
            }
            Ok(notes)
        };
        // A pose network's calibration scales its deviations, which stay
        // the member's own in an ensemble: nothing to rewrite.
        Ensemble::assemble(members, out, check_alike, notes, |_| Ok(()))
    }
}

/// Members must give the same columns. They may read the frame each its
/// own way (a multi-scale ensemble: 128 px and 64 px pin images, say).
pub(crate) fn check_alike(
    first: &PoseArtifact,
    other: &PoseArtifact,
    dir: &Path,
) -> tactile_core::Result<()> {
    if first.targets != other.targets
        || first.model.has_uncertainty() != other.model.has_uncertainty()
    {
        return Err(tactile_core::Error::model(
            dir.join(PoseArtifact::CONFIG_FILE),
            "its targets or uncertainty differ from the first member's",
        ));
    }
    Ok(())
}
