//! `tactile calibrate ball` and `tactile reconstruct`: a GelSight-like
//! sensor calibrated from ball presses, and its skin reconstructed.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Subcommand};
use tactile_burn::Runtime;

use crate::train::ConfigArg;

#[derive(Subcommand)]
pub(crate) enum CalibrateCmd {
    /// Calibrate a GelSight-like sensor from presses of a ball of known radius (docs/datasets.md: the calibration layout; docs/calibration.md).
    Ball(BallArgs),
}

#[derive(Args)]
pub(crate) struct BallArgs {
    /// Calibration folder: sensor.json, background.png, frames/ (a frame per press: PNG, JPEG, BMP, TIFF, WebP or PGM/PPM), optional presses.csv.
    #[arg(long)]
    data: PathBuf,
    /// Output model folder (new).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    config: ConfigArg,
    #[command(flatten)]
    options: tactile_gelsight::BallOptions,
}

pub(crate) fn main(cmd: CalibrateCmd) -> Result<()> {
    match cmd {
        CalibrateCmd::Ball(a) => {
            let options = a.config.resolve(a.options)?;
            let c = options.calibrate(&a.data, &a.out)?;
            for w in &c.warnings {
                tactile_core::note!("{w}");
            }
            say!(
                "sensor model {}; {} presses fitted, {} held out; model in {}",
                c.fit.describe("cap-shape error, mm"),
                c.train_presses,
                c.val_presses,
                a.out.display()
            );
            if let Some(circles) = &c.circles {
                say!("{}", circles.describe());
            }
            say!(
                "render model (optics.json): optics on {} pixels; gel spread {:.2} mm, gain {:.2} (profile error {:.3} mm); ball presses rendered back: colour error {:.1} levels (the bare background: {:.1})",
                c.render.optics_samples,
                c.render.gel.sigma_mm,
                c.render.gel.gain,
                c.render.gel_profile_error_mm,
                c.render.colour_error_levels,
                c.render.colour_error_unpressed_levels
            );
            for s in &c.validation {
                say!(
                    "held out {}: shape error {:.3} mm, far field {:.4} mm, rim sink {:.3} mm, peak {:.3} mm",
                    s.file,
                    s.shape_mae_mm,
                    s.far_field_mm,
                    s.rim_sink_mm,
                    s.peak_mm
                );
            }
            say!("{}", serde_json::to_string(&c)?);
            Ok(())
        }
    }
}

#[derive(Args)]
pub(crate) struct ReconstructArgs {
    /// A calibrated sensor's model folder (tactile calibrate ball).
    #[arg(long)]
    model: PathBuf,
    /// A frame, a folder of frames (PNG, JPEG, BMP, TIFF, WebP or PGM/PPM) of that sensor, a
    /// TIFF of many pages (a stack: <stack stem>-000000.npy, ... per page), or a dataset folder
    /// (its rows' frames).
    #[arg(long)]
    data: PathBuf,
    /// Output folder (new): <frame stem>.npy per frame, float32 H x W, the skin's indentation in metres (toward the camera; 0 at rest).
    #[arg(long)]
    out: PathBuf,
    /// The sensor's rest frame to compare against instead of the calibration's (same size).
    #[arg(long)]
    background: Option<PathBuf>,
    /// Also write pictures into this folder (new): each frame beside its indentation in mm with a colour bar, and a shaded 3-D view.
    #[arg(long)]
    render: Option<PathBuf>,
    /// Where the sensor model runs.
    #[arg(long, value_enum, default_value_t = Runtime::Onnx)]
    runtime: Runtime,
}

pub(crate) fn reconstruct(a: ReconstructArgs) -> Result<()> {
    let r = tactile_pipeline::reconstruct::reconstruct(
        &a.model,
        &a.data,
        &a.out,
        &tactile_gelsight::reconstruct::ReconstructOptions {
            background: a.background.clone(),
            render: a.render.clone(),
            runtime: a.runtime,
        },
    )?;
    for w in &r.warnings {
        tactile_core::note!("{w}");
    }
    say!(
        "{} frames reconstructed into {} ({:.2} ms per frame, {}); deepest {:.3} mm",
        r.frames,
        a.out.display(),
        r.ms_per_frame,
        a.runtime,
        r.peak_mm
    );
    if let Some(dir) = &a.render {
        say!("pictures in {}", dir.display());
    }
    say!("{}", serde_json::to_string(&r)?);
    Ok(())
}
