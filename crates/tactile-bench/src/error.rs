//! What can go wrong measuring.

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors of the benches: those of everything they measure.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Anything the composed models can fail with.
    #[error(transparent)]
    Pipeline(#[from] tactile_pipeline::Error),
    /// A file, dataset or configuration problem.
    #[error(transparent)]
    Core(#[from] tactile_core::Error),
    /// Ball-press calibration.
    #[error(transparent)]
    Gelsight(#[from] tactile_gelsight::Error),
    /// The virtual sensors.
    #[error(transparent)]
    Synth(#[from] datasets_synth::Error),
}

macro_rules! via_pipeline {
    ($($t:ty),*) => {$(
        impl From<$t> for Error {
            fn from(e: $t) -> Self {
                Error::Pipeline(e.into())
            }
        }
    )*};
}
via_pipeline!(
    tactile_preprocess::Error,
    tactile_cae::Error,
    tactile_estimate::Error,
    tactile_detect::Error,
    tactile_segment::Error,
    tactile_depth::Error,
    tactile_onnx::Error,
    tactile_pose::Error
);

impl Error {
    /// The foundation error underneath, when there is one.
    pub fn core(&self) -> Option<&tactile_core::Error> {
        match self {
            Error::Core(e) => Some(e),
            Error::Pipeline(e) => e.core(),
            Error::Gelsight(e) => e.core(),
            Error::Synth(_) => None,
        }
    }
}
