#![allow(clippy::unwrap_used)]
//! Exported ONNX files pass `onnx.checker` (full check) and onnxruntime
//! agrees with burn on ndarray and on flex within 1e-4 (max abs), for the
//! CAE encoder and the whole autoencoder, with the authors' weights and
//! with fresh paper-width weights.

mod common;

use burn::tensor::{Device, Tensor, TensorData};
use tactile_rs::cae::artifact::{load_module, save_module};
use tactile_rs::cae::authors::load_authors_encoder;
use tactile_rs::cae::data::PinSet;
use tactile_rs::cae::{Cae, CaeConfig};
use tactile_rs::core::DeviceKind;
use tactile_rs::core::dataset::Dataset;
use tactile_rs::core::metrics::max_abs_diff;
use tactile_rs::onnx::{OrtModel, export_cae, export_cae_encoder, onnx_full_check};
use tactile_rs::preprocess::PreprocessConfig;

const TOL: f32 = 1e-4;

/// 8 real pin images plus 4 seeded random binary ones.
fn inputs() -> (Vec<usize>, Vec<f32>) {
    let real = common::shared_real().join("polic-shapes");
    let ds = Dataset::open(&real).unwrap();
    let pins = PinSet::from_dataset(&ds, &PreprocessConfig::binary_frames()).unwrap();
    let mut data: Vec<f32> = (0..8)
        .flat_map(|i| pins.images[i * 150].pixels.clone())
        .collect();
    let mut s = 12345u64;
    for _ in 0..4 * 784 {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        data.push(((s >> 33) & 1) as f32);
    }
    (vec![12, 1, 28, 28], data)
}

fn burn_out(
    f: impl Fn(Tensor<4>) -> Vec<f32>,
    shape: &[usize],
    data: &[f32],
    device: &Device,
) -> Vec<f32> {
    f(Tensor::from_data(
        TensorData::new(data.to_vec(), shape.to_vec()),
        device,
    ))
}

fn check(
    name: &str,
    bytes: &[u8],
    shape: &[usize],
    data: &[f32],
    burn: impl Fn(&Device) -> Vec<f32>,
) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("{name}.onnx"));
    std::fs::write(&path, bytes).unwrap();
    onnx_full_check(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut ort = OrtModel::from_bytes(bytes, 1).unwrap();
    let (_, ort_out) = ort.run_f32(shape, data.to_vec()).unwrap();
    for kind in DeviceKind::ALL {
        let b = burn(&kind.device());
        assert_eq!(b.len(), ort_out.len(), "{name}: output sizes differ");
        let d = max_abs_diff(&b, &ort_out);
        println!("{name} {kind} vs onnxruntime: max abs diff {d:.2e}");
        assert!(d <= TOL, "{name} on {kind}: max abs diff {d} > {TOL}");
    }
}

/// A model built once on flex (its fresh weights are random), saved, and
/// loaded again on whichever device asks, so every runtime sees the same weights.
fn frozen(name: &str, cfg: CaeConfig, build: impl Fn() -> Cae) -> impl Fn(&Device) -> Cae {
    let file =
        std::env::temp_dir().join(format!("tactile-parity-{name}-{}.bpk", std::process::id()));
    save_module(&build(), &file).unwrap();
    move |d: &Device| load_module(cfg.init(d), &file).unwrap()
}

type MakeModel = Box<dyn Fn(&Device) -> Cae>;

fn cae_models() -> Vec<(&'static str, MakeModel)> {
    let path = common::shared_real().join("polic-shapes/authors-encoder.safetensors");
    let authors_cfg = CaeConfig::new().with_widths([16, 16, 8, 4]);
    vec![
        // The released encoder with a fresh decoder.
        (
            "authors",
            Box::new(frozen("authors", authors_cfg, move || {
                load_authors_encoder(&path, &Device::flex()).unwrap()
            })),
        ),
        // Paper widths, fresh weights.
        (
            "paper-widths",
            Box::new(frozen("paper", CaeConfig::new(), || {
                CaeConfig::new().init(&Device::flex())
            })),
        ),
    ]
}

#[test]
fn cae_encoder_and_autoencoder_match_onnxruntime() {
    let (shape, data) = inputs();
    for (name, make) in cae_models() {
        let m = make(&Device::flex());
        let enc = export_cae_encoder(&m.encoder, 28).unwrap();
        check(&format!("{name}-encoder"), &enc, &shape, &data, |d| {
            let m = make(d);
            burn_out(
                |x| {
                    m.encoder
                        .forward(x)
                        .into_data()
                        .try_to_vec::<f32>()
                        .unwrap()
                },
                &shape,
                &data,
                d,
            )
        });
        let full = export_cae(&m, 28).unwrap();
        check(&format!("{name}-autoencoder"), &full, &shape, &data, |d| {
            let m = make(d);
            burn_out(
                |x| m.forward(x).into_data().try_to_vec::<f32>().unwrap(),
                &shape,
                &data,
                d,
            )
        });
    }
}

/// Seeded values in [-2, 2): stand-ins for normalised frames.
fn frames(n: usize, seed: u64) -> Vec<f32> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 40) as f32 / (1u64 << 24) as f32) * 4.0 - 2.0
        })
        .collect()
}

/// Any module built once on flex, saved, and rebuilt on each device.
fn frozen_any<M: burn::module::Module>(
    name: &str,
    build: impl Fn(&Device) -> M,
) -> impl Fn(&Device) -> M {
    let file =
        std::env::temp_dir().join(format!("tactile-parity-{name}-{}.bpk", std::process::id()));
    save_module(&build(&Device::flex()), &file).unwrap();
    move |d: &Device| load_module(build(d), &file).unwrap()
}

#[test]
fn detectors_match_onnxruntime() {
    use tactile_rs::detect::{Architecture, DetectorConfig};
    use tactile_rs::onnx::export_detector;
    // Hard-swish and hard-sigmoid are exported as Relu/Add/Sub/Mul/Div:
    // parity here is what proves that form exact.
    for (name, arch) in [
        ("mobilenet", Architecture::MobilenetV3Small),
        ("resnet18", Architecture::Resnet18),
    ] {
        let cfg = DetectorConfig::new()
            .with_architecture(arch)
            .with_width(0.25)
            .with_input_size([64, 48]);
        let make = frozen_any(name, |d| cfg.init(d));
        let bytes = export_detector(&make(&Device::flex()), [64, 48]).unwrap();
        let shape = [3usize, 3, 48, 64];
        let data = frames(shape.iter().product(), 99);
        check(&format!("detector-{name}"), &bytes, &shape, &data, |d| {
            let m = make(d);
            burn_out(
                |x| m.forward(x).into_data().try_to_vec::<f32>().unwrap(),
                &shape,
                &data,
                d,
            )
        });
    }
}

#[test]
fn segmenter_matches_onnxruntime() {
    use tactile_rs::onnx::export_segmenter;
    use tactile_rs::segment::UNetConfig;
    let cfg = UNetConfig::new().with_base(4).with_side(48);
    let make = frozen_any("unet", |d| cfg.init(d).unwrap());
    let bytes = export_segmenter(&make(&Device::flex()), 48).unwrap();
    let shape = [2usize, 3, 48, 48];
    let data = frames(shape.iter().product(), 7);
    check("segmenter", &bytes, &shape, &data, |d| {
        let m = make(d);
        burn_out(
            |x| m.forward(x).into_data().try_to_vec::<f32>().unwrap(),
            &shape,
            &data,
            d,
        )
    });
}

/// Two virtual palpation frames (before contact, full press) at `w x h`.
fn palpation_frames(w: usize, h: usize) -> Vec<tactile_rs::preprocess::visuo::FloatImage> {
    use tactile_rs::synth::VisuotactileConfig;
    use tactile_rs::synth::visuotactile::sample;
    [0usize, 12]
        .iter()
        .map(|&f| {
            let (_, fr) = sample(&VisuotactileConfig::default(), 31, 2, f);
            let img = tactile_rs::core::image_io::rgb_image(fr.width, fr.height, fr.rgb).unwrap();
            tactile_rs::preprocess::visuo::resize_rgb(&img, w, h).unwrap()
        })
        .collect()
}

#[test]
fn shipped_detector_and_segmenter_match_onnxruntime() {
    use tactile_rs::detect::DetectorArtifact;
    use tactile_rs::onnx::{export_detector, export_segmenter};
    use tactile_rs::segment::SegmenterArtifact;
    let models = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    // Real inputs: virtual frames normalised with each model's statistics.
    let det = models.join("detector");
    let (art, m) = DetectorArtifact::load(&det, &Device::flex()).unwrap();
    let [w, h] = art.detector.input_size;
    let bytes = export_detector(&m, [w, h]).unwrap();
    let shape = [2usize, 3, h, w];
    let data: Vec<f32> = palpation_frames(w, h)
        .iter()
        .flat_map(|f| art.stats.to_chw(f).unwrap())
        .collect();
    check("shipped-detector", &bytes, &shape, &data, |d| {
        let (_, m) = DetectorArtifact::load(&det, d).unwrap();
        burn_out(
            |x| m.forward(x).into_data().try_to_vec::<f32>().unwrap(),
            &shape,
            &data,
            d,
        )
    });
    let seg = models.join("segmenter");
    let (art, m) = SegmenterArtifact::load(&seg, &Device::flex()).unwrap();
    let s = art.unet.side;
    let bytes = export_segmenter(&m, s).unwrap();
    let shape = [2usize, 3, s, s];
    let win = art.window();
    let (sw, sh) = win.scaled_size(640, 360);
    let data: Vec<f32> = palpation_frames(sw, sh)
        .iter()
        .flat_map(|f| art.stats.to_chw(&win.cut(f, 0.0)).unwrap())
        .collect();
    check("shipped-segmenter", &bytes, &shape, &data, |d| {
        let (_, m) = SegmenterArtifact::load(&seg, d).unwrap();
        burn_out(
            |x| m.forward(x).into_data().try_to_vec::<f32>().unwrap(),
            &shape,
            &data,
            d,
        )
    });
}

#[test]
fn densenet121_depth_network_matches_onnxruntime() {
    use tactile_rs::depth::{DenseNetConfig, DepthNetConfig, HeadKind};
    use tactile_rs::onnx::export_depth;
    // The real DenseNet-121 encoder (random weights) with the custom head
    // and the mask channel, at a small input to keep the test quick.
    let cfg = DepthNetConfig::new(DenseNetConfig::preset("densenet121").unwrap(), [64, 64])
        .with_in_channels(4)
        .with_head(HeadKind::Custom)
        .with_decoder_width(32);
    let make = frozen_any("densenet121", |d| cfg.init(d).unwrap());
    let bytes = export_depth(&make(&Device::flex()), 4, [64, 64]).unwrap();
    let shape = [1usize, 4, 64, 64];
    let data = frames(shape.iter().product(), 21);
    check("depth-densenet121", &bytes, &shape, &data, |d| {
        let m = make(d);
        burn_out(
            |x| m.forward(x).into_data().try_to_vec::<f32>().unwrap(),
            &shape,
            &data,
            d,
        )
    });
}

#[test]
fn shipped_depth_model_matches_onnxruntime() {
    use tactile_rs::depth::DepthArtifact;
    use tactile_rs::onnx::export_depth;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/depth");
    let (art, m) = DepthArtifact::load(&dir, &Device::flex()).unwrap();
    let [w, h] = art.net.input_size;
    let c = art.net.in_channels;
    let bytes = export_depth(&m, c, [w, h]).unwrap();
    let shape = [2usize, c, h, w];
    let data: Vec<f32> = palpation_frames(w, h)
        .iter()
        .flat_map(|f| {
            let mut x = art.stats.to_chw(f).unwrap();
            x.resize(c * w * h, 0.0);
            x
        })
        .collect();
    // Within 1e-4 mm: stricter than the 1e-4 of the 6 mm depth range.
    check("shipped-depth", &bytes, &shape, &data, |d| {
        let (_, m) = DepthArtifact::load(&dir, d).unwrap();
        burn_out(
            |x| m.forward(x).into_data().try_to_vec::<f32>().unwrap(),
            &shape,
            &data,
            d,
        )
    });
}
