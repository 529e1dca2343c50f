//! The palpation pipeline over a list of frames: decoding on a second
//! thread ahead of the models, an optional hysteresis per sequence,
//! overlays, and a summary of speed and decisions.

use std::path::PathBuf;

use serde::Serialize;
use tactile_core::Runtime;
use tactile_core::image_io::RgbImage;
use tactile_core::metrics::{median, percentile};

use crate::hysteresis::Hysteresis;
use crate::palpation::{FrameRecord, Pipeline};
use crate::source::FrameList;
use crate::{Error, Result};

/// How a run goes.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Two-threshold filter on the detector per sequence: `(on, off)`.
    pub hysteresis: Option<(f32, f32)>,
    /// Decode the next frames on a second thread while the models run.
    pub overlap: bool,
    /// Write an overlay PNG per tendon frame into this folder.
    pub render: Option<PathBuf>,
}

/// Median and 95th percentile, ms.
pub type Spread = [f64; 2];

/// Per-stage times over the frames that ran each stage.
#[derive(Debug, Clone, Serialize)]
pub struct StageTimes {
    /// The detector (every frame).
    pub detect: Option<Spread>,
    /// Segmenter and direction (tendon frames).
    pub segment: Option<Spread>,
    /// Depth (tendon frames).
    pub depth: Option<Spread>,
    /// Every frame, whole.
    pub frame: Option<Spread>,
    /// Tendon frames, whole.
    pub tendon_frame: Option<Spread>,
}

/// What a run did, how fast and how well.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// Frames processed.
    pub frames: usize,
    /// Whether decoding overlapped the models.
    pub overlapped_decoding: bool,
    /// Frames missing from a numbered folder.
    pub missing_frames: u64,
    /// Where the networks ran.
    pub runtime: Runtime,
    /// onnxruntime intra-op threads.
    pub threads: usize,
    /// Frames per second, decoding included.
    pub fps: f64,
    /// Frames the detector gated out.
    pub gated_out: usize,
    /// Frames that went through every stage.
    pub tendon_frames: usize,
    /// Accuracy of the decisions against the labels, when there are labels.
    pub detector_accuracy: Option<f64>,
    /// Changes of decision within sequences.
    pub decision_changes: usize,
    /// Accuracy of the detector's threshold alone.
    pub detector_accuracy_threshold_only: Option<f64>,
    /// Changes of the threshold's decision within sequences.
    pub decision_changes_threshold_only: usize,
    /// Changes of the label within sequences.
    pub label_changes: usize,
    /// The hysteresis `[on, off]`, when used.
    pub hysteresis: Option<[f32; 2]>,
    /// Median and p95 per stage.
    pub stages_ms: StageTimes,
}

/// Every frame's record and the summary.
pub struct RunOutcome {
    /// One record per frame, in order.
    pub records: Vec<FrameRecord>,
    /// Speed and decisions.
    pub summary: RunSummary,
}

/// Accuracy against the labels and decision changes within sequences.
fn decisions(records: &[FrameRecord], frames: &FrameList, raw: bool) -> (Option<f64>, usize) {
    let f = &frames.frames;
    let pick = |r: &FrameRecord| if raw { r.tendon_raw } else { r.tendon };
    let labelled: Vec<(bool, bool)> = records
        .iter()
        .zip(f)
        .filter_map(|(r, e)| e.tendon.map(|t| (pick(r), t)))
        .collect();
    let acc = (!labelled.is_empty())
        .then(|| labelled.iter().filter(|(p, t)| p == t).count() as f64 / labelled.len() as f64);
    let changes = (1..records.len())
        .filter(|&i| {
            f[i].sequence == f[i - 1].sequence && pick(&records[i]) != pick(&records[i - 1])
        })
        .count();
    (acc, changes)
}

/// Run `pipeline` over `frames`. Overlays of tendon frames go to
/// `options.render` as `NAME-overlay.png`.
pub fn run(
    pipeline: &mut Pipeline,
    frames: &FrameList,
    options: &RunOptions,
) -> Result<RunOutcome> {
    // Overlays go to a staging folder first: an error or an interrupt
    // leaves no half set of them.
    let render = match &options.render {
        Some(dir) => {
            tactile_core::io::ensure_writable_dir(dir)?;
            Some(tactile_core::io::StagedDir::new(dir)?)
        }
        None => None,
    };
    let mut filter = options
        .hysteresis
        .map(|(on, off)| Hysteresis::new(on, off))
        .transpose()?;
    let list = &frames.frames;
    let pb = tactile_core::train::progress_bar(list.len() as u64, "run");
    let t0 = std::time::Instant::now();
    let mut records = Vec::with_capacity(list.len());
    // Decode the next frames on another thread while this one runs the
    // models (a queue of 4), or each frame just before it is processed.
    let (tx, rx) = std::sync::mpsc::sync_channel::<tactile_core::Result<RgbImage>>(4);
    let entries = list.clone();
    let decoder = options.overlap.then(|| {
        std::thread::spawn(move || {
            for e in entries {
                if tx.send(e.load()).is_err() {
                    break;
                }
            }
        })
    });
    for (k, entry) in list.iter().enumerate() {
        tactile_core::interrupt::check()?;
        let frame = if options.overlap {
            rx.recv().map_err(|_| {
                Error::Core(tactile_core::Error::Invalid(
                    "the frame decoder stopped".into(),
                ))
            })??
        } else {
            entry.load()?
        };
        let name = entry
            .path
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        if let Some(h) = filter.as_mut()
            && (k == 0 || list[k - 1].sequence != entry.sequence)
        {
            h.reset();
        }
        let (rec, views) = pipeline.process_filtered(&name, &frame, filter.as_mut())?;
        if let (Some(staged), Some(v)) = (&render, views) {
            let stem = entry.path.file_stem().unwrap_or_default().to_string_lossy();
            v.save_png(&staged.path().join(format!("{stem}-overlay.png")), 4)?;
        }
        records.push(rec);
        pb.inc(1);
    }
    drop(rx);
    if let Some(d) = decoder {
        let _ = d.join();
    }
    pb.finish_and_clear();
    if let Some(staged) = render {
        staged.commit_into()?;
    }
    let wall = t0.elapsed().as_secs_f64();
    let stats = |f: &dyn Fn(&FrameRecord) -> Option<f64>| -> Option<Spread> {
        let v: Vec<f64> = records.iter().filter_map(f).collect();
        (!v.is_empty()).then(|| [median(&v), percentile(&v, 95.0)])
    };
    let stages_ms = StageTimes {
        detect: stats(&|r| Some(r.ms_detect)),
        segment: stats(&|r| r.ms_segment),
        depth: stats(&|r| r.ms_depth),
        frame: stats(&|r| Some(r.ms_total)),
        tendon_frame: stats(&|r| r.tendon.then_some(r.ms_total)),
    };
    let gated = records.iter().filter(|r| !r.tendon).count();
    let (acc_raw, flips_raw) = decisions(&records, frames, true);
    let (acc, flips) = decisions(&records, frames, false);
    let label_changes = (1..list.len())
        .filter(|&i| {
            list[i].sequence == list[i - 1].sequence && list[i].tendon != list[i - 1].tendon
        })
        .count();
    let summary = RunSummary {
        frames: records.len(),
        overlapped_decoding: options.overlap,
        missing_frames: frames.missing_frames().count,
        runtime: pipeline.detector.runtime(),
        threads: pipeline.threads,
        fps: records.len() as f64 / wall.max(1e-9),
        gated_out: gated,
        tendon_frames: records.len() - gated,
        detector_accuracy: acc,
        decision_changes: flips,
        detector_accuracy_threshold_only: acc_raw,
        decision_changes_threshold_only: flips_raw,
        label_changes,
        hysteresis: options.hysteresis.map(|(on, off)| [on, off]),
        stages_ms,
    };
    Ok(RunOutcome { records, summary })
}
