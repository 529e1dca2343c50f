#![allow(clippy::unwrap_used)]
//! The authors' released encoder, loaded into our CAE, reproduces all 1200
//! of their released feature vectors from the PNGs through our own
//! preprocessing (OpenCV-exact resize, /255, round(x + 0.3)), on ndarray
//! and on flex.

mod common;

use tactile_rs::cae::authors::{authors_widths, load_authors_encoder};
use tactile_rs::cae::data::PinSet;
use tactile_rs::cae::{CaeArtifact, CaeConfig, TactipEncoder};
use tactile_rs::core::dataset::Dataset;
use tactile_rs::nn::runtime::BurnNetwork;
use tactile_rs::nn::{DeviceKind, Runtime};
use tactile_rs::preprocess::PreprocessConfig;

#[test]
fn authors_encoder_reproduces_golden_features_on_both_devices() {
    let real = common::shared_real().join("polic-shapes");
    let ds = Dataset::open(&real).expect("open polic-shapes");
    let pins = PinSet::from_dataset(&ds, &PreprocessConfig::binary_frames()).expect("preprocess");
    let golden = common::golden_features();
    assert_eq!(golden.len(), 1200);
    let by_file: std::collections::HashMap<_, _> = golden.into_iter().collect();
    for kind in DeviceKind::ALL {
        let device = kind.device();
        let file = real.join("authors-encoder.safetensors");
        let cae = load_authors_encoder(&file, &device).expect("load encoder");
        let artifact = CaeArtifact {
            model: CaeConfig::new().with_widths(authors_widths(&file).unwrap()),
            preprocess: PreprocessConfig::binary_frames(),
            input_profile: None,
            notes: Default::default(),
        };
        let net = Box::new(BurnNetwork::new(cae, kind));
        let feats = TactipEncoder::from_network(artifact, net)
            .encode(&pins.images)
            .expect("encode");
        let mut worst = 0f32;
        let mut worst_file = String::new();
        for (file, f) in pins.files.iter().zip(&feats) {
            let g = &by_file[file];
            assert_eq!(g.len(), f.len());
            for (a, b) in f.iter().zip(g) {
                let d = (a - b).abs();
                if d > worst {
                    worst = d;
                    worst_file = file.clone();
                }
            }
        }
        println!("{kind}: max abs error {worst:.2e} (at {worst_file})");
        assert!(
            worst <= 1e-4,
            "{kind}: max abs error {worst} at {worst_file} exceeds 1e-4"
        );
    }
}

#[test]
fn shipped_shapes_model_still_loads_and_classifies_the_real_test_split() {
    // models/cae-shapes predates later config fields: it must keep loading.
    use tactile_rs::estimate::ClassifierHead;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/cae-shapes");
    let mut encoder = TactipEncoder::load(&root, Runtime::BurnFlex, 0).unwrap();
    let head = ClassifierHead::load(root.join("head"), &DeviceKind::Flex.device()).unwrap();
    let ds = Dataset::open(common::shared_real().join("polic-shapes")).unwrap();
    let test = ds.split_indices("test").unwrap();
    let (_, feats) = encoder.encode_dataset(&ds).unwrap();
    let x: Vec<Vec<f32>> = test.iter().map(|&i| feats[i].clone()).collect();
    let pred = head.predict(&x).unwrap();
    let right = test
        .iter()
        .zip(&pred)
        .filter(|(i, p)| ds.text(**i, "shape").unwrap() == head.classes()[**p])
        .count();
    let acc = right as f64 / test.len() as f64;
    // Measured 97.1 % (461/475); the paper's MLP: 96.7 %.
    assert!(acc >= 0.965, "accuracy {acc}");
}
