//! Training the detector: class-balanced stable BCE on logits, Adam,
//! validation accuracy each epoch, best model kept, resumable.

use std::path::Path;

use burn::config::Config;
use burn::tensor::{Device, Tensor, TensorData};
use tactile_core::nn::elementwise_bce_with_logits;
use tactile_core::train::{FitConfig, FitSummary, fit};
use tactile_core::{Error, Result};
use tactile_preprocess::visuo::ChannelStats;

use crate::{DetectionSet, Detector, DetectorArtifact, DetectorConfig, SoftLabels};

#[derive(Config, Debug)]
pub struct DetectorTrainingConfig {
    pub detector: DetectorConfig,
    /// Paper B: 8.
    #[config(default = 16)]
    pub batch_size: usize,
    #[config(default = 20)]
    pub max_epochs: usize,
    #[config(default = 5)]
    pub patience: usize,
    #[config(default = 1e-3)]
    pub learning_rate: f64,
    /// Learning-rate factor per epoch.
    #[config(default = 0.8)]
    pub lr_decay: f64,
    #[config(default = 42)]
    pub seed: u64,
    /// Train toward soft targets from the ridge amplitude (None: 0/1).
    pub soft_labels: Option<SoftLabels>,
}

/// Weights that make both classes count equally: `n / (2 n_class)`.
pub fn class_weights(labels: &[bool]) -> (f32, f32) {
    let n = labels.len() as f32;
    let pos = labels.iter().filter(|&&t| t).count() as f32;
    let neg = n - pos;
    let w = |k: f32| if k > 0.0 { n / (2.0 * k) } else { 0.0 };
    (w(neg), w(pos))
}

/// Class-weighted mean BCE of logits `[N, 1]`.
fn weighted_bce(logits: Tensor<2>, targets: Tensor<2>, (wn, wp): (f32, f32)) -> Tensor<1> {
    let w = targets.clone().mul_scalar(wp - wn).add_scalar(wn);
    (elementwise_bce_with_logits(logits, targets) * w).mean()
}

/// Probabilities of the frames at `idx`, in batches.
pub fn predict(
    model: &Detector,
    data: &DetectionSet,
    idx: &[usize],
    stats: &ChannelStats,
    batch: usize,
    device: &Device,
) -> Result<Vec<f32>> {
    let mut out = Vec::with_capacity(idx.len());
    for chunk in idx.chunks(batch.max(1)) {
        out.extend(model.probabilities(data.batch(chunk, stats, device)?)?);
    }
    Ok(out)
}

/// The probability threshold (0.05 to 0.95 in steps of 0.05) with the
/// best accuracy on `val`; ties go to the one nearest 0.5.
pub fn best_threshold(probs: &[f32], truth: &[bool]) -> (f64, f64) {
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
    device: &Device,
) -> Result<(f64, f64)> {
    let (mut art, model) = DetectorArtifact::load(out, device)?;
    let p = predict(&model, data, val, &art.stats, 64, device)?;
    let truth: Vec<bool> = val.iter().map(|&i| data.tendon[i]).collect();
    let (t, acc) = best_threshold(&p, &truth);
    art.threshold = t;
    art.save(&model, out)?;
    Ok((t, acc))
}

/// Train on `train`, validate on `val`; the best model goes to `out`.
pub fn train_detector(
    config: &DetectorTrainingConfig,
    data: &DetectionSet,
    (train, val): (&[usize], &[usize]),
    out: &Path,
    device: &Device,
    resume: bool,
    notes: serde_json::Value,
) -> Result<FitSummary> {
    if train.is_empty() || val.is_empty() {
        return Err(Error::Invalid(format!(
            "need training and validation frames (got {} and {})",
            train.len(),
            val.len()
        )));
    }
    let [w, h] = config.detector.input_size;
    if (data.width, data.height) != (w, h) {
        return Err(Error::Invalid(format!(
            "frames were loaded at {}x{}, the detector takes {w}x{h}",
            data.width, data.height
        )));
    }
    let stats = ChannelStats::from_images(
        train
            .iter()
            .map(|&i| data.image(i))
            .collect::<Vec<_>>()
            .iter(),
    )?;
    let labels: Vec<bool> = train.iter().map(|&i| data.tendon[i]).collect();
    let weights = class_weights(&labels);
    let artifact = DetectorArtifact {
        detector: config.detector.clone(),
        stats: stats.clone(),
        threshold: 0.5,
        notes,
    };
    let ad = device.clone().autodiff();
    ad.seed(config.seed);
    let model = config.detector.init(&ad);
    let fit_cfg = FitConfig {
        max_epochs: config.max_epochs,
        patience: config.patience,
        batch_size: config.batch_size,
        learning_rate: config.learning_rate,
        seed: config.seed,
        title: "detector training (class-weighted BCE)".into(),
        checkpoint_every: 1,
        lr_decay: config.lr_decay,
    };
    let val_truth: Vec<bool> = val.iter().map(|&i| data.tendon[i]).collect();
    let (_, summary) = fit(
        &fit_cfg,
        model,
        burn::optim::AdamConfig::new().init(),
        train,
        out,
        resume,
        |m: &Detector, batch, _| {
            let x = data.batch(batch, &stats, &ad)?;
            let y = data.targets(batch, config.soft_labels.as_ref(), &ad);
            Ok(weighted_bce(m.forward(x), y, weights))
        },
        |m| {
            let p = predict(m, data, val, &stats, 64, device)?;
            // Validation loss with the same class weights, from probabilities.
            let logits: Vec<f32> = p
                .iter()
                .map(|&q| {
                    let q = q.clamp(1e-7, 1.0 - 1e-7);
                    (q / (1.0 - q)).ln()
                })
                .collect();
            let z = Tensor::<2>::from_data(TensorData::new(logits, [val.len(), 1]), device);
            let loss: f32 = weighted_bce(z, data.labels(val, device), weights).into_scalar();
            let pred: Vec<bool> = p.iter().map(|&q| q as f64 >= 0.5).collect();
            let acc = tactile_core::metrics::binary_scores(&pred, &val_truth).accuracy;
            Ok((loss as f64, Some(acc)))
        },
        |m| artifact.save(m, out),
    )?;
    tactile_core::io::write_json_atomic(
        out.join("training.json"),
        &serde_json::json!({ "config": config, "summary": summary, "train_frames": train.len(), "val_frames": val.len() }),
    )?;
    Ok(summary)
}
