//! Gradients to height: the Poisson equation `lap h = div g` on the
//! working grid with `h = 0` beyond its border (the skin is at rest far
//! from any contact), solved exactly in the sine basis. The sine
//! transform (DST-I) is an odd extension through `rustfft`, two rows per
//! complex transform.

use std::sync::Arc;

use rustfft::num_complex::Complex32;
use rustfft::{Fft, FftPlanner};

/// A solver for one grid size, its transforms planned once.
pub struct PoissonSolver {
    width: usize,
    height: usize,
    along_x: Arc<dyn Fft<f32>>,
    along_y: Arc<dyn Fft<f32>>,
    /// `1 / eigenvalue` of the 5-point Laplacian per sine mode, `[kx][ky]`.
    inverse_eigen: Vec<f32>,
}

impl std::fmt::Debug for PoissonSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PoissonSolver({}x{})", self.width, self.height)
    }
}

impl PoissonSolver {
    /// A solver for `width x height` grids.
    pub fn new(width: usize, height: usize) -> Self {
        let mut planner = FftPlanner::new();
        let along_x = planner.plan_fft_forward(2 * (width + 1));
        let along_y = planner.plan_fft_forward(2 * (height + 1));
        let pi = std::f64::consts::PI;
        let mut inverse_eigen = vec![0f32; width * height];
        let s = 4.0 / ((width + 1) * (height + 1)) as f64;
        for kx in 0..width {
            let lx = 2.0 * ((pi * (kx + 1) as f64 / (width + 1) as f64).cos() - 1.0);
            for ky in 0..height {
                let ly = 2.0 * ((pi * (ky + 1) as f64 / (height + 1) as f64).cos() - 1.0);
                // The two unnormalised DST-I passes each way scale by
                // (n + 1) / 2: folded in here.
                inverse_eigen[kx * height + ky] = (s / (lx + ly)) as f32;
            }
        }
        Self {
            width,
            height,
            along_x,
            along_y,
            inverse_eigen,
        }
    }

    /// The divergence of forward-difference gradients `gx`, `gy` (row-major
    /// `height x width`, height units per pixel): `gx[x] - gx[x-1] + gy[y] -
    /// gy[y-1]`, zero beyond the border.
    pub fn divergence(&self, gx: &[f32], gy: &[f32]) -> Vec<f32> {
        let (w, h) = (self.width, self.height);
        let mut f = vec![0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let left = if x > 0 { gx[i - 1] } else { 0.0 };
                let up = if y > 0 { gy[i - w] } else { 0.0 };
                f[i] = gx[i] - left + gy[i] - up;
            }
        }
        f
    }

    /// The height whose 5-point Laplacian is `f` (row-major), zero beyond
    /// the border.
    pub fn solve(&self, f: &[f32]) -> Vec<f32> {
        let (w, h) = (self.width, self.height);
        let mut a = f.to_vec();
        let mut buf = Vec::new();
        dst_rows(&mut a, w, &*self.along_x, &mut buf);
        let mut t = transpose(&a, w, h);
        dst_rows(&mut t, h, &*self.along_y, &mut buf);
        for (v, k) in t.iter_mut().zip(&self.inverse_eigen) {
            *v *= k;
        }
        dst_rows(&mut t, h, &*self.along_y, &mut buf);
        let mut out = transpose(&t, h, w);
        dst_rows(&mut out, w, &*self.along_x, &mut buf);
        out
    }

    /// Height from forward-difference gradients.
    pub fn integrate(&self, gx: &[f32], gy: &[f32]) -> Vec<f32> {
        self.solve(&self.divergence(gx, gy))
    }
}

fn transpose(src: &[f32], w: usize, h: usize) -> Vec<f32> {
    let mut dst = vec![0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            dst[x * h + y] = src[y * w + x];
        }
    }
    dst
}

/// Unnormalised DST-I (`X_k = sum_j x_j sin(pi (j+1)(k+1) / (n+1))`) of
/// every row of length `n`, in place: each pair of rows is the real and
/// imaginary part of one odd-extended complex sequence.
fn dst_rows(data: &mut [f32], n: usize, fft: &dyn Fft<f32>, buf: &mut Vec<Complex32>) {
    let m = 2 * (n + 1);
    let rows = data.len() / n;
    let pairs = rows.div_ceil(2);
    buf.clear();
    buf.resize(pairs * m, Complex32::new(0.0, 0.0));
    for p in 0..pairs {
        let y = &mut buf[p * m..(p + 1) * m];
        for j in 0..n {
            let re = data[2 * p * n + j];
            let im = if 2 * p + 1 < rows {
                data[(2 * p + 1) * n + j]
            } else {
                0.0
            };
            y[j + 1] = Complex32::new(re, im);
            y[m - 1 - j] = Complex32::new(-re, -im);
        }
    }
    fft.process(buf);
    for p in 0..pairs {
        let y = &buf[p * m..(p + 1) * m];
        for k in 0..n {
            let v = y[k + 1];
            data[2 * p * n + k] = -v.im / 2.0;
            if 2 * p + 1 < rows {
                data[(2 * p + 1) * n + k] = v.re / 2.0;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn a_bump_comes_back_from_its_gradients() {
        let (w, h) = (37, 23);
        let bump: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 - 18.0, (i / w) as f32 - 11.0);
                (-(x * x + y * y) / 8.0).exp()
            })
            .collect();
        let at = |x: usize, y: usize| if x < w && y < h { bump[y * w + x] } else { 0.0 };
        let gx: Vec<f32> = (0..w * h)
            .map(|i| at(i % w + 1, i / w) - at(i % w, i / w))
            .collect();
        let gy: Vec<f32> = (0..w * h)
            .map(|i| at(i % w, i / w + 1) - at(i % w, i / w))
            .collect();
        let back = PoissonSolver::new(w, h).integrate(&gx, &gy);
        let err = back
            .iter()
            .zip(&bump)
            .map(|(a, b)| (a - b).abs())
            .fold(0f32, f32::max);
        assert!(err < 1e-4, "{err}");
    }
}
