//! ROS 2 bags: listing the image topics of an MCAP file and reading each
//! topic's frames either works or returns an error; a header claiming a
//! huge record, chunk or image is refused before it is allocated.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(dir) = tempfile::tempdir() else { return };
    let path = dir.path().join("b.mcap");
    if std::fs::write(&path, data).is_err() {
        return;
    }
    let Ok(topics) = tactile_core::bag::image_topics(&path) else {
        return;
    };
    for t in topics {
        let Ok(mut frames) = tactile_core::bag::BagImages::open(&path, &t.topic) else {
            continue;
        };
        while let Ok(Some(_)) = frames.next_frame() {}
    }
});
