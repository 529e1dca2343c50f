//! The TacTip chain itself: a frame through lighting, equalisation,
//! threshold, mask, opening, crop and resize to a [`PinImage`].

use std::borrow::Cow;

use tactile_core::image_io::GreyImage;

use crate::config::{Downsample, Lighting, PreprocessConfig};
use crate::morphology::{blank, centre_crop, circular_mask, dilate, erode, top_hat_binary};
use crate::resize::{resize_area, resize_linear};
use crate::{Error, Result, align};

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

/// [`preprocess`] on every frame of a batch, in parallel; a frame that
/// fails is named by its place in the batch (`frames[i]`), since frames
/// given in memory have no file to name.
pub fn preprocess_each(frames: &[GreyImage], cfg: &PreprocessConfig) -> Result<Vec<PinImage>> {
    preprocess_each_by(frames, cfg, |f| Ok(Cow::Borrowed(f)))
}

/// [`preprocess_each`] on frames of another form, each made grey by
/// `grey` only as its turn comes, so a batch is never held twice (once as
/// given, once grey); a frame whose conversion fails is named alike.
pub fn preprocess_each_by<F: Sync>(
    frames: &[F],
    cfg: &PreprocessConfig,
    grey: impl Fn(&F) -> Result<Cow<'_, GreyImage>> + Sync,
) -> Result<Vec<PinImage>> {
    each_by(frames, cfg, grey, |_| ()).map(|pins| pins.into_iter().map(|(p, ())| p).collect())
}

/// [`preprocess_each_by`], each pin image with whether its frame is flat
/// ([`is_flat_frame`]), read off the grey frame while it is held: for
/// frames given in memory, which are warned of as a dataset's are.
pub fn preprocess_each_noting_flat<F: Sync>(
    frames: &[F],
    cfg: &PreprocessConfig,
    grey: impl Fn(&F) -> Result<Cow<'_, GreyImage>> + Sync,
) -> Result<(Vec<PinImage>, Vec<bool>)> {
    Ok(each_by(frames, cfg, grey, |g| is_flat_frame(g, cfg))?
        .into_iter()
        .unzip())
}

/// Each frame made grey, preprocessed, and read by `also` while grey.
fn each_by<F: Sync, T: Send>(
    frames: &[F],
    cfg: &PreprocessConfig,
    grey: impl Fn(&F) -> Result<Cow<'_, GreyImage>> + Sync,
    also: impl Fn(&GreyImage) -> T + Sync,
) -> Result<Vec<(PinImage, T)>> {
    use rayon::prelude::*;
    frames
        .par_iter()
        .enumerate()
        .map(|(index, f)| {
            // A long batch stops between frames at a stop request (Ctrl-C).
            tactile_core::interrupt::check()?;
            grey(f)
                .and_then(|g| Ok((preprocess(&g, cfg)?, also(&g))))
                .map_err(|e| Error::Frame {
                    index,
                    error: Box::new(e),
                })
        })
        .collect()
}

/// A frame whose grey levels inside the chain's centred crop spread less
/// than this (their standard deviation) shows no pins: a blank, covered or
/// saturated camera. Real TacTip frames spread 57 to 106 levels (400
/// frames of each real set) and virtual ones 29.
pub const FLAT_FRAME_LEVELS: f64 = 4.0;

/// True when `frame` is one grey level throughout `cfg`'s crop (within
/// [`FLAT_FRAME_LEVELS`]): there are no pins to read, so estimates made
/// from it mean nothing. Every third row and column is read.
pub fn is_flat_frame(frame: &GreyImage, cfg: &PreprocessConfig) -> bool {
    let (w, h) = (frame.width(), frame.height());
    let side = cfg.crop_px.min(w).min(h);
    let (x0, y0) = ((w - side) / 2, (h - side) / 2);
    let px = frame.as_slice();
    let (mut n, mut sum, mut sq) = (0f64, 0f64, 0f64);
    for y in (y0..y0 + side).step_by(3) {
        for &v in px[y * w + x0..y * w + x0 + side].iter().step_by(3) {
            let v = f64::from(v);
            n += 1.0;
            sum += v;
            sq += v * v;
        }
    }
    if n == 0.0 {
        return false;
    }
    let mean = sum / n;
    (sq / n - mean * mean).max(0.0).sqrt() < FLAT_FRAME_LEVELS
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
    use crate::morphology::{box_extreme, box_kernel};
    use kornia_imgproc::morphology;
    use kornia_imgproc::padding::PaddingMode;

    /// Black, white, grey and a camera's noise of a couple of levels are
    /// flat; pins are not, wherever they sit in the crop, and what lies
    /// outside the crop does not count.
    #[test]
    fn a_frame_of_one_level_is_flat_and_pins_are_not() {
        let cfg = PreprocessConfig {
            crop_px: 60,
            output_px: 20,
            ..PreprocessConfig::paper()
        };
        let frame = |f: &dyn Fn(usize, usize) -> u8| {
            let data = (0..100 * 80).map(|i| f(i % 100, i / 100)).collect();
            tactile_core::image_io::grey_image(100, 80, data).unwrap()
        };
        for level in [0u8, 128, 255] {
            assert!(is_flat_frame(&frame(&|_, _| level), &cfg), "{level}");
        }
        let noise = frame(&|x, y| 100 + ((x * 7 + y * 13) % 5) as u8);
        assert!(is_flat_frame(&noise, &cfg));
        let pins = frame(&|x, y| if x % 9 < 3 && y % 9 < 3 { 230 } else { 20 });
        assert!(!is_flat_frame(&pins, &cfg));
        // Pins only outside the centred 60 px crop: flat inside it.
        let rim = frame(&|x, _| if !(20..80).contains(&x) { 230 } else { 20 });
        assert!(is_flat_frame(&rim, &cfg));
    }

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
