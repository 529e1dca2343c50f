//! `tactile synth tactip|visuotactile`: the virtual sensors of `sensors.md`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use datasets_synth::{
    Range, TactipConfig, TendonPath, VisuotactileConfig, WriteOptions, write_tactip,
    write_visuotactile,
};

/// Options shared by both sensors.
#[derive(Args)]
pub struct CommonArgs {
    /// Frames to write.
    #[arg(long)]
    count: Option<usize>,
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
pub struct TactipArgs {
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
pub struct VisuotactileArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// Frame width: an exact integer fraction of 1920 (with --height).
    #[arg(long)]
    width: Option<u32>,
    #[arg(long)]
    height: Option<u32>,
    /// Tendon paths: straight,arc,s-curve.
    #[arg(long, value_delimiter = ',')]
    paths: Option<Vec<String>>,
    /// Palpation videos to write (count = sequences x frames per sequence).
    #[arg(long)]
    sequences: Option<usize>,
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
}

fn load_config<T: serde::de::DeserializeOwned + Default>(path: Option<&Path>) -> Result<T> {
    match path {
        None => Ok(T::default()),
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("reading generator config {}", p.display()))?;
            serde_json::from_str(&text)
                .with_context(|| format!("{}: invalid generator config", p.display()))
        }
    }
}

fn finish(common: &CommonArgs, out: &Path, what: &str, count: usize, secs: f64) -> Result<()> {
    println!(
        "{count} {what} frames written to {} in {secs:.1} s ({:.1} frames/s)",
        out.display(),
        count as f64 / secs.max(1e-9)
    );
    if let Some(p) = &common.preview {
        datasets_synth::preview::contact_sheet(out, p, common.preview_frames)?;
        println!("preview: {}", p.display());
    }
    Ok(())
}

pub fn tactip(a: TactipArgs) -> Result<()> {
    let mut cfg: TactipConfig = load_config(a.common.config.as_deref())?;
    if let Some(s) = a.shapes {
        cfg.shapes = s;
    }
    macro_rules! set {
        ($($f:ident),*) => { $( if let Some(v) = a.$f { cfg.$f = v; } )* };
    }
    set!(
        depth_mm,
        x_mm,
        y_mm,
        theta_deg,
        noise_sigma,
        blob_probability
    );
    let count = a.common.count.context("--count is required")?;
    let t = std::time::Instant::now();
    let out = write_tactip(
        &cfg,
        count,
        a.common.seed,
        &a.common.out,
        WriteOptions {
            force: a.common.force,
            progress: true,
        },
    )?;
    finish(
        &a.common,
        &out,
        "virtual TacTip",
        count,
        t.elapsed().as_secs_f64(),
    )
}

pub fn visuotactile(a: VisuotactileArgs) -> Result<()> {
    let mut cfg: VisuotactileConfig = load_config(a.common.config.as_deref())?;
    if let Some(p) = a.paths {
        cfg.paths = p
            .iter()
            .map(|s| s.parse::<TendonPath>())
            .collect::<Result<_, _>>()?;
    }
    if let Some(w) = a.width {
        cfg.width = w;
    }
    if let Some(h) = a.height {
        cfg.height = h;
    }
    macro_rules! set {
        ($($f:ident),*) => { $( if let Some(v) = a.$f { cfg.$f = v; } )* };
    }
    set!(
        frames_per_sequence,
        press_mm,
        tendon_radius_mm,
        burial_mm,
        noise_sigma
    );
    let count = match (a.common.count, a.sequences) {
        (Some(c), None) => c,
        (None, Some(k)) => k * cfg.frames_per_sequence,
        (Some(c), Some(k)) if c == k * cfg.frames_per_sequence => c,
        (Some(c), Some(k)) => bail!(
            "--count {c} disagrees with --sequences {k} x {} frames per sequence",
            cfg.frames_per_sequence
        ),
        (None, None) => bail!("give --count N or --sequences K"),
    };
    let t = std::time::Instant::now();
    let out = write_visuotactile(
        &cfg,
        count,
        a.common.seed,
        &a.common.out,
        WriteOptions {
            force: a.common.force,
            progress: true,
        },
    )?;
    finish(
        &a.common,
        &out,
        "virtual visuo-tactile",
        count,
        t.elapsed().as_secs_f64(),
    )
}
