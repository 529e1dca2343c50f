//! The foundation of tactile-rs: the error type, the dataset layout
//! (`datasets.md`) with its checks and splits, image loading, atomic file
//! writes, the burn device switch and the runtimes networks run on, the
//! [`Artifact`](artifact::Artifact) trait every saved model implements, the
//! one training skeleton ([`train::Schedule`], [`train::fit`]), stable
//! losses, Adadelta, metrics, plots and benchmark helpers. Every other
//! crate reuses these instead of copying them.

#![deny(missing_docs)]

pub mod artifact;
pub mod bench;
pub mod dataset;
pub mod device;
pub mod ensemble;
pub mod error;
pub mod image_io;
pub mod interrupt;
pub mod io;
pub mod metrics;
pub mod module_io;
pub mod nn;
pub mod npy;
pub mod optim;
pub mod plot;
pub mod rng;
pub mod runtime;
pub mod train;
pub mod video;

/// A progress note on stderr. Unlike `crate::note!` it never panics: a note
/// that cannot be written (stderr closed, a full pipe) is dropped.
#[macro_export]
macro_rules! note {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

pub use artifact::{Artifact, Loaded};
pub use device::DeviceKind;
pub use error::{Error, Result};
pub use runtime::{Network, Runtime};

#[cfg(test)]
mod tests {
    /// Models are moved into worker threads (the pipeline's, Python's).
    #[test]
    fn burn_modules_are_send() {
        fn send<T: Send>() {}
        send::<burn::nn::Linear>();
        send::<burn::nn::conv::Conv2d>();
        send::<burn::nn::BatchNorm>();
    }
}
