//! The calibrated sensor forward: what the ball presses teach about how
//! the sensor would show any press, so its own training data can be
//! rendered (`datasets_synth::calibrated`). Two parts, both fitted here
//! beside the sensor model and saved as the folder's render model:
//!
//! - the optics: colour change by slope and place, a table fitted to every
//!   pixel whose slope the ball's geometry gives (inside the contact, and
//!   the far field at rest), and to the sensor model's own slopes on the
//!   sinking gel around each contact;
//! - the gel: how far the skin sinks around a contact, fitted to the
//!   sensor model's reconstructions of the presses.
//!
//! Each press is then rendered back through the model and compared with
//! the real frame: the colour error says how close the rendered sensor is.

use datasets_synth::calibrated::{
    BallProfile, CalibratedConfig, CalibratedScene, CalibratedSensor, Contact, GelResponse,
    OpticsSample, RenderModel, SensorOptics, render,
};
use serde::Serialize;
use tactile_core::image_io::RgbImage;

use crate::geometry::{FAR_FIELD_RADII, INNER_FRACTION};
use crate::inference::Reconstructor;
use crate::layout::BallPresses;
use crate::prepare::{PreparedBackground, WorkingImage};
use crate::training::PreparedPress;
use crate::{Error, Result};

/// Slope bins per axis of the optics table.
pub const OPTICS_BINS: usize = 25;
/// The table's slope range, mm per mm (the ball's cap reaches about 2).
pub const OPTICS_MAX_SLOPE: f64 = 2.4;
/// Radial step of the gel's profiles, mm.
const PROFILE_STEP_MM: f64 = 0.1;

/// How well the render model reproduces the presses.
#[derive(Debug, Clone, Serialize)]
pub struct RenderFit {
    /// Pixels the optics were fitted on.
    pub optics_samples: usize,
    /// The gel's spread.
    pub gel: GelResponse,
    /// Mean |reconstructed - model| indentation over the presses' radial
    /// profiles (out to three contact radii), mm.
    pub gel_profile_error_mm: f64,
    /// Mean |rendered - real| colour within two contact radii of each
    /// press, 8-bit levels (exposure matched).
    pub colour_error_levels: f64,
    /// The same for the background itself (no press rendered): what a
    /// render with no model of the press would score.
    pub colour_error_unpressed_levels: f64,
    /// Said when the rendered presses are hardly closer to the real ones
    /// than the bare background ([`BARELY_EXPLAINED`]): the geometry of
    /// `sensor.json` is likely wrong.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<String>,
}

/// A render model whose presses differ from the real ones by more than
/// this share of the bare background's difference barely explains them.
/// The shared R1.5 gives 0.44 (6.4 against 14.5 levels); its presses with
/// the scale or the ball mistyped tenfold give 0.84-0.86.
pub const BARELY_EXPLAINED: f64 = 0.7;

/// Each channel's gain that brings `frame` to the background's exposure
/// (the sensor model's exposure matching).
fn exposure_gain(bg: &PreparedBackground, frame: &RgbImage) -> Result<[f32; 3]> {
    let m = WorkingImage::of(frame, bg.image.grid)?.medians();
    Ok(std::array::from_fn(|c| {
        if m[c] > 1.0 / 255.0 {
            bg.medians[c] / m[c]
        } else {
            1.0
        }
    }))
}

/// The radial mean of `map` (metres) about `(cx, cy)` at
/// `(k + 0.5) * PROFILE_STEP_MM`, out to `reach_mm`, as `(r_mm, mm)`.
fn radial_profile(
    map: &[f32],
    (w, h): (usize, usize),
    (cx, cy): (f64, f64),
    mm_per_px: f64,
    reach_mm: f64,
) -> Vec<(f64, f64)> {
    let bins = (reach_mm / PROFILE_STEP_MM).ceil() as usize;
    let mut sum = vec![0f64; bins];
    let mut n = vec![0usize; bins];
    let r_px = reach_mm / mm_per_px;
    let (x0, x1) = (
        (cx - r_px).floor().max(0.0) as usize,
        ((cx + r_px).ceil() as usize).min(w),
    );
    let (y0, y1) = (
        (cy - r_px).floor().max(0.0) as usize,
        ((cy + r_px).ceil() as usize).min(h),
    );
    for y in y0..y1 {
        for x in x0..x1 {
            let r = (x as f64 - cx).hypot(y as f64 - cy) * mm_per_px;
            let b = (r / PROFILE_STEP_MM) as usize;
            if b < bins {
                sum[b] += map[y * w + x] as f64 * 1e3;
                n[b] += 1;
            }
        }
    }
    (0..bins)
        .filter(|&b| n[b] > 0)
        .map(|b| ((b as f64 + 0.5) * PROFILE_STEP_MM, sum[b] / n[b] as f64))
        .collect()
}

/// The presses as `sensor.json` makes them: the widest contact circle in
/// mm and how deep the ball sank there (its cap's height), in words that
/// name the two values a user may have mistyped (0.00295 for 0.0295 mm
/// per pixel, a 40 mm ball for 4).
fn press_geometry(ds: &BallPresses, profiles: &[BallProfile]) -> String {
    let contact_mm = profiles.iter().map(|p| p.contact_mm).fold(0f64, f64::max);
    let cap_mm = (profiles.iter())
        .map(|p| p.ball_mm - (p.ball_mm.powi(2) - p.contact_mm.powi(2)).max(0.0).sqrt())
        .fold(0f64, f64::max);
    let balls = ds.describe_balls();
    let (given, check) = ds.where_the_balls_are();
    format!(
        "as {given} them ({balls}, {mm} mm per pixel), the widest contact circle is {contact_mm:.3} mm in radius and the ball sank {cap_mm:.4} mm at most; check {check}, which scale every press",
        mm = ds.sensor.mm_per_px,
    )
}

/// No gel response reproduces the presses (a contact past every approach
/// of the render model's sweep).
fn unfitted_gel(ds: &BallPresses, profiles: &[BallProfile]) -> Error {
    Error::Layout {
        path: ds.scale_file.clone(),
        why: format!(
            "no gel response presses a ball into the skin as these presses show: {}",
            press_geometry(ds, profiles)
        ),
    }
}

/// The sensor a calibration folder `dir` renders, as its render model
/// names it (what `tactile synth gelsight` writes in a dataset's manifest);
/// `None` when the folder has no readable render model.
pub fn rendered_sensor(dir: &std::path::Path) -> Option<String> {
    let file = dir.join(datasets_synth::calibrated::RENDER_MODEL_FILE);
    let model: serde_json::Value = tactile_core::io::read_json(file).ok()?;
    Some(model.get("sensor")?.as_str()?.to_string())
}

/// Fit the render model of the sensor of `ds` from its prepared presses
/// and its calibrated reconstruction `rec`; `sensor` names the sensor.
pub fn fit_render_model(
    ds: &BallPresses,
    bg: &PreparedBackground,
    presses: &[PreparedPress],
    rec: &mut Reconstructor,
    sensor: &str,
) -> Result<(RenderModel, RenderFit)> {
    let (w, h) = ds.size();
    let mm = ds.sensor.mm_per_px;
    let background = ds.background.as_slice();
    let mut samples = Vec::new();
    let mut profiles = Vec::with_capacity(presses.len());
    for (i, p) in presses.iter().enumerate() {
        let frame = ds.frame(i)?;
        let gain = exposure_gain(bg, &frame)?;
        let map = rec.reconstruct(&frame, &ds.press_path(i))?;
        let cap = p.cap(ds);
        let (cx, cy, a) = (
            cap.circle.centre_x_px,
            cap.circle.centre_y_px,
            cap.circle.radius_px,
        );
        let change = |x: usize, y: usize| -> [f32; 3] {
            let k = (y * w + x) * 3;
            std::array::from_fn(|c| {
                (frame.as_slice()[k + c] as f32 * gain[c] - background[k + c] as f32) / 255.0
            })
        };
        let depth = |x: usize, y: usize| map.indentation_m[y * w + x] as f64 * 1e3;
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                let r = (x as f64 - cx).hypot(y as f64 - cy);
                let (slope, weight) = if r <= INNER_FRACTION * a {
                    (cap.slope(x as f64, y as f64), 1.0)
                } else if r >= FAR_FIELD_RADII * a {
                    // The skin at rest, sampled thinly: there is a lot of it.
                    ((x % 3 == 0 && y % 3 == 0).then_some((0.0, 0.0)), 1.0)
                } else if r >= a && x % 2 == 0 && y % 2 == 0 {
                    // The sinking gel around the contact: the sensor
                    // model's own slopes.
                    let gx = (depth(x + 1, y) - depth(x - 1, y)) / (2.0 * mm);
                    let gy = (depth(x, y + 1) - depth(x, y - 1)) / (2.0 * mm);
                    (Some((gx, gy)), 0.5)
                } else {
                    (None, 0.0)
                };
                if let Some((gx, gy)) = slope {
                    samples.push(OpticsSample {
                        x: x as f64,
                        y: y as f64,
                        gx,
                        gy,
                        change: change(x, y),
                        weight,
                    });
                }
            }
        }
        profiles.push(BallProfile {
            ball_mm: cap.ball_radius_px * mm,
            contact_mm: a * mm,
            profile: radial_profile(
                &map.indentation_m,
                (w, h),
                (cx, cy),
                mm,
                FAR_FIELD_RADII * a * mm,
            ),
        });
    }
    let optics = SensorOptics::fit((w, h), OPTICS_BINS, OPTICS_MAX_SLOPE, &samples)?;
    let (gel, gel_profile_error_mm) =
        GelResponse::fit(&profiles).map_err(|e| match profiles.is_empty() {
            true => e.into(),
            false => unfitted_gel(ds, &profiles),
        })?;
    let model = RenderModel {
        sensor: sensor.to_string(),
        mm_per_px: mm,
        optics,
        gel,
        fit: serde_json::Value::Null,
    };
    let (colour_error_levels, colour_error_unpressed_levels) =
        colour_error(ds, bg, presses, &model)?;
    let warning = (colour_error_levels > BARELY_EXPLAINED * colour_error_unpressed_levels).then(|| {
        format!(
            "warning: {}: the presses rendered back from this calibration differ from the real ones by {colour_error_levels:.1} grey levels, near the {colour_error_unpressed_levels:.1} of the skin at rest: its render model barely explains them (the shared GelSight R1.5 gives 6.4 against 14.5), and the frames it renders to train a detector would be unlike this sensor's; {}",
            ds.scale_file.display(),
            press_geometry(ds, &profiles)
        )
    });
    let fit = RenderFit {
        optics_samples: samples.len(),
        gel,
        gel_profile_error_mm,
        colour_error_levels,
        colour_error_unpressed_levels,
        warning,
    };
    let model = RenderModel {
        fit: serde_json::to_value(&fit).unwrap_or_default(),
        ..model
    };
    Ok((model, fit))
}

/// A ball pressed to a contact circle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallPress {
    /// The contact circle, frame pixels.
    pub circle: crate::layout::Circle,
    /// The ball's radius, mm.
    pub ball_mm: f64,
}

impl BallPress {
    /// Press `i` of `ds` with its `circle`.
    pub fn of(ds: &BallPresses, i: usize, circle: crate::layout::Circle) -> Self {
        Self {
            circle,
            ball_mm: ds.ball_diameter_mm(i) / 2.0,
        }
    }
}

/// Each of `presses` rendered through `model` over `background`, without
/// noise or jitter: what the sensor would show, as RGB bytes of the
/// frame's size (`None` where the gel cannot reach that contact).
pub fn render_presses(
    model: &RenderModel,
    background: &RgbImage,
    presses: &[BallPress],
) -> Vec<Option<Vec<u8>>> {
    let (w, h) = (background.width(), background.height());
    let sensor = CalibratedSensor {
        dir: Default::default(),
        model: model.clone(),
        background: background.as_slice().to_vec(),
    };
    let config = CalibratedConfig {
        exposure_jitter: datasets_synth::Range::fixed(0.0),
        noise_sigma: datasets_synth::Range::fixed(0.0),
        ..CalibratedConfig::default()
    };
    let mm = model.mm_per_px;
    let (cx0, cy0) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    // One sweep of approaches per ball.
    let mut approaches = vec![None; presses.len()];
    let mut balls: Vec<f64> = presses.iter().map(|p| p.ball_mm).collect();
    balls.sort_by(f64::total_cmp);
    balls.dedup();
    for ball_mm in balls {
        let these: Vec<usize> = (0..presses.len())
            .filter(|&i| presses[i].ball_mm == ball_mm)
            .collect();
        let contacts: Vec<f64> = (these.iter())
            .map(|&i| presses[i].circle.radius_px * mm)
            .collect();
        for (&i, a) in these
            .iter()
            .zip(model.gel.ball_approaches(ball_mm, &contacts))
        {
            approaches[i] = a;
        }
    }
    presses
        .iter()
        .zip(approaches)
        .enumerate()
        .map(|(i, (p, approach))| {
            let approach = approach?;
            let c = p.circle;
            let scene = CalibratedScene {
                contact: Contact::Sphere {
                    radius_mm: p.ball_mm,
                    centre: ((c.centre_x_px - cx0) * mm, (c.centre_y_px - cy0) * mm),
                },
                peak_press_mm: approach,
                optics_gain: [1.0; 3],
                gel_sigma_factor: 1.0,
                blur_px: 0.0,
                shift_px: (0, 0),
            };
            let mut rng = tactile_core::rng::SampleRng::new(0, 0, i as u64);
            Some(render(&sensor, &config, &scene, approach, &mut rng).rgb)
        })
        .collect()
}

/// Render every press through `model` (the ball where its circle is, no
/// noise or jitter) and compare with the real frame within two contact
/// radii: mean |difference| in 8-bit levels, and the same for the bare
/// background.
fn colour_error(
    ds: &BallPresses,
    bg: &PreparedBackground,
    presses: &[PreparedPress],
    model: &RenderModel,
) -> Result<(f64, f64)> {
    let (w, h) = ds.size();
    let pressed: Vec<BallPress> = (presses.iter().enumerate())
        .map(|(i, p)| BallPress::of(ds, i, p.circle))
        .collect();
    let rendered = render_presses(model, &ds.background, &pressed);
    let (mut sum, mut bare, mut n) = (0f64, 0f64, 0usize);
    for (i, (press, out)) in pressed.iter().zip(rendered).enumerate() {
        let Some(out) = out else { continue };
        let c = press.circle;
        let frame = ds.frame(i)?;
        let gain = exposure_gain(bg, &frame)?;
        let real = frame.as_slice();
        let back = ds.background.as_slice();
        for y in 0..h {
            for x in 0..w {
                if (x as f64 - c.centre_x_px).hypot(y as f64 - c.centre_y_px) > 2.0 * c.radius_px {
                    continue;
                }
                for (ch, g) in gain.iter().enumerate() {
                    let k = (y * w + x) * 3 + ch;
                    let r = real[k] as f64 * *g as f64;
                    sum += (out[k] as f64 - r).abs();
                    bare += (back[k] as f64 - r).abs();
                    n += 1;
                }
            }
        }
    }
    let n = n.max(1) as f64;
    Ok((sum / n, bare / n))
}
