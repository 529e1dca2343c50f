//! The reference renderer: the skin's displacement and analytic gradient
//! under contact, Lambert shading by three coloured LEDs, and the camera
//! (exposure, glare, blur, noise, 8 bits); the labels (mask, depth,
//! direction) are geometry, shared with the alternate renderer.

use crate::raster::{Border, gaussian_blur, to_u8};
use crate::rng::SampleRng;

use super::camera::{Camera, sub};
use super::scene::SequenceScene;
use super::*;

/// A rendered frame with its labels.
pub struct VisuotactileFrame {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// RGB, row-major interleaved.
    pub rgb: Vec<u8>,
    /// 0 or 255 per pixel.
    pub mask: Vec<u8>,
    /// Camera-to-skin distance, metres.
    pub depth_m: Vec<f32>,
    /// The `tendon` label.
    pub tendon: bool,
    /// Present when `tendon`.
    pub direction_deg: Option<f64>,
    /// `max(press, 0)`, mm.
    pub press_mm: f64,
    /// Ridge amplitude `A`, mm.
    pub ridge_mm: f64,
}

/// The skin at one point of the window under contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    /// Displacement toward the camera, mm.
    pub disp: f64,
    /// Its gradient along image x, mm per mm.
    pub gx: f64,
    /// Along image y.
    pub gy: f64,
    /// The tendon ridge's part of `disp`, mm.
    pub ridge: f64,
}

/// The displacement of the skin at pixel `(u, v)` (any real position) and
/// its analytic gradient: the whole-window push and the tendon ridge.
pub fn surface(cam: &Camera, scene: &SequenceScene, press_mm: f64, u: f64, v: f64) -> Surface {
    if press_mm <= 0.0 {
        return Surface {
            disp: 0.0,
            gx: 0.0,
            gy: 0.0,
            ridge: 0.0,
        };
    }
    let amp = scene.ridge_amplitude_mm(press_mm);
    let width_mm = scene.ridge_width_mm();
    let mm_per_px = NOMINAL_DEPTH_MM / cam.fx;
    let r2 = (u - cam.cx).powi(2) + (v - cam.cy).powi(2);
    let rm2 = cam.r_max * cam.r_max;
    let mut disp = WINDOW_PUSH * press_mm * (1.0 - r2 / rm2);
    // d/dx of (1 - r^2/rm^2) with r in pixels and x in mm.
    let k = WINDOW_PUSH * press_mm * (-2.0 / rm2) / mm_per_px;
    let (mut gx, mut gy) = (k * (u - cam.cx), k * (v - cam.cy));
    let p = cam.to_mm(u, v);
    let q = scene.line.nearest(p);
    let (dx, dy) = sub(p, q);
    let ridge = amp * libm::exp(-(dx * dx + dy * dy) / (2.0 * width_mm * width_mm));
    disp += ridge;
    gx -= ridge * dx / (width_mm * width_mm);
    gy -= ridge * dy / (width_mm * width_mm);
    Surface {
        disp,
        gx,
        gy,
        ridge,
    }
}

/// The three LEDs' unit directions (light travelling into the skin), one
/// per colour channel.
pub(crate) fn light_vectors() -> [[f64; 3]; 3] {
    let elev = LIGHT_ELEVATION_DEG.to_radians();
    LIGHT_AZIMUTH_DEG.map(|az| {
        let az = az.to_radians();
        [
            libm::cos(elev) * libm::cos(az),
            libm::cos(elev) * libm::sin(az),
            -libm::sin(elev),
        ]
    })
}

/// Lambert shading with ambient, per channel, of skin whose depth slope is
/// `(ex, ey)`: `de/dx`, `de/dy` with `e = depth - d0 = -disp`, per mm. The
/// normal is `normalize(ex, ey, -1)`.
pub(crate) fn shade(ex: f64, ey: f64, lights: &[[f64; 3]; 3]) -> [f64; 3] {
    let len = libm::sqrt(ex * ex + ey * ey + 1.0);
    lights.map(|l| {
        let ndl = (ex * l[0] + ey * l[1] - l[2]) / len;
        ALBEDO * (AMBIENT + ndl.max(0.0))
    })
}

/// A frame before the camera: linear colour planes and the labels, which
/// are geometry and the same for every renderer.
pub(crate) struct Raster {
    /// One linear plane per channel, [0, 1] before exposure and glare.
    pub planes: Vec<Vec<f32>>,
    mask: Vec<u8>,
    depth_m: Vec<f32>,
    tendon: bool,
    ridge_mm: f64,
}

impl Raster {
    /// Every pixel of `scene` at `press_mm`: the housing colour outside the
    /// window, `shade_px(u, v, surface)` inside it, and the mask, depth and
    /// tendon labels.
    pub(crate) fn new(
        cam: &Camera,
        scene: &SequenceScene,
        press_mm: f64,
        mut shade_px: impl FnMut(f64, f64, &Surface) -> [f64; 3],
    ) -> Self {
        let (w, h) = (cam.width, cam.height);
        let amp = scene.ridge_amplitude_mm(press_mm);
        let threshold = (MASK_FRACTION * amp).max(MASK_FLOOR_MM);
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
                let at = surface(cam, scene, press_mm, uf, vf);
                if at.ridge > threshold {
                    mask[i] = 255;
                }
                depth_m[i] = ((d0 - at.disp) * 1e-3) as f32;
                for (plane, value) in planes.iter_mut().zip(shade_px(uf, vf, &at)) {
                    plane[i] = value as f32;
                }
            }
        }
        let tendon =
            press_mm > 0.0 && amp >= TENDON_MIN_AMPLITUDE_MM && mask.iter().any(|&m| m > 0);
        if !tendon {
            mask.fill(0);
        }
        Self {
            planes,
            mask,
            depth_m,
            tendon,
            ridge_mm: amp,
        }
    }

    /// The finished frame: the camera's 8-bit `rgb` with these labels.
    pub(crate) fn into_frame(
        self,
        cam: &Camera,
        scene: &SequenceScene,
        press_mm: f64,
        rgb: Vec<u8>,
    ) -> VisuotactileFrame {
        VisuotactileFrame {
            width: cam.width,
            height: cam.height,
            rgb,
            mask: self.mask,
            depth_m: self.depth_m,
            tendon: self.tendon,
            direction_deg: self.tendon.then(|| scene.line.direction_deg()),
            press_mm: press_mm.max(0.0),
            ridge_mm: self.ridge_mm,
        }
    }
}

/// A frame's exposure factor and noise sigma, the first draws of its
/// random stream (every renderer draws them so).
pub(crate) fn camera_draws(config: &VisuotactileConfig, rng: &mut SampleRng) -> (f64, f64) {
    let exposure = 1.0 + rng.draw(config.exposure_jitter);
    let noise_sigma = rng.draw(config.noise_sigma);
    (exposure, noise_sigma)
}

/// The reference renderer's LED glare, per pixel, in [0, 1] channel units.
pub(crate) fn glare_plane(cam: &Camera) -> Vec<f32> {
    let (w, h) = (cam.width, cam.height);
    let (gu, gv) = cam.glare_centre();
    let g_sigma = GLARE_SIGMA_FRACTION * w as f64;
    (0..w * h)
        .map(|i| {
            let (u, v) = ((i % w) as f64, (i / w) as f64);
            let d2 = (u - gu).powi(2) + (v - gv).powi(2);
            (GLARE_AMPLITUDE * libm::exp(-d2 / (2.0 * g_sigma * g_sigma))) as f32
        })
        .collect()
}

/// Render one frame of `scene` at `press_mm`; `rng` supplies the frame's
/// exposure and noise.
pub fn render(
    config: &VisuotactileConfig,
    scene: &SequenceScene,
    press_mm: f64,
    rng: &mut SampleRng,
) -> VisuotactileFrame {
    let cam = Camera::new(config.width, config.height);
    let (w, h) = (cam.width, cam.height);
    let (exposure, noise_sigma) = camera_draws(config, rng);
    let lights = light_vectors();
    // One analytic sample per pixel.
    let mut raster = Raster::new(&cam, scene, press_mm, |_, _, at| {
        shade(-at.gx, -at.gy, &lights)
    });

    // Camera: exposure, LED glare, optical blur, noise, 8 bits.
    let glare = glare_plane(&cam);
    for plane in raster.planes.iter_mut() {
        for (p, g) in plane.iter_mut().zip(&glare) {
            *p = *p * exposure as f32 + g;
        }
        gaussian_blur(plane, w, h, BLUR_PX, Border::Clamp);
    }
    let mut rgb = vec![0u8; w * h * 3];
    for i in 0..w * h {
        for c in 0..3 {
            rgb[i * 3 + c] =
                to_u8(raster.planes[c][i] * 255.0 + (noise_sigma * rng.normal()) as f32);
        }
    }
    raster.into_frame(&cam, scene, press_mm, rgb)
}
