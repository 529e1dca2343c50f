//! The virtual visuo-tactile palpation sensor of `sensors.md` section 2
//! (version 1): a GelSight-like photometric rendering of a skin pressed into
//! a phantom with a buried tendon, with exact mask, direction and depth.
//!
//! A dataset is a set of palpation videos (sequences). Each sequence fixes
//! the phantom (tendon path, radius, burial, position, orientation) and a
//! peak press; `press` ramps in from below contact, holds, and ramps out,
//! so the detector sees onsets and releases. Choices the spec leaves open
//! are listed in `docs/synth.md`.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};
use tactile_core::spec::visuotactile as spec;
use tactile_core::{Error, Result};

use crate::raster::{Border, gaussian_blur, to_u8};
use crate::rng::{Range, SampleRng};

/// The native frame of the sensor.
pub const NATIVE: (u32, u32) = (1920, 1080);
/// Longest palpation video, frames.
pub const MAX_FRAMES_PER_SEQUENCE: usize = 100_000;
/// Frames per second of a palpation video.
pub const FPS: f64 = 30.0;
/// Nominal skin depth used for the tendon geometry, mm.
pub const NOMINAL_DEPTH_MM: f64 = 15.0;
pub use tactile_core::spec::visuotactile::{DOME_BASE_MM, DOME_RISE_MM, TENDON_MIN_AMPLITUDE_MM};
/// Whole-window displacement per mm of press at the centre.
pub const WINDOW_PUSH: f64 = 0.4;
/// Ridge amplitude factor: `A = 0.35 press radius / (radius + burial)`.
pub const RIDGE_GAIN: f64 = 0.35;
/// Ridge width: `w = 0.6 radius + 0.3 burial`.
pub const RIDGE_WIDTH: (f64, f64) = (0.6, 0.3);
/// Mask threshold: ridge above `max(0.3 A, 0.02 mm)`.
pub const MASK_FRACTION: f64 = 0.3;
/// Smallest ridge height in the mask, mm.
pub const MASK_FLOOR_MM: f64 = 0.02;
/// Skin albedo and ambient term.
pub const ALBEDO: f64 = 0.8;
/// Ambient light term.
pub const AMBIENT: f64 = 0.25;
/// Light elevation and azimuths (red, green, blue), degrees.
pub const LIGHT_ELEVATION_DEG: f64 = 30.0;
/// Light azimuths (red, green, blue), degrees.
pub const LIGHT_AZIMUTH_DEG: [f64; 3] = [90.0, 210.0, 330.0];
/// Housing colour, 8-bit RGB.
pub const HOUSING_RGB: [f64; 3] = [10.0, 10.0, 12.0];
/// LED glare: sigma as a fraction of the width, amplitude, position on the
/// window ellipse (fraction of its radii, direction in degrees).
pub const GLARE_SIGMA_FRACTION: f64 = 0.03;
/// LED glare amplitude, in [0, 1] channel units.
pub const GLARE_AMPLITUDE: f64 = 0.6;
/// LED glare position: fraction of the window ellipse's radii.
pub const GLARE_RADIUS_FRACTION: f64 = 0.92;
/// LED glare position: direction from the centre, degrees.
pub const GLARE_DIRECTION_DEG: f64 = -45.0;
/// Optical blur, pixels.
pub const BLUR_PX: f64 = 1.0;
/// How far past its last arc a curved tendon's straight continuation runs, mm.
const RAY_MM: f64 = 1000.0;

/// The tendon centre-line families.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum TendonPath {
    /// A straight line.
    #[serde(rename = "straight")]
    Straight,
    /// A circular arc.
    #[serde(rename = "arc")]
    Arc,
    /// Two opposite arcs.
    #[serde(rename = "s-curve")]
    SCurve,
}

impl TendonPath {
    /// Every path.
    pub const ALL: [TendonPath; 3] = [TendonPath::Straight, TendonPath::Arc, TendonPath::SCurve];

    /// The label's name.
    pub fn name(self) -> &'static str {
        match self {
            TendonPath::Straight => "straight",
            TendonPath::Arc => "arc",
            TendonPath::SCurve => "s-curve",
        }
    }
}

impl std::str::FromStr for TendonPath {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        TendonPath::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| {
                Error::Config(format!(
                    "paths: unknown tendon path '{s}' (known: straight, arc, s-curve)"
                ))
            })
    }
}

/// The per-sample ranges of the virtual visuo-tactile sensor (defaults:
/// the spec's training distribution at 640 x 360).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct VisuotactileConfig {
    /// Rendered size: an exact integer fraction of 1920 x 1080.
    pub width: u32,
    /// Rendered height.
    pub height: u32,
    /// Tendon paths drawn uniformly.
    pub paths: Vec<TendonPath>,
    /// Tendon radius, mm.
    pub tendon_radius_mm: Range,
    /// Depth of the tendon under the phantom's surface, mm.
    pub burial_mm: Range,
    /// Radius of curvature of `arc` and `s-curve` paths.
    pub curvature_radius_mm: Range,
    /// Peak press of a sequence, mm past first touch.
    pub press_mm: Range,
    /// The centre line passes within this fraction of the half-width of the frame centre.
    pub centre_fraction: f64,
    /// Fraction of sequences whose tendon lies outside the window.
    pub out_of_view_fraction: f64,
    /// Exposure factor `1 + e`, `e` drawn per frame from this range.
    pub exposure_jitter: Range,
    /// Sensor noise, 8-bit levels.
    pub noise_sigma: Range,
    /// Frames per palpation video.
    pub frames_per_sequence: usize,
    /// Which renderer draws the frames (the labels are the same). Left out
    /// of a reference dataset's manifest, which thus stays byte-identical.
    #[serde(skip_serializing_if = "Renderer::is_reference")]
    pub renderer: Renderer,
}

/// The renderers of the sensor.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Renderer {
    /// One analytic sample per pixel ([`render`]); what models train on.
    #[default]
    Reference,
    /// Another raster and shading path of the same spec
    /// ([`crate::alternate::render_alternate`]): a cross-check set.
    Alternate,
}

impl Renderer {
    /// True for [`Renderer::Reference`].
    pub fn is_reference(&self) -> bool {
        *self == Self::Reference
    }
}

impl std::str::FromStr for Renderer {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "reference" => Ok(Self::Reference),
            "alternate" => Ok(Self::Alternate),
            _ => Err(Error::Config(format!(
                "renderer: unknown '{s}' (known: reference, alternate)"
            ))),
        }
    }
}

impl Default for VisuotactileConfig {
    fn default() -> Self {
        Self {
            width: 640,
            height: 360,
            paths: TendonPath::ALL.to_vec(),
            tendon_radius_mm: Range::new(1.5, 4.0),
            burial_mm: Range::new(1.0, 4.0),
            curvature_radius_mm: Range::new(15.0, 60.0),
            press_mm: Range::new(0.0, 4.0),
            centre_fraction: 0.3,
            out_of_view_fraction: 0.15,
            exposure_jitter: Range::new(-0.1, 0.1),
            noise_sigma: Range::new(1.0, 3.0),
            frames_per_sequence: 30,
            renderer: Renderer::Reference,
        }
    }
}

impl VisuotactileConfig {
    /// Check every value; the message names the offending key.
    pub fn validate(&self) -> Result<()> {
        let (nw, nh) = NATIVE;
        let ok = self.width > 0
            && self.height > 0
            && nw % self.width == 0
            && nh % self.height == 0
            && nw / self.width == nh / self.height;
        if !ok {
            return Err(Error::Config(format!(
                "width/height: {}x{} is not an exact integer fraction of the native {nw}x{nh} \
                 (e.g. 1920x1080, 960x540, 640x360, 480x270, 320x180)",
                self.width, self.height
            )));
        }
        if self.paths.is_empty() {
            return Err(Error::Config(
                "paths: at least one tendon path is needed".into(),
            ));
        }
        self.tendon_radius_mm.check("tendon_radius_mm", 0.1, 20.0)?;
        self.burial_mm.check("burial_mm", 0.0, 20.0)?;
        self.curvature_radius_mm
            .check("curvature_radius_mm", 1.0, 1000.0)?;
        self.press_mm.check("press_mm", 0.0, 10.0)?;
        Range::fixed(self.centre_fraction).check("centre_fraction", 0.0, 1.0)?;
        Range::fixed(self.out_of_view_fraction).check("out_of_view_fraction", 0.0, 1.0)?;
        self.exposure_jitter.check("exposure_jitter", -0.9, 0.9)?;
        self.noise_sigma.check("noise_sigma", 0.0, 100.0)?;
        if self.frames_per_sequence == 0 || self.frames_per_sequence > MAX_FRAMES_PER_SEQUENCE {
            return Err(Error::Config(format!(
                "frames_per_sequence: must be 1 to {MAX_FRAMES_PER_SEQUENCE}"
            )));
        }
        Ok(())
    }

    /// Frames to write from `--count` and/or `--sequences` (whole
    /// palpation videos of `frames_per_sequence`): either, or both when
    /// they agree.
    pub fn frame_count(&self, count: Option<usize>, sequences: Option<usize>) -> Result<usize> {
        let f = self.frames_per_sequence;
        let frames = |k: usize| {
            k.checked_mul(f).ok_or_else(|| {
                Error::Config(format!("{k} sequences x {f} frames is too many frames"))
            })
        };
        match (count, sequences) {
            (Some(c), None) => Ok(c),
            (None, Some(k)) => frames(k),
            (Some(c), Some(k)) if c == frames(k)? => Ok(c),
            (Some(c), Some(k)) => Err(Error::Config(format!(
                "count {c} disagrees with {k} sequences x {f} frames per sequence"
            ))),
            (None, None) => Err(Error::Config(
                "give a frame count or a number of sequences".into(),
            )),
        }
    }

    /// The scale divisor from the native frame (3 for 640 x 360).
    pub fn scale_divisor(&self) -> u32 {
        NATIVE.0 / self.width.max(1)
    }
}

/// The camera of a frame size: pinhole, 90-degree horizontal field of view.
#[derive(Debug, Clone, Copy)]
pub struct Camera {
    /// Frame width, pixels.
    pub width: usize,
    /// Frame height, pixels.
    pub height: usize,
    /// Focal length, pixels (`width / 2`).
    pub fx: f64,
    /// Principal point, column.
    pub cx: f64,
    /// Principal point, row.
    pub cy: f64,
    /// Half-diagonal of the frame, pixels.
    pub r_max: f64,
}

impl Camera {
    /// The camera of a `width x height` frame.
    pub fn new(width: u32, height: u32) -> Self {
        let (w, h) = (width as f64, height as f64);
        Self {
            width: width as usize,
            height: height as usize,
            fx: w / 2.0,
            cx: (w - 1.0) / 2.0,
            cy: (h - 1.0) / 2.0,
            r_max: libm::hypot(w, h) / 2.0,
        }
    }

    /// Skin-plane mm at nominal depth of pixel `(u, v)`.
    pub fn to_mm(&self, u: f64, v: f64) -> (f64, f64) {
        let k = NOMINAL_DEPTH_MM / self.fx;
        ((u - self.cx) * k, (v - self.cy) * k)
    }

    /// Pixel of skin-plane mm.
    pub fn to_px(&self, x: f64, y: f64) -> (f64, f64) {
        let k = self.fx / NOMINAL_DEPTH_MM;
        (self.cx + x * k, self.cy + y * k)
    }

    /// Semi-axes of the window ellipse, pixels.
    pub fn window_radii(&self) -> (f64, f64) {
        (self.width as f64 / 2.0, self.height as f64 / 2.0)
    }

    /// Centre of the LED glare, pixels: on the window's rim ellipse
    /// ([`GLARE_RADIUS_FRACTION`] of the way out) at [`GLARE_DIRECTION_DEG`].
    pub fn glare_centre(&self) -> (f64, f64) {
        let (a, b) = self.window_radii();
        let angle = GLARE_DIRECTION_DEG.to_radians();
        (
            self.cx + GLARE_RADIUS_FRACTION * a * libm::cos(angle),
            self.cy + GLARE_RADIUS_FRACTION * b * libm::sin(angle),
        )
    }

    /// True inside the sensing window (the inscribed ellipse).
    pub fn in_window(&self, u: f64, v: f64) -> bool {
        spec::Window::of_frame(self.width as f64, self.height as f64).contains(u, v)
    }

    /// Rest depth `d0` at pixel `(u, v)`, mm.
    pub fn rest_depth_mm(&self, u: f64, v: f64) -> f64 {
        let r2 = (u - self.cx).powi(2) + (v - self.cy).powi(2);
        spec::rest_depth_mm(r2 / (self.r_max * self.r_max))
    }
}

type P2 = (f64, f64);

fn sub(a: P2, b: P2) -> P2 {
    (a.0 - b.0, a.1 - b.1)
}
fn add(a: P2, b: P2) -> P2 {
    (a.0 + b.0, a.1 + b.1)
}
fn scale(a: P2, k: f64) -> P2 {
    (a.0 * k, a.1 * k)
}
fn dot(a: P2, b: P2) -> f64 {
    a.0 * b.0 + a.1 * b.1
}
fn perp(a: P2) -> P2 {
    (-a.1, a.0)
}
fn unit_at(angle: f64) -> P2 {
    (libm::cos(angle), libm::sin(angle))
}

/// One piece of a centre line.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Piece {
    /// From `start` along unit `dir` for `length` mm.
    Segment { start: P2, dir: P2, length: f64 },
    /// Circle arc about `centre`: angles `start_angle` .. `start_angle + sweep`.
    Arc {
        centre: P2,
        radius: f64,
        start_angle: f64,
        sweep: f64,
    },
}

impl Piece {
    fn nearest(&self, p: P2) -> P2 {
        match *self {
            Piece::Segment { start, dir, length } => {
                let t = dot(sub(p, start), dir).clamp(0.0, length);
                add(start, scale(dir, t))
            }
            Piece::Arc {
                centre,
                radius,
                start_angle,
                sweep,
            } => {
                let d = sub(p, centre);
                let a = libm::atan2(d.1, d.0);
                let rel = (sweep.signum() * (a - start_angle)).rem_euclid(2.0 * PI);
                if rel <= sweep.abs() {
                    add(centre, scale(unit_at(a), radius))
                } else {
                    let s = add(centre, scale(unit_at(start_angle), radius));
                    let e = add(centre, scale(unit_at(start_angle + sweep), radius));
                    let ds = dot(sub(p, s), sub(p, s));
                    let de = dot(sub(p, e), sub(p, e));
                    if ds <= de { s } else { e }
                }
            }
        }
    }
}

/// A tendon centre line in skin-plane mm (x right, y down).
#[derive(Debug, Clone, PartialEq)]
pub struct CentreLine {
    pieces: Vec<Piece>,
    /// The point nearest the frame centre and the unit tangent there.
    pub anchor: P2,
    /// The unit tangent there.
    pub tangent: P2,
}

impl CentreLine {
    /// A straight line through `anchor` along `tangent`.
    pub fn straight(anchor: P2, tangent: P2) -> Self {
        Self {
            pieces: vec![Piece::Segment {
                start: sub(anchor, scale(tangent, RAY_MM)),
                dir: tangent,
                length: 2.0 * RAY_MM,
            }],
            anchor,
            tangent,
        }
    }

    /// Arcs of radius `radius` on both sides of `anchor`, each turning
    /// through `half_angle`, then straight on. `bend` is +1/-1 (which side
    /// the forward half curves to); `s_curve` makes the backward half curve
    /// the other way.
    pub fn curved(
        anchor: P2,
        tangent: P2,
        radius: f64,
        half_angle: f64,
        bend: f64,
        s_curve: bool,
    ) -> Self {
        let mut pieces = Vec::new();
        // Forward half along +tangent, backward half along -tangent. For one
        // circle the backward half (walking -tangent) bends the other way.
        let halves = [
            (tangent, bend),
            (scale(tangent, -1.0), if s_curve { bend } else { -bend }),
        ];
        for (dir, sign) in halves {
            let centre = add(anchor, scale(perp(dir), sign * radius));
            let d = sub(anchor, centre);
            let start_angle = libm::atan2(d.1, d.0);
            let sweep = sign * half_angle;
            let end_angle = start_angle + sweep;
            let end = add(centre, scale(unit_at(end_angle), radius));
            let end_dir = scale((-libm::sin(end_angle), libm::cos(end_angle)), sign);
            pieces.push(Piece::Arc {
                centre,
                radius,
                start_angle,
                sweep,
            });
            pieces.push(Piece::Segment {
                start: end,
                dir: end_dir,
                length: RAY_MM,
            });
        }
        Self {
            pieces,
            anchor,
            tangent,
        }
    }

    /// The nearest point of the line to `p`.
    pub fn nearest(&self, p: P2) -> P2 {
        let mut best = self.anchor;
        let mut best_d = f64::INFINITY;
        for piece in &self.pieces {
            let q = piece.nearest(p);
            let d = dot(sub(p, q), sub(p, q));
            if d < best_d {
                best_d = d;
                best = q;
            }
        }
        best
    }

    /// Image direction of the line at its anchor, degrees in `[0, 180)`.
    pub fn direction_deg(&self) -> f64 {
        fold_180(libm::atan2(self.tangent.1, self.tangent.0).to_degrees())
    }
}

/// Fold an angle in degrees into `[0, 180)`.
pub fn fold_180(deg: f64) -> f64 {
    let f = deg.rem_euclid(180.0);
    if f >= 180.0 { 0.0 } else { f }
}

/// The phantom and palpation of one video.
#[derive(Debug, Clone, PartialEq)]
pub struct SequenceScene {
    /// The centre line's family.
    pub path: TendonPath,
    /// Tendon radius, mm.
    pub tendon_radius_mm: f64,
    /// Burial depth, mm.
    pub burial_mm: f64,
    /// Radius of curvature of curved paths, mm.
    pub curvature_radius_mm: f64,
    /// The centre line.
    pub line: CentreLine,
    /// False when the centre line stays outside the window.
    pub in_view: bool,
    /// Peak press of the video, mm.
    pub peak_press_mm: f64,
}

impl SequenceScene {
    /// Ridge width `w`, mm.
    pub fn ridge_width_mm(&self) -> f64 {
        RIDGE_WIDTH.0 * self.tendon_radius_mm + RIDGE_WIDTH.1 * self.burial_mm
    }

    /// Ridge amplitude `A` at `press`, mm.
    pub fn ridge_amplitude_mm(&self, press_mm: f64) -> f64 {
        if press_mm <= 0.0 {
            0.0
        } else {
            RIDGE_GAIN * press_mm * self.tendon_radius_mm / (self.tendon_radius_mm + self.burial_mm)
        }
    }

    /// Draw the phantom of a sequence. The draw order is fixed.
    pub fn draw(config: &VisuotactileConfig, camera: &Camera, rng: &mut SampleRng) -> Self {
        let path = config.paths[rng.index(config.paths.len())];
        let tendon_radius_mm = rng.draw(config.tendon_radius_mm);
        let burial_mm = rng.draw(config.burial_mm);
        let curvature_radius_mm = rng.draw(config.curvature_radius_mm);
        let peak_press_mm = rng.draw(config.press_mm);
        let in_view = !rng.chance(config.out_of_view_fraction);
        let psi = rng.uniform() * 2.0 * PI;
        let radial = unit_at(psi);
        let forward = rng.chance(0.5);
        let bend = if rng.chance(0.5) { 1.0 } else { -1.0 };
        let offset_u = rng.uniform();
        let margin_u = rng.uniform();
        let half_width_mm = camera
            .to_mm(camera.cx + camera.width as f64 / 2.0, camera.cy)
            .0;
        let half_diag_mm = camera.r_max * NOMINAL_DEPTH_MM / camera.fx;
        // The tangent at the anchor is perpendicular to the radial direction,
        // so the anchor is the line's point nearest the frame centre.
        let tangent = if forward {
            perp(radial)
        } else {
            scale(perp(radial), -1.0)
        };
        let w = RIDGE_WIDTH.0 * tendon_radius_mm + RIDGE_WIDTH.1 * burial_mm;
        let (line, path) = if in_view {
            let anchor = scale(radial, offset_u * config.centre_fraction * half_width_mm);
            let half_angle = (half_diag_mm / curvature_radius_mm).min(PI / 2.0);
            let line = match path {
                TendonPath::Straight => CentreLine::straight(anchor, tangent),
                TendonPath::Arc => CentreLine::curved(
                    anchor,
                    tangent,
                    curvature_radius_mm,
                    half_angle,
                    bend,
                    false,
                ),
                TendonPath::SCurve => {
                    CentreLine::curved(anchor, tangent, curvature_radius_mm, half_angle, bend, true)
                }
            };
            (line, path)
        } else {
            // A straight tendon beyond the window: its mask-level ridge
            // (|s| < 1.56 w) never reaches the ellipse.
            let (a, b) = camera.window_radii();
            let k = NOMINAL_DEPTH_MM / camera.fx;
            let support = libm::hypot(a * k * radial.0, b * k * radial.1);
            let anchor = scale(radial, support + (1.6 + 2.0 * margin_u) * w);
            (CentreLine::straight(anchor, tangent), TendonPath::Straight)
        };
        Self {
            path,
            tendon_radius_mm,
            burial_mm,
            curvature_radius_mm,
            line,
            in_view,
            peak_press_mm,
        }
    }
}

/// `press` at frame `index` of `frames`: from a quarter of the peak below
/// first touch up to the peak (40 % of the video), hold (20 %), and back.
pub fn press_profile(peak_mm: f64, index: usize, frames: usize) -> f64 {
    if frames <= 1 {
        return peak_mm;
    }
    let t = index as f64 / (frames - 1) as f64;
    let ramp = |s: f64| -0.25 + 1.25 * (s / 0.4).min(1.0);
    peak_mm * ramp(t.min(1.0 - t))
}

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
    let exposure = 1.0 + rng.draw(config.exposure_jitter);
    let noise_sigma = rng.draw(config.noise_sigma);
    let lights = light_vectors();
    // One analytic sample per pixel.
    let mut raster = Raster::new(&cam, scene, press_mm, |_, _, at| {
        shade(-at.gx, -at.gy, &lights)
    });

    // Camera: exposure, LED glare, optical blur, noise, 8 bits.
    let (gu, gv) = cam.glare_centre();
    let g_sigma = GLARE_SIGMA_FRACTION * w as f64;
    let glare: Vec<f32> = (0..w * h)
        .map(|i| {
            let (u, v) = ((i % w) as f64, (i / w) as f64);
            let d2 = (u - gu).powi(2) + (v - gv).powi(2);
            (GLARE_AMPLITUDE * libm::exp(-d2 / (2.0 * g_sigma * g_sigma))) as f32
        })
        .collect();
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

/// Frame `frame` of sequence `sequence` of a dataset.
pub fn sample(
    config: &VisuotactileConfig,
    seed: u64,
    sequence: u64,
    frame: usize,
) -> (SequenceScene, VisuotactileFrame) {
    let cam = Camera::new(config.width, config.height);
    let scene = SequenceScene::draw(config, &cam, &mut SampleRng::new(seed, 1, sequence));
    let press = press_profile(scene.peak_press_mm, frame, config.frames_per_sequence);
    let mut rng = SampleRng::new(seed, 2 + sequence, frame as u64);
    let out = match config.renderer {
        Renderer::Reference => render(config, &scene, press, &mut rng),
        Renderer::Alternate => {
            let mut glare = SampleRng::new(seed, u64::MAX, sequence);
            crate::alternate::render_alternate(config, &scene, press, &mut rng, &mut glare)
        }
    };
    (scene, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_follows_the_spec() {
        let c = Camera::new(640, 360);
        assert_eq!(c.fx, 320.0);
        assert!((c.to_mm(c.cx + 320.0, c.cy).0 - 15.0).abs() < 1e-12);
        assert_eq!(c.rest_depth_mm(c.cx, c.cy), 15.0);
        assert!(c.rest_depth_mm(0.0, 0.0) <= 18.0);
    }

    #[test]
    fn centre_lines_have_their_anchor_nearest_the_centre() {
        for (bend, s) in [(1.0, false), (-1.0, false), (1.0, true), (-1.0, true)] {
            let psi: f64 = 0.7;
            let anchor = scale(unit_at(psi), 3.0);
            let line = CentreLine::curved(anchor, perp(unit_at(psi)), 15.0, 1.1, bend, s);
            // Nearest points of a grid of probes cover the line near the window.
            let mut closest = f64::INFINITY;
            for i in -100..=100 {
                for j in -100..=100 {
                    let q = line.nearest((i as f64 * 0.2, j as f64 * 0.2));
                    closest = closest.min(libm::hypot(q.0, q.1));
                }
            }
            assert!((closest - 3.0).abs() < 1e-3, "{closest}");
        }
    }

    #[test]
    fn press_ramps_in_and_out() {
        assert!(press_profile(2.0, 0, 30) < 0.0);
        assert_eq!(press_profile(2.0, 15, 30), 2.0);
        assert!(press_profile(2.0, 29, 30) < 0.0);
        assert_eq!(press_profile(2.0, 0, 1), 2.0);
    }
}
