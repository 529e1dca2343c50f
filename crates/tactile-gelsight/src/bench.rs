//! Leave-presses-out cross-validation of sensor models: the presses split
//! into folds (press `i` in fold `i % folds`); each fold's presses are
//! reconstructed by a model calibrated on the others and scored against
//! the ball's geometry, at the frame's size, as recorded and at another
//! exposure. The classic lookup table, the per-pixel MLP and the
//! convolutional model are fitted the same way, so their rows compare.

use std::time::Instant;

use serde::Serialize;
use tactile_burn::DeviceKind;
use tactile_core::image_io::RgbImage;

use crate::eval::{PressScore, score_full};
use crate::geometry::Cap;
use crate::inference::{Reconstructor, SlopeModel};
use crate::layout::BallPresses;
use crate::lookup::LookupTable;
use crate::prepare::PreparedBackground;
use crate::training::{CalibrationConfig, PreparedPress, fit_presses, spread};
use crate::{Error, Result};

/// Most folds.
pub const MAX_FOLDS: usize = 32;

/// A sensor model to cross-validate.
#[derive(Debug, Clone)]
pub enum Candidate {
    /// The colour-change lookup table of `bins` cells per channel.
    Lookup {
        /// Finest cells per channel.
        bins: usize,
    },
    /// A network calibrated with this config.
    Network(Box<CalibrationConfig>),
}

impl Candidate {
    /// The keys of [`Self::standard`]'s candidates, in its order.
    pub const KEYS: [&'static str; 5] = ["lookup", "mlp", "conv-slopes", "shipped", "gated"];

    /// The classic anchors and the toolkit's own models beside `base` (the
    /// shipped recipe), each with its key and its name: lookup table;
    /// per-pixel MLP on slopes (GelSight's SDK); `base`'s network on slopes
    /// alone; `base` itself.
    pub fn standard(base: &CalibrationConfig) -> Vec<(&'static str, String, Candidate)> {
        let mlp = CalibrationConfig {
            model: crate::GradientNetConfig::per_pixel_mlp(),
            height_weight: 0.0,
            ..base.clone()
        };
        let slopes = CalibrationConfig {
            height_weight: 0.0,
            ..base.clone()
        };
        let gated = CalibrationConfig {
            contact_gate: true,
            ..base.clone()
        };
        let [lookup, per_pixel, conv, shipped, with_gate] = Self::KEYS;
        vec![
            (
                lookup,
                "lookup table (Taxim-style)".into(),
                Candidate::Lookup {
                    bins: crate::lookup::DEFAULT_BINS,
                },
            ),
            (
                per_pixel,
                "per-pixel MLP, slope loss (gs_sdk-style)".into(),
                Candidate::Network(Box::new(mlp)),
            ),
            (
                conv,
                "convolutional, slope loss".into(),
                Candidate::Network(Box::new(slopes)),
            ),
            (
                shipped,
                "convolutional, slope + height loss (shipped)".into(),
                Candidate::Network(Box::new(base.clone())),
            ),
            (
                with_gate,
                "the shipped recipe, slopes gated by the colour change".into(),
                Candidate::Network(Box::new(gated)),
            ),
        ]
    }
}

/// Mean of a score over presses.
#[derive(Debug, Clone, Default, Serialize)]
pub struct MeanScore {
    /// Inside-contact shape error, mm.
    pub shape_mm: f64,
    /// Far-field error, mm.
    pub far_field_mm: f64,
    /// Reconstructed rim sink, mm.
    pub rim_sink_mm: f64,
    /// Deepest indentation, mm.
    pub peak_mm: f64,
}

impl MeanScore {
    /// The mean of `scores`.
    pub fn of(scores: &[PressScore]) -> Self {
        let n = scores.len().max(1) as f64;
        let m = |f: fn(&PressScore) -> f64| scores.iter().map(f).sum::<f64>() / n;
        Self {
            shape_mm: m(|s| s.shape_mae_mm),
            far_field_mm: m(|s| s.far_field_mm),
            rim_sink_mm: m(|s| s.rim_sink_mm),
            peak_mm: m(|s| s.peak_mm),
        }
    }
}

/// One candidate cross-validated.
#[derive(Debug, Clone, Serialize)]
pub struct CandidateResult {
    /// Its name.
    pub name: String,
    /// Every press scored by the model that did not see it.
    pub presses: Vec<PressScore>,
    /// Their mean.
    pub mean: MeanScore,
    /// Mean |slope error| inside the contact (mm per mm), on the working grid.
    pub slope_error: f64,
    /// The held-out presses at `1 - exposure` and `1 + exposure` times the
    /// recorded brightness.
    pub darker: MeanScore,
    /// Brighter.
    pub brighter: MeanScore,
    /// The largest |indentation| of the background at another exposure
    /// with sensor noise (no contact), mm.
    pub no_contact_max_mm: f64,
    /// Median seconds to fit one fold (circles and targets excluded).
    pub fit_s: f64,
    /// Median ms per frame through burn on the training device (shrink,
    /// model, Poisson, enlarge).
    pub burn_ms: f64,
    /// The same through onnxruntime (`None`: not a network).
    pub ort_ms: Option<f64>,
    /// Radial profiles of the first held-out press: (r in mm, reconstructed
    /// height above the rim in mm), the offset removed.
    pub profile: Vec<(f64, f64)>,
}

/// What a cross-validation is asked for.
#[derive(Debug, Clone)]
pub struct BenchOptions {
    /// Folds (presses per fold about `presses / folds`).
    pub folds: usize,
    /// The exposure change of the robustness rows (0.15: +-15 %).
    pub exposure: f64,
    /// Frames timed per runtime (median reported).
    pub runs: usize,
    /// Training device.
    pub device: DeviceKind,
    /// Print each fold's progress.
    pub progress: bool,
}

/// A frame with every value scaled by `gain` (clamped) and, with `noise`,
/// a seeded +-`noise` grey-level jitter.
fn exposed(frame: &RgbImage, gain: f64, noise: f64, seed: u64) -> Result<RgbImage> {
    let mut rng = tactile_core::rng::SampleRng::new(seed, 0xe9, 0);
    let v: Vec<u8> = frame
        .as_slice()
        .iter()
        .map(|&p| {
            let j = if noise > 0.0 {
                noise * (2.0 * rng.uniform() - 1.0)
            } else {
                0.0
            };
            (p as f64 * gain + j).round().clamp(0.0, 255.0) as u8
        })
        .collect();
    Ok(RgbImage::new(frame.size(), v)?)
}

/// The radial profile of `map` about `cap`'s centre, offset removed so
/// the rim is at 0, mm against mm, out to 1.5 contact radii.
fn profile(map: &crate::IndentationMap, cap: &Cap, offset_mm: f64) -> Vec<(f64, f64)> {
    let a = cap.circle.radius_px;
    let bins = 30usize;
    let max_r = 1.5 * a;
    let mut sum = vec![0.0; bins];
    let mut n = vec![0usize; bins];
    for y in 0..map.height {
        for x in 0..map.width {
            let r = cap.r_px(x as f64, y as f64);
            if r < max_r {
                let b = ((r / max_r) * bins as f64) as usize;
                sum[b] += map.indentation_m[y * map.width + x] as f64 * 1e3 - offset_mm;
                n[b] += 1;
            }
        }
    }
    (0..bins)
        .filter(|&b| n[b] > 0)
        .map(|b| {
            (
                (b as f64 + 0.5) / bins as f64 * max_r * cap.mm_per_px,
                sum[b] / n[b] as f64,
            )
        })
        .collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

impl BenchOptions {
    /// Refuse options no cross-validation of `presses` presses of the
    /// calibration folder `folder` can run: timing runs out of range,
    /// folds as [`check_folds`] says, or an exposure change outside
    /// [0, 0.9) (a gain of 1 - exposure must stay well above 0).
    pub fn check(&self, presses: usize, folder: &std::path::Path) -> Result<()> {
        tactile_core::bench::check_runs(self.runs)?;
        check_folds(self.folds, presses, folder)?;
        if !(0.0..0.9).contains(&self.exposure) {
            return Err(tactile_core::Error::Config(format!(
                "exposure must be in [0, 0.9), got {:?}",
                self.exposure
            ))
            .into());
        }
        Ok(())
    }
}

/// Refuse `folds` out of 2-[`MAX_FOLDS`], or more folds than the
/// `presses` to split (a fold holds at least one) of the calibration
/// folder `folder`: before any press is prepared, and on the prepared
/// presses a cross-validation is given.
pub fn check_folds(folds: usize, presses: usize, folder: &std::path::Path) -> Result<()> {
    if !(2..=MAX_FOLDS).contains(&folds) {
        return Err(tactile_core::Error::Config(format!(
            "folds must be 2-{MAX_FOLDS}, got {folds}"
        ))
        .into());
    }
    if presses < folds {
        return Err(Error::TooFewPresses {
            path: folder.to_path_buf(),
            count: presses,
            needed: folds,
            purpose: format!("a cross-validation of {folds} folds (a press per fold)"),
        });
    }
    Ok(())
}

/// Cross-validate `candidate` on the prepared presses of `ds`.
pub fn cross_validate(
    name: &str,
    candidate: &Candidate,
    ds: &BallPresses,
    (bg, presses): (&PreparedBackground, &[PreparedPress]),
    options: &BenchOptions,
) -> Result<CandidateResult> {
    let n = presses.len();
    options.check(n, &ds.root)?;
    let grid = bg.image.grid;
    let bg_path = ds.background_path();
    let mut result = CandidateResult {
        name: name.to_string(),
        presses: vec![],
        mean: MeanScore::default(),
        slope_error: 0.0,
        darker: MeanScore::default(),
        brighter: MeanScore::default(),
        no_contact_max_mm: 0.0,
        fit_s: 0.0,
        burn_ms: 0.0,
        ort_ms: None,
        profile: vec![],
    };
    // Speed does not depend on the weights: timed first, on fresh ones,
    // before any training leaves busy threads behind.
    (result.burn_ms, result.ort_ms) = time_candidate(candidate, ds, grid, options)?;
    let (mut darker, mut brighter, mut fits) = (vec![], vec![], vec![]);
    let (mut slope_sum, mut slope_n) = (0.0, 0usize);
    for fold in 0..options.folds {
        let test: Vec<usize> = (0..n).filter(|i| i % options.folds == fold).collect();
        let rest: Vec<usize> = (0..n).filter(|i| i % options.folds != fold).collect();
        let t0 = Instant::now();
        let mut gate = None;
        let model = match candidate {
            Candidate::Lookup { bins } => {
                let mut t = LookupTable::new(*bins)?;
                for &i in &rest {
                    let p = &presses[i];
                    let f = bg.features(&p.frame);
                    t.add(&f, (&p.targets.gx, &p.targets.gy), &p.targets.weight);
                }
                SlopeModel::Lookup(t)
            }
            Candidate::Network(config) => {
                let val: Vec<usize> = spread(rest.len(), config.val_presses)
                    .into_iter()
                    .map(|k| rest[k])
                    .collect();
                let train: Vec<usize> = rest.iter().copied().filter(|i| !val.contains(i)).collect();
                let fitted = fit_presses(
                    config,
                    ds,
                    bg,
                    presses,
                    (&train, &val),
                    options.device,
                    false,
                )?;
                gate = fitted.gate;
                SlopeModel::Network(Box::new(tactile_burn::runtime::BurnNetwork::new(
                    fitted.net,
                    options.device,
                )))
            }
        };
        fits.push(t0.elapsed().as_secs_f64());
        let mut rec =
            Reconstructor::new(grid, ds.sensor.mm_per_px, model, &ds.background, &bg_path)?
                .with_gate(gate);
        for &i in &test {
            let p = &presses[i];
            let frame = ds.frame(i)?;
            let path = ds.press_path(i);
            let cap = p.cap(ds);
            let map = rec.reconstruct(&frame, &path)?;
            let s = score_full(&map, &cap, &p.file);
            if result.profile.is_empty() {
                result.profile = profile(&map, &cap, s.rim_sink_mm);
            }
            result.presses.push(s);
            // Slopes on the working grid where the cap gives them.
            let (gx, gy) = rec.raw_slopes(&p.frame)?;
            let (rx, ry) = rec.rest_slopes();
            for k in 0..gx.len() {
                if p.targets.weight[k] == 1.0 && p.targets.inside[k] == 1.0 {
                    slope_sum += ((gx[k] - rx[k]) - p.targets.gx[k]).abs() as f64
                        + ((gy[k] - ry[k]) - p.targets.gy[k]).abs() as f64;
                    slope_n += 2;
                }
            }
            for (gain, out) in [
                (1.0 - options.exposure, &mut darker),
                (1.0 + options.exposure, &mut brighter),
            ] {
                let m = rec.reconstruct(&exposed(&frame, gain, 0.0, 0)?, &path)?;
                out.push(score_full(&m, &cap, &p.file));
            }
        }
        for (k, gain) in [1.0 - options.exposure, 1.0, 1.0 + options.exposure]
            .into_iter()
            .enumerate()
        {
            let still = exposed(&ds.background, gain, 2.0, (fold * 3 + k) as u64)?;
            let m = rec.reconstruct(&still, &bg_path)?;
            let worst = m
                .indentation_m
                .iter()
                .fold(0f64, |w, v| w.max((*v as f64 * 1e3).abs()));
            result.no_contact_max_mm = result.no_contact_max_mm.max(worst);
        }
        if options.progress {
            tactile_core::note!(
                "{name}: fold {}/{} fitted in {:.0} s; presses so far: shape {:.3} mm",
                fold + 1,
                options.folds,
                fits[fold],
                MeanScore::of(&result.presses).shape_mm
            );
        }
    }
    result.mean = MeanScore::of(&result.presses);
    result.darker = MeanScore::of(&darker);
    result.brighter = MeanScore::of(&brighter);
    result.slope_error = slope_sum / slope_n.max(1) as f64;
    result.fit_s = median(fits);
    Ok(result)
}

/// Median ms per frame of `candidate` (fresh weights) through burn on
/// `options.device` and, for a network, through onnxruntime.
fn time_candidate(
    candidate: &Candidate,
    ds: &BallPresses,
    grid: crate::prepare::WorkingGrid,
    options: &BenchOptions,
) -> Result<(f64, Option<f64>)> {
    let bg_path = ds.background_path();
    // Timed with a gate, as calibrated models run (its thresholds do not
    // change the time).
    let gate = Some(crate::inference::ContactGate {
        from: 0.04,
        to: 0.08,
    });
    let rec = |m: SlopeModel| {
        Ok::<_, Error>(
            Reconstructor::new(grid, ds.sensor.mm_per_px, m, &ds.background, &bg_path)?
                .with_gate(gate),
        )
    };
    match candidate {
        Candidate::Lookup { bins } => {
            let ms = time_frames(
                &mut rec(SlopeModel::Lookup(LookupTable::new(*bins)?))?,
                ds,
                options.runs,
            )?;
            Ok((ms, None))
        }
        Candidate::Network(config) => {
            let net = config.model.init(&options.device.device())?;
            let artifact = crate::GelsightArtifact {
                model: config.model.clone(),
                grid,
                sensor: ds.sensor.clone(),
                contact_gate: None,
                notes: serde_json::Value::Null,
            };
            let bytes = tactile_onnx::Exportable::onnx(&artifact, &net)?;
            let ort = {
                let m =
                    SlopeModel::Network(Box::new(tactile_onnx::OrtModel::from_bytes(&bytes, 0)?));
                time_frames(&mut rec(m)?, ds, options.runs)?
            };
            let burn = SlopeModel::Network(Box::new(tactile_burn::runtime::BurnNetwork::new(
                net,
                options.device,
            )));
            Ok((time_frames(&mut rec(burn)?, ds, options.runs)?, Some(ort)))
        }
    }
}

/// Median ms per frame of `rec` over `runs` reconstructions of the presses.
fn time_frames(rec: &mut Reconstructor, ds: &BallPresses, runs: usize) -> Result<f64> {
    if ds.presses.is_empty() {
        return Err(Error::from(tactile_core::Error::Invalid(
            "no presses".into(),
        )));
    }
    let mut times = Vec::with_capacity(runs);
    let frames: Vec<RgbImage> = (0..ds.presses.len().min(4))
        .map(|i| ds.frame(i))
        .collect::<Result<_>>()?;
    let path = ds.press_path(0);
    // One untimed run warms the runtime.
    rec.reconstruct(&frames[0], &path)?;
    for k in 0..runs.max(1) {
        let t = Instant::now();
        rec.reconstruct(&frames[k % frames.len()], &path)?;
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    Ok(median(times))
}
