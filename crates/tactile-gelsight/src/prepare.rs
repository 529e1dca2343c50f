//! A frame and the background as the sensor model sees them: both shrunk
//! by area averaging to the working resolution (`factor` frame pixels per
//! working pixel), the frame's exposure matched to the background's (each
//! channel's median), then channels first: the colour change, the
//! background's colour, and the position. Used alike by calibration,
//! reconstruction and the circle finder.

use serde::{Deserialize, Serialize};
use tactile_core::image_io::RgbImage;
use tactile_preprocess::shrink_rgb_by;

use crate::Result;

/// Input channels of the sensor model.
pub const FEATURES: usize = 8;
/// The colour change is multiplied by this so it spans about [-1, 1].
pub const DIFF_GAIN: f32 = 4.0;
/// Largest shrink factor.
pub const MAX_FACTOR: usize = 16;
/// A frame whose channels differ by less than this many grey levels on
/// average is grey (a JPEG of a grey picture stays below it).
pub const GREY_SPREAD: f32 = 1.0;
/// A background whose channels differ by more than this many grey levels
/// on average is a colour sensor's (GelSight's lights colour every pixel:
/// the R1.5's background spreads 20 levels).
pub const COLOUR_SPREAD: f32 = 4.0;

/// How far apart a picture's channels are: each pixel's largest less its
/// smallest channel, in grey levels, averaged over every 7th pixel (a
/// spread spans the picture; checked per frame, it costs a seventh).
pub fn colour_spread(img: &RgbImage) -> f32 {
    let (mut sum, mut n) = (0u64, 0u64);
    for p in img.as_slice().chunks_exact(3).step_by(7) {
        sum += u64::from(p.iter().max().unwrap_or(&0) - p.iter().min().unwrap_or(&0));
        n += 1;
    }
    (sum as f64 / n.max(1) as f64) as f32
}

/// True for a colour sensor's rest frame ([`COLOUR_SPREAD`]): grey frames
/// are refused against it.
pub fn is_colour_background(background: &RgbImage) -> bool {
    colour_spread(background) > COLOUR_SPREAD
}

/// A frame whose channels differ by more than this many grey levels on
/// average is a colour sensor's, however its background looks: twice the
/// spread a grey background may have, so a grey sensor's frames, tinted as
/// its background is, stay below it.
pub const COLOUR_FRAME_SPREAD: f32 = 2.0 * COLOUR_SPREAD;

/// Refuse a blank `frame` (named `path`): one colour (black, saturated),
/// by the rule the detector's blank gate keeps
/// ([`tactile_preprocess::visuo::is_blank_levels`]). Such a frame is grey,
/// or a colour, by accident, and is named for what it is.
pub fn check_not_blank(path: &std::path::Path, frame: &RgbImage) -> Result<()> {
    if !tactile_preprocess::visuo::is_blank_levels(frame.as_slice(), 3) {
        return Ok(());
    }
    let level = match frame.as_slice() {
        [r, g, b, ..] => format!("RGB ({r}, {g}, {b})"),
        _ => "no pixel".into(),
    };
    Err(crate::Error::BlankFrame {
        path: path.to_path_buf(),
        level,
    })
}

/// Refuse a blank `frame` (named `path`, [`check_not_blank`]), a grey one for a sensor calibrated on colour
/// frames (`colour`): its colour change would be read as slopes that are
/// not there, a depth of nothing. Refuse a colour frame for a sensor whose
/// background is grey too: the background is then not this camera's rest
/// frame as it records it (a grey copy), or the frame is another sensor's,
/// and every colour change would be read against the wrong rest.
pub fn check_colour(path: &std::path::Path, frame: &RgbImage, colour: bool) -> Result<()> {
    check_not_blank(path, frame)?;
    let spread = colour_spread(frame);
    if colour && spread < GREY_SPREAD {
        return Err(crate::Error::GreyFrame {
            path: path.to_path_buf(),
        });
    }
    if !colour && spread > COLOUR_FRAME_SPREAD {
        return Err(crate::Error::ColourFrame {
            path: path.to_path_buf(),
            spread,
        });
    }
    Ok(())
}

/// A frame whose median colour change from the background, its red and
/// blue swapped back, is below this fraction of its change as given is in
/// BGR order ([`PreparedBackground::swapped_channels`]): the R1.5's
/// presses are 2.9-6.8 times nearer as given, in either order.
pub const SWAPPED_CHANGE_RATIO: f32 = 0.5;

/// The working resolution of a sensor of `width x height` frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct WorkingGrid {
    /// Frame width, pixels.
    pub frame_width: usize,
    /// Frame height, pixels.
    pub frame_height: usize,
    /// Frame pixels per working pixel, along each axis.
    pub factor: usize,
}

impl WorkingGrid {
    /// Working width.
    pub fn width(&self) -> usize {
        self.frame_width / self.factor
    }

    /// Working height.
    pub fn height(&self) -> usize {
        self.frame_height / self.factor
    }

    /// The frame-pixel coordinate of working pixel `i`'s centre (frame
    /// pixel `k`'s centre is `k`).
    pub fn frame_coord(&self, i: f64) -> f64 {
        i * self.factor as f64 + (self.factor as f64 - 1.0) / 2.0
    }

    /// Millimetres per working pixel on a sensor of `mm_per_px`.
    pub fn step_mm(&self, mm_per_px: f64) -> f32 {
        (self.factor as f64 * mm_per_px) as f32
    }

    /// Check the frame against 8K and the factor against the frame.
    pub fn check(&self) -> tactile_core::Result<()> {
        let max = tactile_core::image_io::MAX_IMAGE_PIXELS;
        if (self.frame_width as u64).saturating_mul(self.frame_height as u64) > max {
            return Err(tactile_core::Error::Config(format!(
                "grid: a {}x{} frame is larger than 8K ({max} pixels)",
                self.frame_width, self.frame_height
            )));
        }
        if self.factor == 0 || self.factor > MAX_FACTOR || self.width() < 8 || self.height() < 8 {
            return Err(tactile_core::Error::Config(format!(
                "factor {} must be 1-{MAX_FACTOR} and leave at least 8x8 working pixels of a {}x{} frame",
                self.factor, self.frame_width, self.frame_height
            )));
        }
        Ok(())
    }
}

/// An RGB frame at the working resolution: interleaved values in [0, 1].
#[derive(Debug, Clone)]
pub struct WorkingImage {
    /// The grid.
    pub grid: WorkingGrid,
    /// `height * width * 3` values.
    pub rgb: Vec<f32>,
}

impl WorkingImage {
    /// `frame` shrunk to `grid` (cropping the remainder at the right and
    /// bottom).
    pub fn of(frame: &RgbImage, grid: WorkingGrid) -> Result<Self> {
        let rgb = shrink_rgb_by(
            frame.as_slice(),
            (frame.width(), frame.height()),
            grid.factor,
        )?;
        Ok(Self { grid, rgb })
    }

    /// Each channel's median.
    pub fn medians(&self) -> [f32; 3] {
        let mut out = [0.0; 3];
        for (c, m) in out.iter_mut().enumerate() {
            *m = upper_median(self.rgb.iter().skip(c).step_by(3).copied().collect());
        }
        out
    }

    /// The same image with each channel scaled so its median is `to`'s (a
    /// frame taken at another exposure than the background); a channel
    /// darker than one grey level is left alone.
    pub fn matched_to(&self, to: [f32; 3]) -> Self {
        let m = self.medians();
        let gain: Vec<f32> = (0..3)
            .map(|c| {
                if m[c] > 1.0 / 255.0 {
                    to[c] / m[c]
                } else {
                    1.0
                }
            })
            .collect();
        Self {
            grid: self.grid,
            rgb: self
                .rgb
                .iter()
                .enumerate()
                .map(|(i, v)| v * gain[i % 3])
                .collect(),
        }
    }
}

/// The middle value of `v` (the upper one of an even count), found
/// without sorting; 0 for none.
fn upper_median(mut v: Vec<f32>) -> f32 {
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f32::total_cmp).1
}

/// The background at the working resolution, with its medians.
#[derive(Debug, Clone)]
pub struct PreparedBackground {
    /// The shrunk background.
    pub image: WorkingImage,
    /// Its channel medians.
    pub medians: [f32; 3],
    /// It is a colour sensor's ([`is_colour_background`]).
    pub colour: bool,
}

impl PreparedBackground {
    /// Shrink `background` to `grid`.
    pub fn new(background: &RgbImage, grid: WorkingGrid) -> Result<Self> {
        let image = WorkingImage::of(background, grid)?;
        let medians = image.medians();
        Ok(Self {
            image,
            medians,
            colour: is_colour_background(background),
        })
    }

    /// A frame's exposure-matched working image.
    pub fn matched(&self, frame: &RgbImage) -> Result<WorkingImage> {
        Ok(WorkingImage::of(frame, self.image.grid)?.matched_to(self.medians))
    }

    /// The model's input for an exposure-matched frame: `[FEATURES, h, w]`
    /// channels first (colour change x [`DIFF_GAIN`], background - 0.5,
    /// x and y in [-1, 1]).
    pub fn features(&self, frame: &WorkingImage) -> Vec<f32> {
        let g = self.image.grid;
        let (w, h) = (g.width(), g.height());
        let n = w * h;
        let mut out = vec![0f32; FEATURES * n];
        for p in 0..n {
            for c in 0..3 {
                let (f, b) = (frame.rgb[p * 3 + c], self.image.rgb[p * 3 + c]);
                out[c * n + p] = (f - b) * DIFF_GAIN;
                out[(3 + c) * n + p] = b - 0.5;
            }
            let (x, y) = (p % w, p / w);
            out[6 * n + p] = 2.0 * (x as f32 + 0.5) / w as f32 - 1.0;
            out[7 * n + p] = 2.0 * (y as f32 + 0.5) / h as f32 - 1.0;
        }
        out
    }

    /// The median over working pixels of a frame's colour change from the
    /// background ([`Self::change`]), on its exposure-matched working image
    /// ([`Self::matched`]): a frame of this sensor changes colour only where
    /// the skin is pressed, so half of it or more stays near 0 (noise),
    /// while a frame of another sensor differs throughout.
    pub fn median_change(&self, frame: &WorkingImage) -> f32 {
        upper_median(self.change(frame))
    }

    /// The median colour changes of an exposure-matched `frame` as given
    /// and with its red and blue swapped back, when swapped back it lies
    /// much nearer this background ([`SWAPPED_CHANGE_RATIO`]): a frame in
    /// BGR order (OpenCV's `imread` and `VideoCapture` give frames so),
    /// whose colours the model would read as slopes mirrored. A GelSight's
    /// lights colour each side of the picture differently, so a swap
    /// changes its colours throughout; the 32 presses of the R1.5 change
    /// 0.012-0.030 as given and 0.069-0.101 swapped. `None` for a grey
    /// sensor, or a frame nearer as given.
    pub fn swapped_channels(&self, frame: &WorkingImage) -> Option<(f32, f32)> {
        if !self.colour {
            return None;
        }
        let given = self.median_change(frame);
        let mut back = frame.clone();
        back.rgb.chunks_exact_mut(3).for_each(|p| p.swap(0, 2));
        let back = self.median_change(&back.matched_to(self.medians));
        (back < SWAPPED_CHANGE_RATIO * given).then_some((given, back))
    }

    /// Refuse an exposure-matched `frame` (named `path`) in BGR order
    /// ([`Self::swapped_channels`]): its colours would be read as slopes
    /// mirrored, a wrong skin without a word.
    pub fn check_channel_order(&self, frame: &WorkingImage, path: &std::path::Path) -> Result<()> {
        match self.swapped_channels(frame) {
            Some((given, swapped)) => Err(crate::Error::SwappedChannels {
                path: path.to_path_buf(),
                given,
                swapped,
            }),
            None => Ok(()),
        }
    }

    /// The colour change's size per working pixel (the circle finder's
    /// evidence of contact).
    pub fn change(&self, frame: &WorkingImage) -> Vec<f32> {
        frame
            .rgb
            .chunks_exact(3)
            .zip(self.image.rgb.chunks_exact(3))
            .map(|(f, b)| {
                ((f[0] - b[0]).powi(2) + (f[1] - b[1]).powi(2) + (f[2] - b[2]).powi(2)).sqrt()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reconstruct::REST_CHANGE_LIMIT;
    use tactile_core::image_io::rgb_image;

    /// A 64x48 frame whose pixel (x, y) is `f(x, y)`.
    fn frame(f: impl Fn(usize, usize) -> [u8; 3]) -> RgbImage {
        let (w, h) = (64, 48);
        let data = (0..w * h).flat_map(|i| f(i % w, i / w)).collect();
        rgb_image(w, h, data).unwrap()
    }

    /// The 64x48 frames' working grid.
    const GRID: WorkingGrid = WorkingGrid {
        frame_width: 64,
        frame_height: 48,
        factor: 4,
    };

    /// A rest frame lit red from the left and blue from the right, as a
    /// GelSight's lights colour its sides.
    fn lit(x: usize, y: usize) -> [u8; 3] {
        [90 + x as u8, 120 + y as u8, 200 - x as u8]
    }

    #[test]
    fn only_a_frame_changed_over_half_its_picture_is_far_from_the_rest_frame() {
        let bg = PreparedBackground::new(&frame(lit), GRID).unwrap();
        let change = |f: &RgbImage| bg.median_change(&bg.matched(f).unwrap());
        // At rest, at another exposure, and pressed over a third of the
        // picture (a big contact: lit on the side facing one light, shaded
        // on the other, 40 levels each way, which moves the exposure
        // matching's medians too): well below the limit.
        assert!(change(&frame(lit)) < 1e-6);
        assert!(change(&frame(|x, y| lit(x, y).map(|v| (v as f32 * 0.8) as u8))) < 0.01);
        let pressed = frame(|x, y| {
            lit(x, y).map(|v| match (x < 22, y < 24) {
                (false, _) => v,
                (true, true) => v.saturating_add(40),
                (true, false) => v - 40,
            })
        });
        assert!(
            change(&pressed) < REST_CHANGE_LIMIT / 2.0,
            "{}",
            change(&pressed)
        );
        // Another picture throughout: far above the limit.
        let other = frame(|x, y| {
            let v = if (x / 4 + y / 4) % 2 == 0 { 30 } else { 220 };
            [v, v, v]
        });
        assert!(change(&other) > REST_CHANGE_LIMIT, "{}", change(&other));
    }

    #[test]
    fn a_frame_in_bgr_order_is_told_from_its_colours() {
        let bg = PreparedBackground::new(&frame(lit), GRID).unwrap();
        let swapped = |f: &RgbImage| bg.swapped_channels(&bg.matched(f).unwrap());
        let bgr = |f: &RgbImage| {
            let mut v = f.as_slice().to_vec();
            v.chunks_exact_mut(3).for_each(|p| p.swap(0, 2));
            rgb_image(f.width(), f.height(), v).unwrap()
        };
        // A pressed frame at another exposure as given: not swapped; the
        // same in BGR order: swapped, far nearer once swapped back.
        let pressed = frame(|x, y| {
            lit(x, y).map(|v| match x < 22 && y < 24 {
                true => (v as f32 * 0.8) as u8 + 30,
                false => (v as f32 * 0.8) as u8,
            })
        });
        assert_eq!(swapped(&pressed), None);
        let (given, back) = swapped(&bgr(&pressed)).unwrap();
        assert!(back < SWAPPED_CHANGE_RATIO * given, "{back} {given}");
        // A grey sensor has no order to tell.
        let grey = PreparedBackground::new(&frame(|x, _| [x as u8 * 3; 3]), GRID).unwrap();
        assert!(!grey.colour);
        assert_eq!(
            grey.swapped_channels(&grey.matched(&bgr(&pressed)).unwrap()),
            None
        );
    }
}
