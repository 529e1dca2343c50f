//! Numerically stable losses shared by every model.

use burn::tensor::Tensor;

/// Binary cross-entropy on logits, averaged over all elements.
///
/// Uses `max(z, 0) - z*y + log(1 + exp(-|z|))`, which never takes `log(0)`
/// however saturated the logits are (Keras clips probabilities instead;
/// the minimum is the same, the gradients stay finite).
pub fn bce_with_logits<const D: usize>(logits: Tensor<D>, targets: Tensor<D>) -> Tensor<1> {
    elementwise_bce_with_logits(logits, targets).mean()
}

/// Elementwise stable binary cross-entropy on logits.
pub fn elementwise_bce_with_logits<const D: usize>(
    logits: Tensor<D>,
    targets: Tensor<D>,
) -> Tensor<D> {
    let relu = logits.clone().clamp_min(0.0);
    let soft = logits.clone().abs().neg().exp().log1p();
    relu - logits * targets + soft
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::Device;

    #[test]
    fn bce_is_finite_and_correct_when_saturated() {
        let device = Device::flex();
        let z = Tensor::<1>::from_floats([-1000.0, 1000.0, 0.0, 2.0], &device);
        let y = Tensor::<1>::from_floats([0.0, 1.0, 1.0, 0.0], &device);
        let v: Vec<f32> = elementwise_bce_with_logits(z, y)
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        assert!(v.iter().all(|x| x.is_finite()));
        assert!(v[0].abs() < 1e-6 && v[1].abs() < 1e-6);
        assert!((v[2] - std::f32::consts::LN_2).abs() < 1e-6);
        assert!((v[3] - (1.0 + 2f32.exp()).ln()).abs() < 1e-5);
    }
}
