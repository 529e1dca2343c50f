//! The segmenter scored on the tendon frames of a labelled dataset: mean
//! IoU of the thresholded mask over all frames, curved tendons and each
//! path, and the direction error of the post-processed region, by the
//! artifact's direction method and by the principal-axis baseline.

use serde::Serialize;
use tactile_core::dataset::Dataset;
use tactile_core::metrics::{iou, median, percentile};

use crate::data::SegmentSet;
use crate::inference::TendonSegmenter;
use crate::postprocess::{
    DirectionMethod, Evidence, PostprocessConfig, TendonMask, direction_error_deg, postprocess,
};
use crate::{Error, Result};

/// Windows per network call when scoring.
pub const EVAL_BATCH: usize = 32;

/// The name of the row over curved tendons.
pub const CURVED: &str = "curved (arc + s-curve)";

/// Scores over one group of tendon frames.
#[derive(Debug, Clone, Serialize)]
pub struct PathScores {
    /// `all`, [`CURVED`], or a tendon path.
    pub path: String,
    /// Tendon frames in the group.
    pub frames: usize,
    /// Mean IoU of the thresholded mask.
    pub mean_iou: f64,
    /// Direction by the artifact's method.
    pub direction: DirectionScores,
    /// Direction by the principal axis of the region (paper B's baseline).
    pub principal_axis: DirectionScores,
}

/// Direction errors over one group of tendon frames.
#[derive(Debug, Clone, Serialize)]
pub struct DirectionScores {
    /// Frames with a direction and a direction label.
    pub frames: usize,
    /// Frames without a direction.
    pub no_direction: usize,
    /// Fraction of the group's frames with a direction.
    pub coverage: f64,
    /// Median direction error, degrees.
    pub median_deg: f64,
    /// 90th percentile of the direction error, degrees.
    pub p90_deg: f64,
}

impl DirectionScores {
    fn new(frames: usize, errors: &[f64]) -> Self {
        let stat = |f: &dyn Fn(&[f64]) -> f64| {
            if errors.is_empty() {
                f64::NAN
            } else {
                f(errors)
            }
        };
        Self {
            frames: errors.len(),
            no_direction: frames - errors.len(),
            coverage: errors.len() as f64 / frames.max(1) as f64,
            median_deg: stat(&median),
            p90_deg: stat(&|e| percentile(e, 90.0)),
        }
    }
}

/// A segmenter's scores on a dataset.
#[derive(Debug, Clone, Serialize)]
pub struct SegmenterScores {
    /// `all`, curved, then each path in name order.
    pub paths: Vec<PathScores>,
    /// Inference time per window (batches of [`EVAL_BATCH`], cutting excluded).
    pub ms_per_window: f64,
    /// Post-processing time per window (regions and direction): by the
    /// artifact's method, and by the principal-axis baseline.
    pub ms_postprocess: [f64; 2],
    /// Set when the model's notes say it trained on every frame scored
    /// ([`tactile_burn::artifact::scored_on_fitted`]): the words saying
    /// these are not held-out scores, for the front ends to show.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<String>,
    /// What reading the frames found, each starting "warning: ": tendon
    /// frames that could not be decoded past their header, left out of the
    /// scores.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub frame_warnings: Vec<String>,
}

impl SegmenterScores {
    /// The scores as a Markdown table per path and a timing line
    /// (`device`: where it ran).
    pub fn describe(&self, device: impl std::fmt::Display) -> Vec<String> {
        let mut lines = vec![
            "| tendon path | frames | mean IoU | direction coverage | direction median / p90 (deg) | principal axis (baseline): coverage | median / p90 (deg) |".to_string(),
            "|---|---|---|---|---|---|---|".to_string(),
        ];
        for r in &self.paths {
            // A group without a frame (no curved tendon in the set) has no
            // score: "-", not an IoU of 0 and NaN degrees.
            if r.frames == 0 {
                lines.push(format!("| {} | 0 | - | - | - | - | - |", r.path));
                continue;
            }
            let (d, b) = (&r.direction, &r.principal_axis);
            lines.push(format!(
                "| {} | {} | {:.4} | {:.1} % ({} without) | {:.2} / {:.2} | {:.1} % | {:.2} / {:.2} |",
                r.path,
                r.frames,
                r.mean_iou,
                100.0 * d.coverage,
                d.no_direction,
                d.median_deg,
                d.p90_deg,
                100.0 * b.coverage,
                b.median_deg,
                b.p90_deg,
            ));
        }
        lines.push(format!(
            "{:.2} ms per window ({device}, batch {EVAL_BATCH}, cut excluded); post-processing {:.3} ms per window (principal axis {:.3} ms)",
            self.ms_per_window, self.ms_postprocess[0], self.ms_postprocess[1]
        ));
        lines
    }

    /// The row of `path` (`all`, [`CURVED`], `straight`, ...).
    pub fn path(&self, path: &str) -> Option<&PathScores> {
        self.paths.iter().find(|r| r.path == path)
    }
}

/// Tendon rows of a dataset loaded at once when scoring it: memory stays
/// bounded however many frames the dataset has.
pub const EVAL_CHUNK: usize = 512;

/// Score `segmenter` on every tendon frame of `ds`.
pub fn evaluate(segmenter: &mut TendonSegmenter, ds: &Dataset) -> Result<SegmenterScores> {
    evaluate_in_chunks(segmenter, ds, EVAL_CHUNK)
}

/// The segmenter in `model` scored on the labelled dataset in `data`
/// ([`evaluate`]), with a warning when its notes say it trained on every
/// one of those frames: what `tactile eval segmenter` and
/// `tactile.eval.segmenter` print and return.
pub fn evaluate_folder(
    model: &std::path::Path,
    data: &std::path::Path,
    runtime: tactile_burn::Runtime,
) -> Result<SegmenterScores> {
    let mut seg = TendonSegmenter::load(model, runtime, 0)?;
    let ds = Dataset::open(data)?;
    let mut sc = evaluate(&mut seg, &ds)?;
    sc.warning = tactile_burn::artifact::scored_on_fitted::<crate::SegmenterArtifact>(model, &ds);
    Ok(sc)
}

/// [`evaluate`] reading `chunk_rows` tendon rows at a time (the scores do
/// not depend on it).
pub fn evaluate_in_chunks(
    segmenter: &mut TendonSegmenter,
    ds: &Dataset,
    chunk_rows: usize,
) -> Result<SegmenterScores> {
    let art = segmenter.artifact.clone();
    let rows = ds.tendon_rows(&(0..ds.len()).collect::<Vec<_>>())?;
    if rows.is_empty() {
        return Err(Error::NoTendonFrames {
            path: ds.labels_path(),
            why: "score",
        });
    }
    ds.check_frame_headers(&rows)?;
    let s = art.model.side;
    let baseline = PostprocessConfig {
        direction: DirectionMethod::PrincipalAxis,
        ..art.postprocess
    };
    // (path, IoU, error by the artifact's method, error by the baseline)
    let mut per: Vec<(String, f64, Option<f64>, Option<f64>)> = Vec::new();
    let mut post = [0.0f64; 2];
    let mut network_seconds = 0.0;
    // A frame that cannot be decoded past its header is left out, as every
    // reader of frames leaves it ([`UndecodableFrames`]).
    let mut skipped = tactile_core::source::UndecodableFrames::new(rows.len());
    for part in rows.chunks(chunk_rows.max(1)) {
        let window = art.model.window();
        let set = SegmentSet::from_dataset_skipping(ds, part, window, 1, 0, &mut skipped)?;
        let idx: Vec<usize> = (0..set.len()).collect();
        let t0 = std::time::Instant::now();
        let mut probs = Vec::with_capacity(set.len());
        for chunk in idx.chunks(EVAL_BATCH) {
            let mut x = Vec::new();
            for &i in chunk {
                x.extend(art.model.window_input(&set.image(i), &art.stats)?);
            }
            probs.extend(segmenter.probabilities(&x, chunk.len())?);
        }
        network_seconds += t0.elapsed().as_secs_f64();
        for (i, p) in probs.iter().enumerate() {
            let w = &set.windows[i];
            let mask = TendonMask::from_probabilities(s, s, p, art.threshold)?;
            let score = iou(&mask.pixels, &w.mask);
            let truth = w.direction_deg;
            let image = set.image(i);
            let error = |cfg: &PostprocessConfig| -> Result<Option<f64>> {
                let evidence = Evidence {
                    probabilities: Some(p),
                    window: Some(&image),
                };
                let t = postprocess(&mask, evidence, cfg)?;
                Ok(match (t.direction, truth) {
                    (Ok(d), Some(truth)) => Some(direction_error_deg(d.angle_deg, truth)),
                    _ => None,
                })
            };
            let path = w.path.clone().unwrap_or_else(|| "unknown".into());
            let t1 = std::time::Instant::now();
            let e1 = error(&art.postprocess)?;
            let t2 = std::time::Instant::now();
            let e2 = error(&baseline)?;
            post[0] += (t2 - t1).as_secs_f64();
            post[1] += t2.elapsed().as_secs_f64();
            per.push((path, score, e1, e2));
        }
    }
    let frame_warnings = skipped.warning().into_iter().collect();
    skipped.finish(per.len())?;
    let windows = per.len().max(1) as f64;
    let mut paths: Vec<String> = per.iter().map(|p| p.0.clone()).collect();
    paths.sort();
    paths.dedup();
    let summarise = |name: &str, keep: &dyn Fn(&str) -> bool| {
        let sel: Vec<_> = per.iter().filter(|p| keep(&p.0)).collect();
        let errs: Vec<f64> = sel.iter().filter_map(|p| p.2).collect();
        let base: Vec<f64> = sel.iter().filter_map(|p| p.3).collect();
        PathScores {
            path: name.to_string(),
            frames: sel.len(),
            mean_iou: sel.iter().map(|p| p.1).sum::<f64>() / sel.len().max(1) as f64,
            direction: DirectionScores::new(sel.len(), &errs),
            principal_axis: DirectionScores::new(sel.len(), &base),
        }
    };
    let mut table = vec![summarise("all", &|_| true)];
    table.push(summarise(CURVED, &|p| p == "arc" || p == "s-curve"));
    for p in &paths {
        table.push(summarise(p, &|q| q == p));
    }
    Ok(SegmenterScores {
        paths: table,
        ms_per_window: 1e3 * network_seconds / windows,
        ms_postprocess: post.map(|t| 1e3 * t / windows),
        warning: None,
        frame_warnings,
    })
}
