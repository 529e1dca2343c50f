//! A calibration's ball presses as real negatives for the sensor's rendered
//! training set ([`datasets_synth::calibrated::RealFrames`]): every press is
//! a frame of this very sensor without a tendon, and its indentation label
//! is the calibration's own reconstruction of it.

use std::path::{Path, PathBuf};

use datasets_synth::calibrated::{CalibratedSensor, RealFrame, RealFrames};
use datasets_synth::{CalibratedConfig, WriteOptions};
use tactile_burn::Runtime;

use crate::{BallPresses, Error, Reconstructor, Result};

/// The palpation videos of the calibrated sensor in `sensor`, written to
/// `out`: `count` frames, or `sequences` videos, rendered through its
/// calibration, with the real presses `config` joins to them
/// ([`real_frames`]); what `tactile synth gelsight` and Python's
/// `tactile.synth.gelsight` write. Gives the folder and the frame count.
pub fn write_sensor_videos(
    sensor: &Path,
    config: &CalibratedConfig,
    (count, sequences): (Option<usize>, Option<usize>),
    seed: u64,
    out: &Path,
    options: WriteOptions,
) -> Result<(PathBuf, usize)> {
    config.validate()?;
    let count = config.frame_count(count, sequences)?;
    let unit = CalibratedSensor::load(sensor)?;
    let real = real_frames(config, sensor)?;
    let out = datasets_synth::write_calibrated(&unit, config, count, seed, out, options, &real)?;
    Ok((out, count))
}

/// The real frames `config` asks for (`real_presses`, less the last
/// `real_held_out`, `real_copies` each), reconstructed by the calibrated
/// sensor in `sensor` against the presses' own background; none when
/// `config` names no presses.
pub fn real_frames(config: &CalibratedConfig, sensor: &Path) -> Result<RealFrames> {
    let Some(dir) = &config.real_presses else {
        return Ok(RealFrames::default());
    };
    let presses = BallPresses::open(dir)?;
    let n = presses.presses.len();
    if config.real_held_out >= n {
        return Err(Error::Layout {
            path: dir.clone(),
            why: format!(
                "real_held_out {} leaves none of its {n} presses to use",
                config.real_held_out
            ),
        });
    }
    let mut rec = Reconstructor::load(sensor, Runtime::BurnNdarray, 0)?;
    rec.set_background(&presses.background, &presses.background_path())?;
    let used = n - config.real_held_out;
    let mut frames = Vec::with_capacity(used);
    for (i, p) in presses.presses.iter().enumerate().take(used) {
        tactile_core::interrupt::check()?;
        let rgb = presses.frame(i)?;
        let map = rec.reconstruct(&rgb, &presses.press_path(i))?;
        frames.push(RealFrame {
            file: p.file.clone(),
            rgb: rgb.as_slice().to_vec(),
            indentation_m: map.indentation_m,
        });
    }
    Ok(RealFrames {
        folder: dir.display().to_string(),
        frames,
        held_out: presses.presses[used..]
            .iter()
            .map(|p| p.file.clone())
            .collect(),
        copies: config.real_copies,
    })
}
