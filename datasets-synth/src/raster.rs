//! Raster helpers shared by both sensors: Gaussian blur and 8-bit output.

/// What lies beyond the edge of a plane when blurring.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Border {
    /// Zeros (a field that vanishes outside its grid).
    Zero,
    /// The nearest edge value (a camera image).
    Clamp,
}

/// Normalised 1-D Gaussian kernel, radius `ceil(3 sigma)`.
pub fn gaussian_kernel(sigma: f64) -> Vec<f32> {
    let radius = (3.0 * sigma).ceil().max(1.0) as i64;
    let k: Vec<f64> = (-radius..=radius)
        .map(|i| libm::exp(-((i * i) as f64) / (2.0 * sigma * sigma)))
        .collect();
    let sum: f64 = k.iter().sum();
    k.iter().map(|v| (v / sum) as f32).collect()
}

/// Separable Gaussian blur of one `width x height` plane, in place.
pub fn gaussian_blur(plane: &mut [f32], width: usize, height: usize, sigma: f64, border: Border) {
    if sigma <= 0.0 || width == 0 || height == 0 {
        return;
    }
    let k = gaussian_kernel(sigma);
    let r = k.len() / 2;
    // Each output is summed tap by tap in the kernel's order, as a direct
    // loop would (the same value to the bit), but tap-major over a whole
    // line so the multiply-adds run across pixels in SIMD lanes.
    let mut acc = vec![0.0f32; width];
    // Rows: each row copied once, widened by the kernel's radius on both
    // sides with the border's values, so the taps need no bounds test.
    let mut padded = Vec::with_capacity(width + 2 * r);
    for row in plane[..width * height].chunks_exact_mut(width) {
        let (first, last) = match border {
            Border::Zero => (0.0, 0.0),
            Border::Clamp => (row[0], row[width - 1]),
        };
        padded.clear();
        padded.resize(r, first);
        padded.extend_from_slice(row);
        padded.resize(width + 2 * r, last);
        acc.fill(0.0);
        for (j, kv) in k.iter().enumerate() {
            for (a, v) in acc.iter_mut().zip(&padded[j..j + width]) {
                *a += kv * v;
            }
        }
        row.copy_from_slice(&acc);
    }
    // Columns: a whole output row at a time from the rows above and below
    // (beyond the plane, a row of zeros or the edge row).
    let source = plane[..width * height].to_vec();
    let zeros = vec![0.0f32; width];
    for (y, row) in plane[..width * height].chunks_exact_mut(width).enumerate() {
        acc.fill(0.0);
        for (j, kv) in k.iter().enumerate() {
            let yy = y as isize + j as isize - r as isize;
            let src = match border {
                _ if (0..height as isize).contains(&yy) => {
                    &source[yy as usize * width..(yy as usize + 1) * width]
                }
                Border::Zero => &zeros[..],
                Border::Clamp => {
                    let yy = yy.clamp(0, height as isize - 1) as usize;
                    &source[yy * width..(yy + 1) * width]
                }
            };
            for (a, v) in acc.iter_mut().zip(src) {
                *a += kv * v;
            }
        }
        row.copy_from_slice(&acc);
    }
}

/// Round and clip to 8 bits.
pub fn to_u8(v: f32) -> u8 {
    // Non-negative (or NaN, which gives 0 either way): the cast's
    // truncation is the floor, without a call to `floorf`.
    (v.clamp(0.0, 255.0) + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blur_preserves_mass_with_zero_border_and_constants_with_clamp() {
        let (w, h) = (41, 31);
        let mut p = vec![0.0f32; w * h];
        p[15 * w + 20] = 1.0;
        gaussian_blur(&mut p, w, h, 2.0, Border::Zero);
        let sum: f32 = p.iter().sum();
        assert!((sum - 1.0).abs() < 1e-5, "{sum}");
        assert!(p[15 * w + 20] > p[15 * w + 22] && p[15 * w + 22] > p[15 * w + 25]);
        let mut c = vec![7.0f32; w * h];
        gaussian_blur(&mut c, w, h, 1.5, Border::Clamp);
        assert!(c.iter().all(|v| (v - 7.0).abs() < 1e-4));
    }

    /// Rounding to 8 bits is the floor of `v + 0.5` it always was, at every
    /// level, between levels, out of range and at NaN.
    #[test]
    fn to_u8_rounds_as_the_floor_did() {
        let specials = [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -0.0,
            254.5,
            255.49,
            0.49999997,
        ];
        let steps = (-20_000..600_000).map(|i| i as f32 * 0.000_5);
        for v in steps.chain(specials) {
            let floor = (v.clamp(0.0, 255.0) + 0.5).floor() as u8;
            assert_eq!(to_u8(v), floor, "{v}");
        }
    }

    /// The blur gives, to the bit, what the tap-by-tap loop it replaced
    /// gave (every rendered set of a seed stays the same): both borders, a
    /// kernel wider than the plane, odd sizes.
    #[test]
    fn blur_is_the_tap_by_tap_sum_to_the_bit() {
        fn direct(plane: &mut [f32], w: usize, h: usize, sigma: f64, border: Border) {
            let k = gaussian_kernel(sigma);
            let r = (k.len() / 2) as isize;
            let fetch = |line: &[f32], i: isize| -> f32 {
                let n = line.len() as isize;
                match ((0..n).contains(&i), border) {
                    (true, _) => line[i as usize],
                    (false, Border::Zero) => 0.0,
                    (false, Border::Clamp) => line[i.clamp(0, n - 1) as usize],
                }
            };
            let taps = |line: &[f32], x: usize| {
                let mut acc = 0.0f32;
                for (j, kv) in k.iter().enumerate() {
                    acc += kv * fetch(line, x as isize + j as isize - r);
                }
                acc
            };
            for y in 0..h {
                let line = plane[y * w..(y + 1) * w].to_vec();
                for x in 0..w {
                    plane[y * w + x] = taps(&line, x);
                }
            }
            for x in 0..w {
                let line: Vec<f32> = (0..h).map(|y| plane[y * w + x]).collect();
                for y in 0..h {
                    plane[y * w + x] = taps(&line, y);
                }
            }
        }
        let mut rng = tactile_core::rng::SampleRng::new(4, 0, 0);
        for (w, h, sigma) in [(37, 23, 1.3), (64, 48, 4.0), (5, 9, 6.0), (1, 7, 0.7)] {
            let plane: Vec<f32> = (0..w * h).map(|_| rng.normal() as f32).collect();
            for border in [Border::Zero, Border::Clamp] {
                let (mut a, mut b) = (plane.clone(), plane.clone());
                gaussian_blur(&mut a, w, h, sigma, border);
                direct(&mut b, w, h, sigma, border);
                let same = a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits());
                assert!(same, "{w}x{h}, sigma {sigma}: the blur changed its values");
            }
        }
    }
}
