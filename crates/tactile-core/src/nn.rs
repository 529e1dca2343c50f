//! Numerically stable losses shared by every model.

use burn::tensor::Tensor;
use burn::tensor::activation::relu;

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

/// `relu6(x + 3) / 6`, MobileNetV3's hard sigmoid.
///
/// Written as `(relu(x + 3) - relu(x - 3)) / 6`: burn-onnx 0.22 exports
/// neither HardSigmoid nor an elementwise clamp, but Add, Sub, Relu and Div
/// lower exactly, so burn and onnxruntime run the same arithmetic. It equals
/// the clamp exactly on [-3, 3] and below; above 3, to within float rounding
/// of `x + 3` and `x - 3`.
pub fn hard_sigmoid<const D: usize>(x: Tensor<D>) -> Tensor<D> {
    (relu(x.clone().add_scalar(3.0)) - relu(x.sub_scalar(3.0))).div_scalar(6.0)
}

/// `x * hard_sigmoid(x)`, MobileNetV3's hard swish, in the exportable form.
pub fn hard_swish<const D: usize>(x: Tensor<D>) -> Tensor<D> {
    x.clone() * hard_sigmoid(x)
}

/// Soft Dice loss `1 - (2 sum(p y) + 1) / (sum(p) + sum(y) + 1)` per
/// sample, averaged, with `p = sigmoid(logits)`. The +1 smoothing makes an
/// empty mask predicted empty a loss of 0 instead of 0/0.
pub fn dice_loss_with_logits(logits: Tensor<4>, targets: Tensor<4>) -> Tensor<1> {
    let [n, _, _, _] = logits.dims();
    let p = burn::tensor::activation::sigmoid(logits).reshape([n as i32, -1]);
    let y = targets.reshape([n as i32, -1]);
    let inter = (p.clone() * y.clone()).sum_dim(1);
    let total = p.sum_dim(1) + y.sum_dim(1);
    let dice = (inter.mul_scalar(2.0).add_scalar(1.0)) / total.add_scalar(1.0);
    dice.neg().add_scalar(1.0).mean()
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

    #[test]
    fn hard_swish_matches_its_definition() {
        let device = Device::flex();
        let xs = [-1e6f32, -4.0, -3.0, -1.5, 0.0, 0.7, 3.0, 5.0, 1e3];
        let v: Vec<f32> = hard_swish(Tensor::<1>::from_floats(xs, &device))
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        for (x, y) in xs.iter().zip(&v) {
            let want = x * (x + 3.0).clamp(0.0, 6.0) / 6.0;
            assert!(
                (y - want).abs() <= 1e-6 * want.abs().max(1.0),
                "{x}: {y} vs {want}"
            );
        }
    }

    #[test]
    fn dice_is_zero_for_a_perfect_or_empty_match_and_finite_when_saturated() {
        let device = Device::flex();
        let y = Tensor::<4>::from_data(
            burn::tensor::TensorData::new(
                vec![0.0f32, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [2, 1, 2, 2],
            ),
            &device,
        );
        let perfect = y.clone().mul_scalar(2000.0).sub_scalar(1000.0);
        let l: f32 = dice_loss_with_logits(perfect, y.clone()).into_scalar();
        assert!(l.abs() < 1e-4, "{l}");
        let wrong = y.clone().mul_scalar(-2000.0).add_scalar(1000.0);
        let l: f32 = dice_loss_with_logits(wrong, y).into_scalar();
        assert!(l.is_finite() && l > 0.4, "{l}");
    }
}
