//! The pose network: stages of 3x3 convolution, batch norm, ReLU and 2x2
//! max pooling halve the grey pin image down to a small map, which a dense
//! head (flattened, so where the pins moved still counts) turns into the
//! standardised target columns.

use burn::config::Config;
use burn::module::Module;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::nn::pool::{MaxPool2d, MaxPool2dConfig};
use burn::nn::{
    BatchNorm, BatchNormConfig, Dropout, DropoutConfig, Linear, LinearConfig, PaddingConfig2d,
};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor, TensorData};
use tactile_burn::runtime::Forward;

/// Largest input side accepted, pixels.
pub const MAX_INPUT_PX: usize = 512;
/// Largest channel width of a stage.
pub const MAX_WIDTH: usize = 512;
/// Largest hidden width of the head.
pub const MAX_HIDDEN: usize = 4096;
/// Most output columns.
pub const MAX_OUTPUTS: usize = 64;
/// Widest convolution kernel side.
pub use tactile_burn::nn::MAX_KERNEL_SIDE as MAX_KERNEL;

/// Architecture of a [`PoseNet`].
#[derive(Config, Debug, PartialEq)]
pub struct PoseNetConfig {
    /// Side of the square grey pin image.
    #[config(default = 64)]
    pub input_px: usize,
    /// Channels of each stage; each stage halves the side.
    #[config(default = "vec![16, 32, 64, 64]")]
    pub widths: Vec<usize>,
    /// Hidden units of the dense head.
    #[config(default = 128)]
    pub hidden: usize,
    /// Output columns (an angle takes two).
    #[config(default = 3)]
    pub outputs: usize,
    /// Dropout before each dense layer while training (0 = none).
    #[config(default = 0.0)]
    pub dropout: f64,
    /// A second column per output: the log of a Laplace scale, the
    /// network's own estimate of how far off that output is on this frame
    /// (absent in configs written before it: no uncertainty).
    #[config(default = "None")]
    pub uncertainty: Option<bool>,
    /// Side of each stage's convolution kernel, odd (absent: 3 for every
    /// stage). A wide first kernel sees a pin and its neighbours at once,
    /// so how far a pin slid against them is measured before any pooling.
    #[config(default = "None")]
    pub kernels: Option<Vec<usize>>,
}

impl PoseNetConfig {
    /// Columns the network gives: the outputs, and as many log scales with
    /// [`Self::uncertainty`].
    pub fn columns(&self) -> usize {
        self.outputs * if self.has_uncertainty() { 2 } else { 1 }
    }

    /// Whether the network gives a log scale per output.
    pub fn has_uncertainty(&self) -> bool {
        self.uncertainty == Some(true)
    }

    /// Kernel side of stage `i`.
    pub fn kernel(&self, i: usize) -> usize {
        self.kernels
            .as_ref()
            .and_then(|k| k.get(i).copied())
            .unwrap_or(3)
    }

    /// Side of the last stage's map.
    pub fn map_px(&self) -> usize {
        self.input_px >> self.widths.len()
    }

    /// Check every size against its limit before anything is allocated.
    pub fn check(&self) -> tactile_core::Result<()> {
        let bad = |m: String| Err(tactile_core::Error::Config(m));
        if self.widths.is_empty() || self.widths.len() > 6 {
            return bad(format!(
                "pose network: 1 to 6 stages, got {}",
                self.widths.len()
            ));
        }
        if self.widths.iter().any(|&w| w == 0 || w > MAX_WIDTH) {
            return bad(format!(
                "pose network: stage widths must be 1-{MAX_WIDTH}, got {:?}",
                self.widths
            ));
        }
        if let Some(k) = &self.kernels
            && (k.len() != self.widths.len()
                || k.iter()
                    .any(|&k| !tactile_burn::nn::is_odd_kernel_side(k, MAX_KERNEL)))
        {
            return bad(format!(
                "pose network: one odd kernel side (1-{MAX_KERNEL}) per stage ({} stages), got {k:?}",
                self.widths.len()
            ));
        }
        let step = 1usize << self.widths.len();
        if self.input_px == 0 || self.input_px > MAX_INPUT_PX || !self.input_px.is_multiple_of(step)
        {
            return bad(format!(
                "pose network: input side {} must be a multiple of {step} (one halving per stage) up to {MAX_INPUT_PX}",
                self.input_px
            ));
        }
        if self.hidden == 0 || self.hidden > MAX_HIDDEN {
            return bad(format!(
                "pose network: hidden width must be 1-{MAX_HIDDEN}, got {}",
                self.hidden
            ));
        }
        if self.outputs == 0 || self.outputs > MAX_OUTPUTS {
            return bad(format!(
                "pose network: outputs must be 1-{MAX_OUTPUTS}, got {}",
                self.outputs
            ));
        }
        if !(0.0..0.95).contains(&self.dropout) {
            return bad(format!(
                "pose network: dropout must be in [0, 0.95), got {:?}",
                self.dropout
            ));
        }
        let flat = self.widths[self.widths.len() - 1] * self.map_px() * self.map_px();
        let mut c = 1;
        let mut conv = 0u64;
        for (i, &w) in self.widths.iter().enumerate() {
            conv += (c * w * self.kernel(i) * self.kernel(i)) as u64;
            c = w;
        }
        tactile_burn::artifact::check_parameters("pose network", (flat * self.hidden) as u64 + conv)
    }

    /// A network with fresh weights.
    pub fn init(&self, device: &Device) -> PoseNet {
        let mut stages = Vec::with_capacity(self.widths.len());
        let mut c = 1;
        for (i, &w) in self.widths.iter().enumerate() {
            let k = self.kernel(i);
            let p = k / 2;
            stages.push(Stage {
                conv: Conv2dConfig::new([c, w], [k, k])
                    .with_padding(PaddingConfig2d::Explicit(p, p, p, p))
                    .with_bias(false)
                    .init(device),
                bn: BatchNormConfig::new(w).init(device),
                folded: false,
            });
            c = w;
        }
        let flat = c * self.map_px() * self.map_px();
        PoseNet {
            stages,
            pool: MaxPool2dConfig::new([2, 2]).init(),
            fc1: LinearConfig::new(flat, self.hidden).init(device),
            fc2: LinearConfig::new(self.hidden, self.columns()).init(device),
            dropout: DropoutConfig::new(self.dropout).init(),
        }
    }
}

/// Convolution, batch norm (folded into the convolution for inference),
/// ReLU.
#[derive(Module, Debug)]
pub struct Stage {
    /// `k`x`k` (3 unless the config says), no bias (the norm has one).
    pub conv: Conv2d,
    /// Its batch norm.
    pub bn: BatchNorm,
    /// True once the norm is folded into the convolution.
    #[module(skip)]
    pub folded: bool,
}

impl Stage {
    fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let y = self.conv.forward(x);
        relu(if self.folded { y } else { self.bn.forward(y) })
    }
}

/// Grey pin image `[N, 1, S, S]` -> standardised target columns `[N, K]`,
/// followed by their `K` log Laplace scales when the network has
/// uncertainty.
#[derive(Module, Debug)]
pub struct PoseNet {
    /// The convolution stages.
    pub stages: Vec<Stage>,
    /// 2x2 max pooling after each stage.
    pub pool: MaxPool2d,
    /// Flattened map to the hidden units.
    pub fc1: Linear,
    /// Hidden units to the target columns.
    pub fc2: Linear,
    /// Before each dense layer, while training only.
    pub dropout: Dropout,
}

impl PoseNet {
    /// Standardised target columns.
    ///
    /// # Shapes
    /// - `x`: `[N, 1, S, S]` grey pin images in [0, 1]
    /// - output: `[N, K]`, or `[N, 2K]` with uncertainty (columns, then
    ///   their log scales)
    pub fn forward(&self, x: Tensor<4>) -> Tensor<2> {
        let mut x = x;
        for s in &self.stages {
            x = self.pool.forward(s.forward(x));
        }
        let [n, c, h, w] = x.dims();
        let x = x.reshape([n, c * h * w]);
        let x = relu(self.fc1.forward(self.dropout.forward(x)));
        self.fc2.forward(self.dropout.forward(x))
    }
}

impl Forward for PoseNet {
    fn forward_data(&self, x: Tensor<4>) -> TensorData {
        self.forward(x).into_data()
    }

    fn for_inference(mut self) -> Self {
        for s in &mut self.stages {
            if !s.folded {
                tactile_burn::nn::fold_batch_norm(&mut s.conv, &s.bn);
                s.folded = true;
            }
        }
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tactile_burn::DeviceKind;

    #[test]
    fn shapes_limits_and_folding() {
        let dev = DeviceKind::Flex.device();
        let cfg = PoseNetConfig::new()
            .with_input_px(32)
            .with_widths(vec![4, 8]);
        cfg.check().unwrap();
        let net = cfg.init(&dev);
        let x = Tensor::<4>::ones([2, 1, 32, 32], &dev) * 0.5;
        let y = net.forward(x.clone());
        assert_eq!(y.dims(), [2, 3]);
        let a: Vec<f32> = y.into_data().try_to_vec::<f32>().unwrap();
        let b: Vec<f32> = net
            .for_inference()
            .forward(x)
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        for (p, q) in a.iter().zip(&b) {
            assert!((p - q).abs() < 1e-4, "{p} {q}");
        }
        for bad in [
            PoseNetConfig::new().with_input_px(30),
            PoseNetConfig::new().with_widths(vec![]),
            PoseNetConfig::new().with_widths(vec![0, 4]),
            PoseNetConfig::new().with_hidden(0),
            PoseNetConfig::new().with_outputs(10_000),
            PoseNetConfig::new().with_input_px(1 << 40),
            PoseNetConfig::new().with_kernels(Some(vec![5, 3])),
            PoseNetConfig::new().with_kernels(Some(vec![4, 3, 3, 3])),
            PoseNetConfig::new().with_kernels(Some(vec![17, 3, 3, 3])),
        ] {
            assert!(bad.check().is_err(), "{bad:?}");
        }
    }

    #[test]
    fn wide_kernels_keep_the_map_and_fold() {
        let dev = DeviceKind::Flex.device();
        let cfg = PoseNetConfig::new()
            .with_input_px(32)
            .with_widths(vec![4, 8])
            .with_kernels(Some(vec![7, 5]));
        cfg.check().unwrap();
        let net = cfg.init(&dev);
        assert_eq!(net.stages[0].conv.weight.dims(), [4, 1, 7, 7]);
        assert_eq!(net.stages[1].conv.weight.dims(), [8, 4, 5, 5]);
        // A bright dot in one corner reaches the output only through the
        // wide kernels' padding-preserving maps: same shapes as 3x3.
        let mut px = vec![0.0f32; 2 * 32 * 32];
        px[0] = 1.0;
        let x = Tensor::<4>::from_data(TensorData::new(px, [2, 1, 32, 32]), &dev);
        let a: Vec<f32> = net.forward(x.clone()).into_data().try_to_vec().unwrap();
        let b: Vec<f32> = net
            .for_inference()
            .forward(x)
            .into_data()
            .try_to_vec()
            .unwrap();
        assert_eq!(a.len(), 6);
        for (p, q) in a.iter().zip(&b) {
            assert!((p - q).abs() < 1e-4, "{p} {q}");
        }
        assert_ne!(
            a[..3],
            a[3..],
            "the frame with the dot differs from the empty one"
        );
    }
}
