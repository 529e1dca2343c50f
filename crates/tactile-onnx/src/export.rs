//! Exporting burn modules to ONNX with burn-onnx's graph-capture exporter,
//! with a symbolic batch axis.

use std::path::Path;

use burn::module::Module;
use burn::tensor::{Device, Tensor};
use burn_onnx::export::{AxisSpec, InputSpec, OnnxExporter};

use crate::{Error, Result};

/// Export `forward` of `module` for inputs shaped `[batch, rest...]`, the
/// batch axis symbolic (`batch`). Returns the ONNX protobuf bytes.
pub fn export_batch_dynamic<M, const D: usize, const O: usize>(
    module: &M,
    rest: [usize; D],
    forward: impl Fn(&M, Tensor<D>) -> Tensor<O>,
) -> Result<Vec<u8>>
where
    M: Module,
{
    let device = Device::flex();
    let mut one = rest;
    one[0] = 1;
    let mut two = rest;
    two[0] = 2;
    let mut axes = vec![AxisSpec::dynamic("batch")];
    axes.extend((1..D).map(|_| AxisSpec::Static));
    let specs = [InputSpec::new(axes)];
    let model = OnnxExporter::new()
        .export_dynamic(
            module,
            Tensor::<D>::zeros(one, &device),
            Tensor::<D>::zeros(two, &device),
            &specs,
            forward,
        )
        .map_err(|e| Error::Export(e.to_string()))?;
    Ok(model.into_bytes())
}

/// Write ONNX bytes atomically.
pub fn save_onnx(path: impl AsRef<Path>, bytes: &[u8]) -> Result<()> {
    Ok(tactile_core::io::write_atomic(path, bytes)?)
}
