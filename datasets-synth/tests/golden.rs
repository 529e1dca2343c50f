#![allow(clippy::unwrap_used)]
//! Golden hashes of tiny fixed-seed datasets: any change to what the
//! generators produce (on purpose or not) shows up here. PNGs are hashed by
//! their decoded pixels, so only the content counts, not the PNG encoder's
//! compression; every other file is hashed byte for byte. After an
//! intended change, update the constants and say why in the commit.

use std::path::Path;

use datasets_synth::{TactipConfig, VisuotactileConfig, WriteOptions};
use sha2::{Digest, Sha256};
use tactile_core::image_io::{load_grey, load_rgb};

const TACTIP_GOLDEN: &str = "e4e547b3d2e05079fbea2363c1f71956e560e8153250e164a9e6bf284c506f38";
const VISUOTACTILE_GOLDEN: &str =
    "5a507232cd3019026418e86a1d9006630ebbbaab6e120a1ce788de071b728707";

fn dataset_hash(root: &Path) -> String {
    let mut files: Vec<String> = Vec::new();
    for sub in ["", "frames", "masks", "depth"] {
        let Ok(rd) = std::fs::read_dir(root.join(sub)) else {
            continue;
        };
        for e in rd {
            let p = e.unwrap().path();
            if p.is_file() {
                files.push(p.strip_prefix(root).unwrap().to_string_lossy().into_owned());
            }
        }
    }
    files.sort();
    let mut h = Sha256::new();
    for f in &files {
        h.update(f.as_bytes());
        let p = root.join(f);
        let bytes = if f.ends_with(".png") {
            if f.starts_with("frames/") && root.join("depth").exists() {
                load_rgb(&p).unwrap().as_slice().to_vec()
            } else {
                load_grey(&p).unwrap().as_slice().to_vec()
            }
        } else if f == "manifest.json" {
            // The generator's version string is not content.
            let mut m: serde_json::Value =
                serde_json::from_slice(&std::fs::read(&p).unwrap()).unwrap();
            m["generator"] = serde_json::Value::Null;
            serde_json::to_vec(&m).unwrap()
        } else {
            std::fs::read(&p).unwrap()
        };
        h.update(&bytes);
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

#[test]
fn tactip_golden() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    datasets_synth::write_tactip(
        &TactipConfig::default(),
        6,
        2024,
        &out,
        WriteOptions::default(),
    )
    .unwrap();
    let got = dataset_hash(&out);
    assert_eq!(got, TACTIP_GOLDEN, "virtual TacTip output changed");
}

#[test]
fn visuotactile_golden() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("v");
    let cfg = VisuotactileConfig {
        width: 160,
        height: 90,
        frames_per_sequence: 5,
        ..Default::default()
    };
    datasets_synth::write_visuotactile(&cfg, 10, 2024, &out, WriteOptions::default()).unwrap();
    let got = dataset_hash(&out);
    assert_eq!(
        got, VISUOTACTILE_GOLDEN,
        "virtual visuo-tactile output changed"
    );
}
