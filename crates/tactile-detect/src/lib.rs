//! Paper B's tendon detector: does this visuo-tactile frame show a tendon
//! under the skin? A MobileNetV3-small-style network (or the ResNet-18-style
//! baseline) on the frame resized to a fixed input and normalised with
//! training-set statistics saved beside the weights; the decision threshold
//! is calibrated on validation sequences.

#![deny(missing_docs)]

pub mod artifact;
pub mod augment;
pub mod calibrate;
pub mod data;
pub mod ensemble;
mod error;
pub mod eval;
pub mod inference;
pub mod model;
pub mod options;
pub mod prepare;
pub mod profile;
pub mod training;

pub use artifact::DetectorArtifact;
pub use data::{DetectionSet, SoftLabels};
pub use ensemble::{DetectorEnsemble, DetectorEnsembleArtifact};
pub use error::{Error, Result};
pub use eval::{DetectorScores, evaluate};
pub use inference::{Assessment, Gate, TendonDetector};
pub use model::{Architecture, Detector, DetectorConfig};
pub use options::DetectorOptions;
pub use tactile_preprocess::visuo::{BLANK_FRAME_STD, is_blank};
pub use training::DetectorTrainingConfig;
