#![allow(clippy::unwrap_used)]
//! One autoencoder on two datasets through the library path: each dataset
//! read with its own preprocessing, its own head and shift, the encoder
//! noting both; a further dataset of the wrong side refused up front.
//! (Its own test binary: the device's seed is shared by a process's tests,
//! and the resume test next door compares two runs exactly.)

use serde_json::json;
use tactile_burn::options::Options;
use tactile_burn::{Artifact, Runtime};
use tactile_cae::{CaeOptions, TactipEncoder};
use tactile_core::dataset::Dataset;

#[test]
fn one_autoencoder_trains_on_two_datasets_each_with_its_own_head() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    let cfg = datasets_synth::TactipConfig::default();
    datasets_synth::write_tactip(&cfg, 6, 3, &a, Default::default()).unwrap();
    datasets_synth::write_tactip(&cfg, 4, 4, &b, Default::default()).unwrap();
    let tasks = tmp.path().join("tasks.json");
    let write_tasks = |preprocess: &str| {
        let spec = json!([{
            "data": b, "preprocess": preprocess,
            "joint_targets": ["depth_mm", "theta_deg:360"], "shift": 0.05,
        }]);
        std::fs::write(&tasks, spec.to_string()).unwrap();
    };
    let options = |joint: &[&str]| {
        let kw = json!({
            "max_epochs": 2, "patience": 100, "val_fraction": 0.5,
            "joint_targets": joint, "joint_loss": "l1", "also_tasks": tasks,
        });
        CaeOptions::with_overrides(kw.as_object().unwrap()).unwrap()
    };
    let ds = Dataset::open(&a).unwrap();

    write_tasks("binary");
    let out = tmp.path().join("both");
    let s = options(&["x_mm"]).train(&ds, &out).unwrap();
    assert_eq!(s.epochs_run, 2);
    assert!(s.best_val_metric.is_some_and(f64::is_finite));
    // 6 + 4 frames, half of each held out.
    assert_eq!((s.train_items, s.val_items), (5, 5));
    let art = tactile_cae::CaeArtifact::read(&out).unwrap();
    let also = art.notes["also_trained_on"].as_array().unwrap();
    assert_eq!(also.len(), 1);
    assert!(also[0].as_str().unwrap().ends_with('b'), "{also:?}");
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("training.json")).unwrap()).unwrap();
    assert_eq!(record["config"]["also"][0]["shift"], json!(0.05));
    // The one encoder reads the second dataset's frames too.
    let mut enc = TactipEncoder::load(&out, Runtime::BurnFlex, 0).unwrap();
    let (_, f) = enc.encode_dataset(&Dataset::open(&b).unwrap()).unwrap();
    assert_eq!(f.len(), 4);

    // A further dataset whose pin images are not the encoder's side is
    // refused before anything is trained, naming the task file.
    let wide = tmp.path().join("wide.json");
    let mut pre: serde_json::Value =
        serde_json::to_value(tactile_preprocess::PreprocessConfig::binary_frames()).unwrap();
    pre["output_px"] = json!(56);
    std::fs::write(&wide, pre.to_string()).unwrap();
    write_tasks(wide.to_str().unwrap());
    let err = match options(&[]).config() {
        Ok(_) => panic!("a 56 px further dataset was accepted for a 28 px encoder"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("tasks.json") && err.contains("56 px"), "{err}");
}

#[test]
fn a_dataset_read_in_chunks_gives_every_row_in_order() {
    use tactile_cae::data::PinSet;
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("d");
    let cfg = datasets_synth::TactipConfig::default();
    datasets_synth::write_tactip(&cfg, 7, 5, &d, Default::default()).unwrap();
    let ds = Dataset::open(&d).unwrap();
    let pre = tactile_preprocess::PreprocessConfig::paper();
    let whole = PinSet::from_dataset(&ds, &pre).unwrap();
    let mut chunks = Vec::new();
    PinSet::for_each_chunk(&ds, std::slice::from_ref(&pre), 3, |mut sets| {
        chunks.push(sets.swap_remove(0));
        Ok::<_, tactile_cae::Error>(())
    })
    .unwrap();
    assert_eq!(
        chunks.iter().map(|c| c.files.len()).collect::<Vec<_>>(),
        [3, 3, 1]
    );
    let files: Vec<String> = chunks.iter().flat_map(|c| c.files.clone()).collect();
    assert_eq!(files, whole.files);
    let pixels = |s: &PinSet| {
        s.images
            .iter()
            .map(|p| p.pixels.clone())
            .collect::<Vec<_>>()
    };
    let chunked: Vec<Vec<f32>> = chunks.iter().flat_map(pixels).collect();
    assert_eq!(chunked, pixels(&whole));
}
