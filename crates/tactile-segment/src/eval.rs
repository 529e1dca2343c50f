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
    /// "median / p90" in degrees, or "-" when no frame had both a
    /// direction and a direction label (a set whose rows leave
    /// `direction_deg` empty): no error to summarise, not NaN degrees.
    fn median_p90(&self) -> String {
        match self.frames {
            0 => "-".to_string(),
            _ => format!("{:.2} / {:.2}", self.median_deg, self.p90_deg),
        }
    }

    /// Over a group of `frames` frames, those with a direction (`found`),
    /// each with its error when the frame has a direction label: coverage
    /// counts every direction, labelled or not.
    fn new(frames: usize, found: &[Option<f64>]) -> Self {
        let errors: Vec<f64> = found.iter().flatten().copied().collect();
        let stat = |f: &dyn Fn(&[f64]) -> f64| {
            if errors.is_empty() {
                f64::NAN
            } else {
                f(&errors)
            }
        };
        Self {
            frames: errors.len(),
            no_direction: frames - found.len(),
            coverage: found.len() as f64 / frames.max(1) as f64,
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
                "| {} | {} | {:.4} | {:.1} % ({} without) | {} | {:.1} % | {} |",
                r.path,
                r.frames,
                r.mean_iou,
                100.0 * d.coverage,
                d.no_direction,
                d.median_p90(),
                100.0 * b.coverage,
                b.median_p90(),
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
    let frame_size = (ds.manifest.width as usize, ds.manifest.height as usize);
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
    // (path, IoU, direction by the artifact's method, by the baseline:
    // each `None` when not found, else its error when labelled)
    type Found = Option<Option<f64>>;
    let mut per: Vec<(String, f64, Found, Found)> = Vec::new();
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
            let window = set.image(i);
            let shading = segmenter.shading_window(&window, frame_size);
            let image = shading.unwrap_or(window);
            // `None`: no direction found; `Some(None)`: a direction, and no
            // label to score it against; `Some(Some(error))`.
            let error = |cfg: &PostprocessConfig| -> Result<Option<Option<f64>>> {
                let evidence = Evidence {
                    probabilities: Some(p),
                    window: Some(&image),
                };
                let t = postprocess(&mask, evidence, cfg)?;
                Ok(t.direction
                    .ok()
                    .map(|d| truth.map(|truth| direction_error_deg(d.angle_deg, truth))))
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
        let errs: Vec<Option<f64>> = sel.iter().filter_map(|p| p.2).collect();
        let base: Vec<Option<f64>> = sel.iter().filter_map(|p| p.3).collect();
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A group of frames none of which has a direction label is scored for
    /// its IoU and how many got a direction, its errors shown as "-" (not
    /// NaN); a group of no frames has no score at all.
    #[test]
    fn groups_without_direction_labels_or_frames_print_no_nan() {
        let group = |path: &str, frames: usize, found: &[Option<f64>]| PathScores {
            path: path.into(),
            frames,
            mean_iou: if frames == 0 { -0.0 } else { 0.9 },
            direction: DirectionScores::new(frames, found),
            principal_axis: DirectionScores::new(frames, found),
        };
        let scores = SegmenterScores {
            paths: vec![
                group("all", 3, &[None, None]),
                group(CURVED, 0, &[]),
                group("straight", 3, &[Some(1.0), Some(2.0), Some(3.0)]),
            ],
            ms_per_window: 1.0,
            ms_postprocess: [0.1, 0.1],
            warning: None,
            frame_warnings: Vec::new(),
        };
        let lines = scores.describe("flex");
        // Two of three frames got a direction, neither labelled.
        assert_eq!(
            lines[2],
            "| all | 3 | 0.9000 | 66.7 % (1 without) | - | 66.7 % | - |"
        );
        assert_eq!(lines[3], format!("| {CURVED} | 0 | - | - | - | - | - |"));
        assert_eq!(
            lines[4],
            "| straight | 3 | 0.9000 | 100.0 % (0 without) | 2.00 / 2.80 | 100.0 % | 2.00 / 2.80 |"
        );
        assert!(lines.iter().all(|l| !l.contains("NaN")), "{lines:?}");
    }
}
