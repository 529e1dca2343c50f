//! `tactile bench detector|segmenter`: for every size of a sweep, the error
//! on a held-out dataset beside the median batch-1 latency on each runtime
//! (burn ndarray, burn flex, onnxruntime), as a Markdown table and a plot of
//! error against milliseconds.

use std::path::{Path, PathBuf};

use anyhow::Result;
use burn::module::Module;
use burn::tensor::{Device, Tensor, TensorData};
use clap::Args;
use tactile_core::DeviceKind;
use tactile_core::bench::{Machine, median_seconds};
use tactile_core::dataset::Dataset;
use tactile_core::plot::{Series, line_plot};
use tactile_onnx::OrtModel;

/// Builds, for a device, a closure that runs the model once on an input.
type RunOn<'a> = &'a dyn Fn(&Device) -> Result<Box<dyn Fn(Tensor<4>)>>;

/// Median batch-1 milliseconds of `run` on each burn device, then of the
/// ONNX model in onnxruntime (skipped with a note when it cannot load).
fn latencies(
    shape: [usize; 4],
    data: &[f32],
    runs: usize,
    run: RunOn<'_>,
    onnx: &[u8],
) -> Result<Vec<(String, f64)>> {
    let mut out = Vec::new();
    for kind in DeviceKind::ALL {
        let dev = kind.device();
        let f = run(&dev)?;
        let x = Tensor::<4>::from_data(TensorData::new(data.to_vec(), shape), &dev);
        let s = median_seconds(3, runs, || f(x.clone()));
        out.push((format!("burn {kind}"), 1e3 * s));
    }
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    match OrtModel::from_bytes(onnx, threads) {
        Ok(mut ort) => {
            let s = median_seconds(3, runs, || {
                let _ = ort.run_f32(&shape, data.to_vec());
            });
            out.push(("onnxruntime 1.31.1".into(), 1e3 * s));
        }
        Err(e) => eprintln!("onnxruntime skipped: {e}"),
    }
    Ok(out)
}

/// The latency (ms) of the runtime whose name contains `k`, or "-".
fn ms_cell(lat: &[(String, f64)], k: &str) -> String {
    lat.iter()
        .find(|l| l.0.contains(k))
        .map_or("-".into(), |l| format!("{:.2}", l.1))
}

/// Seeded stand-in input values (latency does not depend on them).
fn input(n: usize) -> Vec<f32> {
    (0..n)
        .map(|i| ((i * 7919) % 255) as f32 / 128.0 - 1.0)
        .collect()
}

#[derive(Args)]
pub struct BenchModelsArgs {
    /// Model folders of the sweep.
    #[arg(long, num_args = 1.., required = true)]
    models: Vec<PathBuf>,
    /// Held-out visuo-tactile dataset for the error column.
    #[arg(long)]
    data: PathBuf,
    /// Timed runs per latency (median reported).
    #[arg(long, default_value_t = 20)]
    runs: usize,
    /// Markdown table; the plot goes beside it as NAME.png.
    #[arg(long)]
    out: Option<PathBuf>,
    /// A second held-out dataset, the one sizes are chosen on: its score
    /// gets a column of its own.
    #[arg(long)]
    select: Option<PathBuf>,
    /// Depth only: a held-out set at the press extremes, scored in columns of its own.
    #[arg(long)]
    extreme: Option<PathBuf>,
}

fn header(what: &str, data: &Path, runs: usize) -> String {
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    format!(
        "Machine: {}. Threads: burn devices use rayon over {threads} cores; onnxruntime {threads} intra-op threads. \
         Latency: median of {runs} runs at batch 1, inference only (loading and resizing excluded). \
         {what} on {} (held out: never used in training or in any choice).\n\n",
        Machine::detect().describe(),
        data.display()
    )
}

/// One model's row for the JSON beside the table: its error metrics and
/// the median milliseconds per runtime (read back by `tactile report`).
fn row_json(model: &Path, metrics: serde_json::Value, lat: &[(String, f64)]) -> serde_json::Value {
    let ms: serde_json::Map<String, serde_json::Value> = lat
        .iter()
        .map(|(k, v)| (k.clone(), serde_json::json!(v)))
        .collect();
    serde_json::json!({
        "model": model.file_name().unwrap_or_default().to_string_lossy(),
        "metrics": metrics,
        "ms": ms,
    })
}

/// Print the table; with `out`, write it, its plot (NAME.png) and its rows
/// as JSON (NAME.json).
fn finish(
    out: &Option<PathBuf>,
    mut md: String,
    title: &str,
    y_label: &str,
    series: Vec<Series>,
    rows: Vec<serde_json::Value>,
) -> Result<()> {
    print!("{md}");
    if let Some(out) = out {
        tactile_core::io::write_json_atomic(out.with_extension("json"), &rows)?;
        let png = out.with_extension("png");
        line_plot(
            &png,
            title,
            "latency, batch 1 (ms)",
            y_label,
            &series,
            false,
        )?;
        let name = png.file_name().unwrap_or_default().to_string_lossy();
        md.push_str(&format!("\n![{title}]({name})\n"));
        tactile_core::io::write_atomic(out, md.as_bytes())?;
        eprintln!("wrote {} and {}", out.display(), png.display());
    }
    Ok(())
}

/// Add one point per runtime to the per-runtime series.
fn add_points(series: &mut Vec<Series>, lat: &[(String, f64)], error: f64) {
    for (name, ms) in lat {
        match series.iter_mut().find(|s| &s.name == name) {
            Some(s) => s.points.push((*ms, error)),
            None => series.push(Series {
                name: name.clone(),
                points: vec![(*ms, error)],
            }),
        }
    }
}

pub fn bench_detector(a: BenchModelsArgs) -> Result<()> {
    use tactile_detect::{DetectionSet, DetectorArtifact};
    let ds = Dataset::open(&a.data)?;
    let mut md = header("Accuracy and F1", &a.data, a.runs);
    md.push_str("| model | architecture | width | input | parameters | accuracy (selection set) | accuracy | F1 | onset/release accuracy | burn ndarray ms | burn flex ms | onnxruntime ms |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    let sel_ds = a.select.as_ref().map(Dataset::open).transpose()?;
    let mut series = Vec::new();
    let mut rows = Vec::new();
    let mut candidates: Vec<Candidate> = Vec::new();
    // Frames are loaded once per input size (test and selection sets).
    type Sets = ([usize; 2], DetectionSet, Option<DetectionSet>);
    let mut cache: Vec<Sets> = Vec::new();
    for m in &a.models {
        let (art, model) = DetectorArtifact::load(m, &DeviceKind::Flex.device())?;
        let size = art.detector.input_size;
        if !cache.iter().any(|c| c.0 == size) {
            eprintln!("loading {} at {}x{}", a.data.display(), size[0], size[1]);
            let sel = sel_ds
                .as_ref()
                .map(|d| DetectionSet::from_dataset(d, size))
                .transpose()?;
            cache.push((size, DetectionSet::from_dataset(&ds, size)?, sel));
        }
        let (_, data, sel_data) = cache.iter().find(|c| c.0 == size).expect("cached");
        let sc = crate::detect_cmds::score(m, data, DeviceKind::Flex)?;
        let sel_acc = match sel_data {
            Some(d) => Some(
                crate::detect_cmds::score(m, d, DeviceKind::Flex)?
                    .all
                    .accuracy,
            ),
            None => None,
        };
        if let (Some(acc), Some(d)) = (sel_acc, sel_data) {
            candidates.push(Candidate {
                parameters: model.num_params(),
                input_pixels: size[0] * size[1],
                folder: m.clone(),
                accuracy: acc,
                frames: d.len(),
            });
        }
        let sel = sel_acc.map_or("-".into(), |v| format!("{v:.4}"));
        let onnx = tactile_onnx::export_detector(&model, size)?;
        let shape = [1, 3, size[1], size[0]];
        let lat = latencies(
            shape,
            &input(shape.iter().product()),
            a.runs,
            &|d| {
                let (_, m) = DetectorArtifact::load(m, d)?;
                Ok(Box::new(move |x| {
                    let _ = m.forward(x).into_data();
                }))
            },
            &onnx,
        )?;
        let ms = |k: &str| ms_cell(&lat, k);
        md.push_str(&format!(
            "| {} | {:?} | {} | {}x{} | {} | {sel} | {:.4} | {:.4} | {:.4} | {} | {} | {} |\n",
            m.file_name().unwrap_or_default().to_string_lossy(),
            art.detector.architecture,
            art.detector.width,
            size[0],
            size[1],
            model.num_params(),
            sc.all.accuracy,
            sc.all.f1,
            sc.onset_release.accuracy,
            ms("ndarray"),
            ms("flex"),
            ms("onnxruntime"),
        ));
        add_points(&mut series, &lat, 100.0 * (1.0 - sc.all.accuracy));
        rows.push(row_json(
            m,
            serde_json::json!({
                "accuracy": sc.all.accuracy,
                "f1": sc.all.f1,
                "onset_release_accuracy": sc.onset_release.accuracy,
                "selection_accuracy": sel_acc,
            }),
            &lat,
        ));
    }
    md.push_str(&format!(
        "\n{}Paper B: MobileNetV3-small 0.958 test accuracy at 11 ms, ResNet-18 85 ms (Intel i7).\n",
        choose_detector(&candidates)
    ));
    finish(
        &a.out,
        md,
        "Detector: error against latency",
        "error (%)",
        series,
        rows,
    )
}

/// A detector of the sweep as the selection rule sees it.
struct Candidate {
    parameters: usize,
    input_pixels: usize,
    folder: PathBuf,
    /// Accuracy on the selection set, of `frames` frames.
    accuracy: f64,
    frames: usize,
}

/// The selection rule's verdict, as a sentence; the smallest is the one
/// with fewest parameters, then fewest input pixels.
fn choose_detector(candidates: &[Candidate]) -> String {
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
            c.folder.file_name().unwrap_or_default().to_string_lossy(),
            c.parameters,
            c.accuracy,
            c.frames
        ),
        None => format!("{rule} No model here meets it. "),
    }
}

pub fn bench_segmenter(a: BenchModelsArgs) -> Result<()> {
    use tactile_segment::SegmenterArtifact;
    let ds = Dataset::open(&a.data)?;
    let mut md = header("Mean IoU and direction error", &a.data, a.runs);
    md.push_str("| model | window | base | parameters | IoU all (selection set) | IoU all | IoU curved | direction straight median / p90 (deg) | direction curved median / p90 (deg) | burn ndarray ms | burn flex ms | onnxruntime ms |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    let sel_ds = a.select.as_ref().map(Dataset::open).transpose()?;
    let mut series = Vec::new();
    let mut rows = Vec::new();
    for m in &a.models {
        let (art, model) = SegmenterArtifact::load(m, &DeviceKind::Flex.device())?;
        let (table, _) = crate::segment_cmds::score(m, &ds, DeviceKind::Flex)?;
        let row = |p: &str| table.iter().find(|r| r.path == p);
        let sel = match &sel_ds {
            Some(ds) => format!(
                "{:.4}",
                crate::segment_cmds::score(m, ds, DeviceKind::Flex)?.0[0].mean_iou
            ),
            None => "-".into(),
        };
        let side = art.unet.side;
        let onnx = tactile_onnx::export_segmenter(&model, side)?;
        let shape = [1, 3, side, side];
        let lat = latencies(
            shape,
            &input(shape.iter().product()),
            a.runs,
            &|d| {
                let (_, m) = SegmenterArtifact::load(m, d)?;
                Ok(Box::new(move |x| {
                    let _ = m.forward(x).into_data();
                }))
            },
            &onnx,
        )?;
        let ms = |k: &str| ms_cell(&lat, k);
        let iou = |p: &str| row(p).map_or("-".into(), |r| format!("{:.4}", r.mean_iou));
        let dir = |p: &str| {
            row(p).map_or("-".into(), |r| {
                format!("{:.2} / {:.2}", r.direction_median_deg, r.direction_p90_deg)
            })
        };
        md.push_str(&format!(
            "| {} | {side}x{side} | {} | {} | {sel} | {} | {} | {} | {} | {} | {} | {} |\n",
            m.file_name().unwrap_or_default().to_string_lossy(),
            art.unet.base,
            model.num_params(),
            iou("all"),
            iou("curved (arc + s-curve)"),
            dir("straight"),
            dir("curved (arc + s-curve)"),
            ms("ndarray"),
            ms("flex"),
            ms("onnxruntime"),
        ));
        let all = row("all").map_or(f64::NAN, |r| r.mean_iou);
        add_points(&mut series, &lat, 1.0 - all);
        let num = |p: &str, f: fn(&crate::segment_cmds::PathScores) -> f64| row(p).map(f);
        rows.push(row_json(
            m,
            serde_json::json!({
                "iou": num("all", |r| r.mean_iou),
                "iou_curved": num("curved (arc + s-curve)", |r| r.mean_iou),
                "direction_straight_median_deg": num("straight", |r| r.direction_median_deg),
                "direction_straight_p90_deg": num("straight", |r| r.direction_p90_deg),
            }),
            &lat,
        ));
    }
    md.push_str(
        "\nThe shipped `models/segmenter` is the smallest meeting every target on the selection set (IoU 0.85 over all tendon frames, 0.80 on curved ones, straight-tendon direction median 3 and 90th percentile 10 degrees). Paper B: IoU 0.879 validation, 0.196 on the curved test tendon; 69 ms (Intel i7).\n",
    );
    finish(
        &a.out,
        md,
        "Segmenter: 1 - IoU against latency",
        "1 - mean IoU",
        series,
        rows,
    )
}

pub fn bench_depth(a: BenchModelsArgs) -> Result<()> {
    use tactile_depth::DepthArtifact;
    let ds = Dataset::open(&a.data)?;
    let mut md = header("Depth error", &a.data, a.runs);
    md.push_str("| model | encoder | input | head | loss | mask channel | parameters | MAE window, selection set (mm) | MAE window (mm) | MAE tendon (mm) | RMSE (mm) | SSIM | extreme presses: MAE window / tendon (mm), SSIM | burn ndarray ms | burn flex ms | onnxruntime ms |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    let sel_ds = a.select.as_ref().map(Dataset::open).transpose()?;
    let ext_ds = a.extreme.as_ref().map(Dataset::open).transpose()?;
    let mut series = Vec::new();
    let mut rows = Vec::new();
    for m in &a.models {
        let (art, model) = DepthArtifact::load(m, &DeviceKind::Flex.device())?;
        let (s, _) = crate::depth_cmds::score(m, &ds, DeviceKind::Flex)?;
        let sel = match &sel_ds {
            Some(d) => format!(
                "{:.4}",
                crate::depth_cmds::score(m, d, DeviceKind::Flex)?.0.mae_mm
            ),
            None => "-".into(),
        };
        let ext = match &ext_ds {
            Some(d) => {
                let e = crate::depth_cmds::score(m, d, DeviceKind::Flex)?.0;
                format!(
                    "{:.4} / {} , {:.4}",
                    e.mae_mm,
                    e.mae_tendon_mm.map_or("-".into(), |v| format!("{v:.4}")),
                    e.ssim
                )
            }
            None => "-".into(),
        };
        let [w, h] = art.net.input_size;
        let onnx = tactile_onnx::export_depth(&model, art.net.in_channels, [w, h])?;
        let shape = [1, art.net.in_channels, h, w];
        let lat = latencies(
            shape,
            &input(shape.iter().product()),
            a.runs,
            &|d| {
                let (_, m) = DepthArtifact::load(m, d)?;
                Ok(Box::new(move |x| {
                    let _ = m.forward(x).into_data();
                }))
            },
            &onnx,
        )?;
        let ms = |k: &str| ms_cell(&lat, k);
        let training: serde_json::Value =
            tactile_core::io::read_json(m.join("training.json")).unwrap_or_default();
        md.push_str(&format!(
            "| {} | {} | {w}x{h} | {:?} | {} | {} | {} | {sel} | {:.4} | {} | {:.4} | {:.4} | {ext} | {} | {} | {} |\n",
            m.file_name().unwrap_or_default().to_string_lossy(),
            art.notes.get("encoder").and_then(|v| v.as_str()).unwrap_or("?"),
            art.net.head,
            training["config"]["loss"].as_str().unwrap_or("?"),
            if art.with_mask { "yes" } else { "no" },
            model.num_params(),
            s.mae_mm,
            s.mae_tendon_mm.map_or("-".into(), |v| format!("{v:.4}")),
            s.rmse_mm,
            s.ssim,
            ms("ndarray"),
            ms("flex"),
            ms("onnxruntime"),
        ));
        add_points(&mut series, &lat, s.mae_mm);
        rows.push(row_json(
            m,
            serde_json::json!({
                "mae_window_mm": s.mae_mm,
                "mae_tendon_mm": s.mae_tendon_mm,
                "rmse_mm": s.rmse_mm,
                "ssim": s.ssim,
            }),
            &lat,
        ));
    }
    md.push_str("\nThe shipped `models/depth` is the smallest meeting every target on the selection set (MAE at most 0.05 mm in the window and 0.10 mm over the tendon mask, SSIM at least 0.97). Paper B: MAE 0.050 mm and SSIM 0.960 on validation, 4.18 mm and 0.941 on an independent run. DenseTact: 0.28 mm.\n");
    finish(
        &a.out,
        md,
        "Depth: MAE against latency",
        "MAE in the window (mm)",
        series,
        rows,
    )
}
