//! ONNX export and onnxruntime. Any burn network exports through one
//! generic exporter ([`export_batch_dynamic`]) with a symbolic batch axis;
//! each model crate says how its own network exports by implementing
//! [`Exportable`], so this crate knows no model. The exported graph runs
//! in onnxruntime (through `ort`, loaded dynamically from the PyPI wheel's
//! `libonnxruntime.so`) as a [`Network`], beside
//! burn's devices: [`load_network`] gives any saved model on any runtime.

#![deny(missing_docs)]

mod error;
pub mod export;
pub mod runtime;
pub mod standalone;

use std::path::Path;

pub use error::{Error, Result};
pub use export::{export_batch_dynamic, save_onnx};
pub use runtime::{OrtModel, onnx_full_check, ort_library_path};
use tactile_burn::runtime::{BurnNetwork, Forward};
use tactile_burn::{Artifact, DeviceKind, Loaded, Network, Runtime};

/// A saved model whose network exports to ONNX.
pub trait Exportable: Artifact
where
    Self::Model: Forward + Send + 'static,
{
    /// The network as ONNX bytes, batch axis dynamic, input and output as
    /// its `forward` takes and gives them.
    fn onnx(&self, model: &Self::Model) -> Result<Vec<u8>>;
}

/// A loaded model's network on `runtime` (`threads` intra-op threads for
/// onnxruntime; 0 = its default). A model loaded on another device than
/// `runtime`'s is reloaded from its folder.
pub fn network<A>(loaded: Loaded<A>, runtime: Runtime, threads: usize) -> Result<Box<dyn Network>>
where
    A: Exportable,
    A::Model: Forward + Send + 'static,
{
    Ok(match runtime.device() {
        None => {
            let bytes = loaded.artifact.onnx(&loaded.model)?;
            Box::new(OrtModel::from_bytes(&bytes, threads)?)
        }
        Some(kind) if device_kind(&loaded) == Some(kind) => {
            Box::new(BurnNetwork::new(loaded.model, kind))
        }
        Some(kind) => {
            let l = A::load(&loaded.dir, &kind.device())?;
            Box::new(BurnNetwork::new(l.model, kind))
        }
    })
}

fn device_kind<A: Artifact>(loaded: &Loaded<A>) -> Option<DeviceKind> {
    DeviceKind::ALL
        .into_iter()
        .find(|k| k.device() == loaded.device)
}

/// Load the model in `dir` and its network on `runtime`: the config (with
/// its input statistics and thresholds) and the runnable network.
pub fn load_network<A>(
    dir: &Path,
    runtime: Runtime,
    threads: usize,
) -> Result<(A, Box<dyn Network>)>
where
    A: Exportable,
    A::Model: Forward + Send + 'static,
{
    let kind = runtime.device().unwrap_or(DeviceKind::Flex);
    let loaded = A::load(dir, &kind.device())?;
    let artifact = loaded.artifact.clone();
    Ok((artifact, network(loaded, runtime, threads)?))
}
