//! Frames of another sensor given to paper A's models: how many frames of
//! each set each TacTip model's pin profile (its training frames' pin
//! spectrum, [`InputProfile::fit_pins`]) flags, and their scores. What
//! `predict` warns of, measured.

use std::path::{Path, PathBuf};

use serde::Serialize;
use tactile_core::dataset::Dataset;
use tactile_core::image_io::GreyImage;
use tactile_preprocess::profile::InputProfile;
use tactile_preprocess::{PreprocessConfig, is_flat_frame, preprocess};

use crate::Result;

/// One model on one set of frames.
#[derive(Debug, Clone, Serialize)]
pub struct PinProfileRow {
    /// The model folder.
    pub model: String,
    /// The frames: a dataset, or a folder of frames.
    pub data: String,
    /// Frames scored (flat ones are left to their own warning).
    pub frames: usize,
    /// Frames scoring above the threshold.
    pub flagged: usize,
    /// Median score.
    pub median: f32,
    /// Largest score.
    pub max: f32,
    /// The profile's threshold.
    pub threshold: f32,
}

/// Each of up to `limit` grey frames of `data` handed to `each`, one at a
/// time: a dataset's rows (those of `split` when given: a dataset without
/// them is refused) evenly spaced, or a frame source's first.
fn each_frame_of(
    data: &Path,
    limit: usize,
    split: Option<&str>,
    mut each: impl FnMut(&GreyImage) -> Result<()>,
) -> Result<()> {
    use tactile_core::source::{FrameSource, SourceOptions, SourceSpec};
    if data.join("manifest.json").is_file() {
        let ds = Dataset::open(data)?;
        let rows = tactile_pipeline::profile::rows_of(&ds, split)?;
        let step = rows.len().div_ceil(limit.max(1)).max(1);
        for &i in rows.iter().step_by(step) {
            each(&ds.load_grey(i, "file")?)?;
        }
        return Ok(());
    }
    let options = SourceOptions {
        limit: Some(limit as u64),
        ..SourceOptions::default()
    };
    let mut source = FrameSource::open(&SourceSpec::Path(data.to_path_buf()), options)?;
    while let Some(f) = source.next_frame()? {
        each(&f.grey()?)?;
    }
    // Frames skipped as undecodable are told, not silently left out.
    source
        .late_warnings()
        .iter()
        .for_each(|w| tactile_core::note!("{w}"));
    Ok(())
}

/// What the pin-profile bench reads (`tactile bench pin-profile`'s flags).
#[derive(Debug, Clone, clap::Args)]
pub struct PinProfileBench {
    /// TacTip model folders (encoders, pose networks or ensembles) with a pin profile.
    #[arg(long, num_args = 1.., required = true)]
    pub models: Vec<PathBuf>,
    /// Sets of frames: datasets, folders of frames, videos.
    #[arg(long, num_args = 1.., required = true)]
    pub data: Vec<PathBuf>,
    /// Frames read of each set at most (a dataset's rows evenly spaced).
    #[arg(long, default_value_t = 400, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,
    /// Only a dataset's rows whose `split` column says this (e.g. val: frames a profile fitted on `train` never saw).
    #[arg(long)]
    pub split: Option<String>,
}

/// Every model of `b.models` on up to `b.frames` frames of every set of
/// `b.data` (a dataset's rows of `b.split` alone, when given). Each frame
/// is read once and scored by every model; only the scores are kept.
pub fn bench_pin_profiles(b: &PinProfileBench) -> Result<Vec<PinProfileRow>> {
    let (models, data, limit, split) = (&b.models, &b.data, b.frames as usize, b.split.as_deref());
    let profiles: Vec<(PreprocessConfig, InputProfile)> = models
        .iter()
        .map(|m| Ok(tactile_pipeline::profile::model_pin_profile(m)?))
        .collect::<Result<_>>()?;
    // Per set, per model, the scores of its frames that are not flat.
    let mut scores: Vec<Vec<Vec<f32>>> = Vec::with_capacity(data.len());
    for d in data {
        let mut per_model = vec![Vec::new(); models.len()];
        each_frame_of(d, limit, split, |f| {
            for ((cfg, profile), s) in profiles.iter().zip(&mut per_model) {
                if !is_flat_frame(f, cfg) {
                    s.push(profile.score_pins(&preprocess(f, cfg)?));
                }
            }
            Ok(())
        })?;
        scores.push(per_model);
    }
    let mut rows = Vec::new();
    for (k, (m, (_, profile))) in models.iter().zip(&profiles).enumerate() {
        for (d, per_model) in data.iter().zip(&mut scores) {
            let s = &mut per_model[k];
            s.sort_by(f32::total_cmp);
            rows.push(PinProfileRow {
                model: m.display().to_string(),
                data: d.display().to_string(),
                frames: s.len(),
                flagged: s.iter().filter(|&&v| v > profile.threshold).count(),
                median: s.get(s.len() / 2).copied().unwrap_or(f32::NAN),
                max: s.last().copied().unwrap_or(f32::NAN),
                threshold: profile.threshold,
            });
        }
    }
    Ok(rows)
}

/// The table of [`bench_pin_profiles`] (`split` as given to it).
pub fn pin_profile_markdown(rows: &[PinProfileRow], b: &PinProfileBench) -> String {
    let (limit, split) = (b.frames as usize, b.split.as_deref());
    let rows_of = match split {
        Some(s) => format!("a dataset's `{s}` rows evenly spaced"),
        None => "a dataset's rows evenly spaced".to_string(),
    };
    let mut md = format!(
        "Each TacTip model's pin profile (where its training frames' pin images hold their power across \
         spatial frequencies, saved in its config) against up to {limit} frames of each set ({rows_of}, \
         a folder's first frames); a frame scoring above the model's threshold is \
         named in a warning by `predict`. Blank frames are left to their own warning.\n\n\
         | model | frames of | scored | flagged | flagged (%) | median score | largest score | threshold |\n\
         |---|---|---|---|---|---|---|---|\n"
    );
    for r in rows {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} |\n",
            r.model,
            r.data,
            r.frames,
            r.flagged,
            100.0 * r.flagged as f64 / r.frames.max(1) as f64,
            r.median,
            r.max,
            r.threshold
        ));
    }
    md
}
