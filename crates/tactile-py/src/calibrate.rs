//! `tactile.calibrate`: a GelSight-like sensor calibrated from ball
//! presses (the options of `tactile calibrate ball`, by keyword), folders
//! reconstructed as `tactile reconstruct` does, and `tactile.Reconstructor`
//! for numpy frames.

use std::path::PathBuf;
use std::sync::Mutex;

use numpy::{PyArray2, PyArrayMethods};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tactile_gelsight::reconstruct::{ReconstructOptions, SensorCheck};
use tactile_gelsight::{BallOptions, Reconstructor};

use crate::args::{Given, PathArg};
use crate::errors::PyResultExt;
use crate::frame::{FrameArg, Layout};
use crate::work::interruptible;

/// Calibrate the sensor of the calibration folder `data` into the new
/// model folder `out`; `options` are [`BallOptions`]' by keyword.
#[pyfunction]
#[pyo3(signature = (data, out, **options))]
pub(crate) fn calibrate_ball<'py>(
    py: Python<'py>,
    data: PathArg,
    out: PathArg,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(data, out);
    let o: BallOptions = crate::json::options(py, options)?;
    o.config().py()?;
    let c = interruptible(py, || o.calibrate(&data, &out).py())?;
    for w in &c.warnings {
        crate::errors::user_warning(py, w)?;
    }
    let mut v = serde_json::to_value(&c)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    if let Some(m) = v.as_object_mut() {
        m.insert("out".into(), out.display().to_string().into());
    }
    crate::json::to_py(py, &v)
}

/// Reconstruct every frame of `data` (a frame, a folder of frames, a TIFF
/// stack's pages, or a dataset folder) with the
/// model in `model` into the new folder `out`: what `tactile reconstruct`
/// prints as its last line.
#[pyfunction]
#[pyo3(
    signature = (model, data, out, *, background=None, render=None, runtime=Given::of("onnx")),
    text_signature = "(model, data, out, *, background=None, render=None, runtime='onnx')"
)]
pub(crate) fn reconstruct_frames<'py>(
    py: Python<'py>,
    model: PathArg,
    data: PathArg,
    out: PathArg,
    background: Option<PathArg>,
    render: Option<PathArg>,
    runtime: Given<String>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(model, data, out, background, render, runtime);
    let options = ReconstructOptions {
        background,
        render,
        runtime: crate::pipeline::runtime(&runtime)?,
    };
    let r = interruptible(py, || {
        tactile_pipeline::reconstruct::reconstruct(&model, &data, &out, &options).py()
    })?;
    for w in &r.warnings {
        crate::errors::user_warning(py, w)?;
    }
    let v = serde_json::to_value(&r)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    crate::json::to_py(py, &v)
}

/// A calibrated sensor (`tactile calibrate ball`'s model folder) that
/// turns its frames into the skin's indentation.
///
/// Thread-safe: calls from several threads take turns, and the
/// interpreter lock is released while a frame is reconstructed.
#[pyclass(module = "tactile", name = "Reconstructor")]
pub struct PyReconstructor {
    inner: Mutex<(Reconstructor, SensorCheck<'static>)>,
    model_dir: PathBuf,
    runtime: tactile_burn::Runtime,
    size: (usize, usize),
}

#[pymethods]
impl PyReconstructor {
    /// Refused, saying what to make in a worker process instead.
    fn __reduce__(&self) -> PyResult<Py<PyAny>> {
        Err(crate::pickling::holds_models(
            "Reconstructor",
            None,
            "tactile.Reconstructor(model_dir)",
        ))
    }

    /// Load the calibrated sensor in `model_dir` onto `runtime`; with
    /// `background`, compare against that rest frame (a PNG of the same
    /// size) instead of the calibration's.
    #[new]
    #[pyo3(
        signature = (model_dir, runtime=Given::of("onnx"), background=None),
        text_signature = "(model_dir, runtime='onnx', background=None)"
    )]
    fn new(
        py: Python<'_>,
        model_dir: PathArg,
        runtime: Given<String>,
        background: Option<PathArg>,
    ) -> PyResult<Self> {
        crate::args::keywords!(model_dir, background, runtime);
        let rt = crate::pipeline::runtime(&runtime)?;
        let dir = model_dir.clone();
        let rec = py
            .detach(move || -> tactile_gelsight::Result<Reconstructor> {
                let mut r = Reconstructor::load(&dir, rt, 0)?;
                if let Some(bg) = &background {
                    r.set_background(&tactile_core::image_io::load_rgb(bg)?, bg)?;
                }
                Ok(r)
            })
            .py()?;
        // The profile of the detector beside the calibration, if any, else
        // the rest frame, names frames of another sensor.
        let (check, unread) = tactile_pipeline::reconstruct::sensor_check(&model_dir);
        if let Some(w) = unread {
            crate::errors::user_warning(py, &w)?;
        }
        let check = SensorCheck::or_rest_frame(check);
        let g = rec.grid();
        Ok(Self {
            size: (g.frame_width, g.frame_height),
            inner: Mutex::new((rec, check)),
            model_dir,
            runtime: rt,
        })
    }

    /// The skin's indentation under an `(H, W, 3)` uint8 RGB frame of the
    /// calibrated size: `(H, W)` float32, metres toward the camera, 0 at
    /// rest. A frame unlike the sensor's (by the profile of the detector
    /// beside the calibration, when there is one, else by its rest frame)
    /// is reconstructed too, with a `UserWarning`.
    fn reconstruct<'py>(
        &self,
        py: Python<'py>,
        frame: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let arg = FrameArg::new(frame, Layout::Rgb, "frame")?;
        let px = arg.view();
        let (map, warning) = py.detach(|| -> PyResult<(tactile_gelsight::IndentationMap, _)> {
            let mut guard = self.inner.lock().map_err(|_| {
                PyRuntimeError::new_err("the reconstructor failed in another thread")
            })?;
            let (r, check) = &mut *guard;
            px.with_rgb(|img| r.reconstruct_checked(img, "frame", check))
                .py()?
                .py()
        })?;
        if let Some(w) = warning {
            crate::errors::user_warning(py, &w)?;
        }
        let arr = numpy::PyArray1::from_vec(py, map.indentation_m);
        arr.reshape([map.height, map.width])
    }

    /// The calibrated frame size, `(width, height)`.
    #[getter]
    fn frame_size(&self) -> (usize, usize) {
        self.size
    }

    /// Where the sensor model runs.
    #[getter]
    fn runtime(&self) -> &'static str {
        self.runtime.name()
    }

    fn __repr__(&self) -> String {
        format!(
            "Reconstructor('{}', runtime='{}', frame_size={:?})",
            self.model_dir.display(),
            self.runtime,
            self.size
        )
    }
}
