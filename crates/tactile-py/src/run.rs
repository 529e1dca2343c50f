//! `tactile.run`: `tactile run` from Python, the same library session
//! ([`tactile_ros::RunSession`]): the palpation pipeline over a source of
//! frames, its records written as JSON Lines or ROS 2 messages in MCAP,
//! overlays rendered, results served live, and the summary returned.

use pyo3::prelude::*;
use tactile_ros::{RunRequest, RunSession};

use crate::args::{Given, PathArg, Whole};
use crate::errors::PyResultExt;
use crate::pipeline::runtime;
use crate::source::{source_limit, source_spec};
use crate::work::interruptible;

/// Run the pipeline of `models` over every frame of `source` (what
/// `tactile.frames` reads; `stdin_size=(w, h)` for raw rgb24 frames on
/// standard input) as `tactile run` does, and return its summary as the
/// dict the command line prints last, with `records`, `mcap`,
/// `mcap_frames`, `render`, `live_sent` and `live_dropped` saying where
/// the outputs went; the summary's warnings (frames a calibrated sensor
/// cannot read, frames unlike the sensor's) are also raised as
/// `UserWarning`s. Every output is checked before any model loads and
/// appears when the run ends; Ctrl-C stops it leaving none.
#[pyfunction]
#[pyo3(signature = (
    source=None, *, models=PathArg::of("models"), runtime=Given::of("onnx"), threads=Whole::of(1),
    pipelines=Whole::of(1), hysteresis=None, out=None, render=None, with_frames=Given::of(false), view=None,
    view_wait=Given::of(0.0), topic=None, stdin_size=None, live_queue=Whole::of(2), limit=None,
    prefetch=Given::of(true)
), text_signature = "(source=None, *, models='models', runtime='onnx', threads=1, pipelines=1, \
    hysteresis=None, out=None, render=None, with_frames=False, view=None, view_wait=0.0, topic=None, \
    stdin_size=None, live_queue=2, limit=None, prefetch=True)")]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run<'py>(
    py: Python<'py>,
    source: Option<PathArg>,
    models: PathArg,
    runtime: Given<String>,
    threads: Whole,
    pipelines: Whole,
    hysteresis: Option<Given<[f32; 2]>>,
    out: Option<PathArg>,
    render: Option<PathArg>,
    with_frames: Given<bool>,
    view: Option<Given<String>>,
    view_wait: Given<f64>,
    topic: Option<Given<String>>,
    stdin_size: Option<Given<[Whole; 2]>>,
    live_queue: Whole,
    limit: Option<Whole>,
    prefetch: Given<bool>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(
        source,
        models,
        out,
        render,
        runtime,
        hysteresis,
        with_frames,
        view,
        view_wait,
        topic,
        stdin_size,
        prefetch
    );
    let rt = self::runtime(&runtime)?;
    let threads = crate::pipeline::threads(&threads)?;
    let pipelines = pipelines.within("pipelines", 1, tactile_pipeline::run::MAX_PIPELINES)?;
    let request = RunRequest {
        source_options: tactile_pipeline::SourceOptions {
            overlap: prefetch,
            live_queue: crate::source::live_queue(&live_queue)?,
            limit: source_limit(limit.as_ref())?,
        },
        runtime: rt,
        threads,
        pipelines,
        // A pair as a tuple or a list.
        hysteresis: hysteresis.map(|[on, off]| (on, off)),
        out,
        render,
        with_frames,
        view,
        view_wait,
        ..RunRequest::new(source_spec(source, topic, stdin_size)?, models)
    };
    let session = interruptible(py, || RunSession::open(&request).py())?;
    for w in session.warnings() {
        crate::errors::user_warning(py, &w)?;
    }
    let report = interruptible(py, || {
        session.wait_for_viewer().py()?;
        session.run().py()
    })?;
    for w in report
        .late_warnings
        .iter()
        .chain(&report.summary.warnings())
    {
        crate::errors::user_warning(py, w)?;
    }
    crate::json::to_py(py, &report)
}
