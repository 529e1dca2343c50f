//! Paper A, section V: the error of every estimator on clean frames and on
//! copies with more noise, an illumination gradient, a light blob or a
//! rotated mounting, three strengths each.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::Serialize;
use tactile_burn::Runtime;
use tactile_cae::data::PinSet;
use tactile_core::dataset::Dataset;
use tactile_core::image_io::GreyImage;
use tactile_core::plot::{Series, line_plot};
use tactile_core::rng::SampleRng;
use tactile_core::source::UndecodableFrames;
use tactile_estimate::eval::Scores;
use tactile_pipeline::tactip::TactipPerception;
use tactile_preprocess::perturb::Perturbation;

pub use tactile_pipeline::options::RobustnessOptions;

use crate::Result;

/// What the study runs on (`tactile robustness`'s flags; Python's
/// `tactile.study.robustness(encoder, data, **options)`).
#[derive(Debug, Clone, clap::Args)]
pub struct Robustness {
    /// Trained encoder folder.
    #[arg(long)]
    pub encoder: PathBuf,
    /// Labelled dataset of raw frames (held-out synthetic TacTip frames).
    #[arg(long)]
    pub data: PathBuf,
    /// The estimators, the frames and the seed.
    #[command(flatten)]
    pub options: RobustnessOptions,
}

/// Errors of every estimator on clean frames and on perturbed copies.
pub fn robustness(r: &Robustness) -> Result<RobustnessResult> {
    tactile_core::source::check_limit(r.options.limit.map(|n| n as u64))?;
    let ds = Dataset::open(&r.data)?;
    let n = r.options.limit.unwrap_or(ds.len()).min(ds.len());
    if n == 0 {
        return Err(tactile_core::Error::Invalid(format!(
            "{}: no frames to perturb",
            r.data.display()
        ))
        .into());
    }
    let mut perception = TactipPerception::load(&r.encoder, &r.options.heads, Runtime::BurnFlex)?;
    let preprocess = perception.encoder.artifact.preprocess.clone();
    let estimators = perception.estimators.len();
    let (frames, ds, warnings) = clean_frames(&ds, n)?;
    // Frames left out (cut short behind their header) are said here too.
    let scored = match frames.len() {
        k if k == n => format!("the first {n} frames"),
        k => format!("{k} of the first {n} frames"),
    };
    let mut run = |p: Option<Perturbation>, stream: u64| -> Result<Scores> {
        let images = frames
            .par_iter()
            .enumerate()
            .map(|(i, f)| {
                let img = match p {
                    Some(p) => p.apply(f, &mut SampleRng::new(r.options.seed, stream, i as u64))?,
                    None => f.clone(),
                };
                tactile_preprocess::preprocess(&img, &preprocess)
                    .map_err(|e| e.in_file(ds.path_of(i, "file").unwrap_or_default()))
            })
            .collect::<std::result::Result<Vec<_>, _>>()?;
        Ok(perception.evaluate_pins(&PinSet::from_images(images), &ds)?)
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
        "Encoder {} with {} estimator(s) on {scored} of {}; each perturbation is applied to the raw frames before preprocessing (seed {}).\n\n{}| condition |",
        r.encoder.display(),
        estimators,
        r.data.display(),
        r.options.seed,
        warnings
            .iter()
            .map(|w| format!("**{w}**\n\n"))
            .collect::<String>()
    );
    for (name, _) in &header {
        md.push_str(&format!(" {name} |"));
    }
    md.push_str("\n|---|");
    md.push_str(&"---|".repeat(header.len()));
    md.push('\n');
    let mut rows = Vec::new();
    let mut row = |md: &mut String, label: &str, s: &Scores| {
        md.push_str(&format!("| {label} |"));
        rows.push(RobustnessRow {
            condition: label.to_string(),
            values: columns(s),
        });
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
    Ok(RobustnessResult {
        markdown: md,
        rows,
        warnings,
        series,
    })
}

/// One condition's errors.
#[derive(Debug, Clone, Serialize)]
pub struct RobustnessRow {
    /// `clean`, or the perturbation and its strength.
    pub condition: String,
    /// Each output's score: `shape accuracy` in percent, `NAME MAE` in
    /// the target's units.
    pub values: Vec<(String, f64)>,
}

/// The first `n` frames of `ds` as recorded, with the dataset of their
/// rows and the warnings of the pass. Every header is read first, so a
/// frame no reader takes stops the study before any is decoded; a frame
/// cut short behind a whole header is then left out with its labels and
/// named in the warnings, as `evaluate` leaves it out
/// ([`UndecodableFrames`], the one rule); when none can be decoded, the
/// study fails with the refusal.
fn clean_frames(ds: &Dataset, n: usize) -> Result<(Vec<GreyImage>, Dataset, Vec<String>)> {
    let rows: Vec<usize> = (0..n).collect();
    ds.check_frame_headers(&rows)?;
    let loaded: Vec<_> = rows.par_iter().map(|&i| ds.load_grey(i, "file")).collect();
    let mut skipped = UndecodableFrames::new(n);
    let (mut kept, mut frames) = (Vec::new(), Vec::new());
    for (i, frame) in loaded.into_iter().enumerate() {
        if let Some(frame) = skipped.decoded(frame)? {
            kept.push(i);
            frames.push(frame);
        }
    }
    // Without the "warning: " the CLI prints before it, as compare's.
    let warnings = (skipped.warning().into_iter())
        .map(|w| w.strip_prefix("warning: ").unwrap_or(&w).to_string())
        .collect();
    skipped.finish(frames.len())?;
    Ok((frames, ds.only_rows(&kept), warnings))
}

/// The table, its rows and the plot's series.
#[derive(Serialize)]
pub struct RobustnessResult {
    /// Markdown, without the plot's link.
    pub markdown: String,
    /// Each condition's row, in the table's order.
    pub rows: Vec<RobustnessRow>,
    /// What the pass left out: a frame cut short behind its header, named
    /// (also in bold on the page), without the `warning: ` the CLI puts
    /// before it.
    pub warnings: Vec<String>,
    /// Error growth per perturbation kind.
    #[serde(skip)]
    pub series: Vec<Series>,
}

impl RobustnessResult {
    /// Write the table to `out`, its rows (`NAME.json`) and its plot
    /// (`NAME.png`) beside it.
    pub fn write(&self, out: &Path) -> Result<()> {
        let _page = crate::output::lock_page(out)?;
        let png = out.with_extension("png");
        line_plot(
            &png,
            "Error growth under perturbed camera conditions",
            "strength step",
            "error / clean error",
            &self.series,
            false,
        )?;
        let name = png.file_name().unwrap_or_default().to_string_lossy();
        let md = format!("{}\n![robustness]({name})\n", self.markdown);
        crate::output::markdown_and_json(out, &md, &self.rows)
    }
}
