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

/// Block mean of an 8-bit RGB frame (`w x h`) over `factor x factor`
/// pixels, through the SIMD resizer's box filter on 16 bits per value (the
/// remainder at the right and bottom cropped): `(w / factor) x (h /
/// factor)` interleaved values in [0, 1], the area average within 1e-5,
/// a few times faster than the general one above.
pub fn shrink_rgb_by(src: &[u8], (w, h): (usize, usize), factor: usize) -> Result<Vec<f32>> {
    use fast_image_resize as fr;
    let (dw, dh) = (w / factor.max(1), h / factor.max(1));
    if factor == 0 || dw == 0 || dh == 0 || src.len() != w * h * 3 {
        return Err(Error::ImageSize {
            width: dw,
            height: dh,
            why: format!(
                "a {w}x{h} RGB frame ({} bytes) cannot shrink by {factor}",
                src.len()
            ),
        });
    }
    let (cw, ch) = (dw * factor, dh * factor);
    // 16 bits per value (v * 257 spans 0-65535) keep the mean's fraction.
    let mut bytes = vec![0u8; cw * ch * 6];
    for y in 0..ch {
        let row = &src[y * w * 3..(y * w + cw) * 3];
        for (o, &v) in bytes[y * cw * 6..(y + 1) * cw * 6]
            .chunks_exact_mut(2)
            .zip(row)
        {
            o.copy_from_slice(&(v as u16 * 257).to_ne_bytes());
        }
    }
    let fail = |e: String| Error::Kornia(format!("shrink {w}x{h} by {factor}: {e}"));
    let img = fr::images::Image::from_vec_u8(cw as u32, ch as u32, bytes, fr::PixelType::U16x3)
        .map_err(|e| fail(e.to_string()))?;
    let mut dst = fr::images::Image::new(dw as u32, dh as u32, fr::PixelType::U16x3);
    let options =
        fr::ResizeOptions::new().resize_alg(fr::ResizeAlg::Convolution(fr::FilterType::Box));
    fr::Resizer::new()
        .resize(&img, &mut dst, &options)
        .map_err(|e| fail(e.to_string()))?;
    Ok(dst
        .buffer()
        .chunks_exact(2)
        .map(|b| u16::from_ne_bytes([b[0], b[1]]) as f32 / 65535.0)
        .collect())
}

/// Bilinear enlargement of a float map `w x h` to `width x height`
/// (pixel centres aligned), through the SIMD resizer.
pub fn enlarge_f32(
    src: &[f32],
    (w, h): (usize, usize),
    (width, height): (usize, usize),
) -> Result<Vec<f32>> {
    use fast_image_resize as fr;
    if w == 0 || h == 0 || width < w || height < h || src.len() != w * h {
        return Err(Error::ImageSize {
            width,
            height,
            why: format!("a {w}x{h} map ({} values) cannot enlarge to it", src.len()),
        });
    }
    let fail = |e: String| Error::Kornia(format!("enlarge {w}x{h} to {width}x{height}: {e}"));
    let bytes: Vec<u8> = src.iter().flat_map(|v| v.to_ne_bytes()).collect();
    let img = fr::images::Image::from_vec_u8(w as u32, h as u32, bytes, fr::PixelType::F32)
        .map_err(|e| fail(e.to_string()))?;
    let mut dst = fr::images::Image::new(width as u32, height as u32, fr::PixelType::F32);
    let options =
        fr::ResizeOptions::new().resize_alg(fr::ResizeAlg::Convolution(fr::FilterType::Bilinear));
    fr::Resizer::new()
        .resize(&img, &mut dst, &options)
        .map_err(|e| fail(e.to_string()))?;
    Ok(dst
        .buffer()
        .chunks_exact(4)
        .map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

#[cfg(test)]
mod simd_tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn the_simd_shrink_is_the_area_average() {
        let (w, h) = (23, 18);
        let src: Vec<u8> = (0..w * h * 3).map(|i| (i * 37 % 251) as u8).collect();
        let fast = shrink_rgb_by(&src, (w, h), 4).unwrap();
        let mut crop = Vec::new();
        for y in 0..16 {
            crop.extend_from_slice(&src[y * w * 3..(y * w + 20) * 3]);
        }
        let slow = resize_area_interleaved(&crop, (20, 16, 3), 5, 4).unwrap();
        assert_eq!(fast.len(), slow.len());
        for (a, b) in fast.iter().zip(&slow) {
            assert!((a - b).abs() < 2e-5, "{a} {b}");
        }
    }

    #[test]
    fn an_enlarged_map_keeps_a_ramp_and_its_range() {
        let (w, h) = (8, 6);
        let src: Vec<f32> = (0..w * h).map(|i| (i % w) as f32).collect();
        let big = enlarge_f32(&src, (w, h), (32, 24)).unwrap();
        assert_eq!(big.len(), 32 * 24);
        assert!(big.iter().all(|v| (-1e-4..=7.0001).contains(v)));
        // Inside, the ramp is linear: a step of 1/4 per output pixel.
        let row = &big[10 * 32..11 * 32];
        for x in 4..27 {
            assert!(
                (row[x + 1] - row[x] - 0.25).abs() < 1e-4,
                "{x}: {:?}",
                &row[x..x + 2]
            );
        }
        assert!(enlarge_f32(&src, (w, h), (4, 4)).is_err());
    }
}
