#![allow(clippy::unwrap_used)]
//! tactile-onnx on its own: a burn network exported with a dynamic batch
//! axis runs in onnxruntime with burn's numbers; a standalone graph made
//! from it takes a `uint8` frame, normalises it and answers with its gates
//! as the toolkit would; bad bytes are an error, not a crash.

use burn::module::Module;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::tensor::{Device, Tensor, TensorData};
use tactile_onnx::standalone::{GateSpec, StandaloneOutput, StandaloneSpec, f32_at_or_above};
use tactile_onnx::{OrtModel, export_batch_dynamic};

const H: usize = 6;
const W: usize = 8;

/// A one-logit "detector": a convolution over the whole frame.
#[derive(Module, Debug)]
struct Logit {
    conv: Conv2d,
}

impl Logit {
    fn forward(&self, x: Tensor<4>) -> Tensor<2> {
        let y = self.conv.forward(x);
        let [n, ..] = y.dims();
        y.reshape([n, 1])
    }
}

fn network() -> Logit {
    let device = Device::flex();
    Logit {
        conv: Conv2dConfig::new([3, 1], [H, W]).init(&device),
    }
}

/// A frame `[H, W, 3]` of levels 0-255 from a seed.
fn frame(seed: u32) -> Vec<u8> {
    (0..H * W * 3)
        .map(|i| (((i as u32).wrapping_mul(2_654_435_761) ^ seed.wrapping_mul(40_503)) >> 7) as u8)
        .collect()
}

fn burn_logits(net: &Logit, x: &[f32], n: usize) -> Vec<f32> {
    let t = Tensor::<4>::from_data(TensorData::new(x.to_vec(), [n, 3, H, W]), &Device::flex());
    net.forward(t).into_data().try_to_vec::<f32>().unwrap()
}

#[test]
fn an_exported_network_runs_in_onnxruntime_with_burns_numbers_at_any_batch() {
    let net = network();
    let onnx = export_batch_dynamic(&net, [1, 3, H, W], |m: &Logit, x| m.forward(x)).unwrap();
    let mut ort = OrtModel::from_bytes(&onnx, 1).unwrap();
    for n in [1, 3] {
        let x: Vec<f32> = (0..n * 3 * H * W)
            .map(|i| ((i * 37) % 101) as f32 / 50.0 - 1.0)
            .collect();
        let (shape, got) = ort.run_f32(&[n, 3, H, W], x.clone()).unwrap();
        assert_eq!(shape, [n, 1]);
        let want = burn_logits(&net, &x, n);
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() <= 1e-4 * (1.0 + w.abs()), "{g} vs {w}");
        }
    }
}

#[test]
fn one_network_exports_to_the_same_bytes_however_many_tensors_came_before() {
    let net = network();
    let export = || export_batch_dynamic(&net, [1, 3, H, W], |m: &Logit, x| m.forward(x)).unwrap();
    let first = export();
    // Tensors made in between (a model run, another export) do not rename
    // the next export's.
    let _ = burn_logits(&net, &vec![0.5; 2 * 3 * H * W], 2);
    let _ = export();
    assert!(first == export(), "a second export of one network differs");
    // The network's input is the first tensor named.
    assert!(first.windows(8).any(|w| w == b"tensor_0"));
}

#[test]
fn a_standalone_graph_normalises_gates_and_decides_as_the_toolkit() {
    let net = network();
    let onnx = export_batch_dynamic(&net, [1, 3, H, W], |m: &Logit, x| m.forward(x)).unwrap();
    let (mean, std) = (vec![0.5, 0.4, 0.3], vec![0.25, 0.2, 0.3]);
    let threshold = 0.5;
    let spec = StandaloneSpec {
        height: H,
        width: W,
        mean: mean.clone(),
        std: std.clone(),
        output: StandaloneOutput::Probability {
            name: "tendon_probability".into(),
        },
        metadata: vec![("threshold".into(), threshold.to_string())],
        input_bits: 8,
        exposure_level: None,
        gates: Some(GateSpec {
            blank_std: 0.5 / 255.0,
            profile: None,
            threshold: f32_at_or_above(threshold),
        }),
    };
    let standalone = tactile_onnx::standalone::make_standalone(&onnx, &spec).unwrap();
    let mut ort = OrtModel::from_bytes(&standalone, 1).unwrap();
    let frames = [frame(1), frame(2), vec![128u8; H * W * 3]];
    let data: Vec<u8> = frames.concat();
    let out = ort.run_frame_outputs(&[3, H, W, 3], data).unwrap();
    let names: Vec<&str> = out.iter().map(|o| o.name.as_str()).collect();
    for want in ["tendon_probability", "gate", "input_score", "tendon"] {
        assert!(names.contains(&want), "{want} not in {names:?}");
    }
    let get = |n: &str| &out.iter().find(|o| o.name == n).unwrap().values;
    let (p, gate, tendon) = (get("tendon_probability"), get("gate"), get("tendon"));
    // What the toolkit computes for the two textured frames: levels to
    // [0, 1], normalised per channel, channels first, the network, sigmoid.
    for (k, f) in frames[..2].iter().enumerate() {
        let mut x = vec![0f32; 3 * H * W];
        for (i, &v) in f.iter().enumerate() {
            let c = i % 3;
            let px = i / 3;
            x[c * H * W + px] = (v as f32 / 255.0 - mean[c]) / std[c];
        }
        let logit = burn_logits(&net, &x, 1)[0];
        let want = 1.0 / (1.0 + (-logit).exp());
        assert!((p[k] - want).abs() < 1e-5, "frame {k}: {} vs {want}", p[k]);
        assert_eq!(gate[k], 0.0, "a textured frame passes the gates");
        assert_eq!(tendon[k] == 1.0, p[k] as f64 >= threshold);
    }
    // The flat frame is blank: probability 0, gate 1, no tendon.
    assert_eq!((p[2], gate[2], tendon[2]), (0.0, 1.0, 0.0));
}

#[test]
fn bad_bytes_and_bad_inputs_are_errors() {
    assert!(OrtModel::from_bytes(b"not a model", 1).is_err());
    assert!(
        tactile_onnx::standalone::make_standalone(b"\x08\x07garbage", &spec_for_garbage()).is_err()
    );
    let onnx = export_batch_dynamic(&network(), [1, 3, H, W], |m: &Logit, x| m.forward(x)).unwrap();
    let mut ort = OrtModel::from_bytes(&onnx, 1).unwrap();
    // A frame of the wrong size is refused by the runtime, with a message.
    let e = ort.run_f32(&[1, 3, H + 1, W], vec![0.0; 3 * (H + 1) * W]);
    assert!(e.is_err());
    // The threshold rounds up to the first f32 at or above it.
    let t = 0.1f64;
    let f = f32_at_or_above(t);
    assert!(f as f64 >= t && (f.next_down() as f64) < t);
}

fn spec_for_garbage() -> StandaloneSpec {
    StandaloneSpec {
        height: H,
        width: W,
        mean: vec![0.0; 3],
        std: vec![1.0; 3],
        output: StandaloneOutput::Affine {
            name: "depth_mm".into(),
            scale: 1.0,
            offset: 0.0,
        },
        metadata: vec![],
        input_bits: 8,
        exposure_level: None,
        gates: None,
    }
}
