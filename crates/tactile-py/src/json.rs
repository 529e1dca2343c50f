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

/// A value JSON has no type for as the one it stands for: a path
/// (`data=Path(...)`, `heads=[Path(...)]`) its string, a numpy value the
/// Python one; `None` for any other value.
fn as_plain<'py>(value: &Bound<'py, PyAny>) -> PyResult<Option<Bound<'py, PyAny>>> {
    let py = value.py();
    let os = py.import("os")?;
    if value.is_instance(&os.getattr("PathLike")?)? {
        return os.call_method1("fspath", (value,)).map(Some);
    }
    let numpy = py.import("numpy")?;
    if value.is_instance(&numpy.getattr("ndarray")?)?
        || value.is_instance(&numpy.getattr("generic")?)?
    {
        return value.call_method0("tolist").map(Some);
    }
    Ok(None)
}

/// `json.dumps`'s `default` for a value inside a keyword's list or dict
/// ([`as_plain`]); anything else gets the `TypeError` `json` itself gives.
#[pyfunction]
fn json_default<'py>(value: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    as_plain(value)?.ok_or_else(|| {
        let name = value
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_default();
        pyo3::exceptions::PyTypeError::new_err(format!(
            "Object of type {name} is not JSON serializable"
        ))
    })
}

/// Whether `value`, or a value in it (a list's, a tuple's, a dict's), is a
/// whole number past 64 bits, which JSON would read as a float ("invalid
/// type: floating point"), so it is said as what it is.
fn past_64_bits(value: &Bound<'_, PyAny>) -> PyResult<bool> {
    use pyo3::types::{PyBool, PyDict, PyInt, PyList, PyTuple};
    if value.is_instance_of::<PyInt>() && !value.is_instance_of::<PyBool>() {
        return Ok(value.extract::<i64>().is_err() && value.extract::<u64>().is_err());
    }
    let items = if let Ok(d) = value.cast::<PyDict>() {
        d.values().into_any()
    } else if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        value.clone()
    } else {
        return Ok(false);
    };
    for item in items.try_iter()? {
        if past_64_bits(&item?)? {
            return Ok(true);
        }
    }
    Ok(false)
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
            let json = py.import("json")?;
            let kwargs = pyo3::types::PyDict::new(py);
            kwargs.set_item("allow_nan", false)?;
            kwargs.set_item("default", wrap_pyfunction!(json_default, py)?)?;
            let mut map = serde_json::Map::new();
            for (k, v) in d.iter() {
                let key: String = k.extract()?;
                // Paths become strings, numpy values Python ones, as JSON
                // has them.
                let v = as_plain(&v)?.unwrap_or(v);
                let refuse = |why: &str| {
                    PyValueError::new_err(format!(
                        "invalid configuration: option '{}' = {}: {why}",
                        tactile_core::printable(&key),
                        v.repr().map(|r| r.to_string()).unwrap_or_default()
                    ))
                };
                if past_64_bits(&v)? {
                    return Err(refuse(tactile_burn::options::BEYOND_64_BITS));
                }
                // Each value alone, so a bad one is named: NaN and
                // infinities are refused (JSON has none).
                let text: String = json
                    .call_method("dumps", (&v,), Some(&kwargs))
                    .and_then(|t| t.extract())
                    .map_err(|e| match v.extract::<f64>() {
                        Ok(x) if !x.is_finite() => refuse("not a finite number"),
                        _ => refuse(&e.to_string()),
                    })?;
                let value = serde_json::from_str(&text).map_err(|e| {
                    let key = tactile_core::printable(&key);
                    PyValueError::new_err(format!("option '{key}': {e}"))
                })?;
                map.insert(key, value);
            }
            map
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
