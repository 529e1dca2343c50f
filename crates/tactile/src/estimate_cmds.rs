//! `tactile train regressor`: pose, depth and force estimators on features.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand::seq::SliceRandom;
use tactile_core::DeviceKind;
use tactile_core::dataset::Dataset;
use tactile_estimate::{Regressor, RegressorConfig, Target};

use crate::cae_cmds::encode_dataset;
use crate::eval_cmds::{Estimator, load_estimators};
use crate::parse_device;

#[derive(Args)]
pub struct TrainRegressorArgs {
    /// Trained encoder folder (features are computed from the frames).
    #[arg(long, required_unless_present = "features")]
    encoder: Option<PathBuf>,
    /// Precomputed feature CSV (file,f0,f1,...) instead of an encoder.
    #[arg(long, conflicts_with = "encoder")]
    features: Option<PathBuf>,
    /// Dataset with the target label columns.
    #[arg(long)]
    data: PathBuf,
    /// Targets: label columns, angles with their period, e.g. x_mm,theta_deg:180,depth_mm.
    #[arg(long, value_delimiter = ',', required = true)]
    targets: Vec<String>,
    /// Output folder (default: ENCODER/regressor).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Without a `split` column: fraction of frames held out for testing.
    #[arg(long, default_value_t = 0.2)]
    test_fraction: f64,
    /// Fraction of the training frames used for early stopping.
    #[arg(long, default_value_t = 0.2)]
    val_fraction: f64,
    /// Hidden layer widths (ReLU), e.g. 32,16 (the authors' force head).
    #[arg(long, value_delimiter = ',', default_values_t = [32, 16])]
    hidden: Vec<usize>,
    #[arg(long, default_value_t = 7)]
    seed: u64,
    #[arg(long, default_value = "flex", value_parser = parse_device)]
    device: DeviceKind,
    /// Use only frames where every target is labelled (e.g. theta_deg,
    /// empty for spheres and flats); otherwise an empty label is an error.
    #[arg(long)]
    only_labelled: bool,
}

/// `(train, val, test)` rows: the dataset's split column when it has one,
/// else a seeded shuffle.
pub fn three_way_split(
    ds: &Dataset,
    test_fraction: f64,
    val_fraction: f64,
    seed: u64,
) -> Result<(Vec<usize>, Vec<usize>, Vec<usize>)> {
    for (name, f) in [
        ("--test-fraction", test_fraction),
        ("--val-fraction", val_fraction),
    ] {
        if !(0.0..1.0).contains(&f) || f == 0.0 {
            bail!("{name} must be in (0, 1), got {f}");
        }
    }
    let mut rng = StdRng::seed_from_u64(seed);
    let (mut train, test) = match (ds.split_indices("train"), ds.split_indices("test")) {
        (Some(tr), Some(te)) => (tr, te),
        _ => {
            let mut all: Vec<usize> = (0..ds.len()).collect();
            all.shuffle(&mut rng);
            let n_test = ((all.len() as f64 * test_fraction).round() as usize).max(1);
            let test = all.split_off(all.len().saturating_sub(n_test));
            (all, test)
        }
    };
    train.shuffle(&mut rng);
    let n_val = ((train.len() as f64 * val_fraction).round() as usize).max(1);
    if train.len() <= n_val || test.is_empty() {
        bail!(
            "{}: too few frames ({}) for train, validation and test sets",
            ds.root.display(),
            ds.len()
        );
    }
    let val = train.split_off(train.len() - n_val);
    Ok((train, val, test))
}

pub fn train_regressor(a: TrainRegressorArgs) -> Result<()> {
    let ds = Dataset::open(&a.data)?;
    let targets: Vec<Target> = a
        .targets
        .iter()
        .map(|t| Target::parse(t))
        .collect::<Result<_, _>>()?;
    let (feats, out) = match (&a.features, &a.encoder) {
        (Some(csv), _) => {
            let (files, f) = tactile_cae::encode::read_features_csv(csv)?;
            let by_file: std::collections::HashMap<&str, &Vec<f32>> =
                files.iter().map(String::as_str).zip(&f).collect();
            let feats = (0..ds.len())
                .map(|i| {
                    let file = ds.text(i, "file")?;
                    by_file
                        .get(file)
                        .map(|v| (*v).clone())
                        .with_context(|| format!("{}: no feature row for '{file}'", csv.display()))
                })
                .collect::<Result<Vec<_>>>()?;
            (feats, a.out.clone().context("--features needs --out")?)
        }
        (None, Some(enc)) => (
            encode_dataset(enc, &ds, a.device)?,
            a.out.clone().unwrap_or_else(|| enc.join("regressor")),
        ),
        (None, None) => bail!("give --encoder DIR or --features CSV"),
    };
    // Every target must be labelled on every frame used: with
    // --only-labelled, frames missing one are left out of every split.
    let labels = (0..ds.len())
        .map(|i| -> Result<Option<Vec<f64>>> {
            let mut row = Vec::with_capacity(targets.len());
            for t in &targets {
                match (ds.number_opt(i, &t.name)?, a.only_labelled) {
                    (Some(v), _) => row.push(v),
                    (None, true) => return Ok(None),
                    (None, false) => row.push(ds.number(i, &t.name)?),
                }
            }
            Ok(Some(row))
        })
        .collect::<Result<Vec<_>>>()?;
    let (mut train, mut val, mut test) =
        three_way_split(&ds, a.test_fraction, a.val_fraction, a.seed)?;
    for rows in [&mut train, &mut val, &mut test] {
        rows.retain(|&i| labels[i].is_some());
    }
    if train.is_empty() || val.is_empty() || test.is_empty() {
        bail!(
            "{}: too few frames with every target labelled ({} train, {} validation, {} test)",
            ds.labels_path().display(),
            train.len(),
            val.len(),
            test.len()
        );
    }
    let labels: Vec<Vec<f64>> = labels.into_iter().map(Option::unwrap_or_default).collect();
    let pick = |idx: &[usize]| -> (Vec<Vec<f32>>, Vec<Vec<f64>>) {
        (
            idx.iter().map(|&i| feats[i].clone()).collect(),
            idx.iter().map(|&i| labels[i].clone()).collect(),
        )
    };
    let (tx, ty) = pick(&train);
    let (vx, vy) = pick(&val);
    let (sx, sy) = pick(&test);
    eprintln!(
        "training a regressor for {} on {} frames ({} validation, {} test)",
        a.targets.join(", "),
        tx.len(),
        vx.len(),
        sx.len()
    );
    let dev = a.device.device();
    let cfg = RegressorConfig::new(feats[0].len(), targets.clone())
        .with_seed(a.seed)
        .with_hidden(
            a.hidden
                .iter()
                .map(|&w| (w, tactile_cae::head::Activation::Relu))
                .collect(),
        );
    let reg = Regressor::train(cfg, (&tx, &ty), (&vx, &vy), &dev)?;
    reg.save(&out)?;
    let err = reg.evaluate(&sx, &sy, &dev)?;
    println!("test mean absolute error ({} frames):", sx.len());
    for (t, e) in targets.iter().zip(&err) {
        println!("  {:<14} {e:.4}", t.name);
    }
    println!("regressor saved in {}", out.display());
    Ok(())
}

#[derive(Args)]
pub struct PerceiveArgs {
    /// Trained encoder folder.
    #[arg(long)]
    encoder: PathBuf,
    /// Estimator folders: classifier heads (head.json) and regressors
    /// (regressor.json), all run on the same feature vector (default:
    /// every such folder inside ENCODER).
    #[arg(long, num_args = 1..)]
    heads: Vec<PathBuf>,
    /// Dataset of frames to perceive.
    #[arg(long)]
    data: PathBuf,
    /// Also write every estimate to this CSV.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Frames to print (all go to --out).
    #[arg(long, default_value_t = 10)]
    show: usize,
    #[arg(long, default_value = "flex", value_parser = parse_device)]
    device: DeviceKind,
}

/// Paper A's simultaneous deployment: one encoding per frame, every
/// estimator on the same features.
pub fn perceive(a: PerceiveArgs) -> Result<()> {
    let dev = a.device.device();
    let estimators = load_estimators(&a.encoder, &a.heads, &dev)?;
    let ds = Dataset::open(&a.data)?;
    let t0 = std::time::Instant::now();
    let feats = encode_dataset(&a.encoder, &ds, a.device)?;
    let t_enc = t0.elapsed().as_secs_f64();
    let mut header = vec!["file".to_string()];
    let mut columns: Vec<Vec<String>> = Vec::new();
    let t1 = std::time::Instant::now();
    for e in &estimators {
        match e {
            Estimator::Classifier(h) => {
                header.push("shape".into());
                let p = h.predict(&feats, &dev)?;
                columns.push(p.iter().map(|&c| h.config.classes[c].clone()).collect());
            }
            Estimator::Regressor(r) => {
                let p = r.predict(&feats, &dev)?;
                for (j, t) in r.config.targets.iter().enumerate() {
                    header.push(t.name.clone());
                    columns.push(p.iter().map(|row| format!("{:.4}", row[j])).collect());
                }
            }
        }
    }
    let t_est = t1.elapsed().as_secs_f64();
    let rows: Vec<Vec<String>> = (0..ds.len())
        .map(|i| {
            let mut r = vec![ds.text(i, "file").unwrap_or("?").to_string()];
            r.extend(columns.iter().map(|c| c[i].clone()));
            r
        })
        .collect();
    println!("{}", header.join("\t"));
    for r in rows.iter().take(a.show) {
        println!("{}", r.join("\t"));
    }
    println!(
        "{} frames: encoding {:.3} ms/frame (preprocessing included), {} estimators {:.4} ms/frame",
        ds.len(),
        1e3 * t_enc / ds.len().max(1) as f64,
        estimators.len(),
        1e3 * t_est / ds.len().max(1) as f64
    );
    if let Some(out) = &a.out {
        tactile_core::io::write_atomic_with(out, |w| {
            let mut csv = csv::Writer::from_writer(w);
            csv.write_record(&header)?;
            for r in &rows {
                csv.write_record(r)?;
            }
            csv.flush()
        })?;
        println!("estimates written to {}", out.display());
    }
    Ok(())
}

#[derive(Args)]
pub struct CompareArgs {
    /// Trained encoder (its preprocessing also makes the pixel baselines).
    #[arg(long)]
    encoder: PathBuf,
    /// Dataset with the target labels.
    #[arg(long)]
    data: PathBuf,
    /// Regression targets, e.g. x_mm,theta_deg:180,depth_mm.
    #[arg(long, value_delimiter = ',', required_unless_present = "classify")]
    targets: Vec<String>,
    /// A class column to classify too (e.g. shape).
    #[arg(long)]
    classify: Option<String>,
    #[arg(long, default_value_t = 0.2)]
    test_fraction: f64,
    #[arg(long, default_value_t = 0.2)]
    val_fraction: f64,
    #[arg(long, default_value_t = 7)]
    seed: u64,
    /// Also write the table to this Markdown file.
    #[arg(long)]
    out: Option<PathBuf>,
    #[arg(long, default_value = "flex", value_parser = parse_device)]
    device: DeviceKind,
    /// Preprocess with this preset or JSON file instead of the encoder's
    /// own (an encoder trained on one dataset applied to another).
    #[arg(long)]
    preprocess: Option<String>,
    /// Hidden widths of the regression MLP (the same for every feature set).
    #[arg(long, value_delimiter = ',', default_values_t = [256, 128])]
    hidden: Vec<usize>,
}

/// Feature sets x estimators on one split: CAE features against PCA of
/// the pin image, the raw pin image and pin tracking, each with the MLP,
/// ridge and k-NN.
pub fn compare(a: CompareArgs) -> Result<()> {
    use tactile_estimate::classical;
    let ds = Dataset::open(&a.data)?;
    let targets: Vec<Target> = a
        .targets
        .iter()
        .map(|t| Target::parse(t))
        .collect::<Result<_, _>>()?;
    let labels = (0..ds.len())
        .map(|i| {
            targets
                .iter()
                .map(|t| ds.number(i, &t.name))
                .collect::<Result<Vec<f64>, _>>()
        })
        .collect::<Result<Vec<_>, _>>()?;
    let dev = a.device.device();
    let (mut art, cae) = tactile_cae::CaeArtifact::load(&a.encoder, &dev)?;
    if let Some(p) = &a.preprocess {
        art.preprocess = tactile_preprocess::PreprocessConfig::preset(p)?;
    }
    eprintln!("preprocessing {} frames", ds.len());
    let pins = tactile_cae::data::PinSet::from_dataset(&ds, &art.preprocess)?;
    let cae_feats = tactile_cae::encode::encode_all(&cae.encoder, &pins, 256, &dev)?;
    let raw: Vec<Vec<f32>> = pins.images.iter().map(|p| p.pixels.clone()).collect();
    let (train, val, test) = three_way_split(&ds, a.test_fraction, a.val_fraction, a.seed)?;
    let pick_x = |f: &[Vec<f32>], idx: &[usize]| -> Vec<Vec<f32>> {
        idx.iter().map(|&i| f[i].clone()).collect()
    };
    let pick_y =
        |idx: &[usize]| -> Vec<Vec<f64>> { idx.iter().map(|&i| labels[i].clone()).collect() };
    let (ty, vy, sy) = (pick_y(&train), pick_y(&val), pick_y(&test));
    let mut sets: Vec<(String, [Vec<Vec<f32>>; 3])> = vec![(
        format!("CAE-{}", art.cae.feature_count()),
        [
            pick_x(&cae_feats, &train),
            pick_x(&cae_feats, &val),
            pick_x(&cae_feats, &test),
        ],
    )];
    let (rtr, rva, rte) = (
        pick_x(&raw, &train),
        pick_x(&raw, &val),
        pick_x(&raw, &test),
    );
    for k in [16, 64] {
        let p = classical::pca(&rtr, &[&rtr, &rva, &rte], k)?;
        let [p0, p1, p2]: [Vec<Vec<f32>>; 3] =
            p.try_into().map_err(|_| anyhow::anyhow!("PCA output"))?;
        sets.push((format!("PCA-{k}"), [p0, p1, p2]));
    }
    sets.push((
        format!("raw {0}x{0}", art.preprocess.output_px),
        [rtr, rva, rte],
    ));
    // Pin tracking: blob centroids at full resolution, matched to the pins
    // of the first training frame; displacements as features.
    eprintln!("tracking pins");
    let centroids = {
        use rayon::prelude::*;
        (0..ds.len())
            .into_par_iter()
            .map(|i| -> Result<Vec<(f32, f32)>> {
                let path = ds.path_of(i, "file")?;
                let frame = tactile_core::image_io::load_grey(&path)?;
                let binary =
                    tactile_preprocess::pins::full_resolution_binary(&frame, &art.preprocess)
                        .with_context(|| path.display().to_string())?;
                Ok(tactile_preprocess::pins::pin_centroids(&binary, 4)?)
            })
            .collect::<Result<Vec<_>>>()?
    };
    let tracker = tactile_preprocess::pins::PinTracker::new(centroids[train[0]].clone())?;
    let tracked: Vec<Vec<f32>> = centroids.iter().map(|c| tracker.displacements(c)).collect();
    sets.push((
        format!("pin tracking ({} pins)", tracker.reference.len()),
        [
            pick_x(&tracked, &train),
            pick_x(&tracked, &val),
            pick_x(&tracked, &test),
        ],
    ));
    let mut md = format!(
        "Machine: {}\n\nDataset {} ({} train, {} validation, {} test frames, seed {}). Encoder {} (trained on {}); preprocessing: {}.\n\n",
        tactile_core::bench::Machine::detect().describe(),
        a.data.display(),
        train.len(),
        val.len(),
        test.len(),
        a.seed,
        a.encoder.display(),
        art.notes
            .get("trained_on")
            .and_then(|v| v.as_str())
            .unwrap_or("unknown data"),
        a.preprocess.as_deref().unwrap_or("the encoder's own"),
    );
    if !targets.is_empty() {
        md.push_str(&regression_table(
            &sets,
            &targets,
            (&ty, &vy, &sy),
            (&a.hidden, a.seed),
            &dev,
        )?);
    }
    if let Some(col) = &a.classify {
        let names: Vec<String> = (0..ds.len())
            .map(|i| ds.text(i, col).map(str::to_string))
            .collect::<Result<_, _>>()?;
        let mut classes = names.clone();
        classes.sort();
        classes.dedup();
        let y: Vec<usize> = names
            .iter()
            .map(|n| classes.iter().position(|c| c == n).unwrap_or(0))
            .collect();
        let pick = |idx: &[usize]| -> Vec<usize> { idx.iter().map(|&i| y[i]).collect() };
        md.push_str(&classification_table(
            &sets,
            &classes,
            (&pick(&train), &pick(&val), &pick(&test)),
            a.seed,
            &dev,
        )?);
    }
    print!("{md}");
    if let Some(out) = &a.out {
        tactile_core::io::write_atomic(out, md.as_bytes())?;
    }
    Ok(())
}

/// One feature set: name and (train, validation, test) vectors.
type FeatureSet = (String, [Vec<Vec<f32>>; 3]);
/// Labels of the (train, validation, test) frames.
type SplitLabels<'a, T> = (&'a [T], &'a [T], &'a [T]);

fn regression_table(
    sets: &[FeatureSet],
    targets: &[Target],
    (ty, vy, sy): SplitLabels<'_, Vec<f64>>,
    (hidden, seed): (&[usize], u64),
    dev: &burn::tensor::Device,
) -> Result<String> {
    let mlp = format!(
        "MLP {}",
        hidden
            .iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join("-")
    );
    use tactile_estimate::classical;
    let mut md = format!(
        "Regression: mean absolute error on the test frames (angles the short way round).\n\n| features | estimator | {} | fit + predict (s) |\n|---|---|{}---|\n",
        targets
            .iter()
            .map(|t| t.name.as_str())
            .collect::<Vec<_>>()
            .join(" | "),
        "---|".repeat(targets.len())
    );
    for (name, [tx, vx, sx]) in sets {
        for est in [mlp.as_str(), "ridge", "k-NN (k=5)"] {
            eprintln!("{name} + {est}");
            let t0 = std::time::Instant::now();
            let pred = match est {
                "ridge" => classical::ridge(targets, (tx, ty), sx, 1e-3)?,
                "k-NN (k=5)" => {
                    // k-NN uses the training and validation frames (no early stopping).
                    let x: Vec<Vec<f32>> = tx.iter().chain(vx).cloned().collect();
                    let y: Vec<Vec<f64>> = ty.iter().chain(vy).cloned().collect();
                    classical::knn(targets, (&x, &y), sx, 5)?
                }
                _ => {
                    let cfg = RegressorConfig::new(tx[0].len(), targets.to_vec())
                        .with_seed(seed)
                        .with_hidden(
                            hidden
                                .iter()
                                .map(|&w| (w, tactile_cae::head::Activation::Relu))
                                .collect(),
                        );
                    Regressor::train(cfg, (tx, ty), (vx, vy), dev)?.predict(sx, dev)?
                }
            };
            let secs = t0.elapsed().as_secs_f64();
            let errs: Vec<String> = targets
                .iter()
                .enumerate()
                .map(|(j, t)| {
                    let p: Vec<f64> = pred.iter().map(|r| r[j]).collect();
                    let tr: Vec<f64> = sy.iter().map(|r| r[j]).collect();
                    format!("{:.3}", t.mae(&p, &tr))
                })
                .collect();
            md.push_str(&format!(
                "| {name} | {est} | {} | {secs:.1} |\n",
                errs.join(" | ")
            ));
        }
    }
    md.push('\n');
    Ok(md)
}

fn classification_table(
    sets: &[FeatureSet],
    classes: &[String],
    (ty, vy, sy): SplitLabels<'_, usize>,
    seed: u64,
    dev: &burn::tensor::Device,
) -> Result<String> {
    use tactile_estimate::classical;
    let mut md = format!(
        "Classification of {} classes ({}): accuracy on the test frames.\n\n| features | estimator | accuracy | fit + predict (s) |\n|---|---|---|---|\n",
        classes.len(),
        classes.join(", ")
    );
    for (name, [tx, vx, sx]) in sets {
        // Classifiers fit on train + validation (the MLP makes its own folds).
        let x: Vec<Vec<f32>> = tx.iter().chain(vx).cloned().collect();
        let y: Vec<usize> = ty.iter().chain(vy).copied().collect();
        for est in [
            "MLP 16-64-32 (10-fold)",
            "Gaussian naive Bayes",
            "k-NN (k=5)",
        ] {
            eprintln!("{name} + {est}");
            let t0 = std::time::Instant::now();
            let pred = match est {
                "Gaussian naive Bayes" => classical::gaussian_nb(&x, &y, sx)?,
                "k-NN (k=5)" => classical::knn_classify(&x, &y, sx, 5)?,
                _ => {
                    let cfg = tactile_cae::head::HeadConfig::new(x[0].len(), classes.to_vec())
                        .with_seed(seed)
                        .with_repeats(1);
                    tactile_cae::head::ClassifierHead::train(cfg, &x, &y, dev)?.predict(sx, dev)?
                }
            };
            let secs = t0.elapsed().as_secs_f64();
            let acc = tactile_core::metrics::accuracy(&pred, sy);
            md.push_str(&format!(
                "| {name} | {est} | {:.1} % | {secs:.1} |\n",
                100.0 * acc
            ));
        }
    }
    md.push('\n');
    Ok(md)
}
