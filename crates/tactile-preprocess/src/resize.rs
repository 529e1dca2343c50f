//! Resizing: OpenCV-exact linear (through kornia) and area averaging
//! (the mean of the input pixels an output pixel covers, in f32, so a
//! pin's sub-pixel position survives the shrink), for grey and
//! interleaved images. One kernel for every model's input.

use kornia_image::{Image, ImageSize};
use kornia_imgproc::interpolation::InterpolationMode;
use tactile_core::image_io::GreyImage;

use crate::{Error, Result};

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
