//! `tactile.PoseEstimator`: a supervised pose network (x, theta, depth
//! directly from the frame) on numpy frames.

use std::path::PathBuf;
use std::sync::Mutex;

use numpy::{IntoPyArray, PyArray2};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tactile_pose::PoseEstimator;
use tactile_preprocess::PinImage;

use crate::args::{Given, PathArg};
use crate::encoder::{pin_image_array, run_on_frames};
use crate::errors::PyResultExt;

/// A pose network folder (`pose.json` + `pose.bpk`) with its preprocessing,
/// or an ensemble of them (members may read different pin image sizes).
#[pyclass(module = "tactile", name = "PoseEstimator")]
pub struct PyPoseEstimator {
    estimator: Mutex<PoseEstimator>,
    model_dir: PathBuf,
    runtime: tactile_burn::Runtime,
    targets: Vec<String>,
    preprocess: tactile_preprocess::PreprocessConfig,
    /// Every member's preprocessing (a multi-scale ensemble's differ).
    scales: Vec<tactile_preprocess::PreprocessConfig>,
}

impl PyPoseEstimator {
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, PoseEstimator>> {
        self.estimator
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the estimator failed in another thread"))
    }
}

#[pymethods]
impl PyPoseEstimator {
    /// Refused, saying what to make in a worker process instead.
    fn __reduce__(&self) -> PyResult<Py<PyAny>> {
        Err(crate::pickling::holds_models(
            "PoseEstimator",
            None,
            "tactile.PoseEstimator(model_dir)",
        ))
    }

    /// Load the pose network in `model_dir` onto `runtime`.
    #[new]
    #[pyo3(
        signature = (model_dir, runtime=Given::of("burn-flex")),
        text_signature = "(model_dir, runtime='burn-flex')"
    )]
    fn new(py: Python<'_>, model_dir: PathArg, runtime: Given<String>) -> PyResult<Self> {
        crate::args::keywords!(model_dir, runtime);
        let rt = crate::pipeline::runtime(&runtime)?;
        let dir = model_dir.clone();
        let estimator = py
            .detach(move || PoseEstimator::load(&dir, rt, 0))
            .map_err(tactile_pipeline::Error::from)
            .py()?;
        Ok(Self {
            targets: estimator
                .artifact
                .targets
                .iter()
                .map(|t| t.name.clone())
                .collect(),
            preprocess: estimator.artifact.preprocess.clone(),
            scales: estimator.scales().to_vec(),
            estimator: Mutex::new(estimator),
            model_dir,
            runtime: rt,
        })
    }

    /// The grey pin image the network reads, `(S, S)` float32 in [0, 1],
    /// from an `(H, W)` grey or `(H, W, 3)` RGB uint8 frame (a multi-scale
    /// ensemble's first member's).
    fn preprocess<'py>(
        &self,
        py: Python<'py>,
        frame: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        pin_image_array(py, frame, &self.preprocess)
    }

    /// Each target (`x_mm`, `theta_deg`, `depth_mm`, ...) to an array with
    /// one value per frame, in the labels' units: `frames` is one `(H, W)`
    /// or `(H, W, 3)` frame, an `(N, H, W)` grey or `(N, H, W, 3)` RGB
    /// uint8 array, or a list of frames.
    fn estimate<'py>(
        &self,
        py: Python<'py>,
        frames: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (profile, uncertain) = {
            let e = self.lock()?;
            (e.artifact.input_profile.clone(), e.has_uncertainty())
        };
        let rows = run_on_frames(py, frames, &self.scales, profile.as_ref(), |pins| {
            let views: Vec<&[PinImage]> = pins.iter().map(Vec::as_slice).collect();
            let (rows, std) = self
                .lock()?
                .predict_scales_with_std(&views)
                .map_err(tactile_pipeline::Error::from)
                .py()?;
            let std = std.unwrap_or_else(|| vec![Vec::new(); rows.len()]);
            Ok(rows.into_iter().zip(std).collect())
        })?;
        let (rows, std): (Vec<Vec<f64>>, Vec<Vec<f64>>) = rows.into_iter().unzip();
        let std = uncertain.then_some(std);
        let out = PyDict::new(py);
        for (j, name) in self.targets.iter().enumerate() {
            let v: Vec<f64> = rows.iter().map(|r| r[j]).collect();
            out.set_item(name, v.into_pyarray(py))?;
            if let Some(std) = &std {
                let v: Vec<f64> = std.iter().map(|r| r[j]).collect();
                out.set_item(
                    tactile_estimate::registry::std_column(name),
                    v.into_pyarray(py),
                )?;
            }
        }
        Ok(out)
    }

    /// The targets, in column order.
    #[getter]
    fn targets(&self) -> Vec<String> {
        self.targets.clone()
    }

    /// Side of the pin image, pixels.
    #[getter]
    fn pin_side(&self) -> usize {
        self.preprocess.output_px
    }

    /// Where the network runs.
    #[getter]
    fn runtime(&self) -> &'static str {
        self.runtime.name()
    }

    fn __repr__(&self) -> String {
        format!(
            "PoseEstimator('{}', runtime='{}', targets={:?})",
            self.model_dir.display(),
            self.runtime,
            self.targets
        )
    }
}
