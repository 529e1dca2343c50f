//! The own-sensor page's scoring of a set of renders: the detector's
//! answers by kind of frame add up to its answers on the whole set, and a
//! set whose press is unknown (its press_mm left empty) is of no kind.

use std::path::{Path, PathBuf};

use tactile_bench::own_sensor::{KINDS, PalpationNetworks, frame_kind, score_renders};
use tactile_burn::Runtime;
use tactile_core::dataset::Dataset;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn the_kinds_of_frame_add_up_to_the_whole_set() {
    let model = root().join("models/gelsight-r15");
    let sensor = datasets_synth::CalibratedSensor::load(&model).unwrap();
    let config = datasets_synth::CalibratedConfig {
        frames_per_sequence: 5,
        press_mm: datasets_synth::Range::new(0.05, 0.3),
        object_press_mm: datasets_synth::Range::new(0.05, 2.0),
        ..Default::default()
    };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("renders");
    datasets_synth::write_calibrated(
        &sensor,
        &config,
        100,
        41,
        &out,
        datasets_synth::WriteOptions::default(),
        &Default::default(),
    )
    .unwrap();
    let ds = Dataset::open(&out).unwrap();
    let mut nets = PalpationNetworks::load(&model, Runtime::BurnFlex).unwrap();
    let s = score_renders(&mut nets, &ds).unwrap();
    let all = &s.detector.all;
    assert_eq!(s.kinds.len(), KINDS.len());
    let frames: usize = s.kinds.iter().map(|k| k.frames).sum();
    let correct: usize = s.kinds.iter().map(|k| k.correct).sum();
    assert_eq!(frames, all.frames, "every rendered frame is of one kind");
    assert_eq!(correct, all.true_pos + all.true_neg, "{:?}", s.kinds);
    assert!(
        s.kinds.iter().filter(|k| k.frames > 0).count() >= 4,
        "{:?}",
        s.kinds
    );
    assert!(s.segmenter.paths[0].frames > 0 && s.depth.mae_mm.is_finite());
    // A set whose press is unknown (its press_mm left empty, as a real
    // recording's labels leave it) is of no kind (not "no contact").
    let labels = std::fs::read_to_string(out.join("labels.csv")).unwrap();
    let header = labels.lines().next().unwrap();
    let press = header.split(',').position(|c| c == "press_mm").unwrap();
    let blanked: String = labels
        .lines()
        .enumerate()
        .map(|(n, l)| {
            let mut cells: Vec<&str> = l.split(',').collect();
            if n > 0 {
                cells[press] = "";
            }
            cells.join(",") + "\n"
        })
        .collect();
    std::fs::write(out.join("labels.csv"), blanked).unwrap();
    let ds = Dataset::open(&out).unwrap();
    for i in 0..ds.len() {
        assert_eq!(frame_kind(&ds, i).unwrap(), None, "row {i}");
    }
}
