#![allow(clippy::unwrap_used)]
//! The detector's library path on tiny data, without the command line:
//! options -> training -> resume -> evaluation, and the evaluation's
//! decisions are the ones `TendonDetector::assess` gives each frame.

use serde_json::json;
use tactile_burn::Runtime;
use tactile_burn::options::Options;
use tactile_core::dataset::Dataset;
use tactile_detect::eval::evaluate_dataset;
use tactile_detect::{DetectionSet, DetectorOptions, TendonDetector, evaluate};

fn options(epochs: usize, resume: bool) -> DetectorOptions {
    let kw = json!({
        "width": 0.25, "input": [64, 48], "max_epochs": epochs,
        "val_fraction": 0.25, "resume": resume,
    });
    DetectorOptions::with_overrides(kw.as_object().unwrap()).unwrap()
}

#[test]
fn the_detector_trains_resumes_and_evaluates_as_it_answers() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("vt");
    let cfg = datasets_synth::VisuotactileConfig {
        width: 320,
        height: 180,
        frames_per_sequence: 8,
        ..Default::default()
    };
    datasets_synth::write_visuotactile(&cfg, 32, 5, &data, Default::default()).unwrap();
    let ds = Dataset::open(&data).unwrap();
    let out = tmp.path().join("det");

    let first = options(1, false)
        .train(std::slice::from_ref(&ds), &out)
        .unwrap();
    assert_eq!(first.summary.epochs_run, 1);
    assert!((0.0..=1.0).contains(&first.threshold));
    // One more epoch from the checkpoint: the run counts both.
    let resumed = options(2, true)
        .train(std::slice::from_ref(&ds), &out)
        .unwrap();
    assert_eq!(resumed.summary.epochs_run, 2);
    for f in [
        "detector.json",
        "detector.bpk",
        "curves.csv",
        "training.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }

    let mut det = TendonDetector::load(&out, Runtime::BurnFlex, 0).unwrap();
    assert_eq!(det.artifact.model.input_size, [64, 48]);
    let set = DetectionSet::from_dataset(&ds, &det.artifact.model).unwrap();
    let scores = evaluate(&mut det, &set).unwrap();
    assert_eq!(scores.all.frames, 32);
    for i in 0..ds.len() {
        let frame = ds.load_rgb(i).unwrap();
        let a = det.assess(&frame).unwrap();
        assert_eq!(a.tendon, scores.decisions[i], "frame {i}");
        assert!((a.probability - scores.probabilities[i]).abs() < 1e-5);
    }
    // Read 5 rows at a time (as a large dataset is): the same answers,
    // scores and labels as the whole set at once, the onset and release
    // frames counted over whole sequences across the chunks.
    let (chunked, labels) = evaluate_dataset(&mut det, &ds, 5).unwrap();
    assert_eq!(chunked.probabilities, scores.probabilities);
    assert_eq!(chunked.decisions, scores.decisions);
    assert_eq!(
        (chunked.all, chunked.ungated, chunked.onset_release),
        (scores.all, scores.ungated, scores.onset_release)
    );
    // (as JSON: an empty bin's mean is NaN, unequal to itself)
    assert_eq!(
        serde_json::to_string(&chunked.calibration).unwrap(),
        serde_json::to_string(&scores.calibration).unwrap()
    );
    assert_eq!(
        (labels.files, labels.tendon, labels.transition),
        (set.files, set.tendon, set.transition)
    );
    assert!(scores.onset_release.frames > 0);
}
