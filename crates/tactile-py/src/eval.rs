//! `tactile.eval`: every evaluation of the command line, returning the
//! dict `tactile eval ...` prints as its last line.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use tactile_core::dataset::Dataset;
use tactile_pipeline::tactip::Predictor;

use crate::args::{Given, PathArg, PathList};
use crate::errors::PyResultExt;
use crate::pipeline::runtime;
use crate::work::interruptible;

/// Score a tendon detector on a labelled visuo-tactile dataset; `options`
/// are [`tactile_detect::eval::EvalOptions`]' (what it writes beside).
#[pyfunction]
#[pyo3(signature = (model, data, *, runtime=Given::of("burn-flex"), **options))]
pub(crate) fn eval_detector<'py>(
    py: Python<'py>,
    model: PathArg,
    data: PathArg,
    runtime: Given<String>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(model, data, runtime);
    let rt = self::runtime(&runtime)?;
    let o: tactile_detect::eval::EvalOptions = crate::json::options(py, options)?;
    let sc = interruptible(py, || {
        tactile_detect::eval::evaluate_folder(&model, &data, rt, &o).py()
    })?;
    warn(py, &sc.frame_warnings, &sc.warning)?;
    crate::json::to_py(
        py,
        &tactile_core::io::scored_record(&model, &data, &sc).py()?,
    )
}

/// Score a tendon segmenter: IoU and direction error per tendon path.
#[pyfunction]
#[pyo3(signature = (model, data, *, runtime=Given::of("burn-flex")))]
pub(crate) fn eval_segmenter<'py>(
    py: Python<'py>,
    model: PathArg,
    data: PathArg,
    runtime: Given<String>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(model, data, runtime);
    let rt = self::runtime(&runtime)?;
    let sc = interruptible(py, || {
        tactile_segment::evaluate_folder(&model, &data, rt).py()
    })?;
    warn(py, &sc.frame_warnings, &sc.warning)?;
    crate::json::to_py(
        py,
        &tactile_core::io::scored_record(&model, &data, &sc).py()?,
    )
}

/// Score a depth network: MAE in the window and over the tendon, RMSE,
/// SSIM; `options` are [`tactile_depth::eval::EvalOptions`]' (heat maps).
#[pyfunction]
#[pyo3(signature = (model, data, *, runtime=Given::of("burn-flex"), **options))]
pub(crate) fn eval_depth<'py>(
    py: Python<'py>,
    model: PathArg,
    data: PathArg,
    runtime: Given<String>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(model, data, runtime);
    let rt = self::runtime(&runtime)?;
    let o: tactile_depth::eval::EvalOptions = crate::json::options(py, options)?;
    let v = interruptible(py, || {
        tactile_depth::eval::evaluate_folder(&model, &data, rt, &o).py()
    })?;
    warn(py, &v.frame_warnings, &v.warning)?;
    crate::json::to_py(py, &v)
}

/// Score every estimator of an encoder (shape accuracy, pose, depth and
/// force errors), or every target of a pose network, on a labelled TacTip
/// dataset (the rows of its `split` alone when given), as `tactile
/// evaluate` does.
#[pyfunction]
#[pyo3(signature = (encoder, data, *, estimators=None, runtime=Given::of("burn-flex"), split=None))]
pub(crate) fn eval_tactip<'py>(
    py: Python<'py>,
    encoder: PathArg,
    data: PathArg,
    estimators: Option<PathList>,
    runtime: Given<String>,
    split: Option<Given<String>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(encoder, data, estimators, runtime, split);
    let rt = self::runtime(&runtime)?;
    let named = estimators.unwrap_or_default();
    let (warnings, v) = interruptible(py, || {
        let ds = Dataset::open_split(&data, split.as_deref()).py()?;
        let mut p = Predictor::load(&encoder, &named, rt).py()?;
        let sc = p.evaluate(&ds).py()?;
        let v = serde_json::to_value(&sc)
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
        Ok((sc.warnings(), v))
    })?;
    for w in &warnings {
        crate::errors::user_warning(py, w)?;
    }
    crate::json::to_py(py, &v)
}

/// Raise an evaluation's warnings as `UserWarning`s: what reading the
/// frames found, then scores on frames the model fitted.
fn warn(py: Python<'_>, frame_warnings: &[String], fitted: &Option<String>) -> PyResult<()> {
    for w in tactile_core::io::scoring_warnings(frame_warnings, fitted) {
        crate::errors::user_warning(py, &w)?;
    }
    Ok(())
}
