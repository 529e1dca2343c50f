//! Training the U-Net: BCE + Dice on logits (stable for thin masks), Adam,
//! mean IoU on the validation windows each epoch, best model kept, resumable.

use std::path::Path;

use burn::config::Config;
use burn::tensor::Device;
use tactile_core::nn::{bce_with_logits, dice_loss_with_logits};
use tactile_core::train::{FitConfig, FitSummary, fit};
use tactile_core::{Error, Result};
use tactile_preprocess::visuo::ChannelStats;

use crate::{PostprocessConfig, SegmentSet, SegmenterArtifact, UNet, UNetConfig};

#[derive(Config, Debug)]
pub struct SegmenterTrainingConfig {
    pub unet: UNetConfig,
    /// Paper B: 16.
    #[config(default = 16)]
    pub batch_size: usize,
    /// Paper B: 26.
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
}

/// Probabilities of the windows at `idx`.
pub fn predict(
    model: &UNet,
    data: &SegmentSet,
    idx: &[usize],
    stats: &ChannelStats,
    device: &Device,
) -> Result<Vec<Vec<f32>>> {
    let mut out = Vec::with_capacity(idx.len());
    for chunk in idx.chunks(32) {
        let (x, _) = data.batch(chunk, stats, device)?;
        out.extend(model.probabilities(x)?);
    }
    Ok(out)
}

/// Mean IoU of predictions thresholded at `t` against the windows' masks.
pub fn mean_iou(data: &SegmentSet, idx: &[usize], probs: &[Vec<f32>], t: f32) -> f64 {
    let ious: Vec<f64> = idx
        .iter()
        .zip(probs)
        .map(|(&i, p)| {
            let pred: Vec<bool> = p.iter().map(|&v| v >= t).collect();
            tactile_core::metrics::iou(&pred, &data.windows[i].mask)
        })
        .collect();
    ious.iter().sum::<f64>() / ious.len().max(1) as f64
}

/// Train on the windows `train`, validate on the windows of `val`.
pub fn train_segmenter(
    config: &SegmenterTrainingConfig,
    train_set: &SegmentSet,
    val_set: &SegmentSet,
    out: &Path,
    device: &Device,
    resume: bool,
    notes: serde_json::Value,
) -> Result<FitSummary> {
    if train_set.is_empty() || val_set.is_empty() {
        return Err(Error::Invalid(format!(
            "need training and validation windows (got {} and {})",
            train_set.len(),
            val_set.len()
        )));
    }
    let images: Vec<_> = (0..train_set.len()).map(|i| train_set.image(i)).collect();
    let stats = ChannelStats::from_images(images.iter())?;
    drop(images);
    let artifact = SegmenterArtifact {
        unet: config.unet.clone(),
        stats: stats.clone(),
        threshold: 0.5,
        postprocess: PostprocessConfig::default(),
        notes,
    };
    let ad = device.clone().autodiff();
    ad.seed(config.seed);
    let model = config.unet.init(&ad)?;
    let fit_cfg = FitConfig {
        max_epochs: config.max_epochs,
        patience: config.patience,
        batch_size: config.batch_size,
        learning_rate: config.learning_rate,
        seed: config.seed,
        title: "segmenter training (BCE + Dice)".into(),
        checkpoint_every: 1,
        lr_decay: config.lr_decay,
    };
    let train: Vec<usize> = (0..train_set.len()).collect();
    let val: Vec<usize> = (0..val_set.len()).collect();
    let (_, summary) = fit(
        &fit_cfg,
        model,
        burn::optim::AdamConfig::new().init(),
        &train,
        out,
        resume,
        |m: &UNet, batch, _| {
            let (x, y) = train_set.batch(batch, &stats, &ad)?;
            let z = m.forward(x);
            Ok(bce_with_logits(z.clone(), y.clone()) + dice_loss_with_logits(z, y))
        },
        |m| {
            let (mut loss, mut n) = (0.0, 0usize);
            let mut probs = Vec::with_capacity(val.len());
            for chunk in val.chunks(32) {
                let (x, y) = val_set.batch(chunk, &stats, device)?;
                let z = m.forward(x);
                let l: f32 = (bce_with_logits(z.clone(), y.clone())
                    + dice_loss_with_logits(z.clone(), y))
                .into_scalar();
                loss += l as f64 * chunk.len() as f64;
                n += chunk.len();
                let [b, _, h, w] = z.dims();
                let p = burn::tensor::activation::sigmoid(z)
                    .into_data()
                    .try_to_vec::<f32>()
                    .map_err(|e| Error::Invalid(format!("{e:?}")))?;
                probs.extend(p.chunks(h * w).take(b).map(<[f32]>::to_vec));
            }
            Ok((
                loss / n.max(1) as f64,
                Some(mean_iou(val_set, &val, &probs, 0.5)),
            ))
        },
        |m| artifact.save(m, out),
    )?;
    tactile_core::io::write_json_atomic(
        out.join("training.json"),
        &serde_json::json!({ "config": config, "summary": summary, "train_windows": train_set.len(), "val_windows": val_set.len() }),
    )?;
    Ok(summary)
}
