//! Models trained apart, averaged as one ([`tactile_burn::ensemble`]): the
//! kind of the member folders says which.

use std::path::{Path, PathBuf};

use tactile_burn::Artifact;
use tactile_detect::{DetectorArtifact, DetectorEnsembleArtifact};
use tactile_estimate::RegressorEnsemble;
use tactile_estimate::regressor::RegressorArtifact;
use tactile_pose::{PoseArtifact, PoseEnsemble};

use crate::Result;

/// Copy the member folders (pose networks, detectors or regressors on one
/// encoder's features, all of one kind)
/// into a new ensemble folder `out` (staged; an existing `out` is left
/// alone) that every front end loads as one model; returns one line saying
/// what was made.
pub fn assemble_ensemble(members: &[PathBuf], out: &Path) -> Result<String> {
    let first = members
        .first()
        .map(PathBuf::as_path)
        .unwrap_or(Path::new(""));
    tactile_core::io::expect_folder(first, "model folder")?;
    if DetectorArtifact::is_in(first) {
        let e = DetectorEnsembleArtifact::assemble(members, out)?;
        Ok(e.describe(out, "detectors"))
    } else if PoseArtifact::is_in(first) {
        let e = PoseEnsemble::assemble(members, out)?;
        Ok(e.describe(out, "pose networks"))
    } else if RegressorArtifact::is_in(first) {
        let e = RegressorEnsemble::assemble(members, out)?;
        Ok(e.describe(out, "regressors"))
    } else {
        Err(tactile_core::Error::wrong_kind(
            first,
            "detector, pose-network or regressor folder",
            "no detector.json, pose.json or regressor.json",
        )
        .into())
    }
}
