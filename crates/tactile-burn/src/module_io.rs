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
    tactile_core::io::write_atomic(path, &module_bytes(module, path)?)
}

/// Refuse a module with a NaN or infinite weight, naming `path`.
pub fn check_finite<M: Module>(module: &M, path: &Path) -> Result<()> {
    struct Finite {
        bad: Option<String>,
    }
    impl burn::module::ModuleVisitor for Finite {
        fn visit_float<const D: usize>(
            &mut self,
            param: &burn::module::Param<burn::tensor::Tensor<D>>,
        ) {
            if self.bad.is_some() {
                return;
            }
            let v = param.val().into_data().convert::<f32>();
            if let Ok(v) = v.as_slice::<f32>()
                && let Some(x) = v.iter().find(|x| !x.is_finite())
            {
                self.bad = Some(format!(
                    "a weight of parameter {:?} is {x}: the model is corrupt (training diverged?)",
                    param.id
                ));
            }
        }
    }
    let mut f = Finite { bad: None };
    module.visit(&mut f);
    match f.bad {
        Some(why) => Err(Error::model(path, why)),
        None => Ok(()),
    }
}

/// Load weights into a freshly built module; errors name the file.
///
/// Every tensor is converted to its parameter's dtype (a record claiming
/// integer weights is converted, not trusted). burn's loader asserts what
/// it cannot convert; such a file is reported as malformed instead of
/// ending the process (found by the `weights` fuzz target).
pub fn load_module<M: Module>(module: M, path: &Path) -> Result<M> {
    if !path.exists() {
        return Err(Error::model(path, "weights file does not exist"));
    }
    // A pipe or a folder named as the weights is refused here, not read.
    tactile_core::io::check_file_size(path, tactile_core::io::MAX_WEIGHTS_BYTES)?;
    let record = ModuleRecord::load(path)
        .map_err(|e| Error::model(path, e.to_string()))?
        .cast_to_module_dtype();
    let load = std::panic::AssertUnwindSafe(move || module.try_load_record(record));
    match std::panic::catch_unwind(load) {
        Ok(loaded) => loaded.map_err(|e| Error::model(path, e.to_string())),
        Err(panic) => {
            let why = panic
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| panic.downcast_ref::<&str>().copied())
                .unwrap_or("unreadable tensor data");
            Err(Error::model(path, format!("malformed weights file: {why}")))
        }
    }
}

/// A float32 tensor of a safetensors file: `(shape, values)`; errors name
/// the file and the tensor (missing, or another dtype).
pub fn safetensors_f32(
    st: &safetensors::SafeTensors,
    path: &Path,
    name: &str,
) -> Result<(Vec<usize>, Vec<f32>)> {
    let t = st
        .tensor(name)
        .map_err(|e| Error::model(path, format!("tensor '{name}': {e}")))?;
    if t.dtype() != safetensors::Dtype::F32 {
        return Err(Error::model(
            path,
            format!("tensor '{name}' is {:?}, expected F32", t.dtype()),
        ));
    }
    let data = t
        .data()
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Ok((t.shape().to_vec(), data))
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::nn::LinearConfig;

    /// A weights file whose header claims integer or boolean tensors (what
    /// the `weights` fuzz target found) loads converted or is refused,
    /// naming the file; it never panics.
    #[test]
    fn weights_claiming_other_dtypes_never_panic() {
        let device = crate::DeviceKind::Flex.device();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("w.bpk");
        save_module(&LinearConfig::new(4, 3).init(&device), &path).unwrap();
        let good = std::fs::read(&path).unwrap();
        for to in [&b"cI32"[..], b"cI64", b"dBool", b"cU8\0"] {
            let mut bytes = good.clone();
            let at = bytes.windows(4).position(|w| w == b"cF32").unwrap();
            bytes[at..at + to.len().min(4)].copy_from_slice(&to[..to.len().min(4)]);
            std::fs::write(&path, &bytes).unwrap();
            let r = load_module(LinearConfig::new(4, 3).init(&device), &path);
            if let Err(e) = r {
                assert!(e.to_string().contains("w.bpk"), "{e}");
            }
        }
    }
}
