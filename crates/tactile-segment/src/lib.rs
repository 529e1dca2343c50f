//! Paper B's tendon segmenter: a small U-Net on a square window of the
//! visuo-tactile frame, then post-processing (largest region, LED-glare
//! override) and the region's direction by PCA.

#![deny(missing_docs)]

pub mod artifact;
pub mod data;
mod error;
pub mod eval;
pub mod inference;
pub mod model;
pub mod options;
pub mod postprocess;
pub mod prepare;
pub mod training;

pub use artifact::SegmenterArtifact;
pub use data::SegmentSet;
pub use error::{Error, Result};
pub use eval::{DirectionScores, PathScores, SegmenterScores, evaluate, evaluate_folder};
pub use inference::{MIN_SHARED_TEXTURE, REST_FILE, RestFrame, Segmentation, TendonSegmenter};
pub use model::{UNet, UNetConfig};
pub use options::SegmenterOptions;
pub use postprocess::{
    Direction, DirectionMethod, Evidence, NoDirection, PostprocessConfig, Tendon, TendonMask,
    postprocess, window_tendon,
};
pub use training::SegmenterTrainingConfig;
