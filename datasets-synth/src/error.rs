//! What can go wrong generating a dataset.

use std::path::PathBuf;

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors of the virtual sensors and the dataset writer.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A configuration, file or image problem.
    #[error(transparent)]
    Core(#[from] tactile_core::Error),
    /// The output folder holds files and `force` was not given.
    #[error("{}: output folder exists and is not empty (use --force to overwrite)", path.display())]
    OutputNotEmpty {
        /// The folder.
        path: PathBuf,
    },
    /// `--force` on a non-empty folder that is not a dataset.
    #[error("{}: not a dataset (no manifest.json): --force replaces only a dataset folder or an empty one, never other files", path.display())]
    NotADataset {
        /// The folder.
        path: PathBuf,
    },
    /// The output path is a file.
    #[error("{}: output exists and is a file, a pipe or a device, not a folder", path.display())]
    OutputIsFile {
        /// The file.
        path: PathBuf,
    },
}
