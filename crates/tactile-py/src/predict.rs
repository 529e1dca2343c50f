//! `tactile.predict`: `tactile predict` from Python, the same library
//! calls: a TacTip model over every frame of a dataset, a folder of
//! frames, an image, a video or a ROS 2 bag, optionally written as CSV or
//! ROS 2 messages in MCAP.

use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tactile_estimate::Column;
use tactile_pipeline::tactip::{PredictInput, Predictor};

use crate::args::{Given, PathArg, PathList, Whole};
use crate::errors::PyResultExt;
use crate::pipeline::runtime;
use crate::work::interruptible;

/// Every estimate of `model` (a pose network, or an encoder with its
/// estimators or those in `heads`) on every frame of `data`: a dict of
/// `file` (list of names), `stamp_ns` (int64 array, a bag's frames
/// only), one float64 array per numeric estimate (with `<target>_std`
/// where the model gives a deviation) and a list of names per classifier,
/// and `ms_per_frame`. With `out`, also written there (CSV, or ROS 2
/// messages for a name ending in `.mcap`), as the command line writes it.
/// A frame that cannot be decoded past its header (cut short) is left out
/// with a `UserWarning` naming it; the other frames keep their estimates.
#[pyfunction]
#[pyo3(
    signature = (model, data, out=None, *, heads=PathList::none(), topic=None, limit=None, runtime=Given::of("burn-flex")),
    text_signature = "(model, data, out=None, *, heads=(), topic=None, limit=None, runtime='burn-flex')"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn predict<'py>(
    py: Python<'py>,
    model: PathArg,
    data: PathArg,
    out: Option<PathArg>,
    heads: PathList,
    topic: Option<Given<String>>,
    limit: Option<Whole>,
    runtime: Given<String>,
) -> PyResult<Bound<'py, PyDict>> {
    crate::args::keywords!(model, data, out, heads, topic, runtime);
    let rt = self::runtime(&runtime)?;
    let limit = crate::source::source_limit(limit.as_ref())?;
    let (r, input_warnings) = interruptible(py, || {
        let mut input = PredictInput::open(&data, topic.as_deref(), limit, false).py()?;
        // Taken now: those found while reading come with the estimates.
        let input_warnings = input.warnings();
        if let Some(out) = &out {
            input.check_output(&data, out).py()?;
        }
        let mut p = Predictor::load(&model, &heads, rt).py()?;
        let r = p.perceive_input(&mut input, &data).py()?;
        if let Some(out) = &out {
            tactile_ros::estimates::write_perception(out, &r).py()?;
        }
        Ok((r, input_warnings))
    })?;
    for w in input_warnings.iter().chain(&r.warnings) {
        crate::errors::user_warning(py, w)?;
    }
    let d = PyDict::new(py);
    d.set_item("file", &r.files)?;
    if let Some(s) = r.stamps_ns {
        d.set_item("stamp_ns", s.into_pyarray(py))?;
    }
    for (name, column) in r.estimates.columns {
        match column {
            Column::Number(v) => d.set_item(name, v.into_pyarray(py))?,
            Column::Class(v) => d.set_item(name, v)?,
        }
    }
    d.set_item("ms_per_frame", r.ms_encode + r.ms_estimate)?;
    Ok(d)
}
