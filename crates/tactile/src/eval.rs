//! `tactile eval detector|segmenter|depth`: a paper B model scored on a
//! labelled dataset; the last line printed is the metrics as JSON.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Subcommand};
use tactile_burn::DeviceKind;

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
    #[command(flatten)]
    options: tactile_detect::eval::EvalOptions,
}

#[derive(Args)]
pub(crate) struct DepthArgs {
    #[command(flatten)]
    m: ModelArgs,
    #[command(flatten)]
    options: tactile_depth::eval::EvalOptions,
}

pub(crate) fn main(cmd: EvalCmd) -> Result<()> {
    match cmd {
        EvalCmd::Detector(a) => detector(a),
        EvalCmd::Segmenter(a) => segmenter(a),
        EvalCmd::Depth(a) => depth(a),
    }
}

fn detector(a: DetectorArgs) -> Result<()> {
    let (m, o) = (&a.m, &a.options);
    let sc = tactile_detect::eval::evaluate_folder(&m.model, &m.data, m.device.runtime(), o)?;
    warn(&sc.frame_warnings, &sc.warning);
    if let Some(path) = &o.frames {
        tactile_core::note!("per-frame decisions in {}", path.display());
    }
    sc.describe(m.device).iter().for_each(|l| say!("{l}"));
    if let Some(path) = &o.reliability {
        tactile_core::note!("reliability diagram in {}", path.display());
    }
    say!(
        "{}",
        tactile_core::io::scored_record(&m.model, &m.data, &sc)?
    );
    Ok(())
}

fn segmenter(m: ModelArgs) -> Result<()> {
    let sc = tactile_segment::evaluate_folder(&m.model, &m.data, m.device.runtime())?;
    warn(&sc.frame_warnings, &sc.warning);
    sc.describe(m.device).iter().for_each(|l| say!("{l}"));
    say!(
        "{}",
        tactile_core::io::scored_record(&m.model, &m.data, &sc)?
    );
    Ok(())
}

fn depth(a: DepthArgs) -> Result<()> {
    let (m, o) = (&a.m, &a.options);
    let e = tactile_depth::eval::evaluate_folder(&m.model, &m.data, m.device.runtime(), o)?;
    warn(&e.frame_warnings, &e.warning);
    e.scores
        .describe(e.ms_per_frame, m.device)
        .iter()
        .for_each(|l| say!("{l}"));
    if let Some(dir) = &o.save_png {
        say!(
            "{} heat maps of the push from the rest dome, mm (true | predicted, one scale) in {}",
            e.heat_maps,
            dir.display()
        );
    }
    say!("{}", serde_json::to_value(&e)?);
    Ok(())
}

/// Note an evaluation's warnings on standard error: what reading the
/// frames found, then scores on frames the model fitted.
fn warn(frame_warnings: &[String], fitted: &Option<String>) {
    for w in tactile_core::io::scoring_warnings(frame_warnings, fitted) {
        tactile_core::note!("{w}");
    }
}
