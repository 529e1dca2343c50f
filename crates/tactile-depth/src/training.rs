//! Training the depth network: L1, MSE or L1 + gradient + SSIM on depth in
//! model units, Adam with a decaying rate, validation MAE (mm, inside the
//! window) each epoch, best model kept, resumable. Files hold metres; the
//! network works in millimetres around the training mean (metres stalled
//! paper B's training: the targets barely vary, which is refused here).

use std::path::Path;

use burn::config::Config;
use burn::tensor::Tensor;
use serde::{Deserialize, Serialize};
use tactile_burn::nn::{gradient_loss, l1_loss, mse_loss, ssim_loss};
use tactile_burn::train::{FitConfig, FitSummary, Schedule, fit};
use tactile_burn::{Artifact, DeviceKind};
use tactile_core::dataset::{Dataset, Provenance};
use tactile_detect::augment::PhotometricAugment;
use tactile_preprocess::visuo::ChannelStats;

use crate::artifact::{DepthArtifact, DepthScale};
use crate::eval::{DEPTH_RANGE_MM, score};
use crate::model::{DenseNetConfig, DepthNet, DepthNetConfig};
use crate::{DepthSet, Error, Result};

/// Which loss trains the network.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum LossKind {
    /// Mean absolute error (paper B).
    L1,
    /// Mean squared error.
    Mse,
    /// L1 + gradient + SSIM (DenseTact).
    L1GradSsim,
}

impl std::str::FromStr for LossKind {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "l1" => Ok(Self::L1),
            "mse" => Ok(Self::Mse),
            "l1-grad-ssim" => Ok(Self::L1GradSsim),
            o => Err(tactile_core::Error::Config(format!(
                "unknown loss '{o}': expected l1, mse or l1-grad-ssim"
            ))
            .into()),
        }
    }
}

/// Everything a depth network's training is set by.
#[derive(Config, Debug)]
pub struct DepthTrainingConfig {
    /// Encoder, input size (paper B: 256x256), decoder and head.
    #[config(default = "DepthNetConfig::new(DenseNetConfig::small(), [160, 96])")]
    pub model: DepthNetConfig,
    /// Paper B: batch 8.
    #[config(default = "Schedule::new(8, 12, 3, 1e-3).with_lr_decay(0.9)")]
    pub schedule: Schedule,
    /// The loss.
    #[config(default = "LossKind::L1")]
    pub loss: LossKind,
    /// Millimetres per model unit (1: millimetres, paper B's fix; 1000: metres).
    #[config(default = 1.0)]
    pub unit_mm: f32,
    /// Feed the ground-truth tendon mask as a fourth channel.
    #[config(default = false)]
    pub with_mask: bool,
    /// Train the decoder only.
    #[config(default = false)]
    pub freeze_encoder: bool,
    /// torchvision DenseNet weights (safetensors, see [`crate::torchvision`])
    /// to start the encoder from.
    #[config(default = "None")]
    pub pretrained: Option<String>,
    /// Fraction of the sequences that validate.
    #[config(default = 0.2)]
    pub val_fraction: f64,
    /// A sensor calibration folder: the network takes its reconstruction
    /// of each frame as a fourth channel and learns a correction to it
    /// ([`crate::prior`]).
    #[config(default = "None")]
    pub prior_calibration: Option<String>,
    /// Photometric augmentation of the training frames' colour channels
    /// (None: off). A prior or mask channel is not changed: the colours
    /// vary, what the calibration reconstructed of the frame does not.
    #[config(default = "None")]
    pub augment: Option<PhotometricAugment>,
}

/// The loss of `kind` on model-unit depth maps.
pub fn depth_loss(kind: LossKind, pred: Tensor<4>, target: Tensor<4>, range: f64) -> Tensor<1> {
    match kind {
        LossKind::L1 => l1_loss(pred, target),
        LossKind::Mse => mse_loss(pred, target),
        LossKind::L1GradSsim => {
            l1_loss(pred.clone(), target.clone())
                + gradient_loss(pred.clone(), target.clone())
                + ssim_loss(pred, target, range)
        }
    }
}

/// Predicted depth in mm of the samples at `idx`, straight from the module.
fn predict_mm(
    model: &DepthNet,
    art: &DepthArtifact,
    data: &DepthSet,
    device: &burn::tensor::Device,
) -> Result<Vec<Vec<f32>>> {
    let hw = data.width * data.height;
    let idx: Vec<usize> = (0..data.len()).collect();
    let mut out = Vec::with_capacity(idx.len());
    for chunk in idx.chunks(crate::eval::EVAL_BATCH) {
        let (x, _) = data.batch(chunk, &art.stats, &art.scale, &art.model, device)?;
        let v = model
            .forward(x)
            .into_data()
            .try_to_vec::<f32>()
            .map_err(|e| tactile_core::Error::Invalid(format!("depth output: {e:?}")))?;
        out.extend(
            v.chunks(hw)
                .map(|c| c.iter().map(|&m| art.scale.to_mm(m)).collect::<Vec<_>>()),
        );
    }
    Ok(out)
}

/// Train on `data` (split by sequence) into `out`.
pub fn train(
    config: &DepthTrainingConfig,
    data: &Dataset,
    out: &Path,
    device: DeviceKind,
    resume: bool,
) -> Result<FitSummary> {
    config.schedule.check()?;
    if let Some(a) = &config.augment {
        a.check()?;
    }
    let prior_dir = config
        .prior_calibration
        .as_ref()
        .map(std::path::PathBuf::from);
    if config.with_mask && prior_dir.is_some() {
        return Err(tactile_core::Error::Config(
            "a depth network takes the tendon mask or a calibration prior as its fourth channel, not both".into(),
        )
        .into());
    }
    let mut net = config.model.clone();
    net.in_channels = 3 + usize::from(config.with_mask || prior_dir.is_some());
    net.residual_channel = prior_dir.as_ref().map(|_| 3);
    net.check()?;
    if !(config.unit_mm.is_finite() && config.unit_mm > 0.0) {
        return Err(tactile_core::Error::Config(format!(
            "unit_mm must be positive, got {:?}",
            config.unit_mm
        ))
        .into());
    }
    <crate::DepthArtifact as tactile_burn::Artifact>::check_out_dir(out, &[data])?;
    let warnings: Vec<String> = prior_dir
        .as_deref()
        .and_then(|dir| crate::prior::other_sensor_warning(data, dir))
        .into_iter()
        .collect();
    for w in &warnings {
        tactile_core::note!("warning: {w}");
    }
    let (train, val) = data.split_by_sequence(config.val_fraction, config.schedule.seed)?;
    let [w, h] = net.input_size;
    tactile_core::note!(
        "loading {} frames at {w}x{h} ({} train, {} validation, split by sequence)",
        data.len(),
        train.len(),
        val.len()
    );
    let (train_set, val_set) =
        DepthSet::from_splits(data, &train, &val, [w, h], prior_dir.as_deref())?;
    if train_set.is_empty() || val_set.is_empty() {
        return Err(tactile_core::Error::Invalid(format!(
            "need training and validation frames (got {} and {})",
            train_set.len(),
            val_set.len()
        ))
        .into());
    }
    let images: Vec<_> = (0..train_set.len()).map(|i| train_set.image(i)).collect();
    let stats = ChannelStats::from_images(images.iter())?;
    drop(images);
    let (mut sum, mut sq, mut n) = (0.0f64, 0.0f64, 0usize);
    for s in &train_set.samples {
        for &d in &s.depth_mm {
            sum += d as f64;
            sq += (d as f64).powi(2);
            n += 1;
        }
    }
    let mean = sum / n.max(1) as f64;
    let std_mm = (sq / n.max(1) as f64 - mean * mean).max(0.0).sqrt();
    let scale = DepthScale {
        offset_mm: mean as f32,
        unit_mm: config.unit_mm,
    };
    // Paper B's stall, caught instead of silently training: in metres the
    // targets vary by about a thousandth of a unit.
    let std_units = std_mm / config.unit_mm as f64;
    if std_units < 1e-2 {
        return Err(Error::Stall {
            std_units,
            std_mm,
            unit_mm: config.unit_mm,
        });
    }
    let artifact = DepthArtifact {
        model: net.clone(),
        stats: stats.clone(),
        scale,
        with_mask: config.with_mask,
        prior: prior_dir
            .as_deref()
            .map(|d| crate::prior::CalibrationPrior::of(d, out)),
        depth_maps: train_set.depth_maps,
        // Split by sequence, the split column aside: it fits every split.
        notes: Provenance::of(&[data])
            .every_split(true)
            .notes(serde_json::json!({
                "device": device.name(),
                "encoder": crate::DenseNetPreset::of(&net.encoder).map_or("custom", |p| p.name()),
            })),
    };
    let dev = device.device();
    let ad = dev.clone().autodiff();
    ad.seed(config.schedule.seed);
    let mut model = net.init(&ad)?;
    if let Some(p) = &config.pretrained {
        model.encoder = crate::torchvision::load_torchvision_encoder(p, model.encoder, &ad)?;
    }
    if config.freeze_encoder {
        if config.pretrained.is_none() {
            tactile_core::note!(
                "warning: freeze_encoder without pretrained weights: only the decoder trains, on the features of an encoder left as initialised (seed {}); give pretrained to start it from torchvision's weights",
                config.schedule.seed
            );
        }
        model = model.freeze_encoder();
    }
    let range = DEPTH_RANGE_MM / config.unit_mm as f64;
    let fit_cfg = FitConfig::new(
        &config.schedule,
        format!("depth training ({:?})", config.loss),
    )
    .saving_to(out, resume)
    .with_run_id(tactile_burn::artifact::run_fingerprint(config, &[data])?);
    let unfinished = tactile_burn::artifact::Unfinished::begin(out)?;
    let train_idx: Vec<usize> = (0..train_set.len()).collect();
    let (_, mut summary) = fit::<_, Error>(
        &fit_cfg,
        model,
        burn::optim::AdamConfig::new().init(),
        (&train_idx, val_set.len()),
        |m: &DepthNet, batch, epoch| {
            let (x, y) = match &config.augment {
                Some(a) => train_set.augmented_batch(
                    batch,
                    &stats,
                    &scale,
                    &net,
                    (a, (config.schedule.seed, epoch as u64 + 1)),
                    &ad,
                )?,
                None => train_set.batch(batch, &stats, &scale, &net, &ad)?,
            };
            Ok(depth_loss(config.loss, m.forward(x), y, range))
        },
        |m| {
            let (mut loss, mut k) = (0.0, 0usize);
            for chunk in (0..val_set.len()).collect::<Vec<_>>().chunks(16) {
                let (x, y) = val_set.batch(chunk, &stats, &scale, &net, &dev)?;
                let l: f32 = depth_loss(config.loss, m.forward(x), y, range).into_scalar();
                loss += l as f64 * chunk.len() as f64;
                k += chunk.len();
            }
            let preds = predict_mm(m, &artifact, &val_set, &dev)?;
            Ok((loss / k.max(1) as f64, Some(score(&val_set, &preds).mae_mm)))
        },
        |m| Ok(artifact.save(m, out)?),
    )?;
    summary.warnings = warnings;
    tactile_burn::artifact::write_training_record(
        out,
        config,
        &summary,
        serde_json::json!({ "train_frames": train_set.len(), "val_frames": val_set.len() }),
    )?;
    unfinished.finish()?;
    Ok(summary)
}
