//! `tactile run`: the palpation pipeline over a folder of frames or a
//! dataset, one JSON Lines record per frame and a speed summary.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use tactile_core::metrics::{median, percentile};
use tactile_pipeline::{Pipeline, Runtime};

#[derive(Args)]
pub struct RunArgs {
    /// A visuo-tactile dataset (frames in labels.csv order) or a folder of
    /// PNG frames (in name order, e.g. a 30 fps video as numbered PNGs).
    #[arg(long)]
    data: PathBuf,
    /// Folder with detector/, segmenter/ and depth/.
    #[arg(long, default_value = "models")]
    models: PathBuf,
    /// onnx (fastest here), burn-flex or burn-ndarray.
    #[arg(long, default_value = "onnx")]
    runtime: Runtime,
    /// onnxruntime intra-op threads. Default 1: these models are small
    /// enough that a second thread costs more than it gains (measured:
    /// 159 against 350 frames/s without overlap), and the other core
    /// decodes the next frames.
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// JSON Lines output, one record per frame (written when the run ends).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Process at most this many frames.
    #[arg(long)]
    limit: Option<usize>,
    /// Write an overlay PNG per tendon frame into this folder: the
    /// segmenter's window with the kept region in green and the direction
    /// in red, beside the depth heat map (paper B's figure 3).
    #[arg(long)]
    render: Option<PathBuf>,
    /// Hysteresis on the detector over each sequence: ON,OFF probabilities
    /// (a tendon appears at ON and disappears below OFF).
    #[arg(long, value_delimiter = ',')]
    hysteresis: Option<Vec<f32>>,
    /// Decode each frame just before it is processed instead of on a
    /// second thread ahead of the models.
    #[arg(long)]
    no_overlap: bool,
}

/// Frames in order, with their sequence (when known) and `tendon` label.
type Frame = (PathBuf, Option<String>, Option<bool>);

fn frames(dir: &std::path::Path) -> Result<Vec<Frame>> {
    if dir.join("labels.csv").is_file() {
        let ds = tactile_core::dataset::Dataset::open(dir)?;
        return (0..ds.len())
            .map(|i| {
                Ok((
                    ds.path_of(i, "file")?,
                    ds.text_opt(i, "sequence").map(str::to_string),
                    ds.number_opt(i, "tendon")?.map(|v| v == 1.0),
                ))
            })
            .collect();
    }
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("png")))
        .collect();
    v.sort();
    if v.is_empty() {
        bail!("{}: no labels.csv and no PNG frames", dir.display());
    }
    Ok(v.into_iter().map(|p| (p, None, None)).collect())
}

/// Frame numbers missing from a numbered sequence of files (`000007.png`):
/// the gaps between consecutive numbers, in order. A video with a dropped
/// frame still runs; the summary says how many frames are missing.
fn missing_frames(frames: &[Frame]) -> Vec<u64> {
    let number = |p: &PathBuf| -> Option<u64> {
        let stem = p.file_stem()?.to_str()?;
        let digits: String = stem
            .chars()
            .rev()
            .take_while(char::is_ascii_digit)
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect();
        digits.parse().ok()
    };
    let nums: Vec<u64> = frames.iter().filter_map(|f| number(&f.0)).collect();
    if nums.len() != frames.len() {
        return Vec::new();
    }
    nums.windows(2)
        .flat_map(|w| (w[0] + 1..w[1]).collect::<Vec<_>>())
        .collect()
}

/// Accuracy against the labels and decision changes within sequences.
fn decisions(
    records: &[tactile_pipeline::FrameRecord],
    frames: &[Frame],
    raw: bool,
) -> (Option<f64>, usize) {
    let pick = |r: &tactile_pipeline::FrameRecord| if raw { r.tendon_raw } else { r.tendon };
    let labelled: Vec<(bool, bool)> = records
        .iter()
        .zip(frames)
        .filter_map(|(r, f)| f.2.map(|t| (pick(r), t)))
        .collect();
    let acc = (!labelled.is_empty())
        .then(|| labelled.iter().filter(|(p, t)| p == t).count() as f64 / labelled.len() as f64);
    let changes = (1..records.len())
        .filter(|&i| frames[i].1 == frames[i - 1].1 && pick(&records[i]) != pick(&records[i - 1]))
        .count();
    (acc, changes)
}

pub fn run(a: RunArgs) -> Result<()> {
    let threads = a.threads.max(1);
    // The input first: a bad folder is reported before any model loads.
    let mut paths = frames(&a.data)?;
    // Outputs next: an unwritable folder fails now, not after the run.
    if let Some(out) = &a.out {
        tactile_core::io::ensure_writable_parent(out)?;
    }
    if let Some(dir) = &a.render {
        tactile_core::io::ensure_writable_dir(dir)?;
    }
    let mut p = Pipeline::load(&a.models, a.runtime, threads)?;
    if let Some(n) = a.limit {
        paths.truncate(n);
    }
    // Only a folder of frames is a video; a dataset lists what it has.
    let missing = if a.data.join("labels.csv").is_file() {
        Vec::new()
    } else {
        missing_frames(&paths)
    };
    if !missing.is_empty() {
        eprintln!(
            "warning: {} frame(s) missing from the numbering, e.g. {:?}",
            missing.len(),
            &missing[..missing.len().min(5)]
        );
    }
    let mut filter = match &a.hysteresis {
        Some(v) if v.len() == 2 => Some(tactile_pipeline::Hysteresis::new(v[0], v[1])?),
        Some(v) => bail!("--hysteresis takes ON,OFF (two probabilities), got {v:?}"),
        None => None,
    };
    let pb = tactile_core::train::progress_bar(paths.len() as u64, "run");
    let t0 = std::time::Instant::now();
    let mut records = Vec::with_capacity(paths.len());
    // Decode the next frames on another thread while this one runs the
    // models (a queue of 4; `--no-overlap` decodes in line).
    let (tx, rx) = std::sync::mpsc::sync_channel::<Result<tactile_core::image_io::RgbImage>>(4);
    let decode_paths: Vec<PathBuf> = paths.iter().map(|f| f.0.clone()).collect();
    let overlap = !a.no_overlap;
    let decoder = overlap.then(|| {
        std::thread::spawn(move || {
            for p in decode_paths {
                let img = tactile_core::image_io::load_rgb(&p).map_err(anyhow::Error::from);
                if tx.send(img).is_err() {
                    break;
                }
            }
        })
    });
    for (k, (path, seq, _)) in paths.iter().enumerate() {
        let frame = if overlap {
            rx.recv()
                .map_err(|_| anyhow::anyhow!("the frame decoder stopped"))??
        } else {
            tactile_core::image_io::load_rgb(path)?
        };
        let name = path
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        if let Some(h) = filter.as_mut()
            && (k == 0 || paths[k - 1].1 != *seq)
        {
            h.reset();
        }
        let (rec, views) = p.process_filtered(&name, &frame, filter.as_mut())?;
        if let (Some(dir), Some(v)) = (&a.render, views) {
            let stem = path.file_stem().unwrap_or_default().to_string_lossy();
            v.save_png(&dir.join(format!("{stem}-overlay.png")), 4)?;
        }
        records.push(rec);
        pb.inc(1);
    }
    drop(rx);
    if let Some(d) = decoder {
        let _ = d.join();
    }
    pb.finish_and_clear();
    let wall = t0.elapsed().as_secs_f64();
    if let Some(out) = &a.out {
        tactile_core::io::write_atomic_with(out, |w| {
            for r in &records {
                writeln!(
                    w,
                    "{}",
                    serde_json::to_string(r).map_err(std::io::Error::other)?
                )?;
            }
            Ok(())
        })?;
    }
    // Median and p95 milliseconds of a stage over the frames that ran it.
    let stats = |f: &dyn Fn(&tactile_pipeline::FrameRecord) -> Option<f64>| -> Option<[f64; 2]> {
        let v: Vec<f64> = records.iter().filter_map(f).collect();
        (!v.is_empty()).then(|| [median(&v), percentile(&v, 95.0)])
    };
    let stage = |f: &dyn Fn(&tactile_pipeline::FrameRecord) -> Option<f64>| -> String {
        stats(f).map_or("-".into(), |[m, p]| format!("{m:.2} / {p:.2} ms"))
    };
    let stages_ms = serde_json::json!({
        "detect": stats(&|r| Some(r.ms_detect)),
        "segment": stats(&|r| r.ms_segment),
        "depth": stats(&|r| r.ms_depth),
        "frame": stats(&|r| Some(r.ms_total)),
        "tendon_frame": stats(&|r| r.tendon.then_some(r.ms_total)),
    });
    let gated = records.iter().filter(|r| !r.tendon).count();
    let (acc_raw, flips_raw) = decisions(&records, &paths, true);
    let (acc, flips) = decisions(&records, &paths, false);
    let truth_changes = (1..paths.len())
        .filter(|&i| paths[i].1 == paths[i - 1].1 && paths[i].2 != paths[i - 1].2)
        .count();
    let summary = serde_json::json!({
        "frames": records.len(),
        "overlapped_decoding": overlap,
        "missing_frames": missing.len(),
        "runtime": a.runtime,
        "threads": threads,
        "fps": records.len() as f64 / wall.max(1e-9),
        "gated_out": gated,
        "tendon_frames": records.len() - gated,
        "detector_accuracy": acc,
        "decision_changes": flips,
        "detector_accuracy_threshold_only": acc_raw,
        "decision_changes_threshold_only": flips_raw,
        "label_changes": truth_changes,
        "hysteresis": a.hysteresis,
        "stages_ms": stages_ms,
    });
    println!(
        "{} frames in {:.2} s ({:.1} frames/s, {:?}, decoding included); {} without a tendon cost one detector pass",
        records.len(),
        wall,
        records.len() as f64 / wall.max(1e-9),
        a.runtime,
        gated
    );
    println!(
        "median / p95 per stage: detect {}, segment + direction {}, depth {}, whole frame {}",
        stage(&|r| Some(r.ms_detect)),
        stage(&|r| r.ms_segment),
        stage(&|r| r.ms_depth),
        stage(&|r| Some(r.ms_total))
    );
    if let Some(acc) = acc {
        println!(
            "tendon decisions: accuracy {acc:.4} with {flips} changes within sequences ({} changes in the labels); the detector's threshold alone: {:.4}, {flips_raw} changes",
            truth_changes,
            acc_raw.unwrap_or(f64::NAN)
        );
    }
    if let Some(out) = &a.out {
        println!("records in {}", out.display());
    }
    println!("{summary}");
    Ok(())
}
