//! What can go wrong training, loading or running the segmenter.

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors of the tendon segmenter.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file, dataset, model folder or configuration problem.
    #[error(transparent)]
    Core(#[from] tactile_core::Error),
    /// A frame that could not be made into the network's input.
    #[error(transparent)]
    Preprocess(#[from] tactile_preprocess::Error),
    /// Export or onnxruntime.
    #[error(transparent)]
    Onnx(#[from] tactile_onnx::Error),
    /// A window or mask of another size than the segmenter's.
    #[error("{what} is {}x{}, the segmenter takes {}x{}", found[0], found[1], expected[0], expected[1])]
    WindowSize {
        /// What had the size.
        what: &'static str,
        /// The segmenter's.
        expected: [usize; 2],
        /// What was given.
        found: [usize; 2],
    },
    /// A dataset without a tendon frame to train or score on.
    #[error("{}: no tendon frames to {why}", path.display())]
    NoTendonFrames {
        /// Its `labels.csv`.
        path: std::path::PathBuf,
        /// What they were needed for.
        why: &'static str,
    },
}

impl Error {
    /// The foundation error underneath, when there is one.
    pub fn core(&self) -> Option<&tactile_core::Error> {
        match self {
            Error::Core(e) => Some(e),
            Error::Preprocess(e) => e.core(),
            Error::Onnx(e) => e.core(),
            _ => None,
        }
    }
}
