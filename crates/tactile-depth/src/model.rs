//! The depth network of paper B: a DenseNet encoder (Huang et al. 2017:
//! dense blocks of BN-ReLU-1x1 bottleneck and BN-ReLU-3x3 layers that each
//! add `growth_rate` channels, transitions that compress and halve) with a
//! U-Net decoder fed by skips from the stem and every dense block, and a
//! 1x1 or a small custom head. The real `densenet121` and `densenet161`
//! presets build, run and export; the small presets train on this machine.

use burn::config::Config;
use burn::module::Module;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::nn::interpolate::{Interpolate2d, Interpolate2dConfig, InterpolateMode};
use burn::nn::pool::{AvgPool2d, AvgPool2dConfig, MaxPool2d, MaxPool2dConfig};
use burn::nn::{BatchNorm, BatchNormConfig, PaddingConfig2d};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};
use tactile_burn::runtime::Forward;
use tactile_core::{Error, Result};

/// DenseNet hyper-parameters (torchvision's names).
#[derive(Config, Debug, PartialEq)]
pub struct DenseNetConfig {
    /// Channels each dense layer adds.
    pub growth_rate: usize,
    /// Dense layers per block (four blocks).
    pub block_config: Vec<usize>,
    /// Channels of the stem convolution.
    pub num_init_features: usize,
    /// Bottleneck width, in multiples of the growth rate.
    #[config(default = 4)]
    pub bn_size: usize,
    /// Fraction of channels a transition keeps.
    #[config(default = 0.5)]
    pub compression: f64,
}

/// The encoders: the published DenseNets and smaller ones that train on
/// this machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum DenseNetPreset {
    /// Growth 8, blocks 2-2-2-2.
    Tiny,
    /// Growth 12, blocks 2-3-4-3.
    Small,
    /// Growth 16, blocks 3-4-6-4.
    Medium,
    /// torchvision's `densenet121`.
    Densenet121,
    /// torchvision's `densenet161`.
    Densenet161,
}

impl DenseNetPreset {
    /// The preset's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Tiny => "tiny",
            Self::Small => "small",
            Self::Medium => "medium",
            Self::Densenet121 => "densenet121",
            Self::Densenet161 => "densenet161",
        }
    }

    /// The preset `config` is, if any.
    pub fn of(config: &DenseNetConfig) -> Option<Self> {
        [
            Self::Tiny,
            Self::Small,
            Self::Medium,
            Self::Densenet121,
            Self::Densenet161,
        ]
        .into_iter()
        .find(|p| p.config() == *config)
    }

    /// Its hyper-parameters.
    pub fn config(self) -> DenseNetConfig {
        match self {
            Self::Tiny => DenseNetConfig::tiny(),
            Self::Small => DenseNetConfig::small(),
            Self::Medium => DenseNetConfig::medium(),
            Self::Densenet121 => DenseNetConfig::densenet121(),
            Self::Densenet161 => DenseNetConfig::densenet161(),
        }
    }
}

impl std::str::FromStr for DenseNetPreset {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        [
            Self::Tiny,
            Self::Small,
            Self::Medium,
            Self::Densenet121,
            Self::Densenet161,
        ]
        .into_iter()
        .find(|p| p.name() == s)
        .ok_or_else(|| {
            Error::Config(format!(
                "unknown encoder '{s}': expected densenet121, densenet161, tiny, small or medium"
            ))
        })
    }
}

/// Largest growth rate, stem width and decoder width accepted (the whole
/// network is also bounded by [`tactile_burn::artifact::MAX_PARAMETERS`]).
pub const MAX_CHANNELS: usize = 1024;
/// Largest number of layers in a dense block.
pub const MAX_BLOCK_LAYERS: usize = 64;
/// Largest input side accepted, pixels.
pub const MAX_INPUT_SIDE: usize = 2048;

impl DenseNetConfig {
    /// torchvision's `densenet121`.
    pub fn densenet121() -> Self {
        Self::new(32, vec![6, 12, 24, 16], 64)
    }

    /// torchvision's `densenet161`.
    pub fn densenet161() -> Self {
        Self::new(48, vec![6, 12, 36, 24], 96)
    }

    /// The smallest: growth 8, two layers per block.
    pub fn tiny() -> Self {
        Self::new(8, vec![2, 2, 2, 2], 16)
    }

    /// Growth 12, blocks 2-3-4-3.
    pub fn small() -> Self {
        Self::new(12, vec![2, 3, 4, 3], 24)
    }

    /// Growth 16, blocks 3-4-6-4.
    pub fn medium() -> Self {
        Self::new(16, vec![3, 4, 6, 4], 32)
    }

    /// A preset by name (see [`DenseNetPreset`]).
    pub fn preset(name: &str) -> Result<Self> {
        Ok(name.parse::<DenseNetPreset>()?.config())
    }

    /// Channels after the stem and after each block (skip widths).
    pub fn skip_channels(&self) -> Vec<usize> {
        let mut c = self.num_init_features;
        let mut out = vec![c];
        for (i, &n) in self.block_config.iter().enumerate() {
            c += n * self.growth_rate;
            out.push(c);
            if i + 1 < self.block_config.len() {
                c = (c as f64 * self.compression).floor() as usize;
            }
        }
        out
    }
}

/// The head on the decoder's last features.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum HeadKind {
    /// One 1x1 convolution (paper B's choice).
    #[value(alias = "1x1")]
    Conv1x1,
    /// Two 3x3 convolutions with ReLU, then 1x1 (paper B's "custom").
    Custom,
}

/// The whole network.
#[derive(Config, Debug, PartialEq)]
pub struct DepthNetConfig {
    /// The DenseNet encoder.
    pub encoder: DenseNetConfig,
    /// Input width and height; both multiples of 32.
    pub input_size: [usize; 2],
    /// 3 (RGB) or 4 (RGB + tendon mask).
    #[config(default = 3)]
    pub in_channels: usize,
    /// Channels of the deepest decoder block (halved at each level up, at least 8).
    #[config(default = 64)]
    pub decoder_width: usize,
    #[config(default = "HeadKind::Conv1x1")]
    /// The head.
    pub head: HeadKind,
    /// The input channel the output is added to: a network with a prior
    /// ([`crate::prior`]) learns a correction to it. `None`: depth itself.
    #[config(default = "None")]
    pub residual_channel: Option<usize>,
}

fn bn(c: usize, device: &Device) -> BatchNorm {
    BatchNormConfig::new(c).init(device)
}

fn conv(i: usize, o: usize, k: usize, bias: bool, device: &Device) -> Conv2d {
    let p = k / 2;
    Conv2dConfig::new([i, o], [k, k])
        .with_padding(PaddingConfig2d::Explicit(p, p, p, p))
        .with_bias(bias)
        .init(device)
}

/// BN-ReLU-1x1 (bn_size x growth) then BN-ReLU-3x3 (growth).
#[derive(Module, Debug)]
pub struct DenseLayer {
    /// Before the bottleneck.
    pub norm1: BatchNorm,
    /// 1x1 bottleneck to `bn_size x growth` channels.
    pub conv1: Conv2d,
    /// Before the 3x3.
    pub norm2: BatchNorm,
    /// 3x3 to `growth` channels.
    pub conv2: Conv2d,
    /// True once `norm2` is folded into `conv1` (inference only).
    #[module(skip)]
    pub folded: bool,
}

impl DenseLayer {
    fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let y = self.conv1.forward(relu(self.norm1.forward(x)));
        let y = if self.folded {
            y
        } else {
            self.norm2.forward(y)
        };
        self.conv2.forward(relu(y))
    }

    /// `norm2` folded into `conv1`, the convolution before it (`norm1`
    /// normalises the concatenated features and stays).
    fn fold(&mut self) {
        if !self.folded {
            tactile_burn::nn::fold_batch_norm(&mut self.conv1, &self.norm2);
            self.folded = true;
        }
    }
}

/// Layers whose outputs are concatenated onto the input, one by one.
#[derive(Module, Debug)]
pub struct DenseBlock {
    /// Its layers.
    pub layers: Vec<DenseLayer>,
}

impl DenseBlock {
    fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let mut feats = x;
        for l in &self.layers {
            let y = l.forward(feats.clone());
            feats = Tensor::cat(vec![feats, y], 1);
        }
        feats
    }
}

/// BN-ReLU-1x1 (compress) then 2x2 average pooling.
#[derive(Module, Debug)]
pub struct Transition {
    /// Before the compression.
    pub norm: BatchNorm,
    /// 1x1 compression.
    pub conv: Conv2d,
    /// 2x2 average pooling.
    pub pool: AvgPool2d,
}

/// The DenseNet feature extractor, returning the five skip tensors.
#[derive(Module, Debug)]
pub struct DenseNetEncoder {
    /// 7x7 stride-2 stem.
    pub conv0: Conv2d,
    /// Its norm.
    pub norm0: BatchNorm,
    /// 3x3 stride-2 max-pooling.
    pub pool0: MaxPool2d,
    /// The four dense blocks.
    pub blocks: Vec<DenseBlock>,
    /// Between the blocks.
    pub transitions: Vec<Transition>,
    /// After the last block.
    pub norm5: BatchNorm,
    /// True once `norm0` is folded into `conv0` (inference only).
    #[module(skip)]
    pub folded: bool,
}

impl DenseNetEncoder {
    /// Every norm that follows a convolution folded into it: the stem's
    /// and each dense layer's second (inference only).
    pub fn fold_batch_norms(&mut self) {
        if !self.folded {
            tactile_burn::nn::fold_batch_norm(&mut self.conv0, &self.norm0);
            self.folded = true;
        }
        for b in &mut self.blocks {
            for l in &mut b.layers {
                l.fold();
            }
        }
    }

    /// The skips, shallow first: the stem (1/2) and blocks 1-3 (1/4, 1/8,
    /// 1/16); and the deepest features, block 4 after the final norm (1/32).
    pub fn forward(&self, x: Tensor<4>) -> (Vec<Tensor<4>>, Tensor<4>) {
        let s0 = self.conv0.forward(x);
        let s0 = relu(if self.folded {
            s0
        } else {
            self.norm0.forward(s0)
        });
        let mut x = self.pool0.forward(s0.clone());
        let mut skips = vec![s0];
        for (i, b) in self.blocks.iter().enumerate() {
            x = b.forward(x);
            if let Some(t) = self.transitions.get(i) {
                skips.push(x.clone());
                x = t.pool.forward(t.conv.forward(relu(t.norm.forward(x))));
            }
        }
        (skips, relu(self.norm5.forward(x)))
    }
}

/// Upsample x2, concatenate the skip, two 3x3 conv + ReLU.
#[derive(Module, Debug)]
pub struct UpBlock {
    /// On the upsampled features and the skip.
    pub conv1: Conv2d,
    /// Second 3x3.
    pub conv2: Conv2d,
}

/// Frame `[N, C, H, W]` (normalised) -> depth `[N, 1, H, W]` in the
/// model's units (the folder's depth scale turns them into millimetres).
#[derive(Module, Debug)]
pub struct DepthNet {
    /// The DenseNet.
    pub encoder: DenseNetEncoder,
    /// 1x1 on the deepest features.
    pub bottleneck: Conv2d,
    /// One per skip, deepest first.
    pub up: Vec<UpBlock>,
    /// 1x1, or two 3x3 then 1x1.
    pub head: Vec<Conv2d>,
    /// Bilinear x2, half-pixel centres.
    pub upsample: Interpolate2d,
    /// The input channel the output is added to (a network with a prior).
    #[module(skip)]
    pub residual_channel: Option<usize>,
}

impl DenseNetConfig {
    /// The encoder with fresh weights, for `in_channels` inputs.
    pub fn init(&self, in_channels: usize, device: &Device) -> DenseNetEncoder {
        let mut c = self.num_init_features;
        let mut blocks = Vec::new();
        let mut transitions = Vec::new();
        for (i, &n) in self.block_config.iter().enumerate() {
            let layers = (0..n)
                .map(|j| {
                    let cin = c + j * self.growth_rate;
                    let mid = self.bn_size * self.growth_rate;
                    DenseLayer {
                        norm1: bn(cin, device),
                        conv1: conv(cin, mid, 1, false, device),
                        norm2: bn(mid, device),
                        conv2: conv(mid, self.growth_rate, 3, false, device),
                        folded: false,
                    }
                })
                .collect();
            blocks.push(DenseBlock { layers });
            c += n * self.growth_rate;
            if i + 1 < self.block_config.len() {
                let o = (c as f64 * self.compression).floor() as usize;
                transitions.push(Transition {
                    norm: bn(c, device),
                    conv: conv(c, o, 1, false, device),
                    pool: AvgPool2dConfig::new([2, 2]).with_strides([2, 2]).init(),
                });
                c = o;
            }
        }
        DenseNetEncoder {
            conv0: Conv2dConfig::new([in_channels, self.num_init_features], [7, 7])
                .with_stride([2, 2])
                .with_padding(PaddingConfig2d::Explicit(3, 3, 3, 3))
                .with_bias(false)
                .init(device),
            norm0: bn(self.num_init_features, device),
            pool0: MaxPool2dConfig::new([3, 3])
                .with_strides([2, 2])
                .with_padding(PaddingConfig2d::Explicit(1, 1, 1, 1))
                .init(),
            blocks,
            transitions,
            norm5: bn(c, device),
            folded: false,
        }
    }
}

impl DepthNetConfig {
    /// Check the sizes against the documented limits before anything is
    /// allocated for them.
    pub fn check(&self) -> Result<()> {
        let [w, h] = self.input_size;
        if w == 0
            || h == 0
            || !w.is_multiple_of(32)
            || !h.is_multiple_of(32)
            || w > MAX_INPUT_SIDE
            || h > MAX_INPUT_SIDE
        {
            return Err(Error::Config(format!(
                "depth input {w}x{h}: both sides must be multiples of 32 from 32 to {MAX_INPUT_SIDE}"
            )));
        }
        let e = &self.encoder;
        if e.block_config.len() != 4 {
            return Err(Error::Config(
                "the DenseNet encoder needs four blocks".into(),
            ));
        }
        if !(3..=4).contains(&self.in_channels) {
            return Err(Error::Config(format!(
                "{} input channels: expected 3 (RGB) or 4 (RGB + mask or prior)",
                self.in_channels
            )));
        }
        if let Some(c) = self.residual_channel
            && (c < 3 || c >= self.in_channels)
        {
            return Err(Error::Config(format!(
                "residual channel {c}: expected the fourth input channel (3) of a 4-channel network"
            )));
        }
        let channels = [
            ("growth rate", e.growth_rate),
            ("stem width", e.num_init_features),
            ("bottleneck size", e.bn_size),
            ("decoder width", self.decoder_width),
        ];
        for (name, v) in channels {
            if v == 0 || v > MAX_CHANNELS {
                return Err(Error::Config(format!(
                    "depth network {name} must be 1 to {MAX_CHANNELS}, got {v}"
                )));
            }
        }
        if let Some(&n) = e
            .block_config
            .iter()
            .find(|&&n| n == 0 || n > MAX_BLOCK_LAYERS)
        {
            return Err(Error::Config(format!(
                "dense blocks need 1 to {MAX_BLOCK_LAYERS} layers, got {n}"
            )));
        }
        if !(e.compression > 0.0 && e.compression <= 1.0) {
            return Err(Error::Config(format!(
                "transition compression must be in (0, 1], got {:?}",
                e.compression
            )));
        }
        // Every transition must keep at least one channel (as init builds them).
        let mut c = e.num_init_features;
        for (i, &n) in e.block_config.iter().enumerate() {
            c += n * e.growth_rate;
            if i + 1 < e.block_config.len() {
                c = (c as f64 * e.compression).floor() as usize;
                if c == 0 {
                    return Err(Error::Config(format!(
                        "transition compression {:?} leaves transition {} with no channels",
                        e.compression,
                        i + 1
                    )));
                }
            }
        }
        tactile_burn::artifact::check_parameters("depth network", self.parameter_bound())
    }

    /// An upper bound on the parameter count from the channel widths: the
    /// convolutions of every dense layer, transition, decoder block and head.
    pub fn parameter_bound(&self) -> u64 {
        let e = &self.encoder;
        let (g, mid) = (e.growth_rate as u64, (e.bn_size * e.growth_rate) as u64);
        let mut p = self.in_channels as u64 * e.num_init_features as u64 * 49;
        let mut c = e.num_init_features as u64;
        for (i, &n) in e.block_config.iter().enumerate() {
            for j in 0..n as u64 {
                let cin = c.saturating_add(j.saturating_mul(g));
                p = p.saturating_add(cin.saturating_mul(mid) + mid * g * 9 + 4 * (cin + mid));
            }
            c = c.saturating_add((n as u64).saturating_mul(g));
            if i + 1 < e.block_config.len() {
                let o = (c as f64 * e.compression) as u64;
                p = p.saturating_add(c.saturating_mul(o));
                c = o;
            }
        }
        let d = self.decoder_width as u64;
        // The decoder: each up block sees at most the deepest width plus a skip.
        p.saturating_add(4 * (c + d) * d * 9 * 2 + d * d * 9 * 2)
    }

    /// Check the sizes and build with fresh weights.
    pub fn init(&self, device: &Device) -> Result<DepthNet> {
        self.check()?;
        let skips = self.encoder.skip_channels();
        let widths: Vec<usize> = (0..4).map(|k| (self.decoder_width >> k).max(8)).collect();
        let mut c = widths[0];
        let bottleneck = conv(skips[4], c, 1, true, device);
        let up = (0..4)
            .map(|k| {
                let skip = skips[3 - k];
                let o = widths[k];
                let b = UpBlock {
                    conv1: conv(c + skip, o, 3, true, device),
                    conv2: conv(o, o, 3, true, device),
                };
                c = o;
                b
            })
            .collect();
        let head = match self.head {
            HeadKind::Conv1x1 => vec![conv(c, 1, 1, true, device)],
            HeadKind::Custom => vec![
                conv(c, c, 3, true, device),
                conv(c, c, 3, true, device),
                conv(c, 1, 1, true, device),
            ],
        };
        Ok(DepthNet {
            encoder: self.encoder.init(self.in_channels, device),
            bottleneck,
            up,
            head,
            upsample: Interpolate2dConfig::new()
                .with_scale_factor(Some([2.0, 2.0]))
                .with_mode(InterpolateMode::Linear)
                .with_align_corners(false)
                .init(),
            residual_channel: self.residual_channel,
        })
    }
}

impl Forward for DepthNet {
    fn forward_data(&self, x: Tensor<4>) -> TensorData {
        self.forward(x).into_data()
    }

    /// The encoder's foldable batch norms folded into their convolutions.
    fn for_inference(mut self) -> Self {
        self.encoder.fold_batch_norms();
        self
    }
}

/// Channel `c` of `x` (`[N, C, H, W]` -> `[N, 1, H, W]`), as a weighted
/// sum over channels: a slice would fix the batch size in the ONNX export.
fn channel(x: &Tensor<4>, c: usize) -> Tensor<4> {
    let n = x.dims()[1];
    let pick: Vec<f32> = (0..n).map(|k| f32::from(u8::from(k == c))).collect();
    let w = Tensor::<4>::from_data(TensorData::new(pick, [1, n, 1, 1]), &x.device());
    (x.clone() * w).sum_dim(1)
}

impl DepthNet {
    /// Depth in the model's units (the folder's depth scale turns them into millimetres).
    ///
    /// # Shapes
    /// - `x`: `[N, C, H, W]`, RGB normalised with the training statistics
    ///   (and the tendon mask as a fourth channel when it takes one)
    /// - output: `[N, 1, H, W]` (the residual channel of `x` plus the
    ///   network's correction, for a network with a prior)
    pub fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let prior = self.residual_channel.map(|c| channel(&x, c));
        let (mut skips, deepest) = self.encoder.forward(x);
        let mut y = self.bottleneck.forward(deepest);
        for b in &self.up {
            let Some(skip) = skips.pop() else { break };
            y = Tensor::cat(vec![self.upsample.forward(y), skip], 1);
            y = relu(b.conv2.forward(relu(b.conv1.forward(y))));
        }
        let n = self.head.len();
        for (i, c) in self.head.iter().enumerate() {
            y = c.forward(y);
            if i + 1 < n {
                y = relu(y);
            }
        }
        let y = self.upsample.forward(y);
        match prior {
            Some(p) => y + p,
            None => y,
        }
    }

    /// Stop gradients into the encoder (paper B's frozen ImageNet encoder).
    pub fn freeze_encoder(mut self) -> Self {
        self.encoder = self.encoder.no_grad();
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_have_the_published_widths() {
        // torchvision: densenet121 ends with 1024 channels, densenet161 with 2208.
        assert_eq!(
            *DenseNetConfig::preset("densenet121")
                .unwrap()
                .skip_channels()
                .last()
                .unwrap(),
            1024
        );
        assert_eq!(
            *DenseNetConfig::preset("densenet161")
                .unwrap()
                .skip_channels()
                .last()
                .unwrap(),
            2208
        );
        assert!(DenseNetConfig::preset("densenet999").is_err());
    }

    #[test]
    fn depth_has_the_input_size_for_every_head_and_channel_count() {
        let device = Device::flex();
        for (head, ch) in [(HeadKind::Conv1x1, 3), (HeadKind::Custom, 4)] {
            let cfg = DepthNetConfig::new(DenseNetConfig::preset("tiny").unwrap(), [64, 32])
                .with_head(head)
                .with_in_channels(ch)
                .with_decoder_width(16);
            let m = cfg.init(&device).unwrap();
            let y = m.forward(Tensor::<4>::zeros([2, ch, 32, 64], &device));
            assert_eq!(y.dims(), [2, 1, 32, 64]);
        }
        let bad = DepthNetConfig::new(DenseNetConfig::preset("tiny").unwrap(), [60, 32]);
        assert!(bad.init(&device).is_err());
    }
}
