//! `tactile evaluate` and `tactile robustness`: every estimator of an
//! encoder scored on a labelled dataset, per class and per shape, and the
//! same scores again on frames with perturbed camera conditions (paper A,
//! section V).

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use clap::Args;
use datasets_synth::rng::SampleRng;
use tactile_cae::CaeArtifact;
use tactile_cae::data::PinSet;
use tactile_cae::encode::encode_all;
use tactile_cae::head::ClassifierHead;
use tactile_core::DeviceKind;
use tactile_core::dataset::Dataset;
use tactile_core::image_io::GreyImage;
use tactile_core::plot::{Series, line_plot};
use tactile_estimate::Regressor;

use crate::parse_device;

/// A trained estimator on the encoder's features.
pub enum Estimator {
    Classifier(ClassifierHead),
    Regressor(Regressor),
}

/// The estimators in `heads`, or every estimator folder inside ENCODER.
pub fn load_estimators(
    encoder: &Path,
    heads: &[PathBuf],
    dev: &burn::tensor::Device,
) -> Result<Vec<Estimator>> {
    let mut dirs = heads.to_vec();
    if dirs.is_empty() {
        // Every sub-folder holding an estimator, in name order.
        if let Ok(entries) = std::fs::read_dir(encoder) {
            dirs = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|d| d.join("head.json").is_file() || d.join("regressor.json").is_file())
                .collect();
            dirs.sort();
        }
    }
    if dirs.is_empty() {
        bail!("no estimators: give --heads DIR... (folders with head.json or regressor.json)");
    }
    dirs.iter()
        .map(|d| {
            if d.join("head.json").is_file() {
                Ok(Estimator::Classifier(ClassifierHead::load(d, dev)?))
            } else if d.join("regressor.json").is_file() {
                Ok(Estimator::Regressor(Regressor::load(d, dev)?))
            } else {
                bail!(
                    "{}: neither head.json nor regressor.json found",
                    d.display()
                )
            }
        })
        .collect()
}

/// A number of frames and a score over them.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Group {
    pub name: String,
    pub frames: usize,
    pub value: f64,
}

/// One regression target's mean absolute error, overall and per shape.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TargetScore {
    pub target: String,
    pub mae: f64,
    pub frames: usize,
    pub per_shape: Vec<Group>,
}

/// Every estimator's score on one set of frames.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Scores {
    pub frames: usize,
    /// Shape accuracy and per-class accuracy, when there is a classifier.
    pub accuracy: Option<f64>,
    pub per_class: Vec<Group>,
    /// `confusion[truth][predicted]` over the classifier's classes.
    pub confusion: Vec<Vec<usize>>,
    pub classes: Vec<String>,
    pub targets: Vec<TargetScore>,
}

/// Score every estimator on `feats`, row `i` labelled by row `i` of `ds`.
/// Frames whose label of a target is empty (theta of a sphere) are left
/// out of that target; a shape the classifier does not know counts as wrong.
pub fn score(
    estimators: &[Estimator],
    feats: &[Vec<f32>],
    ds: &Dataset,
    dev: &burn::tensor::Device,
) -> Result<Scores> {
    let shapes: Vec<Option<&str>> = (0..ds.len()).map(|i| ds.text_opt(i, "shape")).collect();
    let mut kinds: Vec<&str> = shapes.iter().flatten().copied().collect();
    kinds.sort_unstable();
    kinds.dedup();
    let mut out = Scores {
        frames: feats.len(),
        accuracy: None,
        per_class: Vec::new(),
        confusion: Vec::new(),
        classes: Vec::new(),
        targets: Vec::new(),
    };
    for e in estimators {
        match e {
            Estimator::Classifier(h) => {
                let pred = h.predict(feats, dev)?;
                let classes = &h.config.classes;
                let truth: Vec<Option<usize>> = shapes
                    .iter()
                    .map(|s| s.and_then(|s| classes.iter().position(|c| c == s)))
                    .collect();
                let labelled: Vec<usize> =
                    (0..feats.len()).filter(|&i| shapes[i].is_some()).collect();
                if labelled.is_empty() {
                    bail!(
                        "{}: no `shape` labels to score the classifier on",
                        ds.labels_path().display()
                    );
                }
                let right =
                    |rows: &[usize]| rows.iter().filter(|&&i| truth[i] == Some(pred[i])).count();
                out.accuracy = Some(right(&labelled) as f64 / labelled.len() as f64);
                out.per_class = kinds
                    .iter()
                    .map(|k| {
                        let rows: Vec<usize> = labelled
                            .iter()
                            .copied()
                            .filter(|&i| shapes[i] == Some(k))
                            .collect();
                        Group {
                            name: k.to_string(),
                            frames: rows.len(),
                            value: right(&rows) as f64 / rows.len().max(1) as f64,
                        }
                    })
                    .collect();
                let mut confusion = vec![vec![0usize; classes.len()]; classes.len()];
                for &i in &labelled {
                    if let Some(t) = truth[i] {
                        confusion[t][pred[i]] += 1;
                    }
                }
                out.confusion = confusion;
                out.classes = classes.clone();
            }
            Estimator::Regressor(r) => {
                let pred = r.predict(feats, dev)?;
                for (j, t) in r.config.targets.iter().enumerate() {
                    let truth = (0..ds.len())
                        .map(|i| ds.number_opt(i, &t.name))
                        .collect::<Result<Vec<_>, _>>()?;
                    let mae_of = |rows: &mut dyn Iterator<Item = usize>| {
                        let (mut sum, mut n) = (0.0, 0usize);
                        for i in rows {
                            if let Some(v) = truth[i] {
                                sum += t.error(pred[i][j], v);
                                n += 1;
                            }
                        }
                        (if n > 0 { sum / n as f64 } else { f64::NAN }, n)
                    };
                    let (mae, frames) = mae_of(&mut (0..feats.len()));
                    if frames == 0 {
                        bail!(
                            "{}: column '{}' is empty on every frame",
                            ds.labels_path().display(),
                            t.name
                        );
                    }
                    let per_shape = kinds
                        .iter()
                        .filter_map(|k| {
                            let (value, frames) =
                                mae_of(&mut (0..feats.len()).filter(|&i| shapes[i] == Some(k)));
                            (frames > 0).then(|| Group {
                                name: k.to_string(),
                                frames,
                                value,
                            })
                        })
                        .collect();
                    out.targets.push(TargetScore {
                        target: t.name.clone(),
                        mae,
                        frames,
                        per_shape,
                    });
                }
            }
        }
    }
    Ok(out)
}

/// Markdown: accuracy per class with the confusion matrix, then the
/// targets' errors per shape.
pub fn scores_markdown(s: &Scores) -> String {
    let mut md = String::new();
    if let Some(acc) = s.accuracy {
        md.push_str(&format!(
            "Shape accuracy {:.1} % over {} frames (chance {:.1} %).\n\n| shape | frames | accuracy |\n|---|---|---|\n",
            100.0 * acc,
            s.frames,
            100.0 / s.classes.len().max(1) as f64
        ));
        for g in &s.per_class {
            md.push_str(&format!(
                "| {} | {} | {:.1} % |\n",
                g.name,
                g.frames,
                100.0 * g.value
            ));
        }
        md.push_str("\nConfusion (rows: true shape, columns: predicted):\n\n| | ");
        md.push_str(&s.classes.join(" | "));
        md.push_str(" |\n|---|");
        md.push_str(&"---|".repeat(s.classes.len()));
        md.push('\n');
        for (c, row) in s.classes.iter().zip(&s.confusion) {
            let cells: Vec<String> = row.iter().map(usize::to_string).collect();
            md.push_str(&format!("| {c} | {} |\n", cells.join(" | ")));
        }
        md.push('\n');
    }
    if !s.targets.is_empty() {
        let mut shapes: Vec<&str> = s
            .targets
            .iter()
            .flat_map(|t| t.per_shape.iter().map(|g| g.name.as_str()))
            .collect();
        shapes.sort_unstable();
        shapes.dedup();
        md.push_str("Mean absolute error per target (angles the short way round), overall and per shape:\n\n| shape |");
        for t in &s.targets {
            md.push_str(&format!(" {} |", t.target));
        }
        md.push_str("\n|---|");
        md.push_str(&"---|".repeat(s.targets.len()));
        md.push_str("\n| **all** |");
        for t in &s.targets {
            md.push_str(&format!(" **{:.3}** ({}) |", t.mae, t.frames));
        }
        md.push('\n');
        for k in shapes {
            md.push_str(&format!("| {k} |"));
            for t in &s.targets {
                match t.per_shape.iter().find(|g| g.name == k) {
                    Some(g) => md.push_str(&format!(" {:.3} |", g.value)),
                    None => md.push_str(" - |"),
                }
            }
            md.push('\n');
        }
        md.push('\n');
    }
    md
}

#[derive(Args)]
pub struct EvaluateArgs {
    /// Trained encoder folder.
    #[arg(long)]
    encoder: PathBuf,
    /// Estimator folders (default: every folder in ENCODER with head.json or regressor.json).
    #[arg(long, num_args = 1..)]
    heads: Vec<PathBuf>,
    /// Labelled dataset (e.g. held-out synthetic frames).
    #[arg(long)]
    data: PathBuf,
    /// Also write the tables to this Markdown file.
    #[arg(long)]
    out: Option<PathBuf>,
    #[arg(long, default_value = "flex", value_parser = parse_device)]
    device: DeviceKind,
}

/// Score every estimator on a dataset; the last line is the scores as JSON.
pub fn evaluate(a: EvaluateArgs) -> Result<()> {
    let dev = a.device.device();
    let estimators = load_estimators(&a.encoder, &a.heads, &dev)?;
    let ds = Dataset::open(&a.data)?;
    let feats = crate::cae_cmds::encode_dataset(&a.encoder, &ds, a.device)?;
    let s = score(&estimators, &feats, &ds, &dev)?;
    let md = format!(
        "Encoder {} on {} ({} frames).\n\n{}",
        a.encoder.display(),
        a.data.display(),
        ds.len(),
        scores_markdown(&s)
    );
    print!("{md}");
    if let Some(out) = &a.out {
        tactile_core::io::write_atomic(out, md.as_bytes())?;
    }
    println!("{}", serde_json::to_string(&s)?);
    Ok(())
}

/// A change of camera conditions applied to raw frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Perturbation {
    /// Extra Gaussian sensor noise, sigma in grey levels.
    Noise { sigma: f64 },
    /// A linear gain ramp `1 + slope * r` across the frame (r in [-1, 1]
    /// along a random direction) on top of the sensor's own.
    Gradient { slope: f64 },
    /// An external Gaussian light blob of this amplitude (grey levels),
    /// sigma 30 px, centred somewhere within 100 px of the middle.
    Blob { amplitude: f64 },
    /// The sensor turned about the camera axis.
    Rotation { deg: f64 },
}

impl Perturbation {
    /// The study: three strengths of each (the clean frames come first).
    pub fn study() -> Vec<(&'static str, Vec<Perturbation>)> {
        use Perturbation::*;
        vec![
            (
                "noise",
                [6.0, 12.0, 24.0].map(|sigma| Noise { sigma }).to_vec(),
            ),
            (
                "gradient",
                [0.3, 0.6, 0.9].map(|slope| Gradient { slope }).to_vec(),
            ),
            (
                "blob",
                [60.0, 120.0, 180.0]
                    .map(|amplitude| Blob { amplitude })
                    .to_vec(),
            ),
            (
                "rotation",
                [2.0, 5.0, 10.0].map(|deg| Rotation { deg }).to_vec(),
            ),
        ]
    }

    /// Human-readable strength.
    pub fn describe(&self) -> String {
        match *self {
            Self::Noise { sigma } => format!("noise sigma {sigma} grey levels"),
            Self::Gradient { slope } => format!("gain gradient +-{:.0} %", 100.0 * slope),
            Self::Blob { amplitude } => format!("light blob {amplitude} grey levels"),
            Self::Rotation { deg } => format!("rotated {deg} deg"),
        }
    }

    /// Apply to one frame; `rng` makes the random parts (noise, direction,
    /// position) reproducible per frame.
    pub fn apply(&self, img: &GreyImage, rng: &mut SampleRng) -> GreyImage {
        let (w, h) = (img.width(), img.height());
        let src = img.as_slice();
        let (cu, cv) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
        let half = cu.max(cv).max(1.0);
        let mut out = vec![0u8; w * h];
        match *self {
            Self::Noise { sigma } => {
                for (o, &s) in out.iter_mut().zip(src) {
                    *o = (s as f64 + sigma * rng.normal()).round().clamp(0.0, 255.0) as u8;
                }
            }
            Self::Gradient { slope } => {
                let a = 2.0 * std::f64::consts::PI * rng.uniform();
                let (du, dv) = (a.cos(), a.sin());
                for (k, o) in out.iter_mut().enumerate() {
                    let (u, v) = ((k % w) as f64 - cu, (k / w) as f64 - cv);
                    let r = (u * du + v * dv) / half;
                    *o = (src[k] as f64 * (1.0 + slope * r))
                        .round()
                        .clamp(0.0, 255.0) as u8;
                }
            }
            Self::Blob { amplitude } => {
                let (a, d) = (
                    2.0 * std::f64::consts::PI * rng.uniform(),
                    100.0 * rng.uniform().sqrt(),
                );
                let (bu, bv) = (cu + d * a.cos(), cv + d * a.sin());
                for (k, o) in out.iter_mut().enumerate() {
                    let (u, v) = ((k % w) as f64 - bu, (k / w) as f64 - bv);
                    let g = (-(u * u + v * v) / (2.0 * 30.0 * 30.0)).exp();
                    *o = (src[k] as f64 + amplitude * g).round().clamp(0.0, 255.0) as u8;
                }
            }
            Self::Rotation { deg } => {
                // Inverse mapping with bilinear interpolation; outside -> 0.
                let (s, c) = deg.to_radians().sin_cos();
                let at = |x: isize, y: isize| -> f64 {
                    if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
                        0.0
                    } else {
                        src[y as usize * w + x as usize] as f64
                    }
                };
                for (k, o) in out.iter_mut().enumerate() {
                    let (u, v) = ((k % w) as f64 - cu, (k / w) as f64 - cv);
                    let (x, y) = (c * u + s * v + cu, -s * u + c * v + cv);
                    let (x0, y0) = (x.floor(), y.floor());
                    let (fx, fy) = (x - x0, y - y0);
                    let (x0, y0) = (x0 as isize, y0 as isize);
                    let v = at(x0, y0) * (1.0 - fx) * (1.0 - fy)
                        + at(x0 + 1, y0) * fx * (1.0 - fy)
                        + at(x0, y0 + 1) * (1.0 - fx) * fy
                        + at(x0 + 1, y0 + 1) * fx * fy;
                    *o = v.round().clamp(0.0, 255.0) as u8;
                }
            }
        }
        tactile_core::image_io::grey_image(w, h, out).expect("same size as a valid image")
    }
}

#[derive(Args)]
pub struct RobustnessArgs {
    /// Trained encoder folder.
    #[arg(long)]
    encoder: PathBuf,
    /// Estimator folders (default: every folder in ENCODER with head.json or regressor.json).
    #[arg(long, num_args = 1..)]
    heads: Vec<PathBuf>,
    /// Labelled dataset of raw frames (held-out synthetic TacTip frames).
    #[arg(long)]
    data: PathBuf,
    /// Use at most this many frames (the first ones).
    #[arg(long)]
    limit: Option<usize>,
    /// Markdown table; plots go beside it.
    #[arg(long)]
    out: Option<PathBuf>,
    #[arg(long, default_value_t = 11)]
    seed: u64,
    #[arg(long, default_value = "flex", value_parser = parse_device)]
    device: DeviceKind,
}

/// Errors of every estimator on clean frames and on perturbed copies.
pub fn robustness(a: RobustnessArgs) -> Result<()> {
    use rayon::prelude::*;
    let dev = a.device.device();
    let estimators = load_estimators(&a.encoder, &a.heads, &dev)?;
    let (art, cae) = CaeArtifact::load(&a.encoder, &dev)?;
    let ds = Dataset::open(&a.data)?;
    let n = a.limit.unwrap_or(ds.len()).min(ds.len());
    let frames = (0..n)
        .into_par_iter()
        .map(|i| Ok(tactile_core::image_io::load_grey(ds.path_of(i, "file")?)?))
        .collect::<Result<Vec<GreyImage>>>()?;
    let run = |p: Option<Perturbation>, stream: u64| -> Result<Scores> {
        let images = frames
            .par_iter()
            .enumerate()
            .map(|(i, f)| {
                let img = match p {
                    Some(p) => p.apply(f, &mut SampleRng::new(a.seed, stream, i as u64)),
                    None => f.clone(),
                };
                tactile_preprocess::preprocess(&img, &art.preprocess).map_err(|e| {
                    anyhow::anyhow!(
                        "{}: {e}",
                        ds.path_of(i, "file").unwrap_or_default().display()
                    )
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let pins = PinSet {
            files: Vec::new(),
            images,
        };
        let feats = encode_all(&cae.encoder, &pins, 256, &dev)?;
        score(&estimators, &feats, &ds, &dev)
    };
    let clean = run(None, 0)?;
    let columns = |s: &Scores| -> Vec<(String, f64)> {
        let mut c = Vec::new();
        if let Some(acc) = s.accuracy {
            c.push(("shape accuracy".to_string(), 100.0 * acc));
        }
        c.extend(
            s.targets
                .iter()
                .map(|t| (format!("{} MAE", t.target), t.mae)),
        );
        c
    };
    let header = columns(&clean);
    let mut md = format!(
        "Encoder {} with {} estimator(s) on the first {n} frames of {}; each perturbation is applied to the raw frames before preprocessing (seed {}).\n\n| condition |",
        a.encoder.display(),
        estimators.len(),
        a.data.display(),
        a.seed
    );
    for (name, _) in &header {
        md.push_str(&format!(" {name} |"));
    }
    md.push_str("\n|---|");
    md.push_str(&"---|".repeat(header.len()));
    md.push('\n');
    let row = |md: &mut String, label: &str, s: &Scores| {
        md.push_str(&format!("| {label} |"));
        for (name, v) in columns(s) {
            if name == "shape accuracy" {
                md.push_str(&format!(" {v:.1} % |"));
            } else {
                md.push_str(&format!(" {v:.3} |"));
            }
        }
        md.push('\n');
    };
    row(&mut md, "clean", &clean);
    // Relative degradation per perturbation kind, for the plot.
    let mut series: Vec<Series> = Vec::new();
    let study = Perturbation::study();
    let progress =
        indicatif::ProgressBar::new(study.iter().map(|s| s.1.len()).sum::<usize>() as u64);
    for (stream, (kind, levels)) in study.iter().enumerate() {
        let mut points = vec![(0.0, 1.0)];
        for (l, p) in levels.iter().enumerate() {
            let s = run(Some(*p), 1 + (stream * 10 + l) as u64)?;
            row(&mut md, &p.describe(), &s);
            // Mean over targets of error / clean error (accuracy: error rate).
            let ratio = |s: &Scores| -> Vec<f64> {
                let mut r: Vec<f64> = s.targets.iter().map(|t| t.mae).collect();
                if let Some(acc) = s.accuracy {
                    r.push(1.0 - acc);
                }
                r
            };
            let (now, base) = (ratio(&s), ratio(&clean));
            let rel = now
                .iter()
                .zip(&base)
                .map(|(x, b)| x / b.max(1e-9))
                .sum::<f64>()
                / now.len().max(1) as f64;
            points.push(((l + 1) as f64, rel));
            progress.inc(1);
        }
        series.push(Series {
            name: kind.to_string(),
            points,
        });
    }
    progress.finish_and_clear();
    md.push_str("\nThe plot shows each error (shape error rate, target MAEs) divided by its clean value, averaged over the estimators' outputs, against the strength step (0 = clean, 1-3 = the rows above, in order).\n");
    print!("{md}");
    if let Some(out) = &a.out {
        let png = out.with_extension("png");
        line_plot(
            &png,
            "Error growth under perturbed camera conditions",
            "strength step",
            "error / clean error",
            &series,
            false,
        )?;
        let name = png.file_name().unwrap_or_default().to_string_lossy();
        md.push_str(&format!("\n![robustness]({name})\n"));
        tactile_core::io::write_atomic(out, md.as_bytes())?;
        eprintln!("wrote {} and {}", out.display(), png.display());
    }
    Ok(())
}
