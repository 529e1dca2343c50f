//! `tactile.export`: `tactile export` from Python, the same library call.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use tactile_pipeline::export::{Part, export_to};

use crate::args::{Given, PathArg};
use crate::errors::PyResultExt;
use crate::work::interruptible;

/// Export the model folder `model` to the ONNX file `out`: a dict of
/// `kind` (what was exported), `bytes` (the file's size) and `out`.
/// `part` is a CAE's, `"encoder"` (the default) or `"autoencoder"`;
/// `standalone` makes a paper B network's model that stands alone
/// (docs/onnx.md).
#[pyfunction]
#[pyo3(
    signature = (model, out, *, part=None, standalone=Given::of(false)),
    text_signature = "(model, out, *, part=None, standalone=False)"
)]
pub(crate) fn export<'py>(
    py: Python<'py>,
    model: PathArg,
    out: PathArg,
    part: Option<Given<String>>,
    standalone: Given<bool>,
) -> PyResult<Bound<'py, PyDict>> {
    crate::args::keywords!(model, out, part, standalone);
    let part = part.as_deref().map(str::parse::<Part>).transpose().py()?;
    let e = interruptible(py, || export_to(&model, &out, part, standalone).py())?;
    let d = PyDict::new(py);
    d.set_item("kind", e.kind)?;
    d.set_item("bytes", e.bytes.len())?;
    d.set_item("out", out)?;
    Ok(d)
}
