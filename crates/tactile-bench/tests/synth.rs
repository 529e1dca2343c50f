//! The renderers' speed page: with a calibration folder it measures that
//! sensor's renderer beside the virtual ones.

use std::path::Path;

#[test]
fn the_speed_page_measures_a_calibrated_sensors_renderer_when_given_one() {
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/gelsight-r15");
    let md = tactile_bench::synth::bench_synth(2, Some(&model)).unwrap();
    let row = md
        .lines()
        .find(|l| l.starts_with("| calibrated sensor | 640x480 |"))
        .unwrap_or_else(|| panic!("no row of the calibrated sensor:\n{md}"));
    // Milliseconds per frame, frames/s of one thread, frames/s written.
    let numbers: Vec<f64> = row
        .split('|')
        .skip(3)
        .filter_map(|c| c.trim().parse().ok())
        .collect();
    assert!(
        numbers.len() == 3 && numbers.iter().all(|v| *v > 0.0),
        "{row}"
    );
    assert!(md.contains("| virtual TacTip | 300x300 |"), "{md}");
    // Without one, the virtual sensors alone, as before.
    let md = tactile_bench::synth::bench_synth(1, None).unwrap();
    assert!(!md.contains("calibrated sensor"), "{md}");
}
