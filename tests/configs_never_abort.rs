#![allow(clippy::unwrap_used)]
//! Property: a model config read from a file, however hostile its numbers,
//! is either refused by its checks with an error or builds its network;
//! it never panics and never asks for an allocation the limits do not
//! allow (issue 16). Each case mutates numbers of a shipped config to
//! extremes (0, 1, huge, negative, fractional) and runs the loader's own
//! path: parse, check, build.

use std::path::Path;

use burn::tensor::Device;
use proptest::prelude::*;
use serde_json::Value;
use tactile_rs::nn::Artifact;

/// Every numeric leaf of `v`, as JSON pointers; of each array, the first
/// `per_array` elements.
fn numbers(v: &Value, at: String, per_array: usize, out: &mut Vec<String>) {
    match v {
        Value::Number(_) => out.push(at),
        Value::Array(a) => a
            .iter()
            .take(per_array)
            .enumerate()
            .for_each(|(i, x)| numbers(x, format!("{at}/{i}"), per_array, out)),
        Value::Object(o) => o
            .iter()
            .for_each(|(k, x)| numbers(x, format!("{at}/{k}"), per_array, out)),
        _ => {}
    }
}

const EXTREMES: [f64; 14] = [
    0.0, 1.0, 2.0, 3.0, 16.0, 64.0, 1e3, 1e6, 1e9, 1.8e19, -1.0, 0.5, 1e-30, 1e300,
];

/// `v` with the number at `ptr` set to `e` (an integer when it is one).
fn set_number(v: &mut Value, ptr: &str, e: f64) {
    let n = if e.fract() == 0.0 && (0.0..1.8e19).contains(&e) {
        serde_json::json!(e as u64)
    } else {
        serde_json::json!(e)
    };
    if let Some(slot) = v.pointer_mut(ptr) {
        *slot = n;
    }
}

/// `template` with the numbers at `picks` (leaf index, extreme index) replaced.
fn mutate(template: &Value, picks: &[(usize, usize)]) -> Value {
    let mut leaves = Vec::new();
    numbers(template, String::new(), usize::MAX, &mut leaves);
    let mut v = template.clone();
    for &(leaf, x) in picks {
        set_number(
            &mut v,
            &leaves[leaf % leaves.len()],
            EXTREMES[x % EXTREMES.len()],
        );
    }
    v
}

/// Parse, check and build `json` as an `A`; Ok(built) or a clean refusal,
/// which says the value in a few characters (1e300, not 301 digits).
fn load<A: Artifact>(json: &Value) -> bool {
    let Ok(a) = serde_json::from_value::<A>(json.clone()) else {
        return false;
    };
    if let Err(e) = a.check(Path::new("config.json")) {
        let e = e.to_string();
        assert!(!e.contains(&"0".repeat(22)), "{e}");
        return false;
    }
    a.init(&Device::flex()).is_ok()
}

fn template(path: &str) -> Value {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn detector_configs(picks in proptest::collection::vec((0usize..64, 0usize..14), 1..4)) {
        load::<tactile_rs::detect::DetectorArtifact>(&mutate(&template("models/detector/member-0/detector.json"), &picks));
    }

    #[test]
    fn segmenter_configs(picks in proptest::collection::vec((0usize..64, 0usize..14), 1..4)) {
        load::<tactile_rs::segment::SegmenterArtifact>(&mutate(&template("models/segmenter/segmenter.json"), &picks));
    }

    #[test]
    fn depth_configs(picks in proptest::collection::vec((0usize..64, 0usize..14), 1..4)) {
        load::<tactile_rs::depth::DepthArtifact>(&mutate(&template("models/depth/depth.json"), &picks));
    }

    #[test]
    fn cae_configs(picks in proptest::collection::vec((0usize..64, 0usize..14), 1..4)) {
        load::<tactile_rs::cae::CaeArtifact>(&mutate(&template("models/cae-synth/cae.json"), &picks));
    }

    #[test]
    fn head_configs(picks in proptest::collection::vec((0usize..64, 0usize..14), 1..4)) {
        load::<tactile_rs::estimate::HeadArtifact>(&mutate(&template("models/cae-synth/head/head.json"), &picks));
    }

    #[test]
    fn pose_configs(picks in proptest::collection::vec((0usize..64, 0usize..14), 1..4)) {
        load::<tactile_rs::pose::PoseArtifact>(&mutate(&template("models/pose-surface/member-0/pose.json"), &picks));
    }

    #[test]
    fn gelsight_configs(picks in proptest::collection::vec((0usize..64, 0usize..14), 1..4)) {
        load::<tactile_rs::gelsight::GelsightArtifact>(&mutate(&template("models/gelsight-r15/gelsight.json"), &picks));
    }

    #[test]
    fn regressor_configs(picks in proptest::collection::vec((0usize..64, 0usize..14), 1..4)) {
        load::<tactile_rs::estimate::RegressorArtifact>(&mutate(&template("models/cae-synth/position/regressor.json"), &picks));
    }
}

#[test]
fn the_shipped_configs_load() {
    assert!(load::<tactile_rs::detect::DetectorArtifact>(&template(
        "models/detector/member-0/detector.json"
    )));
    // The shipped detector is an ensemble: its folder reads whole.
    let detector = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/detector");
    let ensemble = tactile_rs::detect::DetectorEnsembleArtifact::read(&detector).unwrap();
    assert_eq!(ensemble.members.len(), ensemble.ensemble.members.len());
    assert!(load::<tactile_rs::depth::DepthArtifact>(&template(
        "models/depth/depth.json"
    )));
    assert!(load::<tactile_rs::estimate::HeadArtifact>(&template(
        "models/cae-synth/head/head.json"
    )));
}

/// Every single number of every shipped config set to every extreme, in
/// turn: a deterministic sweep beside the random pairs and triples above
/// (it holds the case a clean CI run found: a depth transition compression
/// of 1e-30 left a transition with no channels).
#[test]
fn every_single_extreme_value_is_loaded_or_refused() {
    fn sweep<A: Artifact>(path: &str) {
        let t = template(path);
        let mut leaves = Vec::new();
        numbers(&t, String::new(), usize::MAX, &mut leaves);
        for leaf in 0..leaves.len() {
            for x in 0..EXTREMES.len() {
                load::<A>(&mutate(&t, &[(leaf, x)]));
            }
        }
    }
    sweep::<tactile_rs::detect::DetectorArtifact>("models/detector/member-0/detector.json");
    sweep::<tactile_rs::segment::SegmenterArtifact>("models/segmenter/segmenter.json");
    sweep::<tactile_rs::depth::DepthArtifact>("models/depth/depth.json");
    sweep::<tactile_rs::cae::CaeArtifact>("models/cae-synth/cae.json");
    sweep::<tactile_rs::estimate::HeadArtifact>("models/cae-synth/head/head.json");
    sweep::<tactile_rs::estimate::RegressorArtifact>("models/cae-synth/position/regressor.json");
    sweep::<tactile_rs::pose::PoseArtifact>("models/pose-surface/member-0/pose.json");
    sweep::<tactile_rs::gelsight::GelsightArtifact>("models/gelsight-r15/gelsight.json");
}

/// A calibrated sensor's render model (`optics.json`, which `synth
/// gelsight --sensor` reads): every number (of its long tables, the first
/// two) set to each extreme in turn is read or refused, never a panic, a
/// refusal saying the value in a few characters (before, 1e300 was
/// printed in 301 digits). A scale a calibration would refuse (1e-30 mm
/// per pixel) is refused here too: it rendered frames before.
#[test]
fn every_extreme_of_a_render_model_is_read_or_refused_in_a_few_words() {
    use tactile_rs::synth::calibrated::RenderModel;
    let shipped = template("models/gelsight-r15/optics.json");
    let model = |v: &Value| serde_json::from_value::<RenderModel>(v.clone()).map(|m| m.check());
    assert!(matches!(model(&shipped), Ok(Ok(()))));
    let mut leaves = Vec::new();
    numbers(&shipped, String::new(), 2, &mut leaves);
    assert!(leaves.len() > 8, "{leaves:?}");
    let mut refused = 0;
    for at in &leaves {
        for x in EXTREMES {
            let mut v = shipped.clone();
            set_number(&mut v, at, x);
            if let Ok(Err(e)) = model(&v) {
                refused += 1;
                let e = e.to_string();
                assert!(
                    e.len() < 200 && !e.contains(&"0".repeat(22)),
                    "{at} = {x}: {e}"
                );
            }
        }
    }
    assert!(refused > 10, "{refused}");
    let mut v = shipped.clone();
    set_number(&mut v, "/mm_per_px", 1e-30);
    let e = model(&v).unwrap().unwrap_err().to_string();
    assert!(
        e.contains("mm_per_px must be 0.0001-1 mm per pixel") && e.contains("1e-30"),
        "{e}"
    );
}
