//! The burn half of tactile-rs's foundation: the device switch and the
//! runtimes networks run on (burn `ndarray`/`flex`, onnxruntime), the
//! [`Artifact`] trait every saved model folder
//! implements, ensembles of folders, weights I/O, the one training skeleton
//! ([`train::Schedule`], [`train::fit`]), stable layers and losses,
//! Adadelta, and the option types the front ends share
//! ([`options`]). Every model crate builds on it; nothing below the models
//! does.

#![deny(missing_docs)]

pub mod artifact;
pub mod device;
pub mod ensemble;
pub mod module_io;
pub mod nn;
pub mod optim;
pub mod options;
pub mod runtime;
pub mod train;

pub use artifact::{Artifact, Loaded};
pub use device::DeviceKind;
pub use runtime::{Network, Runtime};
use tactile_core::{Error, Result};

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
