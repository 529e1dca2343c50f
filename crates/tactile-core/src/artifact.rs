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

    /// True when `dir` holds this kind of model.
    fn is_in(dir: &Path) -> bool {
        dir.join(Self::CONFIG_FILE).is_file()
    }

    /// Save the config and the weights into `dir` (created if needed),
    /// each atomically, the config last.
    fn save(&self, model: &Self::Model, dir: &Path) -> Result<()> {
        crate::io::create_dir_all(dir)?;
        crate::module_io::save_module(model, &dir.join(Self::WEIGHTS_FILE))?;
        crate::io::write_json_atomic(dir.join(Self::CONFIG_FILE), self)
    }

    /// Read and check the config alone.
    fn read(dir: &Path) -> Result<Self> {
        let file = dir.join(Self::CONFIG_FILE);
        if !dir.is_dir() {
            return Err(Error::not_found(dir, format!("{} folder", Self::KIND)));
        }
        if !file.is_file() {
            return Err(Error::wrong_kind(
                dir,
                format!("{} folder", Self::KIND),
                format!("no {}", Self::CONFIG_FILE),
            ));
        }
        let artifact: Self = crate::io::read_json(&file)?;
        artifact.check(&file)?;
        Ok(artifact)
    }

    /// Load config and weights from `dir` onto `device`.
    fn load(dir: &Path, device: &Device) -> Result<Loaded<Self>> {
        let artifact = Self::read(dir)?;
        let model =
            crate::module_io::load_module(artifact.init(device)?, &dir.join(Self::WEIGHTS_FILE))?;
        Ok(Loaded {
            artifact,
            model,
            dir: dir.to_path_buf(),
            device: device.clone(),
        })
    }
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
    crate::io::write_json_atomic(dir.join("training.json"), &record)
}
