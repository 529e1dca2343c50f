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
    numbered_from_zero(model.as_bytes())
}

/// The exported graph with its tensors renamed `tensor_0`, `tensor_1`, ...
/// in the order they first appear. burn-onnx names a tensor by burn's id
/// for it, which counts every tensor the process has made: a model
/// exported after others (a second export, a Python session that ran
/// models first) got other names, so one model gave files that differed.
/// Renamed, a model's export is the same bytes in any process.
fn numbered_from_zero(onnx: &[u8]) -> Result<Vec<u8>> {
    use onnx_ir::{Message, ModelProto};
    use std::collections::HashMap;
    let mut model = ModelProto::parse_from_bytes(onnx)
        .map_err(|e| Error::Export(format!("cannot read the export: {e}")))?;
    let graph = model.graph.mut_or_insert_default();
    // A node holding a subgraph (If, Loop) may name outer tensors inside
    // it: such a graph is left as burn-onnx wrote it.
    let subgraphs = graph
        .node
        .iter()
        .flat_map(|n| &n.attribute)
        .any(|a| a.g.is_some() || !a.graphs.is_empty());
    if subgraphs {
        return Ok(onnx.to_vec());
    }
    let mut ids: HashMap<String, usize> = HashMap::new();
    // `tensor_<id><rest>` (rest: a suffix such as `_output`) -> the id's new number.
    let mut rename = |name: &mut String| {
        let Some(digits) = name.strip_prefix("tensor_") else {
            return;
        };
        let end = digits
            .find(|c: char| !c.is_ascii_digit())
            .unwrap_or(digits.len());
        if end == 0 {
            return;
        }
        let (id, rest) = digits.split_at(end);
        let next = ids.len();
        let k = *ids.entry(id.to_string()).or_insert(next);
        *name = format!("tensor_{k}{rest}");
    };
    for v in graph.input.iter_mut() {
        rename(&mut v.name);
    }
    for t in graph.initializer.iter_mut() {
        rename(&mut t.name);
    }
    for n in graph.node.iter_mut() {
        n.input.iter_mut().for_each(&mut rename);
        n.output.iter_mut().for_each(&mut rename);
    }
    for v in graph.output.iter_mut().chain(graph.value_info.iter_mut()) {
        rename(&mut v.name);
    }
    model
        .write_to_bytes()
        .map_err(|e| Error::Export(format!("cannot write the export: {e}")))
}

/// Write ONNX bytes atomically.
pub fn save_onnx(path: impl AsRef<Path>, bytes: &[u8]) -> Result<()> {
    Ok(tactile_core::io::write_atomic(path, bytes)?)
}
