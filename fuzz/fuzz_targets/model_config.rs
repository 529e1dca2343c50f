//! Model config JSON of every kind of model folder: parsed, checked and, if
//! accepted, built; never a panic or an allocation beyond the limits.
#![no_main]

use std::path::Path;

use burn::tensor::Device;
use libfuzzer_sys::fuzz_target;
use tactile_burn::Artifact;

fn load<A: Artifact>(json: &[u8]) {
    if let Ok(a) = serde_json::from_slice::<A>(json)
        && a.check(Path::new("config.json")).is_ok()
    {
        let _ = a.init(&Device::flex());
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&kind, json)) = data.split_first() else { return };
    match kind % 6 {
        0 => load::<tactile_detect::DetectorArtifact>(json),
        1 => load::<tactile_segment::SegmenterArtifact>(json),
        2 => load::<tactile_depth::DepthArtifact>(json),
        3 => load::<tactile_cae::CaeArtifact>(json),
        4 => load::<tactile_estimate::HeadArtifact>(json),
        _ => load::<tactile_estimate::RegressorArtifact>(json),
    }
});
