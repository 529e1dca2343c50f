//! The own-sensor page's scoring of a set of renders: the detector's
//! answers by kind of frame add up to its answers on the whole set, and a
//! set whose press is unknown (its press_mm left empty) is of no kind; the
//! real presses' summaries, which the page and the depth-seeds page read.

use std::path::{Path, PathBuf};

use tactile_bench::own_sensor::{
    BallRow, BallSummary, KINDS, PalpationNetworks, frame_kind, score_renders,
};
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

fn press(file: &str, in_training: bool, network_shape_mm: f64, probability: f32) -> BallRow {
    let score = |shape_mae_mm, peak_mm| tactile_gelsight::eval::PressScore {
        file: file.into(),
        shape_mae_mm,
        far_field_mm: 0.01,
        rim_sink_mm: 0.0,
        peak_mm,
    };
    BallRow {
        file: file.into(),
        tendon: probability > 0.5,
        probability,
        foreign: false,
        in_training,
        network: score(network_shape_mm, 1.9),
        calibration: score(0.04, 1.8),
    }
}

#[test]
fn the_presses_are_summed_up_over_all_and_over_those_never_trained_on() {
    let ball = [
        press("a.png", true, 0.04, 0.1),
        press("b.png", true, 0.05, 0.7),
        press("c.png", false, 0.06, 0.2),
    ];
    let s = BallSummary::of_presses(&ball);
    assert_eq!(
        s.iter().map(|b| b.presses.as_str()).collect::<Vec<_>>(),
        ["all", "held-out"]
    );
    assert_eq!((s[0].count, s[0].tendon), (3, 1));
    assert!((s[0].shape_ratio - 1.25).abs() < 1e-9, "{:?}", s[0]);
    assert!((s[1].shape_ratio - 1.5).abs() < 1e-9, "{:?}", s[1]);
    assert_eq!(s[1].max_probability, 0.2);
    assert!((s[0].network_peak_mm - 1.9).abs() < 1e-12);
    // No press joined training: one row, not the same one twice.
    let none: Vec<BallRow> = ball
        .iter()
        .cloned()
        .map(|b| BallRow {
            in_training: false,
            ..b
        })
        .collect();
    assert_eq!(BallSummary::of_presses(&none).len(), 1);
    assert!(BallSummary::of_presses(&[]).is_empty());
}
