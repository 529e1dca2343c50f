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
    let r = (k.len() / 2) as isize;
    let fetch = |line: &[f32], i: isize| -> f32 {
        let n = line.len() as isize;
        if (0..n).contains(&i) {
            line[i as usize]
        } else {
            match border {
                Border::Zero => 0.0,
                Border::Clamp => line[i.clamp(0, n - 1) as usize],
            }
        }
    };
    let mut line = vec![0.0f32; width.max(height)];
    // Rows.
    for y in 0..height {
        let row = &mut plane[y * width..(y + 1) * width];
        line[..width].copy_from_slice(row);
        for (x, out) in row.iter_mut().enumerate() {
            let mut acc = 0.0f32;
            for (j, kv) in k.iter().enumerate() {
                acc += kv * fetch(&line[..width], x as isize + j as isize - r);
            }
            *out = acc;
        }
    }
    // Columns.
    for x in 0..width {
        for y in 0..height {
            line[y] = plane[y * width + x];
        }
        for y in 0..height {
            let mut acc = 0.0f32;
            for (j, kv) in k.iter().enumerate() {
                acc += kv * fetch(&line[..height], y as isize + j as isize - r);
            }
            plane[y * width + x] = acc;
        }
    }
}

/// Round and clip to 8 bits.
pub fn to_u8(v: f32) -> u8 {
    (v.clamp(0.0, 255.0) + 0.5).floor() as u8
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
}
