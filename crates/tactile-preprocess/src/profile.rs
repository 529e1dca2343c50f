//! Is this a frame of the sensor the models were trained on? A few input
//! statistics per frame (an [`InputProfile`]'s descriptor) against their
//! spread over the training frames: frames far outside it (another
//! sensor, a uniform or natural image, the camera out of its housing) are
//! flagged instead of getting a confident answer.
//!
//! The descriptor reads the frame as the detector sees it (resized to its
//! input, 8 bits per channel): inside the sensing window (the inscribed
//! ellipse, away from its edge) the mean of each channel, the spread and
//! the fine texture of the brightness, and the colour balance; outside it
//! (the dark housing) the brightness and its spread. A profile may also
//! keep the training frames' colour layout ([`ColourLayout`]): where on
//! the frame each channel is bright. Another unit of the same design (its
//! LEDs in another order, another light, another gel) has global
//! statistics like this one's but not its layout.
//!
//! A TacTip model's profile reads its pin images instead: where their
//! power lies across spatial frequencies ([`pin_spectrum`]), which the
//! pins' spacing sets.

use serde::{Deserialize, Serialize};

use crate::PinImage;
use crate::visuo::FloatImage;
use crate::{Error, Result};

/// The descriptor's values, in order.
pub const DESCRIPTOR: [&str; 9] = [
    "window mean red",
    "window mean green",
    "window mean blue",
    "window brightness spread",
    "window fine texture",
    "window red - green",
    "window blue - green",
    "housing brightness",
    "housing brightness spread",
];

/// The smallest spread a statistic is measured against, in [0, 1] pixel
/// units: a statistic that hardly varies in training still allows this.
pub const MIN_SCALE: f32 = 0.02;

/// Luma weights (ITU-R BT.601) of red, green and blue: the brightness the
/// descriptor reads.
pub const LUMA: [f32; 3] = [0.299, 0.587, 0.114];

/// Cells across and down of the colour layout.
pub const LAYOUT_GRID: (usize, usize) = (16, 12);

/// The names of the colour layout's statistics, after [`DESCRIPTOR`]'s.
pub const LAYOUT_STATISTICS: [&str; 2] = ["colour layout residual", "colour layout contrast"];

/// The smallest spread the colour layout's statistics are measured against
/// (in units of a channel's mean level).
pub const LAYOUT_MIN_SCALE: f32 = 0.001;

/// A heavy-tailed statistic's 99.9th-percentile training distance is at
/// most this many scales: the layout's statistics move with large
/// contacts, so their scales come from their tails as well as their
/// spreads.
pub const TAIL_SCALES: f32 = 4.0;

/// The smallest threshold a profile flags frames above, in scales.
pub const MIN_THRESHOLD: f32 = 6.0;

/// Radial bands a pin image's power spectrum is read in, from the lowest
/// frequency to the Nyquist frequency along an axis (the corners beyond
/// it fall in the last); the first, around the mean, is left out.
pub const PIN_BANDS: usize = 16;

/// How a pin profile's statistic names start ("pin spectrum band 3/16").
pub const PIN_BAND_PREFIX: &str = "pin spectrum band";

/// The smallest spread a pin spectrum band is measured against (natural
/// log of its share of the power: 5 %).
pub const PIN_MIN_SCALE: f32 = 0.05;

/// How far above its training frames' 99.9th-percentile score a pin
/// profile's threshold sits: the real surface set's 2,000 `val` frames,
/// against profiles of its `train` frames, score at most 0.66 of it
/// (`docs/bench-pin-profile-heldout.md`; other sensors' frames in
/// `docs/bench-pin-profile.md`).
pub const PIN_PROFILE_MARGIN: f32 = 1.5;

/// [`pin_spectrum`] of each of `pins`, in parallel, in order.
pub fn pin_spectra(pins: &[&PinImage]) -> Vec<Vec<f32>> {
    use rayon::prelude::*;
    pins.par_iter().map(|p| pin_spectrum(p)).collect()
}

/// The names of [`pin_spectrum`]'s values.
pub fn pin_spectrum_names() -> Vec<String> {
    (1..PIN_BANDS)
        .map(|b| format!("{PIN_BAND_PREFIX} {b}/{PIN_BANDS}"))
        .collect()
}

/// Where a pin image's power lies across spatial frequencies: the natural
/// log of each radial band's share of the power (bands 1 to
/// [`PIN_BANDS`]` - 1`, the mean removed). The pins' spacing sets the
/// bands that carry it, whatever the contact moves them to or turns
/// them by, so a frame of another sensor (other pins, or none: a
/// GelSight frame), of this sensor at another scale, or of noise puts its
/// power elsewhere.
pub fn pin_spectrum(pin: &PinImage) -> Vec<f32> {
    use rustfft::num_complex::Complex;
    let n = pin.side;
    if n == 0 || pin.pixels.len() != n * n {
        return vec![0.0; PIN_BANDS - 1];
    }
    let mean = pin.pixels.iter().map(|&v| v as f64).sum::<f64>() / (n * n) as f64;
    let mut data: Vec<Complex<f32>> = pin
        .pixels
        .iter()
        .map(|&v| Complex::new(v - mean as f32, 0.0))
        .collect();
    thread_local! {
        static PLANNER: std::cell::RefCell<rustfft::FftPlanner<f32>> =
            std::cell::RefCell::new(rustfft::FftPlanner::new());
    }
    let fft = PLANNER.with(|p| p.borrow_mut().plan_fft_forward(n));
    // Rows, then (transposed) columns: the 2-D transform.
    fft.process(&mut data);
    let mut t = vec![Complex::new(0.0, 0.0); n * n];
    for y in 0..n {
        for x in 0..n {
            t[x * n + y] = data[y * n + x];
        }
    }
    fft.process(&mut t);
    let freq = |k: usize| {
        let k = if k < n.div_ceil(2) {
            k as f64
        } else {
            k as f64 - n as f64
        };
        k / n as f64
    };
    let (mut power, mut count) = ([0f64; PIN_BANDS], [0usize; PIN_BANDS]);
    for (i, c) in t.iter().enumerate() {
        let (fx, fy) = (freq(i / n), freq(i % n));
        let r = (fx * fx + fy * fy).sqrt() / 0.5;
        let band = ((r * PIN_BANDS as f64) as usize).min(PIN_BANDS - 1);
        power[band] += c.norm_sqr() as f64;
        count[band] += 1;
    }
    let mean_power: Vec<f64> = (1..PIN_BANDS)
        .map(|b| power[b] / count[b].max(1) as f64)
        .collect();
    let total = mean_power.iter().sum::<f64>() + 1e-12;
    mean_power
        .iter()
        .map(|p| ((p / total) + 1e-9).ln() as f32)
        .collect()
}

/// Each channel's mean over each cell of a `columns x rows` grid, divided
/// by that channel's mean over the grid: `rows x columns x 3` values,
/// row-major, independent of exposure and white balance. The grid covers
/// the top-left `rows * (height / rows)` by `columns * (width / columns)`
/// pixels.
pub fn layout_cells(img: &FloatImage, (columns, rows): (usize, usize)) -> Result<Vec<f32>> {
    let (w, h) = (img.width, img.height);
    if img.channels != 3 {
        return Err(Error::Channels {
            expected: 3,
            found: img.channels,
        });
    }
    if columns == 0 || rows == 0 || w < columns || h < rows {
        return Err(Error::Core(tactile_core::Error::Invalid(format!(
            "a colour layout of {columns} x {rows} cells needs a frame at least that large, got {w} x {h}"
        ))));
    }
    let (cw, ch) = (w / columns, h / rows);
    let mut cells = vec![0f32; rows * columns * 3];
    for (r, row) in cells.chunks_exact_mut(columns * 3).enumerate() {
        for (c, cell) in row.chunks_exact_mut(3).enumerate() {
            let mut acc = [0f64; 3];
            for y in r * ch..(r + 1) * ch {
                let start = (y * w + c * cw) * 3;
                for p in img.data[start..start + cw * 3].chunks_exact(3) {
                    for k in 0..3 {
                        acc[k] += p[k] as f64;
                    }
                }
            }
            for k in 0..3 {
                cell[k] = (acc[k] / (cw * ch) as f64) as f32;
            }
        }
    }
    let n = (rows * columns) as f32;
    let mut level = [0f32; 3];
    for cell in cells.chunks_exact(3) {
        for k in 0..3 {
            level[k] += cell[k];
        }
    }
    let level = level.map(|v| (v / n).max(1.0 / 255.0));
    for cell in cells.chunks_exact_mut(3) {
        for k in 0..3 {
            cell[k] /= level[k];
        }
    }
    Ok(cells)
}

/// The element a sort of `v` puts at index `len / 2` (the upper median).
fn upper_median(mut v: Vec<f32>) -> f32 {
    let k = v.len() / 2;
    *v.select_nth_unstable_by(k, f32::total_cmp).1
}

/// The training frames' colour layout: per cell and channel the median of
/// their [`layout_cells`]. Two statistics compare a frame's layout with
/// it: the residual, the median over cells and channels of their
/// distance from it (so a contact over less than half the frame hardly
/// moves it: another LED order or light moves it everywhere), and the
/// contrast, the slope of the frame's layout against the reference's
/// about the flat level 1 (another gel or black level: less or more
/// contrast at the same places).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColourLayout {
    /// Cells across.
    pub columns: usize,
    /// Cells down.
    pub rows: usize,
    /// `rows x columns x 3` reference values.
    pub reference: Vec<f32>,
}

impl ColourLayout {
    /// Cells a layout may have.
    pub const MAX_CELLS: usize = 4096;

    /// The median layout of `cells` (each from [`layout_cells`] on a
    /// `columns x rows` grid; at least one).
    pub fn fit(cells: &[Vec<f32>], (columns, rows): (usize, usize)) -> Result<Self> {
        let k = rows * columns * 3;
        if cells.is_empty() || cells.iter().any(|c| c.len() != k) {
            return Err(Error::Core(tactile_core::Error::Invalid(format!(
                "a colour layout needs frames of {k} cell values each"
            ))));
        }
        let reference = (0..k)
            .map(|i| upper_median(cells.iter().map(|c| c[i]).collect()))
            .collect();
        Ok(Self {
            columns,
            rows,
            reference,
        })
    }

    /// The residual and the contrast of a frame (see the type).
    pub fn statistics(&self, img: &FloatImage) -> Result<[f32; 2]> {
        Ok(self.of_cells(&layout_cells(img, (self.columns, self.rows))?))
    }

    /// The residual and the contrast of a frame's [`layout_cells`]. The
    /// contrast is `1 + sum((c - r) w)` with `w = (r - 1) / sum((r - 1)^2)`
    /// ([`Self::contrast_weights`]): 1 at the reference's contrast.
    pub fn of_cells(&self, cells: &[f32]) -> [f32; 2] {
        let residual = upper_median(
            cells
                .iter()
                .zip(&self.reference)
                .map(|(c, r)| (c - r).abs())
                .collect(),
        );
        let contrast = 1.0
            + cells
                .iter()
                .zip(&self.reference)
                .zip(self.contrast_weights())
                .map(|((c, r), w)| ((c - r) * w) as f64)
                .sum::<f64>() as f32;
        [residual, contrast]
    }

    /// The contrast's weight per value: `(r - 1) / sum((r - 1)^2)`, all 0
    /// for a flat reference (whose contrast is then always 1).
    pub fn contrast_weights(&self) -> Vec<f32> {
        let d: f64 = self
            .reference
            .iter()
            .map(|&r| (r as f64 - 1.0).powi(2))
            .sum();
        self.reference
            .iter()
            .map(|&r| {
                if d > 1e-8 {
                    ((r as f64 - 1.0) / d) as f32
                } else {
                    0.0
                }
            })
            .collect()
    }

    fn validate(&self) -> std::result::Result<(), String> {
        let cells = self.rows.saturating_mul(self.columns);
        if cells == 0 || cells > Self::MAX_CELLS || self.reference.len() != cells * 3 {
            return Err(format!(
                "input profile: a colour layout of {} x {} cells (at most {}) with {} values",
                self.columns,
                self.rows,
                Self::MAX_CELLS,
                self.reference.len()
            ));
        }
        if self.reference.iter().any(|v| !v.is_finite()) {
            return Err("input profile: the colour layout's values must be finite".into());
        }
        Ok(())
    }
}

/// The value at the 99.9th percentile of `v` (nearest rank; `v` not empty).
fn quantile_999(mut v: Vec<f32>) -> f32 {
    v.sort_by(f32::total_cmp);
    v[((v.len() - 1) as f64 * 0.999).round() as usize]
}

/// Where the descriptor reads a `width x height` frame: the one
/// definition of its regions, used by [`descriptor`] and by the standalone
/// ONNX export's graph of it.
#[derive(Debug, Clone, PartialEq)]
pub struct Regions {
    /// Pixels (row-major) inside the sensing window, away from its edge.
    pub window: Vec<bool>,
    /// Window pixels with four neighbours (where the fine texture, a
    /// Laplacian, is read).
    pub texture: Vec<bool>,
    /// Pixels of the dark housing, well outside the window.
    pub housing: Vec<bool>,
}

impl Regions {
    /// The regions of a `width x height` frame: in the inscribed ellipse's
    /// normalised radius r, the window is r^2 <= 0.8, the housing r^2 >= 1.3.
    pub fn of(width: usize, height: usize) -> Self {
        let n = width * height;
        let mut r = Self {
            window: vec![false; n],
            texture: vec![false; n],
            housing: vec![false; n],
        };
        for y in 0..height {
            let v = (y as f32 + 0.5) / height as f32 - 0.5;
            for x in 0..width {
                let i = y * width + x;
                let u = (x as f32 + 0.5) / width as f32 - 0.5;
                let r2 = 4.0 * (u * u + v * v);
                if r2 <= 0.8 {
                    r.window[i] = true;
                    r.texture[i] = x > 0 && y > 0 && x + 1 < width && y + 1 < height;
                } else if r2 >= 1.3 {
                    r.housing[i] = true;
                }
            }
        }
        r
    }
}

/// The descriptor of an RGB image in [0, 1] (at least 8 x 8).
pub fn descriptor(img: &FloatImage) -> Result<Vec<f32>> {
    let (w, h) = (img.width, img.height);
    if img.channels != 3 || w < 8 || h < 8 {
        return Err(Error::Channels {
            expected: 3,
            found: img.channels,
        });
    }
    let luma: Vec<f32> = img
        .data
        .chunks_exact(3)
        .map(|p| LUMA[0] * p[0] + LUMA[1] * p[1] + LUMA[2] * p[2])
        .collect();
    let regions = Regions::of(w, h);
    let (mut inside, mut outside) = (Vec::with_capacity(w * h), Vec::new());
    let mut texture = Vec::with_capacity(w * h);
    let mut rgb = [0f64; 3];
    for i in 0..w * h {
        if regions.window[i] {
            inside.push(luma[i]);
            for (c, acc) in rgb.iter_mut().enumerate() {
                *acc += img.data[i * 3 + c] as f64;
            }
        } else if regions.housing[i] {
            outside.push(luma[i]);
        }
        if regions.texture[i] {
            let lap = 4.0 * luma[i] - luma[i - 1] - luma[i + 1] - luma[i - w] - luma[i + w];
            texture.push(lap.abs());
        }
    }
    let n = inside.len().max(1) as f64;
    let mean_sd = |v: &[f32]| {
        let n = v.len().max(1) as f64;
        let m = v.iter().map(|&x| x as f64).sum::<f64>() / n;
        let var = v.iter().map(|&x| (x as f64 - m).powi(2)).sum::<f64>() / n;
        (m as f32, var.sqrt() as f32)
    };
    let (_, spread) = mean_sd(&inside);
    let (tex, _) = mean_sd(&texture);
    let (house, house_sd) = mean_sd(&outside);
    let [r, g, b] = rgb.map(|v| (v / n) as f32);
    Ok(vec![r, g, b, spread, tex, r - g, b - g, house, house_sd])
}

/// Whether a frame image is grey: one channel, or three equal in every
/// pixel (a camera in a mono mode, a grey picture given as RGB). A colour
/// camera's frame is never exactly grey: its channels' noise differs.
pub fn is_grey(img: &FloatImage) -> bool {
    match img.channels {
        1 => true,
        3 => img
            .data
            .chunks_exact(3)
            .all(|p| p[0] == p[1] && p[1] == p[2]),
        _ => false,
    }
}

/// Each training frame's [`layout_cells`] and the grid they were read on.
pub type LayoutCells<'a> = (&'a [Vec<f32>], (usize, usize));

/// The training frames' descriptors summarised: per statistic a centre
/// (median) and a scale (1.4826 x the median absolute deviation, at least
/// [`MIN_SCALE`]); a frame's score is its largest distance from the centre
/// in scales, and a frame scoring above `threshold` is out of distribution.
/// With a [`ColourLayout`], its two statistics follow
/// ([`LAYOUT_STATISTICS`], scaled with [`LAYOUT_MIN_SCALE`] and
/// [`TAIL_SCALES`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InputProfile {
    /// What each value is ([`DESCRIPTOR`], or [`pin_spectrum_names`] for
    /// a pin profile).
    pub names: Vec<String>,
    /// Per statistic, the training median.
    pub centre: Vec<f32>,
    /// Per statistic, the training spread.
    pub scale: Vec<f32>,
    /// Scores above this are out of distribution.
    pub threshold: f32,
    /// Training frames it was fitted on.
    pub frames: usize,
    /// The training frames' colour layout (absent in profiles written
    /// before it: the nine statistics alone).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layout: Option<ColourLayout>,
    /// The training frames were grey ([`is_grey`]: a camera in a mono
    /// mode); absent, they were in colour. A frame of the other mode
    /// than this is another camera's: its statistics may still lie near
    /// the training frames' (a grey copy of a colour frame keeps every
    /// mean), but the colour its models read is not there.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub grey_frames: bool,
}

impl InputProfile {
    /// One line for a person: how many frames it was fitted on and where it
    /// flags a frame.
    pub fn describe(&self) -> String {
        format!(
            "input profile of {} frames: flags scores above {:.1}",
            self.frames, self.threshold
        )
    }

    /// Fewest training frames a profile is fitted on.
    pub const MIN_FRAMES: usize = 20;

    /// Fit on the descriptors of the training frames: the threshold is
    /// `margin` times their 99.9th-percentile score (at least 6 scales).
    pub fn fit(descriptors: &[Vec<f32>], margin: f32) -> Result<Self> {
        Self::fit_frames(descriptors, None, margin)
    }

    /// [`Self::fit`], with the colour layout of `cells` (each frame's
    /// [`layout_cells`] on `grid`, in the order of `descriptors`) when
    /// given: its two statistics follow the nine.
    pub fn fit_frames(
        descriptors: &[Vec<f32>],
        cells: Option<LayoutCells<'_>>,
        margin: f32,
    ) -> Result<Self> {
        let k = DESCRIPTOR.len();
        if descriptors.len() < Self::MIN_FRAMES
            || descriptors.iter().any(|d| d.len() != k)
            || cells.is_some_and(|(c, _)| c.len() != descriptors.len())
        {
            return Err(Error::Core(tactile_core::Error::Invalid(format!(
                "an input profile needs at least {} frames with {k} statistics each, got {}",
                Self::MIN_FRAMES,
                descriptors.len()
            ))));
        }
        let layout = cells
            .map(|(c, grid)| ColourLayout::fit(c, grid))
            .transpose()?;
        let mut rows: Vec<Vec<f32>> = descriptors.to_vec();
        let mut names: Vec<String> = DESCRIPTOR.iter().map(|s| s.to_string()).collect();
        if let (Some(l), Some((cells, _))) = (&layout, cells) {
            for (row, c) in rows.iter_mut().zip(cells) {
                row.extend(l.of_cells(c));
            }
            names.extend(LAYOUT_STATISTICS.map(String::from));
        }
        let scale_of = |i: usize, mad: f32, dev: Vec<f32>| {
            if i < k {
                mad.max(MIN_SCALE)
            } else {
                mad.max(LAYOUT_MIN_SCALE)
                    .max(quantile_999(dev) / TAIL_SCALES)
            }
        };
        let mut p = Self::fit_rows(names, &rows, scale_of, margin);
        p.layout = layout;
        Ok(p)
    }

    /// Centre, scale (`scale_of` a statistic's index, its 1.4826 x MAD and
    /// its distances from the centre) and threshold of `rows` (one per
    /// frame, a value per name; at least one row).
    fn fit_rows(
        names: Vec<String>,
        rows: &[Vec<f32>],
        scale_of: impl Fn(usize, f32, Vec<f32>) -> f32,
        margin: f32,
    ) -> Self {
        let centre: Vec<f32> = (0..names.len())
            .map(|i| upper_median(rows.iter().map(|d| d[i]).collect()))
            .collect();
        let scale: Vec<f32> = (0..names.len())
            .map(|i| {
                let dev: Vec<f32> = rows.iter().map(|d| (d[i] - centre[i]).abs()).collect();
                scale_of(i, 1.4826 * upper_median(dev.clone()), dev)
            })
            .collect();
        let mut p = Self {
            names,
            centre,
            scale,
            threshold: f32::INFINITY,
            frames: rows.len(),
            layout: None,
            grey_frames: false,
        };
        let q = quantile_999(rows.iter().map(|d| p.score(d)).collect());
        p.threshold = (margin * q).max(MIN_THRESHOLD);
        p
    }

    /// A TacTip model's profile: fitted on the [`pin_spectrum`] of each of
    /// its training frames' pin images (at least [`Self::MIN_FRAMES`]),
    /// the threshold `margin` times their 99.9th-percentile score (at least
    /// 6 scales). A frame of another sensor, at another scale or of no
    /// pins at all has its power in other bands.
    pub fn fit_pins(spectra: &[Vec<f32>], margin: f32) -> Result<Self> {
        let names = pin_spectrum_names();
        if spectra.len() < Self::MIN_FRAMES || spectra.iter().any(|d| d.len() != names.len()) {
            return Err(Error::Core(tactile_core::Error::Invalid(format!(
                "a pin profile needs at least {} frames with {} statistics each, got {}",
                Self::MIN_FRAMES,
                names.len(),
                spectra.len()
            ))));
        }
        Ok(Self::fit_rows(
            names,
            spectra,
            |_, mad, _| mad.max(PIN_MIN_SCALE),
            margin,
        ))
    }

    /// The pin profile of a TacTip model's training pin images
    /// ([`Self::fit_pins`] with [`PIN_PROFILE_MARGIN`]), or `None` with
    /// fewer than [`Self::MIN_FRAMES`]: too few to tell its spread.
    pub fn of_training_pins(pins: &[&PinImage]) -> Result<Option<Self>> {
        if pins.len() < Self::MIN_FRAMES {
            return Ok(None);
        }
        let spectra = pin_spectra(pins);
        Self::fit_pins(&spectra, PIN_PROFILE_MARGIN).map(Some)
    }

    /// Whether it reads pin images ([`Self::fit_pins`], a TacTip model's)
    /// rather than colour frames (a detector's).
    pub fn reads_pins(&self) -> bool {
        self.names
            .first()
            .is_some_and(|n| n.starts_with(PIN_BAND_PREFIX))
    }

    /// A pin image's score against a pin profile ([`Self::fit_pins`]).
    pub fn score_pins(&self, pin: &PinImage) -> f32 {
        self.score(&pin_spectrum(pin))
    }

    /// The statistics of a frame this profile scores: the
    /// [`descriptor`], then the layout's two when it has a layout.
    pub fn statistics(&self, img: &FloatImage) -> Result<Vec<f32>> {
        let mut d = descriptor(img)?;
        if let Some(l) = &self.layout {
            d.extend(l.statistics(img)?);
        }
        Ok(d)
    }

    /// Whether `img` is of another camera mode than the training frames:
    /// grey ([`is_grey`]) to a profile of colour frames, or in colour to
    /// one of grey frames. A pin profile (a TacTip model's, whose pin
    /// images are grey) never tells.
    pub fn other_camera_mode(&self, img: &FloatImage) -> bool {
        !self.reads_pins() && is_grey(img) != self.grey_frames
    }

    /// A frame's score (see [`Self::score`]).
    pub fn score_frame(&self, img: &FloatImage) -> Result<f32> {
        Ok(self.score(&self.statistics(img)?))
    }

    /// How far a descriptor lies from the training frames: its largest
    /// distance from the centre, in scales.
    pub fn score(&self, descriptor: &[f32]) -> f32 {
        descriptor
            .iter()
            .zip(self.centre.iter().zip(&self.scale))
            .map(|(d, (c, s))| ((d - c) / s).abs())
            .fold(0.0, f32::max)
    }

    /// [`Self::validate`], and that it reads what its model reads: pin
    /// images when `pins` (a TacTip model's), else colour frames.
    pub fn validate_reading(&self, pins: bool) -> std::result::Result<(), String> {
        self.validate()?;
        match (pins, self.reads_pins()) {
            (true, false) => Err("input profile: one of colour frames (a detector's), where a TacTip model's reads pin images".into()),
            (false, true) => Err("input profile: one of pin images (a TacTip model's), where a detector's reads colour frames".into()),
            _ => Ok(()),
        }
    }

    /// Check a loaded profile: as many centres and scales as statistics,
    /// all finite, scales positive, a positive threshold.
    pub fn validate(&self) -> std::result::Result<(), String> {
        if let Some(l) = &self.layout {
            l.validate()?;
        }
        let k = if self.reads_pins() {
            if self.layout.is_some() || self.names != pin_spectrum_names() {
                return Err(format!(
                    "input profile: a pin profile reads the {} bands of a pin image's spectrum, in order, and no colour layout",
                    PIN_BANDS - 1
                ));
            }
            PIN_BANDS - 1
        } else {
            DESCRIPTOR.len() + self.layout.as_ref().map_or(0, |_| LAYOUT_STATISTICS.len())
        };
        if self.centre.len() != k || self.scale.len() != k {
            return Err(format!(
                "input profile: {} centres and {} scales, {k} statistics expected",
                self.centre.len(),
                self.scale.len()
            ));
        }
        if self.centre.iter().any(|v| !v.is_finite())
            || self.scale.iter().any(|v| !(v.is_finite() && *v > 0.0))
            || !(self.threshold.is_finite() && self.threshold > 0.0)
        {
            return Err(
                "input profile: centres must be finite, scales and the threshold positive".into(),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An 80 x 60 frame lit from three sides (red from the left, green from
    /// the top, blue from the right) at `gain`, with pixel noise from
    /// `seed` and, when `press`, a bright disc of radius 8 px.
    fn lit(gain: f32, seed: u64, press: bool) -> FloatImage {
        let (w, h) = (80, 60);
        let mut rng = tactile_core::rng::SampleRng::new(seed, 0, 0);
        let mut data = Vec::with_capacity(w * h * 3);
        for y in 0..h {
            for x in 0..w {
                let (u, v) = (x as f32 / w as f32, y as f32 / h as f32);
                let disc = press && (x as f32 - 40.0).hypot(y as f32 - 30.0) < 8.0;
                for base in [0.7 - 0.3 * u, 0.7 - 0.3 * v, 0.4 + 0.3 * u] {
                    let noise = 0.01 * rng.normal() as f32;
                    let p = if disc { 0.9 } else { base * gain + noise };
                    data.push(p.clamp(0.0, 1.0));
                }
            }
        }
        FloatImage {
            width: w,
            height: h,
            channels: 3,
            data,
        }
    }

    /// `img` made grey: each pixel's three channels their mean.
    fn grey_copy(img: &FloatImage) -> FloatImage {
        let data = img
            .data
            .chunks_exact(3)
            .flat_map(|p| [(p[0] + p[1] + p[2]) / 3.0; 3])
            .collect();
        FloatImage { data, ..*img }
    }

    /// A grey frame to a profile of colour frames is another camera mode,
    /// and a colour frame to one of grey frames; a pin profile never
    /// tells (its pin images are grey).
    #[test]
    fn a_frame_of_the_other_camera_mode_is_told() {
        let mut p = profile();
        let (colour, grey) = (lit(1.0, 7, true), grey_copy(&lit(1.0, 7, true)));
        assert!(is_grey(&grey) && !is_grey(&colour));
        assert!(!p.grey_frames, "fitted on colour frames");
        assert!(p.other_camera_mode(&grey) && !p.other_camera_mode(&colour));
        p.grey_frames = true;
        assert!(!p.other_camera_mode(&grey) && p.other_camera_mode(&colour));
        // Saved only when set: profiles saved before read as colour ones.
        let json = serde_json::to_string(&p).unwrap();
        assert!(json.contains("\"grey_frames\":true"), "{json}");
        p.grey_frames = false;
        let json = serde_json::to_string(&p).unwrap();
        assert!(!json.contains("grey_frames"), "{json}");
        let pins =
            InputProfile::fit_pins(&vec![vec![1.0; pin_spectrum_names().len()]; 30], 1.5).unwrap();
        assert!(!pins.other_camera_mode(&grey) && !pins.other_camera_mode(&colour));
    }

    fn profile() -> InputProfile {
        let frames: Vec<FloatImage> = (0..60)
            .map(|i| lit(0.8 + 0.4 * (i % 7) as f32 / 6.0, i, i % 3 == 0))
            .collect();
        let d: Vec<Vec<f32>> = frames.iter().map(|f| descriptor(f).unwrap()).collect();
        let c: Vec<Vec<f32>> = frames
            .iter()
            .map(|f| layout_cells(f, LAYOUT_GRID).unwrap())
            .collect();
        InputProfile::fit_frames(&d, Some((&c, LAYOUT_GRID)), 1.5).unwrap()
    }

    /// A `side` px pin image of round pins on a hexagonal lattice of
    /// `pitch` px, moved by `shift` px and each pin by up to `jitter` px
    /// (a contact), from `seed`.
    fn lattice(side: usize, pitch: f32, shift: f32, jitter: f32, seed: u64) -> PinImage {
        let mut rng = tactile_core::rng::SampleRng::new(seed, 1, 0);
        let mut centres = Vec::new();
        let rows = (side as f32 / (pitch * 0.866)) as i32 + 2;
        for r in -1..rows {
            for c in -1..(side as f32 / pitch) as i32 + 2 {
                let x = c as f32 * pitch + if r % 2 == 0 { 0.0 } else { pitch / 2.0 };
                let y = r as f32 * pitch * 0.866;
                let j = jitter * rng.normal() as f32;
                centres.push((x + shift + j, y + shift - j));
            }
        }
        let radius = pitch / 4.0;
        let pixels = (0..side * side)
            .map(|i| {
                let (x, y) = ((i % side) as f32, (i / side) as f32);
                let on = centres
                    .iter()
                    .any(|(cx, cy)| (x - cx).hypot(y - cy) <= radius);
                f32::from(u8::from(on))
            })
            .collect();
        PinImage { side, pixels }
    }

    #[test]
    fn a_pin_profile_knows_its_pins_spacing_wherever_they_move() {
        let own: Vec<PinImage> = (0..40)
            .map(|i| lattice(64, 8.0, (i % 8) as f32, 0.3 + 0.1 * (i % 5) as f32, i))
            .collect();
        let p = InputProfile::of_training_pins(&own.iter().collect::<Vec<_>>())
            .unwrap()
            .unwrap();
        p.validate_reading(true).unwrap();
        assert!(p.reads_pins() && p.validate_reading(false).is_err());
        assert_eq!(p.frames, 40);
        // Its own pins moved by a new contact: theirs.
        for seed in 100..110 {
            let f = lattice(64, 8.0, 2.5, 0.6, seed);
            let s = p.score_pins(&f);
            assert!(s <= p.threshold, "own pins scored {s} > {}", p.threshold);
        }
        // Pins twice as dense or far apart (another sensor, or this one
        // at another scale), noise, and a frame without pins: not theirs.
        let mut rng = tactile_core::rng::SampleRng::new(7, 2, 0);
        let noise = PinImage {
            side: 64,
            pixels: (0..64 * 64)
                .map(|_| f32::from(u8::from(rng.normal() > 0.0)))
                .collect(),
        };
        let mut blob = lattice(64, 64.0, 32.0, 0.0, 1);
        blob.pixels.iter_mut().step_by(7).for_each(|v| *v = 0.0);
        for (what, f) in [
            ("denser", lattice(64, 4.0, 0.0, 0.2, 1)),
            ("sparser", lattice(64, 16.0, 0.0, 0.5, 1)),
            ("noise", noise),
            ("one blob", blob),
        ] {
            let s = p.score_pins(&f);
            assert!(s > p.threshold, "{what} scored {s} <= {}", p.threshold);
        }
        // Too few frames to tell a spread: no profile.
        assert!(
            InputProfile::of_training_pins(&own.iter().take(19).collect::<Vec<_>>())
                .unwrap()
                .is_none()
        );
        // A detector's profile is not a TacTip model's, nor the reverse.
        let det = profile();
        assert!(!det.reads_pins() && det.validate_reading(true).is_err());
        let mut renamed = p.clone();
        renamed.names[3] = "window mean red".into();
        assert!(renamed.validate().is_err());
    }

    #[test]
    fn layout_cells_ignore_exposure_and_white_balance() {
        let a = layout_cells(&lit(1.0, 1, false), LAYOUT_GRID).unwrap();
        let mut f = lit(1.0, 1, false);
        for p in f.data.chunks_exact_mut(3) {
            p[0] *= 0.7;
            p[2] *= 0.9;
        }
        let b = layout_cells(&f, LAYOUT_GRID).unwrap();
        assert_eq!(a.len(), 16 * 12 * 3);
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-4, "{x} {y}");
        }
        let tiny = FloatImage {
            width: 8,
            height: 8,
            channels: 3,
            data: vec![0.5; 192],
        };
        assert!(layout_cells(&tiny, LAYOUT_GRID).is_err());
    }

    #[test]
    fn the_layout_flags_another_led_order_but_not_exposure_or_a_press() {
        let p = profile();
        assert_eq!(p.names[9..], LAYOUT_STATISTICS.map(String::from));
        p.validate().unwrap();
        // The sensor at another exposure, and pressed: its own.
        for f in [lit(1.15, 99, false), lit(0.85, 98, true)] {
            let s = p.score_frame(&f).unwrap();
            assert!(s <= p.threshold, "own frame scored {s} > {}", p.threshold);
        }
        // The same frame with its LEDs in another order: the global
        // statistics hardly move, the layout does.
        let own = lit(1.0, 97, false);
        let mut rotated = own.clone();
        for px in rotated.data.chunks_exact_mut(3) {
            px.rotate_left(1);
        }
        let s = p.score_frame(&rotated).unwrap();
        assert!(
            s > p.threshold,
            "rotated LEDs scored {s} <= {}",
            p.threshold
        );
        let stats = p.statistics(&rotated).unwrap();
        let worst = (0..stats.len())
            .max_by(|&a, &b| {
                let z = |i: usize| ((stats[i] - p.centre[i]) / p.scale[i]).abs();
                z(a).total_cmp(&z(b))
            })
            .unwrap();
        assert!(LAYOUT_STATISTICS.contains(&p.names[worst].as_str()));
        // A darker gel of half the contrast: the layout's contrast falls.
        let mut flat = own.clone();
        for v in &mut flat.data {
            *v = *v * 0.5 + 0.16;
        }
        let stats = p.statistics(&flat).unwrap();
        let z = |i: usize| ((stats[i] - p.centre[i]) / p.scale[i]).abs();
        assert!(
            z(10) > p.threshold,
            "contrast {} scored {}",
            stats[10],
            z(10)
        );
        assert!((0.5..0.8).contains(&stats[10]), "contrast {}", stats[10]);
    }

    #[test]
    fn profiles_written_before_the_layout_still_load() {
        let mut p = profile();
        p.layout = None;
        for v in [&mut p.centre, &mut p.scale] {
            v.truncate(9);
        }
        p.names.truncate(9);
        let json = serde_json::to_string(&p).unwrap();
        assert!(!json.contains("layout"));
        let back: InputProfile = serde_json::from_str(&json).unwrap();
        back.validate().unwrap();
        assert_eq!(back.statistics(&lit(1.0, 5, false)).unwrap().len(), 9);
        // A layout whose size does not match its values is refused.
        let mut bad = profile();
        if let Some(l) = &mut bad.layout {
            l.rows = 1 << 40;
        }
        assert!(bad.validate().is_err());
    }
}
