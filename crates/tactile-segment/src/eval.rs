//! The segmenter scored on the tendon frames of a labelled dataset: mean
//! IoU of the thresholded mask over all frames, curved tendons and each
//! path, and the direction error of the post-processed region.

use serde::Serialize;
use tactile_core::dataset::Dataset;
use tactile_core::metrics::{iou, median, percentile};

use crate::data::SegmentSet;
use crate::inference::TendonSegmenter;
use crate::postprocess::{TendonMask, direction_error_deg, postprocess};
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
    /// Frames with a direction and a direction label.
    pub direction_frames: usize,
    /// Frames without a direction.
    pub no_direction: usize,
    /// Median direction error, degrees.
    pub direction_median_deg: f64,
    /// 90th percentile of the direction error, degrees.
    pub direction_p90_deg: f64,
}

/// A segmenter's scores on a dataset.
#[derive(Debug, Clone, Serialize)]
pub struct SegmenterScores {
    /// `all`, curved, then each path in name order.
    pub paths: Vec<PathScores>,
    /// Inference time per window (batches of [`EVAL_BATCH`], cutting excluded).
    pub ms_per_window: f64,
}

impl SegmenterScores {
    /// The scores as a Markdown table per path and a timing line
    /// (`device`: where it ran).
    pub fn describe(&self, device: impl std::fmt::Display) -> Vec<String> {
        let mut lines = vec![
            "| tendon path | frames | mean IoU | direction median (deg) | direction p90 (deg) | no direction |".to_string(),
            "|---|---|---|---|---|---|".to_string(),
        ];
        for r in &self.paths {
            lines.push(format!(
                "| {} | {} | {:.4} | {:.2} | {:.2} | {} |",
                r.path,
                r.frames,
                r.mean_iou,
                r.direction_median_deg,
                r.direction_p90_deg,
                r.no_direction
            ));
        }
        lines.push(format!(
            "{:.2} ms per window ({device}, batch {EVAL_BATCH}, cut excluded)",
            self.ms_per_window
        ));
        lines
    }

    /// The row of `path` (`all`, [`CURVED`], `straight`, ...).
    pub fn path(&self, path: &str) -> Option<&PathScores> {
        self.paths.iter().find(|r| r.path == path)
    }
}

/// Score `segmenter` on every tendon frame of `ds`.
pub fn evaluate(segmenter: &mut TendonSegmenter, ds: &Dataset) -> Result<SegmenterScores> {
    let art = segmenter.artifact.clone();
    let rows = ds.tendon_rows(&(0..ds.len()).collect::<Vec<_>>())?;
    if rows.is_empty() {
        return Err(Error::NoTendonFrames {
            path: ds.labels_path(),
            why: "score",
        });
    }
    let set = SegmentSet::from_dataset(ds, &rows, art.window(), 1, 0)?;
    let idx: Vec<usize> = (0..set.len()).collect();
    let t0 = std::time::Instant::now();
    let mut probs = Vec::with_capacity(set.len());
    for chunk in idx.chunks(EVAL_BATCH) {
        let mut x = Vec::new();
        for &i in chunk {
            x.extend(art.window_input(&set.image(i))?);
        }
        probs.extend(segmenter.probabilities(&x, chunk.len())?);
    }
    let ms_per_window = 1e3 * t0.elapsed().as_secs_f64() / set.len() as f64;
    let s = art.model.side;
    let mut per: Vec<(String, f64, Option<f64>)> = Vec::new();
    for (i, p) in probs.iter().enumerate() {
        let w = &set.windows[i];
        let mask = TendonMask::from_probabilities(s, s, p, art.threshold)?;
        let score = iou(&mask.pixels, &w.mask);
        let t = postprocess(&mask, &art.postprocess)?;
        let err = match (t.direction, set.direction_deg[w.row]) {
            (Ok(d), Some(truth)) => Some(direction_error_deg(d.angle_deg, truth)),
            _ => None,
        };
        let path = set.path[w.row].clone().unwrap_or_else(|| "unknown".into());
        per.push((path, score, err));
    }
    let mut paths: Vec<String> = per.iter().map(|p| p.0.clone()).collect();
    paths.sort();
    paths.dedup();
    let summarise = |name: &str, keep: &dyn Fn(&str) -> bool| {
        let sel: Vec<&(String, f64, Option<f64>)> = per.iter().filter(|p| keep(&p.0)).collect();
        let errs: Vec<f64> = sel.iter().filter_map(|p| p.2).collect();
        let stat = |f: &dyn Fn(&[f64]) -> f64| if errs.is_empty() { f64::NAN } else { f(&errs) };
        PathScores {
            path: name.to_string(),
            frames: sel.len(),
            mean_iou: sel.iter().map(|p| p.1).sum::<f64>() / sel.len().max(1) as f64,
            direction_frames: errs.len(),
            no_direction: sel.len() - errs.len(),
            direction_median_deg: stat(&median),
            direction_p90_deg: stat(&|e| percentile(e, 90.0)),
        }
    };
    let mut table = vec![summarise("all", &|_| true)];
    table.push(summarise(CURVED, &|p| p == "arc" || p == "s-curve"));
    for p in &paths {
        table.push(summarise(p, &|q| q == p));
    }
    Ok(SegmenterScores {
        paths: table,
        ms_per_window,
    })
}
