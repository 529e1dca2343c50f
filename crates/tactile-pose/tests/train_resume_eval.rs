#![allow(clippy::unwrap_used)]
//! The pose network's library path on a few real TacTip edge frames
//! (`../shared/real/tactip127-edge`, read in place), without the command
//! line: options -> training with held-out test frames -> resume ->
//! prediction in the labels' units.

use std::path::{Path, PathBuf};

use serde_json::json;
use tactile_burn::Runtime;
use tactile_burn::options::Options;
use tactile_core::dataset::Dataset;
use tactile_pose::{PoseEstimator, PoseOptions};

fn edge_frames() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/real/tactip127-edge");
    assert!(root.is_dir(), "{} missing", root.display());
    root
}

/// A dataset folder of the first `n` edge frames, their labels and a
/// manifest, in a temporary folder.
fn subset(dir: &Path, n: usize) {
    let real = edge_frames();
    std::fs::create_dir_all(dir.join("frames")).unwrap();
    let text = std::fs::read_to_string(real.join("labels.csv")).unwrap();
    let mut lines = text.lines();
    let mut labels = format!("{}\n", lines.next().unwrap());
    for l in lines.take(n) {
        let file = l.split(',').next().unwrap();
        std::fs::copy(real.join(file), dir.join(file)).unwrap();
        labels.push_str(l);
        labels.push('\n');
    }
    std::fs::write(dir.join("labels.csv"), labels).unwrap();
    let manifest = std::fs::read_to_string(real.join("manifest.json")).unwrap();
    let mut m: serde_json::Value = serde_json::from_str(&manifest).unwrap();
    m["count"] = json!(n);
    std::fs::write(dir.join("manifest.json"), m.to_string()).unwrap();
}

fn options(epochs: usize, resume: bool) -> PoseOptions {
    let kw = json!({
        "input_px": 32, "exclude_test": 0.25, "max_epochs": epochs, "resume": resume,
    });
    PoseOptions::with_overrides(kw.as_object().unwrap()).unwrap()
}

#[test]
fn the_pose_network_trains_resumes_and_predicts_in_the_labels_units() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("edge");
    subset(&data, 40);
    let ds = Dataset::open(&data).unwrap();
    let out = tmp.path().join("pose");

    let first = options(1, false).train(&ds, &out).unwrap();
    assert_eq!(first.fit.epochs_run, 1);
    let resumed = options(2, true).train(&ds, &out).unwrap();
    assert_eq!(resumed.fit.epochs_run, 2, "resume continues the run");
    assert!(resumed.test.is_some(), "held-out frames are scored");
    assert!(out.join("pose.json").is_file() && out.join("curves.csv").is_file());

    let mut est = PoseEstimator::load(&out, Runtime::BurnFlex, 0).unwrap();
    let p = est.predict_dataset(&ds).unwrap();
    assert_eq!(p.names, ["x_mm", "theta_deg", "depth_mm"]);
    assert_eq!(p.values.len(), ds.len());
    assert!(
        p.values
            .iter()
            .all(|v| v.len() == 3 && v.iter().all(|x| x.is_finite()))
    );

    // A network that cannot be built is refused before any frame is read.
    let kw = json!({ "input_px": 30 });
    let bad = PoseOptions::with_overrides(kw.as_object().unwrap()).unwrap();
    let e = bad
        .train(&ds, &tmp.path().join("p2"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("input side 30"), "{e}");
    assert!(!tmp.path().join("p2").join("pose.json").exists());
    // Every split fitted and test frames left out contradict: refused, as
    // the CAE refuses it. Before, the network fitted the test frames, then
    // scored them as "held-out test frames (never trained on)".
    let kw = json!({ "input_px": 32, "exclude_test": 0.25, "every_split": true });
    let both = PoseOptions::with_overrides(kw.as_object().unwrap()).unwrap();
    let e = both
        .train(&ds, &tmp.path().join("p3"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("every_split trains on the test frames that exclude_test leaves out"),
        "{e}"
    );
    assert!(!tmp.path().join("p3").exists());
    // Options that would do nothing are refused before any frame is read.
    // Before, a split seed without a test fraction was ignored, and a
    // borrowed calibration for a network without uncertainty was refused
    // only after every frame was preprocessed.
    for (kw, want) in [
        (
            json!({ "split_seed": 3 }),
            "split_seed 3 picks the test frames that exclude_test leaves out, and no exclude_test",
        ),
        (
            json!({ "calibration_from": "elsewhere" }),
            "calibration_from is for a network with uncertainty",
        ),
    ] {
        let o = PoseOptions::with_overrides(kw.as_object().unwrap()).unwrap();
        let e = o.config().unwrap_err().to_string();
        assert!(e.contains(want), "{e}");
    }
}
