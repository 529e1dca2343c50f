//! Depth maps: `read_depth_npy` either reads a plausible map or returns an
//! error, and never allocates what the header claims before checking it.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(dir) = tempfile::tempdir() else { return };
    let path = dir.path().join("d.npy");
    if std::fs::write(&path, data).is_ok() {
        let _ = tactile_core::npy::read_depth_npy(&path);
    }
});
