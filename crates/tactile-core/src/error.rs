//! The foundation's error type. Every crate of the workspace wraps it in its
//! own enum, so a user sees the same shape of message (which file, which
//! line, what is wrong) wherever it comes from, and a caller can match the
//! variant (a missing file, the wrong kind of model folder, a wrong shape)
//! instead of parsing text.

use std::path::{Path, PathBuf};

/// Result alias used across the workspace.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong with user data, files and models.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Reading or writing a file failed.
    #[error("{}: {source}", shown(path))]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// A file or folder that must exist does not.
    #[error("{}: {what} does not exist", shown(path))]
    NotFound {
        /// The missing path.
        path: PathBuf,
        /// What it should have been ("dataset folder", "weights file").
        what: String,
    },
    /// A folder holds something else than the command needs (a segmenter
    /// where a detector was asked for, a TacTip dataset for a palpation
    /// model).
    #[error("{}: not {} {expected} ({found})", shown(path), article(expected))]
    WrongKind {
        /// The folder or file.
        path: PathBuf,
        /// What was asked for.
        expected: String,
        /// What is there instead.
        found: String,
    },
    /// An image could not be decoded or has the wrong format or size.
    #[error("{}: {message}", shown(path))]
    Image {
        /// The image file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// A dataset file is malformed (a bad label, a bad manifest).
    #[error("{}{}: {message}", shown(path), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Dataset {
        /// The file (`labels.csv`, `manifest.json`, a depth map).
        path: PathBuf,
        /// 1-based line, when known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// A model or its configuration could not be loaded, saved or run.
    #[error("{}: {message}", shown(path))]
    Model {
        /// The model file or folder.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A tensor, image or array has the wrong shape.
    #[error("wrong shape for {what}: expected {expected}, found {found}")]
    Shape {
        /// What has the shape.
        what: String,
        /// The shape that was needed.
        expected: String,
        /// The shape that was given.
        found: String,
    },
    /// A configuration value is invalid.
    #[error("invalid configuration: {0}")]
    Config(String),
    /// Training produced a non-finite loss.
    #[error("{what} is {value}: training diverged")]
    Diverged {
        /// The quantity ("training loss").
        what: String,
        /// Its value (NaN or infinite).
        value: f64,
    },
    /// Stopped on request (Ctrl-C, SIGTERM): nothing half-written is left.
    #[error("interrupted: stopped before finishing, nothing partial was kept")]
    Interrupted,
    /// A ROS 2 bag (MCAP) could not be read: the container, a topic or
    /// one message.
    #[error("{}{}{}: {message}", shown(path),
        topic.as_ref().map(|t| format!(": topic {t}")).unwrap_or_default(),
        index.map(|i| format!(", message {i}")).unwrap_or_default())]
    Bag {
        /// The bag.
        path: PathBuf,
        /// The topic, when the problem is one topic's.
        topic: Option<String>,
        /// The message's index on its topic (0-based), when one message is bad.
        index: Option<u64>,
        /// What is wrong.
        message: String,
    },
    /// A path named as a file to read is a folder, a pipe or a device:
    /// refused before it is opened, as opening a pipe blocks until
    /// something writes to it and a device never ends.
    #[error(
        "{}: is not a regular file (a folder, a pipe or a device); refusing to read it",
        shown(path)
    )]
    NotRegularFile {
        /// The path.
        path: PathBuf,
    },
    /// A folder another run holds (its lock): a model trained or
    /// calibrated, or a page written, by another process right now.
    #[error(
        "{}: another run is writing this folder (training or calibrating a model, or writing a page there): wait for it to end, or give this run another output folder",
        shown(path)
    )]
    Busy {
        /// The folder.
        path: PathBuf,
    },
    /// Frames of a folder or dataset that cannot be read, found from their
    /// headers before any frame is decoded: the first one's refusal and
    /// how many.
    #[error(
        "{first}; {count} of the {total} frames cannot be read (not a picture or cut short, larger than 8K, not 8 bits per channel, or another size than the manifest's): no frame was processed, so mend or move them"
    )]
    UnreadableFrames {
        /// The first such frame's refusal.
        first: Box<Error>,
        /// Frames that cannot be read.
        count: usize,
        /// Frames checked.
        total: usize,
    },
    /// Any other invalid input, described in words.
    #[error("{0}")]
    Invalid(String),
}

/// A path as messages name it: an empty one (`""` from a blank variable or
/// form field) said so, instead of a message that starts with ": ".
pub fn shown(path: &Path) -> String {
    if path.as_os_str().is_empty() {
        "'' (an empty path)".into()
    } else {
        path.display().to_string()
    }
}

/// "an" before a vowel ("an estimator folder"), else "a": the one rule
/// every message that names a kind of thing uses.
pub fn article(noun: &str) -> &'static str {
    if noun.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    }
}

/// `check` every one of `frames` (stopping on a stop request), keeping
/// the first refusal and a count: `Ok` when none, the one alone, or
/// `many(first, count, total)`. The one loop behind every crate's check of
/// a set of frames before any is decoded, whatever its error type.
pub fn check_each<T, E: From<Error>>(
    frames: &[T],
    mut check: impl FnMut(&T) -> Result<(), E>,
    many: impl FnOnce(E, usize, usize) -> E,
) -> Result<(), E> {
    let (mut first, mut count) = (None, 0usize);
    for frame in frames {
        crate::interrupt::check()?;
        if let Err(e) = check(frame) {
            count += 1;
            first.get_or_insert(e);
        }
    }
    match first {
        None => Ok(()),
        Some(e) if count == 1 => Err(e),
        Some(e) => Err(many(e, count, frames.len())),
    }
}

impl Error {
    /// `check` every one of `frames` before any is decoded (stopping on
    /// a stop request), keeping the first refusal and a count, not every
    /// refusal: `Ok` when none, the one alone, or the first with how many
    /// ([`Error::UnreadableFrames`]).
    pub fn check_frames<T>(
        frames: &[T],
        check: impl FnMut(&T) -> Result<(), Self>,
    ) -> Result<(), Self> {
        check_each(frames, check, |first, count, total| {
            Error::UnreadableFrames {
                first: Box::new(first),
                count,
                total,
            }
        })
    }

    /// An I/O error on `path`.
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.as_ref().to_path_buf(),
            source,
        }
    }

    /// `path` (a `what`) does not exist.
    pub fn not_found(path: impl AsRef<Path>, what: impl Into<String>) -> Self {
        Error::NotFound {
            path: path.as_ref().to_path_buf(),
            what: what.into(),
        }
    }

    /// `path` is not a `expected`; it holds `found`.
    pub fn wrong_kind(
        path: impl AsRef<Path>,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> Self {
        Error::WrongKind {
            path: path.as_ref().to_path_buf(),
            expected: expected.into(),
            found: found.into(),
        }
    }

    /// An image error on `path`.
    pub fn image(path: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Error::Image {
            path: path.as_ref().to_path_buf(),
            message: message.into(),
        }
    }

    /// A dataset error on `path`, optionally at a 1-based `line`.
    pub fn dataset(
        path: impl AsRef<Path>,
        line: Option<usize>,
        message: impl Into<String>,
    ) -> Self {
        Error::Dataset {
            path: path.as_ref().to_path_buf(),
            line,
            message: message.into(),
        }
    }

    /// A model error on `path`.
    pub fn model(path: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Error::Model {
            path: path.as_ref().to_path_buf(),
            message: message.into(),
        }
    }

    /// A shape mismatch.
    pub fn shape(what: impl Into<String>, expected: impl ToString, found: impl ToString) -> Self {
        Error::Shape {
            what: what.into(),
            expected: expected.to_string(),
            found: found.to_string(),
        }
    }

    /// True when the error is a missing file or folder (the front ends map
    /// it to "file not found", e.g. Python's `FileNotFoundError`).
    pub fn is_not_found(&self) -> bool {
        match self {
            Error::NotFound { .. } => true,
            Error::Io { source, .. } => source.kind() == std::io::ErrorKind::NotFound,
            _ => false,
        }
    }
}

/// Refuse a configuration error of a loaded config, naming its `file`.
pub fn in_config<T>(file: &Path, r: Result<T>) -> Result<T> {
    r.map_err(|e| match e {
        Error::Config(m) => Error::model(file, m),
        other => other,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_file_and_line() {
        let e = Error::dataset(
            "ds/labels.csv",
            Some(7),
            "column 'x_mm': 'a' is not a number",
        );
        assert_eq!(
            e.to_string(),
            "ds/labels.csv:7: column 'x_mm': 'a' is not a number"
        );
        let e = Error::wrong_kind("models/segmenter", "detector folder", "no detector.json");
        assert!(e.to_string().contains("not a detector folder"));
        assert!(Error::not_found("x", "dataset folder").is_not_found());
        assert!(Error::io("x", std::io::Error::from(std::io::ErrorKind::NotFound)).is_not_found());
        assert!(!Error::Invalid("x".into()).is_not_found());
    }
}
