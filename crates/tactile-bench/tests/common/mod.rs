//! What the bench tests share: the repository root and the writing of a
//! subset of a real set as a dataset folder of its own.
#![allow(clippy::unwrap_used, dead_code)]

use std::path::{Path, PathBuf};

/// The repository root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Finish a subset of the real set in `real` whose frames are copied into
/// `dir`: write its `labels` and the real set's manifest with `count`.
pub fn write_subset(real: &Path, dir: &Path, labels: &str, count: usize) {
    std::fs::write(dir.join("labels.csv"), labels).unwrap();
    let manifest = std::fs::read_to_string(real.join("manifest.json")).unwrap();
    let mut m: serde_json::Value = serde_json::from_str(&manifest).unwrap();
    m["count"] = count.into();
    std::fs::write(dir.join("manifest.json"), m.to_string()).unwrap();
}
