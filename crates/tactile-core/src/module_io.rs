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
pub fn load_module<M: Module>(module: M, path: &Path) -> Result<M> {
    if !path.is_file() {
        return Err(Error::model(path, "weights file does not exist"));
    }
    let record = ModuleRecord::load(path).map_err(|e| Error::model(path, e.to_string()))?;
    module
        .try_load_record(record)
        .map_err(|e| Error::model(path, e.to_string()))
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
