//! `tactile`: the command-line face of tactile-rs. Each verb's module
//! parses its arguments, calls the library and prints; none holds logic.

/// `println!` to stdout that ends the program quietly when stdout is
/// closed (`tactile run ... | head -1`), instead of panicking. What it
/// quotes of a file is shown `tactile_core::printable`.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let text = format!($($arg)*);
        let mut out = std::io::stdout().lock();
        if let Err(e) = writeln!(out, "{}", tactile_core::printable(&text)).and_then(|_| out.flush()) {
            $crate::stdout_failed(e);
        }
    }};
}

/// [`say!`] without the newline.
macro_rules! say_raw {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let text = format!($($arg)*);
        let mut out = std::io::stdout().lock();
        if let Err(e) = write!(out, "{}", tactile_core::printable(&text)).and_then(|_| out.flush()) {
            $crate::stdout_failed(e);
        }
    }};
}

mod args;
mod bench;
mod calibrate;
mod compare;
mod dataset;
mod demo;
mod encode;
mod eval;
mod evaluate;
mod export;
mod perceive;
mod report;
mod robustness;
mod run;
mod sweep;
mod synth;
mod train;

use std::ffi::OsString;

use anyhow::Result;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

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

#[derive(Subcommand)]
enum Command {
    /// Generate a synthetic dataset from a virtual sensor (sensors.md).
    #[command(subcommand)]
    Synth(synth::SynthCmd),
    /// Make a dataset of your own sensor's frames (docs/datasets.md).
    #[command(subcommand)]
    Dataset(dataset::DatasetCmd),
    /// Train a model.
    #[command(subcommand)]
    Train(train::TrainCmd),
    /// Encode every frame of a TacTip dataset to a feature CSV.
    Encode(encode::EncodeArgs),
    /// Paper A's feature-count search: error and latency per trained encoder, table and plots.
    Sweep(sweep::SweepArgs),
    /// Compare feature sets (CAE, PCA, raw pixels, pin tracking) x estimators on one split.
    Compare(compare::CompareArgs),
    /// Run several estimators on one encoding per frame (paper A's simultaneous deployment); `predict --model DIR` is the same.
    #[command(visible_alias = "predict")]
    Perceive(perceive::PerceiveArgs),
    /// Score every estimator of an encoder, or every target of a pose network, on a labelled dataset: accuracy per class, errors per shape.
    Evaluate(evaluate::EvaluateArgs),
    /// Estimator errors when test frames get more noise, an illumination gradient, a light blob or a rotation.
    Robustness(robustness::RobustnessArgs),
    /// Score a paper B model on a visuo-tactile dataset (last line: JSON metrics).
    #[command(subcommand)]
    Eval(eval::EvalCmd),
    /// Paper B's palpation pipeline over frames: detect, then segment, point and reconstruct depth on tendon frames.
    Run(run::RunArgs),
    /// Regenerate docs/results.md: every shipped model's speed against its error, and the pipeline's.
    Report(tactile_bench::report::Report),
    /// Export a model to ONNX.
    Export(export::ExportArgs),
    /// Benchmark models: latency per runtime against error.
    #[command(subcommand)]
    Bench(bench::BenchCmd),
    /// Calibrate a real sensor (a GelSight-like one from ball presses).
    #[command(subcommand)]
    Calibrate(calibrate::CalibrateCmd),
    /// Reconstruct a calibrated GelSight-like sensor's skin: the indentation (metres) under every frame, as .npy, with pictures.
    Reconstruct(calibrate::ReconstructArgs),
    /// Classify frames with the shipped encoder and shape head, printing features.
    Demo(demo::DemoArgs),
}

/// Stdout is gone: a closed pipe ends the run quietly; anything else
/// (a full disk) is said on stderr.
pub(crate) fn stdout_failed(e: std::io::Error) {
    if e.kind() != std::io::ErrorKind::BrokenPipe {
        tactile_core::note!("error: cannot write to standard output: {e}");
        std::process::exit(1);
    }
    std::process::exit(0);
}

/// Parse the command line (`tactile ...`, program name first).
fn parse(
    args: impl IntoIterator<Item = OsString>,
) -> std::result::Result<clap::ArgMatches, clap::Error> {
    Cli::command().try_get_matches_from(
        tactile_burn::options::command_line::attach_negative_values(args),
    )
}

fn main() -> std::process::ExitCode {
    let matches = parse(std::env::args_os()).unwrap_or_else(|e| e.exit());
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    args::keep_matches(matches);
    if let Err(e) = tactile_core::interrupt::install() {
        tactile_core::note!("warning: {e}");
    }
    match dispatch(cli.command) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        // Ctrl-C or SIGTERM: the work stopped cleanly, nothing partial kept.
        Err(_) if tactile_core::interrupt::requested() => {
            tactile_core::note!("interrupted: stopped, nothing partial was kept");
            std::process::ExitCode::from(130)
        }
        Err(e) => {
            tactile_core::note!("Error: {}", describe(&e));
            std::process::ExitCode::FAILURE
        }
    }
}

/// The error and each cause it does not already say (a file error names
/// what the system said in its own words: "x: Not a directory (os error
/// 20)", not that twice).
fn describe(e: &anyhow::Error) -> String {
    let mut message = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !message.contains(&cause) {
            message = format!("{message}: {cause}");
        }
    }
    message
}

fn dispatch(command: Command) -> Result<()> {
    match command {
        Command::Synth(c) => synth::main(c),
        Command::Dataset(c) => dataset::main(c),
        Command::Train(c) => train::main(c),
        Command::Encode(a) => encode::main(a),
        Command::Sweep(a) => sweep::main(a),
        Command::Compare(a) => compare::main(a),
        Command::Perceive(a) => perceive::main(a),
        Command::Evaluate(a) => evaluate::main(a),
        Command::Robustness(a) => robustness::main(a),
        Command::Eval(c) => eval::main(c),
        Command::Run(a) => run::main(a),
        Command::Report(a) => report::main(a),
        Command::Export(a) => export::main(a),
        Command::Bench(c) => bench::main(c),
        Command::Demo(a) => demo::main(a),
        Command::Calibrate(c) => calibrate::main(c),
        Command::Reconstruct(a) => calibrate::reconstruct(a),
    }
}

#[cfg(test)]
mod tests {
    use std::ffi::OsString;
    use std::path::PathBuf;

    use clap::CommandFactory;

    use super::Cli;

    #[test]
    fn every_flag_has_help() {
        fn walk(cmd: &clap::Command, path: &str) {
            for arg in cmd.get_arguments() {
                let id = arg.get_id().as_str();
                if id == "help" || id == "version" {
                    continue;
                }
                assert!(arg.get_help().is_some(), "{path} --{id} has no help");
            }
            for sub in cmd.get_subcommands() {
                walk(sub, &format!("{path} {}", sub.get_name()));
            }
        }
        let cmd = Cli::command();
        cmd.clone().debug_assert();
        walk(&cmd, "tactile");
    }

    /// Ranges and numbers below zero are taken as the help shows them
    /// (`[default: -6,6]`), not as unknown flags.
    #[test]
    fn negative_values_are_values() {
        use tactile_core::rng::Range;
        let parse = |line: &str| super::parse(line.split_whitespace().map(OsString::from));
        let m = parse(
            "tactile synth tactip --out o --count 3 --x-mm -6,6 --gradient -0.25,0.25 --theta-deg -90",
        )
        .unwrap();
        let t = m.subcommand_matches("synth").unwrap();
        let t = t.subcommand_matches("tactip").unwrap();
        assert_eq!(t.get_one::<Range>("x_mm"), Some(&Range::new(-6.0, 6.0)));
        assert_eq!(
            t.get_one::<Range>("gradient"),
            Some(&Range::new(-0.25, 0.25))
        );
        assert_eq!(t.get_one::<Range>("theta_deg"), Some(&Range::fixed(-90.0)));
        // A negative number reaches the flag's own check, which names it.
        let e = parse("tactile run --view-wait -1").unwrap_err().to_string();
        assert!(
            e.contains("seconds must be a finite number >= 0, got -1"),
            "{e}"
        );
        // A size is for raw frames on stdin: with --data it would be
        // ignored, so the two are refused together.
        let e = parse("tactile run --data frames --size 640x480")
            .unwrap_err()
            .to_string();
        assert!(e.contains("cannot be used with"), "{e}");
        assert!(parse("tactile run --stdin --size 640x480").is_ok());
        // A numeric list below zero reaches its own check (the run's
        // hysteresis refuses it), and a count below zero its parser, which
        // names the flag. Before, both were "unexpected argument '-0' found".
        let m = parse("tactile run --data d --out o --hysteresis -0.5,0.3").unwrap();
        let r = m.subcommand_matches("run").unwrap();
        let on_off: Vec<f32> = r.get_many("hysteresis").unwrap().copied().collect();
        assert_eq!(on_off, [-0.5, 0.3]);
        let e = parse("tactile synth tactip --out o --seed -1")
            .unwrap_err()
            .to_string();
        assert!(e.contains("'-1' for '--seed"), "{e}");
        let m =
            parse("tactile compare --encoder e --data d --targets x_mm --hidden 64,32 --hidden 16")
                .unwrap();
        let c = m.subcommand_matches("compare").unwrap();
        let hidden: Vec<usize> = c.get_many("hidden").unwrap().copied().collect();
        assert_eq!(hidden, [64, 32, 16]);
        // A list given no value is an error naming it, not the next flag;
        // a file name starting with a minus is a value too, and so is
        // anything after `--`.
        let e = parse("tactile run --data d --hysteresis --out o")
            .unwrap_err()
            .to_string();
        assert!(e.contains("a value is required for '--hysteresis"), "{e}");
        let m = parse("tactile run --data d --out -1.jsonl").unwrap();
        let r = m.subcommand_matches("run").unwrap();
        assert_eq!(
            r.get_one::<PathBuf>("out"),
            Some(&PathBuf::from("-1.jsonl"))
        );
        // A range given no value is still an error, not a silent default.
        assert!(parse("tactile synth tactip --out o --x-mm --y-mm 1,2").is_err());
        assert!(parse("tactile synth tactip --out o --count 3 --x-mm").is_err());
    }

    /// Every `tactile ...` line of the README's command list parses.
    #[test]
    fn the_readme_synopsis_parses() {
        let readme = include_str!("../../../README.md");
        // Paths in the synopsis are relative to the repository.
        std::env::set_current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).unwrap();
        let section = readme
            .split("## Commands")
            .nth(1)
            .and_then(|s| s.split("\n## ").next())
            .expect("a Commands section in the README");
        let mut n = 0;
        for line in section
            .lines()
            .map(str::trim)
            .filter(|l| l.starts_with("tactile "))
        {
            let words: Vec<&str> = line.split_whitespace().collect();
            if let Err(e) = super::parse(words.iter().map(OsString::from)) {
                panic!("README: `{line}` does not parse:\n{e}");
            }
            n += 1;
        }
        assert!(n >= 20, "only {n} commands in the README synopsis");
    }
}
