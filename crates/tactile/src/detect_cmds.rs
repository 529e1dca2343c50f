//! `tactile train detector` and `tactile eval detector`.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;
use tactile_core::DeviceKind;
use tactile_core::dataset::Dataset;
use tactile_core::metrics::binary_scores;
use tactile_detect::training::{DetectorTrainingConfig, predict, train_detector};
use tactile_detect::{Architecture, DetectionSet, DetectorArtifact, DetectorConfig, SoftLabels};

use crate::parse_device;

/// `WIDTHxHEIGHT`, e.g. `160x120`.
pub fn parse_size(s: &str) -> std::result::Result<[usize; 2], String> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| format!("'{s}': expected WIDTHxHEIGHT, e.g. 160x120"))?;
    let p = |v: &str| {
        v.parse::<usize>()
            .ok()
            .filter(|&n| n >= 16)
            .ok_or_else(|| format!("'{s}': sizes must be whole numbers of at least 16 pixels"))
    };
    Ok([p(w)?, p(h)?])
}

#[derive(Args)]
pub struct TrainDetectorArgs {
    /// Visuo-tactile dataset(s), each split by `sequence` into train and
    /// validation (e.g. the default distribution plus a set of light
    /// presses that crowds the frames near the label's threshold).
    #[arg(long, num_args = 1.., required = true)]
    data: Vec<PathBuf>,
    /// Output model folder.
    #[arg(long)]
    out: PathBuf,
    /// mobilenet-v3-small or resnet18.
    #[arg(long, default_value = "mobilenet-v3-small")]
    architecture: String,
    /// Channel width multiplier.
    #[arg(long, default_value_t = 0.5)]
    width: f64,
    /// Input size WIDTHxHEIGHT (paper B: 320x240).
    #[arg(long, default_value = "160x120", value_parser = parse_size)]
    input: [usize; 2],
    #[arg(long, default_value_t = 12)]
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
    /// Fraction of the sequences that validate.
    #[arg(long, default_value_t = 0.2)]
    val_fraction: f64,
    #[arg(long, default_value_t = 42)]
    seed: u64,
    #[arg(long, default_value = "flex", value_parser = parse_device)]
    device: DeviceKind,
    /// Continue from the checkpoint in the output folder.
    #[arg(long)]
    resume: bool,
    /// Train toward soft targets from each frame's ridge amplitude
    /// (`ridge_mm`): sigmoid(ln(A / 0.03 mm) / WIDTH), 0.03 mm being the
    /// spec's label threshold. Frames near the threshold then teach the
    /// network to measure the ridge. Suggested width: 0.2.
    #[arg(long, value_name = "WIDTH")]
    soft_labels: Option<f64>,
    /// Only re-choose the threshold of the model already in --out on the
    /// validation sequences (training ends with this step anyway).
    #[arg(long)]
    calibrate_only: bool,
}

fn architecture(s: &str) -> Result<Architecture> {
    Ok(match s {
        "mobilenet-v3-small" | "mobilenet" => Architecture::MobilenetV3Small,
        "resnet18" | "resnet-18" => Architecture::Resnet18,
        other => bail!("unknown architecture '{other}': expected mobilenet-v3-small or resnet18"),
    })
}

pub fn train(a: TrainDetectorArgs) -> Result<()> {
    let cfg = DetectorConfig::new()
        .with_architecture(architecture(&a.architecture)?)
        .with_width(a.width)
        .with_input_size(a.input);
    if !(a.width > 0.0 && a.width <= 4.0) {
        bail!("--width must be in (0, 4], got {}", a.width);
    }
    tactile_core::io::ensure_writable_dir(&a.out)?;
    // Every dataset is split by its own sequences; indices of later
    // datasets shift by the frames before them.
    let (mut train, mut val) = (Vec::new(), Vec::new());
    let mut data: Option<DetectionSet> = None;
    for path in &a.data {
        let ds = Dataset::open(path)?;
        let (t, v) = ds.split_by_sequence(a.val_fraction, a.seed)?;
        eprintln!(
            "loading {} frames of {} at {}x{} ({} train, {} validation, split by sequence)",
            ds.len(),
            path.display(),
            a.input[0],
            a.input[1],
            t.len(),
            v.len()
        );
        let set = DetectionSet::from_dataset(&ds, a.input)?;
        if a.soft_labels.is_some() {
            set.check_soft_labels(&ds.labels_path())?;
        }
        let offset = data.as_ref().map_or(0, DetectionSet::len);
        train.extend(t.into_iter().map(|i| i + offset));
        val.extend(v.into_iter().map(|i| i + offset));
        match data.as_mut() {
            None => data = Some(set),
            Some(d) => d.append(set)?,
        }
    }
    let data = data.context("--data names no dataset")?;
    let soft_labels = match a.soft_labels {
        None => None,
        Some(w) if w > 0.0 && w.is_finite() => Some(SoftLabels::new(
            datasets_synth::visuotactile::TENDON_MIN_AMPLITUDE_MM,
            w,
        )),
        Some(w) => bail!("--soft-labels must be a positive width, got {w}"),
    };
    let dev = a.device.device();
    if a.calibrate_only {
        let (t, acc) = tactile_detect::training::calibrate(&a.out, &data, &val, &dev)?;
        println!(
            "threshold {t:.2}: validation accuracy {acc:.4}; saved in {}",
            a.out.display()
        );
        return Ok(());
    }
    let config = DetectorTrainingConfig::new(cfg)
        .with_batch_size(a.batch_size)
        .with_max_epochs(a.max_epochs)
        .with_patience(a.patience)
        .with_learning_rate(a.lr)
        .with_lr_decay(a.lr_decay)
        .with_seed(a.seed)
        .with_soft_labels(soft_labels);
    let s = train_detector(
        &config,
        &data,
        (&train, &val),
        &a.out,
        &dev,
        a.resume,
        serde_json::json!({
            "trained_on": a.data.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(" + "),
            "device": a.device.name(),
        }),
    )?;
    let (t, acc) = tactile_detect::training::calibrate(&a.out, &data, &val, &dev)?;
    println!(
        "{} (accuracy {acc:.4} at the chosen threshold {t:.2}); model in {}",
        s.describe("accuracy at threshold 0.5"),
        a.out.display()
    );
    Ok(())
}

#[derive(Args)]
pub struct EvalDetectorArgs {
    /// Detector folder (detector.json + detector.bpk).
    #[arg(long)]
    model: PathBuf,
    /// Visuo-tactile dataset with `tendon` labels.
    #[arg(long)]
    data: PathBuf,
    #[arg(long, default_value = "flex", value_parser = parse_device)]
    device: DeviceKind,
    /// Also write every frame's probability and decision to this CSV
    /// (file, tendon, probability, predicted, onset_release), to look at
    /// the frames it gets wrong.
    #[arg(long)]
    frames: Option<PathBuf>,
}

/// A detector's scores on a dataset.
pub struct DetectorScores {
    pub all: tactile_core::metrics::BinaryScores,
    pub onset_release: tactile_core::metrics::BinaryScores,
    pub ms_per_frame: f64,
    /// Per-frame tendon probability, in dataset order.
    pub probabilities: Vec<f32>,
    pub threshold: f64,
}

/// Score a detector on every frame of `data` (frames resized on load).
pub fn score(
    model: &std::path::Path,
    data: &DetectionSet,
    device: DeviceKind,
) -> Result<DetectorScores> {
    let dev = device.device();
    let (art, m) = DetectorArtifact::load(model, &dev)?;
    if (data.width, data.height) != (art.detector.input_size[0], art.detector.input_size[1]) {
        bail!(
            "frames loaded at {}x{}, {} takes {:?}",
            data.width,
            data.height,
            model.display(),
            art.detector.input_size
        );
    }
    let all: Vec<usize> = (0..data.len()).collect();
    let t0 = std::time::Instant::now();
    let p = predict(&m, data, &all, &art.stats, 32, &dev)?;
    let ms_per_frame = 1e3 * t0.elapsed().as_secs_f64() / data.len().max(1) as f64;
    let pred: Vec<bool> = p.iter().map(|&q| q as f64 >= art.threshold).collect();
    let tr: Vec<usize> = all
        .iter()
        .copied()
        .filter(|&i| data.transition[i])
        .collect();
    Ok(DetectorScores {
        all: binary_scores(&pred, &data.tendon),
        onset_release: binary_scores(
            &tr.iter().map(|&i| pred[i]).collect::<Vec<_>>(),
            &tr.iter().map(|&i| data.tendon[i]).collect::<Vec<_>>(),
        ),
        ms_per_frame,
        probabilities: p,
        threshold: art.threshold,
    })
}

/// Scores on a dataset; the last line printed is the metrics as JSON.
pub fn eval(a: EvalDetectorArgs) -> Result<()> {
    let (art, _) = DetectorArtifact::load(&a.model, &a.device.device())?;
    let ds = Dataset::open(&a.data)?;
    let data = DetectionSet::from_dataset(&ds, art.detector.input_size)?;
    let DetectorScores {
        all: s,
        onset_release: st,
        ms_per_frame: ms,
        probabilities,
        threshold,
    } = score(&a.model, &data, a.device)?;
    if let Some(path) = &a.frames {
        let mut csv = String::from("file,tendon,probability,predicted,onset_release\n");
        for (i, p) in probabilities.iter().enumerate() {
            csv.push_str(&format!(
                "{},{},{p:.6},{},{}\n",
                data.files[i],
                data.tendon[i] as u8,
                (*p as f64 >= threshold) as u8,
                data.transition[i] as u8
            ));
        }
        tactile_core::io::write_atomic(path, csv.as_bytes())?;
        eprintln!("per-frame decisions in {}", path.display());
    }
    println!(
        "{} frames ({} with a tendon): accuracy {:.4}, precision {:.4}, recall {:.4}, F1 {:.4}",
        s.frames,
        s.true_pos + s.false_neg,
        s.accuracy,
        s.precision,
        s.recall,
        s.f1
    );
    println!(
        "confusion: {} true positive, {} false positive, {} true negative, {} false negative",
        s.true_pos, s.false_pos, s.true_neg, s.false_neg
    );
    println!(
        "onset/release frames (within 2 frames of a label change): {} frames, accuracy {:.4} ({} false positive, {} false negative)",
        st.frames, st.accuracy, st.false_pos, st.false_neg
    );
    println!(
        "{ms:.2} ms per frame ({}, batch 32, resize excluded)",
        a.device.name()
    );
    println!(
        "{}",
        serde_json::json!({ "model": a.model, "data": a.data, "all": s, "onset_release": st, "ms_per_frame": ms })
    );
    Ok(())
}
