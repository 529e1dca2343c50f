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

use super::render::{Raster, light_vectors, shade};
use super::{
    Camera, GLARE_AMPLITUDE, GLARE_SIGMA_FRACTION, NOMINAL_DEPTH_MM, SequenceScene,
    VisuotactileConfig, VisuotactileFrame, surface,
};
use crate::raster::to_u8;
use crate::rng::SampleRng;

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
    let (exposure, noise_sigma) = super::render::camera_draws(config, rng);
    let mm_per_px = NOMINAL_DEPTH_MM / cam.fx;
    let lights = light_vectors();
    let disp = |u: f64, v: f64| surface(&cam, scene, press_mm, u, v).disp;
    // A 2x2 grid of samples per pixel, each with finite-difference normals.
    let mut raster = Raster::new(&cam, scene, press_mm, |uf, vf, _| {
        let mut sum = [0.0f64; 3];
        for (su, sv) in [(-0.25, -0.25), (0.25, -0.25), (-0.25, 0.25), (0.25, 0.25)] {
            let (x, y) = (uf + su, vf + sv);
            // de/dx with e = -disp, per mm.
            let ex = -(disp(x + STEP_PX, y) - disp(x - STEP_PX, y)) / (2.0 * STEP_PX * mm_per_px);
            let ey = -(disp(x, y + STEP_PX) - disp(x, y - STEP_PX)) / (2.0 * STEP_PX * mm_per_px);
            for (s, v) in sum.iter_mut().zip(shade(ex, ey, &lights)) {
                *s += 0.25 * v;
            }
        }
        sum
    });
    // The glare, jittered per sequence.
    let jitter = 0.015 * w as f64;
    let (gu, gv) = cam.glare_centre();
    let (gu, gv) = (
        gu + jitter * (2.0 * glare_rng.uniform() - 1.0),
        gv + jitter * (2.0 * glare_rng.uniform() - 1.0),
    );
    let g_sigma =
        GLARE_SIGMA_FRACTION * w as f64 * (1.0 + 0.15 * (2.0 * glare_rng.uniform() - 1.0));
    for plane in raster.planes.iter_mut() {
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
            let x = raster.planes[c][i].max(0.0) as f64;
            let sigma = noise_sigma * (x / 0.6).sqrt();
            let value = x * 255.0 + sigma * rng.normal() + rng.uniform() - 0.5;
            rgb[i * 3 + c] = to_u8(value as f32);
        }
    }
    raster.into_frame(&cam, scene, press_mm, rgb)
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
