//! A trained pose network on disk: `pose.json` (architecture, the
//! preprocessing that makes its pin images, its targets and their
//! standardisation, provenance) beside `pose.bpk`.

use std::path::Path;

use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_core::Artifact;
use tactile_estimate::Target;
use tactile_estimate::regressor::Scaler;
use tactile_onnx::{Exportable, export_batch_dynamic};
use tactile_preprocess::PreprocessConfig;

use crate::model::{PoseNet, PoseNetConfig};

/// Everything needed to rebuild and use a saved pose network.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PoseArtifact {
    /// The architecture.
    pub model: PoseNetConfig,
    /// How a frame becomes the grey pin image it reads.
    pub preprocess: PreprocessConfig,
    /// What it predicts, in column order.
    pub targets: Vec<Target>,
    /// Standardisation of the encoded target columns.
    pub outputs: Scaler,
    /// Free-form provenance: how it was trained, on what, with which result.
    #[serde(default)]
    pub notes: serde_json::Value,
}

impl PoseArtifact {
    /// Output columns the targets take.
    pub fn columns(&self) -> usize {
        self.targets.iter().map(Target::width).sum()
    }
}

impl Artifact for PoseArtifact {
    type Model = PoseNet;
    const KIND: &'static str = "pose network";
    const CONFIG_FILE: &'static str = "pose.json";
    const WEIGHTS_FILE: &'static str = "pose.bpk";

    fn init(&self, device: &Device) -> tactile_core::Result<PoseNet> {
        self.model.check()?;
        Ok(self.model.init(device))
    }

    fn check(&self, file: &Path) -> tactile_core::Result<()> {
        use tactile_core::artifact::in_config;
        in_config(file, self.model.check())?;
        in_config(file, self.preprocess.check())?;
        let bad = |m: String| Err(tactile_core::Error::model(file, m));
        if self.preprocess.output_px != self.model.input_px {
            return bad(format!(
                "preprocessing makes {0}x{0} pin images, the network takes {1}x{1}",
                self.preprocess.output_px, self.model.input_px
            ));
        }
        if self.targets.is_empty() || self.columns() != self.model.outputs {
            return bad(format!(
                "{} targets take {} columns, the network gives {}",
                self.targets.len(),
                self.columns(),
                self.model.outputs
            ));
        }
        in_config(
            file,
            tactile_estimate::mlp::check_scaler(
                "target scaling",
                &self.outputs.mean,
                &self.outputs.std,
                self.model.outputs,
            ),
        )
    }
}

impl Exportable for PoseArtifact {
    /// `[N, 1, S, S]` grey pin images -> `[N, K]` standardised columns.
    fn onnx(&self, model: &PoseNet) -> tactile_onnx::Result<Vec<u8>> {
        let s = self.model.input_px;
        export_batch_dynamic(model, [1, 1, s, s], |m: &PoseNet, x| m.forward(x))
    }
}

/// A folder of pose networks trained alike but for their seed, whose
/// estimates are averaged: `ensemble.json` names the member folders inside
/// it. Averaging cancels the part of each network's error its seed made,
/// at the sum of the members' latencies (`tactile bench pose` reports
/// both).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PoseEnsemble {
    /// Member folder names, inside the ensemble's folder.
    pub members: Vec<String>,
    /// Provenance; `excluded_test` as a member's when every member left
    /// out the same test frames.
    #[serde(default)]
    pub notes: serde_json::Value,
}

impl PoseEnsemble {
    /// The file that makes a folder an ensemble.
    pub const FILE: &'static str = "ensemble.json";
    /// Most members an ensemble may name.
    pub const MAX_MEMBERS: usize = 8;

    /// Whether `dir` holds an ensemble.
    pub fn is_in(dir: &Path) -> bool {
        dir.join(Self::FILE).is_file()
    }

    /// Read and check `dir/ensemble.json`: 1 to [`Self::MAX_MEMBERS`]
    /// members, each a plain folder name inside `dir` (no path), each a
    /// pose-network folder.
    pub fn read(dir: &Path) -> tactile_core::Result<Self> {
        let file = dir.join(Self::FILE);
        let e: Self = tactile_core::io::read_json(&file)?;
        let bad = |m: String| Err(tactile_core::Error::model(&file, m));
        if let Some(m) = Self::count_problem(e.members.len()) {
            return bad(m);
        }
        for m in &e.members {
            let plain = !m.is_empty()
                && m != "."
                && m != ".."
                && m.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "._-".contains(c));
            if !plain {
                return bad(format!(
                    "member {m:?} is not a plain folder name inside the ensemble"
                ));
            }
            if !PoseArtifact::is_in(&dir.join(m)) {
                return bad(format!(
                    "member {m:?} holds no {}",
                    PoseArtifact::CONFIG_FILE
                ));
            }
        }
        Ok(e)
    }

    /// What is wrong with `n` members, if anything.
    fn count_problem(n: usize) -> Option<String> {
        (n == 0 || n > Self::MAX_MEMBERS).then(|| {
            format!(
                "an ensemble takes 1 to {} members, got {n}",
                Self::MAX_MEMBERS
            )
        })
    }

    /// One line: how many networks are averaged, and where.
    pub fn describe(&self, dir: &Path) -> String {
        format!(
            "{} pose networks averaged in {}",
            self.members.len(),
            dir.display()
        )
    }

    /// The member folders.
    pub fn member_dirs(&self, dir: &Path) -> Vec<std::path::PathBuf> {
        self.members.iter().map(|m| dir.join(m)).collect()
    }

    /// Copy the pose-network folders `members` into a new ensemble folder
    /// `out` (staged, then moved into place; an existing `out` is left
    /// alone). Their preprocessing and targets must agree; the ensemble's
    /// `excluded_test` is theirs when they all share one.
    pub fn assemble(members: &[std::path::PathBuf], out: &Path) -> tactile_core::Result<Self> {
        if let Some(m) = Self::count_problem(members.len()) {
            return Err(tactile_core::Error::Invalid(m));
        }
        let arts = members
            .iter()
            .map(|m| PoseArtifact::read(m))
            .collect::<tactile_core::Result<Vec<_>>>()?;
        for (m, a) in members.iter().zip(&arts).skip(1) {
            check_alike(&arts[0], a, m)?;
        }
        let tests: Vec<_> = arts.iter().map(|a| a.notes.get("excluded_test")).collect();
        let excluded_test = if tests.iter().all(|t| *t == tests[0]) {
            tests[0].cloned()
        } else {
            return Err(tactile_core::Error::Invalid(
                "the members left out different test frames; an ensemble's score would mix them"
                    .into(),
            ));
        };
        let staged = tactile_core::io::StagedDir::new(out)?;
        let mut names = Vec::new();
        for (k, m) in members.iter().enumerate() {
            let name = format!("member-{k}");
            let to = staged.path().join(&name);
            tactile_core::io::create_dir_all(&to)?;
            for f in [PoseArtifact::CONFIG_FILE, PoseArtifact::WEIGHTS_FILE] {
                std::fs::copy(m.join(f), to.join(f))
                    .map_err(|e| tactile_core::Error::io(m.join(f), e))?;
            }
            names.push(name);
        }
        let mut notes = serde_json::json!({
            "members_from": members.iter().map(|m| m.display().to_string()).collect::<Vec<_>>(),
        });
        if let Some(t) = excluded_test {
            notes["excluded_test"] = t;
        }
        let e = Self {
            members: names,
            notes,
        };
        tactile_core::io::write_json_atomic(staged.path().join(Self::FILE), &e)?;
        staged.commit(false)?;
        Ok(e)
    }
}

/// Members must read frames alike and give the same columns.
pub(crate) fn check_alike(
    first: &PoseArtifact,
    other: &PoseArtifact,
    dir: &Path,
) -> tactile_core::Result<()> {
    fn json<T: Serialize>(t: &T) -> serde_json::Value {
        serde_json::to_value(t).unwrap_or(serde_json::Value::Null)
    }
    if json(&first.preprocess) != json(&other.preprocess)
        || first.model.input_px != other.model.input_px
        || first.targets != other.targets
    {
        return Err(tactile_core::Error::model(
            dir.join(PoseArtifact::CONFIG_FILE),
            "its preprocessing, input size or targets differ from the first member's",
        ));
    }
    Ok(())
}
