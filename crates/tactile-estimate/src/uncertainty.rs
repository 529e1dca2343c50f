//! A per-frame uncertainty for every target: the network gives, beside
//! each standardised output, the log of a Laplace scale `b`, trained on
//! the negative log-likelihood `log b + |error| / b` of its own error with
//! the error's gradient stopped (so the outputs learn exactly as without
//! it). The scales are then calibrated on frames the training did not fit:
//! one factor per target makes the ±1 standard deviation interval hold
//! 68.3 % of their errors. The 95 % interval is ±1.96 of it; how often it
//! holds is measured, not assumed.

use burn::tensor::Tensor;
use serde::Serialize;

/// Log scales are clamped to this range, so a frame far from training
/// gives a large but finite deviation and the loss never divides by 0.
pub const LOG_SCALE_RANGE: (f32, f32) = (-9.0, 6.0);

/// Fraction of errors inside ±1 standard deviation of a normal variable.
pub const ONE_SIGMA: f64 = 0.682_689_492;

/// Half-width of the 95 % interval, in standard deviations.
pub const Z95: f64 = 1.959_964;

/// The Laplace negative log-likelihood (without its constant) of `error`
/// (prediction minus label, standardised) under the scales `exp(log_scale)`;
/// the error's gradient is stopped.
///
/// # Shapes
/// - `error`, `log_scale`: `[N, K]`; output `[N, K]`
pub fn laplace_nll(error: Tensor<2>, log_scale: Tensor<2>) -> Tensor<2> {
    let s = log_scale.clamp(LOG_SCALE_RANGE.0, LOG_SCALE_RANGE.1);
    s.clone() + error.detach().abs() * s.neg().exp()
}

/// A network's raw scale from its log-scale output.
pub fn scale(log_scale: f32) -> f64 {
    (log_scale.clamp(LOG_SCALE_RANGE.0, LOG_SCALE_RANGE.1) as f64).exp()
}

/// Per target, the factor that makes `factor * scale` cover 68.3 % of the
/// errors: `ratios[j]` holds `|error| / scale` of each calibration frame
/// for target `j`. A target with no finite ratio gets 1.
pub fn calibrate(ratios: &[Vec<f64>]) -> Vec<f64> {
    ratios
        .iter()
        .map(|r| {
            let mut r: Vec<f64> = r.iter().copied().filter(|v| v.is_finite()).collect();
            if r.is_empty() {
                return 1.0;
            }
            r.sort_by(f64::total_cmp);
            let at = ((r.len() as f64 * ONE_SIGMA).ceil() as usize).clamp(1, r.len()) - 1;
            r[at].max(1e-9)
        })
        .collect()
}

/// Per target, the factor that makes ±1 deviation hold 68.3 % of the
/// errors of raw network rows (`k` standardised estimates, then their `k`
/// log scales) against the standardised labels `truth` (`k` per row).
pub fn calibrate_raw<'a>(
    rows: impl IntoIterator<Item = &'a [f32]>,
    truth: &[f32],
    k: usize,
) -> Vec<f64> {
    let rows: Vec<&[f32]> = rows.into_iter().collect();
    let ratios: Vec<Vec<f64>> = (0..k)
        .map(|j| {
            rows.iter()
                .zip(truth.chunks(k))
                .map(|(r, t)| (r[j] as f64 - t[j] as f64).abs() / scale(r[k + j]))
                .collect()
        })
        .collect();
    calibrate(&ratios)
}

/// Per value its estimates, and with uncertainty each estimate's standard
/// deviation (labels' units).
pub type ValuesWithStd = (Vec<Vec<f64>>, Option<Vec<Vec<f64>>>);

/// One value's standard deviation in the labels' units from a network's
/// log-scale output, the standardisation `output_std` of its column and
/// the calibration `factor`.
pub fn deviation(log_scale: f32, output_std: f64, factor: f64) -> f64 {
    scale(log_scale) * output_std * factor
}

/// Members' estimates of one value with their deviations, as one: their
/// mean, and the deviation of their mixture (the members' mean variance
/// plus their spread), which an ensemble gives.
#[derive(Debug, Clone, Copy, Default)]
pub struct Mixture {
    n: f64,
    sum: f64,
    squares: f64,
    variances: f64,
}

impl Mixture {
    /// Add a member's estimate and its deviation (0 for none).
    pub fn add(&mut self, value: f64, std: f64) {
        self.n += 1.0;
        self.sum += value;
        self.squares += value * value;
        self.variances += std * std;
    }

    /// The members' mean estimate.
    pub fn mean(&self) -> f64 {
        self.sum / self.n.max(1.0)
    }

    /// The mixture's standard deviation.
    pub fn std(&self) -> f64 {
        let (n, m) = (self.n.max(1.0), self.mean());
        (self.variances / n + (self.squares / n - m * m).max(0.0)).sqrt()
    }
}

/// Refuse uncertainty for an angle target: a deviation is given per
/// column, and an angle takes two (its cosine and sine).
pub fn check_linear(targets: &[crate::Target]) -> Result<(), String> {
    match targets.iter().find(|t| t.width() != 1) {
        Some(t) => Err(format!(
            "uncertainty is given for linear targets only; {} is an angle",
            t.name
        )),
        None => Ok(()),
    }
}

/// Refuse a model with uncertainty whose calibration factors are missing,
/// or not one positive finite number per target.
pub fn check_std_scale(targets: &[crate::Target], std_scale: Option<&[f64]>) -> Result<(), String> {
    check_linear(targets)?;
    match std_scale {
        Some(s) if s.len() == targets.len() && s.iter().all(|v| v.is_finite() && *v > 0.0) => {
            Ok(())
        }
        Some(s) => Err(format!(
            "std_scale must hold one positive factor per target ({}), got {s:?}",
            targets.len()
        )),
        None => Err("a model with uncertainty needs its std_scale".into()),
    }
}

/// Fraction of `errors` inside `±z * std`, per target (columns of rows).
pub fn coverage(errors: &[Vec<f64>], std: &[Vec<f64>], z: f64) -> Vec<f64> {
    let k = errors.first().map_or(0, Vec::len);
    (0..k)
        .map(|j| {
            let n = errors.len().max(1) as f64;
            errors
                .iter()
                .zip(std)
                .filter(|(e, s)| e[j].abs() <= z * s[j])
                .count() as f64
                / n
        })
        .collect()
}

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
    /// Why the frames it was measured on are frames the model trained on,
    /// when its notes say so: its factors then fit training errors, and
    /// its intervals are too narrow on new frames.
    pub fitted_frames: Option<String>,
}

impl UncertaintyFit {
    /// Refuse to take the factors of the validated run `from` when its
    /// targets differ, or when one is an ensemble and the other a single
    /// `what` (network, regressor): its calibration would not apply.
    pub fn check_taken(
        from: &std::path::Path,
        (same_targets, same_kind): (bool, bool),
        what: &str,
    ) -> tactile_core::Result<()> {
        if !same_targets {
            return Err(tactile_core::Error::model(
                from,
                format!("its targets are not the {what}'s: its calibration does not apply"),
            ));
        }
        if !same_kind {
            return Err(tactile_core::Error::model(
                from,
                format!(
                    "an ensemble's factors apply to an ensemble of the same recipe, a {what}'s to a {what}"
                ),
            ));
        }
        Ok(())
    }

    /// Factors `scale` taken from the validated run `from` (whose own
    /// calibration notes are `from_notes`) for a model of `targets` that
    /// had `before`; with the note the model keeps of it.
    pub fn taken(
        targets: &[crate::Target],
        before: Vec<f64>,
        scale: Vec<f64>,
        (from, from_notes): (&std::path::Path, Option<serde_json::Value>),
    ) -> (Self, serde_json::Value) {
        let fit = Self {
            frames: 0,
            targets: targets.iter().map(|t| t.name.clone()).collect(),
            std_scale_before: before,
            std_scale: scale,
            coverage_before: [vec![], vec![]],
            coverage_cross_fitted: [vec![], vec![]],
            fitted_frames: None,
        };
        let note = serde_json::json!({ "from": from.display().to_string(), "notes": from_notes });
        (fit, note)
    }

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

    /// What the model's notes keep of it (`uncertainty_calibration`): the
    /// frames it was measured on (`data`, `split`) and the cross-fitted
    /// coverage, which a bench scoring those frames reports instead.
    pub fn note(&self, data: &std::path::Path, split: Option<&str>) -> serde_json::Value {
        serde_json::json!({
            "data": data.display().to_string(),
            "split": split.map(tactile_core::dataset::split_name),
            "frames": self.frames,
            "coverage_cross_fitted": self.coverage_cross_fitted,
            "fitted_frames": self.fitted_frames,
        })
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
    let mut at = cross_fitted_coverage_at(errors, std, &[1.0, Z95]).into_iter();
    [at.next().unwrap_or_default(), at.next().unwrap_or_default()]
}

/// Per half-width of `zs` (in deviations), the coverage of `±z` intervals
/// rescaled ([`rescale`]) on the even frames and measured on the odd
/// ones, and the other way round, averaged per target.
pub fn cross_fitted_coverage_at(
    errors: &[Vec<f64>],
    std: &[Vec<f64>],
    zs: &[f64],
) -> Vec<Vec<f64>> {
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
    let rescaled = |fit: &(Vec<Vec<f64>>, Vec<Vec<f64>>), on: &(Vec<Vec<f64>>, Vec<Vec<f64>>)| {
        let f = rescale(&fit.0, &fit.1);
        on.1.iter()
            .map(|s| s.iter().zip(&f).map(|(v, f)| v * f).collect())
            .collect::<Vec<Vec<f64>>>()
    };
    let (on_b, on_a) = (rescaled(&a, &b), rescaled(&b, &a));
    zs.iter()
        .map(|&z| {
            let (x, y) = (coverage(&b.0, &on_b, z), coverage(&a.0, &on_a, z));
            x.iter().zip(&y).map(|(p, q)| (p + q) / 2.0).collect()
        })
        .collect()
}

/// What a calibration on frames the model never fitted found: the
/// estimates `values` of `targets` against the labels `truth`, with their
/// deviations `std` (per frame, per target), the factors before
/// (`before`) and after (`before` times the rescaling), and the
/// intervals' coverage before and cross-fitted on halves of the frames.
pub fn fit(
    targets: &[crate::Target],
    (values, truth): (&[Vec<f64>], &[Vec<f64>]),
    std: &[Vec<f64>],
    before: Vec<f64>,
) -> UncertaintyFit {
    let errors: Vec<Vec<f64>> = values
        .iter()
        .zip(truth)
        .map(|(p, t)| {
            targets
                .iter()
                .enumerate()
                .map(|(j, target)| target.error(p[j], t[j]))
                .collect()
        })
        .collect();
    let coverage_before = [coverage(&errors, std, 1.0), coverage(&errors, std, Z95)];
    let coverage_cross_fitted = cross_fitted_coverage(&errors, std);
    let factor = rescale(&errors, std);
    let std_scale = before.iter().zip(&factor).map(|(b, f)| b * f).collect();
    UncertaintyFit {
        frames: errors.len(),
        targets: targets.iter().map(|t| t.name.clone()).collect(),
        std_scale_before: before,
        std_scale,
        coverage_before,
        coverage_cross_fitted,
        fitted_frames: None,
    }
}

/// Why `rows` of `ds` are frames a model trained on, when the notes of
/// the model (of any member of an ensemble: `notes`) say it fitted every
/// one of them ([`Provenance::seen`]: the same files or copies, among the
/// rows it fitted of a dataset they name). Its factors would then fit
/// training errors. `None` when it did not, or the notes name no dataset
/// that opens here.
///
/// [`Provenance::seen`]: tactile_core::dataset::Provenance::seen
pub fn fitted_frames(
    notes: &[&serde_json::Value],
    dir: &std::path::Path,
    ds: &tactile_core::dataset::Dataset,
    rows: &[usize],
) -> Option<String> {
    notes.iter().find_map(|n| {
        let p = tactile_core::dataset::Provenance::read(n);
        (p.seen(dir, ds, rows) == tactile_core::dataset::Seen::All).then(|| {
            format!(
                "these {} frames are frames it trained on (its notes: {}{}), so the factors fit its training errors and its intervals will be too narrow on new frames: calibrate on frames it did not train on (another split or recording), or take a validated run's factors (--calibration-from)",
                rows.len(),
                p.names(),
                if p.every_split { ", every split" } else { "" }
            )
        })
    })
}

/// The rows of `ds` to calibrate on: those of `split` (every row without
/// one) with every target labelled; at least 20, or an error naming the
/// labels file.
pub fn calibration_rows(
    ds: &tactile_core::dataset::Dataset,
    split: Option<&str>,
    targets: &[crate::Target],
) -> tactile_core::Result<Vec<usize>> {
    let rows = match split {
        Some(s) => ds.split_rows(s)?,
        None => ds.every_row(),
    };
    let mut labelled = Vec::with_capacity(rows.len());
    for i in rows {
        let mut all = true;
        for t in targets {
            all &= ds.target_opt(i, &t.name)?.is_some();
        }
        if all {
            labelled.push(i);
        }
    }
    if labelled.len() < 20 {
        return Err(tactile_core::Error::dataset(
            ds.labels_path(),
            None,
            format!(
                "{} frames with every target labelled{}: at least 20 are needed to calibrate",
                labelled.len(),
                split.map_or(String::new(), |s| format!(" in split '{s}'"))
            ),
        ));
    }
    Ok(labelled)
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::{Device, TensorData};

    #[test]
    fn calibration_covers_68_percent_and_the_loss_is_finite_at_extremes() {
        // Ratios 1..=100: the 69th smallest leaves 68.3 % at or below it.
        let r: Vec<f64> = (1..=100).map(f64::from).collect();
        let c = calibrate(&[r.clone(), vec![f64::NAN], vec![]]);
        assert_eq!(c, vec![69.0, 1.0, 1.0]);
        let errors: Vec<Vec<f64>> = r.iter().map(|&e| vec![e]).collect();
        let std: Vec<Vec<f64>> = r.iter().map(|_| vec![c[0]]).collect();
        assert!((coverage(&errors, &std, 1.0)[0] - 0.69).abs() < 1e-9);
        // Huge or tiny log scales stay finite.
        let dev = Device::flex();
        let e = Tensor::<2>::from_data(TensorData::new(vec![1e6f32, 0.0], [1, 2]), &dev);
        let s = Tensor::<2>::from_data(TensorData::new(vec![-1e6f32, 1e6], [1, 2]), &dev);
        let v: Vec<f32> = laplace_nll(e, s).into_data().try_to_vec().unwrap();
        assert!(v.iter().all(|x| x.is_finite()), "{v:?}");
        assert!(scale(1e9).is_finite() && scale(-1e9) > 0.0);
    }

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
