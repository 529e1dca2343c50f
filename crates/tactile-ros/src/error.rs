use std::path::PathBuf;

/// What can go wrong writing results to MCAP or serving them live.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The MCAP file could not be written.
    #[error("{}: cannot write MCAP results: {message}", path.display())]
    Write {
        /// The output file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A message could not be encoded (a value CDR cannot hold).
    #[error("cannot encode {topic}: {message}")]
    Encode {
        /// The topic.
        topic: String,
        /// What went wrong.
        message: String,
    },
    /// The live view's address is not `HOST:PORT`.
    #[error("live view at {address}: {message}")]
    Address {
        /// The address given.
        address: String,
        /// What is wrong.
        message: String,
    },
    /// The live view could not start (the address is taken or cannot be bound).
    #[error("live view at {address}: {message}")]
    Live {
        /// The address asked for.
        address: String,
        /// What went wrong.
        message: String,
    },
    /// The foundation's errors (an unwritable folder, an interrupt).
    #[error(transparent)]
    Core(#[from] tactile_core::Error),
    /// The pipeline's errors in a run (a model that does not load, a
    /// frame it cannot take).
    #[error(transparent)]
    Pipeline(#[from] Box<tactile_pipeline::Error>),
}

/// This crate's results.
pub type Result<T> = std::result::Result<T, Error>;

impl From<Error> for tactile_core::Error {
    fn from(e: Error) -> Self {
        match e {
            Error::Core(e) => e,
            Error::Pipeline(p) => match *p {
                tactile_pipeline::Error::Core(c) => c,
                other => tactile_core::Error::Invalid(other.to_string()),
            },
            other => tactile_core::Error::Invalid(other.to_string()),
        }
    }
}
