//! `tactile.train`: every trainer of the command line, with the same
//! options (None keeps the model's default) and the same output folders.
//! Training runs off the interpreter and stops cleanly on Ctrl-C.

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tactile_burn::DeviceKind;
use tactile_burn::train::Schedule;
use tactile_cae::{CaeConfig, CaeTrainingConfig, Optimizer};
use tactile_core::dataset::{Dataset, TestHoldout};
use tactile_depth::{DenseNetPreset, DepthTrainingConfig, HeadKind, LossKind};
use tactile_detect::DetectorOptions;
use tactile_estimate::{HeadConfig, RegressorConfig, Target};
use tactile_pipeline::tactip::{
    FeatureSource, RegressorPlan, RotationAugment, train_head, train_regressor,
};
use tactile_preprocess::PreprocessConfig;
use tactile_segment::SegmenterTrainingConfig;

use crate::errors::PyResultExt;
use crate::work::interruptible;

/// A value named by its configuration name ("adam", "resnet18", "l1").
fn parse<T: serde::de::DeserializeOwned>(what: &str, name: &str) -> PyResult<T> {
    serde_json::from_value(serde_json::Value::String(name.to_string()))
        .map_err(|e| PyValueError::new_err(format!("{what}: {e}")))
}

fn device(name: &str) -> PyResult<DeviceKind> {
    name.trim_start_matches("burn-").parse::<DeviceKind>().py()
}

/// Schedule options; None keeps the model's default.
#[derive(Default)]
pub(crate) struct ScheduleArgs {
    max_epochs: Option<usize>,
    patience: Option<usize>,
    batch_size: Option<usize>,
    lr: Option<f64>,
    lr_decay: Option<f64>,
    seed: Option<u64>,
}

impl ScheduleArgs {
    /// From a dict with any of max_epochs, patience, batch_size, lr,
    /// lr_decay, seed (None values keep the default).
    fn from_dict(d: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let Some(d) = d else {
            return Ok(Self::default());
        };
        const KEYS: [&str; 6] = [
            "max_epochs",
            "patience",
            "batch_size",
            "lr",
            "lr_decay",
            "seed",
        ];
        for k in d.keys() {
            let k: String = k.extract()?;
            if !KEYS.contains(&k.as_str()) {
                return Err(PyValueError::new_err(format!(
                    "schedule: unknown option '{k}' (known: {})",
                    KEYS.join(", ")
                )));
            }
        }
        fn get<'py, T: pyo3::conversion::FromPyObjectOwned<'py>>(
            d: &Bound<'py, PyDict>,
            k: &str,
        ) -> PyResult<Option<T>> {
            match d.get_item(k)? {
                Some(v) if !v.is_none() => v.extract::<T>().map(Some).map_err(|e| {
                    let e: PyErr = e.into();
                    PyValueError::new_err(format!("schedule: {k}: {e}"))
                }),
                _ => Ok(None),
            }
        }
        Ok(Self {
            max_epochs: get(d, "max_epochs")?,
            patience: get(d, "patience")?,
            batch_size: get(d, "batch_size")?,
            lr: get(d, "lr")?,
            lr_decay: get(d, "lr_decay")?,
            seed: get(d, "seed")?,
        })
    }

    fn apply(&self, base: Schedule, default_lr: f64) -> Schedule {
        Schedule {
            batch_size: self.batch_size.unwrap_or(base.batch_size),
            max_epochs: self.max_epochs.unwrap_or(base.max_epochs),
            patience: self.patience.unwrap_or(base.patience),
            learning_rate: self.lr.unwrap_or(default_lr),
            lr_decay: self.lr_decay.unwrap_or(base.lr_decay),
            seed: self.seed.unwrap_or(base.seed),
        }
    }
}

fn open(py: Python<'_>, path: PathBuf) -> PyResult<Dataset> {
    py.detach(move || Dataset::open(&path)).py()
}

fn size(what: &str, v: Option<(usize, usize)>, default: [usize; 2]) -> PyResult<[usize; 2]> {
    match v {
        None => Ok(default),
        Some((w, h)) if w >= 16 && h >= 16 => Ok([w, h]),
        Some((w, h)) => Err(PyValueError::new_err(format!(
            "{what}: sizes must be at least 16 pixels, got ({w}, {h})"
        ))),
    }
}

/// The result dict: the fit summary plus what the trainer adds.
fn summary<'py>(
    py: Python<'py>,
    s: &tactile_burn::train::FitSummary,
    out: &std::path::Path,
    extra: serde_json::Value,
) -> PyResult<Bound<'py, PyAny>> {
    let mut v = serde_json::to_value(s).map_err(|e| PyValueError::new_err(e.to_string()))?;
    if let (Some(m), serde_json::Value::Object(x)) = (v.as_object_mut(), extra) {
        m.insert("out".into(), out.display().to_string().into());
        m.extend(x);
    }
    crate::json::to_py(py, &v)
}

/// Train paper A's convolutional autoencoder.
#[pyfunction]
#[pyo3(signature = (data, out, *, preprocess="binary", widths=None, features=None, linear_latent=false, optimizer="adadelta", val_fraction=None, exclude_test=None, split_seed=7, device="flex", resume=false, schedule=None, rotate_copies=0, rotate_deg=6.0, joint_targets=None, joint_weight=1.0, joint_hidden=64, joint_loss="mse"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn train_cae<'py>(
    py: Python<'py>,
    data: PathBuf,
    out: PathBuf,
    preprocess: &str,
    widths: Option<[usize; 4]>,
    features: Option<usize>,
    linear_latent: bool,
    optimizer: &str,
    val_fraction: Option<f64>,
    exclude_test: Option<f64>,
    split_seed: u64,
    device: &str,
    resume: bool,
    schedule: Option<&Bound<'py, PyDict>>,
    rotate_copies: usize,
    rotate_deg: f64,
    joint_targets: Option<Vec<String>>,
    joint_weight: f64,
    joint_hidden: usize,
    joint_loss: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let schedule = ScheduleArgs::from_dict(schedule)?;
    let dev = self::device(device)?;
    let optimizer: Optimizer = parse("optimizer", optimizer)?;
    let joint = tactile_cae::JointTargets::from_names(
        &joint_targets.unwrap_or_default(),
        joint_weight,
        joint_hidden,
        parse("joint_loss", joint_loss)?,
    )
    .py()?;
    let pre = PreprocessConfig::preset(preprocess).py()?;
    tactile_core::io::ensure_writable_dir(&out).py()?;
    let ds = open(py, data)?;
    let d = CaeTrainingConfig::new();
    let model = CaeConfig::from_options(
        &widths.unwrap_or(CaeConfig::new().widths),
        features,
        linear_latent,
        pre.output_px,
    )
    .py()?;
    let config = CaeTrainingConfig::new()
        .with_model(model)
        .with_preprocess(pre)
        .with_schedule(schedule.apply(d.schedule, optimizer.default_learning_rate()))
        .with_optimizer(optimizer)
        .with_val_fraction(val_fraction.unwrap_or(d.val_fraction))
        .with_holdout(TestHoldout::excluding(exclude_test, split_seed));
    let seed = config.schedule.seed;
    let config = config
        .with_rotation(RotationAugment::optional(rotate_copies, rotate_deg, seed))
        .with_joint(joint);
    let s = interruptible(py, || {
        tactile_cae::training::train(&config, &ds, &out, dev, resume).py()
    })?;
    summary(py, &s, &out, serde_json::json!({}))
}

/// Train paper B's tendon detector on one or more visuo-tactile datasets;
/// `options` are [`DetectorOptions`]' (the flags of `tactile train
/// detector`, by their keyword names).
#[pyfunction]
#[pyo3(signature = (data, out, **options))]
pub(crate) fn train_detector<'py>(
    py: Python<'py>,
    data: Vec<PathBuf>,
    out: PathBuf,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
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
    let mut v = serde_json::to_value(&fit).map_err(|e| PyValueError::new_err(e.to_string()))?;
    if let Some(m) = v.as_object_mut() {
        m.insert("out".into(), out.display().to_string().into());
    }
    crate::json::to_py(py, &v)
}

/// The options of a trainer (`"detector"`): name, help and default of each,
/// in flag order, the same the command line's `--help` shows.
#[pyfunction]
pub(crate) fn options<'py>(py: Python<'py>, trainer: &str) -> PyResult<Bound<'py, PyAny>> {
    use tactile_burn::options::Options;
    let docs = match trainer {
        "detector" => DetectorOptions::docs(),
        other => {
            return Err(PyValueError::new_err(format!(
                "no options for '{other}' (known: detector)"
            )));
        }
    }
    .py()?;
    crate::json::to_py(py, &docs)
}

/// Train paper B's U-Net tendon segmenter.
#[pyfunction]
#[pyo3(signature = (data, out, *, side=None, base=None, copies=None, val_fraction=None, device="flex", resume=false, schedule=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn train_segmenter<'py>(
    py: Python<'py>,
    data: PathBuf,
    out: PathBuf,
    side: Option<usize>,
    base: Option<usize>,
    copies: Option<usize>,
    val_fraction: Option<f64>,
    device: &str,
    resume: bool,
    schedule: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let schedule = ScheduleArgs::from_dict(schedule)?;
    let dev = self::device(device)?;
    tactile_core::io::ensure_writable_dir(&out).py()?;
    let ds = open(py, data)?;
    let d = SegmenterTrainingConfig::new();
    let config = SegmenterTrainingConfig::new()
        .with_model(
            d.model
                .clone()
                .with_side(side.unwrap_or(d.model.side))
                .with_base(base.unwrap_or(d.model.base)),
        )
        .with_schedule(schedule.apply(d.schedule.clone(), d.schedule.learning_rate))
        .with_copies(copies.unwrap_or(d.copies))
        .with_val_fraction(val_fraction.unwrap_or(d.val_fraction));
    let s = interruptible(py, || {
        tactile_segment::training::train(&config, &ds, &out, dev, resume).py()
    })?;
    summary(py, &s, &out, serde_json::json!({}))
}

/// Train paper B's depth U-Net with a DenseNet encoder.
#[pyfunction]
#[pyo3(signature = (data, out, *, encoder="small", input=None, head=None, loss=None, with_mask=false, freeze_encoder=false, pretrained=None, unit_mm=None, decoder_width=None, val_fraction=None, device="flex", resume=false, schedule=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn train_depth<'py>(
    py: Python<'py>,
    data: PathBuf,
    out: PathBuf,
    encoder: &str,
    input: Option<(usize, usize)>,
    head: Option<&str>,
    loss: Option<&str>,
    with_mask: bool,
    freeze_encoder: bool,
    pretrained: Option<PathBuf>,
    unit_mm: Option<f32>,
    decoder_width: Option<usize>,
    val_fraction: Option<f64>,
    device: &str,
    resume: bool,
    schedule: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let schedule = ScheduleArgs::from_dict(schedule)?;
    let dev = self::device(device)?;
    let preset: DenseNetPreset = encoder.parse().py()?;
    let d = DepthTrainingConfig::new();
    let head: HeadKind = match head {
        Some(h) => parse("head", h)?,
        None => d.model.head,
    };
    let loss: LossKind = match loss {
        Some(l) => l.parse().py()?,
        None => d.loss,
    };
    let input = size("input", input, d.model.input_size)?;
    tactile_core::io::ensure_writable_dir(&out).py()?;
    let ds = open(py, data)?;
    let model = tactile_depth::DepthNetConfig::new(preset.config(), input)
        .with_head(head)
        .with_decoder_width(decoder_width.unwrap_or(d.model.decoder_width));
    let config = DepthTrainingConfig::new()
        .with_model(model)
        .with_schedule(schedule.apply(d.schedule.clone(), d.schedule.learning_rate))
        .with_loss(loss)
        .with_unit_mm(unit_mm.unwrap_or(d.unit_mm))
        .with_with_mask(with_mask)
        .with_freeze_encoder(freeze_encoder)
        .with_pretrained(pretrained.map(|p| p.display().to_string()))
        .with_val_fraction(val_fraction.unwrap_or(d.val_fraction));
    let s = interruptible(py, || {
        tactile_depth::training::train(&config, &ds, &out, dev, resume).py()
    })?;
    summary(py, &s, &out, serde_json::json!({}))
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

/// Train the shape head (an ensemble of shallow classifiers) on features.
#[pyfunction]
#[pyo3(signature = (data, *, encoder=None, features=None, out=None, test=None, folds=None, repeats=None, seed=None, device="flex", rotate_copies=0, rotate_deg=6.0))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn train_head_py<'py>(
    py: Python<'py>,
    data: PathBuf,
    encoder: Option<PathBuf>,
    features: Option<PathBuf>,
    out: Option<PathBuf>,
    test: Option<PathBuf>,
    folds: Option<usize>,
    repeats: Option<usize>,
    seed: Option<u64>,
    device: &str,
    rotate_copies: usize,
    rotate_deg: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let rt = self::device(device)?.runtime();
    let src = source(&encoder, &features)?;
    let out = out_or(&encoder, out, "head")?;
    let d = HeadConfig::new(0, vec![]);
    let rotation =
        RotationAugment::optional(rotate_copies, rotate_deg, seed.unwrap_or(d.schedule.seed));
    tactile_core::io::ensure_writable_dir(&out).py()?;
    let ds = open(py, data)?;
    let test = test.map(|t| open(py, t)).transpose()?;
    let mut config = HeadConfig::new(0, vec![])
        .with_folds(folds.unwrap_or(d.folds))
        .with_repeats(repeats.unwrap_or(d.repeats));
    config.schedule.seed = seed.unwrap_or(d.schedule.seed);
    let (head, tested) = interruptible(py, || {
        train_head(config, &src, &ds, test.as_ref(), &out, rt, rotation).py()
    })?;
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

/// Train a regressor (pose, depth, force; angles on the circle) on features.
#[pyfunction]
#[pyo3(signature = (data, targets, *, encoder=None, features=None, out=None, test_fraction=None, val_fraction=None, hidden=None, seed=None, device="flex", only_labelled=false, shapes=Vec::new()))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn train_regressor_py<'py>(
    py: Python<'py>,
    data: PathBuf,
    targets: Vec<String>,
    encoder: Option<PathBuf>,
    features: Option<PathBuf>,
    out: Option<PathBuf>,
    test_fraction: Option<f64>,
    val_fraction: Option<f64>,
    hidden: Option<Vec<usize>>,
    seed: Option<u64>,
    device: &str,
    only_labelled: bool,
    shapes: Vec<String>,
) -> PyResult<Bound<'py, PyAny>> {
    let rt = self::device(device)?.runtime();
    let targets = targets
        .iter()
        .map(|t| t.parse::<Target>())
        .collect::<Result<Vec<_>, _>>()
        .py()?;
    if targets.is_empty() {
        return Err(PyValueError::new_err(
            "targets: give at least one label column",
        ));
    }
    let src = source(&encoder, &features)?;
    let out = out_or(&encoder, out, "regressor")?;
    tactile_core::io::ensure_writable_dir(&out).py()?;
    let ds = open(py, data)?;
    let d = RegressorPlan::new(vec![]);
    let plan = RegressorPlan {
        hidden: hidden.unwrap_or(d.hidden),
        test_fraction: test_fraction.unwrap_or(d.test_fraction),
        val_fraction: val_fraction.unwrap_or(d.val_fraction),
        seed: seed.unwrap_or(RegressorConfig::new(0, vec![]).schedule.seed),
        only_labelled,
        shapes,
        ..RegressorPlan::new(targets)
    };
    let fit = interruptible(py, || train_regressor(&plan, &src, &ds, &out, rt).py())?;
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

/// Average models trained apart (pose networks, or detectors that read a
/// frame alike) in a new ensemble folder; returns what was made, in words.
#[pyfunction]
pub(crate) fn train_ensemble(members: Vec<PathBuf>, out: PathBuf) -> PyResult<String> {
    tactile_pipeline::ensemble::assemble_ensemble(&members, &out).py()
}
