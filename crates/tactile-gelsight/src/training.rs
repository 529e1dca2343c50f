//! Calibration: each press's contact circle (annotated, or found), the
//! ball's geometry as slope targets, and the sensor model fitted to them
//! (Adam, masked squared error on the slopes, a little colour jitter),
//! early-stopped on presses held out for validation.

use std::path::Path;

use burn::config::Config;
use burn::module::Module;
use burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};
use tactile_burn::train::{FitConfig, FitSummary, Schedule, fit};
use tactile_burn::{Artifact, DeviceKind};

use crate::Error;
use crate::artifact::{BACKGROUND_FILE, GelsightArtifact};
use crate::circle::find_contact;
use crate::eval::{PressScore, score_map};
use crate::geometry::{Cap, GradientTargets};
use crate::layout::{Annotations, BallPresses, Circle};
use crate::model::{GradientNet, GradientNetConfig};
use crate::poisson::{PoissonLayer, PoissonSolver};
use crate::prepare::{FEATURES, PreparedBackground, WorkingGrid, WorkingImage};

/// Frame pixels per pixel of the grid the circle finder works on.
pub const FINDER_FACTOR: usize = 2;

/// The working pixel a calibration's default grid aims at, mm: the
/// R1.5's at the factor its recipe was chosen at (4 x 0.0295 mm). A
/// sensor of another scale gets the same skin per working pixel, so the
/// network's kernels and the Poisson solve see a contact as on the R1.5.
pub const WORKING_PIXEL_MM: f64 = 0.118;

/// Frame pixels per working pixel for a sensor of `mm_per_px` whose
/// frames are `(w, h)`: [`WORKING_PIXEL_MM`]'s (4 on the R1.5, 2 on a
/// GelSight Mini at 320x240, 12 on a camera of 0.0098 mm per pixel),
/// within 1-[`crate::prepare::MAX_FACTOR`] and leaving at least 16
/// working pixels across the frame.
pub fn factor_for_scale(mm_per_px: f64, (w, h): (usize, usize)) -> usize {
    let wanted = (WORKING_PIXEL_MM / mm_per_px).round();
    let most = (w.min(h) / 16).clamp(1, crate::prepare::MAX_FACTOR);
    match wanted.is_finite() {
        true => (wanted.max(1.0) as usize).min(most),
        false => most.min(4),
    }
}

/// Fewest presses a calibration fits on (after the validation presses).
pub const MIN_TRAIN_PRESSES: usize = 4;

/// Which circle a press's targets are drawn from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum CircleSource {
    /// The annotated circle where `presses.csv` gives one, else the found one.
    #[default]
    Auto,
    /// Always the circle the toolkit finds.
    Found,
    /// Always the annotated circle (every press must have one).
    Annotated,
}

/// How a sensor is calibrated.
#[derive(Config, Debug, PartialEq)]
pub struct CalibrationConfig {
    /// The network.
    #[config(default = "GradientNetConfig::new()")]
    pub model: GradientNetConfig,
    /// Frame pixels per working pixel; `None`: the scale's
    /// ([`factor_for_scale`]).
    pub factor: Option<usize>,
    /// Epochs, batches, learning rate, seed.
    #[config(default = "Schedule::new(4, 48, 20, 5e-3).with_lr_decay(0.97)")]
    pub schedule: Schedule,
    /// Presses held out to choose the epoch (0: none; it is chosen on four
    /// training presses).
    #[config(default = 4)]
    pub val_presses: usize,
    /// Each channel's gain is jittered by up to this fraction in training.
    #[config(default = 0.03)]
    pub colour_jitter: f64,
    /// Weight of the integrated height's error (shape inside the contact,
    /// rest in the far field, mm squared) beside the slopes' (0: slopes only).
    #[config(default = 4.0)]
    pub height_weight: f64,
    /// Where the contact circles come from.
    #[config(default = "CircleSource::Auto")]
    pub circles: CircleSource,
    /// Integrate slopes only where the colour change shows contact
    /// (`ContactGate`; measured in docs/calibration.md: a little less far
    /// field, a little more shape error).
    #[config(default = false)]
    pub contact_gate: bool,
}

impl CalibrationConfig {
    /// Frame pixels per working pixel for the presses `ds`: the config's
    /// `factor`, else the scale's ([`factor_for_scale`]).
    pub fn working_factor(&self, ds: &BallPresses) -> usize {
        (self.factor).unwrap_or_else(|| factor_for_scale(ds.sensor.mm_per_px, ds.size()))
    }
}

/// One press made ready: its circles, its exposure-matched working frame
/// and its slope targets.
#[derive(Debug, Clone)]
pub struct PreparedPress {
    /// Its frame, relative to the folder.
    pub file: String,
    /// The circle the toolkit found.
    pub found: Circle,
    /// The annotated circle, if any.
    pub annotated: Option<Circle>,
    /// The circle its targets use.
    pub circle: Circle,
    /// The radius of the ball pressed, pixels.
    pub ball_radius_px: f64,
    /// The frame at the working resolution, exposure matched.
    pub frame: WorkingImage,
    /// Slope targets and weights.
    pub targets: GradientTargets,
}

/// How far, as a fraction of an annotated circle's radius, the circle the
/// toolkit finds in the same press may lie from it (centre, or radius)
/// before the press is named: the finder lands within 0.11 of it (centre)
/// and 0.13 (radius) on every press measured (the R1.5's whole presses,
/// presses cut by the frame's edge, a gel with markers, a round gel in a
/// dark housing, JPEG frames, frames of 160x120 to 1920x1440), and a
/// mistyped line (the column and row swapped, a digit dropped) lies far
/// past it.
pub const ANNOTATION_DISAGREES: f64 = 0.35;

/// A warning naming the presses whose annotated circle, which their
/// targets use, lies far from the contact the toolkit finds in the frame
/// ([`ANNOTATION_DISAGREES`]): most likely a mistyped line of
/// `presses.csv`, which would fit the sensor model to a ball that was not
/// there.
fn annotations_far_from_found(
    presses: &[PreparedPress],
    annotations: Annotations,
) -> Option<String> {
    let far: Vec<(&PreparedPress, Circle)> = presses
        .iter()
        .filter_map(|p| {
            let a = p.annotated.filter(|a| *a == p.circle)?;
            let f = p.found;
            let apart = (f.centre_x_px - a.centre_x_px).hypot(f.centre_y_px - a.centre_y_px);
            let limit = ANNOTATION_DISAGREES * a.radius_px;
            (apart > limit || (f.radius_px - a.radius_px).abs() > limit).then_some((p, a))
        })
        .collect();
    let (first, a) = far.first()?;
    let f = first.found;
    Some(format!(
        "warning: {}: the annotated contact circles of {} of the {} presses lie far from the contacts the toolkit finds in their frames (the first: {}, annotated at ({:.1}, {:.1}) of radius {:.1} px, found at ({:.1}, {:.1}) of radius {:.1} px), and their targets follow the annotations: {}, or calibrate with --circles found",
        annotations.file(),
        far.len(),
        presses.len(),
        first.file,
        a.centre_x_px,
        a.centre_y_px,
        a.radius_px,
        f.centre_x_px,
        f.centre_y_px,
        f.radius_px,
        annotations.how_to_mend()
    ))
}

/// A warning naming the presses whose circles were found (none annotated,
/// or `--circles found`) and run off the frame's edge: the finder sees
/// such a contact in part, and lands farther from it (on 12 presses of the
/// R1.5 cropped so, 4 of them cut, 3.3 px on average and 6.8 at most,
/// against 2.9 and 5.2 on whole presses).
fn found_circles_cut_by_edge(
    presses: &[PreparedPress],
    size: (usize, usize),
    annotations: Annotations,
) -> Option<String> {
    let cut: Vec<&PreparedPress> = presses
        .iter()
        .filter(|p| p.circle == p.found && p.circle.cut_by_edge(size))
        .collect();
    let first = cut.first()?;
    let c = first.circle;
    Some(format!(
        "warning: {} of the {} presses run off the frame's edge, and their contact circles were found, not annotated (the first: {}, a circle at ({:.1}, {:.1}) of radius {:.1} px): the finder sees such a contact in part and is least sure of it; {}, or leave them out",
        cut.len(),
        presses.len(),
        first.file,
        c.centre_x_px,
        c.centre_y_px,
        c.radius_px,
        annotations.how_to_give(true)
    ))
}

impl PreparedPress {
    /// The ball's geometry on this press.
    pub fn cap(&self, ds: &BallPresses) -> Cap {
        Cap {
            circle: self.circle,
            ball_radius_px: self.ball_radius_px,
            mm_per_px: ds.sensor.mm_per_px,
        }
    }
}

/// The background and every press of `ds` on the working grid of
/// `factor`, with their circles and targets.
pub fn prepare_presses(
    ds: &BallPresses,
    factor: usize,
    circles: CircleSource,
) -> crate::Result<(PreparedBackground, Vec<PreparedPress>)> {
    let (w, h) = ds.size();
    let grid = WorkingGrid {
        frame_width: w,
        frame_height: h,
        factor,
    };
    grid.check()?;
    let bg = PreparedBackground::new(&ds.background, grid)?;
    // Circles are sought on a finer grid than the model's.
    let fine = PreparedBackground::new(
        &ds.background,
        WorkingGrid {
            factor: FINDER_FACTOR.min(factor),
            ..grid
        },
    )?;
    let mut out = Vec::with_capacity(ds.presses.len());
    for (i, p) in ds.presses.iter().enumerate() {
        let path = ds.press_path(i);
        let full = ds.frame(i)?;
        let frame = bg.matched(&full)?;
        let found = find_contact(&fine, &fine.matched(&full)?, &path)?;
        let circle = match (circles, p.annotated) {
            (CircleSource::Found, _) | (CircleSource::Auto, None) => {
                ds.check_found_circle(i, &path, &found)?;
                found
            }
            (_, Some(a)) => {
                ds.check_circle(i, &path, &a)?;
                a
            }
            (CircleSource::Annotated, None) => {
                return Err(Error::Press {
                    path,
                    why: format!(
                        "no annotated circle in {} (circles = annotated)",
                        ds.annotations.file()
                    ),
                });
            }
        };
        let cap = Cap {
            circle,
            ball_radius_px: ds.ball_radius_px(i),
            mm_per_px: ds.sensor.mm_per_px,
        };
        out.push(PreparedPress {
            file: p.file.clone(),
            found,
            annotated: p.annotated,
            circle,
            ball_radius_px: cap.ball_radius_px,
            targets: GradientTargets::of(&cap, grid),
            frame,
        });
    }
    Ok((bg, out))
}

/// A batch of presses as tensors.
struct Batch {
    /// Features, `[N, FEATURES, H, W]`.
    x: Tensor<4>,
    /// Slope targets, `[N, 2, H, W]`.
    slopes: Tensor<4>,
    /// Their weights, `[N, 1, H, W]`.
    weight: Tensor<4>,
    /// The cap's height above its rim, mm, `[N, H, W]`.
    cap_mm: Tensor<3>,
    /// Inside the contact, `[N, H, W]`.
    inside: Tensor<3>,
    /// In the far field, `[N, H, W]`.
    far: Tensor<3>,
}

/// `presses` as a batch, each channel's gain jittered by up to `jitter`
/// (seeded by `seed`).
fn batch(
    bg: &PreparedBackground,
    presses: &[&PreparedPress],
    jitter: f64,
    seed: u64,
    device: &Device,
) -> Batch {
    let g = bg.image.grid;
    let (w, h) = (g.width(), g.height());
    let n = presses.len();
    let mut x = Vec::with_capacity(n * FEATURES * w * h);
    let mut y: Vec<f32> = Vec::with_capacity(n * 2 * w * h);
    let (mut wt, mut cap, mut inside, mut far): (Vec<f32>, Vec<f32>, Vec<f32>, Vec<f32>) =
        (vec![], vec![], vec![], vec![]);
    for (k, p) in presses.iter().enumerate() {
        let f = if jitter > 0.0 {
            let mut rng = tactile_core::rng::SampleRng::new(seed, 0x6e1, k as u64);
            let gain: Vec<f32> = (0..3)
                .map(|_| (1.0 + jitter * (2.0 * rng.uniform() - 1.0)) as f32)
                .collect();
            WorkingImage {
                grid: g,
                rgb: p
                    .frame
                    .rgb
                    .iter()
                    .enumerate()
                    .map(|(i, v)| v * gain[i % 3])
                    .collect(),
            }
        } else {
            p.frame.clone()
        };
        x.extend(bg.features(&f));
        let t = &p.targets;
        y.extend(&t.gx);
        y.extend(&t.gy);
        wt.extend(&t.weight);
        cap.extend(&t.cap_mm);
        inside.extend(&t.inside);
        far.extend(&t.far);
    }
    let t3 = |v: Vec<f32>| Tensor::<3>::from_data(TensorData::new(v, [n, h, w]), device);
    Batch {
        x: Tensor::<4>::from_data(TensorData::new(x, [n, FEATURES, h, w]), device),
        slopes: Tensor::<4>::from_data(TensorData::new(y, [n, 2, h, w]), device),
        weight: Tensor::<4>::from_data(TensorData::new(wt, [n, 1, h, w]), device),
        cap_mm: t3(cap),
        inside: t3(inside),
        far: t3(far),
    }
}

/// What the loss sees besides the batch: the network's slopes at rest
/// (subtracted before integrating, as reconstruction does), the solve and
/// the working step.
struct HeightTerm<'a> {
    rest: Tensor<4>,
    layer: &'a PoissonLayer,
    step_mm: f32,
    weight: f64,
}

/// Weighted squared error of predicted slopes, plus (with `height`) the
/// integrated height's squared shape error inside the contact (its mean
/// offset removed: the rim's sink is unknown) and its square in the far
/// field, in mm, times the height weight.
fn loss(pred: Tensor<4>, b: Batch, height: Option<&HeightTerm>) -> Tensor<1> {
    let d = (pred.clone() - b.slopes).powi_scalar(2).sum_dim(1);
    let slopes = (d * b.weight.clone()).sum() / (b.weight.sum() * 2.0 + 1e-6);
    let Some(ht) = height else {
        return slopes;
    };
    let [n, _, hh, ww] = pred.dims();
    let skin = (pred - ht.rest.clone()) * ht.step_mm;
    let gx = skin
        .clone()
        .slice([0..n, 0..1, 0..hh, 0..ww])
        .reshape([n, hh, ww]);
    let gy = skin.slice([0..n, 1..2, 0..hh, 0..ww]).reshape([n, hh, ww]);
    let h = ht.layer.integrate(gx, gy);
    let inside_n = b.inside.clone().sum_dim(2).sum_dim(1) + 1e-6;
    let diff = (h.clone() - b.cap_mm) * b.inside.clone();
    let offset = diff.clone().sum_dim(2).sum_dim(1) / inside_n.clone();
    let shape = ((diff - offset) * b.inside)
        .powi_scalar(2)
        .sum_dim(2)
        .sum_dim(1)
        / inside_n;
    let far_n = b.far.clone().sum_dim(2).sum_dim(1) + 1e-6;
    let far = (h * b.far).powi_scalar(2).sum_dim(2).sum_dim(1) / far_n;
    slopes + (shape + far).mean().reshape([1]) * ht.weight
}

/// The network's raw slopes on one exposure-matched working frame (no
/// autodiff).
pub fn predict_slopes(
    net: &GradientNet,
    bg: &PreparedBackground,
    frame: &WorkingImage,
    device: &Device,
) -> crate::Result<(Vec<f32>, Vec<f32>)> {
    let g = bg.image.grid;
    let x = TensorData::new(bg.features(frame), [1, FEATURES, g.height(), g.width()]);
    slopes_of(net.forward(Tensor::<4>::from_data(x, device)))
}

/// A network output's two slope maps.
fn slopes_of(out: Tensor<4>) -> crate::Result<(Vec<f32>, Vec<f32>)> {
    let v = out
        .into_data()
        .try_to_vec::<f32>()
        .map_err(|e| tactile_core::Error::Invalid(format!("{e:?}")))?;
    Ok(crate::inference::split_slopes(v))
}

/// A fitted network and its run, in memory.
pub struct Fitted {
    /// The network (on the inference device).
    pub net: GradientNet,
    /// The run.
    pub summary: FitSummary,
    /// The contact gate of its training presses.
    pub gate: Option<crate::inference::ContactGate>,
}

/// Fit the network on `train` presses, early-stopped on `val` (by the
/// cap-shape plus far-field error after integration, mm), in memory; `progress` reports
/// each epoch.
pub fn fit_presses(
    config: &CalibrationConfig,
    ds: &BallPresses,
    bg: &PreparedBackground,
    presses: &[PreparedPress],
    (train, val): (&[usize], &[usize]),
    device: DeviceKind,
    progress: bool,
) -> crate::Result<Fitted> {
    config.model.check()?;
    let dev = device.device();
    let ad = dev.clone().autodiff();
    ad.seed(config.schedule.seed);
    let model = config.model.init(&ad)?;
    let g = bg.image.grid;
    let solver = PoissonSolver::new(g.width(), g.height());
    let step_mm = g.step_mm(ds.sensor.mm_per_px);
    let layer = PoissonLayer::new(g.width(), g.height(), &ad);
    let features = |d: &Device| {
        Tensor::<4>::from_data(
            TensorData::new(bg.features(&bg.image), [1, FEATURES, g.height(), g.width()]),
            d,
        )
    };
    let bg_ad = features(&ad);
    let mut fit_cfg = FitConfig::new(&config.schedule, "sensor model (slopes)");
    fit_cfg.progress = progress;
    // Without validation presses, the epoch is chosen on four training
    // presses spread over the recording (scoring every one each epoch
    // would cost as much as the training).
    let picked: Vec<usize>;
    let (val_items, watch) = if val.is_empty() {
        picked = spread(train.len(), 4)
            .into_iter()
            .map(|k| train[k])
            .collect();
        (picked.len(), picked.as_slice())
    } else {
        (val.len(), val)
    };
    let train_presses: Vec<&PreparedPress> = train.iter().map(|&i| &presses[i]).collect();
    let gate = match config.contact_gate {
        true => crate::inference::ContactGate::fit(bg, &train_presses),
        false => None,
    };
    let mut best: Option<GradientNet> = None;
    let (net, summary) = fit::<_, Error>(
        &fit_cfg,
        model,
        burn::optim::AdamConfig::new().init(),
        (train, val_items),
        |m: &GradientNet, items, epoch| {
            let ps: Vec<&PreparedPress> = items.iter().map(|&i| &presses[i]).collect();
            let b = batch(
                bg,
                &ps,
                config.colour_jitter,
                (epoch as u64) << 20 | items[0] as u64,
                &ad,
            );
            let pred = m.forward(b.x.clone());
            let height = (config.height_weight > 0.0).then(|| HeightTerm {
                rest: m.forward(bg_ad.clone()),
                layer: &layer,
                step_mm,
                weight: config.height_weight,
            });
            Ok(loss(pred, b, height.as_ref()))
        },
        |m| {
            let m = m.valid();
            let (rx, ry) = predict_slopes(&m, bg, &bg.image, &dev)?;
            let (mut total, mut shape) = (0.0, 0.0);
            for &i in watch {
                let p = &presses[i];
                let b = batch(bg, &[p], 0.0, 0, &dev);
                let (gx, gy) = slopes_of(m.forward(b.x))?;
                let weights = gate.map(|g| g.weights(&bg.change(&p.frame)));
                let h = crate::inference::indentation_mm(
                    &solver,
                    (&gx, &gy),
                    (&rx, &ry),
                    step_mm,
                    weights.as_deref(),
                );
                let s = score_map(
                    &h,
                    (g.width(), g.height()),
                    |i| g.frame_coord(i as f64),
                    &p.cap(ds),
                    &p.file,
                );
                shape += s.shape_mae_mm;
                total += s.shape_mae_mm + s.far_field_mm;
            }
            let n = watch.len().max(1) as f64;
            Ok((total / n, Some(shape / n)))
        },
        |m| {
            best = Some(m.valid());
            Ok(())
        },
    )?;
    Ok(Fitted {
        net: best.unwrap_or_else(|| net.valid()),
        summary,
        gate,
    })
}

/// `k` of `n` items spread evenly over them (the middle of each of `k`
/// equal runs): validation presses drawn from the whole recording.
pub fn spread(n: usize, k: usize) -> Vec<usize> {
    if k == 0 || n == 0 {
        return vec![];
    }
    let step = n as f64 / k.min(n) as f64;
    (0..k.min(n))
        .map(|j| ((j as f64 + 0.5) * step) as usize)
        .collect()
}

/// What a calibration reports.
#[derive(Debug, Clone, Serialize)]
pub struct Calibration {
    /// The training run.
    pub fit: FitSummary,
    /// The circle finder against the annotations, where there are any.
    pub circles: Option<crate::eval::CircleAgreement>,
    /// Presses fitted on.
    pub train_presses: usize,
    /// Presses that stopped training.
    pub val_presses: usize,
    /// Each validation press's scores (full resolution, the saved model).
    pub validation: Vec<PressScore>,
    /// The render model (optics and gel) fitted beside the sensor model.
    pub render: crate::render_model::RenderFit,
    /// What a user should know about the calibration folder (files in
    /// `frames/` that were not read as presses) and its fit (a render
    /// model that barely explains the presses).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// The pictures of the presses with their circles, in the model
    /// folder (`circles.png`, then `circles-2.png`, ... for every 48).
    pub circle_pictures: Vec<String>,
    /// The grid the sensor model and the Poisson solve run on.
    pub working_grid: WorkingGrid,
    /// Millimetres of skin per working pixel.
    pub working_pixel_mm: f64,
    /// Millimetres of skin per frame pixel.
    pub mm_per_px: f64,
    /// The file the scale was read from (`sensor.json`, or gs_sdk's
    /// config copied into the folder).
    pub scale_from: String,
    /// How gs_sdk cuts the camera's frames to the sensor's, where its
    /// config gives the camera's size (`raw_imgw` x `raw_imgh`) and the
    /// presses are its `imgw` x `imgh`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub camera: Option<crate::gs_sdk_config::CameraCut>,
}

impl Calibration {
    /// What the calibration found, a line each, as `tactile calibrate ball`
    /// prints it: the fit (the model folder `out` named), the circle
    /// finder's agreement, the render model and each held-out press.
    pub fn describe(&self, out: &Path) -> Vec<String> {
        let mut lines = vec![format!(
            "sensor model {}; {} presses fitted, {} held out; model in {}",
            self.fit.describe("cap-shape error, mm"),
            self.train_presses,
            self.val_presses,
            out.display()
        )];
        let g = &self.working_grid;
        lines.push(format!(
            "working grid {}x{}: {} frame pixels, {:.3} mm of skin, per working pixel (--factor; the frames' scale {} mm per pixel, from {})",
            g.width(),
            g.height(),
            g.factor,
            self.working_pixel_mm,
            self.mm_per_px,
            self.scale_from
        ));
        if let Some(cut) = &self.camera {
            let ((cw, ch), (w, h)) = (cut.camera, cut.size);
            lines.push(format!(
                "camera: gs_sdk cuts the camera's {cw}x{ch} frames (its config's raw_imgw x raw_imgh) to these {w}x{h}; to run on the camera, cut as gs_sdk does (FFmpeg's resize, not OpenCV's): {}",
                cut.ffmpeg_command(out)
            ));
        }
        lines.extend(self.circles.as_ref().map(|c| c.describe()));
        let more = match &self.circle_pictures[..] {
            [] | [_] => String::new(),
            [_, next] => format!(" and {next}"),
            [_, next, .., last] => format!(" and {next} to {last}"),
        };
        lines.push(format!(
            "circles: {}{more} (green: the circle each press's targets use; yellow: the one found, where that is another)",
            out.join(crate::eval::CIRCLES_PICTURE).display()
        ));
        let r = &self.render;
        lines.push(format!(
            "render model (optics.json): optics on {} pixels; gel spread {:.2} mm, gain {:.2} (profile error {:.3} mm); ball presses rendered back: colour error {:.1} levels (the bare background: {:.1})",
            r.optics_samples,
            r.gel.sigma_mm,
            r.gel.gain,
            r.gel_profile_error_mm,
            r.colour_error_levels,
            r.colour_error_unpressed_levels
        ));
        lines.extend(self.validation.iter().map(|s| {
            format!(
                "held out {}: shape error {:.3} mm, far field {:.4} mm, rim sink {:.3} mm, peak {:.3} mm",
                s.file, s.shape_mae_mm, s.far_field_mm, s.rim_sink_mm, s.peak_mm
            )
        }));
        lines
    }
}

/// Calibrate the sensor of `ds` into the model folder `out` (written whole
/// or not at all): circles, targets, fit, the background copied beside the
/// weights, the training record.
pub fn calibrate(
    config: &CalibrationConfig,
    ds: &BallPresses,
    out: &Path,
    device: DeviceKind,
) -> crate::Result<Calibration> {
    config.model.check()?;
    config.schedule.check()?;
    // The factor used is the one recorded in training.json.
    let config = &(config.clone()).with_factor(Some(config.working_factor(ds)));
    let n = ds.presses.len();
    if n < MIN_TRAIN_PRESSES + config.val_presses {
        return Err(Error::TooFewPresses {
            path: ds.root.clone(),
            count: n,
            needed: MIN_TRAIN_PRESSES + config.val_presses,
            purpose: "the sensor model".into(),
        });
    }
    let staged = tactile_core::io::StagedDir::fresh(out)?;
    let (bg, presses) = prepare_presses(ds, config.working_factor(ds), config.circles)?;
    let circles = crate::eval::CircleAgreement::of(&presses);
    if let Some(c) = &circles {
        tactile_core::note!("{}", c.describe());
    }
    let cut = found_circles_cut_by_edge(&presses, ds.size(), ds.annotations);
    let mistyped = annotations_far_from_found(&presses, ds.annotations);
    // What the folder and its circles tell is said before the minute of
    // training, not only in the summary after it.
    for w in ds.warnings.iter().chain(&cut).chain(&mistyped) {
        tactile_core::note!("{w}");
    }
    let circle_pictures = crate::eval::circles_pictures(ds, &presses, staged.path())?;
    let val = spread(n, config.val_presses);
    let train: Vec<usize> = (0..n).filter(|i| !val.contains(i)).collect();
    let held = match val.len() {
        0 => "every press fitted, the epoch chosen on four of them".to_string(),
        k => format!("{k} held out to choose the epoch"),
    };
    tactile_core::note!(
        "calibrating on {} presses ({held}): {}, {} mm per pixel (from {}), working grid {}x{}",
        train.len(),
        ds.describe_balls(),
        ds.sensor.mm_per_px,
        ds.scale_from(),
        bg.image.grid.width(),
        bg.image.grid.height()
    );
    let dir = staged.path();
    let fitted = fit_presses(config, ds, &bg, &presses, (&train, &val), device, true)?;
    let artifact = GelsightArtifact {
        model: config.model.clone(),
        grid: bg.image.grid,
        sensor: ds.sensor.clone(),
        contact_gate: fitted.gate,
        notes: serde_json::json!({
            "calibrated_on": ds.root.display().to_string(),
            "device": device.name(),
            "presses": n,
        }),
    };
    artifact.save(&fitted.net, dir)?;
    ds.save_background(&dir.join(BACKGROUND_FILE))?;
    let mut rec = crate::inference::Reconstructor::new(
        artifact.grid,
        artifact.sensor.mm_per_px,
        crate::inference::SlopeModel::Network(Box::new(tactile_burn::runtime::BurnNetwork::new(
            fitted.net, device,
        ))),
        &ds.background,
        &ds.background_path(),
    )?
    .with_gate(fitted.gate);
    let sensor_name = match ds.sensor.sensor.is_empty() {
        true => ds.root.display().to_string(),
        false => ds.sensor.sensor.clone(),
    };
    let (render_model, render) =
        crate::render_model::fit_render_model(ds, &bg, &presses, &mut rec, &sensor_name)?;
    tactile_core::io::write_json_atomic(
        dir.join(datasets_synth::calibrated::RENDER_MODEL_FILE),
        &render_model,
    )?;
    let mut validation = Vec::new();
    for &i in &val {
        let p = &presses[i];
        let map = rec.reconstruct(&ds.frame(i)?, &ds.press_path(i))?;
        validation.push(crate::eval::score_full(&map, &p.cap(ds), &p.file));
    }
    tactile_burn::artifact::write_training_record(
        dir,
        config,
        &fitted.summary,
        serde_json::json!({ "circles": circles, "validation": validation, "val_presses": val, "render": render }),
    )?;
    staged.commit(false)?;
    Ok(Calibration {
        fit: fitted.summary,
        circles,
        train_presses: train.len(),
        val_presses: val.len(),
        validation,
        circle_pictures,
        working_grid: bg.image.grid,
        working_pixel_mm: bg.image.grid.factor as f64 * ds.sensor.mm_per_px,
        mm_per_px: ds.sensor.mm_per_px,
        scale_from: ds.scale_from(),
        camera: ds
            .gs_sdk_config
            .as_ref()
            .filter(|c| c.size == Some(ds.size()))
            .and_then(|c| c.camera_cut()),
        warnings: ds
            .warnings
            .iter()
            .chain(&cut)
            .chain(&mistyped)
            .chain(&render.warning)
            .cloned()
            .collect(),
        render,
    })
}
