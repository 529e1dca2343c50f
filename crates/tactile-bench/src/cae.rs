//! The CAE encoder's speed on every runtime beside its error: median
//! latency at batch 1 and throughput at a large batch, with the
//! reconstruction error and the shape head's accuracy.

use std::path::{Path, PathBuf};

use serde::Serialize;
use tactile_burn::{Artifact, DeviceKind, Runtime};
use tactile_cae::CaeArtifact;
use tactile_cae::data::PinSet;
use tactile_cae::eval::reconstruction_bce;
use tactile_core::bench::{Machine, median_seconds};
use tactile_core::dataset::Dataset;
use tactile_core::metrics::accuracy;
use tactile_estimate::ClassifierHead;
use tactile_onnx::load_network;

use crate::Result;
use crate::latency::{RuntimeMs, threads};
use crate::output::{BenchRow, folder_name};

/// Largest throughput batch, frames.
pub const MAX_BATCH: usize = 65_536;

/// One runtime's speed.
#[derive(Debug, Clone)]
pub struct EncoderSpeed {
    /// Runtime name.
    pub runtime: String,
    /// Threads, in words.
    pub threads: String,
    /// Median seconds of a batch-1 call.
    pub batch1_s: f64,
    /// Frames per second at the large batch.
    pub fps: f64,
}

/// Median latency at batch 1 and throughput at `batch` of the encoder in
/// `model` on every runtime, on the pin images of `pins`.
pub fn measure_encoder(
    model: &Path,
    pins: &PinSet,
    batch: usize,
    runs: usize,
) -> Result<Vec<EncoderSpeed>> {
    let art = CaeArtifact::read(model)?;
    let px = art.model.input_px;
    if pins.is_empty() {
        return Err(tactile_core::Error::Invalid("no frames to time the encoder on".into()).into());
    }
    if batch == 0 || batch > MAX_BATCH {
        return Err(tactile_core::Error::Config(format!(
            "the throughput batch must be 1 to {MAX_BATCH} frames, got {batch}"
        ))
        .into());
    }
    let flat = |n: usize| -> Vec<f32> {
        (0..n)
            .flat_map(|i| pins.images[i % pins.len()].pixels.clone())
            .collect()
    };
    let (x1, xb) = (flat(1), flat(batch));
    let mut out = Vec::new();
    for runtime in [Runtime::BurnNdarray, Runtime::BurnFlex, Runtime::Onnx] {
        let mut net = match load_network::<CaeArtifact>(model, runtime, threads()) {
            Ok((_, net)) => net,
            Err(e) if runtime == Runtime::Onnx => {
                tactile_core::note!("onnxruntime skipped: {e}");
                continue;
            }
            Err(e) => return Err(e.into()),
        };
        let t1 = median_seconds(5, runs, || {
            let _ = net.run([1, 1, px, px], x1.clone());
        });
        let tb = median_seconds(2, runs.div_ceil(3).max(3), || {
            let _ = net.run([batch, 1, px, px], xb.clone());
        });
        let (name, th) = match runtime.device() {
            Some(kind) => (format!("burn {kind}"), format!("{} (rayon)", threads())),
            None => (
                "onnxruntime 1.31.1".into(),
                format!("{} (intra-op)", threads()),
            ),
        };
        out.push(EncoderSpeed {
            runtime: name,
            threads: th,
            batch1_s: t1,
            fps: batch as f64 / tb,
        });
    }
    Ok(out)
}

impl EncoderSpeed {
    /// Batch-1 milliseconds per runtime, for the report.
    pub fn runtime_ms(speeds: &[EncoderSpeed]) -> RuntimeMs {
        let ms = |k: &str| {
            speeds
                .iter()
                .find(|s| s.runtime.contains(k))
                .map(|s| 1e3 * s.batch1_s)
        };
        RuntimeMs {
            ndarray: ms("ndarray"),
            flex: ms("flex"),
            onnxruntime: ms("onnxruntime"),
        }
    }
}

/// What the CAE bench measures (`tactile bench cae`'s flags).
#[derive(Debug, Clone, clap::Args)]
pub struct CaeBench {
    /// Model folder (with head/ for an accuracy column).
    #[arg(long, default_value = "models/cae-shapes")]
    pub model: PathBuf,
    /// Dataset to measure error on (its `test` split when it has one).
    #[arg(long, default_value = "../shared/real/polic-shapes")]
    pub data: PathBuf,
    /// Large-batch size for throughput.
    #[arg(long, default_value_t = 256)]
    pub batch: usize,
    /// Timed runs per measurement (median reported).
    #[arg(long, default_value_t = 30)]
    pub runs: usize,
}

/// The CAE's errors, for the JSON and the report.
#[derive(Debug, Clone, Serialize)]
pub struct CaeMetrics {
    /// Mean reconstruction BCE.
    pub reconstruction_bce: f64,
    /// Shape head accuracy, when the folder has a head.
    pub shape_accuracy: Option<f64>,
}

/// The table and its one row.
pub struct CaeBenchResult {
    /// Markdown.
    pub markdown: String,
    /// The row.
    pub row: BenchRow<CaeMetrics>,
}

/// Speed against error of one encoder.
pub fn bench_cae(b: &CaeBench) -> Result<CaeBenchResult> {
    tactile_core::bench::check_runs(b.runs)?;
    let ds = Dataset::open(&b.data)?;
    let rows = ds.split_indices("test").unwrap_or_else(|| ds.every_row());
    let flex = DeviceKind::Flex.device();
    let loaded = CaeArtifact::load(&b.model, &flex)?;
    let art = &loaded.artifact;
    let pins = PinSet::from_rows(&ds, &rows, &art.preprocess)?;
    let all: Vec<usize> = (0..pins.len()).collect();
    let bce = reconstruction_bce(&loaded.model, &pins, &all, 256, &flex);
    let head_acc = match ClassifierHead::load(b.model.join("head"), &flex) {
        Ok(head) => {
            let mut enc = tactile_cae::TactipEncoder::load(&b.model, Runtime::BurnFlex, 0)?;
            let feats = enc.encode(&pins.images)?;
            let truth: Vec<usize> = rows
                .iter()
                .map(|&i| {
                    ds.text_opt(i, "shape")
                        .and_then(|s| head.classes().iter().position(|c| c == s))
                        .unwrap_or(usize::MAX)
                })
                .collect();
            Some(accuracy(&head.predict(&feats)?, &truth))
        }
        Err(_) => None,
    };
    let speeds = measure_encoder(&b.model, &pins, b.batch, b.runs)?;
    let mut md = format!("Machine: {}\n\n", Machine::detect().describe());
    md.push_str(&format!(
        "CAE encoder {:?} ({} features), {} frames of {}; reconstruction BCE {:.4}{}\n\n",
        art.model.widths,
        art.model.feature_count(),
        pins.len(),
        b.data.display(),
        bce,
        head_acc
            .map(|v| format!("; shape accuracy {:.1} %", 100.0 * v))
            .unwrap_or_default()
    ));
    md.push_str(&format!("| runtime | threads | median latency, batch 1 (ms) | throughput, batch {} (frames/s) |\n|---|---|---|---|\n", b.batch));
    for s in &speeds {
        md.push_str(&format!(
            "| {} | {} | {:.3} | {:.0} |\n",
            s.runtime,
            s.threads,
            s.batch1_s * 1e3,
            s.fps
        ));
    }
    Ok(CaeBenchResult {
        markdown: md,
        row: BenchRow {
            model: folder_name(&b.model),
            metrics: CaeMetrics {
                reconstruction_bce: bce,
                shape_accuracy: head_acc,
            },
            ms: EncoderSpeed::runtime_ms(&speeds),
        },
    })
}

impl CaeBenchResult {
    /// Write the table and, beside it, its row as JSON.
    pub fn write(&self, out: &Path) -> Result<()> {
        crate::output::write_markdown_and_json(out, &self.markdown, &[&self.row])
    }
}
