//! Estimators on feature vectors (paper A's "one encoder, many cheap
//! estimators"): the MLP they are made of, a k-fold classifier head,
//! multi-target regressors with angles on the circle, linfa baselines
//! (PCA, ridge, k-NN, Gaussian naive Bayes), the folder registry that runs
//! every estimator of an encoder on one encoding, and their scores.

#![deny(missing_docs)]

pub mod classical;
pub mod ensemble;
mod error;
pub mod eval;
pub mod head;
pub mod mlp;
pub mod registry;
pub mod regressor;
pub mod target;
pub mod uncertainty;

pub use ensemble::RegressorEnsemble;
pub use error::{Error, Result};
pub use head::{ClassifierHead, HeadArtifact, HeadConfig};
pub use mlp::{Activation, Mlp};
pub use registry::{Column, Estimates, Estimator, Estimators};
pub use regressor::{Regressor, RegressorArtifact, RegressorConfig};
pub use target::{Target, TargetKind};
