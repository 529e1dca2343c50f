//! The virtual visuo-tactile palpation sensor of `sensors.md` section 2
//! (version 1): a GelSight-like photometric rendering of a skin pressed into
//! a phantom with a buried tendon, with exact mask, direction and depth.
//!
//! A dataset is a set of palpation videos (sequences). Each sequence fixes
//! the phantom (tendon path, radius, burial, position, orientation) and a
//! peak press; `press` ramps in from below contact, holds, and ramps out,
//! so the detector sees onsets and releases. Choices the spec leaves open
//! are listed in `docs/synth.md`.

mod alternate;
mod bound;
pub(crate) mod camera;
mod render;
mod scene;

use serde::{Deserialize, Serialize};
use tactile_core::{Error, Result};

use crate::rng::{Range, SampleRng};

pub use alternate::render_alternate;
pub use bound::{
    DatasetFrameBound, FrameBound, IdealSummary, dataset_bounds, frame_bound, summarise,
    write_bounds_csv,
};
pub use camera::Camera;
pub use render::{Surface, VisuotactileFrame, render, surface};
pub use scene::{CentreLine, SequenceScene, fold_180, press_profile};

/// The native frame of the sensor.
pub const NATIVE: (u32, u32) = (1920, 1080);
/// Longest palpation video, frames.
pub const MAX_FRAMES_PER_SEQUENCE: usize = 100_000;
/// Frames per second of a palpation video.
pub const FPS: f64 = 30.0;
/// The sensor contract a dataset's manifest names (`sensor_spec`).
pub const SENSOR_SPEC: &str = "virtual-visuotactile/1";
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

impl std::fmt::Display for TendonPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default, deny_unknown_fields)]
pub struct VisuotactileConfig {
    /// Rendered size: an exact integer fraction of 1920 x 1080.
    #[arg(long, default_value_t = VisuotactileConfig::default().width)]
    pub width: u32,
    /// Rendered height.
    #[arg(long, default_value_t = VisuotactileConfig::default().height)]
    pub height: u32,
    /// Tendon paths drawn uniformly.
    #[arg(long, value_delimiter = ',', default_values_t = VisuotactileConfig::default().paths)]
    pub paths: Vec<TendonPath>,
    /// Tendon radius, mm.
    #[arg(long, default_value_t = VisuotactileConfig::default().tendon_radius_mm)]
    pub tendon_radius_mm: Range,
    /// Depth of the tendon under the phantom's surface, mm.
    #[arg(long, default_value_t = VisuotactileConfig::default().burial_mm)]
    pub burial_mm: Range,
    /// Radius of curvature of `arc` and `s-curve` paths.
    #[arg(long, default_value_t = VisuotactileConfig::default().curvature_radius_mm)]
    pub curvature_radius_mm: Range,
    /// Peak press of a sequence, mm past first touch.
    #[arg(long, default_value_t = VisuotactileConfig::default().press_mm)]
    pub press_mm: Range,
    /// The centre line passes within this fraction of the half-width of the frame centre.
    #[arg(long, default_value_t = VisuotactileConfig::default().centre_fraction)]
    pub centre_fraction: f64,
    /// Fraction of sequences whose tendon lies outside the window.
    #[arg(long, default_value_t = VisuotactileConfig::default().out_of_view_fraction)]
    pub out_of_view_fraction: f64,
    /// How far an out-of-view tendon's centre line lies outside the window,
    /// in ridge widths `w`. Below 1.56 its ridge reaches over the rim above
    /// the mask's threshold, and the spec's labels make the frame a tendon
    /// (the default keeps out-of-view frames negatives). Left out of the
    /// manifest at its default, which thus stays byte-identical.
    #[serde(skip_serializing_if = "is_default_margin")]
    #[arg(long, default_value_t = VisuotactileConfig::default().out_of_view_margin_w)]
    pub out_of_view_margin_w: Range,
    /// Exposure factor `1 + e`, `e` drawn per frame from this range.
    #[arg(long, default_value_t = VisuotactileConfig::default().exposure_jitter)]
    pub exposure_jitter: Range,
    /// Sensor noise, 8-bit levels.
    #[arg(long, default_value_t = VisuotactileConfig::default().noise_sigma)]
    pub noise_sigma: Range,
    /// Frames per palpation video.
    #[arg(long, default_value_t = VisuotactileConfig::default().frames_per_sequence)]
    pub frames_per_sequence: usize,
    /// Which renderer draws the frames (the labels are the same). Left out
    /// of a reference dataset's manifest, which thus stays byte-identical.
    #[serde(skip_serializing_if = "Renderer::is_reference")]
    #[arg(long, default_value_t = VisuotactileConfig::default().renderer)]
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
    /// ([`alternate::render_alternate`]): a cross-check set.
    Alternate,
}

impl Renderer {
    /// True for [`Renderer::Reference`].
    pub fn is_reference(&self) -> bool {
        *self == Self::Reference
    }
}

impl std::fmt::Display for Renderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Reference => "reference",
            Self::Alternate => "alternate",
        })
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

/// Out-of-view centre lines 1.6 to 3.6 ridge widths outside the window:
/// no pixel of it reaches the mask's threshold.
const DEFAULT_MARGIN_W: Range = Range { min: 1.6, max: 3.6 };

fn is_default_margin(r: &Range) -> bool {
    *r == DEFAULT_MARGIN_W
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
            out_of_view_margin_w: DEFAULT_MARGIN_W,
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
        self.out_of_view_margin_w
            .check("out_of_view_margin_w", 0.0, 100.0)?;
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
        frames_of(self.frames_per_sequence, count, sequences)
    }

    /// The scale divisor from the native frame (3 for 640 x 360).
    pub fn scale_divisor(&self) -> u32 {
        NATIVE.0 / self.width.max(1)
    }
}

/// Frames to write from `count` and/or `sequences` videos of `f` frames:
/// either, or both when they agree.
pub(crate) fn frames_of(f: usize, count: Option<usize>, sequences: Option<usize>) -> Result<usize> {
    let frames = |k: usize| {
        k.checked_mul(f)
            .ok_or_else(|| Error::Config(format!("{k} sequences x {f} frames is too many frames")))
    };
    if sequences == Some(0) {
        return Err(Error::Config("sequences: must be at least 1, got 0".into()));
    }
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

/// The camera, the sequence's scene, the press and the random stream of
/// frame `frame` of sequence `sequence`.
pub(crate) fn frame_setup(
    config: &VisuotactileConfig,
    seed: u64,
    sequence: u64,
    frame: usize,
) -> (Camera, SequenceScene, f64, SampleRng) {
    let cam = Camera::new(config.width, config.height);
    let scene = SequenceScene::draw(config, &cam, &mut SampleRng::new(seed, 1, sequence));
    let press = press_profile(scene.peak_press_mm, frame, config.frames_per_sequence);
    (
        cam,
        scene,
        press,
        SampleRng::new(seed, 2 + sequence, frame as u64),
    )
}

/// Frame `frame` of sequence `sequence` of a dataset.
pub fn sample(
    config: &VisuotactileConfig,
    seed: u64,
    sequence: u64,
    frame: usize,
) -> (SequenceScene, VisuotactileFrame) {
    let (_, scene, press, mut rng) = frame_setup(config, seed, sequence, frame);
    let out = match config.renderer {
        Renderer::Reference => render(config, &scene, press, &mut rng),
        Renderer::Alternate => {
            let mut glare = SampleRng::new(seed, u64::MAX, sequence);
            render_alternate(config, &scene, press, &mut rng, &mut glare)
        }
    };
    (scene, out)
}

#[cfg(test)]
mod tests {
    use super::camera::{perp, scale, unit_at};
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
    fn a_frame_count_comes_from_count_or_sequences_and_zero_sequences_is_named() {
        assert_eq!(frames_of(30, None, Some(2)).unwrap(), 60);
        assert_eq!(frames_of(30, Some(60), Some(2)).unwrap(), 60);
        assert!(frames_of(30, Some(61), Some(2)).is_err());
        // Before, zero videos passed here and were refused as "count: ... got 0".
        let e = frames_of(30, None, Some(0)).unwrap_err().to_string();
        assert!(e.contains("sequences: must be at least 1"), "{e}");
        assert!(frames_of(usize::MAX, None, Some(2)).is_err());
    }

    #[test]
    fn press_ramps_in_and_out() {
        assert!(press_profile(2.0, 0, 30) < 0.0);
        assert_eq!(press_profile(2.0, 15, 30), 2.0);
        assert!(press_profile(2.0, 29, 30) < 0.0);
        assert_eq!(press_profile(2.0, 0, 1), 2.0);
    }
}
