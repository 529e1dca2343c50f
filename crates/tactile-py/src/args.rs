//! Keywords as the caller gave them, each read under its name where it is
//! used, so a wrong one's error names it: whole numbers (threads,
//! pipelines, limits, queues, repeats, seeds, stamps) with their range
//! ([`Whole::within`]), paths ([`PathArg`]) and any other value ([`Given`])
//! through [`keywords!`].
//! PyO3's own conversions say only "can't convert negative int to
//! unsigned", "'float' object cannot be interpreted as an integer" or
//! "expected str, bytes or os.PathLike object, not int": the keyword is a
//! note a traceback shows from Python 3.11, and nowhere before it (ROS 2
//! Humble's Python is 3.10).

use pyo3::exceptions::{PyOverflowError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBool;
use std::path::PathBuf;

/// A whole-number argument as the caller gave it; [`Whole::within`] makes
/// it a number or an error naming the keyword.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Whole {
    /// An `int`, a numpy integer or anything else with `__index__`.
    Int(i128),
    /// An integer beyond 128 bits: `str()` of it, for the message.
    Huge(String),
    /// Not a whole number (a float, a string, a bool): its type's name.
    Not(String),
}

impl Whole {
    /// The default of a keyword.
    pub(crate) const fn of(value: u64) -> Self {
        Self::Int(value as i128)
    }

    /// The number, if it is a whole number from `min` to `max`; else a
    /// `ValueError` ("threads: must be 1 to 64, got -1") or a `TypeError`
    /// ("threads: expected a whole number, got float") naming `name`.
    pub(crate) fn within<T>(&self, name: &str, min: T, max: T) -> PyResult<T>
    where
        T: Copy + Bounded + TryFrom<i128> + std::fmt::Display + PartialEq,
    {
        // A range open at the top reads "at least 1", unless the number is
        // past the type's end ("at most 18446744073709551615").
        let refuse = |too_large: bool, got: &dyn std::fmt::Display| {
            let range = match (max == T::MAX, too_large) {
                (false, _) => format!("{min} to {max}"),
                (true, false) => format!("at least {min}"),
                (true, true) => format!("at most {max}"),
            };
            PyValueError::new_err(format!("{name}: must be {range}, got {got}"))
        };
        match self {
            Self::Int(v) if *v < min.wide() => Err(refuse(false, v)),
            Self::Int(v) => T::try_from(*v)
                .ok()
                .filter(|_| *v <= max.wide())
                .ok_or_else(|| refuse(true, v)),
            Self::Huge(text) => Err(refuse(!text.starts_with('-'), text)),
            Self::Not(t) => Err(PyTypeError::new_err(format!(
                "{name}: expected a whole number, got {t}"
            ))),
        }
    }
}

/// An integer type a keyword is read into: its largest value, so a range
/// without an upper bound reads "at least 1", and its values as `i128`s,
/// which hold every one of them.
pub(crate) trait Bounded: Sized {
    /// The type's largest value.
    const MAX: Self;
    /// The value as an `i128`.
    fn wide(self) -> i128;
}

macro_rules! bounded {
    ($($t:ty),*) => {$(
        impl Bounded for $t {
            const MAX: Self = <$t>::MAX;
            fn wide(self) -> i128 {
                self as i128
            }
        }
    )*};
}

bounded!(u64, i64, usize);

impl<'a, 'py> FromPyObject<'a, 'py> for Whole {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        // A bool is an int to Python, and `threads=True` is a mistake.
        if obj.is_instance_of::<PyBool>() {
            return Ok(Self::Not("bool".into()));
        }
        match obj.extract::<i128>() {
            Ok(v) => Ok(Self::Int(v)),
            // Python will not print an int of more than 4300 digits.
            Err(e) if e.is_instance_of::<PyOverflowError>(obj.py()) => {
                Ok(Self::Huge(obj.str().map_or_else(
                    |_| "an integer of thousands of digits".into(),
                    |s| s.to_string(),
                )))
            }
            Err(_) => Ok(Self::Not(obj.get_type().name()?.to_string())),
        }
    }
}

/// An optional whole number (`limit=None`): `None` stays `None`.
pub(crate) fn optional<T>(arg: Option<&Whole>, name: &str, min: T, max: T) -> PyResult<Option<T>>
where
    T: Copy + Bounded + TryFrom<i128> + std::fmt::Display + PartialEq,
{
    arg.map(|w| w.within(name, min, max)).transpose()
}

/// A path argument (a `str`, `bytes` or `os.PathLike`) as the caller gave
/// it; [`Keyword::read`] makes it a path or a `TypeError` naming the
/// keyword ("data: expected a path (str, bytes or os.PathLike), got
/// ndarray").
#[derive(Clone, Debug)]
pub(crate) struct PathArg(Result<PathBuf, String>);

impl PathArg {
    /// The default of a keyword.
    pub(crate) fn of(default: &str) -> Self {
        Self(Ok(PathBuf::from(default)))
    }
}

impl<'a, 'py> FromPyObject<'a, 'py> for PathArg {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        match obj.extract::<PathBuf>() {
            Ok(path) => Ok(Self(Ok(path))),
            // PyO3 reads `str` paths; `bytes` (as `os.listdir(b".")` gives
            // names) are the file system's own bytes, as Python's `open`
            // takes them. Anything else is not a path; an `os.PathLike`
            // whose `__fspath__` fails raises its own error.
            Err(e) if e.is_instance_of::<PyTypeError>(obj.py()) => {
                let fspath = obj.py().import("os")?.getattr("fspath")?;
                match fspath.call1((obj,)) {
                    Ok(given) => match given.cast::<pyo3::types::PyBytes>() {
                        Ok(bytes) => {
                            use std::os::unix::ffi::OsStrExt;
                            let name = std::ffi::OsStr::from_bytes(bytes.as_bytes());
                            Ok(Self(Ok(PathBuf::from(name))))
                        }
                        Err(_) => Err(e),
                    },
                    Err(not) if not.is_instance_of::<PyTypeError>(obj.py()) => {
                        Ok(Self(Err(obj.get_type().name()?.to_string())))
                    }
                    Err(other) => Err(other),
                }
            }
            Err(e) => Err(e),
        }
    }
}

/// Paths given as a list, or one given alone (a list of one).
pub(crate) struct PathList(Result<Vec<PathArg>, String>);

impl PathList {
    /// No paths: the default of a keyword.
    pub(crate) fn none() -> Self {
        Self(Ok(Vec::new()))
    }
}

impl<'a, 'py> FromPyObject<'a, 'py> for PathList {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let alone = obj.is_instance_of::<pyo3::types::PyString>()
            || obj.is_instance_of::<pyo3::types::PyBytes>()
            || obj.hasattr("__fspath__")?;
        if alone {
            return Ok(Self(Ok(vec![obj.extract::<PathArg>()?])));
        }
        match obj.extract::<Vec<PathArg>>() {
            Ok(paths) => Ok(Self(Ok(paths))),
            Err(e) if e.is_instance_of::<PyTypeError>(obj.py()) => {
                Ok(Self(Err(obj.get_type().name()?.to_string())))
            }
            Err(e) => Err(e),
        }
    }
}

/// An argument read under its keyword: a path ([`PathArg`]), any other
/// value ([`Given`]), an optional one (`None` stays `None`) or a list
/// (each item named by its place, "heads[1]").
pub(crate) trait Keyword {
    /// What the argument holds.
    type Value;
    /// The value, or the refusal naming `name`.
    fn read(self, name: &str) -> PyResult<Self::Value>;
}

impl Keyword for PathArg {
    type Value = PathBuf;

    fn read(self, name: &str) -> PyResult<PathBuf> {
        self.0.map_err(|got| {
            PyTypeError::new_err(format!(
                "{name}: expected a path (str, bytes or os.PathLike), got {got}"
            ))
        })
    }
}

impl Keyword for PathList {
    type Value = Vec<PathBuf>;

    fn read(self, name: &str) -> PyResult<Vec<PathBuf>> {
        match self.0 {
            Ok(paths) => paths.read(name),
            Err(got) => Err(PyTypeError::new_err(format!(
                "{name}: expected a path or a list of paths, got {got}"
            ))),
        }
    }
}

impl<K: Keyword> Keyword for Option<K> {
    type Value = Option<K::Value>;

    fn read(self, name: &str) -> PyResult<Self::Value> {
        self.map(|k| k.read(name)).transpose()
    }
}

impl<K: Keyword> Keyword for Vec<K> {
    type Value = Vec<K::Value>;

    fn read(self, name: &str) -> PyResult<Self::Value> {
        self.into_iter()
            .enumerate()
            .map(|(i, k)| k.read(&format!("{name}[{i}]")))
            .collect()
    }
}

/// Any other argument (a string, a flag, a number, a pair) as PyO3
/// converts it, a refusal kept for [`Keyword::read`] to name the keyword:
/// "force: 'int' object is not an instance of 'bool'".
pub(crate) struct Given<T>(Result<T, PyErr>);

impl<T> Given<T> {
    /// The default of a keyword.
    pub(crate) fn of(default: impl Into<T>) -> Self {
        Self(Ok(default.into()))
    }
}

impl<'a, 'py, T: FromPyObject<'a, 'py>> FromPyObject<'a, 'py> for Given<T> {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        Ok(Self(obj.extract::<T>().map_err(Into::into)))
    }
}

impl<T> Keyword for Given<T> {
    type Value = T;

    fn read(self, name: &str) -> PyResult<T> {
        self.0.map_err(|e| {
            Python::attach(|py| {
                let why = e.value(py).str().map(|s| s.to_string()).unwrap_or_default();
                if e.is_instance_of::<PyTypeError>(py) {
                    PyTypeError::new_err(format!("{name}: {why}"))
                } else if e.is_instance_of::<PyValueError>(py) {
                    PyValueError::new_err(format!("{name}: {why}"))
                } else if e.is_instance_of::<PyOverflowError>(py) {
                    // A number past the type's range (`view_wait=10**400`).
                    PyOverflowError::new_err(format!("{name}: {why}"))
                } else {
                    e
                }
            })
        })
    }
}

/// `keywords!(data, out, runtime)`: each argument read under its own name
/// ([`Keyword::read`]), shadowing it; the first wrong one's error.
macro_rules! keywords {
    ($($name:ident),+ $(,)?) => {
        $(
            let $name = $crate::args::Keyword::read($name, stringify!($name))?;
        )+
    };
}
pub(crate) use keywords;
