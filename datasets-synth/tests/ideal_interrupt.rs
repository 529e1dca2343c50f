//! A stop request (Ctrl-C) ends the ideal detector with nothing written.
//! Its own test binary: the stop flag is per process, and a request would
//! stop any other test's work running beside it.

use datasets_synth::{Range, VisuotactileConfig, WriteOptions, visuotactile, write_visuotactile};

#[test]
fn a_stop_request_ends_the_ideal_detector_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("set");
    let config = VisuotactileConfig {
        width: 320,
        height: 180,
        press_mm: Range::fixed(0.3),
        frames_per_sequence: 4,
        ..VisuotactileConfig::default()
    };
    write_visuotactile(&config, 4, 9, &out, WriteOptions::default()).unwrap();
    let csv = dir.path().join("bound.csv");
    tactile_core::interrupt::request();
    let stopped = visuotactile::dataset_bounds(&out, Some(&csv), false);
    tactile_core::interrupt::reset();
    assert!(
        matches!(stopped, Err(tactile_core::Error::Interrupted)),
        "{stopped:?}"
    );
    assert!(!csv.exists());
    // Once the request is forgotten, the same call works.
    assert_eq!(
        visuotactile::dataset_bounds(&out, Some(&csv), false)
            .unwrap()
            .len(),
        4
    );
    assert!(csv.exists());
}
