//! What can go wrong while turning a frame into a model input.

use std::path::PathBuf;

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors of preprocessing.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file, dataset or configuration problem.
    #[error(transparent)]
    Core(#[from] tactile_core::Error),
    /// A frame too small for the requested output.
    #[error("frame is {width}x{height}, smaller than the {needed}x{needed} pin image")]
    FrameTooSmall {
        /// Frame width.
        width: usize,
        /// Frame height.
        height: usize,
        /// Side of the pin image.
        needed: usize,
    },
    /// An empty image, or one larger than 8K.
    #[error("{width}x{height} image: {why}")]
    ImageSize {
        /// Width.
        width: usize,
        /// Height.
        height: usize,
        /// Empty, or larger than the limit.
        why: String,
    },
    /// An image with another channel count than the model's.
    #[error("image has {found} channels, the model expects {expected}")]
    Channels {
        /// The model's channel count.
        expected: usize,
        /// The image's.
        found: usize,
    },
    /// A preset name that is not one of the presets nor a JSON file.
    #[error(
        "unknown preprocessing preset '{0}': expected paper, lighting-compensated, binary or a JSON file of a PreprocessConfig"
    )]
    UnknownPreset(String),
    /// An image operation of kornia failed.
    #[error("image operation failed: {0}")]
    Kornia(String),
    /// Any of the above, in the frame at `index` of a batch given in memory.
    #[error("frames[{index}]: {error}")]
    Frame {
        /// The frame's place in the batch.
        index: usize,
        /// What went wrong with it (in the message, not a `source`, so a
        /// chain printed whole does not say it twice).
        error: Box<Error>,
    },
    /// Any of the above, in a named file.
    #[error("{}: {error}", path.display())]
    File {
        /// The frame.
        path: PathBuf,
        /// What went wrong with it (in the message, not a `source`, so a
        /// chain printed whole does not say it twice).
        error: Box<Error>,
    },
}

impl Error {
    /// `self`, naming the file it happened in.
    pub fn in_file(self, path: impl Into<PathBuf>) -> Self {
        match self {
            // A file error already names its file.
            Error::Core(
                e @ (tactile_core::Error::Io { .. }
                | tactile_core::Error::Image { .. }
                | tactile_core::Error::NotFound { .. }
                | tactile_core::Error::NotRegularFile { .. }
                | tactile_core::Error::UnreadableFrames { .. }),
            ) => Error::Core(e),
            other => Error::File {
                path: path.into(),
                error: Box::new(other),
            },
        }
    }

    /// A batch's frame error renumbered for a batch that is the part,
    /// starting at `first`, of a longer one (a call's frames taken a chunk
    /// at a time).
    pub fn frame_from(self, first: usize) -> Self {
        match self {
            Error::Frame { index, error } => Error::Frame {
                index: first + index,
                error,
            },
            other => other,
        }
    }

    /// A batch's frame error named by `name` of its place in the batch
    /// (its file, or its number in a stream) instead of by the place.
    pub fn name_frame(self, name: impl FnOnce(usize) -> Option<String>) -> Self {
        match self {
            Error::Frame { index, error } => match name(index) {
                Some(name) => error.in_file(name),
                None => Error::Frame { index, error },
            },
            other => other,
        }
    }

    /// The foundation error underneath, when there is one.
    pub fn core(&self) -> Option<&tactile_core::Error> {
        match self {
            Error::Core(e) => Some(e),
            Error::File { error, .. } | Error::Frame { error, .. } => error.core(),
            _ => None,
        }
    }
}

impl From<kornia_image::ImageError> for Error {
    fn from(e: kornia_image::ImageError) -> Self {
        Error::Kornia(e.to_string())
    }
}
