//! A supervised pose network for TacTip frames: a small CNN on the grey pin
//! image with a dense head that predicts contact pose (edge position,
//! orientation, depth) directly, beside paper A's route of one
//! unsupervised encoder and cheap estimators on its features. The model,
//! its folder ([`PoseArtifact`]), training with label-preserving
//! augmentation, and inference on any runtime ([`PoseEstimator`]).

#![deny(missing_docs)]

pub mod artifact;
pub mod calibrate;
pub mod data;
mod error;
pub mod inference;
pub mod model;
pub mod options;
pub mod training;
pub use tactile_estimate::uncertainty;

pub use artifact::{PoseArtifact, PoseEnsemble};
pub use error::{Error, Result};
pub use inference::{PoseEstimates, PoseEstimator};
pub use model::{PoseNet, PoseNetConfig};
pub use options::{PoseFit, PoseOptions};
pub use training::PoseTrainingConfig;
