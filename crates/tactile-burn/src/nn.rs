//! Numerically stable losses shared by every model, and folding a batch
//! norm into its convolution for inference.

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

/// The loss on standardised regression columns (pose networks, the
/// autoencoder's joint head).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    Default,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum RegressionLoss {
    /// Mean squared error: the usual choice, pulls hardest on outliers.
    #[default]
    Mse,
    /// Mean absolute error: the loss of the metric reported (MAE), so the
    /// network is not pulled towards a few hard frames at the median's cost.
    L1,
}

impl RegressionLoss {
    /// Its name in configs and curves.
    pub fn name(self) -> &'static str {
        match self {
            Self::Mse => "MSE",
            Self::L1 => "L1",
        }
    }

    /// Elementwise penalty of `diff` (prediction minus label).
    pub fn penalty<const D: usize>(self, diff: Tensor<D>) -> Tensor<D> {
        match self {
            Self::Mse => diff.powi_scalar(2),
            Self::L1 => diff.abs(),
        }
    }
}

/// Widest convolution kernel side the networks' configs accept.
pub const MAX_KERNEL_SIDE: usize = 15;

/// Whether `side` is a kernel side of 1 to `max` that is odd, so its
/// 'same' padding of `side / 2` is symmetric.
pub fn is_odd_kernel_side(side: usize, max: usize) -> bool {
    side % 2 == 1 && side <= max
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

/// Mean absolute error.
pub fn l1_loss(pred: Tensor<4>, target: Tensor<4>) -> Tensor<1> {
    (pred - target).abs().mean()
}

/// Mean squared error.
pub fn mse_loss(pred: Tensor<4>, target: Tensor<4>) -> Tensor<1> {
    (pred - target).square().mean()
}

/// Mean absolute difference of the horizontal and vertical finite
/// differences (DenseTact's gradient term): edges in the right place.
pub fn gradient_loss(pred: Tensor<4>, target: Tensor<4>) -> Tensor<1> {
    let [n, c, h, w] = pred.dims();
    let dx = |t: Tensor<4>| {
        t.clone().slice([0..n, 0..c, 0..h, 1..w]) - t.slice([0..n, 0..c, 0..h, 0..w - 1])
    };
    let dy = |t: Tensor<4>| {
        t.clone().slice([0..n, 0..c, 1..h, 0..w]) - t.slice([0..n, 0..c, 0..h - 1, 0..w])
    };
    (dx(pred.clone()) - dx(target.clone())).abs().mean() + (dy(pred) - dy(target)).abs().mean()
}

/// `(1 - SSIM) / 2` over 7x7 uniform windows, constants `(0.01 L)^2` and
/// `(0.03 L)^2` for a dynamic range `L` in the maps' units (the same SSIM
/// as [`tactile_core::metrics::ssim`], differentiable).
pub fn ssim_loss(pred: Tensor<4>, target: Tensor<4>, range: f64) -> Tensor<1> {
    let k = tactile_core::metrics::SSIM_WINDOW;
    let avg = burn::nn::pool::AvgPool2dConfig::new([k, k])
        .with_strides([1, 1])
        .init();
    let pool = |t: Tensor<4>| avg.forward(t);
    let (c1, c2) = ((0.01 * range).powi(2), (0.03 * range).powi(2));
    let (ma, mb) = (pool(pred.clone()), pool(target.clone()));
    let va = pool(pred.clone().square()) - ma.clone().square();
    let vb = pool(target.clone().square()) - mb.clone().square();
    let cov = pool(pred * target) - ma.clone() * mb.clone();
    let num = (ma.clone() * mb.clone()).mul_scalar(2.0).add_scalar(c1)
        * cov.mul_scalar(2.0).add_scalar(c2);
    let den = (ma.square() + mb.square()).add_scalar(c1) * (va + vb).add_scalar(c2);
    (num / den).mean().neg().add_scalar(1.0).div_scalar(2.0)
}

/// Fold the eval-mode batch norm `bn` that follows `conv` into `conv`'s
/// weights and bias, so the convolution alone gives what both gave:
/// `s = gamma / sqrt(var + eps)`, `w' = w * s` per output channel,
/// `b' = (b - mean) * s + beta`. For inference only (the running
/// statistics are baked in).
pub fn fold_batch_norm(conv: &mut burn::nn::conv::Conv2d, bn: &burn::nn::BatchNorm) {
    use burn::module::Param;
    let s = bn.gamma.val() / (bn.running_var.value() + bn.epsilon).sqrt();
    let [o, _, _, _] = conv.weight.dims();
    let w = conv.weight.val() * s.clone().reshape([o, 1, 1, 1]);
    let b = match &conv.bias {
        Some(b) => b.val(),
        None => Tensor::zeros([o], &w.device()),
    };
    let b = (b - bn.running_mean.value()) * s + bn.beta.val();
    conv.weight = Param::from_tensor(w);
    conv.bias = Some(Param::from_tensor(b));
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
    fn depth_losses_vanish_on_equal_maps_and_ssim_agrees_with_the_metric() {
        let device = Device::flex();
        let w = 12;
        let a: Vec<f32> = (0..w * w)
            .map(|i| ((i * 37) % 11) as f32 * 0.1 + 15.0)
            .collect();
        let b: Vec<f32> = a
            .iter()
            .enumerate()
            .map(|(i, v)| v + 0.05 * (i % 3) as f32)
            .collect();
        let t = |v: &Vec<f32>| {
            Tensor::<4>::from_data(
                burn::tensor::TensorData::new(v.clone(), [1, 1, w, w]),
                &device,
            )
        };
        let zero = |l: Tensor<1>| -> f32 { l.into_scalar() };
        assert_eq!(zero(l1_loss(t(&a), t(&a))), 0.0);
        assert_eq!(zero(mse_loss(t(&a), t(&a))), 0.0);
        assert_eq!(zero(gradient_loss(t(&a), t(&a))), 0.0);
        assert!(zero(ssim_loss(t(&a), t(&a), 6.0)).abs() < 1e-5);
        let l: f32 = ssim_loss(t(&a), t(&b), 6.0).into_scalar();
        let m = tactile_core::metrics::ssim(&a, &b, w, w, 6.0);
        assert!((l as f64 - (1.0 - m) / 2.0).abs() < 1e-4, "{l} vs {m}");
        // Flat maps: finite, no division by zero.
        let flat = vec![15.0f32; w * w];
        assert!(zero(ssim_loss(t(&flat), t(&flat), 6.0)).is_finite());
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

    #[test]
    fn a_folded_batch_norm_gives_what_conv_and_norm_gave() {
        use burn::module::Param;
        use burn::nn::BatchNormConfig;
        use burn::nn::conv::Conv2dConfig;
        let device = crate::DeviceKind::Flex.device();
        let mut conv = Conv2dConfig::new([3, 4], [3, 3]).init(&device);
        let mut bn = BatchNormConfig::new(4).init(&device);
        let t = |v: [f32; 4]| Tensor::<1>::from_floats(v, &device);
        bn.gamma = Param::from_tensor(t([0.5, 2.0, -1.0, 1.5]));
        bn.beta = Param::from_tensor(t([0.1, -0.2, 0.3, 0.0]));
        bn.running_mean = burn::module::RunningState::new(t([0.2, -0.1, 0.05, 1.0]));
        bn.running_var = burn::module::RunningState::new(t([0.5, 2.0, 0.01, 1.0]));
        let x = Tensor::<4>::random(
            [2, 3, 8, 8],
            burn::tensor::Distribution::Normal(0.0, 1.0),
            &device,
        );
        let before = bn.forward(conv.forward(x.clone()));
        fold_batch_norm(&mut conv, &bn);
        let after = conv.forward(x);
        let diff = (before - after).abs().max().into_scalar::<f32>();
        assert!(diff < 1e-4, "largest difference {diff}");
    }
}
