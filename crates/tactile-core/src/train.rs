//! Training bookkeeping shared by every model: early stopping, the curve
//! log (CSV + PNG), progress bars and seeded mini-batches.

use std::path::Path;

use indicatif::{ProgressBar, ProgressStyle};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand::seq::SliceRandom;
use serde::{Deserialize, Serialize};

use crate::plot::{Series, line_plot};
use crate::{Error, Result};

/// Early stopping on a validation loss, resumable (it is saved in checkpoints).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct EarlyStopping {
    pub patience: usize,
    pub best: f64,
    pub best_epoch: usize,
    pub epochs_since_best: usize,
}

/// What an epoch's validation loss means for training.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// New best: keep this model.
    Improved,
    /// No improvement, keep going.
    Continue,
    /// Patience exhausted: stop.
    Stop,
}

impl EarlyStopping {
    /// Stop after `patience` epochs without a new best.
    pub fn new(patience: usize) -> Self {
        Self {
            patience,
            best: f64::INFINITY,
            best_epoch: 0,
            epochs_since_best: 0,
        }
    }

    /// Record `epoch`'s validation loss. A NaN loss never counts as a best.
    pub fn update(&mut self, epoch: usize, val_loss: f64) -> Verdict {
        if val_loss.is_finite() && val_loss < self.best {
            self.best = val_loss;
            self.best_epoch = epoch;
            self.epochs_since_best = 0;
            Verdict::Improved
        } else {
            self.epochs_since_best += 1;
            if self.epochs_since_best >= self.patience {
                Verdict::Stop
            } else {
                Verdict::Continue
            }
        }
    }
}

/// One epoch of a training run.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct EpochRecord {
    pub epoch: usize,
    pub train_loss: f64,
    pub val_loss: f64,
    pub seconds: f64,
    /// The model's own validation metric (accuracy, IoU), when it has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub val_metric: Option<f64>,
}

/// The curves of a run, written as `curves.csv` and `curves.png`.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct TrainingLog {
    pub epochs: Vec<EpochRecord>,
}

impl TrainingLog {
    /// Write `curves.csv` and `curves.png` into `dir`.
    pub fn save(&self, dir: impl AsRef<Path>, title: &str) -> Result<()> {
        let dir = dir.as_ref();
        let csv_path = dir.join("curves.csv");
        crate::io::write_atomic_with(&csv_path, |w| {
            let metric = self.epochs.iter().any(|e| e.val_metric.is_some());
            writeln!(
                w,
                "epoch,train_loss,val_loss,seconds{}",
                if metric { ",val_metric" } else { "" }
            )?;
            for e in &self.epochs {
                write!(
                    w,
                    "{},{},{},{:.3}",
                    e.epoch, e.train_loss, e.val_loss, e.seconds
                )?;
                match (metric, e.val_metric) {
                    (true, Some(m)) => writeln!(w, ",{m}")?,
                    (true, None) => writeln!(w, ",")?,
                    _ => writeln!(w)?,
                }
            }
            Ok(())
        })?;
        if self.epochs.is_empty() {
            return Ok(());
        }
        let series = [
            Series {
                name: "train".into(),
                points: self
                    .epochs
                    .iter()
                    .map(|e| (e.epoch as f64, e.train_loss))
                    .collect(),
            },
            Series {
                name: "validation".into(),
                points: self
                    .epochs
                    .iter()
                    .map(|e| (e.epoch as f64, e.val_loss))
                    .collect(),
            },
        ];
        line_plot(
            dir.join("curves.png"),
            title,
            "epoch",
            "loss",
            &series,
            true,
        )
    }
}

/// Settings of [`fit`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FitConfig {
    pub max_epochs: usize,
    /// Epochs without a better validation loss before stopping.
    pub patience: usize,
    pub batch_size: usize,
    pub learning_rate: f64,
    /// Seeds the weights (by the caller) and each epoch's shuffle.
    pub seed: u64,
    /// Title of the curves plot and prefix of the progress bar.
    pub title: String,
    /// Save a resumable checkpoint every this many epochs (and at the end).
    pub checkpoint_every: usize,
    /// Learning rate of epoch `e` is `learning_rate * lr_decay^e` (1 = constant).
    #[serde(default = "one")]
    pub lr_decay: f64,
}

fn one() -> f64 {
    1.0
}

/// What a [`fit`] run ended with.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FitSummary {
    pub epochs_run: usize,
    pub best_epoch: usize,
    pub best_val_loss: f64,
    /// The validation metric of the best epoch.
    pub best_val_metric: Option<f64>,
    pub seconds: f64,
    pub train_items: usize,
}

impl FitSummary {
    /// One line for the command line: best epoch, its validation loss and
    /// metric (called `metric`), and the training time.
    pub fn describe(&self, metric: &str) -> String {
        format!(
            "best epoch {} of {}: validation loss {:.4}, {metric} {:.4}; {:.0} s",
            self.best_epoch,
            self.epochs_run,
            self.best_val_loss,
            self.best_val_metric.unwrap_or(f64::NAN),
            self.seconds
        )
    }
}

#[derive(Serialize, Deserialize)]
struct FitState {
    next_epoch: usize,
    early: EarlyStopping,
    log: TrainingLog,
    elapsed_s: f64,
}

/// The shared training loop: seeded shuffled mini-batches, one optimiser
/// step per batch on the loss `batch_loss` returns, validation each epoch
/// (`validate` gets the model without autodiff and returns the loss that
/// early stopping watches plus an optional metric), `save_best` on every
/// new best, `curves.csv`/`curves.png` and a resumable `checkpoint/` in
/// `out`. Resuming gives the same result as an uninterrupted run.
#[allow(clippy::too_many_arguments)]
pub fn fit<M: burn::module::Module>(
    cfg: &FitConfig,
    mut model: M,
    mut optim: burn::optim::ModuleOptimizer,
    train: &[usize],
    out: &Path,
    resume: bool,
    mut batch_loss: impl FnMut(&M, &[usize], usize) -> Result<burn::tensor::Tensor<1>>,
    mut validate: impl FnMut(&M) -> Result<(f64, Option<f64>)>,
    mut save_best: impl FnMut(&M) -> Result<()>,
) -> Result<(M, FitSummary)> {
    use burn::optim::GradientsParams;
    if train.is_empty() {
        return Err(Error::Invalid("no training items".into()));
    }
    crate::io::create_dir_all(out)?;
    let ckpt = out.join("checkpoint");
    let mut state = FitState {
        next_epoch: 0,
        early: EarlyStopping::new(cfg.patience),
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
        state = crate::io::read_json(&st)?;
        model = crate::module_io::load_module(model, &ckpt.join("model.bpk"))?;
        let opt_path = ckpt.join("optim.bpk");
        optim = optim
            .load(&opt_path)
            .map_err(|e| Error::model(&opt_path, format!("cannot load optimiser state: {e}")))?;
    }
    let start = std::time::Instant::now();
    let pb = progress_bar(cfg.max_epochs as u64, &cfg.title);
    pb.set_position(state.next_epoch as u64);
    let mut epoch = state.next_epoch;
    let mut best_metric = state
        .log
        .epochs
        .iter()
        .find(|e| e.epoch == state.early.best_epoch)
        .and_then(|e| e.val_metric);
    while epoch < cfg.max_epochs {
        let t0 = std::time::Instant::now();
        let mut total = 0.0;
        let lr = cfg.learning_rate * cfg.lr_decay.powi(epoch as i32);
        for batch in shuffled_batches(train, cfg.batch_size, cfg.seed.wrapping_add(epoch as u64)) {
            let loss = batch_loss(&model, &batch, epoch)?;
            let l: f32 = loss.clone().into_scalar();
            total += l as f64 * batch.len() as f64;
            let grads = GradientsParams::from_grads(loss.backward(), &model);
            model = optim.step(lr, model, grads);
        }
        let train_loss = ensure_finite("training loss", total / train.len() as f64)?;
        let valid = model.valid();
        let (val_loss, val_metric) = validate(&valid)?;
        state.log.epochs.push(EpochRecord {
            epoch,
            train_loss,
            val_loss,
            seconds: t0.elapsed().as_secs_f64(),
            val_metric,
        });
        let verdict = state.early.update(epoch, val_loss);
        if verdict == Verdict::Improved {
            save_best(&valid)?;
            best_metric = val_metric;
        }
        epoch += 1;
        state.next_epoch = epoch;
        pb.set_position(epoch as u64);
        pb.set_message(format!(
            "loss {train_loss:.4} val {val_loss:.4}{} best {:.4}@{}",
            val_metric.map(|m| format!(" ({m:.4})")).unwrap_or_default(),
            state.early.best,
            state.early.best_epoch
        ));
        let last = verdict == Verdict::Stop || epoch == cfg.max_epochs;
        if last || epoch.is_multiple_of(cfg.checkpoint_every.max(1)) {
            state.elapsed_s += start.elapsed().as_secs_f64();
            crate::io::create_dir_all(&ckpt)?;
            crate::module_io::save_module(&model, &ckpt.join("model.bpk"))?;
            let opt_path = ckpt.join("optim.bpk");
            let bytes = optim.into_bytes().map_err(|e| {
                Error::model(&opt_path, format!("cannot serialise optimiser state: {e}"))
            })?;
            crate::io::write_atomic(&opt_path, &bytes)?;
            crate::io::write_json_atomic(ckpt.join("state.json"), &state)?;
            state.elapsed_s -= start.elapsed().as_secs_f64();
            state.log.save(out, &cfg.title)?;
        }
        if verdict == Verdict::Stop {
            break;
        }
    }
    pb.finish_and_clear();
    let summary = FitSummary {
        epochs_run: state.next_epoch,
        best_epoch: state.early.best_epoch,
        best_val_loss: state.early.best,
        best_val_metric: best_metric,
        seconds: state.elapsed_s + start.elapsed().as_secs_f64(),
        train_items: train.len(),
    };
    Ok((model, summary))
}

/// A progress bar with position, rate and ETA; hidden when stderr is not a terminal.
pub fn progress_bar(len: u64, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    let style = ProgressStyle::with_template(
        "{prefix} [{elapsed_precise}] {wide_bar} {pos}/{len} ETA {eta} {msg}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    pb.set_style(style);
    pb.set_prefix(what.to_string());
    pb
}

/// Seeded shuffled mini-batches of `indices` for one epoch.
pub fn shuffled_batches(indices: &[usize], batch_size: usize, seed: u64) -> Vec<Vec<usize>> {
    let mut v = indices.to_vec();
    v.shuffle(&mut StdRng::seed_from_u64(seed));
    v.chunks(batch_size.max(1)).map(|c| c.to_vec()).collect()
}

/// Check a value is a finite number, or fail naming what it is (a diverged loss, for one).
pub fn ensure_finite(what: &str, v: f64) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::Invalid(format!("{what} is {v}: training diverged")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn early_stopping_counts_patience_and_ignores_nan() {
        let mut es = EarlyStopping::new(2);
        assert_eq!(es.update(0, 1.0), Verdict::Improved);
        assert_eq!(es.update(1, f64::NAN), Verdict::Continue);
        assert_eq!(es.update(2, 1.5), Verdict::Stop);
        assert_eq!(es.best_epoch, 0);
    }

    #[test]
    fn batches_cover_everything_once_and_are_seeded() {
        let idx: Vec<usize> = (0..10).collect();
        let a = shuffled_batches(&idx, 4, 7);
        assert_eq!(a, shuffled_batches(&idx, 4, 7));
        let mut all: Vec<usize> = a.concat();
        all.sort();
        assert_eq!(all, idx);
        assert_eq!(a.len(), 3);
    }

    #[test]
    fn log_writes_csv_and_png() {
        let d = tempfile::tempdir().unwrap();
        let log = TrainingLog {
            epochs: (0..3)
                .map(|e| EpochRecord {
                    epoch: e,
                    train_loss: 1.0 / (e + 1) as f64,
                    val_loss: 1.2 / (e + 1) as f64,
                    seconds: 0.1,
                    val_metric: (e > 0).then_some(0.5),
                })
                .collect(),
        };
        log.save(d.path(), "test").unwrap();
        let csv = std::fs::read_to_string(d.path().join("curves.csv")).unwrap();
        assert_eq!(csv.lines().count(), 4);
        assert!(csv.starts_with("epoch,train_loss,val_loss,seconds,val_metric\n"));
        assert!(csv.lines().nth(1).unwrap().ends_with(','));
        let png = crate::image_io::load_rgb(d.path().join("curves.png")).unwrap();
        assert_eq!(png.width(), 900);
    }
}
