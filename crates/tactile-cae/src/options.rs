//! The autoencoder trainer's options, written once: `tactile train cae`
//! flattens them into its flags, `tactile.train.cae(...)` fills them from
//! keyword arguments, and [`CaeOptions::config`] turns either into the one
//! training config.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tactile_burn::options::TestHoldoutArgs;
use tactile_burn::train::FitSummary;
use tactile_core::dataset::Dataset;
use tactile_preprocess::PreprocessConfig;
use tactile_preprocess::perturb::{DEFAULT_ROTATION_DEG, RotationAugment};

use crate::joint::JointArgs;
use crate::tasks::read_extra_tasks;
use crate::{CaeConfig, CaeTrainingConfig, Optimizer, Result};

tactile_burn::schedule_args!(CaeSchedule, CaeTrainingConfig::new().schedule);

/// Rotation augmentation of training frames (`train cae`, `train head`).
#[derive(clap::Args, Serialize, Deserialize, Debug, Clone, Copy)]
pub struct RotateArgs {
    /// Also train on this many copies of each frame turned by up to --rotate-deg (a sensor mounted turned).
    #[arg(long, default_value_t = 0)]
    pub rotate_copies: usize,
    /// Largest turn of those copies, degrees.
    #[arg(long, default_value_t = DEFAULT_ROTATION_DEG)]
    pub rotate_deg: f64,
}

impl RotateArgs {
    /// The augmentation these options ask for (none without copies),
    /// checked. A turn given without copies would do nothing, so it is
    /// refused rather than ignored.
    pub fn augment(&self, seed: u64) -> Result<Option<RotationAugment>> {
        if self.rotate_copies == 0 && self.rotate_deg != DEFAULT_ROTATION_DEG {
            return Err(tactile_core::Error::Config(format!(
                "rotate_deg {:?} turns the rotated copies, and rotate_copies is 0: \
                 give rotate_copies too, or leave rotate_deg out",
                self.rotate_deg
            ))
            .into());
        }
        let augment = RotationAugment::optional(self.rotate_copies, self.rotate_deg, seed);
        if let Some(a) = &augment {
            a.check()?;
        }
        Ok(augment)
    }
}

/// Every option of autoencoder training; each default is the training
/// config's.
#[derive(clap::Args, Serialize, Deserialize, Debug, Clone)]
pub struct CaeOptions {
    /// Preprocessing: binary (already binarised frames), paper, lighting-compensated, or a JSON file.
    #[arg(long, default_value = "binary")]
    pub preprocess: String,
    /// Encoder widths, e.g. 16,8,8,4 (paper) or 16,16,8,4 (authors' release).
    #[arg(long, value_delimiter = ',', num_args = 1.., default_values_t = CaeConfig::new().widths)]
    pub widths: Vec<usize>,
    /// Feature count (8/16/32/64): sets the last width.
    #[arg(long)]
    pub features: Option<usize>,
    /// No ReLU before the last pooling: features cannot die (see CaeConfig).
    #[arg(long)]
    pub linear_latent: bool,
    /// Side of the encoder's first kernel, odd (Table I: 3); 7 or 9 at 56 px sees a pin with its neighbours.
    #[arg(long, default_value_t = 3)]
    #[serde(default = "default_first_kernel")]
    pub first_kernel: usize,
    /// While training, shift each pin image by up to this fraction of its side along each axis (0 = none), so the features must describe pins relative to each other.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub shift: f64,
    /// Adadelta (paper A) or Adam.
    #[arg(long, value_enum, default_value_t = CaeTrainingConfig::new().optimizer)]
    pub optimizer: Optimizer,
    /// Fraction of the training rows held out for early stopping.
    #[arg(long, default_value_t = CaeTrainingConfig::new().val_fraction)]
    pub val_fraction: f64,
    /// Leaving out a later evaluation's test frames.
    #[command(flatten)]
    #[serde(flatten)]
    pub holdout: TestHoldoutArgs,
    /// Train on the rows of every split (`val`, `test` too; --val-fraction of them still stop it): the final model, its recipe chosen on a run that left them out.
    #[arg(long)]
    #[serde(default)]
    pub every_split: bool,
    /// The schedule, the device and resuming.
    #[command(flatten)]
    #[serde(flatten)]
    pub schedule: CaeSchedule,
    /// Rotation augmentation.
    #[command(flatten)]
    #[serde(flatten)]
    pub rotate: RotateArgs,
    /// Joint training of a pose head on the features.
    #[command(flatten)]
    #[serde(flatten)]
    pub joint: JointArgs,
    /// One encoder for several datasets: a JSON list of further datasets trained on beside --data, each {"data", "preprocess", "joint_targets", "shift"} (its head takes the --joint-* settings).
    #[arg(long)]
    #[serde(default)]
    pub also_tasks: Option<PathBuf>,
}

fn default_first_kernel() -> usize {
    3
}

impl CaeOptions {
    /// The training config these options ask for (checked where it can
    /// be before any data is read).
    pub fn config(&self) -> Result<CaeTrainingConfig> {
        let pre = PreprocessConfig::preset(&self.preprocess).map_err(|e| {
            tactile_core::Error::Config(format!("preprocess '{}': {e}", self.preprocess))
        })?;
        let model = CaeConfig::from_options(
            &self.widths,
            self.features,
            self.linear_latent,
            pre.output_px,
        )?
        .with_first_kernel((self.first_kernel != 3).then_some(self.first_kernel));
        model.check()?;
        tactile_preprocess::perturb::check_shift(self.shift)?;
        self.joint.check_used(self.also_tasks.is_some())?;
        let also = match &self.also_tasks {
            Some(path) => read_extra_tasks(
                path,
                model.input_px,
                self.joint.joint_weight,
                self.joint.joint_hidden,
                self.joint.joint_loss,
            )?,
            None => Vec::new(),
        };
        let holdout = self.holdout.holdout()?;
        tactile_core::dataset::check_every_split(self.every_split, holdout)?;
        let s = &self.schedule;
        Ok(CaeTrainingConfig::new()
            .with_model(model)
            .with_preprocess(pre)
            .with_schedule(s.schedule(self.optimizer.default_learning_rate()))
            .with_optimizer(self.optimizer)
            .with_val_fraction(self.val_fraction)
            .with_holdout(holdout)
            .with_every_split(self.every_split)
            .with_rotation(self.rotate.augment(s.seed)?)
            .with_joint(self.joint.config()?)
            .with_shift((self.shift != 0.0).then_some(self.shift))
            .with_also(also))
    }

    /// Train on `data` into `out` as these options say.
    pub fn train(&self, data: &Dataset, out: &Path) -> Result<FitSummary> {
        let s = &self.schedule;
        crate::training::train(&self.config()?, data, out, s.device, s.resume)
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;

    #[derive(Parser)]
    struct Flags {
        #[command(flatten)]
        options: CaeOptions,
    }

    fn config(flags: &[&str]) -> Result<CaeTrainingConfig> {
        let args = std::iter::once("train-cae").chain(flags.iter().copied());
        Flags::try_parse_from(args).unwrap().options.config()
    }

    #[test]
    fn first_kernel_and_shift_reach_the_config_or_are_refused() {
        let plain = config(&[]).unwrap();
        assert_eq!((plain.model.first_kernel, plain.shift), (None, None));
        let wide = config(&["--first-kernel", "9", "--shift", "0.05"]).unwrap();
        assert_eq!((wide.model.first_kernel, wide.shift), (Some(9), Some(0.05)));
        for (flag, says) in [
            ("--first-kernel=4", "first kernel"),
            ("--first-kernel=17", "first kernel"),
            ("--shift=0.5", "augmentation shift"),
            ("--shift=-0.1", "augmentation shift"),
            ("--shift=NaN", "augmentation shift"),
        ] {
            let err = config(&[flag]).unwrap_err().to_string();
            assert!(err.contains(says), "{flag}: {err}");
        }
    }
}
