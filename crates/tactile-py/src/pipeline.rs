//! `tactile.Pipeline`: paper B's palpation pipeline on numpy frames.

use std::path::PathBuf;
use std::sync::{Mutex, OnceLock};

use numpy::{IntoPyArray, PyArray2, PyArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tactile_burn::Runtime;
use tactile_pipeline::{FrameRecord, FrameViews, Hysteresis, Pipeline};

use crate::args::{Given, PathArg, Whole};
use crate::errors::PyResultExt;
use crate::frame::{FrameArg, Layout, each_frame};

/// onnxruntime's intra-op threads as the command line bounds them.
pub(crate) fn threads(arg: &Whole) -> PyResult<usize> {
    arg.within("threads", 1, tactile_onnx::runtime::MAX_THREADS)
}

/// Parse a runtime name as the command line does.
pub(crate) fn runtime(name: &str) -> PyResult<Runtime> {
    name.parse::<Runtime>().py()
}

struct State {
    pipeline: Pipeline,
    filter: Option<Hysteresis>,
    frames: u64,
}

/// Paper B's palpation pipeline: the detector on every frame; the
/// segmenter, the direction and the depth network only on tendon frames.
/// A calibrated sensor's folder (`tactile calibrate ball`) adds the skin's
/// indentation on every frame, or gives only that when it holds no
/// palpation models, or models that cannot all be read yet (one still
/// being trained: a `UserWarning` says so).
///
/// Thread-safe: calls from several threads take turns on the models, and
/// the interpreter lock is released while a frame is processed.
#[pyclass(module = "tactile", name = "Pipeline")]
pub struct PyPipeline {
    state: Mutex<State>,
    models: PathBuf,
    runtime: Runtime,
    threads: usize,
    hysteresis: Option<(f32, f32)>,
    threshold: Option<f64>,
}

impl PyPipeline {
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, State>> {
        self.state
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the pipeline failed in another thread"))
    }

    /// Process one frame, named `what` in messages (`frame`, `frames[i]`).
    fn process_named(
        &self,
        py: Python<'_>,
        frame: &Bound<'_, PyAny>,
        what: &str,
    ) -> PyResult<FrameResult> {
        let arg = FrameArg::new(frame, Layout::Rgb, what)?;
        let px = arg.view();
        let (rec, views) = py.detach(|| -> PyResult<_> {
            let mut st = self.lock()?;
            let State {
                pipeline,
                filter,
                frames,
            } = &mut *st;
            let name = frames.to_string();
            let out = px
                .with_rgb(|img| pipeline.process_filtered(&name, img, filter.as_mut()))
                .py()?
                .py()?;
            *frames += 1;
            Ok(out)
        })?;
        Ok(FrameResult::new(rec, views, (px.width, px.height)))
    }
}

#[pymethods]
impl PyPipeline {
    /// Load `detector/`, `segmenter/` and `depth/` from `models` (and the
    /// calibration, when `models` is a calibrated sensor's folder) onto
    /// `runtime` ("onnx", "burn-flex" or "burn-ndarray"). `threads` is
    /// onnxruntime's intra-op threads (1 to 256); `hysteresis=(on, off)`
    /// filters the tendon decision over a sequence (see `reset`).
    #[new]
    #[pyo3(
        signature = (models=PathArg::of("models"), runtime=Given::of("onnx"), *, threads=Whole::of(1), hysteresis=None),
        text_signature = "(models='models', runtime='onnx', *, threads=1, hysteresis=None)"
    )]
    fn new(
        py: Python<'_>,
        models: PathArg,
        runtime: Given<String>,
        threads: Whole,
        hysteresis: Option<Given<[f32; 2]>>,
    ) -> PyResult<Self> {
        crate::args::keywords!(models, runtime, hysteresis);
        // A pair as a tuple or a list.
        let hysteresis = hysteresis.map(|[on, off]| (on, off));
        let rt = crate::pipeline::runtime(&runtime)?;
        let threads = self::threads(&threads)?;
        let filter = hysteresis
            .map(|(on, off)| Hysteresis::new(on, off))
            .transpose()
            .py()?;
        let dir = models.clone();
        let pipeline = py.detach(move || Pipeline::load(&dir, rt, threads)).py()?;
        for w in &pipeline.warnings {
            crate::errors::user_warning(py, w)?;
        }
        let threshold = pipeline.threshold();
        Ok(Self {
            state: Mutex::new(State {
                pipeline,
                filter,
                frames: 0,
            }),
            models,
            runtime: rt,
            threads,
            hysteresis,
            threshold,
        })
    }

    /// Process one `(H, W, 3)` uint8 RGB frame of any size (a frame a
    /// calibrated sensor cannot read, of another size than its
    /// calibration's or grey for a colour one, is another sensor's:
    /// `out_of_distribution`, `unreadable` says why, and it gets nothing).
    fn process(&self, py: Python<'_>, frame: &Bound<'_, PyAny>) -> PyResult<FrameResult> {
        self.process_named(py, frame, "frame")
    }

    /// Process frames in order: an `(N, H, W, 3)` array or any iterable of
    /// `(H, W, 3)` frames (one `(H, W, 3)` array is one frame). Returns one
    /// result per frame.
    fn process_many(
        &self,
        py: Python<'_>,
        frames: &Bound<'_, PyAny>,
    ) -> PyResult<Vec<FrameResult>> {
        each_frame(frames, |f, what| self.process_named(py, f, what))
    }

    /// Time the pipeline inside Rust on `frame`, `repeats` times, without
    /// the Python call around it: milliseconds per run. With the same loop
    /// over `process`, this measures what the binding costs.
    #[pyo3(signature = (frame, repeats=Whole::of(100)), text_signature = "(self, frame, repeats=100)")]
    fn time_in_rust(
        &self,
        py: Python<'_>,
        frame: &Bound<'_, PyAny>,
        repeats: Whole,
    ) -> PyResult<Vec<f64>> {
        let repeats = repeats.within("repeats", 1u64, 1_000_000)?;
        let arg = FrameArg::new(frame, Layout::Rgb, "frame")?;
        let px = arg.view();
        crate::work::interruptible(py, || -> PyResult<Vec<f64>> {
            let mut st = self.lock()?;
            let State {
                pipeline, filter, ..
            } = &mut *st;
            px.with_rgb(|img| -> PyResult<Vec<f64>> {
                (0..repeats)
                    .map(|_| {
                        tactile_core::interrupt::check().py()?;
                        let t = std::time::Instant::now();
                        pipeline.process_filtered("", img, filter.as_mut()).py()?;
                        Ok(1e3 * t.elapsed().as_secs_f64())
                    })
                    .collect()
            })
            .py()?
        })
    }

    /// Start a new sequence: the hysteresis forgets its state and frame
    /// numbering starts again at 0.
    fn reset(&self) -> PyResult<()> {
        let mut st = self.lock()?;
        if let Some(f) = st.filter.as_mut() {
            f.reset();
        }
        st.frames = 0;
        Ok(())
    }

    /// The frame as the detector takes it and as its standalone ONNX export
    /// (`tactile export --standalone`) reads it: resized to the detector's
    /// input, `(H, W, 3)` levels of its bits per channel (uint8, or uint16
    /// for a 16-bit detector). The standalone model given this answers as
    /// `process` does.
    fn detector_frame<'py>(
        &self,
        py: Python<'py>,
        frame: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let arg = FrameArg::new(frame, Layout::Rgb, "frame")?;
        let px = arg.view();
        let (levels, bits, [w, h]) = py.detach(|| -> PyResult<_> {
            let st = self.lock()?;
            let model = &st
                .pipeline
                .detector()
                .ok_or_else(|| {
                    PyValueError::new_err(format!(
                        "{}: no detector/ in this models folder (a calibration alone)",
                        self.models.display()
                    ))
                })?
                .artifact
                .model;
            let levels = px.with_rgb(|img| model.frame_levels(img)).py()?.py()?;
            Ok((levels, model.bits(), model.input_size))
        })?;
        let shape = [h, w, 3];
        Ok(if bits == 16 {
            levels.into_pyarray(py).reshape(shape)?.into_any()
        } else {
            let bytes: Vec<u8> = levels.into_iter().map(|v| v as u8).collect();
            bytes.into_pyarray(py).reshape(shape)?.into_any()
        })
    }

    /// The detector's probability threshold (None: the folder holds only
    /// a sensor calibration).
    #[getter]
    fn threshold(&self) -> Option<f64> {
        self.threshold
    }

    /// Whether the folder is a calibrated sensor's: every result then
    /// carries the skin's indentation (`indentation_m`).
    #[getter]
    fn calibrated(&self) -> PyResult<bool> {
        Ok(self.lock()?.pipeline.sensor.is_some())
    }

    /// Where the networks run.
    #[getter]
    fn runtime(&self) -> &'static str {
        self.runtime.name()
    }

    /// The models folder.
    #[getter]
    fn models(&self) -> PathBuf {
        self.models.clone()
    }

    /// onnxruntime intra-op threads.
    #[getter]
    fn threads(&self) -> usize {
        self.threads
    }

    /// The hysteresis `(on, off)`, or None.
    #[getter]
    fn hysteresis(&self) -> Option<(f32, f32)> {
        self.hysteresis
    }

    /// Refused, saying what to send to a worker process instead.
    fn __reduce__(&self) -> PyResult<Py<PyAny>> {
        Err(crate::pickling::holds_models(
            "Pipeline",
            Some("a stream's hysteresis state"),
            "tactile.Pipeline(models, threads=1)",
        ))
    }

    fn __repr__(&self) -> String {
        format!(
            "Pipeline(models='{}', runtime='{}', threads={}, hysteresis={:?})",
            self.models.display(),
            self.runtime,
            self.threads,
            self.hysteresis
        )
    }
}

/// What the pipeline made of one frame. `mask` and `depth_m` are built at
/// the frame's resolution on first access.
#[pyclass(module = "tactile", name = "FrameResult", frozen)]
pub struct FrameResult {
    pub(crate) record: FrameRecord,
    pub(crate) views: Option<FrameViews>,
    size: (usize, usize),
    mask: OnceLock<Py<PyArray2<bool>>>,
    depth: OnceLock<Option<Py<PyArray2<f32>>>>,
    indentation: OnceLock<Option<Py<PyArray2<f32>>>>,
}

impl FrameResult {
    /// A result of `size` (width, height) whose arrays are built from
    /// `views` on first access.
    pub(crate) fn new(
        record: FrameRecord,
        views: Option<FrameViews>,
        size: (usize, usize),
    ) -> Self {
        Self {
            record,
            views,
            size,
            mask: OnceLock::new(),
            depth: OnceLock::new(),
            indentation: OnceLock::new(),
        }
    }

    /// What a pickle keeps: the record, the views and the size, as
    /// [`crate::pickling::frame_result`] reads them back.
    pub(crate) fn state(&self) -> (&FrameRecord, Option<&FrameViews>, (usize, usize)) {
        (&self.record, self.views.as_ref(), self.size)
    }
}

#[pymethods]
impl FrameResult {
    /// Whether a tendon is under the skin (the detector's threshold, or
    /// the hysteresis when the pipeline has one).
    #[getter]
    fn tendon(&self) -> bool {
        self.record.tendon
    }

    /// The detector's own threshold decision (before any hysteresis).
    #[getter]
    fn tendon_raw(&self) -> bool {
        self.record.tendon_raw
    }

    /// True when the frame does not look like the sensor's (its input
    /// statistics are far from the training frames', a calibration's rest
    /// frame unlike it, or a calibrated sensor cannot read it): no tendon,
    /// direction, depth or indentation is given.
    #[getter]
    fn out_of_distribution(&self) -> bool {
        self.record.out_of_distribution
    }

    /// Why a calibrated sensor cannot read the frame (another size than
    /// its calibration's, grey for a sensor calibrated in colour); None
    /// when it can.
    #[getter]
    fn unreadable(&self) -> Option<String> {
        self.record.unreadable.clone()
    }

    /// The detector's gate that answered without the network: "blank" (no
    /// channel varies) or "foreign" (out of distribution); None when the
    /// network answered. The same answer `tactile eval detector` scores.
    #[getter]
    fn gate(&self) -> Option<&'static str> {
        self.record.gate.map(tactile_detect::Gate::name)
    }

    /// How far the frame's input statistics lie from the training frames',
    /// in spreads (None when the detector has no input profile).
    #[getter]
    fn input_score(&self) -> Option<f32> {
        self.record.input_score
    }

    /// Detector probability.
    #[getter]
    fn score(&self) -> f32 {
        self.record.score
    }

    /// Direction of the tendon in degrees, [0, 180), image axes (x right,
    /// y down); None without a tendon or a clear direction.
    #[getter]
    fn direction_deg(&self) -> Option<f64> {
        self.record.direction_deg
    }

    /// Major / minor eigenvalue of the kept region; None without a direction.
    #[getter]
    fn anisotropy(&self) -> Option<f64> {
        self.record.anisotropy
    }

    /// Why a tendon frame has no direction (empty, too small, isotropic).
    #[getter]
    fn no_direction(&self) -> Option<String> {
        self.record.no_direction.clone()
    }

    /// Pixels of the kept region in the segmenter's window.
    #[getter]
    fn mask_area_px(&self) -> usize {
        self.record.mask_area_px
    }

    /// The kept tendon region, `(H, W)` bool at the frame's resolution
    /// (all False on frames without a tendon).
    #[getter]
    fn mask<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<bool>>> {
        let (w, h) = self.size;
        // Built outside the cell: a thread waiting on a OnceLock while
        // holding the interpreter would deadlock the one building it.
        if self.mask.get().is_none() {
            let data = match self.views.as_ref().and_then(|v| v.tendon.as_ref()) {
                Some(v) => py.detach(|| v.mask_at(w, h)),
                None => vec![false; w * h],
            };
            let arr = ndarray::Array2::from_shape_vec((h, w), data)
                .map_err(|e| PyValueError::new_err(e.to_string()))?;
            let _ = self.mask.set(arr.into_pyarray(py).unbind());
        }
        match self.mask.get() {
            Some(m) => Ok(m.bind(py).clone()),
            None => Err(PyRuntimeError::new_err("mask unavailable")),
        }
    }

    /// The depth network's map, `(H, W)` float32 metres at the frame's
    /// resolution: camera-to-skin distance, or for a calibrated sensor's
    /// depth network (`depth_maps == "indentation"`) the skin's
    /// indentation; None on frames gated out by the detector.
    #[getter]
    fn depth_m<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f32>>>> {
        let (w, h) = self.size;
        if self.depth.get().is_none() {
            let made = match self.views.as_ref().and_then(|v| v.tendon.as_ref()) {
                Some(v) => {
                    let data = py.detach(|| v.depth_m_at(w, h)).py()?;
                    let arr = ndarray::Array2::from_shape_vec((h, w), data)
                        .map_err(|e| PyValueError::new_err(e.to_string()))?;
                    Some(arr.into_pyarray(py).unbind())
                }
                None => None,
            };
            let _ = self.depth.set(made);
        }
        Ok(self
            .depth
            .get()
            .and_then(|d| d.as_ref().map(|a| a.bind(py).clone())))
    }

    /// A calibrated sensor's skin: how far each pixel is pushed toward the
    /// camera, `(H, W)` float32 metres at the frame's resolution (0 at
    /// rest); None for a folder without a calibration.
    #[getter]
    fn indentation_m<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f32>>>> {
        if self.indentation.get().is_none() {
            let made = match self.views.as_ref().and_then(|v| v.indentation.as_ref()) {
                Some(s) => {
                    let m = &s.map;
                    let arr = ndarray::Array2::from_shape_vec(
                        (m.height, m.width),
                        m.indentation_m.clone(),
                    )
                    .map_err(|e| PyValueError::new_err(e.to_string()))?;
                    Some(arr.into_pyarray(py).unbind())
                }
                None => None,
            };
            let _ = self.indentation.set(made);
        }
        Ok(self
            .indentation
            .get()
            .and_then(|d| d.as_ref().map(|a| a.bind(py).clone())))
    }

    /// A calibrated sensor: the deepest indentation, mm (None without a
    /// calibration).
    #[getter]
    fn indentation_peak_mm(&self) -> Option<f32> {
        self.record.indentation_peak_mm
    }

    /// A calibrated sensor: the area in contact (pushed in past 0.03 mm),
    /// mm² (None without a calibration).
    #[getter]
    fn contact_area_mm2(&self) -> Option<f32> {
        self.record.contact_area_mm2
    }

    /// What `depth_m` holds on this frame: "distance" or "indentation"
    /// (None when the depth network did not run).
    #[getter]
    fn depth_maps(&self) -> Option<&'static str> {
        self.record.depth_maps.map(|m| m.name())
    }

    /// Smallest, mean and largest camera-to-skin distance (or indentation) inside the
    /// sensing window, mm; None when gated out.
    #[getter]
    fn depth_mm_stats(&self) -> Option<(f32, f32, f32)> {
        let r = &self.record;
        Some((r.depth_min_mm?, r.depth_mean_mm?, r.depth_max_mm?))
    }

    /// Milliseconds per stage: prepare (a large frame brought down to the
    /// working resolution), detect, segment (segmenter and direction),
    /// depth, reconstruct (a calibrated sensor), total. Stages a frame did
    /// not run are absent.
    #[getter]
    fn ms<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.record;
        let d = PyDict::new(py);
        d.set_item("prepare", r.ms_prepare)?;
        d.set_item("detect", r.ms_detect)?;
        if let Some(v) = r.ms_segment {
            d.set_item("segment", v)?;
        }
        if let Some(v) = r.ms_depth {
            d.set_item("depth", v)?;
        }
        if let Some(v) = r.ms_reconstruct {
            d.set_item("reconstruct", v)?;
        }
        d.set_item("total", r.ms_total)?;
        Ok(d)
    }

    /// The record `tactile run` writes for this frame (one JSON Lines
    /// object), as a dict.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::json::to_py(py, &self.record)
    }

    /// Pickled whole (record, mask, depth and indentation as made), so a
    /// worker process's results come back as they were: `copy`, `pickle`,
    /// `multiprocessing` and `concurrent.futures` take it.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::pickling::reduce_frame_result(py, self)
    }

    fn __repr__(&self) -> String {
        let r = &self.record;
        match (r.tendon, r.direction_deg) {
            (false, _) => format!("FrameResult(tendon=False, score={:.3})", r.score),
            (true, Some(d)) => format!(
                "FrameResult(tendon=True, score={:.3}, direction_deg={d:.1})",
                r.score
            ),
            (true, None) => format!(
                "FrameResult(tendon=True, score={:.3}, direction_deg=None)",
                r.score
            ),
        }
    }
}
