//! Gradients to height: the Poisson equation `lap h = div g` on the
//! working grid with `h = 0` beyond its border (the skin is at rest far
//! from any contact), solved exactly in the sine basis. The sine
//! transform (DST-I) is an odd extension through `rustfft`, two rows per
//! complex transform.

use std::sync::Arc;

use burn::tensor::{Device, Tensor, TensorData};
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

/// The same solve as [`PoissonSolver`] written as tensor operations (the
/// sine transform as a matrix product), so a loss on the height can train
/// the network that predicts the gradients.
#[derive(Debug, Clone)]
pub struct PoissonLayer {
    width: usize,
    height: usize,
    /// DST-I matrices, `[W, W]` and `[H, H]` (symmetric).
    sine_x: Tensor<2>,
    sine_y: Tensor<2>,
    /// `1 / eigenvalue` per mode with the transforms' scale, `[1, W, H]`.
    inverse_eigen: Tensor<3>,
}

impl PoissonLayer {
    /// The layer for `width x height` grids on `device`.
    pub fn new(width: usize, height: usize, device: &Device) -> Self {
        let sine = |n: usize| {
            let pi = std::f64::consts::PI;
            let v: Vec<f32> = (0..n * n)
                .map(|i| {
                    let (j, k) = (i / n, i % n);
                    (pi * ((j + 1) * (k + 1)) as f64 / (n + 1) as f64).sin() as f32
                })
                .collect();
            Tensor::<2>::from_data(TensorData::new(v, [n, n]), device)
        };
        let e = PoissonSolver::new(width, height).inverse_eigen;
        Self {
            width,
            height,
            sine_x: sine(width),
            sine_y: sine(height),
            inverse_eigen: Tensor::<3>::from_data(TensorData::new(e, [1, width, height]), device),
        }
    }

    /// Heights from forward-difference gradients.
    ///
    /// # Shapes
    /// - `gx`, `gy`: `[N, H, W]`, height units per pixel
    /// - returns `[N, H, W]`, zero beyond the border
    pub fn integrate(&self, gx: Tensor<3>, gy: Tensor<3>) -> Tensor<3> {
        let (w, h) = (self.width, self.height);
        let n = gx.dims()[0];
        let left = gx
            .clone()
            .slice([0..n, 0..h, 0..w - 1])
            .pad((1, 0, 0, 0), 0.0f32);
        let up = gy
            .clone()
            .slice([0..n, 0..h - 1, 0..w])
            .pad((0, 0, 1, 0), 0.0f32);
        let f = gx - left + gy - up;
        // Rows (along x), then columns (along y), scale, and back.
        let a = f.reshape([n * h, w]).matmul(self.sine_x.clone());
        let t = a.reshape([n, h, w]).swap_dims(1, 2).reshape([n * w, h]);
        let t = t.matmul(self.sine_y.clone()).reshape([n, w, h]) * self.inverse_eigen.clone();
        let t = t.reshape([n * w, h]).matmul(self.sine_y.clone());
        let out = t.reshape([n, w, h]).swap_dims(1, 2).reshape([n * h, w]);
        out.matmul(self.sine_x.clone()).reshape([n, h, w])
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

    #[test]
    fn the_tensor_layer_solves_as_the_fft_solver_does() {
        let (w, h) = (19, 11);
        let g = |s: u32| -> Vec<f32> {
            (0..w * h)
                .map(|i| (((i as u32).wrapping_mul(2654435761u32) ^ s) % 1000) as f32 / 500.0 - 1.0)
                .collect()
        };
        let (gx, gy) = (g(1), g(7));
        let want = PoissonSolver::new(w, h).integrate(&gx, &gy);
        let dev = tactile_burn::DeviceKind::Ndarray.device();
        let t = |v: &[f32]| Tensor::<3>::from_data(TensorData::new(v.to_vec(), [1, h, w]), &dev);
        let got: Vec<f32> = PoissonLayer::new(w, h, &dev)
            .integrate(t(&gx), t(&gy))
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        let err = got
            .iter()
            .zip(&want)
            .map(|(a, b)| (a - b).abs())
            .fold(0f32, f32::max);
        let scale = want.iter().fold(0f32, |m, v| m.max(v.abs()));
        assert!(err < 1e-4 * scale, "{err} of {scale}");
    }
}
