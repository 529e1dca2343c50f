//! Feature sets against estimators on one split: the CAE's features beside
//! PCA of the pin image, the raw pin image and pin tracking, each with an
//! MLP, ridge and k-NN (regression) or an MLP head, Gaussian naive Bayes and
//! k-NN (classification).

use std::path::{Path, PathBuf};

use serde::Serialize;

use burn::tensor::Device;
use rayon::prelude::*;
use tactile_burn::{Artifact, DeviceKind, Runtime};
use tactile_cae::data::PinSet;
use tactile_cae::{CaeArtifact, TactipEncoder};
use tactile_core::dataset::{Dataset, Provenance};
use tactile_estimate::classical;
use tactile_estimate::regressor::target_mae;
use tactile_estimate::{
    Activation, ClassifierHead, HeadConfig, Regressor, RegressorConfig, Target,
};
use tactile_pipeline::tactip::{classes_of, encoder_trained_on, holdout_cure};
use tactile_preprocess::NamedPreprocess;

pub use tactile_pipeline::options::CompareOptions;

use crate::{Error, Result};

/// What is compared (`tactile compare`'s flags; Python's
/// `tactile.study.compare(encoder, data, **options)`).
#[derive(Debug, Clone, clap::Args)]
pub struct Compare {
    /// Trained encoder (its preprocessing also makes the pixel baselines).
    #[arg(long)]
    pub encoder: PathBuf,
    /// Dataset with the target labels.
    #[arg(long)]
    pub data: PathBuf,
    /// The targets, the split and the estimators.
    #[command(flatten)]
    pub options: CompareOptions,
}

/// One estimator on one feature set: its test errors or accuracy.
#[derive(Debug, Clone, Serialize)]
pub struct CompareRow {
    /// The feature set (`CAE-32`, `PCA-16`, `raw 56x56`, `pin tracking (314 pins)`).
    pub features: String,
    /// The estimator.
    pub estimator: String,
    /// Regression: each target's mean absolute error on the test frames,
    /// in its label's units; classification: `accuracy` (0 to 1).
    pub values: Vec<(String, f64)>,
    /// Seconds to fit and predict.
    pub seconds: f64,
}

/// The comparison: its page and its rows.
#[derive(Debug, Clone, Serialize)]
pub struct CompareResult {
    /// The page (Markdown).
    pub markdown: String,
    /// Every regression row, in the table's order.
    pub regression: Vec<CompareRow>,
    /// Every classification row, in the table's order.
    pub classification: Vec<CompareRow>,
    /// What the page says under its title: the encoder fitted test frames,
    /// a feature set or estimator left out for a split too small.
    pub warnings: Vec<String>,
}

impl CompareResult {
    /// Its rows and warnings without the page, as JSON: what is written
    /// beside the page and what Python returns beside `markdown`.
    pub fn rows(&self) -> serde_json::Value {
        serde_json::json!({
            "regression": self.regression,
            "classification": self.classification,
            "warnings": self.warnings,
        })
    }

    /// Write the page to `out` and its rows beside it (`NAME.json`).
    pub fn write(&self, out: &Path) -> Result<()> {
        crate::output::write_markdown_and_json(out, &self.markdown, &self.rows())
    }
}

/// What to tell a reader when the encoder fitted some of the `test` rows
/// ([`encoder_trained_on`]): its CAE row then scores features of frames it
/// was trained on, beside rows (PCA, raw pixels, pin tracking) fitted on
/// the training frames only.
fn encoder_saw_test(c: &Compare, ds: &Dataset, test: &[usize]) -> Option<String> {
    let saw = encoder_trained_on(&c.encoder, ds, test)?;
    Some(format!(
        "The encoder {saw}, so its row scores frames its features fitted, unlike the other rows: for a held-out comparison train it {}, or on another recording.",
        holdout_cure(ds, c.options.test_fraction, c.options.seed)
    ))
}

/// The comparison: its page, its rows and its warnings. Targets, the
/// preprocessing and the MLP's widths are checked before any frame is read.
pub fn compare(c: &Compare) -> Result<CompareResult> {
    let o = &c.options;
    if o.targets.is_empty() && o.classify.is_none() {
        return Err(tactile_core::Error::Config(
            "compare: give regression targets (--targets, targets=), a class column (--classify, classify=), or both".into(),
        )
        .into());
    }
    let targets = o
        .targets
        .iter()
        .map(|t| t.parse::<Target>())
        .collect::<std::result::Result<Vec<_>, _>>()?;
    // The MLP's layers are checked before any frame is read (the features'
    // count, its inputs, is known only once they are made).
    let hidden: Vec<(usize, Activation)> =
        o.hidden.iter().map(|&w| (w, Activation::Relu)).collect();
    tactile_estimate::mlp::check_sizes(1, &hidden, targets.len().max(1))?;
    let preprocess = o
        .preprocess
        .as_deref()
        .map(str::parse::<NamedPreprocess>)
        .transpose()?;
    let ds = Dataset::open(&c.data)?;
    let labels = (0..ds.len())
        .map(|i| {
            targets
                .iter()
                .map(|t| ds.target(i, &t.name))
                .collect::<tactile_core::Result<Vec<f64>>>()
        })
        .collect::<tactile_core::Result<Vec<_>>>()?;
    // Split first: a split the dataset cannot give fails before any frame
    // is read.
    let split = ds.three_way_split(o.test_fraction, o.val_fraction, o.seed)?;
    let (train, val, test) = (&split.train, &split.val, &split.test);
    let dev = DeviceKind::Flex.device();
    let mut art = CaeArtifact::read(&c.encoder)?;
    if let Some(p) = &preprocess {
        art.preprocess = p.config.clone();
    }
    let (_, net) = tactile_onnx::load_network::<CaeArtifact>(&c.encoder, Runtime::BurnFlex, 0)?;
    let mut encoder = TactipEncoder::from_network(art.clone(), net);
    tactile_core::note!("preprocessing {} frames", ds.len());
    let pins = PinSet::from_dataset(&ds, &art.preprocess)?;
    let cae_feats = encoder.encode(&pins.images)?;
    let raw: Vec<Vec<f32>> = pins.images.iter().map(|p| p.pixels.clone()).collect();
    let pick_x = |f: &[Vec<f32>], idx: &[usize]| -> Vec<Vec<f32>> {
        idx.iter().map(|&i| f[i].clone()).collect()
    };
    let pick_y =
        |idx: &[usize]| -> Vec<Vec<f64>> { idx.iter().map(|&i| labels[i].clone()).collect() };
    let (ty, vy, sy) = (pick_y(train), pick_y(val), pick_y(test));
    let mut sets: Vec<FeatureSet> = vec![(
        format!("CAE-{}", art.model.feature_count()),
        [
            pick_x(&cae_feats, train),
            pick_x(&cae_feats, val),
            pick_x(&cae_feats, test),
        ],
    )];
    let (rtr, rva, rte) = (pick_x(&raw, train), pick_x(&raw, val), pick_x(&raw, test));
    // A split too small for a PCA's components leaves its row out, said
    // under the table, rather than failing the comparison.
    let mut left_out = Vec::new();
    for k in [16, 64] {
        let pca = classical::pca(&rtr, &[&rtr, &rva, &rte], k).map_err(Error::from);
        let Some(p) = fitted(&format!("PCA-{k}"), pca, &mut left_out)? else {
            continue;
        };
        let mut p = p.into_iter();
        let (Some(p0), Some(p1), Some(p2)) = (p.next(), p.next(), p.next()) else {
            continue;
        };
        sets.push((format!("PCA-{k}"), [p0, p1, p2]));
    }
    sets.push((
        format!("raw {0}x{0}", art.preprocess.output_px),
        [rtr, rva, rte],
    ));
    // Pin tracking: blob centroids at full resolution, matched to the pins
    // of the first training frame; displacements as features.
    tactile_core::note!("tracking pins");
    let centroids = (0..ds.len())
        .into_par_iter()
        .map(|i| -> Result<Vec<(f32, f32)>> {
            let path = ds.path_of(i, "file")?;
            let frame = ds.load_grey(i, "file")?;
            let binary = tactile_preprocess::pins::full_resolution_binary(&frame, &art.preprocess)
                .map_err(|e| e.in_file(&path))?;
            Ok(tactile_preprocess::pins::pin_centroids(&binary, 4)?)
        })
        .collect::<Result<Vec<_>>>()?;
    let tracker = tactile_preprocess::pins::PinTracker::new(centroids[train[0]].clone())?;
    let tracked: Vec<Vec<f32>> = centroids.iter().map(|c| tracker.displacements(c)).collect();
    sets.push((
        format!("pin tracking ({} pins)", tracker.reference.len()),
        [
            pick_x(&tracked, train),
            pick_x(&tracked, val),
            pick_x(&tracked, test),
        ],
    ));
    let mut md = format!(
        "Machine: {}\n\nDataset {} ({} train, {} validation, {} test frames, seed {}). Encoder {} (trained on {}); preprocessing: {}.\n\n",
        tactile_core::bench::Machine::detect().describe(),
        c.data.display(),
        train.len(),
        val.len(),
        test.len(),
        o.seed,
        c.encoder.display(),
        match Provenance::read(&art.notes).names() {
            d if d.is_empty() => "unknown data".to_string(),
            d => d,
        },
        preprocess
            .as_ref()
            .map_or("the encoder's own", |p| p.name.as_str()),
    );
    let mut warnings = Vec::new();
    if let Some(w) = encoder_saw_test(c, &ds, test) {
        tactile_core::note!("warning: {w}");
        md.push_str(&format!("**{w}**\n\n"));
        warnings.push(w);
    }
    md.push_str(&left_out_notes(&left_out));
    let mut regression = Vec::new();
    if !targets.is_empty() {
        md.push_str(&regression_table(
            &sets,
            &targets,
            (&ty, &vy, &sy),
            (&o.hidden, o.seed),
            &dev,
            (&mut regression, &mut left_out),
        )?);
    }
    let mut classification = Vec::new();
    if let Some(col) = &o.classify {
        let (classes, y) = classes_of(&ds, col)?;
        let pick = |idx: &[usize]| -> Vec<usize> { idx.iter().map(|&i| y[i]).collect() };
        // The frame of each train and validation row, for the MLP's folds.
        let frames = ds.frame_of_rows(&[train.as_slice(), val.as_slice()].concat());
        md.push_str(&classification_table(
            &sets,
            &classes,
            (&pick(train), &pick(val), &pick(test)),
            &frames,
            o.seed,
            &dev,
            (&mut classification, &mut left_out),
        )?);
    }
    warnings.extend(left_out);
    Ok(CompareResult {
        markdown: md,
        regression,
        classification,
        warnings,
    })
}

/// `fit`'s result, or `None` when its split has too few frames for it:
/// why `what` is left out is noted in `left_out` (and on standard error),
/// so a small dataset gets every row that can be fitted rather than an
/// error after the rest were.
fn fitted<T>(what: &str, fit: Result<T>, left_out: &mut Vec<String>) -> Result<Option<T>> {
    match fit {
        Ok(v) => Ok(Some(v)),
        Err(Error::Pipeline(tactile_pipeline::Error::Estimate(
            tactile_estimate::Error::TooFewSamples(why),
        ))) => {
            let note = format!("{what} is left out: {why}.");
            tactile_core::note!("warning: {note}");
            left_out.push(note);
            Ok(None)
        }
        Err(e) => Err(e),
    }
}

/// The notes of [`fitted`] as paragraphs.
fn left_out_notes(left_out: &[String]) -> String {
    left_out.iter().map(|n| format!("{n}\n\n")).collect()
}

/// One feature set: name and (train, validation, test) vectors.
type FeatureSet = (String, [Vec<Vec<f32>>; 3]);
/// Labels of the (train, validation, test) frames.
type SplitLabels<'a, T> = (&'a [T], &'a [T], &'a [T]);

/// The MLP regressor (ReLU layers of `hidden`) fitted on the training
/// features, stopped early on the validation ones: its predictions of the
/// test features. Compare's and the shared-encoder bench's estimator.
pub(crate) fn mlp_regression(
    targets: &[Target],
    [tx, vx, sx]: [&[Vec<f32>]; 3],
    (ty, vy): (&[Vec<f64>], &[Vec<f64>]),
    (hidden, seed): (&[usize], u64),
    dev: &Device,
) -> Result<Vec<Vec<f64>>> {
    let mut cfg = RegressorConfig::new(tx[0].len(), targets.to_vec())
        .with_hidden(hidden.iter().map(|&w| (w, Activation::Relu)).collect());
    cfg.schedule.seed = seed;
    Ok(Regressor::train(cfg, (tx, ty), (vx, vy), dev)?.predict(sx)?)
}

/// The MLP classifier head (paper A's 16-64-32, one fold) fitted on `x`
/// (`frames[i]` names row `i`'s frame, so a frame's rows share a fold):
/// its classes of the test features.
pub(crate) fn mlp_classification(
    classes: &[String],
    (x, y, frames): (&[Vec<f32>], &[usize], &[usize]),
    sx: &[Vec<f32>],
    seed: u64,
    dev: &Device,
) -> Result<Vec<usize>> {
    let mut cfg = HeadConfig::new(x[0].len(), classes.to_vec()).with_repeats(1);
    cfg.schedule.seed = seed;
    Ok(ClassifierHead::train_by_frame(cfg, x, y, frames, dev)?.predict(sx)?)
}

fn regression_table(
    sets: &[FeatureSet],
    targets: &[Target],
    (ty, vy, sy): SplitLabels<'_, Vec<f64>>,
    (hidden, seed): (&[usize], u64),
    dev: &Device,
    (rows, notes): (&mut Vec<CompareRow>, &mut Vec<String>),
) -> Result<String> {
    let mlp = format!(
        "MLP {}",
        hidden
            .iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join("-")
    );
    let mut md = format!(
        "Regression: mean absolute error on the test frames (angles the short way round).\n\n| features | estimator | {} | fit + predict (s) |\n|---|---|{}---|\n",
        targets
            .iter()
            .map(|t| t.name.as_str())
            .collect::<Vec<_>>()
            .join(" | "),
        "---|".repeat(targets.len())
    );
    let mut left_out = Vec::new();
    for (name, [tx, vx, sx]) in sets {
        for est in [mlp.as_str(), "ridge", "k-NN (k=5)"] {
            // A classical fit (ridge on raw pixels) can take an hour and
            // cannot be stopped inside: Ctrl-C stops between two.
            tactile_core::interrupt::check()?;
            tactile_core::note!("{name} + {est}");
            let t0 = std::time::Instant::now();
            let pred = match est {
                "ridge" => classical::ridge(targets, (tx, ty), sx, 1e-3).map_err(Error::from),
                "k-NN (k=5)" => {
                    // k-NN uses the training and validation frames (no early stopping).
                    let x: Vec<Vec<f32>> = tx.iter().chain(vx).cloned().collect();
                    let y: Vec<Vec<f64>> = ty.iter().chain(vy).cloned().collect();
                    classical::knn(targets, (&x, &y), sx, 5).map_err(Error::from)
                }
                _ => mlp_regression(targets, [tx, vx, sx], (ty, vy), (hidden, seed), dev),
            };
            let Some(pred) = fitted(&format!("{name} + {est}"), pred, &mut left_out)? else {
                continue;
            };
            let secs = t0.elapsed().as_secs_f64();
            let maes = target_mae(targets, &pred, sy);
            let errs: Vec<String> = maes.iter().map(|e| format!("{e:.3}")).collect();
            md.push_str(&format!(
                "| {name} | {est} | {} | {secs:.1} |\n",
                errs.join(" | ")
            ));
            rows.push(CompareRow {
                features: name.clone(),
                estimator: est.to_string(),
                values: targets.iter().map(|t| t.name.clone()).zip(maes).collect(),
                seconds: secs,
            });
        }
    }
    md.push('\n');
    md.push_str(&left_out_notes(&left_out));
    notes.extend(left_out);
    Ok(md)
}

fn classification_table(
    sets: &[FeatureSet],
    classes: &[String],
    (ty, vy, sy): SplitLabels<'_, usize>,
    frames: &[usize],
    seed: u64,
    dev: &Device,
    (rows, notes): (&mut Vec<CompareRow>, &mut Vec<String>),
) -> Result<String> {
    let mut md = format!(
        "Classification of {} classes ({}): accuracy on the test frames.\n\n| features | estimator | accuracy | fit + predict (s) |\n|---|---|---|---|\n",
        classes.len(),
        classes.join(", ")
    );
    let mut left_out = Vec::new();
    for (name, [tx, vx, sx]) in sets {
        // Classifiers fit on train + validation (the MLP makes its own folds).
        let x: Vec<Vec<f32>> = tx.iter().chain(vx).cloned().collect();
        let y: Vec<usize> = ty.iter().chain(vy).copied().collect();
        for est in [
            "MLP 16-64-32 (10-fold)",
            "Gaussian naive Bayes",
            "k-NN (k=5)",
        ] {
            // A classical fit (ridge on raw pixels) can take an hour and
            // cannot be stopped inside: Ctrl-C stops between two.
            tactile_core::interrupt::check()?;
            tactile_core::note!("{name} + {est}");
            let t0 = std::time::Instant::now();
            let pred = match est {
                "Gaussian naive Bayes" => classical::gaussian_nb(&x, &y, sx).map_err(Error::from),
                "k-NN (k=5)" => classical::knn_classify(&x, &y, sx, 5).map_err(Error::from),
                _ => mlp_classification(classes, (&x, &y, frames), sx, seed, dev),
            };
            let Some(pred) = fitted(&format!("{name} + {est}"), pred, &mut left_out)? else {
                continue;
            };
            let secs = t0.elapsed().as_secs_f64();
            let acc = tactile_core::metrics::accuracy(&pred, sy);
            md.push_str(&format!(
                "| {name} | {est} | {:.1} % | {secs:.1} |\n",
                100.0 * acc
            ));
            rows.push(CompareRow {
                features: name.clone(),
                estimator: est.to_string(),
                values: vec![("accuracy".to_string(), acc)],
                seconds: secs,
            });
        }
    }
    md.push('\n');
    md.push_str(&left_out_notes(&left_out));
    notes.extend(left_out);
    Ok(md)
}
