//! A second, deliberately different renderer of the visuo-tactile sensor of
//! `sensors.md`: the same scene, press and labels, another raster and
//! shading path. It is a cross-check set that no model trains on, standing
//! in for the other implementations of the spec that held-out data come
//! from. Where the reference renderer ([`crate::visuotactile::render`])
//! takes one analytic sample per pixel, this one:
//!
//! - samples the displacement on a 2x2 grid inside each pixel and shades
//!   each sample with normals from central finite differences of that
//!   displacement (not the analytic gradient), then averages the samples;
//! - applies the exposure after the blur, and blurs with three box passes
//!   (a box and a binomial pass, the usual fast stand-in for the Gaussian);
//! - places the LED glare with a per-sequence jitter of its position
//!   (1.5 % of the width) and size (15 %);
//! - adds noise whose variance follows the signal (shot-like, the spec's
//!   sigma at grey 0.6) and quantises with random dither instead of
//!   rounding.
//!
//! The labels (mask, tendon, direction, depth) are the reference's exactly:
//! they are geometry, not rendering.

use crate::raster::to_u8;
use crate::rng::SampleRng;
use crate::visuotactile::{
    ALBEDO, AMBIENT, Camera, GLARE_AMPLITUDE, GLARE_DIRECTION_DEG, GLARE_RADIUS_FRACTION,
    GLARE_SIGMA_FRACTION, HOUSING_RGB, LIGHT_AZIMUTH_DEG, LIGHT_ELEVATION_DEG, MASK_FLOOR_MM,
    MASK_FRACTION, NOMINAL_DEPTH_MM, SequenceScene, TENDON_MIN_AMPLITUDE_MM, VisuotactileConfig,
    VisuotactileFrame, surface,
};

/// Finite-difference step for the normals, pixels.
const STEP_PX: f64 = 0.25;

/// Render one frame of `scene` at `press_mm` the alternate way; `rng`
/// supplies the frame's exposure, noise and dither, `glare_rng` the
/// sequence's glare jitter.
pub fn render_alternate(
    config: &VisuotactileConfig,
    scene: &SequenceScene,
    press_mm: f64,
    rng: &mut SampleRng,
    glare_rng: &mut SampleRng,
) -> VisuotactileFrame {
    let cam = Camera::new(config.width, config.height);
    let (w, h) = (cam.width, cam.height);
    let exposure = 1.0 + rng.draw(config.exposure_jitter);
    let noise_sigma = rng.draw(config.noise_sigma);
    let amp = scene.ridge_amplitude_mm(press_mm);
    let threshold = (MASK_FRACTION * amp).max(MASK_FLOOR_MM);
    let mm_per_px = NOMINAL_DEPTH_MM / cam.fx;
    let elev = LIGHT_ELEVATION_DEG.to_radians();
    let lights: Vec<[f64; 3]> = LIGHT_AZIMUTH_DEG
        .iter()
        .map(|az| {
            let az = az.to_radians();
            [elev.cos() * az.cos(), elev.cos() * az.sin(), -elev.sin()]
        })
        .collect();
    let disp = |u: f64, v: f64| surface(&cam, scene, press_mm, u, v).disp;
    let mut planes = vec![vec![0.0f32; w * h]; 3];
    let mut mask = vec![0u8; w * h];
    let mut depth_m = vec![0.0f32; w * h];
    for v in 0..h {
        for u in 0..w {
            let (uf, vf) = (u as f64, v as f64);
            let i = v * w + u;
            let d0 = cam.rest_depth_mm(uf, vf);
            if !cam.in_window(uf, vf) {
                depth_m[i] = (d0 * 1e-3) as f32;
                for (c, plane) in planes.iter_mut().enumerate() {
                    plane[i] = (HOUSING_RGB[c] / 255.0) as f32;
                }
                continue;
            }
            let centre = surface(&cam, scene, press_mm, uf, vf);
            if centre.ridge > threshold {
                mask[i] = 255;
            }
            depth_m[i] = ((d0 - centre.disp) * 1e-3) as f32;
            let mut shade = [0.0f64; 3];
            for (su, sv) in [(-0.25, -0.25), (0.25, -0.25), (-0.25, 0.25), (0.25, 0.25)] {
                let (x, y) = (uf + su, vf + sv);
                // de/dx with e = -disp, per mm.
                let ex =
                    -(disp(x + STEP_PX, y) - disp(x - STEP_PX, y)) / (2.0 * STEP_PX * mm_per_px);
                let ey =
                    -(disp(x, y + STEP_PX) - disp(x, y - STEP_PX)) / (2.0 * STEP_PX * mm_per_px);
                let len = (ex * ex + ey * ey + 1.0).sqrt();
                for (c, l) in lights.iter().enumerate() {
                    let ndl = (ex * l[0] + ey * l[1] - l[2]) / len;
                    shade[c] += 0.25 * ALBEDO * (AMBIENT + ndl.max(0.0));
                }
            }
            for (c, plane) in planes.iter_mut().enumerate() {
                plane[i] = shade[c] as f32;
            }
        }
    }
    let tendon = press_mm > 0.0 && amp >= TENDON_MIN_AMPLITUDE_MM && mask.iter().any(|&m| m > 0);
    if !tendon {
        mask.fill(0);
    }
    // The glare, jittered per sequence.
    let (a, b) = cam.window_radii();
    let g_angle = GLARE_DIRECTION_DEG.to_radians();
    let jitter = 0.015 * w as f64;
    let (gu, gv) = (
        cam.cx
            + GLARE_RADIUS_FRACTION * a * g_angle.cos()
            + jitter * (2.0 * glare_rng.uniform() - 1.0),
        cam.cy
            + GLARE_RADIUS_FRACTION * b * g_angle.sin()
            + jitter * (2.0 * glare_rng.uniform() - 1.0),
    );
    let g_sigma =
        GLARE_SIGMA_FRACTION * w as f64 * (1.0 + 0.15 * (2.0 * glare_rng.uniform() - 1.0));
    for plane in planes.iter_mut() {
        for (i, p) in plane.iter_mut().enumerate() {
            let (u, v) = ((i % w) as f64, (i / w) as f64);
            let d2 = (u - gu).powi(2) + (v - gv).powi(2);
            *p += (GLARE_AMPLITUDE * (-d2 / (2.0 * g_sigma * g_sigma)).exp()) as f32;
        }
        box_blur3(plane, w, h);
        for p in plane.iter_mut() {
            *p *= exposure as f32;
        }
    }
    let mut rgb = vec![0u8; w * h * 3];
    for i in 0..w * h {
        for c in 0..3 {
            let x = planes[c][i].max(0.0) as f64;
            let sigma = noise_sigma * (x / 0.6).sqrt();
            let value = x * 255.0 + sigma * rng.normal() + rng.uniform() - 0.5;
            rgb[i * 3 + c] = to_u8(value as f32);
        }
    }
    VisuotactileFrame {
        width: w,
        height: h,
        rgb,
        mask,
        depth_m,
        tendon,
        direction_deg: tendon.then(|| scene.line.direction_deg()),
        press_mm: press_mm.max(0.0),
        ridge_mm: amp,
    }
}

/// The spec's 1 px blur the fast way: a 3-tap box (variance 2/3) then
/// a [1, 2, 1] / 4 binomial (variance 1/2) along rows and columns, sigma
/// 1.08 px in all; edges clamped.
fn box_blur3(plane: &mut [f32], w: usize, h: usize) {
    let passes: [&[f32; 3]; 2] = [&[1.0 / 3.0; 3], &[0.25, 0.5, 0.25]];
    let mut line = vec![0.0f32; w.max(h)];
    for k in passes {
        for y in 0..h {
            line[..w].copy_from_slice(&plane[y * w..(y + 1) * w]);
            for x in 0..w {
                let at = |d: isize| line[(x as isize + d).clamp(0, w as isize - 1) as usize];
                plane[y * w + x] = k[0] * at(-1) + k[1] * at(0) + k[2] * at(1);
            }
        }
        for x in 0..w {
            for y in 0..h {
                line[y] = plane[y * w + x];
            }
            for y in 0..h {
                let at = |d: isize| line[(y as isize + d).clamp(0, h as isize - 1) as usize];
                plane[y * w + x] = k[0] * at(-1) + k[1] * at(0) + k[2] * at(1);
            }
        }
    }
}
