//! Training the detector: class-balanced stable BCE on logits (toward 0/1
//! labels or soft targets from the ridge amplitude), Adam with a decaying
//! rate, validation accuracy each epoch, best model kept, resumable; then
//! the decision threshold is calibrated on the validation sequences.

use std::path::Path;

use burn::config::Config;
use burn::tensor::{Device, Tensor, TensorData};
use tactile_burn::nn::elementwise_bce_with_logits;
use tactile_burn::runtime::sigmoid;
use tactile_burn::train::{FitConfig, FitSummary, Schedule, fit};
use tactile_burn::{Artifact, DeviceKind};
use tactile_core::dataset::{Dataset, Provenance};
use tactile_preprocess::visuo::ChannelStats;

use tactile_preprocess::profile::InputProfile;

use crate::augment::PhotometricAugment;
use crate::data::{SoftLabels, load_split};
use crate::{DetectionSet, Detector, DetectorArtifact, DetectorConfig, Error, Result};

/// Everything a detector's training is set by.
#[derive(Config, Debug)]
pub struct DetectorTrainingConfig {
    /// Architecture and input size (paper B: width 1.0 at 320x240; this
    /// machine's default: width 0.5 at 160x120).
    #[config(default = "DetectorConfig::new().with_width(0.5).with_input_size([160, 120])")]
    pub model: DetectorConfig,
    /// Paper B: batch 8.
    #[config(default = "Schedule::new(16, 12, 4, 1e-3).with_lr_decay(0.8)")]
    pub schedule: Schedule,
    /// Fraction of each dataset's sequences that validate.
    #[config(default = 0.2)]
    pub val_fraction: f64,
    /// Train toward soft targets from the ridge amplitude (None: 0/1).
    #[config(default = "None")]
    pub soft_labels: Option<SoftLabels>,
    /// Photometric augmentation of the training frames (None: off).
    #[config(default = "None")]
    pub augment: Option<PhotometricAugment>,
}

/// Weights that make both classes count equally: `n / (2 n_class)`.
pub fn class_weights(labels: &[bool]) -> (f32, f32) {
    let n = labels.len() as f32;
    let pos = labels.iter().filter(|&&t| t).count() as f32;
    let neg = n - pos;
    let w = |k: f32| if k > 0.0 { n / (2.0 * k) } else { 0.0 };
    (w(neg), w(pos))
}

/// The one class `truth` holds, when it holds one (and a frame): the
/// label's value, what it means and what the other class is.
fn one_class(truth: &[bool]) -> Option<(u8, &'static str, &'static str)> {
    let first = *truth.first()?;
    truth.iter().all(|&t| t == first).then_some(match first {
        false => (0, "no tendon", "with a tendon"),
        true => (1, "a tendon", "without one"),
    })
}

/// The labels files of `datasets`, for a message.
fn labels_files(datasets: &[Dataset]) -> String {
    datasets
        .iter()
        .map(|d| d.labels_path().display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Refuse training rows of one class: a detector that sees no frame
/// with a tendon (or none without) learns to give that answer for every
/// frame, and its validation accuracy on such frames would say nothing.
fn check_both_classes(datasets: &[Dataset], tendon: &[bool], train: &[usize]) -> Result<()> {
    let truth: Vec<bool> = train.iter().map(|&i| tendon[i]).collect();
    let Some((value, meaning, missing)) = one_class(&truth) else {
        return Ok(());
    };
    Err(tactile_core::Error::Invalid(format!(
        "{}: every one of the {} training frames is labelled tendon = {value} ({meaning}): a detector learns nothing from one class and would say {meaning} for every frame; give frames {missing} too",
        labels_files(datasets),
        train.len()
    ))
    .into())
}

/// A warning when the validation frames are of one class (whole
/// sequences go to validation, and a recording of presses without a
/// tendon is one): the threshold is not tuned on them
/// ([`best_threshold`]), and their accuracy says nothing of the other
/// class.
fn one_class_validation(datasets: &[Dataset], tendon: &[bool], val: &[usize]) -> Option<String> {
    let truth: Vec<bool> = val.iter().map(|&i| tendon[i]).collect();
    let (value, meaning, missing) = one_class(&truth)?;
    Some(format!(
        "{}: every one of the {} validation frames (whole sequences, split by `sequence`) is labelled tendon = {value} ({meaning}): the threshold stays at 0.5, as frames of one class cannot tune it, and the validation accuracy says nothing of frames {missing}; give validation sequences of both (another --seed or --val-fraction, or sequences that hold both)",
        labels_files(datasets),
        val.len()
    ))
}

/// Class-weighted mean BCE of logits `[N, 1]`.
fn weighted_bce(logits: Tensor<2>, targets: Tensor<2>, (wn, wp): (f32, f32)) -> Tensor<1> {
    let w = targets.clone().mul_scalar(wp - wn).add_scalar(wn);
    (elementwise_bce_with_logits(logits, targets) * w).mean()
}

/// Probabilities of the frames at `idx`, in batches, straight from the
/// module being trained (or a loaded one).
pub(crate) fn predict(
    model: &Detector,
    data: &DetectionSet,
    idx: &[usize],
    stats: &ChannelStats,
    device: &Device,
) -> Result<Vec<f32>> {
    let mut out = Vec::with_capacity(idx.len());
    for chunk in idx.chunks(64) {
        let z = model
            .forward(data.batch(chunk, stats, device)?)
            .into_data()
            .try_to_vec::<f32>()
            .map_err(|e| tactile_core::Error::Invalid(format!("detector output: {e:?}")))?;
        out.extend(z.into_iter().map(sigmoid));
    }
    Ok(out)
}

/// The probability threshold (0.05 to 0.95 in steps of 0.05) with the
/// best accuracy on `val`; ties go to the one nearest 0.5. Frames of one
/// class keep 0.5.
pub fn best_threshold(probs: &[f32], truth: &[bool]) -> (f64, f64) {
    if one_class(truth).is_some() {
        // Frames of one class can only push the threshold away from it,
        // trading away the other class, which no frame here measures.
        let pred: Vec<bool> = probs.iter().map(|&p| p as f64 >= 0.5).collect();
        return (
            0.5,
            tactile_core::metrics::binary_scores(&pred, truth).accuracy,
        );
    }
    let mut best: (f64, f64) = (0.5, -1.0);
    for k in 1..20 {
        let t = k as f64 * 0.05;
        let pred: Vec<bool> = probs.iter().map(|&p| p as f64 >= t).collect();
        let acc = tactile_core::metrics::binary_scores(&pred, truth).accuracy;
        let closer = (t - 0.5).abs() < (best.0 - 0.5).abs();
        if acc > best.1 + 1e-12 || ((acc - best.1).abs() <= 1e-12 && closer) {
            best = (t, acc);
        }
    }
    best
}

/// Set the saved detector's threshold to [`best_threshold`] on `val`;
/// returns (threshold, validation accuracy).
pub fn calibrate(
    out: &Path,
    data: &DetectionSet,
    val: &[usize],
    device: DeviceKind,
) -> Result<(f64, f64)> {
    let loaded = DetectorArtifact::load_unfinished(out, &device.device())?;
    let mut art = loaded.artifact;
    let p = predict(&loaded.model, data, val, &art.stats, &loaded.device)?;
    let truth: Vec<bool> = val.iter().map(|&i| data.tendon[i]).collect();
    let (t, acc) = best_threshold(&p, &truth);
    art.threshold = t;
    art.save(&loaded.model, out)?;
    Ok((t, acc))
}

/// What a training run ended with, the calibrated threshold included.
#[derive(Debug, Clone, serde::Serialize)]
pub struct DetectorFit {
    /// The run.
    #[serde(flatten)]
    pub summary: FitSummary,
    /// The threshold chosen on the validation sequences.
    pub threshold: f64,
    /// Validation accuracy at that threshold.
    pub val_accuracy: f64,
}

impl DetectorFit {
    /// One line: the run, then the accuracy at the chosen threshold.
    pub fn describe(&self) -> String {
        format!(
            "{} (accuracy {:.4} at the chosen threshold {:.2})",
            self.summary.describe("accuracy at threshold 0.5"),
            self.val_accuracy,
            self.threshold
        )
    }
}

/// Train on `datasets` (each split by its own sequences) into `out`, then
/// calibrate the threshold. With `calibrate_only`, only re-choose the
/// threshold of the model already in `out`.
pub fn train(
    config: &DetectorTrainingConfig,
    datasets: &[Dataset],
    out: &Path,
    device: DeviceKind,
    resume: bool,
    calibrate_only: bool,
) -> Result<DetectorFit> {
    config.schedule.check()?;
    if let Some(a) = &config.augment {
        a.check()?;
    }
    config.model.check()?;
    let refs: Vec<&Dataset> = datasets.iter().collect();
    <crate::DetectorArtifact as tactile_burn::Artifact>::check_out_dir(out, &refs)?;
    let [w, h] = config.model.input_size;
    let (data, train, val) = load_split(
        datasets,
        &config.model,
        config.val_fraction,
        config.schedule.seed,
        config.soft_labels.is_some(),
    )?;
    if calibrate_only {
        let (threshold, val_accuracy) = calibrate(out, &data, &val, device)?;
        let summary: FitSummary =
            tactile_core::io::read_json::<serde_json::Value>(out.join("training.json"))
                .ok()
                .and_then(|v| serde_json::from_value(v["summary"].clone()).ok())
                .ok_or_else(|| {
                    tactile_core::Error::not_found(out.join("training.json"), "training record")
                })?;
        return Ok(DetectorFit {
            summary,
            threshold,
            val_accuracy,
        });
    }
    if train.is_empty() || val.is_empty() {
        return Err(tactile_core::Error::Invalid(format!(
            "need training and validation frames (got {} and {})",
            train.len(),
            val.len()
        ))
        .into());
    }
    check_both_classes(datasets, &data.tendon, &train)?;
    let warnings: Vec<String> = one_class_validation(datasets, &data.tendon, &val)
        .into_iter()
        .collect();
    for w in &warnings {
        tactile_core::note!("warning: {w}");
    }
    if (data.width, data.height) != (w, h) {
        return Err(Error::InputSize {
            expected: [w, h],
            found: [data.width, data.height],
        });
    }
    let dev = device.device();
    let stats = ChannelStats::from_images(
        train
            .iter()
            .map(|&i| data.view(i))
            .collect::<Vec<_>>()
            .iter(),
    )?;
    let labels: Vec<bool> = train.iter().map(|&i| data.tendon[i]).collect();
    let weights = class_weights(&labels);
    let artifact = DetectorArtifact {
        model: config.model.clone(),
        stats: stats.clone(),
        threshold: 0.5,
        // A profile needs a few frames; tiny test sets train without one.
        input_profile: (train.len() >= InputProfile::MIN_FRAMES)
            .then(|| crate::profile::fit_input_profile_of(&data, &train))
            .transpose()?,
        // Split by sequence, the split column aside: it fits every split.
        notes: Provenance::of(&datasets.iter().collect::<Vec<_>>())
            .every_split(true)
            .notes(serde_json::json!({ "device": device.name() })),
    };
    let ad = dev.clone().autodiff();
    ad.seed(config.schedule.seed);
    let model = config.model.init(&ad);
    let ds_refs: Vec<&Dataset> = datasets.iter().collect();
    let fit_cfg = FitConfig::new(&config.schedule, "detector training (class-weighted BCE)")
        .saving_to(out, resume)
        .with_run_id(tactile_burn::artifact::run_fingerprint(config, &ds_refs)?);
    let unfinished = tactile_burn::artifact::Unfinished::begin(out)?;
    let val_truth: Vec<bool> = val.iter().map(|&i| data.tendon[i]).collect();
    let (_, mut summary) = fit::<_, Error>(
        &fit_cfg,
        model,
        burn::optim::AdamConfig::new().init(),
        (&train, val.len()),
        |m: &Detector, batch, epoch| {
            let x = match &config.augment {
                Some(a) => data.augmented_batch(
                    batch,
                    &stats,
                    a,
                    (config.schedule.seed, epoch as u64 + 1),
                    &ad,
                )?,
                None => data.batch(batch, &stats, &ad)?,
            };
            let y = data.targets(batch, config.soft_labels.as_ref(), &ad);
            Ok(weighted_bce(m.forward(x), y, weights))
        },
        |m| {
            let p = predict(m, &data, &val, &stats, &dev)?;
            // Validation loss with the same class weights, from probabilities.
            let logits: Vec<f32> = p
                .iter()
                .map(|&q| {
                    let q = q.clamp(1e-7, 1.0 - 1e-7);
                    (q / (1.0 - q)).ln()
                })
                .collect();
            let z = Tensor::<2>::from_data(TensorData::new(logits, [val.len(), 1]), &dev);
            // Against the targets training aims at: with soft labels the
            // best epoch is the one that measures the ridge best, not the
            // most confident one.
            let targets = data.targets(&val, config.soft_labels.as_ref(), &dev);
            let loss: f32 = weighted_bce(z, targets, weights).into_scalar();
            let pred: Vec<bool> = p.iter().map(|&q| q as f64 >= 0.5).collect();
            let acc = tactile_core::metrics::binary_scores(&pred, &val_truth).accuracy;
            Ok((loss as f64, Some(acc)))
        },
        |m| Ok(artifact.save(m, out)?),
    )?;
    summary.warnings = warnings;
    tactile_burn::artifact::write_training_record(
        out,
        config,
        &summary,
        serde_json::json!({ "train_frames": train.len(), "val_frames": val.len() }),
    )?;
    let (threshold, val_accuracy) = calibrate(out, &data, &val, device)?;
    unfinished.finish()?;
    Ok(DetectorFit {
        summary,
        threshold,
        val_accuracy,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_threshold_is_tuned_on_both_classes_and_kept_at_a_half_on_one() {
        // Both classes: the threshold that separates them.
        let (t, acc) = best_threshold(&[0.2, 0.6, 0.7, 0.9], &[false, false, true, true]);
        assert!((t - 0.65).abs() < 1e-9 && acc == 1.0, "{t} {acc}");
        // One class: before, 0.75 (every frame right, at the other class's
        // cost, which no frame measured); now a half.
        let (t, acc) = best_threshold(&[0.6, 0.2, 0.7], &[false; 3]);
        assert!(t == 0.5 && (acc - 1.0 / 3.0).abs() < 1e-9, "{t} {acc}");
        assert_eq!(one_class(&[true, true]).map(|c| c.0), Some(1));
        assert!(one_class(&[true, false]).is_none() && one_class(&[]).is_none());
    }
}
