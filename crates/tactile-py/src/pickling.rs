//! What crosses to another Python process (`pickle`, `copy`,
//! `multiprocessing`, `concurrent.futures`): a frame's result, a frame and
//! a dataset are pickled whole; what holds loaded models or an open stream
//! is refused, saying what to make in each worker instead.

use numpy::{PyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};
use tactile_pipeline::{FrameRecord, FrameViews};

use crate::errors::PyResultExt;
use crate::pipeline::FrameResult;
use crate::source::PyFrame;

/// Which layout a pickled result was written in: another version of the
/// package may lay it out otherwise, so its pickles are refused, naming
/// both versions, rather than misread.
const RESULT_STATE: &str = concat!("tactile ", env!("CARGO_PKG_VERSION"));

/// A function of the native module, as pickle finds it again by name.
fn restorer<'py>(py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("tactile._tactile")?.getattr(name)
}

/// `FrameResult.__reduce__`: the record, the views and the size as
/// MessagePack (serde), restored by [`frame_result`].
pub(crate) fn reduce_frame_result<'py>(
    py: Python<'py>,
    result: &FrameResult,
) -> PyResult<Bound<'py, PyAny>> {
    let bytes = rmp_serde::to_vec_named(&result.state())
        .map_err(|e| PyValueError::new_err(format!("FrameResult: cannot be pickled: {e}")))?;
    let args = (RESULT_STATE, PyBytes::new(py, &bytes));
    Ok(PyTuple::new(
        py,
        [
            restorer(py, "_frame_result")?,
            args.into_pyobject(py)?.into_any(),
        ],
    )?
    .into_any())
}

/// A pickled `FrameResult` read back: refused, naming the problem, when
/// another version wrote it or its parts do not fit together (so no
/// later call indexes past a buffer or allocates a size it was not
/// checked for).
#[pyfunction]
#[pyo3(name = "_frame_result")]
pub(crate) fn frame_result(version: &str, state: &[u8]) -> PyResult<FrameResult> {
    if version != RESULT_STATE {
        // What a pickle holds is shown escaped, never obeyed.
        let version = tactile_core::printable(version);
        return Err(PyValueError::new_err(format!(
            "a FrameResult pickled by {version}, read by {RESULT_STATE}: pickle and unpickle \
             results with one version of tactile"
        )));
    }
    type State = (FrameRecord, Option<FrameViews>, (usize, usize));
    let (record, views, (w, h)): State = rmp_serde::from_slice(state).map_err(|e| {
        let why = e.to_string();
        let why = tactile_core::printable(&why);
        PyValueError::new_err(format!("a pickled FrameResult that cannot be read: {why}"))
    })?;
    match &views {
        Some(v) => v.check(w, h),
        None => FrameViews::default().check(w, h),
    }
    .py()?;
    Ok(FrameResult::new(record, views, (w, h)))
}

/// `Frame.__reduce__`: its fields, restored by [`frame`].
pub(crate) fn reduce_frame<'py>(py: Python<'py>, f: &PyFrame) -> PyResult<Bound<'py, PyAny>> {
    let fields = (
        f.image.clone_ref(py),
        f.name.clone(),
        f.sequence.clone(),
        f.tendon,
        f.age_ms,
        f.stamp_ns,
    );
    let args = fields.into_pyobject(py)?.into_any();
    Ok(PyTuple::new(py, [restorer(py, "_frame")?, args])?.into_any())
}

/// A pickled `Frame` read back; its image must be an `(H, W, 3)` uint8
/// array, as every source gives.
#[pyfunction]
#[pyo3(name = "_frame")]
pub(crate) fn frame(
    image: Bound<'_, PyAny>,
    name: String,
    sequence: Option<String>,
    tendon: Option<bool>,
    age_ms: Option<f64>,
    stamp_ns: Option<i64>,
) -> PyResult<PyFrame> {
    let rgb = image
        .cast::<PyArray3<u8>>()
        .map_err(|_| PyTypeError::new_err("a pickled Frame whose image is not a uint8 array"))?;
    if rgb.shape()[2] != 3 {
        return Err(PyValueError::new_err(format!(
            "a pickled Frame whose image has shape {:?}, not (H, W, 3)",
            rgb.shape()
        )));
    }
    Ok(PyFrame {
        image: image.unbind(),
        name,
        sequence,
        tendon,
        age_ms,
        stamp_ns,
    })
}

/// The refusal to pickle `class`, which holds loaded models (and
/// `state`, if any): make one in each worker with `make` instead.
pub(crate) fn holds_models(class: &str, state: Option<&str>, make: &str) -> PyErr {
    let state = state.map(|s| format!(" and {s}")).unwrap_or_default();
    PyTypeError::new_err(format!(
        "tactile.{class} cannot be pickled: it holds loaded models{state}. For several \
         processes, make one in each worker (in a multiprocessing.Pool or \
         concurrent.futures.ProcessPoolExecutor initializer: {make}) and send it frames; \
         frames and results pickle (docs/python.md, \"Several threads and processes\")"
    ))
}

/// The refusal to pickle `class`, an open `what`: send what it reads, or
/// its output, instead.
pub(crate) fn open_stream(class: &str, what: &str, send: &str) -> PyErr {
    PyTypeError::new_err(format!(
        "tactile.{class} cannot be pickled: it is {what}. {send} (docs/python.md, \"Several \
         threads and processes\")"
    ))
}
