//! Paper A commands: train the CAE and its shape head, encode, export, demo.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand::seq::SliceRandom;
use tactile_cae::CaeArtifact;
use tactile_cae::data::PinSet;
use tactile_cae::encode::{encode_all, write_features_csv};
use tactile_cae::head::{ClassifierHead, HeadConfig};
use tactile_cae::model::CaeConfig;
use tactile_cae::training::{CaeTrainingConfig, train_cae as run_training};
use tactile_core::DeviceKind;
use tactile_core::dataset::Dataset;
use tactile_core::metrics::{accuracy, confusion};
use tactile_core::optim::AdadeltaConfig;
use tactile_preprocess::PreprocessConfig;

use crate::parse_device;

#[derive(Args)]
pub struct TrainCaeArgs {
    /// TacTip dataset folder; with a `split` column, only `train` rows are used.
    #[arg(long)]
    data: PathBuf,
    /// Output model folder.
    #[arg(long)]
    out: PathBuf,
    #[arg(long, default_value = "flex", value_parser = parse_device)]
    device: DeviceKind,
    /// Preprocessing preset: binary (already binarised frames), paper, lighting-compensated.
    #[arg(long, default_value = "binary")]
    preprocess: String,
    /// Encoder widths, e.g. 16,8,8,4 (paper) or 16,16,8,4 (authors' release).
    #[arg(long, value_delimiter = ',', default_values_t = [16, 8, 8, 4])]
    widths: Vec<usize>,
    /// Feature count (8/16/32/64): sets the last width.
    #[arg(long)]
    features: Option<usize>,
    /// No ReLU before the last pooling: features cannot die (see CaeConfig).
    #[arg(long)]
    linear_latent: bool,
    #[arg(long, default_value_t = 3000)]
    max_epochs: usize,
    #[arg(long, default_value_t = 300)]
    patience: usize,
    #[arg(long, default_value_t = 256)]
    batch_size: usize,
    /// Fraction of the training rows held out for early stopping.
    #[arg(long, default_value_t = 0.2)]
    val_fraction: f64,
    #[arg(long, default_value_t = 42)]
    seed: u64,
    /// Without a `split` column: leave out the test frames that `tactile
    /// compare`/`train regressor` with this --test-fraction and
    /// --split-seed hold out, so the encoder never sees them.
    #[arg(long)]
    exclude_test: Option<f64>,
    /// The seed of that split (compare's --seed).
    #[arg(long, default_value_t = 7)]
    split_seed: u64,
    /// adadelta (paper A, lr 1.0) or adam.
    #[arg(long, default_value = "adadelta")]
    optimizer: String,
    /// Learning rate (default: 1.0 for adadelta, 0.003 for adam).
    #[arg(long)]
    lr: Option<f64>,
    /// Continue from the checkpoint in the output folder.
    #[arg(long)]
    resume: bool,
}

/// Split rows into (train, validation): the dataset's `train` split (or all
/// rows), shuffled with `seed`, the last `val_fraction` held out.
fn train_val(
    ds: &Dataset,
    val_fraction: f64,
    seed: u64,
    exclude_test: Option<(f64, u64)>,
) -> Result<(Vec<usize>, Vec<usize>)> {
    let mut rows = match (ds.split_indices("train"), exclude_test) {
        (Some(train), _) => train,
        (None, Some((test_fraction, split_seed))) => {
            let (mut train, val, _test) =
                crate::estimate_cmds::three_way_split(ds, test_fraction, 0.2, split_seed)?;
            train.extend(val);
            train.sort_unstable();
            train
        }
        (None, None) => (0..ds.len()).collect(),
    };
    if rows.len() < 2 {
        bail!(
            "{}: need at least 2 training frames, found {}",
            ds.root.display(),
            rows.len()
        );
    }
    if !(0.0..1.0).contains(&val_fraction) {
        bail!("--val-fraction must be in [0, 1), got {val_fraction}");
    }
    rows.shuffle(&mut StdRng::seed_from_u64(seed));
    let n_val = ((rows.len() as f64 * val_fraction).round() as usize).clamp(1, rows.len() - 1);
    let val = rows.split_off(rows.len() - n_val);
    Ok((rows, val))
}

pub fn train_cae(a: TrainCaeArgs) -> Result<()> {
    let ds = Dataset::open(&a.data)?;
    // An unwritable output folder fails now, not at the first checkpoint.
    tactile_core::io::ensure_writable_dir(&a.out)?;
    let pre = PreprocessConfig::preset(&a.preprocess)?;
    let widths: [usize; 4] = a
        .widths
        .clone()
        .try_into()
        .map_err(|_| anyhow::anyhow!("--widths needs 4 values"))?;
    let mut cae = CaeConfig::new()
        .with_widths(widths)
        .with_latent_relu(a.linear_latent.then_some(false));
    if let Some(f) = a.features {
        cae = cae.with_feature_count(f)?;
    }
    eprintln!("preprocessing {} frames ({})", ds.len(), a.preprocess);
    let pins = PinSet::from_dataset(&ds, &pre)?;
    let (train, val) = train_val(
        &ds,
        a.val_fraction,
        a.seed,
        a.exclude_test.map(|f| (f, a.split_seed)),
    )?;
    let config = CaeTrainingConfig::new(cae.clone(), AdadeltaConfig::new())
        .with_batch_size(a.batch_size)
        .with_max_epochs(a.max_epochs)
        .with_patience(a.patience)
        .with_seed(a.seed)
        .with_learning_rate(a.lr.unwrap_or(if a.optimizer == "adam" { 3e-3 } else { 1.0 }))
        .with_optimizer_kind(a.optimizer.clone());
    let artifact = CaeArtifact {
        cae,
        preprocess: pre,
        notes: serde_json::json!({
            "trained_on": a.data.display().to_string(),
            "device": a.device.name(),
            "excluded_test": a.exclude_test.map(|f| serde_json::json!({ "test_fraction": f, "split_seed": a.split_seed })),
        }),
    };
    let s = run_training(
        &config,
        artifact,
        &pins,
        (&train, &val),
        &a.out,
        &a.device.device(),
        a.resume,
    )?;
    println!(
        "trained {} epochs in {:.0} s; best validation BCE {:.4} at epoch {}; model in {}",
        s.epochs_run,
        s.seconds,
        s.best_val_loss,
        s.best_epoch,
        a.out.display()
    );
    Ok(())
}

#[derive(Args)]
pub struct TrainHeadArgs {
    /// Trained encoder folder; the head is written to ENCODER/head/.
    #[arg(long, required_unless_present = "features")]
    encoder: Option<PathBuf>,
    /// Precomputed feature CSV (file,f0,f1,...) instead of an encoder,
    /// e.g. the authors' golden-features.csv; needs --out.
    #[arg(long, conflicts_with = "encoder", requires = "out")]
    features: Option<PathBuf>,
    /// Head folder (default: ENCODER/head).
    #[arg(long)]
    out: Option<PathBuf>,
    /// A separate test dataset (default: the `test` split of --data).
    #[arg(long)]
    test: Option<PathBuf>,
    /// Dataset with `shape` labels and a `split` column (train/test).
    #[arg(long)]
    data: PathBuf,
    #[arg(long, default_value = "flex", value_parser = parse_device)]
    device: DeviceKind,
    /// Ensemble members; each early-stops on its own fold of the train split.
    #[arg(long, default_value_t = 10)]
    folds: usize,
    /// Repeats of the k-fold split (members = folds x repeats).
    #[arg(long, default_value_t = 3)]
    repeats: usize,
    #[arg(long, default_value_t = 7)]
    seed: u64,
}

/// Feature vectors of every frame of a dataset under a trained encoder.
pub fn encode_dataset(model: &Path, ds: &Dataset, device: DeviceKind) -> Result<Vec<Vec<f32>>> {
    let dev = device.device();
    let (art, cae) = CaeArtifact::load(model, &dev)?;
    let pins = PinSet::from_dataset(ds, &art.preprocess)?;
    Ok(encode_all(&cae.encoder, &pins, 256, &dev)?)
}

/// Features and shape labels of a dataset under an encoder.
fn features_and_shapes(
    model: &Path,
    ds: &Dataset,
    device: DeviceKind,
) -> Result<(Vec<Vec<f32>>, Vec<String>)> {
    let feats = encode_dataset(model, ds, device)?;
    let shapes = (0..ds.len())
        .map(|i| ds.text(i, "shape").map(str::to_string))
        .collect::<Result<Vec<_>, _>>()?;
    Ok((feats, shapes))
}

/// Rows of a feature CSV aligned with the dataset's rows by `file`.
fn features_from_csv(csv: &Path, ds: &Dataset) -> Result<(Vec<Vec<f32>>, Vec<String>)> {
    let (files, feats) = tactile_cae::encode::read_features_csv(csv)?;
    let by_file: std::collections::HashMap<&str, &Vec<f32>> =
        files.iter().map(String::as_str).zip(&feats).collect();
    let mut out = Vec::with_capacity(ds.len());
    let mut shapes = Vec::with_capacity(ds.len());
    for i in 0..ds.len() {
        let file = ds.text(i, "file")?;
        let f = by_file.get(file).with_context(|| {
            format!(
                "{}: no feature row for '{file}' (labels.csv line {})",
                csv.display(),
                i + 2
            )
        })?;
        out.push((*f).clone());
        shapes.push(ds.text(i, "shape")?.to_string());
    }
    Ok((out, shapes))
}

pub fn train_head(a: TrainHeadArgs) -> Result<()> {
    let ds = Dataset::open(&a.data)?;
    let (feats, shapes, out) = match (&a.features, &a.encoder) {
        (Some(csv), _) => {
            let (f, s) = features_from_csv(csv, &ds)?;
            (f, s, a.out.clone().context("--features needs --out")?)
        }
        (None, Some(enc)) => {
            let (f, s) = features_and_shapes(enc, &ds, a.device)?;
            (f, s, a.out.clone().unwrap_or_else(|| enc.join("head")))
        }
        (None, None) => bail!("give --encoder DIR or --features CSV"),
    };
    let mut classes: Vec<String> = shapes.clone();
    classes.sort();
    classes.dedup();
    let y: Vec<usize> = shapes
        .iter()
        .map(|s| classes.iter().position(|c| c == s).unwrap_or(0))
        .collect();
    let train = ds
        .split_indices("train")
        .unwrap_or_else(|| (0..ds.len()).collect());
    let pick = |idx: &[usize]| -> (Vec<Vec<f32>>, Vec<usize>) {
        (
            idx.iter().map(|&i| feats[i].clone()).collect(),
            idx.iter().map(|&i| y[i]).collect(),
        )
    };
    let (tx, ty) = pick(&train);
    let cfg = HeadConfig::new(feats[0].len(), classes.clone())
        .with_seed(a.seed)
        .with_folds(a.folds)
        .with_repeats(a.repeats);
    let dev = a.device.device();
    eprintln!(
        "training a {}-fold head ensemble on {} frames",
        a.folds,
        tx.len()
    );
    let head = ClassifierHead::train(cfg, &tx, &ty, &dev)?;
    head.save(&out)?;
    // Test: a separate dataset (--test, encoder only) or the `test` split.
    let test_set: Option<(Vec<Vec<f32>>, Vec<usize>)> = match (&a.test, &a.encoder) {
        (Some(t), Some(enc)) => {
            let tds = Dataset::open(t)?;
            let (f, s) = features_and_shapes(enc, &tds, a.device)?;
            let y = s
                .iter()
                .enumerate()
                .map(|(i, s)| {
                    classes.iter().position(|c| c == s).with_context(|| {
                        format!(
                            "{}: labels.csv line {}: shape '{s}' was not in the training set",
                            t.display(),
                            i + 2
                        )
                    })
                })
                .collect::<Result<Vec<_>>>()?;
            Some((f, y))
        }
        (Some(_), None) => bail!("--test needs --encoder"),
        (None, _) => ds.split_indices("test").map(|t| pick(&t)),
    };
    if let Some((sx, sy)) = test_set {
        let pred = head.predict(&sx, &dev)?;
        let acc = accuracy(&pred, &sy);
        println!(
            "test shape accuracy: {:.1} % ({}/{})",
            100.0 * acc,
            pred.iter().zip(&sy).filter(|(a, b)| a == b).count(),
            sy.len()
        );
        print_confusion(&classes, &confusion(&pred, &sy, classes.len()));
    }
    println!("head saved in {}", out.display());
    Ok(())
}

fn print_confusion(classes: &[String], m: &[Vec<usize>]) {
    println!(
        "confusion (rows: truth, columns: predicted): {}",
        classes.join(" ")
    );
    for (c, row) in classes.iter().zip(m) {
        println!(
            "  {c:>12} {}",
            row.iter().map(|v| format!("{v:>5}")).collect::<String>()
        );
    }
}

pub fn encode(model: &Path, data: &Path, out: &Path, device: DeviceKind) -> Result<()> {
    let ds = Dataset::open(data)?;
    let dev = device.device();
    let (art, cae) = CaeArtifact::load(model, &dev)?;
    let pins = PinSet::from_dataset(&ds, &art.preprocess)?;
    let feats = encode_all(&cae.encoder, &pins, 256, &dev)?;
    write_features_csv(out, &pins.files, &feats)?;
    println!(
        "{} feature vectors of {} values written to {}",
        feats.len(),
        art.cae.feature_count(),
        out.display()
    );
    Ok(())
}

pub fn export(model: &Path, out: &Path, part: &str) -> Result<()> {
    let dev = DeviceKind::Flex.device();
    // Paper B's models: the folder says which (the input is normalised
    // with the statistics in its JSON).
    if model.join(tactile_detect::CONFIG_FILE).is_file() {
        let (art, m) = tactile_detect::DetectorArtifact::load(model, &dev)?;
        let bytes = tactile_onnx::export_detector(&m, art.detector.input_size)?;
        tactile_onnx::export::save_onnx(out, &bytes)?;
        println!(
            "detector exported to {} ({} bytes)",
            out.display(),
            bytes.len()
        );
        return Ok(());
    }
    if model.join(tactile_segment::CONFIG_FILE).is_file() {
        let (art, m) = tactile_segment::SegmenterArtifact::load(model, &dev)?;
        let bytes = tactile_onnx::export_segmenter(&m, art.unet.side)?;
        tactile_onnx::export::save_onnx(out, &bytes)?;
        println!(
            "segmenter exported to {} ({} bytes)",
            out.display(),
            bytes.len()
        );
        return Ok(());
    }
    if model.join(tactile_depth::CONFIG_FILE).is_file() {
        let (art, m) = tactile_depth::DepthArtifact::load(model, &dev)?;
        let bytes = tactile_onnx::export_depth(&m, art.net.in_channels, art.net.input_size)?;
        tactile_onnx::export::save_onnx(out, &bytes)?;
        println!(
            "depth network exported to {} ({} bytes)",
            out.display(),
            bytes.len()
        );
        return Ok(());
    }
    let (art, cae) = CaeArtifact::load(model, &dev)?;
    let bytes = match part {
        "encoder" => tactile_onnx::export_cae_encoder(&cae.encoder, art.cae.input_px)?,
        "autoencoder" => tactile_onnx::export_cae(&cae, art.cae.input_px)?,
        other => bail!("unknown --part '{other}': expected encoder or autoencoder"),
    };
    tactile_onnx::export::save_onnx(out, &bytes)?;
    println!(
        "{part} exported to {} ({} bytes)",
        out.display(),
        bytes.len()
    );
    Ok(())
}

pub fn demo(model: &Path, data: &Path, per_class: usize) -> Result<()> {
    let dev = DeviceKind::Flex.device();
    let (art, cae) = CaeArtifact::load(model, &dev)
        .with_context(|| format!("loading the shipped model from {}", model.display()))?;
    let head = ClassifierHead::load(model.join("head"), &dev)?;
    let ds = Dataset::open(data)
        .with_context(|| format!("the demo reads TacTip frames from {}", data.display()))?;
    let rows = ds
        .split_indices("test")
        .unwrap_or_else(|| (0..ds.len()).collect());
    let mut picked = Vec::new();
    for class in &head.config.classes {
        picked.extend(
            rows.iter()
                .copied()
                .filter(|&i| ds.text_opt(i, "shape") == Some(class.as_str()))
                .take(per_class),
        );
    }
    let paths: Vec<PathBuf> = picked
        .iter()
        .map(|&i| ds.path_of(i, "file"))
        .collect::<Result<_, _>>()?;
    let pins = tactile_preprocess::preprocess_files(&paths, &art.preprocess)?;
    let set = PinSet {
        files: picked
            .iter()
            .map(|&i| ds.text(i, "file").map(str::to_string))
            .collect::<Result<_, _>>()?,
        images: pins,
    };
    let feats = encode_all(&cae.encoder, &set, 256, &dev)?;
    let pred = head.predict(&feats, &dev)?;
    println!(
        "encoder {:?}, {} features per frame; head classes {}",
        art.cae.widths,
        art.cae.feature_count(),
        head.config.classes.join(", ")
    );
    let mut right = 0;
    for (((file, f), p), &row) in set.files.iter().zip(&feats).zip(&pred).zip(&picked) {
        let truth = ds.text_opt(row, "shape").unwrap_or("?");
        let guess = &head.config.classes[*p];
        right += usize::from(truth == guess);
        let fs: Vec<String> = f.iter().map(|v| format!("{v:.2}")).collect();
        println!(
            "{file:<28} true {truth:<11} predicted {guess:<11} features [{}]",
            fs.join(" ")
        );
    }
    println!("{right}/{} frames classified correctly", feats.len());
    Ok(())
}
