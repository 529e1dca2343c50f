//! Library records and scores (serde) to Python objects, through the
//! standard library's `json` module: the same keys and values the command
//! line prints as JSON.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// `value` as the Python object `json.loads` makes of its JSON.
pub(crate) fn to_py<'py, T: serde::Serialize + ?Sized>(
    py: Python<'py>,
    value: &T,
) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(|e| PyValueError::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// Keyword arguments onto an options type of the library
/// ([`tactile_burn::options::Options`]): through JSON, so a tuple is a
/// list and None keeps the default; `config=` names an options file the
/// keywords override (as `--config` on the command line); an unknown
/// keyword or a value of the wrong type is a `ValueError` naming it.
pub(crate) fn options<'py, T: tactile_burn::options::Options>(
    py: Python<'py>,
    kwargs: Option<&Bound<'py, pyo3::types::PyDict>>,
) -> PyResult<T> {
    let mut map: serde_json::Map<String, serde_json::Value> = match kwargs {
        None => serde_json::Map::new(),
        Some(d) => {
            let d = d.copy()?;
            let os = py.import("os")?;
            let path_like = os.getattr("PathLike")?;
            for (k, v) in d.iter() {
                // Paths become strings, as JSON has them.
                if v.is_instance(&path_like)? {
                    d.set_item(k, os.call_method1("fspath", (v,))?)?;
                }
            }
            let text: String = py.import("json")?.call_method1("dumps", (d,))?.extract()?;
            serde_json::from_str(&text).map_err(|e| PyValueError::new_err(e.to_string()))?
        }
    };
    let config = match map.remove("config") {
        None | Some(serde_json::Value::Null) => None,
        Some(serde_json::Value::String(p)) => Some(std::path::PathBuf::from(p)),
        Some(other) => {
            return Err(PyValueError::new_err(format!(
                "config: an options file's path, got {other}"
            )));
        }
    };
    use crate::errors::PyResultExt;
    T::resolve(config.as_deref(), &map).py()
}
