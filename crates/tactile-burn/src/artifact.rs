//! A trained model on disk: one folder with a JSON config (architecture,
//! input statistics, thresholds, provenance) beside a burnpack weights file,
//! and `training.json` when it was trained here. Every model of the
//! workspace is an [`Artifact`]; saving, loading and the checks on load are
//! written once, here.

use std::path::{Path, PathBuf};

use burn::module::Module;
use burn::tensor::Device;
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::train::FitSummary;
use crate::{Error, Result};

/// What a model folder holds and how to rebuild the network from it.
pub trait Artifact: Serialize + DeserializeOwned + Clone + Sized {
    /// The network.
    type Model: Module;
    /// What the folder is, in words ("detector", "CAE encoder").
    const KIND: &'static str;
    /// The JSON file (`detector.json`).
    const CONFIG_FILE: &'static str;
    /// The weights file (`detector.bpk`).
    const WEIGHTS_FILE: &'static str;

    /// The network with fresh weights (the shapes the saved weights fill).
    fn init(&self, device: &Device) -> Result<Self::Model>;

    /// Checks of a loaded config beyond its syntax (sizes, statistics,
    /// thresholds); `file` is the config file, for the message.
    fn check(&self, _file: &Path) -> Result<()> {
        Ok(())
    }

    /// True when `dir` holds this kind of model (its config, even one
    /// that is no regular file, so that loading it says so).
    fn is_in(dir: &Path) -> bool {
        dir.join(Self::CONFIG_FILE).exists()
    }

    /// Before a trainer reads a frame: `out` can take a model of this kind
    /// trained on `datasets` ([`tactile_core::dataset::check_model_dir`]
    /// with this kind's config file).
    fn check_out_dir(
        out: &Path,
        datasets: &[&tactile_core::dataset::Dataset],
    ) -> tactile_core::Result<()> {
        tactile_core::dataset::check_model_dir(out, datasets, Self::CONFIG_FILE)
    }

    /// Save the config and the weights into `dir` (created if needed),
    /// each atomically, the config last.
    fn save(&self, model: &Self::Model, dir: &Path) -> Result<()> {
        tactile_core::io::create_dir_all(dir)?;
        crate::module_io::save_module(model, &dir.join(Self::WEIGHTS_FILE))?;
        tactile_core::io::write_json_atomic(dir.join(Self::CONFIG_FILE), self)
    }

    /// Read and check the config alone; a folder whose training did not
    /// finish (see [`Unfinished`]) is refused.
    fn read(dir: &Path) -> Result<Self> {
        if dir.join(INCOMPLETE_FILE).exists() {
            return Err(Error::model(
                dir,
                format!(
                    "this {} did not finish training (interrupted or failed): resume it (--resume; resume=True in Python) or train it again",
                    Self::KIND
                ),
            ));
        }
        Self::read_unfinished(dir)
    }

    /// [`Self::read`] of a folder still being trained (for the trainer's
    /// own last steps, such as calibrating a threshold).
    fn read_unfinished(dir: &Path) -> Result<Self> {
        let file = dir.join(Self::CONFIG_FILE);
        tactile_core::io::expect_folder(dir, &format!("{} folder", Self::KIND))?;
        if !file.exists() {
            // A model of this kind, alone or as an ensemble of them.
            let is_model = |d: &Path| Self::is_in(d) || crate::ensemble::Ensemble::is_of::<Self>(d);
            let hint = folder_hint(dir, is_model, "a model of another kind");
            return Err(Error::wrong_kind(
                dir,
                format!("{} folder", Self::KIND),
                format!("no {}{hint}", Self::CONFIG_FILE),
            ));
        }
        let artifact: Self = tactile_core::io::read_json(&file)?;
        artifact.check(&file)?;
        Ok(artifact)
    }

    /// Load config and weights from `dir` onto `device`.
    fn load(dir: &Path, device: &Device) -> Result<Loaded<Self>> {
        Self::read(dir)?;
        Self::load_unfinished(dir, device)
    }

    /// [`Self::load`] of a folder still being trained.
    fn load_unfinished(dir: &Path, device: &Device) -> Result<Loaded<Self>> {
        let artifact = Self::read_unfinished(dir)?;
        let weights = dir.join(Self::WEIGHTS_FILE);
        let model = crate::module_io::load_module(artifact.init(device)?, &weights)?;
        crate::module_io::check_finite(&model, &weights)?;
        Ok(Loaded {
            artifact,
            model,
            dir: dir.to_path_buf(),
            device: device.clone(),
        })
    }
}

/// Most parameters any model may have (400 MB of weights): a config that
/// would build a larger one is refused before anything is allocated.
pub const MAX_PARAMETERS: u64 = 100_000_000;

/// Refuse `parameters` above [`MAX_PARAMETERS`].
pub fn check_parameters(what: &str, parameters: u64) -> Result<()> {
    if parameters > MAX_PARAMETERS {
        return Err(Error::Config(format!(
            "this {what} would have about {parameters} parameters, more than the {MAX_PARAMETERS} allowed"
        )));
    }
    Ok(())
}

/// The file that marks a model folder whose training has not finished.
pub const INCOMPLETE_FILE: &str = "INCOMPLETE";

/// A training run in progress in a model folder: while it exists the folder
/// holds [`INCOMPLETE_FILE`] and every loader refuses it, so an interrupted
/// or failed run never leaves a complete-looking model (with an
/// uncalibrated threshold, say). It also holds the folder's lock, so a
/// second run into the same folder is refused instead of mixing its
/// weights, curves and checkpoints with the first's.
#[must_use = "call finish() when the model is complete"]
pub struct Unfinished {
    marker: PathBuf,
    _lock: tactile_core::io::FolderLock,
}

impl Unfinished {
    /// Lock `dir` (created if needed, [`tactile_core::io::FolderLock`]) and mark it as being
    /// trained; refused while another run holds it.
    pub fn begin(dir: &Path) -> Result<Self> {
        let lock = tactile_core::io::FolderLock::creating(dir)?;
        let marker = dir.join(INCOMPLETE_FILE);
        tactile_core::io::write_atomic(
            &marker,
            b"training in progress, or interrupted: this model is not complete\n",
        )?;
        Ok(Self {
            marker,
            _lock: lock,
        })
    }

    /// The model is complete: remove the mark (and release the folder).
    pub fn finish(self) -> Result<()> {
        std::fs::remove_file(&self.marker).map_err(|e| Error::io(&self.marker, e))
    }
}

/// The identity of a training run: its config (less the epoch budget,
/// which a resumed run may extend) and each dataset's manifest and labels.
/// A checkpoint records it; resuming with another one is refused.
pub fn run_fingerprint(
    config: &impl Serialize,
    datasets: &[&tactile_core::dataset::Dataset],
) -> Result<String> {
    use sha2::Digest;
    let mut json = serde_json::to_value(config)
        .map_err(|e| Error::Invalid(format!("cannot serialise the training config: {e}")))?;
    if let Some(s) = json.get_mut("schedule").and_then(|s| s.as_object_mut()) {
        s.remove("max_epochs");
    }
    let mut h = sha2::Sha256::new();
    h.update(json.to_string().as_bytes());
    for ds in datasets {
        for f in [ds.root.join("manifest.json"), ds.labels_path()] {
            hash_file(&mut h, &f)?;
        }
    }
    Ok(h.finalize().iter().map(|b| format!("{b:02x}")).collect())
}

/// Feed `path`'s bytes to `h` in pieces: labels may run to millions of
/// rows and weights to a gigabyte, neither worth holding whole.
fn hash_file(h: &mut sha2::Sha256, path: &Path) -> Result<()> {
    let mut file = tactile_core::io::open_regular(path)?;
    std::io::copy(&mut file, h).map_err(|e| Error::io(path, e))?;
    Ok(())
}

/// A model loaded from its folder: config, network and where it runs.
pub struct Loaded<A: Artifact> {
    /// The config.
    pub artifact: A,
    /// The network with its trained weights.
    pub model: A::Model,
    /// The folder it came from.
    pub dir: PathBuf,
    /// The device it is on.
    pub device: Device,
}

/// The identity of a model folder's weights: `sha256:` and the hex digest
/// of its weights file. An estimator records the fingerprint of the
/// encoder it was trained on, so it is never run on another one's features.
pub fn fingerprint<A: Artifact>(dir: &Path) -> Result<String> {
    use sha2::Digest;
    let path = dir.join(A::WEIGHTS_FILE);
    let mut h = sha2::Sha256::new();
    hash_file(&mut h, &path)?;
    let digest = h.finalize();
    Ok(format!(
        "sha256:{}",
        digest
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect::<String>()
    ))
}

/// A config value checked on load: refuse `value` unless `ok`, naming the
/// config `file` and the `field`. The value is said in Rust's shortest
/// form (`1e300`, not its 301 digits).
pub fn check_field(
    file: &Path,
    field: &str,
    ok: bool,
    value: impl std::fmt::Debug,
    need: &str,
) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(Error::model(file, format!("{field} is {value:?}: {need}")))
    }
}

/// The training record beside a model trained here.
pub const TRAINING_FILE: &str = "training.json";

/// Write `training.json` beside a trained model: the training config,
/// the run's summary and anything else worth keeping (`extra`, an object).
pub fn write_training_record(
    dir: &Path,
    config: &impl Serialize,
    summary: &FitSummary,
    extra: serde_json::Value,
) -> Result<()> {
    let mut record = serde_json::json!({ "config": config, "summary": summary });
    if let (Some(r), serde_json::Value::Object(e)) = (record.as_object_mut(), extra) {
        r.extend(e);
    }
    tactile_core::io::write_json_atomic(dir.join(TRAINING_FILE), &record)
}

/// What a folder that is not the model a command wants holds, for its
/// error: the subfolders that are (`is_model`: a user who named the folder
/// above the models), or the configuration files it has, said to be
/// `other` (a model of another kind).
pub fn folder_hint(
    dir: &std::path::Path,
    is_model: impl Fn(&std::path::Path) -> bool,
    other: &str,
) -> String {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return String::new();
    };
    let (mut models, mut configs) = (Vec::new(), Vec::new());
    for e in entries.take(1000).flatten() {
        let (path, name) = (e.path(), e.file_name().to_string_lossy().into_owned());
        if path.is_dir() && is_model(&path) {
            models.push(name);
        } else if name.ends_with(".json") && !name.starts_with("training") {
            configs.push(name);
        }
    }
    models.sort();
    configs.sort();
    let list = |v: &[String]| {
        let mut s = v[..v.len().min(6)].join(", ");
        if v.len() > 6 {
            s.push_str(", ...");
        }
        s
    };
    if models.len() == 1 {
        format!("; the folder {} in it is: pass it", models[0])
    } else if !models.is_empty() {
        format!("; the folders {} in it are: pass one", list(&models))
    } else if !configs.is_empty() {
        format!("; it holds {}: {other}", list(&configs))
    } else {
        String::new()
    }
}

/// When the model of kind `A` in `dir` (an ensemble's every member) was
/// trained on every frame of `ds`, as its notes record
/// ([`Provenance::fitted_every`]), the words saying so: an evaluation on
/// them scores frames it fitted. `None` when it was not, or its notes do
/// not say (models trained before their trainer recorded it).
///
/// [`Provenance::fitted_every`]: tactile_core::dataset::Provenance::fitted_every
pub fn scored_on_fitted<A: Artifact>(
    dir: &Path,
    ds: &tactile_core::dataset::Dataset,
) -> Option<String> {
    use tactile_core::dataset::Provenance;
    let dirs = if crate::ensemble::Ensemble::is_of::<A>(dir) {
        crate::ensemble::Ensemble::read::<A>(dir)
            .ok()?
            .member_dirs(dir)
    } else {
        vec![dir.to_path_buf()]
    };
    dirs.iter().find_map(|d| {
        let art = serde_json::to_value(A::read(d).ok()?).ok()?;
        let p = Provenance::read(art.get("notes")?);
        p.fitted_every(d, ds).then(|| {
            format!(
                "the model trained on every one of these {} frames (its notes: {}), so these scores are on frames it fitted: score it on frames it did not train on (another seed or recording)",
                ds.len(),
                p.names()
            )
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_locked_by_one_run_is_refused_to_another_until_it_ends() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("model");
        let first = Unfinished::begin(&dir).unwrap();
        let e = tactile_core::io::FolderLock::acquire(&dir)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("another run is writing this folder"), "{e}");
        assert!(Unfinished::begin(&dir).is_err());
        first.finish().unwrap();
        drop(tactile_core::io::FolderLock::acquire(&dir).unwrap());
        Unfinished::begin(&dir).unwrap().finish().unwrap();
        assert!(!dir.join(INCOMPLETE_FILE).exists());
    }
}
