//! Training the autoencoder: Adadelta, stable BCE, batch 256, early
//! stopping on validation loss, best checkpoint kept, resumable.

use std::path::{Path, PathBuf};
use std::time::Instant;

use burn::config::Config;
use burn::module::Module;
use burn::optim::{GradientsParams, ModuleOptimizer};
use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_core::nn::bce_with_logits;
use tactile_core::optim::AdadeltaConfig;
use tactile_core::train::{
    EarlyStopping, EpochRecord, TrainingLog, Verdict, ensure_finite, progress_bar, shuffled_batches,
};
use tactile_core::{Error, Result};

use crate::artifact::{CaeArtifact, load_module, save_module};
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

#[derive(Serialize, Deserialize)]
struct CheckpointState {
    next_epoch: usize,
    early: EarlyStopping,
    log: TrainingLog,
    elapsed_s: f64,
}

const CKPT_DIR: &str = "checkpoint";

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
    tactile_core::io::create_dir_all(out)?;
    let ckpt: PathBuf = out.join(CKPT_DIR);
    let ad = device.clone().autodiff();
    // Seeded initial weights: the same config gives the same run.
    ad.seed(config.seed);
    let mut model = config.cae.init(&ad);
    let mut optim: ModuleOptimizer = match config.optimizer_kind.as_str() {
        "adadelta" => config.optimizer.init(),
        "adam" => burn::optim::AdamConfig::new().init(),
        other => {
            return Err(Error::Config(format!(
                "unknown optimizer '{other}': expected adadelta or adam"
            )));
        }
    };
    let mut state = CheckpointState {
        next_epoch: 0,
        early: EarlyStopping::new(config.patience),
        log: TrainingLog::default(),
        elapsed_s: 0.0,
    };
    if resume {
        let st = ckpt.join("state.json");
        if !st.is_file() {
            return Err(Error::model(
                &st,
                "nothing to resume: no checkpoint in the output folder",
            ));
        }
        state = tactile_core::io::read_json(&st)?;
        model = load_module(model, &ckpt.join("model.bpk"))?;
        let opt_path = ckpt.join("optim.bpk");
        optim = optim
            .load(&opt_path)
            .map_err(|e| Error::model(&opt_path, format!("cannot load optimiser state: {e}")))?;
    }
    let start = Instant::now();
    let pb = progress_bar(config.max_epochs as u64, "train cae");
    pb.set_position(state.next_epoch as u64);
    let mut epoch = state.next_epoch;
    while epoch < config.max_epochs {
        let t0 = Instant::now();
        let mut train_total = 0.0;
        for batch in shuffled_batches(
            train,
            config.batch_size,
            config.seed.wrapping_add(epoch as u64),
        ) {
            let x = data.batch(&batch, &ad);
            let loss = bce_with_logits(model.forward_logits(x.clone()), x);
            let l: f32 = loss.clone().into_scalar();
            train_total += l as f64 * batch.len() as f64;
            let grads = GradientsParams::from_grads(loss.backward(), &model);
            model = optim.step(config.learning_rate, model, grads);
        }
        let train_loss = ensure_finite("training loss", train_total / train.len() as f64)?;
        let valid = model.valid();
        let val_loss = mean_loss(&valid, data, val, config.batch_size, device);
        state.log.epochs.push(EpochRecord {
            epoch,
            train_loss,
            val_loss,
            seconds: t0.elapsed().as_secs_f64(),
        });
        let verdict = state.early.update(epoch, val_loss);
        if verdict == Verdict::Improved {
            artifact.save(&valid, out)?;
        }
        epoch += 1;
        state.next_epoch = epoch;
        pb.set_position(epoch as u64);
        pb.set_message(format!(
            "loss {train_loss:.4} val {val_loss:.4} best {:.4}@{}",
            state.early.best, state.early.best_epoch
        ));
        let last = verdict == Verdict::Stop || epoch == config.max_epochs;
        if last || epoch.is_multiple_of(25) {
            state.elapsed_s += start.elapsed().as_secs_f64();
            write_checkpoint(&ckpt, &model, &optim, &state)?;
            state.elapsed_s -= start.elapsed().as_secs_f64();
            state.log.save(out, "CAE training (binary cross-entropy)")?;
        }
        if verdict == Verdict::Stop {
            break;
        }
    }
    pb.finish_and_clear();
    let summary = TrainSummary {
        epochs_run: state.next_epoch,
        best_epoch: state.early.best_epoch,
        best_val_loss: state.early.best,
        seconds: state.elapsed_s + start.elapsed().as_secs_f64(),
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

fn write_checkpoint(
    dir: &Path,
    model: &Cae,
    optim: &ModuleOptimizer,
    state: &CheckpointState,
) -> Result<()> {
    tactile_core::io::create_dir_all(dir)?;
    save_module(model, &dir.join("model.bpk"))?;
    let opt_path = dir.join("optim.bpk");
    let bytes = optim
        .into_bytes()
        .map_err(|e| Error::model(&opt_path, format!("cannot serialise optimiser state: {e}")))?;
    tactile_core::io::write_atomic(&opt_path, &bytes)?;
    tactile_core::io::write_json_atomic(dir.join("state.json"), state)
}
