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
    let px = art.cae.input_px;
    let idx1: Vec<usize> = vec![0];
    let idx_b: Vec<usize> = (0..a.batch).map(|i| i % pins.len()).collect();
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
        let (_, m) = CaeArtifact::load(&a.model, &dev)?;
        let x1 = Tensor::<4>::from_data(TensorData::new(flat(&idx1), [1, 1, px, px]), &dev);
        let xb = Tensor::<4>::from_data(TensorData::new(flat(&idx_b), [a.batch, 1, px, px]), &dev);
        let t1 = median_seconds(5, a.runs, || {
            let _ = m.encoder.forward(x1.clone()).into_data();
        });
        let tb = median_seconds(2, a.runs.div_ceil(3).max(3), || {
            let _ = m.encoder.forward(xb.clone()).into_data();
        });
        rows_out.push((
            format!("burn {kind}"),
            format!("{threads} (rayon)"),
            t1,
            a.batch as f64 / tb,
        ));
    }
    let onnx = tactile_onnx::export_cae_encoder(&cae.encoder, px)?;
    match OrtModel::from_bytes(&onnx, threads) {
        Ok(mut ort) => {
            let d1 = flat(&idx1);
            let db = flat(&idx_b);
            let t1 = median_seconds(5, a.runs, || {
                let _ = ort.run_f32(&[1, 1, px, px], d1.clone());
            });
            let tb = median_seconds(2, a.runs.div_ceil(3).max(3), || {
                let _ = ort.run_f32(&[a.batch, 1, px, px], db.clone());
            });
            rows_out.push((
                "onnxruntime 1.31.1".into(),
                format!("{threads} (intra-op)"),
                t1,
                a.batch as f64 / tb,
            ));
        }
        Err(e) => eprintln!("onnxruntime skipped: {e}"),
    }
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
    }
    Ok(())
}
