//! Training the autoencoder: Adadelta, stable BCE, batch 256, early
//! stopping on validation loss, best checkpoint kept, resumable.

use std::path::Path;

use burn::config::Config;
use burn::optim::ModuleOptimizer;
use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_core::nn::bce_with_logits;
use tactile_core::optim::AdadeltaConfig;
use tactile_core::train::{FitConfig, fit};
use tactile_core::{Error, Result};

use crate::artifact::CaeArtifact;
use crate::data::PinSet;
use crate::model::{Cae, CaeConfig};

/// Training settings; defaults are paper A's except the epoch budget.
#[derive(Config, Debug)]
pub struct CaeTrainingConfig {
    pub cae: CaeConfig,
    #[config(default = 256)]
    pub batch_size: usize,
    /// Paper: up to 10 000.
    #[config(default = 3000)]
    pub max_epochs: usize,
    /// Paper: 300 (the released script: 6000).
    #[config(default = 300)]
    pub patience: usize,
    /// Adadelta learning rate (Keras default 1.0).
    #[config(default = 1.0)]
    pub learning_rate: f64,
    pub optimizer: AdadeltaConfig,
    /// `adadelta` (paper A) or `adam` (converges in far fewer epochs on 2 cores).
    #[config(default = "String::from(\"adadelta\")")]
    pub optimizer_kind: String,
    #[config(default = 42)]
    pub seed: u64,
}

/// What a run ended with.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrainSummary {
    pub epochs_run: usize,
    pub best_epoch: usize,
    pub best_val_loss: f64,
    pub seconds: f64,
    pub train_frames: usize,
    pub val_frames: usize,
}

fn mean_loss(model: &Cae, data: &PinSet, idx: &[usize], batch: usize, device: &Device) -> f64 {
    let mut total = 0.0;
    for chunk in idx.chunks(batch.max(1)) {
        let x = data.batch(chunk, device);
        let l: f32 = bce_with_logits(model.forward_logits(x.clone()), x).into_scalar();
        total += l as f64 * chunk.len() as f64;
    }
    total / idx.len().max(1) as f64
}

/// Train on the `(train, validation)` indices of `data`, write everything into `out`.
///
/// `out` receives `cae.json`/`cae.bpk` (best model), `curves.csv`/`curves.png`,
/// `training.json`, and `checkpoint/` (last epoch: model, optimiser and
/// early-stopping state). With `resume`, training continues from that
/// checkpoint and gives the same result as an uninterrupted run.
pub fn train_cae(
    config: &CaeTrainingConfig,
    artifact: CaeArtifact,
    data: &PinSet,
    (train, val): (&[usize], &[usize]),
    out: &Path,
    device: &Device,
    resume: bool,
) -> Result<TrainSummary> {
    if train.is_empty() || val.is_empty() {
        return Err(Error::Invalid(format!(
            "need both training and validation frames (got {} and {})",
            train.len(),
            val.len()
        )));
    }
    let ad = device.clone().autodiff();
    // Seeded initial weights: the same config gives the same run.
    ad.seed(config.seed);
    let model = config.cae.init(&ad);
    let optim: ModuleOptimizer = match config.optimizer_kind.as_str() {
        "adadelta" => config.optimizer.init(),
        "adam" => burn::optim::AdamConfig::new().init(),
        other => {
            return Err(Error::Config(format!(
                "unknown optimizer '{other}': expected adadelta or adam"
            )));
        }
    };
    let fit_cfg = FitConfig {
        max_epochs: config.max_epochs,
        patience: config.patience,
        batch_size: config.batch_size,
        learning_rate: config.learning_rate,
        seed: config.seed,
        title: "CAE training (binary cross-entropy)".into(),
        checkpoint_every: 25,
        lr_decay: 1.0,
    };
    let (_, s) = fit(
        &fit_cfg,
        model,
        optim,
        train,
        out,
        resume,
        |m: &Cae, batch, _| {
            let x = data.batch(batch, &ad);
            Ok(bce_with_logits(m.forward_logits(x.clone()), x))
        },
        |m| Ok((mean_loss(m, data, val, config.batch_size, device), None)),
        |m| artifact.save(m, out),
    )?;
    let summary = TrainSummary {
        epochs_run: s.epochs_run,
        best_epoch: s.best_epoch,
        best_val_loss: s.best_val_loss,
        seconds: s.seconds,
        train_frames: train.len(),
        val_frames: val.len(),
    };
    tactile_core::io::write_json_atomic(
        out.join("training.json"),
        &serde_json::json!({
            "config": config,
            "summary": summary,
        }),
    )?;
    Ok(summary)
}
