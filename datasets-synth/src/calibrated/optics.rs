//! A calibrated sensor's optical response, forward: the colour change a
//! skin slope makes at a place in the frame. This is the lookup table of
//! the classic calibrated simulators (Taxim's polynomial table): slopes
//! `(gx, gy)` are binned on a square grid, and each bin holds, per
//! channel, a quadratic in the frame position fitted by least squares to
//! the ball presses' colour changes. Rendering interpolates bilinearly
//! between the four bins around a slope.

use serde::{Deserialize, Serialize};
use tactile_core::{Error, Result};

/// The table's format tag.
pub const OPTICS_FORMAT: &str = "tactile-optics/1";
/// Terms of the position polynomial: 1, x, y, x², xy, y².
pub const TERMS: usize = 6;
/// Most bins per slope axis.
pub const MAX_BINS: usize = 128;
/// Samples a bin needs to be fitted on its own (fewer: it borrows its
/// nearest fitted neighbour's polynomial).
pub const MIN_BIN_SAMPLES: f64 = 60.0;
/// Ridge on the position terms (not the constant), per unit weight.
const RIDGE: f64 = 1e-3;

/// The terms of the position polynomial at `(x, y)` in `[-1, 1]`.
fn terms(x: f64, y: f64) -> [f64; TERMS] {
    [1.0, x, y, x * x, x * y, y * y]
}

/// Colour change of a skin slope, per channel, by place: what a calibrated
/// sensor shows. Slopes are mm per mm of the skin's indentation (toward
/// the camera) along image x (right) and y (down); colour changes are in
/// `[0, 1]` channel units over the background, at the background's
/// exposure.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SensorOptics {
    /// [`OPTICS_FORMAT`].
    pub format: String,
    /// Frame width, pixels.
    pub width: usize,
    /// Frame height, pixels.
    pub height: usize,
    /// Slopes beyond `+-max_slope` are clamped to it.
    pub max_slope: f64,
    /// Bins per slope axis (centres evenly from `-max_slope` to `max_slope`).
    pub bins: usize,
    /// Per bin (row `gy`, column `gx`), per channel, `TERMS` coefficients.
    pub coefficients: Vec<f32>,
    /// Samples (weighted) each bin was fitted on (0: borrowed).
    pub samples: Vec<f32>,
}

/// One pixel of a press seen by the calibration: where it is, its known
/// slope and the colour change it made.
#[derive(Debug, Clone, Copy)]
pub struct OpticsSample {
    /// Column, frame pixels.
    pub x: f64,
    /// Row, frame pixels.
    pub y: f64,
    /// Slope along x.
    pub gx: f64,
    /// Slope along y.
    pub gy: f64,
    /// Colour change per channel, `[0, 1]` units.
    pub change: [f32; 3],
    /// Its weight.
    pub weight: f64,
}

impl SensorOptics {
    /// Fit a table of `bins x bins` slope bins spanning `+-max_slope` to
    /// `samples` of a `width x height` sensor. Each sample is shared by the
    /// four bins around its slope with bilinear weights, so the fitted
    /// bins interpolate smoothly.
    pub fn fit(
        (width, height): (usize, usize),
        bins: usize,
        max_slope: f64,
        samples: &[OpticsSample],
    ) -> Result<Self> {
        if !(2..=MAX_BINS).contains(&bins) {
            return Err(Error::Config(format!(
                "optics: bins must be 2-{MAX_BINS}, got {bins}"
            )));
        }
        if !(max_slope.is_finite() && max_slope > 0.0 && max_slope <= 20.0) {
            return Err(Error::Config(format!(
                "optics: max_slope must be in (0, 20], got {max_slope:?}"
            )));
        }
        if width == 0 || height == 0 {
            return Err(Error::Config("optics: empty frame".into()));
        }
        let nb = bins * bins;
        // Normal equations per bin: A (TERMS x TERMS) and B (TERMS x 3).
        let mut a = vec![0f64; nb * TERMS * TERMS];
        let mut b = vec![0f64; nb * TERMS * 3];
        let mut n = vec![0f64; nb];
        let probe = Self::empty((width, height), bins, max_slope);
        for s in samples {
            if !(s.gx.is_finite() && s.gy.is_finite() && s.weight > 0.0) {
                continue;
            }
            let t = terms(probe.nx(s.x), probe.ny(s.y));
            for (k, w) in probe.corners(s.gx, s.gy) {
                let w = w * s.weight;
                if w <= 0.0 {
                    continue;
                }
                n[k] += w;
                let ak = &mut a[k * TERMS * TERMS..(k + 1) * TERMS * TERMS];
                for i in 0..TERMS {
                    for j in 0..TERMS {
                        ak[i * TERMS + j] += w * t[i] * t[j];
                    }
                }
                let bk = &mut b[k * TERMS * 3..(k + 1) * TERMS * 3];
                for i in 0..TERMS {
                    for c in 0..3 {
                        bk[i * 3 + c] += w * t[i] * s.change[c] as f64;
                    }
                }
            }
        }
        let mut coefficients = vec![0f32; nb * 3 * TERMS];
        let mut fitted = vec![false; nb];
        for k in 0..nb {
            if n[k] < MIN_BIN_SAMPLES {
                continue;
            }
            let mut ak: Vec<f64> = a[k * TERMS * TERMS..(k + 1) * TERMS * TERMS].to_vec();
            for i in 1..TERMS {
                ak[i * TERMS + i] += RIDGE * n[k];
            }
            for c in 0..3 {
                let rhs: Vec<f64> = (0..TERMS).map(|i| b[k * TERMS * 3 + i * 3 + c]).collect();
                let Some(x) = solve(&ak, &rhs) else { continue };
                for (i, v) in x.iter().enumerate() {
                    coefficients[(k * 3 + c) * TERMS + i] = *v as f32;
                }
                fitted[k] = true;
            }
        }
        if !fitted.iter().any(|&f| f) {
            return Err(Error::Config(format!(
                "optics: no slope bin has {MIN_BIN_SAMPLES} samples; more presses are needed"
            )));
        }
        // Bins without data borrow the nearest fitted bin's polynomial.
        let snapshot = coefficients.clone();
        for k in 0..nb {
            if fitted[k] {
                continue;
            }
            let (r, c) = ((k / bins) as i64, (k % bins) as i64);
            let nearest = (0..nb).filter(|&j| fitted[j]).min_by_key(|&j| {
                let (rj, cj) = ((j / bins) as i64, (j % bins) as i64);
                (rj - r).pow(2) + (cj - c).pow(2)
            });
            if let Some(j) = nearest {
                let (dst, src) = (k * 3 * TERMS, j * 3 * TERMS);
                coefficients[dst..dst + 3 * TERMS].copy_from_slice(&snapshot[src..src + 3 * TERMS]);
            }
        }
        Ok(Self {
            coefficients,
            samples: n.iter().map(|&v| v as f32).collect(),
            ..probe
        })
    }

    /// A table with every bin at zero change.
    fn empty((width, height): (usize, usize), bins: usize, max_slope: f64) -> Self {
        Self {
            format: OPTICS_FORMAT.into(),
            width,
            height,
            max_slope,
            bins,
            coefficients: vec![0.0; bins * bins * 3 * TERMS],
            samples: vec![0.0; bins * bins],
        }
    }

    /// Check a table read from a file.
    pub fn check(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Config(format!("optics: {m}")));
        if self.format != OPTICS_FORMAT {
            return bad(format!(
                "format is {:?}, this version reads {OPTICS_FORMAT:?}",
                self.format
            ));
        }
        if !(2..=MAX_BINS).contains(&self.bins) {
            return bad(format!("bins must be 2-{MAX_BINS}, got {}", self.bins));
        }
        if !(self.max_slope.is_finite() && self.max_slope > 0.0 && self.max_slope <= 20.0) {
            return bad(format!(
                "max_slope must be in (0, 20], got {:?}",
                self.max_slope
            ));
        }
        if self.width == 0 || self.height == 0 || self.width > 8192 || self.height > 8192 {
            return bad(format!("frame {}x{} out of range", self.width, self.height));
        }
        let nb = self.bins * self.bins;
        if self.coefficients.len() != nb * 3 * TERMS || self.samples.len() != nb {
            return bad(format!(
                "{} coefficients and {} sample counts for {} bins",
                self.coefficients.len(),
                self.samples.len(),
                nb
            ));
        }
        if self.coefficients.iter().any(|v| !v.is_finite()) {
            return bad("a coefficient is not finite".into());
        }
        Ok(())
    }

    /// Column `x` (frame pixels) in `[-1, 1]`.
    fn nx(&self, x: f64) -> f64 {
        2.0 * (x + 0.5) / self.width as f64 - 1.0
    }

    /// Row `y` in `[-1, 1]`.
    fn ny(&self, y: f64) -> f64 {
        2.0 * (y + 0.5) / self.height as f64 - 1.0
    }

    /// A slope's position on the bin axis, clamped to the table.
    fn bin_coord(&self, g: f64) -> f64 {
        let step = 2.0 * self.max_slope / (self.bins - 1) as f64;
        ((g.clamp(-self.max_slope, self.max_slope) + self.max_slope) / step)
            .clamp(0.0, (self.bins - 1) as f64)
    }

    /// The four bins around slope `(gx, gy)` with their bilinear weights.
    fn corners(&self, gx: f64, gy: f64) -> [(usize, f64); 4] {
        let (u, v) = (self.bin_coord(gx), self.bin_coord(gy));
        let last = self.bins - 1;
        let (u0, v0) = (
            (u.floor() as usize).min(last),
            (v.floor() as usize).min(last),
        );
        let (u1, v1) = ((u0 + 1).min(last), (v0 + 1).min(last));
        let (fu, fv) = (u - u0 as f64, v - v0 as f64);
        [
            (v0 * self.bins + u0, (1.0 - fu) * (1.0 - fv)),
            (v0 * self.bins + u1, fu * (1.0 - fv)),
            (v1 * self.bins + u0, (1.0 - fu) * fv),
            (v1 * self.bins + u1, fu * fv),
        ]
    }

    /// The colour change of slope `(gx, gy)` at frame pixel `(x, y)`.
    pub fn change(&self, x: f64, y: f64, gx: f64, gy: f64) -> [f32; 3] {
        let t = terms(self.nx(x), self.ny(y));
        let mut out = [0f64; 3];
        for (k, w) in self.corners(gx, gy) {
            if w == 0.0 {
                continue;
            }
            for (c, o) in out.iter_mut().enumerate() {
                let co = &self.coefficients[(k * 3 + c) * TERMS..(k * 3 + c + 1) * TERMS];
                *o += w * co.iter().zip(&t).map(|(a, b)| *a as f64 * b).sum::<f64>();
            }
        }
        out.map(|v| v as f32)
    }
}

/// Solve the symmetric positive system `a x = b` (`n x n`, row-major) by
/// Cholesky; `None` when it is not positive definite.
fn solve(a: &[f64], b: &[f64]) -> Option<Vec<f64>> {
    let n = b.len();
    let mut l = vec![0f64; n * n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k];
            }
            if i == j {
                if s <= 0.0 {
                    return None;
                }
                l[i * n + i] = s.sqrt();
            } else {
                l[i * n + j] = s / l[j * n + j];
            }
        }
    }
    let mut y = vec![0f64; n];
    for i in 0..n {
        let s: f64 = (0..i).map(|k| l[i * n + k] * y[k]).sum();
        y[i] = (b[i] - s) / l[i * n + i];
    }
    let mut x = vec![0f64; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| l[k * n + i] * x[k]).sum();
        x[i] = (y[i] - s) / l[i * n + i];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_learns_a_smooth_response_and_interpolates_it() {
        // Truth: red grows with gx, blue with gy, green with x position.
        let truth = |x: f64, _y: f64, gx: f64, gy: f64| {
            [
                (0.1 * gx) as f32,
                (0.02 * (2.0 * (x + 0.5) / 64.0 - 1.0)) as f32,
                (-0.05 * gy) as f32,
            ]
        };
        let mut samples = vec![];
        for k in 0..40_000u64 {
            let (x, y) = ((k % 64) as f64, ((k / 64) % 48) as f64);
            let gx = ((k * 7919) % 1000) as f64 / 500.0 - 1.0;
            let gy = ((k * 104_729) % 1000) as f64 / 500.0 - 1.0;
            samples.push(OpticsSample {
                x,
                y,
                gx,
                gy,
                change: truth(x, y, gx, gy),
                weight: 1.0,
            });
        }
        let t = SensorOptics::fit((64, 48), 9, 1.0, &samples).unwrap();
        t.check().unwrap();
        for (x, y, gx, gy) in [(10.0, 5.0, 0.3, -0.2), (50.0, 40.0, -0.77, 0.61)] {
            let got = t.change(x, y, gx, gy);
            let want = truth(x, y, gx, gy);
            for c in 0..3 {
                assert!((got[c] - want[c]).abs() < 3e-3, "{got:?} {want:?}");
            }
        }
        // Beyond the table the slope is clamped.
        assert_eq!(t.change(3.0, 3.0, 5.0, 0.0), t.change(3.0, 3.0, 1.0, 0.0));
        let json = serde_json::to_string(&t).unwrap();
        let back: SensorOptics = serde_json::from_str(&json).unwrap();
        back.check().unwrap();
        let mut bad = back.clone();
        bad.coefficients.pop();
        assert!(
            bad.check()
                .unwrap_err()
                .to_string()
                .contains("coefficients")
        );
    }
}
