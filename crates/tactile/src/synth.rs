//! `tactile synth tactip|visuotactile`: the virtual sensors of `sensors.md`.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::{Args, Subcommand};
use datasets_synth::{
    Range, TactipConfig, TendonPath, VisuotactileConfig, WriteOptions, write_tactip,
    write_visuotactile,
};

#[derive(Subcommand)]
pub(crate) enum SynthCmd {
    /// Virtual TacTip frames (paper A): shapes, position, orientation, depth, force.
    Tactip(TactipArgs),
    /// Virtual visuo-tactile palpation videos (paper B): RGB, masks, directions, depth.
    Visuotactile(VisuotactileArgs),
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
    /// JSON file with any of the generator's ranges (see docs/synth.md);
    /// flags given on the command line override it.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Replace a non-empty output folder.
    #[arg(long)]
    force: bool,
    /// Also write a contact sheet of frames sampled through the dataset.
    #[arg(long)]
    preview: Option<PathBuf>,
    /// Frames on the contact sheet.
    #[arg(long, default_value_t = 12)]
    preview_frames: usize,
}

#[derive(Args)]
pub(crate) struct TactipArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// Shapes to draw from (default: all seven).
    #[arg(long, value_delimiter = ',')]
    shapes: Option<Vec<String>>,
    /// Indentation depth range, mm: MIN,MAX.
    #[arg(long)]
    depth_mm: Option<Range>,
    /// Contact x range, mm: MIN,MAX.
    #[arg(long)]
    x_mm: Option<Range>,
    /// Contact y range, mm: MIN,MAX.
    #[arg(long)]
    y_mm: Option<Range>,
    /// Orientation range, degrees: MIN,MAX.
    #[arg(long)]
    theta_deg: Option<Range>,
    /// Sensor noise range, grey levels: MIN,MAX.
    #[arg(long)]
    noise_sigma: Option<Range>,
    /// Probability of an external light blob.
    #[arg(long)]
    blob_probability: Option<f64>,
}

#[derive(Args)]
pub(crate) struct VisuotactileArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// Frame width: an exact integer fraction of 1920 (with --height).
    #[arg(long)]
    width: Option<u32>,
    /// Frame height: the same fraction of 1080.
    #[arg(long)]
    height: Option<u32>,
    /// Tendon paths to draw from.
    #[arg(long, value_delimiter = ',')]
    paths: Option<Vec<TendonPath>>,
    /// Palpation videos to write (count = sequences x frames per sequence).
    #[arg(long)]
    sequences: Option<usize>,
    /// Frames of each palpation video.
    #[arg(long)]
    frames_per_sequence: Option<usize>,
    /// Peak press range, mm: MIN,MAX.
    #[arg(long)]
    press_mm: Option<Range>,
    /// Tendon radius range, mm: MIN,MAX.
    #[arg(long)]
    tendon_radius_mm: Option<Range>,
    /// Burial depth range, mm: MIN,MAX.
    #[arg(long)]
    burial_mm: Option<Range>,
    /// Sensor noise range, 8-bit levels: MIN,MAX.
    #[arg(long)]
    noise_sigma: Option<Range>,
    /// reference (what models train on) or alternate (another raster and
    /// shading path of the same spec, a cross-check set).
    #[arg(long)]
    renderer: Option<datasets_synth::Renderer>,
}

fn config<T: serde::de::DeserializeOwned + Default>(c: &CommonArgs) -> Result<T> {
    Ok(match &c.config {
        None => T::default(),
        Some(p) => tactile_core::io::read_json(p)?,
    })
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

macro_rules! set {
    ($cfg:ident, $a:ident: $($f:ident),*) => { $( if let Some(v) = $a.$f { $cfg.$f = v; } )* };
}

pub(crate) fn main(cmd: SynthCmd) -> Result<()> {
    let t = std::time::Instant::now();
    let common = match &cmd {
        SynthCmd::Tactip(a) => &a.common,
        SynthCmd::Visuotactile(a) => &a.common,
    };
    if let Some(p) = &common.preview {
        tactile_core::dataset::check_output_file(p, &[])?;
    }
    match cmd {
        SynthCmd::Tactip(a) => {
            let mut cfg: TactipConfig = config(&a.common)?;
            set!(cfg, a: shapes, depth_mm, x_mm, y_mm, theta_deg, noise_sigma, blob_probability);
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
        SynthCmd::Visuotactile(a) => {
            let mut cfg: VisuotactileConfig = config(&a.common)?;
            set!(cfg, a: paths, width, height, frames_per_sequence, press_mm, tendon_radius_mm, burial_mm, noise_sigma, renderer);
            let count = cfg.frame_count(a.common.count, a.sequences)?;
            let opts = WriteOptions {
                force: a.common.force,
                progress: true,
            };
            let out = write_visuotactile(&cfg, count, a.common.seed, &a.common.out, opts)?;
            finish(&a.common, out, "virtual visuo-tactile", count, t)
        }
    }
}
