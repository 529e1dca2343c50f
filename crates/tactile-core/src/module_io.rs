//! Saving and loading burn modules as burnpack files; errors name the file.

use std::path::Path;

use burn::module::Module;
use burn::store::ModuleRecord;

use crate::{Error, Result};

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
    crate::io::write_atomic(path, &module_bytes(module, path)?)
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
