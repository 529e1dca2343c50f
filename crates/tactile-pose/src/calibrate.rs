//! A pose network's uncertainty calibrated again, on frames it never
//! fitted. Training calibrates on the rows that stop it early, which come
//! from the training split: on another split's frames the errors are
//! larger and the intervals too narrow (p128 on the surface set's `val`:
//! 62.9 % inside ±1 deviation). `tactile train calibrate --model POSE
//! --data D --split val` rescales the deviations so ±1 holds 68.3 % of
//! that split's errors; a network trained on every frame takes its
//! validated run's factors instead (`--calibration-from`), as training does.

use std::path::Path;

use serde::Serialize;
use tactile_burn::ensemble::Ensemble;
use tactile_burn::{Artifact, Runtime};
use tactile_core::dataset::Dataset;
use tactile_estimate::Target;

use crate::data::PoseSet;
use crate::uncertainty::{Z95, calibrate, coverage};
use crate::{PoseArtifact, PoseEnsemble, PoseEstimator, Result};
use tactile_cae::data::PinSet;

/// What a recalibration found and did.
#[derive(Debug, Clone, Serialize)]
pub struct UncertaintyFit {
    /// Frames it was measured on (0 when taken from another run).
    pub frames: usize,
    /// The targets, in column order.
    pub targets: Vec<String>,
    /// Each target's factor before.
    pub std_scale_before: Vec<f64>,
    /// And after.
    pub std_scale: Vec<f64>,
    /// Fraction of the frames' errors inside ±1 and ±1.96 deviations
    /// before, per target.
    pub coverage_before: [Vec<f64>; 2],
    /// The same for intervals calibrated on one half of the frames and
    /// measured on the other (both ways, averaged): what frames the
    /// calibration never saw can expect.
    pub coverage_cross_fitted: [Vec<f64>; 2],
}

impl UncertaintyFit {
    /// One line for a terminal.
    pub fn describe(&self) -> String {
        let mean = |v: &[f64]| 100.0 * v.iter().sum::<f64>() / v.len().max(1) as f64;
        if self.frames == 0 {
            return format!(
                "deviation factors taken from the validated run: {:?} (were {:?})",
                rounded(&self.std_scale),
                rounded(&self.std_scale_before)
            );
        }
        format!(
            "{} frames: inside ±1 / ±1.96 deviations {:.1} % / {:.1} % before, {:.1} % / {:.1} % after (cross-fitted on halves); factors {:?} (were {:?})",
            self.frames,
            mean(&self.coverage_before[0]),
            mean(&self.coverage_before[1]),
            mean(&self.coverage_cross_fitted[0]),
            mean(&self.coverage_cross_fitted[1]),
            rounded(&self.std_scale),
            rounded(&self.std_scale_before)
        )
    }
}

fn rounded(v: &[f64]) -> Vec<f64> {
    v.iter().map(|x| (x * 1e4).round() / 1e4).collect()
}

/// Per target, the factors that make `std` (per frame, per target) hold
/// 68.3 % of `errors` inside ±1.
pub fn rescale(errors: &[Vec<f64>], std: &[Vec<f64>]) -> Vec<f64> {
    let k = errors.first().map_or(0, Vec::len);
    let ratios: Vec<Vec<f64>> = (0..k)
        .map(|j| {
            errors
                .iter()
                .zip(std)
                .map(|(e, s)| e[j].abs() / s[j])
                .collect()
        })
        .collect();
    calibrate(&ratios)
}

/// Coverage of ±1 and ±1.96 intervals rescaled ([`rescale`]) on the even
/// frames and measured on the odd ones, and the other way round, averaged
/// per target.
pub fn cross_fitted_coverage(errors: &[Vec<f64>], std: &[Vec<f64>]) -> [Vec<f64>; 2] {
    let half = |parity: usize| -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        errors
            .iter()
            .zip(std)
            .enumerate()
            .filter(|(i, _)| i % 2 == parity)
            .map(|(_, (e, s))| (e.clone(), s.clone()))
            .unzip()
    };
    let (a, b) = (half(0), half(1));
    let measured = |fit: &(Vec<Vec<f64>>, Vec<Vec<f64>>), on: &(Vec<Vec<f64>>, Vec<Vec<f64>>)| {
        let f = rescale(&fit.0, &fit.1);
        let s: Vec<Vec<f64>> =
            on.1.iter()
                .map(|s| s.iter().zip(&f).map(|(v, f)| v * f).collect())
                .collect();
        [coverage(&on.0, &s, 1.0), coverage(&on.0, &s, Z95)]
    };
    let (x, y) = (measured(&a, &b), measured(&b, &a));
    let avg = |p: &[f64], q: &[f64]| p.iter().zip(q).map(|(p, q)| (p + q) / 2.0).collect();
    [avg(&x[0], &y[0]), avg(&x[1], &y[1])]
}

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
        let s = PoseEnsemble::std_scale(&e, dir, k)?.unwrap_or_else(|| vec![1.0; k]);
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
                n.insert("uncertainty_calibration".into(), note);
            }
            Ok(tactile_core::io::write_json_atomic(
                dir.join(PoseArtifact::CONFIG_FILE),
                &art,
            )?)
        }
        Factors::Ensemble(mut e) => {
            if !e.notes.is_object() {
                e.notes = serde_json::json!({});
            }
            e.notes["std_scale"] = serde_json::json!(scale);
            e.notes["uncertainty_calibration"] = note;
            Ok(tactile_core::io::write_json_atomic(
                dir.join(Ensemble::FILE),
                &e,
            )?)
        }
    }
}

/// Calibrate the deviations of the pose network (or ensemble) in `dir` on
/// the frames of `ds` (those of `split` when given): one factor per target
/// so ±1 deviation holds 68.3 % of their errors. The estimates are
/// unchanged; `pose.json` (an ensemble's `ensemble.json`) is rewritten
/// atomically with the new factors.
pub fn calibrate_on(dir: &Path, ds: &Dataset, split: Option<&str>) -> Result<UncertaintyFit> {
    let (model, targets, before) = uncertain(dir)?;
    let rows = match split {
        Some(s) => ds
            .split_indices(s)
            .ok_or_else(|| {
                tactile_core::Error::dataset(
                    ds.root.join("labels.csv"),
                    None,
                    format!("no 'split' column to take the '{s}' rows from"),
                )
            })?
            .to_vec(),
        None => (0..ds.len()).collect(),
    };
    let mut est = PoseEstimator::load(dir, Runtime::BurnFlex, 0)?;
    // One set of pin images per scale (three for the multi-scale
    // ensemble), each frame read once; the labels with the first.
    let mut pins = PinSet::from_rows_each(ds, &rows, est.scales())?;
    let set = PoseSet::from_pins(ds, &rows, pins.remove(0), &targets)?;
    let labelled = set.labelled(&(0..rows.len()).collect::<Vec<_>>());
    if labelled.len() < 20 {
        return Err(tactile_core::Error::dataset(
            ds.root.join("labels.csv"),
            None,
            format!(
                "{} frames with every target labelled{}: at least 20 are needed to calibrate",
                labelled.len(),
                split.map_or(String::new(), |s| format!(" in split '{s}'"))
            ),
        )
        .into());
    }
    let images: Vec<Vec<_>> = std::iter::once(&set.pins)
        .chain(&pins)
        .map(|s| labelled.iter().map(|&i| s.images[i].clone()).collect())
        .collect();
    let views: Vec<&[_]> = images.iter().map(Vec::as_slice).collect();
    let (values, std) = est.predict_scales_with_std(&views)?;
    let std = std.ok_or_else(|| tactile_core::Error::model(dir, "no deviations came out"))?;
    let truth = set.label_rows(&labelled);
    let errors: Vec<Vec<f64>> = values
        .iter()
        .zip(&truth)
        .map(|(p, t)| {
            targets
                .iter()
                .enumerate()
                .map(|(j, target)| target.error(p[j], t[j]))
                .collect()
        })
        .collect();
    let coverage_before = [coverage(&errors, &std, 1.0), coverage(&errors, &std, Z95)];
    let coverage_cross_fitted = cross_fitted_coverage(&errors, &std);
    let factor = rescale(&errors, &std);
    let scale: Vec<f64> = before.iter().zip(&factor).map(|(b, f)| b * f).collect();
    let names = targets.iter().map(|t| t.name.clone()).collect();
    save_scale(
        dir,
        model,
        &scale,
        serde_json::json!({
            "data": ds.root.display().to_string(),
            "split": split,
            "frames": errors.len(),
            "coverage_cross_fitted": coverage_cross_fitted,
        }),
    )?;
    Ok(UncertaintyFit {
        frames: errors.len(),
        targets: names,
        std_scale_before: before,
        std_scale: scale,
        coverage_before,
        coverage_cross_fitted,
    })
}

/// Give the network in `dir` the factors of the validated run in `from`
/// (the same targets): a network trained on every frame has none left to
/// calibrate on.
pub fn calibration_from(dir: &Path, from: &Path) -> Result<UncertaintyFit> {
    let (model, targets, before) = uncertain(dir)?;
    let (src, src_targets, scale) = uncertain(from)?;
    if src_targets != targets {
        return Err(tactile_core::Error::model(
            from,
            "its targets are not the network's: its calibration does not apply",
        )
        .into());
    }
    if matches!(src, Factors::Ensemble(_)) != matches!(model, Factors::Ensemble(_)) {
        return Err(tactile_core::Error::model(
            from,
            "an ensemble's factors apply to an ensemble of the same recipe, a network's to a network",
        )
        .into());
    }
    let src_note = match &src {
        Factors::Network(a) => a.notes.get("uncertainty_calibration").cloned(),
        Factors::Ensemble(e) => e.notes.get("uncertainty_calibration").cloned(),
    };
    save_scale(
        dir,
        model,
        &scale,
        serde_json::json!({ "from": from.display().to_string(), "notes": src_note }),
    )?;
    Ok(UncertaintyFit {
        frames: 0,
        targets: targets.iter().map(|t| t.name.clone()).collect(),
        std_scale_before: before,
        std_scale: scale,
        coverage_before: [vec![], vec![]],
        coverage_cross_fitted: [vec![], vec![]],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deviations_half_the_errors_scale_are_doubled_and_hold_on_the_other_half() {
        // Laplace-like errors of scale 2 under deviations that say 1.
        let mut rng = tactile_core::rng::SampleRng::new(3, 0, 0);
        let errors: Vec<Vec<f64>> = (0..4000)
            .map(|_| {
                let u: f64 = rng.uniform() - 0.5;
                vec![-2.0 * u.signum() * (1.0 - 2.0 * u.abs()).ln()]
            })
            .collect();
        let std = vec![vec![1.0]; errors.len()];
        let before = coverage(&errors, &std, 1.0)[0];
        let f = rescale(&errors, &std)[0];
        let after = coverage(&errors, &vec![vec![f]; errors.len()], 1.0)[0];
        assert!(before < 0.5, "{before}");
        assert!((after - 0.683).abs() < 0.005, "{after}");
        // Laplace: the 68.3 % quantile of |e| is b ln(1 / 0.317) = 2.30 b.
        assert!((f - 2.0 * (1.0f64 / 0.317).ln()).abs() < 0.15, "{f}");
        // Held out, ±1 still holds 68.3 %, and ±1.96 the Laplace's
        // 1 - 0.317^1.96 = 89.5 % (a normal's would be 95 %).
        let [c68, c95] = cross_fitted_coverage(&errors, &std);
        assert!((c68[0] - 0.683).abs() < 0.02, "{c68:?}");
        assert!((c95[0] - 0.895).abs() < 0.02, "{c95:?}");
    }
}
