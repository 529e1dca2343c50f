//! The pose network trainer's options, written once: `tactile train pose`
//! flattens them into its flags, `tactile.train.pose(...)` fills them from
//! keyword arguments, and [`PoseOptions::config`] turns either into the
//! one training config.

use std::path::Path;

use serde::{Deserialize, Serialize};
use tactile_burn::options::TestHoldoutArgs;
use tactile_burn::train::FitSummary;
use tactile_core::dataset::Dataset;
use tactile_estimate::Target;

use crate::training::{PoseLoss, PoseScores, PoseTrainingConfig, grey_pin_images};
use crate::{PoseNetConfig, Result};

tactile_burn::schedule_args!(PoseSchedule, PoseTrainingConfig::new(vec![]).schedule);

/// Every option of pose network training; each default is the training
/// config's.
#[derive(clap::Args, Serialize, Deserialize, Debug, Clone)]
pub struct PoseOptions {
    /// Targets: label columns, NAME:PERIOD for an angle.
    #[arg(long, value_delimiter = ',', default_values_t = ["x_mm", "theta_deg", "depth_mm"].map(String::from))]
    pub targets: Vec<String>,
    /// Side of the grey pin image (the central 256 px of the frame, masked to the tip, area-downsampled).
    #[arg(long, default_value_t = PoseTrainingConfig::new(vec![]).preprocess.output_px)]
    pub input_px: usize,
    /// Channels of each stage; each stage halves the side.
    #[arg(long, value_delimiter = ',', default_values_t = PoseNetConfig::new().widths)]
    pub widths: Vec<usize>,
    /// Hidden units of the dense head.
    #[arg(long, default_value_t = PoseNetConfig::new().hidden)]
    pub hidden: usize,
    /// Dropout before each dense layer while training (0 = none).
    #[arg(long, default_value_t = PoseNetConfig::new().dropout)]
    pub dropout: f64,
    /// Fraction of the training rows held out for early stopping.
    #[arg(long, default_value_t = PoseTrainingConfig::new(vec![]).val_fraction)]
    pub val_fraction: f64,
    /// Train on every training row for exactly --max-epochs (the final model).
    #[arg(long)]
    pub all_rows: bool,
    /// Training loss on the standardised targets.
    #[arg(long, value_enum, default_value_t = PoseLoss::default())]
    pub loss: PoseLoss,
    /// Leaving out a later evaluation's test frames.
    #[command(flatten)]
    #[serde(flatten)]
    pub holdout: TestHoldoutArgs,
    /// The schedule, the device and resuming.
    #[command(flatten)]
    #[serde(flatten)]
    pub schedule: PoseSchedule,
}

/// What training a pose network gave: the fit, and its scores on the test
/// frames it left out when it left some out.
#[derive(Debug, Clone, Serialize)]
pub struct PoseFit {
    /// The training run.
    #[serde(flatten)]
    pub fit: FitSummary,
    /// Errors on the held-out test frames.
    pub test: Option<PoseScores>,
}

impl PoseOptions {
    /// The training config these options ask for (checked).
    pub fn config(&self) -> Result<PoseTrainingConfig> {
        let targets = self
            .targets
            .iter()
            .map(|t| t.parse::<Target>())
            .collect::<std::result::Result<Vec<_>, _>>()?;
        let d = PoseTrainingConfig::new(vec![]);
        let model = d
            .model
            .clone()
            .with_widths(self.widths.clone())
            .with_hidden(self.hidden)
            .with_dropout(self.dropout);
        let config = PoseTrainingConfig {
            targets,
            model,
            preprocess: grey_pin_images(self.input_px),
            schedule: self.schedule.schedule(d.schedule.learning_rate),
            val_fraction: self.val_fraction,
            holdout: self.holdout.holdout(),
            all_rows: self.all_rows,
            loss: Some(self.loss),
            ..d
        };
        config.checked()
    }

    /// Train on `data` into `out` as these options say, then score the
    /// test frames it left out, if it left some out.
    pub fn train(&self, data: &Dataset, out: &Path) -> Result<PoseFit> {
        let s = &self.schedule;
        let config = self.config()?;
        let fit = crate::training::train(&config, data, out, s.device, s.resume)?;
        let test = match config.holdout {
            Some(h) => Some(crate::training::test_scores(
                out,
                data,
                h,
                s.device.runtime(),
            )?),
            None => None,
        };
        Ok(PoseFit { fit, test })
    }
}
