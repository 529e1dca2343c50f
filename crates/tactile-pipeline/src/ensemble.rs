//! Models trained apart, averaged as one ([`tactile_burn::ensemble`]): the
//! kind of the member folders says which.

use std::path::{Path, PathBuf};

use tactile_burn::Artifact;
use tactile_depth::{DepthArtifact, DepthEnsembleArtifact};
use tactile_detect::{DetectorArtifact, DetectorEnsembleArtifact};
use tactile_estimate::RegressorEnsemble;
use tactile_estimate::regressor::RegressorArtifact;
use tactile_pose::{PoseArtifact, PoseEnsemble};

use crate::Result;

/// Copy the member folders (pose networks, detectors, depth networks or
/// regressors on one encoder's features, all of one kind)
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
    } else if DepthArtifact::is_in(first) {
        let e = DepthEnsembleArtifact::assemble(members, out)?;
        Ok(e.describe(out, "depth networks"))
    } else if RegressorArtifact::is_in(first) {
        let e = RegressorEnsemble::assemble(members, out)?;
        Ok(e.describe(out, "regressors"))
    } else if tactile_burn::ensemble::Ensemble::is_in(first) {
        // An ensemble's members are single models: name its own.
        use tactile_burn::ensemble::Ensemble;
        let members = tactile_core::io::read_json::<Ensemble>(&first.join(Ensemble::FILE))
            .map(|e| e.member_dirs(first))
            .unwrap_or_default();
        let names: Vec<String> = members.iter().map(|m| m.display().to_string()).collect();
        Err(tactile_core::Error::Invalid(format!(
            "{}: an ensemble already (ensemble.json), and an ensemble's members are single models: give its members' folders ({}) beside the others",
            first.display(),
            names.join(", ")
        ))
        .into())
    } else {
        Err(tactile_core::Error::wrong_kind(
            first,
            "detector, pose-network, depth-network or regressor folder",
            "no detector.json, pose.json, depth.json or regressor.json",
        )
        .into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ensemble_members_are_single_models() {
        let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models");
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("e");
        // One model alone is no average.
        let e = assemble_ensemble(&[models.join("detector/member-0")], &out)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("an ensemble averages 2 to 8 models trained apart, got 1"),
            "{e}"
        );
        // An ensemble as a member: its own members are named.
        let e = assemble_ensemble(
            &[models.join("detector"), models.join("detector/member-0")],
            &out,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("detector: an ensemble already (ensemble.json)")
                && e.contains("detector/member-0, ")
                && e.contains("detector/member-1)"),
            "{e}"
        );
        assert!(!out.exists());
    }
}
