//! The convolutional autoencoder of paper A, Table I.
//!
//! Encoder: four blocks of 3x3 'same' convolution + ReLU + 2x2 max-pool
//! with Keras 'same' pooling (7 -> 4, done here with `ceil_mode`), giving
//! 2x2xC features for a 28x28 pin image. Decoder: conv + ReLU + nearest
//! up-sampling x2, mirrored, with a 'valid' convolution (16 -> 14) before the
//! last up-sampling and a 1-channel output whose sigmoid is the
//! reconstruction. Features are flattened in (row, column, channel) order,
//! as Keras does, so they compare with the authors' released vectors.
//!
//! Larger pin images (56 or 112 px) keep where inside a 28 px cell a pin
//! sits, which the edge pose needs. They go through a stem of extra
//! conv + ReLU + pool blocks down to 28x28 before Table I's encoder, and
//! the decoder ends with as many conv + ReLU + up-sampling blocks, so the
//! latent map (and the feature count) is Table I's whatever the input.

use burn::config::Config;
use burn::module::{Initializer, Module, Param};
use burn::nn::PaddingConfig2d;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::nn::interpolate::{Interpolate2d, Interpolate2dConfig, InterpolateMode};
use burn::nn::pool::{MaxPool2d, MaxPool2dConfig};
use burn::tensor::activation::{relu, sigmoid};
use burn::tensor::{Device, Int, Tensor, TensorData};
use tactile_burn::runtime::Forward;

/// Architecture of the autoencoder.
#[derive(Config, Debug, PartialEq)]
pub struct CaeConfig {
    /// Encoder channel widths, block 1 to 4. Paper: `[16, 8, 8, 4]`; the
    /// authors' released encoder: `[16, 16, 8, 4]`. The feature count is
    /// `4 * widths[3]` (8/16/32/64 for 2/4/8/16).
    #[config(default = "[16, 8, 8, 4]")]
    pub widths: [usize; 4],
    /// Side of the input pin image: 28 (Table I), 56 or 112 (one or two
    /// stem blocks in front).
    #[config(default = 28)]
    pub input_px: usize,
    /// Channels of each stem block (`None`: 16); unused at 28 px.
    #[config(default = "None")]
    pub stem_width: Option<usize>,
    /// ReLU before the last pooling (Table I; `None` means yes, so model
    /// files written before this option load unchanged). Trained on
    /// grey-level pin images, 7 of 16 such features died (zero on every
    /// frame of the edge set); without it the features are the max-pooled
    /// linear responses and none can die.
    #[config(default = "None")]
    pub latent_relu: Option<bool>,
    /// Side of the encoder's first convolution kernel, odd (`None`: 3, as
    /// Table I). At 56 px a 7 or 9 px kernel sees a pin with its
    /// neighbours, so how far it slid against them (shear, twist) is
    /// measured before the first pooling blurs it.
    #[config(default = "None")]
    pub first_kernel: Option<usize>,
}

/// Widest encoder block accepted.
pub const MAX_WIDTH: usize = 256;

/// Widest first kernel side accepted.
pub use tactile_burn::nn::MAX_KERNEL_SIDE as MAX_FIRST_KERNEL;

/// Pin-image sides the autoencoder takes.
pub const INPUT_SIDES: [usize; 3] = [28, 56, 112];

impl CaeConfig {
    /// Check the sizes against the documented limits before anything is
    /// allocated for them: every width 1 to [`MAX_WIDTH`], and an input
    /// side of 28 px (Table I's decoder) times 1, 2 or 4.
    pub fn check(&self) -> tactile_core::Result<()> {
        if let Some(w) = self
            .widths
            .iter()
            .chain(&self.stem_width)
            .find(|&&w| w == 0 || w > MAX_WIDTH)
        {
            return Err(tactile_core::Error::Config(format!(
                "CAE widths must be 1 to {MAX_WIDTH}, got {w} in {:?} (stem {:?})",
                self.widths, self.stem_width
            )));
        }
        if let Some(k) = self.first_kernel
            && !tactile_burn::nn::is_odd_kernel_side(k, MAX_FIRST_KERNEL)
        {
            return Err(tactile_core::Error::Config(format!(
                "the CAE's first kernel side must be odd, 1 to {MAX_FIRST_KERNEL}, got {k}"
            )));
        }
        if !INPUT_SIDES.contains(&self.input_px) {
            return Err(tactile_core::Error::Config(format!(
                "the CAE takes pin images of {INPUT_SIDES:?} px (Table I's 28, or 28 after a stem of 1 or 2 pooling blocks), got input_px {}",
                self.input_px
            )));
        }
        Ok(())
    }

    /// Stem blocks in front of Table I's encoder: 0, 1 or 2.
    pub fn stem_blocks(&self) -> usize {
        (self.input_px / 28).max(1).ilog2() as usize
    }

    /// Channels of each stem block.
    pub fn stem_channels(&self) -> usize {
        self.stem_width.unwrap_or(16)
    }

    /// Number of features the encoder outputs.
    pub fn feature_count(&self) -> usize {
        let s = self.latent_side();
        s * s * self.widths[3]
    }

    /// Side of the latent map after the stem's and Table I's four 'same'
    /// poolings.
    pub fn latent_side(&self) -> usize {
        (0..4 + self.stem_blocks()).fold(self.input_px, |s, _| s.div_ceil(2))
    }

    /// The config the training front ends ask for: four encoder `widths`,
    /// optionally a feature count (sets the last width), the linear
    /// latent (no ReLU before the last pooling), and the pin images' side
    /// (the preprocessing's output).
    pub fn from_options(
        widths: &[usize],
        features: Option<usize>,
        linear_latent: bool,
        input_px: usize,
    ) -> crate::Result<Self> {
        let widths: [usize; 4] = widths.try_into().map_err(|_| {
            tactile_core::Error::Config(format!(
                "CAE widths: 4 values needed, got {}",
                widths.len()
            ))
        })?;
        let model = Self::new()
            .with_widths(widths)
            .with_input_px(input_px)
            .with_latent_relu(linear_latent.then_some(false));
        model.check()?;
        match features {
            Some(f) => model.with_feature_count(f),
            None => Ok(model),
        }
    }

    /// The config with `feature_count` features (paper A's 8/16/32/64 sweep).
    pub fn with_feature_count(self, features: usize) -> crate::Result<Self> {
        let s2 = self.latent_side() * self.latent_side();
        if features == 0 || !features.is_multiple_of(s2) {
            return Err(crate::Error::FeatureCount {
                features,
                cells: s2,
            });
        }
        let mut w = self.widths;
        w[3] = features / s2;
        Ok(self.with_widths(w))
    }

    /// Build the model with fresh weights.
    pub fn init(&self, device: &Device) -> Cae {
        let [c1, c2, c3, c4] = self.widths;
        // Keras' initialisation (Glorot-uniform kernels, zero biases): with
        // burn's default the 4-channel bottleneck's ReLUs tend to die early
        // and every feature stays 0.
        let conv = |i, o, k: usize, padding| {
            let mut c = Conv2dConfig::new([i, o], [k, k])
                .with_padding(padding)
                .with_initializer(Initializer::XavierUniform { gain: 1.0 })
                .init(device);
            c.bias = c.bias.map(|b| Param::from_tensor(b.val().zeros_like()));
            c
        };
        let same_k = |i, o, k: usize| {
            let p = k / 2;
            conv(i, o, k, PaddingConfig2d::Explicit(p, p, p, p))
        };
        let same = |i, o| same_k(i, o, 3);
        let valid = |i, o| conv(i, o, 3, PaddingConfig2d::Valid);
        let first = self.first_kernel.unwrap_or(3);
        let (blocks, s) = (self.stem_blocks(), self.stem_channels());
        // Stem: 1 -> s -> s channels; tail: c1 -> s -> s, then conv5 to 1.
        let stem = (0..blocks).map(|b| match b {
            0 => same_k(1, s, first),
            _ => same(s, s),
        });
        let tail = (0..blocks).map(|b| same(if b == 0 { c1 } else { s }, s));
        let into_conv1 = if blocks > 0 { s } else { 1 };
        Cae {
            encoder: CaeEncoder {
                stem: stem.collect(),
                conv1: if blocks > 0 {
                    same(into_conv1, c1)
                } else {
                    same_k(1, c1, first)
                },
                conv2: same(c1, c2),
                conv3: same(c2, c3),
                conv4: same(c3, c4),
                pool: MaxPool2dConfig::new([2, 2]).with_ceil_mode(true).init(),
                latent_relu: self.latent_relu.unwrap_or(true),
            },
            decoder: CaeDecoder {
                conv1: same(c4, c4),
                conv2: same(c4, c3),
                conv3: same(c3, c2),
                conv4: valid(c2, c1),
                tail: tail.collect(),
                conv5: same(if blocks > 0 { s } else { c1 }, 1),
                up: Interpolate2dConfig::new()
                    .with_scale_factor(Some([2.0, 2.0]))
                    .with_mode(InterpolateMode::Nearest)
                    .init(),
                latent_channels: c4,
                latent_side: self.latent_side(),
            },
        }
    }
}

fn index(values: impl IntoIterator<Item = usize>, device: &Device) -> Tensor<1, Int> {
    let v: Vec<i64> = values.into_iter().map(|i| i as i64).collect();
    let n = v.len();
    Tensor::from_data(TensorData::new(v, [n]), device)
}

/// `[N, C, H, W]` -> `[N, H*W*C]` in (row, column, channel) order.
///
/// Written with gathers and a concatenation rather than a permute, because
/// burn-onnx 0.22's exporter cannot lower `permute`; the result is the same
/// to the bit.
pub fn hwc_flatten(z: Tensor<4>) -> Tensor<2> {
    let [n, c, h, w] = z.dims();
    let device = z.device();
    let cells = (0..h)
        .flat_map(|y| (0..w).map(move |x| (y, x)))
        .map(|(y, x)| {
            z.clone()
                .select(2, index([y], &device))
                .select(3, index([x], &device))
                .reshape([n, c])
        })
        .collect();
    Tensor::cat(cells, 1)
}

/// The inverse of [`hwc_flatten`]: `[N, H*W*C]` -> `[N, C, H, W]`.
pub fn hwc_unflatten(f: Tensor<2>, c: usize, h: usize, w: usize) -> Tensor<4> {
    let [n, _] = f.dims();
    let device = f.device();
    let rows = (0..h)
        .map(|y| {
            let cells = (0..w)
                .map(|x| {
                    let k = y * w + x;
                    f.clone()
                        .select(1, index(k * c..(k + 1) * c, &device))
                        .reshape([n, c, 1, 1])
                })
                .collect();
            Tensor::cat(cells, 3)
        })
        .collect();
    Tensor::cat(rows, 2)
}

/// Pin image -> features.
#[derive(Module, Debug)]
pub struct CaeEncoder {
    /// Stem convolutions (each + ReLU + pool) down to 28 px; none at 28 px.
    pub stem: Vec<Conv2d>,
    /// Block 1 convolution.
    pub conv1: Conv2d,
    /// Block 2 convolution.
    pub conv2: Conv2d,
    /// Block 3 convolution.
    pub conv3: Conv2d,
    /// Block 4 convolution (its channels are the features).
    pub conv4: Conv2d,
    /// Keras 'same' 2x2 max-pooling.
    pub pool: MaxPool2d,
    /// ReLU before the last pooling.
    pub latent_relu: bool,
}

impl CaeEncoder {
    /// The latent map.
    ///
    /// # Shapes
    /// - `x`: `[N, 1, S, S]`, S = 28 times 1, 2 or 4
    /// - output: `[N, C, 2, 2]`
    pub fn latent(&self, x: Tensor<4>) -> Tensor<4> {
        let x = self
            .stem
            .iter()
            .fold(x, |x, c| self.pool.forward(relu(c.forward(x))));
        let x = self.pool.forward(relu(self.conv1.forward(x)));
        let x = self.pool.forward(relu(self.conv2.forward(x)));
        let x = self.pool.forward(relu(self.conv3.forward(x)));
        let x = self.conv4.forward(x);
        self.pool
            .forward(if self.latent_relu { relu(x) } else { x })
    }

    /// Features in (row, column, channel) order.
    ///
    /// # Shapes
    /// - `x`: `[N, 1, S, S]` pin images
    /// - output: `[N, F]`
    pub fn forward(&self, x: Tensor<4>) -> Tensor<2> {
        hwc_flatten(self.latent(x))
    }
}

/// Features -> reconstruction logits.
#[derive(Module, Debug)]
pub struct CaeDecoder {
    /// First convolution, on the latent map.
    pub conv1: Conv2d,
    /// Second.
    pub conv2: Conv2d,
    /// Third.
    pub conv3: Conv2d,
    /// The 'valid' convolution (16 -> 14).
    pub conv4: Conv2d,
    /// Tail convolutions (each + ReLU + up-sampling) from 28 px back to the
    /// input's side; none at 28 px.
    pub tail: Vec<Conv2d>,
    /// To one channel of logits.
    pub conv5: Conv2d,
    /// Nearest up-sampling x2.
    pub up: Interpolate2d,
    /// Channels of the latent map.
    pub latent_channels: usize,
    /// Side of the latent map.
    pub latent_side: usize,
}

impl CaeDecoder {
    /// Reconstruction logits `[N, 1, S, S]` from features `[N, F]`.
    pub fn forward(&self, features: Tensor<2>) -> Tensor<4> {
        let s = self.latent_side;
        self.forward_latent(hwc_unflatten(features, self.latent_channels, s, s))
    }

    /// Reconstruction logits from the latent map `[N, C, 2, 2]`.
    pub fn forward_latent(&self, z: Tensor<4>) -> Tensor<4> {
        let x = self.up.forward(relu(self.conv1.forward(z)));
        let x = self.up.forward(relu(self.conv2.forward(x)));
        let x = self.up.forward(relu(self.conv3.forward(x)));
        let x = self.up.forward(relu(self.conv4.forward(x)));
        let x = self
            .tail
            .iter()
            .fold(x, |x, c| self.up.forward(relu(c.forward(x))));
        self.conv5.forward(x)
    }
}

/// The whole autoencoder.
#[derive(Module, Debug)]
pub struct Cae {
    /// Pin image to features.
    pub encoder: CaeEncoder,
    /// Features to reconstruction.
    pub decoder: CaeDecoder,
}

impl Cae {
    /// Reconstruction logits (train with a stable BCE on these).
    pub fn forward_logits(&self, x: Tensor<4>) -> Tensor<4> {
        // Straight from the latent map: the same numbers as going through the
        // flat feature vector, without a flatten/unflatten round trip.
        self.decoder.forward_latent(self.encoder.latent(x))
    }

    /// Reconstruction in [0, 1] (the Keras model's sigmoid output).
    pub fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        sigmoid(self.forward_logits(x))
    }
}

impl Forward for Cae {
    /// At inference the autoencoder is its encoder: pin images to features.
    fn forward_data(&self, x: Tensor<4>) -> TensorData {
        self.encoder.forward(x).into_data()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_follow_table_one() {
        let device = Device::flex();
        let cfg = CaeConfig::new();
        assert_eq!(cfg.feature_count(), 16);
        let m = cfg.init(&device);
        let x = Tensor::<4>::zeros([3, 1, 28, 28], &device);
        assert_eq!(m.encoder.latent(x.clone()).dims(), [3, 4, 2, 2]);
        assert_eq!(m.encoder.forward(x.clone()).dims(), [3, 16]);
        assert_eq!(m.forward(x.clone()).dims(), [3, 1, 28, 28]);
        let via_features = m.decoder.forward(m.encoder.forward(x.clone()));
        let direct = m.forward_logits(x);
        assert_eq!(via_features.into_data(), direct.into_data());
        for f in [8, 16, 32, 64] {
            let c = CaeConfig::new().with_feature_count(f).unwrap();
            assert_eq!(c.feature_count(), f);
            let m = c.init(&device);
            assert_eq!(
                m.encoder
                    .forward(Tensor::<4>::zeros([1, 1, 28, 28], &device))
                    .dims(),
                [1, f]
            );
        }
        assert!(CaeConfig::new().with_feature_count(10).is_err());
    }

    #[test]
    fn larger_inputs_keep_table_one_latent() {
        let device = Device::flex();
        for (px, blocks) in [(56, 1), (112, 2)] {
            let cfg = CaeConfig::new()
                .with_input_px(px)
                .with_feature_count(32)
                .unwrap();
            cfg.check().unwrap();
            assert_eq!((cfg.stem_blocks(), cfg.latent_side()), (blocks, 2));
            let m = cfg.init(&device);
            let x = Tensor::<4>::zeros([2, 1, px, px], &device);
            assert_eq!(m.encoder.forward(x.clone()).dims(), [2, 32]);
            assert_eq!(m.forward(x).dims(), [2, 1, px, px]);
        }
        for bad in [27, 64, 128, 224] {
            assert!(
                CaeConfig::new().with_input_px(bad).check().is_err(),
                "{bad}"
            );
        }
        assert!(
            CaeConfig::new()
                .with_input_px(56)
                .with_stem_width(Some(0))
                .check()
                .is_err()
        );
    }

    #[test]
    fn a_wide_first_kernel_keeps_every_shape() {
        let device = Device::flex();
        for (px, k) in [(28, 7), (56, 9), (112, 5)] {
            let cfg = CaeConfig::new()
                .with_input_px(px)
                .with_first_kernel(Some(k))
                .with_feature_count(32)
                .unwrap();
            cfg.check().unwrap();
            let m = cfg.init(&device);
            let first = m.encoder.stem.first().unwrap_or(&m.encoder.conv1);
            assert_eq!(first.weight.dims()[2..], [k, k]);
            assert_eq!(m.encoder.conv2.weight.dims()[2..], [3, 3]);
            let x = Tensor::<4>::ones([2, 1, px, px], &device);
            assert_eq!(m.encoder.forward(x.clone()).dims(), [2, 32]);
            assert_eq!(m.forward(x).dims(), [2, 1, px, px]);
        }
        for bad in [0, 4, 17] {
            let cfg = CaeConfig::new().with_first_kernel(Some(bad));
            let err = cfg.check().unwrap_err().to_string();
            assert!(
                err.contains("first kernel") && err.contains(&bad.to_string()),
                "{err}"
            );
        }
    }

    #[test]
    fn hwc_flatten_is_row_column_channel_and_invertible() {
        let device = Device::flex();
        let z = Tensor::<4>::from_data(
            TensorData::new((0..16).map(|v| v as f32).collect::<Vec<_>>(), [1, 4, 2, 2]),
            &device,
        );
        let f = hwc_flatten(z.clone());
        let v: Vec<f32> = f.clone().into_data().try_to_vec::<f32>().unwrap();
        // element (c, y, x) = 4c + 2y + x; order is y, x, c
        assert_eq!(&v[..8], &[0.0, 4.0, 8.0, 12.0, 1.0, 5.0, 9.0, 13.0]);
        let back: Vec<f32> = hwc_unflatten(f, 4, 2, 2)
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        assert_eq!(back, (0..16).map(|v| v as f32).collect::<Vec<_>>());
    }

    #[test]
    fn pooling_is_keras_same() {
        // 7 -> 4 with the last window covering only the last row/column.
        let device = Device::flex();
        let pool = MaxPool2dConfig::new([2, 2]).with_ceil_mode(true).init();
        let x = Tensor::<4>::from_data(
            TensorData::new((0..49).map(|v| v as f32).collect::<Vec<_>>(), [1, 1, 7, 7]),
            &device,
        );
        let y: Vec<f32> = pool.forward(x).into_data().try_to_vec::<f32>().unwrap();
        assert_eq!(y.len(), 16);
        assert_eq!(&y[..4], &[8.0, 10.0, 12.0, 13.0]);
        assert_eq!(y[15], 48.0);
    }
}
