//! A whole palpation run, as `tactile run` and Python's `tactile.run` make
//! it: a source of frames, the models, and every output asked for (JSON
//! Lines records, an MCAP file of ROS 2 messages, a live Foxglove view,
//! overlay pictures). The front ends parse their arguments and print; the
//! order of the checks lives here once: the source first (a bad folder or
//! video is reported before any model loads), then every output (an
//! unwritable folder, one of the inputs, two outputs naming one place),
//! then the models, so nothing fails after the frames were processed.

use std::path::{Path, PathBuf};

use tactile_core::dataset;
use tactile_pipeline::run::JsonLines;
use tactile_pipeline::{
    Flow, FrameSource, Hysteresis, Pipeline, RunOptions, RunSummary, Runtime, SourceOptions,
    SourceSpec,
};

use crate::live::LiveView;
use crate::{McapResults, Result, RobotOutputs, Topic};

/// What a run reads and where its results go.
#[derive(Debug, Clone)]
pub struct RunRequest {
    /// The frames: a dataset, a folder, an image, a video, a bag, a camera
    /// or raw frames on standard input.
    pub source: SourceSpec,
    /// Decoding ahead, the live queue and a frame limit.
    pub source_options: SourceOptions,
    /// The models folder (detector/, segmenter/, depth/) or a calibrated
    /// sensor's folder.
    pub models: PathBuf,
    /// Where the networks run.
    pub runtime: Runtime,
    /// onnxruntime intra-op threads.
    pub threads: usize,
    /// Copies of the models processing frames at once, each on a thread
    /// of its own (a recorded source without a hysteresis:
    /// [`tactile_pipeline::run::check_pipelines`]).
    pub pipelines: usize,
    /// Two-threshold filter on the detector per sequence: `(on, off)`.
    pub hysteresis: Option<(f32, f32)>,
    /// JSON Lines records (`-`: standard output), or ROS 2 messages for a
    /// name ending in `.mcap`.
    pub out: Option<PathBuf>,
    /// A new folder for overlay pictures.
    pub render: Option<PathBuf>,
    /// Also write (and serve) the input frames on `/tactile/image`.
    pub with_frames: bool,
    /// Serve the results live to Foxglove at this `HOST:PORT`.
    pub view: Option<String>,
    /// With `view`: seconds [`RunSession::wait_for_viewer`] holds the run
    /// for a viewer to subscribe before the first frame (0: none).
    pub view_wait: f64,
}

impl RunRequest {
    /// A run of `models` over `source` on onnxruntime with one thread and
    /// no outputs besides its summary.
    pub fn new(source: SourceSpec, models: impl Into<PathBuf>) -> Self {
        Self {
            source,
            source_options: SourceOptions::default(),
            models: models.into(),
            runtime: Runtime::Onnx,
            threads: 1,
            pipelines: 1,
            hysteresis: None,
            out: None,
            render: None,
            with_frames: false,
            view: None,
            view_wait: 0.0,
        }
    }

    /// Whether the records go to standard output.
    pub fn records_to_stdout(&self) -> bool {
        self.out.as_deref() == Some(Path::new("-"))
    }
}

/// A run whose source, outputs and models are open and checked, ready to
/// go over its frames.
pub struct RunSession {
    source: FrameSource,
    /// The first's warnings stand for all (copies of one folder).
    pipelines: Vec<Pipeline>,
    options: RunOptions,
    robot: RobotOutputs,
    records: Option<JsonLines>,
    records_file: Option<PathBuf>,
    view_wait: f64,
}

/// What a run did: the pipeline's summary and where its outputs went.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RunReport {
    /// Speed, latency and decisions over the frames.
    #[serde(flatten)]
    pub summary: RunSummary,
    /// The JSON Lines file written (not standard output).
    pub records: Option<PathBuf>,
    /// The MCAP file written.
    pub mcap: Option<PathBuf>,
    /// Frames written to the MCAP file.
    pub mcap_frames: Option<u64>,
    /// Frames handed to the live view and dropped by it (viewer behind).
    pub live_sent: Option<u64>,
    /// Frames the live view dropped because its viewer was behind.
    pub live_dropped: Option<u64>,
    /// The overlay folder written.
    pub render: Option<PathBuf>,
    /// What the source found only while it was read (e.g. a video's
    /// frames of another size); the front ends show them as warnings.
    #[serde(skip)]
    pub late_warnings: Vec<String>,
}

impl RunSession {
    /// Open the source, check every output and load the models, in that
    /// order, so a bad input or output is reported before any model
    /// loads and nothing is written before the run.
    pub fn open(request: &RunRequest) -> Result<Self> {
        if let Some((on, off)) = request.hysteresis {
            Hysteresis::new(on, off)?;
        }
        crate::live::check_wait_seconds("view_wait", request.view_wait)?;
        if request.view_wait > 0.0 && request.view.is_none() {
            return Err(tactile_core::Error::Config(
                "view_wait: waits for a viewer of the live view, and this run serves none: \
                 give view too, or leave view_wait out"
                    .into(),
            )
            .into());
        }
        // Where the records go: a file (not `-`, standard output), as ROS 2
        // messages when its name says MCAP.
        let out = request
            .out
            .as_deref()
            .filter(|_| !request.records_to_stdout());
        let mcap_out = out.filter(|p| tactile_core::bag::is_bag_file(p));
        if request.with_frames && mcap_out.is_none() && request.view.is_none() {
            return Err(tactile_core::Error::Config(
                "with_frames: the input frames go to an .mcap out or to the live view, \
                 and this run has neither: give one, or leave with_frames out"
                    .into(),
            )
            .into());
        }
        let source = FrameSource::open(&request.source, request.source_options)?;
        let data = match &request.source {
            SourceSpec::Path(p) | SourceSpec::Bag { path: p, .. } => Some(p.as_path()),
            _ => None,
        };
        let inputs: Vec<_> = source.dataset().into_iter().collect();
        if let (Some(out), Some(render)) = (out, &request.render) {
            dataset::refuse_same_output(out, render)?;
        }
        if let Some(out) = out {
            dataset::check_run_output(out, data, &inputs)?;
            // After the refusals that say an output would destroy something;
            // an `.mcap` name (ROS 2 messages) is no misnamed JSON Lines.
            dataset::refuse_misnamed_results(out, dataset::ResultsFormat::JsonLines)?;
        }
        if let Some(dir) = &request.render {
            dataset::check_output_dir(dir, &inputs)?;
            tactile_core::io::refuse_folder_with_files(dir)?;
        }
        tactile_pipeline::run::check_pipelines(
            request.pipelines,
            request.hysteresis,
            source.kind(),
        )
        .map_err(Box::new)?;
        let load = || Pipeline::load(&request.models, request.runtime, request.threads);
        let pipeline = load().map_err(Box::new)?;
        let topics = Topic::written_by(&pipeline, request.with_frames);
        let mut pipelines = vec![pipeline];
        for _ in 1..request.pipelines {
            pipelines.push(load().map_err(Box::new)?);
        }
        let robot = RobotOutputs {
            mcap: mcap_out
                .map(|p| McapResults::create(p, &topics))
                .transpose()?,
            live: request
                .view
                .as_deref()
                .map(|a| LiveView::serve(a, &topics))
                .transpose()?,
            with_frames: request.with_frames,
        };
        let json_out = request.out.as_deref().filter(|_| mcap_out.is_none());
        let records = json_out
            .map(JsonLines::create)
            .transpose()
            .map_err(Box::new)?;
        Ok(Self {
            source,
            pipelines,
            options: RunOptions {
                hysteresis: request.hysteresis,
                render: request.render.clone(),
            },
            robot,
            records,
            records_file: json_out
                .filter(|_| !request.records_to_stdout())
                .map(Path::to_path_buf),
            view_wait: request.view_wait,
        })
    }

    /// What the models and the source noted when they opened (palpation
    /// models beside a calibration that cannot all be read; files of a
    /// folder that are not frames, gaps in the numbering, one split of a
    /// bag read alone).
    pub fn warnings(&self) -> Vec<String> {
        let mut w = self.pipelines[0].warnings.clone();
        w.extend(self.source.warnings());
        w
    }

    /// The live view's address to open in Foxglove, when serving.
    pub fn live_url(&self) -> Option<String> {
        self.robot.live.as_ref().map(LiveView::url)
    }

    /// Hold the run up to the request's `view_wait` seconds for a viewer
    /// to subscribe (replaying a recording to watch it); whether one did.
    /// Without a wait or a live view, at once false.
    pub fn wait_for_viewer(&self) -> Result<bool> {
        match &self.robot.live {
            Some(l) if self.view_wait > 0.0 => l.wait_for_viewer(self.view_wait),
            _ => Ok(false),
        }
    }

    /// Go over every frame, writing each output as records are made;
    /// every file appears when the run ends (an error or an interrupt
    /// leaves none).
    pub fn run(self) -> Result<RunReport> {
        let Self {
            mut source,
            mut pipelines,
            options,
            mut robot,
            mut records,
            records_file,
            ..
        } = self;
        let summary = tactile_pipeline::run(&mut pipelines, &mut source, &options, &mut |item| {
            robot.handle(item).map_err(tactile_core::Error::from)?;
            records
                .as_mut()
                .map_or(Ok(Flow::Continue), |r| r.write(item.record))
        })
        .map_err(Box::new)?;
        if let Some(r) = records {
            r.finish().map_err(Box::new)?;
        }
        let live = robot.live.is_some();
        let robot = robot.finish()?;
        Ok(RunReport {
            summary,
            records: records_file,
            mcap_frames: robot.mcap.as_ref().map(|m| m.1),
            mcap: robot.mcap.map(|m| m.0),
            live_sent: live.then_some(robot.live_sent),
            live_dropped: live.then_some(robot.live_dropped),
            render: options.render,
            late_warnings: source.late_warnings(),
        })
    }
}
