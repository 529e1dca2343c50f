//! Weight files: any bytes as a segmenter's `segmenter.bpk` beside a valid
//! config either load (finite weights of the right shapes) or are refused.
#![no_main]

use burn::tensor::Device;
use libfuzzer_sys::fuzz_target;
use tactile_burn::Artifact;

const CONFIG: &str = r#"{"model":{"base":4,"side":16,"in_channels":3},"stats":{"mean":[0.5,0.5,0.5],"std":[0.1,0.1,0.1]},"threshold":0.5,"postprocess":{"edge_band":0.12,"edge_fraction":0.8,"min_anisotropy":1.5,"min_area":3,"axis_within_window":true}}"#;

fuzz_target!(|data: &[u8]| {
    let Ok(dir) = tempfile::tempdir() else { return };
    let root = dir.path();
    if std::fs::write(root.join("segmenter.json"), CONFIG).is_ok()
        && std::fs::write(root.join("segmenter.bpk"), data).is_ok()
    {
        let _ = tactile_segment::SegmenterArtifact::load(root, &Device::flex());
    }
});
