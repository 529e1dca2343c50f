//! TacTip preprocessing (paper A): a 300x300 sensor frame becomes a binary
//! 28x28 [`PinImage`] (pins 1, background 0).
//!
//! The authors' chain, every step configurable: grey -> (lighting
//! compensation) -> histogram equalisation -> threshold -> circular mask ->
//! open 2x2 -> crop -> resize to 28x28 (OpenCV `INTER_LINEAR`, byte-exact
//! through kornia's OpenCV-compatible path) -> `/255` -> `round(x + 0.3)`.
//! The lighting compensation (white top-hat plus a threshold relative to the
//! local pin contrast) is what makes raw frames with illumination gradients,
//! light blobs and noise come out as clean pin images.
//!
//! Also here: visuo-tactile frames as model inputs ([`visuo`]), pin tracking
//! ([`pins`]) and the camera perturbations of the robustness study
//! ([`perturb`]).

#![deny(missing_docs)]

use kornia_image::{Image, ImageSize};
use kornia_imgproc::interpolation::InterpolationMode;
use kornia_imgproc::morphology::{self, Kernel};
use kornia_imgproc::padding::PaddingMode;

pub mod align;
mod error;
pub mod perturb;
pub mod pins;
pub mod profile;
pub mod visuo;

pub use error::{Error, Result};
use serde::{Deserialize, Serialize};
use tactile_core::image_io::GreyImage;

/// How uneven illumination is removed before thresholding.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum Lighting {
    /// No compensation: the fixed threshold of the authors' lab set-up.
    None,
    /// Background subtraction by a white top-hat (the frame minus its
    /// morphological opening with a box larger than a pin), then a pixel is
    /// a pin when it reaches `relative_threshold` of the local top-hat
    /// maximum (a box of `peak_window_px`) and that maximum is at least
    /// `min_contrast` grey levels. Gains, gradients and blobs cancel out.
    TopHat {
        /// Side of the opening box (larger than a pin), pixels.
        background_window_px: usize,
        /// Side of the local-maximum box, pixels.
        peak_window_px: usize,
        /// Fraction of the local top-hat maximum a pin pixel reaches.
        relative_threshold: f32,
        /// Smallest local maximum that counts as a pin, grey levels.
        min_contrast: u8,
        /// Box-blur size applied first to tame sensor noise (1 = off).
        denoise_px: usize,
    },
}

/// Every step of the chain; see the presets.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PreprocessConfig {
    /// Illumination compensation.
    pub lighting: Lighting,
    /// Histogram equalisation (authors: on; pointless after top-hat).
    pub equalize: bool,
    /// Fixed binary threshold applied after equalisation (authors: 170);
    /// `None` when the lighting step already produced a binary image.
    pub threshold: Option<u8>,
    /// Radius of the circular mask around the frame centre (authors: 145 px).
    pub mask_radius_px: Option<f32>,
    /// Side of the square morphological opening (authors: 2; 0 = off).
    pub open_px: usize,
    /// Side of a square dilation after the opening (0 = off). A 300 px
    /// frame shrinks 10.7 times to 28 px, so a 7 px pin covers a third of
    /// an output pixel and flickers in and out with sub-pixel motion;
    /// growing pins first keeps each one visible in the pin image.
    #[serde(default)]
    pub grow_px: usize,
    /// Side of the centred square crop (authors: 300).
    pub crop_px: usize,
    /// Side of the output pin image (28).
    pub output_px: usize,
    /// Offset of the final rounding `round(x/255 + offset)` (authors: 0.3).
    pub binarise_offset: f64,
    /// How the crop shrinks to `output_px` (authors: bilinear sampling).
    #[serde(default)]
    pub downsample: Downsample,
    /// Round to {0, 1} (paper A). `false` keeps the grey levels in [0, 1],
    /// which with [`Downsample::Area`] keep each pin's sub-pixel position:
    /// the fraction of an output pixel it covers.
    #[serde(default = "yes")]
    pub binarise: bool,
    /// Turn each frame whose pin lattice (measured on the binary image
    /// after the lighting step and the mask) is turned from the training
    /// frames' back before the chain ([`align`]: a sensor mounted turned);
    /// `None` = off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub align: Option<align::PinAlign>,
}

fn yes() -> bool {
    true
}

/// Shrinking the crop to the pin image.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Downsample {
    /// OpenCV's `INTER_LINEAR` (what the authors ran): samples a 2x2
    /// neighbourhood, so at a 10x shrink most pixels are never read.
    #[default]
    Linear,
    /// Mean over each output pixel's footprint, with fractional coverage at
    /// its borders: every input pixel counts.
    Area,
}

impl PreprocessConfig {
    /// The authors' released chain for their lab frames.
    pub fn paper() -> Self {
        Self {
            lighting: Lighting::None,
            equalize: true,
            threshold: Some(170),
            mask_radius_px: Some(145.0),
            open_px: 2,
            grow_px: 0,
            crop_px: 300,
            output_px: 28,
            binarise_offset: 0.3,
            downsample: Downsample::Linear,
            binarise: true,
            align: None,
        }
    }

    /// The chain for raw frames with uneven lighting (the virtual TacTip of
    /// `sensors.md`, or a real sensor without a controlled light).
    pub fn lighting_compensated() -> Self {
        Self {
            lighting: Lighting::TopHat {
                background_window_px: 15,
                peak_window_px: 21,
                relative_threshold: 0.5,
                min_contrast: 25,
                denoise_px: 3,
            },
            equalize: false,
            threshold: None,
            mask_radius_px: Some(145.0),
            // No 2x2 opening: with an even kernel OpenCV's (and kornia's)
            // erode-then-dilate moves every pin by one pixel down and right;
            // the 3x3 denoise already removes isolated noise pixels.
            open_px: 0,
            grow_px: 9,
            crop_px: 300,
            output_px: 28,
            binarise_offset: 0.3,
            downsample: Downsample::Linear,
            binarise: true,
            align: None,
        }
    }

    /// Frames that are already binary pin images (the authors' released
    /// shapes set): only crop, resize and binarise.
    pub fn binary_frames() -> Self {
        Self {
            lighting: Lighting::None,
            equalize: false,
            threshold: None,
            mask_radius_px: None,
            open_px: 0,
            grow_px: 0,
            crop_px: 300,
            output_px: 28,
            binarise_offset: 0.3,
            downsample: Downsample::Linear,
            binarise: true,
            align: None,
        }
    }

    /// Check every size and value against its limit: windows and boxes up
    /// to [`MAX_WINDOW_PX`], the crop up to 8K, the pin image no larger
    /// than the crop, thresholds and offsets finite.
    pub fn check(&self) -> tactile_core::Result<()> {
        let bad = |m: String| Err(tactile_core::Error::Config(format!("preprocessing: {m}")));
        let windows = [("open_px", self.open_px), ("grow_px", self.grow_px)];
        let lighting = match &self.lighting {
            Lighting::None => vec![],
            Lighting::TopHat {
                background_window_px,
                peak_window_px,
                relative_threshold,
                denoise_px,
                ..
            } => {
                if !(0.0..=1.0).contains(relative_threshold) {
                    return bad(format!(
                        "relative_threshold {relative_threshold} must be in [0, 1]"
                    ));
                }
                vec![
                    ("background_window_px", *background_window_px),
                    ("peak_window_px", *peak_window_px),
                    ("denoise_px", *denoise_px),
                ]
            }
        };
        for (name, v) in windows.into_iter().chain(lighting) {
            if v > MAX_WINDOW_PX {
                return bad(format!("{name} {v} is larger than {MAX_WINDOW_PX} pixels"));
            }
        }
        if self.crop_px == 0 || self.crop_px > 7680 {
            return bad(format!("crop_px {} must be 1 to 7680", self.crop_px));
        }
        if self.output_px == 0 || self.output_px > self.crop_px {
            return bad(format!(
                "output_px {} must be 1 to the crop ({})",
                self.output_px, self.crop_px
            ));
        }
        if !self.binarise_offset.is_finite() || self.mask_radius_px.is_some_and(|r| !r.is_finite())
        {
            return bad("binarise_offset and mask_radius_px must be finite".into());
        }
        if let Some(a) = &self.align {
            a.check()?;
        }
        Ok(())
    }

    /// Look a preset up by name (`paper`, `lighting-compensated`, `binary`),
    /// or read a whole configuration from a `.json` file.
    pub fn preset(name: &str) -> Result<Self> {
        match name {
            "paper" => Ok(Self::paper()),
            "lighting-compensated" => Ok(Self::lighting_compensated()),
            "binary" => Ok(Self::binary_frames()),
            path if path.ends_with(".json") => {
                let c: Self = tactile_core::io::read_json(path)?;
                tactile_core::error::in_config(std::path::Path::new(path), c.check())?;
                Ok(c)
            }
            other => Err(Error::UnknownPreset(other.to_string())),
        }
    }
}

/// Largest morphology window or box accepted, pixels.
pub const MAX_WINDOW_PX: usize = 255;

/// A pin image: `side x side` values in {0, 1} (or grey levels in [0, 1]
/// when the chain does not binarise), row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct PinImage {
    /// Side, pixels.
    pub side: usize,
    /// `side * side` values, row-major.
    pub pixels: Vec<f32>,
}

fn blank(like: &GreyImage) -> Result<GreyImage> {
    Ok(Image::from_size_val(like.size(), 0u8)?)
}

fn box_kernel(side: usize) -> Kernel {
    morphology::box_kernel(side.max(1))
}

fn erode(src: &GreyImage, side: usize) -> Result<GreyImage> {
    if side % 2 == 1 {
        return box_extreme(src, side, false);
    }
    let mut dst = blank(src)?;
    morphology::erode(
        src,
        &mut dst,
        &box_kernel(side),
        PaddingMode::Replicate,
        [0],
    )?;
    Ok(dst)
}

fn dilate(src: &GreyImage, side: usize) -> Result<GreyImage> {
    if side % 2 == 1 {
        return box_extreme(src, side, true);
    }
    let mut dst = blank(src)?;
    morphology::dilate(
        src,
        &mut dst,
        &box_kernel(side),
        PaddingMode::Replicate,
        [0],
    )?;
    Ok(dst)
}

/// Erosion (`max = false`) or dilation by a centred odd `side x side` box
/// with replicated borders, done separably: the same result as kornia's
/// 2-D morphology for a box, in O(side) instead of O(side^2) per pixel
/// (the top-hat's 15 and 21 px boxes dominated preprocessing time).
fn box_extreme(src: &GreyImage, side: usize, max: bool) -> Result<GreyImage> {
    let (w, h) = (src.width(), src.height());
    let r = (side / 2) as isize;
    let pick = |a: u8, b: u8| if max { a.max(b) } else { a.min(b) };
    let s = src.as_slice();
    let mut rows = vec![0u8; w * h];
    for y in 0..h {
        let line = &s[y * w..(y + 1) * w];
        for x in 0..w {
            let mut v = line[x];
            for d in -r..=r {
                v = pick(v, line[(x as isize + d).clamp(0, w as isize - 1) as usize]);
            }
            rows[y * w + x] = v;
        }
    }
    let mut out = vec![0u8; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut v = rows[y * w + x];
            for d in -r..=r {
                let yy = (y as isize + d).clamp(0, h as isize - 1) as usize;
                v = pick(v, rows[yy * w + x]);
            }
            out[y * w + x] = v;
        }
    }
    Ok(tactile_core::image_io::grey_image(w, h, out)?)
}

/// Box mean over `side x side`, replicate borders (integer, rounded).
fn box_mean(src: &GreyImage, side: usize) -> Result<GreyImage> {
    if side <= 1 {
        return Ok(src.clone());
    }
    let (w, h) = (src.width(), src.height());
    let s = src.as_slice();
    let r = (side / 2) as isize;
    let mut out = vec![0u8; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut sum = 0u32;
            for dy in -r..=r {
                let yy = (y as isize + dy).clamp(0, h as isize - 1) as usize;
                for dx in -r..=r {
                    let xx = (x as isize + dx).clamp(0, w as isize - 1) as usize;
                    sum += s[yy * w + xx] as u32;
                }
            }
            let n = ((2 * r + 1) * (2 * r + 1)) as u32;
            out[y * w + x] = ((sum + n / 2) / n) as u8;
        }
    }
    Ok(tactile_core::image_io::grey_image(w, h, out)?)
}

fn top_hat_binary(
    src: &GreyImage,
    bg: usize,
    peak: usize,
    rel: f32,
    min_contrast: u8,
    denoise: usize,
) -> Result<GreyImage> {
    let smooth = box_mean(src, denoise)?;
    let background = dilate(&erode(&smooth, bg)?, bg)?;
    let tophat: Vec<u8> = smooth
        .as_slice()
        .iter()
        .zip(background.as_slice())
        .map(|(&a, &b)| a.saturating_sub(b))
        .collect();
    let tophat = tactile_core::image_io::grey_image(src.width(), src.height(), tophat)?;
    let local_max = dilate(&tophat, peak)?;
    let out = tophat
        .as_slice()
        .iter()
        .zip(local_max.as_slice())
        .map(|(&t, &m)| {
            if m >= min_contrast && t as f32 >= rel * m as f32 && t > 0 {
                255
            } else {
                0
            }
        })
        .collect();
    Ok(tactile_core::image_io::grey_image(
        src.width(),
        src.height(),
        out,
    )?)
}

fn circular_mask(img: &mut GreyImage, radius: f32) {
    let (w, h) = (img.width(), img.height());
    // OpenCV `circle` centred at (w/2, h/2) with integer centre, as the authors drew it.
    let (cx, cy) = ((w / 2) as f32, (h / 2) as f32);
    let r2 = radius * radius;
    for (i, p) in img.as_slice_mut().iter_mut().enumerate() {
        let (x, y) = ((i % w) as f32, (i / w) as f32);
        if (x - cx).powi(2) + (y - cy).powi(2) > r2 {
            *p = 0;
        }
    }
}

fn centre_crop(img: &GreyImage, side: usize) -> Result<GreyImage> {
    let (w, h) = (img.width(), img.height());
    if side > w || side > h {
        return Err(tactile_core::Error::shape(
            "frame for cropping",
            format!("at least {side}x{side}"),
            format!("{w}x{h}"),
        )
        .into());
    }
    if side == w && side == h {
        return Ok(img.clone());
    }
    let (x0, y0) = ((w - side) / 2, (h - side) / 2);
    let s = img.as_slice();
    let data = (0..side)
        .flat_map(|y| {
            s[(y0 + y) * w + x0..(y0 + y) * w + x0 + side]
                .iter()
                .copied()
        })
        .collect();
    Ok(tactile_core::image_io::grey_image(side, side, data)?)
}

/// OpenCV `INTER_LINEAR` resize of an 8-bit image (byte-exact with `cv2.resize`).
pub fn resize_linear(img: &GreyImage, width: usize, height: usize) -> Result<GreyImage> {
    let mut dst = Image::from_size_val(ImageSize { width, height }, 0u8)?;
    kornia_imgproc::resize::resize_opencv_u8(img, &mut dst, InterpolationMode::Bilinear)?;
    Ok(dst)
}

/// Area-average resize to `width x height`, values scaled to [0, 1].
pub fn resize_area(img: &GreyImage, width: usize, height: usize) -> Result<Vec<f32>> {
    resize_area_interleaved(
        img.as_slice(),
        (img.width(), img.height(), 1),
        width,
        height,
    )
}

/// Area-average resize of interleaved 8-bit pixels (`channels` per pixel)
/// to `width x height`, values scaled to [0, 1], still interleaved.
pub fn resize_area_interleaved(
    src: &[u8],
    (w, h, c): (usize, usize, usize),
    width: usize,
    height: usize,
) -> Result<Vec<f32>> {
    check_area(src.len(), (w, h, c), width, height)?;
    Ok(area_core(|i| src[i] as f64, (w, h, c), width, height)
        .into_iter()
        .map(|v| (v / 255.0).clamp(0.0, 1.0) as f32)
        .collect())
}

/// Area-average resize of a float map (a depth map), `w x h` -> `width x height`.
pub fn resize_area_f32(
    src: &[f32],
    (w, h): (usize, usize),
    width: usize,
    height: usize,
) -> Result<Vec<f32>> {
    check_area(src.len(), (w, h, 1), width, height)?;
    Ok(area_core(|i| src[i] as f64, (w, h, 1), width, height)
        .into_iter()
        .map(|v| v as f32)
        .collect())
}

fn check_area(
    len: usize,
    (w, h, c): (usize, usize, usize),
    width: usize,
    height: usize,
) -> Result<()> {
    if width == 0 || height == 0 || width > w || height > h || len != w * h * c {
        return Err(Error::ImageSize {
            width,
            height,
            why: format!("an area resize of a {w}x{h} image can only shrink to a non-empty size"),
        });
    }
    Ok(())
}

/// Separable area averaging: each output column (row) is a weighted mean
/// of the input columns (rows) its footprint overlaps, weights = overlap
/// length. Only shrinks (checked by the callers).
fn area_core(
    src: impl Fn(usize) -> f64,
    (w, h, c): (usize, usize, usize),
    width: usize,
    height: usize,
) -> Vec<f64> {
    // (first input index, weights) per output index; weights sum to 1.
    let taps = |n_in: usize, n_out: usize| -> Vec<(usize, Vec<f64>)> {
        let scale = n_in as f64 / n_out as f64;
        (0..n_out)
            .map(|o| {
                let (a, b) = (o as f64 * scale, (o + 1) as f64 * scale);
                let first = a.floor() as usize;
                let last = (b.ceil() as usize).min(n_in);
                let wts = (first..last)
                    .map(|i| ((i + 1) as f64).min(b) - (i as f64).max(a))
                    .map(|len| len / scale)
                    .collect();
                (first, wts)
            })
            .collect()
    };
    let (tx, ty) = (taps(w, width), taps(h, height));
    // Rows first: h x width x c.
    let mut rows = vec![0f64; h * width * c];
    for y in 0..h {
        for (ox, (first, wts)) in tx.iter().enumerate() {
            for ch in 0..c {
                rows[(y * width + ox) * c + ch] = wts
                    .iter()
                    .enumerate()
                    .map(|(k, wt)| wt * src((y * w + first + k) * c + ch))
                    .sum();
            }
        }
    }
    let mut out = vec![0f64; width * height * c];
    for (oy, (first, wts)) in ty.iter().enumerate() {
        for i in 0..width * c {
            out[oy * width * c + i] = wts
                .iter()
                .enumerate()
                .map(|(k, wt)| wt * rows[(first + k) * width * c + i])
                .sum();
        }
    }
    out
}

/// `round(v/255 + offset)` with NumPy's round-half-to-even, per pixel.
pub fn binarise(img: &GreyImage, offset: f64) -> Vec<f32> {
    img.as_slice()
        .iter()
        .map(|&v| {
            (v as f64 / 255.0 + offset)
                .round_ties_even()
                .clamp(0.0, 1.0) as f32
        })
        .collect()
}

/// The chain's first steps: lighting, equalisation, threshold, mask (the
/// binary image the pin alignment measures).
pub(crate) fn lit_and_masked(frame: &GreyImage, cfg: &PreprocessConfig) -> Result<GreyImage> {
    let mut img = frame.clone();
    if let Lighting::TopHat {
        background_window_px,
        peak_window_px,
        relative_threshold,
        min_contrast,
        denoise_px,
    } = &cfg.lighting
    {
        img = top_hat_binary(
            &img,
            *background_window_px,
            *peak_window_px,
            *relative_threshold,
            *min_contrast,
            *denoise_px,
        )?;
    }
    if cfg.equalize {
        let mut dst = blank(&img)?;
        kornia_imgproc::histogram::equalize_hist(&img, &mut dst)?;
        img = dst;
    }
    if let Some(t) = cfg.threshold {
        let mut dst = blank(&img)?;
        // OpenCV THRESH_BINARY: value > t -> 255.
        kornia_imgproc::threshold::threshold_binary(&img, &mut dst, t, 255)?;
        img = dst;
    }
    if let Some(r) = cfg.mask_radius_px {
        circular_mask(&mut img, r);
    }
    Ok(img)
}

/// Run the full configured chain on one frame.
pub fn preprocess(frame: &GreyImage, cfg: &PreprocessConfig) -> Result<PinImage> {
    cfg.check()?;
    if frame.width() < cfg.output_px || frame.height() < cfg.output_px {
        return Err(Error::FrameTooSmall {
            width: frame.width(),
            height: frame.height(),
            needed: cfg.output_px,
        });
    }
    let mut img = lit_and_masked(frame, cfg)?;
    if let Some(a) = &cfg.align
        && let Some(turn) = align::turn_to_undo(&img, a)?
    {
        // Measured on the chain's own binary image (cheap, so a straight
        // frame costs one connected-components pass); a turned frame is
        // turned back raw and lit again, as a straight one would have been.
        img = lit_and_masked(&align::turn_back(frame, turn)?, cfg)?;
    }
    if cfg.open_px > 0 {
        img = dilate(&erode(&img, cfg.open_px)?, cfg.open_px)?;
    }
    if cfg.grow_px > 0 {
        img = dilate(&img, cfg.grow_px)?;
    }
    img = centre_crop(&img, cfg.crop_px.min(img.width()).min(img.height()))?;
    let side = cfg.output_px;
    let pixels = match (cfg.downsample, cfg.binarise) {
        // Bit-exact with the authors' u8 chain.
        (Downsample::Linear, true) => {
            binarise(&resize_linear(&img, side, side)?, cfg.binarise_offset)
        }
        (Downsample::Linear, false) => resize_linear(&img, side, side)?
            .as_slice()
            .iter()
            .map(|&v| v as f32 / 255.0)
            .collect(),
        (Downsample::Area, b) => {
            let soft = resize_area(&img, side, side)?;
            if b {
                soft.iter()
                    .map(|&v| {
                        (v as f64 + cfg.binarise_offset)
                            .round_ties_even()
                            .clamp(0.0, 1.0) as f32
                    })
                    .collect()
            } else {
                soft
            }
        }
    };
    Ok(PinImage { side, pixels })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn area_resize_keeps_the_mean_and_sees_sub_pixel_motion() {
        // A 4x4 white square on a 256x256 frame, moved by one input pixel:
        // 1/9 of an output pixel at a 256 -> 28 shrink.
        let frame = |x0: usize| {
            let mut d = vec![0u8; 256 * 256];
            for y in 100..104 {
                for x in x0..x0 + 4 {
                    d[y * 256 + x] = 255;
                }
            }
            tactile_core::image_io::grey_image(256, 256, d).unwrap()
        };
        let (a, b) = (frame(100), frame(101));
        let (sa, sb) = (
            resize_area(&a, 28, 28).unwrap(),
            resize_area(&b, 28, 28).unwrap(),
        );
        let sum = |v: &[f32]| v.iter().map(|&x| x as f64).sum::<f64>();
        let expected = 16.0 / (256.0 * 256.0) * 784.0;
        assert!(
            (sum(&sa) - expected).abs() < 1e-5,
            "{} vs {expected}",
            sum(&sa)
        );
        assert!((sum(&sb) - expected).abs() < 1e-5);
        // The centroid moves right by a fraction of an output pixel (28/256
        // of one in the continuous limit; on the pixel grid a step).
        let cx = |v: &[f32]| {
            v.iter()
                .enumerate()
                .map(|(i, &p)| (i % 28) as f64 * p as f64)
                .sum::<f64>()
                / sum(v)
        };
        let shift = cx(&sb) - cx(&sa);
        assert!(shift > 0.05 && shift < 0.25, "centroid shift {shift}");
        // Bilinear sampling of the same two frames cannot tell them apart.
        let (la, lb) = (
            resize_linear(&a, 28, 28).unwrap(),
            resize_linear(&b, 28, 28).unwrap(),
        );
        assert_eq!(binarise(&la, 0.3), binarise(&lb, 0.3));
        assert!(resize_area(&a, 300, 28).is_err());
    }

    #[test]
    fn separable_box_morphology_equals_kornia() {
        let (w, h) = (37, 23);
        let data: Vec<u8> = (0..w * h)
            .map(|i| ((i * 7919 + i / 5 * 31) % 251) as u8)
            .collect();
        let img = tactile_core::image_io::grey_image(w, h, data).unwrap();
        for side in [3, 5, 15] {
            for max in [false, true] {
                let mut k = blank(&img).unwrap();
                if max {
                    morphology::dilate(
                        &img,
                        &mut k,
                        &box_kernel(side),
                        PaddingMode::Replicate,
                        [0],
                    )
                    .unwrap();
                } else {
                    morphology::erode(&img, &mut k, &box_kernel(side), PaddingMode::Replicate, [0])
                        .unwrap();
                }
                let ours = box_extreme(&img, side, max).unwrap();
                assert_eq!(ours.as_slice(), k.as_slice(), "side {side} max {max}");
            }
        }
    }
    use tactile_core::image_io::grey_image;

    #[test]
    fn binarise_rounds_half_to_even_like_numpy() {
        let img = grey_image(3, 1, vec![51, 52, 255]).unwrap();
        assert_eq!(binarise(&img, 0.3), vec![0.0, 1.0, 1.0]);
    }

    #[test]
    fn resize_matches_opencv_linear_on_a_ramp() {
        // cv2.resize(np.arange(8, dtype=np.uint8).reshape(1, 8) * 30, (4, 1)) == [15, 75, 135, 195]
        let img = grey_image(8, 1, (0..8).map(|v| v * 30).collect()).unwrap();
        let out = resize_linear(&img, 4, 1).unwrap();
        assert_eq!(out.as_slice(), &[15, 75, 135, 195]);
    }

    fn synthetic_pins(gain: impl Fn(f32, f32) -> f32) -> GreyImage {
        let mut data = vec![0u8; 300 * 300];
        for y in 0..300 {
            for x in 0..300 {
                let (fx, fy) = (x as f32, y as f32);
                let near = ((fx - 150.0) / 20.0).round() * 20.0 + 150.0;
                let neary = ((fy - 150.0) / 20.0).round() * 20.0 + 150.0;
                let pin = (fx - near).powi(2) + (fy - neary).powi(2) < 16.0;
                let v = if pin { 220.0 } else { 30.0 };
                data[y * 300 + x] = (v * gain(fx, fy)).clamp(0.0, 255.0) as u8;
            }
        }
        grey_image(300, 300, data).unwrap()
    }

    #[test]
    fn lighting_compensation_removes_a_strong_gradient() {
        let cfg = PreprocessConfig::lighting_compensated();
        let flat = preprocess(&synthetic_pins(|_, _| 1.0), &cfg).unwrap();
        let graded = preprocess(&synthetic_pins(|x, _| 0.35 + 1.0 * x / 300.0), &cfg).unwrap();
        let differ = flat
            .pixels
            .iter()
            .zip(&graded.pixels)
            .filter(|(a, b)| a != b)
            .count();
        assert!(
            differ <= 8,
            "{differ} of 784 pixels changed under a 3x illumination gradient"
        );
        let on = flat.pixels.iter().filter(|&&v| v == 1.0).count();
        assert!(on > 50 && on < 500, "pin pixels: {on}");
        // The fixed-threshold chain loses the dark half under the same gradient.
        let paper = PreprocessConfig {
            equalize: false,
            ..PreprocessConfig::paper()
        };
        let p_flat = preprocess(&synthetic_pins(|_, _| 1.0), &paper).unwrap();
        let p_graded = preprocess(&synthetic_pins(|x, _| 0.35 + 1.0 * x / 300.0), &paper).unwrap();
        let p_differ = p_flat
            .pixels
            .iter()
            .zip(&p_graded.pixels)
            .filter(|(a, b)| a != b)
            .count();
        assert!(
            p_differ > differ,
            "fixed threshold {p_differ} vs compensated {differ}"
        );
    }

    #[test]
    fn tiny_or_empty_frames_are_errors_not_panics() {
        for side in [1usize, 10, 27] {
            let img = grey_image(side, side, vec![255; side * side]).unwrap();
            let e = preprocess(&img, &PreprocessConfig::paper())
                .unwrap_err()
                .to_string();
            assert!(e.contains(&format!("{side}x{side}")), "{e}");
        }
        // A black frame is a valid (empty) pin image, a white one is all pins.
        let black = grey_image(300, 300, vec![0; 90000]).unwrap();
        let p = preprocess(&black, &PreprocessConfig::lighting_compensated()).unwrap();
        assert!(p.pixels.iter().all(|&v| v == 0.0));
    }
}
