//! `tactile`: the command-line face of tactile-rs.

mod bench;
mod bench_b;
mod cae_cmds;
mod depth_cmds;
mod detect_cmds;
mod estimate_cmds;
mod eval_cmds;
mod report_cmd;
mod run_cmd;
mod segment_cmds;
mod sweep;
mod synth_cmds;

use std::path::PathBuf;

use anyhow::Result;
use clap::{Parser, Subcommand};
use tactile_core::DeviceKind;

#[derive(Parser)]
#[command(
    name = "tactile",
    version,
    about = "Vision-based tactile sensing: TacTip features, tendon perception, depth"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// `--device ndarray|flex`.
pub fn parse_device(s: &str) -> std::result::Result<DeviceKind, String> {
    s.parse().map_err(|e: tactile_core::Error| e.to_string())
}

#[derive(Subcommand)]
enum Command {
    /// Generate a synthetic dataset from a virtual sensor (sensors.md).
    Synth {
        #[command(subcommand)]
        sensor: SynthCmd,
    },
    /// Train a model.
    Train {
        #[command(subcommand)]
        model: TrainCmd,
    },
    /// Encode every frame of a TacTip dataset to a feature CSV.
    Encode {
        /// Model folder (cae.json + cae.bpk).
        #[arg(long)]
        model: PathBuf,
        /// Dataset folder.
        #[arg(long)]
        data: PathBuf,
        /// Output CSV (file,f0,f1,...).
        #[arg(long)]
        out: PathBuf,
        #[arg(long, default_value = "flex", value_parser = parse_device)]
        device: DeviceKind,
    },
    /// Paper A's feature-count search: error and latency per trained encoder, table and plots.
    Sweep(sweep::SweepArgs),
    /// Compare feature sets (CAE, PCA, raw pixels) x estimators (MLP, ridge, k-NN) on one split.
    Compare(estimate_cmds::CompareArgs),
    /// Run several estimators on one encoding per frame (paper A's simultaneous deployment).
    Perceive(estimate_cmds::PerceiveArgs),
    /// Score every estimator of an encoder on a labelled dataset: accuracy per class, errors per shape.
    Evaluate(eval_cmds::EvaluateArgs),
    /// Estimator errors when test frames get more noise, an illumination gradient, a light blob or a rotation.
    Robustness(eval_cmds::RobustnessArgs),
    /// Score a paper B model on a visuo-tactile dataset (last line: JSON metrics).
    Eval {
        #[command(subcommand)]
        model: EvalCmd,
    },
    /// Paper B's palpation pipeline over frames: detect, then segment, point and reconstruct depth on tendon frames.
    Run(run_cmd::RunArgs),
    /// Regenerate docs/results.md: every shipped model's speed against its error, and the pipeline's.
    Report(report_cmd::ReportArgs),
    /// Export a model to ONNX.
    Export {
        /// Model folder.
        #[arg(long)]
        model: PathBuf,
        /// Output .onnx file.
        #[arg(long)]
        out: PathBuf,
        /// `encoder` (pin image -> features) or `autoencoder` (pin image -> reconstruction).
        #[arg(long, default_value = "encoder")]
        part: String,
    },
    /// Benchmark a model: latency and throughput per runtime, against its error.
    Bench {
        #[command(subcommand)]
        model: BenchCmd,
    },
    /// Classify frames with the shipped encoder and shape head, printing features.
    Demo {
        /// Model folder with cae.json/cae.bpk and head/ (also shipped:
        /// models/cae-shapes, trained on the real shapes set).
        #[arg(long, default_value = "models/cae-synth")]
        model: PathBuf,
        /// A TacTip dataset; the demo uses its `test` split (or all frames).
        /// The default is shipped: virtual TacTip frames of a held-out seed.
        #[arg(long, default_value = "samples/virtual-tactip")]
        data: PathBuf,
        /// Frames per class to show.
        #[arg(long, default_value_t = 2)]
        per_class: usize,
    },
}

#[derive(Subcommand)]
enum SynthCmd {
    /// Virtual TacTip frames (paper A): shapes, position, orientation, depth, force.
    Tactip(synth_cmds::TactipArgs),
    /// Virtual visuo-tactile palpation videos (paper B): RGB, masks, directions, depth.
    Visuotactile(synth_cmds::VisuotactileArgs),
}

#[derive(Subcommand)]
enum TrainCmd {
    /// Paper A's convolutional autoencoder.
    Cae(cae_cmds::TrainCaeArgs),
    /// A shallow shape classifier on the features of a trained encoder.
    Head(cae_cmds::TrainHeadArgs),
    /// A regressor (pose, depth, force; angles on the circle) on features.
    Regressor(estimate_cmds::TrainRegressorArgs),
    /// Paper B's tendon detector on visuo-tactile frames.
    Detector(detect_cmds::TrainDetectorArgs),
    /// Paper B's U-Net tendon segmenter on visuo-tactile tendon frames.
    Segmenter(segment_cmds::TrainSegmenterArgs),
    /// Paper B's depth U-Net with a DenseNet encoder.
    Depth(depth_cmds::TrainDepthArgs),
}

#[derive(Subcommand)]
enum EvalCmd {
    /// Tendon detector: accuracy, precision, recall, F1, onset/release frames.
    Detector(detect_cmds::EvalDetectorArgs),
    /// Tendon segmenter: IoU per tendon path, direction error of the post-processed mask.
    Segmenter(segment_cmds::EvalSegmenterArgs),
    /// Depth network: MAE (window, tendon mask), RMSE, SSIM; optional heat maps.
    Depth(depth_cmds::EvalDepthArgs),
}

#[derive(Subcommand)]
enum BenchCmd {
    /// The CAE encoder.
    Cae(bench::BenchCaeArgs),
    /// The virtual sensors: frames/s rendered and written.
    Synth(bench::BenchSynthArgs),
    /// Tendon detectors of a sweep: accuracy against latency per runtime.
    Detector(bench_b::BenchModelsArgs),
    /// Segmenters of a sweep: IoU and direction error against latency per runtime.
    Segmenter(bench_b::BenchModelsArgs),
    /// Depth networks of a sweep or ablation: MAE, SSIM against latency per runtime.
    Depth(bench_b::BenchModelsArgs),
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Synth {
            sensor: SynthCmd::Tactip(a),
        } => synth_cmds::tactip(a),
        Command::Synth {
            sensor: SynthCmd::Visuotactile(a),
        } => synth_cmds::visuotactile(a),
        Command::Train {
            model: TrainCmd::Cae(a),
        } => cae_cmds::train_cae(a),
        Command::Train {
            model: TrainCmd::Head(a),
        } => cae_cmds::train_head(a),
        Command::Train {
            model: TrainCmd::Regressor(a),
        } => estimate_cmds::train_regressor(a),
        Command::Train {
            model: TrainCmd::Detector(a),
        } => detect_cmds::train(a),
        Command::Eval {
            model: EvalCmd::Detector(a),
        } => detect_cmds::eval(a),
        Command::Train {
            model: TrainCmd::Segmenter(a),
        } => segment_cmds::train(a),
        Command::Eval {
            model: EvalCmd::Segmenter(a),
        } => segment_cmds::eval(a),
        Command::Train {
            model: TrainCmd::Depth(a),
        } => depth_cmds::train(a),
        Command::Eval {
            model: EvalCmd::Depth(a),
        } => depth_cmds::eval(a),
        Command::Encode {
            model,
            data,
            out,
            device,
        } => cae_cmds::encode(&model, &data, &out, device),
        Command::Perceive(a) => estimate_cmds::perceive(a),
        Command::Evaluate(a) => eval_cmds::evaluate(a),
        Command::Run(a) => run_cmd::run(a),
        Command::Report(a) => report_cmd::report(a),
        Command::Robustness(a) => eval_cmds::robustness(a),
        Command::Compare(a) => estimate_cmds::compare(a),
        Command::Sweep(a) => sweep::sweep(a),
        Command::Export { model, out, part } => cae_cmds::export(&model, &out, &part),
        Command::Bench {
            model: BenchCmd::Cae(a),
        } => bench::bench_cae(a),
        Command::Bench {
            model: BenchCmd::Synth(a),
        } => bench::bench_synth(a),
        Command::Bench {
            model: BenchCmd::Detector(a),
        } => bench_b::bench_detector(a),
        Command::Bench {
            model: BenchCmd::Segmenter(a),
        } => bench_b::bench_segmenter(a),
        Command::Bench {
            model: BenchCmd::Depth(a),
        } => bench_b::bench_depth(a),
        Command::Demo {
            model,
            data,
            per_class,
        } => cae_cmds::demo(&model, &data, per_class),
    }
}
