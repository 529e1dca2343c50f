//! Paper A's convolutional autoencoder (Table I), alone: the model, its
//! folder ([`CaeArtifact`]), training, the encoder at inference
//! ([`TactipEncoder`]: frames to pin images to features, on any runtime),
//! its ONNX export, and the authors' released encoder. The estimators that
//! use its features are in `tactile-estimate`.

#![deny(missing_docs)]

pub mod artifact;
pub mod authors;
pub mod data;
mod error;
pub mod eval;
pub mod export;
pub mod inference;
pub mod joint;
pub mod model;
pub mod options;
pub mod tasks;
pub mod training;

pub use artifact::CaeArtifact;
pub use error::{Error, Result};
pub use inference::TactipEncoder;
pub use joint::JointTargets;
pub use model::{Cae, CaeConfig, CaeDecoder, CaeEncoder};
pub use options::{CaeOptions, RotateArgs};
pub use training::{CaeTrainingConfig, Optimizer};
