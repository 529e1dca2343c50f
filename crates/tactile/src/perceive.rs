//! `tactile perceive`: paper A's simultaneous deployment, one encoding per
//! frame and every estimator on it.

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;
use tactile_burn::{DeviceKind, Runtime};
use tactile_pipeline::run::JsonLines;
use tactile_pipeline::tactip::{PredictInput, Predictor};

#[derive(Args)]
pub(crate) struct PerceiveArgs {
    /// Trained encoder folder (its estimator subfolders run by default), or
    /// a pose-network folder.
    #[arg(long, visible_alias = "model")]
    encoder: PathBuf,
    /// Estimator folders: classifier heads (head.json) and regressors
    /// (regressor.json, or an ensemble of them: ensemble.json), all run on
    /// the same feature vector (default: every such folder inside ENCODER).
    #[arg(long, num_args = 1..)]
    heads: Vec<PathBuf>,
    /// The frames: a dataset folder (docs/datasets.md; every row of
    /// labels.csv, in order), or a folder of frames (PNG, JPEG, BMP, TIFF,
    /// WebP or PGM/PPM; by the
    /// numbers in their names), one image, a TIFF of many pages (a stack,
    /// page by page), a video file (decoded by
    /// FFmpeg), a ROS 2 bag (its folder, or one .mcap or .db3; see --topic) or a
    /// V4L2 camera (with --limit, or streamed with `--out -`).
    #[arg(long)]
    data: PathBuf,
    /// A ROS 2 bag's image topic (without it, the bag's only image topic).
    #[arg(long)]
    topic: Option<String>,
    /// Estimate only the first this many frames (of a dataset, a folder,
    /// a video, a bag or a camera; a camera needs it unless streamed with
    /// `--out -`, as the estimates are written when the frames end).
    #[arg(long)]
    limit: Option<u64>,
    /// Also write every estimate to this CSV, or, for a name ending in
    /// .mcap, as ROS 2 messages (tactile_msgs/msg/Estimates on
    /// /tactile/estimates, docs/robots.md), or with `-` stream one JSON
    /// object per frame to standard output as soon as it is estimated
    /// (a camera then runs until stopped; the summary goes to standard
    /// error).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Frames to print (all go to --out).
    #[arg(long, default_value_t = 10)]
    show: usize,
    /// Device the networks run on.
    #[arg(long, value_enum, default_value_t = DeviceKind::Flex)]
    device: DeviceKind,
    /// Run the networks here instead of on --device: `onnx` runs each
    /// network's ONNX export through onnxruntime (the deployment path the
    /// benches time), `burn-flex`/`burn-ndarray` are --device's two.
    #[arg(long, value_enum, conflicts_with = "device")]
    runtime: Option<Runtime>,
}

pub(crate) fn main(a: PerceiveArgs) -> Result<()> {
    let streamed = a.out.as_deref() == Some(Path::new("-"));
    let mut input = PredictInput::open(&a.data, a.topic.as_deref(), a.limit, streamed)?;
    for w in input.warnings() {
        tactile_core::note!("{w}");
    }
    if let Some(out) = a.out.as_ref().filter(|_| !streamed) {
        input.check_output(&a.data, out)?;
    }
    let mut p = Predictor::load(
        &a.encoder,
        &a.heads,
        a.runtime.unwrap_or(a.device.runtime()),
    )?;
    if streamed {
        return stream(&mut p, &mut input, &a);
    }
    let r = p.perceive_input(&mut input, &a.data)?;
    for w in &r.warnings {
        tactile_core::note!("{w}");
    }
    let frames = r.files.len();
    // A cell holding a tab or a newline (a frame named so, a label) is
    // escaped, so every row stays one line of the header's columns.
    let row = |cells: Vec<String>| {
        let cells: Vec<_> = cells.iter().map(|c| tactile_core::one_cell(c)).collect();
        cells.join("\t")
    };
    say!("{}", row(r.header()));
    for i in 0..frames.min(a.show) {
        say!("{}", row(r.row(i)));
    }
    match &p {
        // A source's frames are decoded on another thread as they run.
        _ if matches!(input, PredictInput::Source(_)) => say!(
            "{} frames: {:.3} ms/frame (preprocessing and every network included)",
            frames,
            r.ms_encode
        ),
        Predictor::PoseNetwork(_) => say!(
            "{} frames: pose network {:.3} ms/frame (preprocessing included)",
            frames,
            r.ms_encode
        ),
        Predictor::Encoder(_) => say!(
            "{} frames: encoding {:.3} ms/frame (preprocessing included), {} estimator{} {:.4} ms/frame",
            frames,
            r.ms_encode,
            p.estimators(),
            if p.estimators() == 1 { "" } else { "s" },
            r.ms_estimate
        ),
    }
    if let Some(out) = &a.out {
        tactile_ros::estimates::write_perception(out, &r)?;
        let what = if tactile_core::bag::is_bag_file(out) {
            " (ROS 2 messages)"
        } else {
            ""
        };
        say!("estimates written to {}{what}", out.display());
    }
    Ok(())
}

/// `--out -`: one JSON object per frame on standard output as soon as it
/// is estimated (a reader that goes away stops the run quietly), the
/// summary on standard error.
fn stream(p: &mut Predictor, input: &mut PredictInput, a: &PerceiveArgs) -> Result<()> {
    let mut out = JsonLines::create(Path::new("-"))?;
    let t0 = std::time::Instant::now();
    let s = p.stream_input(input, &a.data, &mut |rec| out.write(&rec), &mut |w| {
        tactile_core::note!("{w}")
    })?;
    out.finish()?;
    if let Some(dropped) = s.dropped {
        tactile_core::note!("{dropped} live frames dropped (the models fell behind)");
    }
    tactile_core::note!(
        "{} frames: {:.3} ms/frame (decoding, preprocessing and every network included)",
        s.frames,
        1e3 * t0.elapsed().as_secs_f64() / s.frames.max(1) as f64
    );
    Ok(())
}
