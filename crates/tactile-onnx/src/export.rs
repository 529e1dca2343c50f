//! Exporting burn modules to ONNX with burn-onnx's graph-capture exporter,
//! with a symbolic batch axis.

use std::path::Path;

use burn::module::Module;
use burn::tensor::{Device, Tensor};
use burn_onnx::export::{AxisSpec, InputSpec, OnnxExporter};
use tactile_cae::{Cae, CaeEncoder};
use tactile_core::{Error, Result};

/// Export `forward` of `module` for inputs shaped `[batch, rest...]`, the
/// batch axis symbolic (`batch`). Returns the ONNX protobuf bytes.
pub fn export_module_batch_dynamic<M, const D: usize, const O: usize>(
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
        .map_err(|e| Error::Invalid(format!("ONNX export failed: {e}")))?;
    Ok(model.into_bytes())
}

/// The encoder: `[N, 1, 28, 28]` pin images -> `[N, F]` features.
pub fn export_cae_encoder(encoder: &CaeEncoder, input_px: usize) -> Result<Vec<u8>> {
    export_module_batch_dynamic(encoder, [1, 1, input_px, input_px], |m: &CaeEncoder, x| {
        m.forward(x)
    })
}

/// The whole autoencoder: `[N, 1, 28, 28]` -> reconstruction in [0, 1].
pub fn export_cae(cae: &Cae, input_px: usize) -> Result<Vec<u8>> {
    export_module_batch_dynamic(cae, [1, 1, input_px, input_px], |m: &Cae, x| m.forward(x))
}

/// The tendon detector: `[N, 3, H, W]` normalised frames -> `[N, 1]` logits.
pub fn export_detector(model: &tactile_detect::Detector, [w, h]: [usize; 2]) -> Result<Vec<u8>> {
    export_module_batch_dynamic(model, [1, 3, h, w], |m: &tactile_detect::Detector, x| {
        m.forward(x)
    })
}

/// The U-Net segmenter: `[N, 3, S, S]` normalised windows -> `[N, 1, S, S]` logits.
pub fn export_segmenter(model: &tactile_segment::UNet, side: usize) -> Result<Vec<u8>> {
    export_module_batch_dynamic(model, [1, 3, side, side], |m: &tactile_segment::UNet, x| {
        m.forward(x)
    })
}

/// The depth network: `[N, C, H, W]` normalised frames (C = 3, or 4 with
/// the mask) -> `[N, 1, H, W]` depth in model units.
pub fn export_depth(
    model: &tactile_depth::DepthNet,
    channels: usize,
    [w, h]: [usize; 2],
) -> Result<Vec<u8>> {
    export_module_batch_dynamic(
        model,
        [1, channels, h, w],
        |m: &tactile_depth::DepthNet, x| m.forward(x),
    )
}

/// Write ONNX bytes atomically.
pub fn save_onnx(path: impl AsRef<Path>, bytes: &[u8]) -> Result<()> {
    tactile_core::io::write_atomic(path, bytes)
}
