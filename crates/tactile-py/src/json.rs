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
