//! The one training skeleton every model uses: a [`Schedule`] (batch size,
//! epochs, patience, learning rate and its decay, seed) embedded in each
//! model's training config, the loop [`fit`] (seeded mini-batches, early
//! stopping, best model kept, resumable checkpoints, curves), and the
//! [`FitSummary`] every trainer returns.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use burn::config::Config;
use indicatif::ProgressBar;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand::seq::SliceRandom;
use serde::{Deserialize, Serialize};

use crate::{Error, Result};
use tactile_core::plot::{Series, line_plot};

/// How long and how fast a model trains. Each model's training config
/// embeds one, with that model's defaults.
#[derive(Config, Debug, PartialEq)]
pub struct Schedule {
    /// Items per optimiser step.
    pub batch_size: usize,
    /// Upper bound on epochs.
    pub max_epochs: usize,
    /// Epochs without a better validation loss before stopping.
    pub patience: usize,
    /// Learning rate of the first epoch.
    pub learning_rate: f64,
    /// Learning rate of epoch `e` is `learning_rate * lr_decay^e` (1 = constant).
    #[config(default = 1.0)]
    pub lr_decay: f64,
    /// Seeds the initial weights, every shuffle and every split.
    #[config(default = 42)]
    pub seed: u64,
}

/// The largest learning rate taken: ten times Adadelta's customary 1.
/// Before it was bounded, `--lr 1e300` trained an epoch, diverged and
/// left its new folder marked incomplete.
pub const MAX_LEARNING_RATE: f64 = 10.0;

impl Schedule {
    /// Check the values before any data is loaded.
    pub fn check(&self) -> Result<()> {
        if self.batch_size == 0 || self.max_epochs == 0 {
            return Err(Error::Config(format!(
                "batch size ({}) and epochs ({}) must be at least 1",
                self.batch_size, self.max_epochs
            )));
        }
        // Adadelta's customary rate is 1 and Adam's 1e-3; past
        // MAX_LEARNING_RATE every optimiser here diverges in its first epoch.
        if !(self.learning_rate.is_finite()
            && self.learning_rate > 0.0
            && self.learning_rate <= MAX_LEARNING_RATE)
        {
            return Err(Error::Config(format!(
                "learning rate must be a positive finite number of at most {MAX_LEARNING_RATE:?}, got {:?}",
                self.learning_rate
            )));
        }
        // A factor per epoch: above 1 the rate grows every epoch until the
        // weights diverge.
        if !(self.lr_decay > 0.0 && self.lr_decay <= 1.0) {
            return Err(Error::Config(format!(
                "learning-rate decay must be in (0, 1] (a factor per epoch; 1 keeps the rate), got {:?}",
                self.lr_decay
            )));
        }
        Ok(())
    }
}

/// Early stopping on a validation loss, resumable (it is saved in checkpoints).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct EarlyStopping {
    /// Epochs without a new best before stopping.
    pub patience: usize,
    /// Best validation loss so far.
    pub best: f64,
    /// Epoch of that loss.
    pub best_epoch: usize,
    /// Epochs since it.
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
    /// 0-based epoch.
    pub epoch: usize,
    /// Mean training loss.
    pub train_loss: f64,
    /// Validation loss (what early stopping watches).
    pub val_loss: f64,
    /// Wall time of the epoch.
    pub seconds: f64,
    /// The model's own validation metric (accuracy, IoU), when it has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub val_metric: Option<f64>,
}

/// The curves of a run, written as `curves.csv` and `curves.png`.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct TrainingLog {
    /// Every epoch run so far.
    pub epochs: Vec<EpochRecord>,
}

impl TrainingLog {
    /// Write `curves.csv` and `curves.png` into `dir`.
    pub fn save(&self, dir: impl AsRef<Path>, title: &str) -> Result<()> {
        let dir = dir.as_ref();
        let csv_path = dir.join("curves.csv");
        tactile_core::io::write_atomic_with(&csv_path, |w| {
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

/// A [`Schedule`] and what [`fit`] says and saves along the way.
#[derive(Debug, Clone)]
pub struct FitConfig {
    /// Epochs, batches, learning rate, seed.
    pub schedule: Schedule,
    /// Title of the curves plot and prefix of the progress output.
    pub title: String,
    /// The model folder: checkpoints and curves go there. `None` trains in
    /// memory (the small estimators, fitted by the dozen).
    pub out: Option<PathBuf>,
    /// Continue from the checkpoint in `out`.
    pub resume: bool,
    /// Save a resumable checkpoint every this many epochs (and at the end).
    pub checkpoint_every: usize,
    /// Report each epoch (a bar, or a line when stderr is not a terminal).
    pub progress: bool,
    /// The run's identity (see [`crate::artifact::run_fingerprint`]):
    /// recorded in the checkpoint, and a resume with another is refused.
    pub run_id: Option<String>,
}

impl FitConfig {
    /// `schedule` in memory, without progress output.
    pub fn new(schedule: &Schedule, title: impl Into<String>) -> Self {
        Self {
            schedule: schedule.clone(),
            title: title.into(),
            out: None,
            resume: false,
            checkpoint_every: 1,
            progress: false,
            run_id: None,
        }
    }

    /// Record the run's identity in the checkpoint; resuming with another
    /// dataset or other settings is then refused.
    pub fn with_run_id(mut self, id: String) -> Self {
        self.run_id = Some(id);
        self
    }

    /// Checkpoints, curves and progress for a model trained into `out`,
    /// continuing from its checkpoint when `resume`.
    pub fn saving_to(mut self, out: &Path, resume: bool) -> Self {
        self.out = Some(out.to_path_buf());
        self.resume = resume;
        self.progress = true;
        self
    }

    /// Checkpoint every `epochs` epochs instead (for many short epochs).
    pub fn with_checkpoint_every(mut self, epochs: usize) -> Self {
        self.checkpoint_every = epochs.max(1);
        self
    }
}

/// What a training run ended with; every trainer returns one.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FitSummary {
    /// Epochs run in all (across resumes).
    pub epochs_run: usize,
    /// The epoch whose model was kept, counted from 0 as the training log's
    /// epochs are (`training.json`); what is printed counts from 1.
    pub best_epoch: usize,
    /// Its validation loss.
    pub best_val_loss: f64,
    /// The validation metric of the best epoch.
    pub best_val_metric: Option<f64>,
    /// Training time across resumes.
    pub seconds: f64,
    /// Training items (frames, windows).
    pub train_items: usize,
    /// Validation items.
    #[serde(default)]
    pub val_items: usize,
    /// What the trainer found in its data that a user must know (a target
    /// labelled with one value on every frame it fits, validation frames of
    /// one class): noted on standard error when found, raised as
    /// `UserWarning`s by Python.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

impl FitSummary {
    /// One line for the command line: best epoch, its validation loss and
    /// metric (called `metric`, when there is one), and the training time.
    pub fn describe(&self, metric: &str) -> String {
        let m = self
            .best_val_metric
            .map_or(String::new(), |v| format!(", {metric} {v:.4}"));
        format!(
            "best epoch {} of {}: validation loss {:.4}{m}; {:.0} s",
            self.best_epoch + 1,
            self.epochs_run,
            self.best_val_loss,
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
    #[serde(default)]
    run_id: Option<String>,
}

/// The training loop: seeded shuffled mini-batches, one optimiser step per
/// batch on the loss `batch_loss` returns, validation each epoch
/// (`validate` gets the model without autodiff and returns the loss that
/// early stopping watches plus an optional metric), `save_best` on every
/// new best; with an output folder, `curves.csv`/`curves.png` and a
/// resumable `checkpoint/` there. Resuming gives the same result as an
/// uninterrupted run.
///
/// The callbacks may fail with any error `E` the foundation's errors
/// convert into (each crate's own error type).
pub fn fit<M: burn::module::Module, E: From<Error>>(
    cfg: &FitConfig,
    mut model: M,
    mut optim: burn::optim::ModuleOptimizer,
    (train, val_items): (&[usize], usize),
    mut batch_loss: impl FnMut(&M, &[usize], usize) -> Result<burn::tensor::Tensor<1>, E>,
    mut validate: impl FnMut(&M) -> Result<(f64, Option<f64>), E>,
    mut save_best: impl FnMut(&M) -> Result<(), E>,
) -> Result<(M, FitSummary), E> {
    use burn::optim::GradientsParams;
    let s = &cfg.schedule;
    s.check()?;
    if train.is_empty() {
        return Err(Error::Invalid("no training items".into()).into());
    }
    if let Some(out) = &cfg.out {
        tactile_core::io::create_dir_all(out)?;
    }
    let ckpt = cfg.out.as_ref().map(|o| o.join("checkpoint"));
    let mut state = FitState {
        next_epoch: 0,
        early: EarlyStopping::new(s.patience),
        log: TrainingLog::default(),
        elapsed_s: 0.0,
        run_id: cfg.run_id.clone(),
    };
    if let (true, Some(ckpt)) = (cfg.resume, &ckpt) {
        let st = ckpt.join("state.json");
        if !st.is_file() {
            return Err(
                Error::model(&st, "nothing to resume: no checkpoint in the output folder").into(),
            );
        }
        state = tactile_core::io::read_json(&st)?;
        if let (Some(was), Some(now)) = (&state.run_id, &cfg.run_id)
            && was != now
        {
            return Err(Error::model(
                &st,
                "this checkpoint was made on another dataset or with other settings (only --max-epochs may change on --resume): train into a new folder",
            )
            .into());
        }
        state.run_id = cfg.run_id.clone();
        model = crate::module_io::load_module(model, &ckpt.join("model.bpk"))?;
        let opt_path = ckpt.join("optim.bpk");
        optim = optim
            .load(&opt_path)
            .map_err(|e| Error::model(&opt_path, format!("cannot load optimiser state: {e}")))?;
    }
    let start = std::time::Instant::now();
    let mut progress = Progress::new(s.max_epochs, &cfg.title, cfg.progress);
    progress.set_position(state.next_epoch);
    let mut epoch = state.next_epoch;
    let mut best_metric = state
        .log
        .epochs
        .iter()
        .find(|e| e.epoch == state.early.best_epoch)
        .and_then(|e| e.val_metric);
    while epoch < s.max_epochs {
        let t0 = std::time::Instant::now();
        let mut total = 0.0;
        let lr = s.learning_rate * s.lr_decay.powi(epoch as i32);
        for batch in shuffled_batches(train, s.batch_size, s.seed.wrapping_add(epoch as u64)) {
            tactile_core::interrupt::check()?;
            let loss = batch_loss(&model, &batch, epoch)?;
            let l: f32 = loss.clone().into_scalar();
            total += l as f64 * batch.len() as f64;
            let grads = GradientsParams::from_grads(loss.backward(), &model);
            model = optim.step(lr, model, grads);
        }
        let train_loss = ensure_finite("training loss", total / train.len() as f64)?;
        let valid = model.valid();
        let (val_loss, val_metric) = validate(&valid)?;
        let record = EpochRecord {
            epoch,
            train_loss,
            val_loss,
            seconds: t0.elapsed().as_secs_f64(),
            val_metric,
        };
        let verdict = state.early.update(epoch, val_loss);
        if verdict == Verdict::Improved {
            save_best(&valid)?;
            best_metric = val_metric;
        }
        epoch += 1;
        state.next_epoch = epoch;
        progress.epoch_done(
            &record,
            &state.early,
            state.elapsed_s + start.elapsed().as_secs_f64(),
        );
        state.log.epochs.push(record);
        let last = verdict == Verdict::Stop || epoch == s.max_epochs;
        if let (Some(out), Some(ckpt)) = (&cfg.out, &ckpt)
            && (last || epoch.is_multiple_of(cfg.checkpoint_every.max(1)))
        {
            state.elapsed_s += start.elapsed().as_secs_f64();
            tactile_core::io::create_dir_all(ckpt)?;
            crate::module_io::save_module(&model, &ckpt.join("model.bpk"))?;
            let opt_path = ckpt.join("optim.bpk");
            let bytes = optim.into_bytes().map_err(|e| {
                Error::model(&opt_path, format!("cannot serialise optimiser state: {e}"))
            })?;
            tactile_core::io::write_atomic(&opt_path, &bytes)?;
            tactile_core::io::write_json_atomic(ckpt.join("state.json"), &state)?;
            state.elapsed_s -= start.elapsed().as_secs_f64();
            state.log.save(out, &cfg.title)?;
        }
        if verdict == Verdict::Stop {
            break;
        }
    }
    progress.finish();
    let summary = FitSummary {
        epochs_run: state.next_epoch,
        best_epoch: state.early.best_epoch,
        best_val_loss: state.early.best,
        best_val_metric: best_metric,
        seconds: state.elapsed_s + start.elapsed().as_secs_f64(),
        train_items: train.len(),
        val_items,
        warnings: Vec::new(),
    };
    Ok((model, summary))
}

/// Progress of a training run: a bar on a terminal; one line per epoch
/// (losses, metric, elapsed, ETA) when stderr is a log file or a pipe, where
/// a bar would be hidden.
struct Progress {
    shown: bool,
    bar: Option<ProgressBar>,
    max_epochs: usize,
    title: String,
    first: usize,
    started: std::time::Instant,
}

impl Progress {
    fn new(max_epochs: usize, title: &str, shown: bool) -> Self {
        let bar = (shown && std::io::stderr().is_terminal())
            .then(|| tactile_core::progress::progress_bar(max_epochs as u64, title));
        Self {
            shown,
            bar,
            max_epochs,
            title: title.to_string(),
            first: 0,
            started: std::time::Instant::now(),
        }
    }

    fn set_position(&mut self, epoch: usize) {
        self.first = epoch;
        if let Some(b) = &self.bar {
            b.set_position(epoch as u64);
        }
    }

    fn epoch_done(&self, r: &EpochRecord, early: &EarlyStopping, elapsed_s: f64) {
        let metric = r
            .val_metric
            .map(|m| format!(", metric {m:.4}"))
            .unwrap_or_default();
        match &self.bar {
            Some(b) => {
                b.set_position(r.epoch as u64 + 1);
                b.set_message(format!(
                    "loss {:.4} val {:.4}{metric} best {:.4}@{}",
                    r.train_loss,
                    r.val_loss,
                    early.best,
                    early.best_epoch + 1
                ));
            }
            None if self.shown => {
                let done = r.epoch + 1 - self.first;
                let per_epoch = self.started.elapsed().as_secs_f64() / done.max(1) as f64;
                let eta = per_epoch * self.max_epochs.saturating_sub(r.epoch + 1) as f64;
                tactile_core::note!(
                    "{}: epoch {}/{}: train loss {:.4}, validation loss {:.4}{metric}; best {:.4} at epoch {}; elapsed {:.0} s, ETA {:.0} s at most",
                    self.title,
                    r.epoch + 1,
                    self.max_epochs,
                    r.train_loss,
                    r.val_loss,
                    early.best,
                    early.best_epoch + 1,
                    elapsed_s,
                    eta
                );
            }
            None => {}
        }
    }

    fn finish(self) {
        if let Some(b) = self.bar {
            b.finish_and_clear();
        }
    }
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
        Err(Error::Diverged {
            what: what.to_string(),
            value: v,
        })
    }
}

/// Check every augmentation amount is in [0, 1], or fail naming the first
/// that is not (each model's augmentation config checks its fields here).
pub fn check_augment_amounts(amounts: &[(&str, f64)]) -> Result<()> {
    match amounts.iter().find(|(_, v)| !(0.0..=1.0).contains(v)) {
        Some((name, v)) => Err(Error::Config(format!(
            "augmentation {name} must be in [0, 1], got {v:?}"
        ))),
        None => Ok(()),
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

    /// The log counts epochs from 0; a person reads them from 1, as the
    /// progress line's "epoch 60/60" does: the model kept at the last of
    /// 60 epochs is "best epoch 60 of 60", not 59.
    #[test]
    fn the_best_epoch_is_said_counting_from_one() {
        let fit = FitSummary {
            epochs_run: 60,
            best_epoch: 59,
            best_val_loss: 0.5,
            best_val_metric: None,
            seconds: 1.0,
            train_items: 10,
            val_items: 2,
            warnings: Vec::new(),
        };
        assert!(
            fit.describe("").starts_with("best epoch 60 of 60:"),
            "{}",
            fit.describe("")
        );
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
    fn schedules_are_checked() {
        assert!(Schedule::new(16, 10, 3, 1e-3).check().is_ok());
        assert!(Schedule::new(0, 10, 3, 1e-3).check().is_err());
        assert!(Schedule::new(16, 10, 3, f64::NAN).check().is_err());
        assert!(
            Schedule::new(16, 10, 3, 1e-3)
                .with_lr_decay(0.0)
                .check()
                .is_err()
        );
        let e = Schedule::new(16, 10, 3, f64::INFINITY).check().unwrap_err();
        assert!(
            e.to_string()
                .contains("positive finite number of at most 10.0, got inf"),
            "{e}"
        );
        // A rate no optimiser here survives is refused before any data is
        // read (before, 1e300 diverged in the first epoch); Adadelta's 1
        // and the bound itself are taken.
        let e = Schedule::new(16, 10, 3, 1e300).check().unwrap_err();
        assert!(e.to_string().contains("at most 10.0, got 1e300"), "{e}");
        assert!(Schedule::new(16, 10, 3, 1.0).check().is_ok());
        assert!(Schedule::new(16, 10, 3, 10.0).check().is_ok());
        // A decay above 1 grows the rate every epoch: refused; 1 keeps it.
        let e = Schedule::new(16, 10, 3, 1e-3)
            .with_lr_decay(1.5)
            .check()
            .unwrap_err();
        assert!(e.to_string().contains("must be in (0, 1]"), "{e}");
        assert!(
            Schedule::new(16, 10, 3, 1e-3)
                .with_lr_decay(1.0)
                .check()
                .is_ok()
        );
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
        let png = tactile_core::image_io::load_rgb(d.path().join("curves.png")).unwrap();
        assert_eq!(png.width(), 900);
    }
}
