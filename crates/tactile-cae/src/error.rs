//! What can go wrong training, loading or running the autoencoder.

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors of the autoencoder.
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
    /// A feature count the architecture cannot give.
    #[error(
        "feature count {features} must be a positive multiple of {cells} (the latent map's cells)"
    )]
    FeatureCount {
        /// What was asked for.
        features: usize,
        /// Cells of the latent map.
        cells: usize,
    },
}

impl Error {
    /// The foundation error underneath, when there is one.
    pub fn core(&self) -> Option<&tactile_core::Error> {
        match self {
            Error::Core(e) => Some(e),
            Error::Preprocess(e) => e.core(),
            Error::Onnx(e) => e.core(),
            Error::FeatureCount { .. } => None,
        }
    }
}
