//! `tactile sweep`: paper A's search over the feature count. For each
//! trained encoder: reconstruction error and shape accuracy on the test
//! split, and encoder latency on every runtime; a Markdown table and two
//! plots (error against features, error against latency).

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use tactile_cae::CaeArtifact;
use tactile_cae::data::PinSet;
use tactile_cae::encode::encode_all;
use tactile_cae::head::{ClassifierHead, HeadConfig};
use tactile_core::DeviceKind;
use tactile_core::dataset::Dataset;
use tactile_core::metrics::accuracy;
use tactile_core::nn::bce_with_logits;
use tactile_core::plot::{Series, line_plot};

use crate::bench::measure_encoder;
use crate::estimate_cmds::three_way_split;

#[derive(Args)]
pub struct SweepArgs {
    /// Trained encoders to compare (e.g. 8, 16, 32 and 64 features).
    #[arg(long, num_args = 1.., required = true)]
    encoders: Vec<PathBuf>,
    /// Dataset with a class column (its split column when present).
    #[arg(long)]
    data: PathBuf,
    /// Class column for the accuracy.
    #[arg(long, default_value = "shape")]
    classify: String,
    #[arg(long, default_value_t = 7)]
    seed: u64,
    /// Timed runs per latency measurement.
    #[arg(long, default_value_t = 30)]
    runs: usize,
    /// Markdown table; the plots go beside it (`NAME-features.png`, `NAME-latency.png`).
    #[arg(long)]
    out: Option<PathBuf>,
}

struct Row {
    name: String,
    features: usize,
    bce: f64,
    accuracy: f64,
    /// (runtime, ms at batch 1, frames/s at batch 256).
    speed: Vec<(String, f64, f64)>,
}

pub fn sweep(a: SweepArgs) -> Result<()> {
    let ds = Dataset::open(&a.data)?;
    let (mut train, val, test) = three_way_split(&ds, 0.2, 0.2, a.seed)?;
    train.extend(val);
    let names: Vec<String> = (0..ds.len())
        .map(|i| ds.text(i, &a.classify).map(str::to_string))
        .collect::<Result<_, _>>()?;
    let mut classes = names.clone();
    classes.sort();
    classes.dedup();
    if classes.len() < 2 {
        bail!(
            "{}: column '{}' has fewer than 2 classes",
            a.data.display(),
            a.classify
        );
    }
    let y: Vec<usize> = names
        .iter()
        .map(|n| classes.iter().position(|c| c == n).unwrap_or(0))
        .collect();
    let dev = DeviceKind::Flex.device();
    let mut rows = Vec::new();
    for enc in &a.encoders {
        eprintln!("{}", enc.display());
        let (art, cae) = CaeArtifact::load(enc, &dev)?;
        let pins = PinSet::from_dataset(&ds, &art.preprocess)?;
        let feats = encode_all(&cae.encoder, &pins, 256, &dev)?;
        let mut bce = 0.0;
        for c in test.chunks(256) {
            let x = pins.batch(c, &dev);
            let l: f32 = bce_with_logits(cae.forward_logits(x.clone()), x).into_scalar();
            bce += l as f64 * c.len() as f64;
        }
        bce /= test.len() as f64;
        let pick = |idx: &[usize]| -> (Vec<Vec<f32>>, Vec<usize>) {
            (
                idx.iter().map(|&i| feats[i].clone()).collect(),
                idx.iter().map(|&i| y[i]).collect(),
            )
        };
        let (tx, ty) = pick(&train);
        let (sx, sy) = pick(&test);
        let cfg = HeadConfig::new(tx[0].len(), classes.clone())
            .with_seed(a.seed)
            .with_repeats(1);
        let head = ClassifierHead::train(cfg, &tx, &ty, &dev)?;
        let acc = accuracy(&head.predict(&sx, &dev)?, &sy);
        let speed = measure_encoder(enc, &pins, 256, a.runs)?
            .into_iter()
            .map(|(rt, _, t1, fps)| (rt, t1 * 1e3, fps))
            .collect();
        rows.push(Row {
            name: enc
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            features: art.cae.feature_count(),
            bce,
            accuracy: acc,
            speed,
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
        a.data.display(),
        train.len(),
        test.len(),
        a.classify,
        runtimes
            .iter()
            .map(|r| format!("{r} ms, frames/s"))
            .collect::<Vec<_>>()
            .join(" | "),
        "---|".repeat(runtimes.len())
    );
    for r in &rows {
        md.push_str(&format!(
            "| {} | {} | {:.4} | {:.1} % | {} |\n",
            r.name,
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
    print!("{md}");
    if let Some(out) = &a.out {
        tactile_core::io::write_atomic(out, md.as_bytes())?;
        let stem = out.with_extension("");
        let err = |r: &Row| 100.0 * (1.0 - r.accuracy);
        line_plot(
            stem.with_file_name(format!(
                "{}-features.png",
                stem.file_name().unwrap_or_default().to_string_lossy()
            )),
            "Test error against feature count",
            "features",
            "error (%) / test BCE x 100",
            &[
                Series {
                    name: format!("{} error (%)", a.classify),
                    points: rows.iter().map(|r| (r.features as f64, err(r))).collect(),
                },
                Series {
                    name: "reconstruction BCE x 100".into(),
                    points: rows
                        .iter()
                        .map(|r| (r.features as f64, 100.0 * r.bce))
                        .collect(),
                },
            ],
            false,
        )?;
        let series: Vec<Series> = runtimes
            .iter()
            .enumerate()
            .map(|(k, rt)| Series {
                name: rt.clone(),
                points: rows.iter().map(|r| (r.speed[k].1, err(r))).collect(),
            })
            .collect();
        line_plot(
            stem.with_file_name(format!(
                "{}-latency.png",
                stem.file_name().unwrap_or_default().to_string_lossy()
            )),
            "Test error against encoder latency (batch 1)",
            "latency (ms)",
            "error (%)",
            &series,
            false,
        )?;
        println!("table and plots written beside {}", out.display());
    }
    Ok(())
}
