//! Training the depth network: L1, MSE or L1 + gradient + SSIM on depth in
//! model units, Adam with a decaying rate, validation MAE (mm, inside the
//! window) each epoch, best model kept, resumable.

use std::path::Path;

use burn::config::Config;
use burn::tensor::{Device, Tensor};
use tactile_core::nn::{gradient_loss, l1_loss, mse_loss, ssim_loss};
use tactile_core::train::{FitConfig, FitSummary, fit};
use tactile_core::{Error, Result};
use tactile_preprocess::visuo::ChannelStats;

use crate::{
    DEPTH_RANGE_MM, DepthArtifact, DepthNet, DepthNetConfig, DepthScale, DepthScorer, DepthScores,
    DepthSet, LossKind,
};

#[derive(Config, Debug)]
pub struct DepthTrainingConfig {
    pub net: DepthNetConfig,
    #[config(default = "LossKind::L1")]
    pub loss: LossKind,
    /// Paper B: 8.
    #[config(default = 8)]
    pub batch_size: usize,
    #[config(default = 20)]
    pub max_epochs: usize,
    #[config(default = 4)]
    pub patience: usize,
    #[config(default = 1e-3)]
    pub learning_rate: f64,
    #[config(default = 0.9)]
    pub lr_decay: f64,
    /// Millimetres per model unit (1: millimetres, paper B's fix; 1000: metres).
    #[config(default = 1.0)]
    pub unit_mm: f32,
    /// Feed the tendon mask as a fourth channel.
    #[config(default = false)]
    pub with_mask: bool,
    /// Train the decoder only.
    #[config(default = false)]
    pub freeze_encoder: bool,
    /// torchvision DenseNet weights (safetensors, see [`crate::torchvision`])
    /// to start the encoder from.
    #[config(default = "None")]
    pub pretrained: Option<String>,
    #[config(default = 42)]
    pub seed: u64,
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

/// Predicted depth in mm, one `H*W` map per sample of `idx`.
pub fn predict_mm(
    model: &DepthNet,
    art: &DepthArtifact,
    data: &DepthSet,
    idx: &[usize],
    device: &Device,
) -> Result<Vec<Vec<f32>>> {
    let hw = data.width * data.height;
    let mut out = Vec::with_capacity(idx.len());
    for chunk in idx.chunks(16) {
        let (x, _) = data.batch(chunk, &art.stats, &art.scale, art.with_mask, device)?;
        let v = model
            .forward(x)
            .into_data()
            .try_to_vec::<f32>()
            .map_err(|e| Error::Invalid(format!("depth output: {e:?}")))?;
        out.extend(
            v.chunks(hw)
                .map(|c| c.iter().map(|&m| art.scale.to_mm(m)).collect::<Vec<_>>()),
        );
    }
    Ok(out)
}

/// Score a model on every sample of `data`.
pub fn evaluate(
    model: &DepthNet,
    art: &DepthArtifact,
    data: &DepthSet,
    device: &Device,
) -> Result<DepthScores> {
    let idx: Vec<usize> = (0..data.len()).collect();
    let preds = predict_mm(model, art, data, &idx, device)?;
    let mut sc = DepthScorer::default();
    for (i, p) in preds.iter().enumerate() {
        let s = &data.samples[i];
        sc.add(
            p,
            &s.depth_mm,
            &data.window,
            &s.mask,
            (data.width, data.height),
        );
    }
    Ok(sc.finish())
}

/// Train on `train_set`, validate on `val_set`; the best model goes to `out`.
pub fn train_depth(
    config: &DepthTrainingConfig,
    train_set: &DepthSet,
    val_set: &DepthSet,
    out: &Path,
    device: &Device,
    resume: bool,
    notes: serde_json::Value,
) -> Result<FitSummary> {
    if train_set.is_empty() || val_set.is_empty() {
        return Err(Error::Invalid(format!(
            "need training and validation frames (got {} and {})",
            train_set.len(),
            val_set.len()
        )));
    }
    if !(config.unit_mm.is_finite() && config.unit_mm > 0.0) {
        return Err(Error::Config(format!(
            "unit_mm must be positive, got {}",
            config.unit_mm
        )));
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
        return Err(Error::Config(format!(
            "the depth targets vary by only {std_units:.2e} model units ({std_mm:.3} mm at {} mm per unit): \
             the loss would barely move and training would stall; use millimetres (unit 1 mm)",
            config.unit_mm
        )));
    }
    let mut net = config.net.clone();
    net.in_channels = 3 + config.with_mask as usize;
    let artifact = DepthArtifact {
        net: net.clone(),
        stats: stats.clone(),
        scale,
        with_mask: config.with_mask,
        notes,
    };
    let ad = device.clone().autodiff();
    ad.seed(config.seed);
    let mut model = net.init(&ad)?;
    if let Some(p) = &config.pretrained {
        model.encoder = crate::torchvision::load_torchvision_encoder(p, model.encoder, &ad)?;
    }
    if config.freeze_encoder {
        model = model.freeze_encoder();
    }
    let range = DEPTH_RANGE_MM / config.unit_mm as f64;
    let fit_cfg = FitConfig {
        max_epochs: config.max_epochs,
        patience: config.patience,
        batch_size: config.batch_size,
        learning_rate: config.learning_rate,
        seed: config.seed,
        title: format!("depth training ({:?})", config.loss),
        checkpoint_every: 1,
        lr_decay: config.lr_decay,
    };
    let train: Vec<usize> = (0..train_set.len()).collect();
    let (_, summary) = fit(
        &fit_cfg,
        model,
        burn::optim::AdamConfig::new().init(),
        &train,
        out,
        resume,
        |m: &DepthNet, batch, _| {
            let (x, y) = train_set.batch(batch, &stats, &scale, config.with_mask, &ad)?;
            Ok(depth_loss(config.loss, m.forward(x), y, range))
        },
        |m| {
            let (mut loss, mut k) = (0.0, 0usize);
            for chunk in (0..val_set.len()).collect::<Vec<_>>().chunks(16) {
                let (x, y) = val_set.batch(chunk, &stats, &scale, config.with_mask, device)?;
                let l: f32 = depth_loss(config.loss, m.forward(x), y, range).into_scalar();
                loss += l as f64 * chunk.len() as f64;
                k += chunk.len();
            }
            let sc = evaluate(m, &artifact, val_set, device)?;
            Ok((loss / k.max(1) as f64, Some(sc.mae_mm)))
        },
        |m| artifact.save(m, out),
    )?;
    tactile_core::io::write_json_atomic(
        out.join("training.json"),
        &serde_json::json!({ "config": config, "summary": summary, "train_frames": train_set.len(), "val_frames": val_set.len() }),
    )?;
    Ok(summary)
}
