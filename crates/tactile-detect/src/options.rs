//! The detector trainer's options, written once: `tactile train detector`
//! flattens them into its flags, `tactile.train.detector(...)` fills them
//! from keyword arguments, and [`DetectorOptions::config`] turns either
//! into the one training config.

use serde::{Deserialize, Serialize};
use tactile_burn::options::Size;

use crate::augment::PhotometricAugment;
use crate::{Architecture, DetectorTrainingConfig, Result, SoftLabels};

tactile_burn::schedule_args!(DetectorSchedule, DetectorTrainingConfig::new().schedule);

/// Every option of detector training; each default is the training
/// config's.
#[derive(clap::Args, Serialize, Deserialize, Debug, Clone)]
pub struct DetectorOptions {
    /// The network.
    #[arg(long, value_enum, default_value_t = DetectorTrainingConfig::new().model.architecture)]
    pub architecture: Architecture,
    /// Channel width multiplier.
    #[arg(long, default_value_t = DetectorTrainingConfig::new().model.width)]
    pub width: f64,
    /// Input size WIDTHxHEIGHT (paper B: 320x240).
    #[arg(long, default_value_t = Size(DetectorTrainingConfig::new().model.input_size))]
    pub input: Size,
    /// Bits per channel the resized input keeps (8 or 16): 16 keeps the fraction of a grey level a light press shades the skin by, which averaging down to the input recovers and 8 rounds away.
    #[arg(long, default_value_t = DetectorTrainingConfig::new().model.bits())]
    pub input_bits: u8,
    /// Divide each input channel by its level at the window's centre, so a shading contrast means one ridge height whatever the exposure and LED balance.
    #[arg(long)]
    pub normalise_exposure: bool,
    /// Fraction of each dataset's sequences that validate.
    #[arg(long, default_value_t = DetectorTrainingConfig::new().val_fraction)]
    pub val_fraction: f64,
    /// Train toward soft targets from each frame's ridge amplitude (`ridge_mm`): sigmoid(ln(A / threshold) / WIDTH) about the spec's tendon threshold. Suggested width: 0.2.
    #[arg(long, value_name = "WIDTH")]
    pub soft_labels: Option<f64>,
    /// Photometric augmentation of the training frames (exposure, LED balance, blur, noise, glare, JPEG; see PhotometricAugment). With 16-bit inputs only the noise a camera and its compression leave at the input size (PhotometricAugment::recording), so a light press's shading stays readable.
    #[arg(long)]
    pub augment: bool,
    /// Only re-choose the threshold of the model already in the output folder on the validation sequences (training ends with this step anyway).
    #[arg(long)]
    pub calibrate_only: bool,
    /// The schedule, the device and resuming.
    #[command(flatten)]
    #[serde(flatten)]
    pub schedule: DetectorSchedule,
}

impl DetectorOptions {
    /// The training config these options ask for (checked).
    pub fn config(&self) -> Result<DetectorTrainingConfig> {
        let d = DetectorTrainingConfig::new();
        let soft_labels = self
            .soft_labels
            .map(SoftLabels::about_spec_threshold)
            .transpose()?;
        let config = DetectorTrainingConfig::new()
            .with_model(
                d.model
                    .with_architecture(self.architecture)
                    .with_width(self.width)
                    .with_input_size(self.input.0)
                    .with_input_bits(Some(self.input_bits))
                    .with_normalise_exposure(Some(self.normalise_exposure)),
            )
            .with_schedule(self.schedule.schedule(d.schedule.learning_rate))
            .with_val_fraction(self.val_fraction)
            .with_soft_labels(soft_labels)
            .with_augment(
                self.augment
                    .then(|| PhotometricAugment::for_input_bits(self.input_bits)),
            );
        config.model.check()?;
        Ok(config)
    }

    /// Train on `datasets` into `out` as these options say.
    pub fn train(
        &self,
        datasets: &[tactile_core::dataset::Dataset],
        out: &std::path::Path,
    ) -> Result<crate::training::DetectorFit> {
        let s = &self.schedule;
        crate::training::train(
            &self.config()?,
            datasets,
            out,
            s.device,
            s.resume,
            self.calibrate_only,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tactile_burn::options::Options;

    #[test]
    fn keyword_overrides_reach_the_same_config_as_flags() {
        use clap::{Args, FromArgMatches};
        let flags = [
            "--input-bits",
            "16",
            "--normalise-exposure",
            "--soft-labels",
            "0.6",
            "--augment",
            "--input",
            "160x120",
            "--max-epochs",
            "3",
        ];
        let cmd = DetectorOptions::augment_args(clap::Command::new("t").no_binary_name(true));
        let cli =
            DetectorOptions::from_arg_matches(&cmd.try_get_matches_from(flags).unwrap()).unwrap();
        let kw = serde_json::json!({
            "input_bits": 16, "normalise_exposure": true, "soft_labels": 0.6,
            "augment": true, "input": [160, 120], "max_epochs": 3,
        });
        let py = DetectorOptions::with_overrides(kw.as_object().unwrap()).unwrap();
        assert_eq!(
            serde_json::to_value(cli.config().unwrap()).unwrap(),
            serde_json::to_value(py.config().unwrap()).unwrap()
        );
        // Every flag is a keyword of the same name.
        let defaults = serde_json::to_value(DetectorOptions::defaults().unwrap()).unwrap();
        for doc in DetectorOptions::docs().unwrap() {
            assert!(
                defaults.get(&doc.name).is_some(),
                "{} has no keyword",
                doc.name
            );
        }
        let e = DetectorOptions::with_overrides(
            serde_json::json!({ "input_bit": 16 }).as_object().unwrap(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("unknown option 'input_bit'") && e.contains("input_bits"),
            "{e}"
        );
        let e = DetectorOptions::with_overrides(
            serde_json::json!({ "width": "wide" }).as_object().unwrap(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("option 'width'"), "{e}");
    }
}
