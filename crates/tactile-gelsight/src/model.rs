//! The sensor model: a small fully convolutional network from the working
//! features (colour change, background colour, position) to the skin's
//! two forward-difference gradients. With every kernel 1x1 it is the
//! per-pixel MLP of GelSight's SDK; a 3x3 first layer lets it see the
//! colour change's neighbourhood (the shading's spatial pattern).

use burn::config::Config;
use burn::module::Module;
use burn::nn::PaddingConfig2d;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor, TensorData};
use tactile_burn::runtime::Forward;

use crate::prepare::FEATURES;

/// Widest hidden layer.
pub const MAX_WIDTH: usize = 256;
/// Largest kernel.
pub const MAX_KERNEL: usize = 7;

/// The network's shape.
#[derive(Config, Debug, PartialEq)]
pub struct GradientNetConfig {
    /// Hidden layers' widths.
    #[config(default = "vec![32, 32]")]
    pub widths: Vec<usize>,
    /// Each layer's (odd) kernel size, one more than `widths` (the output
    /// layer last). Two 3x3 layers see 5x5 working pixels (20x20 frame
    /// pixels at factor 4): measured in docs/calibration.md against one.
    #[config(default = "vec![3, 3, 1]")]
    pub kernels: Vec<usize>,
}

impl GradientNetConfig {
    /// GelSight's SDK's model: a per-pixel MLP (every kernel 1x1).
    pub fn per_pixel_mlp() -> Self {
        Self::new().with_kernels(vec![1, 1, 1])
    }

    /// Check the shape before building it.
    pub fn check(&self) -> tactile_core::Result<()> {
        let bad = |m: String| Err(tactile_core::Error::Config(m));
        if self.widths.is_empty() || self.widths.len() > 6 {
            return bad(format!(
                "sensor model: 1-6 hidden layers, got {}",
                self.widths.len()
            ));
        }
        if self.widths.iter().any(|&w| w == 0 || w > MAX_WIDTH) {
            return bad(format!(
                "sensor model: widths must be 1-{MAX_WIDTH}, got {:?}",
                self.widths
            ));
        }
        if self.kernels.len() != self.widths.len() + 1
            || self
                .kernels
                .iter()
                .any(|&k| !tactile_burn::nn::is_odd_kernel_side(k, MAX_KERNEL))
        {
            return bad(format!(
                "sensor model: {} odd kernels of 1-{MAX_KERNEL} (one per layer, the output last), got {:?}",
                self.widths.len() + 1,
                self.kernels
            ));
        }
        Ok(())
    }

    /// Multiply-adds per working pixel.
    pub fn macs_per_pixel(&self) -> usize {
        let mut c = FEATURES;
        let mut total = 0;
        for (i, &k) in self.kernels.iter().enumerate() {
            let out = self.widths.get(i).copied().unwrap_or(2);
            total += c * out * k * k;
            c = out;
        }
        total
    }

    /// The network with fresh weights.
    pub fn init(&self, device: &Device) -> tactile_core::Result<GradientNet> {
        self.check()?;
        let mut layers = Vec::new();
        let mut c = FEATURES;
        for (i, &k) in self.kernels.iter().enumerate() {
            let out = self.widths.get(i).copied().unwrap_or(2);
            let p = k / 2;
            layers.push(
                Conv2dConfig::new([c, out], [k, k])
                    .with_padding(PaddingConfig2d::Explicit(p, p, p, p))
                    .init(device),
            );
            c = out;
        }
        Ok(GradientNet { layers })
    }
}

/// The network.
#[derive(Module, Debug)]
pub struct GradientNet {
    /// Convolutions, ReLU between them.
    pub layers: Vec<Conv2d>,
}

impl GradientNet {
    /// Gradients of the features.
    ///
    /// # Shapes
    /// - `x`: `[N, FEATURES, H, W]`
    /// - returns `[N, 2, H, W]`: the slopes `gx`, `gy` (mm per mm) toward
    ///   the next pixel right and down
    pub fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let last = self.layers.len() - 1;
        let mut x = x;
        for (i, l) in self.layers.iter().enumerate() {
            x = l.forward(x);
            if i < last {
                x = relu(x);
            }
        }
        x
    }
}

impl Forward for GradientNet {
    fn forward_data(&self, x: Tensor<4>) -> TensorData {
        self.forward(x).into_data()
    }
}
