#![allow(clippy::unwrap_used)]
//! A standalone export (`tactile export --standalone`) gives in
//! onnxruntime, from the frame's bytes alone, what the toolkit's own path
//! gives: the detector's probability, the segmenter's mask probabilities
//! and the depth in mm, on the shipped models and sample frames.

use std::path::{Path, PathBuf};

use tactile_burn::Runtime;
use tactile_depth::DepthEstimator;
use tactile_detect::TendonDetector;
use tactile_onnx::runtime::OrtModel;
use tactile_pipeline::export::export_standalone;
use tactile_preprocess::visuo::resize_rgb;
use tactile_segment::TendonSegmenter;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn frames() -> Vec<tactile_core::image_io::RgbImage> {
    (0..12)
        .map(|i| {
            tactile_core::image_io::load_rgb(root().join(format!("samples/palpation/{i:06}.png")))
                .unwrap()
        })
        .collect()
}

/// One network of the shipped detector (its first member when it is an
/// ensemble), for tests that edit a detector's config.
fn shipped_network() -> PathBuf {
    let d = root().join("models/detector");
    match d.join("ensemble.json").is_file() {
        true => d.join("member-0"),
        false => d,
    }
}

fn standalone(model: &str) -> OrtModel {
    let e = export_standalone(&root().join("models").join(model)).unwrap();
    OrtModel::from_bytes(&e.bytes, 1).unwrap()
}

fn max_diff(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

#[test]
fn the_standalone_detector_gives_the_toolkits_probabilities() {
    let mut det = TendonDetector::load(root().join("models/detector"), Runtime::Onnx, 1).unwrap();
    let mut alone = standalone("detector");
    let [w, h] = det.artifact.model.input_size;
    for f in frames() {
        // The frame at the detector's input size, in its bits per channel.
        let img = resize_rgb(&f, w, h).unwrap();
        let (shape, p) = match det.artifact.model.bits() {
            16 => alone.run_u16(&[1, h, w, 3], img.to_levels(16)),
            _ => alone.run_u8(&[1, h, w, 3], img.to_bytes()),
        }
        .unwrap();
        assert_eq!(shape, [1, 1]);
        let q = det.probability(&f).unwrap();
        assert!(
            (p[0] - q).abs() < 1e-5,
            "standalone {} vs toolkit {q}",
            p[0]
        );
        assert_eq!(det.is_tendon(p[0]), det.is_tendon(q));
    }
}

#[test]
fn a_detector_ensemble_runs_on_every_runtime_and_stands_alone_as_one_network() {
    // Two members: the shipped detector and its weights read with other
    // channel statistics (so the graph renormalises for the second).
    let tmp = tempfile::tempdir().unwrap();
    let shipped = shipped_network();
    let other = tmp.path().join("other");
    std::fs::create_dir(&other).unwrap();
    let mut cfg: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(shipped.join("detector.json")).unwrap())
            .unwrap();
    cfg["stats"]["mean"] = serde_json::json!([0.45, 0.5, 0.52]);
    cfg["stats"]["std"] = serde_json::json!([0.2, 0.25, 0.22]);
    std::fs::write(other.join("detector.json"), cfg.to_string()).unwrap();
    std::fs::copy(shipped.join("detector.bpk"), other.join("detector.bpk")).unwrap();
    let ens = tmp.path().join("ensemble");
    let said =
        tactile_pipeline::ensemble::assemble_ensemble(&[shipped.clone(), other.clone()], &ens)
            .unwrap();
    assert!(said.starts_with("2 detectors"), "{said}");
    let mut burn = TendonDetector::load(&ens, Runtime::BurnFlex, 1).unwrap();
    let mut ort = TendonDetector::load(&ens, Runtime::Onnx, 1).unwrap();
    let mut one = TendonDetector::load(&shipped, Runtime::Onnx, 1).unwrap();
    let e = export_standalone(&ens).unwrap();
    let mut alone = OrtModel::from_bytes(&e.bytes, 1).unwrap();
    let [w, h] = ort.artifact.model.input_size;
    let mut differs = false;
    for f in frames() {
        let (p, q) = (ort.probability(&f).unwrap(), burn.probability(&f).unwrap());
        assert!((p - q).abs() < 1e-4, "onnxruntime {p} vs burn {q}");
        differs |= (p - one.probability(&f).unwrap()).abs() > 1e-3;
        let img = resize_rgb(&f, w, h).unwrap();
        let (_, s) = match ort.artifact.model.bits() {
            16 => alone.run_u16(&[1, h, w, 3], img.to_levels(16)),
            _ => alone.run_u8(&[1, h, w, 3], img.to_bytes()),
        }
        .unwrap();
        assert!(
            (s[0] - p).abs() < 1e-5,
            "standalone {} vs toolkit {p}",
            s[0]
        );
    }
    assert!(differs, "the second member changed no probability");
}

#[test]
fn a_sixteen_bit_exposure_normalised_detector_stands_alone_too() {
    // The shipped network read through the other input form: 16-bit
    // levels, each channel divided by its median at the window's centre.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("detector");
    std::fs::create_dir(&dir).unwrap();
    let shipped = shipped_network();
    let mut cfg: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(shipped.join("detector.json")).unwrap())
            .unwrap();
    cfg["model"]["input_bits"] = 16.into();
    cfg["model"]["normalise_exposure"] = true.into();
    std::fs::write(dir.join("detector.json"), cfg.to_string()).unwrap();
    std::fs::copy(shipped.join("detector.bpk"), dir.join("detector.bpk")).unwrap();
    let mut det = TendonDetector::load(&dir, Runtime::Onnx, 1).unwrap();
    let e = export_standalone(&dir).unwrap();
    let mut alone = OrtModel::from_bytes(&e.bytes, 1).unwrap();
    let [w, h] = det.artifact.model.input_size;
    for (i, f) in frames().iter().enumerate() {
        // A darker exposure too: the graph divides it out as the toolkit does.
        let mut img = resize_rgb(f, w, h).unwrap();
        if i % 2 == 1 {
            img.data.iter_mut().for_each(|v| *v *= 0.85);
        }
        let (shape, p) = alone.run_u16(&[1, h, w, 3], img.to_levels(16)).unwrap();
        assert_eq!(shape, [1, 1]);
        let q = det
            .network_probabilities(
                &det.artifact
                    .model
                    .network_input(img.quantised_to(16), &det.artifact.stats)
                    .unwrap(),
                1,
            )
            .unwrap()[0];
        assert!(
            (p[0] - q).abs() < 1e-4,
            "frame {i}: standalone {} vs toolkit {q}",
            p[0]
        );
    }
}

#[test]
fn the_standalone_segmenter_gives_the_toolkits_mask_probabilities() {
    let mut seg = TendonSegmenter::load(root().join("models/segmenter"), Runtime::Onnx, 1).unwrap();
    let mut alone = standalone("segmenter");
    let s = seg.artifact.model.side;
    for f in frames() {
        let window = seg.artifact.model.frame_window(&f).unwrap();
        let (shape, p) = alone.run_u8(&[1, s, s, 3], window.to_bytes()).unwrap();
        assert_eq!(shape, [1, 1, s, s]);
        let input = seg
            .artifact
            .model
            .window_input(&window, &seg.artifact.stats)
            .unwrap();
        let q = seg.probabilities(&input, 1).unwrap().remove(0);
        assert!(
            max_diff(&p, &q) < 1e-5,
            "max difference {}",
            max_diff(&p, &q)
        );
    }
}

#[test]
fn the_standalone_depth_network_gives_the_toolkits_depth_in_mm() {
    let mut depth = DepthEstimator::load(root().join("models/depth"), Runtime::Onnx, 1).unwrap();
    let mut alone = standalone("depth");
    let [w, h] = depth.artifact.model.input_size;
    for f in frames() {
        let bytes = resize_rgb(&f, w, h).unwrap().to_bytes();
        let (shape, mm) = alone.run_u8(&[1, h, w, 3], bytes).unwrap();
        assert_eq!(shape, [1, 1, h, w]);
        let q = depth.depth_mm(&f, None).unwrap();
        assert!(
            max_diff(&mm, &q) < 1e-4,
            "max difference {} mm",
            max_diff(&mm, &q)
        );
    }
}

#[test]
fn the_standalone_model_says_what_it_is_in_its_metadata() {
    let e = export_standalone(&root().join("models/detector")).unwrap();
    let text = String::from_utf8_lossy(&e.bytes);
    for key in [
        "threshold",
        "channel_mean",
        "input_size",
        "tactile.version",
        "tendon_probability",
    ] {
        assert!(text.contains(key), "{key} missing from the model");
    }
    let err = export_standalone(&root().join("models/cae-synth"))
        .err()
        .unwrap();
    assert!(
        err.to_string().contains("detector, segmenter or depth"),
        "{err}"
    );
}
