//! A calibrated sensor's frame: the object's overlap with the skin, the
//! gel's response (indentation), its slopes, the optics' colour change over
//! the sensor's own background, then the camera (blur, exposure, noise, 8
//! bits). The labels are the indentation itself: the tendon mask where a
//! tendon pushes the skin in past the contact threshold.

use tactile_core::spec::calibrated::CONTACT_MIN_INDENTATION_MM;

use crate::raster::{Border, gaussian_blur, to_u8};
use crate::rng::SampleRng;

use super::scene::{CalibratedScene, Contact};
use super::{CalibratedConfig, CalibratedSensor};

/// A rendered frame of a calibrated sensor with its labels.
pub struct CalibratedFrame {
    /// Width, pixels (the sensor's).
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// RGB, row-major interleaved.
    pub rgb: Vec<u8>,
    /// 0 or 255 per pixel: where a tendon pushes the skin in past
    /// [`CONTACT_MIN_INDENTATION_MM`].
    pub mask: Vec<u8>,
    /// The skin's indentation (toward the camera, 0 at rest), metres.
    pub indentation_m: Vec<f32>,
    /// The `tendon` label: a tendon pushes the skin in past the threshold.
    pub tendon: bool,
    /// Present when `tendon`.
    pub direction_deg: Option<f64>,
    /// `max(press, 0)`, mm.
    pub press_mm: f64,
    /// The deepest indentation, mm.
    pub peak_mm: f64,
    /// A tendon's deepest push, mm (0 for other objects): what the
    /// `tendon` label thresholds, for soft labels.
    pub ridge_mm: f64,
}

/// The skin's indentation under `contact` at `press_mm` on `sensor`
/// (`sigma_factor` on the gel's spread), mm, row-major.
pub fn indentation_mm(
    sensor: &CalibratedSensor,
    contact: &Contact,
    press_mm: f64,
    sigma_factor: f64,
) -> Vec<f32> {
    let (w, h) = (sensor.width(), sensor.height());
    if press_mm <= 0.0 || matches!(contact, Contact::Nothing) {
        return vec![0.0; w * h];
    }
    let step = sensor.model.mm_per_px;
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let overlap: Vec<f32> = (0..w * h)
        .map(|i| {
            let p = (((i % w) as f64 - cx) * step, ((i / w) as f64 - cy) * step);
            match contact.height_mm(p) {
                Some(s) => (press_mm - s) as f32,
                None => f32::NEG_INFINITY,
            }
        })
        .collect();
    let gel = super::GelResponse {
        sigma_mm: sensor.model.gel.sigma_mm * sigma_factor,
        ..sensor.model.gel
    };
    gel.indentation_mm(&overlap, (w, h), step)
}

/// Render frame `press_mm` of `scene`; `rng` gives the frame's exposure
/// and noise.
pub fn render(
    sensor: &CalibratedSensor,
    config: &CalibratedConfig,
    scene: &CalibratedScene,
    press_mm: f64,
    rng: &mut SampleRng,
) -> CalibratedFrame {
    let (w, h) = (sensor.width(), sensor.height());
    let exposure = 1.0 + rng.draw(config.exposure_jitter);
    let noise_sigma = rng.draw(config.noise_sigma);
    let ind = indentation_mm(sensor, &scene.contact, press_mm, scene.gel_sigma_factor);
    let step = sensor.model.mm_per_px;
    let at = |x: usize, y: usize| ind[y * w + x] as f64;
    // The background, shifted (the unit's own small misalignment).
    let (sx, sy) = scene.shift_px;
    let bg = &sensor.background;
    let mut planes = vec![vec![0f32; w * h]; 3];
    for y in 0..h {
        let by = (y as i64 + sy).clamp(0, h as i64 - 1) as usize;
        for x in 0..w {
            let bx = (x as i64 + sx).clamp(0, w as i64 - 1) as usize;
            let i = y * w + x;
            // The colour change over the table's own answer at rest (the
            // background already shows the skin at rest), where the skin
            // or a neighbour is pushed in.
            let mut change = [0f32; 3];
            if ind[i] > 0.0
                || (x > 0 && at(x - 1, y) > 0.0)
                || (x + 1 < w && at(x + 1, y) > 0.0)
                || (y > 0 && at(x, y - 1) > 0.0)
                || (y + 1 < h && at(x, y + 1) > 0.0)
            {
                let (x0, x1) = (x.saturating_sub(1), (x + 1).min(w - 1));
                let (y0, y1) = (y.saturating_sub(1), (y + 1).min(h - 1));
                let gx = (at(x1, y) - at(x0, y)) / ((x1 - x0).max(1) as f64 * step);
                let gy = (at(x, y1) - at(x, y0)) / ((y1 - y0).max(1) as f64 * step);
                let optics = &sensor.model.optics;
                let (pushed, rest) = (
                    optics.change(x as f64, y as f64, gx, gy),
                    optics.change(x as f64, y as f64, 0.0, 0.0),
                );
                for c in 0..3 {
                    change[c] = scene.optics_gain[c] as f32 * (pushed[c] - rest[c]);
                }
            }
            for c in 0..3 {
                planes[c][i] = bg[(by * w + bx) * 3 + c] as f32 / 255.0 + change[c];
            }
        }
    }
    for plane in planes.iter_mut() {
        gaussian_blur(plane, w, h, scene.blur_px, Border::Clamp);
    }
    let mut rgb = vec![0u8; w * h * 3];
    for i in 0..w * h {
        for c in 0..3 {
            let v = planes[c][i] * exposure as f32 * 255.0 + (noise_sigma * rng.normal()) as f32;
            rgb[i * 3 + c] = to_u8(v);
        }
    }
    let is_tendon = matches!(scene.contact, Contact::Tendon { .. });
    let min = CONTACT_MIN_INDENTATION_MM as f32;
    let mask: Vec<u8> = ind
        .iter()
        .map(|&v| if is_tendon && v > min { 255 } else { 0 })
        .collect();
    let tendon = mask.iter().any(|&m| m > 0);
    let peak_mm = ind.iter().copied().fold(0f32, f32::max) as f64;
    CalibratedFrame {
        width: w,
        height: h,
        rgb,
        mask,
        indentation_m: ind.iter().map(|v| v * 1e-3).collect(),
        tendon,
        direction_deg: tendon.then(|| scene.contact.direction_deg()).flatten(),
        press_mm: press_mm.max(0.0),
        peak_mm,
        ridge_mm: if is_tendon { peak_mm } else { 0.0 },
    }
}
