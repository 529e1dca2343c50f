//! Regressors trained alike on one encoder's features (other seeds: other
//! initial weights and other early-stopping frames), averaged as one
//! estimator: an `ensemble.json` folder ([`tactile_burn::ensemble`]) whose
//! members are regressor folders. Each member's error is partly its own
//! training's; the average cancels that part, at the members' summed cost,
//! which beside an encoder is small.

use std::path::{Path, PathBuf};

use burn::tensor::Device;
use tactile_burn::Artifact;
use tactile_burn::ensemble::{CALIBRATION_NOTE, Ensemble};

use crate::Result;
use crate::regressor::{Regressor, RegressorArtifact, decode_columns, target_mae};
use crate::target::Target;
use crate::uncertainty::{Mixture, UncertaintyFit, ValuesWithStd};

/// One regressor, or an ensemble of them whose estimates are averaged: a
/// regressor folder as the estimators load it.
pub struct RegressorEnsemble {
    /// The members (at least one), the first one's config standing for all
    /// (they share inputs, targets, encoder and shapes).
    members: Vec<Regressor>,
    /// With uncertainty, the factors a calibration of the ensemble as a
    /// whole put in `ensemble.json`, applied to the members' combined
    /// deviation (each member keeps its own factors).
    std_factor: Option<Vec<f64>>,
    /// Where its deviations were last calibrated (`tactile train
    /// calibrate`), from its notes.
    calibration: Option<serde_json::Value>,
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
            let r = Regressor::load(dir, device)?;
            let calibration = r.artifact.notes.get(CALIBRATION_NOTE).cloned();
            return Ok(Self {
                members: vec![r],
                std_factor: None,
                calibration,
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
        let std_factor = e.std_scale(dir, members[0].targets().len())?;
        Ok(Self {
            members,
            std_factor,
            calibration: e.notes.get(CALIBRATION_NOTE).cloned(),
        })
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

    /// Each member's provenance notes (`trained_on`, `every_split`,
    /// `excluded_test` when its training recorded them).
    pub fn member_notes(&self) -> Vec<&serde_json::Value> {
        self.members.iter().map(|m| &m.artifact.notes).collect()
    }

    /// The targets, in column order.
    pub fn targets(&self) -> &[Target] {
        &self.artifact().model.targets
    }

    /// Predictions, one row of target values per feature vector: the mean
    /// of the members' outputs before decoding, so angles average on their
    /// circle.
    pub fn predict(&self, x: &[Vec<f32>]) -> Result<Vec<Vec<f64>>> {
        Ok(self.predict_with_std(x)?.0)
    }

    /// Whether it gives each target's standard deviation.
    pub fn has_uncertainty(&self) -> bool {
        self.artifact().model.has_uncertainty()
    }

    /// [`Self::predict`] and, with uncertainty, each target's standard
    /// deviation in the labels' units: the members' mean variance plus
    /// their spread, times the ensemble's own factors when it was
    /// calibrated as a whole (one member: its own deviation).
    pub fn predict_with_std(&self, x: &[Vec<f32>]) -> Result<ValuesWithStd> {
        // Per vector and column, the members' estimates (with uncertainty
        // every target is linear: a column is a target, and has a deviation).
        let mut mix: Vec<Vec<Mixture>> = Vec::new();
        for m in &self.members {
            let (cols, std) = m.predict_columns_with_std(x)?;
            mix.resize_with(cols.len(), Vec::new);
            for (i, (acc, row)) in mix.iter_mut().zip(&cols).enumerate() {
                acc.resize(row.len(), Mixture::default());
                for (j, (a, v)) in acc.iter_mut().zip(row).enumerate() {
                    a.add(*v, std.as_ref().map_or(0.0, |s| s[i][j]));
                }
            }
        }
        let values = mix
            .iter()
            .map(|row| {
                let mean: Vec<f64> = row.iter().map(Mixture::mean).collect();
                decode_columns(self.targets(), &mean)
            })
            .collect();
        let factor = |j: usize| self.std_factor.as_ref().map_or(1.0, |f| f[j]);
        let std = self.has_uncertainty().then(|| {
            mix.iter()
                .map(|row| {
                    row.iter()
                        .enumerate()
                        .map(|(j, a)| a.std() * factor(j))
                        .collect()
                })
                .collect()
        });
        Ok((values, std))
    }

    /// Where its deviations were last calibrated on frames it never
    /// fitted (data, split, frames and the cross-fitted coverage), when
    /// they were.
    pub fn calibration(&self) -> Option<&serde_json::Value> {
        self.calibration.as_ref()
    }

    /// Calibrate the deviations of this regressor (or ensemble), loaded
    /// from `dir`, on feature vectors `x` and their labels `y` (frames it
    /// never fitted: `data`'s rows of `split`, recorded in its notes): one
    /// factor per target so ±1 deviation holds 68.3 % of their errors. The
    /// estimates are unchanged; `regressor.json` (an ensemble's
    /// `ensemble.json`) is rewritten atomically.
    pub fn calibrate_on(
        &self,
        dir: &Path,
        (x, y): (&[Vec<f32>], &[Vec<f64>]),
        (data, split): (&Path, Option<&str>),
        fitted_frames: Option<String>,
    ) -> Result<UncertaintyFit> {
        let before = self.factors(dir)?;
        let (values, std) = self.predict_with_std(x)?;
        let std = std.ok_or_else(|| no_uncertainty(dir))?;
        let mut fit = crate::uncertainty::fit(self.targets(), (&values, y), &std, before);
        fit.fitted_frames = fitted_frames;
        self.write_factors(dir, &fit.std_scale, fit.note(data, split))?;
        Ok(fit)
    }

    /// Give the regressor (or ensemble) in `dir` the factors of the
    /// validated one of the same recipe in `from`: one trained on every
    /// frame has none left to calibrate on.
    pub fn calibration_from(dir: &Path, from: &Path, device: &Device) -> Result<UncertaintyFit> {
        let (model, source) = (Self::load(dir, device)?, Self::load(from, device)?);
        let (before, scale) = (model.factors(dir)?, source.factors(from)?);
        // An ensemble's factors scale its combined deviation, a
        // regressor's its own.
        let same_kind = RegressorArtifact::is_in(from) == RegressorArtifact::is_in(dir);
        UncertaintyFit::check_taken(
            from,
            (source.targets() == model.targets(), same_kind),
            "regressor",
        )?;
        let (fit, note) =
            UncertaintyFit::taken(model.targets(), before, scale, (from, source.calibration));
        model.write_factors(dir, &fit.std_scale, note)?;
        Ok(fit)
    }

    /// The factors calibration changes: a regressor's own, an ensemble's
    /// as a whole (1 until it is calibrated so).
    fn factors(&self, dir: &Path) -> Result<Vec<f64>> {
        if !self.has_uncertainty() {
            return Err(no_uncertainty(dir));
        }
        let k = self.targets().len();
        Ok(if RegressorArtifact::is_in(dir) {
            self.artifact()
                .std_scale
                .clone()
                .unwrap_or_else(|| vec![1.0; k])
        } else {
            self.std_factor.clone().unwrap_or_else(|| vec![1.0; k])
        })
    }

    /// Write `scale` where [`Self::factors`] reads it, with `note`.
    fn write_factors(&self, dir: &Path, scale: &[f64], note: serde_json::Value) -> Result<()> {
        if RegressorArtifact::is_in(dir) {
            let mut a = self.artifact().clone();
            a.std_scale = Some(scale.to_vec());
            if !a.notes.is_object() {
                a.notes = serde_json::json!({});
            }
            a.notes[CALIBRATION_NOTE] = note;
            return Ok(tactile_core::io::write_json_atomic(
                dir.join(RegressorArtifact::CONFIG_FILE),
                &a,
            )?);
        }
        Ok(Ensemble::read::<RegressorArtifact>(dir)?.write_std_scale(dir, scale, note)?)
    }

    /// Mean absolute error per target on `(x, y)`.
    pub fn evaluate(&self, x: &[Vec<f32>], y: &[Vec<f64>]) -> Result<Vec<f64>> {
        Ok(target_mae(self.targets(), &self.predict(x)?, y))
    }
}

fn no_uncertainty(dir: &Path) -> crate::Error {
    tactile_core::Error::model(
        dir,
        "this regressor gives no uncertainty (train it with --uncertainty)",
    )
    .into()
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
    } else if first.model.has_uncertainty() != other.model.has_uncertainty() {
        Some("gives an uncertainty otherwise")
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
    use crate::registry::{Column, Estimators};
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
        let c = tmp.path().join("c");
        train(vec![Target::linear("a"), Target::linear("b")], 8, 2, &c);
        RegressorEnsemble::assemble(&[a, c], &ens).unwrap();
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

    #[test]
    fn an_ensembles_deviations_are_calibrated_as_a_whole_and_run_as_std_columns() {
        let dev = DeviceKind::Flex.device();
        let tmp = tempfile::tempdir().unwrap();
        let (x, y, _) = crate::regressor::tests::noisy(1200, 1);
        let (vx, vy, _) = crate::regressor::tests::noisy(300, 2);
        let member = |seed: u64, uncertain: bool| {
            let dir = tmp.path().join(format!("m{seed}-{uncertain}"));
            let cfg =
                RegressorConfig::new(2, vec![Target::linear("depth"), Target::linear("shear")])
                    .with_schedule(Schedule::new(64, 80, 20, 3e-3).with_seed(seed))
                    .with_uncertainty(uncertain.then_some(true));
            Regressor::train(cfg, (&x, &y), (&vx, &vy), &dev)
                .unwrap()
                .save(&dir)
                .unwrap();
            dir
        };
        let (a, b) = (member(7, true), member(8, true));
        // A member without uncertainty is not averaged with them.
        let err =
            RegressorEnsemble::assemble(&[a.clone(), member(9, false)], &tmp.path().join("no"))
                .err()
                .unwrap()
                .to_string();
        assert!(err.contains("gives an uncertainty otherwise"), "{err}");
        let encoder = tmp.path().join("encoder");
        let ens = encoder.join("pose");
        RegressorEnsemble::assemble(&[a, b], &ens).unwrap();
        // Before calibration as a whole the spread widens the deviation;
        // calibrated on 600 other rows, ±1 holds 68.3 % of a third set's
        // errors.
        let (cx, cy, _) = crate::regressor::tests::noisy(600, 3);
        let fit = RegressorEnsemble::load(&ens, &dev)
            .unwrap()
            .calibrate_on(&ens, (&cx, &cy), (tmp.path(), Some("val")), None)
            .unwrap();
        assert_eq!(
            (fit.frames, fit.std_scale_before.clone()),
            (600, vec![1.0, 1.0])
        );
        let e = Ensemble::read::<RegressorArtifact>(&ens).unwrap();
        let kept = e.std_scale(&ens, 2).unwrap().unwrap();
        assert!(
            kept.iter()
                .zip(&fit.std_scale)
                .all(|(a, b)| (a - b).abs() < 1e-9 * b),
            "{kept:?} {:?}",
            fit.std_scale
        );
        let est = Estimators::load(&encoder, &[], &dev).unwrap();
        let (tx, ty, _) = crate::regressor::tests::noisy(2000, 4);
        let out = est.estimate(&tx).unwrap();
        let (Some(Column::Number(v)), Some(Column::Number(s))) =
            (out.get("shear"), out.get("shear_std"))
        else {
            panic!("{:?}", out.columns.iter().map(|c| &c.0).collect::<Vec<_>>());
        };
        let inside = v
            .iter()
            .zip(s)
            .zip(&ty)
            .filter(|((v, s), t)| (*v - t[1]).abs() <= **s)
            .count();
        let c68 = inside as f64 / ty.len() as f64;
        assert!((0.63..0.76).contains(&c68), "{c68}");
        assert_eq!(est.calibration().unwrap()["frames"], 600);
        // Another ensemble of the recipe takes those factors; a lone
        // regressor does not (its factors scale its own deviation, an
        // ensemble's the combined one).
        let (c, d) = (member(11, true), member(12, true));
        let other = tmp.path().join("other");
        RegressorEnsemble::assemble(&[c.clone(), d], &other).unwrap();
        let taken = RegressorEnsemble::calibration_from(&other, &ens, &dev).unwrap();
        assert_eq!((taken.frames, &taken.std_scale), (0, &kept));
        let err = RegressorEnsemble::calibration_from(&c, &ens, &dev)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("a regressor's to a regressor"), "{err}");
        // A regressor of no uncertainty is refused, naming its folder.
        let plain = member(10, false);
        let err = RegressorEnsemble::load(&plain, &dev)
            .unwrap()
            .calibrate_on(&plain, (&cx, &cy), (tmp.path(), None), None)
            .err()
            .unwrap()
            .to_string();
        assert!(
            err.contains("gives no uncertainty") && err.contains("m10-false"),
            "{err}"
        );
    }
}
