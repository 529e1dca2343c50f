//! What several of this crate's tests share: the standalone ONNX export of
//! a detector run by onnxruntime, and the gate codes it answers with.

use std::path::Path;

use tactile_detect::{DetectorConfig, Gate};
use tactile_onnx::runtime::{NamedOutput, OrtModel};
use tactile_pipeline::export::export_standalone;

/// The outputs of a standalone graph, looked up by name.
pub struct StandaloneOutputs(Vec<NamedOutput>);

impl StandaloneOutputs {
    /// The values of output `name` (panics when the graph has none).
    pub fn get(&self, name: &str) -> Vec<f32> {
        self.0
            .iter()
            .find(|o| o.name == name)
            .unwrap_or_else(|| panic!("no output {name}"))
            .values
            .clone()
    }
}

/// The standalone export of the detector in `dir` on `n` frames' `levels`
/// (each `model.frame_levels`), all at once, in the graph's input type.
pub fn run_standalone(
    dir: &Path,
    model: &DetectorConfig,
    levels: Vec<u16>,
    n: usize,
) -> StandaloneOutputs {
    let exported = export_standalone(dir).unwrap();
    let mut alone = OrtModel::from_bytes(&exported.bytes, 0).unwrap();
    let [w, h] = model.input_size;
    let shape = [n, h, w, 3];
    let outputs = match model.bits() {
        16 => alone.run_frame_outputs(&shape, levels),
        _ => alone.run_frame_outputs(&shape, levels.iter().map(|&v| v as u8).collect()),
    };
    StandaloneOutputs(outputs.unwrap())
}

/// The graph's `gate` output for a gate: 0 passed, 1 blank, 2 foreign.
pub fn gate_code(gate: Option<Gate>) -> f32 {
    match gate {
        None => 0.0,
        Some(Gate::Blank) => 1.0,
        Some(Gate::Foreign) => 2.0,
    }
}
