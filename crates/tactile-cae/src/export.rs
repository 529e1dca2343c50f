//! The autoencoder in ONNX, through the workspace's generic exporter.

use tactile_onnx::{Result, export_batch_dynamic};

use crate::model::{Cae, CaeEncoder};

/// The encoder: `[N, 1, S, S]` pin images -> `[N, F]` features.
pub fn encoder_onnx(cae: &Cae, input_px: usize) -> Result<Vec<u8>> {
    export_batch_dynamic(
        &cae.encoder,
        [1, 1, input_px, input_px],
        |m: &CaeEncoder, x| m.forward(x),
    )
}

/// The whole autoencoder: `[N, 1, S, S]` -> reconstruction in [0, 1].
pub fn autoencoder_onnx(cae: &Cae, input_px: usize) -> Result<Vec<u8>> {
    export_batch_dynamic(cae, [1, 1, input_px, input_px], |m: &Cae, x| m.forward(x))
}
