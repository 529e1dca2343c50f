#![allow(clippy::unwrap_used)]
//! The segmenter's library path on tiny data, without the command line:
//! options -> training -> resume -> evaluation.

use serde_json::json;
use tactile_burn::Runtime;
use tactile_burn::options::Options;
use tactile_core::dataset::Dataset;
use tactile_segment::eval::evaluate_in_chunks;
use tactile_segment::{SegmenterOptions, TendonSegmenter, evaluate};

fn options(epochs: usize, resume: bool) -> SegmenterOptions {
    let kw = json!({ "side": 32, "max_epochs": epochs, "resume": resume });
    SegmenterOptions::with_overrides(kw.as_object().unwrap()).unwrap()
}

#[test]
fn the_segmenter_trains_resumes_and_evaluates() {
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
    let out = tmp.path().join("seg");

    let first = options(1, false).train(&ds, &out).unwrap();
    assert_eq!(first.epochs_run, 1);
    let resumed = options(2, true).train(&ds, &out).unwrap();
    assert_eq!(resumed.epochs_run, 2);
    for f in [
        "segmenter.json",
        "segmenter.bpk",
        "curves.csv",
        "training.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let mut seg = TendonSegmenter::load(&out, Runtime::BurnFlex, 0).unwrap();
    assert_eq!(seg.artifact.model.side, 32);
    let scores = evaluate(&mut seg, &ds).unwrap();
    // Every tendon frame is scored, under its path.
    let tendon_frames = (0..ds.len())
        .filter(|&i| ds.number(i, "tendon").unwrap() == 1.0)
        .count();
    assert_eq!(scores.path("all").unwrap().frames, tendon_frames);
    assert!(
        scores
            .paths
            .iter()
            .all(|p| (0.0..=1.0).contains(&p.mean_iou))
    );
    // Read 3 tendon rows at a time (as a large dataset is): the same table
    // of every path.
    let chunked = evaluate_in_chunks(&mut seg, &ds, 3).unwrap();
    assert!(tendon_frames > 3);
    assert_eq!(
        serde_json::to_value(&chunked.paths).unwrap(),
        serde_json::to_value(&scores.paths).unwrap()
    );
    assert!(seg.rest().is_none(), "no rest frame was given");

    // The sensor's rest frame: one of another size is refused before
    // training, naming it; one of the frames' size is kept as rest.png and
    // read back with the model.
    let with_rest = |rest: &std::path::Path| {
        let kw = json!({ "side": 32, "max_epochs": 1, "rest": rest });
        SegmenterOptions::with_overrides(kw.as_object().unwrap()).unwrap()
    };
    let small = tmp.path().join("small-rest.png");
    tactile_core::image_io::save_rgb_png(&small, 160, 90, &vec![128; 160 * 90 * 3]).unwrap();
    let rested = tmp.path().join("seg-rest");
    let e = with_rest(&small)
        .train(&ds, &rested)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("small-rest.png") && e.contains("160x90") && e.contains("320x180"),
        "{e}"
    );
    assert!(!rested.exists(), "nothing written for a refused rest frame");
    let rest = ds.path_of(0, "file").unwrap();
    with_rest(&rest).train(&ds, &rested).unwrap();
    let seg = TendonSegmenter::load(&rested, Runtime::BurnFlex, 0).unwrap();
    let kept = seg.rest().unwrap();
    assert_eq!((kept.width, kept.height), (320, 180));
    assert_eq!(
        tactile_core::image_io::load_rgb(rested.join(tactile_segment::REST_FILE))
            .unwrap()
            .as_slice(),
        tactile_core::image_io::load_rgb(&rest).unwrap().as_slice()
    );
    // Trained again into the folder without --rest, the sensor's rest frame
    // stays (the trainer says so).
    options(1, false).train(&ds, &rested).unwrap();
    let seg = TendonSegmenter::load(&rested, Runtime::BurnFlex, 0).unwrap();
    assert!(seg.rest().is_some());
}
