//! The depth network scored on a labelled dataset: MAE inside the sensing
//! window and over the tendon mask, RMSE and SSIM, all in millimetres; and
//! heat maps of truth beside prediction.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tactile_burn::Runtime;
use tactile_core::dataset::Dataset;

use crate::Result;
use crate::data::DepthSet;
use crate::inference::DepthEstimator;

/// Frames per network call when scoring.
pub const EVAL_BATCH: usize = 16;

/// Depth metrics of predictions against truth, in millimetres.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct DepthScores {
    /// Frames scored.
    pub frames: usize,
    /// Mean absolute error inside the sensing window.
    pub mae_mm: f64,
    /// Mean absolute error over the tendon mask (frames with a tendon).
    pub mae_tendon_mm: Option<f64>,
    /// Root mean squared error inside the window, over frames.
    pub rmse_mm: f64,
    /// Mean SSIM over frames (dynamic range: the 12-18 mm of the spec).
    pub ssim: f64,
}

impl DepthScores {
    /// The scores and a timing line (`ms` per frame on `device`).
    pub fn describe(&self, ms: f64, device: impl std::fmt::Display) -> Vec<String> {
        vec![
            format!(
                "{} frames: MAE {:.4} mm in the window, {} over the tendon mask, RMSE {:.4} mm, SSIM {:.4}",
                self.frames,
                self.mae_mm,
                self.mae_tendon_mm
                    .map_or("-".into(), |v| format!("{v:.4} mm")),
                self.rmse_mm,
                self.ssim
            ),
            format!("{ms:.2} ms per frame ({device}, batch {EVAL_BATCH}, loading excluded)"),
        ]
    }
}

/// Dynamic range used by SSIM, mm (sensors.md: depths lie in 12-18 mm).
pub const DEPTH_RANGE_MM: f64 = 6.0;

/// Accumulates per-frame metrics.
#[derive(Default)]
pub struct DepthScorer {
    n: usize,
    mae: f64,
    rmse_sq: f64,
    ssim: f64,
    tendon_abs: f64,
    tendon_px: usize,
}

impl DepthScorer {
    /// Add one frame (`w x h` maps in mm).
    pub fn add(
        &mut self,
        pred: &[f32],
        truth: &[f32],
        window: &[bool],
        mask: &[bool],
        (w, h): (usize, usize),
    ) {
        use tactile_core::metrics::{masked_mae, masked_rmse, ssim};
        self.n += 1;
        self.mae += masked_mae(pred, truth, Some(window)).unwrap_or(0.0);
        self.rmse_sq += masked_rmse(pred, truth, Some(window))
            .unwrap_or(0.0)
            .powi(2);
        self.ssim += ssim(pred, truth, w, h, DEPTH_RANGE_MM);
        for i in 0..pred.len() {
            if mask[i] {
                self.tendon_abs += (pred[i] as f64 - truth[i] as f64).abs();
                self.tendon_px += 1;
            }
        }
    }

    /// Add every sample of `data` with its predicted map.
    pub fn add_set(&mut self, data: &DepthSet, preds: &[Vec<f32>]) {
        for (s, p) in data.samples.iter().zip(preds) {
            self.add(
                p,
                &s.depth_mm,
                &data.window,
                &s.mask,
                (data.width, data.height),
            );
        }
    }

    /// The scores of every frame added.
    pub fn finish(&self) -> DepthScores {
        let n = self.n.max(1) as f64;
        DepthScores {
            frames: self.n,
            mae_mm: self.mae / n,
            mae_tendon_mm: (self.tendon_px > 0).then(|| self.tendon_abs / self.tendon_px as f64),
            rmse_mm: (self.rmse_sq / n).sqrt(),
            ssim: self.ssim / n,
        }
    }
}

/// Predicted depth in mm of every sample of `data`, one map per sample.
pub fn predict_mm(estimator: &mut DepthEstimator, data: &DepthSet) -> Result<Vec<Vec<f32>>> {
    let art = estimator.artifact.clone();
    let idx: Vec<usize> = (0..data.len()).collect();
    let mut out = Vec::with_capacity(data.len());
    for chunk in idx.chunks(EVAL_BATCH) {
        let x = data.inputs(chunk, &art.stats, &art.model, &art.scale)?;
        out.extend(estimator.depth_mm_of_inputs(&x, chunk.len())?);
    }
    Ok(out)
}

/// The frames at `rows` of `ds` as `estimator` reads them (its input
/// size, and its calibration's reconstruction for a network with a prior),
/// those that cannot be decoded past their header counted in `skipped`.
fn frames_for(
    estimator: &DepthEstimator,
    ds: &Dataset,
    rows: &[usize],
    skipped: &mut tactile_core::source::UndecodableFrames,
) -> Result<DepthSet> {
    DepthSet::from_dataset_skipping(
        ds,
        rows,
        estimator.artifact.model.input_size,
        estimator.prior_folder(),
        skipped,
    )
}

/// Rows of a dataset loaded at once when scoring it: memory stays bounded
/// however many frames the dataset has.
pub const EVAL_CHUNK: usize = 512;

/// Score `estimator` on every frame of `ds`, read [`EVAL_CHUNK`] rows at a
/// time; also the inference time per frame (batches of [`EVAL_BATCH`],
/// loading excluded), and the warning naming the frames that could not be
/// decoded past their header, left out of the scores
/// ([`DepthSet::for_each_chunk`]).
pub fn evaluate(
    estimator: &mut DepthEstimator,
    ds: &Dataset,
) -> Result<(DepthScores, f64, Option<String>)> {
    evaluate_in_chunks(estimator, ds, EVAL_CHUNK)
}

/// [`evaluate`] reading `chunk_rows` rows at a time (the scores do not
/// depend on it).
pub fn evaluate_in_chunks(
    estimator: &mut DepthEstimator,
    ds: &Dataset,
    chunk_rows: usize,
) -> Result<(DepthScores, f64, Option<String>)> {
    same_maps(estimator, ds)?;
    let mut scorer = DepthScorer::default();
    let mut seconds = 0.0;
    let (size, prior) = (
        estimator.artifact.model.input_size,
        estimator.prior_folder().map(Path::to_path_buf),
    );
    let undecodable = DepthSet::for_each_chunk(ds, size, prior.as_deref(), chunk_rows, |data| {
        let t0 = std::time::Instant::now();
        let preds = predict_mm(estimator, &data)?;
        seconds += t0.elapsed().as_secs_f64();
        scorer.add_set(&data, &preds);
        Ok(())
    })?;
    let scores = scorer.finish();
    let ms = 1e3 * seconds / scores.frames.max(1) as f64;
    Ok((scores, ms, undecodable))
}

/// Refuse to score a model on maps of another kind (distances against
/// indentation), naming both.
fn same_maps(estimator: &DepthEstimator, ds: &Dataset) -> Result<()> {
    let (model, data) = (estimator.artifact.depth_maps, ds.manifest.depth_maps());
    if model != data {
        return Err(tactile_core::Error::dataset(
            ds.root.join("manifest.json"),
            None,
            format!(
                "its depth maps hold {}, the depth model predicts {}",
                data.name(),
                model.name()
            ),
        )
        .into());
    }
    Ok(())
}

/// Scores of predicted maps against a set's truth.
pub fn score(data: &DepthSet, preds: &[Vec<f32>]) -> DepthScores {
    let mut sc = DepthScorer::default();
    sc.add_set(data, preds);
    sc.finish()
}

/// Most heat maps one evaluation writes (each is a PNG of two maps).
pub const MAX_HEAT_MAPS: usize = 10_000;

/// What an evaluation writes beside its scores (`tactile eval depth`'s
/// flags, `tactile.eval.depth`'s keywords): written once here.
#[derive(Debug, Clone, clap::Args, Serialize, Deserialize)]
pub struct EvalOptions {
    /// Write heat maps of the skin's displacement from its rest dome in mm (true | predicted, one colour scale with its bar) for the first frames into this folder.
    #[arg(long)]
    pub save_png: Option<PathBuf>,
    /// How many frames `save_png` writes.
    #[arg(long, default_value_t = 8)]
    pub png_frames: usize,
}

impl Default for EvalOptions {
    fn default() -> Self {
        Self {
            save_png: None,
            png_frames: 8,
        }
    }
}

/// A depth network's evaluation as both front ends report it.
#[derive(Debug, Clone, Serialize)]
pub struct DepthEvaluation {
    /// The model folder.
    pub model: PathBuf,
    /// The dataset folder.
    pub data: PathBuf,
    /// The scores.
    pub scores: DepthScores,
    /// Inference time per frame, ms (batches of [`EVAL_BATCH`], loading
    /// excluded).
    pub ms_per_frame: f64,
    /// Heat maps written into `options.save_png`.
    pub heat_maps: usize,
    /// Set when the model's notes say it trained on every frame scored
    /// ([`tactile_burn::artifact::scored_on_fitted`]): the words saying
    /// these are not held-out scores, for the front ends to show.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<String>,
    /// What reading the frames found, each starting "warning: ": frames
    /// that could not be decoded past their header, left out of the scores
    /// and the heat maps.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub frame_warnings: Vec<String>,
}

/// The depth network in `model` scored on the labelled dataset in `data`,
/// with the heat maps `options` ask for (the folder checked to lie outside
/// the dataset before anything runs, written whole or not at all): what
/// both front ends call.
pub fn evaluate_folder(
    model: &Path,
    data: &Path,
    runtime: Runtime,
    options: &EvalOptions,
) -> Result<DepthEvaluation> {
    if options.save_png.is_none() && options.png_frames != EvalOptions::default().png_frames {
        return Err(tactile_core::Error::Config(format!(
            "png_frames {}: the heat maps save_png writes, and no save_png folder is given: \
             give save_png too, or leave png_frames out",
            options.png_frames
        ))
        .into());
    }
    let ds = Dataset::open(data)?;
    if let Some(dir) = &options.save_png {
        ds.refuse_as_output(dir)?;
        // Asking for a folder of heat maps and for none of them is a
        // contradiction, not an empty folder.
        if options.png_frames == 0 || options.png_frames > MAX_HEAT_MAPS {
            return Err(tactile_core::Error::Config(format!(
                "png_frames: must be 1 to {MAX_HEAT_MAPS} heat maps with a folder for them ({}), got {}",
                dir.display(),
                options.png_frames
            ))
            .into());
        }
    }
    // Staged before the work: a folder with files or an unwritable place
    // fails first.
    let staged = options
        .save_png
        .as_ref()
        .map(tactile_core::io::StagedDir::fresh)
        .transpose()?;
    let mut est = DepthEstimator::load(model, runtime, 0)?;
    let (scores, ms_per_frame, undecodable) = evaluate(&mut est, &ds)?;
    let mut heat_maps = 0;
    if let Some(staged) = staged {
        heat_maps = save_heat_maps(&mut est, &ds, staged.path(), options.png_frames)?;
        staged.commit(false)?;
    }
    Ok(DepthEvaluation {
        model: model.to_path_buf(),
        data: data.to_path_buf(),
        scores,
        ms_per_frame,
        heat_maps,
        warning: tactile_burn::artifact::scored_on_fitted::<crate::DepthArtifact>(model, &ds),
        frame_warnings: undecodable.into_iter().collect(),
    })
}

/// Heat maps of how far the skin is pushed in, mm (from the rest dome, or
/// the indentation itself) (truth |
/// prediction, one colour scale per frame with its colour bar) of the first
/// `frames` frames of `ds`, as `depth-000.png`, ... in `dir` (a frame that
/// cannot be decoded past its header left out, as the scores leave it, and
/// the next frame drawn instead); returns how many were written.
pub fn save_heat_maps(
    estimator: &mut DepthEstimator,
    ds: &Dataset,
    dir: &Path,
    frames: usize,
) -> Result<usize> {
    same_maps(estimator, ds)?;
    tactile_core::io::create_dir_all(dir)?;
    let aspect = ds.manifest.width as f64 / ds.manifest.height.max(1) as f64;
    // Its warning is the scores' ([`evaluate`], over every frame).
    let mut skipped = tactile_core::source::UndecodableFrames::new(ds.len());
    let (mut written, mut next) = (0, 0);
    // The rows after the first `frames` stand in for those skipped.
    while written < frames && next < ds.len() {
        let rows: Vec<usize> = (next..ds.len().min(next + frames - written)).collect();
        next += rows.len();
        let data = frames_for(estimator, ds, &rows, &mut skipped)?;
        let preds = predict_mm(estimator, &data)?;
        let (w, h, maps) = (data.width, data.height, data.depth_maps);
        for (sample, p) in data.samples.iter().zip(&preds) {
            let truth = crate::data::push_mm(&sample.depth_mm, maps, (w, h), aspect);
            let pred = crate::data::push_mm(p, maps, (w, h), aspect);
            tactile_core::plot::heat_maps_with_bar(
                dir.join(format!("depth-{written:03}.png")),
                &[&truth, &pred],
                (w, h),
                4,
                "push from rest, mm",
            )?;
            written += 1;
        }
    }
    Ok(written)
}
