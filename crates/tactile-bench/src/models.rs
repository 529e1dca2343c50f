//! Paper B's models across a size sweep: for every model folder, the error
//! on a held-out dataset beside the median batch-1 latency on each runtime,
//! as a Markdown table, a plot of error against milliseconds, and JSON rows.

use std::path::{Path, PathBuf};

use burn::module::Module;
use serde::Serialize;
use tactile_burn::{Artifact, DeviceKind, Runtime};
use tactile_core::dataset::Dataset;
use tactile_depth::{DepthArtifact, DepthEnsembleArtifact, DepthEstimator, DepthScores};
use tactile_detect::{DetectionSet, DetectorArtifact, DetectorEnsembleArtifact, TendonDetector};
use tactile_segment::eval::CURVED;
use tactile_segment::{SegmenterArtifact, SegmenterScores, TendonSegmenter};

use crate::Result;
use crate::latency::{model_latencies, ms_cell};
use crate::output::{BenchRow, Table, add_points, folder_name, header};

/// Model folders and the data they are scored on (the flags of `tactile
/// bench detector|segmenter|depth|pose|surface`).
#[derive(Debug, Clone, clap::Args)]
pub struct ModelBench {
    /// Model folders of the sweep.
    #[arg(long, num_args = 1.., required = true)]
    pub models: Vec<PathBuf>,
    /// Held-out dataset for the error column: visuo-tactile for detector, segmenter and depth; TacTip for pose and surface.
    #[arg(long)]
    pub data: PathBuf,
    /// A second held-out dataset, the one sizes are chosen on: its score
    /// gets a column of its own.
    #[arg(long)]
    pub select: Option<PathBuf>,
    /// Depth only: a held-out set at the press extremes, scored in columns of its own.
    #[arg(long)]
    pub extreme: Option<PathBuf>,
    /// Timed runs per latency (median reported).
    #[arg(long, default_value_t = 20)]
    pub runs: usize,
}

/// The device every score is computed on (scores do not depend on it).
const SCORE_RUNTIME: Runtime = Runtime::BurnFlex;

pub(crate) fn parameters<A: Artifact>(dir: &Path) -> Result<usize>
where
    A::Model: Module,
{
    Ok(A::load(dir, &DeviceKind::Flex.device())?.model.num_params())
}

/// A detector's errors, for the JSON and the report.
#[derive(Debug, Clone, Serialize)]
pub struct DetectorMetrics {
    /// Accuracy on the test set.
    pub accuracy: f64,
    /// F1 on the test set.
    pub f1: f64,
    /// Accuracy on onset and release frames.
    pub onset_release_accuracy: f64,
    /// Accuracy on the selection set.
    pub selection_accuracy: Option<f64>,
    /// Reliability of the probabilities on the test set.
    pub calibration: tactile_core::metrics::Calibration,
}

/// A detector of the sweep as the selection rule sees it.
#[derive(Debug, Clone)]
pub struct Candidate {
    /// Trainable parameters.
    pub parameters: usize,
    /// Input pixels.
    pub input_pixels: usize,
    /// Its folder.
    pub folder: PathBuf,
    /// Accuracy on the selection set, of `frames` frames.
    pub accuracy: f64,
    /// Selection frames.
    pub frames: usize,
}

/// The selection rule's verdict, as a sentence; the smallest is the one
/// with fewest parameters, then fewest input pixels.
pub fn choose_detector(candidates: &[Candidate]) -> String {
    if candidates.is_empty() {
        return String::new();
    }
    let rule = "Selection rule: the smallest model whose selection-set accuracy exceeds the 0.99 target by at least one standard error, sqrt(a (1 - a) / n) (a selection set cannot otherwise tell 0.990 from 0.995).";
    let chosen = candidates
        .iter()
        .filter(|c| {
            let (a, n) = (c.accuracy, c.frames.max(1) as f64);
            a - (a * (1.0 - a) / n).sqrt() >= 0.99
        })
        .min_by_key(|c| (c.parameters, c.input_pixels));
    match chosen {
        Some(c) => format!(
            "{rule} It picks `{}` ({} parameters, {:.4} on {} selection frames). ",
            folder_name(&c.folder),
            c.parameters,
            c.accuracy,
            c.frames
        ),
        None => format!("{rule} No model here meets it. "),
    }
}

/// Accuracy and F1 of every detector against its latency.
pub fn bench_detectors(b: &ModelBench) -> Result<Table<DetectorMetrics>> {
    tactile_core::bench::check_runs(b.runs)?;
    let ds = Dataset::open(&b.data)?;
    let sel_ds = b.select.as_ref().map(Dataset::open).transpose()?;
    let mut md = header("Accuracy and F1", &b.data, b.runs);
    md.push_str("| model | architecture | width | input | parameters | accuracy (selection set) | accuracy | F1 | onset/release accuracy | calibration error: all / p in 0.1-0.9 | burn ndarray ms | burn flex ms | onnxruntime ms |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    let (mut series, mut rows, mut candidates) = (Vec::new(), Vec::new(), Vec::new());
    // Frames are loaded once per input size (test and selection sets).
    type Sets = (([usize; 2], u8), DetectionSet, Option<DetectionSet>);
    let mut cache: Vec<Sets> = Vec::new();
    for m in &b.models {
        let mut det = TendonDetector::load(m, SCORE_RUNTIME, 0)?;
        let art = det.artifact.clone();
        let size = art.model.input_size;
        let key = (size, art.model.bits());
        if !cache.iter().any(|c| c.0 == key) {
            tactile_core::note!("loading {} at {}x{}", b.data.display(), size[0], size[1]);
            let sel = sel_ds
                .as_ref()
                .map(|d| DetectionSet::from_dataset(d, &art.model))
                .transpose()?;
            cache.push((key, DetectionSet::from_dataset(&ds, &art.model)?, sel));
        }
        let Some((_, data, sel_data)) = cache.iter().find(|c| c.0 == key) else {
            continue;
        };
        let sc = tactile_detect::evaluate(&mut det, data)?;
        let sel_acc = match sel_data {
            Some(d) => Some(tactile_detect::evaluate(&mut det, d)?.all.accuracy),
            None => None,
        };
        let ensemble = DetectorEnsembleArtifact::is_in(m);
        let params = match ensemble {
            true => parameters::<DetectorEnsembleArtifact>(m)?,
            false => parameters::<DetectorArtifact>(m)?,
        };
        if let (Some(acc), Some(d)) = (sel_acc, sel_data) {
            candidates.push(Candidate {
                parameters: params,
                input_pixels: size[0] * size[1],
                folder: m.clone(),
                accuracy: acc,
                frames: d.len(),
            });
        }
        let shape = [1, 3, size[1], size[0]];
        let ms = match ensemble {
            true => model_latencies::<DetectorEnsembleArtifact>(m, shape, b.runs)?,
            false => model_latencies::<DetectorArtifact>(m, shape, b.runs)?,
        };
        md.push_str(&format!(
            "| {} | {:?} | {} | {}x{} | {params} | {} | {:.4} | {:.4} | {:.4} | {:.3} / {} | {} | {} | {} |\n",
            folder_name(m),
            art.model.architecture,
            art.model.width,
            size[0],
            size[1],
            sel_acc.map_or("-".into(), |v| format!("{v:.4}")),
            sc.all.accuracy,
            sc.all.f1,
            sc.onset_release.accuracy,
            sc.calibration.ece,
            sc.calibration.ece_uncertain_text(3),
            ms_cell(ms.ndarray),
            ms_cell(ms.flex),
            ms_cell(ms.onnxruntime),
        ));
        add_points(&mut series, &ms, 100.0 * (1.0 - sc.all.accuracy));
        rows.push(BenchRow::new(
            m,
            DetectorMetrics {
                accuracy: sc.all.accuracy,
                f1: sc.all.f1,
                onset_release_accuracy: sc.onset_release.accuracy,
                selection_accuracy: sel_acc,
                calibration: sc.calibration.clone(),
            },
            ms,
        ));
    }
    md.push_str(&format!(
        "\n{}Paper B: MobileNetV3-small 0.958 test accuracy at 11 ms, ResNet-18 85 ms (Intel i7).\n",
        choose_detector(&candidates)
    ));
    Ok(Table {
        markdown: md,
        title: "Detector: error against latency".into(),
        y_label: "error (%)".into(),
        series,
        rows,
        pictures: Vec::new(),
        after_plot: String::new(),
    })
}

/// A segmenter's errors, for the JSON and the report.
#[derive(Debug, Clone, Serialize)]
pub struct SegmenterMetrics {
    /// Mean IoU over every tendon frame.
    pub iou: Option<f64>,
    /// Over curved tendons.
    pub iou_curved: Option<f64>,
    /// Fraction of tendon frames given a direction (centre line).
    pub direction_coverage: Option<f64>,
    /// Median direction error over every tendon frame, degrees.
    pub direction_median_deg: Option<f64>,
    /// Its 90th percentile.
    pub direction_p90_deg: Option<f64>,
    /// The principal-axis baseline's coverage.
    pub principal_axis_coverage: Option<f64>,
    /// The principal-axis baseline's median error, degrees.
    pub principal_axis_median_deg: Option<f64>,
    /// Its 90th percentile.
    pub principal_axis_p90_deg: Option<f64>,
}

/// IoU and direction error of every segmenter against its latency.
pub fn bench_segmenters(b: &ModelBench) -> Result<Table<SegmenterMetrics>> {
    tactile_core::bench::check_runs(b.runs)?;
    let ds = Dataset::open(&b.data)?;
    let sel_ds = b.select.as_ref().map(Dataset::open).transpose()?;
    let mut md = header("Mean IoU and direction error", &b.data, b.runs);
    md.push_str("| model | window | base | parameters | IoU all (selection set) | IoU all | IoU curved | direction: coverage, median / p90 (deg) | curved: median / p90 (deg) | principal axis (baseline): coverage, median / p90 (deg) | burn ndarray ms | burn flex ms | onnxruntime ms |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    let (mut series, mut rows) = (Vec::new(), Vec::new());
    for m in &b.models {
        let mut seg = TendonSegmenter::load(m, SCORE_RUNTIME, 0)?;
        let art = seg.artifact.clone();
        let table: SegmenterScores = tactile_segment::evaluate(&mut seg, &ds)?;
        let sel = match &sel_ds {
            Some(d) => {
                let sel = tactile_segment::evaluate(&mut seg, d)?;
                note_frame_warnings(&sel.frame_warnings);
                sel.path("all")
                    .map_or("-".into(), |r| format!("{:.4}", r.mean_iou))
            }
            None => "-".into(),
        };
        note_frame_warnings(&table.frame_warnings);
        let side = art.model.side;
        let ms = model_latencies::<SegmenterArtifact>(m, [1, 3, side, side], b.runs)?;
        let iou = |p: &str| {
            table
                .path(p)
                .map_or("-".into(), |r| format!("{:.4}", r.mean_iou))
        };
        let dir = |p: &str, baseline: bool, coverage: bool| {
            table.path(p).map_or("-".into(), |r| {
                let d = if baseline {
                    &r.principal_axis
                } else {
                    &r.direction
                };
                let c = format!("{:.1} %, ", 100.0 * d.coverage);
                format!(
                    "{}{:.2} / {:.2}",
                    if coverage { c.as_str() } else { "" },
                    d.median_deg,
                    d.p90_deg
                )
            })
        };
        md.push_str(&format!(
            "| {} | {side}x{side} | {} | {} | {sel} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            folder_name(m),
            art.model.base,
            parameters::<SegmenterArtifact>(m)?,
            iou("all"),
            iou(CURVED),
            dir("all", false, true),
            dir(CURVED, false, false),
            dir("all", true, true),
            ms_cell(ms.ndarray),
            ms_cell(ms.flex),
            ms_cell(ms.onnxruntime),
        ));
        let all = table.path("all").map_or(f64::NAN, |r| r.mean_iou);
        add_points(&mut series, &ms, 1.0 - all);
        rows.push(BenchRow::new(
            m,
            SegmenterMetrics {
                iou: table.path("all").map(|r| r.mean_iou),
                iou_curved: table.path(CURVED).map(|r| r.mean_iou),
                direction_coverage: table.path("all").map(|r| r.direction.coverage),
                direction_median_deg: table.path("all").map(|r| r.direction.median_deg),
                direction_p90_deg: table.path("all").map(|r| r.direction.p90_deg),
                principal_axis_coverage: table.path("all").map(|r| r.principal_axis.coverage),
                principal_axis_median_deg: table.path("all").map(|r| r.principal_axis.median_deg),
                principal_axis_p90_deg: table.path("all").map(|r| r.principal_axis.p90_deg),
            },
            ms,
        ));
    }
    md.push_str(
        "\nThe shipped `models/segmenter` is the smallest meeting every target on the selection set (IoU 0.85 over all tendon frames, 0.80 on curved ones, straight-tendon direction median 3 and 90th percentile 10 degrees). Direction: the tangent of the centre line at its point nearest the window centre (`postprocess::centre_line`); the principal axis of the region (paper B's method) is the baseline. Target over every path: a direction on at least 98 % of tendon frames, median 2 and 90th percentile 5 degrees. Paper B: IoU 0.879 validation, 0.196 on the curved test tendon; 69 ms (Intel i7).\n",
    );
    Ok(Table {
        markdown: md,
        title: "Segmenter: 1 - IoU against latency".into(),
        y_label: "1 - mean IoU".into(),
        series,
        rows,
        pictures: Vec::new(),
        after_plot: String::new(),
    })
}

/// Note a scoring's frame warnings (frames that could not be decoded past
/// their header, left out of its numbers) on standard error.
fn note_frame_warnings<'a>(warnings: impl IntoIterator<Item = &'a String>) {
    for w in warnings {
        tactile_core::note!("{w}");
    }
}

/// A depth network's errors, for the JSON and the report.
#[derive(Debug, Clone, Serialize)]
pub struct DepthMetrics {
    /// MAE inside the window, mm.
    pub mae_window_mm: f64,
    /// MAE over the tendon mask, mm.
    pub mae_tendon_mm: Option<f64>,
    /// RMSE, mm.
    pub rmse_mm: f64,
    /// SSIM.
    pub ssim: f64,
}

/// Depth errors of every depth network against its latency.
pub fn bench_depth(b: &ModelBench) -> Result<Table<DepthMetrics>> {
    tactile_core::bench::check_runs(b.runs)?;
    let ds = Dataset::open(&b.data)?;
    let sel_ds = b.select.as_ref().map(Dataset::open).transpose()?;
    let ext_ds = b.extreme.as_ref().map(Dataset::open).transpose()?;
    let mut md = header("Depth error", &b.data, b.runs);
    md.push_str("| model | encoder | input | head | loss | mask channel | parameters | MAE window, selection set (mm) | MAE window (mm) | MAE tendon (mm) | RMSE (mm) | SSIM | extreme presses: MAE window / tendon (mm), SSIM | burn ndarray ms | burn flex ms | onnxruntime ms |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    let (mut series, mut rows) = (Vec::new(), Vec::new());
    for m in &b.models {
        let mut est = DepthEstimator::load(m, SCORE_RUNTIME, 0)?;
        let art = est.artifact.clone();
        let (s, _, skipped): (DepthScores, f64, _) = tactile_depth::evaluate(&mut est, &ds)?;
        note_frame_warnings(&skipped);
        let mut scored = |d: &Dataset| -> Result<DepthScores> {
            let (s, _, skipped) = tactile_depth::evaluate(&mut est, d)?;
            note_frame_warnings(&skipped);
            Ok(s)
        };
        let sel = match &sel_ds {
            Some(d) => format!("{:.4}", scored(d)?.mae_mm),
            None => "-".into(),
        };
        let ext = match &ext_ds {
            Some(d) => {
                let e = scored(d)?;
                format!(
                    "{:.4} / {} , {:.4}",
                    e.mae_mm,
                    e.mae_tendon_mm.map_or("-".into(), |v| format!("{v:.4}")),
                    e.ssim
                )
            }
            None => "-".into(),
        };
        let [w, h] = art.model.input_size;
        let shape = [1, art.model.in_channels, h, w];
        // An ensemble: its first member's training record (its recipe).
        let ensemble = DepthEnsembleArtifact::is_in(m);
        let (ms, params, record) = match ensemble {
            true => (
                model_latencies::<DepthEnsembleArtifact>(m, shape, b.runs)?,
                parameters::<DepthEnsembleArtifact>(m)?,
                (DepthEnsembleArtifact::read(m)?.ensemble.member_dirs(m))
                    .into_iter()
                    .next()
                    .unwrap_or_default()
                    .join("training.json"),
            ),
            false => (
                model_latencies::<DepthArtifact>(m, shape, b.runs)?,
                parameters::<DepthArtifact>(m)?,
                m.join("training.json"),
            ),
        };
        let training: serde_json::Value = tactile_core::io::read_json(record).unwrap_or_default();
        md.push_str(&format!(
            "| {} | {} | {w}x{h} | {:?} | {} | {} | {} | {sel} | {:.4} | {} | {:.4} | {:.4} | {ext} | {} | {} | {} |\n",
            folder_name(m),
            art.notes.get("encoder").and_then(|v| v.as_str()).unwrap_or("?"),
            art.model.head,
            training["config"]["loss"].as_str().unwrap_or("?"),
            if art.with_mask { "yes" } else { "no" },
            params,
            s.mae_mm,
            s.mae_tendon_mm.map_or("-".into(), |v| format!("{v:.4}")),
            s.rmse_mm,
            s.ssim,
            ms_cell(ms.ndarray),
            ms_cell(ms.flex),
            ms_cell(ms.onnxruntime),
        ));
        add_points(&mut series, &ms, s.mae_mm);
        rows.push(BenchRow::new(
            m,
            DepthMetrics {
                mae_window_mm: s.mae_mm,
                mae_tendon_mm: s.mae_tendon_mm,
                rmse_mm: s.rmse_mm,
                ssim: s.ssim,
            },
            ms,
        ));
    }
    md.push_str("\nThe shipped `models/depth` is the smallest meeting every target on the selection set (MAE at most 0.05 mm in the window and 0.10 mm over the tendon mask, SSIM at least 0.97). Paper B: MAE 0.050 mm and SSIM 0.960 on validation, 4.18 mm and 0.941 on an independent run. DenseTact: 0.28 mm.\n");
    Ok(Table {
        markdown: md,
        title: "Depth: MAE against latency".into(),
        y_label: "MAE in the window (mm)".into(),
        series,
        rows,
        pictures: Vec::new(),
        after_plot: String::new(),
    })
}
