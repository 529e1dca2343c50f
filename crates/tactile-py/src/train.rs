//! `tactile.train`: every trainer of the command line, its options the
//! library's options types (the command line's flags by their keyword
//! names; `config=` an options file they override), the same output
//! folders. Training runs off the interpreter and stops cleanly on Ctrl-C.

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tactile_cae::CaeOptions;
use tactile_core::dataset::Dataset;
use tactile_depth::DepthOptions;
use tactile_detect::DetectorOptions;
use tactile_pipeline::options::{HeadOptions, RegressorOptions};
use tactile_pipeline::tactip::{FeatureSource, train_head, train_regressor};
use tactile_pose::PoseOptions;
use tactile_segment::SegmenterOptions;

use crate::args::{Given, PathArg, PathList};
use crate::errors::PyResultExt;
use crate::work::interruptible;

fn open(py: Python<'_>, path: PathBuf) -> PyResult<Dataset> {
    py.detach(move || Dataset::open(&path)).py()
}

/// A library result as the dict Python gets, with the output folder; its
/// warnings raised as `UserWarning`s.
fn result<'py, T: serde::Serialize>(
    py: Python<'py>,
    value: &T,
    out: &std::path::Path,
) -> PyResult<Bound<'py, PyAny>> {
    let mut v = serde_json::to_value(value).map_err(|e| PyValueError::new_err(e.to_string()))?;
    // The run's warnings (its summary's, which every trainer's result
    // holds or flattens), which the command line noted as it found them.
    let warnings: Vec<String> = v
        .get("warnings")
        .and_then(|w| w.as_array())
        .into_iter()
        .flatten()
        .filter_map(|w| w.as_str().map(String::from))
        .collect();
    for w in &warnings {
        crate::errors::user_warning(py, w)?;
    }
    if let Some(m) = v.as_object_mut() {
        m.insert("out".into(), out.display().to_string().into());
    }
    crate::json::to_py(py, &v)
}

/// One-dataset training from Python: the options read and checked before
/// any data (so a bad keyword leaves nothing behind), the output folder
/// checked, the dataset opened, `train` run off the interpreter, its
/// result returned as a dict with the output folder.
fn train_on_one<'py, T, R, E>(
    py: Python<'py>,
    data: PathBuf,
    out: PathBuf,
    options: Option<&Bound<'py, PyDict>>,
    check: impl Fn(&T) -> std::result::Result<(), E>,
    train: impl Fn(&T, &Dataset, &std::path::Path) -> std::result::Result<R, E> + Send + Sync,
) -> PyResult<Bound<'py, PyAny>>
where
    T: tactile_burn::options::Options + Sync,
    R: serde::Serialize + Send,
    E: crate::errors::LibraryError,
{
    let options: T = crate::json::options(py, options)?;
    check(&options).py()?;
    tactile_core::io::ensure_writable_dir(&out).py()?;
    let ds = open(py, data)?;
    let fit = interruptible(py, || train(&options, &ds, &out).py())?;
    result(py, &fit, &out)
}

/// Train paper A's convolutional autoencoder; `options` are
/// [`CaeOptions`]' by their keyword names.
#[pyfunction]
#[pyo3(signature = (data, out, **options))]
pub(crate) fn train_cae<'py>(
    py: Python<'py>,
    data: PathArg,
    out: PathArg,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(data, out);
    train_on_one(
        py,
        data,
        out,
        options,
        |o: &CaeOptions| o.config().map(drop),
        |o: &CaeOptions, ds, out| o.train(ds, out),
    )
}

/// Train a supervised pose network; `options` are [`PoseOptions`]'.
#[pyfunction]
#[pyo3(signature = (data, out, **options))]
pub(crate) fn train_pose<'py>(
    py: Python<'py>,
    data: PathArg,
    out: PathArg,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(data, out);
    train_on_one(
        py,
        data,
        out,
        options,
        |o: &PoseOptions| o.config().map(drop),
        |o: &PoseOptions, ds, out| o.train(ds, out),
    )
}

/// Train paper B's tendon detector on one or more visuo-tactile datasets;
/// `options` are [`DetectorOptions`]'.
#[pyfunction]
#[pyo3(signature = (data, out, **options))]
pub(crate) fn train_detector<'py>(
    py: Python<'py>,
    data: PathList,
    out: PathArg,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(data, out);
    let options: DetectorOptions = crate::json::options(py, options)?;
    options.config().py()?;
    if data.is_empty() {
        return Err(PyValueError::new_err("data: give at least one dataset"));
    }
    tactile_core::io::ensure_writable_dir(&out).py()?;
    let datasets = data
        .into_iter()
        .map(|p| open(py, p))
        .collect::<PyResult<Vec<_>>>()?;
    let fit = interruptible(py, || options.train(&datasets, &out).py())?;
    result(py, &fit, &out)
}

/// Train paper B's U-Net tendon segmenter; `options` are
/// [`SegmenterOptions`]'.
#[pyfunction]
#[pyo3(signature = (data, out, **options))]
pub(crate) fn train_segmenter<'py>(
    py: Python<'py>,
    data: PathArg,
    out: PathArg,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(data, out);
    train_on_one(
        py,
        data,
        out,
        options,
        |_: &SegmenterOptions| Ok::<(), tactile_segment::Error>(()),
        |o: &SegmenterOptions, ds, out| o.train(ds, out),
    )
}

/// Train paper B's depth U-Net with a DenseNet encoder; `options` are
/// [`DepthOptions`]'.
#[pyfunction]
#[pyo3(signature = (data, out, **options))]
pub(crate) fn train_depth<'py>(
    py: Python<'py>,
    data: PathArg,
    out: PathArg,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(data, out);
    train_on_one(
        py,
        data,
        out,
        options,
        |_: &DepthOptions| Ok::<(), tactile_depth::Error>(()),
        |o: &DepthOptions, ds, out| o.train(ds, out),
    )
}

fn source(encoder: &Option<PathBuf>, features: &Option<PathBuf>) -> PyResult<FeatureSource> {
    match (encoder, features) {
        (Some(_), Some(_)) => Err(PyValueError::new_err(
            "give encoder= or features=, not both",
        )),
        (_, Some(csv)) => Ok(FeatureSource::Csv(csv.clone())),
        (Some(e), None) => Ok(FeatureSource::Encoder(e.clone())),
        (None, None) => Err(PyValueError::new_err(
            "give encoder= (a trained encoder folder) or features= (a feature CSV)",
        )),
    }
}

fn out_or(encoder: &Option<PathBuf>, out: Option<PathBuf>, name: &str) -> PyResult<PathBuf> {
    out.or_else(|| encoder.as_ref().map(|e| e.join(name)))
        .ok_or_else(|| PyValueError::new_err("features= needs out="))
}

/// Train the shape head (an ensemble of shallow classifiers) on features;
/// `options` are [`HeadOptions`]'.
#[pyfunction]
#[pyo3(signature = (data, *, encoder=None, features=None, out=None, test=None, **options))]
pub(crate) fn train_head_py<'py>(
    py: Python<'py>,
    data: PathArg,
    encoder: Option<PathArg>,
    features: Option<PathArg>,
    out: Option<PathArg>,
    test: Option<PathArg>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(data, encoder, features, out, test);
    let options: HeadOptions = crate::json::options(py, options)?;
    let rt = options.device.runtime();
    let src = source(&encoder, &features)?;
    let out = out_or(&encoder, out, "head")?;
    let (config, rotation) = options.config().py()?;
    tactile_core::io::ensure_writable_dir(&out).py()?;
    let ds = open(py, data)?;
    let test = test.map(|t| open(py, t)).transpose()?;
    let (head, tested) = interruptible(py, || {
        train_head(config, &src, &ds, test.as_ref(), &out, rt, rotation).py()
    })?;
    if let Some(w) = tested.as_ref().and_then(|t| t.warning.as_ref()) {
        crate::errors::user_warning(py, w)?;
    }
    let test = tested.map(|t| {
        serde_json::json!({
            "accuracy": t.accuracy, "right": t.right, "frames": t.frames,
            "confusion": t.confusion, "classes": head.classes(),
        })
    });
    crate::json::to_py(
        py,
        &serde_json::json!({ "out": out.display().to_string(), "classes": head.classes(), "test": test }),
    )
}

/// A regressor's targets: a list of label columns, or one string read as
/// the trainers' list options read it (`"x_mm,theta_deg:180"`).
#[derive(FromPyObject)]
pub(crate) enum Targets {
    /// One string.
    Listed(String),
    /// A list of names.
    Names(Vec<String>),
}

impl Targets {
    /// The target names.
    fn names(self) -> Vec<String> {
        match self {
            Self::Listed(text) => tactile_burn::options::list_items(&text)
                .map(String::from)
                .collect(),
            Self::Names(names) => names,
        }
    }
}

/// Train a regressor (pose, depth, force; angles on the circle) on
/// features; `options` are [`RegressorOptions`]'.
#[pyfunction]
#[pyo3(signature = (data, targets, *, encoder=None, features=None, out=None, **options))]
pub(crate) fn train_regressor_py<'py>(
    py: Python<'py>,
    data: PathArg,
    targets: Given<Targets>,
    encoder: Option<PathArg>,
    features: Option<PathArg>,
    out: Option<PathArg>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(data, targets, encoder, features, out);
    let targets = targets.names();
    let options: RegressorOptions = crate::json::options(py, options)?;
    let rt = options.device.runtime();
    let plan = options.plan(&targets).py()?;
    let src = source(&encoder, &features)?;
    let out = out_or(&encoder, out, "regressor")?;
    tactile_core::io::ensure_writable_dir(&out).py()?;
    let ds = open(py, data)?;
    let fit = interruptible(py, || train_regressor(&plan, &src, &ds, &out, rt).py())?;
    for w in &fit.warnings {
        crate::errors::user_warning(py, w)?;
    }
    let mae: serde_json::Map<String, serde_json::Value> = plan
        .targets
        .iter()
        .zip(&fit.test_mae)
        .map(|(t, e)| (t.name.clone(), (*e).into()))
        .collect();
    crate::json::to_py(
        py,
        &serde_json::json!({
            "out": out.display().to_string(),
            "frames": { "train": fit.frames[0], "val": fit.frames[1], "test": fit.frames[2] },
            "test_mae": mae,
        }),
    )
}

/// The options of a trainer (`"cae"`, `"detector"`, ...): name, help and
/// default of each, in flag order, the same the command line's `--help`
/// shows.
#[pyfunction]
pub(crate) fn options<'py>(py: Python<'py>, trainer: Given<String>) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(trainer);
    let docs = tactile_pipeline::options::trainer(&trainer)
        .and_then(|t| t.docs())
        .py()?;
    crate::json::to_py(py, &docs)
}

/// Average models trained apart (pose networks, detectors that read a
/// frame alike, or regressors on one encoder's features trained with other
/// seeds) in a new ensemble folder; returns what was made, in words.
#[pyfunction]
pub(crate) fn train_ensemble(members: PathList, out: PathArg) -> PyResult<String> {
    crate::args::keywords!(members, out);
    tactile_pipeline::ensemble::assemble_ensemble(&members, &out).py()
}

/// Calibrate a trained model on frames it was not trained on: a detector's
/// probabilities on `data`, or a pose network's deviations on `data`'s rows
/// of `split` (or the factors of the validated run `calibration_from`).
/// Returns what changed, in words.
#[pyfunction]
#[pyo3(signature = (model, data, split=None, calibration_from=None))]
pub(crate) fn train_calibrate(
    py: Python<'_>,
    model: PathArg,
    data: PathList,
    split: Option<Given<String>>,
    calibration_from: Option<PathArg>,
) -> PyResult<String> {
    crate::args::keywords!(model, data, calibration_from, split);
    let c = interruptible(py, || {
        let sets = Dataset::open_all(&data).py()?;
        tactile_pipeline::calibrate::calibrate_model(
            &model,
            &sets,
            split.as_deref(),
            calibration_from.as_deref(),
        )
        .py()
    })?;
    for w in &c.warnings {
        crate::errors::user_warning(py, w)?;
    }
    Ok(c.summary)
}

/// Fit a trained model's input profile on `data` (its training frames;
/// a TacTip model's on the rows of `split` alone when given) and save it
/// in its config: frames of another sensor are then flagged. Returns what
/// was saved, in words.
#[pyfunction]
#[pyo3(signature = (model, data, split=None))]
pub(crate) fn train_profile(
    py: Python<'_>,
    model: PathArg,
    data: PathList,
    split: Option<Given<String>>,
) -> PyResult<String> {
    crate::args::keywords!(model, data, split);
    interruptible(py, || {
        let sets = Dataset::open_all(&data).py()?;
        let p =
            tactile_pipeline::profile::add_input_profile(&model, &sets, split.as_deref()).py()?;
        Ok(format!("{} saved in {}", p.describe(), model.display()))
    })
}

/// Measure the pin lattice's orientation on an encoder's training frames
/// (`data`: every frame of each dataset) and save it with the encoder, so
/// frames of a sensor mounted turned are turned back before encoding, as
/// `tactile train align` does. Returns what was saved, in words.
#[pyfunction]
#[pyo3(signature = (model, data))]
pub(crate) fn train_align(py: Python<'_>, model: PathArg, data: PathList) -> PyResult<String> {
    crate::args::keywords!(model, data);
    interruptible(py, || {
        let sets = Dataset::open_all(&data).py()?;
        let (p, n) = tactile_cae::artifact::add_pin_alignment(&model, &sets).py()?;
        Ok(p.describe(n))
    })
}
