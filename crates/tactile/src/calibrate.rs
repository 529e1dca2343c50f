//! `tactile calibrate ball` and `tactile reconstruct`: a GelSight-like
//! sensor calibrated from ball presses, and its skin reconstructed.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Subcommand};

use crate::train::ConfigArg;

#[derive(Subcommand)]
pub(crate) enum CalibrateCmd {
    /// Calibrate a GelSight-like sensor from presses of a ball of known radius (docs/datasets.md: the calibration layout; docs/calibration.md).
    Ball(BallArgs),
}

#[derive(Args)]
pub(crate) struct BallArgs {
    /// Calibration folder: sensor.json, background.png, frames/ (a frame per press: PNG, JPEG, BMP, TIFF, WebP or PGM/PPM), optional presses.csv (and its ball_diameter_mm column for presses of other balls); or gs_sdk's folder as it is (catalog.csv, <d>mm/<n>/gelsight.png and label.npz) with gs_sdk's config of the sensor copied in (gsmini.yaml: ppmm, imgw, imgh) or a sensor.json giving mm_per_px; or Taxim's dataPack.npz (its folder or the file) with a sensor.json giving ball_diameter_mm and mm_per_px.
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
            c.describe(&a.out).iter().for_each(|l| say!("{l}"));
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
    /// TIFF of many pages (a stack: <stack stem>-000000.npy, ... per page), a dataset folder
    /// (its rows' frames), or Taxim's dataPack.npz or its folder (its presses: <name stem>.npy).
    #[arg(long)]
    data: PathBuf,
    /// Output folder (new): <frame stem>.npy per frame, float32 H x W, the skin's indentation in metres (toward the camera; 0 at rest).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    options: tactile_gelsight::reconstruct::ReconstructOptions,
}

pub(crate) fn reconstruct(a: ReconstructArgs) -> Result<()> {
    let r = tactile_pipeline::reconstruct::reconstruct(&a.model, &a.data, &a.out, &a.options)?;
    for w in &r.warnings {
        tactile_core::note!("{w}");
    }
    say!(
        "{} frames reconstructed into {} ({:.2} ms per frame, {}); deepest {:.3} mm",
        r.frames,
        a.out.display(),
        r.ms_per_frame,
        a.options.runtime,
        r.peak_mm
    );
    if let Some(dir) = &a.options.render {
        say!("pictures in {}", dir.display());
    }
    say!("{}", serde_json::to_string(&r)?);
    Ok(())
}
