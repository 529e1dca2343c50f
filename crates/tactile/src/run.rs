//! `tactile run`: the palpation pipeline over any source of frames (a
//! dataset, a folder, a video file, a camera, stdin); JSON Lines records
//! as they are made and a summary of speed, latency and decisions.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use tactile_burn::Runtime;
use tactile_pipeline::{SourceOptions, SourceSpec};
use tactile_ros::{RunRequest, RunSession};

#[derive(Args)]
pub(crate) struct RunArgs {
    /// The frames: a visuo-tactile dataset (frames in labels.csv order), a
    /// folder of frames (PNG, JPEG, BMP, TIFF, WebP or PGM/PPM; by the
    /// numbers in their names), one image, a TIFF of many pages (a stack,
    /// page by page), a video file (mp4, mkv, avi; decoded by FFmpeg, every frame),
    /// a ROS 2 bag (its folder, or one .mcap or .db3; see --topic), a V4L2 camera
    /// such as /dev/video0 (live) or a network stream's URL (rtsp://,
    /// http://, rtmp://, srt://, udp://, rtp://, tcp://; live, or every
    /// frame when it has a length, as a file served over HTTP).
    #[arg(long, required_unless_present = "stdin", conflicts_with = "stdin")]
    data: Option<PathBuf>,
    /// A ROS 2 bag's image topic (sensor_msgs/msg/Image or
    /// CompressedImage); without it, the bag's only image topic.
    #[arg(long, requires = "data")]
    topic: Option<String>,
    /// List the bag's image topics with their message counts and rates,
    /// and stop.
    #[arg(long, requires = "data")]
    list_topics: bool,
    /// Read raw rgb24 frames of --size from standard input (live), e.g.
    /// `ffmpeg -i cam -f rawvideo -pix_fmt rgb24 - | tactile run --stdin --size 640x360`.
    #[arg(long, requires = "size")]
    stdin: bool,
    /// The size of the frames on stdin, WIDTHxHEIGHT.
    #[arg(long, conflicts_with = "data")]
    size: Option<crate::args::Size>,
    /// Folder with detector/, segmenter/ and depth/; a calibrated sensor's
    /// folder (tactile calibrate ball) adds the skin's indentation to every
    /// record, or gives only that when it holds no detector/.
    #[arg(long, default_value = "models")]
    models: PathBuf,
    /// Where the networks run (onnx is the fastest here).
    #[arg(long, value_enum, default_value_t = Runtime::Onnx)]
    runtime: Runtime,
    /// onnxruntime intra-op threads. Default 1: these models are small
    /// enough that a second thread costs more than it gains (240 rendered
    /// 640x360 frames on 2 cores, median of 3 runs: 233 frames/s on one
    /// thread, 214 on two; without overlap 180 and 170), and the other
    /// core decodes the next frames. For more frames per second, give
    /// --pipelines.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=256))]
    threads: u16,
    /// Copies of the models that process frames at once, each on a thread
    /// of its own (a recorded source without --hysteresis; records stay in
    /// the source's order): more frames per second where --threads gives
    /// fewer, when the models rather than decoding are the slower part
    /// (README, "Commands"). At most 64.
    #[arg(long, default_value_t = 1)]
    pipelines: usize,
    /// JSON Lines, one record per frame as it is made: a file (it appears
    /// when the run ends) or `-` for standard output, flushed per frame
    /// (the summary then goes to standard error). A name ending in .mcap
    /// writes ROS 2 messages instead (docs/robots.md): the record, the
    /// tendon mask, the depth or indentation map and the direction, each
    /// stamped like its input frame.
    #[arg(long)]
    out: Option<PathBuf>,
    /// With an .mcap --out or --view: also the input frames, on /tactile/image.
    #[arg(long)]
    with_frames: bool,
    /// Serve the results live over the Foxglove WebSocket protocol at
    /// HOST:PORT (open Foxglove on ws://HOST:PORT); the pipeline never
    /// waits for a viewer (frames it cannot take are dropped and counted).
    #[arg(long, value_name = "HOST:PORT")]
    view: Option<String>,
    /// With --view: wait up to this many seconds for a viewer to subscribe
    /// before the first frame (replaying a bag or a video to watch it).
    #[arg(long, default_value_t = 0.0, requires = "view", value_parser = wait_seconds)]
    view_wait: f64,
    /// Process at most this many frames.
    #[arg(long)]
    limit: Option<u64>,
    /// Write an overlay PNG per tendon frame into this new folder (one
    /// that already holds files is refused and left alone)
    /// (NAME-overlay.png): the segmenter's window with the kept region in
    /// green and the direction in red, beside the depth heat map (paper
    /// B's figure 3); with a calibrated sensor, NAME-indentation.png per
    /// frame (the frame, a shaded 3-D view and the indentation in mm).
    /// NAME is the frame's name without its extension, NAME-2, NAME-3, ...
    /// for later frames of the same name.
    #[arg(long)]
    render: Option<PathBuf>,
    /// Hysteresis on the detector over each sequence: ON,OFF probabilities
    /// (a tendon appears at ON and disappears below OFF).
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    hysteresis: Option<Vec<f32>>,
    /// Decode each frame just before it is processed instead of on a
    /// second thread ahead of the models (recorded sources).
    #[arg(long)]
    no_overlap: bool,
    /// Live sources (camera, stdin): frames that may wait while the models
    /// run; when more arrive the oldest is dropped and counted.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u16).range(1..=64))]
    live_queue: u16,
}

pub(crate) fn main(a: RunArgs) -> Result<()> {
    let hysteresis = match a.hysteresis.as_deref() {
        None => None,
        Some(&[on, off]) => Some((on, off)),
        Some(v) => bail!("--hysteresis takes ON,OFF (two probabilities), got {v:?}"),
    };
    if a.list_topics {
        let Some(bag) = &a.data else {
            bail!("--list-topics needs --data BAG.mcap")
        };
        let listing = tactile_core::bag::list_image_topics(bag)?;
        for w in &listing.warnings {
            tactile_core::note!("{w}");
        }
        let topics = listing.topics;
        if topics.is_empty() {
            say!("{}: no image topics", bag.display());
        }
        for t in &topics {
            say!(
                "{}  {}  {} messages  {:.1} Hz",
                tactile_core::one_cell(&t.topic),
                tactile_core::one_cell(&t.message_type),
                t.count,
                t.rate_hz
            );
        }
        return Ok(());
    }
    let source = match (&a.data, a.size) {
        (Some(p), _) if a.topic.is_some() => SourceSpec::Bag {
            path: p.clone(),
            topic: a.topic.clone(),
        },
        (Some(p), _) => SourceSpec::Path(p.clone()),
        (None, Some(crate::args::Size([width, height]))) => SourceSpec::Stdin { width, height },
        (None, None) => bail!("give --data PATH or --stdin --size WIDTHxHEIGHT"),
    };
    let request = RunRequest {
        source_options: SourceOptions {
            overlap: !a.no_overlap,
            live_queue: a.live_queue as usize,
            limit: a.limit,
        },
        runtime: a.runtime,
        threads: a.threads as usize,
        pipelines: a.pipelines,
        hysteresis,
        out: a.out,
        render: a.render,
        with_frames: a.with_frames,
        view: a.view,
        view_wait: a.view_wait,
        ..RunRequest::new(source, a.models)
    };
    let to_stdout = request.records_to_stdout();
    let session = RunSession::open(&request)?;
    for w in session.warnings() {
        tactile_core::note!("{w}");
    }
    if let Some(url) = session.live_url() {
        tactile_core::note!(
            "live view: open Foxglove on {url} (frames are sent while a viewer is subscribed)"
        );
        session.wait_for_viewer()?;
    }
    let r = session.run()?;
    for w in &r.late_warnings {
        tactile_core::note!("{w}");
    }
    // With records on stdout, the summary goes to stderr.
    let report = |line: String| match to_stdout {
        true => tactile_core::note!("{line}"),
        false => say!("{line}"),
    };
    r.summary.describe().into_iter().for_each(report);
    if let Some(out) = r.records.as_ref().or(r.mcap.as_ref()) {
        report(format!("records in {}", out.display()));
    }
    if let (Some(sent), Some(dropped)) = (r.live_sent, r.live_dropped) {
        report(format!(
            "live view: {sent} frames sent, {dropped} dropped (viewer behind)"
        ));
    }
    report(serde_json::to_string(&r.summary)?);
    Ok(())
}

/// `--view-wait`: a finite number of seconds >= 0 (NaN or a negative wait
/// would silently mean none).
fn wait_seconds(text: &str) -> Result<f64, String> {
    let seconds: f64 = text.parse().map_err(|e| format!("{e}"))?;
    tactile_ros::live::check_wait_seconds("--view-wait", seconds).map_err(|e| e.to_string())?;
    Ok(seconds)
}
