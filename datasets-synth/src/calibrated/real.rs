//! Real frames of the calibrated sensor beside its renders. The ball
//! presses that calibrated the sensor are frames of that very sensor known
//! to hold no tendon: written into the rendered set (each as a few copies
//! under the renders' own exposure and noise), they show the detector what
//! a real contact that is not a tendon looks like, and the depth network
//! real frames labelled by the calibration's own reconstruction. The
//! renders stay the only source of tendons.

use serde::Serialize;
use tactile_core::{Error, Result};

use super::{CalibratedConfig, CalibratedSensor};
use crate::rng::SampleRng;

/// Most copies written of one real frame.
pub const MAX_COPIES: usize = 100;
/// Most real frames joined to one set.
pub const MAX_REAL_FRAMES: usize = 10_000;

/// One real frame with its indentation.
#[derive(Debug, Clone)]
pub struct RealFrame {
    /// The frame's file, relative to [`RealFrames::folder`].
    pub file: String,
    /// RGB, row-major, the sensor's size.
    pub rgb: Vec<u8>,
    /// The skin's indentation, metres (the label; the calibration's
    /// reconstruction for ball presses).
    pub indentation_m: Vec<f32>,
}

/// Real frames to join a rendered set, as negatives (no tendon).
#[derive(Debug, Clone, Default)]
pub struct RealFrames {
    /// Where they came from.
    pub folder: String,
    /// The frames used.
    pub frames: Vec<RealFrame>,
    /// Frames of the folder deliberately left out (kept for a held-out
    /// check), by file.
    pub held_out: Vec<String>,
    /// Copies of each frame, each with its own exposure and noise.
    pub copies: usize,
}

/// What the manifest says of the real frames of a set.
#[derive(Debug, Clone, Serialize)]
pub struct RealFramesRecord {
    /// Where they came from.
    pub folder: String,
    /// The frames used, by file.
    pub used: Vec<String>,
    /// The frames left out, by file.
    pub held_out: Vec<String>,
    /// Copies of each.
    pub copies: usize,
    /// How the depth maps were made.
    pub depth_label: &'static str,
}

impl RealFrames {
    /// Rows these frames add to a set.
    pub fn rows(&self) -> usize {
        self.frames.len() * self.copies
    }

    /// Check the frames against `sensor`'s size and the limits.
    pub fn validate(&self, sensor: &CalibratedSensor) -> Result<()> {
        if self.frames.is_empty() {
            return Ok(());
        }
        if self.copies == 0 || self.copies > MAX_COPIES {
            return Err(Error::Invalid(format!(
                "real frames: copies must be in 1..={MAX_COPIES}, got {}",
                self.copies
            )));
        }
        if self.frames.len() > MAX_REAL_FRAMES {
            return Err(Error::Invalid(format!(
                "real frames: at most {MAX_REAL_FRAMES}, got {}",
                self.frames.len()
            )));
        }
        let n = sensor.width() * sensor.height();
        for f in &self.frames {
            if f.rgb.len() != 3 * n || f.indentation_m.len() != n {
                return Err(Error::Invalid(format!(
                    "real frame {} of {}: not the sensor's {}x{}",
                    f.file,
                    self.folder,
                    sensor.width(),
                    sensor.height()
                )));
            }
        }
        Ok(())
    }

    /// The manifest's record.
    pub fn record(&self) -> RealFramesRecord {
        RealFramesRecord {
            folder: self.folder.clone(),
            used: self.frames.iter().map(|f| f.file.clone()).collect(),
            held_out: self.held_out.clone(),
            copies: self.copies,
            depth_label: "the calibration's reconstruction",
        }
    }

    /// Copy `k` of real row `row` (frame `row / copies`): the frame under
    /// an exposure and noise drawn as the renders draw theirs, determined by
    /// `seed` and `row`.
    pub fn copy(&self, config: &CalibratedConfig, seed: u64, row: usize) -> (&RealFrame, Vec<u8>) {
        let frame = &self.frames[row / self.copies.max(1)];
        // A stream no render uses (renders take 1 and 2 + sequence).
        let mut rng = SampleRng::new(seed, u64::MAX, row as u64);
        let exposure = 1.0 + rng.draw(config.exposure_jitter);
        let sigma = rng.draw(config.noise_sigma);
        let rgb = frame
            .rgb
            .iter()
            .map(|&v| {
                (f64::from(v) * exposure + sigma * rng.normal())
                    .round()
                    .clamp(0.0, 255.0) as u8
            })
            .collect();
        (frame, rgb)
    }
}
