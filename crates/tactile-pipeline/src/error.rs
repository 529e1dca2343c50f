//! What can go wrong composing the models.

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors of the pipelines: those of every model they compose.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file, dataset, model folder or configuration problem.
    #[error(transparent)]
    Core(#[from] tactile_core::Error),
    /// Preprocessing.
    #[error(transparent)]
    Preprocess(#[from] tactile_preprocess::Error),
    /// The autoencoder.
    #[error(transparent)]
    Cae(#[from] tactile_cae::Error),
    /// An estimator.
    #[error(transparent)]
    Estimate(#[from] tactile_estimate::Error),
    /// The tendon detector.
    #[error(transparent)]
    Detect(#[from] tactile_detect::Error),
    /// The segmenter.
    #[error(transparent)]
    Segment(#[from] tactile_segment::Error),
    /// The depth network.
    #[error(transparent)]
    Depth(#[from] tactile_depth::Error),
    /// Export or onnxruntime.
    #[error(transparent)]
    Onnx(#[from] tactile_onnx::Error),
    /// The pose network.
    #[error(transparent)]
    Pose(#[from] tactile_pose::Error),
    /// A calibrated GelSight-like sensor.
    #[error(transparent)]
    Gelsight(#[from] tactile_gelsight::Error),
}

impl Error {
    /// The foundation error underneath, when there is one.
    pub fn core(&self) -> Option<&tactile_core::Error> {
        match self {
            Error::Core(e) => Some(e),
            Error::Preprocess(e) => e.core(),
            Error::Cae(e) => e.core(),
            Error::Estimate(e) => e.core(),
            Error::Detect(e) => e.core(),
            Error::Segment(e) => e.core(),
            Error::Depth(e) => e.core(),
            Error::Onnx(e) => e.core(),
            Error::Pose(e) => e.core(),
            Error::Gelsight(e) => e.core(),
        }
    }
}
