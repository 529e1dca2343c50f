//! Training the U-Net: BCE + Dice on logits (stable for thin masks), Adam
//! with a decaying rate, mean IoU on the validation windows each epoch,
//! best model kept, resumable. Tendon frames are split by sequence and cut
//! into windows, the training ones as rotated copies (paper B's
//! augmentation).

use std::path::Path;

use burn::config::Config;
use burn::tensor::Device;
use tactile_burn::nn::{bce_with_logits, dice_loss_with_logits};
use tactile_burn::train::{FitConfig, FitSummary, Schedule, fit};
use tactile_burn::{Artifact, DeviceKind};
use tactile_core::dataset::{Dataset, Provenance};
use tactile_preprocess::visuo::ChannelStats;

use crate::{Error, PostprocessConfig, Result, SegmentSet, SegmenterArtifact, UNet, UNetConfig};

/// Everything a segmenter's training is set by.
#[derive(Config, Debug)]
pub struct SegmenterTrainingConfig {
    /// The U-Net and its window (paper B: a 160 px window).
    #[config(default = "UNetConfig::new().with_base(8).with_side(96)")]
    pub model: UNetConfig,
    /// Paper B: batch 16, 26 epochs.
    #[config(default = "Schedule::new(16, 15, 4, 1e-3).with_lr_decay(0.8)")]
    pub schedule: Schedule,
    /// Rotated copies of each training window.
    #[config(default = 4)]
    pub copies: usize,
    /// Fraction of the sequences that validate.
    #[config(default = 0.2)]
    pub val_fraction: f64,
}

/// Largest number of rotated copies per frame.
pub const MAX_COPIES: usize = 64;

/// Probabilities of the windows at `idx`, straight from the module.
fn predict(
    model: &UNet,
    data: &SegmentSet,
    idx: &[usize],
    stats: &ChannelStats,
    device: &Device,
) -> Result<(f64, Vec<Vec<f32>>)> {
    let (mut loss, mut n) = (0.0, 0usize);
    let mut probs = Vec::with_capacity(idx.len());
    for chunk in idx.chunks(32) {
        let (x, y) = data.batch(chunk, stats, device)?;
        let z = model.forward(x);
        let l: f32 = (bce_with_logits(z.clone(), y.clone()) + dice_loss_with_logits(z.clone(), y))
            .into_scalar();
        loss += l as f64 * chunk.len() as f64;
        n += chunk.len();
        let [b, _, h, w] = z.dims();
        let p = z
            .into_data()
            .try_to_vec::<f32>()
            .map_err(|e| tactile_core::Error::Invalid(format!("segmenter output: {e:?}")))?;
        let p: Vec<f32> = p.into_iter().map(tactile_burn::runtime::sigmoid).collect();
        probs.extend(p.chunks(h * w).take(b).map(<[f32]>::to_vec));
    }
    Ok((loss / n.max(1) as f64, probs))
}

/// Mean IoU of predictions thresholded at `t` against the windows' masks.
pub fn mean_iou(data: &SegmentSet, idx: &[usize], probs: &[Vec<f32>], t: f64) -> f64 {
    let ious: Vec<f64> = idx
        .iter()
        .zip(probs)
        .map(|(&i, p)| {
            let pred: Vec<bool> = p.iter().map(|&v| v as f64 >= t).collect();
            tactile_core::metrics::iou(&pred, &data.windows[i].mask)
        })
        .collect();
    ious.iter().sum::<f64>() / ious.len().max(1) as f64
}

/// Train on the tendon frames of `data` (split by sequence) into `out`.
pub fn train(
    config: &SegmenterTrainingConfig,
    data: &Dataset,
    out: &Path,
    device: DeviceKind,
    resume: bool,
) -> Result<FitSummary> {
    config.schedule.check()?;
    config.model.check()?;
    if config.copies == 0 || config.copies > MAX_COPIES {
        return Err(tactile_core::Error::Config(format!(
            "copies must be 1 to {MAX_COPIES}, got {}",
            config.copies
        ))
        .into());
    }
    <crate::SegmenterArtifact as tactile_burn::Artifact>::check_out_dir(out, &[data])?;
    let (train, val) = data.split_by_sequence(config.val_fraction, config.schedule.seed)?;
    let (train, val) = (data.tendon_rows(&train)?, data.tendon_rows(&val)?);
    if train.is_empty() || val.is_empty() {
        return Err(Error::NoTendonFrames {
            path: data.labels_path(),
            why: "train or validate on",
        });
    }
    let window = tactile_preprocess::visuo::SquareWindow {
        side: config.model.side,
    };
    tactile_core::note!(
        "cutting {0}x{0} windows: {1} training frames x {2} rotations, {3} validation frames",
        window.side,
        train.len(),
        config.copies,
        val.len()
    );
    let seed = config.schedule.seed;
    // Every frame's header before the first is decoded.
    data.check_frame_headers(&[train.as_slice(), val.as_slice()].concat())?;
    let train_set = SegmentSet::from_dataset(data, &train, window, config.copies, seed)?;
    let val_set = SegmentSet::from_dataset(data, &val, window, 1, seed)?;
    let images: Vec<_> = (0..train_set.len()).map(|i| train_set.image(i)).collect();
    let stats = ChannelStats::from_images(images.iter())?;
    drop(images);
    let artifact = SegmenterArtifact {
        model: config.model.clone(),
        stats: stats.clone(),
        threshold: 0.5,
        postprocess: PostprocessConfig::default(),
        // Split by sequence, the split column aside: it fits every split.
        notes: Provenance::of(&[data])
            .every_split(true)
            .notes(serde_json::json!({
                "device": device.name(),
                "copies": config.copies,
            })),
    };
    let dev = device.device();
    let ad = dev.clone().autodiff();
    ad.seed(seed);
    let model = config.model.init(&ad)?;
    let fit_cfg = FitConfig::new(&config.schedule, "segmenter training (BCE + Dice)")
        .saving_to(out, resume)
        .with_run_id(tactile_burn::artifact::run_fingerprint(config, &[data])?);
    let unfinished = tactile_burn::artifact::Unfinished::begin(out)?;
    let train_idx: Vec<usize> = (0..train_set.len()).collect();
    let val_idx: Vec<usize> = (0..val_set.len()).collect();
    let (_, summary) = fit::<_, Error>(
        &fit_cfg,
        model,
        burn::optim::AdamConfig::new().init(),
        (&train_idx, val_idx.len()),
        |m: &UNet, batch, _| {
            let (x, y) = train_set.batch(batch, &stats, &ad)?;
            let z = m.forward(x);
            Ok(bce_with_logits(z.clone(), y.clone()) + dice_loss_with_logits(z, y))
        },
        |m| {
            let (loss, probs) = predict(m, &val_set, &val_idx, &stats, &dev)?;
            Ok((loss, Some(mean_iou(&val_set, &val_idx, &probs, 0.5))))
        },
        |m| Ok(artifact.save(m, out)?),
    )?;
    tactile_burn::artifact::write_training_record(
        out,
        config,
        &summary,
        serde_json::json!({ "train_windows": train_set.len(), "val_windows": val_set.len() }),
    )?;
    unfinished.finish()?;
    Ok(summary)
}
