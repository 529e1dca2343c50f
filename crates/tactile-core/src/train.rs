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
            writeln!(w, "epoch,train_loss,val_loss,seconds")?;
            for e in &self.epochs {
                writeln!(
                    w,
                    "{},{},{},{:.3}",
                    e.epoch, e.train_loss, e.val_loss, e.seconds
                )?;
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
                })
                .collect(),
        };
        log.save(d.path(), "test").unwrap();
        let csv = std::fs::read_to_string(d.path().join("curves.csv")).unwrap();
        assert_eq!(csv.lines().count(), 4);
        let png = crate::image_io::load_rgb(d.path().join("curves.png")).unwrap();
        assert_eq!(png.width(), 900);
    }
}
