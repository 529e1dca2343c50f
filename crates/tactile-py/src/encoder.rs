//! `tactile.TactipEncoder`: paper A's encoder and every estimator of its
//! folder on numpy frames.

use std::path::PathBuf;
use std::sync::Mutex;

use numpy::{IntoPyArray, PyArray2};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tactile_cae::TactipEncoder;
use tactile_estimate::{Column, Estimators};
use tactile_pipeline::tactip::{GivenFrames, TactipPerception};
use tactile_preprocess::profile::InputProfile;
use tactile_preprocess::{FrameSizeCheck, PinImage, PreprocessConfig};

use crate::args::{Given, PathArg, PathList};
use crate::errors::PyResultExt;
use crate::frame::{FrameArg, Layout, Pixels, frame_chunks};
use crate::work::released;

struct Models {
    encoder: TactipEncoder,
    estimators: Option<Estimators>,
}

/// Paper A's convolutional encoder with its preprocessing, and the
/// estimators (shape head, regressors) trained on its features.
#[pyclass(module = "tactile", name = "TactipEncoder")]
pub struct PyTactipEncoder {
    models: Mutex<Models>,
    model_dir: PathBuf,
    runtime: tactile_burn::Runtime,
    feature_count: usize,
    pin_side: usize,
    names: Vec<String>,
    preprocess: PreprocessConfig,
}

/// What a model makes of the frames of a call: `frames` is one `(H, W)`
/// grey or `(H, W, 3)` RGB frame, an `(N, H, W)` or `(N, H, W, 3)` array,
/// or an iterable of frames ([`crate::frame::each_frame`]), taken a chunk at a time
/// ([`frame_chunks`]). Each chunk is preprocessed through every one of the
/// model's `scales` and its pin images handed to `run` (which gives one
/// row per frame), off the interpreter and stoppable with Ctrl-C; a
/// `UserWarning` comes for each frame size the preprocessing was not made
/// for as it first comes, and, at the end, for the blank frames and for
/// those outside the model's pin `profile`.
pub(crate) fn run_on_frames<T: Send>(
    py: Python<'_>,
    frames: &Bound<'_, PyAny>,
    scales: &[PreprocessConfig],
    profile: Option<&InputProfile>,
    mut run: impl FnMut(Vec<Vec<PinImage>>) -> PyResult<Vec<T>> + Send,
) -> PyResult<Vec<T>> {
    let mut given = GivenFrames::default();
    let mut sizes = FrameSizeCheck::default();
    let mut rows = Vec::new();
    frame_chunks(frames, Layout::GreyOrRgb, |args, first| {
        let px: Vec<Pixels<'_>> = args.iter().map(FrameArg::view).collect();
        warn_frame_sizes(py, &px, first, &mut sizes, scales)?;
        let work = || run(given.preprocess(&px, scales, profile, Pixels::grey).py()?);
        rows.extend(released(py, px.len() > 1, work)?);
        Ok(())
    })?;
    for w in given.warnings(profile) {
        crate::errors::user_warning(py, &w)?;
    }
    Ok(rows)
}

impl PyTactipEncoder {
    /// The encoder's features of the frames of a call ([`run_on_frames`]).
    fn features(&self, py: Python<'_>, frames: &Bound<'_, PyAny>) -> PyResult<Vec<Vec<f32>>> {
        let profile = self.lock()?.encoder.artifact.input_profile.clone();
        let scales = std::slice::from_ref(&self.preprocess);
        run_on_frames(py, frames, scales, profile.as_ref(), |pins| {
            let pins = pins.first().map_or(&[][..], Vec::as_slice);
            self.lock()?.encoder.encode(pins).py()
        })
    }

    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, Models>> {
        self.models
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the encoder failed in another thread"))
    }
}

/// A `UserWarning` for each frame size among `px` (frames of a call from
/// its `first`) that a preprocessing of `cfgs` was not made for (a frame
/// smaller than its crop: another camera or resolution) and that `sizes`
/// has not seen, naming its first frame; the estimates are still made.
pub(crate) fn warn_frame_sizes(
    py: Python<'_>,
    px: &[Pixels<'_>],
    first: usize,
    sizes: &mut FrameSizeCheck,
    cfgs: &[PreprocessConfig],
) -> PyResult<()> {
    for (i, p) in px.iter().enumerate() {
        if let Some(why) = sizes.check(p.width, p.height, cfgs) {
            crate::errors::user_warning(py, &format!("frames[{}]: {why}", first + i))?;
        }
    }
    Ok(())
}

/// One frame's pin image as numpy, `(S, S)` float32 in [0, 1]: what
/// `preprocess()` returns on every model that reads pin images.
pub(crate) fn pin_image_array<'py>(
    py: Python<'py>,
    frame: &Bound<'py, PyAny>,
    cfg: &PreprocessConfig,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let arg = FrameArg::new(frame, Layout::GreyOrRgb, "frame")?;
    let px = [arg.view()];
    let cfgs = std::slice::from_ref(cfg);
    warn_frame_sizes(py, &px, 0, &mut FrameSizeCheck::default(), cfgs)?;
    let grey = px[0].grey().py()?;
    let pin = py
        .detach(|| tactile_preprocess::preprocess(&grey, cfg))
        .py()?;
    let arr = ndarray::Array2::from_shape_vec((pin.side, pin.side), pin.pixels)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(arr.into_pyarray(py))
}

#[pymethods]
impl PyTactipEncoder {
    /// Refused, saying what to make in a worker process instead.
    fn __reduce__(&self) -> PyResult<Py<PyAny>> {
        Err(crate::pickling::holds_models(
            "TactipEncoder",
            None,
            "tactile.TactipEncoder(model_dir)",
        ))
    }

    /// Load the encoder in `model_dir` (cae.json + cae.bpk) onto `runtime`
    /// and its estimators: the folders in `estimators`, or every estimator
    /// folder inside `model_dir`.
    #[new]
    #[pyo3(
        signature = (model_dir, runtime=Given::of("burn-flex"), *, estimators=None),
        text_signature = "(model_dir, runtime='burn-flex', *, estimators=None)"
    )]
    fn new(
        py: Python<'_>,
        model_dir: PathArg,
        runtime: Given<String>,
        estimators: Option<PathList>,
    ) -> PyResult<Self> {
        crate::args::keywords!(model_dir, estimators, runtime);
        let rt = crate::pipeline::runtime(&runtime)?;
        let dir = model_dir.clone();
        let named = estimators.unwrap_or_default();
        let models = py
            .detach(move || -> Result<Models, tactile_pipeline::Error> {
                match TactipPerception::load(&dir, &named, rt) {
                    Ok(p) => Ok(Models {
                        encoder: p.encoder,
                        estimators: Some(p.estimators),
                    }),
                    // An encoder without estimators still encodes.
                    Err(tactile_pipeline::Error::Estimate(
                        tactile_estimate::Error::NoEstimators(_),
                    )) if named.is_empty() => Ok(Models {
                        encoder: TactipEncoder::load(&dir, rt, 0)?,
                        estimators: None,
                    }),
                    Err(e) => Err(e),
                }
            })
            .py()?;
        let names = models
            .estimators
            .as_ref()
            .map(|e| {
                e.items
                    .iter()
                    .map(|(d, _)| {
                        d.file_name()
                            .map_or(String::new(), |n| n.to_string_lossy().into_owned())
                    })
                    .collect()
            })
            .unwrap_or_default();
        Ok(Self {
            preprocess: models.encoder.artifact.preprocess.clone(),
            feature_count: models.encoder.feature_count(),
            pin_side: models.encoder.artifact.model.input_px,
            models: Mutex::new(models),
            model_dir,
            runtime: rt,
            names,
        })
    }

    /// The pin image the encoder reads, `(S, S)` float32 in [0, 1], from an
    /// `(H, W)` grey or `(H, W, 3)` RGB uint8 frame.
    fn preprocess<'py>(
        &self,
        py: Python<'py>,
        frame: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        pin_image_array(py, frame, &self.preprocess)
    }

    /// Features of frames, `(N, F)` float32: `frames` is one `(H, W)` or
    /// `(H, W, 3)` frame, an `(N, H, W)` grey or `(N, H, W, 3)` RGB uint8
    /// array, or a list of frames.
    fn encode<'py>(
        &self,
        py: Python<'py>,
        frames: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let k = self.feature_count;
        let feats = self.features(py, frames)?;
        let flat: Vec<f32> = feats.concat();
        let arr = ndarray::Array2::from_shape_vec((feats.len(), k), flat)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(arr.into_pyarray(py))
    }

    /// Every frame of a TacTip dataset folder encoded, as `tactile encode`
    /// does: `{"file": [...], "row": (N,) int64, "features": (N, F)
    /// float32}`, a frame that cannot be decoded past its header left out
    /// (its row too) with a `UserWarning`, as are blank frames, frames
    /// outside the encoder's pin profile and a frame size its preprocessing
    /// was not made for. With `out`, the same feature CSV as `tactile
    /// encode --out` (checked before any frame is read).
    #[pyo3(signature = (data, *, out=None))]
    fn encode_dataset<'py>(
        &self,
        py: Python<'py>,
        data: PathArg,
        out: Option<PathArg>,
    ) -> PyResult<Bound<'py, PyDict>> {
        crate::args::keywords!(data, out);
        let e = crate::work::interruptible(py, || {
            let ds = tactile_core::dataset::Dataset::open(&data).py()?;
            let mut models = self.lock()?;
            tactile_pipeline::tactip::encode_dataset_to(&mut models.encoder, &ds, out.as_deref())
                .py()
        })?;
        for w in &e.warnings {
            crate::errors::user_warning(py, w)?;
        }
        let k = self.feature_count;
        let features = ndarray::Array2::from_shape_vec((e.features.len(), k), e.features.concat())
            .map_err(|err| PyValueError::new_err(err.to_string()))?;
        let rows: Vec<i64> = e.rows.iter().map(|&r| r as i64).collect();
        let d = PyDict::new(py);
        d.set_item("file", e.files)?;
        d.set_item("row", rows.into_pyarray(py))?;
        d.set_item("features", features.into_pyarray(py))?;
        Ok(d)
    }

    /// Every estimator of the encoder on one encoding of each frame
    /// (paper A's simultaneous deployment): estimator output name to an
    /// array with one value per frame (class names for the shape head).
    fn estimate<'py>(
        &self,
        py: Python<'py>,
        frames: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        if self.names.is_empty() {
            return Err(PyValueError::new_err(format!(
                "{}: this encoder has no estimators (no folder with head.json, regressor.json or ensemble.json); train one or pass estimators=[...]",
                self.model_dir.display()
            )));
        }
        let feats = self.features(py, frames)?;
        let est = py.detach(|| -> PyResult<tactile_estimate::Estimates> {
            match &self.lock()?.estimators {
                Some(e) => e.estimate(&feats).py(),
                None => Err(PyValueError::new_err("no estimators")),
            }
        })?;
        let np = py.import("numpy")?;
        let out = PyDict::new(py);
        for (name, col) in est.columns {
            match col {
                Column::Number(v) => out.set_item(name, v.into_pyarray(py))?,
                Column::Class(v) => out.set_item(name, np.call_method1("array", (v,))?)?,
            }
        }
        Ok(out)
    }

    /// Features per frame.
    #[getter]
    fn feature_count(&self) -> usize {
        self.feature_count
    }

    /// Side of the pin image, pixels.
    #[getter]
    fn pin_side(&self) -> usize {
        self.pin_side
    }

    /// The estimator folders' names, in the order `estimate` runs them.
    #[getter]
    fn estimators(&self) -> Vec<String> {
        self.names.clone()
    }

    /// Where the encoder runs.
    #[getter]
    fn runtime(&self) -> &'static str {
        self.runtime.name()
    }

    fn __repr__(&self) -> String {
        format!(
            "TactipEncoder('{}', runtime='{}', features={}, estimators={:?})",
            self.model_dir.display(),
            self.runtime,
            self.feature_count,
            self.names
        )
    }
}
