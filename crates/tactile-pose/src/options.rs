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
    #[arg(long, value_delimiter = ',', num_args = 1.., default_values_t = ["x_mm", "theta_deg", "depth_mm"].map(String::from))]
    pub targets: Vec<String>,
    /// Side of the grey pin image (the central --crop-px of the frame, masked to the tip, area-downsampled).
    #[arg(long, default_value_t = PoseTrainingConfig::new(vec![]).preprocess.output_px)]
    pub input_px: usize,
    /// Side of the central square of the frame that holds the tip, pixels (256 for the 127-pin TacTip, 440 for the 331-pin one).
    #[arg(long, default_value_t = PoseTrainingConfig::new(vec![]).preprocess.crop_px)]
    #[serde(default = "default_crop_px")]
    pub crop_px: usize,
    /// Radius of the circular mask over the tip inside that square, pixels.
    #[arg(long, default_value_t = default_mask_radius_px())]
    #[serde(default = "default_mask_radius_px")]
    pub mask_radius_px: f32,
    /// Also predict each target's uncertainty (a Laplace scale per target, calibrated on the early-stopping rows; linear targets only).
    #[arg(long)]
    #[serde(default)]
    pub uncertainty: bool,
    /// With --all-rows and --uncertainty: take the uncertainty calibration of this validated run of the same recipe (every row is fitted, so none is left to calibrate on).
    #[arg(long)]
    #[serde(default)]
    pub calibration_from: Option<std::path::PathBuf>,
    /// Train on the rows of every split (`val`, `test` too): the final model, its recipe chosen on a run that left them out.
    #[arg(long)]
    #[serde(default)]
    pub every_split: bool,
    /// Channels of each stage; each stage halves the side.
    #[arg(long, value_delimiter = ',', num_args = 1.., default_values_t = PoseNetConfig::new().widths)]
    pub widths: Vec<usize>,
    /// Kernel side of each stage's convolution, odd (default: 3 for every stage); a wide first kernel sees a pin with its neighbours, so how far it slid against them.
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    #[serde(default)]
    pub kernels: Option<Vec<usize>>,
    /// While training, shift the whole pin image by up to this fraction of its side along each axis (0 = none): the camera never moves against the tip, so the network must read where pins sit relative to each other.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub shift: f64,
    /// While training, turn each frame half a turn about the pin image's centre with probability 1/2 per epoch; a turned copy trains only the targets listed, as TARGET:SIGN, SIGN what the turn multiplies that label by (1 or -1). For a tip whose picture survives a half turn (scripts/surface-half-turn.py measures which targets do): shear_x_mm:-1,shear_y_mm:-1,shear_theta_deg:1.
    #[arg(long, value_delimiter = ',', num_args = 1.., value_name = "TARGET:SIGN")]
    #[serde(default)]
    pub half_turn: Option<Vec<String>>,
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

/// `--half-turn`'s TARGET:SIGN items as the augmentation's signs (each
/// checked by [`crate::data::Augment::check`]).
fn half_turn_signs(items: &[String]) -> Result<std::collections::BTreeMap<String, f64>> {
    let mut signs = std::collections::BTreeMap::new();
    for item in items {
        let parsed = item
            .rsplit_once(':')
            .and_then(|(name, sign)| Some((name.trim(), sign.trim().parse::<f64>().ok()?)));
        let Some((name, sign)) = parsed else {
            return Err(tactile_core::Error::Config(format!(
                "half_turn: {item:?} is not TARGET:SIGN (e.g. shear_x_mm:-1)"
            ))
            .into());
        };
        if signs.insert(name.to_string(), sign).is_some() {
            return Err(
                tactile_core::Error::Config(format!("half_turn: {name} is listed twice")).into(),
            );
        }
    }
    Ok(signs)
}

fn default_crop_px() -> usize {
    PoseTrainingConfig::new(vec![]).preprocess.crop_px
}

fn default_mask_radius_px() -> f32 {
    PoseTrainingConfig::new(vec![])
        .preprocess
        .mask_radius_px
        .unwrap_or(100.0)
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
            .with_dropout(self.dropout)
            .with_uncertainty(Some(self.uncertainty))
            .with_kernels(self.kernels.clone());
        let mut preprocess = grey_pin_images(self.input_px);
        preprocess.crop_px = self.crop_px;
        preprocess.mask_radius_px = Some(self.mask_radius_px);
        let config = PoseTrainingConfig {
            targets,
            model,
            preprocess,
            every_split: Some(self.every_split),
            calibration_from: self
                .calibration_from
                .as_ref()
                .map(|p| p.display().to_string()),
            schedule: self.schedule.schedule(d.schedule.learning_rate),
            val_fraction: self.val_fraction,
            holdout: self.holdout.holdout()?,
            all_rows: self.all_rows,
            loss: Some(self.loss),
            augment: d
                .augment
                .clone()
                .with_shift((self.shift != 0.0).then_some(self.shift))
                .with_half_turn(self.half_turn.as_deref().map(half_turn_signs).transpose()?),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_turn_items_are_target_and_sign() {
        let items = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let signs = half_turn_signs(&items(&["shear_x_mm:-1", " shear_theta_deg : +1"])).unwrap();
        assert_eq!(signs["shear_x_mm"], -1.0);
        assert_eq!(signs["shear_theta_deg"], 1.0);
        let e = half_turn_signs(&items(&["shear_x_mm"]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("\"shear_x_mm\" is not TARGET:SIGN"), "{e}");
        let e = half_turn_signs(&items(&["a:1", "a:-1"]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("a is listed twice"), "{e}");
    }
}
