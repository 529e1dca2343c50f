//! The virtual TacTip of `sensors.md` section 1 (version 1).
//!
//! A frame is made in three steps: the penetration field `p(x, y)` of the
//! object in the undeformed hemisphere (on a 0.2 mm grid, blurred by the
//! gel's sigma of 2 mm), the 127 pins moved and grown by that field, and the
//! camera (illumination field, light blob, optical blur, sensor noise).
//! Choices the spec leaves open are listed in `docs/synth.md`.

use serde::{Deserialize, Serialize};
use tactile_core::spec::{columns, tactip::label_applies};
use tactile_core::{Error, Result};

use crate::raster::{Border, gaussian_blur, to_u8};
use crate::rng::{Range, SampleRng};

/// Tip radius, mm.
pub const TIP_RADIUS_MM: f64 = 20.0;
/// Pin lattice spacing along the surface, mm.
pub const PIN_SPACING_MM: f64 = 2.6;
/// Pin lattice rings around the centre pin.
pub const PIN_RINGS: i32 = 6;
/// Pin disc radius at rest, mm.
pub const PIN_RADIUS_MM: f64 = 0.4;
/// Frame side, pixels.
pub const FRAME_PX: usize = 300;
/// Camera scale, pixels per mm.
pub const PX_PER_MM: f64 = 9.0;
/// Tip centre in pixel coordinates (origin at the top-left pixel's centre).
pub const CENTRE_PX: f64 = 149.5;
/// Gel spread of the load: Gaussian sigma of the penetration field, mm.
pub const GEL_SIGMA_MM: f64 = 2.0;
/// Pin displacement per unit penetration gradient, mm.
pub const PIN_ALPHA_MM: f64 = 2.5;
/// Pin radius growth per mm of penetration.
pub const PIN_GROWTH_PER_MM: f64 = 0.08;
/// Force per unit penetration volume, N / mm^3.
pub const FORCE_N_PER_MM3: f64 = 0.06;
/// Vignetting strength.
pub const VIGNETTE: f64 = 0.35;
/// Optical blur, pixels.
pub const OPTICAL_BLUR_PX: f64 = 0.8;
/// Grid spacing of the penetration field, mm.
pub const GRID_MM: f64 = 0.2;
/// Half-extent of the penetration grid: the tip plus 3 gel sigmas, mm.
pub const GRID_HALF_MM: f64 = 26.0;
/// Cuboid face, mm (long side along theta).
pub const CUBOID_FACE_MM: (f64, f64) = (27.0, 9.0);

/// The contact shapes, in the spec's order (the first four are paper A's classes).
pub const SHAPES: [&str; 7] = [
    "cuboid",
    "cylinderR4",
    "cylinderR8",
    "prism",
    "edge",
    "sphere",
    "flat",
];

/// An object pressed into the tip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// A box face 9 x 27 mm, long side along theta.
    Cuboid,
    /// A cylinder lying with its axis along theta.
    Cylinder {
        /// Radius, mm.
        radius_mm: f64,
    },
    /// A triangular prism on a side, its 60-degree ridge along theta.
    Prism,
    /// A half-plane with its edge along theta.
    Edge,
    /// A sphere.
    Sphere {
        /// Radius, mm.
        radius_mm: f64,
    },
    /// A plane.
    Flat,
}

impl Shape {
    /// The class label.
    pub fn name(&self) -> &'static str {
        match self {
            Shape::Cuboid => "cuboid",
            Shape::Cylinder { radius_mm } if *radius_mm == 4.0 => "cylinderR4",
            Shape::Cylinder { .. } => "cylinderR8",
            Shape::Prism => "prism",
            Shape::Edge => "edge",
            Shape::Sphere { .. } => "sphere",
            Shape::Flat => "flat",
        }
    }

    /// Whether `theta` means something for this shape
    /// ([`label_applies`], which every reader of the labels asks too).
    pub fn has_orientation(&self) -> bool {
        label_applies(self.name(), columns::THETA_DEG)
    }

    /// Whether the contact position means something for this shape.
    pub fn has_position(&self) -> bool {
        label_applies(self.name(), columns::X_MM)
    }
}

/// The per-sample ranges of the virtual TacTip (defaults: the spec's
/// training distribution).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default, deny_unknown_fields)]
pub struct TactipConfig {
    /// Shapes drawn uniformly, by name.
    #[arg(long, value_delimiter = ',', default_values_t = TactipConfig::default().shapes)]
    pub shapes: Vec<String>,
    /// Indentation past first touch, mm.
    #[arg(long, default_value_t = TactipConfig::default().depth_mm)]
    pub depth_mm: Range,
    /// Contact x, mm.
    #[arg(long, default_value_t = TactipConfig::default().x_mm)]
    pub x_mm: Range,
    /// Contact y, mm.
    #[arg(long, default_value_t = TactipConfig::default().y_mm)]
    pub y_mm: Range,
    /// In-plane orientation, degrees.
    #[arg(long, default_value_t = TactipConfig::default().theta_deg)]
    pub theta_deg: Range,
    /// Sphere radius, mm.
    #[arg(long, default_value_t = TactipConfig::default().sphere_radius_mm)]
    pub sphere_radius_mm: Range,
    /// Grey level of a pin at rest.
    #[arg(long, default_value_t = TactipConfig::default().pin_grey)]
    pub pin_grey: Range,
    /// Grey level of the background.
    #[arg(long, default_value_t = TactipConfig::default().background_grey)]
    pub background_grey: Range,
    /// `g0` of the illumination field.
    #[arg(long, default_value_t = TactipConfig::default().gain)]
    pub gain: Range,
    /// `a` and `b` of the illumination field (each drawn from this range).
    #[arg(long, default_value_t = TactipConfig::default().gradient)]
    pub gradient: Range,
    /// Probability of an external light blob.
    #[arg(long, default_value_t = TactipConfig::default().blob_probability)]
    pub blob_probability: f64,
    /// Light blob width, pixels.
    #[arg(long, default_value_t = TactipConfig::default().blob_sigma_px)]
    pub blob_sigma_px: Range,
    /// Light blob amplitude, grey levels.
    #[arg(long, default_value_t = TactipConfig::default().blob_amplitude)]
    pub blob_amplitude: Range,
    /// Sensor noise, grey levels.
    #[arg(long, default_value_t = TactipConfig::default().noise_sigma)]
    pub noise_sigma: Range,
    /// Relative standard deviation of the load-cell noise on `force_n`.
    #[arg(long, default_value_t = TactipConfig::default().force_noise)]
    pub force_noise: f64,
}

impl Default for TactipConfig {
    fn default() -> Self {
        Self {
            shapes: SHAPES.iter().map(|s| s.to_string()).collect(),
            depth_mm: Range::new(0.0, 5.0),
            x_mm: Range::new(-6.0, 6.0),
            y_mm: Range::new(-6.0, 6.0),
            theta_deg: Range::new(0.0, 180.0),
            sphere_radius_mm: Range::new(4.0, 10.0),
            pin_grey: Range::new(210.0, 240.0),
            background_grey: Range::new(20.0, 45.0),
            gain: Range::new(0.8, 1.2),
            gradient: Range::new(-0.25, 0.25),
            blob_probability: 0.3,
            blob_sigma_px: Range::new(40.0, 90.0),
            blob_amplitude: Range::new(20.0, 60.0),
            noise_sigma: Range::new(3.0, 8.0),
            force_noise: 0.02,
        }
    }
}

impl TactipConfig {
    /// Check every value; the message names the offending key.
    pub fn validate(&self) -> Result<()> {
        if self.shapes.is_empty() {
            return Err(Error::Config("shapes: at least one shape is needed".into()));
        }
        for s in &self.shapes {
            if !SHAPES.contains(&s.as_str()) {
                return Err(Error::Config(format!(
                    "shapes: unknown shape '{s}' (known: {})",
                    SHAPES.join(", ")
                )));
            }
        }
        self.depth_mm.check("depth_mm", 0.0, 10.0)?;
        self.x_mm.check("x_mm", -12.0, 12.0)?;
        self.y_mm.check("y_mm", -12.0, 12.0)?;
        self.theta_deg.check("theta_deg", -360.0, 360.0)?;
        self.sphere_radius_mm.check("sphere_radius_mm", 0.5, 40.0)?;
        self.pin_grey.check("pin_grey", 0.0, 255.0)?;
        self.background_grey.check("background_grey", 0.0, 255.0)?;
        self.gain.check("gain", 0.0, 4.0)?;
        self.gradient.check("gradient", -1.0, 1.0)?;
        self.blob_sigma_px.check("blob_sigma_px", 1.0, 1000.0)?;
        self.blob_amplitude.check("blob_amplitude", -255.0, 255.0)?;
        self.noise_sigma.check("noise_sigma", 0.0, 100.0)?;
        Range::fixed(self.blob_probability).check("blob_probability", 0.0, 1.0)?;
        Range::fixed(self.force_noise).check("force_noise", 0.0, 1.0)?;
        Ok(())
    }
}

/// An external light blob (additive Gaussian), in pixels and grey levels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightBlob {
    /// Centre column, pixels.
    pub u: f64,
    /// Centre row, pixels.
    pub v: f64,
    /// Width, pixels.
    pub sigma_px: f64,
    /// Peak, grey levels.
    pub amplitude: f64,
}

/// Everything that makes one frame, drawn from a [`TactipConfig`].
#[derive(Debug, Clone, PartialEq)]
pub struct TactipScene {
    /// The object.
    pub shape: Shape,
    /// Contact position, mm (for `edge`: signed distance of the edge line).
    pub x_mm: f64,
    /// Contact y, mm.
    pub y_mm: f64,
    /// In-plane orientation, degrees.
    pub theta_deg: f64,
    /// Indentation past first touch, mm.
    pub depth_mm: f64,
    /// Grey level of a pin at rest.
    pub pin_grey: f64,
    /// Grey level of the background.
    pub background_grey: f64,
    /// `g0` of the illumination field.
    pub gain: f64,
    /// `a` of the illumination field.
    pub gradient_u: f64,
    /// `b` of the illumination field.
    pub gradient_v: f64,
    /// The external light blob, in 30 % of frames.
    pub blob: Option<LightBlob>,
    /// Sensor noise, grey levels.
    pub noise_sigma: f64,
    /// Standard-normal draw for the load-cell noise.
    pub force_noise_draw: f64,
    /// Relative standard deviation of the load-cell noise.
    pub force_noise: f64,
}

impl TactipScene {
    /// Draw a scene. The draw order is fixed: changing it changes datasets.
    pub fn draw(config: &TactipConfig, rng: &mut SampleRng) -> Self {
        let name = config.shapes[rng.index(config.shapes.len())].as_str();
        let sphere_r = rng.draw(config.sphere_radius_mm);
        let shape = match name {
            "cuboid" => Shape::Cuboid,
            "cylinderR4" => Shape::Cylinder { radius_mm: 4.0 },
            "cylinderR8" => Shape::Cylinder { radius_mm: 8.0 },
            "prism" => Shape::Prism,
            "edge" => Shape::Edge,
            "sphere" => Shape::Sphere {
                radius_mm: sphere_r,
            },
            _ => Shape::Flat,
        };
        let x_mm = rng.draw(config.x_mm);
        let mut y_mm = rng.draw(config.y_mm);
        if shape == Shape::Edge {
            y_mm = 0.0;
        }
        let theta_deg = rng.draw(config.theta_deg);
        let depth_mm = rng.draw(config.depth_mm);
        let pin_grey = rng.draw(config.pin_grey);
        let background_grey = rng.draw(config.background_grey);
        let gain = rng.draw(config.gain);
        let gradient_u = rng.draw(config.gradient);
        let gradient_v = rng.draw(config.gradient);
        let has_blob = rng.chance(config.blob_probability);
        let blob = LightBlob {
            u: rng.uniform() * (FRAME_PX - 1) as f64,
            v: rng.uniform() * (FRAME_PX - 1) as f64,
            sigma_px: rng.draw(config.blob_sigma_px),
            amplitude: rng.draw(config.blob_amplitude),
        };
        let noise_sigma = rng.draw(config.noise_sigma);
        let force_noise_draw = rng.normal();
        Self {
            shape,
            x_mm,
            y_mm,
            theta_deg,
            depth_mm,
            pin_grey,
            background_grey,
            gain,
            gradient_u,
            gradient_v,
            blob: has_blob.then_some(blob),
            noise_sigma,
            force_noise_draw,
            force_noise: config.force_noise,
        }
    }

    /// A scene with a clean camera (unit gain, no blob, no noise) for tests.
    pub fn clean(shape: Shape, x_mm: f64, y_mm: f64, theta_deg: f64, depth_mm: f64) -> Self {
        Self {
            shape,
            x_mm,
            y_mm,
            theta_deg,
            depth_mm,
            pin_grey: 225.0,
            background_grey: 30.0,
            gain: 1.0,
            gradient_u: 0.0,
            gradient_v: 0.0,
            blob: None,
            noise_sigma: 0.0,
            force_noise_draw: 0.0,
            force_noise: 0.0,
        }
    }
}

/// The blurred penetration field on a square grid centred on the tip axis.
pub struct PenetrationField {
    /// Points per side.
    pub n: usize,
    /// Row-major `p` in mm; row = y, column = x.
    pub p: Vec<f32>,
}

impl PenetrationField {
    fn coord(i: usize) -> f64 {
        -GRID_HALF_MM + i as f64 * GRID_MM
    }

    /// The field of `scene`'s object pushed `depth_mm` past first touch.
    pub fn new(scene: &TactipScene) -> Self {
        let n = (2.0 * GRID_HALF_MM / GRID_MM).round() as usize + 1;
        let (s, c) = (
            libm::sin(scene.theta_deg.to_radians()),
            libm::cos(scene.theta_deg.to_radians()),
        );
        // Object surface height above its lowest point, None where absent.
        let object = |x: f64, y: f64| -> Option<f64> {
            let (dx, dy) = (x - scene.x_mm, y - scene.y_mm);
            let along = dx * c + dy * s;
            let across = -dx * s + dy * c;
            match scene.shape {
                Shape::Cuboid => (along.abs() <= CUBOID_FACE_MM.0 / 2.0
                    && across.abs() <= CUBOID_FACE_MM.1 / 2.0)
                    .then_some(0.0),
                Shape::Cylinder { radius_mm: r } => {
                    (across.abs() < r).then(|| r - libm::sqrt(r * r - across * across))
                }
                Shape::Prism => Some(3f64.sqrt() * across.abs()),
                // The object covers n . (x, y) <= x_mm, n = (-sin, cos).
                Shape::Edge => (-x * s + y * c <= scene.x_mm).then_some(0.0),
                Shape::Sphere { radius_mm: r } => {
                    let d2 = dx * dx + dy * dy;
                    (d2 < r * r).then(|| r - libm::sqrt(r * r - d2))
                }
                Shape::Flat => Some(0.0),
            }
        };
        // Gap between object and hemisphere; the smallest gap is first touch.
        let r2 = TIP_RADIUS_MM * TIP_RADIUS_MM;
        let mut gap = vec![f64::INFINITY; n * n];
        let mut min_gap = f64::INFINITY;
        for j in 0..n {
            let y = Self::coord(j);
            for i in 0..n {
                let x = Self::coord(i);
                let rho2 = x * x + y * y;
                if rho2 >= r2 {
                    continue;
                }
                if let Some(o) = object(x, y) {
                    let g = o - libm::sqrt(r2 - rho2);
                    gap[j * n + i] = g;
                    min_gap = min_gap.min(g);
                }
            }
        }
        let mut p: Vec<f32> = gap
            .iter()
            .map(|&g| (scene.depth_mm - (g - min_gap)).max(0.0) as f32)
            .collect();
        gaussian_blur(&mut p, n, n, GEL_SIGMA_MM / GRID_MM, Border::Zero);
        Self { n, p }
    }

    /// `(p, dp/dx, dp/dy)` at `(x, y)` mm, bilinear, with central differences.
    pub fn sample(&self, x: f64, y: f64) -> (f64, f64, f64) {
        let at = |i: isize, j: isize| -> f64 {
            if i < 0 || j < 0 || i as usize >= self.n || j as usize >= self.n {
                0.0
            } else {
                self.p[j as usize * self.n + i as usize] as f64
            }
        };
        let fx = (x + GRID_HALF_MM) / GRID_MM;
        let fy = (y + GRID_HALF_MM) / GRID_MM;
        let (i0, j0) = (fx.floor() as isize, fy.floor() as isize);
        let (tx, ty) = (fx - i0 as f64, fy - j0 as f64);
        let bilinear = |f: &dyn Fn(isize, isize) -> f64| {
            let a = f(i0, j0) * (1.0 - tx) + f(i0 + 1, j0) * tx;
            let b = f(i0, j0 + 1) * (1.0 - tx) + f(i0 + 1, j0 + 1) * tx;
            a * (1.0 - ty) + b * ty
        };
        let p = bilinear(&|i, j| at(i, j));
        let gx = bilinear(&|i, j| (at(i + 1, j) - at(i - 1, j)) / (2.0 * GRID_MM));
        let gy = bilinear(&|i, j| (at(i, j + 1) - at(i, j - 1)) / (2.0 * GRID_MM));
        (p, gx, gy)
    }

    /// `integral(p) dA`, mm^3.
    pub fn volume_mm3(&self) -> f64 {
        self.p.iter().map(|&v| v as f64).sum::<f64>() * GRID_MM * GRID_MM
    }
}

/// Rest positions of the 127 pins in the tip frame (mm, planar `x, y`),
/// centre pin first, then ring by ring, counter-clockwise from `+x`.
pub fn pin_rest_positions_mm() -> Vec<(f64, f64)> {
    let mut pins: Vec<(i32, f64, f64)> = Vec::new();
    let h = 3f64.sqrt() / 2.0;
    for i in -PIN_RINGS..=PIN_RINGS {
        for j in -PIN_RINGS..=PIN_RINGS {
            let ring = i.abs().max(j.abs()).max((i + j).abs());
            if ring > PIN_RINGS {
                continue;
            }
            // Lattice point along the surface, then onto the hemisphere.
            let (lx, ly) = (
                (i as f64 + 0.5 * j as f64) * PIN_SPACING_MM,
                h * j as f64 * PIN_SPACING_MM,
            );
            let s = libm::sqrt(lx * lx + ly * ly);
            let rho = TIP_RADIUS_MM * libm::sin(s / TIP_RADIUS_MM);
            let (x, y) = if s > 0.0 {
                (lx * rho / s, ly * rho / s)
            } else {
                (0.0, 0.0)
            };
            pins.push((ring, x, y));
        }
    }
    let angle = |x: f64, y: f64| {
        let a = libm::atan2(y, x);
        if a < -1e-9 {
            a + 2.0 * std::f64::consts::PI
        } else {
            a.max(0.0)
        }
    };
    pins.sort_by(|a, b| {
        a.0.cmp(&b.0)
            .then(angle(a.1, a.2).total_cmp(&angle(b.1, b.2)))
    });
    pins.into_iter().map(|(_, x, y)| (x, y)).collect()
}

/// Tip-frame mm to pixel coordinates.
pub fn mm_to_px(x: f64, y: f64) -> (f64, f64) {
    (CENTRE_PX + x * PX_PER_MM, CENTRE_PX + y * PX_PER_MM)
}

/// A pin as the camera sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pin {
    /// Column, pixels.
    pub u: f64,
    /// Row, pixels.
    pub v: f64,
    /// Disc radius, pixels.
    pub radius_px: f64,
}

/// A rendered frame with its labels.
pub struct TactipFrame {
    /// 300 x 300 grey pixels, row-major.
    pub pixels: Vec<u8>,
    /// Pins after contact, in [`pin_rest_positions_mm`] order.
    pub pins: Vec<Pin>,
    /// `force_n` without the load-cell noise.
    pub force_clean_n: f64,
    /// The label (with noise).
    pub force_n: f64,
}

/// Pins after contact with `field`.
pub fn deform_pins(field: &PenetrationField) -> Vec<Pin> {
    pin_rest_positions_mm()
        .into_iter()
        .map(|(x, y)| {
            let (p, gx, gy) = field.sample(x, y);
            let (u, v) = mm_to_px(x - PIN_ALPHA_MM * gx, y - PIN_ALPHA_MM * gy);
            Pin {
                u,
                v,
                radius_px: PIN_RADIUS_MM * PX_PER_MM * (1.0 + PIN_GROWTH_PER_MM * p),
            }
        })
        .collect()
}

/// Render one frame and its force label; `rng` supplies the sensor noise.
pub fn render(scene: &TactipScene, rng: &mut SampleRng) -> TactipFrame {
    let field = PenetrationField::new(scene);
    let force_clean_n = FORCE_N_PER_MM3 * field.volume_mm3();
    let force_n = force_clean_n * (1.0 + scene.force_noise * scene.force_noise_draw);
    let pins = deform_pins(&field);

    // Scene radiance: pin coverage (1-pixel antialiased edge) over background.
    let n = FRAME_PX;
    let mut cover = vec![0.0f32; n * n];
    for pin in &pins {
        let r = pin.radius_px + 1.0;
        let (u0, u1) = (
            (pin.u - r).floor().max(0.0) as usize,
            ((pin.u + r).ceil() as usize).min(n - 1),
        );
        let (v0, v1) = (
            (pin.v - r).floor().max(0.0) as usize,
            ((pin.v + r).ceil() as usize).min(n - 1),
        );
        for v in v0..=v1 {
            for u in u0..=u1 {
                let d = libm::hypot(u as f64 - pin.u, v as f64 - pin.v);
                let c = (pin.radius_px + 0.5 - d).clamp(0.0, 1.0) as f32;
                let cell = &mut cover[v * n + u];
                *cell = cell.max(c);
            }
        }
    }
    let (bg, fg) = (scene.background_grey as f32, scene.pin_grey as f32);
    let mut img: Vec<f32> = Vec::with_capacity(n * n);
    for v in 0..n {
        let vp = (v as f64 - CENTRE_PX) / CENTRE_PX;
        for u in 0..n {
            let up = (u as f64 - CENTRE_PX) / CENTRE_PX;
            let gain = scene.gain
                * (1.0 + scene.gradient_u * up + scene.gradient_v * vp)
                * (1.0 - VIGNETTE * (up * up + vp * vp));
            let mut val = (bg + (fg - bg) * cover[v * n + u]) as f64 * gain;
            if let Some(b) = scene.blob {
                let d2 = (u as f64 - b.u).powi(2) + (v as f64 - b.v).powi(2);
                val += b.amplitude * libm::exp(-d2 / (2.0 * b.sigma_px * b.sigma_px));
            }
            img.push(val as f32);
        }
    }
    gaussian_blur(&mut img, n, n, OPTICAL_BLUR_PX, Border::Clamp);
    let pixels = img
        .iter()
        .map(|&v| to_u8(v + (scene.noise_sigma * rng.normal()) as f32))
        .collect();
    TactipFrame {
        pixels,
        pins,
        force_clean_n,
        force_n,
    }
}

/// One sample of a dataset: its scene and frame.
pub fn sample(config: &TactipConfig, seed: u64, index: u64) -> (TactipScene, TactipFrame) {
    let mut rng = SampleRng::new(seed, 0, index);
    let scene = TactipScene::draw(config, &mut rng);
    let frame = render(&scene, &mut rng);
    (scene, frame)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_has_127_pins_inside_the_frame() {
        let pins = pin_rest_positions_mm();
        assert_eq!(pins.len(), 127);
        assert_eq!(pins[0], (0.0, 0.0));
        let far = pins
            .iter()
            .map(|&(x, y)| libm::hypot(x, y))
            .fold(0.0, f64::max);
        // Outer ring: s = 15.6 mm on the surface, R sin(s/R) from the axis.
        assert!((far - 20.0 * (15.6f64 / 20.0).sin()).abs() < 1e-9, "{far}");
        assert!(far * PX_PER_MM < CENTRE_PX);
    }

    #[test]
    fn nothing_moves_without_depth() {
        let field = PenetrationField::new(&TactipScene::clean(Shape::Flat, 0.0, 0.0, 0.0, 0.0));
        assert!(field.volume_mm3() < 1e-9);
    }
}
