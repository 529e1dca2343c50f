//! The segmenter trainer's options, written once: `tactile train
//! segmenter` flattens them into its flags, `tactile.train.segmenter(...)`
//! fills them from keyword arguments, and [`SegmenterOptions::config`]
//! turns either into the one training config.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tactile_burn::train::FitSummary;
use tactile_core::dataset::Dataset;
use tactile_core::image_io::RgbImage;

use crate::inference::REST_FILE;
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
    /// The sensor's frame with nothing touching it (a calibrated sensor's background.png), kept in the model folder as rest.png: the direction then reads each frame's shading against it, so a real gel's own texture does not pull it. Frames of its size only.
    #[arg(long, value_name = "FRAME")]
    pub rest: Option<PathBuf>,
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

    /// Train on `data` into `out` as these options say; with `rest`, its
    /// frame is checked against the dataset's frames before training and
    /// kept in `out` as [`REST_FILE`] after.
    pub fn train(&self, data: &Dataset, out: &Path) -> Result<FitSummary> {
        let rest = match &self.rest {
            Some(path) => Some((path, rest_frame(path, data)?)),
            None => None,
        };
        if rest.is_none() && out.join(REST_FILE).is_file() {
            tactile_core::note!(
                "{} is kept from an earlier training: the directions read against it (give --rest to replace it, or delete it to read each window's own shading)",
                out.join(REST_FILE).display()
            );
        }
        let s = &self.schedule;
        let fit = crate::training::train(&self.config(), data, out, s.device, s.resume)?;
        if let Some((path, frame)) = rest {
            tactile_core::image_io::save_rgb_png(
                out.join(REST_FILE),
                frame.width(),
                frame.height(),
                frame.as_slice(),
            )
            .map_err(|e| {
                tactile_core::Error::image(path, format!("keeping it as the rest frame: {e}"))
            })?;
        }
        Ok(fit)
    }
}

/// The rest frame at `path`, refused unless it is a frame of `data`'s size.
fn rest_frame(path: &Path, data: &Dataset) -> Result<RgbImage> {
    let frame = tactile_core::image_io::load_rgb(path)?;
    let size = (data.manifest.width as usize, data.manifest.height as usize);
    if (frame.width(), frame.height()) != size {
        return Err(tactile_core::Error::image(
            path,
            format!(
                "the rest frame is {}x{}, and the frames of {} are {}x{}: give the rest frame of the sensor they come from",
                frame.width(),
                frame.height(),
                data.root.display(),
                size.0,
                size.1
            ),
        )
        .into());
    }
    Ok(frame)
}
