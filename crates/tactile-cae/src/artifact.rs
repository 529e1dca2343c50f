//! A trained model on disk: `cae.json` (architecture + preprocessing +
//! training summary) beside `cae.bpk` (burnpack weights).

use std::path::{Path, PathBuf};

use burn::module::Module;
use burn::store::ModuleRecord;
use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_core::{Error, Result};
use tactile_preprocess::PreprocessConfig;

use crate::model::{Cae, CaeConfig};

/// Everything needed to rebuild and use a saved autoencoder.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CaeArtifact {
    pub cae: CaeConfig,
    pub preprocess: PreprocessConfig,
    /// Free-form provenance: how it was trained, on what, with which result.
    #[serde(default)]
    pub notes: serde_json::Value,
}

/// File names inside a model folder.
pub const CONFIG_FILE: &str = "cae.json";
pub const WEIGHTS_FILE: &str = "cae.bpk";

/// Serialise a module's weights to burnpack bytes.
pub fn module_bytes<M: Module>(module: &M, path: &Path) -> Result<Vec<u8>> {
    let bytes = module
        .clone()
        .into_record()
        .into_bytes()
        .map_err(|e| Error::model(path, format!("cannot serialise weights: {e}")))?;
    Ok(bytes.to_vec())
}

/// Save a module's weights atomically.
pub fn save_module<M: Module>(module: &M, path: &Path) -> Result<()> {
    tactile_core::io::write_atomic(path, &module_bytes(module, path)?)
}

/// Load weights into a freshly built module; errors name the file.
pub fn load_module<M: Module>(module: M, path: &Path) -> Result<M> {
    if !path.is_file() {
        return Err(Error::model(path, "weights file does not exist"));
    }
    let record = ModuleRecord::load(path).map_err(|e| Error::model(path, e.to_string()))?;
    module
        .try_load_record(record)
        .map_err(|e| Error::model(path, e.to_string()))
}

impl CaeArtifact {
    /// Save config and weights into `dir` (created if needed).
    pub fn save(&self, model: &Cae, dir: impl AsRef<Path>) -> Result<()> {
        let dir = dir.as_ref();
        tactile_core::io::create_dir_all(dir)?;
        save_module(model, &dir.join(WEIGHTS_FILE))?;
        tactile_core::io::write_json_atomic(dir.join(CONFIG_FILE), self)
    }

    /// Load config and weights from `dir` onto `device`.
    pub fn load(dir: impl AsRef<Path>, device: &Device) -> Result<(Self, Cae)> {
        let dir = dir.as_ref();
        let cfg_path: PathBuf = dir.join(CONFIG_FILE);
        if !cfg_path.is_file() {
            return Err(Error::model(
                &cfg_path,
                "not a model folder: missing cae.json",
            ));
        }
        let art: CaeArtifact = tactile_core::io::read_json(&cfg_path)?;
        let model = load_module(art.cae.init(device), &dir.join(WEIGHTS_FILE))?;
        Ok((art, model))
    }
}
