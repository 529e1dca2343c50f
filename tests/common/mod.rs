#![allow(clippy::unwrap_used)]
//! Helpers shared by the workspace-level integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// `../shared/real` beside the repository (or `$TACTILE_SHARED_REAL`).
/// Panics with a clear message when it is missing: the real-data tests
/// must not silently pass without their data.
pub fn shared_real() -> PathBuf {
    let p = std::env::var_os("TACTILE_SHARED_REAL")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/real"));
    assert!(
        p.join("polic-shapes/manifest.json").is_file(),
        "real TacTip data not found at {} (expected ../shared/real beside the repository, or set TACTILE_SHARED_REAL)",
        p.display()
    );
    p
}

/// Read the authors' golden features: file -> 16 values.
pub fn golden_features() -> Vec<(String, Vec<f32>)> {
    let path = shared_real().join("polic-shapes/golden-features.csv");
    let text = std::fs::read_to_string(&path).expect("golden-features.csv");
    text.lines()
        .skip(1)
        .map(|l| {
            let mut it = l.split(',');
            let file = it.next().unwrap().to_string();
            let _split = it.next();
            (file, it.map(|v| v.parse::<f32>().unwrap()).collect())
        })
        .collect()
}
