//! Calibrating a trained model on frames it was not trained on; the kind
//! of its folder says how (`tactile train calibrate`,
//! `tactile.train.calibrate`).

use std::path::Path;

use tactile_burn::{Artifact, Runtime};
use tactile_cae::data::PinSet;
use tactile_cae::{CaeArtifact, TactipEncoder};
use tactile_core::dataset::Dataset;
use tactile_detect::{DetectorArtifact, DetectorEnsembleArtifact};
use tactile_estimate::RegressorEnsemble;
use tactile_estimate::uncertainty::UncertaintyFit;
use tactile_pose::{PoseArtifact, PoseEnsemble};

use crate::Result;

/// What [`calibrate_model`] did: one line for a terminal, and what the
/// user should know, which the command line notes on standard error as
/// `warning: ...` and Python raises as `UserWarning`s.
#[derive(Debug, Clone)]
pub struct Calibrated {
    /// What changed.
    pub summary: String,
    /// Warnings, such as calibration frames the model trained on.
    pub warnings: Vec<String>,
}

impl Calibrated {
    /// A deviation calibration's line, `folder` saying whose when given,
    /// and its warning when its frames are frames the model trained on.
    fn of(fit: &UncertaintyFit, folder: Option<String>) -> Self {
        let summary = match folder {
            Some(f) => format!("{}; {f}", fit.describe()),
            None => fit.describe(),
        };
        let warnings = fit.fitted_frames.iter().cloned().collect();
        Self { summary, warnings }
    }
}

/// Calibrate a trained model on frames it was not trained on, the kind of
/// its folder saying how: a detector's probabilities (one logit scale,
/// decisions unchanged) on `data`; a pose network's deviations, or those of
/// a regressor (or regressor ensemble) inside an encoder folder (one factor
/// per target), on `data`'s rows of `split` (every row without one), or,
/// with `from`, the factors of that validated run. Returns what changed.
pub fn calibrate_model(
    model: &Path,
    data: &[Dataset],
    split: Option<&str>,
    from: Option<&Path>,
) -> Result<Calibrated> {
    // Its configs are rewritten: never while another run writes them.
    let _lock = tactile_core::io::FolderLock::of_existing(model)?;
    if RegressorEnsemble::is_in(model) {
        return calibrate_regressor(model, data, split, from);
    }
    // Both kinds of ensemble hold an `ensemble.json`: its members say which.
    let detector = DetectorArtifact::is_in(model) || DetectorEnsembleArtifact::read(model).is_ok();
    let pose = !detector && (PoseArtifact::is_in(model) || PoseEnsemble::is_in(model));
    match (pose, from, data) {
        (true, Some(f), []) => Ok(Calibrated::of(
            &tactile_pose::calibrate::calibration_from(model, f)?,
            None,
        )),
        (true, None, [ds]) => Ok(Calibrated::of(
            &tactile_pose::calibrate::calibrate_on(model, ds, split)?,
            None,
        )),
        (true, _, _) => Err(tactile_core::Error::Config(
            "a pose network is calibrated on one dataset (with --split to take its rows of one split) or taken from a validated run (--calibration-from), one of the two".into(),
        )
        .into()),
        (false, None, [_, ..]) if split.is_none() => {
            let fit = tactile_detect::calibrate::calibrate_on(model, data)?;
            Ok(Calibrated {
                summary: format!("{}; detector in {}", fit.describe(), model.display()),
                warnings: Vec::new(),
            })
        }
        (false, _, _) => Err(tactile_core::Error::Config(
            "a detector is calibrated on whole datasets (--data, no --split or --calibration-from)".into(),
        )
        .into()),
    }
}

/// [`calibrate_model`] of a regressor on its encoder's features: the
/// encoder is the folder it sits in.
fn calibrate_regressor(
    model: &Path,
    data: &[Dataset],
    split: Option<&str>,
    from: Option<&Path>,
) -> Result<Calibrated> {
    let device = tactile_burn::DeviceKind::Flex.device();
    let fit = match (from, data) {
        (Some(f), []) => RegressorEnsemble::calibration_from(model, f, &device)?,
        (None, [ds]) => {
            let encoder = model
                .parent()
                .filter(|p| CaeArtifact::is_in(p))
                .ok_or_else(|| {
                    tactile_core::Error::model(
                        model,
                        "a regressor is calibrated on its encoder's features: keep it inside the encoder folder it was trained on",
                    )
                })?;
            let regressor = RegressorEnsemble::load(model, &device)?;
            let targets = regressor.targets();
            let rows = tactile_estimate::uncertainty::calibration_rows(ds, split, targets)?;
            let mut enc = TactipEncoder::load(encoder, Runtime::BurnFlex, 0)?;
            let pins = PinSet::from_rows(ds, &rows, &enc.artifact.preprocess)?;
            let feats = enc.encode(&pins.images)?;
            let labels = rows
                .iter()
                .map(|&i| targets.iter().map(|t| ds.target(i, &t.name)).collect())
                .collect::<tactile_core::Result<Vec<Vec<f64>>>>()?;
            let fitted = tactile_estimate::uncertainty::fitted_frames(
                &regressor.member_notes(),
                model,
                ds,
                &rows,
            );
            regressor.calibrate_on(model, (&feats, &labels), (&ds.root, split), fitted)?
        }
        _ => {
            return Err(tactile_core::Error::Config(
                "a regressor is calibrated on one dataset (with --split to take its rows of one split) or taken from a validated one (--calibration-from), one of the two".into(),
            )
            .into());
        }
    };
    Ok(Calibrated::of(
        &fit,
        Some(format!("regressor in {}", model.display())),
    ))
}
