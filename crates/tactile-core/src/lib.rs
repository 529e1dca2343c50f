//! The burn-free foundation of tactile-rs: the error type, the dataset
//! layout (`datasets.md`) with its checks, splits and import, the sensor
//! contract ([`spec`]), image loading, atomic file writes and staged
//! folders, frame sources (folders, videos, cameras, standard input, ROS 2
//! bags),
//! metrics, plots, progress, interrupts and benchmark helpers. It compiles
//! no tensor library, so the virtual sensors and the preprocessing build
//! in seconds; everything that needs burn lives in `tactile-burn`.

#![deny(missing_docs)]

pub mod bag;
pub mod bench;
pub mod csv_lines;
pub mod dataset;
pub mod error;
pub mod image_io;
pub mod import;
pub mod interrupt;
pub mod io;
pub mod metrics;
pub mod npy;
pub mod plot;
pub mod progress;
pub mod rng;
pub mod source;
pub mod spec;
pub mod stack;
pub mod video;

/// A progress note on stderr. Unlike `eprintln!` it never panics: a note
/// that cannot be written (stderr closed, a full pipe) is dropped.
#[macro_export]
macro_rules! note {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

pub use error::{Error, Result};
