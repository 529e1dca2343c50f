//! What can go wrong training, loading or running the pose network.

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors of the pose network.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file, dataset, model folder or configuration problem.
    #[error(transparent)]
    Core(#[from] tactile_core::Error),
    /// A frame that could not be made into a pin image.
    #[error(transparent)]
    Preprocess(#[from] tactile_preprocess::Error),
    /// Export or onnxruntime.
    #[error(transparent)]
    Onnx(#[from] tactile_onnx::Error),
    /// Loading the frames (shared with the autoencoder).
    #[error(transparent)]
    Cae(#[from] tactile_cae::Error),
    /// A target specification.
    #[error(transparent)]
    Estimate(#[from] tactile_estimate::Error),
}

impl Error {
    /// The foundation error underneath, when there is one.
    pub fn core(&self) -> Option<&tactile_core::Error> {
        match self {
            Error::Core(e) => Some(e),
            Error::Preprocess(e) => e.core(),
            Error::Onnx(e) => e.core(),
            Error::Cae(e) => e.core(),
            Error::Estimate(e) => e.core(),
        }
    }
}
