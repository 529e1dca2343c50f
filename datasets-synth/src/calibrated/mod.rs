//! A real sensor's own palpation videos, rendered through its calibration:
//! the optics (slope to colour change by place) and the gel's spread
//! around a contact, both fitted to the sensor's ball presses by
//! `tactile calibrate ball` and saved beside its sensor model as
//! [`RENDER_MODEL_FILE`], over the sensor's own background. Tendons
//! (straight and curved cylinders), spheres, punches, plate edges and
//! frames without contact, pressed in and released as in the virtual
//! sensor's videos; the labels are exact: the indentation map, the tendon
//! mask where a tendon pushes the skin in past the contact threshold, the
//! direction and the press.

mod gel;
mod optics;
mod real;
mod render;
mod scene;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tactile_core::image_io::load_rgb;
use tactile_core::{Error, Result};

use crate::rng::{Range, SampleRng};
use crate::visuotactile::{TendonPath, press_profile};

pub use gel::{BallProfile, GelResponse};
pub use optics::{OPTICS_FORMAT, OpticsSample, SensorOptics};
pub use real::{MAX_COPIES, MAX_REAL_FRAMES, RealFrame, RealFrames, RealFramesRecord};
pub use render::{CalibratedFrame, indentation_mm, render};
pub use scene::{CalibratedScene, Contact};

/// The render model's file in a calibration folder.
pub const RENDER_MODEL_FILE: &str = "optics.json";
/// The `path` column of a real frame joined to a rendered set.
pub const REAL_PRESS_PATH: &str = "real-press";
/// The background's file in a calibration folder.
pub const BACKGROUND_FILE: &str = "background.png";
/// Largest render model file read, bytes.
pub const MAX_RENDER_MODEL_BYTES: u64 = 64 << 20;

/// What rendering needs of a calibrated sensor (the file
/// [`RENDER_MODEL_FILE`]).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct RenderModel {
    /// What sensor it is (`sensor.json`'s description).
    pub sensor: String,
    /// Millimetres per pixel.
    pub mm_per_px: f64,
    /// Slope to colour change.
    pub optics: SensorOptics,
    /// The gel's spread around a contact.
    pub gel: GelResponse,
    /// How well the two reproduce the ball presses (provenance).
    #[serde(default)]
    pub fit: serde_json::Value,
}

impl RenderModel {
    /// Check every field.
    pub fn check(&self) -> Result<()> {
        self.optics.check()?;
        self.gel.check()?;
        if !(self.mm_per_px.is_finite() && (1e-4..=1.0).contains(&self.mm_per_px)) {
            return Err(Error::Config(format!(
                "mm_per_px must be 0.0001-1 mm per pixel (as a calibration's sensor.json), got {:?}",
                self.mm_per_px
            )));
        }
        Ok(())
    }
}

/// A calibrated sensor ready to render: its render model and background.
#[derive(Debug, Clone)]
pub struct CalibratedSensor {
    /// Where it was loaded from.
    pub dir: PathBuf,
    /// Optics, gel, scale.
    pub model: RenderModel,
    /// The skin at rest, RGB bytes of the model's frame size.
    pub background: Vec<u8>,
}

impl CalibratedSensor {
    /// Load the calibration folder `dir` (`tactile calibrate ball`'s).
    pub fn load(dir: &Path) -> Result<Self> {
        let file = dir.join(RENDER_MODEL_FILE);
        if !file.is_file() {
            return Err(Error::Config(format!(
                "{}: no render model here: calibrate the sensor with this version (tactile calibrate ball) to write one",
                file.display()
            )));
        }
        let model: RenderModel =
            tactile_core::io::read_json_limited(&file, MAX_RENDER_MODEL_BYTES)?;
        model.check().map_err(|e| match e {
            // Named at the file, said once ("invalid configuration: FILE:
            // optics: bins must be 2-128, got 0").
            Error::Config(why) => Error::Config(format!("{}: {why}", file.display())),
            other => other,
        })?;
        let bg_path = dir.join(BACKGROUND_FILE);
        let bg = load_rgb(&bg_path)?;
        let (w, h) = (model.optics.width, model.optics.height);
        if (bg.width(), bg.height()) != (w, h) {
            return Err(Error::Config(format!(
                "{}: {}x{}, the render model is {w}x{h}",
                bg_path.display(),
                bg.width(),
                bg.height()
            )));
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            background: bg.as_slice().to_vec(),
            model,
        })
    }

    /// Frame width, pixels.
    pub fn width(&self) -> usize {
        self.model.optics.width
    }

    /// Frame height, pixels.
    pub fn height(&self) -> usize {
        self.model.optics.height
    }

    /// Half the frame's size, mm.
    pub fn half_mm(&self) -> (f64, f64) {
        let s = self.model.mm_per_px;
        (
            self.width() as f64 * s / 2.0,
            self.height() as f64 * s / 2.0,
        )
    }
}

/// The ranges of a calibrated sensor's palpation videos (defaults: tendons
/// of 1.5-3.5 mm pressed 0.05-1.5 mm at any angle and offset, with
/// spheres, punches, plate edges and no contact as negatives).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default, deny_unknown_fields)]
pub struct CalibratedConfig {
    /// Tendon paths drawn uniformly.
    #[arg(long, value_delimiter = ',', default_values_t = CalibratedConfig::default().paths)]
    pub paths: Vec<TendonPath>,
    /// Tendon (cylinder) radius, mm.
    #[arg(long, default_value_t = CalibratedConfig::default().tendon_radius_mm)]
    pub tendon_radius_mm: Range,
    /// Radius of curvature of `arc` and `s-curve` paths, mm.
    #[arg(long, default_value_t = CalibratedConfig::default().curvature_radius_mm)]
    pub curvature_radius_mm: Range,
    /// Peak press of a video (approach past first touch), mm.
    #[arg(long, default_value_t = CalibratedConfig::default().press_mm)]
    pub press_mm: Range,
    /// Peak press of a video of a sphere, punch or plate edge, mm: deeper
    /// than tendons, as a ball pressed into the gel to calibrate it is
    /// (so the depth network learns the indentations it will be shown).
    #[arg(long, default_value_t = CalibratedConfig::default().object_press_mm)]
    pub object_press_mm: Range,
    /// A tendon's centre line passes within this fraction of the frame's half-height of its centre.
    #[arg(long, default_value_t = CalibratedConfig::default().centre_fraction)]
    pub centre_fraction: f64,
    /// Fraction of tendon videos whose tendon lies outside the frame.
    #[arg(long, default_value_t = CalibratedConfig::default().out_of_view_fraction)]
    pub out_of_view_fraction: f64,
    /// Share of videos with a tendon.
    #[arg(long, default_value_t = CalibratedConfig::default().tendon_share)]
    pub tendon_share: f64,
    /// Share of videos pressing a sphere.
    #[arg(long, default_value_t = CalibratedConfig::default().sphere_share)]
    pub sphere_share: f64,
    /// Share of videos pressing a flat punch.
    #[arg(long, default_value_t = CalibratedConfig::default().punch_share)]
    pub punch_share: f64,
    /// Share of videos pressing a flat plate's rounded edge.
    #[arg(long, default_value_t = CalibratedConfig::default().flat_share)]
    pub flat_share: f64,
    /// Share of videos without contact.
    #[arg(long, default_value_t = CalibratedConfig::default().nothing_share)]
    pub nothing_share: f64,
    /// Sphere radius, mm.
    #[arg(long, default_value_t = CalibratedConfig::default().sphere_radius_mm)]
    pub sphere_radius_mm: Range,
    /// Punch radius, mm.
    #[arg(long, default_value_t = CalibratedConfig::default().punch_radius_mm)]
    pub punch_radius_mm: Range,
    /// A punch's edge fillet, as a fraction of its radius (0.05: a nearly
    /// sharp rim, which shades a thin ring).
    #[arg(long, default_value_t = CalibratedConfig::default().punch_fillet)]
    pub punch_fillet: Range,
    /// Where a plate's edge line lies along the plate's normal, as a
    /// fraction of the way from the frame's centre to its border: negative,
    /// the plate covers the centre; positive, it only clips the frame in a
    /// band along one side, which shades a lone band as one side of a
    /// tendon does. Unset: the plate covers the centre and its edge lies
    /// within half the frame's half-height of it.
    #[arg(long)]
    pub plate_edge_reach: Option<Range>,
    /// Per-video gain on each channel's colour change: 1 +- this.
    #[arg(long, default_value_t = CalibratedConfig::default().optics_jitter)]
    pub optics_jitter: f64,
    /// Per-video factor on the gel's spread width: 1 +- this.
    #[arg(long, default_value_t = CalibratedConfig::default().gel_jitter)]
    pub gel_jitter: f64,
    /// Per-video optical blur, pixels.
    #[arg(long, default_value_t = CalibratedConfig::default().blur_px)]
    pub blur_px: Range,
    /// Per-video shift of the background, up to this many pixels.
    #[arg(long, default_value_t = CalibratedConfig::default().shift_px)]
    pub shift_px: u32,
    /// Exposure factor `1 + e`, `e` drawn per frame from this range.
    #[arg(long, default_value_t = CalibratedConfig::default().exposure_jitter)]
    pub exposure_jitter: Range,
    /// Sensor noise, 8-bit levels.
    #[arg(long, default_value_t = CalibratedConfig::default().noise_sigma)]
    pub noise_sigma: Range,
    /// Frames per palpation video.
    #[arg(long, default_value_t = CalibratedConfig::default().frames_per_sequence)]
    pub frames_per_sequence: usize,
    /// A folder of the sensor's real ball presses (the calibration layout)
    /// joined to the renders as negatives: frames of this very sensor that
    /// hold no tendon, labelled with the calibration's reconstruction.
    #[arg(long)]
    pub real_presses: Option<PathBuf>,
    /// Copies of each real press, each with its own exposure and noise.
    #[arg(long, default_value_t = CalibratedConfig::default().real_copies)]
    pub real_copies: usize,
    /// The last this many presses of `real_presses` are left out (kept for
    /// a held-out check; the manifest names them).
    #[arg(long, default_value_t = CalibratedConfig::default().real_held_out)]
    pub real_held_out: usize,
}

impl Default for CalibratedConfig {
    fn default() -> Self {
        Self {
            paths: TendonPath::ALL.to_vec(),
            tendon_radius_mm: Range::new(1.5, 3.5),
            curvature_radius_mm: Range::new(10.0, 40.0),
            press_mm: Range::new(0.05, 1.5),
            object_press_mm: Range::new(0.05, 2.5),
            centre_fraction: 0.6,
            out_of_view_fraction: 0.08,
            tendon_share: 0.6,
            sphere_share: 0.15,
            punch_share: 0.1,
            flat_share: 0.05,
            nothing_share: 0.1,
            sphere_radius_mm: Range::new(2.0, 6.0),
            punch_radius_mm: Range::new(1.0, 3.0),
            punch_fillet: Range::new(0.15, 0.5),
            plate_edge_reach: None,
            optics_jitter: 0.15,
            gel_jitter: 0.25,
            blur_px: Range::new(0.0, 1.2),
            shift_px: 2,
            exposure_jitter: Range::new(-0.1, 0.1),
            noise_sigma: Range::new(0.5, 3.0),
            frames_per_sequence: 25,
            real_presses: None,
            real_copies: 5,
            real_held_out: 0,
        }
    }
}

impl CalibratedConfig {
    /// Check every value; the message names the offending key.
    pub fn validate(&self) -> Result<()> {
        if !(1..=MAX_COPIES).contains(&self.real_copies) {
            return Err(Error::Config(format!(
                "real_copies: must be 1 to {MAX_COPIES}, got {}",
                self.real_copies
            )));
        }
        if self.paths.is_empty() {
            return Err(Error::Config(
                "paths: at least one tendon path is needed".into(),
            ));
        }
        self.tendon_radius_mm.check("tendon_radius_mm", 0.1, 20.0)?;
        self.curvature_radius_mm
            .check("curvature_radius_mm", 1.0, 1000.0)?;
        self.press_mm.check("press_mm", 0.0, 5.0)?;
        self.object_press_mm.check("object_press_mm", 0.0, 5.0)?;
        self.sphere_radius_mm.check("sphere_radius_mm", 0.2, 50.0)?;
        self.punch_radius_mm.check("punch_radius_mm", 0.2, 50.0)?;
        self.punch_fillet.check("punch_fillet", 0.01, 1.0)?;
        if let Some(r) = self.plate_edge_reach {
            r.check("plate_edge_reach", -1.0, 1.0)?;
        }
        for (name, v) in [
            ("centre_fraction", self.centre_fraction),
            ("out_of_view_fraction", self.out_of_view_fraction),
            ("tendon_share", self.tendon_share),
            ("sphere_share", self.sphere_share),
            ("punch_share", self.punch_share),
            ("flat_share", self.flat_share),
            ("nothing_share", self.nothing_share),
            ("optics_jitter", self.optics_jitter),
            ("gel_jitter", self.gel_jitter),
        ] {
            Range::fixed(v).check(name, 0.0, 1.0)?;
        }
        if self.scene_weights().iter().sum::<f64>() <= 0.0 {
            return Err(Error::Config(
                "tendon_share, sphere_share, punch_share, flat_share, nothing_share: at least one must be above 0".into(),
            ));
        }
        if self.gel_jitter >= 0.9 {
            return Err(Error::Config("gel_jitter: must be below 0.9".into()));
        }
        self.blur_px.check("blur_px", 0.0, 10.0)?;
        if self.shift_px > 64 {
            return Err(Error::Config(format!(
                "shift_px: at most 64, got {}",
                self.shift_px
            )));
        }
        self.exposure_jitter.check("exposure_jitter", -0.9, 0.9)?;
        self.noise_sigma.check("noise_sigma", 0.0, 100.0)?;
        let max = crate::visuotactile::MAX_FRAMES_PER_SEQUENCE;
        if self.frames_per_sequence == 0 || self.frames_per_sequence > max {
            return Err(Error::Config(format!(
                "frames_per_sequence: must be 1 to {max}"
            )));
        }
        Ok(())
    }

    /// Frames to write from `count` and/or `sequences` (whole palpation
    /// videos of `frames_per_sequence`): either, or both when they agree.
    pub fn frame_count(&self, count: Option<usize>, sequences: Option<usize>) -> Result<usize> {
        crate::visuotactile::frames_of(self.frames_per_sequence, count, sequences)
    }

    /// The scene kinds' shares, normalised: tendon, sphere, punch, flat,
    /// nothing.
    pub fn scene_weights(&self) -> [f64; 5] {
        let w = [
            self.tendon_share,
            self.sphere_share,
            self.punch_share,
            self.flat_share,
            self.nothing_share,
        ]
        .map(|v| v.max(0.0));
        let sum: f64 = w.iter().sum();
        if sum > 0.0 { w.map(|v| v / sum) } else { w }
    }
}

/// Frame `frame` of video `sequence` of a calibrated sensor's dataset.
pub fn sample(
    sensor: &CalibratedSensor,
    config: &CalibratedConfig,
    seed: u64,
    sequence: u64,
    frame: usize,
) -> (CalibratedScene, CalibratedFrame) {
    let scene = CalibratedScene::draw(
        config,
        sensor.half_mm(),
        &mut SampleRng::new(seed, 1, sequence),
    );
    let press = press_profile(scene.peak_press_mm, frame, config.frames_per_sequence);
    let mut rng = SampleRng::new(seed, 2 + sequence, frame as u64);
    let out = render(sensor, config, &scene, press, &mut rng);
    (scene, out)
}
