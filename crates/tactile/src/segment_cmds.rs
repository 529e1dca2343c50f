//! `tactile train segmenter` and `tactile eval segmenter`.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use tactile_core::DeviceKind;
use tactile_core::dataset::Dataset;
use tactile_core::metrics::{iou, median, percentile};
use tactile_preprocess::visuo::SquareWindow;
use tactile_segment::postprocess::direction_error_deg;
use tactile_segment::training::{SegmenterTrainingConfig, predict, train_segmenter};
use tactile_segment::{SegmentSet, SegmenterArtifact, TendonMask, UNetConfig, postprocess};

use crate::parse_device;

#[derive(Args)]
pub struct TrainSegmenterArgs {
    /// Visuo-tactile dataset; its tendon frames are split by `sequence`.
    #[arg(long)]
    data: PathBuf,
    #[arg(long)]
    out: PathBuf,
    /// Side of the square window (a multiple of 16; paper B: 160).
    #[arg(long, default_value_t = 96)]
    side: usize,
    /// Channels of the first U-Net block.
    #[arg(long, default_value_t = 8)]
    base: usize,
    /// Rotated copies of each training frame (paper B's augmentation).
    #[arg(long, default_value_t = 4)]
    copies: usize,
    #[arg(long, default_value_t = 15)]
    max_epochs: usize,
    #[arg(long, default_value_t = 4)]
    patience: usize,
    #[arg(long, default_value_t = 16)]
    batch_size: usize,
    #[arg(long, default_value_t = 1e-3)]
    lr: f64,
    /// Learning-rate factor per epoch.
    #[arg(long, default_value_t = 0.8)]
    lr_decay: f64,
    #[arg(long, default_value_t = 0.2)]
    val_fraction: f64,
    #[arg(long, default_value_t = 42)]
    seed: u64,
    #[arg(long, default_value = "flex", value_parser = parse_device)]
    device: DeviceKind,
    #[arg(long)]
    resume: bool,
}

/// Rows of `rows` whose `tendon` label is 1.
fn tendon_rows(ds: &Dataset, rows: &[usize]) -> Result<Vec<usize>> {
    let mut out = Vec::new();
    for &i in rows {
        if ds.number(i, "tendon")? == 1.0 {
            out.push(i);
        }
    }
    Ok(out)
}

pub fn train(a: TrainSegmenterArgs) -> Result<()> {
    let ds = Dataset::open(&a.data)?;
    tactile_core::io::ensure_writable_dir(&a.out)?;
    let unet = UNetConfig::new().with_base(a.base).with_side(a.side);
    unet.init(&tactile_core::DeviceKind::Flex.device())?;
    let (train, val) = ds.split_by_sequence(a.val_fraction, a.seed)?;
    let (train, val) = (tendon_rows(&ds, &train)?, tendon_rows(&ds, &val)?);
    if train.is_empty() || val.is_empty() {
        bail!(
            "{}: no tendon frames to train or validate on",
            ds.labels_path().display()
        );
    }
    let window = SquareWindow { side: a.side };
    eprintln!(
        "cutting {}x{} windows: {} training frames x {} rotations, {} validation frames",
        a.side,
        a.side,
        train.len(),
        a.copies,
        val.len()
    );
    let train_set = SegmentSet::from_dataset(&ds, &train, window, a.copies, a.seed)?;
    let val_set = SegmentSet::from_dataset(&ds, &val, window, 1, a.seed)?;
    let config = SegmenterTrainingConfig::new(unet)
        .with_batch_size(a.batch_size)
        .with_max_epochs(a.max_epochs)
        .with_patience(a.patience)
        .with_learning_rate(a.lr)
        .with_lr_decay(a.lr_decay)
        .with_seed(a.seed);
    let s = train_segmenter(
        &config,
        &train_set,
        &val_set,
        &a.out,
        &a.device.device(),
        a.resume,
        serde_json::json!({ "trained_on": a.data.display().to_string(), "device": a.device.name(), "copies": a.copies }),
    )?;
    println!("{}; model in {}", s.describe("mean IoU"), a.out.display());
    Ok(())
}

#[derive(Args)]
pub struct EvalSegmenterArgs {
    /// Segmenter folder (segmenter.json + segmenter.bpk).
    #[arg(long)]
    model: PathBuf,
    /// Visuo-tactile dataset; its tendon frames are scored.
    #[arg(long)]
    data: PathBuf,
    #[arg(long, default_value = "flex", value_parser = parse_device)]
    device: DeviceKind,
}

#[derive(serde::Serialize)]
pub struct PathScores {
    pub path: String,
    pub frames: usize,
    pub mean_iou: f64,
    pub direction_frames: usize,
    pub no_direction: usize,
    pub direction_median_deg: f64,
    pub direction_p90_deg: f64,
}

/// IoU over all tendon frames, curved ones and per path, and the direction
/// error of the post-processed mask; with the inference time per window.
pub fn score(
    model: &std::path::Path,
    ds: &Dataset,
    device: DeviceKind,
) -> Result<(Vec<PathScores>, f64)> {
    let dev = device.device();
    let (art, m) = SegmenterArtifact::load(model, &dev)?;
    let rows = tendon_rows(ds, &(0..ds.len()).collect::<Vec<_>>())?;
    if rows.is_empty() {
        bail!("{}: no tendon frames to score", ds.labels_path().display());
    }
    let set = SegmentSet::from_dataset(ds, &rows, art.window(), 1, 0)?;
    let idx: Vec<usize> = (0..set.len()).collect();
    let t0 = std::time::Instant::now();
    let probs = predict(&m, &set, &idx, &art.stats, &dev)?;
    let ms = 1e3 * t0.elapsed().as_secs_f64() / set.len() as f64;
    let s = art.unet.side;
    let mut per: Vec<(String, f64, Option<f64>)> = Vec::new();
    for (i, p) in probs.iter().enumerate() {
        let w = &set.windows[i];
        let mask = TendonMask::from_probabilities(s, s, p, art.threshold)?;
        let score = iou(&mask.pixels, &w.mask);
        let t = postprocess(&mask, &art.postprocess)?;
        let err = match (t.direction, set.direction_deg[w.row]) {
            (Ok(d), Some(truth)) => Some(direction_error_deg(d.angle_deg, truth)),
            _ => None,
        };
        let path = set.path[w.row].clone().unwrap_or_else(|| "unknown".into());
        per.push((path, score, err));
    }
    let mut paths: Vec<String> = per.iter().map(|p| p.0.clone()).collect();
    paths.sort();
    paths.dedup();
    let summarise = |name: &str, keep: &dyn Fn(&str) -> bool| {
        let sel: Vec<&(String, f64, Option<f64>)> = per.iter().filter(|p| keep(&p.0)).collect();
        let errs: Vec<f64> = sel.iter().filter_map(|p| p.2).collect();
        PathScores {
            path: name.to_string(),
            frames: sel.len(),
            mean_iou: sel.iter().map(|p| p.1).sum::<f64>() / sel.len().max(1) as f64,
            direction_frames: errs.len(),
            no_direction: sel.len() - errs.len(),
            direction_median_deg: if errs.is_empty() {
                f64::NAN
            } else {
                median(&errs)
            },
            direction_p90_deg: if errs.is_empty() {
                f64::NAN
            } else {
                percentile(&errs, 90.0)
            },
        }
    };
    let mut table = vec![summarise("all", &|_| true)];
    table.push(summarise("curved (arc + s-curve)", &|p| {
        p == "arc" || p == "s-curve"
    }));
    for p in &paths {
        table.push(summarise(p, &|q| q == p));
    }
    Ok((table, ms))
}

/// Print [`score`]; the last line is the metrics as JSON.
pub fn eval(a: EvalSegmenterArgs) -> Result<()> {
    let ds = Dataset::open(&a.data)?;
    let (table, ms) = score(&a.model, &ds, a.device)?;
    println!(
        "| tendon path | frames | mean IoU | direction median (deg) | direction p90 (deg) | no direction |"
    );
    println!("|---|---|---|---|---|---|");
    for r in &table {
        println!(
            "| {} | {} | {:.4} | {:.2} | {:.2} | {} |",
            r.path,
            r.frames,
            r.mean_iou,
            r.direction_median_deg,
            r.direction_p90_deg,
            r.no_direction
        );
    }
    println!(
        "{ms:.2} ms per window ({}, batch 32, cut excluded)",
        a.device.name()
    );
    println!(
        "{}",
        serde_json::json!({ "model": a.model, "data": a.data, "paths": table, "ms_per_window": ms })
    );
    Ok(())
}
