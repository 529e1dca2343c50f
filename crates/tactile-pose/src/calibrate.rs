//! A pose network's uncertainty calibrated again, on frames it never
//! fitted. Training calibrates on the rows that stop it early, which come
//! from the training split: on another split's frames the errors are
//! larger and the intervals too narrow (p128 on the surface set's `val`:
//! 62.9 % inside ±1 deviation). `tactile train calibrate --model POSE
//! --data D --split val` rescales the deviations so ±1 holds 68.3 % of
//! that split's errors; a network trained on every frame takes its
//! validated run's factors instead (`--calibration-from`), as training does.

use std::path::Path;

use tactile_burn::ensemble::{CALIBRATION_NOTE, Ensemble};
use tactile_burn::{Artifact, Runtime};
use tactile_core::dataset::Dataset;
use tactile_estimate::Target;

use crate::data::PoseSet;
use crate::uncertainty::UncertaintyFit;
use crate::{PoseArtifact, PoseEnsemble, PoseEstimator, Result};
use tactile_cae::data::PinSet;

/// Where a model keeps its deviation factors.
enum Factors {
    /// A network's `pose.json` (`std_scale`).
    Network(Box<PoseArtifact>),
    /// An ensemble's `ensemble.json` (`notes.std_scale`), applied to the
    /// deviation its members give together (their own factors stay).
    Ensemble(Ensemble),
}

/// The model in `dir` with its factors, its targets, and the factors.
fn uncertain(dir: &Path) -> Result<(Factors, Vec<Target>, Vec<f64>)> {
    let no_uncertainty = || {
        tactile_core::Error::model(
            dir,
            "this pose network gives no uncertainty (train it with --uncertainty)",
        )
    };
    if PoseEnsemble::is_in(dir) {
        let e = PoseEnsemble::read(dir)?;
        let first = e
            .member_dirs(dir)
            .into_iter()
            .next()
            .ok_or_else(|| tactile_core::Error::not_found(dir, "ensemble member"))?;
        let a = PoseArtifact::read(&first)?;
        if a.std_scale.is_none() {
            return Err(no_uncertainty().into());
        }
        let k = a.targets.len();
        let s = e.std_scale(dir, k)?.unwrap_or_else(|| vec![1.0; k]);
        return Ok((Factors::Ensemble(e), a.targets, s));
    }
    let a = PoseArtifact::read(dir)?;
    let s = a.std_scale.clone().ok_or_else(no_uncertainty)?;
    let targets = a.targets.clone();
    Ok((Factors::Network(Box::new(a)), targets, s))
}

/// Rewrite `dir`'s `pose.json` or `ensemble.json` (atomically; no weights
/// are touched) with the factors `scale`, its notes saying where they came
/// from.
fn save_scale(dir: &Path, model: Factors, scale: &[f64], note: serde_json::Value) -> Result<()> {
    match model {
        Factors::Network(mut art) => {
            art.std_scale = Some(scale.to_vec());
            if let serde_json::Value::Object(n) = &mut art.notes {
                n.insert(CALIBRATION_NOTE.into(), note);
            }
            Ok(tactile_core::io::write_json_atomic(
                dir.join(PoseArtifact::CONFIG_FILE),
                &art,
            )?)
        }
        Factors::Ensemble(e) => Ok(e.write_std_scale(dir, scale, note)?),
    }
}

/// Calibrate the deviations of the pose network (or ensemble) in `dir` on
/// the frames of `ds` (those of `split` when given): one factor per target
/// so ±1 deviation holds 68.3 % of their errors. The estimates are
/// unchanged; `pose.json` (an ensemble's `ensemble.json`) is rewritten
/// atomically with the new factors.
pub fn calibrate_on(dir: &Path, ds: &Dataset, split: Option<&str>) -> Result<UncertaintyFit> {
    let (model, targets, before) = uncertain(dir)?;
    let rows = crate::uncertainty::calibration_rows(ds, split, &targets)?;
    let mut est = PoseEstimator::load(dir, Runtime::BurnFlex, 0)?;
    // One set of pin images per scale (three for the multi-scale
    // ensemble), each frame read once; the labels with the first.
    let mut pins = PinSet::from_rows_each(ds, &rows, est.scales())?;
    let set = PoseSet::from_pins(ds, &rows, pins.remove(0), &targets)?;
    let views: Vec<&[_]> = std::iter::once(&set.pins)
        .chain(&pins)
        .map(|s| s.images.as_slice())
        .collect();
    let (values, std) = est.predict_scales_with_std(&views)?;
    let std = std.ok_or_else(|| tactile_core::Error::model(dir, "no deviations came out"))?;
    let truth = set.label_rows(&(0..rows.len()).collect::<Vec<_>>());
    let mut fit = crate::uncertainty::fit(&targets, (&values, &truth), &std, before);
    fit.fitted_frames = fitted_frames(&model, dir, ds, &rows)?;
    save_scale(dir, model, &fit.std_scale, fit.note(&ds.root, split))?;
    Ok(fit)
}

/// [`crate::uncertainty::fitted_frames`] of the network, or of an
/// ensemble's members.
fn fitted_frames(
    model: &Factors,
    dir: &Path,
    ds: &Dataset,
    rows: &[usize],
) -> Result<Option<String>> {
    let notes: Vec<serde_json::Value> = match model {
        Factors::Network(a) => vec![a.notes.clone()],
        Factors::Ensemble(e) => e
            .member_dirs(dir)
            .iter()
            .map(|d| Ok(PoseArtifact::read(d)?.notes))
            .collect::<Result<_>>()?,
    };
    let notes: Vec<&serde_json::Value> = notes.iter().collect();
    Ok(crate::uncertainty::fitted_frames(&notes, dir, ds, rows))
}

/// Give the network in `dir` the factors of the validated run in `from`
/// (the same targets): a network trained on every frame has none left to
/// calibrate on.
pub fn calibration_from(dir: &Path, from: &Path) -> Result<UncertaintyFit> {
    let (model, targets, before) = uncertain(dir)?;
    let (src, src_targets, scale) = uncertain(from)?;
    let same_kind = matches!(src, Factors::Ensemble(_)) == matches!(model, Factors::Ensemble(_));
    UncertaintyFit::check_taken(from, (src_targets == targets, same_kind), "network")?;
    let src_note = match &src {
        Factors::Network(a) => a.notes.get(CALIBRATION_NOTE).cloned(),
        Factors::Ensemble(e) => e.notes.get(CALIBRATION_NOTE).cloned(),
    };
    let (fit, note) = UncertaintyFit::taken(&targets, before, scale, (from, src_note));
    save_scale(dir, model, &fit.std_scale, note)?;
    Ok(fit)
}
