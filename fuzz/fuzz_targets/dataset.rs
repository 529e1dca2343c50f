//! labels.csv and manifest.json of a dataset folder: `Dataset::open` and
//! the splits either work or return an error, whatever the bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use tactile_core::dataset::Dataset;

fuzz_target!(|data: &[u8]| {
    // manifest.json, then 0xFF, then labels.csv.
    let (manifest, labels) = match data.iter().position(|&b| b == 0xFF) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &b"file\nframes/0.png\n"[..]),
    };
    let Ok(dir) = tempfile::tempdir() else { return };
    let root = dir.path();
    let _ = std::fs::create_dir(root.join("frames"));
    let _ = std::fs::write(root.join("frames/0.png"), b"not a png");
    let _ = std::fs::write(root.join("manifest.json"), manifest);
    let _ = std::fs::write(root.join("labels.csv"), labels);
    if let Ok(ds) = Dataset::open(root) {
        let _ = ds.split_by_sequence(0.25, 1);
        let _ = ds.three_way_split(0.2, 0.2, 1);
        let _ = ds.training_rows(None);
        let _ = ds.tendon_rows(&(0..ds.len()).collect::<Vec<_>>());
        for i in 0..ds.len().min(8) {
            let _ = ds.load_rgb(i);
            let _ = ds.number_opt(i, "x_mm");
        }
    }
});
