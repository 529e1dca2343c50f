//! A calibrated GelSight-like sensor's reconstruction of a folder of
//! frames (`tactile reconstruct`, `tactile.calibrate.reconstruct`), with
//! frames of another sensor named: when the model folder holds the
//! palpation detector trained on this sensor's rendered frames
//! (`detector/`), its input profile scores each frame, as `tactile run`'s
//! gate does; a calibration alone compares them with its rest frame.

use std::path::Path;

use tactile_burn::Artifact;
use tactile_detect::{DetectorArtifact, DetectorEnsembleArtifact};
use tactile_gelsight::reconstruct::{
    CheckBasis, ReconstructOptions, ReconstructReport, SensorCheck, reconstruct_folder,
};

use crate::Result;

/// The input profile of the detector in `model`'s `detector/` (its lead
/// member's, for an ensemble) as a [`SensorCheck`]; `None` when the folder
/// has no detector or the detector no profile (the reconstruction then
/// checks frames against the rest frame). A detector that cannot be read
/// (one still being trained, a broken config) gives no check and a
/// warning saying why: the reconstruction does not need it.
pub fn sensor_check(model: &Path) -> (Option<SensorCheck<'static>>, Option<String>) {
    match detector_profile(model) {
        Ok(check) => (check, None),
        Err(e) => (
            None,
            Some(format!(
                "warning: {e}; without the detector's input profile, only frames unlike the sensor's rest frame are told as another sensor's"
            )),
        ),
    }
}

/// [`sensor_check`]'s check, or why the detector in `model` cannot be read.
pub fn detector_profile(model: &Path) -> std::result::Result<Option<SensorCheck<'static>>, String> {
    let dir = model.join("detector");
    let artifact = if DetectorEnsembleArtifact::is_in(&dir) {
        DetectorEnsembleArtifact::read(&dir)
            .map_err(|e| e.to_string())
            .and_then(|e| e.lead().cloned().map_err(|e| e.to_string()))?
    } else if DetectorArtifact::is_in(&dir) {
        DetectorArtifact::read(&dir).map_err(|e| e.to_string())?
    } else {
        return Ok(None);
    };
    let Some(profile) = artifact.input_profile.clone() else {
        return Ok(None);
    };
    let (threshold, frames) = (profile.threshold, profile.frames);
    let config = artifact.model;
    let score = move |frame: &tactile_core::image_io::RgbImage| {
        // The frame as the pipeline's detector reads it: one working
        // downsample of a large frame, then the detector's input image.
        let working = tactile_preprocess::visuo::working_frame(
            frame,
            tactile_preprocess::visuo::WORKING_HEIGHT,
        )
        .map_err(invalid)?;
        let img = config
            .frame_image(working.as_ref().unwrap_or(frame))
            .map_err(invalid)?;
        profile.score_frame(&img).map_err(invalid)
    };
    let check = SensorCheck {
        basis: CheckBasis::DetectorProfile {
            frames,
            score: Box::new(score),
        },
        threshold,
    };
    Ok(Some(check))
}

/// A library error met while scoring a frame, as the reconstruction's.
fn invalid(e: impl std::fmt::Display) -> tactile_gelsight::Error {
    tactile_core::Error::Invalid(e.to_string()).into()
}

/// Reconstruct every frame `data` names with the calibrated sensor in
/// `model` into the new folder `out`
/// ([`tactile_gelsight::reconstruct::reconstruct_folder`]); frames unlike
/// the sensor's ([`sensor_check`]) are reconstructed too, and named in a
/// warning.
pub fn reconstruct(
    model: &Path,
    data: &Path,
    out: &Path,
    options: &ReconstructOptions,
) -> Result<ReconstructReport> {
    let (check, unread) = sensor_check(model);
    let mut report = reconstruct_folder(model, data, out, options, check)?;
    report.warnings.extend(unread);
    Ok(report)
}
