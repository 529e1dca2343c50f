//! Paper A's search over the feature count: for each trained encoder, the
//! reconstruction error and shape accuracy on the test split, and the
//! encoder's latency on every runtime; a table and two plots (error against
//! features, error against latency).

use std::path::{Path, PathBuf};

use serde::Serialize;

use tactile_burn::{Artifact, DeviceKind, Runtime};
use tactile_cae::data::PinSet;
use tactile_cae::eval::reconstruction_bce;
use tactile_cae::{CaeArtifact, TactipEncoder};
use tactile_core::dataset::Dataset;
use tactile_core::metrics::accuracy;
use tactile_core::plot::{Series, line_plot};
use tactile_estimate::{ClassifierHead, HeadConfig};
use tactile_pipeline::tactip::{classes_of, encoder_trained_on};

pub use tactile_pipeline::options::SweepOptions;

use crate::Result;
use crate::cae::measure_encoder;
use crate::output::folder_name;

/// What the sweep compares (`tactile sweep`'s flags; Python's
/// `tactile.study.sweep(encoders, data, **options)`).
#[derive(Debug, Clone, clap::Args)]
pub struct Sweep {
    /// Trained encoders to compare (e.g. 8, 16, 32 and 64 features).
    #[arg(long, num_args = 1.., required = true)]
    pub encoders: Vec<PathBuf>,
    /// Dataset with a class column (its split column when present).
    #[arg(long)]
    pub data: PathBuf,
    /// The class column, the seed and the timing.
    #[command(flatten)]
    pub options: SweepOptions,
}

/// One encoder's row.
#[derive(Debug, Clone, Serialize)]
pub struct SweepRow {
    /// Folder name.
    pub name: String,
    /// Features.
    pub features: usize,
    /// Test reconstruction BCE.
    pub bce: f64,
    /// Test accuracy of a 10-fold head.
    pub accuracy: f64,
    /// `(runtime, ms at batch 1, frames/s at batch 256)`.
    pub speed: Vec<(String, f64, f64)>,
    /// True when the encoder trained on some of the test frames: its BCE
    /// and accuracy are then partly on frames it fitted.
    pub saw_test_frames: bool,
}

/// The table and its rows.
#[derive(Debug, Clone, Serialize)]
pub struct SweepResult {
    /// Markdown.
    pub markdown: String,
    /// Rows, by feature count.
    pub rows: Vec<SweepRow>,
    #[serde(skip)]
    classify: String,
}

/// Run the sweep.
pub fn sweep(s: &Sweep) -> Result<SweepResult> {
    tactile_core::bench::check_runs(s.options.runs)?;
    let ds = Dataset::open(&s.data)?;
    let split = ds.three_way_split(0.2, 0.2, s.options.seed)?;
    let (train, test) = ([split.train, split.val].concat(), split.test);
    let (classes, y) = classes_of(&ds, &s.options.classify)?;
    // The frame of each training row, so a frame's rows share a fold.
    let frames = ds.frame_of_rows(&train);
    let dev = DeviceKind::Flex.device();
    let mut rows = Vec::new();
    for enc in &s.encoders {
        tactile_core::note!("{}", enc.display());
        let loaded = CaeArtifact::load(enc, &dev)?;
        let art = &loaded.artifact;
        let pins = PinSet::from_dataset(&ds, &art.preprocess)?;
        let feats = TactipEncoder::load(enc, Runtime::BurnFlex, 0)?.encode(&pins.images)?;
        let bce = reconstruction_bce(&loaded.model, &pins, &test, 256, &dev);
        let pick = |idx: &[usize]| -> (Vec<Vec<f32>>, Vec<usize>) {
            (
                idx.iter().map(|&i| feats[i].clone()).collect(),
                idx.iter().map(|&i| y[i]).collect(),
            )
        };
        let (tx, ty) = pick(&train);
        let (sx, sy) = pick(&test);
        let mut cfg = HeadConfig::new(art.model.feature_count(), classes.clone()).with_repeats(1);
        cfg.schedule.seed = s.options.seed;
        let head = ClassifierHead::train_by_frame(cfg, &tx, &ty, &frames, &dev)?;
        let acc = accuracy(&head.predict(&sx)?, &sy);
        let speed = measure_encoder(enc, &pins, 256, s.options.runs)?
            .into_iter()
            .map(|sp| (sp.runtime, sp.batch1_s * 1e3, sp.fps))
            .collect();
        rows.push(SweepRow {
            name: folder_name(enc),
            features: art.model.feature_count(),
            bce,
            accuracy: acc,
            speed,
            saw_test_frames: encoder_trained_on(enc, &ds, &test).is_some(),
        });
    }
    rows.sort_by_key(|r| r.features);
    let runtimes: Vec<String> = rows
        .first()
        .map(|r| r.speed.iter().map(|s| s.0.clone()).collect())
        .unwrap_or_default();
    let mut md = format!(
        "Machine: {}\n\n{} ({} train, {} test frames); `{}` accuracy of a 10-fold MLP head on each encoder's features; latency: median at batch 1, throughput at batch 256.\n\n| encoder | features | test BCE | accuracy | {} |\n|---|---|---|---|{}\n",
        tactile_core::bench::Machine::detect().describe(),
        s.data.display(),
        train.len(),
        test.len(),
        s.options.classify,
        runtimes
            .iter()
            .map(|r| format!("{r} ms, frames/s"))
            .collect::<Vec<_>>()
            .join(" | "),
        "---|".repeat(runtimes.len())
    );
    for r in &rows {
        md.push_str(&format!(
            "| {}{} | {} | {:.4} | {:.1} % | {} |\n",
            r.name,
            if r.saw_test_frames {
                " (trained on test frames)"
            } else {
                ""
            },
            r.features,
            r.bce,
            100.0 * r.accuracy,
            r.speed
                .iter()
                .map(|(_, ms, fps)| format!("{ms:.3}, {fps:.0}"))
                .collect::<Vec<_>>()
                .join(" | ")
        ));
    }
    if rows.iter().any(|r| r.saw_test_frames) {
        md.push_str("\nAn encoder marked \"(trained on test frames)\" fitted some of these test frames (its notes say so): its BCE and accuracy are partly on frames it was trained on.\n");
    }
    Ok(SweepResult {
        markdown: md,
        rows,
        classify: s.options.classify.clone(),
    })
}

impl SweepResult {
    /// Write the table to `out`, its rows (`NAME.json`) and the plots
    /// beside it (`NAME-features.png`, `NAME-latency.png`).
    pub fn write(&self, out: &Path) -> Result<()> {
        let _page = crate::output::lock_page(out)?;
        crate::output::markdown_and_json(out, &self.markdown, &self.rows)?;
        let stem = out.with_extension("");
        let name = stem.file_name().unwrap_or_default().to_string_lossy();
        let err = |r: &SweepRow| 100.0 * (1.0 - r.accuracy);
        line_plot(
            stem.with_file_name(format!("{name}-features.png")),
            "Test error against feature count",
            "features",
            "error (%) / test BCE x 100",
            &[
                Series {
                    name: format!("{} error (%)", self.classify),
                    points: self
                        .rows
                        .iter()
                        .map(|r| (r.features as f64, err(r)))
                        .collect(),
                },
                Series {
                    name: "reconstruction BCE x 100".into(),
                    points: self
                        .rows
                        .iter()
                        .map(|r| (r.features as f64, 100.0 * r.bce))
                        .collect(),
                },
            ],
            false,
        )?;
        let runtimes: Vec<String> = self
            .rows
            .first()
            .map(|r| r.speed.iter().map(|s| s.0.clone()).collect())
            .unwrap_or_default();
        let series: Vec<Series> = runtimes
            .iter()
            .enumerate()
            .map(|(k, rt)| Series {
                name: rt.clone(),
                points: self.rows.iter().map(|r| (r.speed[k].1, err(r))).collect(),
            })
            .collect();
        line_plot(
            stem.with_file_name(format!("{name}-latency.png")),
            "Test error against encoder latency (batch 1)",
            "latency (ms)",
            "error (%)",
            &series,
            false,
        )?;
        Ok(())
    }
}
