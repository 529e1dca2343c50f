//! Calibration's options, written once: `tactile calibrate ball` flattens
//! them into its flags, `tactile.calibrate.ball(...)` fills them from
//! keyword arguments, and [`BallOptions::config`] turns either into the
//! one calibration config.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::training::{Calibration, CalibrationConfig, CircleSource, calibrate};
use crate::{BallPresses, Result};

tactile_burn::schedule_args!(CalibrationSchedule, CalibrationConfig::new().schedule);

/// Every option of a ball-press calibration; each default is the
/// calibration config's.
#[derive(clap::Args, Serialize, Deserialize, Debug, Clone)]
pub struct BallOptions {
    /// Hidden layers' widths of the sensor model.
    #[arg(long, value_delimiter = ',', num_args = 1.., default_values_t = CalibrationConfig::new().model.widths)]
    pub widths: Vec<usize>,
    /// Each layer's odd kernel size, the output layer last (all 1: GelSight's per-pixel MLP).
    #[arg(long, value_delimiter = ',', num_args = 1.., default_values_t = CalibrationConfig::new().model.kernels)]
    pub kernels: Vec<usize>,
    /// Frame pixels per working pixel (the grid the model and the Poisson solve run on); default: the scale's, a working pixel of about 0.118 mm (4 at the R1.5's 0.0295 mm per pixel, 2 for a GelSight Mini at 320x240).
    #[arg(long)]
    pub factor: Option<usize>,
    /// Presses held out to choose the epoch, spread over the recording (0: all presses fit; the epoch is chosen on four of them).
    #[arg(long, default_value_t = CalibrationConfig::new().val_presses)]
    pub val_presses: usize,
    /// Each channel's gain is jittered by up to this fraction in training.
    #[arg(long, default_value_t = CalibrationConfig::new().colour_jitter)]
    pub colour_jitter: f64,
    /// Weight of the integrated height's error beside the slopes' (0: slopes only).
    #[arg(long, default_value_t = CalibrationConfig::new().height_weight)]
    pub height_weight: f64,
    /// Where the contact circles come from: auto (annotated where presses.csv gives them), found, annotated.
    #[arg(long, value_enum, default_value_t = CircleSource::Auto)]
    pub circles: CircleSource,
    /// Integrate slopes only where the colour change shows contact (its thresholds from the presses' far field).
    #[arg(long)]
    pub contact_gate: bool,
    /// The schedule and the device.
    #[command(flatten)]
    #[serde(flatten)]
    pub schedule: CalibrationSchedule,
}

impl BallOptions {
    /// The calibration config these options ask for.
    pub fn config(&self) -> Result<CalibrationConfig> {
        if self.schedule.resume {
            return Err(tactile_core::Error::Config(
                "resume: a calibration takes a minute or two and starts afresh; leave resume off"
                    .into(),
            )
            .into());
        }
        let d = CalibrationConfig::new();
        let c = CalibrationConfig::new()
            .with_model(
                d.model
                    .clone()
                    .with_widths(self.widths.clone())
                    .with_kernels(self.kernels.clone()),
            )
            .with_factor(self.factor)
            .with_schedule(self.schedule.schedule(d.schedule.learning_rate))
            .with_val_presses(self.val_presses)
            .with_colour_jitter(self.colour_jitter)
            .with_height_weight(self.height_weight)
            .with_circles(self.circles)
            .with_contact_gate(self.contact_gate);
        c.model.check()?;
        c.schedule.check()?;
        if !(0.0..0.5).contains(&c.colour_jitter) {
            return Err(tactile_core::Error::Config(format!(
                "colour_jitter must be in [0, 0.5), got {:?}",
                c.colour_jitter
            ))
            .into());
        }
        if !(0.0..=1e4).contains(&c.height_weight) {
            return Err(tactile_core::Error::Config(format!(
                "height_weight must be in [0, 10000], got {:?}",
                c.height_weight
            ))
            .into());
        }
        Ok(c)
    }

    /// Calibrate from the folder `data` into the model folder `out`.
    pub fn calibrate(&self, data: &Path, out: &Path) -> Result<Calibration> {
        let config = self.config()?;
        let ds = BallPresses::open(data)?;
        calibrate(&config, &ds, out, self.schedule.device)
    }
}
