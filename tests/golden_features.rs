#![allow(clippy::unwrap_used)]
//! The authors' released encoder, loaded into our CAE, reproduces all 1200
//! of their released feature vectors from the PNGs through our own
//! preprocessing (OpenCV-exact resize, /255, round(x + 0.3)), on ndarray
//! and on flex.

mod common;

use tactile_rs::cae::authors::load_authors_encoder;
use tactile_rs::cae::data::PinSet;
use tactile_rs::cae::encode::encode_all;
use tactile_rs::core::DeviceKind;
use tactile_rs::core::dataset::Dataset;
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
        let cae = load_authors_encoder(real.join("authors-encoder.safetensors"), &device)
            .expect("load encoder");
        let feats = encode_all(&cae.encoder, &pins, 256, &device).expect("encode");
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
