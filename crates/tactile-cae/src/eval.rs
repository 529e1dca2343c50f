//! How well the autoencoder reconstructs its input.

use burn::tensor::Device;
use tactile_burn::nn::bce_with_logits;

use crate::data::PinSet;
use crate::model::Cae;

/// Mean reconstruction binary cross-entropy over the images at `rows`,
/// in batches of `batch`.
pub fn reconstruction_bce(
    model: &Cae,
    pins: &PinSet,
    rows: &[usize],
    batch: usize,
    device: &Device,
) -> f64 {
    let mut total = 0.0;
    for chunk in rows.chunks(batch.max(1)) {
        let x = pins.batch(chunk, device);
        let l: f32 = bce_with_logits(model.forward_logits(x.clone()), x).into_scalar();
        total += l as f64 * chunk.len() as f64;
    }
    total / rows.len().max(1) as f64
}
