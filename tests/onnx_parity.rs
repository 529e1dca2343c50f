#![allow(clippy::unwrap_used)]
//! Every model's exported ONNX passes `onnx.checker` (full check), and
//! onnxruntime agrees with burn on ndarray and on flex within 1e-4 (max
//! abs) through the one inference path every front end uses
//! (`tactile_onnx::load_network`): the CAE (the authors' weights and fresh
//! paper-width ones, encoder and whole autoencoder), both detector
//! architectures, the U-Net, a DenseNet-121 depth network, and the shipped
//! detector, segmenter and depth model on real inputs.

mod common;

use std::path::{Path, PathBuf};

use burn::tensor::{Device, Tensor, TensorData};
use tactile_rs::cae::authors::load_authors_encoder;
use tactile_rs::cae::data::PinSet;
use tactile_rs::cae::{Cae, CaeArtifact, CaeConfig};
use tactile_rs::core::dataset::Dataset;
use tactile_rs::core::metrics::max_abs_diff;
use tactile_rs::nn::runtime::Forward;
use tactile_rs::nn::{Artifact, DeviceKind, Runtime};
use tactile_rs::onnx::{Exportable, OrtModel, load_network, onnx_full_check};
use tactile_rs::preprocess::PreprocessConfig;
use tactile_rs::preprocess::visuo::ChannelStats;

const TOL: f32 = 1e-4;

/// The network in `dir` on every runtime on the same input; onnxruntime's
/// output against each burn device's, and the export's full check.
fn check<A>(name: &str, dir: &Path, shape: [usize; 4], data: &[f32])
where
    A: Exportable,
    A::Model: Forward + Send + 'static,
{
    let l = A::load(dir, &Device::flex()).unwrap();
    let bytes = l.artifact.onnx(&l.model).unwrap();
    let file = tempfile::tempdir().unwrap();
    let path = file.path().join(format!("{name}.onnx"));
    std::fs::write(&path, &bytes).unwrap();
    onnx_full_check(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    let run = |rt: Runtime| {
        let (_, mut net) = load_network::<A>(dir, rt, 1).unwrap();
        net.run(shape, data.to_vec()).unwrap()
    };
    let ort = run(Runtime::Onnx);
    for rt in [Runtime::BurnNdarray, Runtime::BurnFlex] {
        let b = run(rt);
        assert_eq!(b.len(), ort.len(), "{name}: output sizes differ");
        let d = max_abs_diff(&b, &ort);
        println!("{name} {rt} vs onnxruntime: max abs diff {d:.2e}");
        assert!(d <= TOL, "{name} on {rt}: max abs diff {d} > {TOL}");
    }
}

/// A model folder holding `artifact` and `model`'s weights.
fn folder<A: Artifact>(tmp: &Path, name: &str, artifact: &A, model: &A::Model) -> PathBuf {
    let dir = tmp.join(name);
    artifact.save(model, &dir).unwrap();
    dir
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

/// Neutral channel statistics (inputs here are already normalised).
fn unit_stats(c: usize) -> ChannelStats {
    ChannelStats {
        mean: vec![0.0; c],
        std: vec![1.0; c],
    }
}

/// 8 real pin images plus 4 seeded random binary ones.
fn pin_inputs() -> Vec<f32> {
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
    data
}

/// `data` (`[N, 1, 28, 28]` images) nearest-upsampled to `[N, 1, 56, 56]`.
fn upsampled_twice(data: &[f32]) -> Vec<f32> {
    data.chunks(784)
        .flat_map(|img| (0..56 * 56).map(move |k| img[(k / 56 / 2) * 28 + (k % 56) / 2]))
        .collect()
}

#[test]
fn cae_encoder_and_autoencoder_match_onnxruntime() {
    let tmp = tempfile::tempdir().unwrap();
    let data28 = pin_inputs();
    let authors = common::shared_real().join("polic-shapes/authors-encoder.safetensors");
    let stem = CaeConfig::new()
        .with_input_px(56)
        .with_feature_count(32)
        .unwrap();
    let models: Vec<(&str, CaeConfig, Cae)> = vec![
        // The released encoder with a fresh decoder.
        (
            "authors",
            CaeConfig::new().with_widths([16, 16, 8, 4]),
            load_authors_encoder(&authors, &Device::flex()).unwrap(),
        ),
        // Paper widths, fresh weights.
        (
            "paper-widths",
            CaeConfig::new(),
            CaeConfig::new().init(&Device::flex()),
        ),
        // 56 px pin images through a stem block, fresh weights.
        ("stem-56", stem.clone(), stem.init(&Device::flex())),
    ];
    for (name, cfg, cae) in models {
        let px = cfg.input_px;
        let shape = [12, 1, px, px];
        let data = match px {
            28 => data28.clone(),
            _ => upsampled_twice(&data28),
        };
        let art = CaeArtifact {
            model: cfg,
            preprocess: PreprocessConfig {
                output_px: px,
                ..PreprocessConfig::binary_frames()
            },
            input_profile: None,
            notes: Default::default(),
        };
        let dir = folder(tmp.path(), name, &art, &cae);
        // The encoder, through the inference path.
        check::<CaeArtifact>(&format!("{name}-encoder"), &dir, shape, &data);
        // The whole autoencoder's export against burn's reconstruction.
        let bytes = tactile_rs::cae::export::autoencoder_onnx(&cae, px).unwrap();
        let (_, ort) = OrtModel::from_bytes(&bytes, 1)
            .unwrap()
            .run_f32(&shape, data.clone())
            .unwrap();
        for kind in DeviceKind::ALL {
            let m = CaeArtifact::load(&dir, &kind.device()).unwrap().model;
            let x = Tensor::<4>::from_data(TensorData::new(data.clone(), shape), &kind.device());
            let b: Vec<f32> = m.forward(x).into_data().try_to_vec().unwrap();
            let d = max_abs_diff(&b, &ort);
            assert!(d <= TOL, "{name} autoencoder on {kind}: {d}");
        }
    }
}

#[test]
fn detectors_match_onnxruntime() {
    use tactile_rs::detect::{Architecture, DetectorArtifact, DetectorConfig};
    // Hard-swish and hard-sigmoid are exported as Relu/Add/Sub/Mul/Div:
    // parity here is what proves that form exact.
    let tmp = tempfile::tempdir().unwrap();
    for (name, arch) in [
        ("mobilenet", Architecture::MobilenetV3Small),
        ("resnet18", Architecture::Resnet18),
    ] {
        let art = DetectorArtifact {
            model: DetectorConfig::new()
                .with_architecture(arch)
                .with_width(0.25)
                .with_input_size([64, 48]),
            stats: unit_stats(3),
            threshold: 0.5,
            input_profile: None,
            notes: Default::default(),
        };
        let dir = folder(tmp.path(), name, &art, &art.init(&Device::flex()).unwrap());
        let shape = [3, 3, 48, 64];
        check::<DetectorArtifact>(name, &dir, shape, &frames(shape.iter().product(), 99));
    }
}

#[test]
fn segmenter_matches_onnxruntime() {
    use tactile_rs::segment::{PostprocessConfig, SegmenterArtifact, UNetConfig};
    let tmp = tempfile::tempdir().unwrap();
    let art = SegmenterArtifact {
        model: UNetConfig::new().with_base(4).with_side(48),
        stats: unit_stats(3),
        threshold: 0.5,
        postprocess: PostprocessConfig::default(),
        notes: Default::default(),
    };
    let dir = folder(
        tmp.path(),
        "unet",
        &art,
        &art.init(&Device::flex()).unwrap(),
    );
    let shape = [2, 3, 48, 48];
    check::<SegmenterArtifact>("segmenter", &dir, shape, &frames(shape.iter().product(), 7));
}

#[test]
fn densenet121_depth_network_matches_onnxruntime() {
    use tactile_rs::depth::{DenseNetConfig, DepthArtifact, DepthNetConfig, DepthScale, HeadKind};
    // The real DenseNet-121 encoder (random weights) with the custom head
    // and the mask channel, at a small input to keep the test quick.
    let tmp = tempfile::tempdir().unwrap();
    let art = DepthArtifact {
        model: DepthNetConfig::new(DenseNetConfig::densenet121(), [64, 64])
            .with_in_channels(4)
            .with_head(HeadKind::Custom)
            .with_decoder_width(32),
        stats: unit_stats(3),
        scale: DepthScale {
            offset_mm: 15.0,
            unit_mm: 1.0,
        },
        with_mask: true,
        prior: None,
        depth_maps: Default::default(),
        notes: Default::default(),
    };
    let dir = folder(
        tmp.path(),
        "densenet121",
        &art,
        &art.init(&Device::flex()).unwrap(),
    );
    let shape = [1, 4, 64, 64];
    check::<DepthArtifact>(
        "depth-densenet121",
        &dir,
        shape,
        &frames(shape.iter().product(), 21),
    );
}

#[test]
fn a_depth_network_correcting_its_calibration_matches_onnxruntime_at_any_batch() {
    use tactile_rs::depth::prior::CalibrationPrior;
    use tactile_rs::depth::{DenseNetConfig, DepthArtifact, DepthNetConfig, DepthScale};
    // The prior (fourth channel) is added to the output: the export keeps
    // that addition and the batch axis free.
    let tmp = tempfile::tempdir().unwrap();
    let art = DepthArtifact {
        model: DepthNetConfig::new(DenseNetConfig::tiny(), [64, 32])
            .with_in_channels(4)
            .with_residual_channel(Some(3))
            .with_decoder_width(16),
        stats: unit_stats(3),
        scale: DepthScale {
            offset_mm: 0.1,
            unit_mm: 1.0,
        },
        with_mask: false,
        prior: Some(CalibrationPrior {
            calibration: "..".into(),
        }),
        depth_maps: Default::default(),
        notes: Default::default(),
    };
    let dir = folder(
        tmp.path(),
        "prior",
        &art,
        &art.init(&Device::flex()).unwrap(),
    );
    let shape = [3, 4, 32, 64];
    check::<DepthArtifact>(
        "depth-prior",
        &dir,
        shape,
        &frames(shape.iter().product(), 23),
    );
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
fn shipped_models_match_onnxruntime_on_real_inputs() {
    use tactile_rs::depth::DepthArtifact;
    use tactile_rs::detect::DetectorArtifact;
    use tactile_rs::segment::SegmenterArtifact;
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    // Real inputs: virtual frames normalised with each model's statistics.
    let det = models.join("detector");
    let art = tactile_rs::detect::ensemble::read_config(&det).unwrap();
    let [w, h] = art.model.input_size;
    let data: Vec<f32> = palpation_frames(w, h)
        .iter()
        .flat_map(|f| art.stats.to_chw(f).unwrap())
        .collect();
    // One network or an ensemble (the shipped one), as the folder holds.
    if tactile_rs::detect::DetectorEnsembleArtifact::is_in(&det) {
        check::<tactile_rs::detect::DetectorEnsembleArtifact>(
            "shipped-detector",
            &det,
            [2, 3, h, w],
            &data,
        );
    } else {
        check::<DetectorArtifact>("shipped-detector", &det, [2, 3, h, w], &data);
    }
    let seg = models.join("segmenter");
    let art = SegmenterArtifact::read(&seg).unwrap();
    let s = art.model.side;
    let win = art.model.window();
    let (sw, sh) = win.scaled_size(640, 360);
    let data: Vec<f32> = palpation_frames(sw, sh)
        .iter()
        .flat_map(|f| art.stats.to_chw(&win.cut(f, 0.0)).unwrap())
        .collect();
    check::<SegmenterArtifact>("shipped-segmenter", &seg, [2, 3, s, s], &data);
    // Within 1e-4 mm: stricter than the 1e-4 of the 6 mm depth range.
    let dir = models.join("depth");
    let art = DepthArtifact::read(&dir).unwrap();
    let [w, h] = art.model.input_size;
    let c = art.model.in_channels;
    let data: Vec<f32> = palpation_frames(w, h)
        .iter()
        .flat_map(|f| {
            let mut x = art.stats.to_chw(f).unwrap();
            x.resize(c * w * h, 0.0);
            x
        })
        .collect();
    check::<DepthArtifact>("shipped-depth", &dir, [2, c, h, w], &data);
}
