//! Reconstruction: a frame of a calibrated sensor to the skin's
//! indentation. The frame is shrunk and exposure matched to the
//! background, the network gives the slopes, a Poisson solve integrates
//! them on the working grid (rest at the border), and the height is
//! brought back to the frame's size bilinearly.

use std::path::Path;

use tactile_burn::{Network, Runtime};
use tactile_core::image_io::{RgbImage, load_rgb};

use crate::artifact::{BACKGROUND_FILE, GelsightArtifact};
use crate::lookup::LookupTable;
use crate::poisson::PoissonSolver;
use crate::prepare::{FEATURES, PreparedBackground, WorkingGrid, WorkingImage, check_colour};
use crate::{Error, Result};

/// The skin's indentation over a frame: how far each pixel's skin is
/// pushed toward the camera, metres (0 at rest).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct IndentationMap {
    /// Width, pixels (the frame's).
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// Row-major metres.
    pub indentation_m: Vec<f32>,
}

impl IndentationMap {
    /// The deepest indentation, mm.
    pub fn peak_mm(&self) -> f32 {
        1e3 * self.indentation_m.iter().copied().fold(0f32, f32::max)
    }

    /// The area in contact, mm²: pixels pushed in by more than
    /// [`tactile_core::spec::calibrated::CONTACT_MIN_INDENTATION_MM`],
    /// each `mm_per_px` square.
    pub fn contact_area_mm2(&self, mm_per_px: f64) -> f32 {
        let min_m = (tactile_core::spec::calibrated::CONTACT_MIN_INDENTATION_MM * 1e-3) as f32;
        let n = self.indentation_m.iter().filter(|&&v| v > min_m).count();
        (n as f64 * mm_per_px * mm_per_px) as f32
    }
}

/// Where the skin is in contact, from the colour change alone: slopes are
/// kept in full where the change is at least `to`, dropped where it is at
/// most `from`, and faded between, before they are integrated. The far
/// field's change (lighting drift, noise) then adds no slope, so it
/// integrates to rest, as the classic reconstructions' contact mask makes
/// it. The thresholds come from the far field of the calibration presses.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactGate {
    /// Colour change (RGB distance, `[0, 1]` units) at and below which a
    /// working pixel's slopes are dropped.
    pub from: f32,
    /// At and above which they are kept.
    pub to: f32,
}

impl ContactGate {
    /// The gate of presses seen against `bg`: from the 90th to past the
    /// 99th percentile of the colour change beyond three contact radii
    /// (where the skin is at rest).
    pub fn fit(
        bg: &PreparedBackground,
        presses: &[&crate::training::PreparedPress],
    ) -> Option<Self> {
        let mut far: Vec<f32> = presses
            .iter()
            .flat_map(|p| {
                bg.change(&p.frame)
                    .into_iter()
                    .zip(p.targets.far.clone())
                    .filter(|(_, f)| *f > 0.5)
                    .map(|(c, _)| c)
            })
            .collect();
        if far.len() < 100 {
            return None;
        }
        far.sort_by(f32::total_cmp);
        let at = |q: f64| far[((far.len() - 1) as f64 * q) as usize];
        let (from, p99) = (at(0.9), at(0.99));
        Some(Self {
            from,
            to: p99.max(from * 1.25) + 1e-4,
        })
    }

    /// Each working pixel's weight for a frame's colour change.
    pub fn weights(&self, change: &[f32]) -> Vec<f32> {
        let span = (self.to - self.from).max(1e-6);
        change
            .iter()
            .map(|&c| ((c - self.from) / span).clamp(0.0, 1.0))
            .collect()
    }

    /// Check a gate read from a file.
    pub fn check(&self) -> tactile_core::Result<()> {
        if !(self.from.is_finite()
            && self.to.is_finite()
            && 0.0 <= self.from
            && self.from < self.to
            && self.to <= 2.0)
        {
            return Err(tactile_core::Error::Config(format!(
                "contact_gate: need 0 <= from < to <= 2, got {self:?}"
            )));
        }
        Ok(())
    }
}

/// What gives a working frame's slopes.
pub enum SlopeModel {
    /// A calibrated network on a runtime.
    Network(Box<dyn Network>),
    /// The classic colour-change lookup table.
    Lookup(LookupTable),
}

impl SlopeModel {
    /// `gx` then `gy` of `features` (`[FEATURES, h, w]`).
    fn slopes(&mut self, features: Vec<f32>, (w, h): (usize, usize)) -> Result<Vec<f32>> {
        match self {
            Self::Network(net) => Ok(net.run([1, FEATURES, h, w], features)?),
            Self::Lookup(t) => Ok(t.slopes(&features)),
        }
    }
}

/// A calibrated sensor ready to reconstruct frames.
pub struct Reconstructor {
    grid: WorkingGrid,
    mm_per_px: f64,
    model: SlopeModel,
    background: PreparedBackground,
    /// The network's slopes on the background itself, subtracted from
    /// every frame's: the skin at rest reconstructs to exactly 0.
    rest: (Vec<f32>, Vec<f32>),
    solver: PoissonSolver,
    gate: Option<ContactGate>,
}

impl std::fmt::Debug for Reconstructor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Reconstructor({:?})", self.grid)
    }
}

impl Reconstructor {
    /// Load the model in `dir` onto `runtime`, with the background it was
    /// calibrated against.
    pub fn load(dir: impl AsRef<Path>, runtime: Runtime, threads: usize) -> Result<Self> {
        let dir = dir.as_ref();
        let (artifact, net) =
            tactile_onnx::load_network::<GelsightArtifact>(dir, runtime, threads)?;
        let bg_path = dir.join(BACKGROUND_FILE);
        let background = load_rgb(&bg_path)?;
        Ok(Self::new(
            artifact.grid,
            artifact.sensor.mm_per_px,
            SlopeModel::Network(net),
            &background,
            &bg_path,
        )?
        .with_gate(artifact.contact_gate))
    }

    /// The same reconstructor with slopes gated by the colour change
    /// (`None`: every slope integrated).
    pub fn with_gate(self, gate: Option<ContactGate>) -> Self {
        Self { gate, ..self }
    }

    /// A reconstructor on `grid` of a sensor of `mm_per_px` whose slopes
    /// come from `model`, against `background` (`path` names it in
    /// errors).
    pub fn new(
        grid: WorkingGrid,
        mm_per_px: f64,
        model: SlopeModel,
        background: &RgbImage,
        path: &Path,
    ) -> Result<Self> {
        let g = grid;
        check_size(
            path,
            (g.frame_width, g.frame_height),
            frame_size(background),
        )?;
        let mut r = Self {
            background: PreparedBackground::new(background, g)?,
            rest: (vec![], vec![]),
            solver: PoissonSolver::new(g.width(), g.height()),
            grid,
            mm_per_px,
            model,
            gate: None,
        };
        r.rest = r.raw_slopes(&r.background.image.clone())?;
        Ok(r)
    }

    /// The same model against another background (`--background FILE`: the
    /// sensor's rest frame today), of the calibrated size (and in colour,
    /// when the calibration's was).
    pub fn set_background(&mut self, background: &RgbImage, path: &Path) -> Result<()> {
        let g = self.grid;
        check_size(
            path,
            (g.frame_width, g.frame_height),
            frame_size(background),
        )?;
        check_colour(path, background, self.background.colour)?;
        // A rest frame in BGR order against a calibration in RGB.
        self.check_working(&self.background.matched(background)?, path)?;
        self.background = PreparedBackground {
            colour: self.background.colour,
            ..PreparedBackground::new(background, g)?
        };
        self.rest = self.raw_slopes(&self.background.image.clone())?;
        Ok(())
    }

    /// The runtime the network runs on (`None`: the lookup table).
    pub fn runtime(&self) -> Option<Runtime> {
        match &self.model {
            SlopeModel::Network(n) => Some(n.runtime()),
            SlopeModel::Lookup(_) => None,
        }
    }

    /// The working grid.
    pub fn grid(&self) -> WorkingGrid {
        self.grid
    }

    /// Millimetres per frame pixel.
    pub fn mm_per_px(&self) -> f64 {
        self.mm_per_px
    }

    /// The background as the model sees it.
    pub fn background(&self) -> &PreparedBackground {
        &self.background
    }

    /// The model's slopes on an exposure-matched working frame, the
    /// rest's not subtracted.
    pub fn raw_slopes(&mut self, frame: &WorkingImage) -> Result<(Vec<f32>, Vec<f32>)> {
        let g = self.grid;
        let (w, h) = (g.width(), g.height());
        let x = self.background.features(frame);
        let out = self.model.slopes(x, (w, h))?;
        if out.len() != 2 * w * h {
            return Err(tactile_core::Error::Invalid(format!(
                "the sensor model gave {} values for a {w}x{h} grid",
                out.len()
            ))
            .into());
        }
        Ok(split_slopes(out))
    }

    /// The rest's slopes (the model on the background).
    pub fn rest_slopes(&self) -> (&[f32], &[f32]) {
        (&self.rest.0, &self.rest.1)
    }

    /// The indentation on the working grid, mm, of a frame's working
    /// image ([`Self::working_frame`]).
    pub fn working_mm(&mut self, f: &WorkingImage) -> Result<Vec<f32>> {
        let (gx, gy) = self.raw_slopes(f)?;
        let step_mm = self.grid.step_mm(self.mm_per_px);
        let weights = self.gate.map(|g| g.weights(&self.background.change(f)));
        Ok(indentation_mm(
            &self.solver,
            (&gx, &gy),
            (&self.rest.0, &self.rest.1),
            step_mm,
            weights.as_deref(),
        ))
    }

    /// Refuse a frame this sensor cannot read (`path` names it): another
    /// size than the calibrated one, or grey when the calibration was in
    /// colour.
    pub fn check_frame(&self, frame: &RgbImage, path: &Path) -> Result<()> {
        let g = self.grid;
        check_size(path, (g.frame_width, g.frame_height), frame_size(frame))?;
        check_colour(path, frame, self.background.colour)
    }

    /// Refuse `files` this sensor cannot read, from their headers alone
    /// (no picture, or one no frame reader takes: see
    /// [`tactile_core::image_io::rgb_frame_header`]; another size than the
    /// calibrated one; stored grey when the calibration was in colour),
    /// before any is decoded: a folder's bad
    /// frame is named at once, not after the frames before it. One such
    /// file gives its own refusal; several, the first's and their count
    /// ([`Error::UnreadableFrames`]). A grey picture stored as colour is
    /// still refused by [`Self::check_frame`] once decoded.
    pub fn check_files(&self, files: &[std::path::PathBuf]) -> Result<()> {
        self.check_headers(files, |f| {
            Ok((f.clone(), tactile_core::image_io::rgb_frame_header(f)?))
        })
    }

    /// [`Self::check_files`] of any `frames`, each giving its name (for
    /// errors) and its header through `header` (a file's, or a stack's
    /// page's read when it was opened).
    pub fn check_headers<T>(
        &self,
        frames: &[T],
        header: impl Fn(&T) -> Result<(std::path::PathBuf, tactile_core::image_io::ImageHeader)>,
    ) -> Result<()> {
        let g = self.grid;
        let expected = (g.frame_width, g.frame_height);
        let check = |f: &T| {
            let (path, h) = header(f)?;
            check_size(&path, expected, (h.width as usize, h.height as usize))?;
            match h.grey() && self.background.colour {
                true => Err(Error::GreyFrame { path }),
                false => Ok(()),
            }
        };
        tactile_core::error::check_each(frames, check, |first, count, total| {
            Error::UnreadableFrames {
                first: Box::new(first),
                count,
                total,
            }
        })
    }

    /// The skin's indentation over `frame` (the calibrated size, in colour
    /// when the calibration was; `path` names it in errors), at the frame's
    /// size, metres.
    pub fn reconstruct(&mut self, frame: &RgbImage, path: &Path) -> Result<IndentationMap> {
        let working = self.working_frame(frame, path)?;
        self.reconstruct_working(&working)
    }

    /// `frame` checked ([`Self::check_frame`]), shrunk to the working grid
    /// and its exposure matched to the rest frame: what the reconstruction
    /// reads, and the rest-frame check
    /// ([`PreparedBackground::median_change`]) with it.
    pub fn working_frame(&self, frame: &RgbImage, path: &Path) -> Result<WorkingImage> {
        self.check_frame(frame, path)?;
        let working = self.background.matched(frame)?;
        self.check_working(&working, path)?;
        Ok(working)
    }

    /// Refuse a frame's exposure-matched `working` image (the frame named
    /// `path`) in BGR order ([`Error::SwappedChannels`]): its colours would
    /// be read as slopes mirrored, a wrong skin without a word.
    pub fn check_working(&self, working: &WorkingImage, path: &Path) -> Result<()> {
        self.background.check_channel_order(working, path)
    }

    /// [`Self::reconstruct`] of a frame's working image.
    pub fn reconstruct_working(&mut self, working: &WorkingImage) -> Result<IndentationMap> {
        let g = self.grid;
        let mm = self.working_mm(working)?;
        let size = (g.frame_width, g.frame_height);
        let big = tactile_preprocess::enlarge_f32(&mm, (g.width(), g.height()), size)?;
        Ok(IndentationMap {
            width: size.0,
            height: size.1,
            indentation_m: big.iter().map(|v| v * 1e-3).collect(),
        })
    }
}

/// A network output's `gx` and `gy` maps (the first and second half).
pub(crate) fn split_slopes(mut v: Vec<f32>) -> (Vec<f32>, Vec<f32>) {
    let gy = v.split_off(v.len() / 2);
    (v, gy)
}

/// The indentation on the working grid, mm: the network's `raw` slopes
/// less its slopes at `rest`, in mm per working pixel (`step_mm`), each
/// times its `weight` (the contact gate's) when given, integrated.
/// Reconstruction and calibration's validation share it.
pub fn indentation_mm(
    solver: &PoissonSolver,
    raw: (&[f32], &[f32]),
    rest: (&[f32], &[f32]),
    step_mm: f32,
    weight: Option<&[f32]>,
) -> Vec<f32> {
    let skin = |g: &[f32], r: &[f32]| -> Vec<f32> {
        g.iter()
            .zip(r)
            .enumerate()
            .map(|(i, (v, r))| (v - r) * step_mm * weight.map_or(1.0, |w| w[i]))
            .collect()
    };
    solver.integrate(&skin(raw.0, rest.0), &skin(raw.1, rest.1))
}

/// An image's `(width, height)`.
fn frame_size(img: &RgbImage) -> (usize, usize) {
    (img.width(), img.height())
}

/// Refuse a frame (or rest frame) named `path` of size `found`, decoded or
/// read off its header, when it is not the calibrated size.
fn check_size(path: &Path, expected: (usize, usize), found: (usize, usize)) -> Result<()> {
    if found != expected {
        return Err(Error::FrameSize {
            path: path.to_path_buf(),
            expected,
            found,
        });
    }
    Ok(())
}
