//! `tactile report`: regenerates `docs/results.md` from the shipped models,
//! freshly generated held-out synthetic data and the real TacTip shapes
//! set, by running the project's own `bench`, `eval` and `run` commands and
//! collecting their tables. No number in the page is typed by hand.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};
use clap::Args;

#[derive(Args)]
pub struct ReportArgs {
    /// The real TacTip data (`polic-shapes` inside).
    #[arg(long, default_value = "../shared/real")]
    real: PathBuf,
    /// Shipped models.
    #[arg(long, default_value = "models")]
    models: PathBuf,
    /// Where held-out synthetic sets are generated (kept for reuse).
    #[arg(long, default_value = "data/report")]
    work: PathBuf,
    /// The page; its tables and plots go into a folder beside it.
    #[arg(long, default_value = "docs/results.md")]
    out: PathBuf,
}

/// Run this binary with `args`; its stdout, or an error with its stderr.
fn tactile(args: &[&str]) -> Result<String> {
    let exe = std::env::current_exe().context("locating the tactile binary")?;
    eprintln!(">> tactile {}", args.join(" "));
    let out = Command::new(exe).args(args).output()?;
    if !out.status.success() {
        bail!(
            "`tactile {}` failed: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap_or_default()
}

/// The Markdown of a generated table, without its machine line, its
/// images linked from the page's folder (`prefix/`).
fn body(path: &Path, prefix: &str) -> Result<String> {
    let t = std::fs::read_to_string(path).with_context(|| path.display().to_string())?;
    Ok(t.lines()
        .filter(|l| !l.starts_with("Machine:"))
        .map(|l| l.replace("](", &format!("]({prefix}/")))
        .collect::<Vec<_>>()
        .join("\n"))
}

pub fn report(a: ReportArgs) -> Result<()> {
    let dir = a.out.with_extension("");
    tactile_core::io::create_dir_all(&dir)?;
    tactile_core::io::create_dir_all(&a.work)?;
    // Held-out synthetic sets: seeds no model was trained or chosen on.
    let test = a.work.join("vt-test");
    let extreme = a.work.join("vt-extreme");
    if !test.join("labels.csv").is_file() {
        tactile(&[
            "synth",
            "visuotactile",
            "--sequences",
            "40",
            "--frames-per-sequence",
            "25",
            "--seed",
            "200",
            "--out",
            s(&test),
            "--force",
        ])?;
    }
    if !extreme.join("labels.csv").is_file() {
        tactile(&[
            "synth",
            "visuotactile",
            "--sequences",
            "16",
            "--frames-per-sequence",
            "15",
            "--seed",
            "300",
            "--press-mm",
            "3.6,4.0",
            "--out",
            s(&extreme),
            "--force",
        ])?;
    }
    let m = |name: &str| a.models.join(name);
    let t = |name: &str| dir.join(name);
    let shapes = a.real.join("polic-shapes");
    tactile(&[
        "bench",
        "cae",
        "--model",
        s(&m("cae-shapes")),
        "--data",
        s(&shapes),
        "--out",
        s(&t("cae.md")),
    ])?;
    tactile(&[
        "bench",
        "detector",
        "--models",
        s(&m("detector")),
        "--data",
        s(&test),
        "--out",
        s(&t("detector.md")),
    ])?;
    tactile(&[
        "bench",
        "segmenter",
        "--models",
        s(&m("segmenter")),
        "--data",
        s(&test),
        "--out",
        s(&t("segmenter.md")),
    ])?;
    tactile(&[
        "bench",
        "depth",
        "--models",
        s(&m("depth")),
        "--data",
        s(&test),
        "--extreme",
        s(&extreme),
        "--out",
        s(&t("depth.md")),
    ])?;
    let mut pipeline = String::from(
        "| runtime | frames/s (decoding included) | whole tendon frame, median / p95 | per stage, median / p95 |\n|---|---|---|---|\n",
    );
    for rt in ["onnx", "burn-flex", "burn-ndarray"] {
        let out = tactile(&[
            "run",
            "--data",
            s(&test),
            "--models",
            s(&a.models),
            "--runtime",
            rt,
        ])?;
        let json: serde_json::Value = out
            .lines()
            .rev()
            .find_map(|l| serde_json::from_str(l).ok())
            .context("no summary from tactile run")?;
        let stages = out
            .lines()
            .find(|l| l.starts_with("median / p95 per stage"))
            .unwrap_or_default();
        let whole = stages.rsplit("whole frame ").next().unwrap_or("-");
        let per = stages
            .trim_start_matches("median / p95 per stage: ")
            .split(", whole frame")
            .next()
            .unwrap_or("-");
        pipeline.push_str(&format!(
            "| {rt} | {:.0} | {whole} | {per} |\n",
            json["fps"].as_f64().unwrap_or(f64::NAN)
        ));
    }
    let rustc = Command::new("rustc")
        .arg("-V")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|_| "rustc (unknown)".into());
    let machine = tactile_core::bench::Machine::detect().describe();
    let prefix = dir
        .file_name()
        .unwrap_or_default()
        .to_string_lossy()
        .to_string();
    let rel = |name: &str| format!("{prefix}/{name}");
    let md = format!(
        "# Results: speed against error for every shipped model\n\n\
         Generated by `tactile report` (`just report`). Machine: {machine}. Threads: burn uses rayon over the cores; \
         onnxruntime 1 intra-op thread in the pipeline, all cores in the model benches. Versions: burn 0.22.1, \
         burn-onnx 0.22, onnxruntime 1.31.1 (ort 2.0.0-rc.15), {rustc}. Held-out synthetic data: seed 200 \
         (all tendon paths) and seed 300 (the deepest presses), generated by this command; real data: \
         the authors' shapes set. Size sweeps and their Pareto plots: `docs/bench-detector.md`, \
         `docs/bench-segmenter.md`, `docs/bench-depth.md`, `docs/paper-a.md`.\n\n\
         ## The palpation pipeline (`tactile run`)\n\nDetector on every frame; segmenter, direction and depth only on tendon frames. \
         Paper B: 80 ms per frame (12.5 Hz) for detect + segment on an Intel i7. Target here: 30 frames/s.\n\n{pipeline}\n\
         ## Paper A encoder on the real shapes set (`{}`)\n\n{}\n\n\
         ## Tendon detector (`{}`)\n\n{}\n\n\
         ## Tendon segmenter (`{}`)\n\n{}\n\n\
         ## Depth (`{}`)\n\n{}\n",
        rel("cae.md"),
        body(&t("cae.md"), &prefix)?,
        rel("detector.md"),
        body(&t("detector.md"), &prefix)?,
        rel("segmenter.md"),
        body(&t("segmenter.md"), &prefix)?,
        rel("depth.md"),
        body(&t("depth.md"), &prefix)?,
    );
    tactile_core::io::write_atomic(&a.out, md.as_bytes())?;
    println!(
        "wrote {} and the tables in {}",
        a.out.display(),
        dir.display()
    );
    Ok(())
}
