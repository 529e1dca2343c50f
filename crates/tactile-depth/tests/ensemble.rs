#![allow(clippy::unwrap_used)]
//! Depth networks averaged as one: the shipped own-sensor network (with
//! its calibration prior) and a second of other statistics and depth
//! scale, on a real GelSight press, through burn and onnxruntime; what an
//! ensemble refuses.

use std::path::{Path, PathBuf};

use tactile_burn::{Artifact, Runtime};
use tactile_core::image_io::load_rgb;
use tactile_depth::prior::CalibrationPrior;
use tactile_depth::{DepthArtifact, DepthEnsembleArtifact, DepthEstimator};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A copy of the shipped calibration (what reconstructs a frame) in `dir`.
fn calibration_copy(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    for f in ["gelsight.json", "gelsight.bpk", "background.png"] {
        std::fs::copy(root().join("models/gelsight-r15").join(f), dir.join(f)).unwrap();
    }
}

fn mean_abs(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<f32>() / a.len() as f32
}

#[test]
fn a_depth_ensemble_gives_its_members_mean_map_on_every_runtime_and_refuses_unlike_members() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let device = tactile_burn::DeviceKind::Flex.device();

    // Member a: the shipped network, beside its own copy of the calibration.
    let a_sensor = t.join("a-sensor");
    calibration_copy(&a_sensor);
    // (The shipped depth folder is an ensemble: its first member.)
    let shipped = root().join("models/gelsight-r15/depth");
    let shipped = match DepthEnsembleArtifact::is_in(&shipped) {
        true => shipped.join("member-0"),
        false => shipped,
    };
    let a = a_sensor.join("depth");
    std::fs::create_dir_all(&a).unwrap();
    std::fs::copy(shipped.join("depth.bpk"), a.join("depth.bpk")).unwrap();
    let mut art = DepthArtifact::read(&shipped).unwrap();
    art.prior = Some(CalibrationPrior::of(&a_sensor, &a));
    assert_eq!(art.prior.as_ref().unwrap().calibration, "..");
    tactile_core::io::write_json_atomic(a.join("depth.json"), &art).unwrap();
    // Member b: fresh weights, other channel statistics and another depth
    // scale, its prior an absolute path to another copy of the calibration:
    // the graph converts its input and output to the first member's.
    let b_sensor = t.join("b-sensor");
    calibration_copy(&b_sensor);
    let mut art = DepthArtifact::read(&a).unwrap();
    art.stats.mean = vec![0.45, 0.58, 0.49];
    art.stats.std = vec![0.09, 0.05, 0.11];
    art.scale.offset_mm = 0.31;
    art.scale.unit_mm = 0.5;
    let b = t.join("b");
    art.prior = Some(CalibrationPrior::of(&b_sensor, &b));
    art.save(&art.model.init(&device).unwrap(), &b).unwrap();

    // The ensemble in a third copy of the sensor folder: its members find
    // the calibration as `../..`, so the sensor folder moves whole.
    let sensor = t.join("sensor");
    calibration_copy(&sensor);
    let ens = sensor.join("depth");
    DepthEnsembleArtifact::assemble(&[a.clone(), b.clone()], &ens).unwrap();
    for m in ["member-0", "member-1"] {
        let p = DepthArtifact::read(&ens.join(m)).unwrap().prior.unwrap();
        assert_eq!(p.calibration, "../..", "{m}");
    }
    let moved = t.join("moved");
    std::fs::rename(&sensor, &moved).unwrap();
    let ens = moved.join("depth");

    let frame = load_rgb(root().join("../shared/real/gelsight-ball/frames/press_01.png")).unwrap();
    let map = |dir: &Path, runtime| {
        DepthEstimator::load(dir, runtime, 1)
            .unwrap()
            .depth_mm(&frame, None)
            .unwrap()
    };
    let (za, zb) = (map(&a, Runtime::BurnFlex), map(&b, Runtime::BurnFlex));
    let mean: Vec<f32> = za.iter().zip(&zb).map(|(x, y)| (x + y) / 2.0).collect();
    // The members differ, so the mean is no member's map.
    assert!(mean_abs(&za, &zb) > 0.01, "{}", mean_abs(&za, &zb));
    let est = DepthEstimator::load(&ens, Runtime::BurnFlex, 1).unwrap();
    assert_eq!(
        std::fs::canonicalize(est.prior_folder().unwrap()).unwrap(),
        std::fs::canonicalize(&moved).unwrap()
    );
    assert_eq!(est.artifact.scale, DepthArtifact::read(&a).unwrap().scale);
    for runtime in [Runtime::BurnFlex, Runtime::Onnx] {
        let ze = map(&ens, runtime);
        let worst = ze
            .iter()
            .zip(&mean)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f32, f32::max);
        assert!(
            worst < 2e-3,
            "{runtime:?}: {worst} mm off the members' mean"
        );
    }

    // Refused, naming the member's config, and no folder made: a member
    // correcting another calibration, and one taking the mask instead.
    let other_sensor = t.join("other-sensor");
    calibration_copy(&other_sensor);
    let mut g: serde_json::Value =
        serde_json::from_slice(&std::fs::read(other_sensor.join("gelsight.json")).unwrap())
            .unwrap();
    g["notes"] = serde_json::json!({ "recalibrated": true });
    std::fs::write(other_sensor.join("gelsight.json"), g.to_string()).unwrap();
    let c = t.join("c");
    art.prior = Some(CalibrationPrior::of(&other_sensor, &c));
    art.save(&art.model.init(&device).unwrap(), &c).unwrap();
    let out = t.join("e2");
    let e = DepthEnsembleArtifact::assemble(&[a.clone(), c.clone()], &out)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("c/depth.json") && e.contains("other-sensor") && e.contains("alike"),
        "{e}"
    );
    let mut masked = art.clone();
    masked.prior = None;
    masked.with_mask = true;
    masked.model.residual_channel = None;
    let d = t.join("d");
    masked
        .save(&masked.model.init(&device).unwrap(), &d)
        .unwrap();
    let e = DepthEnsembleArtifact::assemble(&[a.clone(), d], &out)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("d/depth.json") && e.contains("tendon mask"),
        "{e}"
    );
    assert!(!out.exists());
    // A member changed by hand after assembly is refused at load.
    std::fs::copy(c.join("depth.json"), ens.join("member-1/depth.json")).unwrap();
    let e = DepthEstimator::load(&ens, Runtime::BurnFlex, 1)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("member-1/depth.json") && e.contains("alike"),
        "{e}"
    );
}
