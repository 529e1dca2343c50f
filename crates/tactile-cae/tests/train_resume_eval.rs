#![allow(clippy::unwrap_used)]
//! The autoencoder's library path on tiny data, without the command line:
//! options -> training -> resume (to the same result as an uninterrupted
//! run) -> encoding.

use serde_json::json;
use tactile_burn::Runtime;
use tactile_burn::options::Options;
use tactile_cae::{CaeOptions, TactipEncoder};
use tactile_core::dataset::Dataset;

fn options(epochs: usize, resume: bool) -> CaeOptions {
    let kw = json!({
        "max_epochs": epochs, "patience": 100, "val_fraction": 0.5, "resume": resume,
    });
    CaeOptions::with_overrides(kw.as_object().unwrap()).unwrap()
}

#[test]
fn the_autoencoder_resumes_to_the_same_result_and_encodes() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("ds");
    let cfg = datasets_synth::TactipConfig::default();
    datasets_synth::write_tactip(&cfg, 6, 3, &data, Default::default()).unwrap();
    let ds = Dataset::open(&data).unwrap();
    let straight = tmp.path().join("straight");
    let resumed = tmp.path().join("resumed");

    let s = options(4, false).train(&ds, &straight).unwrap();
    assert_eq!(s.epochs_run, 4);
    options(2, false).train(&ds, &resumed).unwrap();
    let r = options(4, true).train(&ds, &resumed).unwrap();
    assert_eq!(r.epochs_run, 4);
    let losses = |dir: &std::path::Path| {
        std::fs::read_to_string(dir.join("curves.csv"))
            .unwrap()
            .lines()
            .map(|l| l.rsplit_once(',').unwrap().0.to_string())
            .collect::<Vec<_>>()
    };
    assert_eq!(
        losses(&straight),
        losses(&resumed),
        "resumed training diverged from the uninterrupted run"
    );
    // The kept models give the same features, 16 per frame.
    let features = |dir: &std::path::Path| {
        let mut enc = TactipEncoder::load(dir, Runtime::BurnFlex, 0).unwrap();
        enc.encode_dataset(&ds).unwrap().1
    };
    let (a, b) = (features(&straight), features(&resumed));
    assert_eq!(a.len(), ds.len());
    assert!(
        a.iter()
            .all(|f| f.len() == 16 && f.iter().all(|v| v.is_finite()))
    );
    assert_eq!(a, b, "resumed model differs from the uninterrupted one");
}
