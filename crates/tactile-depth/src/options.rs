//! The depth network trainer's options, written once: `tactile train
//! depth` flattens them into its flags, `tactile.train.depth(...)` fills
//! them from keyword arguments, and [`DepthOptions::config`] turns either
//! into the one training config.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tactile_burn::options::Size;
use tactile_burn::train::FitSummary;
use tactile_core::dataset::Dataset;
use tactile_detect::augment::PhotometricAugment;

use crate::{DenseNetPreset, DepthNetConfig, DepthTrainingConfig, HeadKind, LossKind, Result};

tactile_burn::schedule_args!(DepthSchedule, DepthTrainingConfig::new().schedule);

/// The encoder preset of the default training config.
fn default_encoder() -> DenseNetPreset {
    DenseNetPreset::of(&DepthTrainingConfig::new().model.encoder).unwrap_or(DenseNetPreset::Small)
}

/// Every option of depth network training; each default is the training
/// config's.
#[derive(clap::Args, Serialize, Deserialize, Debug, Clone)]
pub struct DepthOptions {
    /// DenseNet encoder preset.
    #[arg(long, value_enum, default_value_t = default_encoder())]
    pub encoder: DenseNetPreset,
    /// Input WIDTHxHEIGHT, multiples of 32 (paper B: 256x256).
    #[arg(long, default_value_t = Size(DepthTrainingConfig::new().model.input_size))]
    pub input: Size,
    /// conv1x1 (paper B) or custom (two 3x3 conv + ReLU, then 1x1).
    #[arg(long, value_enum, default_value_t = DepthTrainingConfig::new().model.head)]
    pub head: HeadKind,
    /// l1 (paper B), mse, or l1-grad-ssim (DenseTact).
    #[arg(long, value_enum, default_value_t = DepthTrainingConfig::new().loss)]
    pub loss: LossKind,
    /// Feed the ground-truth tendon mask as a fourth channel.
    #[arg(long)]
    pub with_mask: bool,
    /// Train the decoder only.
    #[arg(long)]
    pub freeze_encoder: bool,
    /// A sensor calibration folder (`tactile calibrate ball`): the network takes its reconstruction of each frame as a fourth channel and learns a correction to it, so it starts from what the calibration sees on the real sensor (save the network in that folder's `depth/`).
    #[arg(long, value_name = "DIR")]
    pub prior_calibration: Option<PathBuf>,
    /// Photometric augmentation of the training frames' colour channels (exposure, LED balance, offset, blur, noise, glare, JPEG; see PhotometricAugment), drawn again each epoch; the prior or mask channel is left as recorded. On a calibrated sensor's renders it did not make training runs agree on frames unlike them (docs/own-sensor-depth-seeds.md).
    #[arg(long)]
    pub augment: bool,
    /// torchvision DenseNet weights as safetensors (key mapping: the tactile-depth `torchvision` module docs); the preset must match.
    #[arg(long)]
    pub pretrained: Option<PathBuf>,
    /// Millimetres per model unit (1 = millimetres; 1000 = metres, which stalls and is refused).
    #[arg(long, default_value_t = DepthTrainingConfig::new().unit_mm)]
    pub unit_mm: f32,
    /// Channels of the deepest decoder block.
    #[arg(long, default_value_t = DepthTrainingConfig::new().model.decoder_width)]
    pub decoder_width: usize,
    /// Fraction of the sequences that validate.
    #[arg(long, default_value_t = DepthTrainingConfig::new().val_fraction)]
    pub val_fraction: f64,
    /// The schedule, the device and resuming.
    #[command(flatten)]
    #[serde(flatten)]
    pub schedule: DepthSchedule,
}

impl DepthOptions {
    /// The training config these options ask for.
    pub fn config(&self) -> DepthTrainingConfig {
        let d = DepthTrainingConfig::new();
        let model = DepthNetConfig::new(self.encoder.config(), self.input.0)
            .with_head(self.head)
            .with_decoder_width(self.decoder_width);
        DepthTrainingConfig::new()
            .with_model(model)
            .with_schedule(self.schedule.schedule(d.schedule.learning_rate))
            .with_loss(self.loss)
            .with_unit_mm(self.unit_mm)
            .with_with_mask(self.with_mask)
            .with_freeze_encoder(self.freeze_encoder)
            .with_pretrained(self.pretrained.as_ref().map(|p| p.display().to_string()))
            .with_val_fraction(self.val_fraction)
            .with_augment(self.augment.then(PhotometricAugment::new))
            .with_prior_calibration(
                self.prior_calibration
                    .as_ref()
                    .map(|p| p.display().to_string()),
            )
    }

    /// Train on `data` into `out` as these options say.
    pub fn train(&self, data: &Dataset, out: &Path) -> Result<FitSummary> {
        let s = &self.schedule;
        crate::training::train(&self.config(), data, out, s.device, s.resume)
    }
}
