//! Results into the robot stack from Python: `tactile.McapWriter` writes
//! `Pipeline.process` results as ROS 2 messages to an MCAP file, and
//! `tactile.LiveView` serves them to Foxglove, through the same encoder
//! as `tactile run --out X.mcap` and `--view` (`tactile_ros`).

use std::path::PathBuf;
use std::sync::Mutex;

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use tactile_ros::live::LiveView;
use tactile_ros::{FrameMessages, McapResults, Topic};

use crate::args::{Given, PathArg, Whole, optional};
use crate::errors::PyResultExt;
use crate::frame::{FrameArg, Layout};
use crate::pipeline::FrameResult;

/// `stamp_ns=`: nanoseconds as a ROS 2 stamp's signed 64 bits hold them
/// (which stamps a message can carry is the library's check).
fn stamp(arg: Option<&Whole>) -> PyResult<Option<i64>> {
    optional(arg, "stamp_ns", i64::MIN, i64::MAX)
}

/// The messages of one result, stamped `stamp_ns` when given, with the
/// `(H, W, 3)` uint8 `frame` when given.
fn encode(
    result: &FrameResult,
    frame: Option<&Bound<'_, PyAny>>,
    stamp_ns: Option<i64>,
) -> PyResult<FrameMessages> {
    let mut record = result.record.clone();
    if stamp_ns.is_some() {
        record.stamp_ns = stamp_ns;
    }
    let views = result.views.as_ref();
    match frame {
        None => FrameMessages::encode(&record, views, None).py(),
        Some(f) => {
            let arg = FrameArg::new(f, Layout::Rgb, "frame")?;
            arg.view()
                .with_rgb(|img| FrameMessages::encode(&record, views, Some(img)))
                .py()?
                .py()
        }
    }
}

/// An MCAP file of ROS 2 result messages (the channels of
/// `tactile run --out results.mcap`, docs/robots.md). It appears at `path`
/// on `close()` (or leaving a `with` block without an error); dropped
/// before that, nothing is left.
#[pyclass(module = "tactile", name = "McapWriter")]
pub struct PyMcapWriter {
    inner: Mutex<Option<McapResults>>,
    path: PathBuf,
}

impl PyMcapWriter {
    fn with<R>(&self, f: impl FnOnce(&mut McapResults) -> PyResult<R>) -> PyResult<R> {
        let mut g = self
            .inner
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the MCAP writer failed in another thread"))?;
        match g.as_mut() {
            Some(w) => f(w),
            None => Err(PyValueError::new_err(format!(
                "{}: the MCAP writer is closed",
                self.path.display()
            ))),
        }
    }
}

#[pymethods]
impl PyMcapWriter {
    /// Refused: one file has one writer.
    fn __reduce__(&self) -> PyResult<Py<PyAny>> {
        Err(crate::pickling::open_stream(
            "McapWriter",
            "an MCAP file being written",
            "Send the results (FrameResult pickles) back to the process that writes the file",
        ))
    }

    #[new]
    fn new(py: Python<'_>, path: PathArg) -> PyResult<Self> {
        crate::args::keywords!(path);
        let p = path.clone();
        // Paper B's pipeline's topics now, so a reader lists them even when
        // no frame had a tendon; the input frame and a sensor's indentation
        // when first written.
        let topics = Topic::written(true, false, false);
        let w = py.detach(move || McapResults::create(&p, &topics)).py()?;
        Ok(Self {
            inner: Mutex::new(Some(w)),
            path,
        })
    }

    /// Write one `Pipeline.process` result; `frame` (the input, `(H, W, 3)`
    /// uint8) goes on /tactile/image when given; `stamp_ns` stamps every
    /// message (default: the time now).
    #[pyo3(signature = (result, frame=None, *, stamp_ns=None))]
    fn write(
        &self,
        result: Given<PyRef<'_, FrameResult>>,
        frame: Option<&Bound<'_, PyAny>>,
        stamp_ns: Option<Whole>,
    ) -> PyResult<()> {
        crate::args::keywords!(result);
        let m = encode(&result, frame, stamp(stamp_ns.as_ref())?)?;
        self.with(|w| w.write(&m).py())
    }

    /// Frames written so far.
    #[getter]
    fn frames(&self) -> PyResult<u64> {
        self.with(|w| Ok(w.frames()))
    }

    /// Finish the file and move it into place; returns its path.
    fn close(&self, py: Python<'_>) -> PyResult<PathBuf> {
        let w = self
            .inner
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the MCAP writer failed in another thread"))?
            .take();
        match w {
            Some(w) => py.detach(move || w.finish()).py(),
            None => Ok(self.path.clone()),
        }
    }

    fn __enter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    /// Leaving a `with` block: finished on success, discarded on an error.
    #[pyo3(signature = (exc_type=None, _exc=None, _tb=None))]
    fn __exit__(
        &self,
        py: Python<'_>,
        exc_type: Option<&Bound<'_, PyAny>>,
        _exc: Option<&Bound<'_, PyAny>>,
        _tb: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<bool> {
        if exc_type.is_some_and(|t| !t.is_none()) {
            if let Ok(mut g) = self.inner.lock() {
                g.take();
            }
        } else {
            self.close(py)?;
        }
        Ok(false)
    }
}

/// The Foxglove live view (`tactile run --view`): the result channels
/// served over the Foxglove WebSocket protocol at `address` (`HOST:PORT`;
/// port 0 picks a free one, see `port`). `publish` never waits: results
/// are encoded only while a viewer is subscribed, and dropped (counted in
/// `dropped`) when the server's thread is behind.
#[pyclass(module = "tactile", name = "LiveView")]
pub struct PyLiveView {
    inner: Mutex<Option<LiveView>>,
}

impl PyLiveView {
    fn with<R>(&self, f: impl FnOnce(&LiveView) -> PyResult<R>) -> PyResult<R> {
        let g = self
            .inner
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the live view failed in another thread"))?;
        match g.as_ref() {
            Some(v) => f(v),
            None => Err(PyValueError::new_err("the live view is closed")),
        }
    }
}

#[pymethods]
impl PyLiveView {
    /// Refused: the server runs in the process that started it.
    fn __reduce__(&self) -> PyResult<Py<PyAny>> {
        Err(crate::pickling::open_stream(
            "LiveView",
            "a running server",
            "Send the results (FrameResult pickles) back to the process that serves them",
        ))
    }

    #[new]
    #[pyo3(
        signature = (address=Given::of("127.0.0.1:8765")),
        text_signature = "(address='127.0.0.1:8765')"
    )]
    fn new(py: Python<'_>, address: Given<String>) -> PyResult<Self> {
        crate::args::keywords!(address);
        // Any pipeline's results may come: every topic.
        let v = py
            .detach(move || LiveView::serve(&address, &Topic::ALL))
            .py()?;
        Ok(Self {
            inner: Mutex::new(Some(v)),
        })
    }

    /// Send one `Pipeline.process` result (and the input `frame` when
    /// given); returns whether a viewer was subscribed.
    #[pyo3(signature = (result, frame=None, *, stamp_ns=None))]
    fn publish(
        &self,
        result: Given<PyRef<'_, FrameResult>>,
        frame: Option<&Bound<'_, PyAny>>,
        stamp_ns: Option<Whole>,
    ) -> PyResult<bool> {
        crate::args::keywords!(result);
        let stamp_ns = stamp(stamp_ns.as_ref())?;
        // A stamp no message can hold is refused whether or not a viewer
        // watches, so a script tried without one fails as it would live.
        if let Some(s) = stamp_ns {
            tactile_ros::checked_stamp(&result.record.frame, s).py()?;
        }
        if !self.with(|v| Ok(v.watched()))? {
            return Ok(false);
        }
        let m = encode(&result, frame, stamp_ns)?;
        self.with(|v| {
            v.publish(m);
            Ok(true)
        })
    }

    /// The port served.
    #[getter]
    fn port(&self) -> PyResult<u16> {
        self.with(|v| Ok(v.port()))
    }

    /// The address a viewer opens (`ws://HOST:PORT`, an IPv6 host in
    /// brackets).
    #[getter]
    fn url(&self) -> PyResult<String> {
        self.with(|v| Ok(v.url()))
    }

    /// Wait up to `seconds` (at most an hour) for a viewer to subscribe,
    /// so a recording is watched from its first frame; true when one did.
    /// Ctrl-C ends the wait with `KeyboardInterrupt`.
    fn wait_for_viewer(&self, py: Python<'_>, seconds: f64) -> PyResult<bool> {
        self.with(|v| crate::work::interruptible(py, || v.wait_for_viewer(seconds).py()))
    }

    /// Whether a viewer is subscribed.
    #[getter]
    fn watched(&self) -> PyResult<bool> {
        self.with(|v| Ok(v.watched()))
    }

    /// Results handed to the server.
    #[getter]
    fn sent(&self) -> PyResult<u64> {
        self.with(|v| Ok(v.sent()))
    }

    /// Results dropped because the server's thread was behind.
    #[getter]
    fn dropped(&self) -> PyResult<u64> {
        self.with(|v| Ok(v.dropped()))
    }

    /// Send what is queued and stop serving.
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        let v = self
            .inner
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the live view failed in another thread"))?
            .take();
        if let Some(mut v) = v {
            py.detach(move || v.close());
        }
        Ok(())
    }

    fn __enter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    #[pyo3(signature = (_exc_type=None, _exc=None, _tb=None))]
    fn __exit__(
        &self,
        py: Python<'_>,
        _exc_type: Option<&Bound<'_, PyAny>>,
        _exc: Option<&Bound<'_, PyAny>>,
        _tb: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<bool> {
        self.close(py)?;
        Ok(false)
    }
}
