//! `tactile run`: the palpation pipeline over a dataset or a folder of
//! frames; JSON Lines records and a speed summary.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use tactile_core::Runtime;
use tactile_pipeline::{FrameList, Pipeline, RunOptions};

#[derive(Args)]
pub(crate) struct RunArgs {
    /// A visuo-tactile dataset (frames in labels.csv order) or a folder of
    /// PNG frames (in name order, e.g. a 30 fps video as numbered PNGs).
    #[arg(long)]
    data: PathBuf,
    /// Folder with detector/, segmenter/ and depth/.
    #[arg(long, default_value = "models")]
    models: PathBuf,
    /// Where the networks run (onnx is the fastest here).
    #[arg(long, value_enum, default_value_t = Runtime::Onnx)]
    runtime: Runtime,
    /// onnxruntime intra-op threads. Default 1: these models are small
    /// enough that a second thread costs more than it gains (measured:
    /// 159 against 350 frames/s without overlap), and the other core
    /// decodes the next frames.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=256))]
    threads: u16,
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

pub(crate) fn main(a: RunArgs) -> Result<()> {
    let hysteresis = match a.hysteresis.as_deref() {
        None => None,
        Some(&[on, off]) => Some((on, off)),
        Some(v) => bail!("--hysteresis takes ON,OFF (two probabilities), got {v:?}"),
    };
    // The input first: a bad folder is reported before any model loads.
    let mut frames = FrameList::open(&a.data)?;
    // Outputs next: an unwritable folder, or one of the inputs, fails now,
    // not after the run.
    let input = match frames.is_dataset {
        true => Some(tactile_core::dataset::Dataset::open(&a.data)?),
        false => None,
    };
    let inputs: Vec<_> = input.iter().collect();
    if let Some(out) = &a.out {
        tactile_core::io::check_output_file(out, &inputs)?;
    }
    if let Some(dir) = &a.render {
        tactile_core::io::check_output_dir(dir, &inputs)?;
    }
    let mut pipeline = Pipeline::load(&a.models, a.runtime, a.threads as usize)?;
    if let Some(n) = a.limit {
        frames.truncate(n);
    }
    let missing = frames.missing_frames();
    if missing.count > 0 {
        tactile_core::note!(
            "warning: {} frame(s) missing from the numbering, e.g. {:?}",
            missing.count,
            missing.first
        );
    }
    let options = RunOptions {
        hysteresis,
        overlap: !a.no_overlap,
        render: a.render.clone(),
    };
    let r = tactile_pipeline::run(&mut pipeline, &frames, &options)?;
    if let Some(out) = &a.out {
        tactile_core::io::write_atomic_with(out, |w| {
            for rec in &r.records {
                writeln!(
                    w,
                    "{}",
                    serde_json::to_string(rec).map_err(std::io::Error::other)?
                )?;
            }
            Ok(())
        })?;
    }
    let s = &r.summary;
    let stage = |v: Option<[f64; 2]>| v.map_or("-".into(), |[m, p]| format!("{m:.2} / {p:.2} ms"));
    say!(
        "{} frames ({:.1} frames/s, {}, decoding included); {} without a tendon cost one detector pass",
        s.frames,
        s.fps,
        s.runtime,
        s.gated_out
    );
    say!(
        "median / p95 per stage: detect {}, segment + direction {}, depth {}, whole frame {}",
        stage(s.stages_ms.detect),
        stage(s.stages_ms.segment),
        stage(s.stages_ms.depth),
        stage(s.stages_ms.frame)
    );
    if let Some(acc) = s.detector_accuracy {
        say!(
            "tendon decisions: accuracy {acc:.4} with {} changes within sequences ({} changes in the labels); the detector's threshold alone: {:.4}, {} changes",
            s.decision_changes,
            s.label_changes,
            s.detector_accuracy_threshold_only.unwrap_or(f64::NAN),
            s.decision_changes_threshold_only
        );
    }
    if let Some(out) = &a.out {
        say!("records in {}", out.display());
    }
    say!("{}", serde_json::to_string(s)?);
    Ok(())
}
