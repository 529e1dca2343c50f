//! Calibrating a trained model on frames it was not trained on; the kind
//! of its folder says how (`tactile train calibrate`,
//! `tactile.train.calibrate`).

use std::path::Path;

use tactile_burn::Artifact;
use tactile_detect::{DetectorArtifact, DetectorEnsembleArtifact};
use tactile_pose::{PoseArtifact, PoseEnsemble};

use crate::Result;

/// Calibrate a trained model on frames it was not trained on, the kind of
/// its folder saying how: a detector's probabilities (one logit scale,
/// decisions unchanged) on `data`; a pose network's deviations (one factor
/// per target) on `data`'s rows of `split` (every row without one), or,
/// with `from`, the factors of that validated run. Returns one line saying
/// what changed.
pub fn calibrate_model(
    model: &Path,
    data: &[tactile_core::dataset::Dataset],
    split: Option<&str>,
    from: Option<&Path>,
) -> Result<String> {
    // Both kinds of ensemble hold an `ensemble.json`: its members say which.
    let detector = DetectorArtifact::is_in(model) || DetectorEnsembleArtifact::read(model).is_ok();
    let pose = !detector && (PoseArtifact::is_in(model) || PoseEnsemble::is_in(model));
    match (pose, from, data) {
        (true, Some(f), []) => Ok(tactile_pose::calibrate::calibration_from(model, f)?.describe()),
        (true, None, [ds]) => Ok(tactile_pose::calibrate::calibrate_on(model, ds, split)?.describe()),
        (true, _, _) => Err(tactile_core::Error::Config(
            "a pose network is calibrated on one dataset (with --split to take its rows of one split) or taken from a validated run (--calibration-from), one of the two".into(),
        )
        .into()),
        (false, None, [_, ..]) if split.is_none() => {
            let fit = tactile_detect::calibrate::calibrate_on(model, data)?;
            Ok(format!("{}; detector in {}", fit.describe(), model.display()))
        }
        (false, _, _) => Err(tactile_core::Error::Config(
            "a detector is calibrated on whole datasets (--data, no --split or --calibration-from)".into(),
        )
        .into()),
    }
}
