//! The morphology the chain uses: separable box erosion, dilation and
//! mean, the white top-hat with a threshold relative to the local pin
//! contrast (lighting compensation), the circular mask and the centre
//! crop; `(&src) -> dst` over grey images.

use kornia_image::Image;
use kornia_imgproc::morphology::{self, Kernel};
use kornia_imgproc::padding::PaddingMode;
use tactile_core::image_io::GreyImage;

use crate::Result;

pub(crate) fn blank(like: &GreyImage) -> Result<GreyImage> {
    Ok(Image::from_size_val(like.size(), 0u8)?)
}

pub(crate) fn box_kernel(side: usize) -> Kernel {
    morphology::box_kernel(side.max(1))
}

pub(crate) fn erode(src: &GreyImage, side: usize) -> Result<GreyImage> {
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

pub(crate) fn dilate(src: &GreyImage, side: usize) -> Result<GreyImage> {
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
pub(crate) fn box_extreme(src: &GreyImage, side: usize, max: bool) -> Result<GreyImage> {
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
pub(crate) fn box_mean(src: &GreyImage, side: usize) -> Result<GreyImage> {
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

pub(crate) fn top_hat_binary(
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

pub(crate) fn circular_mask(img: &mut GreyImage, radius: f32) {
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

pub(crate) fn centre_crop(img: &GreyImage, side: usize) -> Result<GreyImage> {
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
