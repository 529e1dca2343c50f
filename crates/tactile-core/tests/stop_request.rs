#![allow(clippy::unwrap_used)]
//! A stop request (Ctrl-C, SIGTERM: what the signal thread sets) during
//! the header pass over a folder's frames (or a TIFF stack's pages) ends it with `Interrupted`
//! before any frame is decoded. A binary of its own: the request is
//! process-wide, and would stop the other tests' work.

use tactile_core::Error;
use tactile_core::interrupt;
use tactile_core::source::{FrameList, FrameSource, SourceOptions, SourceSpec};

#[test]
fn a_stop_request_ends_the_header_pass() {
    let dir = tempfile::tempdir().unwrap();
    for i in 0..3 {
        let px = vec![90u8; 8 * 6 * 3];
        tactile_core::image_io::save_rgb_png(dir.path().join(format!("{i}.png")), 8, 6, &px)
            .unwrap();
    }
    let list = FrameList::open(dir.path()).unwrap();
    let spec = SourceSpec::Path(dir.path().to_path_buf());
    // A TIFF stack given alone: its header pass stops alike.
    use tiff::encoder::{TiffEncoder, colortype::RGB8};
    let mut bytes = std::io::Cursor::new(Vec::new());
    let mut tiff = TiffEncoder::new(&mut bytes).unwrap();
    for _ in 0..2 {
        tiff.write_image::<RGB8>(8, 6, &[90u8; 8 * 6 * 3]).unwrap();
    }
    let stack_dir = tempfile::tempdir().unwrap();
    let stack = SourceSpec::Path(stack_dir.path().join("stack.tif"));
    std::fs::write(stack_dir.path().join("stack.tif"), bytes.into_inner()).unwrap();
    interrupt::request();
    let e = list.check_headers(None).unwrap_err();
    assert!(matches!(e, Error::Interrupted), "{e}");
    let e = FrameSource::open(&spec, SourceOptions::default())
        .err()
        .unwrap();
    assert!(matches!(e, Error::Interrupted), "{e}");
    let e = FrameSource::open(&stack, SourceOptions::default())
        .err()
        .unwrap();
    assert!(matches!(e, Error::Interrupted), "{e}");
    // The request forgotten (as Python's package does after a Ctrl-C),
    // the same folder opens and gives its frames.
    interrupt::reset();
    list.check_headers(None).unwrap();
    let source = FrameSource::open(&spec, SourceOptions::default()).unwrap();
    assert_eq!(source.count(), 3);
    let source = FrameSource::open(&stack, SourceOptions::default()).unwrap();
    assert_eq!(source.count(), 2);
}
