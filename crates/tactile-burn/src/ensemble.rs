//! A folder of models trained alike, whose outputs are averaged:
//! `ensemble.json` names member folders inside it. Averaging cancels the
//! part of each model's error its own training made, at the sum of the
//! members' costs. Reading, checking and assembling such a folder is
//! written once, here, for every kind of model ([`Artifact`]).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::artifact::TRAINING_FILE;
use crate::{Artifact, Error, Result};

/// What `ensemble.json` holds.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Ensemble {
    /// Member folder names, inside the ensemble's folder.
    pub members: Vec<String>,
    /// Provenance: where the members were copied from, and what the kind
    /// of model adds (a pose ensemble's `excluded_test`, a detector
    /// ensemble's calibration).
    #[serde(default)]
    pub notes: serde_json::Value,
}

/// The key under which a model's notes say where its deviations were last
/// calibrated on frames it never fitted (data, split, frames, cross-fitted
/// coverage), or whose factors it took.
pub const CALIBRATION_NOTE: &str = "uncertainty_calibration";

impl Ensemble {
    /// The file that makes a folder an ensemble.
    pub const FILE: &'static str = "ensemble.json";
    /// Most members an ensemble may name.
    pub const MAX_MEMBERS: usize = 8;

    /// Whether `dir` holds an ensemble.
    pub fn is_in(dir: &Path) -> bool {
        dir.join(Self::FILE).exists()
    }

    /// Whether `dir` holds an ensemble of `A`s: `ensemble.json` and a
    /// folder in it holding an `A` (an ensemble of another kind of model
    /// is not one; a broken ensemble of `A`s still is, to be refused by
    /// [`Self::read`] with its reason).
    pub fn is_of<A: Artifact>(dir: &Path) -> bool {
        Self::is_in(dir)
            && std::fs::read_dir(dir)
                .is_ok_and(|rd| rd.take(1000).flatten().any(|e| A::is_in(&e.path())))
    }

    /// Read and check `dir/ensemble.json`: 1 to [`Self::MAX_MEMBERS`]
    /// members, each a plain folder name inside `dir` (no path, so nothing
    /// outside the folder is read), each holding an `A`.
    pub fn read<A: Artifact>(dir: &Path) -> Result<Self> {
        let file = dir.join(Self::FILE);
        let e: Self = tactile_core::io::read_json(&file)?;
        let bad = |m: String| Err(Error::model(&file, m));
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
            if !A::is_in(&dir.join(m)) {
                return bad(format!("member {m:?} holds no {}", A::CONFIG_FILE));
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

    /// One line: how many models (`what`, plural) are averaged, and where.
    pub fn describe(&self, dir: &Path, what: &str) -> String {
        format!(
            "{} {what} averaged in {}",
            self.members.len(),
            dir.display()
        )
    }

    /// The factors a calibration of the ensemble as a whole (`tactile
    /// train calibrate`) put in its notes, one per target, applied to the
    /// members' combined deviation; `None` when it was never calibrated as
    /// a whole. `dir` is the ensemble's folder, named in the error.
    pub fn std_scale(&self, dir: &Path, targets: usize) -> Result<Option<Vec<f64>>> {
        let Some(v) = self.notes.get("std_scale") else {
            return Ok(None);
        };
        let bad = || {
            Error::model(
                dir.join(Self::FILE),
                format!("notes.std_scale must be {targets} positive numbers, one per target"),
            )
        };
        let f: Vec<f64> = serde_json::from_value(v.clone()).map_err(|_| bad())?;
        if f.len() != targets || f.iter().any(|x| !x.is_finite() || *x <= 0.0) {
            return Err(bad());
        }
        Ok(Some(f))
    }

    /// Rewrite `dir`'s `ensemble.json` (atomically; no member is touched)
    /// with the factors `scale` of a calibration as a whole (see
    /// [`Self::std_scale`]), its notes saying where they came from.
    pub fn write_std_scale(
        mut self,
        dir: &Path,
        scale: &[f64],
        note: serde_json::Value,
    ) -> Result<()> {
        if !self.notes.is_object() {
            self.notes = serde_json::json!({});
        }
        self.notes["std_scale"] = serde_json::json!(scale);
        self.notes[CALIBRATION_NOTE] = note;
        tactile_core::io::write_json_atomic(dir.join(Self::FILE), &self)
    }

    /// The member folders.
    pub fn member_dirs(&self, dir: &Path) -> Vec<PathBuf> {
        self.members.iter().map(|m| dir.join(m)).collect()
    }

    /// The ensemble in `dir` (a `what` folder; `ensemble.json` checked by
    /// [`Self::read`]) and every member's config, in order.
    pub fn read_with_configs<A: Artifact>(dir: &Path, what: &str) -> Result<(Self, Vec<A>)> {
        tactile_core::io::expect_folder(dir, &format!("{what} folder"))?;
        let e = Self::read::<A>(dir)?;
        let configs = e
            .member_dirs(dir)
            .iter()
            .map(|d| A::read(d))
            .collect::<Result<Vec<_>>>()?;
        Ok((e, configs))
    }

    /// The members' networks with fresh weights (the shapes their saved
    /// weights fill), from their configs; none is refused, naming `what`.
    pub fn init_members<A: Artifact>(
        members: &[A],
        device: &burn::tensor::Device,
        what: &str,
    ) -> Result<Vec<A::Model>> {
        if members.is_empty() {
            return Err(Error::Invalid(format!("a {what} without members")));
        }
        members.iter().map(|m| m.init(device)).collect()
    }

    /// The members' networks, each loaded (and checked) from its folder
    /// inside the ensemble's folder `dir`.
    pub fn load_members<A: Artifact>(
        &self,
        dir: &Path,
        device: &burn::tensor::Device,
    ) -> Result<Vec<A::Model>> {
        self.member_dirs(dir)
            .iter()
            .map(|d| Ok(A::load(d, device)?.model))
            .collect()
    }

    /// Every member into its folder inside `dir` (weights, then config),
    /// then `ensemble.json`, each atomically.
    pub fn save_members<A: Artifact>(
        &self,
        members: &[A],
        models: &[A::Model],
        dir: &Path,
    ) -> Result<()> {
        for ((m, net), d) in members.iter().zip(models).zip(self.member_dirs(dir)) {
            m.save(net, &d)?;
        }
        tactile_core::io::write_json_atomic(dir.join(Self::FILE), self)
    }

    /// Copy the `A` folders `members` (config, weights and the training
    /// record when there is one) into a new
    /// ensemble folder `out` as `member-0`, `member-1`, ... (staged, then
    /// moved into place; an existing `out` is left alone). `alike` refuses
    /// a member that does not read its input or give its output as the
    /// first one does; `notes` makes what the kind of model adds to the
    /// ensemble's provenance from the members' configs (or refuses them);
    /// `prepare` may rewrite each copied member folder before the ensemble
    /// is moved into place (a detector unfolds its calibration there).
    pub fn assemble<A: Artifact>(
        members: &[PathBuf],
        out: &Path,
        alike: impl Fn(&A, &A, &Path) -> Result<()>,
        notes: impl FnOnce(&[A]) -> Result<serde_json::Value>,
        prepare: impl Fn(&Path) -> Result<()>,
    ) -> Result<Self> {
        // One model alone is no average (reading a folder of one, made by
        // hand, is still allowed).
        let n = members.len();
        if !(2..=Self::MAX_MEMBERS).contains(&n) {
            return Err(Error::Invalid(format!(
                "an ensemble averages 2 to {} models trained apart, got {n}",
                Self::MAX_MEMBERS
            )));
        }
        let arts = members
            .iter()
            .map(|m| A::read(m))
            .collect::<Result<Vec<_>>>()?;
        for (m, a) in members.iter().zip(&arts).skip(1) {
            alike(&arts[0], a, m)?;
        }
        // One model twice (a folder given twice, or a plain copy) would
        // count its error twice and hide the spread the deviations add.
        // The same weights read or calibrated another way are another model.
        let identity = |m: &Path| -> Result<(String, Vec<u8>)> {
            let config = m.join(A::CONFIG_FILE);
            let bytes = tactile_core::io::read_limited(&config, tactile_core::io::MAX_JSON_BYTES)?;
            Ok((crate::artifact::fingerprint::<A>(m)?, bytes))
        };
        let identities = members
            .iter()
            .map(|m| identity(m))
            .collect::<Result<Vec<_>>>()?;
        for (k, id) in identities.iter().enumerate() {
            if let Some(j) = identities[..k].iter().position(|other| other == id) {
                return Err(Error::model(
                    &members[k],
                    format!(
                        "the same model as {} (identical config and weights): an ensemble \
                         averages networks trained apart (with another --seed); give each once",
                        members[j].display()
                    ),
                ));
            }
        }
        let notes = notes(&arts)?;
        let staged = tactile_core::io::StagedDir::new(out)?;
        let mut names = Vec::new();
        for (k, m) in members.iter().enumerate() {
            let name = format!("member-{k}");
            let to = staged.path().join(&name);
            tactile_core::io::create_dir_all(&to)?;
            for f in [A::CONFIG_FILE, A::WEIGHTS_FILE, TRAINING_FILE] {
                if f == TRAINING_FILE && !m.join(f).is_file() {
                    continue;
                }
                std::fs::copy(m.join(f), to.join(f)).map_err(|e| Error::io(m.join(f), e))?;
            }
            prepare(&to)?;
            names.push(name);
        }
        let mut all_notes = serde_json::json!({
            "members_from": members.iter().map(|m| m.display().to_string()).collect::<Vec<_>>(),
        });
        if let (Some(all), serde_json::Value::Object(more)) = (all_notes.as_object_mut(), notes) {
            all.extend(more);
        }
        let e = Self {
            members: names,
            notes: all_notes,
        };
        tactile_core::io::write_json_atomic(staged.path().join(Self::FILE), &e)?;
        staged.commit(false)?;
        Ok(e)
    }
}
