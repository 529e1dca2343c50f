//! Regressors trained alike on one encoder's features (other seeds: other
//! initial weights and other early-stopping frames), averaged as one
//! estimator: an `ensemble.json` folder ([`tactile_burn::ensemble`]) whose
//! members are regressor folders. Each member's error is partly its own
//! training's; the average cancels that part, at the members' summed cost,
//! which beside an encoder is small.

use std::path::{Path, PathBuf};

use burn::tensor::Device;
use tactile_burn::Artifact;
use tactile_burn::ensemble::Ensemble;

use crate::Result;
use crate::regressor::{Regressor, RegressorArtifact, decode_columns, target_mae};
use crate::target::Target;

/// One regressor, or an ensemble of them whose estimates are averaged: a
/// regressor folder as the estimators load it.
pub struct RegressorEnsemble {
    /// The members (at least one), the first one's config standing for all
    /// (they share inputs, targets, encoder and shapes).
    members: Vec<Regressor>,
}

impl RegressorEnsemble {
    /// Whether `dir` holds a regressor (`regressor.json`) or an ensemble
    /// of them: an `ensemble.json` whose first member is not a folder of
    /// another kind of model (a pose ensemble kept beside the estimators is
    /// not one of them). Its members are checked on loading, which names
    /// what is wrong with an unreadable one.
    pub fn is_in(dir: &Path) -> bool {
        if RegressorArtifact::is_in(dir) {
            return true;
        }
        if !Ensemble::is_in(dir) {
            return false;
        }
        let Ok(e) = tactile_core::io::read_json::<Ensemble>(&dir.join(Ensemble::FILE)) else {
            return true;
        };
        e.members.first().is_none_or(|m| {
            let mut parts = Path::new(m).components();
            let plain = matches!(
                (parts.next(), parts.next()),
                (Some(std::path::Component::Normal(_)), None)
            );
            !(plain && dir.join(m).is_dir()) || RegressorArtifact::is_in(&dir.join(m))
        })
    }

    /// Load the regressor in `dir`, or every member of the ensemble there,
    /// refusing members that do not take and give what the first does.
    pub fn load(dir: &Path, device: &Device) -> Result<Self> {
        if RegressorArtifact::is_in(dir) {
            return Ok(Self {
                members: vec![Regressor::load(dir, device)?],
            });
        }
        let e = Ensemble::read::<RegressorArtifact>(dir)?;
        let members = e
            .member_dirs(dir)
            .iter()
            .map(|d| Regressor::load(d, device))
            .collect::<Result<Vec<_>>>()?;
        for (d, m) in e.member_dirs(dir).iter().zip(&members).skip(1) {
            check_alike(&members[0].artifact, &m.artifact, d)?;
        }
        Ok(Self { members })
    }

    /// Copy the regressor folders `members` into a new ensemble folder
    /// `out` (see [`Ensemble::assemble`]): they must take the same features
    /// of the same encoder and give the same targets for the same shapes.
    pub fn assemble(members: &[PathBuf], out: &Path) -> Result<Ensemble> {
        Ok(Ensemble::assemble::<RegressorArtifact>(
            members,
            out,
            check_alike,
            |_| Ok(serde_json::json!({})),
            |_| Ok(()),
        )?)
    }

    /// The members, in folder order.
    pub fn members(&self) -> &[Regressor] {
        &self.members
    }

    /// The config, scalers and provenance of the first member.
    pub fn artifact(&self) -> &RegressorArtifact {
        &self.members[0].artifact
    }

    /// The targets, in column order.
    pub fn targets(&self) -> &[Target] {
        &self.artifact().model.targets
    }

    /// Predictions, one row of target values per feature vector: the mean
    /// of the members' outputs before decoding, so angles average on their
    /// circle.
    pub fn predict(&self, x: &[Vec<f32>]) -> Result<Vec<Vec<f64>>> {
        let mut sum = self.members[0].predict_columns(x)?;
        for m in &self.members[1..] {
            for (s, row) in sum.iter_mut().zip(m.predict_columns(x)?) {
                s.iter_mut().zip(row).for_each(|(a, b)| *a += b);
            }
        }
        let n = self.members.len() as f64;
        Ok(sum
            .iter()
            .map(|cols| {
                let mean: Vec<f64> = cols.iter().map(|v| v / n).collect();
                decode_columns(self.targets(), &mean)
            })
            .collect())
    }

    /// Mean absolute error per target on `(x, y)`.
    pub fn evaluate(&self, x: &[Vec<f32>], y: &[Vec<f64>]) -> Result<Vec<f64>> {
        Ok(target_mae(self.targets(), &self.predict(x)?, y))
    }
}

/// Members must read the same features (count and encoder) and answer the
/// same targets for the same shapes as the first.
fn check_alike(
    first: &RegressorArtifact,
    other: &RegressorArtifact,
    dir: &Path,
) -> tactile_core::Result<()> {
    let differs = if first.model.inputs != other.model.inputs {
        Some("takes another feature count")
    } else if first.model.targets != other.model.targets {
        Some("answers other targets")
    } else if first.encoder != other.encoder {
        Some("was trained on another encoder's features")
    } else if first.shapes != other.shapes {
        Some("answers for other shapes")
    } else {
        None
    };
    match differs {
        Some(what) => Err(tactile_core::Error::model(
            dir.join(RegressorArtifact::CONFIG_FILE),
            format!(
                "this member {what} than the first; an ensemble averages regressors trained alike"
            ),
        )),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::registry::Estimators;
    use crate::regressor::RegressorConfig;
    use crate::regressor::tests::data;
    use tactile_burn::DeviceKind;
    use tactile_burn::train::Schedule;

    fn train(targets: Vec<Target>, seed: u64, epochs: usize, dir: &Path) -> Regressor {
        let (x, y) = data(300, 0);
        let (vx, vy) = data(80, 1000);
        let y: Vec<Vec<f64>> = y.iter().map(|r| r[..targets.len()].to_vec()).collect();
        let vy: Vec<Vec<f64>> = vy.iter().map(|r| r[..targets.len()].to_vec()).collect();
        let cfg = RegressorConfig::new(3, targets)
            .with_schedule(Schedule::new(64, epochs, 40, 1e-3).with_seed(seed));
        let r = Regressor::train(cfg, (&x, &y), (&vx, &vy), &DeviceKind::Flex.device()).unwrap();
        r.save(dir).unwrap();
        r
    }

    fn angle_gap(a: f64, b: f64) -> f64 {
        let d = (a - b).rem_euclid(180.0);
        d.min(180.0 - d)
    }

    #[test]
    fn an_ensemble_averages_lines_and_angles_on_the_circle_and_runs_as_one_estimator() {
        let dev = DeviceKind::Flex.device();
        let tmp = tempfile::tempdir().unwrap();
        let targets = vec![Target::linear("a"), Target::angle("theta_deg", 180.0)];
        let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
        let ra = train(targets.clone(), 7, 150, &a);
        let rb = train(targets.clone(), 8, 150, &b);
        // Inside an encoder folder the ensemble is one estimator; its
        // members, a level down, are not run on their own.
        let encoder = tmp.path().join("encoder");
        let e = RegressorEnsemble::assemble(&[a, b], &encoder.join("pose")).unwrap();
        assert_eq!(e.members, ["member-0", "member-1"]);
        // An ensemble of another kind of model kept there is not run.
        std::fs::create_dir_all(encoder.join("pose-networks/member-0")).unwrap();
        std::fs::write(
            encoder.join("pose-networks/ensemble.json"),
            r#"{"members": ["member-0"]}"#,
        )
        .unwrap();
        std::fs::write(encoder.join("pose-networks/member-0/pose.json"), "{}").unwrap();
        let est = Estimators::load(&encoder, &[], &dev).unwrap();
        assert_eq!(est.len(), 1);
        let (tx, ty) = data(120, 5000);
        let out = est.estimate(&tx).unwrap();
        assert_eq!(
            out.columns.iter().map(|c| c.0.as_str()).collect::<Vec<_>>(),
            ["a", "theta_deg"]
        );
        let ens = RegressorEnsemble::load(&encoder.join("pose"), &dev).unwrap();
        let (pa, pb, pe) = (
            ra.predict(&tx).unwrap(),
            rb.predict(&tx).unwrap(),
            ens.predict(&tx).unwrap(),
        );
        for ((a, b), e) in pa.iter().zip(&pb).zip(&pe) {
            assert!(
                (e[0] - (a[0] + b[0]) / 2.0).abs() < 1e-4,
                "{a:?} {b:?} {e:?}"
            );
            // On the shorter arc between the members' angles: averaged as
            // cos/sin pairs, not as degrees, which across the wrap at
            // +-90 would land on the far side.
            let span = angle_gap(a[1], b[1]);
            assert!(
                angle_gap(e[1], a[1]) <= span + 1e-3 && angle_gap(e[1], b[1]) <= span + 1e-3,
                "{a:?} {b:?} {e:?}"
            );
        }
        let (ea, eb, ee) = (
            ra.evaluate(&tx, &ty).unwrap(),
            rb.evaluate(&tx, &ty).unwrap(),
            ens.evaluate(&tx, &ty).unwrap(),
        );
        for j in 0..2 {
            assert!(ee[j] <= ea[j].max(eb[j]), "{ea:?} {eb:?} {ee:?}");
        }
    }

    #[test]
    fn members_trained_on_other_targets_are_refused_naming_the_member() {
        let tmp = tempfile::tempdir().unwrap();
        let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
        train(vec![Target::linear("a"), Target::linear("b")], 7, 2, &a);
        train(vec![Target::linear("a")], 7, 2, &b);
        let err = RegressorEnsemble::assemble(&[a.clone(), b.clone()], &tmp.path().join("e"))
            .err()
            .unwrap()
            .to_string();
        assert!(
            err.contains("answers other targets") && err.contains("b/regressor.json"),
            "{err}"
        );
        assert!(!tmp.path().join("e").exists());
        // An ensemble edited afterwards to hold one is refused on loading.
        let ens = tmp.path().join("ok");
        RegressorEnsemble::assemble(&[a.clone(), a], &ens).unwrap();
        std::fs::remove_dir_all(ens.join("member-1")).unwrap();
        let copy = |f: &str| std::fs::copy(b.join(f), ens.join("member-1").join(f)).unwrap();
        std::fs::create_dir(ens.join("member-1")).unwrap();
        copy("regressor.json");
        copy("regressor.bpk");
        let err = RegressorEnsemble::load(&ens, &DeviceKind::Flex.device())
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("member-1/regressor.json"), "{err}");
    }
}
