//! A trained model on disk: `cae.json` (architecture + preprocessing +
//! training summary) beside `cae.bpk` (burnpack weights).

use std::path::Path;

use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_core::Result;
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
        tactile_core::module_io::save_artifact(
            dir.as_ref(),
            (CONFIG_FILE, WEIGHTS_FILE),
            self,
            model,
        )
    }

    /// Load config and weights from `dir` onto `device`.
    pub fn load(dir: impl AsRef<Path>, device: &Device) -> Result<(Self, Cae)> {
        tactile_core::module_io::load_artifact(
            dir.as_ref(),
            (CONFIG_FILE, WEIGHTS_FILE),
            "model",
            |a: &Self| Ok(a.cae.init(device)),
        )
    }
}
