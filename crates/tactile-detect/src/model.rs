//! The tendon detector of paper B: a MobileNetV3-small-style network
//! (inverted residuals, depthwise convolutions, squeeze-and-excite,
//! hard-swish, batch norm) with a width multiplier, and the ResNet-18-style
//! network the paper started from. Both end in paper B's head, FC 256 -> 1
//! logit (tendon present).

use burn::config::Config;
use burn::module::Module;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::nn::pool::{AdaptiveAvgPool2d, AdaptiveAvgPool2dConfig, MaxPool2d, MaxPool2dConfig};
use burn::nn::{BatchNorm, BatchNormConfig, Linear, LinearConfig, PaddingConfig2d};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};
use tactile_burn::nn::{hard_sigmoid, hard_swish};
use tactile_burn::runtime::Forward;

/// Which network.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Architecture {
    /// MobileNetV3-small (Howard et al. 2019, Table 2).
    #[value(alias = "mobilenet")]
    #[serde(alias = "mobilenet")]
    MobilenetV3Small,
    /// ResNet-18 (two basic blocks per stage), paper B's slower baseline.
    #[value(name = "resnet18", alias = "resnet-18")]
    #[serde(alias = "resnet-18")]
    Resnet18,
}

/// Architecture and input size of a detector.
#[derive(Config, Debug, PartialEq)]
pub struct DetectorConfig {
    #[config(default = "Architecture::MobilenetV3Small")]
    /// Which network.
    pub architecture: Architecture,
    /// Channel width multiplier (1.0 = the published network).
    #[config(default = 1.0)]
    pub width: f64,
    /// Input width and height in pixels (paper B: 320 x 240).
    #[config(default = "[320, 240]")]
    pub input_size: [usize; 2],
    /// Hidden width of the head (paper B: 256).
    #[config(default = 256)]
    pub head_hidden: usize,
    /// Bits per channel the resized input keeps (8 or 16). A light press
    /// shades the skin by a grey level or two; averaging the frame down to
    /// the input recovers a fraction of a level from the sensor's noise,
    /// which 8 bits round away and 16 keep. None (folders saved before
    /// it existed): 8.
    #[config(default = "None")]
    pub input_bits: Option<u8>,
    /// Divide each channel by its level at the window's centre before the
    /// network (see `normalise_exposure`): the label is a threshold on the
    /// ridge's height, and the shading contrast a height makes scales with
    /// the exposure and the LEDs. None (folders saved before it existed):
    /// off.
    #[config(default = "None")]
    pub normalise_exposure: Option<bool>,
}

/// `v * width`, rounded to a multiple of 8 and not below 90 % of it, as in
/// the MobileNet reference code.
pub fn make_divisible(v: f64) -> usize {
    let d = 8.0;
    let mut n = ((v + d / 2.0) / d).floor() * d;
    n = n.max(d);
    if n < 0.9 * v {
        n += d;
    }
    n as usize
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Act {
    Relu,
    HardSwish,
}

fn act(a: Act, x: Tensor<4>) -> Tensor<4> {
    match a {
        Act::Relu => relu(x),
        Act::HardSwish => hard_swish(x),
    }
}

/// Conv + batch norm (no bias: the norm has one).
#[derive(Module, Debug)]
pub struct ConvBn {
    /// The convolution, without bias.
    pub conv: Conv2d,
    /// Its batch norm.
    pub bn: BatchNorm,
    /// True once the norm is folded into the convolution (inference only).
    #[module(skip)]
    pub folded: bool,
}

impl ConvBn {
    fn new([i, o]: [usize; 2], k: usize, stride: usize, groups: usize, device: &Device) -> Self {
        let p = k / 2;
        Self {
            conv: Conv2dConfig::new([i, o], [k, k])
                .with_stride([stride, stride])
                .with_padding(PaddingConfig2d::Explicit(p, p, p, p))
                .with_groups(groups)
                .with_bias(false)
                .init(device),
            bn: BatchNormConfig::new(o).init(device),
            folded: false,
        }
    }

    fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let y = self.conv.forward(x);
        if self.folded { y } else { self.bn.forward(y) }
    }

    /// Fold the norm into the convolution: one op instead of two.
    fn fold(&mut self) {
        if !self.folded {
            tactile_burn::nn::fold_batch_norm(&mut self.conv, &self.bn);
            self.folded = true;
        }
    }
}

/// Squeeze-and-excite: channel weights from the global average.
#[derive(Module, Debug)]
pub struct SqueezeExcite {
    /// Global average.
    pub pool: AdaptiveAvgPool2d,
    /// To a quarter of the channels.
    pub reduce: Conv2d,
    /// Back to every channel.
    pub expand: Conv2d,
}

impl SqueezeExcite {
    fn new(c: usize, device: &Device) -> Self {
        let squeezed = make_divisible(c as f64 / 4.0);
        Self {
            pool: AdaptiveAvgPool2dConfig::new([1, 1]).init(),
            reduce: Conv2dConfig::new([c, squeezed], [1, 1]).init(device),
            expand: Conv2dConfig::new([squeezed, c], [1, 1]).init(device),
        }
    }

    fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let s = self.pool.forward(x.clone());
        let s = hard_sigmoid(self.expand.forward(relu(self.reduce.forward(s))));
        x * s
    }
}

/// Inverted residual: 1x1 expand, k x k depthwise, optional SE, 1x1 project.
#[derive(Module, Debug)]
pub struct InvertedResidual {
    /// 1x1 expansion (absent when the expansion equals the input width).
    pub expand: Option<ConvBn>,
    /// k x k depthwise convolution.
    pub depthwise: ConvBn,
    /// Squeeze-and-excite, in the blocks that have it.
    pub se: Option<SqueezeExcite>,
    /// 1x1 projection, linear.
    pub project: ConvBn,
    /// Hard-swish (else ReLU) after expansion and depthwise.
    pub hard_swish: bool,
    /// Add the input (stride 1, same width).
    pub residual: bool,
}

impl InvertedResidual {
    fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let a = if self.hard_swish {
            Act::HardSwish
        } else {
            Act::Relu
        };
        let mut y = x.clone();
        if let Some(e) = &self.expand {
            y = act(a, e.forward(y));
        }
        y = act(a, self.depthwise.forward(y));
        if let Some(se) = &self.se {
            y = se.forward(y);
        }
        y = self.project.forward(y);
        if self.residual { y + x } else { y }
    }
}

/// (kernel, expansion, output, squeeze-excite, hard-swish, stride).
const MOBILENET_V3_SMALL: [(usize, usize, usize, bool, bool, usize); 11] = [
    (3, 16, 16, true, false, 2),
    (3, 72, 24, false, false, 2),
    (3, 88, 24, false, false, 1),
    (5, 96, 40, true, true, 2),
    (5, 240, 40, true, true, 1),
    (5, 240, 40, true, true, 1),
    (5, 120, 48, true, true, 1),
    (5, 144, 48, true, true, 1),
    (5, 288, 96, true, true, 2),
    (5, 576, 96, true, true, 1),
    (5, 576, 96, true, true, 1),
];

/// ResNet basic block: two 3x3 conv-BN, identity or 1x1 projection shortcut.
#[derive(Module, Debug)]
pub struct BasicBlock {
    /// First 3x3 conv-BN (carries the stride).
    pub conv1: ConvBn,
    /// Second 3x3 conv-BN.
    pub conv2: ConvBn,
    /// 1x1 projection when the shape changes.
    pub shortcut: Option<ConvBn>,
}

impl BasicBlock {
    fn new(i: usize, o: usize, stride: usize, device: &Device) -> Self {
        Self {
            conv1: ConvBn::new([i, o], 3, stride, 1, device),
            conv2: ConvBn::new([o, o], 3, 1, 1, device),
            shortcut: (stride != 1 || i != o).then(|| ConvBn::new([i, o], 1, stride, 1, device)),
        }
    }

    fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let y = self.conv2.forward(relu(self.conv1.forward(x.clone())));
        let s = match &self.shortcut {
            Some(p) => p.forward(x),
            None => x,
        };
        relu(y + s)
    }
}

/// The feature extractor of either architecture. (Built once per model, so
/// the size difference of the variants does not matter; burn's `Module`
/// derive does not accept boxed fields.)
#[allow(clippy::large_enum_variant)]
#[derive(Module, Debug)]
pub enum Backbone {
    /// MobileNetV3-small.
    Mobilenet(MobilenetBody),
    /// ResNet-18.
    Resnet(ResnetBody),
}

/// MobileNetV3-small's stem, blocks and last 1x1 convolution.
#[derive(Module, Debug)]
pub struct MobilenetBody {
    /// 3x3 stride-2 stem.
    pub stem: ConvBn,
    /// The eleven inverted residuals.
    pub blocks: Vec<InvertedResidual>,
    /// 1x1 to six times the last width.
    pub last: ConvBn,
}

/// ResNet-18's stem, pooling and eight basic blocks.
#[derive(Module, Debug)]
pub struct ResnetBody {
    /// 7x7 stride-2 stem.
    pub stem: ConvBn,
    /// 3x3 stride-2 max-pooling.
    pub pool: MaxPool2d,
    /// Two blocks per stage.
    pub blocks: Vec<BasicBlock>,
}

/// Frame `[N, 3, H, W]` (normalised) -> tendon logit `[N, 1]`.
#[derive(Module, Debug)]
pub struct Detector {
    /// Feature extractor.
    pub backbone: Backbone,
    /// Global average.
    pub pool: AdaptiveAvgPool2d,
    /// Paper B's FC 256.
    pub fc1: Linear,
    /// To one logit.
    pub fc2: Linear,
}

/// Largest channel width multiplier accepted.
pub const MAX_WIDTH: f64 = 2.0;
/// Input sides accepted, pixels.
pub const INPUT_SIDE: std::ops::RangeInclusive<usize> = 16..=2048;
/// Largest hidden width of the head.
pub const MAX_HEAD_HIDDEN: usize = 4096;

impl DetectorConfig {
    /// Check the sizes against the documented limits before anything is
    /// allocated for them.
    pub fn check(&self) -> tactile_core::Result<()> {
        let [w, h] = self.input_size;
        if !(self.width > 0.0 && self.width <= MAX_WIDTH) {
            return Err(tactile_core::Error::Config(format!(
                "detector width must be in (0, {MAX_WIDTH}], got {:?}",
                self.width
            )));
        }
        if !INPUT_SIDE.contains(&w) || !INPUT_SIDE.contains(&h) {
            return Err(tactile_core::Error::Config(format!(
                "detector input {w}x{h}: each side must be {} to {} pixels",
                INPUT_SIDE.start(),
                INPUT_SIDE.end()
            )));
        }
        if !tactile_preprocess::visuo::INPUT_BITS.contains(&self.bits()) {
            return Err(tactile_core::Error::Config(format!(
                "detector input bits must be 8 or 16, got {}",
                self.bits()
            )));
        }
        if self.head_hidden == 0 || self.head_hidden > MAX_HEAD_HIDDEN {
            return Err(tactile_core::Error::Config(format!(
                "detector head width must be 1 to {MAX_HEAD_HIDDEN}, got {}",
                self.head_hidden
            )));
        }
        Ok(())
    }

    /// Bits per channel of the input (8 unless `input_bits` says).
    pub fn bits(&self) -> u8 {
        self.input_bits.unwrap_or(8)
    }

    /// Whether inputs are divided by their window level.
    pub fn normalises_exposure(&self) -> bool {
        self.normalise_exposure.unwrap_or(false)
    }

    /// Build with fresh weights.
    pub fn init(&self, device: &Device) -> Detector {
        let w = self.width;
        let (backbone, features) = match self.architecture {
            Architecture::MobilenetV3Small => {
                let stem_c = make_divisible(16.0 * w);
                let mut c = stem_c;
                let blocks = MOBILENET_V3_SMALL
                    .iter()
                    .map(|&(k, exp, out, se, hs, stride)| {
                        let (e, o) = (
                            make_divisible(exp as f64 * w),
                            make_divisible(out as f64 * w),
                        );
                        let b = InvertedResidual {
                            expand: (e != c).then(|| ConvBn::new([c, e], 1, 1, 1, device)),
                            depthwise: ConvBn::new([e, e], k, stride, e, device),
                            se: se.then(|| SqueezeExcite::new(e, device)),
                            project: ConvBn::new([e, o], 1, 1, 1, device),
                            hard_swish: hs,
                            residual: stride == 1 && c == o,
                        };
                        c = o;
                        b
                    })
                    .collect();
                let last_c = 6 * c;
                (
                    Backbone::Mobilenet(MobilenetBody {
                        stem: ConvBn::new([3, stem_c], 3, 2, 1, device),
                        blocks,
                        last: ConvBn::new([c, last_c], 1, 1, 1, device),
                    }),
                    last_c,
                )
            }
            Architecture::Resnet18 => {
                let widths = [64.0, 128.0, 256.0, 512.0].map(|c| make_divisible(c * w));
                let mut c = widths[0];
                let mut blocks = Vec::new();
                for (stage, &o) in widths.iter().enumerate() {
                    for b in 0..2 {
                        let stride = if stage > 0 && b == 0 { 2 } else { 1 };
                        blocks.push(BasicBlock::new(c, o, stride, device));
                        c = o;
                    }
                }
                (
                    Backbone::Resnet(ResnetBody {
                        stem: ConvBn::new([3, widths[0]], 7, 2, 1, device),
                        pool: MaxPool2dConfig::new([3, 3])
                            .with_strides([2, 2])
                            .with_padding(PaddingConfig2d::Explicit(1, 1, 1, 1))
                            .init(),
                        blocks,
                    }),
                    c,
                )
            }
        };
        Detector {
            backbone,
            pool: AdaptiveAvgPool2dConfig::new([1, 1]).init(),
            fc1: LinearConfig::new(features, self.head_hidden).init(device),
            fc2: LinearConfig::new(self.head_hidden, 1).init(device),
        }
    }
}

impl Forward for Detector {
    fn forward_data(&self, x: Tensor<4>) -> TensorData {
        self.forward(x).into_data()
    }

    /// Every batch norm folded into its convolution.
    fn for_inference(mut self) -> Self {
        match &mut self.backbone {
            Backbone::Mobilenet(m) => {
                m.stem.fold();
                for b in &mut m.blocks {
                    if let Some(e) = b.expand.as_mut() {
                        e.fold();
                    }
                    b.depthwise.fold();
                    b.project.fold();
                }
                m.last.fold();
            }
            Backbone::Resnet(r) => {
                r.stem.fold();
                for b in &mut r.blocks {
                    b.conv1.fold();
                    b.conv2.fold();
                    if let Some(s) = b.shortcut.as_mut() {
                        s.fold();
                    }
                }
            }
        }
        self
    }
}

impl Detector {
    /// Tendon logits; their sigmoid is the tendon probability.
    ///
    /// # Shapes
    /// - `x`: `[N, 3, H, W]`, normalised with the training statistics
    /// - output: `[N, 1]`
    pub fn forward(&self, x: Tensor<4>) -> Tensor<2> {
        let (x, hs) = match &self.backbone {
            Backbone::Mobilenet(m) => {
                let mut x = hard_swish(m.stem.forward(x));
                for b in &m.blocks {
                    x = b.forward(x);
                }
                (hard_swish(m.last.forward(x)), true)
            }
            Backbone::Resnet(r) => {
                let mut x = r.pool.forward(relu(r.stem.forward(x)));
                for b in &r.blocks {
                    x = b.forward(x);
                }
                (x, false)
            }
        };
        let [n, c, _, _] = x.dims();
        let f = self.pool.forward(x).reshape([n, c]);
        let h = self.fc1.forward(f);
        let h = if hs { hard_swish(h) } else { relu(h) };
        self.fc2.forward(h)
    }
}

/// Number of trainable parameters.
pub fn parameter_count(m: &Detector) -> usize {
    m.num_params()
}

#[cfg(test)]
mod tests {
    use super::*;
    use tactile_preprocess::visuo::FloatImage;

    #[test]
    fn folders_saved_before_the_input_form_existed_read_as_eight_bits_unnormalised() {
        let old = r#"{"architecture": "mobilenet-v3-small", "width": 0.5, "input_size": [80, 60], "head_hidden": 256}"#;
        let cfg: DetectorConfig = serde_json::from_str(old).unwrap();
        assert_eq!((cfg.bits(), cfg.normalises_exposure()), (8, false));
        assert!(cfg.check().is_ok());
        let twelve = cfg.clone().with_input_bits(Some(12)).check().unwrap_err();
        assert!(twelve.to_string().contains("8 or 16"), "{twelve}");
        // Off, the view is the frame itself; on, its gain is divided out.
        let img = FloatImage {
            width: 4,
            height: 4,
            channels: 3,
            data: vec![0.3; 48],
        };
        assert_eq!(cfg.network_view(img.clone()), img);
        let on = cfg.with_normalise_exposure(Some(true)).network_view(img);
        assert!(on.data.iter().all(|&v| (v - 0.6).abs() < 1e-6));
    }

    #[test]
    fn both_architectures_give_one_logit_per_frame() {
        let device = Device::flex();
        for arch in [Architecture::MobilenetV3Small, Architecture::Resnet18] {
            let cfg = DetectorConfig::new()
                .with_architecture(arch)
                .with_width(0.25)
                .with_input_size([64, 48]);
            let m = cfg.init(&device);
            let y = m.forward(Tensor::<4>::zeros([2, 3, 48, 64], &device));
            assert_eq!(y.dims(), [2, 1]);
        }
        // The published MobileNetV3-small backbone (width 1.0) has about
        // 0.93 M parameters before its classifier; ours adds 576x256 + 256.
        let full = DetectorConfig::new().init(&device);
        let n = parameter_count(&full);
        assert!((1_050_000..1_150_000).contains(&n), "{n}");
    }

    #[test]
    fn width_rounds_to_multiples_of_eight() {
        assert_eq!(make_divisible(16.0 * 0.25), 8);
        assert_eq!(make_divisible(72.0 * 0.5), 40);
        assert_eq!(make_divisible(576.0), 576);
    }
}
