//! The library's errors as Python exceptions of fitting types, with the
//! message the command line prints: a missing file or folder is a
//! `FileNotFoundError`, an unreadable one (or a pipe, a device or a
//! folder where a file is read) an `OSError`, an output folder
//! that holds other files a `FileExistsError`, a model folder another run
//! is writing a `BlockingIOError`, a stop request a
//! `KeyboardInterrupt`; onnxruntime missing or failing, a diverged or
//! stalled training a `RuntimeError`; anything wrong with the input (a bad
//! label, a model config out of range, a frame of the wrong shape) a
//! `ValueError`.

use pyo3::PyErr;
use pyo3::exceptions::{
    PyBlockingIOError, PyFileExistsError, PyFileNotFoundError, PyKeyboardInterrupt,
    PyNotADirectoryError, PyOSError, PyPermissionError, PyRuntimeError, PyValueError,
};

/// What kind of Python exception an error is.
#[derive(Clone, Copy)]
pub(crate) enum Kind {
    NotFound,
    Exists,
    NotADirectory,
    Permission,
    Os,
    Interrupt,
    Busy,
    Runtime,
    Value,
}

fn core_kind(e: &tactile_core::Error) -> Kind {
    use tactile_core::Error as E;
    match e {
        E::NotFound { .. } => Kind::NotFound,
        E::Interrupted => Kind::Interrupt,
        E::Io { source, .. } => match source.kind() {
            std::io::ErrorKind::NotFound => Kind::NotFound,
            std::io::ErrorKind::PermissionDenied => Kind::Permission,
            _ => Kind::Os,
        },
        // As Python's own `open` of a folder is an `IsADirectoryError`.
        E::NotRegularFile { .. } => Kind::Os,
        // As Python's own `fcntl.flock(..., LOCK_NB)` of a held lock.
        E::Busy { .. } => Kind::Busy,
        E::Diverged { .. } => Kind::Runtime,
        _ => Kind::Value,
    }
}

fn onnx_kind(e: &tactile_onnx::Error) -> Kind {
    match e {
        tactile_onnx::Error::Core(c) => core_kind(c),
        _ => Kind::Runtime,
    }
}

fn preprocess_kind(e: &tactile_preprocess::Error) -> Kind {
    use tactile_preprocess::Error as E;
    match e {
        E::Core(c) => core_kind(c),
        E::File { error, .. } | E::Frame { error, .. } => preprocess_kind(error),
        E::Kornia(_) => Kind::Runtime,
        _ => Kind::Value,
    }
}

/// An error of one of the library's crates.
pub(crate) trait LibraryError: std::fmt::Display {
    /// Which exception it becomes.
    fn kind(&self) -> Kind;
}

impl LibraryError for tactile_core::Error {
    fn kind(&self) -> Kind {
        core_kind(self)
    }
}

impl LibraryError for tactile_preprocess::Error {
    fn kind(&self) -> Kind {
        preprocess_kind(self)
    }
}

impl LibraryError for tactile_cae::Error {
    fn kind(&self) -> Kind {
        use tactile_cae::Error as E;
        match self {
            E::Core(c) => core_kind(c),
            E::Preprocess(p) => preprocess_kind(p),
            E::Onnx(o) => onnx_kind(o),
            _ => Kind::Value,
        }
    }
}

impl LibraryError for tactile_ros::Error {
    fn kind(&self) -> Kind {
        use tactile_ros::Error as E;
        match self {
            E::Core(c) => core_kind(c),
            E::Write { .. } | E::Live { .. } => Kind::Os,
            E::Encode { .. } | E::Address { .. } => Kind::Value,
            E::Pipeline(p) => p.kind(),
        }
    }
}

impl LibraryError for tactile_gelsight::Error {
    fn kind(&self) -> Kind {
        use tactile_gelsight::Error as E;
        match self {
            E::Core(c) => core_kind(c),
            E::Onnx(o) => onnx_kind(o),
            E::Synth(s) => s.kind(),
            _ => Kind::Value,
        }
    }
}

impl LibraryError for tactile_estimate::Error {
    fn kind(&self) -> Kind {
        use tactile_estimate::Error as E;
        match self {
            E::Core(c) => core_kind(c),
            E::Linfa { .. } => Kind::Runtime,
            _ => Kind::Value,
        }
    }
}

impl LibraryError for tactile_detect::Error {
    fn kind(&self) -> Kind {
        use tactile_detect::Error as E;
        match self {
            E::Core(c) => core_kind(c),
            E::Preprocess(p) => preprocess_kind(p),
            E::Onnx(o) => onnx_kind(o),
            _ => Kind::Value,
        }
    }
}

impl LibraryError for tactile_segment::Error {
    fn kind(&self) -> Kind {
        use tactile_segment::Error as E;
        match self {
            E::Core(c) => core_kind(c),
            E::Preprocess(p) => preprocess_kind(p),
            E::Onnx(o) => onnx_kind(o),
            _ => Kind::Value,
        }
    }
}

impl LibraryError for tactile_depth::Error {
    fn kind(&self) -> Kind {
        use tactile_depth::Error as E;
        match self {
            E::Core(c) => core_kind(c),
            E::Preprocess(p) => preprocess_kind(p),
            E::Onnx(o) => onnx_kind(o),
            E::Stall { .. } => Kind::Runtime,
            _ => Kind::Value,
        }
    }
}

impl LibraryError for tactile_pose::Error {
    fn kind(&self) -> Kind {
        use tactile_pose::Error as E;
        match self {
            E::Core(c) => core_kind(c),
            E::Preprocess(p) => preprocess_kind(p),
            E::Onnx(o) => onnx_kind(o),
            E::Cae(e) => e.kind(),
            E::Estimate(e) => e.kind(),
        }
    }
}

impl LibraryError for tactile_pipeline::Error {
    fn kind(&self) -> Kind {
        use tactile_pipeline::Error as E;
        match self {
            E::Core(c) => core_kind(c),
            E::Preprocess(e) => e.kind(),
            E::Cae(e) => e.kind(),
            E::Estimate(e) => e.kind(),
            E::Detect(e) => e.kind(),
            E::Segment(e) => e.kind(),
            E::Depth(e) => e.kind(),
            E::Onnx(e) => onnx_kind(e),
            E::Pose(e) => e.kind(),
            E::Gelsight(e) => e.kind(),
        }
    }
}

impl LibraryError for tactile_bench::Error {
    fn kind(&self) -> Kind {
        use tactile_bench::Error as E;
        match self {
            E::Pipeline(e) => e.kind(),
            E::Core(c) => core_kind(c),
            E::Gelsight(e) => e.kind(),
            E::Synth(e) => e.kind(),
        }
    }
}

impl LibraryError for datasets_synth::Error {
    fn kind(&self) -> Kind {
        use datasets_synth::Error as E;
        match self {
            E::Core(c) => core_kind(c),
            E::OutputIsFile { .. } => Kind::NotADirectory,
            E::OutputNotEmpty { .. } | E::NotADataset { .. } => Kind::Exists,
        }
    }
}

/// The Python exception for a library error, what it quotes of a file
/// shown `tactile_core::printable` (as Python's own `OSError` shows a file
/// name by its `repr`).
pub(crate) fn to_py<E: LibraryError>(e: E) -> PyErr {
    let msg = tactile_core::printable(&e.to_string()).into_owned();
    match e.kind() {
        Kind::NotFound => PyFileNotFoundError::new_err(msg),
        Kind::Exists => PyFileExistsError::new_err(msg),
        Kind::NotADirectory => PyNotADirectoryError::new_err(msg),
        Kind::Permission => PyPermissionError::new_err(msg),
        Kind::Os => PyOSError::new_err(msg),
        Kind::Interrupt => PyKeyboardInterrupt::new_err(msg),
        Kind::Busy => PyBlockingIOError::new_err(msg),
        Kind::Runtime => PyRuntimeError::new_err(msg),
        Kind::Value => PyValueError::new_err(msg),
    }
}

/// `.py()` on a library result: its error as a Python exception.
pub(crate) trait PyResultExt<T> {
    /// Map the error with [`to_py`].
    fn py(self) -> pyo3::PyResult<T>;
}

impl<T, E: LibraryError> PyResultExt<T> for Result<T, E> {
    fn py(self) -> pyo3::PyResult<T> {
        self.map_err(to_py)
    }
}

/// `msg` as a Python `UserWarning`: what the command line notes on
/// standard error (a notebook shows warnings, not the process's stderr),
/// without the note's leading `warning: `, which the category says.
pub(crate) fn user_warning(py: pyo3::Python<'_>, msg: &str) -> pyo3::PyResult<()> {
    let msg = msg.strip_prefix("warning: ").unwrap_or(msg);
    // Escaped, a NUL is no longer one, so the text is always a C string.
    let text = std::ffi::CString::new(tactile_core::printable(msg).as_bytes()).unwrap_or_default();
    PyErr::warn(
        py,
        py.get_type::<pyo3::exceptions::PyUserWarning>().as_any(),
        &text,
        1,
    )
}
