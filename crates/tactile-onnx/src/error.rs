//! What can go wrong exporting a network or running it in onnxruntime.

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors of ONNX export and onnxruntime.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file, model folder or configuration problem.
    #[error(transparent)]
    Core(#[from] tactile_core::Error),
    /// burn-onnx could not lower the network.
    #[error("ONNX export failed: {0}")]
    Export(String),
    /// The onnxruntime library is missing or cannot start.
    #[error("{0}")]
    Library(String),
    /// onnxruntime refused the model or failed to run it.
    #[error("onnxruntime: {0}")]
    Run(String),
}

impl Error {
    /// The foundation error underneath, when there is one.
    pub fn core(&self) -> Option<&tactile_core::Error> {
        match self {
            Error::Core(e) => Some(e),
            _ => None,
        }
    }
}

impl From<Error> for tactile_core::Error {
    /// For [`tactile_burn::Network::run`], whose errors are the foundation's.
    fn from(e: Error) -> Self {
        match e {
            Error::Core(c) => c,
            other => tactile_core::Error::Invalid(other.to_string()),
        }
    }
}
