//! tactile-rs: one toolkit for vision-based tactile sensing.
//!
//! The workspace's crates, re-exported under short names so a user can
//! depend on this one library.

#![deny(missing_docs)]

pub use datasets_synth as synth;
pub use tactile_bench as bench;
pub use tactile_burn as nn;
pub use tactile_cae as cae;
pub use tactile_core as core;
pub use tactile_depth as depth;
pub use tactile_detect as detect;
pub use tactile_estimate as estimate;
pub use tactile_gelsight as gelsight;
pub use tactile_onnx as onnx;
pub use tactile_pipeline as pipeline;
pub use tactile_pose as pose;
pub use tactile_preprocess as preprocess;
pub use tactile_ros as ros;
pub use tactile_segment as segment;
