//! Paper B's depth reconstruction: from one visuo-tactile RGB frame (and
//! optionally the tendon mask as a fourth channel) to the camera-to-skin
//! distance of every pixel. A DenseNet encoder with a U-Net decoder; files
//! hold metres, the network works in millimetres around the training mean.

#![deny(missing_docs)]

pub mod artifact;
pub mod data;
pub mod ensemble;
mod error;
pub mod eval;
pub mod inference;
pub mod model;
pub mod options;
pub mod prepare;
pub mod prior;
pub mod torchvision;
pub mod training;

pub use artifact::{DepthArtifact, DepthScale};
pub use data::DepthSet;
pub use ensemble::{DepthEnsemble, DepthEnsembleArtifact};
pub use error::{Error, Result};
pub use eval::{DEPTH_RANGE_MM, DepthScorer, DepthScores, evaluate};
pub use inference::DepthEstimator;
pub use model::{DenseNetConfig, DenseNetPreset, DepthNet, DepthNetConfig, HeadKind};
pub use options::DepthOptions;
pub use training::{DepthTrainingConfig, LossKind};
