//! `tactile bench cae|synth|resolution|devices|detector|segmenter|depth`: speed against error.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Subcommand};
use tactile_bench::cae::{CaeBench, bench_cae};
use tactile_bench::models::{ModelBench, bench_depth, bench_detectors, bench_segmenters};
use tactile_bench::output::write_markdown_and_json;
use tactile_bench::own_sensor::OwnSensorBench;
use tactile_bench::pin_profile::PinProfileBench;

use crate::args::Paged;

#[derive(Subcommand)]
pub(crate) enum BenchCmd {
    /// The CAE encoder: latency and throughput per runtime, reconstruction and head accuracy.
    Cae(Paged<CaeBench>),
    /// The virtual sensors: frames/s rendered and written.
    Synth(SynthArgs),
    /// The palpation pipeline per stage at 640x360 against the sensor's
    /// native 1920x1080, and FFmpeg's 1080p H.264 decoding rate.
    Resolution(ResolutionArgs),
    /// The shipped paper B models at batch 1 on every device, as trained and
    /// with batch norms folded, beside onnxruntime.
    Devices(DevicesArgs),
    /// Frames of another sensor: flagged and tendon rates on fresh own
    /// frames and on frames that are not the sensor's.
    Ood(DevicesArgs),
    /// Frames of another sensor given to paper A's models: how many frames
    /// of each set each TacTip model's pin profile flags (what `predict`
    /// warns of).
    PinProfile(Paged<PinProfileBench>),
    /// Tendon detectors of a sweep: accuracy against latency per runtime.
    Detector(Paged<ModelBench>),
    /// Segmenters of a sweep: IoU and direction error against latency per runtime.
    Segmenter(Paged<ModelBench>),
    /// Depth networks of a sweep or ablation: MAE, SSIM against latency per runtime.
    Depth(Paged<ModelBench>),
    /// Edge pose on the real TacTip edge set: pose networks and encoders
    /// with estimators, error on their held-out frames against latency.
    Pose(Paged<ModelBench>),
    /// Surface pose and shear on the real 331-pin TacTip set: every target
    /// against the authors' CNN on their held-out split, interval coverage,
    /// latency, errors, gains and intervals by tap depth (beside an estimate
    /// that reads no frame, each target's `train` median), how alike each model's
    /// errors are to the first model's, and the first model's predictions
    /// plotted against the truth.
    Surface(Paged<ModelBench>),
    /// One encoder for many tasks: every encoder on every task of a list
    /// (configs/bench/shared-encoder.json), an MLP per task, beside each
    /// task's own encoder.
    SharedEncoder(Paged<tactile_bench::shared::SharedEncoderBench>),
    /// Ball-press calibration: sensor models cross-validated by press
    /// (lookup table, per-pixel MLP, the toolkit's networks), speed and
    /// robustness; writes docs/calibration.md.
    Calibration(CalibrationArgs),
    /// A calibrated sensor's own pipeline (scripts/own-sensor.sh trains it):
    /// held-out renders, the real ball presses, frames of other sensors and
    /// the loop's times; writes docs/own-sensor.md.
    OwnSensor(OwnSensorArgs),
}

#[derive(Args)]
pub(crate) struct OwnSensorArgs {
    #[command(flatten)]
    bench: OwnSensorBench,
    /// The page; its numbers (JSON) go beside it.
    #[arg(long, default_value = "docs/own-sensor.md")]
    out: PathBuf,
}

#[derive(Args)]
pub(crate) struct CalibrationArgs {
    #[command(flatten)]
    bench: tactile_bench::calibration::CalibrationRequest,
    /// The page; its plots and numbers (JSON) go beside it.
    #[arg(long, default_value = "docs/calibration.md")]
    out: PathBuf,
}

#[derive(Args)]
pub(crate) struct DevicesArgs {
    /// Folder with detector/, segmenter/ and depth/.
    #[arg(long, default_value = "models")]
    models: PathBuf,
    /// Timed runs per measurement (median reported).
    #[arg(long, default_value_t = 200, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    runs: u32,
    /// Also write the table to this Markdown file (its rows as JSON beside it).
    #[arg(long)]
    out: Option<PathBuf>,
}

#[derive(Args)]
pub(crate) struct ResolutionArgs {
    /// Folder with detector/, segmenter/ and depth/.
    #[arg(long, default_value = "models")]
    models: PathBuf,
    /// Where the networks run.
    #[arg(long, value_enum, default_value_t = tactile_burn::Runtime::Onnx)]
    runtime: tactile_burn::Runtime,
    /// Tendon frames rendered per size.
    #[arg(long, default_value_t = 24, value_parser = clap::value_parser!(u16).range(1..=1000))]
    frames: u16,
    /// Timed passes over the frames.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u16).range(1..=1000))]
    repeats: u16,
    /// Also write the table to this Markdown file (its rows as JSON beside it).
    #[arg(long)]
    out: Option<PathBuf>,
}

#[derive(Args)]
pub(crate) struct SynthArgs {
    /// Frames per measurement at default sizes (fewer at 1920x1080).
    #[arg(long, default_value_t = 64)]
    frames: usize,
    /// Also measure the renderer of this calibrated sensor (a folder of
    /// `tactile calibrate ball`, e.g. models/gelsight-r15), with the scene
    /// mix of `tactile synth gelsight`'s defaults.
    #[arg(long, value_name = "DIR")]
    sensor: Option<PathBuf>,
    /// Also write the table to this Markdown file.
    #[arg(long)]
    out: Option<PathBuf>,
}

pub(crate) fn main(cmd: BenchCmd) -> Result<()> {
    let out = match &cmd {
        BenchCmd::Cae(a) => &a.out,
        BenchCmd::Synth(a) => &a.out,
        BenchCmd::Resolution(a) => &a.out,
        BenchCmd::Devices(a) | BenchCmd::Ood(a) => &a.out,
        BenchCmd::Detector(a)
        | BenchCmd::Segmenter(a)
        | BenchCmd::Depth(a)
        | BenchCmd::Pose(a)
        | BenchCmd::Surface(a) => &a.out,
        BenchCmd::SharedEncoder(a) => &a.out,
        BenchCmd::PinProfile(a) => &a.out,
        BenchCmd::Calibration(a) => &Some(a.out.clone()),
        BenchCmd::OwnSensor(a) => &Some(a.out.clone()),
    };
    if let Some(out) = out {
        tactile_bench::output::check_page(out, &[])?;
    }
    match cmd {
        BenchCmd::Cae(a) => {
            let r = bench_cae(&a.bench)?;
            say_raw!("{}", r.markdown);
            if let Some(out) = &a.out {
                r.write(out)?;
            }
        }
        BenchCmd::Synth(a) => {
            let md = tactile_bench::synth::bench_synth(a.frames, a.sensor.as_deref())?;
            say_raw!("{md}");
            if let Some(out) = &a.out {
                tactile_core::io::write_atomic(out, md.as_bytes())?;
            }
        }
        BenchCmd::PinProfile(a) => {
            let rows = tactile_bench::pin_profile::bench_pin_profiles(&a.bench)?;
            let md = tactile_bench::pin_profile::pin_profile_markdown(&rows, &a.bench);
            say_raw!("{md}");
            if let Some(out) = &a.out {
                write_markdown_and_json(out, &md, &rows)?;
            }
        }
        BenchCmd::Ood(a) => {
            let r = tactile_bench::ood::bench_ood(&a.models, tactile_burn::Runtime::Onnx)?;
            let md = tactile_bench::ood::ood_markdown(&r);
            say_raw!("{md}");
            if let Some(out) = &a.out {
                write_markdown_and_json(out, &md, &r.rows)?;
            }
        }
        BenchCmd::Devices(a) => {
            let rows = tactile_bench::devices::bench_devices(&a.models, a.runs as usize)?;
            let probes = tactile_bench::devices::conv_probes(a.runs as usize)?;
            let md = tactile_bench::devices::devices_markdown(&rows, &probes, a.runs as usize);
            say_raw!("{md}");
            if let Some(out) = &a.out {
                let json = serde_json::json!({"models": rows, "convolutions": probes});
                write_markdown_and_json(out, &md, &json)?;
            }
        }
        BenchCmd::Resolution(a) => {
            let r = tactile_bench::resolution::bench_resolution(
                &a.models,
                a.runtime,
                &[(640, 360), (1920, 1080)],
                a.frames as usize,
                a.repeats as usize,
            )?;
            let md = r.markdown();
            say_raw!("{md}");
            if let Some(out) = &a.out {
                write_markdown_and_json(out, &md, &r)?;
            }
        }
        BenchCmd::Detector(a) => show(a, bench_detectors)?,
        BenchCmd::Segmenter(a) => show(a, bench_segmenters)?,
        BenchCmd::Depth(a) => show(a, bench_depth)?,
        BenchCmd::Pose(a) => show(a, tactile_bench::pose::bench_pose)?,
        BenchCmd::SharedEncoder(a) => {
            let (cells, md) = a.bench.run()?;
            say_raw!("{md}");
            if let Some(out) = &a.out {
                write_markdown_and_json(out, &md, &cells)?;
            }
        }
        BenchCmd::Surface(a) => {
            let t = tactile_bench::surface::bench_surface(&a.bench, a.out.as_deref())?;
            say_raw!("{}", t.markdown);
            if let Some(out) = &a.out {
                t.write(out)?;
            }
        }
        BenchCmd::OwnSensor(a) => {
            let r = tactile_bench::own_sensor::bench_own_sensor(&a.bench)?;
            let command: Vec<String> = std::env::args().skip(1).collect();
            let md = r.write(&a.bench, &format!("tactile {}", command.join(" ")), &a.out)?;
            say_raw!("{md}");
        }
        BenchCmd::Calibration(a) => {
            let b = a.bench.bench()?;
            let r = tactile_bench::calibration::bench_calibration(&b)?;
            let command: Vec<String> = std::env::args().skip(1).collect();
            let md = r.write(&b, &format!("tactile {}", command.join(" ")), &a.out)?;
            say_raw!("{md}");
        }
    }
    Ok(())
}

/// Run a model bench, print its table and write it (with plot and rows) to `out`.
fn show<M: serde::Serialize>(
    a: Paged<ModelBench>,
    bench: fn(&ModelBench) -> tactile_bench::Result<tactile_bench::output::Table<M>>,
) -> Result<()> {
    let t = bench(&a.bench)?;
    say_raw!("{}", t.markdown);
    if let Some(out) = &a.out {
        t.write(out)?;
    }
    Ok(())
}
