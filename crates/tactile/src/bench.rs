//! `tactile bench`: median latency at batch 1 and throughput at a large
//! batch per runtime (burn ndarray, burn flex, onnxruntime), beside the
//! model's error, as one Markdown table with the machine and thread counts.

use std::path::PathBuf;

use anyhow::Result;
use burn::tensor::{Tensor, TensorData};
use clap::Args;
use tactile_cae::CaeArtifact;
use tactile_cae::data::PinSet;
use tactile_cae::encode::encode_all;
use tactile_cae::head::ClassifierHead;
use tactile_core::DeviceKind;
use tactile_core::bench::{Machine, median_seconds};
use tactile_core::dataset::Dataset;
use tactile_core::metrics::accuracy;
use tactile_core::nn::bce_with_logits;
use tactile_onnx::OrtModel;

#[derive(Args)]
pub struct BenchCaeArgs {
    /// Model folder (with head/ for an accuracy column).
    #[arg(long, default_value = "models/cae-shapes")]
    model: PathBuf,
    /// Dataset to measure error on (its `test` split when it has one).
    #[arg(long, default_value = "../shared/real/polic-shapes")]
    data: PathBuf,
    /// Large-batch size for throughput.
    #[arg(long, default_value_t = 256)]
    batch: usize,
    /// Timed runs per measurement (median reported).
    #[arg(long, default_value_t = 30)]
    runs: usize,
    /// Also write the table to this Markdown file.
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn bench_cae(a: BenchCaeArgs) -> Result<()> {
    let ds = Dataset::open(&a.data)?;
    let rows = ds
        .split_indices("test")
        .unwrap_or_else(|| (0..ds.len()).collect());
    let flex = DeviceKind::Flex.device();
    let (art, cae) = CaeArtifact::load(&a.model, &flex)?;
    let paths: Vec<PathBuf> = rows
        .iter()
        .map(|&i| ds.path_of(i, "file"))
        .collect::<Result<_, _>>()?;
    let pins = PinSet {
        files: vec![],
        images: tactile_preprocess::preprocess_files(&paths, &art.preprocess)?,
    };
    // Error: reconstruction BCE on the rows, and head accuracy when present.
    let all: Vec<usize> = (0..pins.len()).collect();
    let mut bce = 0.0;
    for c in all.chunks(256) {
        let x = pins.batch(c, &flex);
        let l: f32 = bce_with_logits(cae.forward_logits(x.clone()), x).into_scalar();
        bce += l as f64 * c.len() as f64;
    }
    bce /= pins.len().max(1) as f64;
    let head_acc = match ClassifierHead::load(a.model.join("head"), &flex) {
        Ok(head) => {
            let feats = encode_all(&cae.encoder, &pins, 256, &flex)?;
            let truth: Vec<usize> = rows
                .iter()
                .map(|&i| {
                    ds.text_opt(i, "shape")
                        .and_then(|s| head.config.classes.iter().position(|c| c == s))
                        .unwrap_or(usize::MAX)
                })
                .collect();
            Some(accuracy(&head.predict(&feats, &flex)?, &truth))
        }
        Err(_) => None,
    };
    let rows_out = measure_encoder(&a.model, &pins, a.batch, a.runs)?;
    let machine = Machine::detect();
    let mut md = String::new();
    md.push_str(&format!("Machine: {}\n\n", machine.describe()));
    md.push_str(&format!(
        "CAE encoder {:?} ({} features), {} frames of {}; reconstruction BCE {:.4}{}\n\n",
        art.cae.widths,
        art.cae.feature_count(),
        pins.len(),
        a.data.display(),
        bce,
        head_acc
            .map(|v| format!("; shape accuracy {:.1} %", 100.0 * v))
            .unwrap_or_default()
    ));
    md.push_str(&format!("| runtime | threads | median latency, batch 1 (ms) | throughput, batch {} (frames/s) |\n|---|---|---|---|\n", a.batch));
    for (name, th, t1, fps) in &rows_out {
        md.push_str(&format!(
            "| {name} | {th} | {:.3} | {:.0} |\n",
            t1 * 1e3,
            fps
        ));
    }
    print!("{md}");
    if let Some(out) = a.out {
        tactile_core::io::write_atomic(&out, md.as_bytes())?;
        // The same numbers for `tactile report`, beside the table.
        let ms: serde_json::Map<String, serde_json::Value> = rows_out
            .iter()
            .map(|(name, _, t1, _)| (name.clone(), serde_json::json!(t1 * 1e3)))
            .collect();
        tactile_core::io::write_json_atomic(
            out.with_extension("json"),
            &serde_json::json!([{
                "model": a.model.file_name().unwrap_or_default().to_string_lossy(),
                "metrics": { "reconstruction_bce": bce, "shape_accuracy": head_acc },
                "ms": ms,
            }]),
        )?;
    }
    Ok(())
}

#[derive(Args)]
pub struct BenchSynthArgs {
    /// Frames per measurement at default sizes (fewer at 1920x1080).
    #[arg(long, default_value_t = 64)]
    frames: usize,
    /// Also write the table to this Markdown file.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Median single-thread render time per frame over distinct samples.
fn median_render(n: usize, mut render: impl FnMut(usize)) -> f64 {
    let mut t: Vec<f64> = (0..n.max(1))
        .map(|i| {
            let s = std::time::Instant::now();
            render(i);
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// Frames/s of writing a whole dataset (render + PNG/NPY encode + disk), all threads.
fn write_rate(
    n: usize,
    write: impl Fn(&std::path::Path) -> tactile_core::Result<PathBuf>,
) -> Result<f64> {
    let dir = std::env::temp_dir().join(format!("tactile-bench-synth-{}", std::process::id()));
    let mut rates = Vec::new();
    for _ in 0..3 {
        let out = dir.join("ds");
        let s = std::time::Instant::now();
        write(&out)?;
        rates.push(n as f64 / s.elapsed().as_secs_f64());
        std::fs::remove_dir_all(&dir).ok();
    }
    rates.sort_by(f64::total_cmp);
    Ok(rates[1])
}

pub fn bench_synth(a: BenchSynthArgs) -> Result<()> {
    use datasets_synth::{TactipConfig, VisuotactileConfig, WriteOptions, tactip, visuotactile};
    let threads = rayon::current_num_threads();
    let opts = WriteOptions::default();
    let mut rows = Vec::new();
    let tc = TactipConfig::default();
    eprintln!("virtual TacTip 300x300");
    let t1 = median_render(a.frames, |i| {
        let _ = tactip::sample(&tc, 1, i as u64);
    });
    let w = write_rate(a.frames, |out| {
        datasets_synth::write_tactip(&tc, a.frames, 1, out, opts)
    })?;
    rows.push(("virtual TacTip", "300x300".to_string(), t1, w));
    for (wd, ht, n) in [
        (640u32, 360u32, a.frames),
        (1920, 1080, (a.frames / 8).max(3)),
    ] {
        eprintln!("virtual visuo-tactile {wd}x{ht}");
        let vc = VisuotactileConfig {
            width: wd,
            height: ht,
            ..Default::default()
        };
        let f = vc.frames_per_sequence;
        let t1 = median_render(n, |i| {
            let _ = visuotactile::sample(&vc, 1, (i / f) as u64, i % f);
        });
        let w = write_rate(n, |out| {
            datasets_synth::write_visuotactile(&vc, n, 1, out, opts)
        })?;
        rows.push(("virtual visuo-tactile", format!("{wd}x{ht}"), t1, w));
    }
    let mut md = format!(
        "Machine: {}\n\nRender: one frame with its labels in memory, one thread, median over distinct samples. \
         Write: a whole dataset to disk (render, PNG and NPY encoding, files) with {threads} rayon threads, median of 3 runs.\n\n\
         | sensor | size | render, 1 thread (ms/frame) | render, 1 thread (frames/s) | write, {threads} threads (frames/s) |\n|---|---|---|---|---|\n",
        Machine::detect().describe()
    );
    for (name, size, t1, w) in &rows {
        md.push_str(&format!(
            "| {name} | {size} | {:.1} | {:.1} | {:.1} |\n",
            t1 * 1e3,
            1.0 / t1,
            w
        ));
    }
    print!("{md}");
    if let Some(out) = a.out {
        tactile_core::io::write_atomic(&out, md.as_bytes())?;
    }
    Ok(())
}

/// Median latency at batch 1 and throughput at `batch` of an encoder on
/// every runtime: `(runtime, threads, seconds per batch-1 call, frames/s)`.
pub fn measure_encoder(
    model: &std::path::Path,
    pins: &PinSet,
    batch: usize,
    runs: usize,
) -> Result<Vec<(String, String, f64, f64)>> {
    let flex = DeviceKind::Flex.device();
    let (art, cae) = CaeArtifact::load(model, &flex)?;
    let px = art.cae.input_px;
    let idx1: Vec<usize> = vec![0];
    let idx_b: Vec<usize> = (0..batch).map(|i| i % pins.len()).collect();
    let flat = |idx: &[usize]| -> Vec<f32> {
        idx.iter()
            .flat_map(|&i| pins.images[i].pixels.clone())
            .collect()
    };
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    let mut rows_out = Vec::new();
    for kind in DeviceKind::ALL {
        let dev = kind.device();
        let (_, m) = CaeArtifact::load(model, &dev)?;
        let x1 = Tensor::<4>::from_data(TensorData::new(flat(&idx1), [1, 1, px, px]), &dev);
        let xb = Tensor::<4>::from_data(TensorData::new(flat(&idx_b), [batch, 1, px, px]), &dev);
        let t1 = median_seconds(5, runs, || {
            let _ = m.encoder.forward(x1.clone()).into_data();
        });
        let tb = median_seconds(2, runs.div_ceil(3).max(3), || {
            let _ = m.encoder.forward(xb.clone()).into_data();
        });
        rows_out.push((
            format!("burn {kind}"),
            format!("{threads} (rayon)"),
            t1,
            batch as f64 / tb,
        ));
    }
    let onnx = tactile_onnx::export_cae_encoder(&cae.encoder, px)?;
    match OrtModel::from_bytes(&onnx, threads) {
        Ok(mut ort) => {
            let d1 = flat(&idx1);
            let db = flat(&idx_b);
            let t1 = median_seconds(5, runs, || {
                let _ = ort.run_f32(&[1, 1, px, px], d1.clone());
            });
            let tb = median_seconds(2, runs.div_ceil(3).max(3), || {
                let _ = ort.run_f32(&[batch, 1, px, px], db.clone());
            });
            rows_out.push((
                "onnxruntime 1.31.1".into(),
                format!("{threads} (intra-op)"),
                t1,
                batch as f64 / tb,
            ));
        }
        Err(e) => eprintln!("onnxruntime skipped: {e}"),
    }
    Ok(rows_out)
}
