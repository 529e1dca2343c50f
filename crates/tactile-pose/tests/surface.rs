#![allow(clippy::unwrap_used)]
//! The surface pose-and-shear path on a few real 331-pin TacTip frames
//! (`../shared/real/tactip331-surface`, copied to a temporary folder):
//! the authors' `val` split is the held-out one, a network with
//! uncertainty gives a calibrated standard deviation per target, and the
//! final model trained on every split borrows its validated run's
//! calibration.

use std::path::{Path, PathBuf};

use serde_json::json;
use tactile_burn::options::Options;
use tactile_burn::{Artifact, Runtime};
use tactile_core::dataset::Dataset;
use tactile_pose::{PoseArtifact, PoseEnsemble, PoseEstimator, PoseOptions};

const TARGETS: [&str; 6] = [
    "depth_mm",
    "roll_deg",
    "pitch_deg",
    "shear_x_mm",
    "shear_y_mm",
    "shear_theta_deg",
];

fn surface_frames() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/real/tactip331-surface");
    assert!(root.is_dir(), "{} missing", root.display());
    root
}

/// A dataset of the first `train` training and `val` validation frames.
/// The files of `from` (not its sub-folders) copied into a new `to`.
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        if p.is_file() {
            std::fs::copy(&p, to.join(p.file_name().unwrap())).unwrap();
        }
    }
}

fn subset(dir: &Path, train: usize, val: usize) {
    let real = surface_frames();
    std::fs::create_dir_all(dir.join("frames")).unwrap();
    let text = std::fs::read_to_string(real.join("labels.csv")).unwrap();
    let mut lines = text.lines();
    let mut labels = format!("{}\n", lines.next().unwrap());
    let (mut nt, mut nv) = (0, 0);
    for l in lines {
        let keep = if l.ends_with(",train") && nt < train {
            nt += 1;
            true
        } else if l.ends_with(",val") && nv < val {
            nv += 1;
            true
        } else {
            false
        };
        if keep {
            let file = l.split(',').next().unwrap();
            std::fs::copy(real.join(file), dir.join(file)).unwrap();
            labels.push_str(l);
            labels.push('\n');
        }
    }
    assert_eq!((nt, nv), (train, val));
    std::fs::write(dir.join("labels.csv"), labels).unwrap();
    let manifest = std::fs::read_to_string(real.join("manifest.json")).unwrap();
    let mut m: serde_json::Value = serde_json::from_str(&manifest).unwrap();
    m["count"] = json!(train + val);
    std::fs::write(dir.join("manifest.json"), m.to_string()).unwrap();
}

fn options(extra: serde_json::Value) -> PoseOptions {
    let mut kw = json!({
        "targets": TARGETS, "input_px": 32, "crop_px": 440, "mask_radius_px": 215.0,
        "widths": [4, 8], "hidden": 16, "max_epochs": 2, "uncertainty": true, "loss": "l1",
    });
    kw.as_object_mut()
        .unwrap()
        .extend(extra.as_object().unwrap().clone());
    PoseOptions::with_overrides(kw.as_object().unwrap()).unwrap()
}

#[test]
fn surface_pose_with_calibrated_uncertainty_on_the_authors_split() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("surface");
    subset(&data, 30, 10);
    let ds = Dataset::open(&data).unwrap();
    // The authors' val rows are the held-out ones: no test rows to find.
    assert_eq!(ds.evaluation_split().unwrap(), (30..40).collect::<Vec<_>>());
    let split = ds.three_way_split(0.2, 0.2, 7).unwrap();
    assert_eq!(split.test.len(), 10);
    assert_eq!(split.train.len() + split.val.len(), 30);

    let validated = tmp.path().join("validated");
    options(json!({})).train(&ds, &validated).unwrap();
    let art = PoseArtifact::read(&validated).unwrap();
    let scale = art.std_scale.clone().unwrap();
    assert_eq!(scale.len(), 6);
    assert!(scale.iter().all(|s| s.is_finite() && *s > 0.0), "{scale:?}");
    assert_eq!(art.notes["every_split"], json!(false));

    let mut est = PoseEstimator::load(&validated, Runtime::BurnFlex, 0).unwrap();
    let p = est.predict_dataset(&ds).unwrap();
    assert_eq!(p.names, TARGETS);
    let std = p.std.clone().unwrap();
    assert_eq!(std.len(), ds.len());
    assert!(
        std.iter()
            .all(|r| r.len() == 6 && r.iter().all(|s| s.is_finite() && *s > 0.0))
    );
    // onnxruntime gives the same values and deviations (the exported graph
    // carries the log scales beside the columns).
    let mut ort = PoseEstimator::load(&validated, Runtime::Onnx, 1).unwrap();
    let q = ort.predict_dataset(&ds).unwrap();
    let close = |a: &[Vec<f64>], b: &[Vec<f64>]| {
        a.iter()
            .flatten()
            .zip(b.iter().flatten())
            .all(|(x, y)| (x - y).abs() <= 1e-4 * x.abs().max(1.0))
    };
    assert!(
        close(&p.values, &q.values),
        "{:?} vs {:?}",
        p.values[0],
        q.values[0]
    );
    assert!(close(&std, &q.std.unwrap()));

    // An ensemble of two copies, the second calibrated twice as wide: each
    // member's deviations keep their own calibration (equal estimates, so
    // no spread: the ensemble's deviation is the root mean square).
    let twin = tmp.path().join("twin");
    copy_dir(&validated, &twin);
    let mut wide = PoseArtifact::read(&twin).unwrap();
    wide.std_scale = Some(scale.iter().map(|s| 2.0 * s).collect());
    std::fs::write(
        twin.join(PoseArtifact::CONFIG_FILE),
        serde_json::to_string(&wide).unwrap(),
    )
    .unwrap();
    let both = tmp.path().join("both");
    PoseEnsemble::assemble(&[validated.clone(), twin], &both).unwrap();
    let e = PoseEstimator::load(&both, Runtime::BurnFlex, 0)
        .unwrap()
        .predict_dataset(&ds)
        .unwrap();
    assert!(close(&e.values, &p.values));
    let rms = 2.5f64.sqrt();
    for (got, one) in e.std.unwrap().iter().flatten().zip(std.iter().flatten()) {
        assert!(
            (got - rms * one).abs() <= 1e-4 * one,
            "{got} vs {}",
            rms * one
        );
    }

    // The final model: every split, every row, the validated calibration.
    let last = tmp.path().join("final");
    let kw = json!({
        "every_split": true, "all_rows": true,
        "calibration_from": validated.display().to_string(),
    });
    let fit = options(kw).train(&ds, &last).unwrap();
    assert_eq!(fit.fit.train_items, 40, "val rows trained on too");
    let art = PoseArtifact::read(&last).unwrap();
    assert_eq!(art.std_scale.unwrap(), scale);
    assert_eq!(art.notes["every_split"], json!(true));

    // Borrowing from a network without uncertainty is refused, by file.
    let plain = tmp.path().join("plain");
    options(json!({"uncertainty": false, "max_epochs": 1}))
        .train(&ds, &plain)
        .unwrap();
    let kw = json!({"all_rows": true, "calibration_from": plain.display().to_string()});
    let e = options(kw)
        .train(&ds, &tmp.path().join("bad"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("pose.json") && e.contains("calibration_from"),
        "{e}"
    );
    // An angle target cannot carry a deviation.
    let kw = json!({"targets": ["depth_mm", "roll_deg:360"]});
    let e = options(kw).config().unwrap_err().to_string();
    assert!(e.contains("linear targets only"), "{e}");

    // Calibrated again on frames it did not fit (`tactile train calibrate`):
    // too few rows of a split are refused, naming the split; on every row
    // the deviations are rescaled so ±1 holds 68.3 % of the errors, the
    // estimates unchanged, and the final model takes those factors.
    use tactile_pose::calibrate::{calibrate_on, calibration_from};
    let recal = tmp.path().join("recal");
    copy_dir(&validated, &recal);
    let e = calibrate_on(&recal, &ds, Some("val"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("labels.csv") && e.contains("'val'") && e.contains("20"),
        "{e}"
    );
    let fit = calibrate_on(&recal, &ds, None).unwrap();
    assert_eq!(
        (fit.frames, fit.std_scale_before.clone()),
        (40, scale.clone())
    );
    // Its 10 `val` frames it never fitted: no warning.
    assert_eq!(fit.fitted_frames, None);
    // Calibrated on frames it trained on (its `train` rows; every frame of
    // the final model): calibrated, with a warning in its line and notes,
    // since the factors fit training errors.
    let on_train = tmp.path().join("on-train");
    copy_dir(&validated, &on_train);
    let warned = calibrate_on(&on_train, &ds, Some("train")).unwrap();
    let why = warned.fitted_frames.clone().unwrap_or_default();
    assert!(
        why.contains("these 30 frames are frames it trained on") && !why.contains("every split"),
        "{why}"
    );
    let every = tmp.path().join("every");
    copy_dir(&last, &every);
    let why = calibrate_on(&every, &ds, None)
        .unwrap()
        .fitted_frames
        .unwrap_or_default();
    assert!(
        why.contains("these 40 frames") && why.contains("every split"),
        "{why}"
    );
    let notes = PoseArtifact::read(&every).unwrap().notes;
    assert_eq!(
        notes["uncertainty_calibration"]["fitted_frames"].as_str(),
        Some(why.as_str())
    );
    let r = PoseEstimator::load(&recal, Runtime::BurnFlex, 0)
        .unwrap()
        .predict_dataset(&ds)
        .unwrap();
    assert!(close(&r.values, &p.values));
    let truth: Vec<Vec<f64>> = (0..ds.len())
        .map(|i| TARGETS.iter().map(|t| ds.number(i, t).unwrap()).collect())
        .collect();
    let rstd = r.std.unwrap();
    for j in 0..6 {
        let inside = (0..ds.len())
            .filter(|&i| (r.values[i][j] - truth[i][j]).abs() <= rstd[i][j] * (1.0 + 1e-9))
            .count();
        assert_eq!(inside, 28, "target {j}: ceil(0.683 * 40) frames inside ±1");
    }
    calibration_from(&last, &recal).unwrap();
    let taken = PoseArtifact::read(&last).unwrap().std_scale.unwrap();
    assert!(
        taken
            .iter()
            .zip(&fit.std_scale)
            .all(|(a, b)| (a - b).abs() < 1e-12 * b)
    );
    let e = calibrate_on(&plain, &ds, None).unwrap_err().to_string();
    assert!(e.contains("--uncertainty"), "{e}");

    // A multi-scale ensemble: a 32 px and a 16 px network, each reading
    // the frame through its own preprocessing; the estimates are the
    // members' mean whichever way the frames come in.
    let small = tmp.path().join("small");
    options(json!({"input_px": 16, "widths": [4], "max_epochs": 1}))
        .train(&ds, &small)
        .unwrap();
    let scales = tmp.path().join("scales");
    PoseEnsemble::assemble(&[recal.clone(), small.clone()], &scales).unwrap();
    let mut ms = PoseEstimator::load(&scales, Runtime::BurnFlex, 0).unwrap();
    assert_eq!(
        ms.scales().iter().map(|s| s.output_px).collect::<Vec<_>>(),
        [32, 16]
    );
    let m = ms.predict_dataset(&ds).unwrap();
    let s16 = PoseEstimator::load(&small, Runtime::BurnFlex, 0)
        .unwrap()
        .predict_dataset(&ds)
        .unwrap();
    for i in 0..ds.len() {
        for j in 0..6 {
            let mean = (r.values[i][j] + s16.values[i][j]) / 2.0;
            assert!((m.values[i][j] - mean).abs() <= 1e-6 * mean.abs().max(1.0));
        }
    }
    let frames: Vec<_> = (0..ds.len())
        .map(|i| ds.load_grey(i, "file").unwrap())
        .collect();
    let (from_frames, _) = ms.predict_frames_with_std(&frames).unwrap();
    assert!(close(&from_frames, &m.values));
    // One set of pin images is not enough: the error says what it needs.
    let pins = ms.preprocess(&frames).unwrap();
    let e = ms.predict_with_std(&pins[0]).unwrap_err().to_string();
    assert!(
        e.contains("2 pin image(s)") && e.contains("32x32, 16x16"),
        "{e}"
    );
    // Swapped scales are refused by size, not run.
    let e = ms
        .predict_scales_with_std(&[&pins[1], &pins[0]])
        .unwrap_err()
        .to_string();
    assert!(e.contains("32") && e.contains("16"), "{e}");

    // Calibrated as a whole: the factors go into ensemble.json and apply
    // to the members' combined deviation; no member's file changes.
    let member_json =
        std::fs::read(scales.join("member-0").join(PoseArtifact::CONFIG_FILE)).unwrap();
    let fit = calibrate_on(&scales, &ds, None).unwrap();
    assert_eq!(
        (fit.frames, fit.std_scale_before.clone()),
        (40, vec![1.0; 6])
    );
    assert_eq!(
        std::fs::read(scales.join("member-0").join(PoseArtifact::CONFIG_FILE)).unwrap(),
        member_json
    );
    let c = PoseEstimator::load(&scales, Runtime::BurnFlex, 0)
        .unwrap()
        .predict_dataset(&ds)
        .unwrap();
    assert!(close(&c.values, &m.values));
    let cstd = c.std.unwrap();
    for j in 0..6 {
        let inside = (0..ds.len())
            .filter(|&i| (c.values[i][j] - truth[i][j]).abs() <= cstd[i][j] * (1.0 + 1e-9))
            .count();
        assert_eq!(inside, 28, "target {j}");
    }
    // An ensemble's factors are not a network's, and broken ones are named.
    let e = calibration_from(&last, &scales).unwrap_err().to_string();
    assert!(e.contains("ensemble"), "{e}");
    let text = std::fs::read_to_string(scales.join("ensemble.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["notes"]["std_scale"] = json!([1.0, -2.0]);
    std::fs::write(scales.join("ensemble.json"), v.to_string()).unwrap();
    let e = PoseEstimator::load(&scales, Runtime::BurnFlex, 0)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("ensemble.json") && e.contains("std_scale"),
        "{e}"
    );
}
