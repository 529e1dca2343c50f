//! The segmenter trainer's options, written once: `tactile train
//! segmenter` flattens them into its flags, `tactile.train.segmenter(...)`
//! fills them from keyword arguments, and [`SegmenterOptions::config`]
//! turns either into the one training config.

use std::path::Path;

use serde::{Deserialize, Serialize};
use tactile_burn::train::FitSummary;
use tactile_core::dataset::Dataset;

use crate::{Result, SegmenterTrainingConfig};

tactile_burn::schedule_args!(SegmenterSchedule, SegmenterTrainingConfig::new().schedule);

/// Every option of segmenter training; each default is the training
/// config's.
#[derive(clap::Args, Serialize, Deserialize, Debug, Clone)]
pub struct SegmenterOptions {
    /// Side of the square window (a multiple of 16; paper B: 160).
    #[arg(long, default_value_t = SegmenterTrainingConfig::new().model.side)]
    pub side: usize,
    /// Channels of the first U-Net block.
    #[arg(long, default_value_t = SegmenterTrainingConfig::new().model.base)]
    pub base: usize,
    /// Rotated copies of each training frame (paper B's augmentation).
    #[arg(long, default_value_t = SegmenterTrainingConfig::new().copies)]
    pub copies: usize,
    /// Fraction of the sequences that validate.
    #[arg(long, default_value_t = SegmenterTrainingConfig::new().val_fraction)]
    pub val_fraction: f64,
    /// The schedule, the device and resuming.
    #[command(flatten)]
    #[serde(flatten)]
    pub schedule: SegmenterSchedule,
}

impl SegmenterOptions {
    /// The training config these options ask for.
    pub fn config(&self) -> SegmenterTrainingConfig {
        let d = SegmenterTrainingConfig::new();
        SegmenterTrainingConfig::new()
            .with_model(d.model.with_side(self.side).with_base(self.base))
            .with_schedule(self.schedule.schedule(d.schedule.learning_rate))
            .with_copies(self.copies)
            .with_val_fraction(self.val_fraction)
    }

    /// Train on `data` into `out` as these options say.
    pub fn train(&self, data: &Dataset, out: &Path) -> Result<FitSummary> {
        let s = &self.schedule;
        crate::training::train(&self.config(), data, out, s.device, s.resume)
    }
}
