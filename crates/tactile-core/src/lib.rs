//! Shared foundation of tactile-rs: the error type, dataset reading and
//! validation (`../shared/spec/datasets.md`), image loading, atomic file
//! writes, the burn device switch, shared neural-network pieces (stable
//! losses, Adadelta), training bookkeeping, metrics, plots and benchmark
//! helpers. Every other crate reuses these instead of copying them.

pub mod bench;
pub mod dataset;
pub mod device;
pub mod error;
pub mod image_io;
pub mod io;
pub mod metrics;
pub mod module_io;
pub mod nn;
pub mod npy;
pub mod optim;
pub mod plot;
pub mod train;

pub use device::DeviceKind;
pub use error::{Error, Result};
