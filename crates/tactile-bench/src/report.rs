//! `docs/results.md` regenerated from the shipped models, freshly
//! generated held-out synthetic data and the real TacTip shapes set: every
//! bench and the pipeline on each runtime, run in this process, and the
//! headline table for the README. No number in the page is typed by hand.

use std::path::{Path, PathBuf};

use datasets_synth::{Range, VisuotactileConfig, WriteOptions, write_visuotactile};
use tactile_burn::Runtime;
use tactile_core::dataset::Manifest;
use tactile_pipeline::{FrameSource, Pipeline, RunOptions, RunSummary, SourceOptions, SourceSpec};

use crate::Result;
use crate::cae::{CaeBench, CaeMetrics, bench_cae};
use crate::latency::{RuntimeMs, ms_cell};
use crate::models::{
    DepthMetrics, DetectorMetrics, ModelBench, SegmenterMetrics, bench_depth, bench_detectors,
    bench_segmenters,
};
use crate::output::{BenchRow, Picture};

/// What the report runs on and where it goes (`tactile report`'s flags).
#[derive(Debug, Clone, clap::Args)]
pub struct Report {
    /// The real TacTip data (`polic-shapes` inside).
    #[arg(long, default_value = "../shared/real")]
    pub real: PathBuf,
    /// Shipped models.
    #[arg(long, default_value = "models")]
    pub models: PathBuf,
    /// Where held-out synthetic sets are generated (kept for reuse).
    #[arg(long, default_value = "data/report")]
    pub work: PathBuf,
    /// The page; its tables and plots go into a folder beside it.
    #[arg(long, default_value = "docs/results.md")]
    pub out: PathBuf,
    /// Also put the headline table into this file, between the lines
    /// `<!-- headline:begin -->` and `<!-- headline:end -->` (the README).
    #[arg(long)]
    pub readme: Option<PathBuf>,
    /// Sequences of 25 frames in the held-out test set (seed 200).
    #[arg(long, default_value_t = 40)]
    pub sequences: usize,
    /// Sequences of 15 frames at the deepest presses (seed 300).
    #[arg(long, default_value_t = 16)]
    pub extreme_sequences: usize,
    /// Timed runs per latency in the model benches (median reported).
    #[arg(long, default_value_t = 20)]
    pub runs: usize,
}

/// Held-out sequences the report renders per set: 100,000 frames of 640x360.
pub const MAX_REPORT_SEQUENCES: usize = 4_000;

/// Start of the README's headline block.
pub const HEADLINE_BEGIN: &str = "<!-- headline:begin -->";
/// Its end.
pub const HEADLINE_END: &str = "<!-- headline:end -->";

/// ON and OFF probabilities of the hysteresis the report measures.
pub const HYSTERESIS: (f32, f32) = (0.6, 0.3);

/// `text` with the lines between the headline markers replaced by `table`;
/// an error naming `file` when the markers are missing or out of order.
pub fn replace_headline(text: &str, table: &str, file: &Path) -> Result<String> {
    let (Some(b), Some(e)) = (text.find(HEADLINE_BEGIN), text.find(HEADLINE_END)) else {
        return Err(tactile_core::Error::dataset(
            file,
            None,
            format!(
                "no `{HEADLINE_BEGIN}` ... `{HEADLINE_END}` lines to put the headline table between"
            ),
        )
        .into());
    };
    if e < b {
        return Err(tactile_core::Error::dataset(
            file,
            None,
            format!("`{HEADLINE_END}` comes before `{HEADLINE_BEGIN}`"),
        )
        .into());
    }
    Ok(format!(
        "{}{HEADLINE_BEGIN}\n{table}{}",
        &text[..b],
        &text[e..]
    ))
}

/// A held-out set of `sequences` x `frames` at `seed` in `dir`, generated
/// unless one with exactly that seed and count is there.
fn held_out(
    dir: &Path,
    seed: u64,
    sequences: usize,
    frames: usize,
    press_mm: Option<Range>,
) -> Result<()> {
    let have: Option<Manifest> = tactile_core::io::read_json(dir.join("manifest.json")).ok();
    let fits = have.is_some_and(|m| m.seed == Some(seed) && m.count == sequences * frames)
        && dir.join("labels.csv").is_file();
    if fits {
        return Ok(());
    }
    let mut cfg = VisuotactileConfig {
        frames_per_sequence: frames,
        ..Default::default()
    };
    if let Some(p) = press_mm {
        cfg.press_mm = p;
    }
    tactile_core::note!(
        "generating {} ({sequences} palpations, seed {seed})",
        dir.display()
    );
    write_visuotactile(
        &cfg,
        sequences * frames,
        seed,
        dir,
        WriteOptions {
            force: true,
            progress: true,
        },
    )?;
    Ok(())
}

/// The pipeline over `test` on `runtime` (one onnxruntime thread, decoding
/// overlapped, as `tactile run` does by default).
fn run_pipeline(
    test: &Path,
    models: &Path,
    runtime: Runtime,
    hysteresis: Option<(f32, f32)>,
) -> Result<RunSummary> {
    tactile_core::note!(
        "pipeline on {runtime}{}",
        if hysteresis.is_some() {
            " with hysteresis"
        } else {
            ""
        }
    );
    let mut pipeline = Pipeline::load(models, runtime, 1)?;
    let mut frames = FrameSource::open(
        &SourceSpec::Path(test.to_path_buf()),
        SourceOptions::default(),
    )?;
    let options = RunOptions {
        hysteresis,
        render: None,
    };
    let summary = tactile_pipeline::run_collect(&mut pipeline, &mut frames, &options)?.summary;
    // Frames skipped as undecodable are told, not silently left out.
    frames
        .late_warnings()
        .iter()
        .for_each(|w| tactile_core::note!("{w}"));
    Ok(summary)
}

fn median_of(s: Option<[f64; 2]>) -> Option<f64> {
    s.map(|v| v[0])
}

/// One line per model and one for the whole pipeline: error on held-out
/// data beside the paper's number and the milliseconds per runtime.
fn headline(
    cae: &BenchRow<CaeMetrics>,
    det: &BenchRow<DetectorMetrics>,
    seg: &BenchRow<SegmenterMetrics>,
    depth: &BenchRow<DepthMetrics>,
    pipeline: &[(Runtime, RunSummary)],
) -> String {
    let mut t = String::from(
        "| stage | error on held-out data (ours) | paper | onnxruntime ms | burn flex ms | burn ndarray ms |\n|---|---|---|---|---|---|\n",
    );
    let mut line = |stage: &str, ours: String, paper: &str, ms: &RuntimeMs| {
        t.push_str(&format!(
            "| {stage} | {ours} | {paper} | {} | {} | {} |\n",
            ms_cell(ms.onnxruntime),
            ms_cell(ms.flex),
            ms_cell(ms.ndarray)
        ));
    };
    let f3 = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.3}"));
    line(
        "paper A: CAE-16 + shape head, real shapes set",
        cae.metrics
            .shape_accuracy
            .map_or("-".into(), |v| format!("accuracy {:.1} %", 100.0 * v)),
        "96.7 %",
        &cae.ms,
    );
    line(
        "paper B: tendon detector",
        format!(
            "accuracy {} (onset/release frames {})",
            f3(Some(det.metrics.accuracy)),
            f3(Some(det.metrics.onset_release_accuracy))
        ),
        "accuracy 0.958",
        &det.ms,
    );
    line(
        "paper B: tendon segmenter + direction",
        format!(
            "IoU {} (curved {}); direction on {} of tendon frames, median {} / p90 {} deg",
            f3(seg.metrics.iou),
            f3(seg.metrics.iou_curved),
            seg.metrics
                .direction_coverage
                .map_or("-".into(), |v| format!("{:.1} %", 100.0 * v)),
            seg.metrics
                .direction_median_deg
                .map_or("-".into(), |v| format!("{v:.2}")),
            seg.metrics
                .direction_p90_deg
                .map_or("-".into(), |v| format!("{v:.2}"))
        ),
        "IoU 0.879 val, 0.196 curved test",
        &seg.ms,
    );
    line(
        "paper B: depth U-Net (DenseNet encoder)",
        format!(
            "MAE {} mm (tendon {} mm), SSIM {}",
            f3(Some(depth.metrics.mae_window_mm)),
            f3(depth.metrics.mae_tendon_mm),
            f3(Some(depth.metrics.ssim))
        ),
        "MAE 0.050 mm, SSIM 0.960",
        &depth.ms,
    );
    let tendon_ms = |rt: Runtime| {
        pipeline
            .iter()
            .find(|(r, _)| *r == rt)
            .and_then(|(_, s)| median_of(s.stages_ms.tendon_frame))
    };
    let fps =
        tendon_ms(Runtime::Onnx).map_or("-".into(), |m| format!("{:.0} tendon frames/s", 1e3 / m));
    line(
        "pipeline, tendon frame (detect, segment, direction, depth)",
        fps,
        "80 ms (detect + segment, i7)",
        &RuntimeMs {
            onnxruntime: tendon_ms(Runtime::Onnx),
            flex: tendon_ms(Runtime::BurnFlex),
            ndarray: tendon_ms(Runtime::BurnNdarray),
        },
    );
    t
}

/// The detector's decisions over each sequence with its threshold alone
/// (from the onnxruntime run `plain`) and with hysteresis: accuracy
/// against the labels and how often the decision changes within a
/// sequence, beside how often the label does.
fn temporal_filter(plain: &RunSummary, filtered: &RunSummary) -> String {
    let labels = plain.label_changes;
    let (a0, c0) = (
        plain.detector_accuracy_threshold_only.unwrap_or(f64::NAN),
        plain.decision_changes_threshold_only,
    );
    let (a1, c1) = (
        filtered.detector_accuracy.unwrap_or(f64::NAN),
        filtered.decision_changes,
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
    format!(
        "Flicker at onsets and releases (the same held-out sequences, onnxruntime):\n\n\
         | decision rule | accuracy | decision changes within sequences | label changes |\n|---|---|---|---|\n\
         | the detector's saved threshold | {a0:.4} | {c0} | {labels} |\n\
         | hysteresis ON {}, OFF {} | {a1:.4} | {c1} | {labels} |\n\n{verdict}\n",
        HYSTERESIS.0, HYSTERESIS.1
    )
}

/// The Markdown of a generated table, without its machine line, its
/// images linked from the page's folder (`prefix/`).
fn body(markdown: &str, prefix: &str) -> String {
    markdown
        .lines()
        .filter(|l| !l.starts_with("Machine:"))
        .map(|l| l.replace("](", &format!("]({prefix}/")))
        .collect::<Vec<_>>()
        .join("\n")
        .trim_start()
        .to_string()
}

/// Regenerate the page (and the README's headline); returns the headline.
pub fn report(r: &Report) -> Result<String> {
    tactile_core::bench::check_runs(r.runs)?;
    if r.out.extension().is_none() {
        return Err(tactile_core::Error::Invalid(format!(
            "{}: the report's tables and plots go into a folder of the page's name without its extension, which would be the page itself; give NAME.md",
            r.out.display()
        ))
        .into());
    }
    for (what, n) in [
        ("sequences", r.sequences),
        ("extreme sequences", r.extreme_sequences),
    ] {
        if !(1..=MAX_REPORT_SEQUENCES).contains(&n) {
            return Err(tactile_core::Error::Config(format!(
                "{what}: must be 1 to {MAX_REPORT_SEQUENCES} (each a held-out video rendered to disk), got {n}"
            ))
            .into());
        }
    }
    // A README without its markers fails now, not after the benches.
    if let Some(readme) = &r.readme {
        let text = tactile_core::io::read_text(readme)?;
        replace_headline(&text, "", readme)?;
    }
    // Every input read, checked before the held-out sets are rendered and
    // before any folder is made: a mistyped --real or --models fails now,
    // not after minutes of work, and leaves nothing behind.
    tactile_core::dataset::Dataset::open(r.real.join("polic-shapes"))?;
    for (model, what) in [
        ("cae-shapes", "CAE model folder"),
        ("detector", "detector folder"),
        ("segmenter", "segmenter folder"),
        ("depth", "depth model folder"),
    ] {
        tactile_core::io::expect_folder(&r.models.join(model), what)?;
    }
    let dir = r.out.with_extension("");
    tactile_core::io::create_dir_all(&dir)?;
    tactile_core::io::create_dir_all(&r.work)?;
    // Held-out synthetic sets: seeds no model was trained or chosen on.
    let test = r.work.join("vt-test");
    let extreme = r.work.join("vt-extreme");
    held_out(&test, 200, r.sequences, 25, None)?;
    held_out(
        &extreme,
        300,
        r.extreme_sequences,
        15,
        Some(Range::new(3.6, 4.0)),
    )?;
    let t = |name: &str| dir.join(name);
    let prefix = dir
        .file_name()
        .unwrap_or_default()
        .to_string_lossy()
        .to_string();
    tactile_core::note!("bench cae");
    let cae = bench_cae(&CaeBench {
        model: r.models.join("cae-shapes"),
        data: r.real.join("polic-shapes"),
        batch: 256,
        runs: r.runs,
    })?;
    cae.write(&t("cae.md"))?;
    let bench = |model: &str, extreme: Option<PathBuf>| ModelBench {
        models: vec![r.models.join(model)],
        data: test.clone(),
        select: None,
        extreme,
        runs: r.runs,
    };
    tactile_core::note!("bench detector");
    let mut det = bench_detectors(&bench("detector", None))?;
    if let Some(row) = det.rows.first() {
        let c = row.metrics.calibration.clone();
        det.after_plot = format!(
            "\nCalibration of the shipped detector on the same frames: expected calibration error {:.4} over 10 bins, {} over the {} frames with a probability in [0.1, 0.9]; Brier score {:.4}.\n\n![Detector: reliability](detector-reliability.png)\n",
            c.ece,
            c.ece_uncertain_text(4),
            c.uncertain_frames,
            c.brier
        );
        det.pictures
            .push(Picture::new(t("detector-reliability.png"), move |path| {
                Ok(tactile_detect::eval::save_reliability_plot(
                    &c,
                    path,
                    "Tendon detector: reliability on the held-out frames",
                )?)
            }));
    }
    let det_md = det.write(&t("detector.md"))?;
    tactile_core::note!("bench segmenter");
    let seg = bench_segmenters(&bench("segmenter", None))?;
    let seg_md = seg.write(&t("segmenter.md"))?;
    tactile_core::note!("bench depth");
    let depth = bench_depth(&bench("depth", Some(extreme)))?;
    let depth_md = depth.write(&t("depth.md"))?;
    let mut pipeline = String::from(
        "| runtime | frames/s (decoding included) | whole tendon frame, median / p95 | tendon frame against onnxruntime | per stage, median / p95 |\n|---|---|---|---|---|\n",
    );
    let mut summaries: Vec<(Runtime, RunSummary)> = Vec::new();
    for rt in Runtime::ALL {
        let s = run_pipeline(&test, &r.models, rt, None)?;
        let st = &s.stages_ms;
        let cell =
            |v: Option<[f64; 2]>| v.map_or("-".into(), |[m, p]| format!("{m:.2} / {p:.2} ms"));
        // The first runtime is onnxruntime: every ratio is to it, same run.
        let tendon_ms = median_of(st.tendon_frame);
        let ort_ms = summaries
            .first()
            .map_or(tendon_ms, |(_, o)| median_of(o.stages_ms.tendon_frame));
        let ratio = match (tendon_ms, ort_ms) {
            (Some(t), Some(o)) if o > 0.0 => format!("{:.2}x", t / o),
            _ => "-".into(),
        };
        pipeline.push_str(&format!(
            "| {rt} | {:.0} | {} | {ratio} | detect {}, segment + direction {}, depth {} |\n",
            s.fps,
            cell(st.tendon_frame),
            cell(st.detect),
            cell(st.segment),
            cell(st.depth),
        ));
        summaries.push((rt, s));
    }
    let filtered = run_pipeline(&test, &r.models, Runtime::Onnx, Some(HYSTERESIS))?;
    let filter = temporal_filter(&summaries[0].1, &filtered);
    let (Some(det_row), Some(seg_row), Some(depth_row)) =
        (det.rows.first(), seg.rows.first(), depth.rows.first())
    else {
        return Err(tactile_core::Error::Invalid("a bench returned no row".into()).into());
    };
    let headline = headline(&cae.row, det_row, seg_row, depth_row, &summaries);
    let rustc = std::process::Command::new("rustc")
        .arg("-V")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|_| "rustc (unknown)".into());
    let machine = tactile_core::bench::Machine::detect().describe();
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
        body(&cae.markdown, &prefix),
        rel("detector.md"),
        body(&det_md, &prefix),
        rel("segmenter.md"),
        body(&seg_md, &prefix),
        rel("depth.md"),
        body(&depth_md, &prefix),
    );
    tactile_core::io::write_atomic(&r.out, md.as_bytes())?;
    if let Some(readme) = &r.readme {
        let text = tactile_core::io::read_text(readme)?;
        let block = format!(
            "{headline}\nMeasured on {machine} by `tactile report` (`just report`); the full tables and plots are in `{}`.\n",
            r.out.display()
        );
        tactile_core::io::write_atomic(
            readme,
            replace_headline(&text, &block, readme)?.as_bytes(),
        )?;
    }
    Ok(headline)
}
