//! `tactile train depth` and `tactile eval depth`.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use tactile_core::DeviceKind;
use tactile_core::dataset::Dataset;
use tactile_depth::training::{DepthTrainingConfig, evaluate, predict_mm, train_depth};
use tactile_depth::{DenseNetConfig, DepthArtifact, DepthNetConfig, DepthSet, HeadKind, LossKind};

use crate::detect_cmds::parse_size;
use crate::parse_device;

#[derive(Args)]
pub struct TrainDepthArgs {
    /// Visuo-tactile dataset (split by `sequence`).
    #[arg(long)]
    data: PathBuf,
    #[arg(long)]
    out: PathBuf,
    /// DenseNet preset: tiny, small, medium, densenet121, densenet161.
    #[arg(long, default_value = "small")]
    encoder: String,
    /// Input WIDTHxHEIGHT, multiples of 32 (paper B: 256x256).
    #[arg(long, default_value = "160x96", value_parser = parse_size)]
    input: [usize; 2],
    /// conv1x1 (paper B) or custom (two 3x3 conv + ReLU).
    #[arg(long, default_value = "conv1x1")]
    head: String,
    /// l1 (paper B), mse, or l1-grad-ssim (DenseTact).
    #[arg(long, default_value = "l1")]
    loss: LossKind,
    /// Feed the ground-truth tendon mask as a fourth channel.
    #[arg(long)]
    with_mask: bool,
    /// Train the decoder only.
    #[arg(long)]
    freeze_encoder: bool,
    /// torchvision DenseNet weights as safetensors (key mapping: the
    /// tactile-depth `torchvision` module docs); the preset must match.
    #[arg(long)]
    pretrained: Option<PathBuf>,
    /// Millimetres per model unit (1 = millimetres; 1000 = metres, which stalls and is refused).
    #[arg(long, default_value_t = 1.0)]
    unit_mm: f32,
    /// Channels of the deepest decoder block.
    #[arg(long, default_value_t = 64)]
    decoder_width: usize,
    #[arg(long, default_value_t = 12)]
    max_epochs: usize,
    #[arg(long, default_value_t = 3)]
    patience: usize,
    #[arg(long, default_value_t = 8)]
    batch_size: usize,
    #[arg(long, default_value_t = 1e-3)]
    lr: f64,
    #[arg(long, default_value_t = 0.2)]
    val_fraction: f64,
    #[arg(long, default_value_t = 42)]
    seed: u64,
    #[arg(long, default_value = "flex", value_parser = parse_device)]
    device: DeviceKind,
    #[arg(long)]
    resume: bool,
}

fn head(s: &str) -> Result<HeadKind> {
    Ok(match s {
        "conv1x1" | "1x1" => HeadKind::Conv1x1,
        "custom" => HeadKind::Custom,
        o => bail!("unknown head '{o}': expected conv1x1 or custom"),
    })
}

pub fn train(a: TrainDepthArgs) -> Result<()> {
    let ds = Dataset::open(&a.data)?;
    tactile_core::io::ensure_writable_dir(&a.out)?;
    let net = DepthNetConfig::new(DenseNetConfig::preset(&a.encoder)?, a.input)
        .with_head(head(&a.head)?)
        .with_decoder_width(a.decoder_width)
        .with_in_channels(3 + a.with_mask as usize);
    net.init(&DeviceKind::Flex.device())?;
    let (train, val) = ds.split_by_sequence(a.val_fraction, a.seed)?;
    eprintln!(
        "loading {} frames at {}x{} ({} train, {} validation, split by sequence)",
        ds.len(),
        a.input[0],
        a.input[1],
        train.len(),
        val.len()
    );
    let tr = DepthSet::from_dataset(&ds, &train, a.input)?;
    let va = DepthSet::from_dataset(&ds, &val, a.input)?;
    let config = DepthTrainingConfig::new(net)
        .with_loss(a.loss)
        .with_batch_size(a.batch_size)
        .with_max_epochs(a.max_epochs)
        .with_patience(a.patience)
        .with_learning_rate(a.lr)
        .with_unit_mm(a.unit_mm)
        .with_with_mask(a.with_mask)
        .with_freeze_encoder(a.freeze_encoder)
        .with_pretrained(a.pretrained.as_ref().map(|p| p.display().to_string()))
        .with_seed(a.seed);
    let s = train_depth(
        &config,
        &tr,
        &va,
        &a.out,
        &a.device.device(),
        a.resume,
        serde_json::json!({ "trained_on": a.data.display().to_string(), "device": a.device.name(), "encoder": a.encoder }),
    )?;
    println!("{}; model in {}", s.describe("MAE (mm)"), a.out.display());
    Ok(())
}

#[derive(Args)]
pub struct EvalDepthArgs {
    /// Depth model folder (depth.json + depth.bpk).
    #[arg(long)]
    model: PathBuf,
    #[arg(long)]
    data: PathBuf,
    /// Write true | predicted | error heat maps (one shared colour scale per
    /// frame) for the first frames into this folder.
    #[arg(long)]
    save_png: Option<PathBuf>,
    /// How many frames `--save-png` writes.
    #[arg(long, default_value_t = 8)]
    png_frames: usize,
    #[arg(long, default_value = "flex", value_parser = parse_device)]
    device: DeviceKind,
}

/// Scores of a depth model on a dataset (all frames), and the time per frame.
pub fn score(
    model: &std::path::Path,
    ds: &Dataset,
    device: DeviceKind,
) -> Result<(tactile_depth::DepthScores, f64)> {
    let dev = device.device();
    let (art, m) = DepthArtifact::load(model, &dev)?;
    let rows: Vec<usize> = (0..ds.len()).collect();
    let data = DepthSet::from_dataset(ds, &rows, art.net.input_size)?;
    let t0 = std::time::Instant::now();
    let s = evaluate(&m, &art, &data, &dev)?;
    Ok((
        s,
        1e3 * t0.elapsed().as_secs_f64() / data.len().max(1) as f64,
    ))
}

pub fn eval(a: EvalDepthArgs) -> Result<()> {
    let ds = Dataset::open(&a.data)?;
    let (s, ms) = score(&a.model, &ds, a.device)?;
    println!(
        "{} frames: MAE {:.4} mm in the window, {} over the tendon mask, RMSE {:.4} mm, SSIM {:.4}",
        s.frames,
        s.mae_mm,
        s.mae_tendon_mm.map_or("-".into(), |v| format!("{v:.4} mm")),
        s.rmse_mm,
        s.ssim
    );
    println!(
        "{ms:.2} ms per frame ({}, batch 16, loading excluded)",
        a.device.name()
    );
    if let Some(dir) = &a.save_png {
        let dev = a.device.device();
        let (art, m) = DepthArtifact::load(&a.model, &dev)?;
        let rows: Vec<usize> = (0..ds.len().min(a.png_frames)).collect();
        let data = DepthSet::from_dataset(&ds, &rows, art.net.input_size)?;
        let idx: Vec<usize> = (0..data.len()).collect();
        let preds = predict_mm(&m, &art, &data, &idx, &dev)?;
        tactile_core::io::create_dir_all(dir)?;
        for (i, p) in preds.iter().enumerate() {
            let path = dir.join(format!("depth-{i:03}.png"));
            tactile_core::plot::heat_maps(
                &path,
                &[&data.samples[i].depth_mm, p],
                (data.width, data.height),
            )?;
        }
        println!(
            "{} heat maps (true | predicted, shared scale) in {}",
            preds.len(),
            dir.display()
        );
    }
    println!(
        "{}",
        serde_json::json!({ "model": a.model, "data": a.data, "scores": s, "ms_per_frame": ms })
    );
    Ok(())
}
