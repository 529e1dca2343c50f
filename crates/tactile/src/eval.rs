//! `tactile eval detector|segmenter|depth`: a paper B model scored on a
//! labelled dataset; the last line printed is the metrics as JSON.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Subcommand};
use tactile_burn::DeviceKind;
use tactile_core::dataset::Dataset;
use tactile_depth::DepthEstimator;
use tactile_detect::{DetectionSet, TendonDetector};
use tactile_segment::TendonSegmenter;

#[derive(Subcommand)]
pub(crate) enum EvalCmd {
    /// Tendon detector: accuracy, precision, recall, F1, onset/release frames.
    Detector(DetectorArgs),
    /// Tendon segmenter: IoU per tendon path, direction error of the post-processed mask.
    Segmenter(ModelArgs),
    /// Depth network: MAE (window, tendon mask), RMSE, SSIM; optional heat maps.
    Depth(DepthArgs),
}

#[derive(Args)]
pub(crate) struct ModelArgs {
    /// Model folder.
    #[arg(long)]
    model: PathBuf,
    /// Visuo-tactile dataset with labels.
    #[arg(long)]
    data: PathBuf,
    /// Device the network runs on.
    #[arg(long, value_enum, default_value_t = DeviceKind::Flex)]
    device: DeviceKind,
}

#[derive(Args)]
pub(crate) struct DetectorArgs {
    #[command(flatten)]
    m: ModelArgs,
    /// Also write every frame's probability and decision to this CSV (file, tendon, probability, predicted, onset_release), to look at the frames it gets wrong.
    #[arg(long)]
    frames: Option<PathBuf>,
    /// Also save the reliability diagram (observed tendon fraction against predicted probability) as this PNG.
    #[arg(long)]
    reliability: Option<PathBuf>,
}

#[derive(Args)]
pub(crate) struct DepthArgs {
    #[command(flatten)]
    m: ModelArgs,
    /// Write heat maps of the skin's displacement from its rest dome in mm (true | predicted, one colour scale with its bar) for the first frames into this folder.
    #[arg(long)]
    save_png: Option<PathBuf>,
    /// How many frames `--save-png` writes.
    #[arg(long, default_value_t = 8)]
    png_frames: usize,
}

pub(crate) fn main(cmd: EvalCmd) -> Result<()> {
    match cmd {
        EvalCmd::Detector(a) => detector(a),
        EvalCmd::Segmenter(a) => segmenter(a),
        EvalCmd::Depth(a) => depth(a),
    }
}

fn detector(a: DetectorArgs) -> Result<()> {
    let m = &a.m;
    let ds = Dataset::open(&m.data)?;
    for out in a.frames.iter().chain(&a.reliability) {
        tactile_core::dataset::check_output_file(out, &[&ds])?;
    }
    let mut det = TendonDetector::load(&m.model, m.device.runtime(), 0)?;
    let data = DetectionSet::from_dataset(&ds, &det.artifact.model)?;
    let sc = tactile_detect::evaluate(&mut det, &data)?;
    if let Some(path) = &a.frames {
        tactile_detect::eval::write_decisions_csv(path, &data, &sc)?;
        tactile_core::note!("per-frame decisions in {}", path.display());
    }
    sc.describe(m.device).iter().for_each(|l| say!("{l}"));
    if let Some(path) = &a.reliability {
        sc.save_reliability_plot(path, "Tendon detector: reliability")?;
        tactile_core::note!("reliability diagram in {}", path.display());
    }
    say!(
        "{}",
        tactile_core::io::scored_record(&m.model, &m.data, &sc)?
    );
    Ok(())
}

fn segmenter(m: ModelArgs) -> Result<()> {
    let mut seg = TendonSegmenter::load(&m.model, m.device.runtime(), 0)?;
    let ds = Dataset::open(&m.data)?;
    let sc = tactile_segment::evaluate(&mut seg, &ds)?;
    sc.describe(m.device).iter().for_each(|l| say!("{l}"));
    say!(
        "{}",
        tactile_core::io::scored_record(&m.model, &m.data, &sc)?
    );
    Ok(())
}

fn depth(a: DepthArgs) -> Result<()> {
    let m = &a.m;
    let ds = Dataset::open(&m.data)?;
    if let Some(dir) = &a.save_png {
        tactile_core::dataset::check_output_dir(dir, &[&ds])?;
    }
    let mut est = DepthEstimator::load(&m.model, m.device.runtime(), 0)?;
    let (s, ms) = tactile_depth::evaluate(&mut est, &ds)?;
    s.describe(ms, m.device).iter().for_each(|l| say!("{l}"));
    if let Some(dir) = &a.save_png {
        let n = tactile_depth::eval::save_heat_maps(&mut est, &ds, dir, a.png_frames)?;
        say!(
            "{n} heat maps of the push from the rest dome, mm (true | predicted, one scale) in {}",
            dir.display()
        );
    }
    say!(
        "{}",
        serde_json::json!({ "model": m.model, "data": m.data, "scores": s, "ms_per_frame": ms })
    );
    Ok(())
}
