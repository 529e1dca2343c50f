//! A trained model on disk: `cae.json` (architecture + preprocessing +
//! training summary) beside `cae.bpk` (burnpack weights).

use std::path::{Path, PathBuf};

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

pub use tactile_core::module_io::{load_module, module_bytes, save_module};

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
