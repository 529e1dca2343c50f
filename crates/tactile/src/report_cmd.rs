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
    /// Also put the headline table into this file, between the lines
    /// `<!-- headline:begin -->` and `<!-- headline:end -->` (the README).
    #[arg(long)]
    readme: Option<PathBuf>,
    /// Sequences of 25 frames in the held-out test set (seed 200).
    #[arg(long, default_value_t = 40)]
    sequences: usize,
    /// Sequences of 15 frames at the deepest presses (seed 300).
    #[arg(long, default_value_t = 16)]
    extreme_sequences: usize,
    /// Timed runs per latency in the model benches (median reported).
    #[arg(long, default_value_t = 20)]
    runs: usize,
}

const HEADLINE_BEGIN: &str = "<!-- headline:begin -->";
const HEADLINE_END: &str = "<!-- headline:end -->";

/// `text` with the lines between the headline markers replaced by `table`;
/// an error naming `file` when the markers are missing or out of order.
fn replace_headline(text: &str, table: &str, file: &Path) -> Result<String> {
    let (Some(b), Some(e)) = (text.find(HEADLINE_BEGIN), text.find(HEADLINE_END)) else {
        bail!(
            "{}: no `{HEADLINE_BEGIN}` ... `{HEADLINE_END}` lines to put the headline table between",
            file.display()
        );
    };
    if e < b {
        bail!(
            "{}: `{HEADLINE_END}` comes before `{HEADLINE_BEGIN}`",
            file.display()
        );
    }
    Ok(format!(
        "{}{HEADLINE_BEGIN}\n{table}{}",
        &text[..b],
        &text[e..]
    ))
}

/// The rows a bench wrote beside its table (NAME.json).
fn bench_rows(table: &Path) -> Result<Vec<serde_json::Value>> {
    tactile_core::io::read_json(table.with_extension("json")).map_err(Into::into)
}

/// A runtime's milliseconds in a bench row, or "-".
fn ms_of(row: &serde_json::Value, key: &str) -> String {
    row["ms"]
        .as_object()
        .and_then(|m| m.iter().find(|(k, _)| k.contains(key)))
        .and_then(|(_, v)| v.as_f64())
        .map_or("-".into(), |v| format!("{v:.2}"))
}

/// A metric of a bench row, formatted, or "-".
fn metric(row: &serde_json::Value, key: &str, f: impl Fn(f64) -> String) -> String {
    row["metrics"][key].as_f64().map_or("-".into(), f)
}

/// One line per model and one for the whole pipeline: error on held-out
/// data beside the paper's number and the milliseconds per runtime.
fn headline(
    cae: &serde_json::Value,
    det: &serde_json::Value,
    seg: &serde_json::Value,
    depth: &serde_json::Value,
    pipeline: &[(String, serde_json::Value)],
) -> String {
    let mut t = String::from(
        "| stage | error on held-out data (ours) | paper | onnxruntime ms | burn flex ms | burn ndarray ms |\n|---|---|---|---|---|---|\n",
    );
    let mut line = |stage: &str, ours: String, paper: &str, r: &serde_json::Value| {
        t.push_str(&format!(
            "| {stage} | {ours} | {paper} | {} | {} | {} |\n",
            ms_of(r, "onnxruntime"),
            ms_of(r, "flex"),
            ms_of(r, "ndarray")
        ));
    };
    line(
        "paper A: CAE-16 + shape head, real shapes set",
        metric(cae, "shape_accuracy", |v| {
            format!("accuracy {:.1} %", 100.0 * v)
        }),
        "96.7 %",
        cae,
    );
    line(
        "paper B: tendon detector",
        format!(
            "accuracy {} (onset/release frames {})",
            metric(det, "accuracy", |v| format!("{v:.3}")),
            metric(det, "onset_release_accuracy", |v| format!("{v:.3}"))
        ),
        "accuracy 0.958",
        det,
    );
    line(
        "paper B: tendon segmenter + direction",
        format!(
            "IoU {} (curved {}); straight direction median {} deg",
            metric(seg, "iou", |v| format!("{v:.3}")),
            metric(seg, "iou_curved", |v| format!("{v:.3}")),
            metric(seg, "direction_straight_median_deg", |v| format!("{v:.2}"))
        ),
        "IoU 0.879 val, 0.196 curved test",
        seg,
    );
    line(
        "paper B: depth U-Net (DenseNet encoder)",
        format!(
            "MAE {} mm (tendon {} mm), SSIM {}",
            metric(depth, "mae_window_mm", |v| format!("{v:.3}")),
            metric(depth, "mae_tendon_mm", |v| format!("{v:.3}")),
            metric(depth, "ssim", |v| format!("{v:.3}"))
        ),
        "MAE 0.050 mm, SSIM 0.960",
        depth,
    );
    let ms: serde_json::Map<String, serde_json::Value> = pipeline
        .iter()
        .map(|(rt, j)| (rt.clone(), j["stages_ms"]["tendon_frame"][0].clone()))
        .collect();
    let fps = pipeline
        .iter()
        .find(|(rt, _)| rt == "onnx")
        .and_then(|(_, j)| j["stages_ms"]["tendon_frame"][0].as_f64())
        .map_or("-".into(), |m| format!("{:.0} tendon frames/s", 1e3 / m));
    line(
        "pipeline, tendon frame (detect, segment, direction, depth)",
        fps,
        "80 ms (detect + segment, i7)",
        &serde_json::json!({ "ms": {
            "onnxruntime": ms.get("onnx"),
            "flex": ms.get("burn-flex"),
            "ndarray": ms.get("burn-ndarray"),
        }}),
    );
    t
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
        .join("\n")
        .trim_start()
        .to_string())
}

/// A held-out set of `sequences` x `frames` at `seed` in `dir`, generated
/// unless one with exactly that seed and count is there.
fn held_out(dir: &Path, seed: u64, sequences: usize, frames: usize, extra: &[&str]) -> Result<()> {
    let have: Option<serde_json::Value> =
        tactile_core::io::read_json(dir.join("manifest.json")).ok();
    let fits = have.is_some_and(|m| {
        m["seed"].as_u64() == Some(seed) && m["count"].as_u64() == Some((sequences * frames) as u64)
    }) && dir.join("labels.csv").is_file();
    if fits {
        return Ok(());
    }
    let (seq, fr, sd) = (sequences.to_string(), frames.to_string(), seed.to_string());
    let mut args = vec![
        "synth",
        "visuotactile",
        "--sequences",
        &seq,
        "--frames-per-sequence",
        &fr,
        "--seed",
        &sd,
        "--out",
        s(dir),
        "--force",
    ];
    args.extend_from_slice(extra);
    tactile(&args)?;
    Ok(())
}

/// The summary (the last JSON line) of `tactile run` over `test` on
/// `runtime`, with `extra` options.
fn run_summary(
    test: &Path,
    models: &Path,
    runtime: &str,
    extra: &[&str],
) -> Result<serde_json::Value> {
    let mut args = vec![
        "run",
        "--data",
        s(test),
        "--models",
        s(models),
        "--runtime",
        runtime,
    ];
    args.extend_from_slice(extra);
    tactile(&args)?
        .lines()
        .rev()
        .find_map(|l| serde_json::from_str(l).ok())
        .with_context(|| format!("no summary from tactile {}", args.join(" ")))
}

/// ON and OFF probabilities of the hysteresis the report measures.
const HYSTERESIS: [&str; 2] = ["0.6", "0.3"];

/// The detector's decisions over each sequence with its threshold alone
/// (from the onnxruntime run in `summaries`) and with hysteresis: accuracy
/// against the labels and how often the decision changes within a
/// sequence, beside how often the label does.
fn temporal_filter(
    test: &Path,
    models: &Path,
    summaries: &[(String, serde_json::Value)],
) -> Result<String> {
    let plain = &summaries
        .first()
        .context("no onnxruntime run to compare the filter with")?
        .1;
    let on_off = HYSTERESIS.join(",");
    let filtered = run_summary(test, models, "onnx", &["--hysteresis", &on_off])?;
    let acc = |j: &serde_json::Value, k: &str| j[k].as_f64().unwrap_or(f64::NAN);
    let changes = |j: &serde_json::Value, k: &str| j[k].as_u64().unwrap_or(0);
    let labels = changes(plain, "label_changes");
    let (a0, c0) = (
        acc(plain, "detector_accuracy_threshold_only"),
        changes(plain, "decision_changes_threshold_only"),
    );
    let (a1, c1) = (
        acc(&filtered, "detector_accuracy"),
        changes(&filtered, "decision_changes"),
    );
    let verdict = if c1 < c0 {
        format!(
            "Hysteresis removes {} decision change(s) at an accuracy change of {:+.4}.",
            c0 - c1,
            a1 - a0
        )
    } else {
        format!(
            "Hysteresis removes no flicker here (the threshold alone changes its decision {c0} times against {labels} label changes; accuracy {a1:.4} with it, {a0:.4} without), so `tactile run` leaves it off unless `--hysteresis ON,OFF` is given."
        )
    };
    Ok(format!(
        "Flicker at onsets and releases (the same held-out sequences, onnxruntime):\n\n\
         | decision rule | accuracy | decision changes within sequences | label changes |\n|---|---|---|---|\n\
         | the detector's saved threshold | {a0:.4} | {c0} | {labels} |\n\
         | hysteresis ON {}, OFF {} | {a1:.4} | {c1} | {labels} |\n\n{verdict}\n",
        HYSTERESIS[0], HYSTERESIS[1]
    ))
}

pub fn report(a: ReportArgs) -> Result<()> {
    if a.sequences == 0 || a.extreme_sequences == 0 || a.runs == 0 {
        bail!("--sequences, --extreme-sequences and --runs must be at least 1");
    }
    // A README without its markers fails now, not after the benches.
    if let Some(readme) = &a.readme {
        let text = std::fs::read_to_string(readme)
            .with_context(|| format!("{}: cannot read", readme.display()))?;
        replace_headline(&text, "", readme)?;
    }
    let dir = a.out.with_extension("");
    tactile_core::io::create_dir_all(&dir)?;
    tactile_core::io::create_dir_all(&a.work)?;
    // Held-out synthetic sets: seeds no model was trained or chosen on.
    let test = a.work.join("vt-test");
    let extreme = a.work.join("vt-extreme");
    held_out(&test, 200, a.sequences, 25, &[])?;
    held_out(
        &extreme,
        300,
        a.extreme_sequences,
        15,
        &["--press-mm", "3.6,4.0"],
    )?;
    let runs = a.runs.to_string();
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
        "--runs",
        &runs,
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
        "--runs",
        &runs,
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
        "--runs",
        &runs,
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
        "--runs",
        &runs,
        "--out",
        s(&t("depth.md")),
    ])?;
    let mut pipeline = String::from(
        "| runtime | frames/s (decoding included) | whole tendon frame, median / p95 | tendon frame against onnxruntime | per stage, median / p95 |\n|---|---|---|---|---|\n",
    );
    let mut summaries = Vec::new();
    for rt in ["onnx", "burn-flex", "burn-ndarray"] {
        let json = run_summary(&test, &a.models, rt, &[])?;
        let st = &json["stages_ms"];
        let cell = |k: &str| match (st[k][0].as_f64(), st[k][1].as_f64()) {
            (Some(m), Some(p)) => format!("{m:.2} / {p:.2} ms"),
            _ => "-".into(),
        };
        // The first runtime is onnxruntime: every ratio is to it, same run.
        let tendon_ms = st["tendon_frame"][0].as_f64();
        let ort_ms = summaries
            .first()
            .map_or(tendon_ms, |(_, j): &(String, serde_json::Value)| {
                j["stages_ms"]["tendon_frame"][0].as_f64()
            });
        let ratio = match (tendon_ms, ort_ms) {
            (Some(t), Some(o)) if o > 0.0 => format!("{:.2}x", t / o),
            _ => "-".into(),
        };
        pipeline.push_str(&format!(
            "| {rt} | {:.0} | {} | {ratio} | detect {}, segment + direction {}, depth {} |\n",
            json["fps"].as_f64().unwrap_or(f64::NAN),
            cell("tendon_frame"),
            cell("detect"),
            cell("segment"),
            cell("depth"),
        ));
        summaries.push((rt.to_string(), json));
    }
    let filter = temporal_filter(&test, &a.models, &summaries)?;
    let first = |name: &str| -> Result<serde_json::Value> {
        bench_rows(&t(name))?
            .into_iter()
            .next()
            .with_context(|| format!("{}: no rows", t(name).with_extension("json").display()))
    };
    let headline = headline(
        &first("cae.md")?,
        &first("detector.md")?,
        &first("segmenter.md")?,
        &first("depth.md")?,
        &summaries,
    );
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
         ## Headline\n\n{headline}\n\
         ## The palpation pipeline (`tactile run`)\n\nDetector on every frame; segmenter, direction and depth only on tendon frames. \
         Paper B: 80 ms per frame (12.5 Hz) for detect + segment on an Intel i7. Target here: 30 frames/s; burn flex within 2x and ndarray within 5x of onnxruntime.\n\n{pipeline}\n{filter}\n\
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
    if let Some(readme) = &a.readme {
        let text = std::fs::read_to_string(readme)
            .with_context(|| format!("{}: cannot read", readme.display()))?;
        let block = format!(
            "{headline}\nMeasured on {machine} by `tactile report` (`just report`); the full tables and plots are in `{}`.\n",
            a.out.display()
        );
        tactile_core::io::write_atomic(
            readme,
            replace_headline(&text, &block, readme)?.as_bytes(),
        )?;
        println!("headline table in {}", readme.display());
    }
    println!(
        "wrote {} and the tables in {}",
        a.out.display(),
        dir.display()
    );
    Ok(())
}
