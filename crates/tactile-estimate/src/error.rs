//! What can go wrong training, loading or running an estimator.

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors of the estimators.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file, model folder or configuration problem.
    #[error(transparent)]
    Core(#[from] tactile_core::Error),
    /// Feature vectors of another length than the estimator's inputs
    /// (features of another encoder, for one).
    #[error("feature vectors have {found} values, the estimator takes {expected}")]
    Features {
        /// The estimator's input count.
        expected: usize,
        /// The vectors'.
        found: usize,
    },
    /// Too few samples to train on.
    #[error("{0}")]
    TooFewSamples(String),
    /// A folder with no estimator in it.
    #[error("no estimators: {0}")]
    NoEstimators(String),
    /// A linfa model failed.
    #[error("{what}: {message}")]
    Linfa {
        /// Which model.
        what: String,
        /// linfa's message.
        message: String,
    },
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
