//! `tactile synth tactip|visuotactile`: the virtual sensors of `sensors.md`.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::{Args, Subcommand};
use datasets_synth::{
    CalibratedConfig, TactipConfig, VisuotactileConfig, WriteOptions, visuotactile, write_tactip,
    write_visuotactile,
};
use tactile_gelsight::negatives::write_sensor_videos;

#[derive(Subcommand)]
pub(crate) enum SynthCmd {
    /// Virtual TacTip frames (paper A): shapes, position, orientation, depth, force.
    Tactip(TactipArgs),
    /// Virtual visuo-tactile palpation videos (paper B): RGB, masks, directions, depth; with --sensor, a calibrated sensor's own (the same as `synth gelsight`).
    Visuotactile(VisuotactileArgs),
    /// A calibrated GelSight-like sensor's own palpation videos, rendered through its calibration (tactile calibrate ball): RGB, masks, directions, indentation maps.
    Gelsight(GelsightArgs),
    /// The ideal detector of a virtual visuo-tactile set: per frame, how precisely the frame tells its ridge's height (the Cramér–Rao bound, scenes drawn again from the manifest) and the best chance any detector has of labelling it right; its mean bounds every detector's accuracy on the set.
    IdealDetector(IdealArgs),
}

#[derive(Args)]
pub(crate) struct IdealArgs {
    /// A virtual visuo-tactile dataset written by `tactile synth visuotactile`.
    #[arg(long)]
    data: PathBuf,
    /// Write the per-frame bounds here (CSV: file, tendon, ridge_mm, ridge_sigma_mm, in_view, ideal_p_correct).
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Options shared by both sensors.
#[derive(Args)]
pub(crate) struct CommonArgs {
    /// Frames to write.
    #[arg(long)]
    count: Option<usize>,
    /// Seed of every sample's random stream.
    #[arg(long, default_value_t = 1234)]
    seed: u64,
    /// Output dataset folder.
    #[arg(long)]
    out: PathBuf,
    /// JSON file with any of the generator's options (the flags' names
    /// with underscores; see docs/synth.md); flags given on the command
    /// line override it.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Replace a non-empty output folder.
    #[arg(long)]
    force: bool,
    /// Also write a contact sheet of frames sampled through the dataset.
    #[arg(long)]
    preview: Option<PathBuf>,
    /// Frames on the contact sheet (1-400).
    #[arg(long, default_value_t = 12, requires = "preview")]
    preview_frames: usize,
}

#[derive(Args)]
pub(crate) struct TactipArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// Every range of the generator (defaults: the spec's).
    #[command(flatten)]
    config: TactipConfig,
}

#[derive(Args)]
pub(crate) struct VisuotactileArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// Palpation videos to write (count = sequences x frames per sequence).
    #[arg(long)]
    sequences: Option<usize>,
    /// Render a calibrated sensor's own videos instead (its calibration
    /// folder): the flags it shares with `synth gelsight` apply (paths,
    /// ranges of tendon radius, curvature, press, exposure, noise, frames
    /// per sequence); its other options go in --config.
    #[arg(long)]
    sensor: Option<PathBuf>,
    /// Every range of the generator (defaults: the spec's).
    #[command(flatten)]
    config: VisuotactileConfig,
}

#[derive(Args)]
pub(crate) struct GelsightArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// The calibrated sensor's folder (tactile calibrate ball).
    #[arg(long)]
    sensor: PathBuf,
    /// Palpation videos to write (count = sequences x frames per sequence).
    #[arg(long)]
    sequences: Option<usize>,
    /// Every range of the generator.
    #[command(flatten)]
    config: CalibratedConfig,
}

fn finish(
    c: &CommonArgs,
    out: PathBuf,
    what: &str,
    count: usize,
    t: std::time::Instant,
) -> Result<()> {
    let secs = t.elapsed().as_secs_f64();
    say!(
        "{count} {what} frames written to {} in {secs:.1} s ({:.1} frames/s)",
        out.display(),
        count as f64 / secs.max(1e-9)
    );
    if let Some(p) = &c.preview {
        datasets_synth::preview::contact_sheet(&out, p, c.preview_frames)?;
        say!("preview: {}", p.display());
    }
    Ok(())
}

pub(crate) fn main(cmd: SynthCmd) -> Result<()> {
    let t = std::time::Instant::now();
    let common = match &cmd {
        SynthCmd::Tactip(a) => Some(&a.common),
        SynthCmd::Visuotactile(a) => Some(&a.common),
        SynthCmd::Gelsight(a) => Some(&a.common),
        SynthCmd::IdealDetector(_) => None,
    };
    if let Some((c, p)) = common.and_then(|c| c.preview.as_ref().map(|p| (c, p))) {
        tactile_core::dataset::check_output_file(p, &[])?;
        datasets_synth::preview::check_preview_frames(c.preview_frames)?;
    }
    match cmd {
        SynthCmd::Tactip(a) => {
            let cfg = crate::args::resolve(a.config, a.common.config.as_deref())?;
            let Some(count) = a.common.count else {
                bail!("--count is required")
            };
            let opts = WriteOptions {
                force: a.common.force,
                progress: true,
            };
            let out = write_tactip(&cfg, count, a.common.seed, &a.common.out, opts)?;
            finish(&a.common, out, "virtual TacTip", count, t)
        }
        SynthCmd::Visuotactile(a) if a.sensor.is_some() => {
            let cfg: CalibratedConfig =
                crate::args::resolve_as(&a.config, a.common.config.as_deref())?;
            let sensor = a.sensor.unwrap_or_default();
            gelsight(&a.common, &sensor, a.sequences, &cfg, t)
        }
        SynthCmd::Gelsight(a) => {
            let cfg = crate::args::resolve(a.config, a.common.config.as_deref())?;
            gelsight(&a.common, &a.sensor, a.sequences, &cfg, t)
        }
        SynthCmd::Visuotactile(a) => {
            let cfg = crate::args::resolve(a.config, a.common.config.as_deref())?;
            let count = cfg.frame_count(a.common.count, a.sequences)?;
            let opts = WriteOptions {
                force: a.common.force,
                progress: true,
            };
            let out = write_visuotactile(&cfg, count, a.common.seed, &a.common.out, opts)?;
            finish(&a.common, out, "virtual visuo-tactile", count, t)
        }
        SynthCmd::IdealDetector(a) => ideal_detector(&a),
    }
}

fn gelsight(
    c: &CommonArgs,
    sensor: &std::path::Path,
    sequences: Option<usize>,
    cfg: &CalibratedConfig,
    t: std::time::Instant,
) -> Result<()> {
    let opts = WriteOptions {
        force: c.force,
        progress: true,
    };
    let (out, count) =
        write_sensor_videos(sensor, cfg, (c.count, sequences), c.seed, &c.out, opts)?;
    finish(c, out, "calibrated-sensor", count, t)
}

fn ideal_detector(a: &IdealArgs) -> Result<()> {
    let bounds = visuotactile::dataset_bounds(&a.data, a.out.as_deref(), true)?;
    let s = visuotactile::summarise(&bounds);
    say!(
        "{}: {} frames; the ideal detector's expected accuracy {:.4} ({} frames it labels right with a chance under 0.99); ridge height measurable to {:.2e} mm (median one-sigma bound over frames with a tendon in view)",
        a.data.display(),
        s.frames,
        s.accuracy,
        s.uncertain,
        s.median_sigma_mm
    );
    if let Some(out) = &a.out {
        say!("per-frame bounds: {}", out.display());
    }
    Ok(())
}
