//! What can go wrong training, loading or running the detector.

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors of the tendon detector.
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
    /// Frames loaded at another size than the detector's input.
    #[error("frames were loaded at {}x{}, the detector takes {}x{}", found[0], found[1], expected[0], expected[1])]
    InputSize {
        /// The detector's input, width and height.
        expected: [usize; 2],
        /// The frames'.
        found: [usize; 2],
    },
}

impl Error {
    /// The foundation error underneath, when there is one.
    pub fn core(&self) -> Option<&tactile_core::Error> {
        match self {
            Error::Core(e) => Some(e),
            Error::Preprocess(e) => e.core(),
            Error::Onnx(e) => e.core(),
            Error::InputSize { .. } => None,
        }
    }
}
