//! Visuo-tactile frames (paper B) as model inputs: resizing, the
//! segmenter's rotated square window, tendon masks, and per-channel
//! normalisation with training-set statistics.
//!
//! Images here are interleaved `H x W x C` `f32` in [0, 1] until
//! [`ChannelStats::to_chw`] turns them into a normalised `C x H x W` input.

use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use tactile_core::image_io::{GreyImage, RgbImage};

use crate::resize_area_interleaved;

/// Largest frame accepted, in pixels (8K UHD): bigger inputs are rejected
/// before any buffer is allocated for them.
pub const MAX_FRAME_PIXELS: usize = 7680 * 4320;

/// Bits per channel a model's input may be held at.
pub const INPUT_BITS: [u8; 2] = [8, 16];

/// The top level of a `bits`-bit code (`bits` is 8 or 16; anything else
/// counts as 16).
fn level_max(bits: u8) -> f32 {
    if bits == 8 { 255.0 } else { 65535.0 }
}

/// An interleaved float image.
#[derive(Debug, Clone, PartialEq)]
pub struct FloatImage {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// Values per pixel.
    pub channels: usize,
    /// `height * width * channels` values in [0, 1], interleaved.
    pub data: Vec<f32>,
}

impl FloatImage {
    /// A float image in [0, 1] from interleaved 8-bit values.
    pub fn from_bytes(width: usize, height: usize, channels: usize, bytes: &[u8]) -> Self {
        Self {
            width,
            height,
            channels,
            data: bytes.iter().map(|&v| v as f32 / 255.0).collect(),
        }
    }

    /// The values rounded to 8 bits (clamped to [0, 1]): how every model's
    /// training set holds its frames in memory.
    pub fn to_bytes(&self) -> Vec<u8> {
        self.data
            .iter()
            .map(|&v| (v * 255.0).round().clamp(0.0, 255.0) as u8)
            .collect()
    }

    /// The image as a model was trained on it: 8 bits per channel, as the
    /// training sets store frames. Every model's inference input goes
    /// through this, so a frame gets the same answer in `tactile run` as in
    /// `tactile eval` (without it, the detector's probabilities differed by
    /// up to 0.07 on onset frames).
    pub fn quantised(&self) -> Self {
        Self::from_bytes(self.width, self.height, self.channels, &self.to_bytes())
    }

    /// The values as whole levels of a `bits`-bit code (8 or 16; clamped
    /// to [0, 1]): 16 bits keep the fraction of a grey level that averaging
    /// a frame down to a model's input recovers from its noise.
    pub fn to_levels(&self, bits: u8) -> Vec<u16> {
        let top = level_max(bits);
        self.data
            .iter()
            .map(|&v| (v * top).round().clamp(0.0, top) as u16)
            .collect()
    }

    /// A float image in [0, 1] from interleaved levels of a `bits`-bit code.
    pub fn from_levels(
        width: usize,
        height: usize,
        channels: usize,
        levels: &[u16],
        bits: u8,
    ) -> Self {
        let top = level_max(bits);
        Self {
            width,
            height,
            channels,
            data: levels.iter().map(|&v| v as f32 / top).collect(),
        }
    }

    /// The image rounded to `bits` bits per channel, as a model trained on
    /// frames held at that precision saw them ([`Self::quantised`] for 8).
    pub fn quantised_to(&self, bits: u8) -> Self {
        Self::from_levels(
            self.width,
            self.height,
            self.channels,
            &self.to_levels(bits),
            bits,
        )
    }

    fn at(&self, x: isize, y: isize, c: usize) -> f32 {
        if x < 0 || y < 0 || x >= self.width as isize || y >= self.height as isize {
            0.0
        } else {
            self.data[(y as usize * self.width + x as usize) * self.channels + c]
        }
    }
}

fn check_size(width: usize, height: usize) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(Error::ImageSize {
            width,
            height,
            why: "empty".into(),
        });
    }
    if width.saturating_mul(height) > MAX_FRAME_PIXELS {
        return Err(Error::ImageSize {
            width,
            height,
            why: format!("larger than 8K ({MAX_FRAME_PIXELS} pixels)"),
        });
    }
    Ok(())
}

/// Resize interleaved 8-bit pixels to `width x height`: the mean over each
/// output pixel's footprint when shrinking on both axes (no aliasing of
/// thin ridges), bilinear with half-pixel centres otherwise.
pub fn resize_u8(
    src: &[u8],
    (w, h, c): (usize, usize, usize),
    width: usize,
    height: usize,
) -> Result<FloatImage> {
    check_size(w, h)?;
    check_size(width, height)?;
    let data = if width <= w && height <= h {
        resize_area_interleaved(src, (w, h, c), width, height)?
    } else {
        let f = FloatImage::from_bytes(w, h, c, src);
        let (sx, sy) = (w as f64 / width as f64, h as f64 / height as f64);
        let mut out = Vec::with_capacity(width * height * c);
        for y in 0..height {
            let fy = ((y as f64 + 0.5) * sy - 0.5).clamp(0.0, (h - 1) as f64);
            for x in 0..width {
                let fx = ((x as f64 + 0.5) * sx - 0.5).clamp(0.0, (w - 1) as f64);
                for ch in 0..c {
                    out.push(bilinear(&f, fx, fy, ch, true));
                }
            }
        }
        out
    };
    Ok(FloatImage {
        width,
        height,
        channels: c,
        data,
    })
}

/// Bilinear sample at `(x, y)`; outside the image counts as 0 unless
/// `clamp_edges` holds the border pixels.
fn bilinear(img: &FloatImage, x: f64, y: f64, c: usize, clamp_edges: bool) -> f32 {
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
    let (mut x0, mut y0) = (x0 as isize, y0 as isize);
    let (mut x1, mut y1) = (x0 + 1, y0 + 1);
    if clamp_edges {
        let (mw, mh) = (img.width as isize - 1, img.height as isize - 1);
        x0 = x0.clamp(0, mw);
        x1 = x1.clamp(0, mw);
        y0 = y0.clamp(0, mh);
        y1 = y1.clamp(0, mh);
    }
    img.at(x0, y0, c) * (1.0 - fx) * (1.0 - fy)
        + img.at(x1, y0, c) * fx * (1.0 - fy)
        + img.at(x0, y1, c) * (1.0 - fx) * fy
        + img.at(x1, y1, c) * fx * fy
}

/// Frames at least twice this tall are first brought down to about it by
/// [`working_frame`]: the height of the virtual sensor's frames (640 x 360,
/// a third of the native 1920 x 1080) the shipped models were trained on.
pub const WORKING_HEIGHT: usize = 360;

/// The frame every model of the pipeline takes its input from: a frame at
/// least twice `working_height` tall is box-averaged by the largest whole
/// factor `k` that keeps it at least that tall (1920 x 1080 becomes
/// 640 x 360), once, with a SIMD resizer; smaller frames are used as they
/// are (`None`). The models' own resizes then read a few hundred thousand
/// pixels instead of millions, three times.
pub fn working_frame(frame: &RgbImage, working_height: usize) -> Result<Option<RgbImage>> {
    use fast_image_resize as fr;
    let (w, h) = (frame.width(), frame.height());
    check_size(w, h)?;
    let k = h / working_height.max(1);
    if k < 2 {
        return Ok(None);
    }
    let (dw, dh) = ((w / k).max(1), h / k);
    let fail = |e: String| Error::Kornia(format!("working frame {w}x{h} to {dw}x{dh}: {e}"));
    let src = fr::images::ImageRef::new(w as u32, h as u32, frame.as_slice(), fr::PixelType::U8x3)
        .map_err(|e| fail(e.to_string()))?;
    let mut dst = fr::images::Image::new(dw as u32, dh as u32, fr::PixelType::U8x3);
    let options =
        fr::ResizeOptions::new().resize_alg(fr::ResizeAlg::Convolution(fr::FilterType::Box));
    fr::Resizer::new()
        .resize(&src, &mut dst, &options)
        .map_err(|e| fail(e.to_string()))?;
    Ok(Some(tactile_core::image_io::rgb_image(
        dw,
        dh,
        dst.into_vec(),
    )?))
}

/// An RGB frame resized to `width x height`.
pub fn resize_rgb(img: &RgbImage, width: usize, height: usize) -> Result<FloatImage> {
    resize_u8(
        img.as_slice(),
        (img.width(), img.height(), 3),
        width,
        height,
    )
}

/// A grey image (a mask) resized to `width x height`.
pub fn resize_grey(img: &GreyImage, width: usize, height: usize) -> Result<FloatImage> {
    resize_u8(
        img.as_slice(),
        (img.width(), img.height(), 1),
        width,
        height,
    )
}

/// How the segmenter looks at a frame: a square window of `side` pixels
/// cut from the frame's centre after scaling the frame so that its height
/// is `side * sqrt(2)`. Any rotation of that square about the centre stays
/// inside the scaled frame, so rotated copies (paper B's augmentation) have
/// no empty corners.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SquareWindow {
    /// Side of the window, pixels.
    pub side: usize,
}

impl SquareWindow {
    /// Size the frame is scaled to before the cut, for a `w x h` frame:
    /// its shorter side to the window's diagonal, its aspect kept, so a
    /// direction in the window is the direction in the frame (a portrait
    /// frame too; before, it was stretched square).
    pub fn scaled_size(&self, w: usize, h: usize) -> (usize, usize) {
        let short = (self.side as f64 * std::f64::consts::SQRT_2).ceil() as usize;
        let long = |a: usize, b: usize| {
            ((a as f64 * short as f64 / b.max(1) as f64).round() as usize).max(short)
        };
        match w >= h {
            true => (long(w, h), short),
            false => (short, long(h, w)),
        }
    }

    /// Scale factor from frame pixels to window pixels.
    pub fn scale(&self, w: usize, h: usize) -> f64 {
        let (sw, sh) = self.scaled_size(w, h);
        // The shorter side's, scaled exactly (the longer is rounded).
        match w >= h {
            true => sh as f64 / h.max(1) as f64,
            false => sw as f64 / w.max(1) as f64,
        }
    }

    /// Where the centre of pixel `(u, v)` of a `w x h` frame falls in the
    /// (unrotated) window, in window pixels: the inverse of scaling the
    /// frame and cutting the window. Outside `[0, side)` the window does
    /// not see that pixel.
    pub fn frame_to_window(&self, (u, v): (f64, f64), (w, h): (usize, usize)) -> (f64, f64) {
        let (sw, sh) = self.scaled_size(w, h);
        let sx = (u + 0.5) * sw as f64 / w.max(1) as f64 - 0.5;
        let sy = (v + 0.5) * sh as f64 / h.max(1) as f64 - 0.5;
        let half = (self.side as f64 - 1.0) / 2.0;
        (
            sx - (sw as f64 - 1.0) / 2.0 + half,
            sy - (sh as f64 - 1.0) / 2.0 + half,
        )
    }

    /// The window of an image already scaled by [`Self::scaled_size`],
    /// rotated by `deg` about its centre (bilinear; masks are thresholded
    /// by the caller).
    pub fn cut(&self, scaled: &FloatImage, deg: f64) -> FloatImage {
        let s = self.side;
        let c = scaled.channels;
        let (cx, cy) = (
            (scaled.width as f64 - 1.0) / 2.0,
            (scaled.height as f64 - 1.0) / 2.0,
        );
        let (sin, cos) = deg.to_radians().sin_cos();
        let half = (s as f64 - 1.0) / 2.0;
        let mut data = Vec::with_capacity(s * s * c);
        for y in 0..s {
            for x in 0..s {
                let (u, v) = (x as f64 - half, y as f64 - half);
                // Output pixel (u, v) shows the input point rotated by -deg.
                let (px, py) = (cos * u + sin * v + cx, -sin * u + cos * v + cy);
                for ch in 0..c {
                    data.push(bilinear(scaled, px, py, ch, false));
                }
            }
        }
        FloatImage {
            width: s,
            height: s,
            channels: c,
            data,
        }
    }
}

/// Standard deviation (in [0, 1] units, of each channel) below which a
/// frame is blank: half a grey level, under the sensor's own noise.
pub const BLANK_FRAME_STD: f32 = 0.5 / 255.0;

/// True when no channel of the image varies (black, saturated, one colour
/// of any hue): it cannot show a tendon, and a network's answer on such a
/// far-from-training input would be arbitrary. Each channel is measured on
/// its own, so a uniform green frame is as blank as a black one.
pub fn is_blank(img: &FloatImage) -> bool {
    let c = img.channels.max(1);
    (0..c).all(|ch| {
        let values = || img.data.iter().skip(ch).step_by(c).map(|&v| v as f64);
        let n = values().count().max(1) as f64;
        let mean = values().sum::<f64>() / n;
        let var = values().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
        (var.sqrt() as f32) < BLANK_FRAME_STD
    })
}

/// [`is_blank`] of interleaved 8-bit levels of `channels` channels (a
/// camera frame before any conversion): the same rule, one level being
/// 1/255.
pub fn is_blank_levels(levels: &[u8], channels: usize) -> bool {
    // Whole-number sums in one pass over the bytes (exact): it runs on
    // every frame a calibrated sensor reads.
    let c = channels.clamp(1, 4);
    let (mut sum, mut squares) = ([0u64; 4], [0u64; 4]);
    for pixel in levels.chunks_exact(c) {
        for (ch, &v) in pixel.iter().enumerate() {
            sum[ch] += u64::from(v);
            squares[ch] += u64::from(v) * u64::from(v);
        }
    }
    let n = (levels.len() / c).max(1) as f64;
    let limit = f64::from(BLANK_FRAME_STD) * 255.0;
    (0..c).all(|ch| {
        let mean = sum[ch] as f64 / n;
        let var = (squares[ch] as f64 / n - mean * mean).max(0.0);
        var.sqrt() < limit
    })
}

/// Grey level of a flat skin at rest under the spec's lights (albedo 0.8
/// times 0.25 + sin 30 deg): what [`normalise_exposure`] maps each
/// channel's typical window level to.
pub const FLAT_SKIN_LEVEL: f32 = 0.6;

/// Fraction of the window ellipse's radii whose pixels set the level in
/// [`normalise_exposure`]: inside the window, clear of the housing and of
/// the LED glare on the rim.
const LEVEL_REGION: f64 = 0.6;

/// Divide each channel by its median over the window's centre, so the
/// frame's flat skin sits at [`FLAT_SKIN_LEVEL`] whatever the exposure and
/// the balance of the LEDs. Shading contrast scales with both, while a
/// tendon's label is a threshold on the ridge's height: once the gain is
/// divided out, a contrast means one height. A channel whose centre is
/// nearly black (under 1 grey level) is left alone.
pub fn normalise_exposure(img: &mut FloatImage) {
    let c = img.channels;
    for (ch, level) in exposure_levels(img).into_iter().enumerate() {
        let Some(level) = level else { continue };
        let gain = FLAT_SKIN_LEVEL / level;
        img.data
            .iter_mut()
            .skip(ch)
            .step_by(c)
            .for_each(|v| *v *= gain);
    }
}

/// The pixels (row-major indices of a `w x h` image) whose median sets a
/// channel's level in [`normalise_exposure`]: the ellipse at
/// `LEVEL_REGION` of the window's radii.
pub fn exposure_pixels(w: usize, h: usize) -> Vec<usize> {
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let (rx, ry) = (LEVEL_REGION * w as f64 / 2.0, LEVEL_REGION * h as f64 / 2.0);
    (0..w * h)
        .filter(|&i| {
            let (dx, dy) = (((i % w) as f64 - cx) / rx, ((i / w) as f64 - cy) / ry);
            dx * dx + dy * dy <= 1.0
        })
        .collect()
}

/// Each channel's median over the window's centre (None where it is under
/// one grey level, or the image is empty).
fn exposure_levels(img: &FloatImage) -> Vec<Option<f32>> {
    let (w, h, c) = (img.width, img.height, img.channels);
    if w == 0 || h == 0 || c == 0 {
        return vec![None; c];
    }
    let centre = exposure_pixels(w, h);
    if centre.is_empty() {
        return vec![None; c];
    }
    let mut values = Vec::with_capacity(centre.len());
    (0..c)
        .map(|ch| {
            values.clear();
            values.extend(centre.iter().map(|&i| img.data[i * c + ch]));
            let mid = values.len() / 2;
            let (_, &mut median, _) = values.select_nth_unstable_by(mid, f32::total_cmp);
            (median >= 1.0 / 255.0).then_some(median)
        })
        .collect()
}

/// 1 where a resized or rotated mask is at least half tendon.
pub fn binarise_mask(mask: &FloatImage) -> Vec<f32> {
    mask.data
        .iter()
        .map(|&v| if v >= 0.5 { 1.0 } else { 0.0 })
        .collect()
}

/// Per-channel mean and standard deviation of the training frames, saved
/// with a model and applied to every input.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelStats {
    /// Mean per channel, in [0, 1] units.
    pub mean: Vec<f32>,
    /// Standard deviation per channel (at least 1e-3).
    pub std: Vec<f32>,
}

impl ChannelStats {
    /// Statistics over every pixel of `images` (all with the same channel count).
    pub fn from_images<'a>(images: impl IntoIterator<Item = &'a FloatImage>) -> Result<Self> {
        let mut sum: Vec<f64> = Vec::new();
        let mut sq: Vec<f64> = Vec::new();
        let mut n = 0usize;
        for img in images {
            if sum.is_empty() {
                sum = vec![0.0; img.channels];
                sq = vec![0.0; img.channels];
            }
            if img.channels != sum.len() {
                return Err(Error::Channels {
                    expected: sum.len(),
                    found: img.channels,
                });
            }
            for px in img.data.chunks_exact(img.channels) {
                for (c, &v) in px.iter().enumerate() {
                    sum[c] += v as f64;
                    sq[c] += (v as f64) * (v as f64);
                }
            }
            n += img.width * img.height;
        }
        if n == 0 {
            return Err(
                tactile_core::Error::Invalid("no images to compute statistics on".into()).into(),
            );
        }
        let mean: Vec<f64> = sum.iter().map(|s| s / n as f64).collect();
        let std = tactile_core::metrics::safe_scales(
            sq.iter()
                .zip(&mean)
                .map(|(q, m)| (q / n as f64 - m * m).max(0.0).sqrt()),
        );
        Ok(Self {
            mean: mean.iter().map(|&m| m as f32).collect(),
            std: std.iter().map(|&s| s.max(1e-3) as f32).collect(),
        })
    }

    /// Refuse statistics that cannot normalise a `channels`-channel image:
    /// another length, a non-finite mean, a standard deviation that is not
    /// a positive finite number.
    pub fn check(&self, channels: usize) -> tactile_core::Result<()> {
        let bad = |m: String| Err(tactile_core::Error::Config(m));
        if self.mean.len() != channels || self.std.len() != channels {
            return bad(format!(
                "channel statistics have {} means and {} standard deviations, the model takes {channels} channels",
                self.mean.len(),
                self.std.len()
            ));
        }
        if let Some(m) = self.mean.iter().find(|m| !m.is_finite()) {
            return bad(format!("a channel mean is {m}"));
        }
        if let Some(s) = self.std.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
            return bad(format!(
                "a channel standard deviation is {s}: it must be a positive number"
            ));
        }
        Ok(())
    }

    /// Normalised `C x H x W` values of an interleaved image.
    pub fn to_chw(&self, img: &FloatImage) -> Result<Vec<f32>> {
        if img.channels != self.mean.len() {
            return Err(Error::Channels {
                expected: self.mean.len(),
                found: img.channels,
            });
        }
        let (c, hw) = (img.channels, img.width * img.height);
        let mut out = vec![0f32; c * hw];
        for (i, px) in img.data.chunks_exact(c).enumerate() {
            for (ch, &v) in px.iter().enumerate() {
                out[ch * hw + i] = (v - self.mean[ch]) / self.std[ch];
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sixteen_bits_keep_a_fraction_of_a_grey_level_that_eight_round_away() {
        // A smooth ramp of a third of a grey level, as averaging recovers it.
        let data: Vec<f32> = (0..30).map(|i| (150.0 + i as f32 / 90.0) / 255.0).collect();
        let img = FloatImage {
            width: 10,
            height: 1,
            channels: 3,
            data,
        };
        let eight = img.quantised_to(8);
        let sixteen = img.quantised_to(16);
        assert!(
            eight.data.iter().all(|&v| v == 150.0 / 255.0),
            "8 bits: one level"
        );
        let err = |q: &FloatImage| {
            q.data
                .iter()
                .zip(&img.data)
                .map(|(a, b)| (a - b).abs())
                .fold(0f32, f32::max)
        };
        assert!(
            err(&sixteen) < 1e-5,
            "16 bits within 1e-5: {}",
            err(&sixteen)
        );
        assert_eq!(
            img.quantised_to(8),
            img.quantised(),
            "8 bits is the old quantisation"
        );
    }

    #[test]
    fn normalising_the_exposure_takes_out_gain_and_led_balance_but_keeps_contrast() {
        // A flat skin with a vertical band one level brighter, under two
        // exposures and LED balances.
        let frame = |gain: [f32; 3]| {
            let (w, h) = (80, 60);
            let mut data = Vec::with_capacity(w * h * 3);
            for i in 0..w * h {
                let band = if (35..45).contains(&(i % w)) {
                    1.0 / 255.0
                } else {
                    0.0
                };
                data.extend(gain.map(|g| g * (FLAT_SKIN_LEVEL + band)));
            }
            FloatImage {
                width: w,
                height: h,
                channels: 3,
                data,
            }
        };
        let (mut a, mut b) = (frame([1.0, 1.0, 1.0]), frame([1.1, 0.92, 1.05]));
        normalise_exposure(&mut a);
        normalise_exposure(&mut b);
        for (x, y) in a.data.iter().zip(&b.data) {
            assert!((x - y).abs() < 1e-6, "{x} {y}");
        }
        assert!((a.data[0] - FLAT_SKIN_LEVEL).abs() < 1e-6);
        assert!(
            (a.data[40 * 3] - a.data[0] - 1.0 / 255.0).abs() < 1e-6,
            "contrast kept"
        );
        // A black frame is left alone rather than blown up.
        let mut black = FloatImage {
            width: 8,
            height: 6,
            channels: 3,
            data: vec![0.0; 144],
        };
        normalise_exposure(&mut black);
        assert!(black.data.iter().all(|&v| v == 0.0));
    }

    #[test]
    fn frame_pixels_map_onto_the_window_they_were_cut_into() {
        let win = SquareWindow { side: 48 };
        let (w, h) = (640, 360);
        let (sw, sh) = win.scaled_size(w, h);
        // A frame with one bright pixel per 8 x 8 block, scaled and cut.
        let mut bytes = vec![0u8; w * h];
        for v in (4..h).step_by(16) {
            for u in (4..w).step_by(16) {
                bytes[v * w + u] = 255;
            }
        }
        let frame = crate::visuo::resize_u8(&bytes, (w, h, 1), sw, sh).unwrap();
        let cut = win.cut(&frame, 0.0);
        // The window's brightest pixel is where the mapping puts a bright frame pixel.
        let (best, _) = cut
            .data
            .iter()
            .enumerate()
            .fold((0, 0.0f32), |b, (i, &x)| if x > b.1 { (i, x) } else { b });
        let (bx, by) = ((best % 48) as f64, (best / 48) as f64);
        let near = (4..h)
            .step_by(16)
            .flat_map(|v| (4..w).step_by(16).map(move |u| (u, v)))
            .any(|(u, v)| {
                let (x, y) = win.frame_to_window((u as f64, v as f64), (w, h));
                (x - bx).abs() <= 1.0 && (y - by).abs() <= 1.0
            });
        assert!(near, "window pixel ({bx}, {by})");
        // The frame's centre is the window's centre.
        let (x, y) = win.frame_to_window((319.5, 179.5), (w, h));
        assert!(
            (x - 23.5).abs() < 1e-9 && (y - 23.5).abs() < 1e-9,
            "{x} {y}"
        );
    }

    fn ramp(w: usize, h: usize) -> FloatImage {
        FloatImage {
            width: w,
            height: h,
            channels: 1,
            data: (0..w * h).map(|i| (i % w) as f32 / w as f32).collect(),
        }
    }

    #[test]
    fn rotated_windows_have_no_empty_corners() {
        let win = SquareWindow { side: 40 };
        let (sw, sh) = win.scaled_size(640, 360);
        assert_eq!(sh, 57);
        assert!(sw > sh);
        // A portrait frame keeps its aspect too, its shorter side the same.
        assert_eq!(win.scaled_size(360, 640), (sh, sw));
        assert_eq!(win.scale(360, 640), win.scale(640, 360));
        let img = FloatImage {
            width: sw,
            height: sh,
            channels: 1,
            data: vec![1.0; sw * sh],
        };
        for deg in [0.0, 17.0, 45.0, 90.0, 133.0, 271.0] {
            let cut = win.cut(&img, deg);
            let min = cut.data.iter().copied().fold(f32::INFINITY, f32::min);
            assert!(min > 0.99, "{deg} deg: a corner fell outside ({min})");
        }
        // 90 degrees turns a left-to-right ramp into a top-to-bottom one.
        let r = ramp(sw, sh);
        let cut = win.cut(&r, 90.0);
        let col = |x: usize, y: usize| cut.data[y * 40 + x];
        assert!(
            col(20, 35) > col(20, 5) + 0.2,
            "{} {}",
            col(20, 35),
            col(20, 5)
        );
        assert!((col(5, 20) - col(35, 20)).abs() < 0.02);
    }

    #[test]
    fn blank_means_no_channel_varies_whatever_the_colour() {
        let solid = |rgb: [f32; 3]| FloatImage {
            width: 8,
            height: 4,
            channels: 3,
            data: (0..32).flat_map(|_| rgb).collect(),
        };
        assert!(is_blank(&solid([0.0, 0.0, 0.0])));
        assert!(is_blank(&solid([1.0, 1.0, 1.0])));
        // Channels differ from each other, but none varies over the frame.
        assert!(is_blank(&solid([0.16, 0.78, 0.35])));
        // One bright pixel in one channel is a picture.
        let mut img = solid([0.16, 0.78, 0.35]);
        img.data[3 * 5 + 1] += 1.0 / 255.0 * 16.0;
        assert!(!is_blank(&img));
        assert!(!is_blank(&ramp(16, 4)));
        // The same rule on a camera's 8-bit levels: one colour of any hue
        // is blank, and stays blank with one pixel a level off; a pixel far
        // off in one channel, or half the pixels two levels off, is not.
        let mut levels: Vec<u8> = [40u8, 200, 90].repeat(64);
        assert!(is_blank_levels(&levels, 3));
        levels[3 * 33 + 1] = 201;
        assert!(is_blank_levels(&levels, 3));
        levels[3 * 33 + 1] = 91;
        assert!(!is_blank_levels(&levels, 3));
        let mut dither: Vec<u8> = [40u8, 200, 90].repeat(64);
        dither.iter_mut().step_by(6).for_each(|v| *v += 2);
        assert!(!is_blank_levels(&dither, 3));
    }

    #[test]
    fn stats_normalise_to_zero_mean_unit_std() {
        let imgs = [ramp(10, 4), ramp(10, 4)];
        let st = ChannelStats::from_images(&imgs).unwrap();
        let v = st.to_chw(&imgs[0]).unwrap();
        let mean = v.iter().sum::<f32>() / v.len() as f32;
        let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f32>() / v.len() as f32;
        assert!(mean.abs() < 1e-5 && (var - 1.0).abs() < 1e-4);
        // A constant (black) training set does not divide by zero.
        let black = FloatImage {
            data: vec![0.0; 40],
            ..ramp(10, 4)
        };
        let st = ChannelStats::from_images([&black]).unwrap();
        assert!(st.to_chw(&black).unwrap().iter().all(|v| v.is_finite()));
    }

    #[test]
    fn resize_shrinks_by_area_grows_bilinearly_and_refuses_absurd_sizes() {
        let src: Vec<u8> = (0..8 * 4)
            .map(|i| if i % 8 < 4 { 0 } else { 255 })
            .collect();
        let small = resize_u8(&src, (8, 4, 1), 2, 1).unwrap();
        assert_eq!(small.data, vec![0.0, 1.0]);
        let big = resize_u8(&src, (8, 4, 1), 16, 8).unwrap();
        assert_eq!(big.data.len(), 128);
        assert!(big.data.iter().all(|v| (0.0..=1.0).contains(v)));
        assert!(resize_u8(&[], (0, 0, 1), 2, 2).is_err());
        assert!(resize_u8(&src, (8, 4, 1), 10_000, 10_000).is_err());
    }
}
