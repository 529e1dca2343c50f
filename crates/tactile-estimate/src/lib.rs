//! Estimators on feature vectors (paper A's "one encoder, many cheap
//! estimators"): regression of contact pose, depth and force, with angles
//! handled on the circle.

pub mod classical;
pub mod regressor;
pub mod target;

pub use regressor::{Regressor, RegressorConfig};
pub use target::{Target, TargetKind};
