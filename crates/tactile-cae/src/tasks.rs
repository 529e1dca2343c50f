//! One autoencoder trained on several datasets at once: paper A's claim is
//! one encoder for many tasks, and an encoder that has seen each task's
//! frames (and, with joint targets, each task's labels through its own
//! head) is the fair test of it. The training command's dataset is the
//! first task; a task file lists the further ones, each with its own
//! preprocessing (of the encoder's input side), joint targets and shift.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tactile_burn::nn::RegressionLoss;
use tactile_preprocess::PreprocessConfig;

use crate::joint::JointTargets;

/// Most further datasets one autoencoder trains on.
pub const MAX_EXTRA_TASKS: usize = 8;

/// A further dataset as a task file lists it.
#[derive(Serialize, Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct ExtraTaskSpec {
    /// TacTip dataset folder (a relative path is taken from the current
    /// folder, as on the command line).
    pub data: PathBuf,
    /// Preprocessing: a preset name or a JSON file; its `output_px` must
    /// be the encoder's input side.
    pub preprocess: String,
    /// Label columns this dataset's own head predicts (`NAME` or
    /// `NAME:PERIOD`); none: reconstruction only.
    #[serde(default)]
    pub joint_targets: Vec<String>,
    /// Shift augmentation of this dataset's images (fraction of the side;
    /// 0: none, as for a target that is a position in the image).
    #[serde(default)]
    pub shift: f64,
}

/// A further dataset of a training run, as its config saves it.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
pub struct ExtraTask {
    /// Dataset folder.
    pub data: PathBuf,
    /// How its frames become pin images.
    pub preprocess: PreprocessConfig,
    /// Its head's targets, if any.
    pub joint: Option<JointTargets>,
    /// Its shift augmentation, if any.
    pub shift: Option<f64>,
}

impl ExtraTask {
    /// Check every value against the encoder's input side `input_px`.
    pub fn check(&self, input_px: usize) -> tactile_core::Result<()> {
        let bad = |m: String| {
            Err(tactile_core::Error::Config(format!(
                "further dataset {}: {m}",
                self.data.display()
            )))
        };
        self.preprocess.check()?;
        if self.preprocess.output_px != input_px {
            return bad(format!(
                "its preprocessing makes {} px pin images, the encoder reads {input_px} px",
                self.preprocess.output_px
            ));
        }
        if let Some(j) = &self.joint {
            j.check()?;
        }
        tactile_preprocess::perturb::check_shift(self.shift.unwrap_or(0.0))
    }
}

/// Check further tasks against the encoder's input side `input_px`: how
/// many there are, and each one.
pub fn check_extra_tasks(tasks: &[ExtraTask], input_px: usize) -> tactile_core::Result<()> {
    if tasks.len() > MAX_EXTRA_TASKS {
        return Err(tactile_core::Error::Config(format!(
            "at most {MAX_EXTRA_TASKS} further datasets, got {}",
            tasks.len()
        )));
    }
    tasks.iter().try_for_each(|t| t.check(input_px))
}

/// Read the task file `path` into checked further tasks; their heads take
/// the main task's `weight`, `hidden` width and `loss`.
pub fn read_extra_tasks(
    path: &Path,
    input_px: usize,
    weight: f64,
    hidden: usize,
    loss: RegressionLoss,
) -> crate::Result<Vec<ExtraTask>> {
    let specs: Vec<ExtraTaskSpec> = tactile_core::io::read_json(path)?;
    let in_file =
        |e: &dyn std::fmt::Display| tactile_core::Error::Config(format!("{}: {e}", path.display()));
    if specs.is_empty() {
        return Err(in_file(&format!("1 to {MAX_EXTRA_TASKS} further datasets, got 0")).into());
    }
    let tasks = specs
        .into_iter()
        .map(|s| {
            let preprocess = PreprocessConfig::preset(&s.preprocess)
                .map_err(|e| in_file(&format!("preprocess '{}': {e}", s.preprocess)))?;
            Ok(ExtraTask {
                joint: JointTargets::from_names(&s.joint_targets, weight, hidden, loss)
                    .map_err(|e| in_file(&e))?,
                shift: (s.shift != 0.0).then_some(s.shift),
                data: s.data,
                preprocess,
            })
        })
        .collect::<tactile_core::Result<Vec<_>>>()?;
    check_extra_tasks(&tasks, input_px).map_err(|e| in_file(&e))?;
    Ok(tasks)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, text: &str) -> PathBuf {
        let p = dir.join("tasks.json");
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn task_files_are_read_and_bad_ones_named() {
        let tmp = tempfile::tempdir().unwrap();
        let l1 = RegressionLoss::L1;
        let ok = write(
            tmp.path(),
            r#"[{"data": "edge", "preprocess": "binary", "joint_targets": ["x_mm", "theta_deg:180"]},
                {"data": "surface", "preprocess": "binary", "shift": 0.05}]"#,
        );
        let tasks = read_extra_tasks(&ok, 28, 10.0, 64, l1).unwrap();
        assert_eq!(tasks.len(), 2);
        let j = tasks[0].joint.as_ref().unwrap();
        assert_eq!((j.columns(), j.weight, j.loss), (3, 10.0, Some(l1)));
        assert_eq!((tasks[0].shift, tasks[1].shift), (None, Some(0.05)));
        assert!(tasks[1].joint.is_none());
        for (text, says) in [
            ("[]", "1 to 8"),
            (r#"[{"data": "a", "preprocess": "binary"}]"#, "56 px"),
            (r#"[{"data": "a", "preprocess": "nope"}]"#, "nope"),
            (
                r#"[{"data": "a", "preprocess": "binary", "shift": 0.9}]"#,
                "shift",
            ),
            (
                r#"[{"data": "a", "preprocess": "binary", "joint_targets": ["t:-5"]}]"#,
                "t:-5",
            ),
            (
                r#"[{"data": "a", "preprocess": "binary", "shfit": 0}]"#,
                "shfit",
            ),
        ] {
            let p = write(tmp.path(), text);
            let px = if says == "56 px" { 56 } else { 28 };
            let err = read_extra_tasks(&p, px, 1.0, 64, l1)
                .unwrap_err()
                .to_string();
            assert!(
                err.contains("tasks.json") && err.contains(says),
                "{text}: {err}"
            );
        }
    }
}
