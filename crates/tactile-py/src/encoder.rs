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
use tactile_pipeline::tactip::{TactipPerception, frames_warnings};
use tactile_preprocess::PinImage;

use crate::errors::PyResultExt;
use crate::frame::{FrameArg, Layout, Pixels, each_frame};

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
    preprocess: tactile_preprocess::PreprocessConfig,
}

/// Every frame of `frames` (one `(H, W)` grey or `(H, W, 3)` RGB frame,
/// an `(N, H, W)` or `(N, H, W, 3)` array, or an iterable of frames),
/// checked (see [`each_frame`]).
pub(crate) fn frame_args<'py>(frames: &Bound<'py, PyAny>) -> PyResult<Vec<FrameArg<'py>>> {
    each_frame(frames, |f, what| FrameArg::new(f, Layout::GreyOrRgb, what))
}

impl PyTactipEncoder {
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, Models>> {
        self.models
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the encoder failed in another thread"))
    }

    /// Pin images of frames, preprocessed in parallel as a dataset's are,
    /// with whether each frame is blank (one grey level in its crop).
    fn pins(&self, px: &[Pixels<'_>]) -> PyResult<(Vec<PinImage>, Vec<bool>)> {
        // Each frame made grey as its turn comes; one that fails is named `frames[i]`.
        tactile_preprocess::preprocess_each_noting_flat(px, &self.preprocess, |p| {
            Ok(std::borrow::Cow::Owned(p.grey()?))
        })
        .py()
    }
}

/// A `UserWarning` for each frame size among `px` that a preprocessing of
/// `cfgs` was not made for (a frame smaller than its crop: another camera
/// or resolution), naming its first frame; the estimates are still made.
pub(crate) fn warn_frame_sizes(
    py: Python<'_>,
    px: &[Pixels<'_>],
    cfgs: &[tactile_preprocess::PreprocessConfig],
) -> PyResult<()> {
    let mut sizes = tactile_preprocess::FrameSizeCheck::default();
    for (i, p) in px.iter().enumerate() {
        if let Some(why) = sizes.check(p.width, p.height, cfgs) {
            crate::errors::user_warning(py, &format!("frames[{i}]: {why}"))?;
        }
    }
    Ok(())
}

/// One frame's pin image as numpy, `(S, S)` float32 in [0, 1]: what
/// `preprocess()` returns on every model that reads pin images.
pub(crate) fn pin_image_array<'py>(
    py: Python<'py>,
    frame: &Bound<'py, PyAny>,
    cfg: &tactile_preprocess::PreprocessConfig,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let arg = FrameArg::new(frame, Layout::GreyOrRgb, "frame")?;
    let px = [arg.view()];
    warn_frame_sizes(py, &px, std::slice::from_ref(cfg))?;
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
    /// Load the encoder in `model_dir` (cae.json + cae.bpk) onto `runtime`
    /// and its estimators: the folders in `estimators`, or every estimator
    /// folder inside `model_dir`.
    #[new]
    #[pyo3(signature = (model_dir, runtime="burn-flex", *, estimators=None))]
    fn new(
        py: Python<'_>,
        model_dir: PathBuf,
        runtime: &str,
        estimators: Option<Vec<PathBuf>>,
    ) -> PyResult<Self> {
        let rt = crate::pipeline::runtime(runtime)?;
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
        let args = frame_args(frames)?;
        let px: Vec<Pixels<'_>> = args.iter().map(FrameArg::view).collect();
        warn_frame_sizes(py, &px, std::slice::from_ref(&self.preprocess))?;
        let k = self.feature_count;
        let (feats, warnings) = py.detach(|| -> PyResult<(Vec<Vec<f32>>, Vec<String>)> {
            let (pins, flat) = self.pins(&px)?;
            let mut m = self.lock()?;
            let warnings = frames_warnings(&flat, &pins, m.encoder.artifact.input_profile.as_ref());
            Ok((m.encoder.encode(&pins).py()?, warnings))
        })?;
        for w in warnings {
            crate::errors::user_warning(py, &w)?;
        }
        let flat: Vec<f32> = feats.concat();
        let arr = ndarray::Array2::from_shape_vec((feats.len(), k), flat)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(arr.into_pyarray(py))
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
        let args = frame_args(frames)?;
        let px: Vec<Pixels<'_>> = args.iter().map(FrameArg::view).collect();
        warn_frame_sizes(py, &px, std::slice::from_ref(&self.preprocess))?;
        let (est, warnings) = py.detach(|| -> PyResult<(tactile_estimate::Estimates, _)> {
            let (pins, flat) = self.pins(&px)?;
            let mut m = self.lock()?;
            let warnings = frames_warnings(&flat, &pins, m.encoder.artifact.input_profile.as_ref());
            let feats = m.encoder.encode(&pins).py()?;
            match &m.estimators {
                Some(e) => Ok((e.estimate(&feats).py()?, warnings)),
                None => Err(PyValueError::new_err("no estimators")),
            }
        })?;
        for w in warnings {
            crate::errors::user_warning(py, &w)?;
        }
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
