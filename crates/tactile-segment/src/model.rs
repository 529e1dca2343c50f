//! Paper B's small U-Net: four encoder blocks (3x3 conv, ReLU, 2x2
//! max-pool), a bottleneck conv, four decoder blocks (3x3 conv, ReLU,
//! bilinear x2 interpolation, concatenation with the encoder's skip) and a
//! 1x1 convolution to one logit per pixel.

use burn::config::Config;
use burn::module::Module;
use burn::nn::PaddingConfig2d;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::nn::interpolate::{Interpolate2d, Interpolate2dConfig, InterpolateMode};
use burn::nn::pool::{MaxPool2d, MaxPool2dConfig};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor, TensorData};
use tactile_burn::runtime::Forward;

/// Largest window side accepted, pixels.
pub const MAX_SIDE: usize = 1024;
/// Largest first-block width accepted.
pub const MAX_BASE: usize = 64;

/// Width and input side of a U-Net.
#[derive(Config, Debug, PartialEq)]
pub struct UNetConfig {
    /// Channels of the first block; block k has `base * 2^k` (capped at 8x).
    #[config(default = 16)]
    pub base: usize,
    /// Side of the square input window (a multiple of 16; paper B: 160).
    #[config(default = 160)]
    pub side: usize,
    /// Input channels (3: RGB).
    #[config(default = 3)]
    pub in_channels: usize,
}

/// Frame window `[N, C, S, S]` (normalised) -> tendon logits `[N, 1, S, S]`.
#[derive(Module, Debug)]
pub struct UNet {
    /// The four encoder convolutions.
    pub enc: Vec<Conv2d>,
    /// At 1/16 of the input.
    pub bottleneck: Conv2d,
    /// The four decoder convolutions.
    pub dec: Vec<Conv2d>,
    /// 1x1 to one logit per pixel.
    pub head: Conv2d,
    /// 2x2 max-pooling.
    pub pool: MaxPool2d,
    /// Bilinear x2, half-pixel centres.
    pub up: Interpolate2d,
}

fn conv3(i: usize, o: usize, device: &Device) -> Conv2d {
    Conv2dConfig::new([i, o], [3, 3])
        .with_padding(PaddingConfig2d::Explicit(1, 1, 1, 1))
        .init(device)
}

impl UNetConfig {
    /// Channel widths of the four levels.
    pub fn widths(&self) -> [usize; 4] {
        [1, 2, 4, 8].map(|k| self.base * k)
    }

    /// Check the sizes against the documented limits.
    pub fn check(&self) -> tactile_core::Result<()> {
        if self.side == 0
            || !self.side.is_multiple_of(16)
            || self.side > MAX_SIDE
            || self.base == 0
            || self.base > MAX_BASE
            || !(1..=4).contains(&self.in_channels)
        {
            return Err(tactile_core::Error::Config(format!(
                "U-Net side {} must be a multiple of 16 from 16 to {MAX_SIDE}, base {} from 1 to {MAX_BASE}, and input channels {} from 1 to 4",
                self.side, self.base, self.in_channels
            )));
        }
        Ok(())
    }

    /// Check the sizes and build with fresh weights.
    pub fn init(&self, device: &Device) -> tactile_core::Result<UNet> {
        self.check()?;
        let w = self.widths();
        let enc = vec![
            conv3(self.in_channels, w[0], device),
            conv3(w[0], w[1], device),
            conv3(w[1], w[2], device),
            conv3(w[2], w[3], device),
        ];
        // Decoder k sees the previous level's output concatenated with skip k.
        let dec = vec![
            conv3(w[3], w[3], device),
            conv3(2 * w[3], w[2], device),
            conv3(2 * w[2], w[1], device),
            conv3(2 * w[1], w[0], device),
        ];
        Ok(UNet {
            enc,
            bottleneck: conv3(w[3], w[3], device),
            dec,
            head: Conv2dConfig::new([2 * w[0], 1], [1, 1]).init(device),
            pool: MaxPool2dConfig::new([2, 2]).init(),
            up: Interpolate2dConfig::new()
                .with_scale_factor(Some([2.0, 2.0]))
                .with_mode(InterpolateMode::Linear)
                // Half-pixel centres, as PyTorch's default.
                .with_align_corners(false)
                .init(),
        })
    }
}

impl Forward for UNet {
    fn forward_data(&self, x: Tensor<4>) -> TensorData {
        self.forward(x).into_data()
    }
}

impl UNet {
    /// Per-pixel tendon logits.
    ///
    /// # Shapes
    /// - `x`: `[N, 3, S, S]` windows, normalised with the training statistics
    /// - output: `[N, 1, S, S]`
    pub fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let mut skips = Vec::with_capacity(4);
        let mut x = x;
        for conv in &self.enc {
            let s = relu(conv.forward(x));
            x = self.pool.forward(s.clone());
            skips.push(s);
        }
        x = relu(self.bottleneck.forward(x));
        for conv in &self.dec {
            let Some(skip) = skips.pop() else { break };
            x = self.up.forward(relu(conv.forward(x)));
            x = Tensor::cat(vec![x, skip], 1);
        }
        self.head.forward(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_matches_input_size_and_bad_sides_are_errors() {
        let device = Device::flex();
        let m = UNetConfig::new()
            .with_base(4)
            .with_side(64)
            .init(&device)
            .unwrap();
        let y = m.forward(Tensor::<4>::zeros([2, 3, 64, 64], &device));
        assert_eq!(y.dims(), [2, 1, 64, 64]);
        assert!(UNetConfig::new().with_side(100).init(&device).is_err());
    }
}
