//! Reconstructing a folder of frames, or a TIFF stack's pages (what
//! `tactile reconstruct` and `tactile.calibrate.reconstruct` run): one
//! `<stem>.npy` per frame (`<stack stem>-000000.npy`, ... per page)
//! (float32 `H x W`, metres) and, if asked, a picture per frame: the
//! frame, a shaded 3-D view of the skin and its indentation in mm with a
//! colour bar. Both folders are written whole or not at all.

use std::path::{Path, PathBuf};

use serde::Serialize;
use tactile_burn::Runtime;
use tactile_core::image_io::{RgbImage, load_rgb};
use tactile_core::plot::{COLOUR_BAR_WIDTH, colour, colour_range, draw_colour_bar};

use crate::inference::{IndentationMap, Reconstructor};
use crate::prepare::{PreparedBackground, WorkingImage};
use crate::{Error, Result};

/// Most frames one call reconstructs.
pub const MAX_FRAMES: usize = 100_000;

/// What a reconstruction of a folder is asked for beside the model
/// (flags of `tactile reconstruct`).
#[derive(Debug, Clone, clap::Args)]
pub struct ReconstructOptions {
    /// The sensor's rest frame to compare against instead of the calibration's (same size).
    #[arg(long)]
    pub background: Option<PathBuf>,
    /// Also write pictures into this folder (new): each frame beside its indentation in mm with a colour bar, and a shaded 3-D view.
    #[arg(long)]
    pub render: Option<PathBuf>,
    /// Where the sensor model runs.
    #[arg(long, value_enum, default_value_t = Runtime::Onnx)]
    pub runtime: Runtime,
}

/// What was reconstructed.
#[derive(Debug, Clone, Serialize)]
pub struct ReconstructReport {
    /// Frames written.
    pub frames: usize,
    /// Median time per frame (shrink, network, Poisson, enlarge), ms.
    pub ms_per_frame: f64,
    /// The deepest indentation over all frames, mm.
    pub peak_mm: f64,
    /// Frames skipped because they could not be decoded past a whole
    /// header (cut short), named by a warning.
    pub undecodable_frames: usize,
    /// What a user should know of the input (files that are not frames,
    /// gaps in the numbering).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// The frames `data` names: itself, or those of a folder as every command
/// reads one (`tactile_core::source::FrameList`: a dataset's rows, else its
/// frame files in the order of the numbers in their names, each
/// checked to be a file inside the folder), with what the user should be
/// told (files that are not frames, gaps in the numbering). Two frames of one name once their extensions
/// are dropped are refused: both would be written to one `.npy`.
pub fn frame_files(data: &Path) -> Result<(Vec<PathBuf>, Vec<String>)> {
    if let Some(e) = tactile_core::dataset::file_of_a_dataset(data) {
        return Err(e.into());
    }
    if data.is_file() {
        return Ok((vec![data.to_path_buf()], Vec::new()));
    }
    let list = tactile_core::source::FrameList::open(data)?;
    if list.frames.len() > MAX_FRAMES {
        return Err(Error::Layout {
            path: data.to_path_buf(),
            why: format!("more than {MAX_FRAMES} frames"),
        });
    }
    let mut by_stem = std::collections::HashMap::new();
    for f in &list.frames {
        let stem = f.path.file_stem().unwrap_or_default();
        if let Some(before) = by_stem.insert(stem, &f.path) {
            return Err(Error::Layout {
                path: f.path.clone(),
                why: format!(
                    "has the name of {} once their extensions are dropped; both would be written to {}.npy (rename one)",
                    before.display(),
                    stem.to_string_lossy()
                ),
            });
        }
    }
    let warnings = list.warnings();
    Ok((list.frames.into_iter().map(|f| f.path).collect(), warnings))
}

/// A frame's score against a sensor's profile ([`SensorCheck`]).
pub type FrameScore<'a> = Box<dyn FnMut(&RgbImage) -> Result<f32> + Send + 'a>;

/// What a [`SensorCheck`] compares frames with.
pub enum CheckBasis<'a> {
    /// The palpation detector's input profile of this sensor (its colours
    /// and colour layout): it tells other units of the same design too.
    DetectorProfile {
        /// The frames the profile was fitted on.
        frames: usize,
        /// A frame's score, in the profile's spreads.
        score: FrameScore<'a>,
    },
    /// The sensor's rest frame (the calibration's background, or the one
    /// given instead), read off the reconstruction's own working image
    /// ([`PreparedBackground::median_change`]): a calibration alone has
    /// nothing else. It tells frames of another kind of sensor, not
    /// another unit of this one.
    RestFrame,
}

/// Median colour change from the rest frame ([`PreparedBackground::median_change`],
/// an RGB distance on a 0-1 scale) above which a frame is not the sensor's:
/// the 32 real presses of the calibrated R1.5 stay below 0.03, its renders
/// below 0.04, and under spheres of 15-40 mm pressed 1.5-3 mm (half the
/// gel or more in contact) below 0.07; TacTip frames on its canvas score
/// 0.84 and more.
pub const REST_CHANGE_LIMIT: f32 = 0.2;

/// How far a frame lies from the sensor's own frames, to name frames of
/// another sensor: the palpation detector's input profile of this sensor
/// when the model folder has one (`tactile_pipeline` builds it), else the
/// rest frame ([`SensorCheck::rest_frame`]).
pub struct SensorCheck<'a> {
    /// What a frame is compared with, and how it is scored.
    pub basis: CheckBasis<'a>,
    /// Scores above this are not the sensor's frames.
    pub threshold: f32,
}

impl SensorCheck<'_> {
    /// The check of a calibration alone: a frame's median colour change
    /// from the rest frame the reconstruction subtracts.
    pub fn rest_frame() -> Self {
        Self {
            basis: CheckBasis::RestFrame,
            threshold: REST_CHANGE_LIMIT,
        }
    }

    /// `check` when there is one, else the rest frame's
    /// ([`SensorCheck::rest_frame`]): every reconstruction names frames of
    /// another sensor by the best check it has.
    pub fn or_rest_frame(check: Option<Self>) -> Self {
        check.unwrap_or_else(Self::rest_frame)
    }

    /// The score of `frame` when it is unlike the sensor's frames (above
    /// the threshold); `None` when it is like them. `working` is the
    /// reconstruction's working image of it
    /// ([`Reconstructor::working_frame`]), against `rest`.
    pub fn unlike(
        &mut self,
        frame: &RgbImage,
        working: &WorkingImage,
        rest: &PreparedBackground,
    ) -> Result<Option<f32>> {
        let score = match &mut self.basis {
            CheckBasis::DetectorProfile { score, .. } => score(frame)?,
            CheckBasis::RestFrame => rest.median_change(working),
        };
        Ok((score > self.threshold).then_some(score))
    }
}

impl Reconstructor {
    /// [`Reconstructor::reconstruct`], with the warning for `frame`
    /// (named `name`) when `check` finds it unlike the sensor's, in words
    /// without its score ([`unlike_warning`]): a frame given alone, as a
    /// loop gives them, is warned of alike each time.
    pub fn reconstruct_checked(
        &mut self,
        frame: &RgbImage,
        name: &str,
        check: &mut SensorCheck<'_>,
    ) -> Result<(IndentationMap, Option<String>)> {
        let working = self.working_frame(frame, Path::new(name))?;
        let unlike = check.unlike(frame, &working, self.background())?;
        let warning =
            unlike.and_then(|score| unlike_warning(&[(name.to_string(), score)], check, false));
        Ok((self.reconstruct_working(&working)?, warning))
    }
}

/// The warning naming `unlike` (frame, score), frames `check` finds unlike
/// the sensor's, with their largest score when `scored` (a frame given
/// alone, in a loop, is warned of in words that repeat alike); `None`
/// when there are none.
pub fn unlike_warning(
    unlike: &[(String, f32)],
    check: &SensorCheck<'_>,
    scored: bool,
) -> Option<String> {
    let worst = unlike.iter().map(|u| u.1).reduce(f32::max)?;
    let files: Vec<String> = unlike.iter().map(|u| u.0.clone()).collect();
    let (named, these) = tactile_core::source::named_frames(&files);
    Some(match check.basis {
        CheckBasis::DetectorProfile { frames, .. } => {
            let scores = match (scored, unlike.len()) {
                (false, _) => "above".to_string(),
                (true, 1) => format!("{worst:.1},"),
                (true, _) => format!("up to {worst:.1},"),
            };
            format!(
                "warning: {named}: colours unlike this sensor's (scored against the {frames} frames of it its detector was trained on: {scores} where the sensor's own frames stay below {:.1}): a frame of another sensor, or of this one under other light or with another gel? The indentation of {these} may mean nothing",
                check.threshold
            )
        }
        CheckBasis::RestFrame => {
            let by = match (scored, unlike.len()) {
                (false, _) => String::new(),
                (true, 1) => format!(" by {worst:.2}"),
                (true, _) => format!(" by up to {worst:.2}"),
            };
            format!(
                "warning: {named}: half of the picture or more changed colour from this sensor's rest frame{by}, where its own frames, which change only where pressed, stay below {:.2} (the median change, an RGB distance on a 0-1 scale once exposure is matched): a frame of another sensor, or of this one under other light, or against another day's rest frame? The indentation of {these} may mean nothing",
                check.threshold
            )
        }
    })
}

/// The frames a reconstruction reads: a folder's files (or one file), the
/// pages of a TIFF stack given alone, or the presses of Taxim's pack.
enum FramesToRead {
    Files(Vec<PathBuf>),
    Stack {
        stack: tactile_core::stack::StackFrames,
        /// The stack file.
        path: PathBuf,
    },
    Pack {
        /// Its presses and their names.
        frames: crate::taxim::PackFrames,
        /// The pack file.
        path: PathBuf,
        /// Each press's outputs' name.
        stems: Vec<String>,
    },
}

/// Whether `data` is Taxim's pack (a `.npz` file) or its folder, and the
/// pack's path.
fn taxim_pack(data: &Path) -> Option<PathBuf> {
    let npz = data
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npz"));
    match (data.is_file() && npz, crate::taxim::is_taxim_folder(data)) {
        (true, _) => Some(data.to_path_buf()),
        (false, true) => Some(data.join(crate::taxim::PACK_FILE)),
        _ => None,
    }
}

impl FramesToRead {
    /// What `data` holds (a stack given alone, else [`frame_files`]), with
    /// what the user should be told.
    fn of(data: &Path) -> Result<(Self, Vec<String>)> {
        // One page past the bound is read to tell a stack too long.
        let past_bound = Some(MAX_FRAMES as u64 + 1);
        if let Some(path) = taxim_pack(data) {
            let frames = crate::taxim::read_frames(&path)?;
            let pack_stem = (path.file_stem()).map_or("pack".into(), |s| s.to_string_lossy());
            // Each press's name's stem (press_01), or its place in the pack
            // (dataPack-000003) where the names are none or share a stem.
            let by_name: Option<Vec<String>> = frames.names.as_ref().and_then(|names| {
                (names.iter())
                    .map(|n| {
                        Path::new(n)
                            .file_stem()
                            .map(|s| s.to_string_lossy().into_owned())
                    })
                    .collect()
            });
            let stems = match by_name {
                Some(stems)
                    if stems.iter().collect::<std::collections::HashSet<_>>().len()
                        == stems.len() =>
                {
                    stems
                }
                _ => (0..frames.presses.len())
                    .map(|i| format!("{pack_stem}-{i:06}"))
                    .collect(),
            };
            return Ok((
                Self::Pack {
                    frames,
                    path,
                    stems,
                },
                Vec::new(),
            ));
        }
        if data.is_file()
            && tactile_core::dataset::file_of_a_dataset(data).is_none()
            && let Some(stack) = tactile_core::stack::StackFrames::open(data, past_bound)?
        {
            if stack.len() > MAX_FRAMES {
                return Err(Error::Layout {
                    path: data.to_path_buf(),
                    why: format!("more than {MAX_FRAMES} frames"),
                });
            }
            let warnings = stack.cut_short_warning().map(str::to_string);
            let frames = Self::Stack {
                stack,
                path: data.to_path_buf(),
            };
            return Ok((frames, warnings.into_iter().collect()));
        }
        let (files, warnings) = frame_files(data)?;
        Ok((Self::Files(files), warnings))
    }

    fn len(&self) -> usize {
        match self {
            Self::Files(files) => files.len(),
            Self::Stack { stack, .. } => stack.len(),
            Self::Pack { frames, .. } => frames.presses.len(),
        }
    }

    /// Frame `i` named in messages: its file, or the stack's page.
    fn label(&self, i: usize) -> PathBuf {
        match self {
            Self::Files(files) => files[i].clone(),
            Self::Stack { path, .. } => {
                PathBuf::from(format!("{}, frame {i:06} of the stack", path.display()))
            }
            Self::Pack { frames, path, .. } => {
                let pack = path.display().to_string();
                PathBuf::from(crate::taxim::press_file(&pack, &frames.name(i)))
            }
        }
    }

    /// The name of frame `i`'s outputs: its file's stem, or the stack's
    /// stem and the page's number (`stack-000003`).
    fn stem(&self, i: usize) -> String {
        let stem = |p: &Path| {
            p.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "frame".into())
        };
        match self {
            Self::Files(files) => stem(&files[i]),
            Self::Stack { path, .. } => format!("{}-{i:06}", stem(path)),
            Self::Pack { stems, .. } => stems[i].clone(),
        }
    }

    fn load(&self, i: usize) -> tactile_core::Result<RgbImage> {
        match self {
            Self::Files(files) => load_rgb(&files[i]),
            Self::Stack { stack, .. } => stack.load(i),
            Self::Pack { frames, .. } => Ok(frames.presses[i].clone()),
        }
    }

    /// Refuse frames `rec` cannot read, from their headers alone.
    fn check(&self, rec: &Reconstructor) -> Result<()> {
        match self {
            Self::Files(files) => rec.check_files(files),
            Self::Stack { stack, .. } => {
                let pages: Vec<usize> = (0..stack.len()).collect();
                rec.check_headers(&pages, |&i| {
                    let header = stack
                        .header(i)
                        .ok_or_else(|| tactile_core::Error::image(self.label(i), "no such page"))?;
                    Ok((self.label(i), header))
                })
            }
            // One size and colour for every press (checked as it was read).
            Self::Pack { frames, .. } => match frames.presses.first() {
                Some(first) => rec.check_frame(first, &self.label(0)),
                None => Ok(()),
            },
        }
    }
}

/// Reconstruct every frame `data` names with the model in `model` into
/// the new folder `out`. Frames unlike the sensor's (by `check`, else by
/// the rest frame: [`SensorCheck::rest_frame`]) are still reconstructed,
/// and named in a warning.
pub fn reconstruct_folder(
    model: &Path,
    data: &Path,
    out: &Path,
    options: &ReconstructOptions,
    check: Option<SensorCheck<'_>>,
) -> Result<ReconstructReport> {
    let (frames, mut warnings) = FramesToRead::of(data)?;
    // Both folders are new: one with files in it is refused before any work.
    if let Some(render) = &options.render {
        tactile_core::dataset::refuse_same_output(out, render)?;
    }
    let staged = tactile_core::io::StagedDir::fresh(out)?;
    let render = options
        .render
        .as_ref()
        .map(tactile_core::io::StagedDir::fresh)
        .transpose()?;
    let mut rec = Reconstructor::load(model, options.runtime, 0)?;
    if let Some(bg) = &options.background {
        rec.set_background(&load_rgb(bg)?, bg)?;
    }
    frames.check(&rec)?;
    let mut check = SensorCheck::or_rest_frame(check);
    let mut times = Vec::with_capacity(frames.len());
    let mut peak = 0f64;
    let mut unlike = Vec::new();
    // A frame cut short behind a whole header is found only here: skipped
    // and named, so the other frames' maps are kept, as `tactile run`
    // keeps their records.
    let mut undecodable = tactile_core::source::UndecodableFrames::new(frames.len());
    for i in 0..frames.len() {
        if tactile_core::interrupt::requested() {
            return Err(tactile_core::Error::Interrupted.into());
        }
        let Some(frame) = undecodable.decoded(frames.load(i))? else {
            continue;
        };
        let f = &frames.label(i);
        let t0 = std::time::Instant::now();
        let working = rec.working_frame(&frame, f)?;
        let map = rec.reconstruct_working(&working)?;
        times.push(t0.elapsed().as_secs_f64() * 1e3);
        if let Some(score) = check.unlike(&frame, &working, rec.background())? {
            unlike.push((f.display().to_string(), score));
        }
        peak = peak.max(map.peak_mm() as f64);
        let stem = frames.stem(i);
        tactile_core::npy::write_depth_npy(
            staged.path().join(format!("{stem}.npy")),
            map.width,
            map.height,
            &map.indentation_m,
        )?;
        if let Some(r) = &render {
            let mm_per_px = rec.mm_per_px();
            render_picture(
                &r.path().join(format!("{stem}.png")),
                &frame,
                &map,
                mm_per_px,
            )?;
        }
    }
    warnings.extend(undecodable.warning());
    undecodable.finish(times.len())?;
    staged.commit(false)?;
    if let Some(r) = render {
        r.commit(false)?;
    }
    times.sort_by(f64::total_cmp);
    warnings.extend(unlike_warning(&unlike, &check, true));
    Ok(ReconstructReport {
        frames: times.len(),
        ms_per_frame: times[times.len() / 2],
        peak_mm: peak,
        undecodable_frames: undecodable.count(),
        warnings,
    })
}

/// Every other pixel of a row-major map (for pictures half the frame's size).
fn halve<T: Copy>(v: &[T], (w, h): (usize, usize), channels: usize) -> Vec<T> {
    let mut out = Vec::with_capacity(w / 2 * (h / 2) * channels);
    for y in (0..h - h % 2).step_by(2) {
        for x in (0..w - w % 2).step_by(2) {
            let o = (y * w + x) * channels;
            out.extend_from_slice(&v[o..o + channels]);
        }
    }
    out
}

/// The frame, a shaded 3-D view of the skin and its indentation in mm
/// with a colour bar, side by side at half size (`mm_per_px`: the
/// sensor's scale, for the shading's slopes).
pub fn render_picture(
    path: &Path,
    frame: &RgbImage,
    map: &IndentationMap,
    mm_per_px: f64,
) -> Result<()> {
    let (w, h) = (map.width, map.height);
    let (hw, hh) = (w / 2, h / 2);
    let rgb = halve(frame.as_slice(), (w, h), 3);
    let mm: Vec<f32> = halve(&map.indentation_m, (w, h), 1)
        .iter()
        .map(|v| v * 1e3)
        .collect();
    let gap = 6;
    let width = 3 * (hw + gap) + COLOUR_BAR_WIDTH;
    let mut out = vec![255u8; width * hh * 3];
    // Lambertian shading of the skin (light from the upper left), the
    // relief exaggerated so a press of a millimetre shows.
    // A picture pixel is two frame pixels.
    let px_mm = 2.0 * mm_per_px;
    let light = {
        let l = [-1.0f32, -1.0, 1.5];
        let n = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
        [l[0] / n, l[1] / n, l[2] / n]
    };
    let (lo, hi) = colour_range(mm.iter().copied());
    for y in 0..hh {
        for x in 0..hw {
            let i = y * hw + x;
            let o = |k: usize| (y * width + k * (hw + gap) + x) * 3;
            out[o(0)..o(0) + 3].copy_from_slice(&rgb[i * 3..i * 3 + 3]);
            // The skin's height is minus its indentation.
            let at = |xx: usize, yy: usize| -mm[yy.min(hh - 1) * hw + xx.min(hw - 1)];
            let dx = (at(x + 1, y) - at(x.saturating_sub(1), y)) / (2.0 * px_mm as f32) * 3.0;
            let dy = (at(x, y + 1) - at(x, y.saturating_sub(1))) / (2.0 * px_mm as f32) * 3.0;
            let n = (dx * dx + dy * dy + 1.0).sqrt();
            let shade = ((-dx * light[0] - dy * light[1] + light[2]) / n).clamp(0.0, 1.0);
            let g = (40.0 + 215.0 * shade) as u8;
            out[o(1)..o(1) + 3].copy_from_slice(&[g, g, g]);
            let c = colour((mm[i] as f64 - lo) / (hi - lo));
            out[o(2)..o(2) + 3].copy_from_slice(&c);
        }
    }
    draw_colour_bar(
        &mut out,
        width,
        hh,
        3 * (hw + gap),
        (lo, hi),
        "indentation, mm",
    )?;
    Ok(tactile_core::image_io::save_rgb_png(path, width, hh, &out)?)
}
